!> The weighted-residual (harmonic balance) solve of the periodic response: the entry point
!> a structural code calls with a model built in memory.
!>
!> Flow: validate -> condense the linear dynamics on the contacts -> solve the projected
!> friction equations for the friction-force coefficients with hybrj (exact generalized
!> Jacobian; a ladder of warm starts from fewer harmonics when a cold start stalls;
!> convergence judged by convergence_scale) -> settle an undetermined mean force -> recover
!> every DOF -> energy balance and samples -> the checks as diagnostics (check_solution).
module stickslip_hbm
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_diagnostics, only: level_warning, level_untrusted
    use stickslip_model, only: model_t, validate_model, contact_velocity_direction, &
        force_direction
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem, new_condensed_problem
    use stickslip_dynamics, only: dynamics_t, near_singular_threshold
    use stickslip_minpack, only: hybrj_options_t, hybrj_report_t, solve_hybrj
    use stickslip_powell, only: solve_powell
    use stickslip_newton, only: newton_options_t, newton_report_t, solve_newton, &
        newton_converged
    use stickslip_rho, only: automatic_rho, rho_fraction
    implicit none
    private
    public :: solve_periodic, validate_options, convergence_scale
    public :: condensed_structure_t, solve_condensed
    public :: hbm_max_harmonics, hbm_max_samples, hbm_max_unknowns, newton_min_unknowns

    !> Largest harmonics H accepted by validate_options (the basis has 2 H + 1 terms).
    integer, parameter :: hbm_max_harmonics = 4096
    !> Largest quadrature samples per period accepted by validate_options (2**20).
    integer, parameter :: hbm_max_samples = 2**20
    !> Largest number of unknowns (2 H + 1) x contacts of a solve: its dense Jacobian holds
    !> the square of it (8193**2 doubles = 0.5 GB). Checked by the case reader, which knows
    !> the model.
    integer, parameter :: hbm_max_unknowns = 2*hbm_max_harmonics + 1

    !> What the weighted-residual solve needs of a structure beside its condensed dynamics
    !> (solve_condensed): built from a dense model_t by solve_periodic, from a
    !> sparse_model_t by solve_periodic_sparse.
    type :: condensed_structure_t
        !> Fundamental angular frequency [rad/s].
        real(dp) :: omega = 0.0_dp
        !> Number of contacts.
        integer :: ncontact = 0
        !> Friction limits mu_j N_j [N].
        real(dp), allocatable :: limit(:)
        !> The automatic rho of the structure (stickslip_rho) [m/(N s)].
        real(dp) :: rho_auto = 1.0_dp
        !> Load shape of each forcing term on the displacement columns (all N DOFs, or the
        !> kept DOFs of a sparse condensation), ncols x nforce: force_direction restricted.
        real(dp), allocatable :: force_rows(:, :)
        !> Harmonic, amplitude [N] and phase [rad] of each forcing term.
        integer, allocatable :: force_harmonic(:)
        real(dp), allocatable :: force_amplitude(:), force_phase(:)
    end type condensed_structure_t

    !> Number of unknowns (basis size x contacts) from which &hbm solver = 'auto' takes the
    !> semismooth Newton path (warm starts, LU) instead of hybrj: where it starts to win
    !> (bench/bench_solver.f90, README "Solvers").
    integer, parameter :: newton_min_unknowns = 48

    !> hybrj calls per stage: the first plus restarts from the last iterate.
    integer, parameter :: max_calls_per_stage = 4
    !> Lowest harmonic of the warm-start ladder.
    integer, parameter :: ladder_first = 3

    !> Thresholds of the checks of a solution (check_solution; README, "Where each method
    !> fails"). Energy balance error: exact for the truncated series up to roundoff.
    real(dp), parameter, public :: energy_warning = 1.0e-6_dp, energy_untrusted = 1.0e-2_dp
    !> |friction - Coulomb dissipation| / (the larger of Coulomb's and the whole dissipation
    !> per period): ~1% on the examples (the truncated force is not exactly -mu N sign(v)
    !> near the events).
    real(dp), parameter, public :: dissipation_warning = 0.1_dp, dissipation_untrusted = 0.5_dp
    !> max |r| / mu N - 1: the Gibbs overshoot of the truncated force at the stick-slip
    !> events is 2.6-5% on the seed case (stickslip_rho), up to 9% of a jump of 2 mu N
    !> (18%) at a reversal; 20% is reached on the damped 4-DOF chain at omega = 0.27.
    real(dp), parameter, public :: force_excess_warning = 0.5_dp, force_excess_untrusted = 1.0_dp
    !> Band of rho / contact mobility in which the friction equality keeps its digits.
    real(dp), parameter, public :: rho_ratio_min = 1.0e-6_dp, rho_ratio_max = 1.0e6_dp

contains

    !> Check solver options. Errors (stat input) name the component
    !> ("opts%harmonics = 5000: must be <= 4096").
    subroutine validate_options(opts, error)
        !> Options to check.
        type(hbm_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=200) :: buf
        if (opts%harmonics < 0 .or. (opts%odd_only .and. opts%harmonics < 1)) then
            write (buf, '(a,i0,a)') "opts%harmonics = ", opts%harmonics, &
                ": must be >= 0 (>= 1 with odd_only)"
        else if (opts%harmonics > hbm_max_harmonics) then
            write (buf, '(a,i0,a,i0)') "opts%harmonics = ", opts%harmonics, &
                ": must be <= ", hbm_max_harmonics
        else if (opts%samples > hbm_max_samples) then
            write (buf, '(a,i0,a,i0,a)') "opts%samples = ", opts%samples, &
                ": must be <= ", hbm_max_samples, " (2**20)"
        else if (opts%samples < 2*opts%harmonics + 1) then
            write (buf, '(a,i0,a,i0,a,i0,a)') "opts%samples = ", opts%samples, &
                ": too few samples for the harmonics: need samples >= 2*harmonics+1 = ", &
                2*opts%harmonics + 1, " (harmonics = ", opts%harmonics, ")"
        else if (.not. (opts%rho >= 0.0_dp) .or. opts%rho > huge(1.0_dp)) then
            write (buf, '(a,g0.6,a)') "opts%rho = ", opts%rho, &
                ": must be finite and >= 0 (0: automatic)"
        else if (.not. (opts%tol > 0.0_dp) .or. opts%tol >= 1.0_dp) then
            write (buf, '(a,g0.6,a)') "opts%tol = ", opts%tol, ": must be in (0, 1)"
        else if (.not. (opts%xtol >= 0.0_dp) .or. opts%xtol >= 1.0_dp) then
            write (buf, '(a,g0.6,a)') "opts%xtol = ", opts%xtol, ": must be in [0, 1)"
        else if (opts%maxfev < 0) then
            write (buf, '(a,i0,a)') "opts%maxfev = ", opts%maxfev, ": must be >= 0 (0: automatic)"
        else if (opts%start /= 'auto' .and. opts%start /= 'direct' .and. opts%start /= 'ladder') then
            write (buf, '(a)') "opts%start = '"//trim(opts%start)// &
                "': must be 'auto', 'direct' or 'ladder'"
        else if (opts%solver /= 'auto' .and. opts%solver /= 'hybrj' .and. &
                 opts%solver /= 'newton') then
            write (buf, '(a)') "opts%solver = '"//trim(opts%solver)// &
                "': must be 'auto', 'hybrj' or 'newton'"
        else
            return
        end if
        call fatal_error(error, trim(buf), stickslip_stat%input)
    end subroutine validate_options

    !> Periodic response of `model` by the weighted-residual method with options `opts`.
    !> Optionally start from friction-force coefficients `r_start` (nb x n_c, the layout of
    !> hbm_solution_t%rcoef for the same basis; a start from fewer harmonics is embedded).
    !> opts%rho = 0 selects the automatic weight (stickslip_rho); sol%rho is the one used.
    !> A non-converged solve is an outcome: sol%converged = .false. and sol%diagnosis says
    !> why. The checks of the answer go to sol%diagnostics (not_converged, rho_out_of_range,
    !> near_resonance, energy_balance, coulomb_dissipation, coulomb_law; README, "Where each
    !> method fails"). Errors: stat input (invalid model or options), stat numerical
    !> (singular dynamic stiffness: "undamped resonance at harmonic h ...", NaN in the
    !> residual).
    !> With `dyn` (the condensed dynamics of `model` on the basis of `opts`, as a
    !> continuation keeps them), Z_h is not factorized again (see new_hb_problem); `dyn_out`
    !> returns the dynamics the solve used (for a truncation estimate of the solution).
    subroutine solve_periodic(model, opts, sol, error, r_start, dyn, dyn_out)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Solver options.
        type(hbm_options_t), intent(in) :: opts
        !> The solution and its convergence report.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Optional start for the friction-force coefficients [N].
        real(dp), intent(in), optional :: r_start(:, :)
        !> The condensed dynamics of `model` on this basis, already built.
        type(dynamics_t), intent(in), optional :: dyn
        !> The condensed dynamics of the solve (set unless an error occurred).
        type(dynamics_t), intent(out), optional :: dyn_out
        type(hbm_options_t) :: o
        type(hb_problem_t) :: prob
        type(condensed_structure_t) :: s
        integer(int64) :: c0, c1, rate

        call system_clock(c0, rate)
        call validate_model(model, error)
        if (allocated(error)) return
        call validate_options(opts, error)
        if (allocated(error)) return
        s = dense_structure(model)
        ! the options in effect: rho = 0 asks for the automatic weight
        o = opts
        if (o%rho == 0.0_dp) o%rho = s%rho_auto
        call new_hb_problem(prob, model, o%harmonics, o%odd_only, o%samples, o%rho, error, &
                            dyn)
        if (allocated(error)) return
        call solve_condensed(s, prob, opts, o, sol, error, r_start, dyn_out, model)
        if (allocated(error)) return
        call system_clock(c1)
        sol%seconds = real(c1 - c0, dp)/real(rate, dp)
    end subroutine solve_periodic

    !> The data of a dense model the weighted-residual solve needs beside its dynamics.
    function dense_structure(model) result(s)
        !> A validated model.
        type(model_t), intent(in) :: model
        type(condensed_structure_t) :: s
        integer :: i
        s%omega = model%omega
        s%ncontact = model%ncontact()
        s%limit = model%mu*model%normal_load
        s%rho_auto = automatic_rho(model)
        allocate (s%force_rows(model%ndof, model%nforce()))
        do i = 1, model%nforce()
            s%force_rows(:, i) = force_direction(model, i)
        end do
        s%force_harmonic = model%force_harmonic
        s%force_amplitude = model%force_amplitude
        s%force_phase = model%force_phase
    end function dense_structure

    !> The weighted-residual solve on projected friction equations already built (`prob`,
    !> whose dynamics condense the structure `s`), shared by solve_periodic (dense) and
    !> solve_periodic_sparse (stickslip_hbm_sparse): start, hybrj stages and ladder,
    !> settling, recovery, energies, samples and checks. `opts` as given, `o` in effect (rho
    !> set). The displacement columns are those of the dynamics (all N, or its kept DOFs).
    !> With `dense_model` (the dense path), the contact velocities of the energy balance are
    !> W^T v and the viscous dissipation uses its C; without it, the contact velocities come
    !> from the dynamics (V0 + G R) and the energies from its Gram matrices (exact over all
    !> N DOFs, dynamics_t%damping_gram, forcing_gram). Destroys `prob`. Errors: as
    !> solve_periodic. sol%seconds is the caller's.
    subroutine solve_condensed(s, prob, opts, o, sol, error, r_start, dyn_out, dense_model)
        !> The structure's data (limits, forcing, automatic rho).
        type(condensed_structure_t), intent(in) :: s
        !> The projected friction equations (destroyed on return).
        type(hb_problem_t), intent(inout) :: prob
        !> Solver options as given.
        type(hbm_options_t), intent(in) :: opts
        !> Solver options in effect (rho > 0).
        type(hbm_options_t), intent(in) :: o
        !> The solution and its convergence report.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Optional start for the friction-force coefficients [N].
        real(dp), intent(in), optional :: r_start(:, :)
        !> The condensed dynamics of the solve (set unless an error occurred).
        type(dynamics_t), intent(out), optional :: dyn_out
        !> The dense model (dense path only).
        type(model_t), intent(in), optional :: dense_model
        real(dp), allocatable :: y(:), vzero(:, :)
        integer :: nb, nc, ncopy
        real(dp) :: target_norm

        nb = prob%basis%nb
        nc = prob%nc
        sol%harmonics = opts%harmonics
        sol%odd_only = opts%odd_only
        sol%samples = opts%samples
        sol%rho = o%rho
        sol%nb = nb
        sol%omega = s%omega
        sol%harmonic = prob%basis%harmonic_of([(ncopy, ncopy=1, nb)])

        allocate (y(prob%n), vzero(nb, nc))
        y = 0.0_dp
        if (present(r_start)) then
            if (size(r_start, 2) /= nc .or. size(r_start, 1) > nb) then
                call fatal_error(error, "solve_periodic: r_start must be nb x n_c "// &
                                 "(nb at most that of the requested basis)", stickslip_stat%input)
                call prob%destroy()
                return
            end if
            ncopy = size(r_start, 1)
            vzero = 0.0_dp
            vzero(1:ncopy, :) = r_start
            y = reshape(vzero, [prob%n])
        end if
        sol%fscale = condensed_convergence_scale(prob, s%rho_auto)
        target_norm = opts%tol*sol%fscale

        if (nc == 0) then
            sol%converged = .true.
            sol%fnorm = 0.0_dp
        else if (use_newton(opts, prob%n) .and. target_norm > 0.0_dp) then
            ! Newton only from warm starts: r_start, or the halving ladder H/2^k
            select case (opts%start)
            case ('ladder')
                call solve_halving_ladder(s, o, prob, y, target_norm, sol, error, &
                                          present(r_start))
            case ('direct')
                call solve_stage(prob, y, opts, target_norm, sol, error, present(r_start))
            case default
                if (present(r_start)) then
                    call solve_stage(prob, y, opts, target_norm, sol, error, .true.)
                    if (.not. allocated(error) .and. .not. sol%converged .and. &
                        opts%harmonics > ladder_first) then
                        y = reshape(vzero, [prob%n])
                        call solve_halving_ladder(s, o, prob, y, target_norm, sol, error, &
                                                  .true.)
                    end if
                else
                    call solve_halving_ladder(s, o, prob, y, target_norm, sol, error, .false.)
                end if
            end select
        else
            select case (opts%start)
            case ('ladder')
                call solve_ladder(s, o, prob, y, target_norm, sol, error)
            case default
                call solve_stage(prob, y, opts, target_norm, sol, error)
                if (.not. allocated(error) .and. .not. sol%converged .and. opts%start == 'auto' &
                    .and. opts%harmonics > ladder_first) then
                    y = 0.0_dp
                    if (present(r_start)) y = reshape(vzero, [prob%n])
                    call solve_ladder(s, o, prob, y, target_norm, sol, error)
                end if
            end select
            if (allocated(error)) then
                if (error%stat == stickslip_stat%numerical .and. rho_out_of_band(s, o%rho)) &
                    error%message = error%message//" (rho = "//rtoa(o%rho)// &
                    " is far from the contact mobility "//rtoa(o%rho/rho_ratio(s, o%rho))// &
                    " m/(N s): use &hbm rho = 0, the automatic choice)"
                call prob%destroy()
                return
            end if
        end if

        if (.not. sol%converged) then
            block
                character(len=400) :: buf
                write (buf, '(a,es11.3e3,a,es11.3e3,a,i0,a,i0,a,i0,a)') &
                    "not converged: residual ||F|| = ", sol%fnorm, " > tol * fscale = ", &
                    target_norm, " (hybrj info ", sol%info, ", ", sol%nfev, &
                    " evaluations, ", sol%hybrj_calls, " hybrj calls). Try &hbm start = "// &
                    "'ladder', rho = 0 (automatic) or a smaller rho, more samples, or a "// &
                    "start from a nearby solution"
                sol%diagnosis = trim(buf)
            end block
        else
            sol%diagnosis = ""
        end if

        call finish_solution(s, opts, prob, y, sol, dense_model)
        call check_solution(s, o, prob, sol)
        if (present(dyn_out)) dyn_out = prob%dyn
        call prob%destroy()
    end subroutine solve_condensed

    !> The residual scale of the convergence test ||F||_2 <= tol * fscale [m/s]:
    !>     fscale = min(||V0||_2, rho * Rs),  Rs = max(min(max_j mu_j N_j, Rstop), 1e-6 Rstop),
    !> V0 the contact velocity coefficients without friction forces, Rstop = ||V0||_2 / m
    !> the force that stops that motion (m the geometric mean of the resonance-free contact
    !> mobilities, stickslip_rho). F holds velocities where a sample sticks (Psi = v) and
    !> rho times force errors where it slips (Psi = rho (r -/+ mu N)): the smaller of the
    !> two scales judges both kinds of rows, so neither a huge rho mu N (a large mu, rho or
    !> normal load) nor a tiny one can let the zero start pass. Invariant under a change of
    !> units (M, C, K, forces scaled together) with the automatic rho; with a fixed rho far
    !> from the contact mobility the test is stricter (the solve may then not converge, it
    !> cannot return an unconverged answer as converged). 0 when V0 = 0 (only F = 0 passes:
    !> the zero start is then exact) or when there are no contacts.
    function convergence_scale(model, prob) result(fscale)
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Its projected friction equations.
        type(hb_problem_t), intent(in) :: prob
        real(dp) :: fscale
        fscale = 0.0_dp
        if (prob%nc == 0) return
        fscale = condensed_convergence_scale(prob, automatic_rho(model))
    end function convergence_scale

    !> convergence_scale with the automatic rho of the structure given (`rho_auto`).
    function condensed_convergence_scale(prob, rho_auto) result(fscale)
        !> The projected friction equations.
        type(hb_problem_t), intent(in) :: prob
        !> The automatic rho of the structure [m/(N s)].
        real(dp), intent(in) :: rho_auto
        real(dp) :: fscale
        real(dp) :: rzero(prob%basis%nb, prob%nc), vfree(prob%basis%nb, prob%nc)
        real(dp) :: vnorm, rstop, rs
        fscale = 0.0_dp
        if (prob%nc == 0) return
        rzero = 0.0_dp
        call prob%dyn%contact_velocity(prob%basis, rzero, vfree)
        vnorm = norm2(vfree)
        rstop = vnorm*rho_fraction/rho_auto
        rs = max(min(maxval(prob%limit), rstop), 1.0e-6_dp*rstop)
        fscale = min(vnorm, prob%rho*rs)
    end function condensed_convergence_scale

    !> The Newton path is taken for `n` unknowns (opts%solver; 'auto': n >=
    !> newton_min_unknowns).
    pure logical function use_newton(opts, n)
        type(hbm_options_t), intent(in) :: opts
        integer, intent(in) :: n
        select case (opts%solver)
        case ('newton')
            use_newton = .true.
        case ('hybrj')
            use_newton = .false.
        case default
            use_newton = n >= newton_min_unknowns
        end select
    end function use_newton

    !> One solve on a fixed basis. With `warm` (y is a warm start) and the Newton path
    !> selected (use_newton), semismooth Newton first; when it does not meet the target,
    !> hybrj from its best point. hybrj restarts from its last iterate while it stops short
    !> of the target without exhausting its evaluations.
    subroutine solve_stage(prob, y, opts, target_norm, sol, error, warm)
        type(hb_problem_t), intent(inout) :: prob
        real(dp), intent(inout) :: y(:)
        type(hbm_options_t), intent(in) :: opts
        real(dp), intent(in) :: target_norm
        type(hbm_solution_t), intent(inout) :: sol
        type(error_type), allocatable, intent(out) :: error
        logical, intent(in), optional :: warm
        type(hybrj_options_t) :: hopts
        type(hybrj_report_t) :: report
        integer :: call_no

        sol%converged = .false.
        if (present(warm)) then
            if (warm .and. use_newton(opts, prob%n) .and. target_norm > 0.0_dp) then
                block
                    type(newton_options_t) :: nopts
                    type(newton_report_t) :: nrep
                    real(dp), allocatable :: y0(:)
                    integer :: attempt
                    nopts%ftarget = target_norm
                    y0 = y
                    ! a Newton run that used single-precision LUs and failed is run again
                    ! from the same start in double precision before Powell's method takes
                    ! over (measured: 1 warm start of 2760 in the robustness study, at an
                    ! extreme rho, failed with single-precision LUs and not without)
                    do attempt = 1, 2
                        call solve_newton(prob, y, nopts, nrep, error)
                        sol%nfev = sol%nfev + nrep%nfev
                        sol%njev = sol%njev + nrep%njev
                        sol%newton_calls = sol%newton_calls + 1
                        if (allocated(error)) then
                            if (error%stat == stickslip_stat%callback) then
                                error%message = "the residual or its Jacobian became NaN "// &
                                                "during the solve"
                                error%stat = stickslip_stat%numerical
                            end if
                            return
                        end if
                        sol%fnorm = nrep%fnorm
                        if (nrep%outcome == newton_converged) then
                            sol%info = -1
                            sol%converged = .true.
                            return
                        end if
                        if (nrep%single_lus == 0) exit
                        y = y0
                        nopts%single_min_unknowns = 0
                    end do
                    sol%newton_fallbacks = sol%newton_fallbacks + 1
                end block
            end if
        end if

        hopts%xtol = opts%xtol
        hopts%maxfev = opts%maxfev
        hopts%mode = 1
        if (opts%stop_at_tol) hopts%ftarget = target_norm
        do call_no = 1, max_calls_per_stage
            ! the Newton path's Powell stages run hybrj's algorithm on LAPACK's blocked QR
            if (use_newton(opts, prob%n)) then
                call solve_powell(prob, y, hopts, report, error)
            else
                call solve_hybrj(prob, y, hopts, report, error)
            end if
            sol%nfev = sol%nfev + report%nfev
            sol%njev = sol%njev + report%njev
            sol%hybrj_calls = sol%hybrj_calls + 1
            if (allocated(error)) then
                if (error%stat == stickslip_stat%callback) then
                    error%message = "the residual or its Jacobian became NaN during the solve"
                    error%stat = stickslip_stat%numerical
                end if
                return
            end if
            sol%info = report%info
            sol%fnorm = report%fnorm
            if (report%target_met .or. report%fnorm <= target_norm) then
                sol%converged = .true.
                return
            end if
            if (report%info == 2) return
        end do
    end subroutine solve_stage

    !> Climb from `ladder_first` harmonics, doubling, each stage warm-started from the one
    !> before (the lower basis is a prefix of the higher one), up to the requested basis.
    subroutine solve_ladder(s, opts, prob, y, target_norm, sol, error)
        type(condensed_structure_t), intent(in) :: s
        type(hbm_options_t), intent(in) :: opts
        type(hb_problem_t), intent(inout) :: prob
        real(dp), intent(inout) :: y(:)
        real(dp), intent(in) :: target_norm
        type(hbm_solution_t), intent(inout) :: sol
        type(error_type), allocatable, intent(out) :: error
        type(hb_problem_t) :: low
        real(dp), allocatable :: ylow(:), rlow(:, :), rfull(:, :)
        integer :: h, nbl, nb, nc
        real(dp) :: low_target

        nb = prob%basis%nb
        nc = prob%nc
        allocate (rfull(nb, nc))
        rfull = reshape(y, [nb, nc])
        ! the lowest rung must hold every forcing harmonic
        h = max(ladder_first, maxval([0, s%force_harmonic]))
        do while (h < opts%harmonics)
            ! the lower basis is a subset of prob's: its dynamics without a factorization
            call new_condensed_problem(low, prob%dyn, prob%limit, h, opts%odd_only, &
                                       opts%samples, opts%rho, error, s%force_harmonic)
            if (allocated(error)) return
            nbl = low%basis%nb
            rlow = rfull(1:nbl, :)
            ylow = reshape(rlow, [nbl*nc])
            ! the stages only need to be good starts: a looser target
            low_target = max(target_norm, 1.0e-6_dp*sol%fscale)
            call solve_stage(low, ylow, opts, low_target, sol, error)
            call low%destroy()
            if (allocated(error)) return
            rfull(1:nbl, :) = reshape(ylow, [nbl, nc])
            h = 2*h
        end do
        y = reshape(rfull, [nb*nc])
        call solve_stage(prob, y, opts, target_norm, sol, error)
    end subroutine solve_ladder

    !> The ladder of the Newton path: levels H, H/2, H/4, ... down to `ladder_first` (or the
    !> highest forcing harmonic when larger)
    !> (integer halving: 3, 7, 15 for H = 15), solved from the lowest up, each stage
    !> warm-started from the one below; the lowest is cold (hybrj) unless `warm` (y holds
    !> a start).
    subroutine solve_halving_ladder(s, opts, prob, y, target_norm, sol, error, warm)
        type(condensed_structure_t), intent(in) :: s
        type(hbm_options_t), intent(in) :: opts
        type(hb_problem_t), intent(inout) :: prob
        real(dp), intent(inout) :: y(:)
        real(dp), intent(in) :: target_norm
        type(hbm_solution_t), intent(inout) :: sol
        type(error_type), allocatable, intent(out) :: error
        logical, intent(in) :: warm
        type(hb_problem_t) :: low
        real(dp), allocatable :: ylow(:), rfull(:, :)
        integer :: levels(32), nlev, i, nbl, nb, nc, hmin
        real(dp) :: low_target

        nb = prob%basis%nb
        nc = prob%nc
        allocate (rfull(nb, nc))
        rfull = reshape(y, [nb, nc])
        ! halving down to ladder_first, but never below a forcing harmonic
        hmin = max(ladder_first, maxval([0, s%force_harmonic]))
        nlev = 1
        levels(1) = opts%harmonics
        do while (levels(nlev) > hmin .and. nlev < size(levels))
            nlev = nlev + 1
            levels(nlev) = max(hmin, levels(nlev - 1)/2)
        end do
        low_target = max(target_norm, 1.0e-6_dp*sol%fscale)
        do i = nlev, 2, -1
            call new_condensed_problem(low, prob%dyn, prob%limit, levels(i), opts%odd_only, &
                                       level_samples(opts%samples, opts%harmonics, levels(i)), &
                                       opts%rho, error, s%force_harmonic)
            if (allocated(error)) return
            nbl = low%basis%nb
            ylow = reshape(rfull(1:nbl, :), [nbl*nc])
            call solve_stage(low, ylow, opts, low_target, sol, error, warm .or. i < nlev)
            call low%destroy()
            if (allocated(error)) return
            rfull(1:nbl, :) = reshape(ylow, [nbl, nc])
        end do
        y = reshape(rfull, [nb*nc])
        call solve_stage(prob, y, opts, target_norm, sol, error, warm .or. nlev > 1)
    end subroutine solve_halving_ladder

    !> Samples of a lower level of the halving ladder: the requested samples per harmonic
    !> kept (samples h / H, up to a power of two, at least 64), never more than `samples`.
    !> A level is only a warm start; its cost goes with its samples (the residual, the
    !> Jacobian and, for the cold hybrj stage, every evaluation).
    pure integer function level_samples(samples, harmonics, h) result(nt)
        integer, intent(in) :: samples, harmonics, h
        nt = 64
        do while (real(nt, dp)*real(harmonics, dp) < real(samples, dp)*real(h, dp))
            nt = 2*nt
        end do
        nt = max(min(nt, samples), 2*h + 1)
    end function level_samples

    !> Settle undetermined mean forces, recover every DOF, energies, stick statistics and
    !> samples.
    subroutine finish_solution(s, opts, prob, y, sol, model)
        type(condensed_structure_t), intent(in) :: s
        type(hbm_options_t), intent(in) :: opts
        type(hb_problem_t), intent(inout) :: prob
        real(dp), intent(inout) :: y(:)
        type(hbm_solution_t), intent(inout) :: sol
        type(model_t), intent(in), optional :: model
        real(dp), allocatable :: rs(:, :), vs(:, :), ss(:, :), fcoef(:, :), vc(:, :), work(:)
        complex(dp), allocatable :: cw(:)
        integer :: nb, nc, nt, n, j, i, k, p, q, i0
        real(dp) :: period, lo, hi, shift, coulomb_slip, max_force_ratio

        max_force_ratio = 0.0_dp
        nb = prob%basis%nb
        nc = prob%nc
        nt = prob%basis%nt
        n = size(prob%dyn%x0, 1)
        i0 = prob%basis%i0
        period = two_pi/s%omega
        allocate (rs(nt, nc), vs(nt, nc), ss(nt, nc), sol%offset_undetermined(nc))
        sol%offset_undetermined = .false.
        if (nc > 0) call prob%contact_samples(y, rs, vs, ss)

        ! A contact stuck over the whole period holds any mean force in an interval:
        ! choose the admissible value closest to zero (minimum norm), never an arbitrary one.
        if (prob%basis%has_zero) then
            do j = 1, nc
                if (all(ss(:, j) > 0.5_dp)) then
                    sol%offset_undetermined(j) = .true.
                    k = (j - 1)*nb + i0
                    lo = -prob%limit(j) - minval(rs(:, j) - y(k))
                    hi = prob%limit(j) - maxval(rs(:, j) - y(k))
                    shift = min(max(0.0_dp, lo), hi) - y(k)
                    y(k) = y(k) + shift
                    rs(:, j) = rs(:, j) + shift
                end if
            end do
        end if

        sol%rcoef = reshape(y, [nb, nc])
        allocate (sol%xcoef(nb, n), sol%vcoef(nb, n))
        call prob%dyn%displacement(prob%basis, sol%rcoef, sol%xcoef)
        do p = 1, n
            call prob%basis%derivative(sol%xcoef(:, p), s%omega, sol%vcoef(:, p))
        end do

        allocate (sol%stick_fraction(nc), sol%stick_phases(nc))
        do j = 1, nc
            sol%stick_fraction(j) = sum(ss(:, j))/real(nt, dp)
            sol%stick_phases(j) = count_phases(ss(:, j) > 0.5_dp, &
                                               max(1, nt/max(1, opts%harmonics)))
        end do

        ! energy balance over one period, exact for the truncated series (Parseval)
        allocate (fcoef(nb, n), vc(nb, nc))
        fcoef = 0.0_dp
        do i = 1, size(s%force_harmonic)
            if (s%force_harmonic(i) == 0) then
                fcoef(i0, :) = fcoef(i0, :) + s%force_amplitude(i)*cos(s%force_phase(i))* &
                               s%force_rows(:, i)
            else
                k = prob%basis%icos(findloc(prob%basis%harm, s%force_harmonic(i), 1))
                fcoef(k, :) = fcoef(k, :) + s%force_amplitude(i)*cos(s%force_phase(i))* &
                              s%force_rows(:, i)
                fcoef(k + 1, :) = fcoef(k + 1, :) - s%force_amplitude(i)*sin(s%force_phase(i))* &
                                  s%force_rows(:, i)
            end if
        end do
        if (present(model)) then
            do j = 1, nc
                vc(:, j) = matmul(sol%vcoef, contact_velocity_direction(model, j))
            end do
        else if (nc > 0) then
            call prob%dyn%contact_velocity(prob%basis, sol%rcoef, vc)
        end if
        sol%work_forcing = 0.0_dp
        if (present(model)) then
            do p = 1, n
                sol%work_forcing = sol%work_forcing + inner(fcoef(:, p), sol%vcoef(:, p))
            end do
        else
            sol%work_forcing = gram_energy(.true.)
        end if
        ! the gross work, integral |f . v| dt: the scale of the energy balance
        block
            real(dp) :: fs(nt), vt(nt), pw(nt)
            complex(dp) :: cwork(nt/2 + 1)
            pw = 0.0_dp
            do p = 1, n
                if (all(fcoef(:, p) == 0.0_dp)) cycle
                call prob%basis%synthesize(fcoef(:, p), fs, cwork)
                call prob%basis%synthesize(sol%vcoef(:, p), vt, cwork)
                pw = pw + fs*vt
            end do
            sol%work_gross = period*sum(abs(pw))/nt
        end block
        sol%diss_friction = 0.0_dp
        sol%diss_coulomb = 0.0_dp
        coulomb_slip = 0.0_dp
        do j = 1, nc
            sol%diss_friction = sol%diss_friction - inner(sol%rcoef(:, j), vc(:, j))
            sol%diss_coulomb = sol%diss_coulomb + prob%limit(j)*period*sum(abs(vs(:, j)))/nt
            ! what Coulomb's law dissipates: mu N |v| where the contact slips, |r v| (<= mu
            ! N |v|, ~0) where it sticks (a stuck contact's roundoff slip times a huge mu N
            ! is no dissipation)
            coulomb_slip = coulomb_slip + period*sum(merge(abs(rs(:, j)*vs(:, j)), &
                prob%limit(j)*abs(vs(:, j)), ss(:, j) > 0.5_dp))/nt
            if (prob%limit(j) > 0.0_dp) max_force_ratio = max(max_force_ratio, &
                                                              maxval(abs(rs(:, j)))/prob%limit(j))
        end do
        sol%diss_damping = 0.0_dp
        if (present(model)) then
            do q = 1, n
                do p = 1, n
                    sol%diss_damping = sol%diss_damping + &
                        model%damping(p, q)*inner(sol%vcoef(:, p), sol%vcoef(:, q))
                end do
            end do
        else
            sol%diss_damping = gram_energy(.false.)
        end if

        sol%coulomb_check = abs(coulomb_slip - sol%diss_friction)/ &
                            max(coulomb_slip, abs(sol%diss_friction) + abs(sol%diss_damping), &
                                1.0e-6_dp*sol%work_gross, tiny(1.0_dp))
        sol%max_force_ratio = max_force_ratio

        if (opts%want_samples) then
            allocate (sol%t(nt), sol%x(nt, n), sol%v(nt, n), work(nt), cw(nt/2 + 1))
            sol%t = [(period*real(k, dp)/real(nt, dp), k=0, nt - 1)]
            do p = 1, n
                call prob%basis%synthesize(sol%xcoef(:, p), sol%x(:, p), cw)
                call prob%basis%synthesize(sol%vcoef(:, p), sol%v(:, p), cw)
            end do
            sol%r = rs
            sol%stick = ss
        end if

    contains

        !> Energy per period from the Gram matrices of a sparse condensation, with
        !> u_h = [1; R_h] (R_h = r_cos - i r_sin of each contact): the forcing work
        !> (`forcing`; q_h = forcing_gram) sum_h (T/2) Re(i h omega q_h u_h), or the viscous
        !> dissipation (P_h = damping_gram) sum_h (T/2) (h omega)^2 u_h^H P_h u_h.
        real(dp) function gram_energy(forcing) result(e)
            logical, intent(in) :: forcing
            complex(dp) :: u(nc + 1)
            real(dp) :: homega
            integer :: ih, kk
            e = 0.0_dp
            do ih = 1, prob%basis%nharm
                kk = prob%basis%icos(ih)
                homega = prob%basis%harm(ih)*s%omega
                u(1) = (1.0_dp, 0.0_dp)
                u(2:) = cmplx(sol%rcoef(kk, :), -sol%rcoef(kk + 1, :), dp)
                if (forcing) then
                    e = e + 0.5_dp*period*homega* &
                        real((0.0_dp, 1.0_dp)*sum(prob%dyn%forcing_gram(:, ih)*u), dp)
                else
                    e = e + 0.5_dp*period*homega**2* &
                        real(dot_product(u, matmul(prob%dyn%damping_gram(:, :, ih), u)), dp)
                end if
            end do
        end function gram_energy

        !> integral over one period of the product of two functions given by coefficients
        pure real(dp) function inner(a, b)
            real(dp), intent(in) :: a(:), b(:)
            inner = 0.5_dp*period*dot_product(a, b)
            if (i0 > 0) inner = inner + 0.5_dp*period*a(i0)*b(i0)
        end function inner
    end subroutine finish_solution

    !> The checks of a solution as diagnostics items (README, "Where each method fails"):
    !> not_converged; rho_out_of_range (rho / contact mobility outside [rho_ratio_min,
    !> rho_ratio_max]: the friction equality loses its digits); near_resonance (Z_h nearly
    !> singular); and, once converged, energy_balance, coulomb_dissipation and coulomb_law.
    subroutine check_solution(s, opts, prob, sol)
        type(condensed_structure_t), intent(in) :: s
        type(hbm_options_t), intent(in) :: opts
        type(hb_problem_t), intent(in) :: prob
        type(hbm_solution_t), intent(inout) :: sol
        real(dp) :: e
        character(len=400) :: buf
        if (.not. sol%converged) &
            call sol%diagnostics%add(level_untrusted, "not_converged", sol%diagnosis)
        if (prob%nc > 0 .and. rho_out_of_band(s, opts%rho)) then
            write (buf, '(a,es10.2e3,a,es10.2e3,a,es9.1e3,a,es9.1e3,a)') "rho = ", opts%rho, &
                " is ", rho_ratio(s, opts%rho), " times the contact mobility (outside ", &
                rho_ratio_min, " .. ", rho_ratio_max, "): the friction equality cannot "// &
                "resolve the forces; use &hbm rho = 0 (automatic)"
            call sol%diagnostics%add(level_untrusted, "rho_out_of_range", trim(buf))
        end if
        if (prob%dyn%relative_conditioning < near_singular_threshold) then
            write (buf, '(a,i0,a,g0.6,a,es10.2e3,a,es9.1e3,a)') "near an undamped resonance at "// &
                "harmonic h = ", prob%dyn%worst_harmonic, " (h omega = ", &
                prob%dyn%worst_harmonic*s%omega, " rad/s): the dynamic stiffness is "// &
                "nearly singular (relative conditioning ", prob%dyn%relative_conditioning, &
                " < ", near_singular_threshold, "), the response hangs on the last digits "// &
                "of omega, M and K; add damping or move omega"
            call sol%diagnostics%add(level_untrusted, "near_resonance", trim(buf))
        end if
        if (.not. sol%converged .or. prob%nc == 0) return
        e = abs(sol%work_forcing - sol%diss_friction - sol%diss_damping)/ &
            max(abs(sol%work_forcing), 1.0e-6_dp*sol%work_gross, tiny(1.0_dp))
        call graded("energy_balance", e, energy_warning, energy_untrusted, &
                    "energy balance error (forcing work - friction - viscous dissipation, "// &
                    "relative to the work per period)")
        call graded("coulomb_dissipation", sol%coulomb_check, dissipation_warning, &
                    dissipation_untrusted, "friction dissipation differs from Coulomb's "// &
                    "(mu N |v| where the contacts slip), relative difference")
        call graded("coulomb_law", sol%max_force_ratio - 1.0_dp, force_excess_warning, &
                    force_excess_untrusted, "friction force exceeds mu N (max |r| / mu N "// &
                    "- 1, beyond the Gibbs overshoot of a truncated series)")

    contains

        subroutine graded(key, value, warn, untrusted, what)
            character(len=*), intent(in) :: key, what
            real(dp), intent(in) :: value, warn, untrusted
            character(len=300) :: text
            if (.not. (value <= untrusted)) then
                write (text, '(a,es10.2e3,a,es10.2e3)') "weighted residual: "//what//" ", value, &
                    " > ", untrusted
                call sol%diagnostics%add(level_untrusted, key, trim(text))
            else if (value > warn) then
                write (text, '(a,es10.2e3,a,es10.2e3)') "weighted residual: "//what//" ", value, &
                    " > ", warn
                call sol%diagnostics%add(level_warning, key, trim(text))
            end if
        end subroutine graded
    end subroutine check_solution

    !> rho / (the geometric mean of the resonance-free contact mobilities) (dimensionless).
    real(dp) function rho_ratio(s, rho)
        type(condensed_structure_t), intent(in) :: s
        real(dp), intent(in) :: rho
        rho_ratio = rho*rho_fraction/s%rho_auto
    end function rho_ratio

    !> rho is outside [rho_ratio_min, rho_ratio_max] times the contact mobility.
    logical function rho_out_of_band(s, rho)
        type(condensed_structure_t), intent(in) :: s
        real(dp), intent(in) :: rho
        real(dp) :: q
        rho_out_of_band = .false.
        if (s%ncontact == 0) return
        q = rho_ratio(s, rho)
        rho_out_of_band = .not. (q >= rho_ratio_min .and. q <= rho_ratio_max)
    end function rho_out_of_band

    !> A real as short text.
    function rtoa(x) result(text)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=24) :: buf
        write (buf, '(es12.3e3)') x
        text = trim(adjustl(buf))
    end function rtoa

    !> Number of stick phases in one period of the cyclic stick indicator `stick`, counted at
    !> the resolution of the basis: slip gaps and stick phases shorter than `minlen` samples
    !> (one period of the highest harmonic) are ripples of the truncated series around the
    !> friction limit, not phases: gaps are closed, then short phases are not counted.
    pure integer function count_phases(stick, minlen) result(phases)
        !> Stick indicator at the samples.
        logical, intent(in) :: stick(:)
        !> Shortest run, in samples, the basis can resolve.
        integer, intent(in) :: minlen
        logical :: s(size(stick))
        integer :: nt, k, first, len
        nt = size(stick)
        phases = 0
        if (all(stick)) phases = 1
        if (all(stick) .or. .not. any(stick)) return
        first = 1
        do k = 1, nt
            if (stick(k) .neqv. stick(modulo(k - 2, nt) + 1)) then
                first = k
                exit
            end if
        end do
        s = cshift(stick, first - 1)
        ! close short slip gaps
        k = 1
        do while (k <= nt)
            len = run_length(k)
            if (.not. s(k) .and. len < minlen) s(k:k + len - 1) = .true.
            k = k + len
        end do
        if (all(s)) then
            phases = 1
            return
        end if
        ! count the stick runs the basis resolves (a run may now wrap around the end)
        ! (one rotation to the first slip sample: linear in nt)
        if (s(1)) s = cshift(s, findloc(s, .false., 1) - 1)
        k = 1
        do while (k <= nt)
            len = run_length(k)
            if (s(k) .and. len >= minlen) phases = phases + 1
            k = k + len
        end do

    contains

        pure integer function run_length(k0)
            integer, intent(in) :: k0
            run_length = 1
            do while (k0 + run_length <= nt)
                if (s(k0 + run_length) .neqv. s(k0)) exit
                run_length = run_length + 1
            end do
        end function run_length
    end function count_phases
end module stickslip_hbm
