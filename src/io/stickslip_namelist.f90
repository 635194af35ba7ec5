!> A strict reader of Fortran namelist text as users write it, in place of gfortran's
!> `read (u, nml=...)`: the whole file is parsed once into groups -> entries (name, value
!> tokens, line); the typed getters of stickslip_namelist_values convert the values with
!> messages that name the file, the line, the group and the variable at fault.
!>
!> Syntax accepted: `&group` ... `/` (or `&end`); `name = value, value ...` with values
!> separated by commas and/or blanks, over any number of lines; `!` comments anywhere outside
!> quotes; strings in '...' or "..." (a doubled quote stands for one); logicals T, F, .true.,
!> .false., true, false (any case); integers; reals (1, 1.5, 1d-3, 1.0E+5, NaN, Inf); repeat
!> counts `3*0.0`; names in any case. Text outside groups is ignored, as gfortran does.
!> Rejected with a message: array element or section syntax `mass(3) = ...`, empty values
!> (`1,,2`), a group not closed, non-printable bytes (shown as \xNN, never echoed raw).
module stickslip_namelist
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    implicit none
    private
    public :: nml_token_t, nml_entry_t, nml_group_t, nml_file_t
    public :: read_namelist_file, parse_namelist, sanitize, edit_distance, lower
    public :: max_case_bytes, max_entry_values

    !> Largest case file read [bytes].
    integer, parameter :: max_case_bytes = 16*1024*1024
    !> Most values one variable may list (before repeat counts are expanded); the getters
    !> apply each variable's own, smaller limit.
    integer, parameter :: max_entry_values = 65536

    character(len=*), parameter :: lf = achar(10), cr = achar(13), tab = achar(9)

    !> One value as written: its text (a string without its quotes), whether it was quoted.
    type :: nml_token_t
        character(len=:), allocatable :: text
        logical :: quoted = .false.
        integer :: line = 0
    end type nml_token_t

    !> One `name = values` of a group; the name in lower case.
    type :: nml_entry_t
        character(len=:), allocatable :: name
        integer :: line = 0
        type(nml_token_t), allocatable :: values(:)
        integer :: nvalues = 0
    end type nml_entry_t

    !> One group `&name ... /`; the name in lower case.
    type :: nml_group_t
        character(len=:), allocatable :: name
        integer :: line = 0
        type(nml_entry_t), allocatable :: entries(:)
        integer :: nentries = 0
    end type nml_group_t

    !> A parsed namelist file: its path (the prefix of every message) and its groups, in the
    !> order written (a group given twice appears twice).
    type :: nml_file_t
        character(len=:), allocatable :: path
        type(nml_group_t), allocatable :: groups(:)
        integer :: ngroups = 0
    contains
        !> Index of the first group `name` (0 when absent).
        procedure :: find => file_find
    end type nml_file_t

