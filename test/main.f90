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
    use test_robustness, only: run_robustness_tests
    use test_continuation, only: run_continuation_tests
    use test_sweep_files, only: run_sweep_file_tests
    use test_truncation, only: run_truncation_tests
    use test_trust, only: run_trust_tests
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
    ran = 0
    if (selected("basis")) call run_basis_tests(t)
    if (selected("hbm")) call run_hbm_tests(t)
    if (selected("case")) call run_case_tests(t)
    if (selected("euler")) call run_euler_tests(t)
    if (selected("exact_reference")) call run_exact_reference_tests(t)
    if (selected("stability")) call run_stability_tests(t)
    if (selected("robustness")) call run_robustness_tests(t)
    if (selected("continuation")) call run_continuation_tests(t)
    if (selected("sweep_files")) call run_sweep_file_tests(t)
    if (selected("truncation")) call run_truncation_tests(t)
    if (selected("trust")) call run_trust_tests(t)
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
