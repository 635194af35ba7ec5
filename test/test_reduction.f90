!> stickslip_reduction (Craig-Bampton) on a fixed-free spring-mass chain with unequal masses:
!> with every interior mode the reduced receptance equals the full one to roundoff; the
!> error falls as modes are added; the reduced M is SPD; with no modes K_r is the Schur
!> complement (static condensation, computed densely here) and recovery reproduces the full
!> static response at interior DOFs; the mode-count rule; a 3000-DOF chain through ARPACK;
!> a case file with 3000-DOF Matrix Market files reduced by read_case and solved; the weighted
!> residual on the reduced example beam converges to the exact reference on the same model.
module test_reduction
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa, stickslip_stat
    use stickslip_lapack, only: dgesv, dpotrf
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_to_dense, &
        sparse_scaled_sum
    use stickslip_reduction, only: reduction_options_t, reduction_report_t, reduced_model_t, &
        craig_bampton, recover_dofs, receptance_error
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_case, only: case_t, read_case, write_case
    use stickslip_matrix_market, only: write_matrix_market
    use testing, only: test_counter_t, check, check_close
    use stickslip_cli, only: run_cli, string_t
    use fixtures, only: enter_project_root, scratch, write_lines, project_path, msg, rt
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side
    use stickslip_case_reduction, only: error_frequencies
    implicit none
    private
    public :: run_reduction_tests, chain_matrices

