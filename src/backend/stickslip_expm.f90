!> The matrix exponential exp(A) of a real square matrix: scaling and squaring with the
!> diagonal Pade approximant of degree 3, 5, 7, 9 or 13 chosen by the 1-norm of A, as in
!> N. J. Higham, "The scaling and squaring method for the matrix exponential revisited",
!> SIAM J. Matrix Anal. Appl. 26 (2005) 1179-1193 (Algorithm 2.3; the backward error of
!> each degree below the unit roundoff up to its theta_m). The approximant is evaluated
!> from the even powers of A (U = A * odd part, V = even part, r = (V - U) \ (V + U)):
!> 2 to 6 matrix products and one LU solve, then s squarings, where the fixed degree 8 at
!> norm 1/2 it replaced took 7 products and a squaring per doubling of the norm (a phase of
!> a stiff reduced FE model, norm 5 to 20: 9 to 11 products instead of 11 to 13 plus a
!> solve). Used by the exact event-driven reference, whose phases are linear ODEs. Knows
!> nothing of the model.
module stickslip_expm
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_lapack, only: dgetrf, dgetrs
    use stickslip_dense_products, only: mat_mul
    implicit none
    private
    public :: expm

    !> theta_m of Higham (2005), Table 2.3: the largest 1-norm for which the degree-m Pade
    !> approximant has a backward error below 2^-53, m = 3, 5, 7, 9, 13.
    real(dp), parameter :: theta(5) = [1.495585217958292e-2_dp, 2.539398330063230e-1_dp, &
                                       9.504178996162932e-1_dp, 2.097847961257068e0_dp, &
                                       5.371920351148152e0_dp]
    integer, parameter :: degrees(5) = [3, 5, 7, 9, 13]

