!> A tiny test harness: a counter of passed and failed checks; failures go to stderr (and,
!> with STICKSLIP_TEST_VERBOSE=1 in the environment, the figures of the passing checks that
!> measure something: doc/layout.md).
module testing
    use, intrinsic :: iso_fortran_env, only: error_unit
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    implicit none
    private
    public :: test_counter_t, check, check_close, check_error

    !> Counts of passed and failed checks.
    type :: test_counter_t
        integer :: passed = 0
        integer :: failed = 0
    end type test_counter_t

    interface check_close
        module procedure check_close_scalar, check_close_array
    end interface check_close

contains

    !> Record a check of `cond`, printing `FAIL name: detail` on failure.
    subroutine check(t, cond, name, detail)
        type(test_counter_t), intent(inout) :: t
        logical, intent(in) :: cond
        character(len=*), intent(in) :: name
        character(len=*), intent(in), optional :: detail
        if (cond) then
            t%passed = t%passed + 1
            if (present(detail)) then
                if (verbose() .and. len_trim(detail) > 0) &
                    write (error_unit, '(a)') "PASS "//name//": "//trim(detail)
            end if
        else
            t%failed = t%failed + 1
            if (present(detail)) then
                write (error_unit, '(a)') "FAIL "//name//": "//detail
            else
                write (error_unit, '(a)') "FAIL "//name
            end if
        end if
    end subroutine check

    !> STICKSLIP_TEST_VERBOSE is set to 1: passing checks print their figures.
    logical function verbose()
        character(len=8) :: value
        integer :: stat
        call get_environment_variable("STICKSLIP_TEST_VERBOSE", value, status=stat)
        verbose = stat == 0 .and. trim(value) == "1"
    end function verbose

    !> Check |actual - expected| <= max(atol, rtol |expected|).
    subroutine check_close_scalar(t, actual, expected, name, rtol, atol)
        type(test_counter_t), intent(inout) :: t
        real(dp), intent(in) :: actual, expected
        character(len=*), intent(in) :: name
        real(dp), intent(in), optional :: rtol, atol
        real(dp) :: rt, at
        character(len=200) :: buf
        rt = 1.0e-12_dp
        at = 0.0_dp
        if (present(rtol)) rt = rtol
        if (present(atol)) at = atol
        write (buf, '(a,es24.16,a,es24.16,a,es10.3)') "actual ", actual, " expected ", expected, &
            " diff ", abs(actual - expected)
        call check(t, abs(actual - expected) <= max(at, rt*abs(expected)), name, trim(buf))
    end subroutine check_close_scalar

    !> Elementwise check_close over arrays of equal size; reports the worst element.
    subroutine check_close_array(t, actual, expected, name, rtol, atol)
        type(test_counter_t), intent(inout) :: t
        real(dp), intent(in) :: actual(:), expected(:)
        character(len=*), intent(in) :: name
        real(dp), intent(in), optional :: rtol, atol
        real(dp) :: rt, at
        integer :: i
        character(len=200) :: buf
        rt = 1.0e-12_dp
        at = 0.0_dp
        if (present(rtol)) rt = rtol
        if (present(atol)) at = atol
        if (size(actual) /= size(expected)) then
            call check(t, .false., name, "size mismatch")
            return
        end if
        if (size(actual) == 0) then
            call check(t, .true., name)
            return
        end if
        i = maxloc(abs(actual - expected) - max(at, rt*abs(expected)), 1)
        write (buf, '(a,i0,a,es24.16,a,es24.16,a,es10.3)') "worst element ", i, ": actual ", &
            actual(i), " expected ", expected(i), " diff ", abs(actual(i) - expected(i))
        call check(t, all(abs(actual - expected) <= max(at, rt*abs(expected))), name, trim(buf))
    end subroutine check_close_array

    !> Check that an error was (expect_fail) or was not raised; optionally that its message
    !> contains every string of `contains`.
    subroutine check_error(t, error, name, expect_fail, contains)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable, intent(in) :: error
        character(len=*), intent(in) :: name
        logical, intent(in) :: expect_fail
        character(len=*), intent(in), optional :: contains(:)
        integer :: i
        if (expect_fail) then
            if (.not. allocated(error)) then
                call check(t, .false., name, "expected an error, got none")
                return
            end if
            if (present(contains)) then
                do i = 1, size(contains)
                    if (index(error%message, trim(contains(i))) == 0) then
                        call check(t, .false., name, "message '"//error%message// &
                                   "' lacks '"//trim(contains(i))//"'")
                        return
                    end if
                end do
            end if
            call check(t, .true., name)
        else
            if (allocated(error)) then
                call check(t, .false., name, "unexpected error: "//error%message)
            else
                call check(t, .true., name)
            end if
        end if
    end subroutine check_error
end module testing
