!> What a user checks about a weighted-residual solution beyond its residual: the harmonic
!> truncation error estimate (always, once converged), optionally a harmonic count raised until
!> a requested accuracy, the Floquet multipliers (stability) and the periodicity defect of the
!> exact flow started from it (a-posteriori verification). Plain computation; the summary
!> writer reports it.
module stickslip_checks
    use stickslip_kinds, only: dp
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_untrusted
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_dynamics, only: dynamics_t
    use stickslip_hbm, only: hbm_max_harmonics
    use stickslip_reference, only: reference_options_t
    use stickslip_truncation, only: truncation_t, estimate_truncation, solve_to_tolerance
    use stickslip_stability, only: floquet_t, periodic_stability, verify_periodicity
    implicit none
    private
    public :: check_options_t, validate_check_options, hbm_checks_t, solve_and_check, truncation_findings, &
        sampling_notes, sampling_diagnostics

    !> A truncation estimate above this makes the stick-phase count a lower bound (the
    !> 8 phases of examples/many_sticks.nml, six shorter than T/20, appear as 2 at H = 10
    !> and 20 (estimates 0.21, 0.13), 6 at H = 30 .. 100 (0.13 .. 0.023), 8 from H = 160).
    real(dp), parameter :: coarse_estimate = 0.05_dp
    !> Truncation estimates above these give a warning / make the solution untrusted
    !> (diagnostics key 'truncation'; the estimate is within a factor 0.5 to 5 of the true
    !> error on the seed case, stickslip_truncation).
    real(dp), parameter, public :: truncation_warning = 0.1_dp, truncation_untrusted = 0.5_dp

    !> What to check about a weighted-residual solution (the &hbm variables harmonics_tol,
    !> max_harmonics, stability, verify_periods of a case file).
    type :: check_options_t
        !> Harmonic truncation tolerance: 0 keeps H = harmonics; > 0 doubles H from
        !> `harmonics` (warm starts) until the relative truncation error estimate is below
        !> it, or H = max_harmonics.
        real(dp) :: harmonics_tol = 0.0_dp
        !> Highest H the harmonics_tol loop may reach (0: 8 * harmonics).
        integer :: max_harmonics = 0
        !> Floquet multipliers of the solution (exact event-driven monodromy).
        logical :: stability = .false.
        !> Periods of the exact flow integrated from the solution to report its periodicity
        !> defect (0: none).
        integer :: verify_periods = 0
        !> Observed combinations of DOFs for the truncation estimate, nobs x ndof (optional;
        !> a reduced model: the rows of its basis for the output DOFs, so that the estimate
        !> judges physical displacements, not the coordinates of stiff modes).
        real(dp), allocatable :: observe(:, :)
    end type check_options_t

    !> The checks of one solution.
    type :: hbm_checks_t
        !> Truncation error estimate (est%available when computed).
        type(truncation_t) :: truncation
        !> Floquet multipliers (computed when `stability`).
        logical :: stability = .false.
        type(floquet_t) :: floquet
        !> Relative periodicity defect of the exact flow after 1, 2, ... periods (empty when
        !> not asked).
        real(dp), allocatable :: defect(:)
        !> Warnings about the sampling of the solution ('' when none): sampling_notes.
        character(len=:), allocatable :: notes
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type hbm_checks_t

