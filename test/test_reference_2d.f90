!> The exact reference with 2D friction (slip phases whose direction turns, integrated by
!> exponential collocation under ode_tol; stickslip_flow_nonlinear) against independent
!> truth:
!> - the circular path of a point mass forced by a rotating force: the radius of the closed
!>   form, the force on the disk's edge, the energy balance, an error estimate stated;
!> - a 2D stick-slip orbit (the point mass under a weaker elliptical force sticks about
!>   half the period, in two phases): Coulomb's law at every sample (inside the disk when
!>   stuck, on its edge and against the slip velocity when slipping), the energy balance,
!>   implicit Euler started on the orbit converging to it at first order, the weighted
!>   residual converging to it as H grows;
!> - 2D friction on a contact that lifts off (the limit mu lambda varies, opens and sticks
!>   once a period): the normal law and Coulomb's law with the varying disk at every
!>   sample, the energy balance, implicit Euler and the weighted residual converging to it;
!> - a contact stuck all period (roundoff slip velocities at the start count as rest);
!> - ode_tol: the samples at 1e-6, 1e-8, 1e-10 against those at 1e-12, each within the
!>   error estimate the reference states, the estimate falling with the tolerance;
!> - a 2D Jenkins element on a contact that lifts off (sliders in the state, unloaded while
!>   open): the normal law, the spring's law, the disk and the slider's motion at every
!>   sample, the energy balance, the monodromy, implicit Euler and the weighted residual
!>   converging to it;
!> - the monodromy matrix against central differences of the period map, in a 2D slip
!>   (circle, the stick-slip orbit's section), at a 2D stuck instant and for a 2D Jenkins
!>   element (slider states in the state);
!> - the sweep's Floquet stability with 2D friction (also lifting off, also behind a
!>   tangential stiffness) and with a Jenkins element: the largest multiplier of points of
!>   the curve against the eigenvalues of central differences of the period map of the
!>   orbit shot from the point.
module test_reference_2d
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, real_text
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t, reference_options_t, sample_reference
    use stickslip_reference_start, only: solve_reference_from_starts, reference_start_options_t
    use stickslip_flow, only: flow_t
    use stickslip_contact_law, only: state_open, state_stick, state_slip
    use stickslip_stability, only: floquet_t, floquet_multipliers
    use stickslip_sweep_options, only: sweep_options_t
    use stickslip_sweep_result, only: sweep_result_t
    use stickslip_sweep, only: run_sweep
    use fixtures, only: planar_model, seed_model, liftoff_2d_model
    use test_jenkins, only: central_differences
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_reference_2d_tests, test_euler_first_order, compare_monodromy, test_disk_law, &
        reference, test_jenkins_disk_law

    !> The planar model's friction limit mu N and angular frequency.
    real(dp), parameter :: mun = 0.3_dp, omega = 1.7_dp

