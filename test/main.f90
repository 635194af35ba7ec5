!> The one test driver: runs every suite and ends with the line "N passed, N failed".
program tester
    use, intrinsic :: iso_fortran_env, only: output_unit
    use testing, only: test_counter_t
    use test_basis, only: run_basis_tests
    use test_hbm, only: run_hbm_tests
    use test_case, only: run_case_tests
    use test_euler, only: run_euler_tests
    use test_exact_reference, only: run_exact_reference_tests
    use test_stability, only: run_stability_tests
    use test_robustness, only: run_robustness_tests
    use test_continuation, only: run_continuation_tests
    use test_sweep_files, only: run_sweep_file_tests
    use test_truncation, only: run_truncation_tests
    implicit none
    type(test_counter_t) :: t
    integer :: n, i
    ! deterministic random points for the finite-difference and basis checks
    call random_seed(size=n)
    call random_seed(put=[(20261122 + 7919*i, i=1, n)])
    call run_basis_tests(t)
    call run_hbm_tests(t)
    call run_case_tests(t)
    call run_euler_tests(t)
    call run_exact_reference_tests(t)
    call run_stability_tests(t)
    call run_robustness_tests(t)
    call run_continuation_tests(t)
    call run_sweep_file_tests(t)
    call run_truncation_tests(t)
    write (output_unit, '(i0," passed, ",i0," failed")') t%passed, t%failed
    if (t%failed > 0) error stop 1
end program tester
