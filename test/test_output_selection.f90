!> Tests of the output selection, &output dofs: the default (every DOF of a small model, so
!> its files are unchanged; the contact and forced DOFs of a model above 64 DOFs), an
!> explicit list (columns in the order given, named by DOF number, values those of the full
!> solution), the echo in summary.nml, frc.csv and frc.gp, euler.csv, reference.csv and
!> study.csv, and bad lists rejected with a message naming &output dofs(k); with a
!> Craig-Bampton reduction, columns named by full-model numbers with the unreduced values.
module test_output_selection
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat, itoa
    use stickslip_case, only: case_t, read_case, selected_dofs, default_output_dofs
    use stickslip_solution, only: hbm_solution_t
    use stickslip_checks, only: hbm_checks_t, solve_and_check
    use stickslip_model, only: model_t
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets
    use stickslip_matrix_market, only: write_matrix_market, read_matrix_market, &
        write_matrix_market_array
    use stickslip_sparse, only: sparse_to_dense
    use stickslip_sweep, only: sweep_result_t
    use stickslip_csv, only: write_frc_csv
    use stickslip_plot_scripts, only: write_frc_plot_script, write_modes_plot_script
    use stickslip_plot_units, only: plot_units_t
    use stickslip_files, only: make_directory
    use test_cli, only: cli
    use testing, only: test_counter_t, check, check_error
    use fixtures, only: enter_project_root, first_line, scratch, write_lines, good_system, &
        good_forcing, good_friction, sweep_case, seed_model, count_commas
    implicit none
    private
    public :: run_output_selection_tests

    character(len=*), parameter :: dir = scratch//"/output_selection"
    !> The DOFs of the 70-DOF chain.
    integer, parameter :: nchain = 70

