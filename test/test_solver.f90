!> The solver paths of the weighted-residual solve (hbm_options_t%solver): semismooth Newton
!> with LU from warm starts (stickslip_newton) against MINPACK's hybrj, the reference. The
!> same converged solutions to the tolerance on the seed case, the 4-DOF chain and a chain
!> with 20 contacts at several H (all and odd harmonics); a start r_start taken by Newton;
!> contacts stuck over the whole period (a singular Jacobian: the fallback to hybrj);
!> solve_newton on small piecewise-linear systems with known roots; option validation.
module test_solver
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options, newton_min_unknowns
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_newton, only: newton_options_t, newton_report_t, solve_newton, &
        newton_converged, newton_singular
    use stickslip_minpack, only: hybrj_options_t, hybrj_report_t, solve_hybrj
    use stickslip_powell, only: solve_powell
    use fixtures, only: seed_model, chain_model
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_solver_tests, contact_chain_model

    !> F(x) = A x + max(x, 0) - b (piecewise linear, A + D nonsingular on every piece).
    type, extends(nonlinear_system_t) :: kink_t
        real(dp), allocatable :: a(:, :), b(:)
    contains
        procedure :: residual => kink_residual
        procedure :: jacobian => kink_jacobian
    end type kink_t

    !> Broyden's tridiagonal function (a smooth MINPACK test problem):
    !> F_i = (3 - 2 x_i) x_i - x_{i-1} - 2 x_{i+1} + 1, x_0 = x_{n+1} = 0.
    type, extends(nonlinear_system_t) :: broyden_t
    contains
        procedure :: residual => broyden_residual
        procedure :: jacobian => broyden_jacobian
    end type broyden_t

