!> Tests of the namelist parser and its typed getters (stickslip_namelist) on text in memory:
!> the syntax users write is read as gfortran reads it, and every class of bad input gives a
!> message with the file, the line, the group and the variable (and never raw bytes).
module test_namelist
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_namelist, only: nml_file_t, parse_namelist, sanitize, edit_distance
    use stickslip_namelist_values, only: check_names, get_integer, get_real, get_logical, &
        get_string, get_integers, get_reals
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_namelist_tests

    character(len=*), parameter :: nl = new_line('a')

contains

    subroutine run_namelist_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_syntax(t)
        call test_values(t)
        call test_errors(t)
        call test_helpers(t)
    end subroutine run_namelist_tests

    !> Groups, comments, closings, names: what is read and what is ignored.
    subroutine test_syntax(t)
        type(test_counter_t), intent(inout) :: t
        type(nml_file_t) :: nml
        type(error_type), allocatable :: error
        integer, allocatable :: iv(:)
        real(dp), allocatable :: rv(:)
        logical :: found
        character(len=:), allocatable :: text
        text = "text before the groups is ignored, as gfortran does"//nl// &
               "! the &euler group is not needed (a comment that mentions a group)"//nl// &
               "&SYSTEM NDOF = 2, Mass = 1, 0, ! comment after a comma in an array"//nl// &
               "   0  1   ! blanks separate values too"//nl// &
               "/ ! after the closing slash"//nl// &
               "&hbm harmonics=3 &end"//nl// &
               "&run method = 'it''s / not ! a comment' /"//nl// &
               "some text after the groups, in no group, is ignored too"
        call parse_namelist("mem.nml", text, nml, error)
        call check_error(t, error, "namelist: valid unusual text parsed", .false.)
        if (allocated(error)) return
        call check(t, nml%ngroups == 3, "namelist: three groups (comments, text ignored)")
        call check(t, nml%find("system") == 1 .and. nml%find("hbm") == 2 .and. &
                   nml%find("run") == 3 .and. nml%find("euler") == 0, &
                   "namelist: group names in lower case, comments and outside text ignored")
        call get_reals(nml, "system", "mass", rv, found, 16, error)
        call check(t, found .and. .not. allocated(error), "namelist: mass read")
        if (found .and. .not. allocated(error)) &
            call check(t, size(rv) == 4 .and. all(rv == [1, 0, 0, 1]), &
                       "namelist: array over lines, comment after a comma, blank separators")
        call get_integers(nml, "system", "ndof", iv, found, 1, error)
        call check(t, found .and. .not. allocated(error), "namelist: upper-case name found")
        if (found) call check(t, iv(1) == 2, "namelist: NDOF = 2")
        block
            character(len=:), allocatable :: s
            s = "unset"
            call get_string(nml, "run", "method", s, error)
            call check(t, s == "it's / not ! a comment", &
                       "namelist: doubled quote, slash and ! inside a string", s)
        end block
        block
            integer :: h
            h = 0
            call get_integer(nml, "hbm", "harmonics", h, error)
            call check(t, h == 3, "namelist: group closed by &end")
        end block

        ! the last line without a newline; CR LF line ends; double quotes
        call parse_namelist("mem.nml", "&output directory = ""a 'b'"" /"//achar(13)//nl// &
                            "&run method='x'/", nml, error)
        call check_error(t, error, "namelist: CRLF and no final newline", .false.)
        if (.not. allocated(error)) call check(t, nml%ngroups == 2, &
                                               "namelist: both groups of the CRLF text")
    end subroutine test_syntax

    !> Typed values: logicals, reals, integers, repeat counts, defaults kept when absent.
    subroutine test_values(t)
        type(test_counter_t), intent(inout) :: t
        type(nml_file_t) :: nml
        type(error_type), allocatable :: error
        logical :: l(8), found
        real(dp), allocatable :: rv(:)
        integer, allocatable :: iv(:)
        real(dp) :: x
        integer :: k
        call parse_namelist("mem.nml", "&g a = T, b = F, c = .true., d = .FALSE., e = true, "// &
                            "f = False, g = .t., h = .f." //nl// &
                            "r = 1d-3, 1.0E+5, -2, +.5, 3*0.25, 7. /"//nl// &
                            "&h n = -12, 2*4, 0 /", nml, error)
        call check_error(t, error, "namelist: typed values parsed", .false.)
        if (allocated(error)) return
        l = .false.
        l(1:7:2) = .true.
        l(2:8:2) = .true.
        call get_logical(nml, "g", "a", l(1), error)
        call get_logical(nml, "g", "b", l(2), error)
        call get_logical(nml, "g", "c", l(3), error)
        call get_logical(nml, "g", "d", l(4), error)
        call get_logical(nml, "g", "e", l(5), error)
        call get_logical(nml, "g", "f", l(6), error)
        call get_logical(nml, "g", "g", l(7), error)
        call get_logical(nml, "g", "h", l(8), error)
        call check(t, all(l .eqv. [.true., .false., .true., .false., .true., .false., .true., &
                                   .false.]), "namelist: logical spellings")
        call get_reals(nml, "g", "r", rv, found, 100, error)
        call check_error(t, error, "namelist: reals read", .false.)
        if (.not. allocated(error)) then
            call check(t, size(rv) == 8, "namelist: repeat count expands (8 values)")
            if (size(rv) == 8) call check_close(t, rv, [1.0e-3_dp, 1.0e5_dp, -2.0_dp, 0.5_dp, &
                                                        0.25_dp, 0.25_dp, 0.25_dp, 7.0_dp], &
                                                "namelist: real forms", rtol=0.0_dp)
        end if
        call get_integers(nml, "h", "n", iv, found, 4, error)
        call check(t, .not. allocated(error) .and. found, "namelist: integers read")
        if (found .and. .not. allocated(error)) call check(t, all(iv == [-12, 4, 4, 0]), &
                                                           "namelist: integers and 2*4")
        x = 42.0_dp
        call get_real(nml, "h", "absent", x, error, found)
        call check(t, .not. found .and. x == 42.0_dp .and. .not. allocated(error), &
                   "namelist: absent variable keeps the default")
        k = 7
        call get_integer(nml, "nogroup", "n", k, error, found)
        call check(t, .not. found .and. k == 7, "namelist: absent group keeps the default")
    end subroutine test_values

    !> One parse or getter error: status input and every fragment in the message.
    subroutine expect(t, name, text, fragments, group, variable, kind)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: name, text
        character(len=*), intent(in) :: fragments(:)
        character(len=*), intent(in), optional :: group, variable, kind
        type(nml_file_t) :: nml
        type(error_type), allocatable :: error
        integer :: i
        real(dp) :: x
        integer :: n
        logical :: l
        character(len=:), allocatable :: s
        integer, allocatable :: iv(:)
        logical :: found
        call parse_namelist("mem.nml", text, nml, error)
        if (.not. allocated(error) .and. present(kind)) then
            select case (kind)
            case ('real')
                call get_real(nml, group, variable, x, error)
            case ('integer')
                call get_integer(nml, group, variable, n, error)
            case ('integers')
                call get_integers(nml, group, variable, iv, found, 4, error)
            case ('logical')
                call get_logical(nml, group, variable, l, error)
            case ('string')
                s = ""
                call get_string(nml, group, variable, s, error)
            case ('names')
                call check_names(nml, group, [character(len=9) :: "ndof", "mass", "stiffness"], &
                                     error)
            end select
        end if
        call check_error(t, error, "namelist error: "//name, .true., fragments)
        if (.not. allocated(error)) return
        call check(t, error%stat == stickslip_stat%input, "namelist error status: "//name)
        do i = 1, len(error%message)
            if (iachar(error%message(i:i)) < 32 .or. iachar(error%message(i:i)) > 126) then
                call check(t, .false., "namelist error printable: "//name)
                return
            end if
        end do
    end subroutine expect

    subroutine test_errors(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: garbage
        integer :: i
        call expect(t, "unclosed", "&system ndof = 2"//nl//"mass = 1", &
                    [character(len=40) :: "mem.nml:1:", "&system", "not closed by '/'"])
        call expect(t, "unclosed before next", "&forcing omega = 1"//nl//"&hbm /", &
                    [character(len=40) :: "mem.nml:1:", "&forcing", "not closed", "&hbm", &
                    "line 2"])
        call expect(t, "unquoted string", "&run method = hbm /", &
                    [character(len=40) :: "mem.nml:1:", "&run method = hbm", "quoted", &
                    "method = 'hbm'"], "run", "method", "string")
        call expect(t, "unclosed string", "&run method = 'hbm /", &
                    [character(len=40) :: "&run", "string not closed"])
        garbage = "&system ndof = 2 "
        do i = 0, 40
            garbage = garbage//achar(mod(i*37, 256))
        end do
        call expect(t, "binary garbage", garbage//" /", &
                    [character(len=40) :: "mem.nml:1:", "non-printable", "\x00", "..."])
        call expect(t, "integer overflow", "&hbm harmonics = 99999999999 /", &
                    [character(len=40) :: "&hbm harmonics = 99999999999", "out of range", &
                    "2147483647"], "hbm", "harmonics", "integer")
        call expect(t, "integer overflow 2**31", "&hbm samples = 2147483648 /", &
                    [character(len=40) :: "&hbm samples", "out of range"], "hbm", "samples", &
                    "integer")
        call expect(t, "too many values", "&f list = 1, 2, 3, 4, 5 /", &
                    [character(len=40) :: "&f list", "too many values", "at most 4"], &
                    "f", "list", "integers")
        call expect(t, "too many by repeat", "&f list = 2, 999999999999999*3 /", &
                    [character(len=40) :: "&f list", "too many values", "at most 4"], &
                    "f", "list", "integers")
        call expect(t, "scalar given twice", "&hbm harmonics = 3, 4 /", &
                    [character(len=40) :: "&hbm harmonics", "too many values", "at most 1 value"], &
                    "hbm", "harmonics", "integer")
        call expect(t, "real for integer", "&hbm harmonics = 3.5 /", &
                    [character(len=40) :: "&hbm harmonics = 3.5", "not an integer"], &
                    "hbm", "harmonics", "integer")
        call expect(t, "string for real", "&forcing omega = 'fast' /", &
                    [character(len=40) :: "&forcing omega = 'fast'", "a string"], &
                    "forcing", "omega", "real")
        call expect(t, "word for real", "&forcing omega = fast /", &
                    [character(len=40) :: "&forcing omega = fast", "not a number"], &
                    "forcing", "omega", "real")
        call expect(t, "NaN", "&hbm rho = NaN /", &
                    [character(len=40) :: "&hbm rho = NaN", "not a finite number"], &
                    "hbm", "rho", "real")
        call expect(t, "Inf", "&hbm rho = -Inf /", &
                    [character(len=40) :: "&hbm rho = -Inf", "not a finite number"], &
                    "hbm", "rho", "real")
        call expect(t, "overflowing real", "&hbm rho = 1e400 /", &
                    [character(len=40) :: "&hbm rho = 1e400", "not a finite number"], &
                    "hbm", "rho", "real")
        ! fuzz: a nonzero literal that underflows to 0 must not pass for 0 (rho = 0: automatic)
        call expect(t, "real underflow", "&hbm rho = 1e-400 /", &
                    [character(len=40) :: "&hbm rho = 1e-400", "underflows to 0"], &
                    "hbm", "rho", "real")
        call expect(t, "real underflow, long literal", "&hbm rho = 0."//repeat("0", 400)//"1 /", &
                    [character(len=40) :: "&hbm rho = 0.000", "underflows to 0"], &
                    "hbm", "rho", "real")
        call expect(t, "bad logical", "&hbm odd_only = yes /", &
                    [character(len=40) :: "&hbm odd_only = yes", "not a logical"], &
                    "hbm", "odd_only", "logical")
        call expect(t, "variable twice", "&hbm tol = 1e-9,"//nl//" rho = 1, tol = 1e-8 /", &
                    [character(len=40) :: "mem.nml:2:", "&hbm tol", "given twice", &
                    "lines 1 and 2"])
        call expect(t, "element syntax", "&system mass(3) = 1 /", &
                    [character(len=40) :: "&system mass(3)", "not supported", "mass = v1"])
        call expect(t, "empty value", "&system mass = 1,,2 /", &
                    [character(len=40) :: "&system mass", "empty value"])
        call expect(t, "no value", "&system mass = /", &
                    [character(len=40) :: "&system mass", "no value"])
        call expect(t, "value before name", "&system 3 /", &
                    [character(len=40) :: "&system", "before any variable name"])
        call expect(t, "misspelled variable", "&system ndof = 2, stiffnesss = 1 /", &
                    [character(len=60) :: "&system stiffnesss: unknown variable", &
                    "did you mean stiffness?"], "system", "", "names")
        call expect(t, "unknown variable", "&system bogus_variable = 3 /", &
                    [character(len=60) :: "&system bogus_variable: unknown variable", &
                    "known: ndof, mass, stiffness"], "system", "", "names")
        call expect(t, "huge list", "&f list = "//repeat("1 ", 70000)//"/", &
                    [character(len=40) :: "&f list", "too many values (more than 65536)"])
        call expect(t, "repeat count zero", "&f list = 0*3 /", &
                    [character(len=40) :: "&f list", "repeat count"], "f", "list", "integers")
        call expect(t, "repeat without value", "&f list = 3* /", &
                    [character(len=40) :: "&f list", "repeat count"], "f", "list", "integers")
    end subroutine test_errors

    subroutine test_helpers(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: s
        call check(t, edit_distance("hbmm", "hbm") == 1 .and. edit_distance("solver", "sweep") > 2 &
                   .and. edit_distance("", "abc") == 3 .and. edit_distance("kitten", "sitting") == 3, &
                   "namelist: edit distance")
        s = sanitize("ab"//achar(0)//achar(255)//"c")
        call check(t, s == "ab\x00\xFFc", "namelist: sanitize shows bytes as \xNN", s)
        s = sanitize(repeat("x", 100))
        call check(t, len(s) == 43, "namelist: sanitize cuts to 40 characters")
    end subroutine test_helpers
end module test_namelist