contains

    !> Check the check options against the solver options `opts`. Errors (stat input) name
    !> the component ("copts%max_harmonics = 3: must be 0 (automatic) or >= harmonics = 5").
    subroutine validate_check_options(copts, opts, error)
        !> Check options.
        type(check_options_t), intent(in) :: copts
        !> Solver options (harmonics).
        type(hbm_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Most periods of the exact flow verify_periods may ask for.
        integer, parameter :: max_verify_periods = 1000
        character(len=200) :: buf
        if (.not. (copts%harmonics_tol >= 0.0_dp .and. copts%harmonics_tol < 1.0_dp)) then
            write (buf, '(a,g0.6,a)') "copts%harmonics_tol = ", copts%harmonics_tol, &
                ": must be in [0, 1) (0: keep harmonics)"
        else if (copts%max_harmonics < 0 .or. (copts%max_harmonics > 0 .and. &
                                                copts%max_harmonics < opts%harmonics)) then
            write (buf, '(a,i0,a,i0,a)') "copts%max_harmonics = ", copts%max_harmonics, &
                ": must be 0 (automatic) or >= harmonics = ", opts%harmonics, ""
        else if (copts%max_harmonics > hbm_max_harmonics) then
            write (buf, '(a,i0,a,i0)') "copts%max_harmonics = ", copts%max_harmonics, &
                ": must be <= ", hbm_max_harmonics
        else if (copts%verify_periods < 0 .or. copts%verify_periods > max_verify_periods) then
            write (buf, '(a,i0,a,i0)') "copts%verify_periods = ", copts%verify_periods, &
                ": must be in 0..", max_verify_periods
        else
            return
        end if
        call fatal_error(error, trim(buf), stickslip_stat%input)
    end subroutine validate_check_options

    !> Solve `model` with `opts` (with copts%harmonics_tol > 0: raise H until the truncation
    !> estimate meets it, up to copts%max_harmonics) and run the checks copts asks for. A
    !> solve that does not converge is an outcome (sol%converged = .false.; no checks then).
    !> Errors: as solve_periodic, and those of the checks (stat input for bad options).
    subroutine solve_and_check(model, opts, copts, ref, sol, checks, error)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Solver options.
        type(hbm_options_t), intent(in) :: opts
        !> What to check.
        type(check_options_t), intent(in) :: copts
        !> Options of the exact reference (stability).
        type(reference_options_t), intent(in) :: ref
        !> The solution.
        type(hbm_solution_t), intent(out) :: sol
        !> The checks.
        type(hbm_checks_t), intent(out) :: checks
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: hmax
        character(len=300) :: buf
        type(dynamics_t) :: dyn
        checks%notes = ""
        if (copts%harmonics_tol > 0.0_dp) then
            hmax = copts%max_harmonics
            if (hmax == 0) hmax = 8*max(1, opts%harmonics)
            call solve_to_tolerance(model, opts, copts%harmonics_tol, hmax, sol, &
                                    checks%truncation, error, observe=copts%observe)
            if (allocated(error)) return
        else
            ! the estimate's coarse solve restricts the solve's dynamics (no refactorization)
            call solve_periodic(model, opts, sol, error, dyn_out=dyn)
            if (allocated(error)) return
            if (sol%converged) then
                call estimate_truncation(model, opts, sol, checks%truncation, error, dyn=dyn, &
                                         observe=copts%observe)
                if (allocated(error)) return
            end if
        end if
        checks%notes = sampling_notes(sol%samples, sol%harmonics)
        call sampling_diagnostics(sol%samples, checks%diagnostics)
        if (.not. sol%converged) return
        call truncation_findings(checks)
        if (copts%stability) then
            checks%stability = .true.
            call periodic_stability(model, sol, ref, checks%floquet, error)
            if (allocated(error)) return
        end if
        if (copts%verify_periods > 0) then
            call verify_periodicity(model, sol, copts%verify_periods, checks%defect, error)
            if (allocated(error)) return
        end if
    end subroutine solve_and_check

    !> The notes and findings of a solution's truncation estimate (checks%truncation): a
    !> note above 5 % (stick phases shorter than T/H unresolved), a warning 'truncation'
    !> above truncation_warning, distrust above truncation_untrusted. No errors.
    subroutine truncation_findings(checks)
        !> The checks, their truncation estimate set.
        type(hbm_checks_t), intent(inout) :: checks
        character(len=200) :: buf
        if (.not. allocated(checks%notes)) checks%notes = ""
        if (checks%truncation%available .and. checks%truncation%estimate > coarse_estimate) then
            if (len(checks%notes) > 0) checks%notes = checks%notes//"; "
            checks%notes = checks%notes//"truncation estimate above 5%: stick phases "// &
                "shorter than a period of the highest harmonic (T/H) are not resolved, so "// &
                "stick_phases is a lower bound; raise harmonics or set harmonics_tol"
        end if
        if (checks%truncation%available) then
            if (checks%truncation%estimate > truncation_untrusted) then
                write (buf, '(a,es10.2e3,a,f4.2,a)') "truncation error estimate ", &
                    checks%truncation%estimate, " > ", truncation_untrusted, ": the harmonics "// &
                    "do not resolve the response; raise harmonics (and samples) or set "// &
                    "harmonics_tol"
                call checks%diagnostics%add(level_untrusted, "truncation", trim(buf))
            else if (checks%truncation%estimate > truncation_warning) then
                write (buf, '(a,es10.2e3,a,f4.2,a)') "truncation error estimate ", &
                    checks%truncation%estimate, " > ", truncation_warning, ": raise "// &
                    "harmonics or set harmonics_tol"
                call checks%diagnostics%add(level_warning, "truncation", trim(buf))
            end if
        end if
    end subroutine truncation_findings

    !> The sampling check as a diagnostics item: an odd number of samples is a warning
    !> (key 'odd_samples', prefixed with `prefix` when given): the mean friction force of a
    !> sticking contact is then biased (seed case, H = 15 with 31 samples: x2 off by 590%).
    pure subroutine sampling_diagnostics(samples, diag, prefix)
        !> Quadrature samples per period.
        integer, intent(in) :: samples
        !> The findings, appended to.
        type(diagnostics_t), intent(inout) :: diag
        !> Prefix of the key.
        character(len=*), intent(in), optional :: prefix
        character(len=300) :: buf
        if (mod(samples, 2) == 0) return
        write (buf, '(a,i0,a)') "samples = ", samples, " is odd: the mean friction "// &
            "force of a sticking contact is biased and its stuck position drifts (off by "// &
            "up to 590% on the seed case); use an even count, e.g. a power of two"
        if (present(prefix)) then
            call diag%add(level_warning, prefix//"odd_samples", trim(buf))
        else
            call diag%add(level_warning, "odd_samples", trim(buf))
        end if
    end subroutine sampling_diagnostics

    !> Warnings about a quadrature of `samples` points per period for `harmonics` harmonics
    !> ('' when none). An odd count loses the half-period symmetry of the grid (t_k + T/2 is
    !> no sample): the sampled friction equations then bias the mean friction force of a
    !> contact that sticks, and the stuck position drifts (seed case, H = 10: x2 errors of
    !> 200-540% with 21 or 41 samples against 7% with 42). Fewer than 4 H samples resolve the
    !> kinks of r(t) coarsely (seed, H = 30: x error 2.4% with 64 samples, 1.5% with 256).
    pure function sampling_notes(samples, harmonics) result(notes)
        !> Quadrature samples per period.
        integer, intent(in) :: samples
        !> Highest harmonic H.
        integer, intent(in) :: harmonics
        character(len=:), allocatable :: notes
        character(len=24) :: a, b
        notes = ""
        write (a, '(i0)') samples
        write (b, '(i0)') 4*harmonics
        if (mod(samples, 2) == 1) then
            notes = "samples = "//trim(a)//" is odd: the samples lose the half-period "// &
                    "symmetry and the mean friction force of a sticking contact is biased "// &
                    "(its stuck position drifts); use an even count, e.g. a power of two"
        else if (samples < 4*harmonics) then
            notes = "samples = "//trim(a)//" < 4 H = "//trim(b)//": the kinks of the "// &
                    "friction force are sampled coarsely (aliasing); more samples are cheap"
        end if
    end function sampling_notes
end module stickslip_checks
