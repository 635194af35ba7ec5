!> stickslip_error: fatal_error fills the message and the category (input by default), the
!> categories are distinct, exit_code_of maps them to the exit codes (1 input, 2 numerical,
!> 3 I/O as in README "Exit codes"; 4 for the other categories), itoa prints integers.
module test_error
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, exit_code_of, itoa
    use testing, only: test_counter_t, check
    implicit none
    private
    public :: run_error_tests

contains

    subroutine run_error_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        integer :: cats(6), i
        call fatal_error(error, "mu must be >= 0")
        call check(t, allocated(error), "error: fatal_error allocates the error")
        if (.not. allocated(error)) return
        call check(t, error%message == "mu must be >= 0" .and. error%stat == stickslip_stat%input, &
                   "error: message kept, category input by default")
        call fatal_error(error, "cannot write", stickslip_stat%io)
        call check(t, error%stat == stickslip_stat%io .and. error%message == "cannot write", &
                   "error: a second fatal_error replaces the first")
        cats = [stickslip_stat%input, stickslip_stat%numerical, stickslip_stat%io, &
                stickslip_stat%lapack, stickslip_stat%callback, stickslip_stat%internal]
        call check(t, all([(count(cats == cats(i)) == 1, i=1, 6)]), &
                   "error: the categories are distinct")
        call check(t, exit_code_of(stickslip_stat%input) == 1 .and. &
                   exit_code_of(stickslip_stat%numerical) == 2 .and. &
                   exit_code_of(stickslip_stat%io) == 3, "error: exit codes 1, 2, 3")
        call check(t, exit_code_of(stickslip_stat%lapack) == 4 .and. &
                   exit_code_of(stickslip_stat%callback) == 4 .and. &
                   exit_code_of(stickslip_stat%internal) == 4 .and. exit_code_of(-7) == 4, &
                   "error: every other category exits 4")
        call check(t, itoa(0) == "0" .and. itoa(-42) == "-42" .and. &
                   itoa(huge(0)) == "2147483647" .and. itoa(-huge(0) - 1) == "-2147483648", &
                   "error: itoa")
    end subroutine run_error_tests
end module test_error
