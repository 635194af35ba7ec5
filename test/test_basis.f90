!> Tests of the Fourier basis, its FFT quadrature and the stick-product matrix, against a
!> naive discrete Fourier transform; and of the friction law Psi in each region.
module test_basis
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_friction, only: psi, psi_stick
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_basis_tests, naive_synthesis

contains

    subroutine run_basis_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_psi_regions(t)
        call test_round_trip(t, 7, .false., 15)
        call test_round_trip(t, 9, .true., 64)
        call test_round_trip(t, 30, .false., 1024)
        call test_stick_product(t, 6, .false., 13)
        call test_stick_product(t, 11, .true., 40)
        call test_stick_product(t, 20, .false., 128)
        call test_bad_sizes(t)
    end subroutine run_basis_tests

    !> Samples of a function from its coefficients by direct summation.
    function naive_synthesis(b, coef) result(u)
        type(basis_t), intent(in) :: b
        real(dp), intent(in) :: coef(:)
        real(dp) :: u(b%nt)
        integer :: k, i
        real(dp) :: th
        u = 0.0_dp
        do k = 1, b%nt
            th = two_pi*real(k - 1, dp)/real(b%nt, dp)
            if (b%has_zero) u(k) = coef(b%i0)
            do i = 1, b%nharm
                u(k) = u(k) + coef(b%icos(i))*cos(b%harm(i)*th) + &
                       coef(b%icos(i) + 1)*sin(b%harm(i)*th)
            end do
        end do
    end function naive_synthesis

    function naive_analysis(b, u) result(coef)
        type(basis_t), intent(in) :: b
        real(dp), intent(in) :: u(:)
        real(dp) :: coef(b%nb)
        integer :: k, i
        real(dp) :: th
        coef = 0.0_dp
        do k = 1, b%nt
            th = two_pi*real(k - 1, dp)/real(b%nt, dp)
            if (b%has_zero) coef(b%i0) = coef(b%i0) + u(k)/b%nt
            do i = 1, b%nharm
                coef(b%icos(i)) = coef(b%icos(i)) + 2*u(k)*cos(b%harm(i)*th)/b%nt
                coef(b%icos(i) + 1) = coef(b%icos(i) + 1) + 2*u(k)*sin(b%harm(i)*th)/b%nt
            end do
        end do
    end function naive_analysis

    subroutine test_psi_regions(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: g = 0.45_dp, rho = 0.2_dp
        ! slip with v > 0: r = -g  => Psi = rho (r + g)
        call check_close(t, psi(-0.3_dp, 2.0_dp, g, rho), rho*(-0.3_dp + g), "psi slip v>0")
        call check_close(t, psi_stick(-0.3_dp, 2.0_dp, g, rho), 0.0_dp, "stick flag slip v>0")
        call check_close(t, psi(-g, 2.0_dp, g, rho), 0.0_dp, "psi zero on Coulomb slip v>0", &
                         atol=1e-15_dp)
        ! slip with v < 0: Psi = rho (r - g)
        call check_close(t, psi(0.7_dp, -1.5_dp, g, rho), rho*(0.7_dp - g), "psi slip v<0")
        call check_close(t, psi(g, -1.5_dp, g, rho), 0.0_dp, "psi zero on Coulomb slip v<0", &
                         atol=1e-15_dp)
        ! stick: Psi = v
        call check_close(t, psi(0.1_dp, 1.0e-3_dp, g, rho), 1.0e-3_dp, "psi stick = v")
        call check_close(t, psi_stick(0.1_dp, 1.0e-3_dp, g, rho), 1.0_dp, "stick flag stick")
        call check_close(t, psi(0.1_dp, 0.0_dp, g, rho), 0.0_dp, "psi zero on Coulomb stick")
        ! Coulomb violations give nonzero Psi
        call check(t, abs(psi(0.3_dp, 1.0_dp, g, rho)) > 0.1_dp, "psi nonzero off the law")
        call check(t, abs(psi(0.5_dp, 0.0_dp, g, rho)) > 0.0_dp, "psi nonzero |r| > mu N, v = 0")
        ! mu = 0: Psi = rho r
        call check_close(t, psi(0.3_dp, -0.2_dp, 0.0_dp, rho), rho*0.3_dp, "psi mu = 0")
        ! continuity across the boundaries
        call check_close(t, psi(0.2_dp, rho*(0.2_dp + g), g, rho), &
                         psi(0.2_dp, rho*(0.2_dp + g) + 1e-14_dp, g, rho), &
                         "psi continuous at a = 0", atol=1e-13_dp)
    end subroutine test_psi_regions

    subroutine test_round_trip(t, h, odd, nt)
        type(test_counter_t), intent(inout) :: t
        integer, intent(in) :: h, nt
        logical, intent(in) :: odd
        type(basis_t) :: b
        type(error_type), allocatable :: error
        real(dp), allocatable :: c(:), c2(:), u(:), dc(:), w(:)
        complex(dp), allocatable :: cw(:)
        character(len=40) :: tag
        integer :: i
        real(dp) :: eps, th, omega, q1, q2

        write (tag, '(a,i0,a,l1,a,i0)') "H=", h, " odd=", odd, " nt=", nt
        call new_basis(b, h, odd, nt, error)
        call check_error(t, error, "basis build "//trim(tag), .false.)
        if (allocated(error)) return
        allocate (c(b%nb), c2(b%nb), dc(b%nb), u(nt), w(nt), cw(nt/2 + 1))
        call random_number(c)
        c = c - 0.5_dp
        call b%synthesize(c, u, cw)
        call check_close(t, u, naive_synthesis(b, c), "synthesis vs naive DFT "//trim(tag), &
                         atol=1e-13_dp)
        call b%analyse(u, c2, cw)
        call check_close(t, c2, c, "round trip "//trim(tag), atol=1e-13_dp)
        ! analysis of arbitrary samples = naive projection
        call random_number(w)
        call b%analyse(w, c2, cw)
        call check_close(t, c2, naive_analysis(b, w), "analysis vs naive DFT "//trim(tag), &
                         atol=1e-13_dp)
        ! time derivative by finite differences of the synthesized function (t in units 1/omega)
        omega = 1.7_dp
        call b%derivative(c, omega, dc)
        eps = 1.0e-6_dp
        do i = 1, 3
            th = 0.37_dp*i
            call check_close(t, eval(dc, th), (eval(c, th + eps) - eval(c, th - eps))/ &
                             (2*eps/omega), "derivative "//trim(tag), rtol=1e-6_dp, atol=1e-6_dp)
        end do
        ! quadrature exactness: mean of the product of two series equals Parseval's sum
        call random_number(c2)
        call b%synthesize(c2, w, cw)
        q1 = sum(u*w)/nt
        q2 = 0.5_dp*dot_product(c, c2)
        if (b%has_zero) q2 = q2 + 0.5_dp*c(b%i0)*c2(b%i0)
        call check_close(t, q1, q2, "quadrature of products exact "//trim(tag), atol=1e-13_dp)
        call b%destroy()

    contains

        real(dp) function eval(cc, theta)
            real(dp), intent(in) :: cc(:), theta
            integer :: m
            eval = 0.0_dp
            if (b%has_zero) eval = cc(b%i0)
            do m = 1, b%nharm
                eval = eval + cc(b%icos(m))*cos(b%harm(m)*theta) + cc(b%icos(m) + 1)* &
                       sin(b%harm(m)*theta)
            end do
        end function eval
    end subroutine test_round_trip

    !> A = P diag(s) Q from the spectrum of s equals the dense product, column by column.
    subroutine test_stick_product(t, h, odd, nt)
        type(test_counter_t), intent(inout) :: t
        integer, intent(in) :: h, nt
        logical, intent(in) :: odd
        type(basis_t) :: b
        type(error_type), allocatable :: error
        real(dp), allocatable :: s(:), a(:, :), e(:), u(:), col(:)
        complex(dp), allocatable :: cw(:)
        integer :: q
        character(len=40) :: tag

        write (tag, '(a,i0,a,l1,a,i0)') "H=", h, " odd=", odd, " nt=", nt
        call new_basis(b, h, odd, nt, error)
        if (allocated(error)) return
        allocate (s(nt), a(b%nb, b%nb), e(b%nb), u(nt), col(b%nb), cw(nt/2 + 1))
        call random_number(s)
        s = merge(1.0_dp, 0.0_dp, s > 0.4_dp)
        u = s
        call b%fft%forward(u, cw)
        cw = cw/nt
        call b%stick_product(cw, a)
        do q = 1, b%nb
            e = 0.0_dp
            e(q) = 1.0_dp
            u = s*naive_synthesis(b, e)
            col = naive_analysis(b, u)
            call check_close(t, a(:, q), col, "stick product column "//trim(tag), atol=1e-12_dp)
        end do
        call b%destroy()
    end subroutine test_stick_product

    subroutine test_bad_sizes(t)
        type(test_counter_t), intent(inout) :: t
        type(basis_t) :: b
        type(error_type), allocatable :: error
        call new_basis(b, 30, .false., 60, error)
        call check_error(t, error, "too few samples rejected", .true., &
                         [character(len=40) :: "samples = 60", "too few samples"])
        call new_basis(b, -1, .false., 60, error)
        call check_error(t, error, "negative harmonics rejected", .true., &
                         [character(len=40) :: "harmonics = -1"])
    end subroutine test_bad_sizes
end module test_basis
