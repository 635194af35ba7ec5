!> The weighted residual on one sector of a tuned bladed disk in its travelling wave
!> (stickslip_cyclic, stickslip_cyclic_dynamics): the friction equations of the sector's
!> contacts (those against the next sector included) on the sector's cyclic condensation,
!> solved by the same stages, fallbacks and checks as solve_periodic. The answer is sector
!> 0's; sector s is its copy delayed by EO s / N of the period.
module stickslip_hbm_cyclic
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, assemble_disk, phased_copies
    use stickslip_cyclic_dynamics, only: new_cyclic_dynamics
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t, new_condensed_problem
    use stickslip_hbm, only: condensed_structure_t, solve_condensed, solve_setup, &
        solution_from_forces, solution_from_problem
    implicit none
    private
    public :: solve_periodic_cyclic, disk_solution, cyclic_solution_from_forces

contains

    !> The periodic solution of the sector `model` of the disk `cyc` under its engine-order
    !> forcing, with the options `opts` (rho = 0: the automatic weight of the sector's
    !> contacts). sol holds sector 0: its coefficients, samples, contact forces and the
    !> energies per period of one sector. Errors: as solve_periodic, and those of
    !> validate_cyclic and new_cyclic_dynamics.
    subroutine solve_periodic_cyclic(model, cyc, opts, sol, error, r_start)
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
        type(condensed_structure_t) :: s
        type(hbm_options_t) :: o
        type(basis_t) :: basis
        type(dynamics_t) :: dyn
        type(hb_problem_t) :: prob
        integer(int64) :: c0, c1, rate
        call system_clock(c0, rate)
        call solve_setup(model, opts, s, o, error)
        if (allocated(error)) return
        call validate_cyclic(model, cyc, error)
        if (allocated(error)) return
        call new_basis(basis, o%harmonics, o%odd_only, o%samples, error)
        if (allocated(error)) return
        call new_cyclic_dynamics(dyn, model, cyc, basis, error)
        call basis%destroy()
        if (allocated(error)) return
        call new_condensed_problem(prob, dyn, s%contacts, o%harmonics, o%odd_only, o%samples, &
                                   o%rho, error, s%force_harmonic)
        if (allocated(error)) return
        call solve_condensed(s, prob, opts, o, sol, error, r_start)
        if (allocated(error)) return
        call system_clock(c1)
        sol%seconds = real(c1 - c0, dp)/real(rate, dp)
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
    end subroutine disk_solution
end module stickslip_hbm_cyclic
