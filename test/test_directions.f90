!> General contact directions (model_t%contact_direction, &friction direction_file) and
!> distributed loads (model_t%force_shape, &forcing force_file): a DOF-list contact equals
!> the same contact given as +1/-1 directions, unit load columns equal force_dof (weighted
!> residual and implicit Euler, to roundoff); an oblique contact w = (e1 + e2)/sqrt(2)
!> against the same structure built in rotated coordinates (contact on a DOF there); a
!> distributed load on a Craig-Bampton-reduced cantilever beam: the reduced static response
!> equals the full sparse solve, the dynamic response is within the measured reduction
!> error and better than without load vectors; the case files (reading, echo, default
!> outputs, a reduced beam against the unreduced one), bad files named in the messages, the
!> command line writing hbm.csv for a case with a direction_file, and method 'all' giving
!> byte-identical files for the seed case inline and with direction_file/force_file.
module test_directions
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_positive_inf
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_model, only: model_t, validate_model, contact_velocity_direction, &
        force_direction
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_to_dense
    use stickslip_umfpack, only: sparse_lu_t
    use stickslip_reduction, only: reduction_options_t, reduction_report_t, reduced_model_t, &
        craig_bampton, recover_dofs, receptance_error, reduce_vectors
    use stickslip_lapack, only: dgesv, zgesv
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_case, only: case_t, read_case, write_case, default_output_dofs
    use stickslip_matrix_market, only: write_matrix_market, write_matrix_market_array
    use stickslip_files, only: make_directory
    use test_cli, only: cli
    use testing, only: test_counter_t, check, check_close, check_error
    use fixtures, only: rt, chain_model, damped_seed, enter_project_root, scratch, write_lines, &
        first_line
    implicit none
    private
    public :: run_directions_tests

    character(len=*), parameter :: dir = scratch//"/directions"
    !> Beam elements of the cantilever (N = 2 x elements DOFs).
    integer, parameter :: elements = 60

