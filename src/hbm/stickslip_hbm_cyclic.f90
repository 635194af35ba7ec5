!> The weighted residual on one sector of a tuned bladed disk in its travelling wave
!> (stickslip_cyclic, stickslip_cyclic_dynamics): the friction equations of the sector's
!> contacts (those against the next sector included) on the sector's cyclic condensation,
!> solved by the same stages, fallbacks and checks as solve_periodic. The answer is sector
!> 0's; sector s is its copy delayed by EO s / N of the period.
module stickslip_hbm_cyclic
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, assemble_disk, phased_copies, &
        structure_key
    use stickslip_cyclic_dynamics, only: new_cyclic_dynamics
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t, new_condensed_problem
    use stickslip_hbm, only: condensed_structure_t, solve_condensed, solve_setup, &
        solution_from_forces, solution_from_problem, validate_options
    implicit none
    private
    public :: solve_periodic_cyclic, disk_solution, cyclic_solution_from_forces

contains

    !> The periodic solution of the sector `model` of the disk `cyc` under its engine-order
    !> forcing, with the options `opts` (rho = 0: the automatic weight of the sector's
    !> contacts). sol holds sector 0: its coefficients, samples, contact forces and the
    !> energies per period of one sector. With `dyn` (the sector's cyclic condensation at
    !> model%omega on this basis or a larger one, e.g. a sweep's at its point) nothing is
    !> condensed again. With `structure` set by an earlier call for this sector at this
    !> omega (e.g. a sweep point's own solve, for its truncation estimate's coarse one), the
    !> sector is neither validated nor its automatic rho computed again; unset (omega 0),
    !> it is set here. Errors: as solve_periodic, and those of validate_cyclic and
    !> new_cyclic_dynamics (stat input when `dyn` was built for another omega or size).
    subroutine solve_periodic_cyclic(model, cyc, opts, sol, error, r_start, dyn, structure)
        !> The sector.
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> Solver options.
        type(hbm_options_t), intent(in) :: opts
        !> The solution of sector 0.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Optional start for the friction-force coefficients [N].
        real(dp), intent(in), optional :: r_start(:, :)
        !> The sector's condensation at model%omega, already built (not rebuilt).
        type(dynamics_t), intent(in), optional :: dyn
        !> What the solve needs of the sector beside its dynamics (reused or set).
        type(condensed_structure_t), intent(inout), optional :: structure
        type(condensed_structure_t) :: s
        type(hbm_options_t) :: o
        type(basis_t) :: basis
        type(dynamics_t) :: built
        type(hb_problem_t) :: prob
        integer(int64) :: c0, c1, rate
        logical :: reuse
        call system_clock(c0, rate)
        reuse = reusable()
        if (reuse) then
            call validate_options(opts, error)
            if (allocated(error)) return
            s = structure
            o = opts
            if (o%rho == 0.0_dp) o%rho = s%rho_auto
        else if (free_modes()) then
            ! the sector's prepared free modes give its contact mobility (automatic rho)
            call solve_setup(model, opts, s, o, error, cyc%free_lambda, cyc%free_shapes)
        else
            call solve_setup(model, opts, s, o, error)
        end if
        if (.not. reuse) then
            if (allocated(error)) return
            call validate_cyclic(model, cyc, error)
            if (allocated(error)) return
            if (present(structure)) structure = s
        end if
        if (present(dyn)) then
            if (dyn%ndof /= model%ndof .or. .not. (dyn%omega == model%omega)) then
                call fatal_error(error, "solve_periodic_cyclic: dyn was not built for this "// &
                                 "sector (sizes or omega differ)", stickslip_stat%input)
                return
            end if
            call new_condensed_problem(prob, dyn, s%contacts, o%harmonics, o%odd_only, &
                                       o%samples, o%rho, error, s%force_harmonic)
        else
            call new_basis(basis, o%harmonics, o%odd_only, o%samples, error)
            if (allocated(error)) return
            call new_cyclic_dynamics(built, model, cyc, basis, error)
            call basis%destroy()
            if (allocated(error)) return
            call new_condensed_problem(prob, built, s%contacts, o%harmonics, o%odd_only, &
                                       o%samples, o%rho, error, s%force_harmonic)
        end if
        if (allocated(error)) return
        call solve_condensed(s, prob, opts, o, sol, error, r_start)
        if (allocated(error)) return
        call system_clock(c1)
        sol%seconds = real(c1 - c0, dp)/real(rate, dp)

    contains

        !> cyc holds the free modes of this sector (its fingerprint, once its matrices
        !> have the sizes it reads; validate_model checks the rest).
        logical function free_modes()
            integer :: n
            free_modes = .false.
            if (.not. allocated(cyc%free_lambda)) return
            n = model%ndof
            if (.not. (allocated(model%mass) .and. allocated(model%stiffness))) return
            if (any(shape(model%mass) /= [n, n]) .or. any(shape(model%stiffness) /= [n, n])) &
                return
            if (allocated(model%damping)) then
                if (any(shape(model%damping) /= [n, n])) return
            end if
            free_modes = cyc%modes_key == structure_key(model, cyc%sectors)
        end function free_modes

        !> `structure` was set for this sector at this omega.
        logical function reusable()
            reusable = .false.
            if (.not. present(structure)) return
            reusable = allocated(structure%force_harmonic) .and. &
                       structure%omega == model%omega .and. structure%omega > 0.0_dp
        end function reusable
    end subroutine solve_periodic_cyclic

    !> The sector's solution (sector 0) whose friction-force coefficients `rcoef` (nb x
    !> channels, on the basis of `opts`, rho > 0) were found elsewhere, e.g. by the
    !> continuation of a nonlinear mode: no solve, as solution_from_forces gives a whole
    !> structure's, on the sector's cyclic condensation (energies per sector from its Gram
    !> matrices; with `mass_damping` xi the damping C - xi M, see new_cyclic_dynamics).
    !> Errors: those of validate_cyclic, new_cyclic_dynamics and solution_from_problem.
    subroutine cyclic_solution_from_forces(model, cyc, opts, rcoef, sol, error, mass_damping)
        !> The sector.
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> Basis options, rho > 0.
        type(hbm_options_t), intent(in) :: opts
        !> Friction-force (channel) coefficients [N].
        real(dp), intent(in) :: rcoef(:, :)
        !> The solution of sector 0.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Mass-proportional damping removed, xi [1/s] (default 0).
        real(dp), intent(in), optional :: mass_damping
        type(condensed_structure_t) :: s
        type(hbm_options_t) :: o
        type(basis_t) :: basis
        type(dynamics_t) :: dyn
        type(hb_problem_t) :: prob
        call solve_setup(model, opts, s, o, error)
        if (allocated(error)) return
        call new_basis(basis, o%harmonics, o%odd_only, o%samples, error)
        if (allocated(error)) return
        call new_cyclic_dynamics(dyn, model, cyc, basis, error, mass_damping=mass_damping)
        call basis%destroy()
        if (allocated(error)) return
        call new_condensed_problem(prob, dyn, s%contacts, o%harmonics, o%odd_only, o%samples, &
                                   o%rho, error, s%force_harmonic)
        if (allocated(error)) return
        call solution_from_problem(s, o, prob, rcoef, sol, error)
    end subroutine cyclic_solution_from_forces

    !> The whole disk's weighted-residual solution of a sector's travelling wave `sol`
    !> (solved with `opts` and sol%rho): the disk assembled (assemble_disk) and its solution
    !> from the friction forces of every sector, each sector's the phased copy of sector 0's
    !> (harmonic h of sector s times exp(-i h 2 pi EO s / N)); no solve (solution_from_forces:
    !> samples, energies, recovery as solve_periodic gives them). For what needs the disk
    !> itself, e.g. its Floquet multipliers, which cover every perturbation and not only
    !> those of the wave's symmetry. Errors: those of assemble_disk and solution_from_forces.
    subroutine disk_solution(sector, cyc, opts, sol, disk, dsol, error)
        !> The sector.
        type(model_t), intent(in) :: sector
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> The options `sol` was solved with.
        type(hbm_options_t), intent(in) :: opts
        !> The sector's solution (converged).
        type(hbm_solution_t), intent(in) :: sol
        !> The assembled disk.
        type(model_t), intent(out) :: disk
        !> Its solution.
        type(hbm_solution_t), intent(out) :: dsol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(hbm_options_t) :: o
        call assemble_disk(sector, cyc, disk, error)
        if (allocated(error)) return
        o = opts
        o%rho = sol%rho
        o%want_samples = .true.
        call solution_from_forces(disk, o, phased_copies(sol%rcoef, sol%harmonic, cyc), dsol, &
                                  error)
        if (allocated(error)) return
        ! the sector's solve resolves the copies as well as itself (N sectors' forcing work)
        dsol%fscale = sol%fscale
        dsol%velocity_resolution = sol%velocity_resolution
        dsol%work_resolution = cyc%sectors*sol%work_resolution
        dsol%at_rest = sol%at_rest
    end subroutine disk_solution
end module stickslip_hbm_cyclic
