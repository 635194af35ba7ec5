!> Forced-response curves: the weighted-residual solution continued in a parameter (omega,
!> a forcing amplitude, mu or the normal load) by pseudo-arclength continuation
!> (stickslip_continuation), with for every point its amplitudes, dissipation, contact
!> statistics and, on request, its Floquet stability (stickslip_stability).
!>
!> The pieces: the options and the swept parameter (stickslip_sweep_options), the points
!> and the curve (stickslip_sweep_result), the friction equations as a family in the
!> parameter with its analytic dF/dlambda (stickslip_friction_family), one point's outputs
!> and checks (stickslip_sweep_point), folds and retraces (stickslip_sweep_retrace). This
!> module runs the sweep and re-exports their public names.
!>
!> Checkpoints: run_sweep calls an observer after every point with the continuation state
!> and the points so far; stickslip_checkpoint saves them, and a sweep given that saved
!> state resumes where it stopped. No file is touched here.
module stickslip_sweep
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp
    use stickslip_thread_clock, only: thread_cpu_seconds, thread_nap
    !$ use omp_lib, only: omp_get_thread_num
    use stickslip_diagnostics, only: diagnostics_t
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t, validate_model
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options
    use stickslip_sparse_model, only: sparse_model_t, validate_sparse_model
    use stickslip_hbm_sparse, only: solve_periodic_sparse
    use stickslip_lapack, only: dgetrf, dgetrs, dgeev
    use stickslip_continuation, only: continuation_options_t, continuation_state_t, &
        continuation_report_t, start_continuation, continuation_step, reason_running, &
        reason_end, reason_left, reason_failures, reason_max_points, point_status
    use stickslip_reference, only: reference_options_t, reference_cache_t
    use stickslip_progress, only: progress_t
    use stickslip_sweep_options, only: sweep_options_t, validate_sweep_options, &
        continuation_options_of, sweep_parameter_value, set_sweep_parameter
    use stickslip_sweep_result, only: frc_point_t, sweep_result_t, sweep_observer_t, &
        reason_text
    use stickslip_friction_family, only: friction_family_t, new_friction_family, &
        dynamics_cache_size
    use stickslip_sweep_point, only: point_tally_t, evaluate_point, stability_block
    use stickslip_blas_threads, only: parallel_threads
    use stickslip_sweep_retrace, only: fold_watch_t, new_fold_watch
    use stickslip_cyclic, only: cyclic_t, validate_cyclic
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic
    implicit none
    private
    public :: sweep_options_t, frc_point_t, sweep_result_t, sweep_observer_t, run_sweep
    public :: validate_sweep_options, sweep_parameter_value, set_sweep_parameter
    public :: continuation_options_of, reason_text, friction_family_t, new_friction_family
    public :: undamped_resonance_notes
    public :: dynamics_cache_size

