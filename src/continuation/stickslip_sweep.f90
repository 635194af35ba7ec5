!> Forced-response curves: the weighted-residual solution continued in a parameter (omega,
!> a forcing amplitude, mu or the normal load) by pseudo-arclength continuation
!> (stickslip_continuation), with for every point its amplitudes, dissipation, contact
!> statistics and, on request, its Floquet stability (stickslip_stability).
!>
!> The friction-force coefficients R are the unknowns, as in a single solve; the parameter
!> derivative dF/dlambda is analytic: P diag(s) Q dV/dlambda for omega (dV/domega from the
!> condensed dynamics) and a forcing amplitude (V0 is linear in it), P dPsi/dg Q dg/dlambda
!> for mu and the normal load (g = mu N, the friction limit).
!>
!> Checkpoints: run_sweep calls an observer after every point with the continuation state
!> and the points so far; stickslip_checkpoint saves them, and a sweep given that saved
!> state resumes where it stopped. No file is touched here.
module stickslip_sweep
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_diagnostics, only: diagnostics_t, level_note, level_warning, level_untrusted
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t, validate_model
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem, new_condensed_problem
    use stickslip_dynamics, only: dynamics_t, new_dynamics
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_sparse_model, only: sparse_model_t, validate_sparse_model
    use stickslip_sparse_dynamics, only: new_sparse_dynamics
    use stickslip_hbm_sparse, only: solve_periodic_sparse, kept_dofs
    use stickslip_friction, only: psi_limit_derivative
    use stickslip_lapack, only: dgetrf, dgetrs, dgeev
    use stickslip_continuation, only: parametric_system_t, continuation_options_t, &
        continuation_state_t, continuation_report_t, start_continuation, continuation_step, &
        validate_continuation_options, reason_running, reason_end, reason_failures, &
        reason_max_points, reason_left
    use stickslip_reference, only: reference_options_t
    use stickslip_stability, only: floquet_t, periodic_stability
    use stickslip_truncation, only: truncation_t, estimate_truncation
    use stickslip_progress, only: progress_t
    use stickslip_checks, only: truncation_warning, truncation_untrusted
    implicit none
    private
    public :: sweep_options_t, frc_point_t, sweep_result_t, sweep_observer_t, run_sweep
    public :: validate_sweep_options, sweep_parameter_value, set_sweep_parameter
    public :: continuation_options_of, reason_text, friction_family_t, new_friction_family
    public :: undamped_resonance_notes

    !> Dynamics kept by a friction family in omega (distinct omega values).
    integer, parameter, public :: dynamics_cache_size = 4
    !> Points in a row after a turn back that must retrace the curve before the sweep takes
    !> the turn for a kink (not a fold) and steps past it; at most max_retrace_jumps times.
    integer, parameter :: max_retrace_hits = 3, max_retrace_jumps = 5
    !> Relative amplitude agreement that makes a point lie on the curve already traced.
    real(dp), parameter :: retrace_tolerance = 1.0e-3_dp

    !> Options of a sweep (&sweep).
    type :: sweep_options_t
        !> The parameter: 'omega' [rad/s], 'force_amplitude' [N] (every forcing term scaled
        !> so that term 1 has this amplitude), 'mu' (every contact) or 'normal_load' [N]
        !> (every contact).
        character(len=16) :: parameter = 'omega'
        !> Range of the parameter, from start to stop.
        real(dp) :: start = 0.0_dp, stop = 0.0_dp
        !> First, smallest and largest continuation step in parameter units
        !> (0: |stop - start| / 100, / 1e5 and / 25).
        real(dp) :: step = 0.0_dp, min_step = 0.0_dp, max_step = 0.0_dp
        !> Most points, and failed points in a row before the sweep gives up.
        integer :: max_points = 2000, max_failures = 3
        !> Floquet multipliers of every point (exact event-driven monodromy).
        logical :: stability = .true.
        !> Harmonic truncation error estimate of every point (stickslip_truncation).
        logical :: truncation = .true.
        !> Observed combinations of DOFs, nobs x ndof (optional): when allocated, the
        !> amplitudes of a point are max_t |observe(i, :) x(t)|, i = 1..nobs, instead of one
        !> per DOF (e.g. the rows of a reduction basis: full-model DOFs of a reduced model).
        real(dp), allocatable :: observe(:, :)
    end type sweep_options_t

    !> One point of a forced-response curve.
    type :: frc_point_t
        !> Parameter value.
        real(dp) :: parameter = 0.0_dp
        !> Arclength from the start (parameter units).
        real(dp) :: arclength = 0.0_dp
        !> max_t |x_k(t)| per DOF [m].
        real(dp), allocatable :: amplitude(:)
        !> Energy dissipated per period: friction + viscous, and each [J].
        real(dp) :: dissipation = 0.0_dp, diss_friction = 0.0_dp, diss_damping = 0.0_dp
        !> max_t |r_j(t)| [N] and stick fraction per contact.
        real(dp), allocatable :: rmax(:), stick(:)
        !> Harmonic count H of the point.
        integer :: harmonics = 0
        !> ||F|| / fscale of the point.
        real(dp) :: residual = 0.0_dp
        !> 'start', 'ok' (corrected in the first try), 'halved' (after step halvings),
        !> 'recovered' (harmonic ladder), 'end' (the end of the range).
        character(len=12) :: status = ''
        !> Corrector evaluations spent on the point.
        integer :: nfev = 0
        !> Largest Floquet multiplier modulus (NaN when not computed).
        real(dp) :: floquet_max = 0.0_dp
        !> 1 stable, 0 unstable, -1 unknown or not computed.
        integer :: stable = -1
        !> Relative harmonic truncation error estimate (NaN when not computed).
        real(dp) :: truncation = 0.0_dp
    end type frc_point_t

    !> A forced-response curve.
    type :: sweep_result_t
        !> The points, in continuation order (npoints of them are filled).
        type(frc_point_t), allocatable :: points(:)
        integer :: npoints = 0
        !> The continuation state at the end (or at the interruption).
        type(continuation_state_t) :: state
        !> The run resumed from a checkpoint with this many points.
        integer :: resumed_points = 0
        !> Why it stopped, in words; the end of the range is the only complete outcome.
        logical :: complete = .false.
        character(len=:), allocatable :: diagnosis
        !> CPU seconds: all, and the stability part.
        real(dp) :: seconds = 0.0_dp, stability_seconds = 0.0_dp
        !> Turning points passed (sign changes of the parameter's tangent component).
        integer :: folds = 0
        !> Factorizations of the dynamic stiffnesses by the continuation of this run (see
        !> friction_family_t%factorizations; the points' own solves reuse them).
        integer :: factorizations = 0
        !> Warnings about the curve ('' when none): undamped_resonance_notes.
        character(len=:), allocatable :: notes
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type sweep_result_t

    !> Which checks the points of a curve failed: per diagnostics key, how many points, the
    !> worst level and the parameter of the first (sweep_result_t%diagnostics gets one
    !> item per key, 'points_<key>').
    type :: point_tally_t
        character(len=48), allocatable :: key(:)
        integer, allocatable :: count(:), level(:)
        real(dp), allocatable :: first(:)
        integer :: points = 0
    contains
        procedure :: add_point => tally_add_point
        procedure :: report => tally_report
    end type point_tally_t

    !> Called after every point; a checkpoint writer extends it.
    type, abstract :: sweep_observer_t
    contains
        procedure(observe_iface), deferred :: observe
    end type sweep_observer_t

    abstract interface
        !> See the curve so far; an error stops the sweep.
        subroutine observe_iface(self, res, error)
            import :: sweep_observer_t, sweep_result_t, error_type
            class(sweep_observer_t), intent(inout) :: self
            type(sweep_result_t), intent(in) :: res
            type(error_type), allocatable, intent(out) :: error
        end subroutine observe_iface
    end interface

    !> The projected friction equations as a family in the parameter.
    type, extends(parametric_system_t) :: friction_family_t
        type(model_t) :: model
        type(hbm_options_t) :: opts
        character(len=16) :: parameter = ''
        type(hb_problem_t) :: prob
        !> Dynamics at unit amplitude of forcing term 1 ('force_amplitude').
        type(dynamics_t) :: unit
        real(dp) :: current = 0.0_dp
        logical :: have_current = .false.
        !> How many times the family factorized the dynamic stiffnesses Z_h of its basis
        !> (new_dynamics calls, the unit dynamics of 'force_amplitude' included): once per
        !> distinct omega met ('omega'), once at the start otherwise.
        integer :: factorizations = 0
        !> The dynamics at the last few omega values met ('omega'): the corrector, the
        !> tangent and the residual scale come back to an omega already seen; a value is
        !> looked up exactly (==), the oldest entry is replaced.
        type(dynamics_t) :: cached(dynamics_cache_size)
        real(dp) :: cached_omega(dynamics_cache_size) = 0.0_dp
        integer :: cached_age(dynamics_cache_size) = 0
        integer :: clock = 0
        !> s(K), s(M) of the model (see dynamics_t%smin_k; -1: not yet known).
        real(dp) :: singular_values(2) = -1.0_dp
        real(dp), allocatable :: amplitude0(:), rs(:, :), vs(:, :), ss(:, :), dv(:, :), &
                                 dvs(:)
        complex(dp), allocatable :: cw(:)
        !> The model's sparse matrices (a sweep of the exact sparse condensation; its
        !> %model follows `model`), and the DOFs whose rows the dynamics keep.
        type(sparse_model_t), allocatable :: sparse
        integer, allocatable :: kept(:)
    contains
        procedure :: residual => family_residual
        procedure :: jacobian => family_jacobian
        procedure :: recover => family_recover
        procedure :: residual_scale => family_scale
        procedure :: set => family_set
        procedure :: destroy => family_destroy
    end type friction_family_t

contains

    !> Check sweep options against the model. Errors (stat input) name the component
    !> ("opts%step, opts%min_step, ...: must be >= 0").
    subroutine validate_sweep_options(model, opts, error)
        !> The model swept.
        type(model_t), intent(in) :: model
        !> Options to check.
        type(sweep_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Most points of one sweep.
        integer, parameter :: max_points = 100000
        character(len=200) :: buf
        buf = ""
        select case (opts%parameter)
        case ('omega')
            if (.not. (min(opts%start, opts%stop) > 0.0_dp)) &
                buf = "opts%start, opts%stop: omega must stay > 0"
        case ('mu', 'normal_load')
            if (.not. (min(opts%start, opts%stop) >= 0.0_dp)) &
                buf = "opts%start, opts%stop: "//trim(opts%parameter)//" must stay >= 0"
            if (model%ncontact() == 0) buf = "opts%parameter = '"//trim(opts%parameter)// &
                                             "': the model has no contact"
        case ('force_amplitude')
            if (model%nforce() == 0) then
                buf = "opts%parameter = 'force_amplitude': the model has no forcing term"
            else if (model%force_amplitude(1) == 0.0_dp) then
                buf = "opts%parameter = 'force_amplitude': force_amplitude(1) is 0, so the "// &
                      "forcing terms cannot be scaled from it"
            end if
        case default
            buf = "opts%parameter = '"//trim(opts%parameter)// &
                  "': must be 'omega', 'force_amplitude', 'mu' or 'normal_load'"
        end select
        if (len_trim(buf) == 0) then
            if (opts%step < 0.0_dp .or. opts%min_step < 0.0_dp .or. opts%max_step < 0.0_dp) &
                buf = "opts%step, opts%min_step, opts%max_step: must be >= 0 (0: automatic)"
        end if
        if (len_trim(buf) == 0 .and. opts%max_points > max_points) &
            write (buf, '(a,i0,a,i0)') "opts%max_points = ", opts%max_points, &
            ": must be <= ", max_points
        if (len_trim(buf) == 0 .and. allocated(opts%observe)) then
            if (size(opts%observe, 2) /= model%ndof) then
                write (buf, '(a,i0,a,i0,a)') "opts%observe: has ", size(opts%observe, 2), &
                    " columns, the model ", model%ndof, " DOFs"
            else if (.not. all(ieee_is_finite(opts%observe))) then
                buf = "opts%observe: not finite"
            end if
        end if
        if (len_trim(buf) > 0) then
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        block
            type(continuation_options_t) :: co
            co = continuation_options_of(opts)
            call validate_continuation_options(co, error)
        end block
    end subroutine validate_sweep_options

    !> The continuation options of a sweep (automatic steps filled in).
    pure function continuation_options_of(opts) result(co)
        !> Sweep options.
        type(sweep_options_t), intent(in) :: opts
        type(continuation_options_t) :: co
        real(dp) :: range
        range = abs(opts%stop - opts%start)
        co%start = opts%start
        co%stop = opts%stop
        co%step = opts%step
        co%min_step = opts%min_step
        co%max_step = opts%max_step
        if (co%step == 0.0_dp) co%step = range/100.0_dp
        if (co%min_step == 0.0_dp) co%min_step = min(range*1.0e-5_dp, co%step)
        if (co%max_step == 0.0_dp) co%max_step = max(range/25.0_dp, co%step)
        co%max_points = opts%max_points
        co%max_failures = opts%max_failures
    end function continuation_options_of

    !> The value of the swept parameter in `model`.
    pure real(dp) function sweep_parameter_value(model, parameter) result(p)
        !> The model.
        type(model_t), intent(in) :: model
        !> 'omega', 'force_amplitude', 'mu' or 'normal_load'.
        character(len=*), intent(in) :: parameter
        select case (parameter)
        case ('omega')
            p = model%omega
        case ('force_amplitude')
            p = model%force_amplitude(1)
        case ('mu')
            p = model%mu(1)
        case default
            p = model%normal_load(1)
        end select
    end function sweep_parameter_value

    !> Set the swept parameter of `model` to p ('force_amplitude' scales every term from
    !> the amplitudes `amplitude0` of the case, term 1 taking the value p).
    pure subroutine set_sweep_parameter(model, parameter, p, amplitude0)
        !> The model, changed.
        type(model_t), intent(inout) :: model
        !> 'omega', 'force_amplitude', 'mu' or 'normal_load'.
        character(len=*), intent(in) :: parameter
        !> The value.
        real(dp), intent(in) :: p
        !> The forcing amplitudes of the case.
        real(dp), intent(in) :: amplitude0(:)
        select case (parameter)
        case ('omega')
            model%omega = p
        case ('force_amplitude')
            model%force_amplitude = amplitude0*(p/amplitude0(1))
        case ('mu')
            model%mu = p
        case default
            model%normal_load = p
        end select
    end subroutine set_sweep_parameter

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
                         sparse, dofs)
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
        type(friction_family_t), target :: fam
        type(continuation_options_t) :: co
        type(continuation_report_t) :: rep
        type(hbm_solution_t) :: sol
        type(hbm_options_t) :: ho
        real(dp) :: c0, c1, tl_before, weight, dir
        type(continuation_state_t) :: state_before, before_turn
        integer :: turn_points, retrace_hits, jumps
        logical :: turned
        integer :: nb, nc
        character(len=40) :: buf
        type(model_t) :: m0
        real(dp), allocatable :: amplitude0(:)
        type(point_tally_t) :: tally
        integer :: k

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
        call validate_options(hbm, error)
        if (allocated(error)) return
        call validate_sweep_options(model, opts, error)
        if (allocated(error)) return
        co = continuation_options_of(opts)
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
            call solve_periodic_sparse(fam%sparse, ho, fam%kept, sol, error)
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
        else
            call new_friction_family(fam, model, hbm, opts%parameter, opts%start, sol%rho, error)
        end if
        if (allocated(error)) return
        nb = fam%prob%basis%nb
        co%tol = hbm%tol
        co%fscale = max(fam%prob%rho*maxval(fam%prob%limit), tiny(1.0_dp))
        ! the arclength measures the friction force by the RMS of its coefficients relative to
        ! the friction limit, weighted so that the smallest change the quadrature can make
        ! (one sample switching between slip directions through stick: a force change of
        ! about 2.8 / samples in these units) is a tenth of the largest step: the curve of
        ! the sampled equations is a staircase of such switches near a resonance, and
        ! the parameter must dominate the step there; the force still takes over at folds
        weight = max(1.0_dp, 28.0_dp*abs(co%stop - co%start)/(real(hbm%samples, dp)*co%max_step))
        co%yscale = [max(maxval(fam%prob%limit), tiny(1.0_dp))*sqrt(real(nb, dp))*weight]
        if (opts%parameter == 'mu' .or. opts%parameter == 'normal_load') then
            ! the limits change along the curve: scale by the largest on the range
            block
                type(model_t) :: m2
                m2 = fam%model
                call set_sweep_parameter(m2, opts%parameter, max(abs(opts%start), &
                                         abs(opts%stop)), fam%amplitude0)
                co%yscale = [max(maxval(m2%mu*m2%normal_load), tiny(1.0_dp))]
                co%fscale = max(fam%prob%rho*co%yscale(1), tiny(1.0_dp))
                co%yscale = co%yscale*sqrt(real(nb, dp))*weight
            end block
        end if
        allocate (res%points(64))

        if (present(resume)) then
            if (resume%npoints > 0) then
                if (size(resume%state%y) /= fam%prob%n) then
                    call fatal_error(error, "sweep: the checkpoint has another number of "// &
                                     "unknowns than this case", stickslip_stat%input)
                    call fam%prob%destroy()
                    return
                end if
                res%state = resume%state
                res%npoints = resume%npoints
                res%points = resume%points(1:resume%npoints)
                res%resumed_points = resume%npoints
                res%folds = resume%folds
                res%seconds = resume%seconds
                res%stability_seconds = resume%stability_seconds
                ! the checks of resumed points: only their truncation estimate was kept
                do k = 1, res%npoints
                    call tally%add_point(diagnostics_t(), res%points(k)%truncation, &
                                         res%points(k)%parameter)
                end do
            end if
        end if

        if (res%npoints == 0) then
            call start_continuation(fam, co, reshape(sol%rcoef, [fam%prob%n]), res%state, &
                                    rep, error)
            if (allocated(error)) then
                call fam%prob%destroy()
                return
            end if
            if (res%state%reason /= reason_running) then
                call fatal_error(error, "sweep: "//rep%message, stickslip_stat%numerical)
                call fam%prob%destroy()
                return
            end if
            call add_point("start")
            if (allocated(error)) then
                call fam%prob%destroy()
                return
            end if
        end if

        ! A turn back in the parameter is a fold, or a kink of the sampled friction equations
        ! where the corrector came back onto the branch already traced: then the points
        ! after the turn retrace the earlier ones. After max_retrace_hits of them in a row the
        ! sweep returns to the last point before the turn and steps the parameter past it.
        dir = sign(1.0_dp, opts%stop - opts%start)
        turned = .false.
        turn_points = 0
        retrace_hits = 0
        jumps = 0
        do while (res%state%reason == reason_running)
            tl_before = res%state%tl
            state_before = res%state
            call continuation_step(fam, co, res%state, rep, error)
            if (allocated(error)) exit
            if (rep%accepted) then
                if (tl_before*res%state%tl < 0.0_dp) then
                    res%folds = res%folds + 1
                    turned = tl_before*dir > 0.0_dp
                    if (turned) then
                        before_turn = state_before
                        turn_points = res%npoints
                        retrace_hits = 0
                    end if
                end if
                if (rep%recovered) then
                    call add_point("recovered")
                else if (res%state%reason == reason_end) then
                    call add_point("end")
                else if (rep%halvings > 0) then
                    call add_point("halved")
                else
                    call add_point("ok")
                end if
                if (allocated(error)) exit
                if (turned .and. jumps < max_retrace_jumps .and. &
                    res%state%reason /= reason_end) then
                    if (retraces(res%points(res%npoints), res%points(1:turn_points))) then
                        retrace_hits = retrace_hits + 1
                    else
                        retrace_hits = 0
                    end if
                    if (retrace_hits >= max_retrace_hits) then
                        ! not a fold: back before the turn, a parameter step past it
                        res%state = before_turn
                        res%state%ty = 0.0_dp
                        res%state%tl = dir
                        res%state%ds = min(2.0_dp*before_turn%ds, co%max_step)
                        res%state%points = res%npoints
                        res%folds = res%folds - 1
                        jumps = jumps + 1
                        turned = .false.
                        call res%diagnostics%add(level_note, "retrace", "sweep: the curve "// &
                            "turned back at "//trim(opts%parameter)//" = "// &
                            rtoa6(before_turn%lambda)//" and retraced itself (a kink of the "// &
                            "sampled friction equations, not a fold): continued past it by "// &
                            "a parameter step")
                    end if
                end if
            end if
            if (res%state%reason /= reason_running) then
                if (len(rep%message) > 0) res%diagnosis = rep%message
            end if
        end do
        call fam%prob%destroy()
        res%factorizations = fam%factorizations
        if (allocated(error)) return
        res%complete = res%state%reason == reason_end
        if (opts%parameter == 'omega' .and. .not. present(sparse)) then
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
        end if

    contains

        !> Solve the accepted point for its outputs, add it, tell the observer.
        subroutine add_point(status)
            character(len=*), intent(in) :: status
            type(frc_point_t) :: pt
            type(floquet_t) :: fl
            type(truncation_t) :: est
            type(model_t) :: m
            type(hbm_solution_t) :: ps
            type(hbm_options_t) :: po
            type(frc_point_t), allocatable :: grown(:)
            real(dp) :: s0, s1
            integer :: k
            logical :: at_point
            m = fam%model
            call set_sweep_parameter(m, opts%parameter, res%state%lambda, fam%amplitude0)
            po = fam%opts
            po%want_samples = .true.
            po%start = 'direct'
            ! the family's dynamics are at this parameter (the tangent was just computed
            ! there): the point and its truncation estimate need no new factorization
            at_point = fam%have_current .and. fam%current == res%state%lambda
            if (allocated(fam%sparse)) then
                fam%sparse%model = m
                if (at_point) then
                    call solve_periodic_sparse(fam%sparse, po, fam%kept, ps, error, &
                                               r_start=reshape(res%state%y, [nb, nc]), &
                                               dyn=fam%prob%dyn)
                else
                    call solve_periodic_sparse(fam%sparse, po, fam%kept, ps, error, &
                                               r_start=reshape(res%state%y, [nb, nc]))
                end if
            else if (at_point) then
                call solve_periodic(m, po, ps, error, &
                                    r_start=reshape(res%state%y, [nb, nc]), dyn=fam%prob%dyn)
            else
                call solve_periodic(m, po, ps, error, &
                                    r_start=reshape(res%state%y, [nb, nc]))
            end if
            if (allocated(error)) return
            pt%parameter = res%state%lambda
            pt%arclength = res%state%arclength
            if (allocated(opts%observe)) then
                pt%amplitude = maxval(abs(matmul(ps%x, transpose(opts%observe))), dim=1)
            else
                pt%amplitude = [(maxval(abs(ps%x(:, k))), k=1, size(ps%x, 2))]
            end if
            pt%diss_friction = ps%diss_friction
            pt%diss_damping = ps%diss_damping
            pt%dissipation = ps%diss_friction + ps%diss_damping
            pt%rmax = [(maxval(abs(ps%r(:, k))), k=1, nc)]
            pt%stick = ps%stick_fraction
            pt%harmonics = ps%harmonics
            pt%residual = ps%fnorm/max(ps%fscale, tiny(1.0_dp))
            pt%status = status
            pt%nfev = rep%nfev
            pt%floquet_max = ieee_value(1.0_dp, ieee_quiet_nan)
            pt%stable = -1
            pt%truncation = ieee_value(1.0_dp, ieee_quiet_nan)
            if (opts%truncation .and. .not. allocated(fam%sparse)) then
                if (at_point) then
                    call estimate_truncation(m, po, ps, est, error, dyn=fam%prob%dyn, &
                                             observe=opts%observe)
                else
                    call estimate_truncation(m, po, ps, est, error, observe=opts%observe)
                end if
                if (allocated(error)) return
                if (est%available) pt%truncation = est%estimate
            end if
            call tally%add_point(ps%diagnostics, pt%truncation, pt%parameter)
            if (opts%stability) then
                s0 = thread_cpu_seconds()
                call periodic_stability(m, ps, ref, fl, error)
                s1 = thread_cpu_seconds()
                res%stability_seconds = res%stability_seconds + (s1 - s0)
                if (allocated(error)) return
                if (fl%verdict /= 'unknown') then
                    pt%floquet_max = fl%max_modulus
                    pt%stable = merge(1, 0, fl%stable)
                end if
            end if
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
            if (present(progress)) then
                write (buf, '(g0.6)') res%state%lambda
                call progress%report(res%npoints, 0, trim(opts%parameter)//" = "// &
                                     trim(adjustl(buf)))
            end if
        end subroutine add_point
    end subroutine run_sweep

    !> Whether point p lies on the curve of the points `earlier` (in continuation order):
    !> some pair of consecutive earlier points brackets p's parameter and their amplitudes,
    !> interpolated linearly, agree with p's to retrace_tolerance of the largest.
    pure logical function retraces(p, earlier)
        type(frc_point_t), intent(in) :: p
        type(frc_point_t), intent(in) :: earlier(:)
        integer :: k
        real(dp) :: w, scale
        retraces = .false.
        do k = 1, size(earlier) - 1
            associate (a => earlier(k), b => earlier(k + 1))
                if ((p%parameter - a%parameter)*(p%parameter - b%parameter) > 0.0_dp) cycle
                if (a%parameter == b%parameter) cycle
                if (size(a%amplitude) /= size(p%amplitude) .or. &
                    size(b%amplitude) /= size(p%amplitude)) cycle
                w = (p%parameter - a%parameter)/(b%parameter - a%parameter)
                scale = max(maxval(abs(a%amplitude)), maxval(abs(b%amplitude)), tiny(1.0_dp))
                if (maxval(abs(p%amplitude - ((1.0_dp - w)*a%amplitude + w*b%amplitude))) <= &
                    retrace_tolerance*scale) then
                    retraces = .true.
                    return
                end if
            end associate
        end do
    end function retraces

    !> A real with 6 significant digits.
    function rtoa6(x) result(text)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=32) :: buf
        write (buf, '(g0.6)') x
        text = trim(adjustl(buf))
    end function rtoa6

    !> Count the failed checks of one point: its solution's diagnostics (warnings and
    !> distrust) and its truncation estimate (stickslip_checks thresholds; NaN: not
    !> computed).
    subroutine tally_add_point(self, diag, truncation, parameter)
        class(point_tally_t), intent(inout) :: self
        type(diagnostics_t), intent(in) :: diag
        real(dp), intent(in) :: truncation, parameter
        integer :: k
        if (.not. allocated(self%key)) allocate (self%key(0), self%count(0), self%level(0), &
                                                 self%first(0))
        self%points = self%points + 1
        if (allocated(diag%items)) then
            do k = 1, size(diag%items)
                if (diag%items(k)%level >= level_warning) &
                    call count_key(diag%items(k)%key, diag%items(k)%level)
            end do
        end if
        if (ieee_is_finite(truncation)) then
            if (truncation > truncation_untrusted) then
                call count_key("truncation", level_untrusted)
            else if (truncation > truncation_warning) then
                call count_key("truncation", level_warning)
            end if
        end if

    contains

        subroutine count_key(key, level)
            character(len=*), intent(in) :: key
            integer, intent(in) :: level
            integer :: i
            i = findloc(self%key, key, 1)
            if (i == 0) then
                self%key = [character(len=48) :: self%key, key]
                self%count = [self%count, 0]
                self%level = [self%level, level]
                self%first = [self%first, parameter]
                i = size(self%key)
            end if
            self%count(i) = self%count(i) + 1
            self%level(i) = max(self%level(i), level)
        end subroutine count_key
    end subroutine tally_add_point

    !> One diagnostics item per failed check, key 'points_<key>': a warning naming how many
    !> points failed it and where the first one is (the curve is usable elsewhere); untrusted
    !> when every point of the curve failed a check at level untrusted.
    subroutine tally_report(self, parameter, diag)
        class(point_tally_t), intent(in) :: self
        character(len=*), intent(in) :: parameter
        type(diagnostics_t), intent(inout) :: diag
        integer :: i, level
        character(len=300) :: buf
        if (.not. allocated(self%key)) return
        do i = 1, size(self%key)
            level = level_warning
            if (self%level(i) == level_untrusted .and. self%count(i) == self%points) &
                level = level_untrusted
            write (buf, '(i0,a,i0,a,es13.5e3,a)') self%count(i), " of ", self%points, &
                " points failed the check '"//trim(self%key(i))//"' (the first at "// &
                trim(parameter)//" = ", self%first(i), "): see the points' columns"
            call diag%add(level, "points_"//trim(self%key(i)), trim(buf))
        end do
    end subroutine tally_report

    !> Build the friction equations of `model` as a family in `parameter` ('omega',
    !> 'force_amplitude', 'mu' or 'normal_load'), set at `p`, on the basis of `hbm` with the
    !> weight `rho` > 0 (fixed along the family). Errors: as new_hb_problem and
    !> new_dynamics.
    !> With `sparse` (and `dofs`, see run_sweep), the dynamics are the exact sparse
    !> condensation; `build` = .false. only sets the family's data (no dynamics, no basis).
    subroutine new_friction_family(fam, model, hbm, parameter, p, rho, error, sparse, dofs, &
                                   build)
        !> The family.
        type(friction_family_t), intent(out) :: fam
        !> A validated model with friction contacts.
        type(model_t), intent(in) :: model
        !> Basis and tolerance options.
        type(hbm_options_t), intent(in) :: hbm
        !> The parameter.
        character(len=*), intent(in) :: parameter
        !> Its value.
        real(dp), intent(in) :: p
        !> Weight of Psi [m/(N s)].
        real(dp), intent(in) :: rho
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The model's sparse matrices.
        type(sparse_model_t), intent(in), optional :: sparse
        !> With `sparse`: the DOFs to keep (then the contact and forced ones).
        integer, intent(in), optional :: dofs(:)
        !> Build the problem (default .true.).
        logical, intent(in), optional :: build
        integer :: nb, nc, stat
        fam%model = model
        fam%opts = hbm
        fam%opts%rho = rho
        fam%parameter = parameter
        fam%amplitude0 = model%force_amplitude
        call set_sweep_parameter(fam%model, parameter, p, fam%amplitude0)
        if (present(sparse)) then
            fam%sparse = sparse
            fam%sparse%model = fam%model
            if (present(dofs)) then
                fam%kept = kept_dofs(sparse, dofs, error)
            else
                fam%kept = kept_dofs(sparse, [integer ::], error)
            end if
            if (allocated(error)) return
        end if
        if (present(build)) then
            if (.not. build) return
        end if
        if (allocated(fam%sparse)) then
            block
                type(basis_t) :: basis
                type(dynamics_t) :: dyn
                call new_basis(basis, hbm%harmonics, hbm%odd_only, hbm%samples, error)
                if (allocated(error)) return
                call new_sparse_dynamics(dyn, fam%sparse, basis, fam%kept, error)
                call basis%destroy()
                if (allocated(error)) return
                call new_condensed_problem(fam%prob, dyn, fam%model%mu*fam%model%normal_load, &
                                           hbm%harmonics, hbm%odd_only, hbm%samples, rho, &
                                           error, fam%model%force_harmonic)
            end block
        else
            call new_hb_problem(fam%prob, fam%model, hbm%harmonics, hbm%odd_only, &
                                hbm%samples, rho, error)
        end if
        fam%factorizations = 1
        if (allocated(error)) return
        nb = fam%prob%basis%nb
        nc = fam%prob%nc
        allocate (fam%rs(hbm%samples, nc), fam%vs(hbm%samples, nc), fam%ss(hbm%samples, nc), &
                  fam%dv(nb, nc), fam%dvs(hbm%samples), fam%cw(hbm%samples/2 + 1))
        if (parameter == 'force_amplitude') then
            block
                type(model_t) :: m1
                m1 = fam%model
                m1%force_amplitude = fam%amplitude0/fam%amplitude0(1)
                if (allocated(fam%sparse)) then
                    fam%sparse%model = m1
                    call new_sparse_dynamics(fam%unit, fam%sparse, fam%prob%basis, fam%kept, &
                                             error)
                    fam%sparse%model = fam%model
                else
                    call new_dynamics(fam%unit, m1, fam%prob%basis, error)
                end if
                fam%factorizations = fam%factorizations + 1
                if (allocated(error)) return
            end block
        end if
        stat = 0
        call fam%set(p, stat)
        if (stat /= 0) call fatal_error(error, "sweep: the structure has no dynamics at "// &
                                        "the start of the range", stickslip_stat%numerical)
    end subroutine new_friction_family

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

    !> Words for a continuation_state_t%reason.
    pure function reason_text(reason) result(text)
        !> reason_* of stickslip_continuation.
        integer, intent(in) :: reason
        character(len=:), allocatable :: text
        select case (reason)
        case (reason_running)
            text = "interrupted"
        case (reason_end)
            text = "reached the end of the range"
        case (reason_failures)
            text = "stopped after failed points"
        case (reason_max_points)
            text = "stopped at max_points before the end of the range"
        case (reason_left)
            text = "the branch left the range"
        case default
            text = "unknown"
        end select
    end function reason_text

    !> Move the family to parameter p (rebuild or rescale what depends on it).
    subroutine family_set(self, p, stat)
        class(friction_family_t), intent(inout) :: self
        real(dp), intent(in) :: p
        integer, intent(inout) :: stat
        if (self%have_current .and. p == self%current) return
        if (.not. ieee_is_finite(p)) then
            stat = 1
            return
        end if
        select case (self%parameter)
        case ('omega')
            if (.not. (p > 0.0_dp)) then
                stat = 1
                return
            end if
            self%model%omega = p
            call set_omega_dynamics(self, p, stat)
            if (stat /= 0) return
        case ('force_amplitude')
            self%prob%dyn%v0 = p*self%unit%v0
            self%prob%dyn%x0 = p*self%unit%x0
            if (allocated(self%unit%x0_static)) self%prob%dyn%x0_static = p*self%unit%x0_static
            if (allocated(self%unit%forcing_gram)) then
                ! the Gram matrices of [X0, Y]: the X0 row and column scale with p
                self%prob%dyn%forcing_gram(1, :) = p*p*self%unit%forcing_gram(1, :)
                self%prob%dyn%forcing_gram(2:, :) = p*self%unit%forcing_gram(2:, :)
                self%prob%dyn%damping_gram = self%unit%damping_gram
                self%prob%dyn%damping_gram(1, :, :) = p*self%unit%damping_gram(1, :, :)
                self%prob%dyn%damping_gram(:, 1, :) = p*self%unit%damping_gram(:, 1, :)
                self%prob%dyn%damping_gram(1, 1, :) = p*p*self%unit%damping_gram(1, 1, :)
            end if
        case ('mu', 'normal_load')
            if (p < 0.0_dp) then
                stat = 1
                return
            end if
            call set_sweep_parameter(self%model, self%parameter, p, self%amplitude0)
            self%prob%limit = self%model%mu*self%model%normal_load
        end select
        self%current = p
        self%have_current = .true.
    end subroutine family_set

    !> The dynamics of a family in omega at omega = p (self%model%omega already p): from
    !> the cache when p was met before (exactly), else factorized and cached. stat = 1 when
    !> Z_h is singular there.
    subroutine set_omega_dynamics(self, p, stat)
        class(friction_family_t), intent(inout) :: self
        real(dp), intent(in) :: p
        integer, intent(inout) :: stat
        type(error_type), allocatable :: error
        integer :: k
        self%clock = self%clock + 1
        do k = 1, dynamics_cache_size
            if (self%cached_age(k) > 0 .and. self%cached_omega(k) == p) then
                self%prob%dyn = self%cached(k)
                self%cached_age(k) = self%clock
                return
            end if
        end do
        ! K and M do not change along the family: their smallest singular values neither
        if (allocated(self%sparse)) then
            self%sparse%model = self%model
            if (self%singular_values(1) >= 0.0_dp) then
                call new_sparse_dynamics(self%prob%dyn, self%sparse, self%prob%basis, &
                                         self%kept, error, singular_values=self%singular_values, &
                                         with_omega_derivative=.true.)
            else
                call new_sparse_dynamics(self%prob%dyn, self%sparse, self%prob%basis, &
                                         self%kept, error, with_omega_derivative=.true.)
            end if
        else if (self%singular_values(1) >= 0.0_dp) then
            call new_dynamics(self%prob%dyn, self%model, self%prob%basis, error, &
                              with_omega_derivative=.true., &
                              singular_values=self%singular_values)
        else
            call new_dynamics(self%prob%dyn, self%model, self%prob%basis, error, &
                              with_omega_derivative=.true.)
        end if
        self%singular_values = [self%prob%dyn%smin_k, self%prob%dyn%smin_m]
        self%factorizations = self%factorizations + 1
        if (allocated(error)) then
            ! a singular dynamic stiffness (undamped resonance at h omega): no point here
            stat = 1
            self%have_current = .false.
            return
        end if
        k = minloc(self%cached_age, 1)
        self%cached(k) = self%prob%dyn
        self%cached_omega(k) = p
        self%cached_age(k) = self%clock
    end subroutine set_omega_dynamics

    !> ||V0||_2 at lambda, the contact velocities without friction (as solve_periodic's
    !> fscale): near a resonance the residual cannot be computed more accurately than that
    !> allows.
    real(dp) function family_scale(self, lambda) result(s)
        class(friction_family_t), intent(inout) :: self
        real(dp), intent(in) :: lambda
        integer :: stat
        stat = 0
        s = 0.0_dp
        call self%set(lambda, stat)
        if (stat /= 0) return
        self%dv = 0.0_dp
        call self%prob%dyn%contact_velocity(self%prob%basis, 0.0_dp*self%dv, self%dv)
        s = norm2(self%dv)
    end function family_scale

    !> Release the FFT plans.
    subroutine family_destroy(self)
        class(friction_family_t), intent(inout) :: self
        call self%prob%destroy()
    end subroutine family_destroy

    !> F(y, lambda): the projected friction equations at parameter lambda.
    subroutine family_residual(self, y, lambda, f, stat)
        class(friction_family_t), intent(inout) :: self
        real(dp), intent(in) :: y(:), lambda
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        call self%set(lambda, stat)
        if (stat /= 0) then
            f = huge(1.0_dp)
            return
        end if
        call self%prob%residual(y, f, stat)
    end subroutine family_residual

    !> dF/dy (the exact generalized Jacobian of a single solve) and dF/dlambda.
    subroutine family_jacobian(self, y, lambda, jy, jl, stat)
        class(friction_family_t), intent(inout) :: self
        real(dp), intent(in) :: y(:), lambda
        real(dp), intent(out) :: jy(:, :), jl(:)
        integer, intent(inout) :: stat
        integer :: j, nb, nc
        call self%set(lambda, stat)
        if (stat /= 0) then
            jy = 0.0_dp
            jl = 0.0_dp
            return
        end if
        call self%prob%jacobian(y, jy, stat)
        nb = self%prob%basis%nb
        nc = self%prob%nc
        call self%prob%contact_samples(y, self%rs, self%vs, self%ss)
        select case (self%parameter)
        case ('omega')
            call self%prob%dyn%contact_velocity_derivative(self%prob%basis, &
                                                           reshape(y, [nb, nc]), self%dv)
        case ('force_amplitude')
            ! dV/dp = V0 at unit amplitude (V = p V0_unit + G R)
            call self%unit%contact_velocity(self%prob%basis, 0.0_dp*reshape(y, [nb, nc]), &
                                            self%dv)
        end select
        do j = 1, nc
            select case (self%parameter)
            case ('omega', 'force_amplitude')
                ! dPsi/dv = s
                call self%prob%basis%synthesize(self%dv(:, j), self%dvs, self%cw)
                self%dvs = self%ss(:, j)*self%dvs
            case ('mu')
                self%dvs = psi_limit_derivative(self%rs(:, j), self%vs(:, j), &
                           self%prob%limit(j), self%prob%rho)*self%model%normal_load(j)
            case default
                self%dvs = psi_limit_derivative(self%rs(:, j), self%vs(:, j), &
                           self%prob%limit(j), self%prob%rho)*self%model%mu(j)
            end select
            call self%prob%basis%analyse(self%dvs, jl((j - 1)*nb + 1:j*nb), self%cw)
        end do
        if (.not. all(ieee_is_finite(jl))) stat = 1
    end subroutine family_jacobian

    !> Recovery at a fixed parameter: the harmonic ladder (warm starts from fewer harmonics,
    !> the lowest stage starting from the truncated y).
    subroutine family_recover(self, y, lambda, ok, error)
        class(friction_family_t), intent(inout) :: self
        real(dp), intent(inout) :: y(:)
        real(dp), intent(in) :: lambda
        logical, intent(out) :: ok
        type(error_type), allocatable, intent(out) :: error
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        ok = .false.
        if (.not. ieee_is_finite(lambda)) return
        if (self%parameter == 'omega' .and. .not. (lambda > 0.0_dp)) return
        if ((self%parameter == 'mu' .or. self%parameter == 'normal_load') .and. lambda < 0.0_dp) &
            return
        m = self%model
        call set_sweep_parameter(m, self%parameter, lambda, self%amplitude0)
        o = self%opts
        o%start = 'ladder'
        o%want_samples = .false.
        if (allocated(self%sparse)) then
            self%sparse%model = m
            call solve_periodic_sparse(self%sparse, o, self%kept, s, error, &
                                       r_start=reshape(y, [self%prob%basis%nb, self%prob%nc]))
        else
            call solve_periodic(m, o, s, error, r_start=reshape(y, [self%prob%basis%nb, &
                                                                   self%prob%nc]))
        end if
        if (allocated(error)) then
            ! a singular dynamic stiffness at this parameter: no recovery here
            if (error%stat == stickslip_stat%numerical) deallocate (error)
            return
        end if
        if (.not. s%converged) return
        y = reshape(s%rcoef, [size(y)])
        ok = .true.
    end subroutine family_recover
end module stickslip_sweep