contains

    subroutine run_reference_2d_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        call test_circle(t)
        call reference(t, planar_model(0.33_dp, 0.15_dp, 0.0_dp), res, "stick-slip")
        if (res%converged) then
            call test_stick_slip_law(t, res)
            call test_euler_first_order(t, res, planar_model(0.33_dp, 0.15_dp, 0.0_dp), &
                                        "stick-slip")
            call test_hbm_converges(t, res, planar_model(0.33_dp, 0.15_dp, 0.0_dp), "stick-slip", &
                                    .true.)
            call test_monodromy_stick_slip(t, res, "stick-slip")
        end if
        call reference(t, liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp), res, "lift-off")
        if (res%converged) then
            call test_liftoff_law(t, res)
            call test_euler_first_order(t, res, liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp), &
                                        "lift-off")
            call test_hbm_converges(t, res, liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp), &
                                    "lift-off", .false.)
            call test_monodromy_stick_slip(t, res, "lift-off")
        end if
        call test_stuck_all_period(t)
        call test_ode_tol(t)
        call test_jenkins_2d(t)
        call test_jenkins_2d_liftoff(t)
        call test_sweep_stability(t)
    end subroutine run_reference_2d_tests

    !> The reference of model m from the weighted-residual start (or `start`; ode_tol given
    !> or the default), checked converged.
    subroutine reference(t, m, res, name, ode_tol, tol, start)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(out) :: res
        character(len=*), intent(in) :: name
        real(dp), intent(in), optional :: ode_tol, tol
        character(len=*), intent(in), optional :: start
        type(reference_start_options_t) :: o
        type(error_type), allocatable :: error
        o%start = 'hbm'
        if (present(start)) o%start = start
        if (present(ode_tol)) o%ode_tol = ode_tol
        if (present(tol)) o%tol = tol
        call solve_reference_from_starts(m, o, res, error)
        call check_error(t, error, "reference_2d: "//name//": solved", .false.)
        if (allocated(error)) return
        call check(t, res%converged, "reference_2d: "//name//": periodic", res%diagnosis)
    end subroutine reference

    !> The circle: a point mass (m = k = 1, c = 0.1) forced by a rotating force of 1 at
    !> omega = 1.7 slips in full on a circle, the friction force mu N opposite to the
    !> velocity; with Z = k - m w^2 + i c w, the radius A solves |Z A + i mu N| = F. The
    !> reference's radius equals it to 1e-9, the path is a circle, the force on the disk's
    !> edge at every sample, the energy balance to 1e-11, and the reference states a
    !> nonzero integration error estimate below 1e-9.
    subroutine test_circle(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        real(dp) :: z, cw, a
        real(dp), allocatable :: radius(:)
        call reference(t, planar_model(1.0_dp, 1.0_dp, 0.0_dp), res, "circle")
        if (.not. res%converged) return
        z = 1.0_dp - omega**2
        cw = 0.1_dp*omega
        a = (-cw*mun + sqrt((cw*mun)**2 - (z**2 + cw**2)*(mun**2 - 1.0_dp)))/(z**2 + cw**2)
        radius = hypot(res%x(:, 1), res%x(:, 2))
        call check_close(t, maxval(radius), a, "reference_2d: circle: the radius of the "// &
                         "closed form", rtol=1.0e-9_dp)
        call check(t, maxval(radius) - minval(radius) <= 1.0e-9_dp*a, &
                   "reference_2d: circle: the path is a circle", &
                   real_text((maxval(radius) - minval(radius))/a))
        call check(t, maxval(abs(hypot(res%r(:, 1), res%r(:, 2)) - mun)) <= 1.0e-12_dp .and. &
                   all(res%state(:, 1) == state_slip), &
                   "reference_2d: circle: full slip, the force on the disk's edge")
        call check(t, balance(res) <= 1.0e-11_dp, "reference_2d: circle: energy balance", &
                   real_text(balance(res)))
        call check(t, res%integration_error > 0.0_dp .and. &
                   res%integration_error <= 1.0e-9_dp, &
                   "reference_2d: circle: the integration error estimate is stated", &
                   real_text(res%integration_error))
    end subroutine test_circle

    !> The relative energy balance error of a reference over one period.
    real(dp) function balance(res)
        type(reference_result_t), intent(in) :: res
        balance = abs(res%work_forcing - res%diss_friction - res%diss_damping)/ &
                  max(res%work_forcing, tiny(1.0_dp))
    end function balance

    !> Coulomb's law at every sample of the stick-slip orbit: stuck inside the disk
    !> (|r| <= mu N (1 + 1e-9)) with the slip velocity zero, slipping on its edge (1e-12)
    !> and against the slip velocity (r . v / |v| = -mu N to 1e-8 of mu N); stuck 30 to 70
    !> % of the period in 2 phases; the energy balance to 1e-10.
    subroutine test_stick_slip_law(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        real(dp) :: worst_stuck, worst_edge, worst_dir, sp
        integer :: k
        worst_stuck = 0.0_dp
        worst_edge = 0.0_dp
        worst_dir = 0.0_dp
        do k = 1, size(res%t)
            sp = hypot(res%v(k, 1), res%v(k, 2))
            if (res%state(k, 1) == state_stick) then
                worst_stuck = max(worst_stuck, hypot(res%r(k, 1), res%r(k, 2))/mun - 1.0_dp, &
                                  sp/maxval(abs(res%v)))
            else
                worst_edge = max(worst_edge, abs(hypot(res%r(k, 1), res%r(k, 2)) - mun))
                if (sp > 1.0e-6_dp*maxval(abs(res%v))) worst_dir = max(worst_dir, &
                    abs((res%r(k, 1)*res%v(k, 1) + res%r(k, 2)*res%v(k, 2))/sp + mun))
            end if
        end do
        call check(t, res%stick_fraction(1) > 0.3_dp .and. res%stick_fraction(1) < 0.7_dp .and. &
                   res%stick_phases(1) == 2, "reference_2d: stick-slip: stuck in two phases", &
                   real_text(res%stick_fraction(1)))
        call check(t, worst_stuck <= 1.0e-9_dp, "reference_2d: stick-slip: stuck inside "// &
                   "the disk, at rest", real_text(worst_stuck))
        call check(t, worst_edge <= 1.0e-12_dp .and. worst_dir <= 1.0e-8_dp*mun, &
                   "reference_2d: stick-slip: slipping on the disk's edge against the slip", &
                   real_text(worst_edge)//", "//real_text(worst_dir))
        call check(t, balance(res) <= 1.0e-10_dp, "reference_2d: stick-slip: energy "// &
                   "balance", real_text(balance(res)))
    end subroutine test_stick_slip_law

    !> Implicit Euler started on the orbit of model m (the reference's state at t = 0, over
    !> two periods) converges to it at first order: the max displacement error of the
    !> second period (relative) at 1000, 10000 and 100000 steps falls by 5 to 20 per decade.
    subroutine test_euler_first_order(t, res, m, name)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(model_t), intent(in) :: m
        character(len=*), intent(in) :: name
        type(euler_options_t) :: o
        type(euler_result_t) :: e
        type(error_type), allocatable :: error
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: err(3)
        integer :: k
        do k = 1, 3
            o%steps_per_period = 1000*10**(k - 1)
            o%max_periods = 2
            call integrate_euler(m, o, e, error, x0=res%x(1, :), v0=res%v(1, :))
            call check_error(t, error, "reference_2d: "//name//": Euler integrated", .false.)
            if (allocated(error)) return
            call sample_reference(res, o%steps_per_period, xr, vr, rr, error)
            if (allocated(error)) return
            err(k) = maxval(abs(e%x - xr))/maxval(abs(xr))
        end do
        call check(t, err(1)/err(2) > 5.0_dp .and. err(1)/err(2) < 20.0_dp .and. &
                   err(2)/err(3) > 5.0_dp .and. err(2)/err(3) < 20.0_dp, &
                   "reference_2d: "//name//": implicit Euler converges to the reference at "// &
                   "first order", "errors at 1000, 10000, 100000 steps: "// &
                   real_text(err(1))//", "//real_text(err(2))//", "//real_text(err(3)))
    end subroutine test_euler_first_order

    !> The weighted residual of model m converges to its reference as H grows (H = 10, 20,
    !> 40, 80): the max displacement error at H = 80 more than 4 times below that at H = 10;
    !> `monotone`, falling at every step (the stick-slip orbit: 4.7e-2, 3.9e-2, 1.7e-2,
    !> 8.1e-3), else at H = 40 below H = 10 and at H = 80 below H = 20 (the truncation error
    !> of the 2D lift-off does not fall at every step: 3.1e-3, 3.6e-3, 6.0e-5, 4.8e-4).
    subroutine test_hbm_converges(t, res, m, name, monotone)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(model_t), intent(in) :: m
        character(len=*), intent(in) :: name
        logical, intent(in) :: monotone
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: e(4)
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        integer :: k
        call sample_reference(res, 1024, xr, vr, rr, error)
        if (allocated(error)) return
        do k = 1, 4
            o%harmonics = 10*2**(k - 1)
            o%samples = 1024
            call solve_periodic(m, o, sol, error)
            if (allocated(error) .or. .not. sol%converged) then
                call check(t, .false., "reference_2d: "//name//": weighted residual H = "// &
                           real_text(real(o%harmonics, dp))//" converged")
                return
            end if
            e(k) = maxval(abs(sol%x - xr))/maxval(abs(xr))
        end do
        call check(t, e(4) < e(1)/4.0_dp .and. merge(all(e(2:4) < e(1:3)), &
                                                       e(3) < e(1) .and. e(4) < e(2), monotone), &
                   "reference_2d: "//name//": the weighted residual converges to the "// &
                   "reference as H grows", "errors at H = 10, 20, 40, 80: "// &
                   real_text(e(1))//", "//real_text(e(2))//", "//real_text(e(3))//", "// &
                   real_text(e(4)))
    end subroutine test_hbm_converges

    !> The monodromy of a stick-slip orbit against central differences of the period map:
    !> at the section (the mass slips) and at a stuck instant (the sample of least |r|).
    subroutine test_monodromy_stick_slip(t, res, name)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        character(len=*), intent(in) :: name
        type(flow_t) :: flow
        real(dp), allocatable :: z0(:)
        integer :: k
        flow = res%flow
        z0 = res%orbit%phase_y(1:flow%nz, 1)
        call compare_monodromy(t, flow, res%t_section, z0, name//", at the section "// &
                               "(slipping)", res%monodromy)
        k = minloc(hypot(res%r(:, 1), res%r(:, 2)), 1, mask=res%state(:, 1) == state_stick)
        z0 = [res%x(k, :), res%v(k, :)]
        call compare_monodromy(t, flow, res%t(k), z0, name//", at a stuck instant")
    end subroutine test_monodromy_stick_slip

    !> 2D friction on a contact that lifts off (liftoff_2d_model(0.3, 0.15, 1): the limit mu
    !> lambda varies, the contact opens once and sticks once per period): the law at every
    !> sample (test_disk_law, k_n = 10).
    subroutine test_liftoff_law(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        call check(t, res%open_fraction(1) > 0.1_dp .and. res%open_fraction(1) < 0.3_dp .and. &
                   res%stick_fraction(1) > 0.1_dp .and. res%stick_phases(1) == 1, &
                   "reference_2d: lift-off: opens and sticks once a period", &
                   real_text(res%open_fraction(1))//" open, "//real_text(res%stick_fraction(1))// &
                   " stuck")
        call test_disk_law(t, res, "lift-off", 10.0_dp)
    end subroutine test_liftoff_law

    !> 2D friction with mu = 0.3 on a unilateral contact (normal stiffness kn, 0: rigid) at
    !> every sample: open, no force; closed, lambda = -k_n g (1e-12 of lambda_max; rigid:
    !> the gap zero to 1e-12 of the displacement and lambda >= 0), stuck inside the disk of
    !> radius mu lambda (1e-9) at rest, or slipping on its edge (1e-12 of mu lambda_max)
    !> against the slip velocity (1e-8); the energy balance with the impact losses to 1e-10.
    subroutine test_disk_law(t, res, name, kn)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: kn
        real(dp) :: worst_open, worst_normal, worst_stuck, worst_edge, worst_dir, sp, rn, &
                    lmax, vmax, xmax, bal
        integer :: k
        worst_open = 0.0_dp
        worst_normal = 0.0_dp
        worst_stuck = 0.0_dp
        worst_edge = 0.0_dp
        worst_dir = 0.0_dp
        lmax = maxval(res%normal(:, 1))
        vmax = maxval(abs(res%v(:, 1:2)))
        xmax = maxval(abs(res%x))
        do k = 1, size(res%t)
            sp = hypot(res%v(k, 1), res%v(k, 2))
            rn = hypot(res%r(k, 1), res%r(k, 2))
            if (res%state(k, 1) == state_open) then
                worst_open = max(worst_open, rn, abs(res%normal(k, 1)))
                cycle
            end if
            worst_normal = max(worst_normal, normal_law_error(res, k, kn, lmax, xmax))
            if (res%state(k, 1) == state_stick) then
                worst_stuck = max(worst_stuck, (rn - mun*res%normal(k, 1))/(mun*lmax), sp/vmax)
            else
                worst_edge = max(worst_edge, abs(rn - mun*res%normal(k, 1))/(mun*lmax))
                if (sp > 1.0e-6_dp*vmax) worst_dir = max(worst_dir, &
                    abs((res%r(k, 1)*res%v(k, 1) + res%r(k, 2)*res%v(k, 2))/sp + rn)/(mun*lmax))
            end if
        end do
        call check(t, worst_open == 0.0_dp .and. worst_normal <= 1.0e-12_dp, "reference_2d: "// &
                   name//": no force when open, the normal law when closed", &
                   real_text(worst_open)//", "//real_text(worst_normal))
        call check(t, worst_stuck <= 1.0e-9_dp, "reference_2d: "//name//": stuck inside the "// &
                   "disk of radius mu lambda, at rest", real_text(worst_stuck))
        call check(t, worst_edge <= 1.0e-12_dp .and. worst_dir <= 1.0e-8_dp, &
                   "reference_2d: "//name//": slipping on the edge of the varying disk "// &
                   "against the slip", real_text(worst_edge)//", "//real_text(worst_dir))
        bal = abs(res%work_forcing - res%diss_friction - res%diss_damping - res%impact_loss)/ &
              res%work_forcing
        call check(t, bal <= 1.0e-10_dp, "reference_2d: "//name//": energy balance (with the "// &
                   "impact losses)", real_text(bal))
    end subroutine test_disk_law

    !> The normal law's error at closed sample k: lambda + k_n g relative to lambda_max
    !> (elastic); rigid, the gap relative to the largest displacement and a negative lambda
    !> relative to lambda_max.
    real(dp) function normal_law_error(res, k, kn, lmax, xmax) result(e)
        type(reference_result_t), intent(in) :: res
        integer, intent(in) :: k
        real(dp), intent(in) :: kn, lmax, xmax
        if (kn > 0.0_dp) then
            e = abs(res%normal(k, 1) + kn*res%gap(k, 1))/lmax
        else
            e = max(abs(res%gap(k, 1))/xmax, -res%normal(k, 1)/lmax)
        end if
    end function normal_law_error

    !> flow%period_map's monodromy from z0 at t0 (or `given`, the reference's) against its
    !> central differences (steps 1e-6 of max(|z0_k|, 1e-2)), relative to its largest entry:
    !> within 1e-5.
    subroutine compare_monodromy(t, flow, t0, z0, name, given)
        type(test_counter_t), intent(inout) :: t
        type(flow_t), intent(inout) :: flow
        real(dp), intent(in) :: t0, z0(:)
        character(len=*), intent(in) :: name
        real(dp), intent(in), optional :: given(:, :)
        type(error_type), allocatable :: error
        real(dp), allocatable :: fd(:, :), mono(:, :), z1(:)
        real(dp) :: worst
        allocate (mono(size(z0), size(z0)), z1(size(z0)))
        if (present(given)) then
            mono = given
        else
            call flow%period_map(t0, z0, z1, error, mono=mono)
            call check_error(t, error, "reference_2d: "//name//": period map", .false.)
            if (allocated(error)) return
        end if
        call central_differences(flow, t0, z0, fd, error)
        call check_error(t, error, "reference_2d: "//name//": perturbed period maps", .false.)
        if (allocated(error)) return
        worst = maxval(abs(fd - mono))/maxval(abs(mono))
        call check(t, worst <= 1.0e-5_dp, "reference_2d: "//name//": monodromy = central "// &
                   "differences of the period map", "relative "//real_text(worst))
    end subroutine compare_monodromy

    !> A 2D contact stuck all period (the point mass under a force below mu N: it does not
    !> move, the start's slip velocities are roundoff): the reference converges, stuck the
    !> whole period with the force inside the disk.
    subroutine test_stuck_all_period(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        call reference(t, planar_model(0.1_dp, 0.05_dp, 0.0_dp), res, "stuck all period")
        if (.not. res%converged) return
        call check(t, all(res%state(:, 1) == state_stick) .and. &
                   maxval(hypot(res%r(:, 1), res%r(:, 2))) <= mun, "reference_2d: stuck "// &
                   "all period: stuck at every sample inside the disk")
    end subroutine test_stuck_all_period

    !> ode_tol on the stick-slip orbit (periodicity defect 1e-13): the samples of x and v at
    !> 1e-6, 1e-8 and 1e-10 against those at 1e-12, relative to the largest state, each
    !> within twice the error estimate the reference states; the estimates fall with the
    !> tolerance.
    subroutine test_ode_tol(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: best, res
        real(dp) :: d(3), est(3), ymax
        integer :: k
        character(len=:), allocatable :: table
        call reference(t, planar_model(0.33_dp, 0.15_dp, 0.0_dp), best, "ode_tol 1e-12", &
                       ode_tol=1.0e-12_dp, tol=1.0e-13_dp)
        if (.not. best%converged) return
        ymax = maxval(sqrt(sum(best%x**2, 2) + sum(best%v**2, 2)))
        table = ""
        do k = 1, 3
            call reference(t, planar_model(0.33_dp, 0.15_dp, 0.0_dp), res, "ode_tol", &
                           ode_tol=10.0_dp**(-4 - 2*k), tol=1.0e-13_dp)
            if (.not. res%converged) return
            d(k) = maxval(sqrt(sum((res%x - best%x)**2, 2) + sum((res%v - best%v)**2, 2)))/ymax
            est(k) = res%integration_error
            table = table//" ode_tol "//real_text(10.0_dp**(-4 - 2*k))//": difference "// &
                    real_text(d(k))//", estimate "//real_text(est(k))//";"
        end do
        call check(t, all(d <= 2.0_dp*est) .and. est(2) < est(1) .and. est(3) < est(2), &
                   "reference_2d: ode_tol: each result within its stated error estimate, "// &
                   "the estimate falling with the tolerance", table)
    end subroutine test_ode_tol

    !> A 2D Jenkins element (the stick-slip point mass with k_t = 10: the slider sticks
    !> about a fifth of the period, in two phases): converged, the energy balance to 1e-10,
    !> the spring's force within the disk at every sample, and the monodromy of [x; v; s]
    !> (6 x 6) against central differences at a stuck instant.
    subroutine test_jenkins_2d(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        type(flow_t) :: flow
        real(dp), allocatable :: z0(:)
        integer :: k
        call reference(t, planar_model(0.33_dp, 0.15_dp, 10.0_dp), res, "2D Jenkins")
        if (.not. res%converged) return
        call check(t, balance(res) <= 1.0e-10_dp, "reference_2d: 2D Jenkins: energy balance", &
                   real_text(balance(res)))
        call check(t, maxval(hypot(res%r(:, 1), res%r(:, 2))) <= mun*(1.0_dp + 1.0e-9_dp), &
                   "reference_2d: 2D Jenkins: the force within the disk")
        flow = res%flow
        call check(t, flow%nz == 6, "reference_2d: 2D Jenkins: two slider states in the flow")
        if (flow%nz /= 6 .or. .not. any(res%state(:, 1) == state_stick)) then
            call check(t, .false., "reference_2d: 2D Jenkins: the slider sticks at times")
            return
        end if
        k = minloc(hypot(res%r(:, 1), res%r(:, 2)), 1, mask=res%state(:, 1) == state_stick)
        z0 = [res%x(k, :), res%v(k, :), res%s(k, :)]
        call compare_monodromy(t, flow, res%t(k), z0, "2D Jenkins, at a stuck instant")
    end subroutine test_jenkins_2d

    !> A 2D Jenkins element on a contact that lifts off (the 2D lift-off with k_t = 20: the
    !> limit mu lambda varies, the contact opens once a period and the slider sticks in two
    !> phases): converged, the energy balance to 1e-10; at every sample no force when open,
    !> the normal law, the spring's force r = -k_t (P x - s) (1e-9 of mu lambda_max) inside
    !> the disk when stuck, on its edge when slipping (1e-9) and against the slider's motion
    !> (the central difference of the slider samples: cosine below -0.999); the monodromy of
    !> [x; v; s] (8 x 8) against central differences at the most open, a stuck and a slipping
    !> instant; implicit Euler started on the orbit converging to it at first order; the
    !> weighted residual converging to it as H grows.
    subroutine test_jenkins_2d_liftoff(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: name = "2D Jenkins lift-off"
        real(dp), parameter :: kn = 10.0_dp, kt = 20.0_dp
        character(len=*), parameter :: instant(3) = [character(len=21) :: &
                                                     "the most open instant", "a stuck instant", &
                                                     "a slipping instant"]
        type(reference_result_t) :: res
        type(model_t) :: m
        type(flow_t) :: flow
        integer :: k, kind
        m = liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp)
        m%tangential_stiffness = [kt]
        call reference(t, m, res, name)
        if (.not. res%converged) return
        call check(t, balance(res) <= 1.0e-10_dp, "reference_2d: "//name//": energy balance", &
                   real_text(balance(res)))
        call check(t, res%open_fraction(1) > 0.1_dp .and. res%stick_phases(1) == 2, &
                   "reference_2d: "//name//": opens once and sticks twice a period", &
                   real_text(res%open_fraction(1))//" open, "//real_text(res%stick_fraction(1))// &
                   " stuck in "//real_text(real(res%stick_phases(1), dp))//" phases")
        call test_jenkins_disk_law(t, res, name, kn, kt)
        flow = res%flow
        call check(t, flow%nz == 8, "reference_2d: "//name//": two slider states in the flow")
        if (flow%nz /= 8) return
        do kind = 1, 3
            select case (kind)
            case (1)
                k = maxloc(res%gap(:, 1), 1)
            case (2)
                k = minloc(hypot(res%r(:, 1), res%r(:, 2)), 1, &
                           mask=res%state(:, 1) == state_stick)
            case default
                k = maxloc(res%normal(:, 1), 1, mask=res%state(:, 1) == state_slip)
            end select
            call compare_monodromy(t, flow, res%t(k), [res%x(k, :), res%v(k, :), res%s(k, :)], &
                                   name//", at "//trim(instant(kind)))
        end do
        call test_euler_first_order(t, res, m, name)
        call test_hbm_converges(t, res, m, name, .false.)
    end subroutine test_jenkins_2d_liftoff

    !> A 2D Jenkins element with mu = 0.3 on a unilateral contact (normal stiffness kn, 0:
    !> rigid; tangential stiffness kt) at every sample: open, no friction force, a normal
    !> force below 1e-6 of its largest (a closed contact below the element's force floor
    !> counts as open) and the sliders on the structure, s = P x (1e-12 of the largest
    !> displacement: the spring unloaded as the contact opened); closed, lambda = -k_n g
    !> (1e-12 of lambda_max; rigid: the gap zero to 1e-12 of the displacement and lambda >=
    !> 0), the spring's force r = -k_t (P x - s)
    !> (1e-9 of mu lambda_max), inside the disk when stuck, on its edge when slipping (1e-9)
    !> and against the slider's motion (the central difference of the slider samples: cosine
    !> below -0.999).
    subroutine test_jenkins_disk_law(t, res, name, kn, kt)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: kn, kt
        real(dp) :: lmax, xmax, worst_open, worst_floor, worst_follow, worst_law, worst_dir, rn, &
                    ds(2), ns
        integer :: k, nk
        lmax = maxval(res%normal(:, 1))
        xmax = maxval(abs(res%x))
        nk = size(res%t)
        worst_open = 0.0_dp
        worst_floor = 0.0_dp
        worst_follow = 0.0_dp
        worst_law = 0.0_dp
        worst_dir = -1.0_dp
        do k = 1, nk
            rn = hypot(res%r(k, 1), res%r(k, 2))
            if (res%state(k, 1) == state_open) then
                worst_open = max(worst_open, rn)
                worst_floor = max(worst_floor, abs(res%normal(k, 1))/lmax)
                worst_follow = max(worst_follow, &
                                   maxval(abs(res%s(k, 1:2) - res%x(k, 1:2)))/xmax)
                cycle
            end if
            worst_law = max(worst_law, normal_law_error(res, k, kn, lmax, xmax), &
                            maxval(abs(res%r(k, 1:2) + kt*(res%x(k, 1:2) - res%s(k, 1:2))))/ &
                            (mun*lmax))
            if (res%state(k, 1) == state_stick) then
                worst_law = max(worst_law, (rn - mun*res%normal(k, 1))/(mun*lmax))
                cycle
            end if
            worst_law = max(worst_law, abs(rn - mun*res%normal(k, 1))/(mun*lmax))
            if (k == 1 .or. k == nk) cycle
            if (any(res%state(k - 1:k + 1:2, 1) /= state_slip)) cycle
            ds = res%s(k + 1, 1:2) - res%s(k - 1, 1:2)
            ns = norm2(ds)
            if (ns > 1.0e-3_dp*maxval(abs(res%s)) .and. rn > 1.0e-3_dp*mun*lmax) &
                worst_dir = max(worst_dir, dot_product(res%r(k, 1:2), ds)/(rn*ns))
        end do
        call check(t, worst_open == 0.0_dp .and. worst_floor <= 1.0e-6_dp .and. &
                   worst_follow <= 1.0e-12_dp .and. worst_law <= 1.0e-9_dp .and. &
                   worst_dir < -0.999_dp, "reference_2d: "//name//": no force when open, the "// &
                   "sliders on the structure (unloaded); the normal law and the spring's "// &
                   "force, inside the disk when stuck, on its edge against the slider's "// &
                   "motion when slipping", real_text(worst_open)//", "//real_text(worst_floor)// &
                   ", "//real_text(worst_follow)//", "//real_text(worst_law)//", cosine "// &
                   real_text(worst_dir))
    end subroutine test_jenkins_disk_law

    !> The sweep's Floquet stability with 2D friction (the stick-slip point mass over omega
    !> in [1.6, 1.8], and lifting off over the same range) and with a 1D Jenkins element
    !> (the seed with k_t = 5 over [4.2, 4.8]):
    !> steps of a quarter of the range; every point gets a largest multiplier; at the first
    !> and last points it equals the
    !> largest eigenvalue modulus of central differences of the period map of the orbit
    !> shot from the point (1e-4).
    subroutine test_sweep_stability(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        m = planar_model(0.33_dp, 0.15_dp, 0.0_dp)
        call sweep_and_check(t, m, 1.6_dp, 1.8_dp, "2D friction")
        m = seed_model()
        m%damping = 0.02_dp*m%mass
        m%tangential_stiffness = [5.0_dp]
        call sweep_and_check(t, m, 4.2_dp, 4.8_dp, "Jenkins")
        call sweep_and_check(t, liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp), 1.6_dp, 1.8_dp, &
                             "2D friction that lifts off")
        m = liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp)
        m%tangential_stiffness = [20.0_dp]
        call sweep_and_check(t, m, 1.6_dp, 1.8_dp, "2D Jenkins that lifts off")
    end subroutine test_sweep_stability

    subroutine sweep_and_check(t, m, lo, hi, name)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        real(dp), intent(in) :: lo, hi
        character(len=*), intent(in) :: name
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: sw
        type(error_type), allocatable :: error
        type(reference_result_t) :: res
        type(model_t) :: mp
        type(floquet_t) :: fl
        type(flow_t) :: flow
        real(dp), allocatable :: fd(:, :), z0(:)
        integer :: k, p
        ho%harmonics = 20
        ho%samples = 512
        so%parameter = 'omega'
        so%start = lo
        so%stop = hi
        so%stability = .true.
        so%step = (hi - lo)/4.0_dp
        so%max_step = so%step
        call run_sweep(m, ho, ro, so, sw, error)
        call check_error(t, error, "reference_2d: sweep with stability, "//name, .false.)
        if (allocated(error)) return
        call check(t, sw%complete .and. sw%npoints >= 3 .and. &
                   all(sw%points(1:sw%npoints)%floquet_max == &
                       sw%points(1:sw%npoints)%floquet_max), "reference_2d: sweep with "// &
                   "stability, "//name//": complete, a multiplier at every point")
        if (.not. sw%complete .or. sw%npoints < 1) return
        do k = 1, 2
            p = merge(1, sw%npoints, k == 1)
            mp = m
            mp%omega = sw%points(p)%parameter
            call reference(t, mp, res, name//" sweep point")
            if (.not. res%converged) return
            flow = res%flow
            z0 = res%orbit%phase_y(1:flow%nz, 1)
            call central_differences(flow, res%t_section, z0, fd, error)
            if (allocated(error)) exit
            call floquet_multipliers(fd, fl, error)
            if (allocated(error)) exit
            call check(t, abs(fl%max_modulus - sw%points(p)%floquet_max) <= &
                       1.0e-4_dp*max(1.0_dp, fl%max_modulus), "reference_2d: sweep with "// &
                       "stability, "//name//": the largest multiplier = that of central "// &
                       "differences of the period map", real_text(sw%points(p)%floquet_max)// &
                       " vs "//real_text(fl%max_modulus))
        end do
        call check_error(t, error, "reference_2d: "//name//": central differences", .false.)
    end subroutine sweep_and_check
end module test_reference_2d
