!> Error handling: an allocatable `error_type` returned as the last argument of anything that
!> can fail. Library code never stops and never prints; only the app turns errors into exit codes.
module stickslip_error
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: error_type, fatal_error, stickslip_stat, exit_code_of, itoa, real_text

    !> Decimal text of an integer (default or 64-bit kind).
    interface itoa
        module procedure itoa_default, itoa_int64
    end interface itoa

    !> Error categories (`error_type%stat`).
    type :: stat_enum_t
        !> Bad input: case file, model data, options.
        integer :: input = 1
        !> Numerical failure: singular dynamic stiffness, non-converged solve, NaN.
        integer :: numerical = 2
        !> File input/output failure.
        integer :: io = 3
        !> A LAPACK routine reported an argument error.
        integer :: lapack = 4
        !> A user callback asked to stop.
        integer :: callback = 5
        !> Impossible state (a bug).
        integer :: internal = 6
    end type stat_enum_t

    !> The one instance of the error categories.
    type(stat_enum_t), parameter :: stickslip_stat = stat_enum_t()

    !> An error: a category and a message meant for a person.
    type :: error_type
        !> Category, one of `stickslip_stat`.
        integer :: stat = 1
        !> Message naming what went wrong and where.
        character(len=:), allocatable :: message
    end type error_type

contains

    !> Create an error with `message` and category `stat` (default: input).
    pure subroutine fatal_error(error, message, stat)
        !> The error to create.
        type(error_type), allocatable, intent(out) :: error
        !> What went wrong, where.
        character(len=*), intent(in) :: message
        !> Category (`stickslip_stat%...`).
        integer, intent(in), optional :: stat
        allocate (error)
        error%message = message
        if (present(stat)) error%stat = stat
    end subroutine fatal_error

    !> Process exit code for an error category: 1 input/usage, 2 numerical failure, 3 I/O,
    !> 4 internal or library failure.
    pure integer function exit_code_of(stat) result(code)
        !> Error category.
        integer, intent(in) :: stat
        select case (stat)
        case (stickslip_stat%input)
            code = 1
        case (stickslip_stat%numerical)
            code = 2
        case (stickslip_stat%io)
            code = 3
        case default
            code = 4
        end select
    end function exit_code_of

    !> Decimal text of an integer.
    pure function itoa_default(i) result(s)
        !> The integer.
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=24) :: buf
        write (buf, '(i0)') i
        s = trim(buf)
    end function itoa_default

    !> Decimal text of a 64-bit integer.
    pure function itoa_int64(i) result(s)
        !> The integer.
        integer(int64), intent(in) :: i
        character(len=:), allocatable :: s
        character(len=24) :: buf
        write (buf, '(i0)') i
        s = trim(buf)
    end function itoa_int64

    !> A real as text without blanks, for messages: written with the edit descriptor `edit`
    !> (default '(g0.6)', six significant digits; e.g. '(es12.5)'). No errors.
    pure function real_text(x, edit) result(s)
        !> The value.
        real(dp), intent(in) :: x
        !> A Fortran edit descriptor with its parentheses, at most 32 characters wide.
        character(len=*), intent(in), optional :: edit
        character(len=:), allocatable :: s
        character(len=40) :: buf
        if (present(edit)) then
            write (buf, edit) x
        else
            write (buf, '(g0.6)') x
        end if
        s = trim(adjustl(buf))
    end function real_text
end module stickslip_error
