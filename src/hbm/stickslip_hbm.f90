!> The weighted-residual (harmonic balance) solve of the periodic response: the entry point
!> a structural code calls with a model built in memory.
!>
!> Flow: validate -> condense the linear dynamics on the contacts -> solve the projected
!> friction equations for the friction-force coefficients with hybrj (exact generalized
!> Jacobian; a ladder of warm starts from fewer harmonics when a cold start stalls; the
!> fallbacks of stickslip_hbm_fallback when that fails too; convergence judged by
!> convergence_scale) -> settle an undetermined mean force -> recover
!> every DOF -> energy balance and samples -> the checks as diagnostics (check_solution).
!> The start strategies and ladders live in stickslip_hbm_strategy, the work after the solve
!> (recovery, energies, checks) in stickslip_hbm_finish, the structure's data in
!> stickslip_condensed_structure; their public names used elsewhere are re-exported here.
module stickslip_hbm
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, real_text
    use stickslip_model, only: model_t, validate_model, force_direction
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem
    use stickslip_dynamics, only: dynamics_t
    use stickslip_rho, only: automatic_rho, rho_fraction
    use stickslip_contact_set, only: new_contact_set
    use stickslip_condensed_structure, only: condensed_structure_t, rho_ratio, &
        rho_out_of_band, rho_ratio_min, rho_ratio_max
    use stickslip_hbm_strategy, only: newton_min_unknowns, solve_primary, &
        condensed_convergence_scale
    use stickslip_hbm_fallback, only: solve_fallbacks, rigid_contact_opens
    use stickslip_hbm_finish, only: finish_solution, check_solution, energy_warning, &
        energy_untrusted, dissipation_warning, dissipation_untrusted, force_excess_warning, &
        force_excess_untrusted
    implicit none
    private
    public :: solve_periodic, validate_options, convergence_scale, solution_from_forces
    public :: condensed_structure_t, solve_condensed, solve_setup, solution_from_problem
    public :: hbm_max_harmonics, hbm_max_samples, hbm_max_unknowns, newton_min_unknowns
    public :: energy_warning, energy_untrusted, dissipation_warning, dissipation_untrusted
    public :: force_excess_warning, force_excess_untrusted, rho_ratio_min, rho_ratio_max

    !> Largest harmonics H accepted by validate_options (the basis has 2 H + 1 terms).
    integer, parameter :: hbm_max_harmonics = 4096
    !> Largest quadrature samples per period accepted by validate_options (2**20).
    integer, parameter :: hbm_max_samples = 2**20
    !> Largest number of unknowns (2 H + 1) x contacts of a solve: its dense Jacobian holds
    !> the square of it (8193**2 doubles = 0.5 GB). Checked by the case reader, which knows
    !> the model.
    integer, parameter :: hbm_max_unknowns = 2*hbm_max_harmonics + 1

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
    !> near_resonance, energy_balance, coulomb_dissipation, coulomb_law; doc/where-methods-fail.md, "Where each
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
        call solve_setup(model, opts, s, o, error)
        if (allocated(error)) return
        call new_hb_problem(prob, model, o%harmonics, o%odd_only, o%samples, o%rho, error, &
                            dyn)
        if (allocated(error)) return
        call solve_condensed(s, prob, opts, o, sol, error, r_start, dyn_out, model)
        if (allocated(error)) return
        call system_clock(c1)
        sol%seconds = real(c1 - c0, dp)/real(rate, dp)
    end subroutine solve_periodic

    !> What a dense solve of `model` with `opts` starts from: both validated, the condensed
    !> structure `s` and the options in effect `o` (rho = 0 asks for the automatic weight,
    !> s%rho_auto; with the model's modes `lambda`, `shapes`, from their sums: see
    !> contact_mobility). Errors: those of validate_model and validate_options (stat input).
    subroutine solve_setup(model, opts, s, o, error, lambda, shapes)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Solver options as given.
        type(hbm_options_t), intent(in) :: opts
        !> The condensed structure.
        type(condensed_structure_t), intent(out) :: s
        !> The options in effect.
        type(hbm_options_t), intent(out) :: o
        !> Set on invalid input.
        type(error_type), allocatable, intent(out) :: error
        !> Optional: the model's modes, K Phi = M Phi Lambda, Phi^H M Phi = I.
        real(dp), intent(in), optional :: lambda(:)
        complex(dp), intent(in), optional :: shapes(:, :)
        call validate_model(model, error)
        if (allocated(error)) return
        call validate_options(opts, error)
        if (allocated(error)) return
        s = dense_structure(model, lambda, shapes)
        o = opts
        if (o%rho == 0.0_dp) o%rho = s%rho_auto
    end subroutine solve_setup

    !> The weighted-residual solution of `model` whose friction-force coefficients `rcoef`
    !> (nb x channels, on the basis of `opts` with its weight rho > 0) were found elsewhere
    !> (e.g. by a continuation that solved a larger system): no solve, the recovery of every
    !> DOF, the energies, the stick statistics and the samples as solve_periodic gives them
    !> (finish_solution), with sol%fnorm the residual of the projected equations at
    !> `rcoef` and sol%converged = .true.; the checks of check_solution are left to the
    !> caller (they judge a forced response). Errors: as new_hb_problem.
    subroutine solution_from_forces(model, opts, rcoef, sol, error)
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Basis options, rho > 0.
        type(hbm_options_t), intent(in) :: opts
        !> Friction-force (channel) coefficients [N].
        real(dp), intent(in) :: rcoef(:, :)
        !> The solution.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(hb_problem_t) :: prob
        call new_hb_problem(prob, model, opts%harmonics, opts%odd_only, opts%samples, opts%rho, &
                            error)
        if (allocated(error)) return
        call solution_from_problem(dense_structure(model), opts, prob, rcoef, sol, error, model)
    end subroutine solution_from_forces

    !> solution_from_forces on projected friction equations already built (`prob`, whose
    !> dynamics condense the structure `s`; with `dense_model` the dense path's energies, see
    !> solve_condensed). Destroys `prob`. Errors: stat input when rcoef is not nb x channels.
    subroutine solution_from_problem(s, opts, prob, rcoef, sol, error, dense_model)
        !> The structure's data (omega, forcing).
        type(condensed_structure_t), intent(in) :: s
        !> Basis options, rho > 0.
        type(hbm_options_t), intent(in) :: opts
        !> The projected friction equations (destroyed on return).
        type(hb_problem_t), intent(inout) :: prob
        !> Friction-force (channel) coefficients [N].
        real(dp), intent(in) :: rcoef(:, :)
        !> The solution.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The dense model (dense path only).
        type(model_t), intent(in), optional :: dense_model
        real(dp), allocatable :: y(:), f(:)
        integer :: k, stat
        if (size(rcoef, 1) /= prob%basis%nb .or. size(rcoef, 2) /= prob%nc) then
            call fatal_error(error, "solution_from_forces: rcoef must be nb x channels", &
                             stickslip_stat%input)
            call prob%destroy()
            return
        end if
        sol%harmonics = opts%harmonics
        sol%odd_only = opts%odd_only
        sol%samples = opts%samples
        sol%rho = opts%rho
        sol%nb = prob%basis%nb
        sol%omega = s%omega
        sol%harmonic = prob%basis%harmonic_of([(k, k=1, prob%basis%nb)])
        y = reshape(rcoef, [prob%n])
        allocate (f(prob%n))
        stat = 0
        call prob%residual(y, f, stat)
        sol%fnorm = norm2(f)
        sol%converged = .true.
        sol%diagnosis = ""
        call finish_solution(s, opts, prob, y, sol, dense_model)
        call prob%destroy()
    end subroutine solution_from_problem

    !> The data of a dense model the weighted-residual solve needs beside its dynamics
    !> (with its modes `lambda`, `shapes`, the automatic rho from their sums).
    function dense_structure(model, lambda, shapes) result(s)
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Optional: its modes (automatic_rho).
        real(dp), intent(in), optional :: lambda(:)
        complex(dp), intent(in), optional :: shapes(:, :)
        type(condensed_structure_t) :: s
        integer :: i
        s%omega = model%omega
        s%ncontact = model%ncontact()
        call new_contact_set(s%contacts, model)
        s%rho_auto = automatic_rho(model, lambda, shapes)
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
        real(dp) :: target_norm, rho_used
        type(hbm_options_t) :: oe
        type(error_type), allocatable :: first_error

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

        rho_used = o%rho
        if (nc == 0) then
            sol%converged = .true.
            sol%fnorm = 0.0_dp
        else
            call solve_primary(s, opts, o, prob, y, vzero, target_norm, sol, error, &
                               present(r_start))
            ! start = 'direct' asks for the first attempt alone. A NaN met by the first
            ! attempt (an iterate far out) is an error only when no fallback finds the answer
            ! from the start
            if (allocated(error) .and. opts%start /= 'direct') then
                if (error%stat == stickslip_stat%numerical) then
                    call move_alloc(error, first_error)
                    y = reshape(vzero, [prob%n])
                    sol%converged = .false.
                    sol%fnorm = huge(1.0_dp)
                end if
            end if
            if (.not. allocated(error) .and. .not. sol%converged .and. target_norm > 0.0_dp &
                .and. opts%start /= 'direct') &
                call solve_fallbacks(s, o, prob, y, target_norm, sol, error, rho_used)
            if (allocated(first_error) .and. .not. allocated(error) .and. &
                .not. sol%converged) call move_alloc(first_error, error)
            if (allocated(error)) then
                if (error%stat == stickslip_stat%numerical .and. rho_out_of_band(s, o%rho)) &
                    error%message = error%message//" (rho = "// &
                                    real_text(o%rho, '(es12.3e3)')// &
                                    " is far from the contact mobility "// &
                                    real_text(o%rho/rho_ratio(s, o%rho), '(es12.3e3)')// &
                    " m/(N s): use &hbm rho = 0, the automatic choice)"
                call prob%destroy()
                return
            end if
        end if

        ! the options of the answer: its weight may be another one ('rho_kept')
        oe = o
        oe%rho = rho_used
        sol%rho = rho_used
        if (.not. sol%converged) then
            if (rigid_contact_opens(prob, y)) then
                sol%diagnosis = "not converged: a rigid unilateral contact opens and closes "// &
                                "(an impact: its normal velocity jumps when it lands, which "// &
                                "a truncated Fourier series cannot carry). Give the contact "// &
                                "its measured normal_stiffness in &friction, or use &run "// &
                                "method = 'euler' or 'reference', which handle impacts"
            else
                block
                    character(len=500) :: buf
                    character(len=:), allocatable :: tried
                    tried = "the ladder, Newton, the load homotopy and rho x 1/16 .. 16 tried"
                    if (opts%start == 'direct') tried = "start = 'direct': no fallback "// &
                                                        "tried; start = 'auto' tries them"
                    write (buf, '(a,es11.3e3,a,es11.3e3,a,i0,a,i0,a,i0,a,i0,a)') &
                        "not converged: residual ||F|| = ", sol%fnorm, " > tol * fscale = ", &
                        target_norm, " (hybrj info ", sol%info, ", ", sol%nfev, &
                        " evaluations, ", sol%hybrj_calls, " hybrj and ", sol%newton_calls, &
                        " Newton calls; "//tried//"). Try other harmonics (harmonics_tol), "// &
                        "more samples, a start from a nearby solution (a sweep), or check "// &
                        "the case against &run method = 'euler'"
                    sol%diagnosis = trim(buf)
                end block
            end if
        else
            sol%diagnosis = ""
        end if

        call finish_solution(s, opts, prob, y, sol, dense_model)
        call check_solution(s, oe, prob, sol)
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
        type(hb_problem_t), intent(inout) :: prob
        real(dp) :: fscale
        fscale = 0.0_dp
        if (prob%nc == 0) return
        fscale = condensed_convergence_scale(prob, automatic_rho(model))
    end function convergence_scale

end module stickslip_hbm
