!> stickslip_reduction_estimate (estimate_reduction_error) against the exact measure
!> (receptance_error, a complex sparse LU of the full model per frequency): on the damped
!> chain of test_reduction with the rule's modes and with a few modes (the enrichment
!> agrees with the exact measure), with modes far too few for the frequencies (the levels
!> disagree: the exact measure takes over, equal to receptance_error), with a damping
!> matrix that is not alpha M + beta K (damping vectors), with every mode kept (nothing
!> to add: 0), on the factorization the reduction hands over and on one of its own (the
!> same), on the CalculiX strip of examples/calculix_beam (2412 DOFs), on the CalculiX
!> bladed-disk sector with its cyclic faces kept (the response-seeded first level, Rayleigh
!> and general damping; the reduction's C_r from M_r and K_r) and with a direction on an
!> interior DOF (refused). Also the phases progress_t%phase prints.
module test_reduction_estimate
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_scaled_sum
    use stickslip_namelist, only: nml_file_t, read_namelist_file
    use stickslip_namelist_values, only: get_integers
    use stickslip_reduction, only: reduction_options_t, reduction_report_t, reduced_model_t, &
        craig_bampton, receptance_error, reduction_estimate_t, estimate_reduction_error
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_cholmod, only: sparse_cholesky_t
    use stickslip_progress, only: progress_t
    use stickslip_matrix_market, only: read_matrix_market
    use testing, only: test_counter_t, check, check_close
    use fixtures, only: enter_project_root, msg, rt, scratch, file_text
    use test_reduction, only: chain_matrices
    implicit none
    private
    public :: run_reduction_estimate_tests

contains

    subroutine run_reduction_estimate_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_chain(t)
        call test_fallback(t)
        call test_general_damping(t)
        call test_all_modes_kept(t)
        call test_calculix(t)
        call test_sector_faces(t)
        call test_refused(t)
        call test_phase_lines(t)
    end subroutine run_reduction_estimate_tests

    !> W for contacts at DOFs (to the ground), N x size(dofs).
    function unit_directions(n, dofs) result(w)
        integer, intent(in) :: n, dofs(:)
        real(dp), allocatable :: w(:, :)
        integer :: j
        allocate (w(n, size(dofs)))
        w = 0.0_dp
        do j = 1, size(dofs)
            w(dofs(j), j) = 1.0_dp
        end do
    end function unit_directions

    !> The 600-DOF chain, contacts at 300 and 590, force at 600, Rayleigh damping
    !> (proportional): with the rule's modes and with 3 and 8 modes, the estimate agrees
    !> with the exact measure (within 5 % of it, or 1e-9), as 'enriched', per frequency too;
    !> the factorization handed over by craig_bampton gives the same as one made here.
    subroutine test_chain(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(reduction_estimate_t) :: est, own
        class(sparse_factor_t), allocatable :: lu
        type(error_type), allocatable :: error
        real(dp), allocatable :: w(:, :)
        real(dp) :: exact, fe(4)
        real(dp), parameter :: omega = 0.05_dp, freqs(4) = omega*[1.0_dp, 3.0_dp, 5.0_dp, 7.0_dp]
        integer, parameter :: mode_counts(3) = [0, 3, 8]
        integer :: case, modes
        character(len=:), allocatable :: name
        call chain_matrices(600, k, m, c)
        w = unit_directions(600, [300, 590])
        do case = 1, 3
            modes = mode_counts(case)
            name = "estimate: chain, "//itoa(modes)//" modes (0: the rule)"
            call craig_bampton(k, m, [300, 590, 600], reduction_options_t(modes=modes, &
                               highest_frequency=5*omega), red, rep, error, cmat=c, &
                               interior_lu=lu)
            call check(t, .not. allocated(error), name//": reduces", msg(error))
            if (allocated(error)) return
            call check(t, allocated(lu), name//": K_ii handed over")
            if (.not. allocated(lu)) return
            call check(t, lu%factorized() .and. same_type_as(lu, sparse_cholesky_t()), name// &
                       ": K_ii handed over, a Cholesky factor", lu%name())
            call estimate_reduction_error(k, m, red, w, freqs, est, error, cmat=c, &
                                          proportional=.true., interior_lu=lu)
            call check(t, .not. allocated(error), name//": estimate runs", msg(error))
            if (allocated(error)) return
            call receptance_error(k, m, red, w, freqs, exact, error, cmat=c, &
                                  frequency_errors=fe)
            call check(t, .not. allocated(error), name//": exact runs", msg(error))
            if (allocated(error)) return
            call check(t, est%method == 'enriched' .and. est%levels >= 2, name// &
                       ": by enrichment, two levels at least", trim(est%method)//" "// &
                       itoa(est%levels))
            call check(t, abs(est%error - exact) <= 0.05_dp*exact + 1.0e-9_dp, name// &
                       ": equals the exact measure", "estimate "//rt(est%error)//" exact "// &
                       rt(exact))
            call check(t, all(abs(est%frequency_errors - fe) <= 0.05_dp*fe + 1.0e-9_dp), &
                       name//": per frequency too")
            call check(t, exact > 1.0e-6_dp .or. modes == 0, name// &
                       ": the chain's error is not trivially small")
            ! K_ii factorized by the estimate itself: the same
            call estimate_reduction_error(k, m, red, w, freqs, own, error, cmat=c, &
                                          proportional=.true.)
            call check(t, .not. allocated(error), name//": own factorization runs", msg(error))
            if (allocated(error)) return
            call check_close(t, own%frequency_errors, est%frequency_errors, name// &
                             ": own factorization, same estimate", rtol=1.0e-8_dp, &
                             atol=1.0e-12_dp)
            if (allocated(lu)) call lu%release()
        end do
    end subroutine test_chain

    !> 2 modes kept and error frequencies above the third interior mode: the enrichment
    !> levels cannot agree, the exact measure runs ('sparse LU', with why) and is
    !> receptance_error's.
    subroutine test_fallback(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(reduction_estimate_t) :: est
        type(error_type), allocatable :: error
        real(dp), allocatable :: w(:, :)
        real(dp) :: exact, freqs(2)
        call chain_matrices(600, k, m, c)
        call craig_bampton(k, m, [300, 590, 600], reduction_options_t(modes=2), red, rep, &
                           error, cmat=c)
        call check(t, .not. allocated(error), "estimate fallback: reduces", msg(error))
        if (allocated(error)) return
        ! well above the highest kept mode, near the next ones
        freqs = [3.0_dp, 6.0_dp]*red%frequencies(2)
        w = unit_directions(600, [300, 590])
        call estimate_reduction_error(k, m, red, w, freqs, est, error, cmat=c, &
                                      proportional=.true.)
        call check(t, .not. allocated(error), "estimate fallback: runs", msg(error))
        if (allocated(error)) return
        call receptance_error(k, m, red, w, freqs, exact, error, cmat=c)
        call check(t, est%method == 'sparse LU' .and. allocated(est%fallback), &
                   "estimate fallback: the exact measure took over", trim(est%method))
        call check_close(t, est%error, exact, "estimate fallback: receptance_error's value", &
                         rtol=1.0e-12_dp)
        call check(t, est%error > 0.05_dp, "estimate fallback: a large error, reported", &
                   rt(est%error))
    end subroutine test_fallback

    !> A damping matrix with a dashpot between two interior DOFs (not alpha M + beta K): with
    !> the damping vectors (proportional absent) the estimate agrees with the exact measure.
    subroutine test_general_damping(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c, dash, cc
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(reduction_estimate_t) :: est
        type(error_type), allocatable :: error
        real(dp), allocatable :: w(:, :)
        real(dp) :: exact
        real(dp), parameter :: freqs(3) = [0.05_dp, 0.15_dp, 0.25_dp]
        call chain_matrices(600, k, m, c)
        call new_sparse_from_triplets(dash, 600, 600, [100, 100, 101, 101], [100, 101, 100, 101], &
                                      [5.0_dp, -5.0_dp, -5.0_dp, 5.0_dp], error)
        call sparse_scaled_sum(1.0_dp, c, 1.0_dp, dash, cc, error)
        call craig_bampton(k, m, [300, 590, 600], reduction_options_t(modes=6), red, rep, &
                           error, cmat=cc)
        call check(t, .not. allocated(error), "estimate general damping: reduces", msg(error))
        if (allocated(error)) return
        w = unit_directions(600, [300, 590])
        call estimate_reduction_error(k, m, red, w, freqs, est, error, cmat=cc)
        call check(t, .not. allocated(error), "estimate general damping: runs", msg(error))
        if (allocated(error)) return
        call receptance_error(k, m, red, w, freqs, exact, error, cmat=cc)
        call check(t, est%method == 'enriched' .and. &
                   abs(est%error - exact) <= 0.05_dp*exact + 1.0e-9_dp, &
                   "estimate general damping: equals the exact measure", trim(est%method)// &
                   " estimate "//rt(est%error)//" exact "//rt(exact))
    end subroutine test_general_damping

    !> Every interior mode kept (a 60-DOF chain): nothing to enrich, the estimate is the
    !> exact measure's roundoff (below 1e-9).
    subroutine test_all_modes_kept(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(reduction_estimate_t) :: est
        type(error_type), allocatable :: error
        call chain_matrices(60, k, m, c)
        call craig_bampton(k, m, [30, 60], reduction_options_t(modes=58), red, rep, error, &
                           cmat=c)
        call check(t, .not. allocated(error), "estimate all modes: reduces", msg(error))
        if (allocated(error)) return
        call estimate_reduction_error(k, m, red, unit_directions(60, [30]), [0.1_dp, 0.3_dp], &
                                      est, error, cmat=c, proportional=.true.)
        call check(t, .not. allocated(error) .and. est%method == 'enriched' .and. &
                   est%vectors == 0 .and. est%error < 1.0e-9_dp, &
                   "estimate all modes: nothing added, error 0", rt(est%error))
    end subroutine test_all_modes_kept

    !> The CalculiX strip (examples/calculix_beam: 2412 DOFs, C = 2 M) reduced as case.nml
    !> does (tip 2409 and drive 2244, H = 15 up to 620 rad/s): the estimate at the rule's
    !> frequencies equals the exact measure (8-9e-3, largest at the resonance).
    subroutine test_calculix(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(reduction_estimate_t) :: est
        class(sparse_factor_t), allocatable :: lu
        type(error_type), allocatable :: error
        real(dp) :: exact
        real(dp), parameter :: freqs(6) = [470.0_dp, 620.0_dp, 1410.0_dp, 1860.0_dp, &
                                           2350.0_dp, 3100.0_dp]
        call enter_project_root()
        call read_matrix_market("examples/calculix_beam/stiffness.mtx", k, error)
        if (.not. allocated(error)) call read_matrix_market("examples/calculix_beam/mass.mtx", &
                                                            m, error)
        call check(t, .not. allocated(error), "estimate calculix: files read", msg(error))
        if (allocated(error)) return
        call sparse_scaled_sum(2.0_dp, m, 0.0_dp, k, c, error)
        call craig_bampton(k, m, [2244, 2409], reduction_options_t(highest_frequency= &
                           15*620.0_dp), red, rep, error, cmat=c, interior_lu=lu)
        call check(t, .not. allocated(error), "estimate calculix: reduces", msg(error))
        if (allocated(error)) return
        call estimate_reduction_error(k, m, red, unit_directions(k%nrows, [2409]), freqs, est, &
                                      error, cmat=c, proportional=.true., interior_lu=lu)
        if (allocated(lu)) call lu%release()
        call check(t, .not. allocated(error), "estimate calculix: runs", msg(error))
        if (allocated(error)) return
        call receptance_error(k, m, red, unit_directions(k%nrows, [2409]), freqs, exact, &
                              error, cmat=c)
        call check(t, .not. allocated(error), "estimate calculix: exact runs", msg(error))
        call check(t, est%method == 'enriched' .and. abs(est%error - exact) <= 0.01_dp*exact, &
                   "estimate calculix: within 1 % of the exact measure", "estimate "// &
                   rt(est%error)//" exact "//rt(exact))
        call check(t, exact > 1.0e-3_dp .and. exact < 2.0e-2_dp, &
                   "estimate calculix: the known error (about 9e-3)", rt(exact))
    end subroutine test_calculix

    !> The CalculiX bladed-disk sector (examples/calculix_sector: 1662 DOFs, C = 29.5 M) with
    !> its 144 face DOFs, the contact, its partner and the drive as boundary, as the case
    !> reduces it: the boundary is far larger than the 2 contact directions at 3 frequencies,
    !> so the first level is seeded by the reduced model's responses (12 vectors, not 147);
    !> the estimate equals the exact measure (within 1 %, per frequency too), with the
    !> Rayleigh factors and with a damping matrix that is not alpha M + beta K (dashpots on
    !> two interior DOFs: damping seeds too). The reduction told C = alpha M forms C_r from
    !> M_r and K_r: the projection of C (to 1e-12).
    subroutine test_sector_faces(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: folder = "examples/calculix_sector/"
        type(sparse_matrix_t) :: k, m, c, dashpots, cg
        type(reduced_model_t) :: red, plain
        type(reduction_report_t) :: rep
        type(reduction_estimate_t) :: est
        class(sparse_factor_t), allocatable :: lu
        type(error_type), allocatable :: error
        type(nml_file_t) :: nml
        integer, allocatable :: left(:), right(:), boundary(:)
        logical :: found
        real(dp) :: exact
        real(dp), allocatable :: fe(:), w(:, :)
        real(dp), parameter :: alpha = 29.5_dp, freqs(3) = [4924.6_dp, 14773.8_dp, 24623.0_dp]
        type(reduction_options_t), parameter :: opts = &
            reduction_options_t(highest_frequency=15*5417.1_dp)
        call enter_project_root()
        call read_matrix_market(folder//"stiffness.mtx", k, error)
        if (.not. allocated(error)) call read_matrix_market(folder//"mass.mtx", m, error)
        if (.not. allocated(error)) call read_namelist_file(folder//"case.nml", nml, error)
        if (.not. allocated(error)) call get_integers(nml, "cyclic", "left_dofs", left, found, &
                                                      10000, error)
        if (.not. allocated(error)) call get_integers(nml, "cyclic", "right_dofs", right, &
                                                      found, 10000, error)
        call check(t, .not. allocated(error), "estimate sector: files read", msg(error))
        if (allocated(error)) return
        boundary = [left, right, 1659, 1653, 1539]
        w = unit_directions(k%nrows, [1659, 1653])
        allocate (fe(size(freqs)))
        call sparse_scaled_sum(alpha, m, 0.0_dp, k, c, error)
        if (.not. allocated(error)) call craig_bampton(k, m, boundary, opts, red, rep, error, &
                                                       cmat=c, interior_lu=lu, &
                                                       rayleigh=[alpha, 0.0_dp])
        if (.not. allocated(error)) call craig_bampton(k, m, boundary, opts, plain, rep, error, &
                                                       cmat=c)
        call check(t, .not. allocated(error), "estimate sector: reduces", msg(error))
        if (allocated(error)) return
        call check(t, maxval(abs(red%damping - plain%damping)) <= &
                   1.0e-12_dp*maxval(abs(plain%damping)), "estimate sector: C_r from M_r "// &
                   "and K_r (rayleigh) = T^T C T", rt(maxval(abs(red%damping - plain%damping))))
        call estimate_reduction_error(k, m, red, w, freqs, est, error, cmat=c, &
                                      interior_lu=lu, rayleigh=[alpha, 0.0_dp])
        if (.not. allocated(error)) call receptance_error(k, m, red, w, freqs, exact, error, &
                                                          cmat=c, frequency_errors=fe)
        if (allocated(lu)) call lu%release()
        call check(t, .not. allocated(error), "estimate sector: runs", msg(error))
        if (allocated(error)) return
        call check(t, est%response_seeded .and. est%method == 'enriched' .and. &
                   est%vectors <= 12*est%levels, "estimate sector: response-seeded levels "// &
                   "of at most 12 vectors", itoa(est%vectors)//" vectors in "// &
                   itoa(est%levels)//" levels")
        call check(t, abs(est%error - exact) <= 0.01_dp*exact .and. &
                   all(abs(est%frequency_errors - fe) <= 0.01_dp*fe + 1.0e-9_dp) .and. &
                   exact > 1.0e-4_dp, "estimate sector: within 1 % of the exact measure, "// &
                   "per frequency too", "estimate "//rt(est%error)//" exact "//rt(exact))
        ! dashpots on two interior DOFs: C is not proportional, damping seeds too
        call new_sparse_from_triplets(dashpots, k%nrows, k%nrows, [700, 1200], [700, 1200], &
                                      [5.0e3_dp, 5.0e3_dp], error)
        if (.not. allocated(error)) call sparse_scaled_sum(1.0_dp, c, 1.0_dp, dashpots, cg, error)
        if (.not. allocated(error)) call craig_bampton(k, m, boundary, opts, red, rep, error, &
                                                       cmat=cg)
        if (.not. allocated(error)) call estimate_reduction_error(k, m, red, w, freqs, est, &
                                                                  error, cmat=cg)
        if (.not. allocated(error)) call receptance_error(k, m, red, w, freqs, exact, error, &
                                                          cmat=cg)
        call check(t, .not. allocated(error), "estimate sector, dashpots: runs", msg(error))
        if (allocated(error)) return
        call check(t, est%response_seeded .and. est%method == 'enriched' .and. &
                   abs(est%error - exact) <= 0.01_dp*exact, "estimate sector, dashpots: "// &
                   "within 1 % of the exact measure", "estimate "//rt(est%error)//" exact "// &
                   rt(exact))
    end subroutine test_sector_faces

    !> A direction on an interior DOF is refused (input), naming the DOF.
    subroutine test_refused(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(reduction_estimate_t) :: est
        type(error_type), allocatable :: error
        call chain_matrices(60, k, m, c)
        call craig_bampton(k, m, [30, 60], reduction_options_t(modes=3), red, rep, error)
        call estimate_reduction_error(k, m, red, unit_directions(60, [31]), [0.1_dp], est, error)
        call check(t, allocated(error), "estimate: an interior direction refused")
        if (allocated(error)) call check(t, index(error%message, "interior DOF 31") > 0, &
                                         "estimate: ... naming the DOF", error%message)
    end subroutine test_refused

    !> progress_t%phase: a line 'stickslip: <text> in <s> s' for a phase of at least
    !> min_phase, none below it or with the unit off; craig_bampton reports its phases.
    subroutine test_phase_lines(t)
        type(test_counter_t), intent(inout) :: t
        type(progress_t) :: p
        type(sparse_matrix_t) :: k, m, c
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/phase_lines.txt"
        character(len=:), allocatable :: text
        integer :: u
        call enter_project_root()
        open (newunit=u, file=path, status='replace', action='write')
        p%unit = u
        call p%phase("reduction: something", 2.5_dp)
        call p%phase("reduction: too short", 0.5_dp)
        p%min_phase = 0.0_dp
        call chain_matrices(600, k, m, c)
        call craig_bampton(k, m, [300, 600], reduction_options_t(modes=4), red, rep, error, &
                           progress=p)
        close (u)
        text = file_text(path)
        call check(t, index(text, "stickslip: reduction: something in 2.5 s") > 0 .and. &
                   index(text, "too short") == 0, "progress phase: one line at or above "// &
                   "min_phase", text)
        call check(t, index(text, "stickslip: reduction: K_ii factorized") > 0 .and. &
                   index(text, "fixed-interface modes") > 0 .and. &
                   index(text, "constraint modes") > 0, &
                   "progress phase: the reduction's phases", text)
        p = progress_t()
        call p%phase("nothing", 10.0_dp)
        call check(t, p%lines == 0, "progress phase: off by default")
    end subroutine test_phase_lines
end module test_reduction_estimate