contains

    subroutine run_directions_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(dir, error)
        call check_error(t, error, "directions: scratch directory", .false.)
        if (allocated(error)) return
        call test_dof_lists_as_directions(t)
        call test_oblique(t)
        call test_validation(t)
        call test_beam_library(t)
        call test_case_files(t)
        call test_bad_files(t)
        call test_reduced_case(t)
        call test_cli_run(t)
        call test_all_methods(t)
    end subroutine run_directions_tests

    !> The chain (a ground contact and a relative one, forcing on DOFs 1 and 3 at harmonics 1
    !> and 3) with contact_direction = the +1/-1 columns of its DOF lists, and with
    !> force_shape = unit columns: the weighted residual and implicit Euler give the same
    !> solution to roundoff (dense path).
    subroutine test_dof_lists_as_directions(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: base, bydir, byshape
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: s0, s1, s2
        type(euler_options_t) :: eo
        type(euler_result_t) :: e0, e1, e2
        type(error_type), allocatable :: error
        integer :: j
        base = chain_model()
        bydir = base
        allocate (bydir%contact_direction(4, 2))
        do j = 1, 2
            bydir%contact_direction(:, j) = contact_velocity_direction(base, j)
        end do
        deallocate (bydir%contact_dof, bydir%contact_dof2)
        byshape = base
        allocate (byshape%force_shape(4, 2))
        do j = 1, 2
            byshape%force_shape(:, j) = force_direction(base, j)
        end do
        deallocate (byshape%force_dof)
        call check(t, bydir%ncontact() == 2 .and. byshape%nforce() == 2, &
                   "dof lists: ncontact and nforce count the matrices")
        call check(t, all(bydir%contact_direction(:, 2) == [0.0_dp, 0.0_dp, -1.0_dp, 1.0_dp]), &
                   "dof lists: relative contact column is e4 - e3")
        opts%harmonics = 9
        call solve_periodic(base, opts, s0, error)
        call check_error(t, error, "dof lists: chain solves", .false.)
        if (allocated(error)) return
        call solve_periodic(bydir, opts, s1, error)
        call check_error(t, error, "dof lists: chain with directions solves", .false.)
        if (allocated(error)) return
        call solve_periodic(byshape, opts, s2, error)
        call check_error(t, error, "dof lists: chain with load shapes solves", .false.)
        if (allocated(error)) return
        call check(t, s0%converged .and. s1%converged .and. s2%converged, &
                   "dof lists: all converge")
        call check_close(t, reshape(s1%xcoef, [size(s1%xcoef)]), &
                         reshape(s0%xcoef, [size(s0%xcoef)]), &
                         "dof lists: directions give the same displacements", rtol=1.0e-13_dp, &
                         atol=1.0e-14_dp*maxval(abs(s0%xcoef)))
        call check_close(t, reshape(s1%rcoef, [size(s1%rcoef)]), &
                         reshape(s0%rcoef, [size(s0%rcoef)]), &
                         "dof lists: directions give the same contact forces", rtol=1.0e-13_dp, &
                         atol=1.0e-14_dp*maxval(abs(s0%rcoef)))
        call check_close(t, reshape(s2%xcoef, [size(s2%xcoef)]), &
                         reshape(s0%xcoef, [size(s0%xcoef)]), &
                         "dof lists: unit load shapes = force_dof (displacements)", &
                         rtol=1.0e-13_dp, atol=1.0e-14_dp*maxval(abs(s0%xcoef)))
        call check_close(t, [s2%work_forcing, s1%work_forcing], &
                         [s0%work_forcing, s0%work_forcing], &
                         "dof lists: the same work of the forcing", rtol=1.0e-13_dp)
        call check(t, all(s1%xcoef == s0%xcoef) .and. all(s2%xcoef == s0%xcoef), &
                   "dof lists: bitwise identical coefficients")
        eo%steps_per_period = 200
        eo%max_periods = 60
        call integrate_euler(base, eo, e0, error)
        call check_error(t, error, "dof lists: Euler on the chain", .false.)
        if (allocated(error)) return
        call integrate_euler(bydir, eo, e1, error)
        call check_error(t, error, "dof lists: Euler with directions", .false.)
        if (allocated(error)) return
        call integrate_euler(byshape, eo, e2, error)
        call check_error(t, error, "dof lists: Euler with load shapes", .false.)
        if (allocated(error)) return
        call check(t, e0%periods == e1%periods .and. e0%periods == e2%periods .and. &
                   all(e1%x == e0%x) .and. all(e2%x == e0%x) .and. all(e1%r == e0%r), &
                   "dof lists: Euler bitwise identical")
    end subroutine test_dof_lists_as_directions

    !> An oblique contact: the damped seed structure in coordinates y (contact on y1 to the
    !> ground, force on y2) and the same structure in x = R y, R the rotation by 45 degrees:
    !> M_x = R M R^T (same for C and K), contact direction R e1 = (e1 + e2)/sqrt(2), load shape
    !> R e2 = (e2 - e1)/sqrt(2). The x solution is R times the y solution, the contact force
    !> is the same.
    subroutine test_oblique(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: my, mx
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sy, sx
        type(error_type), allocatable :: error
        real(dp) :: r(2, 2), c
        real(dp), allocatable :: rotated(:, :)
        c = 1.0_dp/sqrt(2.0_dp)
        r = reshape([c, c, -c, c], [2, 2])
        my = damped_seed()
        my%omega = 1.3_dp
        my%contact_dof = [1]
        my%force_dof = [2]
        my%force_amplitude = [3.0_dp]
        my%mu = [1.0_dp]
        my%normal_load = [3.5_dp]
        mx = my
        mx%mass = matmul(r, matmul(my%mass, transpose(r)))
        mx%stiffness = matmul(r, matmul(my%stiffness, transpose(r)))
        mx%damping = matmul(r, matmul(my%damping, transpose(r)))
        mx%mass = 0.5_dp*(mx%mass + transpose(mx%mass))
        deallocate (mx%contact_dof, mx%contact_dof2, mx%force_dof)
        mx%contact_direction = reshape([c, c], [2, 1])
        mx%force_shape = reshape([-c, c], [2, 1])
        call validate_model(mx, error)
        call check_error(t, error, "oblique: rotated model valid", .false.)
        if (allocated(error)) return
        opts%harmonics = 15
        opts%tol = 1.0e-12_dp
        call solve_periodic(my, opts, sy, error)
        call check_error(t, error, "oblique: contact on a DOF solves", .false.)
        if (allocated(error)) return
        call solve_periodic(mx, opts, sx, error)
        call check_error(t, error, "oblique: oblique contact solves", .false.)
        if (allocated(error)) return
        call check(t, sy%converged .and. sx%converged, "oblique: both converge")
        call check(t, minval(sy%stick_fraction) > 0.05_dp .and. &
                   maxval(sy%stick_fraction) < 0.95_dp, "oblique: the contact sticks and slips", &
                   "stick fraction "//rt(sy%stick_fraction(1)))
        rotated = transpose(matmul(r, transpose(sy%xcoef)))
        call check_close(t, reshape(sx%xcoef, [size(sx%xcoef)]), &
                         reshape(rotated, [size(rotated)]), &
                         "oblique: x = R y", rtol=1.0e-7_dp, atol=1.0e-8_dp*maxval(abs(rotated)))
        call check_close(t, sx%rcoef(:, 1), sy%rcoef(:, 1), "oblique: same contact force", &
                         rtol=1.0e-7_dp, atol=1.0e-8_dp*maxval(abs(sy%rcoef)))
    end subroutine test_oblique

    !> validate_model on the matrices: both forms given, wrong rows, a zero column, NaN, counts.
    subroutine test_validation(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m, b
        type(error_type), allocatable :: error
        m = damped_seed()
        b = m
        b%contact_direction = reshape([0.0_dp, 1.0_dp], [2, 1])
        call validate_model(b, error)
        call check_error(t, error, "validation: contact_direction beside contact_dof", .true., &
                         [character(len=40) :: "model%contact_direction", "model%contact_dof"])
        deallocate (b%contact_dof, b%contact_dof2)
        call validate_model(b, error)
        call check_error(t, error, "validation: contact_direction alone is valid", .false.)
        b%contact_direction = reshape([0.0_dp, 1.0_dp, 0.0_dp], [3, 1])
        call validate_model(b, error)
        call check_error(t, error, "validation: wrong rows", .true., &
                         [character(len=40) :: "model%contact_direction", "rows"])
        b%contact_direction = reshape([0.0_dp, 1.0_dp, 0.0_dp, 0.0_dp], [2, 2])
        b%mu = [0.1_dp, 0.1_dp]
        b%normal_load = [1.0_dp, 1.0_dp]
        call validate_model(b, error)
        call check_error(t, error, "validation: zero direction", .true., &
                         [character(len=40) :: "model%contact_direction(:, 2)", "zero"])
        b%contact_direction(1, 2) = 1.0_dp
        b%mu = [0.1_dp]
        call validate_model(b, error)
        call check_error(t, error, "validation: one mu per column", .true., &
                         [character(len=40) :: "model%mu"])
        b = m
        b%force_shape = reshape([1.0_dp, 0.0_dp], [2, 1])
        call validate_model(b, error)
        call check_error(t, error, "validation: force_shape beside force_dof", .true., &
                         [character(len=40) :: "model%force_shape", "model%force_dof"])
        deallocate (b%force_dof)
        b%force_shape(2, 1) = ieee_value(1.0_dp, ieee_positive_inf)
        call validate_model(b, error)
        call check_error(t, error, "validation: infinite load shape", .true., &
                         [character(len=40) :: "model%force_shape(2, 1)"])
    end subroutine test_validation

    !> A cantilever Euler-Bernoulli beam (`elements` elements, EI = 1, rho A = 1, length 1,
    !> clamped at x = 0): DOF 2k-1 the transverse displacement of node k, 2k its rotation;
    !> N = 2 elements. K, M, C = alpha M + beta K sparse, and two distributed loads: a
    !> uniform pressure (consistent nodal loads) and a pressure on the half x > 0.5 rising
    !> linearly (lumped on the transverse DOFs).
    subroutine beam(kmat, mmat, cmat, loads)
        type(sparse_matrix_t), intent(out) :: kmat, mmat, cmat
        real(dp), allocatable, intent(out) :: loads(:, :)
        real(dp), parameter :: alpha = 0.05_dp, beta = 1.0e-5_dp
        integer :: e, a, b, m, n, d(4)
        integer, allocatable :: ri(:), ci(:)
        real(dp), allocatable :: kv(:), mv(:)
        real(dp) :: l, ke(4, 4), me(4, 4), x, fe(4)
        type(error_type), allocatable :: error
        n = 2*elements
        l = 1.0_dp/elements
        fe = [l/2, l*l/12, l/2, -l*l/12]
        ke = reshape([12.0_dp, 6*l, -12.0_dp, 6*l, 6*l, 4*l*l, -6*l, 2*l*l, &
                      -12.0_dp, -6*l, 12.0_dp, -6*l, 6*l, 2*l*l, -6*l, 4*l*l], [4, 4])/l**3
        me = reshape([156.0_dp, 22*l, 54.0_dp, -13*l, 22*l, 4*l*l, 13*l, -3*l*l, &
                      54.0_dp, 13*l, 156.0_dp, -22*l, -13*l, -3*l*l, -22*l, 4*l*l], &
                     [4, 4])*l/420.0_dp
        allocate (ri(16*elements), ci(16*elements), kv(16*elements), mv(16*elements))
        allocate (loads(n, 2))
        loads = 0.0_dp
        m = 0
        do e = 1, elements
            ! element e joins nodes e-1 and e (node 0 clamped: its DOFs are dropped)
            d = [2*e - 3, 2*e - 2, 2*e - 1, 2*e]
            do b = 1, 4
                do a = 1, 4
                    if (d(a) < 1 .or. d(b) < 1) cycle
                    m = m + 1
                    ri(m) = d(a)
                    ci(m) = d(b)
                    kv(m) = ke(a, b)
                    mv(m) = me(a, b)
                end do
                if (d(b) >= 1) loads(d(b), 1) = loads(d(b), 1) + fe(b)
            end do
            x = (e - 0.5_dp)*l
            if (x > 0.5_dp) loads(2*e - 1, 2) = loads(2*e - 1, 2) + (x - 0.5_dp)*l
        end do
        call new_sparse_from_triplets(kmat, n, n, ri(1:m), ci(1:m), kv(1:m), error)
        call new_sparse_from_triplets(mmat, n, n, ri(1:m), ci(1:m), mv(1:m), error)
        call new_sparse_from_triplets(cmat, n, n, ri(1:m), ci(1:m), alpha*mv(1:m) + &
                                      beta*kv(1:m), error)
    end subroutine beam

    !> The beam reduced with the tip's transverse DOF as boundary, with the two loads: one
    !> load vector each; the reduced static response to T^T F equals the full sparse solve
    !> at every DOF (recovered); the dynamic response at the tip to F is within the measured
    !> receptance error and better than without load vectors; a repeated load column adds
    !> no vector; the reduced mass stays the identity on the added vectors.
    subroutine test_beam_library(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        real(dp), allocatable :: f(:, :), fr(:, :), xfull(:, :), xr(:, :), xrec(:), kr(:, :), &
                                 fr0(:, :), w(:, :)
        type(reduced_model_t) :: red, red0, red2
        type(reduction_report_t) :: rep, rep0, rep2
        type(error_type), allocatable :: error
        type(sparse_lu_t) :: lu
        integer :: n, tip, j, nr, info
        integer, allocatable :: ipiv(:), all_dofs(:)
        real(dp) :: err_static, err0_static, err_meas, err_dyn, err0_dyn, omega
        real(dp), parameter :: freqs(2) = [2.5_dp, 7.5_dp]
        call beam(k, m, c, f)
        n = k%nrows
        tip = n - 1
        omega = freqs(1)
        call craig_bampton(k, m, [tip], reduction_options_t(highest_frequency=freqs(2)), red, &
                           rep, error, cmat=c, loads=f)
        call check_error(t, error, "beam: reduction with loads", .false.)
        if (allocated(error)) return
        call craig_bampton(k, m, [tip], reduction_options_t(highest_frequency=freqs(2)), red0, &
                           rep0, error, cmat=c)
        call check_error(t, error, "beam: reduction without loads", .false.)
        if (allocated(error)) return
        call check(t, rep%load_vectors == 2 .and. red%nl == 2 .and. &
                   red%nr == red%nb + red%nm + 2 .and. rep%reduced_dof == red%nr .and. &
                   rep0%load_vectors == 0 .and. rep%modes == rep0%modes, &
                   "beam: two load vectors after the modes", "modes "//itoa(rep%modes)// &
                   " load vectors "//itoa(rep%load_vectors))
        nr = red%nr
        call check_close(t, reshape(red%mass(nr - 1:nr, nr - 1:nr), [4]), &
                         [1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], &
                         "beam: load vectors of unit modal mass, M_ii-orthogonal", &
                         atol=1.0e-10_dp)
        call check_close(t, reshape(red%mass(red%nb + 1:nr - 2, nr - 1:nr), &
                                    [2*(nr - 2 - red%nb)]), [(0.0_dp, j=1, 2*(nr - 2 - red%nb))], &
                         "beam: load vectors M_ii-orthogonal to the modes", atol=1.0e-10_dp)
        ! static: the full sparse solve K x = F against the reduced K_r q = T^T F, recovered
        allocate (xfull(n, 2))
        call lu%factorize(n, k%row_start, k%col, k%val, error)
        if (.not. allocated(error)) call lu%solve(f, xfull, error)
        call lu%release()
        call check_error(t, error, "beam: full static solve", .false.)
        if (allocated(error)) return
        all_dofs = [(j, j=1, n)]
        call static_error(red, err_static)
        call static_error(red0, err0_static)
        call check(t, err_static < 1.0e-8_dp, "beam: reduced static response = full "// &
                   "(every DOF)", "relative error "//rt(err_static))
        call check(t, err0_static > 1.0e3_dp*err_static, "beam: without load vectors the "// &
                   "static response is not exact", "relative error "//rt(err0_static))
        ! dynamic: tip response to F at omega and 3 omega, full (dense complex) vs reduced
        w = reshape([(0.0_dp, j=1, n)], [n, 1])
        w(tip, 1) = 1.0_dp
        call receptance_error(k, m, red, w, freqs, err_meas, error, cmat=c)
        call check_error(t, error, "beam: receptance error with directions", .false.)
        if (allocated(error)) return
        call dynamic_error(red, err_dyn)
        call dynamic_error(red0, err0_dyn)
        call check(t, err_dyn <= max(10.0_dp*err_meas, 1.0e-8_dp), "beam: dynamic tip "// &
                   "response to the loads within the measured reduction error", &
                   "error "//rt(err_dyn)//" measured "//rt(err_meas))
        call check(t, err_dyn < 0.2_dp*err0_dyn, "beam: load vectors improve the dynamic "// &
                   "response", "with "//rt(err_dyn)//" without "//rt(err0_dyn))
        ! a load repeated (and one on the boundary only) adds no load vector
        fr0 = reshape([f(:, 1), 2.0_dp*f(:, 1), w(:, 1)], [n, 3])
        call craig_bampton(k, m, [tip], reduction_options_t(highest_frequency=freqs(2)), red2, &
                           rep2, error, cmat=c, loads=fr0)
        call check_error(t, error, "beam: reduction with dependent loads", .false.)
        if (.not. allocated(error)) call check(t, rep2%load_vectors == 1, &
                                               "beam: a dependent load vector is dropped", &
                                               itoa(rep2%load_vectors))

    contains

        subroutine static_error(rm, err)
            type(reduced_model_t), intent(in) :: rm
            real(dp), intent(out) :: err
            integer :: col
            allocate (xrec(n))
            call reduce_vectors(rm, f, fr, error)
            kr = rm%stiffness
            xr = fr
            allocate (ipiv(rm%nr))
            call dgesv(rm%nr, 2, kr, rm%nr, ipiv, xr, rm%nr, info)
            err = 0.0_dp
            do col = 1, 2
                call recover_dofs(rm, all_dofs, xr(:, col), xrec, error)
                err = max(err, maxval(abs(xrec - xfull(:, col)))/maxval(abs(xfull(:, col))))
            end do
            deallocate (xrec, ipiv)
        end subroutine static_error

        subroutine dynamic_error(rm, err)
            type(reduced_model_t), intent(in) :: rm
            real(dp), intent(out) :: err
            real(dp), allocatable :: kd(:, :), md(:, :), cd(:, :)
            complex(dp), allocatable :: z(:, :), x(:, :), zr(:, :), q(:, :)
            integer, allocatable :: piv(:)
            integer :: fi
            call sparse_to_dense(k, kd, error)
            call sparse_to_dense(m, md, error)
            call sparse_to_dense(c, cd, error)
            call reduce_vectors(rm, f, fr, error)
            err = 0.0_dp
            do fi = 1, size(freqs)
                associate (om => freqs(fi))
                    z = cmplx(kd - om**2*md, om*cd, dp)
                    x = cmplx(f, 0.0_dp, dp)
                    allocate (piv(n))
                    call zgesv(n, 2, z, n, piv, x, n, info)
                    deallocate (piv)
                    zr = cmplx(rm%stiffness - om**2*rm%mass, om*rm%damping, dp)
                    q = cmplx(fr, 0.0_dp, dp)
                    allocate (piv(rm%nr))
                    call zgesv(rm%nr, 2, zr, rm%nr, piv, q, rm%nr, info)
                    deallocate (piv)
                    ! the tip is boundary DOF 1 of the reduced model
                    err = max(err, maxval(abs(q(1, :) - x(tip, :))/abs(x(tip, :))))
                end associate
            end do
        end subroutine dynamic_error
    end subroutine test_beam_library

    !> Case files: the seed case with direction_file (+1 column) and force_file (unit column)
    !> reads the same model as its DOF lists; Matrix Market array and coordinate both read;
    !> relative paths resolve against the case folder; the echo writes direction_file and
    !> force_file (absolute) and reads back; force_amplitude defaults to 1 with a force_file;
    !> the default outputs of a model above 64 DOFs.
    subroutine test_case_files(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c, back
        type(error_type), allocatable :: error
        type(sparse_matrix_t) :: s
        type(model_t) :: big
        integer :: u, stat, i
        character(len=300) :: iomsg
        call write_matrix_market_array(dir//"/w_seed.mtx", reshape([0.0_dp, 1.0_dp], [2, 1]), &
                                       .false., error)
        call new_sparse_from_triplets(s, 2, 1, [1], [1], [10.0_dp], error)
        call write_matrix_market(dir//"/f_seed.mtx", s, .false., error)
        call check_error(t, error, "case files: matrices written", .false.)
        if (allocated(error)) return
        call write_lines(dir//"/seed_files.nml", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 4.5, force_file = 'f_seed.mtx' /", &
            "&friction direction_file = 'w_seed.mtx', mu = 0.45, normal_load = 1.0 /", &
            "&output directory = '"//dir//"/out_seed' /"])
        call read_case(dir//"/seed_files.nml", c, error)
        call check_error(t, error, "case files: seed with files reads", .false.)
        if (allocated(error)) return
        call check(t, c%model%ncontact() == 1 .and. c%model%nforce() == 1 .and. &
                   all(c%model%contact_direction(:, 1) == [0.0_dp, 1.0_dp]) .and. &
                   all(c%model%force_shape(:, 1) == [10.0_dp, 0.0_dp]) .and. &
                   all(c%model%force_amplitude == [1.0_dp]) .and. &
                   all(c%model%force_harmonic == [1]), &
                   "case files: directions, load shape, amplitude 1 by default")
        call check(t, c%system_files%direction_path == dir//"/w_seed.mtx" .and. &
                   c%system_files%direction_absolute(1:1) == "/", &
                   "case files: paths resolved against the case folder")
        call check(t, all(c%output_dofs == [1, 2]), "case files: every DOF of a small model")
        open (newunit=u, file=dir//"/seed_echo.nml", status='replace', action='write')
        call write_case(u, c, stat, iomsg)
        close (u)
        call check(t, stat == 0, "case files: echo written")
        call read_case(dir//"/seed_echo.nml", back, error)
        call check_error(t, error, "case files: echo reads back", .false.)
        if (allocated(error)) return
        call check(t, allocated(back%system_files%direction_file) .and. &
                   allocated(back%system_files%force_file) .and. &
                   all(back%model%contact_direction == c%model%contact_direction) .and. &
                   all(back%model%force_shape == c%model%force_shape), &
                   "case files: echo names direction_file and force_file")
        ! the default outputs above 64 DOFs: the DOFs of W and force_dof; not those of F
        big%ndof = 100
        allocate (big%contact_direction(100, 2), big%force_shape(100, 1))
        big%contact_direction = 0.0_dp
        big%contact_direction(40, 1) = 0.6_dp
        big%contact_direction(41, 1) = 0.8_dp
        big%contact_direction(7, 2) = 1.0_dp
        big%force_shape = 1.0_dp
        call check(t, same(default_output_dofs(big), [7, 40, 41]), &
                   "case files: default outputs = the DOFs of W (not those of F)")
        deallocate (big%force_shape)
        big%force_dof = [90]
        call check(t, same(default_output_dofs(big), [7, 40, 41, 90]), &
                   "case files: default outputs = the DOFs of W and force_dof")
        big%ndof = 64
        call check(t, same(default_output_dofs(big), [(i, i=1, 64)]), &
                   "case files: default outputs, 64 DOFs: every DOF")
    end subroutine test_case_files

    !> Bad files and variables: wrong rows, a zero column, direction_file beside contact_dof
    !> and contact_dof2, force_file beside force_dof, a missing file, mu of the wrong length,
    !> a NaN entry (named with its line): messages name the case, group, variable and file.
    subroutine test_bad_files(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=*), parameter :: sys = &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /"
        character(len=*), parameter :: frc = "&forcing omega = 4.5, force_dof = 1, " // &
            "force_amplitude = 10.0 /"
        call write_matrix_market_array(dir//"/w_rows.mtx", reshape([0.0_dp, 1.0_dp, 0.0_dp], &
                                       [3, 1]), .false., error)
        call write_matrix_market_array(dir//"/w_zero.mtx", reshape([0.0_dp, 1.0_dp, 0.0_dp, &
                                       0.0_dp], [2, 2]), .false., error)
        call write_matrix_market_array(dir//"/w_good.mtx", reshape([0.0_dp, 1.0_dp], [2, 1]), &
                                       .false., error)
        call write_lines(dir//"/w_nan.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real general", "2 1 2", "1 1 0.5", "2 1 NaN"])
        call bad("rows", [character(len=120) :: sys, frc, &
            "&friction direction_file = 'w_rows.mtx', mu = 0.3, normal_load = 1 /"], &
            [character(len=60) :: "bad_rows.nml", "&friction direction_file", "w_rows.mtx", &
             "3 x 1", "N = 2"])
        call bad("zero", [character(len=120) :: sys, frc, &
            "&friction direction_file = 'w_zero.mtx', mu = 0.3, 0.3, normal_load = 1, 1 /"], &
            [character(len=60) :: "&friction direction_file", "w_zero.mtx", "column 2 is zero"])
        call bad("both", [character(len=120) :: sys, frc, &
            "&friction direction_file = 'w_good.mtx', contact_dof = 2, mu = 0.3, " // &
            "normal_load = 1 /"], &
            [character(len=60) :: "bad_both.nml:3", "&friction direction_file and contact_dof"])
        call bad("both2", [character(len=120) :: sys, frc, &
            "&friction direction_file = 'w_good.mtx', contact_dof2 = 1, mu = 0.3, " // &
            "normal_load = 1 /"], &
            [character(len=60) :: "&friction direction_file and contact_dof2"])
        call bad("force_both", [character(len=120) :: sys, &
            "&forcing omega = 4.5, force_dof = 1, force_file = 'w_good.mtx' /"], &
            [character(len=60) :: "&forcing force_file and force_dof"])
        call bad("force_rows", [character(len=120) :: sys, &
            "&forcing omega = 4.5, force_file = 'w_rows.mtx' /"], &
            [character(len=60) :: "&forcing force_file", "w_rows.mtx", "N = 2"])
        call bad("missing", [character(len=120) :: sys, frc, &
            "&friction direction_file = 'nowhere.mtx', mu = 0.3, normal_load = 1 /"], &
            [character(len=60) :: "&friction direction_file", "nowhere.mtx"])
        call bad("mu", [character(len=120) :: sys, frc, &
            "&friction direction_file = 'w_good.mtx', mu = 0.3, 0.2, normal_load = 1 /"], &
            [character(len=60) :: "&friction mu", "one per column of direction_file"])
        call bad("amplitudes", [character(len=120) :: sys, &
            "&forcing omega = 4.5, force_file = 'w_good.mtx', force_amplitude = 1, 2 /"], &
            [character(len=60) :: "&forcing force_amplitude", "one per column of force_file"])
        call bad("nan", [character(len=120) :: sys, frc, &
            "&friction direction_file = 'w_nan.mtx', mu = 0.3, normal_load = 1 /"], &
            [character(len=60) :: "&friction direction_file", "w_nan.mtx:4"])

    contains

        subroutine bad(name, lines, expect)
            character(len=*), intent(in) :: name
            character(len=*), intent(in) :: lines(:), expect(:)
            call write_lines(dir//"/bad_"//name//".nml", lines)
            call read_case(dir//"/bad_"//name//".nml", c, error)
            call check_error(t, error, "bad files: "//name, .true., expect)
        end subroutine bad
    end subroutine test_bad_files

    !> The beam as a case: Matrix Market M, K, a direction_file at the tip (transverse DOF
    !> plus a little rotation: an oblique, local-frame contact) and a force_file with the two
    !> loads; 'craig-bampton' reduces it (two load vectors, W_r and F_r of the reduced size,
    !> summary keys) and its weighted-residual solution matches the unreduced 'none' case at
    !> the contact within a modest multiple of the measured reduction error.
    subroutine test_reduced_case(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        real(dp), allocatable :: f(:, :), w(:, :)
        type(case_t) :: cr, cf
        type(hbm_solution_t) :: sr, sf
        type(error_type), allocatable :: error
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        integer :: n, h
        real(dp) :: diff, scale, err_all
        call beam(k, m, c, f)
        n = k%nrows
        call write_matrix_market(dir//"/beam_m.mtx", m, .true., error)
        call write_matrix_market(dir//"/beam_k.mtx", k, .true., error)
        call write_matrix_market_array(dir//"/beam_f.mtx", f, .false., error)
        allocate (w(n, 1))
        w = 0.0_dp
        w(n - 1, 1) = 1.0_dp
        w(n, 1) = 0.02_dp
        call write_matrix_market_array(dir//"/beam_w.mtx", w, .false., error)
        call check_error(t, error, "reduced case: files written", .false.)
        if (allocated(error)) return
        call beam_case("beam_cb", "craig-bampton")
        call beam_case("beam_full", "none")
        call read_case(dir//"/beam_cb.nml", cr, error)
        call check_error(t, error, "reduced case: reads and reduces", .false.)
        if (allocated(error)) return
        associate (r => cr%reduction%report)
            call check(t, r%method == 'craig-bampton' .and. r%boundary_dof == 2 .and. &
                       r%load_vectors == 2 .and. r%reduced_dof == 2 + r%modes + 2 .and. &
                       cr%model%ndof == r%reduced_dof .and. &
                       size(cr%model%contact_direction, 1) == r%reduced_dof .and. &
                       size(cr%model%force_shape, 1) == r%reduced_dof .and. &
                       size(cr%model%force_shape, 2) == 2, &
                       "reduced case: sizes (2 boundary DOFs, 2 load vectors)", &
                       "reduced "//itoa(r%reduced_dof)//" modes "//itoa(r%modes)// &
                       " load vectors "//itoa(r%load_vectors))
            call check(t, r%error >= 0.0_dp .and. r%error < 0.05_dp, &
                       "reduced case: reduction error measured", rt(r%error))
        end associate
        call check(t, same(cr%output_dofs, [n - 1, n]), &
                   "reduced case: default outputs are the DOFs of W")
        call check(t, all(cr%model%contact_direction(1:2, 1) == [1.0_dp, 0.02_dp]) .and. &
                   all(cr%model%contact_direction(3:, 1) == 0.0_dp), &
                   "reduced case: W_r = the boundary rows of W")
        call read_case(dir//"/beam_full.nml", cf, error)
        call check_error(t, error, "reduced case: unreduced reads", .false.)
        if (allocated(error)) return
        call solve_periodic(cr%model, cr%hbm, sr, error)
        call check_error(t, error, "reduced case: reduced solves", .false.)
        if (allocated(error)) return
        call solve_periodic(cf%model, cf%hbm, sf, error)
        call check_error(t, error, "reduced case: unreduced solves", .false.)
        if (allocated(error)) return
        call check(t, sr%converged .and. sf%converged, "reduced case: both converge")
        ! the reduction error at every harmonic of the run (the case measures it at the
        ! forcing harmonic only; the friction excites the odd harmonics up to 7 omega)
        call craig_bampton(k, m, [n - 1, n], reduction_options_t(highest_frequency= &
                           7*2.5_dp), red, rep, error, cmat=c, loads=f)
        if (.not. allocated(error)) call receptance_error(k, m, red, w, &
            [(h*2.5_dp, h=1, 7)], err_all, error, cmat=c)
        call check_error(t, error, "reduced case: error at every harmonic", .false.)
        if (allocated(error)) return
        call check(t, rep%modes == cr%reduction%report%modes .and. &
                   abs(red%mass(red%nr, red%nr) - cr%model%mass(red%nr, red%nr)) < 1.0e-12_dp, &
                   "reduced case: the case's reduction is the library's")
        scale = maxval(abs(sf%rcoef(:, 1)))
        diff = maxval(abs(sr%rcoef(:, 1) - sf%rcoef(:, 1)))
        call check(t, diff <= max(10.0_dp*err_all, 1.0e-8_dp)*scale, &
                   "reduced case: contact force of the reduced beam = the full one", &
                   "diff/scale "//rt(diff/scale)//" reduction error "//rt(err_all))
        scale = maxval(abs(sf%xcoef(:, n - 1)))
        diff = maxval(abs(sr%xcoef(:, 1) - sf%xcoef(:, n - 1)))
        call check(t, diff <= max(10.0_dp*err_all, 1.0e-8_dp)*scale, &
                   "reduced case: tip displacement of the reduced beam = the full one", &
                   "diff/scale "//rt(diff/scale))
        ! the command line: summary.nml counts the load vectors and reads back as the case
        block
            character(len=:), allocatable :: out, err
            integer :: code, u, stat
            character(len=400) :: line
            logical :: counted
            type(case_t) :: back
            call write_lines(dir//"/beam_cli.nml", [character(len=120) :: &
                "&system mass_file = 'beam_m.mtx', stiffness_file = 'beam_k.mtx',", &
                "  rayleigh_alpha = 0.05, rayleigh_beta = 1e-5 /", &
                "&forcing omega = 2.5, force_file = 'beam_f.mtx', force_amplitude = 2.0, 1.5 /", &
                "&friction direction_file = 'beam_w.mtx', mu = 0.5, normal_load = 1.0 /", &
                "&reduction method = 'craig-bampton' /", "&hbm harmonics = 7 /", &
                "&output directory = '"//dir//"/out_beam' /"])
            ! a reduction cache left by an earlier run of the tests must not answer
            open (newunit=u, file=dir//"/out_beam/reduction.cache", status='old', iostat=stat)
            if (stat == 0) close (u, status='delete')
            call cli([character(len=200) :: dir//"/beam_cli.nml"], code, out, err)
            call check(t, code == 0, "reduced case: the command line runs", err)
            call check(t, first_line(dir//"/out_beam/hbm.csv") == "t,x"//itoa(n - 1)//",x"// &
                       itoa(n)//",v"//itoa(n - 1)//",v"//itoa(n)//",r1", &
                       "reduced case: hbm.csv holds the DOFs of W", &
                       first_line(dir//"/out_beam/hbm.csv"))
            counted = .false.
            open (newunit=u, file=dir//"/out_beam/summary.nml", status='old', action='read', &
                  iostat=stat)
            do while (stat == 0)
                read (u, '(a)', iostat=stat) line
                if (stat /= 0) exit
                if (index(line, "reduction_load_vectors = 2") > 0) counted = .true.
            end do
            close (u, iostat=stat)
            call check(t, counted, "reduced case: summary.nml reduction_load_vectors = 2")
            call read_case(dir//"/out_beam/summary.nml", back, error)
            call check_error(t, error, "reduced case: summary.nml reads back", .false.)
            if (.not. allocated(error)) call check(t, back%model%ndof == cr%model%ndof .and. &
                back%reduction%report%load_vectors == 2 .and. &
                all(abs(back%model%force_shape - cr%model%force_shape) <= &
                    1.0e-12_dp*maxval(abs(cr%model%force_shape))), &
                "reduced case: summary.nml gives the same reduced loads")
        end block

    contains

        subroutine beam_case(name, method)
            character(len=*), intent(in) :: name, method
            call write_lines(dir//"/"//name//".nml", [character(len=120) :: &
                "&system mass_file = 'beam_m.mtx', stiffness_file = 'beam_k.mtx',", &
                "  rayleigh_alpha = 0.05, rayleigh_beta = 1e-5 /", &
                "&forcing omega = 2.5, force_file = 'beam_f.mtx', force_amplitude = 2.0, 1.5,", &
                "  force_harmonic = 1, 1, force_phase = 0, 0.5 /", &
                "&friction direction_file = 'beam_w.mtx', mu = 0.5, normal_load = 1.0 /", &
                "&reduction method = '"//method//"' /", &
                "&hbm harmonics = 7 /"])
        end subroutine beam_case
    end subroutine test_reduced_case

    !> The command line on a case with a direction_file (the oblique contact on the damped
    !> seed): exit 0, hbm.csv written with the usual columns, summary.nml echoes the file.
    subroutine test_cli_run(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err
        integer :: code, u, stat
        character(len=400) :: line
        logical :: echoed
        type(error_type), allocatable :: error
        real(dp) :: c
        c = 1.0_dp/sqrt(2.0_dp)
        call write_matrix_market_array(dir//"/w_oblique.mtx", reshape([c, c], [2, 1]), .false., &
                                       error)
        call check_error(t, error, "cli: direction file written", .false.)
        if (allocated(error)) return
        call write_lines(dir//"/oblique.nml", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1,", &
            "  damping = 0.06,-0.02,-0.02,0.04 /", &
            "&forcing omega = 1.3, force_dof = 2, force_amplitude = 3.0 /", &
            "&friction direction_file = 'w_oblique.mtx', mu = 0.3, normal_load = 1.0 /", &
            "&hbm harmonics = 9 /", &
            "&output directory = '"//dir//"/out_oblique' /"])
        call cli([character(len=200) :: dir//"/oblique.nml"], code, out, err)
        call check(t, code == 0, "cli: a case with direction_file runs", err)
        call check(t, first_line(dir//"/out_oblique/hbm.csv") == "t,x1,x2,v1,v2,r1", &
                   "cli: hbm.csv written with its columns", first_line(dir//"/out_oblique/hbm.csv"))
        echoed = .false.
        open (newunit=u, file=dir//"/out_oblique/summary.nml", status='old', action='read', &
              iostat=stat)
        do while (stat == 0)
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (index(line, "direction_file = '") > 0 .and. index(line, "w_oblique.mtx") > 0) &
                echoed = .true.
        end do
        close (u, iostat=stat)
        call check(t, echoed, "cli: summary.nml echoes direction_file")
    end subroutine test_cli_run

    !> Method 'all' (weighted residual, implicit Euler, exact reference) on the seed case
    !> inline and with the same contact and forcing as direction_file and force_file (unit
    !> columns): the result files are identical byte for byte.
    subroutine test_all_methods(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        character(len=:), allocatable :: out, err
        character(len=16), parameter :: files(3) = [character(len=16) :: "hbm.csv", &
                                                    "euler.csv", "reference.csv"]
        integer :: code, k
        call write_matrix_market_array(dir//"/f_unit.mtx", reshape([1.0_dp, 0.0_dp], [2, 1]), &
                                       .false., error)
        call check_error(t, error, "all methods: load file written", .false.)
        if (allocated(error)) return
        call all_case("all_inline", "&forcing omega = 4.5, force_dof = 1, force_amplitude = 10 /", &
                      "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /")
        call all_case("all_files", "&forcing omega = 4.5, force_file = 'f_unit.mtx', " // &
                      "force_amplitude = 10 /", &
                      "&friction direction_file = 'w_seed.mtx', mu = 0.45, normal_load = 1.0 /")
        call cli([character(len=200) :: dir//"/all_inline.nml"], code, out, err)
        call check(t, code == 0, "all methods: inline seed runs", err)
        call cli([character(len=200) :: dir//"/all_files.nml"], code, out, err)
        call check(t, code == 0, "all methods: seed with files runs", err)
        do k = 1, size(files)
            call check(t, same_text(dir//"/out_all_inline/"//trim(files(k)), &
                                    dir//"/out_all_files/"//trim(files(k))), &
                       "all methods: "//trim(files(k))//" identical")
        end do

    contains

        subroutine all_case(name, forcing, friction)
            character(len=*), intent(in) :: name, forcing, friction
            call write_lines(dir//"/"//name//".nml", [character(len=120) :: &
                "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", forcing, &
                friction, "&hbm harmonics = 15, samples = 256 /", &
                "&euler steps_per_period = 200 /", "&run method = 'all' /", &
                "&output directory = '"//dir//"/out_"//name//"' /"])
        end subroutine all_case
    end subroutine test_all_methods

    !> The two text files exist and have the same lines.
    logical function same_text(a, b)
        character(len=*), intent(in) :: a, b
        character(len=2000) :: la, lb
        integer :: ua, ub, sa, sb
        same_text = .false.
        open (newunit=ua, file=a, status='old', action='read', iostat=sa)
        if (sa /= 0) return
        open (newunit=ub, file=b, status='old', action='read', iostat=sb)
        if (sb /= 0) then
            close (ua)
            return
        end if
        do
            read (ua, '(a)', iostat=sa) la
            read (ub, '(a)', iostat=sb) lb
            if (sa /= 0 .or. sb /= 0) exit
            if (la /= lb) exit
        end do
        same_text = sa /= 0 .and. sb /= 0 .and. sa == sb
        close (ua)
        close (ub)
    end function same_text

    pure logical function same(a, b)
        integer, intent(in) :: a(:), b(:)
        same = size(a) == size(b)
        if (same) same = all(a == b)
    end function same
end module test_directions