contains

    !> Read and parse the namelist file `path`. Errors: stat io when it cannot be opened or
    !> read; stat input for a file larger than max_case_bytes and for every parse error.
    subroutine read_namelist_file(path, nml, error)
        !> Path of the file.
        character(len=*), intent(in) :: path
        !> The groups read.
        type(nml_file_t), intent(out) :: nml
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat
        integer(int64) :: bytes
        character(len=512) :: msg
        character(len=:), allocatable :: text
        open (newunit=u, file=path, status='old', action='read', access='stream', &
              form='unformatted', iostat=stat, iomsg=msg)
        if (stat /= 0) then
            call fatal_error(error, path//": cannot open the case file: "//trim(msg), &
                             stickslip_stat%io)
            return
        end if
        inquire (unit=u, size=bytes)
        if (bytes > max_case_bytes) then
            close (u)
            call fatal_error(error, path//": the case file is larger than "// &
                             itoa(max_case_bytes/1024/1024)//" MiB (not a case file?)", &
                             stickslip_stat%input)
            return
        end if
        allocate (character(len=max(bytes, 0_int64)) :: text)
        if (bytes > 0) read (u, iostat=stat, iomsg=msg) text
        close (u)
        if (bytes > 0 .and. stat /= 0) then
            call fatal_error(error, path//": cannot read the case file: "//trim(msg), &
                             stickslip_stat%io)
            return
        end if
        call parse_namelist(path, text, nml, error)
    end subroutine read_namelist_file

    !> Parse namelist `text` (lines ended by LF; CR ignored) read from `path`. Errors (stat
    !> input) start "<path>:<line>: " and name the group and variable.
    subroutine parse_namelist(path, text, nml, error)
        !> Where the text came from (message prefix).
        character(len=*), intent(in) :: path
        !> The text.
        character(len=*), intent(in) :: text
        !> The groups.
        type(nml_file_t), intent(out) :: nml
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer :: i, j, n, line, g, e, k, gline
        logical :: in_group, expect_value
        character(len=1) :: c
        character(len=:), allocatable :: word, value

        nml%path = path
        allocate (nml%groups(4))
        n = len(text)
        ! control characters anywhere (binary data): never echo them
        line = 1
        do i = 1, n
            k = modulo(iachar(text(i:i)), 256)
            if (k == 10) line = line + 1
            if ((k < 32 .and. k /= 9 .and. k /= 10 .and. k /= 13) .or. k == 127) then
                call fail(line, "non-printable byte (not a text file?): "// &
                          sanitize(line_of(i)))
                return
            end if
        end do

        line = 1
        in_group = .false.
        expect_value = .false.
        g = 0
        e = 0
        gline = 0
        i = 1
        do while (i <= n)
            c = text(i:i)
            if (c == lf) then
                line = line + 1
                i = i + 1
                cycle
            end if
            if (c == ' ' .or. c == tab .or. c == cr) then
                i = i + 1
                cycle
            end if
            if (c == '!') then
                do while (i <= n)
                    if (text(i:i) == lf) exit
                    i = i + 1
                end do
                cycle
            end if
            if (.not. in_group) then
                if (c == '&' .or. c == '$') then
                    j = i + 1
                    do while (j <= n)
                        if (.not. is_name_char(text(j:j))) exit
                        j = j + 1
                    end do
                    word = lower(text(i + 1:j - 1))
                    if (len(word) == 0) then
                        call fail(line, "'"//c//"' not followed by a group name: "// &
                                  sanitize(line_of(i)))
                        return
                    end if
                    if (word == 'end') then
                        call fail(line, "&end outside a group")
                        return
                    end if
                    call add_group(word, line)
                    g = nml%ngroups
                    gline = line
                    e = 0
                    expect_value = .false.
                    in_group = .true.
                    i = j
                else
                    i = i + 1
                end if
                cycle
            end if

            ! inside group g
            select case (c)
            case ('/')
                if (.not. entry_done()) return
                in_group = .false.
                i = i + 1
            case (',')
                if (expect_value .and. e > 0) then
                    call fail(line, gname()//" "//nml%groups(g)%entries(e)%name// &
                              ": empty value (a comma with no value before it)")
                    return
                end if
                expect_value = .true.
                i = i + 1
            case ('&', '$')
                j = i + 1
                do while (j <= n)
                    if (.not. is_name_char(text(j:j))) exit
                    j = j + 1
                end do
                word = lower(text(i + 1:j - 1))
                if (word == 'end') then
                    if (.not. entry_done()) return
                    in_group = .false.
                    i = j
                else
                    call fail(gline, gname()//": the group is not closed by '/' (before "// &
                              "&"//word//" on line "//itoa(line)//")")
                    return
                end if
            case ("'", '"')
                if (.not. read_string(i, line, value)) return
                if (.not. add_value(value, .true.)) return
            case ('=')
                call fail(line, gname()//": '=' without a variable name before it")
                return
            case default
                j = i
                do while (j <= n)
                    c = text(j:j)
                    if (c == ' ' .or. c == tab .or. c == cr .or. c == lf .or. c == ',' .or. &
                        c == '/' .or. c == '!' .or. c == '=' .or. c == "'" .or. c == '"') exit
                    if (c == '(') then
                        ! a subscript may hold commas: take it whole
                        do while (j <= n)
                            if (text(j:j) == ')' .or. text(j:j) == lf) exit
                            j = j + 1
                        end do
                        if (j > n) exit
                        if (text(j:j) == lf) exit
                    end if
                    j = j + 1
                end do
                word = text(i:j - 1)
                do k = 1, len(word)
                    if (modulo(iachar(word(k:k)), 256) > 126) then
                        call fail(line, gname()//": non-printable or non-ASCII text: "// &
                                  sanitize(line_of(i)))
                        return
                    end if
                end do
                i = j
                ! a name when '=' follows (after blanks)
                k = i
                do while (k <= n)
                    if (text(k:k) /= ' ' .and. text(k:k) /= tab) exit
                    k = k + 1
                end do
                if (k <= n) then
                    if (text(k:k) == '=') then
                        if (.not. new_entry(word)) return
                        i = k + 1
                        cycle
                    end if
                end if
                if (.not. add_value(word, .false.)) return
            end select
        end do
        if (in_group) then
            call fail(gline, gname()//": the group is not closed by '/'")
            return
        end if

    contains

        function gname() result(s)
            character(len=:), allocatable :: s
            s = "&"//nml%groups(g)%name
        end function gname

        !> The line holding text(i:i).
        function line_of(i) result(s)
            integer, intent(in) :: i
            character(len=:), allocatable :: s
            integer :: a, b
            a = i
            do while (a > 1)
                if (text(a - 1:a - 1) == lf) exit
                a = a - 1
            end do
            b = i
            do while (b < n)
                if (text(b + 1:b + 1) == lf) exit
                b = b + 1
            end do
            ! start the excerpt near the culprit
            s = text(max(a, i - 10):b)
        end function line_of

        subroutine fail(at, message)
            integer, intent(in) :: at
            character(len=*), intent(in) :: message
            call fatal_error(error, path//":"//itoa(at)//": "//message, stickslip_stat%input)
        end subroutine fail

        subroutine add_group(name, at)
            character(len=*), intent(in) :: name
            integer, intent(in) :: at
            type(nml_group_t), allocatable :: tmp(:)
            if (nml%ngroups == size(nml%groups)) then
                allocate (tmp(2*size(nml%groups)))
                tmp(1:nml%ngroups) = nml%groups(1:nml%ngroups)
                call move_alloc(tmp, nml%groups)
            end if
            nml%ngroups = nml%ngroups + 1
            nml%groups(nml%ngroups)%name = name
            nml%groups(nml%ngroups)%line = at
            allocate (nml%groups(nml%ngroups)%entries(8))
        end subroutine add_group

        !> The current entry has a value (or there is none): the group may close.
        logical function entry_done() result(ok)
            ok = .true.
            if (e == 0) return
            if (nml%groups(g)%entries(e)%nvalues == 0) then
                call fail(nml%groups(g)%entries(e)%line, gname()//" "// &
                          nml%groups(g)%entries(e)%name//": no value after '='")
                ok = .false.
            end if
        end function entry_done

        logical function new_entry(raw) result(ok)
            character(len=*), intent(in) :: raw
            character(len=:), allocatable :: name
            type(nml_entry_t), allocatable :: tmp(:)
            integer :: m
            ok = .false.
            if (.not. entry_done()) return
            name = lower(raw)
            if (index(name, '(') > 0) then
                call fail(line, gname()//" "//name//": array element or section syntax is "// &
                          "not supported; give the whole array: "// &
                          name(1:index(name, '(') - 1)//" = v1, v2, ...")
                return
            end if
            if (.not. is_name(name)) then
                call fail(line, gname()//": '"//sanitize(raw)//"' is not a variable name")
                return
            end if
            associate (grp => nml%groups(g))
                do m = 1, grp%nentries
                    if (grp%entries(m)%name == name) then
                        call fail(line, gname()//" "//name//": given twice in the group "// &
                                  "(lines "//itoa(grp%entries(m)%line)//" and "// &
                                  itoa(line)//")")
                        return
                    end if
                end do
                if (grp%nentries == size(grp%entries)) then
                    allocate (tmp(2*size(grp%entries)))
                    tmp(1:grp%nentries) = grp%entries(1:grp%nentries)
                    call move_alloc(tmp, grp%entries)
                end if
                grp%nentries = grp%nentries + 1
                e = grp%nentries
                grp%entries(e)%name = name
                grp%entries(e)%line = line
                allocate (grp%entries(e)%values(4))
            end associate
            expect_value = .true.
            ok = .true.
        end function new_entry

        logical function add_value(text, quoted) result(ok)
            character(len=*), intent(in) :: text
            logical, intent(in) :: quoted
            type(nml_token_t), allocatable :: tmp(:)
            ok = .false.
            if (e == 0) then
                call fail(line, gname()//": value '"//sanitize(text)// &
                          "' before any variable name")
                return
            end if
            associate (en => nml%groups(g)%entries(e))
                if (en%nvalues == max_entry_values) then
                    call fail(line, gname()//" "//en%name//": too many values (more than "// &
                              itoa(max_entry_values)//")")
                    return
                end if
                if (en%nvalues == size(en%values)) then
                    allocate (tmp(2*size(en%values)))
                    tmp(1:en%nvalues) = en%values(1:en%nvalues)
                    call move_alloc(tmp, en%values)
                end if
                en%nvalues = en%nvalues + 1
                en%values(en%nvalues)%text = text
                en%values(en%nvalues)%quoted = quoted
                en%values(en%nvalues)%line = line
            end associate
            expect_value = .false.
            ok = .true.
        end function add_value

        !> A quoted string from text(i:): i moves past it, line counts its line ends.
        logical function read_string(i, line, s) result(ok)
            integer, intent(inout) :: i, line
            character(len=:), allocatable, intent(out) :: s
            character(len=1) :: q
            integer :: j, start, first_line
            ok = .false.
            q = text(i:i)
            first_line = line
            s = ""
            j = i + 1
            start = j
            do
                if (j > n) then
                    call fail(first_line, gname()//": string not closed by "//q)
                    return
                end if
                if (text(j:j) == lf) line = line + 1
                if (text(j:j) == q) then
                    s = s//text(start:j - 1)
                    if (j < n) then
                        if (text(j + 1:j + 1) == q) then
                            s = s//q
                            j = j + 2
                            start = j
                            cycle
                        end if
                    end if
                    i = j + 1
                    ok = .true.
                    return
                end if
                j = j + 1
            end do
        end function read_string
    end subroutine parse_namelist

    !> Index of the first group `name` (lower case) in nml, 0 when absent.
    pure integer function file_find(self, name) result(k)
        !> The file.
        class(nml_file_t), intent(in) :: self
        !> Group name without '&', lower case.
        character(len=*), intent(in) :: name
        do k = 1, self%ngroups
            if (self%groups(k)%name == name) return
        end do
        k = 0
    end function file_find

    !> Levenshtein distance between a and b.
    pure integer function edit_distance(a, b) result(d)
        !> The strings.
        character(len=*), intent(in) :: a, b
        integer :: prev(0:len(b)), cur(0:len(b)), i, j
        prev = [(j, j=0, len(b))]
        do i = 1, len(a)
            cur(0) = i
            do j = 1, len(b)
                cur(j) = min(prev(j) + 1, cur(j - 1) + 1, &
                             prev(j - 1) + merge(0, 1, a(i:i) == b(j:j)))
            end do
            prev = cur
        end do
        d = prev(len(b))
    end function edit_distance

    pure logical function is_name_char(c)
        character(len=1), intent(in) :: c
        is_name_char = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z') .or. &
                       (c >= '0' .and. c <= '9') .or. c == '_'
    end function is_name_char

    pure logical function is_name(s)
        character(len=*), intent(in) :: s
        integer :: i
        is_name = .false.
        if (len(s) == 0) return
        if (.not. ((s(1:1) >= 'a' .and. s(1:1) <= 'z'))) return
        do i = 2, len(s)
            if (.not. is_name_char(s(i:i))) return
        end do
        is_name = .true.
    end function is_name

    !> Printable excerpt of s: bytes outside ASCII 32..126 as \xNN, cut to about 40
    !> characters ("..." appended when cut).
    pure function sanitize(s) result(t)
        !> The raw text.
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: t
        character(len=*), parameter :: hex = '0123456789ABCDEF'
        integer :: i, k
        t = ""
        do i = 1, len(s)
            if (len(t) >= 40) then
                t = t//"..."
                return
            end if
            k = modulo(iachar(s(i:i)), 256)
            if (k >= 32 .and. k <= 126) then
                t = t//s(i:i)
            else
                t = t//"\x"//hex(k/16 + 1:k/16 + 1)//hex(mod(k, 16) + 1:mod(k, 16) + 1)
            end if
        end do
    end function sanitize

    !> s in lower case (ASCII).
    pure function lower(s) result(t)
        !> The text.
        character(len=*), intent(in) :: s
        character(len=len(s)) :: t
        integer :: i
        t = s
        do i = 1, len(s)
            if (s(i:i) >= 'A' .and. s(i:i) <= 'Z') t(i:i) = achar(iachar(s(i:i)) + 32)
        end do
    end function lower
end module stickslip_namelist
