!> Families of forced-response curves: the sweep in omega (stickslip_sweep) repeated for a
!> list of values of a second parameter (the normal load, the preload, the friction
!> coefficient or the forcing amplitude), with each curve's peak and the peaks of the two
!> linear limits (every contact stuck, every contact slipping: stickslip_linear_response).
!> The classic damper-design chart, the resonance peak against the normal load with its
!> optimum between the stuck and the slipping limits, comes from one run.
!>
!> The curves' first points are solved one after the other, each started from its
!> neighbour's (the value before it in the list); the curves are then traced in parallel
!> over OpenMP threads, each from its first point (a curve's own stability runs on its
!> thread). A curve's peak is its largest point, refined by single solves: a golden-section
!> search in omega between the largest point's neighbours, so that it does not depend on
!> where the continuation happened to put its points. Checkpoints: one observer per curve
!> (stickslip_checkpoint writes one file each), and a saved curve per curve to go on from.
module stickslip_sweep_family
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_untrusted
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, validate_model
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options
    use stickslip_reference, only: reference_options_t
    use stickslip_progress, only: progress_t
    use stickslip_sweep_options, only: sweep_options_t, validate_sweep_options, &
        set_sweep_parameter
    use stickslip_sweep_result, only: frc_point_t, sweep_result_t, sweep_observer_t, &
        point_amplitudes, vibration_samples_t
    use stickslip_sweep, only: run_sweep
    use stickslip_sweep_point, only: keep_coefficients
    use stickslip_linear_response, only: limit_peak_t, linear_limit_peaks
    use stickslip_golden, only: golden_search_t
    use stickslip_cyclic, only: cyclic_t
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic
    use stickslip_blas_threads, only: parallel_threads
    implicit none
    private
    public :: family_options_t, family_peak_t, family_result_t, run_family, curve_peaks
    public :: validate_family_options, observer_slot_t

    !> Most curves in a family.
    integer, parameter, public :: max_family_curves = 200

    !> The second parameter of a family and how its peaks are measured.
    type :: family_options_t
        !> 'normal_load', 'preload', 'mu' or 'force_amplitude' (as &sweep parameter).
        character(len=16) :: family_parameter = ''
        !> Its values, one curve each, in this order (each curve starts from the one
        !> before it).
        real(dp), allocatable :: family_values(:)
        !> The amplitude the peaks are measured by: 'half_peak_to_peak' (the vibration
        !> amplitude), 'first_harmonic' or 'max_abs' (stickslip_sweep_result's
        !> point_amplitudes).
        character(len=20) :: measure = 'half_peak_to_peak'
        !> The peaks of the linear limits (stuck, slipping) of every curve's model.
        logical :: references = .true.
    end type family_options_t

    !> The peak of one observed displacement on one curve.
    type :: family_peak_t
        !> Amplitude (measure of family_options_t) [model length unit], the omega where it
        !> is reached [rad/s] and the energy dissipated per period there [energy unit].
        real(dp) :: amplitude = 0.0_dp, omega = 0.0_dp, dissipation = 0.0_dp
        !> Found by single solves between the neighbours of the curve's largest point
        !> (.false.: the largest point itself: at an end of the curve, between points where
        !> omega turns back (a fold), or a solve failed).
        logical :: refined = .false.
        !> The largest point is not the first or the last of the curve.
        logical :: interior = .false.
        !> The curve's largest point.
        integer :: point = 0
        !> Worst level of the failed checks (0, level_warning, level_untrusted) and the
        !> first such check: the largest point's own, 'peak_at_end' (a warning: the range
        !> does not hold the resonance), 'incomplete' (untrusted: the curve stopped short).
        integer :: check_level = 0
        character(len=32) :: check = ''
        !> Single solves of the refinement.
        integer :: solves = 0
    end type family_peak_t

    !> An observer of one curve of a family (e.g. its checkpoint writer).
    type :: observer_slot_t
        class(sweep_observer_t), allocatable :: observer
    end type observer_slot_t

    !> One curve's peaks and linear limits, while the curves are traced.
    type :: curve_peaks_t
        type(family_peak_t), allocatable :: peaks(:)
        type(limit_peak_t), allocatable :: stuck(:), slipping(:)
    end type curve_peaks_t

    !> A family of curves.
    type :: family_result_t
        !> The second parameter and its values.
        character(len=16) :: family_parameter = ''
        real(dp), allocatable :: values(:)
        !> The curves, one per value (a curve whose first point has no solution has no
        !> points and says why in its diagnosis).
        type(sweep_result_t), allocatable :: curves(:)
        !> Peaks, observed displacement x curve.
        type(family_peak_t), allocatable :: peaks(:, :)
        !> The linear limits' peaks over the sweep's range, observed displacement x curve
        !> (unallocated without references).
        type(limit_peak_t), allocatable :: stuck(:, :), slipping(:, :)
        !> Every curve reached the end of its range.
        logical :: complete = .false.
        character(len=:), allocatable :: diagnosis
        !> Every curve's findings, keys prefixed with 'curve<k>_', messages with the curve and
        !> its value.
        type(diagnostics_t) :: diagnostics
        !> CPU seconds summed over the curves, wall seconds of the run, threads used.
        real(dp) :: seconds = 0.0_dp, wall_seconds = 0.0_dp
        integer :: threads = 1
    end type family_result_t