contains

    subroutine run_output_selection_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(dir, error)
        call check_error(t, error, "output selection: scratch directory", .false.)
        if (allocated(error)) return
        call test_small_model_unchanged(t)
        call test_default_rule(t)
        call test_chain(t)
        call test_full_field(t)
        call test_truncation_observed(t)
        call test_seed_selected(t)
        call test_frc(t)
        call test_bad_dofs(t)
    end subroutine run_output_selection_tests

    !> The seed case (2 DOFs) without &output dofs: every DOF, and the headers of today.
    subroutine test_small_model_unchanged(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: out_dir = dir//"/seed_default"
        character(len=:), allocatable :: out, err
        type(case_t) :: c, back
        type(error_type), allocatable :: error
        integer :: code
        call write_lines(dir//"/seed_default.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 10, samples = 64 /", &
            "&output directory = '"//out_dir//"' /"])
        call read_case(dir//"/seed_default.nml", c, error)
        call check_error(t, error, "seed default: reads", .false.)
        if (allocated(error)) return
        call check(t, same(c%output_dofs, [1, 2]) .and. .not. c%output_dofs_given, &
                   "seed default: every DOF selected, not given")
        call cli([character(len=200) :: dir//"/seed_default.nml"], code, out, err)
        call check(t, code == 0, "seed default: exit 0", err)
        call check(t, first_line(out_dir//"/hbm.csv") == "t,x1,x2,v1,v2,r1", &
                   "seed default: hbm.csv header unchanged", first_line(out_dir//"/hbm.csv"))
        call check(t, first_line(out_dir//"/coefficients.csv") == "harmonic,kind,x1,x2,r1", &
                   "seed default: coefficients.csv header unchanged", &
                   first_line(out_dir//"/coefficients.csv"))
        call check(t, .not. has_line_starting(out_dir//"/summary.nml", "dofs"), &
                   "seed default: summary.nml echoes no dofs")
        call read_case(out_dir//"/summary.nml", back, error)
        call check_error(t, error, "seed default: summary.nml reads back", .false.)
        if (.not. allocated(error)) call check(t, same(back%output_dofs, [1, 2]) .and. &
            .not. back%output_dofs_given, "seed default: summary.nml gives the default")
    end subroutine test_small_model_unchanged

    !> default_output_dofs: all DOFs up to 64; above, the contact DOFs (both sides) and the
    !> forced DOFs, increasing, no duplicates; selected_dofs of a case built in memory.
    subroutine test_default_rule(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(case_t) :: c
        integer :: i
        m = seed_model()
        call check(t, same(default_output_dofs(m), [1, 2]), "default rule: small model, all")
        m%ndof = 64
        call check(t, same(default_output_dofs(m), [(i, i=1, 64)]), "default rule: 64 DOFs, all")
        m%ndof = 100
        m%force_dof = [90, 7, 90]
        m%contact_dof = [50, 7]
        m%contact_dof2 = [0, 3]
        call check(t, same(default_output_dofs(m), [3, 7, 50, 90]), &
                   "default rule: 100 DOFs, contact and forced DOFs sorted and unique")
        c%model = seed_model()
        call check(t, same(selected_dofs(c), [1, 2]), "default rule: case in memory, all")
        c%output_dofs = [2]
        call check(t, same(selected_dofs(c), [2]), "default rule: case in memory, its list")
    end subroutine test_default_rule

    !> A 70-DOF chain from Matrix Market files: the default columns are the contact and forced
    !> DOFs; `dofs = 3, 1` gives x3,x1 (the order given), the values of the full solution
    !> (all 70 DOFs selected); summary.nml echoes and reads back the list.
    subroutine test_chain(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err, all_dofs
        type(case_t) :: c, back
        type(error_type), allocatable :: error
        real(dp), allocatable :: a(:, :), b(:, :), full(:, :), ca(:, :), cfull(:, :)
        integer :: code, i
        character(len=*), parameter :: sel_header = "t,x11,x12,x40,x70,v11,v12,v40,v70,r1,r2"
        call write_chain(error)
        call check_error(t, error, "chain: matrix files written", .false.)
        if (allocated(error)) return
        call chain_case("chain_default", "")
        call read_case(dir//"/chain_default.nml", c, error)
        call check_error(t, error, "chain: reads", .false.)
        if (allocated(error)) return
        call check(t, c%model%ndof == nchain, "chain: 70 DOFs from the files")
        call check(t, same(c%output_dofs, [11, 12, 40, 70]) .and. .not. c%output_dofs_given, &
                   "chain: default selection = contact and forced DOFs")
        call cli([character(len=200) :: dir//"/chain_default.nml"], code, out, err)
        call check(t, code == 0, "chain default: runs", err)
        call check(t, first_line(dir//"/chain_default/hbm.csv") == sel_header, &
                   "chain default: hbm.csv columns", first_line(dir//"/chain_default/hbm.csv"))
        call check(t, first_line(dir//"/chain_default/coefficients.csv") == &
                   "harmonic,kind,x11,x12,x40,x70,r1,r2", "chain default: coefficients.csv "// &
                   "columns", first_line(dir//"/chain_default/coefficients.csv"))

        call chain_case("chain_31", "dofs = 3, 1")
        call cli([character(len=200) :: dir//"/chain_31.nml"], code, out, err)
        call check(t, code == 0, "chain dofs = 3, 1: runs", err)
        call check(t, first_line(dir//"/chain_31/hbm.csv") == "t,x3,x1,v3,v1,r1,r2", &
                   "chain dofs = 3, 1: columns in the order given", &
                   first_line(dir//"/chain_31/hbm.csv"))
        call check(t, first_line(dir//"/chain_31/coefficients.csv") == &
                   "harmonic,kind,x3,x1,r1,r2", "chain dofs = 3, 1: coefficients.csv columns", &
                   first_line(dir//"/chain_31/coefficients.csv"))
        call check(t, has_line_starting(dir//"/chain_31/summary.nml", "dofs = 3, 1"), &
                   "chain dofs = 3, 1: echoed in summary.nml")
        call read_case(dir//"/chain_31/summary.nml", back, error)
        call check_error(t, error, "chain dofs = 3, 1: summary.nml reads back", .false.)
        if (.not. allocated(error)) call check(t, same(back%output_dofs, [3, 1]) .and. &
            back%output_dofs_given, "chain dofs = 3, 1: summary.nml gives the list")

        ! every DOF, given explicitly: the full solution
        all_dofs = "dofs = "
        do i = 1, nchain
            all_dofs = all_dofs//itoa(i)
            if (i < nchain) all_dofs = all_dofs//", "
        end do
        call chain_case("chain_all", all_dofs)
        call cli([character(len=200) :: dir//"/chain_all.nml"], code, out, err)
        call check(t, code == 0, "chain all DOFs: runs", err)
        full = read_numbers(dir//"/chain_all/hbm.csv")
        a = read_numbers(dir//"/chain_default/hbm.csv")
        b = read_numbers(dir//"/chain_31/hbm.csv")
        call check(t, size(full, 2) == 1 + 2*nchain + 2 .and. size(full, 1) == 32, &
                   "chain all DOFs: 143 columns, 32 rows")
        if (size(full, 2) /= 1 + 2*nchain + 2 .or. size(a, 2) /= 11 .or. size(b, 2) /= 7 .or. &
            size(a, 1) /= size(full, 1) .or. size(b, 1) /= size(full, 1)) then
            call check(t, .false., "chain: the three hbm.csv files have the expected shapes")
            return
        end if
        call check(t, all(a(:, 1) == full(:, 1)) .and. &
                   all(a(:, 2:5) == full(:, 1 + [11, 12, 40, 70])) .and. &
                   all(a(:, 6:9) == full(:, 1 + nchain + [11, 12, 40, 70])) .and. &
                   all(a(:, 10:11) == full(:, 2 + 2*nchain:3 + 2*nchain)), &
                   "chain default: selected columns equal the full solution's")
        call check(t, all(b(:, 2:3) == full(:, 1 + [3, 1])) .and. &
                   all(b(:, 4:5) == full(:, 1 + nchain + [3, 1])) .and. &
                   all(b(:, 6:7) == full(:, 2 + 2*nchain:3 + 2*nchain)), &
                   "chain dofs = 3, 1: columns equal the full solution's x3, x1, v3, v1, r")
        call check(t, maxval(abs(full(:, 1 + 70))) > 0.0_dp .and. &
                   maxval(abs(full(:, 1 + 3))) > 0.0_dp, "chain: the DOFs move")
        ca = read_numbers(dir//"/chain_31/coefficients.csv", 2)
        cfull = read_numbers(dir//"/chain_all/coefficients.csv", 2)
        if (size(ca, 1) == size(cfull, 1) .and. size(ca, 2) == 4 .and. &
            size(cfull, 2) == nchain + 2) then
            call check(t, all(ca(:, 1:2) == cfull(:, [3, 1])) .and. &
                       all(ca(:, 3:4) == cfull(:, nchain + 1:nchain + 2)), &
                       "chain dofs = 3, 1: coefficients equal the full solution's")
        else
            call check(t, .false., "chain: coefficients.csv shapes")
        end if

        ! with an exact reduction (every interior mode) the files hold FULL-model DOFs, named
        ! by their full numbers, with the unreduced solution's values: 3 interior, 70 contact
        call chain_case("chain_reduced", "dofs = 3, 70 / &reduction method = 'craig-bampton', "// &
                        "modes = 66")
        call read_case(dir//"/chain_reduced.nml", c, error)
        call check_error(t, error, "chain reduced, dofs = 3, 70: reads", .false.)
        if (allocated(error)) return
        call check(t, c%model%ndof == 4 + 66 .and. same(c%output_dofs, [3, 70]) .and. &
                   c%output_dofs_given, "chain reduced: 70 reduced DOFs, dofs in full numbers")
        call cli([character(len=200) :: dir//"/chain_reduced.nml"], code, out, err)
        call check(t, code == 0, "chain reduced, dofs = 3, 70: runs", err)
        call check(t, first_line(dir//"/chain_reduced/hbm.csv") == "t,x3,x70,v3,v70,r1,r2", &
                   "chain reduced: hbm.csv columns named by full numbers", &
                   first_line(dir//"/chain_reduced/hbm.csv"))
        call check(t, first_line(dir//"/chain_reduced/coefficients.csv") == &
                   "harmonic,kind,x3,x70,r1,r2", "chain reduced: coefficients.csv columns", &
                   first_line(dir//"/chain_reduced/coefficients.csv"))
        b = read_numbers(dir//"/chain_reduced/hbm.csv")
        if (size(b, 1) == size(full, 1) .and. size(b, 2) == 7) then
            call check(t, close_to(b(:, 2:3), full(:, 1 + [3, 70])) .and. &
                       close_to(b(:, 4:5), full(:, 1 + nchain + [3, 70])) .and. &
                       close_to(b(:, 6:7), full(:, 2 + 2*nchain:3 + 2*nchain)), &
                       "chain reduced: x3, x70, v3, v70, r equal the unreduced solution's")
        else
            call check(t, .false., "chain reduced: hbm.csv shape")
        end if
        ca = read_numbers(dir//"/chain_reduced/coefficients.csv", 2)
        if (size(ca, 1) == size(cfull, 1) .and. size(ca, 2) == 4) then
            call check(t, close_to(ca(:, 1:2), cfull(:, [3, 70])), &
                       "chain reduced: coefficients of x3, x70 equal the unreduced ones")
        else
            call check(t, .false., "chain reduced: coefficients.csv shape")
        end if
        call check(t, has_line_starting(dir//"/chain_reduced/summary.nml", "dofs = 3, 70"), &
                   "chain reduced: dofs echoed in full numbers")
        call read_case(dir//"/chain_reduced/summary.nml", back, error)
        call check_error(t, error, "chain reduced: summary.nml reads back", .false.)
        if (.not. allocated(error)) call check(t, same(back%output_dofs, [3, 70]) .and. &
            back%output_dofs_given .and. back%model%ndof == 70 .and. &
            back%reduction%report%full_dof == nchain, &
            "chain reduced: summary.nml gives the list and the reduction")

        ! the default with a reduction: the contact and forced DOFs, full numbers
        call chain_case("chain_reduced_default", "/ &reduction method = 'craig-bampton', "// &
                        "modes = 66")
        call cli([character(len=200) :: dir//"/chain_reduced_default.nml"], code, out, err)
        call check(t, code == 0, "chain reduced default: runs", err)
        call check(t, first_line(dir//"/chain_reduced_default/hbm.csv") == sel_header, &
                   "chain reduced default: contact and forced DOFs, full numbers", &
                   first_line(dir//"/chain_reduced_default/hbm.csv"))
        b = read_numbers(dir//"/chain_reduced_default/hbm.csv")
        if (size(b, 1) == size(full, 1) .and. size(b, 2) == 11) then
            call check(t, close_to(b(:, 2:5), full(:, 1 + [11, 12, 40, 70])) .and. &
                       close_to(b(:, 6:9), full(:, 1 + nchain + [11, 12, 40, 70])), &
                       "chain reduced default: values equal the unreduced solution's")
        else
            call check(t, .false., "chain reduced default: hbm.csv shape")
        end if

        ! a DOF beyond the full N, and an interior DOF in a sweep, rejected
        call chain_case("chain_reduced_bad", "dofs = 3, 71 / &reduction method = "// &
                        "'craig-bampton', modes = 66")
        call read_case(dir//"/chain_reduced_bad.nml", c, error)
        call check_error(t, error, "chain reduced, dofs = 3, 71: rejected", .true., &
                         [character(len=60) :: "&output dofs(2) = 71", "1..70"])
        ! a sweep of the reduced chain writes the amplitudes of the selected full-model
        ! DOFs, interior ones too: those of the unreduced sweep (exact reduction)
        call chain_case("chain_sweep_full", "dofs = 70, 3 / &sweep start = 1.2, stop = 1.4, "// &
                        "stability = F, truncation = F, max_points = 12")
        call cli([character(len=200) :: dir//"/chain_sweep_full.nml"], code, out, err)
        ! max_points = 12 stops the curve short (fast): exit 2 with the points computed
        call check(t, code == 2 .and. index(err, "stopped at max_points") > 0, &
                   "chain sweep unreduced: 12 points, stopped at max_points", err)
        call chain_case("chain_reduced_sweep", "dofs = 70, 3 / &reduction method = "// &
                        "'craig-bampton', modes = 66 / &sweep start = 1.2, stop = 1.4, "// &
                        "stability = F, truncation = F, max_points = 12")
        call cli([character(len=200) :: dir//"/chain_reduced_sweep.nml"], code, out, err)
        call check(t, code == 2 .and. index(err, "stopped at max_points") > 0, &
                   "chain reduced sweep: 12 points, stopped at max_points", err)
        call check(t, index(first_line(dir//"/chain_reduced_sweep/frc.csv"), &
                            ",amp_70,amp_3,") > 0, "chain reduced sweep: amp_70, amp_3 columns", &
                   first_line(dir//"/chain_reduced_sweep/frc.csv"))
        a = read_numbers(dir//"/chain_sweep_full/frc.csv", keep=3)
        b = read_numbers(dir//"/chain_reduced_sweep/frc.csv", keep=3)
        if (all(shape(a) == shape(b)) .and. size(a, 1) > 3) then
            call check(t, close_to(b(:, 1:1), a(:, 1:1)) .and. &
                       maxval(abs(b(:, 2:3) - a(:, 2:3))) <= 1.0e-7_dp*maxval(abs(a(:, 2:3))), &
                       "chain reduced sweep: amplitudes of DOFs 70 and 3 = unreduced sweep's")
        else
            call check(t, .false., "chain reduced sweep: frc.csv shapes", &
                       itoa(size(a, 1))//"x"//itoa(size(a, 2))//" vs "//itoa(size(b, 1))// &
                       "x"//itoa(size(b, 2)))
        end if
        ! method 'all' on a reduced model compares the selected full-model DOFs
        call chain_case("chain_reduced_all", "dofs = 3, 70 / &reduction method = "// &
                        "'craig-bampton', modes = 4 / &run method = 'all'")
        call cli([character(len=200) :: dir//"/chain_reduced_all.nml"], code, out, err)
        call check(t, code == 0, "chain reduced, method all: trusted (exit 0)", err)
        call check(t, has_line_starting(dir//"/chain_reduced_all/summary.nml", &
                                        "quantities = 'x3', 'x70', 'v3', 'v70', 'r1', 'r2'"), &
                   "chain reduced, method all: compares x3, x70 (full numbers)")
        ! too few modes: the measured reduction error is reported as a warning (stderr and
        ! summary), the run still exits 0
        call chain_case("chain_reduced_err", "dofs = 3, 70 / &reduction method = "// &
                        "'craig-bampton', modes = 1")
        call cli([character(len=200) :: dir//"/chain_reduced_err.nml"], code, out, err)
        call check(t, code == 0 .and. index(err, "stickslip: warning: reduction: the "// &
                   "measured error") > 0, "chain reduced, 1 mode: reduction error warning", err)
        call check(t, has_line_starting(dir//"/chain_reduced_err/summary.nml", &
                                        "warning_reduction_error = "), &
                   "chain reduced, 1 mode: warning_reduction_error in summary.nml")
        ! a study of the reduced chain: the listed DOFs are boundary DOFs, so it compares them
        call chain_case("chain_reduced_study", "dofs = 70, 3 / &reduction method = "// &
                        "'craig-bampton', modes = 10 / &study harmonics = 3, 5")
        call read_case(dir//"/chain_reduced_study.nml", c, error)
        call check_error(t, error, "chain reduced study, dofs = 70, 3: reads", .false.)
        if (.not. allocated(error)) call check(t, all(c%reduction%output_reduced > 0) .and. &
            c%reduction%report%boundary_dof == 5 .and. c%model%ndof == 15, &
            "chain reduced study: DOF 3 is a boundary DOF (5 boundary + 10 modes)")

    contains

        subroutine chain_case(name, output)
            character(len=*), intent(in) :: name, output
            character(len=400) :: lines(5)
            lines(1) = "&system mass_file = 'chain_m.mtx', stiffness_file = 'chain_k.mtx', "// &
                       "rayleigh_alpha = 0.05, rayleigh_beta = 0.002 /"
            lines(2) = "&forcing omega = 1.3, force_dof = 40, force_amplitude = 5.0 /"
            lines(3) = "&friction contact_dof = 70, 12, contact_dof2 = 0, 11, mu = 0.5, 0.3, "// &
                       "normal_load = 1.0, 0.5 /"
            lines(4) = "&hbm harmonics = 5, samples = 32 /"
            lines(5) = "&output directory = '"//dir//"/"//name//"' "//output//" /"
            call write_lines(dir//"/"//name//".nml", lines)
        end subroutine chain_case
    end subroutine test_chain

    !> &output full_field on the 70-DOF chain (after test_chain, whose chain_all run holds
    !> every DOF's coefficients): unreduced, full_field.mtx is coefficients.csv transposed
    !> (70 x nb, the same digits); reduced exactly (every interior mode) the recovered field
    !> equals it to 1e-9; reduced with 10 modes it differs (the recovery uses the basis, not
    !> the unreduced values) but by less than 5% at the largest entry; removed by a run
    !> without it; refused with another method.
    subroutine test_full_field(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err
        type(error_type), allocatable :: error
        real(dp), allocatable :: cfull(:, :), f(:, :), fr(:, :), f10(:, :)
        type(case_t) :: c
        integer :: code
        logical :: there
        cfull = read_numbers(dir//"/chain_all/coefficients.csv", 2)
        call full_case("full_plain", "")
        call cli([character(len=200) :: dir//"/full_plain.nml"], code, out, err)
        call check(t, code == 0, "full field unreduced: runs", err)
        call read_field(dir//"/full_plain/full_field.mtx", f)
        call check(t, first_line(dir//"/full_plain/full_field.mtx") == &
                   "%%MatrixMarket matrix array real general", "full field: Matrix Market header")
        if (size(f, 1) /= nchain .or. size(cfull, 2) < nchain .or. &
            size(f, 2) /= size(cfull, 1)) then
            call check(t, .false., "full field unreduced: 70 x nb", itoa(size(f, 1))//" x "// &
                       itoa(size(f, 2)))
            return
        end if
        call check(t, all(f == transpose(cfull(:, 1:nchain))), &
                   "full field unreduced: equals coefficients.csv of every DOF")
        call full_case("full_exact", "/ &reduction method = 'craig-bampton', modes = 66")
        call cli([character(len=200) :: dir//"/full_exact.nml"], code, out, err)
        call check(t, code == 0, "full field exact reduction: runs", err)
        call read_field(dir//"/full_exact/full_field.mtx", fr)
        call check(t, same_shape(fr, f), "full field exact reduction: 70 x nb")
        if (same_shape(fr, f)) call check(t, close_to(fr, f), &
                                          "full field exact reduction: equals the unreduced one")
        call full_case("full_10", "/ &reduction method = 'craig-bampton', modes = 10")
        call cli([character(len=200) :: dir//"/full_10.nml"], code, out, err)
        call check(t, code == 0, "full field 10 modes: runs", err)
        call read_field(dir//"/full_10/full_field.mtx", f10)
        call check(t, same_shape(f10, f), "full field 10 modes: 70 x nb")
        if (same_shape(f10, f)) call check(t, .not. close_to(f10, f) .and. &
            maxval(abs(f10 - f)) < 0.05_dp*maxval(abs(f)), &
            "full field 10 modes: near the unreduced one, not equal")
        ! a distributed load (force_file: load vectors in the basis): the full field at the
        ! output DOFs equals the coefficients recovered for coefficients.csv (two paths)
        block
            real(dp) :: shape_f(nchain, 1)
            real(dp), allocatable :: cl(:, :), fl(:, :)
            integer :: i
            shape_f(:, 1) = [(0.1_dp*i, i=1, nchain)]
            call write_matrix_market_array(dir//"/chain_f.mtx", shape_f, .false., error)
            call check_error(t, error, "full field with loads: file written", .false.)
            call full_case("full_loads", "dofs = 3, 70 / &reduction method = "// &
                           "'craig-bampton', modes = 10", loads=.true.)
            call cli([character(len=200) :: dir//"/full_loads.nml"], code, out, err)
            call check(t, code == 0, "full field with loads: runs", err)
            call check(t, has_line_starting(dir//"/full_loads/summary.nml", &
                                            "reduction_load_vectors = 1"), &
                       "full field with loads: one load vector")
            call read_field(dir//"/full_loads/full_field.mtx", fl)
            cl = read_numbers(dir//"/full_loads/coefficients.csv", 2)
            if (size(fl, 1) == nchain .and. size(cl, 2) >= 2 .and. &
                size(fl, 2) == size(cl, 1)) then
                call check(t, maxval(abs(fl([3, 70], :) - transpose(cl(:, 1:2)))) <= &
                           1.0e-12_dp*maxval(abs(cl(:, 1:2))), &
                           "full field with loads: = recovered coefficients of x3, x70")
            else
                call check(t, .false., "full field with loads: shapes")
            end if
        end block
        ! a later run without full_field into the same directory removes the stale file
        call full_case("full_10", "/ &reduction method = 'craig-bampton', modes = 10", .false.)
        call cli([character(len=200) :: dir//"/full_10.nml"], code, out, err)
        inquire (file=dir//"/full_10/full_field.mtx", exist=there)
        call check(t, .not. there, "full field: a run without it removes the stale file")
        call full_case("full_sweep", "/ &sweep start = 1, stop = 2")
        call read_case(dir//"/full_sweep.nml", c, error)
        call check_error(t, error, "full field with a sweep: rejected", .true., &
                         [character(len=60) :: "&output full_field", "method = 'hbm'"])

    contains

        subroutine full_case(name, extra, wanted, loads)
            character(len=*), intent(in) :: name, extra
            logical, intent(in), optional :: wanted, loads
            character(len=400) :: lines(5)
            character(len=20) :: flag
            flag = "full_field = T"
            if (present(wanted)) then
                if (.not. wanted) flag = ""
            end if
            lines(1) = "&system mass_file = 'chain_m.mtx', stiffness_file = 'chain_k.mtx', "// &
                       "rayleigh_alpha = 0.05, rayleigh_beta = 0.002 /"
            lines(2) = "&forcing omega = 1.3, force_dof = 40, force_amplitude = 5.0 /"
            lines(3) = "&friction contact_dof = 70, 12, contact_dof2 = 0, 11, mu = 0.5, 0.3, "// &
                       "normal_load = 1.0, 0.5 /"
            lines(4) = "&hbm harmonics = 5, samples = 32 /"
            lines(5) = "&output directory = '"//dir//"/"//name//"' "//trim(flag)//" "// &
                       extra//" /"
            if (present(loads)) then
                if (loads) lines(2) = "&forcing omega = 1.3, force_file = 'chain_f.mtx', "// &
                                      "force_amplitude = 5.0 /"
            end if
            call write_lines(dir//"/"//name//".nml", lines)
        end subroutine full_case

        subroutine read_field(path, a)
            character(len=*), intent(in) :: path
            real(dp), allocatable, intent(out) :: a(:, :)
            type(sparse_matrix_t) :: s
            type(error_type), allocatable :: e
            call read_matrix_market(path, s, e)
            if (.not. allocated(e)) call sparse_to_dense(s, a, e)
            call check_error(t, e, "full field: "//path//" reads", .false.)
            if (.not. allocated(a)) allocate (a(0, 0))
        end subroutine read_field

        logical function same_shape(a, b)
            real(dp), intent(in) :: a(:, :), b(:, :)
            same_shape = all(shape(a) == shape(b))
        end function same_shape
    end subroutine test_full_field

    !> The truncation estimate of a reduced model judges the output DOFs: with every interior
    !> mode kept (exact reduction), its displacement changes of DOFs 3 and 70 equal those of
    !> the unreduced chain at DOFs 3 and 70, and it has one entry per output DOF.
    subroutine test_truncation_observed(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: full, red
        type(hbm_solution_t) :: sf, sr
        type(hbm_checks_t) :: cf, cr
        type(error_type), allocatable :: error
        call read_case(dir//"/chain_all.nml", full, error)
        if (.not. allocated(error)) call read_case(dir//"/chain_reduced.nml", red, error)
        call check_error(t, error, "truncation observed: cases read", .false.)
        if (allocated(error)) return
        call solve_and_check(full%model, full%hbm, full%checks, &
                             full%reference%reference_options_t, sf, cf, error)
        if (.not. allocated(error)) call solve_and_check(red%model, red%hbm, red%checks, &
            red%reference%reference_options_t, sr, cr, error)
        call check_error(t, error, "truncation observed: both solve", .false.)
        if (allocated(error)) return
        call check(t, size(cr%truncation%displacement_change_rel) == 2 .and. &
                   size(cf%truncation%displacement_change_rel) == nchain, &
                   "truncation observed: one entry per output DOF (reduced), per DOF (full)")
        if (size(cr%truncation%displacement_change_rel) /= 2) return
        call check(t, maxval(abs(cr%truncation%displacement_change_rel - &
                                 cf%truncation%displacement_change_rel([3, 70]))) <= &
                   1.0e-6_dp*maxval(cf%truncation%displacement_change_rel([3, 70])), &
                   "truncation observed: exact reduction = unreduced changes at DOFs 3, 70")
    end subroutine test_truncation_observed

    !> The seed case with dofs = 2: hbm.csv, euler.csv, reference.csv (method 'all') and
    !> study.csv hold x2, v2 only (and every contact force).
    subroutine test_seed_selected(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err
        integer :: code
        character(len=*), parameter :: all_dir = dir//"/seed_all", study_dir = dir//"/seed_study"
        call write_lines(dir//"/seed_all.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 10, samples = 64 /", &
            "&run method = 'all' /", "&euler steps_per_period = 200 /", &
            "&reference samples = 50 /", "&output directory = '"//all_dir//"', dofs = 2 /"])
        call cli([character(len=200) :: dir//"/seed_all.nml"], code, out, err)
        call check(t, code == 0, "seed dofs = 2, method all: runs", err)
        call check(t, first_line(all_dir//"/hbm.csv") == "t,x2,v2,r1", &
                   "seed dofs = 2: hbm.csv", first_line(all_dir//"/hbm.csv"))
        call check(t, first_line(all_dir//"/euler.csv") == "t,x2,v2,r1", &
                   "seed dofs = 2: euler.csv", first_line(all_dir//"/euler.csv"))
        call check(t, first_line(all_dir//"/reference.csv") == "t,x2,v2,r1", &
                   "seed dofs = 2: reference.csv", first_line(all_dir//"/reference.csv"))
        call check(t, size(read_numbers(all_dir//"/reference.csv"), 2) == 4, &
                   "seed dofs = 2: reference.csv rows have 4 values")
        call write_lines(dir//"/seed_study.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 10, samples = 64 /", &
            "&run method = 'study' /", "&study harmonics = 5, samples = 0, " // &
            "steps_per_period = 200, repeats = 1 /", &
            "&output directory = '"//study_dir//"', dofs = 2 /"])
        call cli([character(len=200) :: dir//"/seed_study.nml"], code, out, err)
        call check(t, code == 0, "seed dofs = 2, method study: runs", err)
        call check(t, first_line(study_dir//"/study.csv") == &
                   "method,parameter,samples,converged,cpu_seconds,repeats,iterations,"// &
                   "err_x,err_v,err_r,rms_x,rms_v,rms_r,err_x2,err_v2,err_r1", &
                   "seed dofs = 2: study.csv header", first_line(study_dir//"/study.csv"))
    end subroutine test_seed_selected

    !> frc.csv and frc.gp: amp_<d> for the DOFs selected, in their order, with the values of
    !> those DOFs; the sweep of the seed case with dofs = 2 through the command line.
    subroutine test_frc(t)
        type(test_counter_t), intent(inout) :: t
        type(sweep_result_t) :: res
        type(error_type), allocatable :: error
        character(len=:), allocatable :: out, err, script
        real(dp), allocatable :: v(:, :)
        integer :: k, code
        character(len=*), parameter :: frc_dir = dir//"/frc_unit", sweep_dir = dir//"/seed_sweep"
        call make_directory(frc_dir, error)
        if (allocated(error)) return
        res%npoints = 2
        allocate (res%points(2))
        do k = 1, 2
            res%points(k)%parameter = real(k, dp)
            res%points(k)%amplitude = [1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp]*k
            res%points(k)%rmax = [0.5_dp]
            res%points(k)%stick = [0.25_dp]
            res%points(k)%status = 'ok'
        end do
        call write_frc_csv(frc_dir, res, error, [4, 2])
        call check_error(t, error, "frc unit: written", .false.)
        if (allocated(error)) return
        call check(t, first_line(frc_dir//"/frc.csv") == "parameter,amp_4,amp_2,dissipation,"// &
                   "rmax_1,stick_1,harmonics,residual,status,floquet_max,stable,truncation,"// &
                   "arclength,diss_friction,diss_damping,nfev,omega,frequency,vib_4,vib_2,h1_4,h1_2,"// &
                   "trusted,check", &
                   "frc unit: header", &
                   first_line(frc_dir//"/frc.csv"))
        v = read_numbers(frc_dir//"/frc.csv", 0, 3)
        call check(t, size(v, 1) == 2, "frc unit: two rows")
        if (size(v, 1) == 2) call check(t, all(v(:, 2) == [4.0_dp, 8.0_dp]) .and. &
            all(v(:, 3) == [2.0_dp, 4.0_dp]), "frc unit: amp_4, amp_2 values")
        call write_frc_plot_script(frc_dir, "omega", 5, error, [4, 2])
        call check_error(t, error, "frc unit: frc.gp written", .false.)
        if (allocated(error)) return
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "title 'DOF 4'") > 0 .and. index(script, "title 'DOF 2'") > 0 &
                   .and. index(script, "DOF 1") == 0 .and. index(script, "DOF 3") == 0 .and. &
                   index(script, "DOF 5") == 0 .and. &
                   index(script, "do for [name in 'vib_4 vib_2']") > 0 .and. &
                   index(script, "column('vib_4')") > 0 .and. &
                   index(script, "column('vib_2')") > 0 .and. index(script, "vib_1") == 0 .and. &
                   index(script, "amp_") == 0, &
                   "frc unit: frc.gp draws vib_4, vib_2 only (the vibration amplitude by default)")
        call write_frc_plot_script(frc_dir, "omega", 5, error, [4, 2], amplitude='max_abs')
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "column('amp_4')") > 0 .and. index(script, "vib_") == 0 &
                   .and. index(script, "max_t |x(t)|") > 0, &
                   "frc unit: plot_amplitude 'max_abs' draws amp_4, amp_2")
        call write_frc_plot_script(frc_dir, "omega", 5, error, [4, 2], amplitude='first_harmonic')
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "column('h1_2')") > 0 .and. index(script, "vib_") == 0, &
                   "frc unit: plot_amplitude 'first_harmonic' draws h1_4, h1_2")
        ! an mm-t-s model on a Hz axis: the labels name its units, the x column is frequency
        call write_frc_plot_script(frc_dir, "omega", 5, error, [4, 2], &
                                   units=plot_units_t(length='mm', force='N', time='s', &
                                                      cycles=.true.))
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "/ 2 [mm]'") > 0 .and. index(script, "[N mm]'") > 0 .and. &
                   index(script, "omega / 2 pi [Hz]'") > 0 .and. &
                   index(script, "using (column('frequency')):(column('vib_4'))") > 0 .and. &
                   index(script, "[m]") == 0 .and. index(script, "[J]") == 0, &
                   "frc unit: an mm-t-s model's labels in mm, N mm and Hz")
        call write_frc_plot_script(frc_dir, "preload", 5, error, [4, 2], &
                                   units=plot_units_t(length='mm', force='kN', time='ms', &
                                                      cycles=.true.))
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "contacts [kN]'") > 0 .and. index(script, "[kN mm]'") > 0 &
                   .and. index(script, "using 1:(column('vib_4'))") > 0, &
                   "frc unit: a preload sweep in kN keeps the parameter on x")
        ! a backbone of an mm-t-s model on a Hz axis: modes.csv's frequency, the limits in Hz
        call write_modes_plot_script(frc_dir, 1, 62.83185307179586_dp, 31.41592653589793_dp, &
                                     error, plot_units_t(length='mm', force='N', time='s', &
                                                         cycles=.true.))
        script = slurp_file(frc_dir//"/modes.gp")
        call check(t, index(script, "plot f using 1:3 ") > 0 .and. &
                   index(script, "omega / 2 pi [Hz]'") > 0 .and. &
                   index(script, "/(2*pi); w_slip") > 0 .and. &
                   index(script, "[mm sqrt(t)]'") > 0 .and. index(script, "rad/s") == 0, &
                   "modes unit: an mm-t-s backbone in Hz and mm sqrt(t)")
        call write_modes_plot_script(frc_dir, 1, 62.83185307179586_dp, 31.41592653589793_dp, &
                                     error)
        script = slurp_file(frc_dir//"/modes.gp")
        call check(t, index(script, "plot f using 1:2 ") > 0 .and. &
                   index(script, "frequency omega [rad/s]'") > 0 .and. &
                   index(script, "[m sqrt(kg)]'") > 0, "modes unit: SI by default, omega in rad/s")
        ! without stability: no unstable points named; the key beside the plot; 1-2-5 labels
        call write_frc_plot_script(frc_dir, "omega", 5, error, [4, 2], stability=.false.)
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "title 'unstable'") == 0 .and. &
                   index(script, "(unstable(") == 0 .and. &
                   index(script, "stability not computed") > 0 .and. &
                   index(script, "outside right top") > 0 .and. &
                   index(script, "set ytics add (sprintf('%g', v) v)") > 0 .and. &
                   index(script, "set xtics add (sprintf('%g', v) v)") > 0, &
                   "frc unit: without stability no unstable points; key outside; decade labels")
        call write_frc_plot_script(frc_dir, "omega", 5, error, [4, 2])
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "title 'unstable'") > 0 .and. &
                   index(script, "stability not computed") == 0, &
                   "frc unit: with stability the unstable points drawn and named")
        ! labels (a reduced model: reduced DOFs 4, 2 are full DOFs 70, 40)
        call write_frc_csv(frc_dir, res, error, [4, 2], [70, 40])
        call check_error(t, error, "frc unit, labels: written", .false.)
        if (allocated(error)) return
        call check(t, index(first_line(frc_dir//"/frc.csv"), "parameter,amp_70,amp_40,"// &
                   "dissipation,") == 1, "frc unit, labels: header", first_line(frc_dir//"/frc.csv"))
        v = read_numbers(frc_dir//"/frc.csv", 0, 3)
        if (size(v, 1) == 2) call check(t, all(v(:, 2) == [4.0_dp, 8.0_dp]) .and. &
            all(v(:, 3) == [2.0_dp, 4.0_dp]), "frc unit, labels: values of DOFs 4, 2")
        call write_frc_plot_script(frc_dir, "omega", 5, error, [4, 2], [70, 40])
        call check_error(t, error, "frc unit, labels: frc.gp written", .false.)
        if (allocated(error)) return
        script = slurp_file(frc_dir//"/frc.gp")
        call check(t, index(script, "title 'full-model DOF 70'") > 0 .and. &
                   index(script, "title 'full-model DOF 40'") > 0 .and. &
                   index(script, "DOF 4'") == 0, &
                   "frc unit, labels: frc.gp titles full-model DOF 70, 40")

        call write_lines(dir//"/seed_sweep.nml", [character(len=120) :: sweep_case, &
            "&output directory = '"//sweep_dir//"', dofs = 2 /"])
        call cli([character(len=200) :: dir//"/seed_sweep.nml"], code, out, err)
        call check(t, code == 0, "seed sweep dofs = 2: exit 0", err)
        call check(t, first_line(sweep_dir//"/frc.csv") == "parameter,amp_2,dissipation,"// &
                   "rmax_1,stick_1,harmonics,residual,status,floquet_max,stable,truncation,"// &
                   "arclength,diss_friction,diss_damping,nfev,omega,frequency,vib_2,h1_2,trusted,check", &
                   "seed sweep dofs = 2: frc.csv "// &
                   "header", first_line(sweep_dir//"/frc.csv"))
        script = slurp_file(sweep_dir//"/frc.gp")
        call check(t, index(script, "title 'DOF 2'") > 0 .and. index(script, "DOF 1") == 0, &
                   "seed sweep dofs = 2: frc.gp draws amp_2 only")
    end subroutine test_frc

    !> dofs = 0, above N, repeated: errors (stat input) naming the file and &output dofs(k).
    subroutine test_bad_dofs(t)
        type(test_counter_t), intent(inout) :: t
        call bad("1, 0", "&output dofs(2) = 0")
        call bad("3", "&output dofs(1) = 3")
        call bad("2, 1, 2", "&output dofs(3) = 2")
        call bad("-1", "&output dofs(1) = -1")
        call bad("1.5", "&output dofs")

    contains

        subroutine bad(list, what)
            character(len=*), intent(in) :: list, what
            type(case_t) :: c
            type(error_type), allocatable :: error
            call write_lines(dir//"/bad.nml", [character(len=120) :: good_system, good_forcing, &
                good_friction, "&output dofs = "//list//" /"])
            call read_case(dir//"/bad.nml", c, error)
            call check(t, allocated(error), "bad dofs = "//list//": rejected")
            if (.not. allocated(error)) return
            call check(t, error%stat == stickslip_stat%input .and. &
                       index(error%message, dir//"/bad.nml") == 1 .and. &
                       index(error%message, what) > 0, "bad dofs = "//list//": names "//what, &
                       error%message)
        end subroutine bad
    end subroutine test_bad_dofs

    !> Write the 70-DOF chain: M = diag(1 + 0.01 i), K tridiagonal (springs of 100 between
    !> neighbours and to the ground at DOF 1), as symmetric coordinate Matrix Market files.
    subroutine write_chain(error)
        type(error_type), allocatable, intent(out) :: error
        type(sparse_matrix_t) :: m, k
        integer, allocatable :: r(:), c(:)
        real(dp), allocatable :: v(:)
        integer :: i
        call new_sparse_from_triplets(m, nchain, nchain, [(i, i=1, nchain)], &
                                      [(i, i=1, nchain)], [(1.0_dp + 0.01_dp*i, i=1, nchain)], &
                                      error)
        if (allocated(error)) return
        call write_matrix_market(dir//"/chain_m.mtx", m, .true., error)
        if (allocated(error)) return
        r = [(i, i=1, nchain), (i + 1, i=1, nchain - 1), (i, i=1, nchain - 1)]
        c = [(i, i=1, nchain), (i, i=1, nchain - 1), (i + 1, i=1, nchain - 1)]
        v = [(200.0_dp, i=1, nchain - 1), 100.0_dp, (-100.0_dp, i=1, 2*(nchain - 1))]
        call new_sparse_from_triplets(k, nchain, nchain, r, c, v, error)
        if (allocated(error)) return
        call write_matrix_market(dir//"/chain_k.mtx", k, .true., error)
    end subroutine write_chain

    !> a and b agree to 1e-9 of the largest |b| (two converged solves of the same problem).
    logical function close_to(a, b)
        real(dp), intent(in) :: a(:, :), b(:, :)
        close_to = maxval(abs(a - b)) <= 1.0e-9_dp*max(maxval(abs(b)), tiny(1.0_dp))
    end function close_to

    logical function same(a, b)
        integer, allocatable, intent(in) :: a(:)
        integer, intent(in) :: b(:)
        same = .false.
        if (.not. allocated(a)) return
        if (size(a) /= size(b)) return
        same = all(a == b)
    end function same


    !> The whole text of a file ('' when it cannot be read).
    function slurp_file(path) result(text)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: text
        character(len=4000) :: buf
        integer :: u, stat
        text = ''
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        do
            read (u, '(a)', iostat=stat) buf
            if (stat /= 0) exit
            text = text//trim(buf)//new_line('a')
        end do
        close (u)
    end function slurp_file

    !> A line of the file that starts (after blanks) with `start`.
    logical function has_line_starting(path, start)
        character(len=*), intent(in) :: path, start
        character(len=4000) :: buf
        integer :: u, stat
        has_line_starting = .false.
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        do
            read (u, '(a)', iostat=stat) buf
            if (stat /= 0) exit
            if (index(adjustl(buf), start) == 1) then
                has_line_starting = .true.
                exit
            end if
        end do
        close (u)
    end function has_line_starting

    !> The numbers of a CSV file with a header, rows x columns, skipping `skip` leading fields
    !> of each row and keeping at most `keep` fields (0 x 0 on failure).
    function read_numbers(path, skip, keep) result(a)
        character(len=*), intent(in) :: path
        integer, intent(in), optional :: skip, keep
        real(dp), allocatable :: a(:, :)
        character(len=20000) :: buf
        character(len=:), allocatable :: line
        integer :: u, stat, rows, cols, k, s, i
        allocate (a(0, 0))
        s = 0
        if (present(skip)) s = skip
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        read (u, '(a)', iostat=stat) buf
        cols = count_commas(trim(buf)) + 1 - s
        if (present(keep)) cols = min(cols, keep)
        rows = 0
        do
            read (u, '(a)', iostat=stat) buf
            if (stat /= 0) exit
            rows = rows + 1
        end do
        deallocate (a)
        allocate (a(rows, cols))
        rewind (u)
        read (u, '(a)') buf
        do k = 1, rows
            read (u, '(a)') buf
            line = trim(buf)
            do i = 1, s
                line = line(index(line, ",") + 1:)
            end do
            read (line, *, iostat=stat) a(k, :)
            if (stat /= 0) then
                deallocate (a)
                allocate (a(0, 0))
                exit
            end if
        end do
        close (u)
    end function read_numbers

end module test_output_selection
