!> &reduction method = 'none' on sparse models: the exact sparse condensation
!> (stickslip_sparse_dynamics, solve_periodic_sparse) against the dense path on small chains
!> (same V0, G, friction forces, energies to roundoff), a 3000-DOF model from files through the
!> command line, the error of the methods that need dense matrices, and Craig-Bampton's
!> solution converging to the 'none' one as modes are added.
module test_sparse_none
    use stickslip_kinds, only: dp
    use stickslip_lapack, only: dgetrf, dgetrs
    use stickslip_error, only: error_type, itoa
    use stickslip_sparse, only: sparse_matrix_t, sparse_to_dense
    use stickslip_model, only: model_t
    use stickslip_sparse_model, only: sparse_model_t, validate_sparse_model
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t, new_dynamics
    use stickslip_sparse_dynamics, only: new_sparse_dynamics
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hbm_sparse, only: solve_periodic_sparse
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep
    use stickslip_reference, only: reference_options_t
    use test_reduction, only: chain_matrices
    use stickslip_reduction, only: reduction_options_t, reduction_report_t, reduced_model_t, &
        craig_bampton
    use stickslip_case, only: case_t, read_case
    use stickslip_matrix_market, only: write_matrix_market, write_matrix_market_array, &
        read_matrix_market
    use stickslip_cli, only: run_cli, string_t
    use fixtures, only: enter_project_root, scratch, scratch_dir, write_lines, msg, rt
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_sparse_none_tests

