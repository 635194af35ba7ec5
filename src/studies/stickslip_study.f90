!> The work-precision study: one model solved by the weighted residual over a list of
!> harmonic counts (and quadrature sample counts) and by implicit Euler over a list of steps
!> per period, each run's error measured against the exact event-driven reference and its
!> CPU time measured (median of repeats for fast runs). Plain computation: the rows are
!> written by stickslip_csv and stickslip_summary.
module stickslip_study
    use stickslip_kinds, only: dp
    use stickslip_diagnostics, only: diagnostics_t
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, validate_model
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options
    use stickslip_hbm, only: hbm_max_harmonics, hbm_max_samples
    use stickslip_euler, only: euler_max_steps_per_period
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t, sample_reference
    use stickslip_reference_start, only: solve_reference_from_starts, reference_start_options_t, &
        validate_reference_start_options
    use stickslip_compare, only: comparison_t, compare_samples, evaluate_series
    use stickslip_progress, only: progress_t
    use stickslip_blas_threads, only: parallel_threads
    use stickslip_thread_clock, only: thread_cpu_seconds
    implicit none
    private
    public :: study_options_t, study_row_t, study_result_t, run_study, validate_study_options
    public :: default_study_options, median

    !> Options of the study (&study).
    type :: study_options_t
        !> Harmonic counts H of the weighted-residual runs.
        integer, allocatable :: harmonics(:)
        !> Quadrature samples of the weighted-residual runs, each combined with every H
        !> (0: the &hbm samples, raised to the smallest power of two >= 4 H when fewer).
        !> Pairs with samples < 2 H + 1, and H below a forcing harmonic, are skipped (and
        !> counted).
        integer, allocatable :: samples(:)
        !> Steps per period of the implicit Euler runs (integrated from rest until periodic).
        integer, allocatable :: steps_per_period(:)
        !> Points per period of the grid on which weighted-residual errors are measured.
        integer :: error_samples = 4096
        !> Most runs per configuration; a run faster than repeat_below is repeated and the
        !> median CPU time reported.
        integer :: repeats = 5
        !> CPU seconds below which a run is repeated [s].
        real(dp) :: repeat_below = 0.5_dp
    end type study_options_t

    !> One run of the study.
    type :: study_row_t
        !> 'hbm' or 'euler'.
        character(len=8) :: method = ''
        !> H for 'hbm', steps per period for 'euler'.
        integer :: parameter = 0
        !> Quadrature samples ('hbm'), steps per period ('euler').
        integer :: samples = 0
        !> Runs timed; hybrj residual evaluations ('hbm') or periods integrated ('euler').
        integer :: repeats = 0, iterations = 0
        !> Converged ('hbm') or periodic ('euler').
        logical :: converged = .false.
        !> Median CPU seconds of one run, on the thread that ran it [s].
        real(dp) :: cpu_seconds = 0.0_dp
        !> Errors against the reference (allocated arrays only when the run produced a
        !> solution, converged or not).
        type(comparison_t) :: cmp
    end type study_row_t

    !> The study: the reference and one row per run.
    type :: study_result_t
        !> The exact reference all errors are measured against.
        type(reference_result_t) :: reference
        !> CPU seconds of the reference (its start included), on the calling thread [s].
        real(dp) :: reference_seconds = 0.0_dp
        !> The runs, weighted residual first.
        type(study_row_t), allocatable :: rows(:)
        !> (H, samples) pairs skipped because samples < 2 H + 1 or because the basis of H
        !> harmonics does not hold every forcing harmonic.
        integer :: skipped = 0
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type study_result_t

    !> The error of one parallel run (the first in row order is returned).
    type :: task_error_t
        type(error_type), allocatable :: error
    end type task_error_t

