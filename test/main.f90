!> The one test driver: runs every suite (or the suites named on the command line,
!> `fpm test -- basis hbm`) and ends with the line "N passed, N failed".
program tester
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use testing, only: test_counter_t
    use test_basis, only: run_basis_tests
    use test_hbm, only: run_hbm_tests
    use test_case, only: run_case_tests
    use test_euler, only: run_euler_tests
    use test_exact_reference, only: run_exact_reference_tests
    use test_stability, only: run_stability_tests
    use test_stiff_flow, only: run_stiff_flow_tests
    use test_robustness, only: run_robustness_tests
    use test_continuation, only: run_continuation_tests
    use test_factorizations, only: run_factorizations_tests
    use test_sweep_files, only: run_sweep_file_tests
    use test_truncation, only: run_truncation_tests
    use test_namelist, only: run_namelist_tests
    use test_openmp, only: run_openmp_tests
    use test_version_info, only: run_version_info_tests
    use test_friction, only: run_friction_tests
    use test_contact_law, only: run_contact_law_tests
    use test_contact_case, only: run_contact_case_tests
    use test_file_faults, only: run_file_faults_tests
    use test_fft, only: run_fft_tests
    use test_expm, only: run_expm_tests
    use test_lapack, only: run_lapack_tests
    use test_compare, only: run_compare_tests
    use test_diagnostics, only: run_diagnostics_tests
    use test_error, only: run_error_tests
    use test_minpack, only: run_minpack_tests
    use test_cli, only: run_cli_tests
    use test_api, only: run_api_tests
    use test_trust, only: run_trust_tests
    use test_case_messages, only: run_case_messages_tests
    use test_fuzz, only: run_fuzz_tests
    use test_umfpack, only: run_umfpack_tests
    use test_reduction, only: run_reduction_tests
    use test_arpack, only: run_arpack_tests
    use test_sparse, only: run_sparse_tests
    use test_matrix_market, only: run_matrix_market_tests
    use test_system_files, only: run_system_files_tests
    use test_output_selection, only: run_output_selection_tests
    use test_directions, only: run_directions_tests
    use test_sparse_none, only: run_sparse_none_tests
    use test_calculix, only: run_calculix_tests
    use test_solver, only: run_solver_tests
    use test_csv_format, only: run_csv_format_tests
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    type(test_counter_t) :: t
    integer :: n, i, ran
    character(len=64), allocatable :: wanted(:)
    ! deterministic random points for the finite-difference and basis checks
    call random_seed(size=n)
    call random_seed(put=[(20261122 + 7919*i, i=1, n)])
    allocate (wanted(command_argument_count()))
    do i = 1, size(wanted)
        call get_command_argument(i, wanted(i))
    end do
    ! as the stickslip program does: one BLAS thread (OpenBLAS's pthreads build)
    call limit_blas_threads()
    ran = 0
    if (selected("basis")) call run_basis_tests(t)
    if (selected("hbm")) call run_hbm_tests(t)
    if (selected("case")) call run_case_tests(t)
    if (selected("euler")) call run_euler_tests(t)
    if (selected("exact_reference")) call run_exact_reference_tests(t)
    if (selected("stability")) call run_stability_tests(t)
    if (selected("stiff_flow")) call run_stiff_flow_tests(t)
    if (selected("robustness")) call run_robustness_tests(t)
    if (selected("continuation")) call run_continuation_tests(t)
    if (selected("factorizations")) call run_factorizations_tests(t)
    if (selected("sweep_files")) call run_sweep_file_tests(t)
    if (selected("truncation")) call run_truncation_tests(t)
    if (selected("namelist")) call run_namelist_tests(t)
    if (selected("openmp")) call run_openmp_tests(t)
    if (selected("version_info")) call run_version_info_tests(t)
    if (selected("friction")) call run_friction_tests(t)
    if (selected("contact_law")) call run_contact_law_tests(t)
    if (selected("contact_case")) call run_contact_case_tests(t)
    if (selected("file_faults")) call run_file_faults_tests(t)
    if (selected("fft")) call run_fft_tests(t)
    if (selected("expm")) call run_expm_tests(t)
    if (selected("lapack")) call run_lapack_tests(t)
    if (selected("compare")) call run_compare_tests(t)
    if (selected("diagnostics")) call run_diagnostics_tests(t)
    if (selected("error")) call run_error_tests(t)
    if (selected("minpack")) call run_minpack_tests(t)
    if (selected("cli")) call run_cli_tests(t)
    if (selected("api")) call run_api_tests(t)
    if (selected("case_messages")) call run_case_messages_tests(t)
    if (selected("trust")) call run_trust_tests(t)
    if (selected("fuzz")) call run_fuzz_tests(t)
    if (selected("umfpack")) call run_umfpack_tests(t)
    if (selected("reduction")) call run_reduction_tests(t)
    if (selected("arpack")) call run_arpack_tests(t)
    if (selected("sparse")) call run_sparse_tests(t)
    if (selected("matrix_market")) call run_matrix_market_tests(t)
    if (selected("system_files")) call run_system_files_tests(t)
    if (selected("output_selection")) call run_output_selection_tests(t)
    if (selected("directions")) call run_directions_tests(t)
    if (selected("sparse_none")) call run_sparse_none_tests(t)
    if (selected("calculix")) call run_calculix_tests(t)
    if (selected("solver")) call run_solver_tests(t)
    if (selected("csv_format")) call run_csv_format_tests(t)
    if (ran < size(wanted) .or. ran == 0) then
        write (error_unit, '(a)') "tester: unknown suite name among the arguments"
        t%failed = t%failed + 1
    end if
    write (output_unit, '(i0," passed, ",i0," failed")') t%passed, t%failed
    if (t%failed > 0) error stop 1

contains

    !> Whether the suite `name` runs: all run when no names are given.
    logical function selected(name)
        character(len=*), intent(in) :: name
        if (size(wanted) == 0) then
            selected = .true.
            ran = ran + 1
        else
            selected = any(wanted == name)
            if (selected) ran = ran + 1
        end if
    end function selected
end program tester