contains

    !> e = exp(a). The lowest Pade degree whose theta bounds the 1-norm of a, else degree 13
    !> on a scaled by 2^-s to within theta_13, squared s times. `stat` is 0, or nonzero when
    !> a is not finite, the Pade denominator is singular (impossible for finite a) or
    !> exp(a) overflows (reported, never stopped on; e is then 0).
    subroutine expm(a, e, stat)
        !> Square matrix.
        real(dp), intent(in) :: a(:, :)
        !> exp(a), same shape.
        real(dp), intent(out) :: e(:, :)
        !> 0 on success.
        integer, intent(out) :: stat
        real(dp), allocatable :: x(:, :), u(:, :), v(:, :)
        real(dp) :: anorm
        integer :: n, s, k, m

        n = size(a, 1)
        stat = 0
        if (n == 0) return
        anorm = maxval(sum(abs(a), dim=1))
        if (.not. (anorm <= huge(1.0_dp))) then
            stat = 1
            e = 0.0_dp
            return
        end if
        s = 0
        m = 13
        do k = 1, 4
            if (anorm <= theta(k)) then
                m = degrees(k)
                exit
            end if
        end do
        if (m == 13 .and. anorm > theta(5)) s = max(0, ceiling(log(anorm/theta(5))/log(2.0_dp)))
        x = a*(0.5_dp**s)
        call pade_parts(x, m, u, v)
        ! r = (V - U)^-1 (V + U)
        e = v + u
        v = v - u
        call solve_in_place(v, e, stat)
        if (stat /= 0) then
            e = 0.0_dp
            return
        end if
        do k = 1, s
            e = mat_mul(e, e)
        end do
        ! a norm too large for the squarings (the exponential overflows)
        if (.not. all(ieee_is_finite(e))) then
            stat = 2
            e = 0.0_dp
        end if
    end subroutine expm

    !> U (odd) and V (even) parts of the numerator p(x) = V + U of the degree-m diagonal
    !> Pade approximant of exp (the denominator is p(-x) = V - U).
    subroutine pade_parts(x, m, u, v)
        real(dp), intent(in) :: x(:, :)
        integer, intent(in) :: m
        real(dp), allocatable, intent(out) :: u(:, :), v(:, :)
        real(dp), allocatable :: x2(:, :), x4(:, :), x6(:, :), w(:, :), id(:, :)
        real(dp) :: b(0:13)
        integer :: n, i
        n = size(x, 1)
        allocate (id(n, n))
        id = 0.0_dp
        do i = 1, n
            id(i, i) = 1.0_dp
        end do
        b = 0.0_dp
        select case (m)
        case (3)
            b(0:3) = [120.0_dp, 60.0_dp, 12.0_dp, 1.0_dp]
        case (5)
            b(0:5) = [30240.0_dp, 15120.0_dp, 3360.0_dp, 420.0_dp, 30.0_dp, 1.0_dp]
        case (7)
            b(0:7) = [17297280.0_dp, 8648640.0_dp, 1995840.0_dp, 277200.0_dp, 25200.0_dp, &
                      1512.0_dp, 56.0_dp, 1.0_dp]
        case (9)
            b(0:9) = [17643225600.0_dp, 8821612800.0_dp, 2075673600.0_dp, 302702400.0_dp, &
                      30270240.0_dp, 2162160.0_dp, 110880.0_dp, 3960.0_dp, 90.0_dp, 1.0_dp]
        case default
            b = [64764752532480000.0_dp, 32382376266240000.0_dp, 7771770303897600.0_dp, &
                 1187353796428800.0_dp, 129060195264000.0_dp, 10559470521600.0_dp, &
                 670442572800.0_dp, 33522128640.0_dp, 1323241920.0_dp, 40840800.0_dp, &
                 960960.0_dp, 16380.0_dp, 182.0_dp, 1.0_dp]
        end select
        x2 = mat_mul(x, x)
        select case (m)
        case (3)
            w = b(3)*x2 + b(1)*id
            v = b(2)*x2 + b(0)*id
        case (5)
            x4 = mat_mul(x2, x2)
            w = b(5)*x4 + b(3)*x2 + b(1)*id
            v = b(4)*x4 + b(2)*x2 + b(0)*id
        case (7)
            x4 = mat_mul(x2, x2)
            x6 = mat_mul(x4, x2)
            w = b(7)*x6 + b(5)*x4 + b(3)*x2 + b(1)*id
            v = b(6)*x6 + b(4)*x4 + b(2)*x2 + b(0)*id
        case (9)
            x4 = mat_mul(x2, x2)
            x6 = mat_mul(x4, x2)
            w = mat_mul(x6, x2)
            v = b(8)*w + b(6)*x6 + b(4)*x4 + b(2)*x2 + b(0)*id
            w = b(9)*w + b(7)*x6 + b(5)*x4 + b(3)*x2 + b(1)*id
        case default
            x4 = mat_mul(x2, x2)
            x6 = mat_mul(x4, x2)
            w = mat_mul(x6, b(13)*x6 + b(11)*x4 + b(9)*x2) + b(7)*x6 + b(5)*x4 + b(3)*x2 + &
                b(1)*id
            v = mat_mul(x6, b(12)*x6 + b(10)*x4 + b(8)*x2) + b(6)*x6 + b(4)*x4 + b(2)*x2 + &
                b(0)*id
        end select
        u = mat_mul(x, w)
    end subroutine pade_parts

    !> b = a^-1 b by LU with partial pivoting (a overwritten); stat from LAPACK.
    subroutine solve_in_place(a, b, stat)
        real(dp), intent(inout) :: a(:, :), b(:, :)
        integer, intent(out) :: stat
        integer, allocatable :: ipiv(:)
        integer :: n
        n = size(a, 1)
        allocate (ipiv(n))
        call dgetrf(n, n, a, n, ipiv, stat)
        if (stat /= 0) return
        call dgetrs('N', n, n, a, n, ipiv, b, n, stat)
    end subroutine solve_in_place
end module stickslip_expm
