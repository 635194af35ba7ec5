!> The Jenkins element (1D: a spring k_t in series with a Coulomb slider) across the three
!> methods, against independent truth, on a damped 2-DOF structure (M = I, K = [2 -1; -1 1],
!> C = 0.02 I, 1.0 cos(1.2 t) on DOF 1) whose DOF 2 rubs on the ground through the element
!> (mu N = 0.3, k_t = 2) and sticks and slips twice a period (26% of it stuck):
!> - the exact reference converges: energy balance, the force within mu N and on it where
!>   the slider slips (against the slip), the spring law r = -k_t (x_2 - s) at every sample,
!>   two stick phases;
!> - implicit Euler started on the orbit (the forcing's phase put where the spring is
!>   unloaded in a stick phase, so that Euler's unloaded start is the orbit's state)
!>   converges to it at first order: the error falls tenfold per decade of steps;
!> - the weighted residual converges to it as H grows;
!> - its monodromy matrix (with the slider) against differences of the period map: central
!>   differences at a stuck instant; at the shooting section, where the slider slips, central
!>   differences in the directions along which the map is smooth and one-sided ones (towards
!>   a loaded spring) across the slip boundary (see test_monodromy);
!> - limits: k_t -> infinity gives the rigid Coulomb reference (as k_t^-1/2: the slider
!>   reloads over a time ~ sqrt(mu N / (k_t |a|)) at each reversal); mu N -> infinity the
!>   linear structure with the spring k_t on DOF 2 (closed form, per harmonic).
module test_jenkins
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, real_text
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t, sample_reference, &
        reference_energy_error
    use stickslip_reference_start, only: solve_reference_from_starts, reference_start_options_t
    use stickslip_flow, only: flow_t
    use stickslip_contact_law, only: state_stick, state_slip
    use testing, only: test_counter_t, check, check_error
    implicit none
    private
    public :: run_jenkins_tests, linear_response, central_differences

    !> The structure's forcing frequency, the element's slip force mu N and stiffness k_t.
    real(dp), parameter :: omega = 1.2_dp, mun = 0.3_dp, kt = 2.0_dp

