!> LU factorization with partial pivoting, solves and the exact 1-norm condition of small
!> complex matrices, in plain Fortran: for the condensation of small models, harmonic by
!> harmonic. OpenBLAS takes one process-wide lock for the work buffer of each level-2 and
!> level-3 call (blas_memory_alloc), so threads that make many calls on tiny matrices wait
!> for each other (the curves of a family traced on two threads ran no faster than on one,
!> each thread's CPU time doubled by the waits); below about 16 unknowns the calls' own
!> overhead also exceeds the arithmetic. Same results as LAPACK's zgetrf and zgetrs to
!> roundoff (the same pivots: the largest |re| + |im| of the column, as izamax); the
!> condition is exact, 1 / (||A||_1 ||A^-1||_1), where zgecon estimates ||A^-1||_1 from
!> below. No state: callable from several threads at once.
module stickslip_small_dense
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: small_zgetrf, small_zgetrs, small_zrcond

    !> Largest order the condensation factorizes here rather than with LAPACK.
    integer, parameter, public :: small_dense_max = 16

contains

    !> A = P L U in place (L unit lower, U upper, as zgetrf). info = 0, or k > 0 when
    !> U(k, k) is exactly zero (the factorization is completed, as zgetrf).
    pure subroutine small_zgetrf(n, a, ipiv, info)
        !> Order.
        integer, intent(in) :: n
        !> The matrix, then its factors.
        complex(dp), intent(inout) :: a(n, n)
        !> Row interchanges: row k was swapped with row ipiv(k).
        integer, intent(out) :: ipiv(n)
        !> 0 or the first zero pivot.
        integer, intent(out) :: info
        integer :: k, p, i, j
        complex(dp) :: t(n), r
        real(dp) :: best
        info = 0
        do k = 1, n
            p = k
            best = abs(real(a(k, k), dp)) + abs(aimag(a(k, k)))
            do i = k + 1, n
                if (abs(real(a(i, k), dp)) + abs(aimag(a(i, k))) > best) then
                    p = i
                    best = abs(real(a(i, k), dp)) + abs(aimag(a(i, k)))
                end if
            end do
            ipiv(k) = p
            if (p /= k) then
                t = a(k, :)
                a(k, :) = a(p, :)
                a(p, :) = t
            end if
            if (a(k, k) == (0.0_dp, 0.0_dp)) then
                if (info == 0) info = k
                cycle
            end if
            r = 1.0_dp/a(k, k)
            a(k + 1:n, k) = a(k + 1:n, k)*r
            do j = k + 1, n
                a(k + 1:n, j) = a(k + 1:n, j) - a(k + 1:n, k)*a(k, j)
            end do
        end do
    end subroutine small_zgetrf

    !> Solve A X = B with the factors of small_zgetrf (no zero pivot), B overwritten by X.
    pure subroutine small_zgetrs(n, nrhs, a, ipiv, b)
        !> Order and number of right-hand sides.
        integer, intent(in) :: n, nrhs
        !> The factors.
        complex(dp), intent(in) :: a(n, n)
        !> The interchanges.
        integer, intent(in) :: ipiv(n)
        !> Right-hand sides, then the solutions.
        complex(dp), intent(inout) :: b(n, nrhs)
        integer :: k, j
        complex(dp) :: t(nrhs)
        do k = 1, n
            if (ipiv(k) /= k) then
                t = b(k, :)
                b(k, :) = b(ipiv(k), :)
                b(ipiv(k), :) = t
            end if
        end do
        do j = 1, nrhs
            ! L y = b (unit diagonal), then U x = y
            do k = 1, n - 1
                b(k + 1:n, j) = b(k + 1:n, j) - a(k + 1:n, k)*b(k, j)
            end do
            do k = n, 1, -1
                b(k, j) = b(k, j)/a(k, k)
                b(1:k - 1, j) = b(1:k - 1, j) - a(1:k - 1, k)*b(k, j)
            end do
        end do
    end subroutine small_zgetrs

    !> The reciprocal condition number 1 / (anorm ||A^-1||_1) in the 1-norm, exact, from
    !> the factors of small_zgetrf (no zero pivot) and anorm = ||A||_1.
    pure real(dp) function small_zrcond(n, a, ipiv, anorm) result(rcond)
        !> Order.
        integer, intent(in) :: n
        !> The factors.
        complex(dp), intent(in) :: a(n, n)
        !> The interchanges.
        integer, intent(in) :: ipiv(n)
        !> ||A||_1.
        real(dp), intent(in) :: anorm
        complex(dp) :: e(n, n)
        integer :: k
        real(dp) :: inorm
        e = (0.0_dp, 0.0_dp)
        do k = 1, n
            e(k, k) = (1.0_dp, 0.0_dp)
        end do
        call small_zgetrs(n, n, a, ipiv, e)
        inorm = maxval(sum(abs(e), dim=1))
        rcond = 0.0_dp
        if (anorm > 0.0_dp .and. inorm > 0.0_dp) rcond = 1.0_dp/(anorm*inorm)
    end function small_zrcond
end module stickslip_small_dense
