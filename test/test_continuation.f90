!> Tests of the pseudo-arclength continuation (generic, on a smooth system with two known
!> folds) and of the forced-response sweep of the friction equations (analytic parameter
!> derivatives against central differences, the curve against point-by-point solves).
module test_continuation
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat, itoa
    use stickslip_case, only: rtoa
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_reference, only: reference_options_t
    use stickslip_continuation, only: parametric_system_t, continuation_options_t, &
        continuation_state_t, continuation_report_t, start_continuation, continuation_step, &
        reason_running, reason_end
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep, &
        friction_family_t, new_friction_family, set_sweep_parameter, sweep_parameter_value, &
        undamped_resonance_notes
    use stickslip_sweep_retrace, only: fold_watch_t, new_fold_watch
    use stickslip_checks, only: sampling_notes
    use testing, only: test_counter_t, check, check_close, check_error
    use fixtures, only: seed_model, damped_seed, msg
    use stickslip_sweep_point, only: stability_block
    use stickslip_sweep_result, only: frc_point_t
    use stickslip_stability, only: floquet_t, periodic_stability
    implicit none
    private
    public :: run_continuation_tests, damped_seed

    !> F1 = y1^3 - 3 y1 + lambda, F2 = y2 - y1^2: folds at (y1, lambda) = (1, 2), (-1, -2).
    type, extends(parametric_system_t) :: cubic_t
        integer :: evaluations = 0
    contains
        procedure :: residual => cubic_residual
        procedure :: jacobian => cubic_jacobian
    end type cubic_t