contains

    subroutine run_jenkins_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        call reference(t, jenkins_model(kt, mun, 0.0_dp), res, "seed-like")
        if (.not. res%converged) return
        call test_reference_law(t, res)
        call test_monodromy(t, res)
        call test_hbm_converges(t, res)
        call test_euler_first_order(t, res)
        call test_rigid_limit(t)
        call test_stuck_limit(t)
    end subroutine run_jenkins_tests

    !> The 2-DOF structure with a Jenkins contact on DOF 2 (stiffness `k`, slip force `f`; k = 0
    !> the rigid Coulomb contact), forced by 1.0 cos(omega t + phase) on DOF 1.
    function jenkins_model(k, f, phase) result(m)
        real(dp), intent(in) :: k, f, phase
        type(model_t) :: m
        m%ndof = 2
        m%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        m%stiffness = reshape([2.0_dp, -1.0_dp, -1.0_dp, 1.0_dp], [2, 2])
        m%damping = 0.02_dp*m%mass
        m%omega = omega
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [1.0_dp]
        m%force_phase = [phase]
        m%contact_dof = [2]
        m%contact_dof2 = [0]
        m%mu = [f]
        m%normal_load = [1.0_dp]
        if (k > 0.0_dp) m%tangential_stiffness = [k]
    end function jenkins_model

    !> The exact reference of `m` (weighted-residual start, 1024 samples): converged, its
    !> energy balance within 1e-9 of the forcing's work.
    subroutine reference(t, m, res, name, bracket_steps)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(out) :: res
        character(len=*), intent(in) :: name
        integer, intent(in), optional :: bracket_steps
        type(reference_start_options_t) :: o
        type(error_type), allocatable :: error
        o%samples = 1024
        if (present(bracket_steps)) o%bracket_steps = bracket_steps
        call solve_reference_from_starts(m, o, res, error)
        call check_error(t, error, "jenkins: reference ("//name//"): no error", .false.)
        if (allocated(error)) return
        call check(t, res%converged, "jenkins: reference ("//name//") converged", &
                   res%diagnosis)
        if (.not. res%converged) return
        call check(t, res%work_forcing > 0.0_dp .and. reference_energy_error(res) < 1.0e-9_dp, &
                   "jenkins: reference ("//name//"): energy balance within 1e-9", &
                   "error "//real_text(reference_energy_error(res)))
    end subroutine reference

    !> Coulomb's law of the slider and the spring's at every sample of the reference: |r| <=
    !> mu N (1 + 1e-9), |r| = mu N against the slip velocity where the slider slips, r = -k_t
    !> (x_2 - s); the contact sticks part of the period, in two phases.
    subroutine test_reference_law(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        real(dp) :: spring, slip_limit, slip_sign
        logical, allocatable :: slip(:)
        call check(t, size(res%s, 2) == 1 .and. size(res%r, 2) == 1, &
                   "jenkins: reference: one channel, one slider state")
        if (size(res%s, 2) /= 1) return
        slip = res%state(:, 1) == state_slip
        call check(t, maxval(abs(res%r(:, 1))) <= mun*(1.0_dp + 1.0e-9_dp) .and. &
                   maxval(abs(res%r(:, 1))) >= mun*(1.0_dp - 1.0e-9_dp), &
                   "jenkins: reference: |r| <= mu N, reached", &
                   "max |r| / mu N - 1 = "//real_text(maxval(abs(res%r(:, 1)))/mun - 1.0_dp))
        slip_limit = maxval(abs(abs(res%r(:, 1)) - mun), mask=slip)
        slip_sign = maxval(res%r(:, 1)*res%v(:, 2), mask=slip)
        call check(t, count(slip) > 0 .and. slip_limit <= 1.0e-9_dp*mun .and. &
                   slip_sign <= 0.0_dp, "jenkins: reference: slipping, r = -mu N sign(v_2)", &
                   "||r| - mu N| "//real_text(slip_limit)//", max r v_2 "// &
                   real_text(slip_sign))
        spring = maxval(abs(res%r(:, 1) + kt*(res%x(:, 2) - res%s(:, 1))))
        call check(t, spring <= 1.0e-9_dp*mun, "jenkins: reference: r = -k_t (x_2 - s)", &
                   "worst "//real_text(spring))
        call check(t, res%stick_phases(1) == 2 .and. res%stick_fraction(1) > 0.1_dp .and. &
                   res%stick_fraction(1) < 0.5_dp .and. &
                   abs(count(res%state(:, 1) == state_stick)/real(size(res%t), dp) - &
                       res%stick_fraction(1)) < 0.01_dp, &
                   "jenkins: reference: sticks in two phases (26% of the period)", &
                   "phases "//real_text(real(res%stick_phases(1), dp))//", share "// &
                   real_text(res%stick_fraction(1)))
    end subroutine test_reference_law

    !> The monodromy matrix against differences of the period map.
    !>
    !> At an instant where the slider sticks (the sample of least |r|), the period map is
    !> smooth: the monodromy of flow%period_map there equals its central differences.
    !>
    !> At the shooting section (where the contact slips fastest) the slider slips on the limit
    !> |k_t (x_2 - s)| = mu N, and the period map has a kink across that surface: a
    !> perturbation that unloads the spring starts stuck and slips again once the spring is
    !> reloaded (the perturbation is forgotten, to second order), one that loads it beyond the
    !> limit is projected back onto it at the start (the slider yields at once: the flow's
    !> start_states), so that along s from the loading side the map does not move (its
    !> column of s is 0 there). res%monodromy is the derivative from the loading side
    !> (central differences give the mean of both sides in the columns of x_2 and s:
    !> measured 0.34 of the largest entry off). It is checked
    !> along a basis where that derivative is defined: central differences along x_1, v_1, v_2
    !> and x_2 + s (the spring's force unchanged) and a one-sided second-order difference
    !> along s towards the loading side.
    subroutine test_monodromy(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(flow_t) :: flow
        type(error_type), allocatable :: error
        real(dp), allocatable :: z0(:), z1(:), fd(:, :), mono(:, :), dirs(:, :), md(:, :)
        real(dp) :: r0, h, worst
        real(dp), allocatable :: zp(:), zq(:)
        integer :: nz, k
        flow = res%flow
        nz = flow%nz
        call check(t, nz == 5 .and. all(shape(res%monodromy) == [5, 5]), &
                   "jenkins: monodromy of [x; v; s] is 5 x 5")
        if (nz /= 5) return
        ! a stuck instant: every direction, central differences
        k = minloc(abs(res%r(:, 1)), 1, mask=res%state(:, 1) == state_stick)
        z0 = [res%x(k, :), res%v(k, :), res%s(k, :)]
        allocate (z1(nz), mono(nz, nz))
        call flow%period_map(res%t(k), z0, z1, error, mono=mono)
        call check_error(t, error, "jenkins: period map from a stuck instant", .false.)
        if (allocated(error)) return
        call check(t, maxval(abs(z1 - z0)) <= 1.0e-9_dp*maxval(abs(z0)), &
                   "jenkins: the sampled stuck state is on the periodic orbit", &
                   real_text(maxval(abs(z1 - z0))))
        call central_differences(flow, res%t(k), z0, fd, error)
        call check_error(t, error, "jenkins: perturbed period maps (stuck)", .false.)
        if (allocated(error)) return
        worst = maxval(abs(fd - mono))/maxval(abs(mono))
        call check(t, worst <= 1.0e-5_dp, "jenkins: monodromy at a stuck instant = central "// &
                   "differences of the period map", "relative "//real_text(worst))

        ! the section: the slider slips (|r| = mu N)
        z0 = res%orbit%phase_y(1:nz, 1)
        r0 = -kt*(z0(2) - z0(5))
        call check(t, abs(abs(r0) - mun) <= 1.0e-9_dp*mun, &
                   "jenkins: the shooting section is in a slip phase", real_text(r0))
        allocate (dirs(nz, nz), md(nz, nz))
        dirs = 0.0_dp
        dirs(1, 1) = 1.0_dp
        dirs(3, 2) = 1.0_dp
        dirs(4, 3) = 1.0_dp
        dirs([2, 5], 4) = 1.0_dp
        do k = 1, 4
            h = 1.0e-6_dp*max(maxval(abs(z0)*dirs(:, k)), 1.0e-2_dp)
            call flow%period_map(res%t_section, z0 + h*dirs(:, k), z1, error)
            if (allocated(error)) exit
            md(:, k) = z1
            call flow%period_map(res%t_section, z0 - h*dirs(:, k), z1, error)
            if (allocated(error)) exit
            md(:, k) = (md(:, k) - z1)/(2.0_dp*h)
        end do
        if (.not. allocated(error)) then
            ! s towards the loading side: r = -k_t (x_2 - s) grows in magnitude
            dirs(5, 5) = sign(1.0_dp, r0)
            h = 1.0e-6_dp*max(abs(z0(5)), 1.0e-2_dp)
            allocate (zp(nz), zq(nz))
            call flow%period_map(res%t_section, z0, z1, error)
            if (.not. allocated(error)) call flow%period_map(res%t_section, z0 + h*dirs(:, 5), &
                                                             zp, error)
            if (.not. allocated(error)) call flow%period_map(res%t_section, &
                                                             z0 + 2.0_dp*h*dirs(:, 5), zq, error)
            if (.not. allocated(error)) md(:, 5) = (-3.0_dp*z1 + 4.0_dp*zp - zq)/(2.0_dp*h)
        end if
        call check_error(t, error, "jenkins: perturbed period maps (section)", .false.)
        if (allocated(error)) return
        worst = maxval(abs(md - matmul(res%monodromy, dirs)))/maxval(abs(res%monodromy))
        call check(t, worst <= 1.0e-5_dp, "jenkins: monodromy at the (slipping) section = "// &
                   "differences of the period map along x1, v1, v2, x2 + s, and s loading", &
                   "relative "//real_text(worst))
    end subroutine test_monodromy

    !> Central differences of the period map from z0 at t0: fd(:, k) = dz1/dz0_k, steps 1e-6
    !> of max(|z0_k|, 1e-2).
    subroutine central_differences(flow, t0, z0, fd, error)
        type(flow_t), intent(inout) :: flow
        real(dp), intent(in) :: t0, z0(:)
        real(dp), allocatable, intent(out) :: fd(:, :)
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: zp(:), z1(:)
        real(dp) :: h
        integer :: k, nz
        nz = size(z0)
        allocate (fd(nz, nz), z1(nz))
        do k = 1, nz
            h = 1.0e-6_dp*max(abs(z0(k)), 1.0e-2_dp)
            zp = z0
            zp(k) = zp(k) + h
            call flow%period_map(t0, zp, z1, error)
            if (allocated(error)) return
            fd(:, k) = z1
            zp(k) = z0(k) - h
            call flow%period_map(t0, zp, z1, error)
            if (allocated(error)) return
            fd(:, k) = (fd(:, k) - z1)/(2.0_dp*h)
        end do
    end subroutine central_differences

    !> The weighted residual converges to the reference as H grows: the max displacement
    !> error (relative) falls at every step of H = 10, 20, 40, 80, by more than 2 from 10
    !> to 80 and is below 2e-3 at 80 (measured 1.9e-2, 3.2e-3, 1.7e-3, 1.2e-3: the kinks of
    !> r' at the slip events converge slowly).
    subroutine test_hbm_converges(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: e(4)
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        integer :: k
        call sample_reference(res, 1024, xr, vr, rr, error)
        call check_error(t, error, "jenkins: reference sampled", .false.)
        if (allocated(error)) return
        do k = 1, 4
            o%harmonics = 10*2**(k - 1)
            o%samples = 1024
            call solve_periodic(jenkins_model(kt, mun, 0.0_dp), o, sol, error)
            if (allocated(error) .or. .not. sol%converged) then
                call check(t, .false., "jenkins: weighted residual H = "// &
                           real_text(real(o%harmonics, dp))//" converged")
                return
            end if
            e(k) = maxval(abs(sol%x - xr))/maxval(abs(xr))
        end do
        call check(t, all(e(2:4) < e(1:3)) .and. e(4) < e(1)/2.0_dp .and. e(4) < 2.0e-3_dp, &
                   "jenkins: the weighted residual converges to the reference as H grows", &
                   "errors at H = 10, 20, 40, 80: "//real_text(e(1))//", "//real_text(e(2))// &
                   ", "//real_text(e(3))//", "//real_text(e(4)))
    end subroutine test_hbm_converges

    !> Implicit Euler converges to the reference at first order. Euler's slider starts
    !> unloaded (r = 0), so the forcing's phase is put where the reference's spring is
    !> unloaded in a stick phase (t* from the samples, refined once by Newton on r(t*) = 0):
    !> started from the reference's x, v there, Euler starts on the orbit and two periods
    !> suffice. The max displacement error of the second period (relative), at 2000, 20000
    !> and 200000 steps per period, falls by 5 to 20 per decade and is below 1e-4 at 200000
    !> (measured 7.9e-3, 7.9e-4, 7.9e-5).
    subroutine test_euler_first_order(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(reference_result_t) :: shifted
        type(euler_options_t) :: o
        type(euler_result_t) :: e
        type(error_type), allocatable :: error
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: tz, phase, err(3), rdot
        integer :: k, it
        ! a zero of the spring's force in a stick phase
        do k = 1, size(res%t) - 1
            if (res%state(k, 1) == state_stick .and. res%state(k + 1, 1) == state_stick .and. &
                res%r(k, 1)*res%r(k + 1, 1) <= 0.0_dp) exit
        end do
        call check(t, k < size(res%t), "jenkins: the spring unloads in a stick phase")
        if (k == size(res%t)) return
        tz = res%t(k) + (res%t(k + 1) - res%t(k))*res%r(k, 1)/(res%r(k, 1) - res%r(k + 1, 1))
        phase = omega*tz
        do it = 1, 2
            call reference(t, jenkins_model(kt, mun, phase), shifted, "phase shifted")
            if (.not. shifted%converged) return
            ! Newton on r(0) = 0: r' = -k_t v_2 while stuck
            rdot = -kt*shifted%v(1, 2)
            phase = phase - omega*shifted%r(1, 1)/rdot
        end do
        call check(t, abs(shifted%r(1, 1)) <= 1.0e-8_dp*mun .and. &
                   shifted%state(1, 1) == state_stick, &
                   "jenkins: the shifted reference starts stuck with the spring unloaded", &
                   "r(0) = "//real_text(shifted%r(1, 1)))
        do k = 1, 3
            o%steps_per_period = 2000*10**(k - 1)
            o%max_periods = 2
            call integrate_euler(jenkins_model(kt, mun, phase), o, e, error, &
                                 x0=shifted%x(1, :), v0=shifted%v(1, :))
            call check_error(t, error, "jenkins: Euler integrated", .false.)
            if (allocated(error)) return
            call sample_reference(shifted, o%steps_per_period, xr, vr, rr, error)
            if (allocated(error)) return
            err(k) = maxval(abs(e%x - xr))/maxval(abs(xr))
        end do
        call check(t, err(1)/err(2) > 5.0_dp .and. err(1)/err(2) < 20.0_dp .and. &
                   err(2)/err(3) > 5.0_dp .and. err(2)/err(3) < 20.0_dp .and. &
                   err(3) < 1.0e-4_dp, "jenkins: implicit Euler converges to the "// &
                   "reference at first order", "errors at 2000, 20000, 200000 steps: "// &
                   real_text(err(1))//", "//real_text(err(2))//", "//real_text(err(3)))
    end subroutine test_euler_first_order

    !> k_t -> infinity: the Jenkins reference tends to the rigid Coulomb one (the same model
    !> without tangential_stiffness) as k_t^-1/2: at each reversal the slider sticks while the
    !> spring reloads by 2 mu N / k_t, a time ~ sqrt(mu N / (k_t |a_2|)), which shifts the
    !> force's reversal. Measured (max displacement difference, relative): 3.8e-3 at k_t = 1e4,
    !> 3.8e-4 at 1e6 (1.2e-2 at 1e3, 1.2e-3 at 1e5).
    subroutine test_rigid_limit(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: rigid, stiff
        real(dp) :: d(2)
        integer :: k
        call reference(t, jenkins_model(0.0_dp, mun, 0.0_dp), rigid, "rigid Coulomb")
        if (.not. rigid%converged) return
        do k = 1, 2
            ! the stiff spring's oscillations (sqrt(k_t) rad/s) need a finer event grid
            call reference(t, jenkins_model(10.0_dp**(2*k + 2), mun, 0.0_dp), stiff, &
                           "k_t = 1e"//achar(48 + 2*k + 2), bracket_steps=1000*10**(k - 1))
            if (.not. stiff%converged) return
            d(k) = maxval(abs(stiff%x - rigid%x))/maxval(abs(rigid%x))
        end do
        call check(t, d(1) < 1.0e-2_dp .and. d(2) < 1.0e-3_dp .and. d(1)/d(2) > 7.0_dp .and. &
                   d(1)/d(2) < 14.0_dp, "jenkins: k_t -> infinity gives the rigid Coulomb "// &
                   "reference (as k_t^-1/2)", "differences at k_t = 1e4, 1e6: "// &
                   real_text(d(1))//", "//real_text(d(2)))
    end subroutine test_rigid_limit

    !> mu N -> infinity (1e4): the contact never slips and every method gives the linear
    !> structure with the spring k_t added on DOF 2, solved here per harmonic (harmonic 1:
    !> X = (K + k_t e2 e2^T - omega^2 M + i omega C)^-1 F): the reference and the weighted
    !> residual to 1e-8 of the amplitude.
    subroutine test_stuck_limit(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        type(model_t) :: m
        real(dp), allocatable :: x(:, :), stiffness(:, :)
        real(dp) :: d
        m = jenkins_model(kt, 1.0e4_dp, 0.0_dp)
        call reference(t, m, res, "stuck")
        if (.not. res%converged) return
        stiffness = m%stiffness
        stiffness(2, 2) = stiffness(2, 2) + kt
        x = linear_response(m%mass, m%damping, stiffness, omega, [1.0_dp, 0.0_dp], res%t)
        d = maxval(abs(res%x - x))/maxval(abs(x))
        call check(t, d <= 1.0e-8_dp .and. res%stick_fraction(1) == 1.0_dp, &
                   "jenkins: mu N -> infinity: the reference is the structure with the "// &
                   "spring k_t", "relative "//real_text(d))
        o%harmonics = 5
        o%samples = 64
        call solve_periodic(m, o, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged, &
                   "jenkins: stuck: weighted residual converged")
        if (allocated(error) .or. .not. sol%converged) return
        x = linear_response(m%mass, m%damping, stiffness, omega, [1.0_dp, 0.0_dp], sol%t)
        d = maxval(abs(sol%x - x))/maxval(abs(x))
        call check(t, d <= 1.0e-8_dp, "jenkins: mu N -> infinity: the weighted residual is "// &
                   "the structure with the spring k_t", "relative "//real_text(d))
    end subroutine test_stuck_limit

    !> The response x(t_k) (samples x N) of the linear structure M x'' + C x' + K x = Re(f
    !> e^(i omega t)) at the instants t, by a complex solve of (K - omega^2 M + i omega C) X
    !> = f (Gaussian elimination with partial pivoting).
    function linear_response(mass, damping, stiffness, w, f, times) result(x)
        real(dp), intent(in) :: mass(:, :), damping(:, :), stiffness(:, :), w, f(:), times(:)
        real(dp), allocatable :: x(:, :)
        complex(dp), allocatable :: z(:, :), b(:), row(:)
        complex(dp) :: piv, tmp
        integer :: n, i, k, p
        n = size(f)
        z = cmplx(stiffness - w**2*mass, w*damping, dp)
        b = cmplx(f, 0.0_dp, dp)
        do k = 1, n
            p = k - 1 + maxloc(abs(z(k:n, k)), 1)
            if (p /= k) then
                row = z(k, :)
                z(k, :) = z(p, :)
                z(p, :) = row
                tmp = b(k)
                b(k) = b(p)
                b(p) = tmp
            end if
            do i = k + 1, n
                piv = z(i, k)/z(k, k)
                z(i, k:n) = z(i, k:n) - piv*z(k, k:n)
                b(i) = b(i) - piv*b(k)
            end do
        end do
        do i = n, 1, -1
            b(i) = (b(i) - sum(z(i, i + 1:n)*b(i + 1:n)))/z(i, i)
        end do
        allocate (x(size(times), n))
        do k = 1, size(times)
            x(k, :) = real(b*exp(cmplx(0.0_dp, w*times(k), dp)), dp)
        end do
    end function linear_response
end module test_jenkins
