!> Typed getters of a parsed namelist file (stickslip_namelist): integers, finite reals,
!> logicals, quoted strings of any length, lists with repeat counts up to a given length, and
!> the check that a group holds only known variables. A variable that is absent leaves its
!> default; every error (stat input) starts "<path>:<line>: &<group> <variable>" and says what
!> was expected (the range of an integer, the most values of a list, quotes for a string).
module stickslip_namelist_values
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_namelist, only: nml_file_t, nml_entry_t, nml_token_t, sanitize, lower, &
        edit_distance
    implicit none
    private
    public :: check_names, get_integer, get_real, get_logical, get_string, get_integers, &
        get_reals, is_given

contains

    !> Error (stat input) naming the first variable of group `group` that is not in `known`,
    !> with the closest known name when it is a likely misspelling (edit distance <= 2),
    !> otherwise the list of known names. No error when the group is absent.
    subroutine check_names(self, group, known, error)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group name (lower case, no '&').
        character(len=*), intent(in) :: group
        !> Its variables (lower case).
        character(len=*), intent(in) :: known(:)
        !> Set on the first unknown variable.
        type(error_type), allocatable, intent(out) :: error
        integer :: g, k
        g = self%find(group)
        if (g == 0) return
        do k = 1, self%groups(g)%nentries
            associate (en => self%groups(g)%entries(k))
                if (any(known == en%name)) cycle
                call fatal_error(error, self%path//":"//itoa(en%line)//": &"//group//" "// &
                                 en%name//": unknown variable "//suggestion(en%name, known), &
                                 stickslip_stat%input)
                return
            end associate
        end do
    end subroutine check_names

    !> "(did you mean x?)" for the closest of `known` within edit distance 2, otherwise
    !> "(known: a, b, ...)".
    function suggestion(name, known) result(s)
        character(len=*), intent(in) :: name
        character(len=*), intent(in) :: known(:)
        character(len=:), allocatable :: s
        integer :: k, d, best, kbest
        best = huge(1)
        kbest = 0
        do k = 1, size(known)
            d = edit_distance(name, trim(known(k)))
            if (d < best) then
                best = d
                kbest = k
            end if
        end do
        if (kbest > 0 .and. best <= 2 .and. best < len(name)) then
            s = "(did you mean "//trim(known(kbest))//"?)"
        else
            s = "(known: "
            do k = 1, size(known)
                s = s//trim(known(k))
                if (k < size(known)) s = s//", "
            end do
            s = s//")"
        end if
    end function suggestion

    !> Whether the case file gives the variable `name` in group `group` (lower case).
    logical function is_given(self, group, name)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group and variable names (lower case).
        character(len=*), intent(in) :: group, name
        integer :: g, k
        call locate(self, group, name, g, k)
        is_given = k > 0
    end function is_given

    !> The entry `name` of group `group`: g, k (0 when absent).
    subroutine locate(self, group, name, g, k)
        type(nml_file_t), intent(in) :: self
        character(len=*), intent(in) :: group, name
        integer, intent(out) :: g, k
        g = self%find(group)
        k = 0
        if (g == 0) return
        do k = 1, self%groups(g)%nentries
            if (self%groups(g)%entries(k)%name == name) return
        end do
        k = 0
    end subroutine locate

    !> Expand the values of an entry (repeat counts r*v) into tokens, at most `max_count`.
    !> Errors name the variable and the limit.
    subroutine expand(self, group, en, max_count, tokens, error)
        type(nml_file_t), intent(in) :: self
        character(len=*), intent(in) :: group
        type(nml_entry_t), intent(in) :: en
        integer, intent(in) :: max_count
        type(nml_token_t), allocatable, intent(out) :: tokens(:)
        type(error_type), allocatable, intent(out) :: error
        integer(int64) :: total, r
        integer :: v, star, m, k
        integer(int64), allocatable :: reps(:)
        allocate (reps(en%nvalues))
        total = 0
        do v = 1, en%nvalues
            reps(v) = 1
            star = 0
            if (.not. en%values(v)%quoted) star = index(en%values(v)%text, '*')
            if (star > 1) then
                if (verify(en%values(v)%text(1:star - 1), '0123456789') == 0) then
                    if (star - 1 > 12) then
                        r = huge(1_int64)/4
                    else
                        read (en%values(v)%text(1:star - 1), *) r
                    end if
                    if (r < 1 .or. star == len(en%values(v)%text)) then
                        call fatal_error(error, self%path//":"//itoa(en%values(v)%line)// &
                                         ": &"//group//" "//en%name//": repeat count '"// &
                                         sanitize(en%values(v)%text)// &
                                         "' must be r*value with r >= 1", stickslip_stat%input)
                        return
                    end if
                    reps(v) = r
                end if
            end if
            total = total + reps(v)
            if (total > max_count) then
                call fatal_error(error, self%path//":"//itoa(en%line)//": &"//group//" "// &
                                 en%name//": too many values (at most "//itoa(max_count)// &
                                 merge(" value) ", " values)", max_count == 1), &
                                 stickslip_stat%input)
                return
            end if
        end do
        allocate (tokens(total))
        m = 0
        do v = 1, en%nvalues
            star = 0
            if (reps(v) > 1 .or. .not. en%values(v)%quoted) star = index(en%values(v)%text, '*')
            do k = 1, int(reps(v))
                m = m + 1
                tokens(m) = en%values(v)
                if (star > 1) then
                    if (verify(en%values(v)%text(1:star - 1), '0123456789') == 0) &
                        tokens(m)%text = en%values(v)%text(star + 1:)
                end if
            end do
        end do
    end subroutine expand

    !> Integers of variable `name` of group `group` (allocated, absent: found = .false.), at
    !> most max_count of them. Errors (stat input) name the variable and its element.
    subroutine get_integers(self, group, name, values, found, max_count, error)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group and variable names (lower case).
        character(len=*), intent(in) :: group, name
        !> The values given.
        integer, allocatable, intent(out) :: values(:)
        !> The variable was given.
        logical, intent(out) :: found
        !> Most values accepted.
        integer, intent(in) :: max_count
        !> Set on the first bad value.
        type(error_type), allocatable, intent(out) :: error
        type(nml_token_t), allocatable :: tokens(:)
        integer :: g, k, m
        character(len=:), allocatable :: why
        call locate(self, group, name, g, k)
        found = k > 0
        if (.not. found) return
        call expand(self, group, self%groups(g)%entries(k), max_count, tokens, error)
        if (allocated(error)) return
        allocate (values(size(tokens)))
        do m = 1, size(tokens)
            call to_integer(tokens(m), values(m), why)
            if (len(why) > 0) then
                call value_error(self, group, name, tokens(m), m, max_count, why, error)
                return
            end if
        end do
    end subroutine get_integers

    !> Reals of variable `name` of group `group` (see file_get_integers); every value must be
    !> finite (NaN, Inf: error naming the element).
    subroutine get_reals(self, group, name, values, found, max_count, error)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group and variable names (lower case).
        character(len=*), intent(in) :: group, name
        !> The values given.
        real(dp), allocatable, intent(out) :: values(:)
        !> The variable was given.
        logical, intent(out) :: found
        !> Most values accepted.
        integer, intent(in) :: max_count
        !> Set on the first bad value.
        type(error_type), allocatable, intent(out) :: error
        type(nml_token_t), allocatable :: tokens(:)
        integer :: g, k, m
        character(len=:), allocatable :: why
        call locate(self, group, name, g, k)
        found = k > 0
        if (.not. found) return
        call expand(self, group, self%groups(g)%entries(k), max_count, tokens, error)
        if (allocated(error)) return
        allocate (values(size(tokens)))
        do m = 1, size(tokens)
            call to_real(tokens(m), values(m), why)
            if (len(why) > 0) then
                call value_error(self, group, name, tokens(m), m, max_count, why, error)
                return
            end if
        end do
    end subroutine get_reals

    !> One integer (unchanged when the variable is absent). Errors name the variable.
    subroutine get_integer(self, group, name, value, error, found)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group and variable names (lower case).
        character(len=*), intent(in) :: group, name
        !> The value; kept when absent.
        integer, intent(inout) :: value
        !> Set on a bad or repeated value.
        type(error_type), allocatable, intent(out) :: error
        !> The variable was given.
        logical, intent(out), optional :: found
        integer, allocatable :: v(:)
        logical :: given
        call get_integers(self, group, name, v, given, 1, error)
        if (present(found)) found = given
        if (given .and. .not. allocated(error)) value = v(1)
    end subroutine get_integer

    !> One finite real (unchanged when absent). Errors name the variable.
    subroutine get_real(self, group, name, value, error, found)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group and variable names (lower case).
        character(len=*), intent(in) :: group, name
        !> The value; kept when absent.
        real(dp), intent(inout) :: value
        !> Set on a bad or repeated value.
        type(error_type), allocatable, intent(out) :: error
        !> The variable was given.
        logical, intent(out), optional :: found
        real(dp), allocatable :: v(:)
        logical :: given
        call get_reals(self, group, name, v, given, 1, error)
        if (present(found)) found = given
        if (given .and. .not. allocated(error)) value = v(1)
    end subroutine get_real

    !> One logical (unchanged when absent): T, F, .true., .false., true, false (any case).
    subroutine get_logical(self, group, name, value, error)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group and variable names (lower case).
        character(len=*), intent(in) :: group, name
        !> The value; kept when absent.
        logical, intent(inout) :: value
        !> Set on a bad or repeated value.
        type(error_type), allocatable, intent(out) :: error
        type(nml_token_t), allocatable :: tokens(:)
        character(len=:), allocatable :: t
        integer :: g, k
        call locate(self, group, name, g, k)
        if (k == 0) return
        call expand(self, group, self%groups(g)%entries(k), 1, tokens, error)
        if (allocated(error)) return
        t = lower(tokens(1)%text)
        if (tokens(1)%quoted) then
            t = "?"
        else if (len(t) > 1) then
            if (t(1:1) == '.') t = t(2:)
            if (len(t) > 1) then
                if (t(len(t):len(t)) == '.') t = t(1:len(t) - 1)
            end if
        end if
        select case (t)
        case ('t', 'true')
            value = .true.
        case ('f', 'false')
            value = .false.
        case default
            call value_error(self, group, name, tokens(1), 1, 1, &
                             "not a logical (T, F, .true. or .false.)", error)
        end select
    end subroutine get_logical

    !> One quoted string of any length (unchanged when absent). An unquoted word is an error
    !> that says to quote it.
    subroutine get_string(self, group, name, value, error, found)
        !> The file.
        type(nml_file_t), intent(in) :: self
        !> Group and variable names (lower case).
        character(len=*), intent(in) :: group, name
        !> The value; kept when absent.
        character(len=:), allocatable, intent(inout) :: value
        !> Set on a bad or repeated value.
        type(error_type), allocatable, intent(out) :: error
        !> The variable was given.
        logical, intent(out), optional :: found
        type(nml_token_t), allocatable :: tokens(:)
        integer :: g, k
        call locate(self, group, name, g, k)
        if (present(found)) found = k > 0
        if (k == 0) return
        call expand(self, group, self%groups(g)%entries(k), 1, tokens, error)
        if (allocated(error)) return
        if (.not. tokens(1)%quoted) then
            call fatal_error(error, self%path//":"//itoa(tokens(1)%line)//": &"//group// &
                             " "//name//" = "//sanitize(tokens(1)%text)// &
                             ": a string must be quoted: "//name//" = '"// &
                             sanitize(tokens(1)%text)//"'", stickslip_stat%input)
            return
        end if
        value = tokens(1)%text
    end subroutine get_string

    !> The error of one bad value: "<path>:<line>: &group name[(i)] = value: why".
    subroutine value_error(self, group, name, token, i, count, why, error)
        type(nml_file_t), intent(in) :: self
        character(len=*), intent(in) :: group, name
        type(nml_token_t), intent(in) :: token
        integer, intent(in) :: i, count
        character(len=*), intent(in) :: why
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: what
        what = name
        if (count > 1) what = name//"("//itoa(i)//")"
        if (token%quoted) then
            what = what//" = '"//sanitize(token%text)//"'"
        else
            what = what//" = "//sanitize(token%text)
        end if
        call fatal_error(error, self%path//":"//itoa(token%line)//": &"//group//" "//what// &
                         ": "//why, stickslip_stat%input)
    end subroutine value_error

    !> Integer of a token; why = '' or the reason it is not one.
    subroutine to_integer(token, value, why)
        type(nml_token_t), intent(in) :: token
        integer, intent(out) :: value
        character(len=:), allocatable, intent(out) :: why
        integer :: a, k
        integer(int64) :: big
        value = 0
        why = ""
        if (token%quoted) then
            why = "a string where an integer is expected"
            return
        end if
        a = 1
        if (len(token%text) > 0) then
            if (scan(token%text(1:1), '+-') == 1) a = 2
        end if
        if (len(token%text) < a .or. verify(token%text(a:), '0123456789') /= 0) then
            if (is_real(token%text)) then
                why = "not an integer (a real where an integer is expected)"
            else
                why = "not an integer"
            end if
            return
        end if
        k = verify(token%text(a:), '0')
        if (k == 0) return
        if (len(token%text) - (a + k - 1) + 1 > 10) then
            why = "integer out of range (-"//itoa(huge(1))//" .. "//itoa(huge(1))//")"
            return
        end if
        read (token%text, *) big
        if (abs(big) > huge(1)) then
            why = "integer out of range (-"//itoa(huge(1))//" .. "//itoa(huge(1))//")"
            return
        end if
        value = int(big)
    end subroutine to_integer

    !> Finite real of a token; why = '' or the reason it is not one.
    subroutine to_real(token, value, why)
        type(nml_token_t), intent(in) :: token
        real(dp), intent(out) :: value
        character(len=:), allocatable, intent(out) :: why
        integer :: stat, k
        character(len=:), allocatable :: t
        value = 0.0_dp
        why = ""
        if (token%quoted) then
            why = "a string where a number is expected"
            return
        end if
        t = lower(token%text)
        if (t == 'nan' .or. t == '+nan' .or. t == '-nan' .or. t == 'inf' .or. &
            t == '+inf' .or. t == '-inf' .or. t == 'infinity' .or. t == '+infinity' .or. &
            t == '-infinity') then
            why = "not a finite number (NaN or Inf)"
            return
        end if
        if (.not. is_real(t)) then
            why = "not a number"
            return
        end if
        read (t, *, iostat=stat) value
        if (stat /= 0 .or. .not. ieee_is_finite(value)) then
            why = "not a finite number (out of the range of a double)"
            value = 0.0_dp
            return
        end if
        ! a nonzero literal that underflows to 0 (1e-400) must not pass for 0 (rho = 0
        ! means "automatic")
        k = scan(t, 'ed')
        if (k == 0) k = len(t) + 1
        if (value == 0.0_dp .and. scan(t(1:k - 1), '123456789') > 0) &
            why = "too small: underflows to 0 (the smallest double is about 4.9e-324)"
    end subroutine to_real

    !> Whether s is a Fortran real literal: [sign] digits [. digits] [e|d [sign] digits].
    pure logical function is_real(s)
        character(len=*), intent(in) :: s
        integer :: i, nd
        character(len=1) :: c
        is_real = .false.
        i = 1
        if (len(s) == 0) return
        if (scan(s(1:1), '+-') == 1) i = 2
        nd = 0
        do while (i <= len(s))
            if (scan(s(i:i), '0123456789') == 0) exit
            nd = nd + 1
            i = i + 1
        end do
        if (i <= len(s)) then
            if (s(i:i) == '.') then
                i = i + 1
                do while (i <= len(s))
                    if (scan(s(i:i), '0123456789') == 0) exit
                    nd = nd + 1
                    i = i + 1
                end do
            end if
        end if
        if (nd == 0) return
        if (i <= len(s)) then
            c = s(i:i)
            if (scan(c, 'eEdD') == 0) return
            i = i + 1
            if (i <= len(s)) then
                if (scan(s(i:i), '+-') == 1) i = i + 1
            end if
            if (i > len(s)) return
            if (verify(s(i:), '0123456789') /= 0) return
        end if
        is_real = .true.
    end function is_real
end module stickslip_namelist_values