contains

    subroutine run_reduction_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_all_modes(t)
        call test_convergence(t)
        call test_static(t)
        call test_rule(t)
        call test_rule_damped(t)
        call test_large(t)
        call test_damping_and_errors(t)
        call test_weighted_residual(t)
        call test_case_file(t)
        call test_beam_reference(t)
        call test_error_frequencies(t)
    end subroutine run_reduction_tests

    !> Fixed-free chain of n masses: springs k between neighbours and to the ground at DOF 1,
    !> masses 1 + 0.3 mod(i, 3) (no repeated eigenvalues); C = alpha M + beta K.
    subroutine chain_matrices(n, kmat, mmat, cmat)
        integer, intent(in) :: n
        type(sparse_matrix_t), intent(out) :: kmat, mmat, cmat
        integer, allocatable :: r(:), c(:)
        real(dp), allocatable :: v(:), vm(:), vc(:)
        integer :: i, m
        type(error_type), allocatable :: error
        real(dp), parameter :: k = 1.0e4_dp, alpha = 0.5_dp, beta = 1.0e-4_dp
        allocate (r(3*n), c(3*n), v(3*n))
        m = 0
        do i = 1, n
            m = m + 1
            r(m) = i
            c(m) = i
            v(m) = 2.0_dp*k
            if (i == n) v(m) = k
            if (i < n) then
                m = m + 1
                r(m) = i
                c(m) = i + 1
                v(m) = -k
                m = m + 1
                r(m) = i + 1
                c(m) = i
                v(m) = -k
            end if
        end do
        call new_sparse_from_triplets(kmat, n, n, r(1:m), c(1:m), v(1:m), error)
        allocate (vm(n))
        do i = 1, n
            vm(i) = 1.0_dp + 0.3_dp*mod(i, 3)
        end do
        call new_sparse_from_triplets(mmat, n, n, [(i, i=1, n)], [(i, i=1, n)], vm, error)
        ! C = alpha M + beta K on K's pattern (M is diagonal, inside it)
        allocate (vc(m))
        vc = beta*v(1:m)
        do i = 1, m
            if (r(i) == c(i)) vc(i) = vc(i) + alpha*vm(r(i))
        end do
        call new_sparse_from_triplets(cmat, n, n, r(1:m), c(1:m), vc, error)
    end subroutine chain_matrices

    !> Every interior mode kept: T is square and invertible, so the reduced receptance is the
    !> full one up to roundoff; reduced M SPD.
    subroutine test_all_modes(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: err
        real(dp), allocatable :: mr(:, :)
        integer :: info
        call chain_matrices(200, k, m, c)
        call craig_bampton(k, m, [60, 200, 120], reduction_options_t(modes=197), red, rep, &
                           error, cmat=c)
        call check(t, .not. allocated(error), "reduction: all modes runs")
        if (allocated(error)) return
        call check(t, rep%reduced_dof == 200 .and. rep%modes == 197 .and. rep%full_dof == 200 &
                   .and. rep%boundary_dof == 3, "reduction: all modes sizes")
        call check(t, all(red%boundary == [60, 120, 200]), "reduction: boundary ascending")
        call receptance_error(k, m, red, [60, 200], [0, 120], [1.0_dp, 30.0_dp, 150.0_dp], &
                              err, error, cmat=c)
        call check(t, .not. allocated(error), "reduction: receptance error runs")
        call check(t, err < 1.0e-9_dp, "reduction: all modes receptance to roundoff", &
                   "error "//rt(err))
        mr = red%mass
        call dpotrf('U', size(mr, 1), mr, size(mr, 1), info)
        call check(t, info == 0, "reduction: reduced M SPD (all modes)")
    end subroutine test_all_modes

    !> Error falls as fixed-interface modes are added (from 10 modes on: with fewer, the
    !> reduced resonances sit at other places in the band 2..10 rad/s and the error is O(1),
    !> not ordered).
    subroutine test_convergence(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        integer, parameter :: counts(5) = [0, 5, 10, 20, 40]
        real(dp) :: errs(5)
        real(dp), allocatable :: mr(:, :)
        integer :: j, info
        call chain_matrices(300, k, m, c)
        do j = 1, size(counts)
            call craig_bampton(k, m, [100, 300], reduction_options_t(modes=counts(j)), red, &
                               rep, error, cmat=c)
            if (allocated(error)) exit
            call receptance_error(k, m, red, [100, 300], [0, 0], [2.0_dp, 5.0_dp, 10.0_dp], &
                                  errs(j), error, cmat=c)
            if (allocated(error)) exit
        end do
        call check(t, .not. allocated(error), "reduction: convergence runs")
        if (allocated(error)) return
        call check(t, errs(5) < errs(4) .and. errs(4) < errs(3), "reduction: error falls with modes", &
                   rt(errs(1))//" "//rt(errs(2))//" "//rt(errs(3))//" "//rt(errs(4))//" "// &
                   rt(errs(5)))
        call check(t, errs(5) < 1.0e-2_dp .and. errs(1) > 0.5_dp, &
                   "reduction: 40 modes accurate, none not", rt(errs(1))//" "//rt(errs(5)))
        mr = red%mass
        call dpotrf('U', size(mr, 1), mr, size(mr, 1), info)
        call check(t, info == 0, "reduction: reduced M SPD (40 modes)")
    end subroutine test_convergence

    !> No modes: K_r = K_bb - K_bi K_ii^-1 K_ib (dense Schur complement), and the static
    !> response to boundary forces recovered at interior DOFs equals the full solution.
    subroutine test_static(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp), allocatable :: kd(:, :), kr(:, :), f(:), u(:), q(:), x(:)
        integer, allocatable :: ipiv(:), bset(:), iset(:)
        real(dp), allocatable :: kii(:, :), kib(:, :), schur(:, :)
        integer :: n, info, i
        n = 120
        call chain_matrices(n, k, m, c)
        bset = [30, 80, 120]
        call craig_bampton(k, m, bset, reduction_options_t(modes=0), red, rep, error)
        call check(t, .not. allocated(error), "reduction: static runs")
        if (allocated(error)) return
        call check(t, rep%modes == 0 .and. rep%reduced_dof == 3, "reduction: static sizes")
        call sparse_to_dense(k, kd, error)
        iset = pack([(i, i=1, n)], [(all(bset /= i), i=1, n)])
        kii = kd(iset, iset)
        kib = kd(iset, bset)
        allocate (ipiv(size(iset)))
        call dgesv(size(iset), size(bset), kii, size(iset), ipiv, kib, size(iset), info)
        schur = kd(bset, bset) - matmul(kd(bset, iset), kib)
        call check_close(t, reshape(red%stiffness, [9]), reshape(schur, [9]), &
                         "reduction: K_r is the Schur complement", rtol=1.0e-9_dp, &
                         atol=1.0e-9_dp*maxval(abs(schur)))
        ! static response to f at the boundary
        allocate (f(n))
        f = 0.0_dp
        f(30) = 1.0_dp
        f(120) = -2.0_dp
        u = f
        deallocate (ipiv)
        allocate (ipiv(n))
        call dgesv(n, 1, kd, n, ipiv, u, n, info)
        kr = red%stiffness
        q = f(bset)
        deallocate (ipiv)
        allocate (ipiv(3))
        call dgesv(3, 1, kr, 3, ipiv, q, 3, info)
        allocate (x(4))
        call recover_dofs(red, [1, 30, 55, 100], q, x, error)
        call check(t, .not. allocated(error), "reduction: recover runs")
        call check_close(t, x, u([1, 30, 55, 100]), "reduction: static response recovered", &
                         rtol=1.0e-9_dp, atol=1.0e-12_dp)
    end subroutine test_static

    !> The rule: modes = 0 keeps the fixed-interface modes below 3 H omega; the count
    !> matches the dense eigenvalues, max_frequency overrides, and the error at the harmonic
    !> frequencies is small and falls as the factor grows.
    subroutine test_rule(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red, red_all
        type(reduction_report_t) :: rep, rep_all
        type(error_type), allocatable :: error
        real(dp) :: w, err3, err6, err1
        integer :: expected
        call chain_matrices(250, k, m, c)
        w = 2.0_dp
        call craig_bampton(k, m, [125, 250], reduction_options_t(modes=248), red_all, rep_all, &
                           error, cmat=c)
        if (allocated(error)) then
            call check(t, .false., "reduction: rule reference", error%message)
            return
        end if
        expected = count(red_all%frequencies < 3.0_dp*3.0_dp*w)
        call craig_bampton(k, m, [125, 250], reduction_options_t(highest_frequency=3.0_dp*w), &
                           red, rep, error, cmat=c)
        call check(t, .not. allocated(error), "reduction: rule runs")
        if (allocated(error)) return
        call check(t, rep%modes == expected .and. rep%modes > 0 .and. rep%modes < 248, &
                   "reduction: rule keeps the modes below 3 H omega", &
                   "kept "//itoa(rep%modes)//", expected "//itoa(expected))
        call check(t, rep%highest_mode_frequency < 9.0_dp*w .and. &
                   abs(rep%frequency_limit - 9.0_dp*w) < 1.0e-12_dp, "reduction: rule limit")
        call receptance_error(k, m, red, [125, 250], [0, 0], [w, 2.0_dp*w, 3.0_dp*w], err3, &
                              error, cmat=c)
        call craig_bampton(k, m, [125, 250], reduction_options_t(highest_frequency=3.0_dp*w, &
                           cutoff_factor=6.0_dp), red, rep, error, cmat=c)
        call receptance_error(k, m, red, [125, 250], [0, 0], [w, 2.0_dp*w, 3.0_dp*w], err6, &
                              error, cmat=c)
        call craig_bampton(k, m, [125, 250], reduction_options_t(highest_frequency=3.0_dp*w, &
                           cutoff_factor=1.5_dp), red, rep, error, cmat=c)
        call receptance_error(k, m, red, [125, 250], [0, 0], [w, 2.0_dp*w, 3.0_dp*w], err1, &
                              error, cmat=c)
        call check(t, .not. allocated(error), "reduction: rule variants run")
        call check(t, err3 < 0.05_dp .and. err6 < err3 .and. err3 < err1, &
                   "reduction: rule error small, falls as the factor grows", &
                   rt(err1)//" "//rt(err3)//" "//rt(err6))
        call craig_bampton(k, m, [125, 250], reduction_options_t(highest_frequency=3.0_dp*w, &
                           max_frequency=30.0_dp), red, rep, error)
        call check(t, .not. allocated(error) .and. rep%modes == &
                   count(red_all%frequencies < 30.0_dp), "reduction: max_frequency overrides")
    end subroutine test_rule

    !> The rule on a heavily damped model (C = 20 M): modes whose damping force at H omega
    !> rivals their stiffness are kept too, and the error is then far below that of the
    !> plain frequency limit.
    subroutine test_rule_damped(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c, heavy
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep, rep_plain
        type(error_type), allocatable :: error
        real(dp) :: err_rule, err_plain
        real(dp), parameter :: w = 2.0_dp
        call chain_matrices(250, k, m, c)
        call sparse_scaled_sum(20.0_dp, m, 0.0_dp, m, heavy, error)
        call craig_bampton(k, m, [125, 250], reduction_options_t(highest_frequency=w, &
                           max_frequency=3.0_dp*w), red, rep_plain, error, cmat=heavy)
        call receptance_error(k, m, red, [125, 250], [0, 0], [0.5_dp*w, w], err_plain, error, &
                              cmat=heavy)
        call craig_bampton(k, m, [125, 250], reduction_options_t(highest_frequency=w), red, &
                           rep, error, cmat=heavy)
        call check(t, .not. allocated(error), "reduction: damped rule runs", msg(error))
        if (allocated(error)) return
        call receptance_error(k, m, red, [125, 250], [0, 0], [0.5_dp*w, w], err_rule, error, &
                              cmat=heavy)
        call check(t, rep%modes > rep_plain%modes .and. &
                   rep%highest_mode_frequency**2 <= 9.0_dp*w*20.0_dp*(1.0_dp + 1.0e-12_dp), &
                   "reduction: damped rule keeps the damping-dominated modes", &
                   itoa(rep_plain%modes)//" -> "//itoa(rep%modes))
        call check(t, err_rule < 0.02_dp .and. err_rule < 0.5_dp*err_plain, &
                   "reduction: damped rule error small", rt(err_plain)//" -> "//rt(err_rule))
    end subroutine test_rule_damped

    !> A 3000-DOF chain (sparse LU + ARPACK in batches): rule-chosen modes, small error.
    subroutine test_large(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: err
        real(dp), allocatable :: mr(:, :)
        integer :: info
        call chain_matrices(3000, k, m, c)
        call craig_bampton(k, m, [1500, 3000], reduction_options_t(highest_frequency=1.0_dp), &
                           red, rep, error, cmat=c)
        call check(t, .not. allocated(error), "reduction: 3000 DOFs runs", msg(error))
        if (allocated(error)) return
        call check(t, rep%modes > 20 .and. rep%highest_mode_frequency < 3.0_dp .and. &
                   .not. rep%capped, "reduction: 3000 DOFs batches pass the limit", &
                   "modes "//itoa(rep%modes)//" highest "//rt(rep%highest_mode_frequency))
        call receptance_error(k, m, red, [1500, 3000], [0, 0], [0.3_dp, 0.6_dp, 1.0_dp], err, &
                              error, cmat=c)
        call check(t, .not. allocated(error) .and. err < 0.05_dp, &
                   "reduction: 3000 DOFs receptance error", rt(err))
        mr = red%mass
        call dpotrf('U', size(mr, 1), mr, size(mr, 1), info)
        call check(t, info == 0, "reduction: reduced M SPD (3000 DOFs)")
        ! sizes bounded (issue 17): more modes than a reduction keeps, asked for by number or
        ! by a max_frequency far above the spectrum, is an input error naming the option,
        ! found from the lowest modes (not after computing the 500 the cap allows)
        call craig_bampton(k, m, [1500, 3000], reduction_options_t(modes=600), red, rep, error)
        call check(t, allocated(error), "reduction: modes above max_modes refused")
        if (allocated(error)) call check(t, index(error%message, "options%modes = 600") > 0 &
                                         .and. error%stat == stickslip_stat%input, &
                                         "reduction: modes above max_modes named", error%message)
        call craig_bampton(k, m, [1500, 3000], reduction_options_t(max_frequency=1.0e300_dp), &
                           red, rep, error)
        call check(t, allocated(error), "reduction: max_frequency = 1e300 refused")
        if (allocated(error)) call check(t, index(error%message, &
                                         "options%max_frequency = 1.000E+300") > 0 .and. &
                                         index(error%message, "about 2998 fixed-interface") > 0, &
                                         "reduction: max_frequency = 1e300 named with the "// &
                                         "interior's modes", error%message)
        ! the chain's modes below 150 rad/s: w_k = 2 sqrt(k/m) sin(k pi / (2 (n + 1))), about
        ! 1/3 of 2998 of them: far above the cap, estimated from the lowest twenty
        call craig_bampton(k, m, [1500, 3000], reduction_options_t(max_frequency=150.0_dp), &
                           red, rep, error)
        call check(t, allocated(error), "reduction: a max_frequency with too many modes "// &
                   "below it refused")
        if (allocated(error)) call check(t, index(error%message, "more than "// &
                                         "options%max_modes = 500") > 0, &
                                         "reduction: too many modes below max_frequency "// &
                                         "named", error%message)
    end subroutine test_large

    !> damping_ratio alone gives the modal damping 2 zeta w_k on the modal diagonal and
    !> nothing else; bad input is an error, never a crash: a boundary DOF out of range, no
    !> interior, a floating interior (K_ii singular), wrong sizes to recover_dofs.
    subroutine test_damping_and_errors(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c, kf
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp), allocatable :: expected(:, :), x(:)
        integer :: j
        call chain_matrices(60, k, m, c)
        call craig_bampton(k, m, [30], reduction_options_t(modes=5, damping_ratio=0.02_dp), &
                           red, rep, error)
        call check(t, .not. allocated(error), "reduction: damping ratio runs", msg(error))
        if (allocated(error)) return
        allocate (expected(6, 6))
        expected = 0.0_dp
        do j = 1, 5
            expected(1 + j, 1 + j) = 2.0_dp*0.02_dp*red%frequencies(j)
        end do
        call check_close(t, reshape(red%damping, [36]), reshape(expected, [36]), &
                         "reduction: modal damping 2 zeta w_k", rtol=1.0e-12_dp, atol=1.0e-14_dp)
        ! modes are M_ii-orthonormal: the reduced M has the identity on the modal block
        call check_close(t, [(red%mass(1 + j, 1 + j), j=1, 5)], [(1.0_dp, j=1, 5)], &
                         "reduction: modal block of M_r is the identity", rtol=1.0e-10_dp)
        call check_close(t, [(red%stiffness(1 + j, 1 + j), j=1, 5)], red%frequencies**2, &
                         "reduction: modal block of K_r is diag(w_k^2)", rtol=1.0e-10_dp)
        call craig_bampton(k, m, [0, 3], reduction_options_t(), red, rep, error)
        call check(t, allocated(error), "reduction: boundary DOF 0 refused")
        call craig_bampton(k, m, [(j, j=1, 60)], reduction_options_t(), red, rep, error)
        call check(t, allocated(error), "reduction: no interior refused")
        ! a floating interior: two free chains 1..30 and 31..60 (no ground spring, no spring
        ! between 30 and 31); the boundary DOF 60 holds only the second one
        block
            integer, allocatable :: r(:), cc(:)
            real(dp), allocatable :: v(:)
            integer :: i
            allocate (r(0), cc(0), v(0))
            do i = 1, 59
                if (i == 30) cycle
                r = [r, i, i + 1, i, i + 1]
                cc = [cc, i, i + 1, i + 1, i]
                v = [v, 1.0_dp, 1.0_dp, -1.0_dp, -1.0_dp]
            end do
            call new_sparse_from_triplets(kf, 60, 60, r, cc, v, error)
        end block
        call craig_bampton(kf, m, [60], reduction_options_t(), red, rep, error)
        call check(t, allocated(error), "reduction: floating interior refused")
        if (allocated(error)) call check(t, index(error%message, "K_ii") > 0, &
                                         "reduction: floating interior named", error%message)
        call craig_bampton(k, m, [30], reduction_options_t(modes=2), red, rep, error)
        allocate (x(2))
        call recover_dofs(red, [1, 2], [1.0_dp, 2.0_dp], x, error)
        call check(t, allocated(error), "reduction: recover with a wrong size q refused")
        call recover_dofs(red, [1, 61], [1.0_dp, 2.0_dp, 3.0_dp], x, error)
        call check(t, allocated(error), "reduction: recover of a DOF out of range refused")
    end subroutine test_damping_and_errors

    !> The weighted residual on the reduced chain (N = 200, all modes below 3 H omega) against
    !> the same on the full dense chain: the contact's harmonic amplitudes agree to the
    !> measured reduction error (times a modest factor: the friction is a nonlinear function
    !> of the receptance).
    subroutine test_weighted_residual(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        type(model_t) :: full, small
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sf, sr
        real(dp) :: err, diff, scale
        integer, parameter :: n = 200, dc = 150, df = 200
        real(dp), parameter :: omega = 0.5_dp
        call chain_matrices(n, k, m, c)
        opts%harmonics = 5
        call craig_bampton(k, m, [dc, df], reduction_options_t(highest_frequency= &
                           opts%harmonics*omega), red, rep, error, cmat=c)
        call check(t, .not. allocated(error), "reduction: residual model reduces", msg(error))
        if (allocated(error)) return
        call receptance_error(k, m, red, [dc], [0], omega*[1.0_dp, 2.0_dp, 3.0_dp, 5.0_dp], &
                              err, error, cmat=c)
        full%ndof = n
        call sparse_to_dense(m, full%mass, error)
        call sparse_to_dense(k, full%stiffness, error)
        call sparse_to_dense(c, full%damping, error)
        full%omega = omega
        full%force_dof = [df]
        full%force_harmonic = [1]
        full%force_amplitude = [2.0_dp]
        full%force_phase = [0.0_dp]
        full%contact_dof = [dc]
        full%contact_dof2 = [0]
        full%mu = [0.5_dp]
        full%normal_load = [1.0_dp]
        small = full
        small%ndof = red%nr
        small%mass = red%mass
        small%stiffness = red%stiffness
        small%damping = red%damping
        small%force_dof = [2]
        small%contact_dof = [1]
        call solve_periodic(full, opts, sf, error)
        call check(t, .not. allocated(error) .and. sf%converged, &
                   "reduction: residual on the full chain converges", msg(error))
        if (allocated(error)) return
        call solve_periodic(small, opts, sr, error)
        call check(t, .not. allocated(error) .and. sr%converged, &
                   "reduction: residual on the reduced chain converges", msg(error))
        if (allocated(error)) return
        scale = maxval(abs(sf%xcoef(:, dc)))
        diff = maxval(abs(sr%xcoef(:, 1) - sf%xcoef(:, dc)))
        call check(t, diff <= max(10.0_dp*err, 1.0e-8_dp)*scale, &
                   "reduction: residual reduced vs full agree to the reduction error", &
                   "diff/scale "//rt(diff/scale)//" reduction error "//rt(err)//" modes "// &
                   itoa(rep%modes))
        diff = maxval(abs(sr%rcoef(:, 1) - sf%rcoef(:, 1)))
        call check(t, diff <= max(10.0_dp*err, 1.0e-8_dp)*maxval(abs(sf%rcoef(:, 1))), &
                   "reduction: contact force reduced vs full", rt(diff))
    end subroutine test_weighted_residual

    !> A case file with 3000-DOF Matrix Market files (written here) and &reduction method =
    !> 'craig-bampton': read_case reduces it (DOFs remapped, report filled), the weighted
    !> residual solves it; the echo names the full DOF numbers; 'none' keeps it sparse.
    subroutine test_case_file(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(error_type), allocatable :: error
        type(case_t) :: cs
        type(hbm_solution_t) :: s
        integer :: u, stat
        character(len=200) :: iomsg
        character(len=2000) :: line
        logical :: echo_ok
        call enter_project_root()
        call chain_matrices(3000, k, m, c)
        call write_matrix_market(scratch//"/cb_m.mtx", m, .true., error)
        call write_matrix_market(scratch//"/cb_k.mtx", k, .true., error)
        call check(t, .not. allocated(error), "reduction case: files written", msg(error))
        if (allocated(error)) return
        call write_lines(scratch//"/cb.nml", [character(len=100) :: &
            "&system mass_file = 'cb_m.mtx', stiffness_file = 'cb_k.mtx',", &
            "  rayleigh_alpha = 0.01 /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction method = 'craig-bampton' /", &
            "&hbm harmonics = 3 /"])
        call read_case(scratch//"/cb.nml", cs, error)
        call check(t, .not. allocated(error), "reduction case: reads", msg(error))
        if (allocated(error)) return
        associate (r => cs%reduction%report)
            call check(t, r%method == 'craig-bampton' .and. r%full_dof == 3000 .and. &
                       r%boundary_dof == 2 .and. r%reduced_dof == 2 + r%modes .and. &
                       cs%model%ndof == r%reduced_dof .and. r%modes > 0, &
                       "reduction case: reduced sizes", "reduced "//itoa(r%reduced_dof)// &
                       " modes "//itoa(r%modes))
            call check(t, r%error >= 0.0_dp .and. r%error < 0.05_dp, &
                       "reduction case: reduction error measured and small", rt(r%error))
            call check(t, r%highest_mode_frequency < 3.0_dp*3*0.03_dp, &
                       "reduction case: modes below 3 H omega")
        end associate
        call check(t, all(cs%model%contact_dof == [1]) .and. all(cs%model%force_dof == [2]), &
                   "reduction case: DOFs remapped (2990 -> 1, 3000 -> 2)")
        call solve_periodic(cs%model, cs%hbm, s, error)
        call check(t, .not. allocated(error) .and. s%converged, "reduction case: solves", &
                   msg(error))
        ! the echo: full ndof and full DOF numbers, and the &reduction group
        open (newunit=u, file=scratch//"/cb_echo.nml", status='replace', action='write')
        call write_case(u, cs, stat, iomsg)
        close (u)
        echo_ok = .false.
        open (newunit=u, file=scratch//"/cb_echo.nml", status='old', action='read')
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (index(line, "contact_dof = 2990") > 0) echo_ok = .true.
        end do
        close (u)
        call check(t, echo_ok, "reduction case: echo holds the full contact DOF")
        ! the command line: summary.nml holds the reduction keys and reads back as the case
        block
            type(string_t), allocatable :: args(:)
            type(case_t) :: back
            integer :: uo, ue, code
            logical :: keys(3)
            call write_lines(scratch//"/cb_cli.nml", [character(len=100) :: &
                "&system mass_file = 'cb_m.mtx', stiffness_file = 'cb_k.mtx',", &
                "  rayleigh_alpha = 0.01 /", &
                "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
                "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
                "&hbm harmonics = 3 /", &
                "&output directory = '"//scratch//"/out_cb' /"])
            allocate (args(1))
            args(1)%s = scratch//"/cb_cli.nml"
            open (newunit=uo, status='scratch', action='readwrite')
            open (newunit=ue, status='scratch', action='readwrite')
            code = run_cli(args, uo, ue)
            close (uo)
            close (ue)
            call check(t, code == 0, "reduction case: the command line exits 0 ('auto', "// &
                       "N = 3000)", itoa(code))
            keys = .false.
            open (newunit=u, file=scratch//"/out_cb/summary.nml", status='old', &
                  action='read', iostat=stat)
            do while (stat == 0)
                read (u, '(a)', iostat=stat) line
                if (stat /= 0) exit
                if (index(line, "reduction_method = 'craig-bampton'") > 0) keys(1) = .true.
                if (index(line, "full_dof = 3000") > 0) keys(2) = .true.
                if (index(line, "reduction_error = ") > 0) keys(3) = .true.
            end do
            close (u, iostat=stat)
            call check(t, all(keys), "reduction case: summary.nml reduction keys")
            call read_case(scratch//"/out_cb/summary.nml", back, error)
            call check(t, .not. allocated(error), "reduction case: summary.nml reads back", &
                       msg(error))
            if (.not. allocated(error)) call check(t, back%model%ndof == cs%model%ndof .and. &
                all(abs(back%model%stiffness - cs%model%stiffness) <= &
                    1.0e-9_dp*maxval(abs(cs%model%stiffness))) .and. &
                all(back%model%contact_dof == cs%model%contact_dof), &
                "reduction case: summary.nml gives the same reduced model")
        end block
        ! damping_file plus Rayleigh through the case = the library's projection of their sum
        block
            type(sparse_matrix_t) :: csum
            type(reduced_model_t) :: red
            type(reduction_report_t) :: rep
            call write_matrix_market(scratch//"/cb_c.mtx", c, .true., error)
            call write_lines(scratch//"/cb_damped.nml", [character(len=100) :: &
                "&system mass_file = 'cb_m.mtx', stiffness_file = 'cb_k.mtx',", &
                "  damping_file = 'cb_c.mtx', rayleigh_alpha = 0.01, rayleigh_beta = 1e-5 /", &
                "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
                "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
                "&hbm harmonics = 3 /"])
            call read_case(scratch//"/cb_damped.nml", cs, error)
            call check(t, .not. allocated(error), "reduction case: damped reads", msg(error))
            if (allocated(error)) return
            call sparse_scaled_sum(1.0_dp, c, 0.01_dp, m, csum, error)
            call sparse_scaled_sum(1.0_dp, csum, 1.0e-5_dp, k, c, error)
            call craig_bampton(k, m, [2990, 3000], reduction_options_t(highest_frequency= &
                               3*0.03_dp), red, rep, error, cmat=c)
            call check(t, .not. allocated(error), "reduction case: damped direct", msg(error))
            if (allocated(error)) return
            call check(t, cs%model%ndof == red%nr, "reduction case: damped sizes")
            if (cs%model%ndof == red%nr) call check_close(t, reshape(cs%model%damping, &
                [red%nr**2]), reshape(red%damping, [red%nr**2]), &
                "reduction case: damping_file + Rayleigh projected", rtol=1.0e-8_dp, &
                atol=1.0e-10_dp*maxval(abs(red%damping)))
        end block
        ! a sweep over omega: the rule takes the sweep's top frequency
        call write_lines(scratch//"/cb_sweep.nml", [character(len=100) :: &
            "&system mass_file = 'cb_m.mtx', stiffness_file = 'cb_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&hbm harmonics = 3 /", &
            "&sweep parameter = 'omega', start = 0.02, stop = 0.09 /"])
        call read_case(scratch//"/cb_sweep.nml", cs, error)
        call check(t, .not. allocated(error), "reduction case: sweep reads", msg(error))
        if (.not. allocated(error)) call check(t, abs(cs%reduction%report%frequency_limit - &
            3.0_dp*3.0_dp*0.09_dp) < 1.0e-12_dp .and. cs%method == 'sweep', &
            "reduction case: the rule takes the sweep's stop frequency", &
            rt(cs%reduction%report%frequency_limit))
        ! 'none' beyond 2000 DOFs names the limit
        call write_lines(scratch//"/cb_none.nml", [character(len=100) :: &
            "&system mass_file = 'cb_m.mtx', stiffness_file = 'cb_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&reduction method = 'none' /"])
        ! 'none' beyond 2000 DOFs keeps the model sparse (test_sparse_none)
        call read_case(scratch//"/cb_none.nml", cs, error)
        call check(t, .not. allocated(error), "reduction case: 'none' beyond 2000 DOFs "// &
                   "reads", msg(error))
        if (.not. allocated(error)) call check(t, allocated(cs%sparse_model) .and. &
                                               cs%model%ndof == 3000, &
                                               "reduction case: 'none' keeps the model sparse")
        call write_lines(scratch//"/cb_bad.nml", [character(len=100) :: &
            "&system mass_file = 'cb_m.mtx', stiffness_file = 'cb_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3001, force_amplitude = 1.0 /", &
            "&reduction method = 'cb' /"])
        call read_case(scratch//"/cb_bad.nml", cs, error)
        call check(t, allocated(error), "reduction case: bad method refused")
        if (allocated(error)) call check(t, index(error%message, "&reduction method") > 0, &
                                         "reduction case: bad method named", error%message)
    end subroutine test_case_file

    !> The weighted residual on a reduced beam (examples/beam_mm, Craig-Bampton with 3
    !> fixed-interface modes: 5 reduced DOFs, a fixed model) against the exact event-driven
    !> reference on the same reduced model, compared on the contact and forced DOFs (full
    !> numbers 79, 77) over one period: the difference falls as harmonics are added (H = 7,
    !> 15, 31) and is below 0.5% of the amplitude at H = 31.
    subroutine test_beam_reference(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: cs
        type(side_by_side_t) :: res
        type(error_type), allocatable :: error
        integer, parameter :: hs(3) = [7, 15, 31]
        real(dp) :: diff(3)
        integer :: j
        character(len=4096) :: lines(8)
        ! one element at a time: gfortran 12 cuts a typed array constructor holding
        ! deferred-length function results to the length of its first element
        lines(1) = "&system mass_file = '"//project_path("examples/beam_mm/mass.mtx")//"',"
        lines(2) = "  stiffness_file = '"//project_path("examples/beam_mm/stiffness.mtx")//"',"
        lines(3) = "  rayleigh_alpha = 0.5, rayleigh_beta = 1.0e-5 /"
        lines(4) = "&forcing omega = 40.0, force_dof = 77, force_amplitude = 5.0 /"
        lines(5) = "&friction contact_dof = 79, mu = 0.5, normal_load = 4.0 /"
        lines(6) = "&reduction method = 'craig-bampton', modes = 3 /"
        lines(7) = "&hbm harmonics = 7, odd_only = T, samples = 1024 /"
        lines(8) = "&euler steps_per_period = 200 /"
        call write_lines(scratch//"/beam_ref.nml", lines)
        call read_case(scratch//"/beam_ref.nml", cs, error)
        call check(t, .not. allocated(error), "beam reference: case reads", msg(error))
        if (allocated(error)) return
        call check(t, cs%model%ndof == 5, "beam reference: 2 boundary DOFs + 3 modes")
        diff = huge(1.0_dp)
        do j = 1, size(hs)
            cs%hbm%harmonics = hs(j)
            call solve_side_by_side(cs%model, cs%hbm, cs%euler, cs%reference, res, error, &
                                    observe=cs%reduction%output_rows)
            call check(t, .not. allocated(error), "beam reference: H = "//itoa(hs(j))// &
                       " solves", msg(error))
            if (allocated(error)) return
            call check(t, res%hbm%converged .and. res%reference%converged, &
                       "beam reference: H = "//itoa(hs(j))//" hbm and reference converge", &
                       res%diagnosis)
            if (.not. (res%hbm%converged .and. res%reference%converged)) return
            ! comparisons(1): hbm vs reference; quantities x79, x77 (ascending full numbers)
            diff(j) = maxval(res%comparisons(1)%max_error(1:2))
        end do
        call check(t, diff(2) < diff(1) .and. diff(3) < diff(2) .and. diff(3) < 5.0e-3_dp, &
                   "beam reference: hbm -> reference as H grows", rt(diff(1))//" "// &
                   rt(diff(2))//" "//rt(diff(3)))
    end subroutine test_beam_reference

    !> Where the reduction error is measured: 1, 3, 5 times the forcing frequencies, both
    !> sweep ends, distinct, m <= harmonics, a static load alone as h = 1, at most 8.
    subroutine test_error_frequencies(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: f(:)
        f = error_frequencies([1], [2.0_dp], 30)
        call check(t, size(f) == 3 .and. all(f == [2.0_dp, 6.0_dp, 10.0_dp]), &
                   "error frequencies: omega, 3 omega, 5 omega")
        f = error_frequencies([1], [1.0_dp, 3.0_dp], 30)
        call check(t, size(f) == 5 .and. all(f == [1.0_dp, 3.0_dp, 9.0_dp, 5.0_dp, 15.0_dp]), &
                   "error frequencies: sweep ends, distinct")
        f = error_frequencies([0], [2.0_dp], 1)
        call check(t, size(f) == 1 .and. all(f == [2.0_dp]), &
                   "error frequencies: static load alone, H = 1")
        f = error_frequencies([1, 2, 3], [1.0_dp, 1.5_dp], 30)
        call check(t, size(f) == 8, "error frequencies: at most 8")
    end subroutine test_error_frequencies
end module test_reduction