contains

    subroutine run_solver_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_newton_kink(t)
        call test_newton_singular(t)
        call test_newton_mixed(t)
        call test_powell(t)
        call test_options(t)
        call test_seed(t)
        call test_chain(t)
        call test_contact_chain(t)
        call test_warm_start(t)
        call test_stuck(t)
    end subroutine run_solver_tests

    !> A chain of `n` unit masses (spring 1 to the next, spring 1 to ground at the first),
    !> Rayleigh damping 0.01 M + 0.01 K, forcing 1 cos(omega t) + 0.3 cos(3 omega t) on the
    !> last DOF and a ground contact on every DOF with mu N = 0.05 + 0.02 (j mod 5).
    function contact_chain_model(n, omega) result(m)
        integer, intent(in) :: n
        real(dp), intent(in) :: omega
        type(model_t) :: m
        integer :: i
        m%ndof = n
        allocate (m%mass(n, n), m%stiffness(n, n))
        m%mass = 0.0_dp
        m%stiffness = 0.0_dp
        do i = 1, n
            m%mass(i, i) = 1.0_dp
            m%stiffness(i, i) = 2.0_dp
            if (i < n) then
                m%stiffness(i, i + 1) = -1.0_dp
                m%stiffness(i + 1, i) = -1.0_dp
            end if
        end do
        m%stiffness(n, n) = 1.0_dp
        m%damping = 0.01_dp*m%mass + 0.01_dp*m%stiffness
        m%omega = omega
        m%force_dof = [n, n]
        m%force_harmonic = [1, 3]
        m%force_amplitude = [1.0_dp, 0.3_dp]
        m%force_phase = [0.0_dp, 0.4_dp]
        m%contact_dof = [(i, i=1, n)]
        m%contact_dof2 = [(0, i=1, n)]
        m%mu = [(0.05_dp + 0.02_dp*mod(i, 5), i=1, n)]
        m%normal_load = [(1.0_dp, i=1, n)]
    end function contact_chain_model

    !> Solve `m` with hybrj and with Newton (opts as given otherwise); both converge to the
    !> same friction coefficients (to the tolerance: 1e-6 of the friction limit).
    subroutine compare_paths(t, m, h, odd, name, expect_newton)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        integer, intent(in) :: h
        logical, intent(in) :: odd
        character(len=*), intent(in) :: name
        logical, intent(in) :: expect_newton
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sh, sn
        type(error_type), allocatable :: error
        character(len=80) :: tag
        write (tag, '(a,": H = ",i0,a)') name, h, merge(" odd", " all", odd)
        o%harmonics = h
        o%odd_only = odd
        o%samples = 512
        o%want_samples = .false.
        o%solver = 'hybrj'
        call solve_periodic(m, o, sh, error)
        call check_error(t, error, trim(tag)//" hybrj runs", .false.)
        if (allocated(error)) return
        o%solver = 'newton'
        call solve_periodic(m, o, sn, error)
        call check_error(t, error, trim(tag)//" newton runs", .false.)
        if (allocated(error)) return
        call check(t, sh%converged .and. sn%converged, trim(tag)//" both converge")
        call check(t, sh%newton_calls == 0, trim(tag)//" hybrj path makes no Newton call")
        if (expect_newton) call check(t, sn%newton_calls > 0, trim(tag)//" newton path used")
        call check(t, sn%fnorm <= o%tol*sn%fscale, trim(tag)//" newton meets the test")
        call check_close(t, sn%fscale, sh%fscale, trim(tag)//" same fscale", rtol=1.0e-14_dp)
        call check_close(t, reshape(sn%rcoef, [size(sn%rcoef)]), &
                         reshape(sh%rcoef, [size(sh%rcoef)]), trim(tag)//" same forces", &
                         rtol=0.0_dp, atol=1.0e-6_dp*maxval(m%mu*m%normal_load))
        call check_close(t, reshape(sn%xcoef, [size(sn%xcoef)]), &
                         reshape(sh%xcoef, [size(sh%xcoef)]), trim(tag)//" same motion", &
                         rtol=0.0_dp, atol=1.0e-6_dp*maxval(abs(sh%xcoef)))
        call check(t, sn%diagnostics%count(3) == sh%diagnostics%count(3), &
                   trim(tag)//" same untrusted findings")
    end subroutine compare_paths

    subroutine test_seed(t)
        type(test_counter_t), intent(inout) :: t
        call compare_paths(t, seed_model(), 10, .false., "seed", .true.)
        call compare_paths(t, seed_model(), 31, .false., "seed", .true.)
        call compare_paths(t, seed_model(), 64, .false., "seed", .true.)
        call compare_paths(t, seed_model(), 63, .true., "seed", .true.)
        ! a forcing harmonic above the ladder's first rung (3): the rungs start at 5
        block
            type(model_t) :: m
            m = seed_model()
            m%force_harmonic = [5]
            m%omega = 0.9_dp
            call compare_paths(t, m, 31, .true., "seed forced at 5 omega", .true.)
        end block
    end subroutine test_seed

    subroutine test_chain(t)
        type(test_counter_t), intent(inout) :: t
        call compare_paths(t, chain_model(), 7, .false., "chain", .true.)
        call compare_paths(t, chain_model(), 15, .false., "chain", .true.)
        call compare_paths(t, chain_model(), 40, .false., "chain", .true.)
    end subroutine test_chain

    subroutine test_contact_chain(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        type(error_type), allocatable :: error
        m = contact_chain_model(20, 0.3_dp)
        call compare_paths(t, m, 3, .false., "20 contacts", .false.)
        call compare_paths(t, m, 6, .false., "20 contacts", .true.)
        call compare_paths(t, m, 7, .true., "20 contacts", .true.)
        ! 'auto' takes Newton at 260 unknowns and reaches the hybrj answer as above
        o%harmonics = 6
        o%samples = 512
        o%want_samples = .false.
        call solve_periodic(m, o, s, error)
        call check_error(t, error, "20 contacts auto runs", .false.)
        if (allocated(error)) return
        call check(t, 13*20 >= newton_min_unknowns .eqv. s%newton_calls > 0, &
                   "20 contacts: auto picks Newton above newton_min_unknowns")
    end subroutine test_contact_chain

    !> A start r_start from fewer harmonics is a warm start: Newton at H directly.
    subroutine test_warm_start(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s1, s2, sh
        type(error_type), allocatable :: error
        o%samples = 512
        o%want_samples = .false.
        o%harmonics = 20
        o%solver = 'hybrj'
        call solve_periodic(seed_model(), o, s1, error)
        if (allocated(error)) return
        o%harmonics = 40
        call solve_periodic(seed_model(), o, sh, error)
        if (allocated(error)) return
        o%solver = 'newton'
        call solve_periodic(seed_model(), o, s2, error, r_start=s1%rcoef)
        call check_error(t, error, "warm start runs", .false.)
        if (allocated(error)) return
        call check(t, s2%converged .and. s2%newton_calls == 1 .and. s2%hybrj_calls == 0, &
                   "warm start: one Newton call, no hybrj")
        call check_close(t, reshape(s2%rcoef, [size(s2%rcoef)]), &
                         reshape(sh%rcoef, [size(sh%rcoef)]), "warm start: same forces", &
                         rtol=0.0_dp, atol=1.0e-6_dp*0.45_dp)
    end subroutine test_warm_start

    !> A contact stuck over the whole period: the mean force is undetermined (a singular
    !> Jacobian there); the Newton path returns hybrj's settled answer.
    subroutine test_stuck(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sh, sn
        type(error_type), allocatable :: error
        ! the 4-DOF chain with its ground contact stuck (the relative one slips)
        m = chain_model()
        m%mu(1) = 50.0_dp
        o%harmonics = 16
        o%samples = 512
        o%want_samples = .false.
        o%solver = 'hybrj'
        call solve_periodic(m, o, sh, error)
        if (allocated(error)) return
        o%solver = 'newton'
        call solve_periodic(m, o, sn, error)
        call check_error(t, error, "stuck: newton path runs", .false.)
        if (allocated(error)) return
        call check(t, sh%converged .and. sn%converged, "stuck: both converge")
        call check(t, sn%offset_undetermined(1) .and. sh%offset_undetermined(1), &
                   "stuck: contact stuck all period on both paths")
        ! Newton meets the target where the stuck set is settled, or hands a singular
        ! Jacobian to hybrj; either way the answer is hybrj's
        call check(t, sn%newton_calls > 0, "stuck: the Newton path was taken")
        call check_close(t, reshape(sn%rcoef, [size(sn%rcoef)]), &
                         reshape(sh%rcoef, [size(sh%rcoef)]), "stuck: same settled forces", &
                         rtol=0.0_dp, atol=1.0e-6_dp*maxval(abs(sh%rcoef)))
        ! a start near that answer: Newton at H meets the singular Jacobian (the stuck
        ! contact's mean force enters no equation) and hands over to hybrj
        block
            real(dp), allocatable :: start(:, :)
            type(hbm_solution_t) :: sf
            start = sh%rcoef
            start(2:3, 2) = start(2:3, 2) + 0.01_dp
            o%start = 'direct'
            call solve_periodic(m, o, sf, error, r_start=start)
            call check_error(t, error, "stuck: newton from a start runs", .false.)
            if (allocated(error)) return
            call check(t, sf%converged .and. sf%newton_calls == 1 .and. &
                       sf%newton_fallbacks == 1 .and. sf%hybrj_calls >= 1, &
                       "stuck: singular Jacobian handed to hybrj")
            call check_close(t, reshape(sf%rcoef, [size(sf%rcoef)]), &
                             reshape(sh%rcoef, [size(sh%rcoef)]), &
                             "stuck: same settled forces after the fallback", &
                             rtol=0.0_dp, atol=1.0e-6_dp*maxval(abs(sh%rcoef)))
        end block
    end subroutine test_stuck

    subroutine test_options(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(error_type), allocatable :: error
        call check(t, o%solver == 'auto', "solver defaults to auto")
        o%solver = 'lu'
        call validate_options(o, error)
        call check_error(t, error, "solver = 'lu' rejected", .true., ["opts%solver"])
        o%solver = 'newton'
        call validate_options(o, error)
        call check_error(t, error, "solver = 'newton' accepted", .false.)
    end subroutine test_options

    !> Known root of a piecewise-linear system; a start on the wrong piece still ends there.
    subroutine test_newton_kink(t)
        type(test_counter_t), intent(inout) :: t
        type(kink_t) :: sys
        type(newton_options_t) :: opts
        type(newton_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: x(3), root(3)
        sys%a = reshape([3.0_dp, 1.0_dp, 0.0_dp, 1.0_dp, 3.0_dp, 1.0_dp, 0.0_dp, 1.0_dp, &
                         3.0_dp], [3, 3])
        root = [1.0_dp, -2.0_dp, 0.5_dp]
        sys%b = matmul(sys%a, root) + max(root, 0.0_dp)
        x = [-1.0_dp, 1.0_dp, -1.0_dp]
        opts%ftarget = 1.0e-12_dp
        call solve_newton(sys, x, opts, rep, error)
        call check_error(t, error, "newton kink runs", .false.)
        call check(t, rep%outcome == newton_converged .and. rep%njev <= 5, &
                   "newton kink converges in a few steps")
        call check_close(t, x, root, "newton kink root", rtol=1.0e-12_dp, atol=1.0e-12_dp)
        opts%ftarget = 0.0_dp
        call solve_newton(sys, x, opts, rep, error)
        call check_error(t, error, "newton ftarget = 0 rejected", .true.)
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "newton ftarget = 0 is an input error")
    end subroutine test_newton_kink

    !> Chord steps and single-precision factorizations (n >= single_min_unknowns) reach the
    !> root of the all-double Newton iteration; a Jacobian that single precision cannot hold
    !> (the pivot screen turned off) is factorized again in double precision after its step
    !> fails, and the iteration still converges. (A Jacobian of condition 1e10 converged in
    !> single precision alone: its step errors lie where ||F|| hardly sees them.)
    subroutine test_newton_mixed(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 240
        type(kink_t) :: sys
        type(newton_options_t) :: opts, plain
        type(newton_report_t) :: rep, rep_plain
        type(error_type), allocatable :: error
        real(dp) :: x(n), x_plain(n), root(n)
        integer :: i, j
        allocate (sys%a(n, n))
        do j = 1, n
            do i = 1, n
                sys%a(i, j) = 0.3_dp*sin(real(3*i + 7*j, dp))/sqrt(real(n, dp))
            end do
            sys%a(j, j) = sys%a(j, j) + 2.0_dp
        end do
        root = [(cos(real(5*i, dp)), i=1, n)]
        sys%b = matmul(sys%a, root) + max(root, 0.0_dp)
        opts%ftarget = 1.0e-11_dp
        plain = opts
        plain%chord_ratio = 0.0_dp
        plain%single_min_unknowns = 0
        x = -root
        call solve_newton(sys, x, opts, rep, error)
        call check_error(t, error, "newton mixed runs", .false.)
        x_plain = -root
        call solve_newton(sys, x_plain, plain, rep_plain, error)
        call check_error(t, error, "newton plain runs", .false.)
        call check(t, rep%outcome == newton_converged .and. rep%single_lus >= 1 .and. &
                   rep_plain%outcome == newton_converged .and. rep_plain%single_lus == 0 .and. &
                   rep_plain%chord_steps == 0 .and. rep%double_retries == 0, &
                   "newton mixed: single-precision LUs, converged")
        call check_close(t, x, root, "newton mixed: the root", rtol=1.0e-10_dp, atol=1.0e-10_dp)
        call check_close(t, x, x_plain, "newton mixed = all-double Newton", rtol=1.0e-10_dp, &
                         atol=1.0e-10_dp)
        ! a Jacobian beyond single precision's range (entries 1e40) with the pivot screen
        ! turned off: the single-precision step is NaN and fails, the same step in double
        ! precision is taken
        sys%a = 1.0e40_dp*sys%a
        sys%b = matmul(sys%a, root) + max(root, 0.0_dp)
        opts%single_pivot_min = 0.0_dp
        opts%ftarget = 1.0e-11_dp*1.0e40_dp
        x = root + 0.01_dp
        call solve_newton(sys, x, opts, rep, error)
        call check_error(t, error, "newton out of single range runs", .false.)
        call check(t, rep%outcome == newton_converged .and. rep%single_lus >= 1 .and. &
                   rep%double_retries >= 1, &
                   "newton out of single range: the single step failed, double converged")
        call check_close(t, x, root, "newton out of single range: the root", &
                         rtol=1.0e-10_dp, atol=1.0e-10_dp)
    end subroutine test_newton_mixed

    !> Powell's hybrid method on LAPACK's QR (solve_powell) against MINPACK's hybrj: the same
    !> iterates up to roundoff, so the same evaluation counts, info and answer, on a smooth
    !> system (Broyden tridiagonal, n = 60, from x = -1) and on a piecewise-linear one (the
    !> kink system, n = 240); mode 2 without diag is an input error.
    subroutine test_powell(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 60, nk = 240
        type(broyden_t) :: smooth
        type(kink_t) :: kink
        type(hybrj_options_t) :: opts
        type(hybrj_report_t) :: rep_h, rep_p
        type(error_type), allocatable :: error
        real(dp) :: xh(n), xp(n), root(nk), kh(nk), kp(nk)
        integer :: i, j
        xh = -1.0_dp
        xp = -1.0_dp
        opts%xtol = 1.0e-13_dp
        call solve_hybrj(smooth, xh, opts, rep_h, error)
        call check_error(t, error, "powell: hybrj on Broyden's function runs", .false.)
        call solve_powell(smooth, xp, opts, rep_p, error)
        call check_error(t, error, "powell: solve_powell on Broyden's function runs", .false.)
        call check(t, rep_p%info == rep_h%info .and. rep_p%info == 1 .and. &
                   rep_p%nfev == rep_h%nfev .and. rep_p%njev == rep_h%njev, &
                   "powell: Broyden's function, same info and counts as hybrj")
        call check_close(t, xp, xh, "powell: Broyden's function, hybrj's root", &
                         rtol=1.0e-12_dp, atol=1.0e-12_dp)
        call check(t, rep_p%fnorm < 1.0e-12_dp, "powell: Broyden's function, ||F|| ~ 0")
        allocate (kink%a(nk, nk))
        do j = 1, nk
            do i = 1, nk
                kink%a(i, j) = 0.3_dp*sin(real(3*i + 7*j, dp))/sqrt(real(nk, dp))
            end do
            kink%a(j, j) = kink%a(j, j) + 2.0_dp
        end do
        root = [(cos(real(5*i, dp)), i=1, nk)]
        kink%b = matmul(kink%a, root) + max(root, 0.0_dp)
        kh = -root
        kp = -root
        opts%ftarget = 1.0e-10_dp
        call solve_hybrj(kink, kh, opts, rep_h, error)
        call check_error(t, error, "powell: hybrj on the kink system runs", .false.)
        call solve_powell(kink, kp, opts, rep_p, error)
        call check_error(t, error, "powell: solve_powell on the kink system runs", .false.)
        call check(t, rep_p%target_met .and. rep_h%target_met .and. &
                   rep_p%nfev == rep_h%nfev .and. rep_p%njev == rep_h%njev, &
                   "powell: kink system, target met with hybrj's counts")
        call check_close(t, kp, root, "powell: kink system root", rtol=1.0e-9_dp, &
                         atol=1.0e-9_dp)
        opts%mode = 2
        call solve_powell(smooth, xp, opts, rep_p, error)
        call check_error(t, error, "powell: mode 2 without diag rejected", .true.)
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "powell: mode 2 without diag is an input error")
    end subroutine test_powell

    subroutine broyden_residual(self, x, f, stat)
        class(broyden_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        integer :: i, n
        n = size(x)
        do i = 1, n
            f(i) = (3.0_dp - 2.0_dp*x(i))*x(i) + 1.0_dp
            if (i > 1) f(i) = f(i) - x(i - 1)
            if (i < n) f(i) = f(i) - 2.0_dp*x(i + 1)
        end do
        if (stat /= 0) return
    end subroutine broyden_residual

    subroutine broyden_jacobian(self, x, jac, stat)
        class(broyden_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: jac(:, :)
        integer, intent(inout) :: stat
        integer :: i, n
        n = size(x)
        jac = 0.0_dp
        do i = 1, n
            jac(i, i) = 3.0_dp - 4.0_dp*x(i)
            if (i > 1) jac(i, i - 1) = -1.0_dp
            if (i < n) jac(i, i + 1) = -2.0_dp
        end do
        if (stat /= 0) return
    end subroutine broyden_jacobian

    !> A singular Jacobian is an outcome (the caller falls back), not an error.
    subroutine test_newton_singular(t)
        type(test_counter_t), intent(inout) :: t
        type(kink_t) :: sys
        type(newton_options_t) :: opts
        type(newton_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: x(2)
        ! A + D(x) = [[0 0] [0 1]] + D: singular for x(1) < 0
        sys%a = reshape([0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        sys%b = [1.0_dp, 1.0_dp]
        x = [-1.0_dp, 0.0_dp]
        opts%ftarget = 1.0e-12_dp
        call solve_newton(sys, x, opts, rep, error)
        call check_error(t, error, "newton singular runs", .false.)
        call check(t, rep%outcome == newton_singular, "newton singular reported")
        call check(t, all(x == [-1.0_dp, 0.0_dp]), "newton singular keeps the best point")
    end subroutine test_newton_singular

    subroutine kink_residual(self, x, f, stat)
        class(kink_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        f = matmul(self%a, x) + max(x, 0.0_dp) - self%b
        if (stat /= 0) return
    end subroutine kink_residual

    subroutine kink_jacobian(self, x, jac, stat)
        class(kink_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: jac(:, :)
        integer, intent(inout) :: stat
        integer :: i
        jac = self%a
        do i = 1, size(x)
            if (x(i) > 0.0_dp) jac(i, i) = jac(i, i) + 1.0_dp
        end do
        if (stat /= 0) return
    end subroutine kink_jacobian
end module test_solver