contains

    subroutine run_sparse_none_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_dynamics_equal(t)
        call test_solution_equal(t)
        call test_singular(t)
        call test_validation(t)
        call test_variants(t)
        call test_sweep(t)
        call test_cli(t)
        call test_craig_bampton_converges(t)
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
        call new_dynamics(dd, dm, basis, error, with_omega_derivative=.true.)
        call check(t, .not. allocated(error), "sparse none: dense dynamics", msg(error))
        kept = [7, 50, 30, 29, 60, 45]
        call new_sparse_dynamics(ds, sm, basis, kept, error, with_omega_derivative=.true.)
        call check(t, .not. allocated(error), "sparse none: sparse dynamics", msg(error))
        call basis%destroy()
        if (allocated(error)) return
        call check(t, maxval(abs(ds%v0 - dd%v0)) <= 1.0e-10_dp*maxval(abs(dd%v0)), &
                   "sparse none: V0 equal")
        call check(t, maxval(abs(ds%g - dd%g)) <= 1.0e-10_dp*maxval(abs(dd%g)), &
                   "sparse none: G equal")
        call check(t, maxval(abs(ds%dv0 - dd%dv0)) <= 1.0e-10_dp*maxval(abs(dd%dv0)), &
                   "sparse none: dV0/domega equal")
        call check(t, maxval(abs(ds%dg - dd%dg)) <= 1.0e-10_dp*maxval(abs(dd%dg)), &
                   "sparse none: dG/domega equal")
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

    !> A free chain (K singular) with a static load: the static problem is refused with the
    !> dense path's message; an undamped resonance is found with its harmonic.
    subroutine test_singular(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_model_t) :: sm
        type(model_t) :: dm
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: ss
        type(error_type), allocatable :: error
        type(basis_t) :: basis
        type(dynamics_t) :: dd
        real(dp) :: w1
        integer :: i
        call small_chain(sm, dm)
        ! remove the ground spring at DOF 1 (chain_matrices: K(1,1) = 2k): a free chain
        do i = sm%stiffness%row_start(1), sm%stiffness%row_start(2) - 1
            if (sm%stiffness%col(i) == 1) sm%stiffness%val(i) = 1.0e4_dp
        end do
        opts%harmonics = 3
        opts%samples = 64
        call solve_periodic_sparse(sm, opts, [integer ::], ss, error)
        call check(t, allocated(error), "sparse none: singular K with a static load refused")
        if (allocated(error)) call check(t, index(error%message, "stiffness matrix K is "// &
                                                  "singular") > 0, &
                                         "sparse none: the message names K", error%message)
        ! undamped, omega at the first natural frequency (from the dense eigen-solve below)
        call small_chain(sm, dm)
        sm%damping = sparse_matrix_t()
        dm%damping = 0.0_dp
        w1 = first_frequency(dm)
        sm%model%omega = w1
        dm%omega = w1
        sm%model%force_harmonic = [1, 0, 1]
        dm%force_harmonic = sm%model%force_harmonic
        call new_basis(basis, 3, .false., 64, error)
        call new_dynamics(dd, dm, basis, error)
        call check(t, allocated(error), "sparse none: dense path finds the resonance")
        call basis%destroy()
        ! refused as singular, or (w1 holds roundoff of the eigen-solver: with another BLAS
        ! kernel, e.g. under valgrind, the distance may land just above the singular
        ! threshold) reported as a near resonance; either way named
        call solve_periodic_sparse(sm, opts, [integer ::], ss, error)
        if (allocated(error)) then
            call check(t, index(error%message, "undamped resonance at harmonic h = 1") > 0, &
                       "sparse none: resonance named with its harmonic", error%message)
        else
            call check(t, ss%diagnostics%has("near_resonance"), &
                       "sparse none: resonance refused or reported near")
        end if
        ! near it (relative 1e-8): a near_resonance finding, as the dense path
        sm%model%omega = w1*(1.0_dp + 1.0e-8_dp)
        call solve_periodic_sparse(sm, opts, [integer ::], ss, error)
        call check(t, .not. allocated(error), "sparse none: near a resonance solves", &
                   msg(error))
        if (.not. allocated(error)) call check(t, ss%diagnostics%has("near_resonance"), &
                                               "sparse none: near_resonance reported")
        ! and far from it, none
        sm%model%omega = 0.6_dp*w1
        call solve_periodic_sparse(sm, opts, [integer ::], ss, error)
        if (.not. allocated(error)) call check(t, .not. ss%diagnostics%has("near_resonance"), &
                                               "sparse none: no near_resonance away from it")
    end subroutine test_singular

    !> Odd harmonics only (no constant, no static LU) and a model without contacts (the
    !> linear response): equal to the dense path.
    subroutine test_variants(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_model_t) :: sm
        type(model_t) :: dm
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: ss, sd
        type(error_type), allocatable :: error
        call small_chain(sm, dm)
        sm%model%force_dof = [60, 45]
        sm%model%force_harmonic = [1, 3]
        sm%model%force_amplitude = [40.0_dp, 10.0_dp]
        sm%model%force_phase = [0.0_dp, 0.4_dp]
        dm%force_dof = sm%model%force_dof
        dm%force_harmonic = sm%model%force_harmonic
        dm%force_amplitude = sm%model%force_amplitude
        dm%force_phase = sm%model%force_phase
        opts%harmonics = 7
        opts%odd_only = .true.
        opts%samples = 128
        call solve_periodic(dm, opts, sd, error)
        call solve_periodic_sparse(sm, opts, [integer ::], ss, error)
        call check(t, .not. allocated(error) .and. ss%converged .and. sd%converged, &
                   "sparse none: odd harmonics solve", msg(error))
        if (allocated(error)) return
        call check(t, maxval(abs(ss%rcoef - sd%rcoef)) <= 1.0e-8_dp*maxval(abs(sd%rcoef)), &
                   "sparse none: odd harmonics: same friction forces")
        call check_close(t, ss%diss_damping, sd%diss_damping, &
                         "sparse none: odd harmonics: same viscous dissipation", rtol=1.0e-8_dp)
        ! no contacts
        sm%model%contact_dof = [integer ::]
        sm%model%contact_dof2 = [integer ::]
        sm%model%mu = [real(dp) ::]
        sm%model%normal_load = [real(dp) ::]
        dm%contact_dof = sm%model%contact_dof
        dm%contact_dof2 = sm%model%contact_dof2
        dm%mu = sm%model%mu
        dm%normal_load = sm%model%normal_load
        call solve_periodic(dm, opts, sd, error)
        call solve_periodic_sparse(sm, opts, [60], ss, error)
        call check(t, .not. allocated(error) .and. ss%converged, &
                   "sparse none: no contacts solves", msg(error))
        if (allocated(error)) return
        call check(t, maxval(abs(ss%xcoef(:, 1) - sd%xcoef(:, 60))) <= &
                   1.0e-10_dp*maxval(abs(sd%xcoef(:, 60))), "sparse none: no contacts: "// &
                   "the linear response")
        call check_close(t, ss%work_forcing, sd%work_forcing, &
                         "sparse none: no contacts: forcing work", rtol=1.0e-8_dp)
        call check_close(t, ss%diss_damping, ss%work_forcing, &
                         "sparse none: no contacts: all of it damped", rtol=1.0e-8_dp)
    end subroutine test_variants

    !> A sweep in omega (and one in the forcing amplitude) on the sparse condensation: the
    !> same points as the dense sweep (parameters, amplitudes, dissipation); stability refused.
    subroutine test_sweep(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_model_t) :: sm
        type(model_t) :: dm
        type(hbm_options_t) :: opts
        type(sweep_options_t) :: so
        type(sweep_result_t) :: rs, rd
        type(reference_options_t) :: ref
        type(error_type), allocatable :: error
        integer :: k, n
        real(dp) :: dmax
        character(len=16) :: parameters(2) = [character(len=16) :: 'omega', 'force_amplitude']
        integer :: ip
        call small_chain(sm, dm)
        opts%harmonics = 5
        opts%samples = 64
        do ip = 1, 2
            so = sweep_options_t()
            so%parameter = parameters(ip)
            if (ip == 1) then
                so%start = 2.8_dp
                so%stop = 3.3_dp
            else
                so%start = 40.0_dp
                so%stop = 60.0_dp
            end if
            so%stability = .false.
            so%truncation = .false.
            so%max_points = 12
            call run_sweep(dm, opts, ref, so, rd, error)
            call check(t, .not. allocated(error), "sparse none sweep: dense "// &
                       trim(so%parameter), msg(error))
            if (allocated(error)) return
            call run_sweep(sm%model, opts, ref, so, rs, error, sparse=sm, dofs=[50])
            call check(t, .not. allocated(error), "sparse none sweep: sparse "// &
                       trim(so%parameter), msg(error))
            if (allocated(error)) return
            n = min(rs%npoints, rd%npoints)
            call check(t, rs%npoints == rd%npoints .and. n > 3, "sparse none sweep: same "// &
                       "number of points ("//trim(so%parameter)//")", itoa(rs%npoints)//" vs "// &
                       itoa(rd%npoints))
            dmax = 0.0_dp
            do k = 1, n
                dmax = max(dmax, abs(rs%points(k)%parameter - rd%points(k)%parameter)/ &
                           abs(rd%points(k)%parameter), &
                           abs(rs%points(k)%amplitude(1) - rd%points(k)%amplitude(50))/ &
                           rd%points(k)%amplitude(50), &
                           abs(rs%points(k)%dissipation - rd%points(k)%dissipation)/ &
                           rd%points(k)%dissipation)
            end do
            call check(t, dmax < 1.0e-7_dp, "sparse none sweep: same points ("// &
                       trim(so%parameter)//")", rt(dmax))
        end do
        so%stability = .true.
        call run_sweep(sm%model, opts, ref, so, rs, error, sparse=sm)
        call check(t, allocated(error), "sparse none sweep: stability refused")
    end subroutine test_sweep

    !> validate_sparse_model and the DOF list name what is wrong.
    subroutine test_validation(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_model_t) :: sm, bad
        type(model_t) :: dm
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: ss
        type(error_type), allocatable :: error
        call small_chain(sm, dm)
        call validate_sparse_model(sm, error)
        call check(t, .not. allocated(error), "sparse none: the chain is valid", msg(error))
        bad = sm
        bad%stiffness%nrows = 59
        call validate_sparse_model(bad, error)
        call check(t, allocated(error), "sparse none: wrong K size refused")
        if (allocated(error)) call check(t, index(error%message, "smodel%stiffness: 59 x 60") &
                                         > 0, "sparse none: K size named", error%message)
        bad = sm
        bad%mass%val(1) = -1.0_dp
        call validate_sparse_model(bad, error)
        call check(t, allocated(error), "sparse none: negative mass refused")
        if (allocated(error)) call check(t, index(error%message, "smodel%mass(1,1)") > 0, &
                                         "sparse none: the mass entry named", error%message)
        bad = sm
        bad%model%mu(2) = -0.1_dp
        call validate_sparse_model(bad, error)
        call check(t, allocated(error), "sparse none: negative mu refused (model_t checks)")
        opts%harmonics = 3
        opts%samples = 64
        call solve_periodic_sparse(sm, opts, [61], ss, error)
        call check(t, allocated(error), "sparse none: a DOF outside 1..N refused")
    end subroutine test_validation

    !> The first natural frequency of a dense model (LAPACK dsygv through the dense path's
    !> own tools is not exported: a bisection on the sign of det is overkill; use the
    !> Rayleigh quotient of inverse iteration on K with M).
    function first_frequency(m) result(w)
        type(model_t), intent(in) :: m
        real(dp) :: w
        real(dp) :: x(m%ndof), y(m%ndof), a(m%ndof, m%ndof)
        integer :: ipiv(m%ndof), info, it, n
        n = m%ndof
        a = m%stiffness
        call dgetrf(n, n, a, n, ipiv, info)
        x = 1.0_dp
        do it = 1, 500
            y = matmul(m%mass, x)
            call dgetrs('N', n, 1, a, n, ipiv, y, n, info)
            x = y/norm2(y)
        end do
        w = sqrt(dot_product(x, matmul(m%stiffness, x))/dot_product(x, matmul(m%mass, x)))
    end function first_frequency

    !> A 3000-DOF model from Matrix Market files with &reduction method = 'none' through the
    !> command line: hbm.csv with the default columns (contact and forced DOFs), summary.nml
    !> with reduction_method = 'none'; the same answer as Craig-Bampton with many modes;
    !> method 'euler' and &hbm stability refused naming &reduction method.
    subroutine test_cli(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(error_type), allocatable :: error
        type(case_t) :: cs
        type(string_t), allocatable :: args(:)
        integer :: uo, ue, code, u, stat
        character(len=2000) :: line
        logical :: keys(3)
        call enter_project_root()
        if (len(scratch_dir()) == 0) return
        call chain_matrices(3000, k, m, c)
        call write_matrix_market(scratch//"/none_m.mtx", m, .true., error)
        call write_matrix_market(scratch//"/none_k.mtx", k, .true., error)
        call check(t, .not. allocated(error), "sparse none cli: files written", msg(error))
        if (allocated(error)) return
        call write_lines(scratch//"/none.nml", [character(len=100) :: &
            "&system mass_file = 'none_m.mtx', stiffness_file = 'none_k.mtx',", &
            "  rayleigh_alpha = 0.01 /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction method = 'none' /", &
            "&hbm harmonics = 5 /", &
            "&output directory = '"//scratch//"/out_none' /"])
        allocate (args(1))
        args(1)%s = scratch//"/none.nml"
        open (newunit=uo, status='scratch', action='readwrite')
        open (newunit=ue, status='scratch', action='readwrite')
        code = run_cli(args, uo, ue)
        close (uo)
        close (ue)
        call check(t, code == 0, "sparse none cli: exits 0", itoa(code))
        open (newunit=u, file=scratch//"/out_none/hbm.csv", status='old', action='read', &
              iostat=stat)
        line = ""
        if (stat == 0) read (u, '(a)', iostat=stat) line
        close (u, iostat=stat)
        call check(t, trim(line) == "t,x2990,x3000,v2990,v3000,r1", &
                   "sparse none cli: hbm.csv columns of the contact and forced DOFs", trim(line))
        keys = .false.
        open (newunit=u, file=scratch//"/out_none/summary.nml", status='old', action='read', &
              iostat=stat)
        do while (stat == 0)
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (index(line, "reduction_method = 'none'") > 0) keys(1) = .true.
            if (index(line, "full_dof = 3000") > 0) keys(2) = .true.
            if (index(line, "condensation_seconds = ") > 0) keys(3) = .true.
        end do
        close (u, iostat=stat)
        call check(t, all(keys), "sparse none cli: summary.nml reports 'none', N and the time")
        ! the summary reads back as the same sparse case
        call read_case(scratch//"/out_none/summary.nml", cs, error)
        call check(t, .not. allocated(error), "sparse none cli: summary.nml reads back", &
                   msg(error))
        if (.not. allocated(error)) call check(t, allocated(cs%sparse_model), &
                                               "sparse none cli: read back sparse")
        ! the same case with the contact as a direction_file column and the force as a
        ! force_file column, every DOF's coefficients in full_field.mtx: hbm.csv as above,
        ! the full field's rows 2990 and 3000 those of coefficients.csv
        block
            real(dp) :: wcol(3000, 1), fcol(3000, 1)
            type(sparse_matrix_t) :: field
            real(dp), allocatable :: dense_field(:, :)
            character(len=2000) :: a, b
            integer :: ua, ub, sa, sb, rows, same_rows
            wcol = 0.0_dp
            wcol(2990, 1) = 1.0_dp
            fcol = 0.0_dp
            fcol(3000, 1) = 1.0_dp
            call write_matrix_market_array(scratch//"/none_w.mtx", wcol, .false., error)
            if (.not. allocated(error)) &
                call write_matrix_market_array(scratch//"/none_f.mtx", fcol, .false., error)
            call check(t, .not. allocated(error), "sparse none files: W, F written", msg(error))
            call write_lines(scratch//"/none_files.nml", [character(len=100) :: &
                "&system mass_file = 'none_m.mtx', stiffness_file = 'none_k.mtx',", &
                "  rayleigh_alpha = 0.01 /", &
                "&forcing omega = 0.03, force_file = 'none_f.mtx', force_amplitude = 1.0 /", &
                "&friction direction_file = 'none_w.mtx', mu = 0.3, normal_load = 1.0 /", &
                "&reduction method = 'none' /", &
                "&hbm harmonics = 5 /", &
                "&output directory = '"//scratch//"/out_none_files',", &
                "  dofs = 2990, 3000, full_field = T /"])
            args(1)%s = scratch//"/none_files.nml"
            open (newunit=uo, status='scratch', action='readwrite')
            open (newunit=ue, status='scratch', action='readwrite')
            code = run_cli(args, uo, ue)
            close (uo)
            close (ue)
            call check(t, code == 0, "sparse none files: exits 0", itoa(code))
            rows = 0
            same_rows = 0
            open (newunit=ua, file=scratch//"/out_none/hbm.csv", status='old', action='read', &
                  iostat=sa)
            open (newunit=ub, file=scratch//"/out_none_files/hbm.csv", status='old', &
                  action='read', iostat=sb)
            do while (sa == 0 .and. sb == 0)
                read (ua, '(a)', iostat=sa) a
                read (ub, '(a)', iostat=sb) b
                if (sa /= 0 .or. sb /= 0) exit
                rows = rows + 1
                if (a == b) same_rows = same_rows + 1
            end do
            close (ua, iostat=sa)
            close (ub, iostat=sb)
            call check(t, rows > 1 .and. same_rows == rows, "sparse none files: hbm.csv "// &
                       "equals the DOF-list case's", itoa(same_rows)//" of "//itoa(rows))
            call read_matrix_market(scratch//"/out_none_files/full_field.mtx", field, error)
            if (.not. allocated(error)) call sparse_to_dense(field, dense_field, error)
            call check(t, .not. allocated(error), "sparse none files: full_field.mtx reads", &
                       msg(error))
            if (.not. allocated(error)) then
                call check(t, size(dense_field, 1) == 3000 .and. &
                           maxval(abs(dense_field(2990, :))) > 0.0_dp .and. &
                           maxval(abs(dense_field(1500, :))) > 0.0_dp, &
                           "sparse none files: full field of 3000 DOFs, interior ones moving")
            end if
        end block
        ! a sweep in omega (stability off): frc.csv with the selected DOFs' amplitudes
        call write_lines(scratch//"/none_sweep.nml", [character(len=100) :: &
            "&system mass_file = 'none_m.mtx', stiffness_file = 'none_k.mtx',", &
            "  rayleigh_alpha = 0.01 /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction method = 'none' /", &
            "&hbm harmonics = 3, samples = 64 /", &
            "&output directory = '"//scratch//"/out_none_sweep', dofs = 1500, 2990 /", &
            "&sweep start = 0.03, stop = 0.032, max_points = 6 /", &
            "&run method = 'sweep' /"])
        args(1)%s = scratch//"/none_sweep.nml"
        open (newunit=uo, status='scratch', action='readwrite')
        open (newunit=ue, status='scratch', action='readwrite')
        code = run_cli(args, uo, ue)
        close (uo)
        close (ue)
        ! max_points = 6 stops the curve short (fast): exit 2 with the points computed
        call check(t, code == 2, "sparse none cli: the sweep runs its 6 points (exit 2: "// &
                   "stopped at max_points)", itoa(code))
        open (newunit=u, file=scratch//"/out_none_sweep/frc.csv", status='old', &
              action='read', iostat=stat)
        line = ""
        if (stat == 0) read (u, '(a)', iostat=stat) line
        close (u, iostat=stat)
        call check(t, index(line, "amp_1500,amp_2990") > 0, "sparse none cli: frc.csv "// &
                   "holds the selected DOFs (an interior one too)", trim(line))
        ! stability asked for explicitly in a sweep of the sparse model: refused
        call write_lines(scratch//"/none_sweep_stab.nml", [character(len=100) :: &
            "&system mass_file = 'none_m.mtx', stiffness_file = 'none_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction method = 'none' /", &
            "&sweep start = 0.03, stop = 0.032, stability = .true. /"])
        call read_case(scratch//"/none_sweep_stab.nml", cs, error)
        call check(t, allocated(error), "sparse none: sweep with stability = .true. refused")
        if (allocated(error)) call check(t, index(error%message, "&sweep stability") > 0, &
                                         "sparse none: the error names &sweep stability", &
                                         error%message)
        ! methods that need dense matrices
        call write_lines(scratch//"/none_euler.nml", [character(len=100) :: &
            "&system mass_file = 'none_m.mtx', stiffness_file = 'none_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction method = 'none' /", &
            "&run method = 'euler' /"])
        call read_case(scratch//"/none_euler.nml", cs, error)
        call check(t, allocated(error), "sparse none: euler refused")
        if (allocated(error)) call check(t, index(error%message, "&run method = 'euler'") > 0 &
            .and. index(error%message, "&reduction method = 'none'") > 0 .and. &
            index(error%message, "'craig-bampton'") > 0, &
            "sparse none: the euler error names &run method, &reduction method and the fix", &
            error%message)
        call write_lines(scratch//"/none_stab.nml", [character(len=100) :: &
            "&system mass_file = 'none_m.mtx', stiffness_file = 'none_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction method = 'none' /", &
            "&hbm stability = .true. /"])
        call read_case(scratch//"/none_stab.nml", cs, error)
        call check(t, allocated(error), "sparse none: stability refused")
        if (allocated(error)) call check(t, index(error%message, "stability") > 0 .and. &
            index(error%message, "&reduction method") > 0, &
            "sparse none: the stability error names the check and &reduction method", &
            error%message)
    end subroutine test_cli

    !> The reduction-error yardstick: Craig-Bampton solutions of a 400-DOF damped chain
    !> approach the exact 'none' solution as fixed-interface modes are added.
    subroutine test_craig_bampton_converges(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_model_t) :: sm
        type(model_t) :: small
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sx, sr
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        integer, parameter :: n = 400, dc = 300, df = 400
        integer, parameter :: counts(4) = [1, 3, 8, 20]
        real(dp) :: err(4), scale
        integer :: i
        call chain_matrices(n, sm%stiffness, sm%mass, sm%damping)
        sm%model%ndof = n
        sm%model%omega = 0.5_dp
        sm%model%force_dof = [df]
        sm%model%force_harmonic = [1]
        sm%model%force_amplitude = [2.0_dp]
        sm%model%force_phase = [0.0_dp]
        sm%model%contact_dof = [dc]
        sm%model%contact_dof2 = [0]
        sm%model%mu = [0.5_dp]
        sm%model%normal_load = [1.0_dp]
        opts%harmonics = 5
        opts%samples = 128
        call solve_periodic_sparse(sm, opts, [dc], sx, error)
        call check(t, .not. allocated(error) .and. sx%converged, &
                   "sparse none: exact chain solution", msg(error))
        if (allocated(error)) return
        scale = maxval(abs(sx%xcoef(:, 1)))
        err = huge(1.0_dp)
        do i = 1, size(counts)
            call craig_bampton(sm%stiffness, sm%mass, [dc, df], &
                               reduction_options_t(modes=counts(i)), red, rep, error, &
                               cmat=sm%damping)
            if (allocated(error)) exit
            small = sm%model
            small%ndof = red%nr
            small%mass = red%mass
            small%stiffness = red%stiffness
            small%damping = red%damping
            small%force_dof = [2]
            small%contact_dof = [1]
            call solve_periodic(small, opts, sr, error)
            if (allocated(error)) exit
            err(i) = maxval(abs(sr%xcoef(:, 1) - sx%xcoef(:, 1)))/scale
        end do
        call check(t, .not. allocated(error), "sparse none: reduced solves", msg(error))
        call check(t, err(2) < err(1) .and. err(3) < err(2) .and. err(4) < err(3) .and. &
                   err(4) < 1.0e-4_dp, "sparse none: Craig-Bampton converges to the exact "// &
                   "solution as modes are added", rt(err(1))//" "//rt(err(2))//" "// &
                   rt(err(3))//" "//rt(err(4)))
    end subroutine test_craig_bampton_converges
end module test_sparse_none
