!> &reduction method = 'none' on sparse models: the exact sparse condensation
!> (stickslip_sparse_dynamics, solve_periodic_sparse) against the dense path on small chains
!> (same V0, G, friction forces, energies to roundoff), a 3000-DOF model from files through the
!> command line, the error of the methods that need dense matrices, and Craig-Bampton's
!> solution converging to the 'none' one as modes are added.
module test_sparse_none
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_sparse, only: sparse_matrix_t, sparse_to_dense
    use stickslip_model, only: model_t
    use stickslip_sparse_model, only: sparse_model_t
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t, new_dynamics
    use stickslip_sparse_dynamics, only: new_sparse_dynamics
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hbm_sparse, only: solve_periodic_sparse
    use test_reduction, only: chain_matrices
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_sparse_none_tests

contains

    subroutine run_sparse_none_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_dynamics_equal(t)
        call test_solution_equal(t)
    end subroutine run_sparse_none_tests

    !> A 60-DOF damped chain with two contacts (one relative), forcing on harmonics 0, 1, 3.
    subroutine small_chain(sm, dense)
        type(sparse_model_t), intent(out) :: sm
        type(model_t), intent(out) :: dense
        type(error_type), allocatable :: error
        integer, parameter :: n = 60
        call chain_matrices(n, sm%stiffness, sm%mass, sm%damping)
        sm%model%ndof = n
        sm%model%omega = 3.0_dp
        sm%model%force_dof = [60, 60, 45]
        sm%model%force_harmonic = [1, 0, 3]
        sm%model%force_amplitude = [40.0_dp, 5.0_dp, 10.0_dp]
        sm%model%force_phase = [0.0_dp, 0.0_dp, 0.4_dp]
        sm%model%contact_dof = [50, 30]
        sm%model%contact_dof2 = [0, 29]
        sm%model%mu = [0.3_dp, 0.2_dp]
        sm%model%normal_load = [10.0_dp, 5.0_dp]
        dense = sm%model
        call sparse_to_dense(sm%mass, dense%mass, error)
        call sparse_to_dense(sm%stiffness, dense%stiffness, error)
        call sparse_to_dense(sm%damping, dense%damping, error)
    end subroutine small_chain

    subroutine test_dynamics_equal(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_model_t) :: sm
        type(model_t) :: dm
        type(basis_t) :: basis
        type(dynamics_t) :: ds, dd
        type(error_type), allocatable :: error
        integer, allocatable :: kept(:)
        call small_chain(sm, dm)
        call new_basis(basis, 5, .false., 64, error)
        call new_dynamics(dd, dm, basis, error)
        call check(t, .not. allocated(error), "sparse none: dense dynamics", msg(error))
        kept = [7, 50, 30, 29, 60, 45]
        call new_sparse_dynamics(ds, sm, basis, kept, error)
        call check(t, .not. allocated(error), "sparse none: sparse dynamics", msg(error))
        call basis%destroy()
        if (allocated(error)) return
        call check(t, maxval(abs(ds%v0 - dd%v0)) <= 1.0e-10_dp*maxval(abs(dd%v0)), &
                   "sparse none: V0 equal")
        call check(t, maxval(abs(ds%g - dd%g)) <= 1.0e-10_dp*maxval(abs(dd%g)), &
                   "sparse none: G equal")
        call check(t, maxval(abs(ds%x0 - dd%x0(kept, :))) <= 1.0e-10_dp*maxval(abs(dd%x0)), &
                   "sparse none: X0 rows equal")
        call check(t, maxval(abs(ds%y - dd%y(kept, :, :))) <= 1.0e-10_dp*maxval(abs(dd%y)), &
                   "sparse none: Y rows equal")
        call check(t, maxval(abs(ds%x0_static - dd%x0_static(kept))) <= &
                   1.0e-10_dp*maxval(abs(dd%x0_static)), "sparse none: static rows equal")
        call check(t, maxval(abs(ds%y_static - dd%y_static(kept, :))) <= &
                   1.0e-10_dp*maxval(abs(dd%y_static)), "sparse none: static flexibility equal")
        ! the conditioning estimates: 2-norm (inverse iteration) vs LAPACK's 1-norm
        call check(t, ds%relative_conditioning > 0.1_dp*dd%relative_conditioning .and. &
                   ds%relative_conditioning < 10.0_dp*dd%relative_conditioning .and. &
                   ds%worst_harmonic == dd%worst_harmonic, &
                   "sparse none: relative conditioning within a decade of the dense one", &
                   rt(ds%relative_conditioning)//" vs "//rt(dd%relative_conditioning))
    end subroutine test_dynamics_equal

    subroutine test_solution_equal(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_model_t) :: sm
        type(model_t) :: dm
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: ss, sd
        type(error_type), allocatable :: error
        real(dp) :: e
        call small_chain(sm, dm)
        opts%harmonics = 7
        opts%samples = 256
        call solve_periodic(dm, opts, sd, error)
        call check(t, .not. allocated(error) .and. sd%converged, "sparse none: dense solve", &
                   msg(error))
        if (allocated(error)) return
        call solve_periodic_sparse(sm, opts, [10, 60], ss, error)
        call check(t, .not. allocated(error) .and. ss%converged, "sparse none: sparse solve", &
                   msg(error))
        if (allocated(error)) return
        call check(t, all(ss%dofs == [10, 60, 50, 30, 29, 45]), "sparse none: kept DOFs")
        call check_close(t, ss%rho, sd%rho, "sparse none: same automatic rho", rtol=1.0e-10_dp)
        call check(t, maxval(abs(ss%rcoef - sd%rcoef)) <= 1.0e-8_dp*maxval(abs(sd%rcoef)), &
                   "sparse none: same friction forces", rt(maxval(abs(ss%rcoef - sd%rcoef))))
        call check(t, maxval(abs(ss%xcoef - sd%xcoef(:, ss%dofs))) <= &
                   1.0e-8_dp*maxval(abs(sd%xcoef)), "sparse none: same displacements")
        call check_close(t, ss%work_forcing, sd%work_forcing, "sparse none: same forcing work", &
                         rtol=1.0e-8_dp)
        call check_close(t, ss%diss_damping, sd%diss_damping, &
                         "sparse none: same viscous dissipation (exact Gram formula)", &
                         rtol=1.0e-8_dp)
        call check_close(t, ss%diss_friction, sd%diss_friction, &
                         "sparse none: same friction dissipation", rtol=1.0e-8_dp)
        e = abs(ss%work_forcing - ss%diss_friction - ss%diss_damping)/abs(ss%work_forcing)
        call check(t, e < 1.0e-8_dp .and. ss%diss_damping > 0.0_dp, &
                   "sparse none: energy balance holds", rt(e))
        call check(t, ss%diagnostics%worst() == sd%diagnostics%worst(), &
                   "sparse none: same diagnostics")
        call check(t, size(ss%x, 2) == 6 .and. size(ss%x, 1) == 256, "sparse none: samples "// &
                   "of the kept DOFs only")
    end subroutine test_solution_equal

    function msg(error) result(s)
        type(error_type), allocatable, intent(in) :: error
        character(len=:), allocatable :: s
        s = ""
        if (allocated(error)) s = error%message
    end function msg

    function rt(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: buf
        write (buf, '(es10.3)') x
        s = trim(buf)
    end function rt
end module test_sparse_none