contains

    !> Check family options against the model and the sweep. Errors (stat input) name the
    !> component (family%family_values(3) = ...).
    subroutine validate_family_options(model, sweep, family, error)
        !> The model.
        type(model_t), intent(in) :: model
        !> The sweep each curve runs.
        type(sweep_options_t), intent(in) :: sweep
        !> The family.
        type(family_options_t), intent(in) :: family
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        type(sweep_options_t) :: probe
        character(len=200) :: buf
        integer :: k
        buf = ''
        if (sweep%parameter /= 'omega') then
            buf = "sweep%parameter = '"//trim(sweep%parameter)//"': a family sweeps omega "// &
                  "(its curves are forced-response curves)"
        else
            select case (family%family_parameter)
            case ('normal_load', 'preload', 'mu', 'force_amplitude')
            case default
                buf = "family%family_parameter = '"//trim(family%family_parameter)// &
                      "': must be 'normal_load', 'preload', 'mu' or 'force_amplitude'"
            end select
        end if
        if (len_trim(buf) == 0) then
            if (.not. allocated(family%family_values)) then
                buf = "family%family_values: missing (one value per curve)"
            else if (size(family%family_values) < 1 .or. &
                     size(family%family_values) > max_family_curves) then
                write (buf, '(a,i0,a,i0)') "family%family_values: ", &
                    size(family%family_values), " values; give 1 to ", max_family_curves
            else
                do k = 1, size(family%family_values)
                    if (.not. ieee_is_finite(family%family_values(k))) then
                        write (buf, '(a,i0,a)') "family%family_values(", k, "): not finite"
                        exit
                    end if
                    if (any(family%family_values(1:k - 1) == family%family_values(k))) then
                        write (buf, '(a,i0,a,g0.6,a)') "family%family_values(", k, ") = ", &
                            family%family_values(k), ": given twice"
                        exit
                    end if
                end do
            end if
        end if
        if (len_trim(buf) == 0) then
            select case (family%measure)
            case ('half_peak_to_peak', 'first_harmonic', 'max_abs')
            case default
                buf = "family%measure = '"//trim(family%measure)//"': must be "// &
                      "'half_peak_to_peak', 'first_harmonic' or 'max_abs'"
            end select
        end if
        if (len_trim(buf) > 0) then
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        ! the values as a range of the parameter: the sweep's own checks of it
        probe = sweep
        probe%parameter = family%family_parameter
        probe%start = minval(family%family_values)
        probe%stop = maxval(family%family_values)
        probe%step = 0.0_dp
        probe%min_step = 0.0_dp
        probe%max_step = 0.0_dp
        probe%stability = .false.
        call validate_sweep_options(model, probe, error)
        if (allocated(error)) then
            ! in the family's words: the parameter is family_parameter, its range the values
            k = index(error%message, "opts%start, opts%stop: ")
            if (k == 1) then
                error%message = "family%family_values: "//error%message(24:)
            else if (index(error%message, "opts%parameter") == 1) then
                error%message = "family%family_parameter"//error%message(15:)
            else
                error%message = "family%family_values: "//error%message
            end if
            return
        end if
        if (family%family_parameter == 'force_amplitude' .and. &
            .not. all(family%family_values > 0.0_dp)) then
            call fatal_error(error, "family%family_values: a forcing amplitude must be > 0", &
                             stickslip_stat%input)
        end if
    end subroutine validate_family_options

    !> The forced-response curves of `model` over the omega range of `sweep`, one per value
    !> of family%family_parameter, with their peaks and the linear limits' peaks. Each
    !> point is solved with the options `hbm`; with sweep%stability its Floquet multipliers
    !> come from the exact reference (options `ref`). `observers(k)` sees curve k after
    !> every point; `resumes(k)`, when `resumed(k)`, is a saved curve k to go on from.
    !> A curve that stops short or has no first point is an outcome (res%complete false,
    !> res%diagnosis), not an error. Errors: stat input (invalid model or options, a
    !> resume of another size), the observers' errors, stat numerical (a NaN).
    subroutine run_family(model, hbm, ref, sweep, family, res, error, observers, resumes, &
                          resumed, progress, cyclic)
        !> The model at the case's values.
        type(model_t), intent(in) :: model
        !> Weighted-residual options of every point.
        type(hbm_options_t), intent(in) :: hbm
        !> Options of the exact reference used for the stability.
        type(reference_options_t), intent(in) :: ref
        !> The sweep of every curve (parameter 'omega').
        type(sweep_options_t), intent(in) :: sweep
        !> The second parameter and its values.
        type(family_options_t), intent(in) :: family
        !> The family.
        type(family_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> One observer per curve (e.g. its checkpoint; a curve whose slot holds none is not
        !> observed).
        type(observer_slot_t), intent(inout), optional :: observers(:)
        !> Saved curves, and which of them to go on from.
        type(sweep_result_t), intent(in), optional :: resumes(:)
        logical, intent(in), optional :: resumed(:)
        !> Progress hook: told after every curve.
        type(progress_t), intent(inout), optional :: progress
        !> `model` is one sector of this tuned disk: every curve is its travelling wave
        !> (run_sweep's cyclic); the linear limits are the sector's travelling wave's.
        type(cyclic_t), intent(in), optional :: cyclic
        type(model_t), allocatable :: models(:)
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: errors(:)
        type(curve_peaks_t), allocatable :: found(:)
        type(progress_t) :: curves_progress
        integer :: j
        type(error_type), allocatable :: e
        real(dp), allocatable :: starts(:, :, :), amplitude0(:)
        logical, allocatable :: started(:), go_on(:)
        integer :: n, k, nthreads, done, nobs, last
        integer(int64) :: c0, c1, rate
        character(len=40) :: buf

        call system_clock(c0, rate)
        call validate_model(model, error)
        if (allocated(error)) return
        call validate_options(hbm, error)
        if (allocated(error)) return
        call validate_family_options(model, sweep, family, error)
        if (allocated(error)) return
        n = size(family%family_values)
        if (present(observers)) then
            if (size(observers) /= n) then
                call fatal_error(error, "observers: one per curve", stickslip_stat%input)
                return
            end if
        end if
        allocate (go_on(n))
        go_on = .false.
        if (present(resumes) .and. present(resumed)) then
            if (size(resumes) /= n .or. size(resumed) /= n) then
                call fatal_error(error, "resumes, resumed: one per curve", stickslip_stat%input)
                return
            end if
            go_on = resumed
        end if
        res%family_parameter = family%family_parameter
        res%values = family%family_values
        allocate (res%curves(n), models(n), errors(n), started(n), found(n))
        amplitude0 = model%force_amplitude
        do k = 1, n
            models(k) = model
            call set_sweep_parameter(models(k), family%family_parameter, &
                                     family%family_values(k), amplitude0)
        end do

        ! the first points, each from its neighbour's (a cold start where that fails)
        ho = hbm
        ho%want_samples = .false.
        started = .false.
        last = 0
        do k = 1, n
            block
                type(model_t) :: m
                m = models(k)
                call set_sweep_parameter(m, 'omega', sweep%start, m%force_amplitude)
                if (present(cyclic)) then
                    if (last > 0) then
                        call solve_periodic_cyclic(m, cyclic, ho, sol, e, &
                                                   r_start=starts(:, :, last))
                        if (.not. allocated(e)) then
                            if (.not. sol%converged) &
                                call solve_periodic_cyclic(m, cyclic, ho, sol, e)
                        end if
                    else
                        call solve_periodic_cyclic(m, cyclic, ho, sol, e)
                    end if
                else if (last > 0) then
                    call solve_periodic(m, ho, sol, e, r_start=starts(:, :, last))
                    if (.not. allocated(e)) then
                        if (.not. sol%converged) call solve_periodic(m, ho, sol, e)
                    end if
                else
                    call solve_periodic(m, ho, sol, e)
                end if
            end block
            if (allocated(e)) then
                if (e%stat /= stickslip_stat%numerical) then
                    call move_alloc(e, error)
                    return
                end if
                deallocate (e)
                cycle
            end if
            if (.not. sol%converged) cycle
            if (.not. allocated(starts)) allocate (starts(size(sol%rcoef, 1), &
                                                         size(sol%rcoef, 2), n))
            starts(:, :, k) = sol%rcoef
            started(k) = .true.
            last = k
        end do

        ! the curves, in parallel (each with its own model, options and observer)
        if (present(progress)) curves_progress = progress%stage('family', 'curves')
        nthreads = max(1, min(parallel_threads(), n))
        res%threads = nthreads
        done = 0
        !$omp parallel do num_threads(nthreads) schedule(dynamic, 1) default(shared) &
        !$omp private(k)
        do k = 1, n
            call one_curve(k)
            !$omp critical (family_progress)
            done = done + 1
            if (present(progress)) then
                write (buf, '(g0.6)') family%family_values(k)
                call curves_progress%report(done, n, "the last "// &
                                            trim(family%family_parameter)//" = "//trim(buf))
            end if
            !$omp end critical (family_progress)
        end do
        !$omp end parallel do

        do k = 1, n
            if (allocated(errors(k)%message)) then
                if (errors(k)%stat /= stickslip_stat%numerical) then
                    allocate (error)
                    error = errors(k)
                    return
                end if
            end if
        end do
        ! the peaks: observed displacement x curve
        nobs = 0
        do k = 1, n
            if (res%curves(k)%npoints > 0) then
                nobs = size(res%curves(k)%points(1)%amplitude)
                exit
            end if
        end do
        allocate (res%peaks(nobs, n))
        if (family%references) allocate (res%stuck(nobs, n), res%slipping(nobs, n))
        do k = 1, n
            if (allocated(found(k)%peaks)) then
                if (size(found(k)%peaks) == nobs) res%peaks(:, k) = found(k)%peaks
            end if
            if (.not. family%references) cycle
            res%stuck(:, k) = limit_peak_t(ieee_value(1.0_dp, ieee_quiet_nan), &
                                           ieee_value(1.0_dp, ieee_quiet_nan))
            res%slipping(:, k) = res%stuck(:, k)
            if (allocated(found(k)%stuck)) then
                if (size(found(k)%stuck) == nobs) res%stuck(:, k) = found(k)%stuck
            end if
            if (allocated(found(k)%slipping)) then
                if (size(found(k)%slipping) == nobs) res%slipping(:, k) = found(k)%slipping
            end if
        end do
        res%complete = .true.
        res%diagnosis = ''
        do k = 1, n
            associate (c => res%curves(k))
                res%seconds = res%seconds + c%seconds
                write (buf, '(g0.6)') family%family_values(k)
                if (c%npoints == 0) then
                    res%complete = .false.
                    if (.not. allocated(c%diagnosis)) c%diagnosis = "no solution at the start"
                    res%diagnosis = res%diagnosis//"; curve "//itoa(k)//" ("// &
                                    trim(family%family_parameter)//" = "//trim(buf)//"): "// &
                                    c%diagnosis
                    cycle
                end if
                if (.not. c%complete) then
                    res%complete = .false.
                    res%diagnosis = res%diagnosis//"; curve "//itoa(k)//" ("// &
                                    trim(family%family_parameter)//" = "//trim(buf)//"): "// &
                                    c%diagnosis
                end if
                ! each finding named by its curve
                if (allocated(c%diagnostics%items)) then
                    do j = 1, size(c%diagnostics%items)
                        associate (item => c%diagnostics%items(j))
                            call res%diagnostics%add(item%level, "curve"//itoa(k)//"_"// &
                                                     item%key, "curve "//itoa(k)//" ("// &
                                                     trim(family%family_parameter)//" = "// &
                                                     trim(buf)//"): "//item%message)
                        end associate
                    end do
                end if
            end associate
        end do
        if (len(res%diagnosis) > 2) res%diagnosis = res%diagnosis(3:)
        call system_clock(c1)
        res%wall_seconds = real(c1 - c0, dp)/real(rate, dp)

    contains

        !> Curve k: its sweep, its peaks and its linear limits.
        subroutine one_curve(k)
            integer, intent(in) :: k
            type(hbm_options_t) :: hk
            type(error_type), allocatable :: ek
            logical :: resume_k
            character(len=40) :: text
            resume_k = go_on(k)
            if (.not. started(k) .and. .not. resume_k) then
                write (text, '(g0.6)') sweep%start
                res%curves(k)%diagnosis = "no solution at the start of the range (omega = "// &
                                          trim(text)//")"
                return
            end if
            call trace_curve(k, resume_k, ek)
            if (allocated(ek)) then
                if (ek%stat == stickslip_stat%numerical .and. &
                    res%curves(k)%npoints == 0) then
                    res%curves(k)%diagnosis = ek%message
                else
                    errors(k) = ek
                    return
                end if
            end if
            if (res%curves(k)%npoints == 0) return
            hk = hbm
            hk%rho = res%curves(k)%rho
            call curve_peaks(models(k), hk, sweep, family%measure, res%curves(k), &
                             found(k)%peaks, ek, cyclic)
            if (allocated(ek)) then
                errors(k) = ek
                return
            end if
            if (.not. family%references) return
            ! the linear limits (on a sector: its travelling wave's); a limit without motion
            ! (every DOF held) has no peak
            call linear_limit_peaks(models(k), .true., min(sweep%start, sweep%stop), &
                                    max(sweep%start, sweep%stop), family%measure, &
                                    found(k)%stuck, ek, observe=sweep%observe, cyclic=cyclic)
            if (allocated(ek)) deallocate (ek)
            call linear_limit_peaks(models(k), .false., min(sweep%start, sweep%stop), &
                                    max(sweep%start, sweep%stop), family%measure, &
                                    found(k)%slipping, ek, observe=sweep%observe, &
                                    cyclic=cyclic)
            if (allocated(ek)) deallocate (ek)
        end subroutine one_curve

        !> Run curve k's sweep (from its saved state when resumed).
        subroutine trace_curve(k, resume_k, ek)
            integer, intent(in) :: k
            logical, intent(in) :: resume_k
            type(error_type), allocatable, intent(out) :: ek
            ! the first point's start when it was found (absent otherwise)
            real(dp), allocatable :: r(:, :)
            logical :: observed
            if (started(k)) r = starts(:, :, k)
            observed = present(observers)
            if (observed) observed = allocated(observers(k)%observer)
            if (observed .and. resume_k) then
                call run_sweep(models(k), hbm, ref, sweep, res%curves(k), ek, &
                               observer=observers(k)%observer, resume=resumes(k), r_start=r, &
                               cyclic=cyclic)
            else if (observed) then
                call run_sweep(models(k), hbm, ref, sweep, res%curves(k), ek, &
                               observer=observers(k)%observer, r_start=r, cyclic=cyclic)
            else if (resume_k) then
                call run_sweep(models(k), hbm, ref, sweep, res%curves(k), ek, &
                               resume=resumes(k), r_start=r, cyclic=cyclic)
            else
                call run_sweep(models(k), hbm, ref, sweep, res%curves(k), ek, r_start=r, &
                               cyclic=cyclic)
            end if
        end subroutine trace_curve
    end subroutine run_family

    !> The peaks of `curve` (a sweep in omega of `model` with the options `sweep`) per
    !> observed displacement, measured as `measure`: its largest point, refined when it is
    !> interior and omega runs one way through it by a golden-section search in omega
    !> between its two neighbours, each step a single solve with the options `hbm` (the
    !> curve's rho) started from the best solution so far, to 1e-5 of that interval (the
    !> value to about 1e-10 relative where the peak is smooth). `interior`, `refined` and
    !> the check say which. Errors: those of solve_periodic (stat input).
    subroutine curve_peaks(model, hbm, sweep, measure, curve, peaks, error, cyclic)
        !> The model of the curve (omega is set per solve).
        type(model_t), intent(in) :: model
        !> Weighted-residual options with the curve's rho.
        type(hbm_options_t), intent(in) :: hbm
        !> The sweep's options (its observed combinations).
        type(sweep_options_t), intent(in) :: sweep
        !> 'half_peak_to_peak', 'first_harmonic' or 'max_abs'.
        character(len=*), intent(in) :: measure
        !> The curve.
        type(sweep_result_t), intent(in) :: curve
        !> Its peaks, one per observed displacement.
        type(family_peak_t), allocatable, intent(out) :: peaks(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> `model` is one sector of this disk (the curve its travelling wave).
        type(cyclic_t), intent(in), optional :: cyclic
        real(dp), allocatable :: a(:, :), best_r(:, :), ai(:)
        type(golden_search_t) :: search
        type(vibration_samples_t) :: samples
        type(hbm_solution_t) :: ps
        type(hbm_options_t) :: ho
        type(model_t) :: m
        integer :: np, nobs, i, k
        real(dp) :: w, lo, hi, best
        logical :: failed
        np = curve%npoints
        if (np == 0) then
            allocate (peaks(0))
            return
        end if
        nobs = size(curve%points(1)%amplitude)
        allocate (peaks(nobs), a(nobs, np))
        do k = 1, np
            a(:, k) = point_amplitudes(curve%points(k), measure, samples)
        end do
        ho = hbm
        ho%start = 'direct'
        ho%want_samples = measure == 'max_abs'
        m = model
        do i = 1, nobs
            associate (p => peaks(i))
                k = maxloc(a(i, :), 1, mask=ieee_is_finite(a(i, :)))
                if (k == 0) k = 1
                p%point = k
                p%amplitude = a(i, k)
                p%omega = curve%points(k)%omega
                p%dissipation = curve%points(k)%dissipation
                p%check_level = curve%points(k)%check_level
                p%check = curve%points(k)%check
                p%interior = k > 1 .and. k < np
                if (.not. p%interior) then
                    if (p%check_level < level_warning) then
                        p%check_level = level_warning
                        p%check = 'peak_at_end'
                    end if
                else if ((curve%points(k - 1)%omega - p%omega)* &
                         (curve%points(k + 1)%omega - p%omega) < 0.0_dp) then
                    lo = curve%points(k - 1)%omega
                    hi = curve%points(k + 1)%omega
                    best = p%amplitude
                    best_r = curve%points(k)%rcoef
                    failed = .false.
                    call search%begin(lo, hi, 1.0e-5_dp*abs(hi - lo))
                    do while (.not. search%done())
                        w = search%next()
                        call set_sweep_parameter(m, 'omega', w, model%force_amplitude)
                        if (present(cyclic)) then
                            call solve_periodic_cyclic(m, cyclic, ho, ps, error, r_start=best_r)
                        else
                            call solve_periodic(m, ho, ps, error, r_start=best_r)
                        end if
                        if (allocated(error)) return
                        p%solves = p%solves + 1
                        if (.not. ps%converged) then
                            failed = .true.
                            exit
                        end if
                        ai = measured(ps)
                        call search%tell(ai(i))
                        if (ai(i) > best) then
                            best = ai(i)
                            best_r = ps%rcoef
                            p%omega = w
                            p%dissipation = ps%diss_friction + ps%diss_damping
                        end if
                    end do
                    p%amplitude = best
                    p%refined = .not. failed
                end if
                if (.not. curve%complete) then
                    p%check_level = level_untrusted
                    p%check = 'incomplete'
                end if
            end associate
        end do

    contains

        !> The measured amplitudes of a solution's observed displacements.
        function measured(s) result(v)
            type(hbm_solution_t), intent(in) :: s
            real(dp), allocatable :: v(:)
            type(frc_point_t) :: pt
            integer :: j
            call keep_coefficients(m, s, sweep, pt, cyclic)
            if (measure == 'max_abs') then
                if (allocated(sweep%observe)) then
                    pt%amplitude = maxval(abs(matmul(s%x, transpose(sweep%observe))), dim=1)
                else
                    pt%amplitude = [(maxval(abs(s%x(:, j))), j=1, size(s%x, 2))]
                end if
            else
                allocate (pt%amplitude(size(pt%xcoef, 2)))
            end if
            v = point_amplitudes(pt, measure, samples)
        end function measured
    end subroutine curve_peaks
end module stickslip_sweep_family
