!> Tests of the exact event-driven reference against independent truth: the energy balance
!> over a period, Coulomb's law and the events, the linear response (mu = 0), the stuck
!> system (large mu), the monodromy matrix against finite differences of the period map,
!> implicit Euler converging to it at first order, and the weighted-residual error against it
!> decreasing as harmonics are added.
module test_exact_reference
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_model, only: model_t, contact_velocity_direction
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_options_t, reference_result_t, sample_reference
    use stickslip_reference_start, only: solve_reference_from_starts, reference_start_options_t
    use stickslip_flow, only: flow_t, new_flow, event_stick, event_slip
    use fixtures, only: seed_model, chain_model
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_exact_reference_tests

contains

    subroutine run_exact_reference_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: seed, chain
        call solved(t, seed_model(), seed, "seed")
        call solved(t, chain_model(), chain, "chain")
        if (seed%converged) then
            call test_coulomb_and_events(t, seed_model(), seed, "seed")
            call test_monodromy(t, seed_model(), seed)
            call test_euler_first_order(t, seed)
            call test_hbm_error_decreases(t, seed)
        end if
        if (chain%converged) call test_coulomb_and_events(t, chain_model(), chain, "chain")
        call test_linear_limit(t)
        call test_stuck_limit(t)
        call test_bad_options(t)
    end subroutine run_exact_reference_tests

    !> Solve the reference of `m`: converged, periodicity defect within the tolerance,
    !> forcing work = friction + viscous dissipation over a period.
    subroutine solved(t, m, res, name)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(out) :: res
        character(len=*), intent(in) :: name
        type(reference_start_options_t) :: o
        type(error_type), allocatable :: error
        real(dp) :: balance
        o%samples = 512
        call solve_reference_from_starts(m, o, res, error)
        call check_error(t, error, "reference "//name//": no error", .false.)
        if (allocated(error)) return
        call check(t, res%converged .and. res%defect <= o%tol, "reference "//name// &
                   ": converged within tol", res%diagnosis)
        balance = abs(res%work_forcing - res%diss_friction - res%diss_damping)/res%work_forcing
        call check(t, res%work_forcing > 0.0_dp .and. balance < 1.0e-9_dp, "reference "// &
                   name//": energy balance over a period")
    end subroutine solved

    !> |r| <= mu N everywhere; r = -mu N sign(v) where the contact slips; zero slip velocity
    !> in stick; stick events at zero velocity, slip events at the friction limit with the
    !> slip against the force; events sorted in [0, T); each contact alternates stick and slip.
    subroutine test_coulomb_and_events(t, m, res, name)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(in) :: res
        character(len=*), intent(in) :: name
        real(dp), allocatable :: w(:), vs(:)
        real(dp) :: limit, vscale, period
        integer :: j, k, last
        logical :: bounded, slip_law, stuck_still, stick_ok, slip_ok, alternate
        period = two_pi/m%omega
        bounded = .true.
        slip_law = .true.
        stuck_still = .true.
        stick_ok = .true.
        slip_ok = .true.
        alternate = .true.
        do j = 1, m%ncontact()
            limit = m%mu(j)*m%normal_load(j)
            w = contact_velocity_direction(m, j)
            vs = matmul(res%v, w)
            vscale = maxval(abs(vs))
            bounded = bounded .and. all(abs(res%r(:, j)) <= limit*(1.0_dp + 1.0e-12_dp))
            do k = 1, size(vs)
                if (abs(vs(k)) > 1.0e-6_dp*vscale) then
                    slip_law = slip_law .and. &
                               abs(res%r(k, j) + limit*sign(1.0_dp, vs(k))) <= 1.0e-12_dp*limit
                else if (abs(res%r(k, j)) < limit*(1.0_dp - 1.0e-6_dp)) then
                    stuck_still = stuck_still .and. abs(vs(k)) <= 1.0e-9_dp*vscale
                end if
            end do
            last = 0
            do k = 1, res%nevent
                if (res%event_contact(k) /= j) cycle
                if (res%event_kind(k) == event_stick) then
                    stick_ok = stick_ok .and. abs(res%event_velocity(k)) <= 1.0e-9_dp*vscale &
                               .and. res%event_direction(k) == 0
                    alternate = alternate .and. last /= event_stick
                    last = event_stick
                else if (res%event_kind(k) == event_slip) then
                    slip_ok = slip_ok .and. abs(abs(res%event_force(k)) - limit) <= &
                              1.0e-9_dp*limit .and. &
                              res%event_direction(k) == -nint(sign(1.0_dp, res%event_force(k)))
                    alternate = alternate .and. last /= event_slip
                    last = event_slip
                end if
            end do
        end do
        call check(t, bounded, "reference "//name//": |r| <= mu N at every sample")
        call check(t, slip_law, "reference "//name//": r = -mu N sign(v) while slipping")
        call check(t, stuck_still, "reference "//name//": zero slip velocity while stuck")
        call check(t, stick_ok, "reference "//name//": stick events at zero velocity")
        call check(t, slip_ok, "reference "//name//": slip events at the limit, against r")
        call check(t, alternate, "reference "//name//": stick and slip events alternate")
        call check(t, res%nevent >= 2*m%ncontact(), "reference "//name//": events found")
        call check(t, all(res%event_t(1:res%nevent) >= 0.0_dp .and. &
                          res%event_t(1:res%nevent) < period) .and. &
                   all(res%event_t(2:res%nevent) >= res%event_t(1:res%nevent - 1)), &
                   "reference "//name//": events sorted in [0, T)")
        call check(t, all(res%stick_fraction > 0.0_dp .and. res%stick_fraction < 1.0_dp), &
                   "reference "//name//": every contact sticks and slips")
    end subroutine test_coulomb_and_events

    !> The monodromy matrix returned by the period map against central differences of the
    !> map at the periodic state (section time of the shooting).
    subroutine test_monodromy(t, m, res)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(in) :: res
        type(flow_t) :: flow
        type(error_type), allocatable :: error
        real(dp) :: z0(4), zp(4), zm(4), z1(4), mono(4, 4), fd(4, 4), h
        real(dp), allocatable :: xs(:, :), vs(:, :), rs(:, :)
        integer :: k, ng
        ! the state at the section time: sample on a grid that holds it
        ng = 4096
        call sample_reference(res, ng, xs, vs, rs, error)
        call check_error(t, error, "monodromy: sampling", .false.)
        if (allocated(error)) return
        k = nint(res%t_section*m%omega/two_pi*ng)
        z0 = [xs(modulo(k, ng) + 1, :), vs(modulo(k, ng) + 1, :)]
        call new_flow(flow, m, 1000, [maxval(abs(vs(:, 2)))], error)
        if (allocated(error)) return
        call flow%period_map(real(k, dp)*two_pi/m%omega/ng, z0, z1, error, mono=mono)
        call check_error(t, error, "monodromy: period map", .false.)
        if (allocated(error)) return
        do k = 1, 4
            h = 1.0e-6_dp*max(abs(z0(k)), 1.0e-3_dp)
            zp = z0
            zp(k) = zp(k) + h
            call flow%period_map(real(nint(res%t_section*m%omega/two_pi*ng), dp)*two_pi/ &
                                 m%omega/ng, zp, z1, error)
            if (allocated(error)) return
            fd(:, k) = z1
            zm = z0
            zm(k) = zm(k) - h
            call flow%period_map(real(nint(res%t_section*m%omega/two_pi*ng), dp)*two_pi/ &
                                 m%omega/ng, zm, z1, error)
            if (allocated(error)) return
            fd(:, k) = (fd(:, k) - z1)/(2.0_dp*h)
        end do
        call check(t, maxval(abs(fd - mono)) <= 1.0e-5_dp*maxval(abs(mono)), &
                   "monodromy matrix = central differences of the period map")
    end subroutine test_monodromy

    !> Implicit Euler from rest converges to the reference at first order: its max error in x
    !> halves when the step halves.
    subroutine test_euler_first_order(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(euler_options_t) :: o
        type(euler_result_t) :: e
        type(error_type), allocatable :: error
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: err(3)
        integer :: i
        character(len=80) :: buf
        do i = 1, 3
            o%steps_per_period = 400*2**(i - 1)
            call integrate_euler(seed_model(), o, e, error)
            if (allocated(error) .or. .not. e%periodic) then
                call check(t, .false., "Euler vs reference: periodic state reached")
                return
            end if
            call sample_reference(res, o%steps_per_period, xr, vr, rr, error)
            if (allocated(error)) return
            err(i) = maxval(abs(e%x - xr))/maxval(abs(xr))
        end do
        write (buf, '(3es10.2)') err
        call check(t, err(1)/err(2) > 1.8_dp .and. err(1)/err(2) < 2.2_dp .and. &
                   err(2)/err(3) > 1.8_dp .and. err(2)/err(3) < 2.2_dp, &
                   "Euler converges to the reference at first order", buf)
    end subroutine test_euler_first_order

    !> The weighted-residual error against the reference decreases as harmonics are added.
    subroutine test_hbm_error_decreases(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        integer, parameter :: hs(4) = [5, 10, 20, 40]
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: err(4), amp(2)
        integer :: i, p
        character(len=80) :: buf
        o%samples = 512
        do i = 1, size(hs)
            o%harmonics = hs(i)
            call solve_periodic(seed_model(), o, sol, error)
            if (allocated(error) .or. .not. sol%converged) then
                call check(t, .false., "weighted residual vs reference: converged")
                return
            end if
            call sample_reference(res, o%samples, xr, vr, rr, error)
            if (allocated(error)) return
            amp = maxval(abs(xr), 1)
            err(i) = maxval([(maxval(abs(sol%x(:, p) - xr(:, p)))/amp(p), p=1, 2)])
        end do
        write (buf, '(4es10.2)') err
        call check(t, err(2) < err(1) .and. err(3) < err(2) .and. err(4) < 0.5_dp*err(2), &
                   "weighted-residual error decreases with H", buf)
        call check(t, err(4) < 2.0e-2_dp, "weighted residual at H = 40 within 2% of the "// &
                   "reference", buf)
    end subroutine test_hbm_error_decreases

    !> mu = 0 with damping: the reference is the linear forced response, computed here from
    !> the complex dynamic stiffness of the 2-DOF system.
    subroutine test_linear_limit(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(reference_start_options_t) :: o
        type(reference_result_t) :: res
        type(error_type), allocatable :: error
        complex(dp) :: z(2, 2), det, xc(2)
        real(dp) :: tk, xa(2), errmax
        integer :: k
        m = seed_model()
        m%damping = 0.05_dp*m%stiffness + 0.02_dp*m%mass
        m%mu = [0.0_dp]
        z = m%stiffness - m%omega**2*m%mass + (0.0_dp, 1.0_dp)*m%omega*m%damping
        det = z(1, 1)*z(2, 2) - z(1, 2)*z(2, 1)
        ! F = [10, 0]: x = Z^-1 F
        xc = [z(2, 2)*10.0_dp, -z(2, 1)*10.0_dp]/det
        o%samples = 64
        call solve_reference_from_starts(m, o, res, error)
        call check_error(t, error, "reference mu = 0: no error", .false.)
        if (allocated(error)) return
        errmax = 0.0_dp
        do k = 1, o%samples
            tk = res%t(k)
            xa = real(xc*exp(cmplx(0.0_dp, m%omega*tk, dp)), dp)
            errmax = max(errmax, maxval(abs(res%x(k, :) - xa)))
        end do
        call check(t, res%converged .and. errmax <= 1.0e-9_dp*maxval(abs(xc)), &
                   "reference mu = 0 = linear forced response")
    end subroutine test_linear_limit

    !> A huge mu: the contact DOF never moves and DOF 1 responds as the 1-DOF system
    !> (m = 1, k = 2, c = C(1, 1)) about the static offset x2 / 2.
    subroutine test_stuck_limit(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(reference_start_options_t) :: o
        type(reference_result_t) :: res
        type(error_type), allocatable :: error
        complex(dp) :: xc
        real(dp) :: xa, errmax
        integer :: k
        m = seed_model()
        m%damping = 0.05_dp*m%stiffness + 0.02_dp*m%mass
        m%mu = [100.0_dp]
        xc = 10.0_dp/(2.0_dp - m%omega**2 + (0.0_dp, 1.0_dp)*m%omega*m%damping(1, 1))
        o%samples = 64
        call solve_reference_from_starts(m, o, res, error)
        call check_error(t, error, "reference stuck: no error", .false.)
        if (allocated(error)) return
        call check(t, res%converged, "reference stuck: converged", res%diagnosis)
        if (.not. res%converged) return
        call check(t, maxval(abs(res%v(:, 2))) <= 1.0e-12_dp*maxval(abs(res%v(:, 1))) .and. &
                   maxval(res%x(:, 2)) - minval(res%x(:, 2)) <= 1.0e-12_dp*abs(xc), &
                   "reference stuck: the contact DOF does not move")
        errmax = 0.0_dp
        do k = 1, o%samples
            xa = real(xc*exp(cmplx(0.0_dp, m%omega*res%t(k), dp)), dp) + 0.5_dp*res%x(1, 2)
            errmax = max(errmax, abs(res%x(k, 1) - xa))
        end do
        call check(t, errmax <= 1.0e-9_dp*abs(xc), "reference stuck = the reduced system")
        call check_close(t, res%stick_fraction(1), 1.0_dp, "reference stuck: stuck all period")
    end subroutine test_stuck_limit

    !> Invalid options are input errors naming the options argument (opts%...).
    subroutine test_bad_options(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_start_options_t) :: o
        type(reference_result_t) :: res
        type(error_type), allocatable :: error
        o%samples = 0
        call solve_reference_from_starts(seed_model(), o, res, error)
        call check_error(t, error, "reference samples = 0 rejected", .true., &
                         [character(len=20) :: "opts%samples"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "reference bad options: stat input")
        o = reference_start_options_t()
        o%start = 'cold'
        call solve_reference_from_starts(seed_model(), o, res, error)
        call check_error(t, error, "reference start = 'cold' rejected", .true., &
                         [character(len=20) :: "opts%start"])
    end subroutine test_bad_options
end module test_exact_reference
