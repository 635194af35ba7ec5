!> The matrix exponential exp(A) of a real square matrix: diagonal Pade approximant of
!> degree 8 with scaling and squaring (Golub & Van Loan, "Matrix Computations", 11.3).
!> Used by the exact event-driven reference, whose phases are linear ODEs. Knows nothing
!> of the model.
module stickslip_expm
    use stickslip_kinds, only: dp
    use stickslip_lapack, only: dgetrf, dgetrs
    use stickslip_dense_products, only: mat_mul
    implicit none
    private
    public :: expm

    !> Degree of the diagonal Pade approximant.
    integer, parameter :: q = 8

contains

    !> e = exp(a). The matrix is scaled by 2^-s so that its infinity norm is at most 1/2,
    !> where the degree-8 Pade approximant is accurate to well below double-precision
    !> roundoff, then squared s times. `stat` is 0, or nonzero when a is not finite or the
    !> Pade denominator is singular (impossible for finite a; reported, never stopped on).
    subroutine expm(a, e, stat)
        !> Square matrix.
        real(dp), intent(in) :: a(:, :)
        !> exp(a), same shape.
        real(dp), intent(out) :: e(:, :)
        !> 0 on success.
        integer, intent(out) :: stat
        real(dp), allocatable :: x(:, :), xk(:, :), num(:, :), den(:, :)
        integer, allocatable :: ipiv(:)
        real(dp) :: anorm, c
        integer :: n, s, k, i

        n = size(a, 1)
        stat = 0
        if (n == 0) return
        anorm = maxval(sum(abs(a), dim=2))
        if (.not. (anorm <= huge(1.0_dp))) then
            stat = 1
            e = 0.0_dp
            return
        end if
        s = 0
        if (anorm > 0.5_dp) s = max(0, exponent(anorm) + 1)
        allocate (x(n, n), xk(n, n), num(n, n), den(n, n), ipiv(n))
        x = a*(0.5_dp**s)
        num = 0.0_dp
        do i = 1, n
            num(i, i) = 1.0_dp
        end do
        den = num
        c = 0.5_dp
        num = num + c*x
        den = den - c*x
        xk = x
        do k = 2, q
            c = c*real(q - k + 1, dp)/real(k*(2*q - k + 1), dp)
            xk = mat_mul(x, xk)
            num = num + c*xk
            if (mod(k, 2) == 0) then
                den = den + c*xk
            else
                den = den - c*xk
            end if
        end do
        call dgetrf(n, n, den, n, ipiv, stat)
        if (stat /= 0) then
            e = 0.0_dp
            return
        end if
        call dgetrs('N', n, n, den, n, ipiv, num, n, stat)
        do k = 1, s
            num = mat_mul(num, num)
        end do
        e = num
    end subroutine expm
end module stickslip_expm
