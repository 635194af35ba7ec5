!> Library messages in case-file words. The library names the arguments of the procedure
!> that failed ("opts%harmonics = 5000: must be <= 4096", "model%mu(2) = -0.1: must be >= 0");
!> a case-file user never saw those arguments, so the case reader and the driver rewrite
!> them into the group and variable of the case file ("&hbm harmonics = 5000: ...",
!> "&friction mu(2) = -0.1: ..."). This module holds that one translation.
module stickslip_case_messages
    use stickslip_error, only: error_type
    implicit none
    private
    public :: case_message, to_case_message, model_group

    !> Components of a model_t and the case-file group each comes from.
    character(len=*), parameter :: model_components(21) = [character(len=20) :: 'ndof', 'mass', &
        'stiffness', 'damping', 'omega', 'force_dof', 'force_harmonic', 'force_amplitude', &
        'force_phase', 'contact_dof', 'contact_dof2', 'mu', 'normal_load', 'force_shape', &
        'contact_direction', 'normal_direction', 'tangent2_direction', 'gap', 'preload', &
        'normal_stiffness', 'tangential_stiffness']
    character(len=*), parameter :: model_groups(21) = [character(len=8) :: 'system', 'system', &
        'system', 'system', 'forcing', 'forcing', 'forcing', 'forcing', 'forcing', 'friction', &
        'friction', 'friction', 'friction', 'forcing', 'friction', 'friction', 'friction', &
        'friction', 'friction', 'friction', 'friction']

contains

    !> The case-file group of the model_t component `component` ('system', 'forcing' or
    !> 'friction'; '' for a name that is not a component read from a case file).
    pure function model_group(component) result(group)
        !> A component name of model_t, e.g. 'mass' or 'normal_load'.
        character(len=*), intent(in) :: component
        character(len=:), allocatable :: group
        integer :: k
        group = ''
        do k = 1, size(model_components)
            if (component == trim(model_components(k))) group = trim(model_groups(k))
        end do
    end function model_group

    !> `message` with the library's argument names replaced by case-file names: every
    !> "<argument>%<component>" whose argument is `arguments(k)` becomes "&<groups(k)>
    !> <component>" the first time group groups(k) appears in the message and "<component>"
    !> after that; "model%<component>" maps by model_group; a message that starts with
    !> "<argument>:" starts with "&<group>:". Other text is kept as it is.
    !> Example: case_message("opts%step, opts%min_step: must be > 0", ['opts'], ['sweep'])
    !> is "&sweep step, min_step: must be > 0".
    pure function case_message(message, arguments, groups) result(text)
        !> A library message.
        character(len=*), intent(in) :: message
        !> Names of the dummy arguments that hold case-file variables (besides `model`).
        character(len=*), intent(in) :: arguments(:)
        !> The case-file group of each argument (without the '&').
        character(len=*), intent(in) :: groups(:)
        character(len=:), allocatable :: text, seen, word, component, group
        integer :: i, j, k, n

        text = ''
        seen = ' '
        n = len(message)
        i = 1
        do while (i <= n)
            if (.not. is_name_start(message, i)) then
                text = text//message(i:i)
                i = i + 1
                cycle
            end if
            j = i
            do while (j < n)
                if (.not. is_name_char(message(j + 1:j + 1))) exit
                j = j + 1
            end do
            word = message(i:j)
            group = ''
            do k = 1, min(size(arguments), size(groups))
                if (word == trim(arguments(k))) group = trim(groups(k))
            end do
            if (j < n .and. (len(group) > 0 .or. word == 'model')) then
                if (message(j + 1:j + 1) == '%' .and. j + 2 <= n) then
                    k = j + 2
                    do while (k < n)
                        if (.not. is_name_char(message(k + 1:k + 1))) exit
                        k = k + 1
                    end do
                    component = message(j + 2:k)
                    if (word == 'model') group = model_group(component)
                    if (len(group) > 0 .and. len(component) > 0) then
                        if (index(seen, ' '//group//' ') == 0) then
                            text = text//'&'//group//' '//component
                            seen = seen//group//' '
                        else
                            text = text//component
                        end if
                        i = k + 1
                        cycle
                    end if
                else if (i == 1 .and. message(j + 1:j + 1) == ':' .and. len(group) > 0) then
                    text = '&'//group
                    seen = seen//group//' '
                    i = j + 1
                    cycle
                end if
            end if
            text = text//word
            i = j + 1
        end do
    end function case_message

    !> Rewrite the message of `error` from a library procedure into case-file words
    !> (case_message) and prefix it with `path` ("<path>: "; no prefix when path is '').
    !> The stat code is kept.
    subroutine to_case_message(error, path, arguments, groups)
        !> The error raised by the library.
        type(error_type), intent(inout) :: error
        !> Path of the case file.
        character(len=*), intent(in) :: path
        !> Names of the dummy arguments that hold case-file variables (besides `model`).
        character(len=*), intent(in) :: arguments(:)
        !> The case-file group of each argument.
        character(len=*), intent(in) :: groups(:)
        error%message = case_message(error%message, arguments, groups)
        if (len(path) > 0) error%message = path//": "//error%message
    end subroutine to_case_message

    !> A name starts at message(i:i): a letter not preceded by a name character or '%'.
    pure logical function is_name_start(message, i)
        character(len=*), intent(in) :: message
        integer, intent(in) :: i
        is_name_start = is_letter(message(i:i))
        if (is_name_start .and. i > 1) is_name_start = &
            .not. (is_name_char(message(i - 1:i - 1)) .or. message(i - 1:i - 1) == '%')
    end function is_name_start

    pure logical function is_letter(c)
        character, intent(in) :: c
        is_letter = (c >= 'a' .and. c <= 'z') .or. (c >= 'A' .and. c <= 'Z')
    end function is_letter

    pure logical function is_name_char(c)
        character, intent(in) :: c
        is_name_char = is_letter(c) .or. (c >= '0' .and. c <= '9') .or. c == '_'
    end function is_name_char
end module stickslip_case_messages
