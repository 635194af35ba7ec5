!> The robustness study, "where methods fail, measured": one model solved over a grid of
!> forcing frequencies omega x friction coefficients mu, by the weighted residual for every
!> harmonic count H, quadrature sample count and weight rho (0: automatic), from a cold start
!> and from a warm start (the converged solution at the previous omega of the grid), and by
!> implicit Euler for every number of steps per period. Each run records whether it
!> converged, its work (hybrj residual evaluations, or periods integrated), its CPU time and
!> its error against the exact event-driven reference of its (omega, mu), computed once per
!> grid point and shared by every run there. A run that fails is a row, never an error.
!> Mirrors stickslip_study (the work-precision study at one point); also writes
!> robustness.csv.
module stickslip_robustness
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
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
    use stickslip_rho, only: automatic_rho
    use stickslip_progress, only: progress_t
    use stickslip_blas_threads, only: parallel_threads
    use stickslip_thread_clock, only: thread_cpu_seconds
    implicit none
    private
    public :: robustness_options_t, robustness_row_t, run_robustness
    public :: validate_robustness_options, default_robustness_options, robustness_samples
    public :: robustness_success

    !> Options of the robustness study (&robustness).
    type :: robustness_options_t
        !> Forcing frequencies of the grid, in sweep order (warm starts follow it) [rad/s].
        real(dp), allocatable :: omegas(:)
        !> Friction coefficients of the grid, each given to every contact (>= 0).
        real(dp), allocatable :: mus(:)
        !> Harmonic counts H of the weighted-residual runs (>= 1).
        integer, allocatable :: harmonics(:)
        !> Weights rho of Psi [m/(N s)]; 0 is the automatic choice (stickslip_rho).
        real(dp), allocatable :: rhos(:)
        !> Quadrature samples, each combined with every H (0: the &hbm samples, raised to
        !> the smallest power of two >= 4 H when fewer; see robustness_samples).
        integer, allocatable :: samples(:)
        !> Steps per period of the implicit Euler runs (integrated from rest until
        !> periodic); empty: no Euler run.
        integer, allocatable :: steps_per_period(:)
        !> Also run every weighted-residual configuration from a warm start.
        logical :: warm = .true.
        !> Points per period of the grid on which weighted-residual errors are measured.
        integer :: error_samples = 1024
        !> A converged run whose error exceeds this is counted as a failure ("wrong
        !> solution": another root, or a basis or step far too coarse). The default is
        !> loose: at H = 10 the truncation alone reaches 0.4 at a contact DOF that barely
        !> moves.
        real(dp) :: wrong_tol = 0.5_dp
    end type robustness_options_t

    !> One run of the robustness study.
    type :: robustness_row_t
        !> 'hbm-cold', 'hbm-warm' or 'euler'.
        character(len=8) :: method = ''
        !> Forcing frequency [rad/s] and friction coefficient of the grid point.
        real(dp) :: omega = 0.0_dp, mu = 0.0_dp
        !> Highest harmonic H (0 for 'euler').
        integer :: harmonics = 0
        !> Weight rho used [m/(N s)] (NaN for 'euler').
        real(dp) :: rho = 0.0_dp
        !> rho was the automatic choice (the option rho = 0).
        logical :: rho_auto = .false.
        !> Quadrature samples ('hbm-*'), steps per period ('euler').
        integer :: samples = 0
        !> Converged ('hbm-*': residual met the tolerance) or periodic ('euler').
        logical :: converged = .false.
        !> Residual evaluations, all hybrj calls included ('hbm-*'), periods integrated
        !> ('euler').
        integer :: iterations = 0
        !> CPU seconds of the run, on the thread that ran it [s].
        real(dp) :: cpu_seconds = 0.0_dp
        !> Largest error of the displacements against the reference, max over DOFs and
        !> instants of |x - x_ref| relative to the amplitude max |x_ref| of that DOF (err_x
        !> of study.csv; it bounds the relative error of each amplitude); NaN when there is
        !> no reference or the run produced no solution.
        real(dp) :: err_amplitude = 0.0_dp
        !> Converged and, when the reference is known, err_amplitude <= wrong_tol.
        logical :: success = .false.
        !> What happened, '; '-separated: 'not converged ...', 'not periodic: ...',
        !> 'wrong solution ...', 'failed: <error>', 'no reference: ...', and for a warm row
        !> without a converged neighbour 'cold start: ...'. Empty for a plain success.
        character(len=:), allocatable :: diagnosis
    end type robustness_row_t

    !> The reference of one grid point, sampled for the error measurements.
    type :: point_reference_t
        logical :: ok = .false.
        character(len=:), allocatable :: diagnosis
        real(dp), allocatable :: x(:, :), v(:, :), r(:, :)
    end type point_reference_t

    !> The error of one parallel task (the first in task order is returned).
    type :: task_error_t
        type(error_type), allocatable :: error
    end type task_error_t

contains

    !> The default grid: omega = 0.5, 1, .., 6 rad/s, mu = 0.1, 0.45, 1, 3, H = 10, 30, 100,
    !> rho = 0.02, 0.2, 1, 5 and automatic, the &hbm samples, warm starts, no Euler run.
    pure function default_robustness_options() result(opts)
        type(robustness_options_t) :: opts
        integer :: i
        opts%omegas = [(0.5_dp*i, i=1, 12)]
        opts%mus = [0.1_dp, 0.45_dp, 1.0_dp, 3.0_dp]
        opts%harmonics = [10, 30, 100]
        opts%rhos = [0.02_dp, 0.2_dp, 1.0_dp, 5.0_dp, 0.0_dp]
        opts%samples = [0]
        allocate (opts%steps_per_period(0))
    end function default_robustness_options

    !> Check robustness options. Errors (stat input) name the
    !> component ("opts%omegas: every entry must be finite and > 0"); "hbm_opts%samples" in a
    !> message is the samples of run_robustness's argument `hbm_opts`.
    subroutine validate_robustness_options(opts, error)
        !> Options to check.
        type(robustness_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Longest list of omegas, mus, harmonics, rhos, samples or steps_per_period.
        integer, parameter :: max_list = 256
        !> Most runs of one study (grid points x configurations).
        integer(int64), parameter :: max_runs = 100000
        !> Largest error_samples (points of the error grid per period).
        integer, parameter :: max_error_samples = 10**6
        character(len=:), allocatable :: msg
        integer :: i, j
        integer(int64) :: runs
        msg = ""
        if (.not. (allocated(opts%omegas) .and. allocated(opts%mus) .and. &
                   allocated(opts%harmonics) .and. allocated(opts%rhos) .and. &
                   allocated(opts%samples) .and. allocated(opts%steps_per_period))) then
            msg = "opts%omegas, opts%mus, opts%harmonics, opts%rhos, opts%samples and "// &
                  "opts%steps_per_period: must be set"
        else if (max(size(opts%omegas), size(opts%mus), size(opts%harmonics), size(opts%rhos), &
                     size(opts%samples), size(opts%steps_per_period)) > max_list) then
            msg = "opts%omegas, opts%mus, opts%harmonics, opts%rhos, opts%samples, "// &
                  "opts%steps_per_period: at most "//itoa(max_list)//" values each"
        else if (size(opts%omegas) == 0 .or. size(opts%mus) == 0) then
            msg = "opts%omegas, opts%mus: both need at least one value"
        else if (size(opts%harmonics)*size(opts%rhos)*size(opts%samples) + &
                 size(opts%steps_per_period) == 0) then
            msg = "opts%harmonics, opts%rhos, opts%samples, opts%steps_per_period: nothing to run"
        else if (.not. all(opts%omegas > 0.0_dp .and. opts%omegas < huge(1.0_dp))) then
            msg = "opts%omegas: every entry must be finite and > 0"
        else if (.not. all(opts%mus >= 0.0_dp .and. opts%mus < huge(1.0_dp))) then
            msg = "opts%mus: every entry must be finite and >= 0"
        else if (any(opts%harmonics < 1)) then
            msg = "opts%harmonics: every entry must be >= 1"
        else if (any(opts%harmonics > hbm_max_harmonics)) then
            msg = "opts%harmonics: every entry must be <= "//itoa(hbm_max_harmonics)
        else if (any(opts%samples > hbm_max_samples)) then
            msg = "opts%samples: every entry must be <= "//itoa(hbm_max_samples)// &
                  " (2**20)"
        else if (any(opts%steps_per_period > euler_max_steps_per_period)) then
            msg = "opts%steps_per_period: every entry must be <= "// &
                  itoa(euler_max_steps_per_period)
        else if (.not. all(opts%rhos >= 0.0_dp .and. opts%rhos < huge(1.0_dp))) then
            msg = "opts%rhos: every entry must be finite and >= 0 (0: automatic)"
        else if (any(opts%samples < 0)) then
            msg = "opts%samples: every entry must be >= 0 (0: the hbm_opts%samples)"
        else if (any(opts%steps_per_period < 2)) then
            msg = "opts%steps_per_period: every entry must be >= 2"
        else if (opts%error_samples < 2 .or. opts%error_samples > max_error_samples) then
            msg = "opts%error_samples = "//itoa(opts%error_samples)//": must be in "// &
                  "2.."//itoa(max_error_samples)
        else if (.not. (opts%wrong_tol > 0.0_dp .and. opts%wrong_tol < huge(1.0_dp))) then
            msg = "opts%wrong_tol: must be finite and > 0"
        else
            runs = int(size(opts%omegas), int64)*size(opts%mus)* &
                   (int(size(opts%harmonics), int64)*size(opts%rhos)*size(opts%samples)* &
                    merge(2, 1, opts%warm) + size(opts%steps_per_period))
            if (runs > max_runs) msg = "opts: the grid asks for "// &
                                       itoa(int(min(runs, int(huge(1), int64))))// &
                                       " runs, at most "//itoa(int(max_runs))//" allowed"
            do i = 1, size(opts%harmonics)
                if (len(msg) > 0) exit
                do j = 1, size(opts%samples)
                    if (opts%samples(j) > 0 .and. &
                        opts%samples(j) < 2*opts%harmonics(i) + 1) then
                        msg = "opts%samples = "//itoa(opts%samples(j))// &
                              ": too few for harmonics = "//itoa(opts%harmonics(i))// &
                              " (need >= "//itoa(2*opts%harmonics(i) + 1)//")"
                        exit
                    end if
                end do
                if (len(msg) > 0) exit
            end do
        end if
        if (len(msg) > 0) call fatal_error(error, msg, stickslip_stat%input)
    end subroutine validate_robustness_options

    !> Quadrature samples of a run with H harmonics for the option value `samples`: itself
    !> when > 0, otherwise `hbm_samples` (the &hbm samples) raised to the smallest power of
    !> two >= 4 H when fewer (the rule of the work-precision study).
    pure integer function robustness_samples(samples, harmonics, hbm_samples) result(ns)
        !> Option value (0: automatic).
        integer, intent(in) :: samples
        !> Highest harmonic H.
        integer, intent(in) :: harmonics
        !> The &hbm samples.
        integer, intent(in) :: hbm_samples
        ns = samples
        if (ns > 0) return
        ns = 1
        do while (ns < 4*harmonics)
            ns = 2*ns
        end do
        ns = max(hbm_samples, ns)
    end function robustness_samples

    !> Run the robustness study on `model` (its omega and every contact's mu replaced by
    !> the grid values). Per grid point (omega, mu): the exact reference (options `ref_opts`,
    !> started from the weighted residual with `hbm_opts`, or implicit Euler with
    !> `euler_opts`), then one 'euler' row per steps per period. Then per (mu, H, samples,
    !> rho), sweeping omega in grid order: an 'hbm-cold' row (start from zero forces; the
    !> `hbm_opts%start` strategy applies, so 'auto' may climb the harmonic ladder) and, with
    !> opts%warm, an 'hbm-warm' row started from the converged solution at the previous
    !> omega (warm if converged there, else cold; cold again when none converged). Rows are
    !> ordered by mu, then Euler before the weighted residual, then H, samples, rho, omega.
    !> Failures of runs and references are rows (converged = F, diagnosis). Errors: stat input
    !> (invalid model or options).
    !> Built with OpenMP, the independent tasks run on every thread (OMP_NUM_THREADS): first
    !> the grid points' references (with their Euler rows), then the omega sweeps of each
    !> (mu, H, samples, rho), heaviest H first; every row is computed exactly as in a serial
    !> run (same inputs, same warm-start chain), so the rows do not depend on the thread
    !> count. cpu_seconds is the CPU time of the thread that ran the row.
    subroutine run_robustness(model, hbm_opts, euler_opts, ref_opts, opts, rows, error, &
                              progress)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Weighted-residual options (harmonics, samples and rho are replaced).
        type(hbm_options_t), intent(in) :: hbm_opts
        !> Time-stepping options (steps_per_period is replaced).
        type(euler_options_t), intent(in) :: euler_opts
        !> Options of the reference.
        type(reference_start_options_t), intent(in) :: ref_opts
        !> Robustness options.
        type(robustness_options_t), intent(in) :: opts
        !> The runs.
        type(robustness_row_t), allocatable, intent(out) :: rows(:)
        !> Set on invalid input.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook: told after every run (rows so far of all, omega and mu).
        type(progress_t), intent(inout), optional :: progress
        type(point_reference_t), allocatable :: refs(:, :)
        type(task_error_t), allocatable :: ref_errors(:), sweep_errors(:)
        integer, allocatable :: order(:)
        integer :: nw, nmu, ne, ncfg, nwarm, per_mu, nrow, done, t, n, h, nthreads

        call validate_model(model, error)
        if (allocated(error)) return
        call validate_robustness_options(opts, error)
        if (allocated(error)) return
        call validate_reference_start_options(ref_opts, error)
        if (allocated(error)) return
        call validate_options(hbm_opts, error)
        if (allocated(error)) return

        nw = size(opts%omegas)
        nmu = size(opts%mus)
        ne = size(opts%steps_per_period)
        ncfg = size(opts%harmonics)*size(opts%samples)*size(opts%rhos)
        nwarm = merge(2, 1, opts%warm)
        per_mu = nw*(ne + ncfg*nwarm)
        nrow = nmu*per_mu
        allocate (rows(nrow), refs(nw, nmu), ref_errors(nw*nmu), sweep_errors(nmu*ncfg))
        done = 0
        nthreads = parallel_threads()

        ! the references of every grid point, and the Euler rows beside each
        !$omp parallel do schedule(dynamic, 1) default(shared) private(t) num_threads(nthreads)
        do t = 1, nw*nmu
            call reference_task(t)
        end do
        !$omp end parallel do
        do t = 1, size(ref_errors)
            if (allocated(ref_errors(t)%error)) then
                call move_alloc(ref_errors(t)%error, error)
                return
            end if
        end do

        ! the omega sweeps of every (mu, H, samples, rho), the largest H first (the longest
        ! tasks first balance the threads); each task fills its own rows
        allocate (order(0))
        do h = maxval(opts%harmonics), 1, -1
            order = [order, pack([(t, t=1, nmu*ncfg)], [(harmonics_of(t) == h, t=1, nmu*ncfg)])]
        end do
        !$omp parallel do schedule(dynamic, 1) default(shared) private(n) num_threads(nthreads)
        do n = 1, size(order)
            call sweep_task(order(n))
        end do
        !$omp end parallel do
        do t = 1, size(sweep_errors)
            if (allocated(sweep_errors(t)%error)) then
                call move_alloc(sweep_errors(t)%error, error)
                return
            end if
        end do

    contains

        !> H of sweep task t ((mu, H, samples, rho) in row order).
        integer function harmonics_of(t)
            integer, intent(in) :: t
            integer :: c
            c = mod(t - 1, ncfg)
            harmonics_of = opts%harmonics(c/(size(opts%samples)*size(opts%rhos)) + 1)
        end function harmonics_of

        !> The reference of grid point t ((mu, omega) in row order) and its Euler rows.
        subroutine reference_task(t)
            integer, intent(in) :: t
            type(model_t) :: m
            integer :: i, k, base
            k = (t - 1)/nw + 1
            i = mod(t - 1, nw) + 1
            m = model
            m%mu = [(opts%mus(k), base=1, m%ncontact())]
            m%omega = opts%omegas(i)
            base = (k - 1)*per_mu + (i - 1)*ne
            call point_reference(m, hbm_opts, euler_opts, ref_opts, opts, opts%mus(k), &
                                 refs(i, k), rows(base + 1:base + ne), ref_errors(t)%error)
            do base = 1, ne
                call tick(opts%omegas(i), opts%mus(k))
            end do
        end subroutine reference_task

        !> The cold and warm omega sweep of task t ((mu, H, samples, rho) in row order).
        subroutine sweep_task(t)
            integer, intent(in) :: t
            type(model_t) :: m
            type(hbm_options_t) :: ho
            type(hbm_solution_t) :: cold, warm
            type(error_type), allocatable :: error
            real(dp), allocatable :: last_r(:, :)
            logical :: have_last
            integer :: k, c, ih, is, ir, i, irow
            k = (t - 1)/ncfg + 1
            c = mod(t - 1, ncfg)
            ir = mod(c, size(opts%rhos)) + 1
            is = mod(c/size(opts%rhos), size(opts%samples)) + 1
            ih = c/(size(opts%rhos)*size(opts%samples)) + 1
            m = model
            m%mu = [(opts%mus(k), i=1, m%ncontact())]
            ho = hbm_opts
            ho%harmonics = opts%harmonics(ih)
            ho%samples = robustness_samples(opts%samples(is), ho%harmonics, hbm_opts%samples)
            ho%rho = opts%rhos(ir)
            ho%want_samples = .false.
            have_last = .false.
            do i = 1, nw
                m%omega = opts%omegas(i)
                irow = (k - 1)*per_mu + nw*ne + (c*nw + i - 1)*nwarm + 1
                call hbm_run('hbm-cold', m, ho, opts%mus(k), opts, refs(i, k), cold, &
                             rows(irow), error)
                if (allocated(error)) exit
                call tick(m%omega, opts%mus(k))
                if (.not. opts%warm) cycle
                if (have_last) then
                    call hbm_run('hbm-warm', m, ho, opts%mus(k), opts, refs(i, k), warm, &
                                 rows(irow + 1), error, last_r)
                    if (allocated(error)) exit
                else
                    call hbm_run('hbm-warm', m, ho, opts%mus(k), opts, refs(i, k), warm, &
                                 rows(irow + 1), error)
                    if (allocated(error)) exit
                    rows(irow + 1)%diagnosis = join(rows(irow + 1)%diagnosis, &
                        "cold start: no converged solution at a previous omega")
                end if
                call tick(m%omega, opts%mus(k))
                ! the start of the next omega: this omega's solution, warm first
                have_last = .false.
                if (warm%converged .and. allocated(warm%rcoef)) then
                    last_r = warm%rcoef
                    have_last = .true.
                else if (cold%converged .and. allocated(cold%rcoef)) then
                    last_r = cold%rcoef
                    have_last = .true.
                end if
            end do
            if (allocated(error)) call move_alloc(error, sweep_errors(t)%error)
        end subroutine sweep_task

        !> One more row is done: tell the progress hook (one thread at a time).
        subroutine tick(omega, mu)
            real(dp), intent(in) :: omega, mu
            character(len=80) :: buf
            if (.not. present(progress)) return
            !$omp critical (stickslip_robustness_progress)
            done = done + 1
            write (buf, '(a,g0.4,a,g0.4)') "omega = ", omega, ", mu = ", mu
            call progress%report(done, nrow, trim(buf))
            !$omp end critical (stickslip_robustness_progress)
        end subroutine tick
    end subroutine run_robustness

    !> The reference at the grid point of `m` (its omega and mu set), sampled on the error
    !> grid, and the Euler rows of that point (one per opts%steps_per_period). A reference
    !> that fails is recorded in `pr`, not raised.
    subroutine point_reference(m, hbm_opts, euler_opts, ref_opts, opts, mu, pr, erows, error)
        type(model_t), intent(in) :: m
        type(hbm_options_t), intent(in) :: hbm_opts
        type(euler_options_t), intent(in) :: euler_opts
        type(reference_start_options_t), intent(in) :: ref_opts
        type(robustness_options_t), intent(in) :: opts
        real(dp), intent(in) :: mu
        type(point_reference_t), intent(out) :: pr
        type(robustness_row_t), intent(inout) :: erows(:)
        type(error_type), allocatable, intent(out) :: error
        type(reference_result_t) :: ref
        type(euler_options_t) :: eo
        integer :: j
        call solve_reference_from_starts(m, ref_opts, ref, error, hbm_opts=hbm_opts, &
                                         euler_opts=euler_opts)
        if (allocated(error)) then
            if (error%stat /= stickslip_stat%numerical) return
            pr%diagnosis = "no reference: "//error%message
            deallocate (error)
        else if (.not. ref%converged) then
            pr%diagnosis = "no reference: "//ref%diagnosis
        else
            call sample_reference(ref, opts%error_samples, pr%x, pr%v, pr%r, error)
            if (allocated(error)) return
            pr%ok = .true.
            pr%diagnosis = ""
        end if
        do j = 1, size(opts%steps_per_period)
            eo = euler_opts
            eo%steps_per_period = opts%steps_per_period(j)
            call euler_run(m, eo, mu, opts, ref, pr, erows(j), error)
            if (allocated(error)) return
        end do
    end subroutine point_reference

    !> One weighted-residual run of `m` with the options ho (its row: `row`).
    subroutine hbm_run(method, m, ho, mu, opts, pr, sol, row, error, r_start)
        character(len=*), intent(in) :: method
        type(model_t), intent(in) :: m
        type(hbm_options_t), intent(in) :: ho
        real(dp), intent(in) :: mu
        type(robustness_options_t), intent(in) :: opts
        type(point_reference_t), intent(in) :: pr
        type(hbm_solution_t), intent(out) :: sol
        type(robustness_row_t), intent(inout) :: row
        type(error_type), allocatable, intent(out) :: error
        real(dp), intent(in), optional :: r_start(:, :)
        real(dp), allocatable :: xs(:, :), vs(:, :), rs(:, :)
        type(comparison_t) :: cmp
        real(dp) :: c0, c1
        character(len=80) :: buf
        row%method = method
        row%omega = m%omega
        row%mu = mu
        row%harmonics = ho%harmonics
        row%rho_auto = ho%rho == 0.0_dp
        row%rho = ho%rho
        if (row%rho_auto) row%rho = automatic_rho(m)
        row%samples = ho%samples
        row%err_amplitude = ieee_value(1.0_dp, ieee_quiet_nan)
        row%diagnosis = ""
        c0 = thread_cpu_seconds()
        call solve_periodic(m, ho, sol, error, r_start)
        c1 = thread_cpu_seconds()
        row%cpu_seconds = c1 - c0
        if (allocated(error)) then
            if (error%stat /= stickslip_stat%numerical) return
            row%diagnosis = "failed: "//error%message
            deallocate (error)
            return
        end if
        row%rho = sol%rho
        row%converged = sol%converged
        row%iterations = sol%nfev
        if (.not. sol%converged) then
            write (buf, '(a,i0,a,es10.2e3)') "not converged: hybrj info ", &
                sol%info, "; ||F||/fscale = ", sol%fnorm/max(sol%fscale, tiny(1.0_dp))
            row%diagnosis = trim(buf)
        end if
        if (pr%ok .and. allocated(sol%xcoef)) then
            call evaluate_series(sol, opts%error_samples, xs, vs, rs, error)
            if (allocated(error)) return
            call compare_samples('hbm', xs, vs, rs, 'reference', pr%x, pr%v, pr%r, &
                                 cmp, error)
            if (allocated(error)) return
            row%err_amplitude = cmp%worst('x')
        end if
        call judge(row, pr, opts%wrong_tol)
    end subroutine hbm_run

    !> One implicit Euler run of `m` with the options eo (its row: `row`).
    subroutine euler_run(m, eo, mu, opts, ref, pr, row, error)
        type(model_t), intent(in) :: m
        type(euler_options_t), intent(in) :: eo
        real(dp), intent(in) :: mu
        type(robustness_options_t), intent(in) :: opts
        type(reference_result_t), intent(in) :: ref
        type(point_reference_t), intent(in) :: pr
        type(robustness_row_t), intent(inout) :: row
        type(error_type), allocatable, intent(out) :: error
        type(euler_result_t) :: es
        type(comparison_t) :: cmp
        real(dp), allocatable :: xe(:, :), ve(:, :), re(:, :)
        real(dp) :: c0, c1
        row%method = 'euler'
        row%omega = m%omega
        row%mu = mu
        row%harmonics = 0
        row%rho = ieee_value(1.0_dp, ieee_quiet_nan)
        row%samples = eo%steps_per_period
        row%err_amplitude = ieee_value(1.0_dp, ieee_quiet_nan)
        row%diagnosis = ""
        c0 = thread_cpu_seconds()
        call integrate_euler(m, eo, es, error)
        c1 = thread_cpu_seconds()
        row%cpu_seconds = c1 - c0
        if (allocated(error)) then
            if (error%stat /= stickslip_stat%numerical) return
            row%diagnosis = "failed: "//error%message
            deallocate (error)
            return
        end if
        row%converged = es%periodic
        row%iterations = es%periods
        if (.not. es%periodic) row%diagnosis = "not periodic: "//es%diagnosis
        if (pr%ok .and. allocated(es%x)) then
            call sample_reference(ref, eo%steps_per_period, xe, ve, re, error)
            if (allocated(error)) return
            call compare_samples('euler', es%x, es%v, es%r, 'reference', xe, ve, re, &
                                 cmp, error)
            if (allocated(error)) return
            row%err_amplitude = cmp%worst('x')
        end if
        call judge(row, pr, opts%wrong_tol)
    end subroutine euler_run

    !> success and the diagnosis of a finished run.
    subroutine judge(row, pr, wrong_tol)
        type(robustness_row_t), intent(inout) :: row
        type(point_reference_t), intent(in) :: pr
        real(dp), intent(in) :: wrong_tol
        character(len=80) :: buf
        row%success = robustness_success(row, wrong_tol)
        if (row%converged .and. .not. row%success) then
            write (buf, '(a,es10.2e3,a,es10.2e3)') "wrong solution: err_amplitude ", &
                row%err_amplitude, " > wrong_tol ", wrong_tol
            row%diagnosis = join(row%diagnosis, trim(buf))
        end if
        if (.not. pr%ok) row%diagnosis = join(row%diagnosis, pr%diagnosis)
    end subroutine judge

    !> A run succeeds when it converged and its error is at most `wrong_tol` (or unknown:
    !> no reference).
    elemental logical function robustness_success(row, wrong_tol) result(ok)
        !> The run.
        type(robustness_row_t), intent(in) :: row
        !> Largest err_amplitude of a success.
        real(dp), intent(in) :: wrong_tol
        ok = row%converged
        if (ok .and. ieee_is_finite(row%err_amplitude)) ok = row%err_amplitude <= wrong_tol
    end function robustness_success

    !> Two diagnoses joined by "; " (either may be empty).
    pure function join(a, b) result(s)
        character(len=*), intent(in) :: a, b
        character(len=:), allocatable :: s
        if (len(a) == 0) then
            s = b
        else if (len(b) == 0) then
            s = a
        else
            s = a//"; "//b
        end if
    end function join
end module stickslip_robustness
