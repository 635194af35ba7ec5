!> The one test driver: runs every suite (or the suites named on the command line,
!> `fpm test -- basis hbm`) and ends with the line "N passed, N failed". Each suite is one
!> entry of the `suites` list (its name and its run procedure; mctc-lib's collect pattern);
!> an unknown name on the command line is an error that lists the known ones.
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
    use test_contact_hbm, only: run_contact_hbm_tests
    use test_contact_euler, only: run_contact_euler_tests
    use test_contact_reference, only: run_contact_reference_tests
    use test_contact_sweep, only: run_contact_sweep_tests
    use test_modes, only: run_modes_tests
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
    use test_cholmod, only: run_cholmod_tests
    use test_reduction, only: run_reduction_tests
    use test_reduction_estimate, only: run_reduction_estimate_tests
    use test_reduction_cache, only: run_reduction_cache_tests
    use test_arpack, only: run_arpack_tests
    use test_block_lanczos, only: run_block_lanczos_tests
    use test_sparse, only: run_sparse_tests
    use test_matrix_market, only: run_matrix_market_tests
    use test_decimal, only: run_decimal_tests
    use test_system_files, only: run_system_files_tests
    use test_output_selection, only: run_output_selection_tests
    use test_directions, only: run_directions_tests
    use test_sparse_none, only: run_sparse_none_tests
    use test_calculix, only: run_calculix_tests
    use test_solver, only: run_solver_tests
    use test_csv_format, only: run_csv_format_tests
    use test_jenkins, only: run_jenkins_tests
    use test_microslip, only: run_microslip_tests
    use test_reference_2d, only: run_reference_2d_tests
    use test_impacts_2d, only: run_impacts_2d_tests
    use test_fallback, only: run_fallback_tests
    use test_family, only: run_family_tests
    use test_cyclic, only: run_cyclic_tests
    use test_cyclic_fe, only: run_cyclic_fe_tests
    use test_cyclic_modes, only: run_cyclic_modes_tests
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none

    abstract interface
        !> A suite: runs its tests, counting them in t.
        subroutine run_suite(t)
            import :: test_counter_t
            type(test_counter_t), intent(inout) :: t
        end subroutine run_suite
    end interface

    !> A suite of the driver: its name (the command-line argument) and its procedure.
    type :: suite_t
        character(len=24) :: name = ''
        procedure(run_suite), pointer, nopass :: run => null()
    end type suite_t

    type(suite_t), allocatable :: suites(:)
    type(test_counter_t) :: t
    integer :: n, i, k
    character(len=64), allocatable :: wanted(:)
    character(len=:), allocatable :: known

    suites = [ &
        suite_t("basis", run_basis_tests),&
        suite_t("hbm", run_hbm_tests),&
        suite_t("case", run_case_tests),&
        suite_t("euler", run_euler_tests),&
        suite_t("exact_reference", run_exact_reference_tests),&
        suite_t("stability", run_stability_tests),&
        suite_t("stiff_flow", run_stiff_flow_tests),&
        suite_t("robustness", run_robustness_tests),&
        suite_t("continuation", run_continuation_tests),&
        suite_t("factorizations", run_factorizations_tests),&
        suite_t("sweep_files", run_sweep_file_tests),&
        suite_t("truncation", run_truncation_tests),&
        suite_t("namelist", run_namelist_tests),&
        suite_t("openmp", run_openmp_tests),&
        suite_t("version_info", run_version_info_tests),&
        suite_t("friction", run_friction_tests),&
        suite_t("contact_law", run_contact_law_tests),&
        suite_t("contact_case", run_contact_case_tests),&
        suite_t("contact_hbm", run_contact_hbm_tests),&
        suite_t("contact_euler", run_contact_euler_tests),&
        suite_t("contact_reference", run_contact_reference_tests),&
        suite_t("contact_sweep", run_contact_sweep_tests),&
        suite_t("family", run_family_tests),&
        suite_t("cyclic", run_cyclic_tests),&
        suite_t("cyclic_fe", run_cyclic_fe_tests),&
        suite_t("cyclic_modes", run_cyclic_modes_tests),&
        suite_t("modes", run_modes_tests),&
        suite_t("file_faults", run_file_faults_tests),&
        suite_t("fft", run_fft_tests),&
        suite_t("expm", run_expm_tests),&
        suite_t("lapack", run_lapack_tests),&
        suite_t("compare", run_compare_tests),&
        suite_t("diagnostics", run_diagnostics_tests),&
        suite_t("error", run_error_tests),&
        suite_t("minpack", run_minpack_tests),&
        suite_t("cli", run_cli_tests),&
        suite_t("api", run_api_tests),&
        suite_t("case_messages", run_case_messages_tests),&
        suite_t("trust", run_trust_tests),&
        suite_t("fuzz", run_fuzz_tests),&
        suite_t("umfpack", run_umfpack_tests),&
        suite_t("cholmod", run_cholmod_tests),&
        suite_t("reduction", run_reduction_tests),&
        suite_t("reduction_estimate", run_reduction_estimate_tests),&
        suite_t("reduction_cache", run_reduction_cache_tests),&
        suite_t("arpack", run_arpack_tests),&
        suite_t("block_lanczos", run_block_lanczos_tests),&
        suite_t("sparse", run_sparse_tests),&
        suite_t("decimal", run_decimal_tests),&
        suite_t("matrix_market", run_matrix_market_tests),&
        suite_t("system_files", run_system_files_tests),&
        suite_t("output_selection", run_output_selection_tests),&
        suite_t("directions", run_directions_tests),&
        suite_t("sparse_none", run_sparse_none_tests),&
        suite_t("calculix", run_calculix_tests),&
        suite_t("solver", run_solver_tests),&
        suite_t("csv_format", run_csv_format_tests),&
        suite_t("jenkins", run_jenkins_tests),&
        suite_t("microslip", run_microslip_tests),&
        suite_t("reference_2d", run_reference_2d_tests), &
        suite_t("impacts_2d", run_impacts_2d_tests), &
        suite_t("fallback", run_fallback_tests)]
    ! deterministic random points for the finite-difference and basis checks
    call random_seed(size=n)
    call random_seed(put=[(20261122 + 7919*i, i=1, n)])
    allocate (wanted(command_argument_count()))
    do i = 1, size(wanted)
        call get_command_argument(i, wanted(i))
        if (.not. any(suites%name == wanted(i))) then
            known = ""
            do k = 1, size(suites)
                known = known//" "//trim(suites(k)%name)
            end do
            write (error_unit, '(a)') "tester: unknown suite '"//trim(wanted(i))// &
                "' (known:"//known//")"
            t%failed = t%failed + 1
        end if
    end do
    ! as the stickslip program does: one BLAS thread (OpenBLAS's pthreads build)
    call limit_blas_threads()
    do k = 1, size(suites)
        if (size(wanted) > 0) then
            if (.not. any(wanted == suites(k)%name)) cycle
        end if
        call suites(k)%run(t)
    end do
    write (output_unit, '(i0," passed, ",i0," failed")') t%passed, t%failed
    if (t%failed > 0) error stop 1
end program tester