contains

    !> The forced-response curve of `model` over the parameter range of `opts`, each point
    !> solved with the weighted-residual options `hbm` (harmonics, samples, rho, tol) and,
    !> with opts%stability, its Floquet multipliers from the exact reference (options
    !> `ref`). With `resume` (a state and points saved by an observer), the curve goes on
    !> from there. The observer sees the curve after every point. Stopping early (too many
    !> failed points, max_points, the branch leaving the range) is an outcome:
    !> res%complete = .false. and res%diagnosis. Errors: stat input (invalid model or
    !> options, a resume of another size), stat numerical (no solution at the start, NaN),
    !> the observer's errors.
    !> With `sparse` (the model's matrices kept sparse, &reduction method = 'none' above the
    !> dense limit; `model` is then sparse%model, without dense matrices), every point is
    !> condensed exactly by sparse LU factorizations (stickslip_sparse_dynamics, redone per
    !> omega), the points hold the amplitudes of kept_dofs(sparse, dofs) in that order, and
    !> neither the truncation estimate nor the stability is computed (opts%stability is
    !> then an input error).
    subroutine run_sweep(model, hbm, ref, opts, res, error, observer, resume, progress, &
                         sparse, dofs, r_start, cyclic)
        !> The model at the case's values (the parameter is overwritten along the curve).
        type(model_t), intent(in) :: model
        !> Weighted-residual options of every point.
        type(hbm_options_t), intent(in) :: hbm
        !> Options of the exact reference used for the stability.
        type(reference_options_t), intent(in) :: ref
        !> Sweep options.
        type(sweep_options_t), intent(in) :: opts
        !> The curve.
        type(sweep_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Called after every point.
        class(sweep_observer_t), intent(inout), optional :: observer
        !> A saved curve to continue.
        type(sweep_result_t), intent(in), optional :: resume
        !> Progress hook: told after every point (points so far, the parameter).
        type(progress_t), intent(inout), optional :: progress
        !> The model with sparse matrices (the exact sparse condensation).
        type(sparse_model_t), intent(in), optional :: sparse
        !> With `sparse`: the DOFs whose amplitudes the points hold (then the contact and
        !> forced DOFs, kept_dofs); default none beyond those.
        integer, intent(in), optional :: dofs(:)
        !> A start for the first point's solve: friction-force coefficients [N] on the basis
        !> of `hbm` (a neighbouring curve's first point); default the solver's own start.
        real(dp), intent(in), optional :: r_start(:, :)
        !> `model` is one sector of this tuned disk: the curve of its travelling wave
        !> (stickslip_cyclic_dynamics); with opts%stability the Floquet multipliers are the
        !> assembled disk's (every perturbation, not only the wave's symmetry), point by point.
        type(cyclic_t), intent(in), optional :: cyclic
        type(friction_family_t), target :: fam
        type(continuation_options_t) :: co
        type(continuation_report_t) :: rep
        type(hbm_solution_t) :: sol
        type(hbm_options_t) :: ho
        real(dp) :: c0, c1, weight
        type(continuation_state_t) :: state_before
        type(fold_watch_t) :: watch
        integer :: nb, nc
        character(len=40) :: buf
        type(model_t) :: m0
        real(dp), allocatable :: amplitude0(:)
        type(point_tally_t) :: tally
        integer :: nthreads
        logical :: defer
        type(reference_cache_t) :: rcache
        type(diagnostics_t) :: held
        integer :: k
        ! the stability beside the curve (defer): the curve's model and options as they
        ! were at the start, the points taken from the front and from the back so far, the
        ! count done, their CPU time and error, whether the curve is traced
        type(model_t) :: base_model
        type(hbm_options_t) :: base_opts
        integer :: front, back, stage_done
        real(dp) :: stage_seconds
        type(error_type), allocatable :: stage_error
        type(progress_t) :: stage_progress
        logical :: curve_done
        !> Points a thread takes at a time for their stability.
        integer, parameter :: stage_chunk = 8

        c0 = thread_cpu_seconds()
        if (present(sparse)) then
            call validate_sparse_model(sparse, error)
            if (allocated(error)) return
            if (opts%stability) then
                call fatal_error(error, "opts%stability: the Floquet multipliers need the "// &
                                 "dense matrices of a small or reduced model, not the "// &
                                 "sparse condensation", stickslip_stat%input)
                return
            end if
        else
            call validate_model(model, error)
            if (allocated(error)) return
        end if
        if (present(cyclic)) then
            call validate_cyclic(model, cyclic, error)
            if (allocated(error)) return
            if (present(sparse)) then
                call fatal_error(error, "cyclic: a sector is dense, not a sparse "// &
                                 "condensation", stickslip_stat%input)
                return
            end if
        end if
        call validate_options(hbm, error)
        if (allocated(error)) return
        call validate_sweep_options(model, opts, error)
        if (allocated(error)) return
        co = continuation_options_of(opts)
        ! with several threads the stability of the points runs on the other threads while
        ! the curve is traced (stability_worker); with one, point by point as they come
        nthreads = parallel_threads()
        ! (a sector's multipliers are its disk's, point by point: stickslip_sweep_point)
        defer = opts%stability .and. nthreads > 1 .and. .not. present(sparse) .and. &
                .not. present(cyclic)
        nc = model%ncontact()
        if (nc == 0) then
            call fatal_error(error, "sweep: the model has no friction contact (nothing to "// &
                             "continue: the response is linear)", stickslip_stat%input)
            return
        end if

        ! the first point: a full solve at the start (cold start, ladder if needed); its
        ! rho (the automatic one when &hbm rho = 0) is kept along the whole curve
        m0 = model
        amplitude0 = model%force_amplitude
        call set_sweep_parameter(m0, opts%parameter, opts%start, amplitude0)
        ho = hbm
        ho%want_samples = .false.
        if (present(sparse)) then
            call new_friction_family(fam, model, hbm, opts%parameter, opts%start, 1.0_dp, &
                                     error, sparse, dofs, build=.false.)
            if (allocated(error)) return
            fam%sparse%model = m0
            if (present(progress)) then
                call solve_periodic_sparse(fam%sparse, ho, fam%kept, sol, error, &
                                           progress=progress)
            else
                call solve_periodic_sparse(fam%sparse, ho, fam%kept, sol, error)
            end if
        else if (present(cyclic)) then
            call solve_periodic_cyclic(m0, cyclic, ho, sol, error, r_start=r_start)
        else if (present(r_start)) then
            call solve_periodic(m0, ho, sol, error, r_start=r_start)
            ! a start that leads nowhere: the solver's own
            if (.not. allocated(error)) then
                if (.not. sol%converged) call solve_periodic(m0, ho, sol, error)
            end if
        else
            call solve_periodic(m0, ho, sol, error)
        end if
        if (allocated(error)) return
        if (.not. sol%converged) then
            write (buf, '(g0.6)') opts%start
            call fatal_error(error, "sweep: no solution at the start of the range ("// &
                             trim(opts%parameter)//" = "//trim(buf)//"): "// &
                             sol%diagnosis, stickslip_stat%numerical)
            return
        end if
        if (present(sparse)) then
            call new_friction_family(fam, model, hbm, opts%parameter, opts%start, sol%rho, &
                                     error, sparse, dofs)
        else if (present(cyclic)) then
            call new_friction_family(fam, model, hbm, opts%parameter, opts%start, sol%rho, &
                                     error, cyclic=cyclic)
        else
            call new_friction_family(fam, model, hbm, opts%parameter, opts%start, sol%rho, error)
        end if
        if (allocated(error)) return
        if (present(progress)) fam%progress = progress
        res%rho = fam%prob%rho
        front = 1
        back = 0
        curve_done = .false.
        stage_done = 0
        stage_seconds = 0.0_dp
        if (defer) then
            base_model = fam%model
            base_opts = fam%opts
        end if
        nb = fam%prob%basis%nb
        co%tol = hbm%tol
        co%fscale = max(fam%prob%rho*force_scale(fam%model), tiny(1.0_dp))
        ! the arclength measures the friction force by the RMS of its coefficients (over
        ! every channel of every contact: with 16 contacts a change of all of them by the
        ! same amount measures as much as one contact's) relative to the friction limit,
        ! weighted so that the smallest change the quadrature can make
        ! (one sample switching between slip directions through stick: a force change of
        ! about 2.8 / samples in these units) is a tenth of the largest step: the curve of
        ! the sampled equations is a staircase of such switches near a resonance, and
        ! the parameter must dominate the step there; the force still takes over at folds
        weight = max(1.0_dp, 28.0_dp*abs(co%stop - co%start)/(real(hbm%samples, dp)*co%max_step))
        co%yscale = [max(force_scale(fam%model), tiny(1.0_dp))*sqrt(real(fam%prob%n, dp))*weight]
        if (opts%parameter == 'mu' .or. opts%parameter == 'normal_load' .or. &
            opts%parameter == 'preload') then
            ! the limits change along the curve: scale by the largest on the range
            block
                type(model_t) :: m2
                m2 = fam%model
                call set_sweep_parameter(m2, opts%parameter, max(abs(opts%start), &
                                         abs(opts%stop)), fam%amplitude0)
                co%yscale = [max(force_scale(m2), tiny(1.0_dp))]
                co%fscale = max(fam%prob%rho*co%yscale(1), tiny(1.0_dp))
                co%yscale = co%yscale*sqrt(real(fam%prob%n, dp))*weight
            end block
        end if
        ! where the contact forces grow beyond that scale (a resonance with lift-off, where
        ! the normal load and so the friction limit rise tenfold, and every sample switch
        ! with them) the scale grows with the forces: relative steps, not crawling ones
        co%yref = co%yscale(1)/(sqrt(real(fam%prob%n, dp))*weight)* &
                  sqrt(real(max(fam%prob%n/nb, 1), dp))
        allocate (res%points(64))

        if (present(resume)) then
            if (resume%npoints > 0) then
                if (size(resume%state%y) /= fam%prob%n) then
                    call fatal_error(error, "sweep: the checkpoint has another number of "// &
                                     "unknowns than this case", stickslip_stat%input)
                    call release_family()
                    return
                end if
                res%state = resume%state
                res%npoints = resume%npoints
                res%points = resume%points(1:resume%npoints)
                res%resumed_points = resume%npoints
                res%folds = resume%folds
                res%seconds = resume%seconds
                res%stability_seconds = resume%stability_seconds
                ! the checks of resumed points: their verdict as the checkpoint kept it
                do k = 1, res%npoints
                    associate (q => res%points(k))
                        held = diagnostics_t()
                        if (q%check_level > 0) call held%add(q%check_level, trim(q%check), "")
                        call tally%add_point(held, ieee_value(1.0_dp, ieee_quiet_nan), &
                                             q%parameter)
                    end associate
                end do
            end if
        end if

        if (res%npoints == 0) then
            call start_continuation(fam, co, reshape(sol%rcoef, [fam%prob%n]), res%state, &
                                    rep, error)
            if (allocated(error)) then
                call release_family()
                return
            end if
            if (res%state%reason /= reason_running) then
                call fatal_error(error, "sweep: "//rep%message, stickslip_stat%numerical)
                call release_family()
                return
            end if
            call add_point("start")
            if (allocated(error)) then
                call release_family()
                return
            end if
        end if

        ! folds, and turns back that retrace the curve: stickslip_sweep_retrace
        call new_fold_watch(watch, opts%start, opts%stop)
        if (defer) then
            ! the stability of the points on the other threads while this one traces the
            ! curve, each thread taking the next chunk of points in order and carrying its
            ! reference cache from one chunk to the next; once the curve is traced this
            ! thread takes chunks from the end of the curve backwards, until all are done
            ! (the master thread traces: its CPU clock is the one c0 was read from)
            if (present(progress)) stage_progress = progress%stage('stability', 'points')
            !$omp parallel num_threads(nthreads) default(shared)
            !$omp master
            call trace()
            !$omp critical (sweep_points)
            curve_done = .true.
            !$omp end critical (sweep_points)
            !$omp end master
            call stability_worker()
            !$omp end parallel
            res%stability_seconds = res%stability_seconds + stage_seconds
            ! the sweep's CPU time counts its stability, on whichever thread it ran
            res%seconds = res%seconds + stage_seconds
            if (allocated(stage_error) .and. .not. allocated(error)) &
                call move_alloc(stage_error, error)
            if (.not. allocated(error) .and. present(observer)) call observer%observe(res, error)
        else
            call trace()
        end if
        call release_family()
        res%factorizations = fam%factorizations
        if (allocated(error)) return
        res%complete = res%state%reason == reason_end
        if (opts%parameter == 'omega' .and. .not. present(sparse) .and. &
            .not. present(cyclic)) then
            res%notes = undamped_resonance_notes(model, opts%start, opts%stop)
        else
            res%notes = ""
        end if
        call tally%report(opts%parameter, res%diagnostics)
        if (.not. allocated(res%diagnosis)) res%diagnosis = ""
        if (.not. res%complete) then
            if (len(res%diagnosis) > 0) then
                res%diagnosis = reason_text(res%state%reason)//": "//res%diagnosis
            else
                res%diagnosis = reason_text(res%state%reason)
            end if
            res%diagnosis = res%diagnosis//remedy(res%state%reason)
        end if

    contains

        !> The continuation from the current state to the end of the range (or a stop).
        subroutine trace()
            do while (res%state%reason == reason_running)
                state_before = res%state
                call continuation_step(fam, co, res%state, rep, error)
                if (allocated(error)) exit
                if (rep%accepted) then
                    call watch%accepted(state_before, res)
                    call add_point(point_status(rep, res%state))
                    if (allocated(error)) exit
                    !$omp critical (sweep_points)
                    call watch%check_retrace(res, co%max_step, opts%parameter)
                    !$omp end critical (sweep_points)
                end if
                if (res%state%reason /= reason_running) then
                    if (len(rep%message) > 0) res%diagnosis = rep%message
                end if
            end do
        end subroutine trace

        !> The stability of the curve's points, chunk by chunk (stage_chunk points taken in
        !> order, from the front while the curve is traced, from the back by the thread
        !> that traced it), on copies (the curve goes on meanwhile), the verdicts written
        !> back; returns when no point is left (or after an error).
        subroutine stability_worker()
            type(reference_cache_t) :: cache
            type(frc_point_t), allocatable :: copy(:)
            type(error_type), allocatable :: task_error
            real(dp) :: seconds
            integer :: lo, hi, j
            logical :: finished, backward
            do
                lo = 0
                hi = -1
                !$omp critical (sweep_points)
                finished = allocated(stage_error) .or. &
                           (curve_done .and. (front > res%npoints - back .or. allocated(error)))
                backward = curve_done .and. traced_here()
                if (.not. finished) then
                    if (backward) then
                        hi = res%npoints - back
                        lo = max(front, hi - stage_chunk + 1)
                        back = back + (hi - lo + 1)
                    else if (front + stage_chunk - 1 <= res%npoints - back .or. &
                             (curve_done .and. front <= res%npoints - back)) then
                        lo = front
                        hi = min(front + stage_chunk - 1, res%npoints - back)
                        front = hi + 1
                    end if
                end if
                if (hi >= lo) copy = res%points(lo:hi)
                !$omp end critical (sweep_points)
                if (finished) exit
                if (hi < lo) then
                    ! the curve has not reached the next chunk yet
                    call thread_nap(0.01_dp)
                    cycle
                end if
                seconds = 0.0_dp
                call stability_block(base_model, base_opts, amplitude0, opts, ref, copy, &
                                     seconds, task_error, stage_point_done, cache)
                !$omp critical (sweep_points)
                do j = lo, hi
                    res%points(j)%stable = copy(j - lo + 1)%stable
                    res%points(j)%floquet_max = copy(j - lo + 1)%floquet_max
                end do
                stage_seconds = stage_seconds + seconds
                if (allocated(task_error) .and. .not. allocated(stage_error)) &
                    call move_alloc(task_error, stage_error)
                !$omp end critical (sweep_points)
            end do
        end subroutine stability_worker

        !> Whether the calling thread is the one that traced the curve (OpenMP's master).
        logical function traced_here()
            traced_here = .true.
            !$ traced_here = omp_get_thread_num() == 0
        end function traced_here

        !> One more point's stability done: counted, reported.
        subroutine stage_point_done(pt)
            type(frc_point_t), intent(in) :: pt
            character(len=40) :: text
            !$omp critical (sweep_progress)
            stage_done = stage_done + 1
            if (present(progress)) then
                write (text, '(g0.6)') pt%parameter
                call stage_progress%report(stage_done, 0, trim(opts%parameter)//" = "// &
                                           trim(adjustl(text)))
            end if
            !$omp end critical (sweep_progress)
        end subroutine stage_point_done

        !> Free what the family holds beyond Fortran's reach (the sparse analysis).
        subroutine release_family()
            call fam%prob%destroy()
            call fam%analysis%release()
        end subroutine release_family

        !> What to change when the curve stops for `reason` (&sweep and &hbm variables).
        function remedy(reason) result(text)
            integer, intent(in) :: reason
            character(len=:), allocatable :: text
            character(len=40) :: a, b
            write (a, '(g0.6)') opts%stop
            write (b, '(g0.6)') opts%start
            select case (reason)
            case (reason_left)
                text = ". The curve folds back there: the answer at the start lies on a "// &
                       "branch that turns and leaves the range (several answers at the same "// &
                       trim(opts%parameter)//", a resonance bent by the contacts). Sweep from "// &
                       "the other end (&sweep start = "//trim(adjustl(a))//", stop = "// &
                       trim(adjustl(b))//"), or start where the response is unique, further "// &
                       "from the resonance"
            case (reason_failures)
                text = ". Try a smaller &sweep max_step (the corrector failed at the "// &
                       "smallest step: the curve bends sharply there, e.g. where a contact "// &
                       "starts to slip or to lift off), more &hbm harmonics (or "// &
                       "harmonics_tol), or the sweep from the other end"
            case (reason_max_points)
                text = ". Raise &sweep max_points, or a larger max_step"
            case default
                text = ""
            end select
        end function remedy

        !> Solve the accepted point for its outputs, add it, tell the observer.
        subroutine add_point(status)
            character(len=*), intent(in) :: status
            type(frc_point_t) :: pt
            type(frc_point_t), allocatable :: grown(:)
            call evaluate_point(fam, opts, ref, res%state, status, rep%nfev, pt, tally, &
                                res%stability_seconds, error, rcache, defer_stability=defer)
            if (allocated(error)) return
            !$omp critical (sweep_points)
            if (res%npoints == size(res%points)) then
                allocate (grown(2*res%npoints))
                grown(1:res%npoints) = res%points(1:res%npoints)
                call move_alloc(grown, res%points)
            end if
            res%npoints = res%npoints + 1
            res%points(res%npoints) = pt
            c1 = thread_cpu_seconds()
            res%seconds = res%seconds + (c1 - c0)
            c0 = c1
            if (present(observer)) call observer%observe(res, error)
            !$omp end critical (sweep_points)
            if (present(progress)) then
                write (buf, '(g0.6)') res%state%lambda
                call progress%report(res%npoints, 0, trim(opts%parameter)//" = "// &
                                     trim(adjustl(buf)))
            end if
        end subroutine add_point
    end subroutine run_sweep

    !> Warnings for a sweep in omega over [lo, hi] of a structure without viscous damping:
    !> the forcing frequencies h omega that hit a natural frequency of the structure without
    !> friction (eigenvalues of M^-1 K). There the dynamic stiffness is singular and, unless
    !> friction can bound it, the response is unbounded; the friction forces (the unknowns)
    !> stay bounded, so the continuation passes such a point without noticing, and the curve
    !> shows a finite peak between two points. '' when damped or when no such point lies in
    !> the range.
    function undamped_resonance_notes(model, lo, hi) result(notes)
        !> The model.
        type(model_t), intent(in) :: model
        !> The range of omega [rad/s].
        real(dp), intent(in) :: lo, hi
        character(len=:), allocatable :: notes
        real(dp), allocatable :: a(:, :), b(:, :), wr(:), wi(:), work(:), vdum(:, :)
        integer, allocatable :: ipiv(:)
        integer :: n, info, k, i, h
        real(dp) :: wn, om
        character(len=80) :: buf
        notes = ""
        if (any(model%damping /= 0.0_dp)) return
        n = model%ndof
        a = model%mass
        b = model%stiffness
        allocate (ipiv(n), wr(n), wi(n), work(8*n), vdum(1, 1))
        call dgetrf(n, n, a, n, ipiv, info)
        if (info /= 0) return
        call dgetrs('N', n, n, a, n, ipiv, b, n, info)
        if (info /= 0) return
        call dgeev('N', 'N', n, b, n, wr, wi, vdum, 1, vdum, 1, work, size(work), info)
        if (info /= 0) return
        do k = 1, n
            if (.not. (wr(k) > 0.0_dp)) cycle
            wn = sqrt(wr(k))
            do i = 1, model%nforce()
                h = model%force_harmonic(i)
                if (h == 0) cycle
                om = wn/h
                if (om >= min(lo, hi) .and. om <= max(lo, hi) .and. index(notes, trim(fmt(om))) == 0) then
                    write (buf, '(a,i0,a)') trim(fmt(om))//" rad/s (h = ", h, ")"
                    if (len(notes) > 0) notes = notes//", "
                    notes = notes//trim(buf)
                end if
            end do
        end do
        if (len(notes) > 0) notes = "no damping: the range crosses natural frequencies of "// &
            "the structure without friction at omega = "//notes//"; there the response "// &
            "may be unbounded (friction does not always bound it) while the curve shows a "// &
            "finite peak between two points: add damping, or refine max_step there"
    contains
        function fmt(x) result(t)
            real(dp), intent(in) :: x
            character(len=20) :: t
            write (t, '(f0.5)') x
            if (t(1:1) == '.') t = '0'//t
        end function fmt
    end function undamped_resonance_notes
    !> The force scale of a model's contacts [N]: the largest friction limit mu N; with
    !> contact laws also the largest preload and mu times it (the normal force and the
    !> friction a unilateral contact carries at rest).
    function force_scale(model) result(f)
        !> The model.
        type(model_t), intent(in) :: model
        real(dp) :: f
        type(contact_set_t) :: cs
        call new_contact_set(cs, model)
        f = cs%force_scale()
    end function force_scale
end module stickslip_sweep