contains

    subroutine run_continuation_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_folds(t)
        call test_parameter_derivatives(t)
        call test_sweep_against_solves(t)
        call test_sweep_amplitude(t)
        call test_many_contacts(t)
        call test_bad_sweep(t)
        call test_notes(t)
        call test_recovery(t)
        call test_retrace_watch(t)
        call test_fresh_start(t)
    end subroutine run_continuation_tests

    !> The fold watch of a sweep on synthetic curves (amplitude = parameter, a sweep from 0
    !> to 2): a turn back whose next 3 points lie on the curve already traced is a kink: the
    !> state goes back before the turn with a parameter step forward, the fold is uncounted
    !> and a 'retrace' note is added; a turn back onto another branch (a true fold) is left
    !> alone.
    subroutine test_retrace_watch(t)
        type(test_counter_t), intent(inout) :: t
        type(sweep_result_t) :: res
        type(fold_watch_t) :: watch
        type(continuation_state_t) :: before
        integer :: k
        logical :: kink_ok, fold_ok
        do k = 1, 2
            call new_fold_watch(watch, 0.0_dp, 2.0_dp)
            res = sweep_result_t()
            allocate (res%points(20))
            ! ten points forward, lambda = 0.1 .. 1.0
            do while (res%npoints < 10)
                res%npoints = res%npoints + 1
                res%points(res%npoints)%parameter = 0.1_dp*res%npoints
                res%points(res%npoints)%amplitude = [0.1_dp*res%npoints]
            end do
            before%y = [1.0_dp]
            before%ty = [0.5_dp]
            before%lambda = 1.0_dp
            before%tl = 1.0_dp
            before%ds = 0.1_dp
            before%points = 10
            res%state = before
            res%state%tl = -1.0_dp
            call watch%accepted(before, res)
            ! three points back: on the curve (k = 1) or on another branch (k = 2)
            do while (res%npoints < 13)
                res%npoints = res%npoints + 1
                res%points(res%npoints)%parameter = 1.0_dp - 0.05_dp*(res%npoints - 10)
                res%points(res%npoints)%amplitude = [merge(1.0_dp, 2.0_dp, k == 1)* &
                                                     res%points(res%npoints)%parameter]
                call watch%check_retrace(res, 0.5_dp, "omega")
            end do
            if (k == 1) then
                kink_ok = res%folds == 0 .and. res%state%lambda == 1.0_dp .and. &
                          res%state%tl == 1.0_dp .and. abs(res%state%ds - 0.2_dp) < 1.0e-15_dp &
                          .and. all(res%state%ty == 0.0_dp) .and. res%diagnostics%has("retrace")
            else
                fold_ok = res%folds == 1 .and. res%state%tl == -1.0_dp .and. &
                          .not. res%diagnostics%has("retrace")
            end if
        end do
        call check(t, kink_ok, "retrace: a turn back onto the traced curve is stepped past")
        call check(t, fold_ok, "retrace: a turn back onto another branch stays a fold")
    end subroutine test_retrace_watch

    !> The recovery of a failed point: the harmonic ladder at a fixed parameter, from a bad
    !> start, lands on the solution a separate solve finds.
    subroutine test_recovery(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(friction_family_t) :: fam
        type(error_type), allocatable :: error
        real(dp), allocatable :: y(:), f(:)
        logical :: ok
        integer :: stat
        m = damped_seed()
        ho%harmonics = 30
        ho%samples = 256
        ho%rho = 0.2_dp
        call new_friction_family(fam, m, ho, 'omega', 3.0_dp, 0.2_dp, error)
        call check_error(t, error, "recovery: family", .false.)
        if (allocated(error)) return
        ! a start far from the solution: forces of twice the limit everywhere
        y = [(0.9_dp, stat=1, fam%prob%n)]
        call fam%recover(y, 3.0_dp, ok, error)
        call check_error(t, error, "recovery: no error", .false.)
        call check(t, ok, "recovery: the ladder converged")
        allocate (f(size(y)))
        stat = 0
        call fam%residual(y, 3.0_dp, f, stat)
        m%omega = 3.0_dp
        call solve_periodic(m, ho, sol, error)
        call check(t, norm2(f) <= ho%tol*sol%fscale, "recovery: F = 0 there (solve's tolerance)")
        call check_close(t, y, reshape(sol%rcoef, [size(y)]), "recovery: = a separate solve", &
                         atol=1.0e-8_dp)
        call fam%destroy()
    end subroutine test_recovery

    !> The warnings printed with a result: an undamped sweep across a natural frequency, odd
    !> or few samples.
    subroutine test_notes(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: note
        note = undamped_resonance_notes(seed_model(), 0.5_dp, 0.8_dp)
        call check(t, index(note, "0.61803 rad/s (h = 1)") > 0 .and. &
                   index(note, "1.61803") == 0, "notes: undamped resonance in the range", note)
        note = undamped_resonance_notes(seed_model(), 0.5_dp, 2.0_dp)
        call check(t, index(note, "0.61803") > 0 .and. index(note, "1.61803") > 0, &
                   "notes: both natural frequencies", note)
        note = undamped_resonance_notes(damped_seed(), 0.5_dp, 2.0_dp)
        call check(t, len(note) == 0, "notes: none with damping", note)
        note = undamped_resonance_notes(seed_model(), 2.0_dp, 6.0_dp)
        call check(t, len(note) == 0, "notes: none outside the range", note)
        call check(t, index(sampling_notes(41, 10), "odd") > 0, "notes: odd samples")
        call check(t, index(sampling_notes(30, 10), "< 4 H") > 0, "notes: fewer than 4 H")
        call check(t, len(sampling_notes(1024, 30)) == 0, "notes: none for 1024 samples, H = 30")
    end subroutine test_notes

    subroutine cubic_residual(self, y, lambda, f, stat)
        class(cubic_t), intent(inout) :: self
        real(dp), intent(in) :: y(:), lambda
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        self%evaluations = self%evaluations + 1
        f(1) = y(1)**3 - 3.0_dp*y(1) + lambda
        f(2) = y(2) - y(1)**2
    end subroutine cubic_residual

    subroutine cubic_jacobian(self, y, lambda, jy, jl, stat)
        class(cubic_t), intent(inout) :: self
        real(dp), intent(in) :: y(:), lambda
        real(dp), intent(out) :: jy(:, :), jl(:)
        integer, intent(inout) :: stat
        jy(1, :) = [3.0_dp*y(1)**2 - 3.0_dp, 0.0_dp]
        jy(2, :) = [-2.0_dp*y(1), 1.0_dp]
        jl = [1.0_dp, 0.0_dp]
    end subroutine cubic_jacobian

    !> From lambda = -3 (y1 = 2.1038) to lambda = 3 (y1 = -2.1038) the curve must pass the
    !> fold at lambda = 2 going back to lambda = -2, then forward again.
    subroutine test_folds(t)
        type(test_counter_t), intent(inout) :: t
        type(cubic_t) :: sys
        type(continuation_options_t) :: co
        type(continuation_state_t) :: st
        type(continuation_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: lmax, lmin, ymin_at_lmax, worst, tl_old, y1_end
        integer :: folds, k
        co%start = -3.0_dp
        co%stop = 3.0_dp
        co%step = 0.05_dp
        co%min_step = 1.0e-6_dp
        co%max_step = 0.2_dp
        co%tol = 1.0e-12_dp
        co%yscale = [1.0_dp]
        call start_continuation(sys, co, [2.0_dp, 4.0_dp], st, rep, error)
        call check_error(t, error, "fold: start", .false.)
        call check(t, st%reason == reason_running, "fold: started")
        lmax = -huge(1.0_dp)
        lmin = huge(1.0_dp)
        ymin_at_lmax = 0.0_dp
        worst = 0.0_dp
        folds = 0
        do k = 1, 2000
            tl_old = st%tl
            call continuation_step(sys, co, st, rep, error)
            if (allocated(error)) exit
            if (rep%accepted) then
                if (tl_old*st%tl < 0.0_dp) folds = folds + 1
                worst = max(worst, abs(st%y(1)**3 - 3.0_dp*st%y(1) + st%lambda), &
                            abs(st%y(2) - st%y(1)**2))
                if (st%y(1) > 0.0_dp .and. st%lambda > lmax) then
                    lmax = st%lambda
                    ymin_at_lmax = st%y(1)
                end if
                if (st%y(1) < 0.5_dp .and. st%y(1) > -1.5_dp) lmin = min(lmin, st%lambda)
            end if
            if (st%reason /= reason_running) exit
        end do
        call check_error(t, error, "fold: steps", .false.)
        call check(t, st%reason == reason_end, "fold: reached the end of the range")
        y1_end = -2.10380340273554_dp
        call check_close(t, st%lambda, 3.0_dp, "fold: last point at the end exactly", 1.0e-14_dp)
        call check_close(t, st%y(1), y1_end, "fold: the far branch at the end", 1.0e-9_dp)
        call check(t, folds == 2, "fold: two turning points passed", "folds = "//itoa(folds))
        call check(t, lmax <= 2.0_dp + 1.0e-9_dp .and. lmax > 1.98_dp, &
                   "fold: the upper fold lambda = 2 is approached")
        call check_close(t, ymin_at_lmax, 1.0_dp, "fold: upper fold at y1 = 1", atol=0.15_dp)
        call check(t, lmin >= -2.0_dp - 1.0e-9_dp .and. lmin < -1.98_dp, &
                   "fold: the lower fold lambda = -2 is approached")
        call check(t, worst <= 1.0e-10_dp, "fold: every point solves F = 0")
        call check(t, st%points > 40 .and. st%points < 400, "fold: a reasonable number of points", &
                   "points = "//itoa(st%points))
    end subroutine test_folds

    !> dF/dlambda of the friction family against central differences, for every parameter.
    subroutine test_parameter_derivatives(t)
        type(test_counter_t), intent(inout) :: t
        character(len=16), parameter :: names(4) = [character(len=16) :: 'omega', &
                                                   'force_amplitude', 'mu', 'normal_load']
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(friction_family_t) :: fam
        type(error_type), allocatable :: error
        real(dp), allocatable :: y(:), jy(:, :), jl(:), fp(:), fm(:), fd(:)
        real(dp) :: p, h, err
        integer :: k, n, stat
        character(len=120) :: buf
        m = damped_seed()
        ho%harmonics = 15
        ho%samples = 256
        ho%rho = 0.2_dp
        call solve_periodic(m, ho, sol, error)
        call check_error(t, error, "dF/dlambda: solve", .false.)
        if (allocated(error)) return
        do k = 1, size(names)
            p = sweep_parameter_value(m, names(k))
            call new_friction_family(fam, m, ho, names(k), p, 0.2_dp, error)
            call check_error(t, error, "dF/dlambda "//trim(names(k))//": family", .false.)
            if (allocated(error)) return
            n = fam%prob%n
            ! a point off the solution, so that every term of the derivative is exercised
            y = reshape(sol%rcoef, [n])*0.9_dp
            allocate (jy(n, n), jl(n), fp(n), fm(n))
            stat = 0
            call fam%jacobian(y, p, jy, jl, stat)
            h = 1.0e-6_dp*abs(p)
            call fam%residual(y, p + h, fp, stat)
            call fam%residual(y, p - h, fm, stat)
            fd = (fp - fm)/(2.0_dp*h)
            err = maxval(abs(fd - jl))/maxval(abs(fd))
            write (buf, '(a,es9.2,a,es9.2)') "relative difference ", err, ", |dF/dl| ", &
                maxval(abs(fd))
            call check(t, stat == 0 .and. err <= 1.0e-6_dp .and. maxval(abs(fd)) > 0.0_dp, &
                       "dF/dlambda "//trim(names(k))//" = central differences", trim(buf))
            call fam%destroy()
            deallocate (jy, jl, fp, fm)
        end do
    end subroutine test_parameter_derivatives

    !> A curve in omega through both resonances of the damped seed system; every point must
    !> be the solution a separate solve finds at its omega, the energy must balance and the
    !> points above the resonances must be stable.
    !> Step control with many contacts (issue 25): a main mass with 16 tuned-apart absorbers,
    !> each rubbing on the ground (mu N 0.01-0.0175), swept through the resonance where the
    !> absorbers go from stuck to slipping and back, with the default step control (no
    !> min_step): the curve ends in about as many points as the range over max_step asks
    !> (before, the norm of the 16 contacts' forces made the steps crawl through the peak),
    !> and its points are the separate solves'.
    subroutine test_many_contacts(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: nt = 16
        type(model_t) :: m, mk
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(reference_options_t) :: ro
        type(error_type), allocatable :: error
        real(dp) :: kt, worst, peak
        integer :: i, k, kpeak, nslip
        m%ndof = nt + 1
        allocate (m%mass(nt + 1, nt + 1), m%stiffness(nt + 1, nt + 1))
        m%mass = 0.0_dp
        m%stiffness = 0.0_dp
        m%mass(1, 1) = 1.0_dp
        m%stiffness(1, 1) = 1.0_dp
        do i = 2, nt + 1
            kt = 0.05_dp*(1.0_dp + 0.03_dp*(i - 1))
            m%mass(i, i) = 0.05_dp
            m%stiffness(1, 1) = m%stiffness(1, 1) + kt
            m%stiffness(i, i) = kt
            m%stiffness(1, i) = -kt
            m%stiffness(i, 1) = -kt
        end do
        m%damping = 0.01_dp*m%stiffness
        m%omega = 1.0_dp
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [0.1_dp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [(i, i=2, nt + 1)]
        m%contact_dof2 = [(0, i=1, nt)]
        m%mu = [(0.5_dp, i=1, nt)]
        m%normal_load = [(0.02_dp*(1.0_dp + 0.05_dp*(i - 1)), i=1, nt)]
        ho%harmonics = 3
        ho%odd_only = .true.
        so%parameter = 'omega'
        so%start = 1.0_dp
        so%stop = 1.8_dp
        so%max_step = 0.04_dp
        so%step = 0.04_dp
        so%stability = .false.
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "16 contacts: sweep without error", .false.)
        if (allocated(error)) return
        call check(t, res%complete, "16 contacts: the sweep reaches the end", res%diagnosis)
        call check(t, res%npoints <= 100, "16 contacts: no crawl through the resonance "// &
                   "(range / max_step = 20; 58 points, 204 before issue 25)", &
                   itoa(res%npoints)//" points")
        peak = 0.0_dp
        kpeak = 1
        do k = 1, res%npoints
            if (res%points(k)%amplitude(1) > peak) then
                peak = res%points(k)%amplitude(1)
                kpeak = k
            end if
        end do
        nslip = 0
        do k = 1, res%npoints
            if (res%points(k)%stick(1) < 0.5_dp) nslip = nslip + 1
        end do
        call check(t, nslip > 3 .and. res%points(1)%stick(1) > 0.99_dp, "16 contacts: the "// &
                   "absorbers stick off resonance and slip through it", itoa(nslip))
        ! the separate solves with the curve's rho (the automatic one at its start: the
        ! sampled equations near the peak have nearby solutions a different rho can pick)
        mk = m
        mk%omega = so%start
        call solve_periodic(mk, ho, sol, error)
        call check_error(t, error, "16 contacts: the start's solve", .false.)
        if (allocated(error)) return
        ho%rho = sol%rho
        worst = 0.0_dp
        do k = max(1, kpeak - 3), min(res%npoints, kpeak + 3)
            mk = m
            mk%omega = res%points(k)%parameter
            call solve_periodic(mk, ho, sol, error)
            if (allocated(error)) exit
            worst = max(worst, maxval(abs([(maxval(abs(sol%x(:, i))), i=1, nt + 1)] - &
                                          res%points(k)%amplitude))/peak)
        end do
        call check_error(t, error, "16 contacts: separate solves", .false.)
        call check(t, worst <= 1.0e-6_dp, "16 contacts: the points about the peak are the "// &
                   "separate solves'", "worst relative difference "//rtoa(worst))
    end subroutine test_many_contacts

    subroutine test_sweep_against_solves(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m, mk
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(reference_options_t) :: ro
        type(error_type), allocatable :: error
        real(dp) :: worst, balance, amp(2), peak
        integer :: k, i, nstable_high, nhigh
        logical :: monotone
        m = damped_seed()
        ho%harmonics = 15
        ho%samples = 64
        ho%rho = 0.2_dp
        so%parameter = 'omega'
        so%start = 0.3_dp
        so%stop = 3.0_dp
        so%step = 0.05_dp
        so%max_step = 0.1_dp
        so%stability = .false.
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "sweep omega: no error", .false.)
        if (allocated(error)) return
        call check(t, res%complete, "sweep omega: reached the end", res%diagnosis)
        call check(t, res%npoints > 20, "sweep omega: points", itoa(res%npoints))
        call check_close(t, res%points(res%npoints)%parameter, 3.0_dp, "sweep omega: ends at stop")
        worst = 0.0_dp
        balance = 0.0_dp
        monotone = .true.
        nhigh = 0
        nstable_high = 0
        do k = 1, res%npoints, 3
            mk = m
            mk%omega = res%points(k)%parameter
            call solve_periodic(mk, ho, sol, error)
            if (allocated(error)) exit
            amp = [(maxval(abs(sol%x(:, i))), i=1, 2)]
            worst = max(worst, maxval(abs(amp - res%points(k)%amplitude)/amp))
            balance = max(balance, abs(sol%work_forcing - res%points(k)%dissipation)/ &
                          sol%work_forcing)
        end do
        call check_error(t, error, "sweep omega: point solves", .false.)
        call check(t, worst <= 1.0e-6_dp, "sweep omega: amplitudes = separate solves", &
                   "worst relative difference "//rtoa(worst))
        call check(t, balance <= 1.0e-6_dp, "sweep omega: dissipation = forcing work")
        do k = 2, res%npoints
            if (res%points(k)%arclength <= res%points(k - 1)%arclength) monotone = .false.
        end do
        call check(t, monotone, "sweep omega: arclength increases")
        ! the stability of a few points above the resonances
        so%start = 2.0_dp
        so%stop = 3.0_dp
        so%step = 0.25_dp
        so%max_step = 0.25_dp
        so%stability = .true.
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "sweep omega with stability: no error", .false.)
        if (allocated(error)) return
        do k = 1, res%npoints
            nhigh = nhigh + 1
            if (res%points(k)%stable == 1 .and. res%points(k)%floquet_max < 1.0_dp) &
                nstable_high = nstable_high + 1
        end do
        call check(t, nhigh > 3 .and. nstable_high == nhigh, &
                   "sweep omega: stable above the resonances", itoa(nstable_high)//"/"//itoa(nhigh))
        peak = 0.0_dp
        do k = 1, res%npoints
            peak = max(peak, res%points(k)%amplitude(2))
        end do
        call check(t, peak > 3.0_dp*res%points(res%npoints)%amplitude(2), &
                   "sweep omega: a resonance peak")
    end subroutine test_sweep_against_solves

    !> A sweep in the forcing amplitude and one in mu, checked at their ends against solves.
    subroutine test_sweep_amplitude(t)
        type(test_counter_t), intent(inout) :: t
        character(len=16), parameter :: names(3) = [character(len=16) :: 'force_amplitude', &
                                                   'mu', 'normal_load']
        real(dp), parameter :: lo(3) = [2.0_dp, 0.2_dp, 0.5_dp], hi(3) = [15.0_dp, 1.5_dp, 3.0_dp]
        type(model_t) :: m, mk
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(reference_options_t) :: ro
        type(error_type), allocatable :: error
        real(dp) :: amp(2)
        integer :: k, i, last
        m = damped_seed()
        m%omega = 1.2_dp
        ho%harmonics = 15
        ho%samples = 64
        ho%rho = 0.2_dp
        do k = 1, 3
            so%parameter = names(k)
            so%start = lo(k)
            so%stop = hi(k)
            so%step = 0.0_dp
            so%max_step = 0.0_dp
            so%stability = .false.
            call run_sweep(m, ho, ro, so, res, error)
            call check_error(t, error, "sweep "//trim(names(k))//": no error", .false.)
            if (allocated(error)) return
            call check(t, res%complete, "sweep "//trim(names(k))//": complete", res%diagnosis)
            last = res%npoints
            mk = m
            call set_sweep_parameter(mk, names(k), res%points(last)%parameter, m%force_amplitude)
            call solve_periodic(mk, ho, sol, error)
            if (allocated(error)) return
            amp = [(maxval(abs(sol%x(:, i))), i=1, 2)]
            call check_close(t, res%points(last)%amplitude, amp, "sweep "//trim(names(k))// &
                             ": last point = a separate solve", 1.0e-6_dp)
            call check(t, all(res%points(1:last)%stable == -1), "sweep "//trim(names(k))// &
                       ": stability not computed when not asked")
        end do
    end subroutine test_sweep_amplitude

    !> Bad sweep options are input errors naming the argument opts%...
    subroutine test_bad_sweep(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(reference_options_t) :: ro
        type(error_type), allocatable :: error
        m = damped_seed()
        so%parameter = 'stiffness'
        so%start = 1.0_dp
        so%stop = 2.0_dp
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "bad sweep: unknown parameter", .true.)
        if (allocated(error)) call check(t, index(error%message, "opts%parameter") > 0 .and. &
                                         error%stat == stickslip_stat%input, &
                                         "bad sweep: names opts%parameter", error%message)
        so%parameter = 'omega'
        so%start = -1.0_dp
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "bad sweep: omega < 0", .true.)
        so%start = 1.0_dp
        so%stop = 1.0_dp
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "bad sweep: empty range", .true.)
    end subroutine test_bad_sweep

    !> stability_block: a point whose weighted-residual solve at the curve's rho does not
    !> converge (rho = 1e-14 on the damped seed: the friction equality barely sees the
    !> force) gets its verdict from a fresh solve with the automatic rho, the multipliers of
    !> periodic_stability on an ordinary solve.
    subroutine test_fresh_start(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho, curve
        type(hbm_solution_t) :: ps
        type(sweep_options_t) :: so
        type(reference_options_t) :: ro
        type(floquet_t) :: fl
        type(frc_point_t) :: pts(1)
        type(error_type), allocatable :: error
        real(dp) :: seconds
        m = damped_seed()
        m%omega = 4.5_dp
        ho%harmonics = 15
        ho%want_samples = .true.
        call solve_periodic(m, ho, ps, error)
        if (.not. allocated(error)) call periodic_stability(m, ps, ro, fl, error)
        call check(t, .not. allocated(error) .and. fl%verdict /= 'unknown', &
                   "fresh start: the ordinary solve has a verdict", msg(error))
        if (allocated(error)) return
        curve = ho
        curve%rho = 1.0e-14_dp
        curve%start = 'direct'
        call solve_periodic(m, curve, ps, error)
        call check(t, .not. allocated(error) .and. .not. ps%converged, &
                   "fresh start: the solve at the curve's rho does not converge (the case "// &
                   "tests the retry)")
        if (allocated(error)) return
        so%parameter = 'omega'
        so%stability = .true.
        pts(1)%parameter = 4.5_dp
        pts(1)%stable = -1
        seconds = 0.0_dp
        call stability_block(m, curve, m%force_amplitude, so, ro, pts, seconds, error)
        call check(t, .not. allocated(error), "fresh start: the block runs", msg(error))
        if (allocated(error)) return
        call check(t, pts(1)%stable == merge(1, 0, fl%stable), &
                   "fresh start: the verdict of the ordinary solve", itoa(pts(1)%stable))
        call check_close(t, [pts(1)%floquet_max], [fl%max_modulus], &
                         "fresh start: its largest multiplier", rtol=1.0e-9_dp, atol=0.0_dp)
    end subroutine test_fresh_start

end module test_continuation