contains

    !> The default study: H = 1, 2, 3, 5, 7, 10, 15, 20, 30, 40, 60, 80 with the &hbm
    !> samples, and Euler with 100 .. 20000 steps per period.
    pure function default_study_options() result(opts)
        type(study_options_t) :: opts
        opts%harmonics = [1, 2, 3, 5, 7, 10, 15, 20, 30, 40, 60, 80]
        opts%samples = [0]
        opts%steps_per_period = [100, 200, 500, 1000, 2000, 5000, 10000, 20000]
    end function default_study_options

    !> Check study options. Errors (stat input) name the component
    !> ("opts%repeats = 0: must be in 1..1000"); "hbm%samples" in a message is the samples
    !> of run_study's argument `hbm`.
    subroutine validate_study_options(opts, error)
        !> Options to check.
        type(study_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Longest list of harmonics, samples or steps_per_period.
        integer, parameter :: max_list = 256
        !> Largest error_samples (points of the error grid per period).
        integer, parameter :: max_error_samples = 10**6
        !> Most repeats of one run.
        integer, parameter :: max_repeats = 1000
        character(len=:), allocatable :: msg
        msg = ""
        if (.not. (allocated(opts%harmonics) .and. allocated(opts%samples) .and. &
                   allocated(opts%steps_per_period))) then
            msg = "opts%harmonics, opts%samples and opts%steps_per_period: must be set"
        else if (size(opts%harmonics) + size(opts%steps_per_period) == 0) then
            msg = "opts%harmonics, opts%steps_per_period: both empty, nothing to study"
        else if (size(opts%harmonics) > 0 .and. size(opts%samples) == 0) then
            msg = "opts%samples: empty (give 0 for the hbm%samples)"
        else if (max(size(opts%harmonics), size(opts%samples), size(opts%steps_per_period)) &
                 > max_list) then
            msg = "opts%harmonics, opts%samples, opts%steps_per_period: at most "//itoa(max_list)// &
                  " values each"
        else if (any(opts%harmonics < 1)) then
            msg = "opts%harmonics: every entry must be >= 1"
        else if (any(opts%harmonics > hbm_max_harmonics)) then
            msg = "opts%harmonics: every entry must be <= "//itoa(hbm_max_harmonics)
        else if (any(opts%samples < 0)) then
            msg = "opts%samples: every entry must be >= 0 (0: the hbm%samples)"
        else if (any(opts%samples > hbm_max_samples)) then
            msg = "opts%samples: every entry must be <= "//itoa(hbm_max_samples)//" (2**20)"
        else if (any(opts%steps_per_period < 2)) then
            msg = "opts%steps_per_period: every entry must be >= 2"
        else if (any(opts%steps_per_period > euler_max_steps_per_period)) then
            msg = "opts%steps_per_period: every entry must be <= "// &
                  itoa(euler_max_steps_per_period)
        else if (opts%error_samples < 2 .or. opts%error_samples > max_error_samples) then
            msg = "opts%error_samples = "//itoa(opts%error_samples)//": must be in 2.."// &
                  itoa(max_error_samples)
        else if (opts%repeats < 1 .or. opts%repeats > max_repeats) then
            msg = "opts%repeats = "//itoa(opts%repeats)//": must be in 1.."//itoa(max_repeats)
        else if (.not. (opts%repeat_below >= 0.0_dp .and. opts%repeat_below < huge(1.0_dp))) then
            msg = "opts%repeat_below: must be a finite number >= 0"
        end if
        if (len(msg) > 0) call fatal_error(error, msg, stickslip_stat%input)
    end subroutine validate_study_options

    !> Run the study on `model`: the reference (options `ref_opts`, started from the
    !> weighted residual with `hbm` or implicit Euler with `euler`), then every
    !> weighted-residual run (the options `hbm` with H and samples from `opts`) and every
    !> Euler run (the options `euler` with the steps from `opts`). A run that does not
    !> converge is a row with converged = F. Errors: stat input (invalid model or options);
    !> stat numerical (no reference: its diagnosis). Built with OpenMP, the runs after the
    !> reference share the threads (OMP_NUM_THREADS; the longest first), each computed as in
    !> a serial run and stored in its serial place; cpu_seconds is the CPU time of the thread
    !> that ran it.
    subroutine run_study(model, hbm, euler, ref_opts, opts, res, error, progress)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Weighted-residual options (H and samples are replaced).
        type(hbm_options_t), intent(in) :: hbm
        !> Time-stepping options (steps_per_period is replaced).
        type(euler_options_t), intent(in) :: euler
        !> Options of the reference.
        type(reference_start_options_t), intent(in) :: ref_opts
        !> Study options.
        type(study_options_t), intent(in) :: opts
        !> The study.
        type(study_result_t), intent(out) :: res
        !> Set on invalid input or when the reference cannot be computed.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook: told after every run (runs so far of the grid, the run).
        type(progress_t), intent(inout), optional :: progress
        type(hbm_options_t) :: ho
        type(euler_options_t) :: eo
        type(hbm_options_t), allocatable :: hos(:)
        type(euler_options_t), allocatable :: eos(:)
        type(task_error_t), allocatable :: errors(:)
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: c0, c1
        integer :: i, j, ns, n, ntask, done, nthreads

        call validate_model(model, error)
        if (allocated(error)) return
        call validate_study_options(opts, error)
        if (allocated(error)) return
        call validate_reference_start_options(ref_opts, error)
        if (allocated(error)) return
        call validate_options(hbm, error)
        if (allocated(error)) return

        c0 = thread_cpu_seconds()
        call solve_reference_from_starts(model, ref_opts, res%reference, error, hbm_opts=hbm, &
                                         euler_opts=euler)
        c1 = thread_cpu_seconds()
        res%reference_seconds = c1 - c0
        if (allocated(error)) return
        ! the judge's own checks (the runs' errors are the study's measurements, not
        ! findings: a work-precision study runs coarse settings on purpose)
        call res%diagnostics%extend(res%reference%diagnostics, "reference_")
        if (.not. res%reference%converged) then
            call fatal_error(error, "the study needs the exact reference, which did not "// &
                             "converge: "//res%reference%diagnosis, stickslip_stat%numerical)
            return
        end if

        ! weighted residual: every (H, samples) pair, errors on the fine grid; then implicit
        ! Euler from rest, errors on its own grid. The runs are independent: built with
        ! OpenMP they share the threads (the last, longest ones first), each row computed as
        ! in a serial run.
        call sample_reference(res%reference, opts%error_samples, xr, vr, rr, error)
        if (allocated(error)) return
        allocate (hos(0), eos(0))
        do i = 1, size(opts%harmonics)
            do j = 1, size(opts%samples)
                ho = hbm
                ho%harmonics = opts%harmonics(i)
                ns = opts%samples(j)
                if (ns == 0) then
                    ! the &hbm samples, or the smallest power of two >= 4 H when fewer
                    ns = 1
                    do while (ns < 4*ho%harmonics)
                        ns = 2*ns
                    end do
                    ns = max(hbm%samples, ns)
                end if
                if (ns < 2*ho%harmonics + 1 .or. .not. forcing_in_basis(ho)) then
                    res%skipped = res%skipped + 1
                    cycle
                end if
                ho%samples = ns
                ho%want_samples = .false.
                hos = [hos, ho]
            end do
        end do
        do i = 1, size(opts%steps_per_period)
            eo = euler
            eo%steps_per_period = opts%steps_per_period(i)
            eos = [eos, eo]
        end do
        ntask = size(hos) + size(eos)
        allocate (res%rows(ntask), errors(ntask))
        done = res%skipped
        nthreads = parallel_threads()
        !$omp parallel do schedule(dynamic, 1) default(shared) private(n) num_threads(nthreads)
        do n = ntask, 1, -1
            if (n <= size(hos)) then
                call hbm_row(hos(n), res%rows(n), errors(n)%error)
            else
                call euler_row(eos(n - size(hos)), res%rows(n), errors(n)%error)
            end if
            if (present(progress)) then
                !$omp critical (stickslip_study_progress)
                done = done + 1
                if (n <= size(hos)) then
                    call progress%report(done, size(opts%harmonics)*size(opts%samples) + &
                        size(opts%steps_per_period), "hbm H = "//itoa(hos(n)%harmonics)// &
                        ", samples = "//itoa(hos(n)%samples))
                else
                    call progress%report(done, size(opts%harmonics)*size(opts%samples) + &
                        size(opts%steps_per_period), "euler steps_per_period = "// &
                        itoa(eos(n - size(hos))%steps_per_period))
                end if
                !$omp end critical (stickslip_study_progress)
            end if
        end do
        !$omp end parallel do
        do n = 1, ntask
            if (allocated(errors(n)%error)) then
                call move_alloc(errors(n)%error, error)
                return
            end if
        end do

    contains

        logical function forcing_in_basis(ho)
            type(hbm_options_t), intent(in) :: ho
            forcing_in_basis = all(model%force_harmonic <= ho%harmonics)
            if (ho%odd_only) forcing_in_basis = forcing_in_basis .and. &
                                                all(mod(model%force_harmonic, 2) == 1)
        end function forcing_in_basis

        subroutine hbm_row(ho, row, error)
            type(hbm_options_t), intent(in) :: ho
            type(study_row_t), intent(out) :: row
            type(error_type), allocatable, intent(out) :: error
            type(hbm_solution_t) :: sol, again
            real(dp) :: times(opts%repeats), c0, c1
            real(dp), allocatable :: xs(:, :), vs(:, :), rs(:, :)
            integer :: k
            c0 = thread_cpu_seconds()
            call solve_periodic(model, ho, sol, error)
            c1 = thread_cpu_seconds()
            if (allocated(error)) return
            times(1) = c1 - c0
            row%repeats = 1
            do k = 2, opts%repeats
                if (times(1) >= opts%repeat_below) exit
                c0 = thread_cpu_seconds()
                call solve_periodic(model, ho, again, error)
                c1 = thread_cpu_seconds()
                if (allocated(error)) return
                times(k) = c1 - c0
                row%repeats = k
            end do
            row%method = 'hbm'
            row%parameter = ho%harmonics
            row%samples = ho%samples
            row%iterations = sol%nfev
            row%converged = sol%converged
            row%cpu_seconds = median(times(1:row%repeats))
            if (.not. allocated(sol%xcoef)) return
            call evaluate_series(sol, opts%error_samples, xs, vs, rs, error)
            if (allocated(error)) return
            call compare_samples('hbm', xs, vs, rs, 'reference', xr, vr, rr, row%cmp, error)
        end subroutine hbm_row

        subroutine euler_row(eo, row, error)
            type(euler_options_t), intent(in) :: eo
            type(study_row_t), intent(out) :: row
            type(error_type), allocatable, intent(out) :: error
            type(euler_result_t) :: es, again
            real(dp) :: times(opts%repeats), c0, c1
            real(dp), allocatable :: xe(:, :), ve(:, :), re(:, :)
            integer :: k
            c0 = thread_cpu_seconds()
            call integrate_euler(model, eo, es, error)
            c1 = thread_cpu_seconds()
            if (allocated(error)) return
            times(1) = c1 - c0
            row%repeats = 1
            do k = 2, opts%repeats
                if (times(1) >= opts%repeat_below) exit
                c0 = thread_cpu_seconds()
                call integrate_euler(model, eo, again, error)
                c1 = thread_cpu_seconds()
                if (allocated(error)) return
                times(k) = c1 - c0
                row%repeats = k
            end do
            row%method = 'euler'
            row%parameter = eo%steps_per_period
            row%samples = eo%steps_per_period
            row%iterations = es%periods
            row%converged = es%periodic
            row%cpu_seconds = median(times(1:row%repeats))
            if (.not. allocated(es%x)) return
            call sample_reference(res%reference, eo%steps_per_period, xe, ve, re, error)
            if (allocated(error)) return
            call compare_samples('euler', es%x, es%v, es%r, 'reference', xe, ve, re, &
                                 row%cmp, error)
        end subroutine euler_row
    end subroutine run_study

    !> Median of a few values (0 for none); the benchmarks use it too.
    pure real(dp) function median(a)
        real(dp), intent(in) :: a(:)
        real(dp) :: s(size(a)), tmp
        integer :: i, k, n
        median = 0.0_dp
        n = size(a)
        if (n == 0) return
        s = a
        do i = 2, n
            k = i
            do while (k > 1)
                if (s(k - 1) <= s(k)) exit
                tmp = s(k)
                s(k) = s(k - 1)
                s(k - 1) = tmp
                k = k - 1
            end do
        end do
        if (mod(n, 2) == 1) then
            median = s((n + 1)/2)
        else
            median = 0.5_dp*(s(n/2) + s(n/2 + 1))
        end if
    end function median
end module stickslip_study
