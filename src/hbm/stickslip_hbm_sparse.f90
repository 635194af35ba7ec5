!> The weighted-residual solve of a sparse model condensed exactly per harmonic
!> (&reduction method = 'none' for models from files): the sparse entry beside
!> solve_periodic. The condensation is stickslip_sparse_dynamics (one sparse complex LU of
!> Z_h per harmonic); the solve itself is solve_condensed, shared with the dense path. Only
!> the DOFs asked for (and the contact and forced DOFs) are recovered.
module stickslip_hbm_sparse
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_sparse_model, only: sparse_model_t, validate_sparse_model
    use stickslip_sparse_dynamics, only: new_sparse_dynamics, sparse_contact_mobility
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t, new_condensed_problem
    use stickslip_hbm, only: condensed_structure_t, solve_condensed, validate_options
    use stickslip_rho, only: rho_from_channels, dominant_harmonic
    use stickslip_contact_set, only: new_contact_set
    use stickslip_progress, only: progress_t
    implicit none
    private
    public :: solve_periodic_sparse, kept_dofs

contains

    !> Periodic response of the sparse model `smodel` by the weighted-residual method
    !> (as solve_periodic: options, outcome, diagnostics), with the structure condensed
    !> exactly per harmonic by sparse LU factorizations. The solution's displacement and
    !> velocity columns are the DOFs kept_dofs(smodel, dofs): `dofs` in their order, then
    !> the contact and forced DOFs not among them (sol%dofs). The energy balance is exact
    !> over all N DOFs (dynamics_t%damping_gram, forcing_gram). With `dyn_out`, the
    !> condensed dynamics used. Errors: as solve_periodic (stat input: invalid model,
    !> options or `dofs` outside 1..N; stat numerical: singular K with a constant term,
    !> undamped resonance, an UMFPACK failure such as out of memory).
    subroutine solve_periodic_sparse(smodel, opts, dofs, sol, error, r_start, dyn, dyn_out, &
                                     progress)
        !> The structure with sparse matrices, its contacts and forcing.
        type(sparse_model_t), intent(in) :: smodel
        !> Solver options.
        type(hbm_options_t), intent(in) :: opts
        !> The DOFs to recover (1..N; may be empty).
        integer, intent(in) :: dofs(:)
        !> The solution (columns: sol%dofs).
        type(hbm_solution_t), intent(out) :: sol
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Optional start for the friction-force coefficients [N].
        real(dp), intent(in), optional :: r_start(:, :)
        !> The condensed dynamics of `smodel` on this basis (or a larger one), with the rows of
        !> kept_dofs(smodel, dofs), already built (as a continuation keeps them): nothing is
        !> factorized for the condensation.
        type(dynamics_t), intent(in), optional :: dyn
        !> The condensed dynamics of the solve.
        type(dynamics_t), intent(out), optional :: dyn_out
        !> Progress of the condensation, a line per harmonic (the host's unit).
        type(progress_t), intent(in), optional :: progress
        type(condensed_structure_t) :: s
        type(hbm_options_t) :: o
        type(basis_t) :: basis
        type(dynamics_t) :: built
        type(hb_problem_t) :: prob
        real(dp), allocatable :: mob(:)
        integer, allocatable :: kept(:)
        integer(int64) :: c0, c1, c2, c3, rate
        integer :: i

        call system_clock(c0, rate)
        call validate_sparse_model(smodel, error)
        if (allocated(error)) return
        call validate_options(opts, error)
        if (allocated(error)) return
        kept = kept_dofs(smodel, dofs, error)
        if (allocated(error)) return
        associate (m => smodel%model)
            s%omega = m%omega
            s%ncontact = m%ncontact()
            call new_contact_set(s%contacts, m)
            call sparse_contact_mobility(smodel, mob, error)
            if (allocated(error)) return
            s%rho_auto = rho_from_channels(mob, s%contacts, m%omega, &
                                           dominant_harmonic(m)*m%omega)
            allocate (s%force_rows(size(kept), m%nforce()))
            do i = 1, m%nforce()
                s%force_rows(:, i) = force_rows_of(i)
            end do
            s%force_harmonic = m%force_harmonic
            s%force_amplitude = m%force_amplitude
            s%force_phase = m%force_phase
        end associate
        o = opts
        if (o%rho == 0.0_dp) o%rho = s%rho_auto

        call system_clock(c2)
        if (present(dyn)) then
            if (.not. allocated(dyn%kept)) then
                call fatal_error(error, "solve_periodic_sparse: dyn is not a sparse "// &
                                 "condensation", stickslip_stat%input)
                return
            end if
            if (size(dyn%kept) /= size(kept) .or. .not. (dyn%omega == s%omega)) then
                call fatal_error(error, "solve_periodic_sparse: dyn was not built for "// &
                                 "this model (kept DOFs or omega differ)", stickslip_stat%input)
                return
            end if
            if (any(dyn%kept /= kept)) then
                call fatal_error(error, "solve_periodic_sparse: dyn was not built for "// &
                                 "these DOFs", stickslip_stat%input)
                return
            end if
            call system_clock(c3)
            call new_condensed_problem(prob, dyn, s%contacts, o%harmonics, o%odd_only, &
                                       o%samples, o%rho, error, s%force_harmonic)
        else
            call new_basis(basis, o%harmonics, o%odd_only, o%samples, error)
            if (allocated(error)) return
            call new_sparse_dynamics(built, smodel, basis, kept, error, progress=progress)
            call system_clock(c3)
            call basis%destroy()
            if (allocated(error)) return
            call new_condensed_problem(prob, built, s%contacts, o%harmonics, o%odd_only, &
                                       o%samples, o%rho, error, s%force_harmonic)
        end if
        if (allocated(error)) return
        call solve_condensed(s, prob, opts, o, sol, error, r_start, dyn_out)
        if (allocated(error)) return
        sol%dofs = kept
        sol%condensation_seconds = real(c3 - c2, dp)/real(rate, dp)
        call system_clock(c1)
        sol%seconds = real(c1 - c0, dp)/real(rate, dp)

    contains

        !> Load shape of forcing term i on the kept DOFs.
        function force_rows_of(i) result(f)
            integer, intent(in) :: i
            real(dp) :: f(size(kept))
            if (allocated(smodel%model%force_shape)) then
                f = smodel%model%force_shape(kept, i)
            else
                f = merge(1.0_dp, 0.0_dp, kept == smodel%model%force_dof(i))
            end if
        end function force_rows_of
    end subroutine solve_periodic_sparse

    !> The DOFs a sparse solve recovers: `dofs` in their order, then the contact DOFs
    !> (contact_dof, contact_dof2 > 0, or the DOFs where a column of contact_direction is
    !> nonzero) and the forced DOFs (force_dof; none for a force_shape) not given yet, each
    !> once.
    !> Errors (stat input): a DOF of `dofs` outside 1..N.
    function kept_dofs(smodel, dofs, error) result(kept)
        !> The sparse model.
        type(sparse_model_t), intent(in) :: smodel
        !> The DOFs asked for.
        integer, intent(in) :: dofs(:)
        !> Set on a DOF out of range.
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: kept(:)
        integer :: i
        integer, allocatable :: extra(:)
        if (any(dofs < 1 .or. dofs > smodel%model%ndof)) then
            call fatal_error(error, "solve_periodic_sparse: dofs: a DOF outside 1.."// &
                             itoa(smodel%model%ndof), stickslip_stat%input)
            allocate (kept(0))
            return
        end if
        kept = [integer ::]
        do i = 1, size(dofs)
            if (.not. any(kept == dofs(i))) kept = [kept, dofs(i)]
        end do
        extra = [integer ::]
        if (allocated(smodel%model%contact_dof)) extra = [extra, smodel%model%contact_dof]
        if (allocated(smodel%model%contact_dof2)) extra = [extra, &
            pack(smodel%model%contact_dof2, smodel%model%contact_dof2 > 0)]
        if (allocated(smodel%model%contact_direction)) extra = [extra, &
            pack([(i, i=1, smodel%model%ndof)], any(smodel%model%contact_direction /= 0.0_dp, &
                                                    dim=2))]
        if (allocated(smodel%model%force_dof)) extra = [extra, smodel%model%force_dof]
        ! the DOFs of the normal and second tangential directions of the contact laws
        if (allocated(smodel%model%normal_direction)) extra = [extra, &
            pack([(i, i=1, smodel%model%ndof)], any(smodel%model%normal_direction /= 0.0_dp, &
                                                    dim=2))]
        if (allocated(smodel%model%tangent2_direction)) extra = [extra, &
            pack([(i, i=1, smodel%model%ndof)], any(smodel%model%tangent2_direction /= 0.0_dp, &
                                                    dim=2))]
        do i = 1, size(extra)
            if (.not. any(kept == extra(i))) kept = [kept, extra(i)]
        end do
    end function kept_dofs
end module stickslip_hbm_sparse
