!> The &friction group of a case file: the contacts of the model (doc/contacts.md).
!>
!> Tangential directions: contact_dof with contact_dof2 (default 0: the ground), or
!> direction_file (a Matrix Market file, N x n_c). mu one per contact (required); normal_load
!> one per contact (required, except for contacts with a normal direction).
!> Contact laws (all optional): a normal direction per contact, as normal_dof/normal_dof2
!> (n = e_normal_dof - e_normal_dof2, 0 the ground; both 0: no normal, constant normal_load),
!> inline normal_direction (N values per contact, column-major) or normal_file (N x n_c); a
!> second tangential direction (2D friction) as tangent2_dof/tangent2_dof2, inline
!> tangent2_direction or tangent2_file (a zero column: 1D friction); gap [m], preload [N],
!> normal_stiffness [N/m], tangential_stiffness [N/m] one per contact. The directions are
!> stored as the N x n_c matrices of model_t; the form given is kept (friction_form_t) for
!> the echo in summary.nml and for messages.
module stickslip_case_friction
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_model, only: model_t
    use stickslip_namelist, only: nml_file_t
    use stickslip_namelist_values, only: check_names, get_integers, get_reals
    use stickslip_case_model, only: system_files_t, group_error, max_terms, max_dof, &
        take_reals, take_integers, take_file_variable, read_column_file, not_beside_file
    implicit none
    private
    public :: read_friction_group, friction_form_t, contact_law_variables

    !> The case-file variables of the contact laws (beyond contact_dof, contact_dof2,
    !> direction_file, mu, normal_load).
    character(len=*), parameter :: contact_law_variables(12) = [character(len=20) :: &
        "normal_dof", "normal_dof2", "normal_direction", "normal_file", "tangent2_dof", &
        "tangent2_dof2", "tangent2_direction", "tangent2_file", "gap", "preload", &
        "normal_stiffness", "tangential_stiffness"]

    !> How the normal and second tangential directions were given (for the echo in
    !> summary.nml and for messages): 'dof' (the DOF lists, kept here in full-model
    !> numbers), 'inline', 'file' (the file names kept here) or '' (not given).
    type :: friction_form_t
        character(len=8) :: normal = '', tangent2 = ''
        integer, allocatable :: normal_dof(:), normal_dof2(:), tangent2_dof(:), tangent2_dof2(:)
        !> normal_file / tangent2_file as written, resolved against the case's folder,
        !> absolute.
        character(len=:), allocatable :: normal_file, normal_path, normal_absolute
        character(len=:), allocatable :: tangent2_file, tangent2_path, tangent2_absolute
    end type friction_form_t

contains

    !> Read &friction (optional: no group, no contact). Errors (stat input; io for an
    !> unreadable file) name the case file, the group, the variable and the contact: lists
    !> of the wrong length, a DOF out of range, a direction given in two forms, a zero
    !> normal direction, a contact without normal direction and without normal_load.
    !> The checks of the values (signs, orthogonality, ...) are validate_model's.
    subroutine read_friction_group(nml, model, error, files, form)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model (ndof set): the contacts set (none when the group, contact_dof and
        !> direction_file are absent).
        type(model_t), intent(inout) :: model
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> The file variables: direction_file, direction_path, direction_absolute set when
        !> given.
        type(system_files_t), intent(inout), optional :: files
        !> How the contact-law directions were given.
        type(friction_form_t), intent(out), optional :: form
        type(friction_form_t) :: f
        logical :: found, load_given
        integer :: nc, j
        real(dp) :: load_j
        real(dp), allocatable :: dummy(:)
        character(len=:), allocatable :: given, path, absolute, per
        call check_names(nml, "friction", [character(len=20) :: "contact_dof", "contact_dof2", &
                                          "mu", "normal_load", "direction_file", &
                                          contact_law_variables], error)
        if (allocated(error)) return
        call take_file_variable(nml, "friction", "direction_file", given, path, absolute, error)
        if (allocated(error)) return
        if (allocated(path)) then
            call not_beside_file(nml, "friction", "contact_dof", "direction_file", error)
            if (allocated(error)) return
            call not_beside_file(nml, "friction", "contact_dof2", "direction_file", error)
            if (allocated(error)) return
            call read_column_file(nml, "friction", "direction_file", path, model%ndof, .true., &
                                  model%contact_direction, error)
            if (allocated(error)) return
            if (present(files)) then
                files%direction_file = given
                files%direction_path = path
                files%direction_absolute = absolute
            end if
            nc = size(model%contact_direction, 2)
            allocate (model%contact_dof(0), model%contact_dof2(0))
            per = "column of direction_file"
        else
            call get_integers(nml, "friction", "contact_dof", model%contact_dof, found, &
                              max_terms, error)
            if (allocated(error)) return
            if (.not. found) allocate (model%contact_dof(0))
            nc = size(model%contact_dof)
            per = "contact_dof"
        end if
        call take_reals(nml, "friction", "mu", nc, .true., 0.0_dp, model%mu, error, per)
        if (allocated(error)) return
        if (.not. allocated(path)) then
            call take_integers(nml, "friction", "contact_dof2", nc, 0, model%contact_dof2, error)
            if (allocated(error)) return
        end if

        call read_directions(nml, "normal", model%ndof, nc, per, model%normal_direction, &
                             f%normal, f%normal_dof, f%normal_dof2, f%normal_file, &
                             f%normal_path, f%normal_absolute, error)
        if (allocated(error)) return
        call read_directions(nml, "tangent2", model%ndof, nc, per, model%tangent2_direction, &
                             f%tangent2, f%tangent2_dof, f%tangent2_dof2, f%tangent2_file, &
                             f%tangent2_path, f%tangent2_absolute, error)
        if (allocated(error)) return

        ! normal_load: required for every contact without a normal direction
        call get_reals(nml, "friction", "normal_load", dummy, load_given, max_terms, error)
        if (allocated(error)) return
        if (f%normal == 'inline' .or. f%normal == 'file') then
            do j = 1, nc
                if (all(model%normal_direction(:, j) == 0.0_dp)) then
                    load_j = 0.0_dp
                    if (load_given) then
                        if (size(dummy) >= j) load_j = dummy(j)
                    end if
                    if (load_j == 0.0_dp) then
                        call group_error(nml, error, "&friction "// &
                                         form_variable("normal", f%normal)//": column "// &
                                         itoa(j)//" is zero and normal_load("//itoa(j)// &
                                         ") is not given or 0: contact "//itoa(j)//" has "// &
                                         "neither a normal direction nor a normal load")
                        return
                    end if
                end if
            end do
        end if
        if (load_given .or. len_trim(f%normal) == 0) then
            call take_reals(nml, "friction", "normal_load", nc, .true., 0.0_dp, &
                            model%normal_load, error, per)
            if (allocated(error)) return
        else
            allocate (model%normal_load(nc))
            model%normal_load = 0.0_dp
            do j = 1, nc
                if (all(model%normal_direction(:, j) == 0.0_dp)) then
                    call group_error(nml, error, "&friction normal_load: missing (contact "// &
                                     itoa(j)//" has no normal direction: it needs its "// &
                                     "normal load; give one value per "//per//", 0 for "// &
                                     "the unilateral contacts)")
                    return
                end if
            end do
        end if
        call optional_reals("gap", model%gap)
        if (allocated(error)) return
        call optional_reals("preload", model%preload)
        if (allocated(error)) return
        call optional_reals("normal_stiffness", model%normal_stiffness)
        if (allocated(error)) return
        call optional_reals("tangential_stiffness", model%tangential_stiffness)
        if (allocated(error)) return
        if (present(form)) form = f

    contains

        !> A per-contact list left unallocated when not given.
        subroutine optional_reals(name, a)
            character(len=*), intent(in) :: name
            real(dp), allocatable, intent(out) :: a(:)
            real(dp), allocatable :: values(:)
            logical :: here
            call get_reals(nml, "friction", name, values, here, max_terms, error)
            if (allocated(error) .or. .not. here) return
            call take_reals(nml, "friction", name, nc, .false., 0.0_dp, a, error, per)
        end subroutine optional_reals
    end subroutine read_friction_group

    !> The case-file variable of a form of directions: <kind>_dof, <kind>_direction,
    !> <kind>_file.
    pure function form_variable(kind, form) result(name)
        character(len=*), intent(in) :: kind, form
        character(len=:), allocatable :: name
        select case (form)
        case ('dof')
            name = kind//"_dof"
        case ('inline')
            name = kind//"_direction"
        case default
            name = kind//"_file"
        end select
    end function form_variable

    !> The N x n_c directions `d` of kind `kind` ('normal' or 'tangent2') from one of its
    !> three forms (<kind>_dof/<kind>_dof2, <kind>_direction, <kind>_file), unallocated when
    !> none is given. Errors: two forms given, a DOF out of range, equal DOFs (a zero
    !> direction), a wrong count of values or columns.
    subroutine read_directions(nml, kind, n, nc, per, d, form, dof, dof2, file, path, &
                               absolute, error)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: kind, per
        integer, intent(in) :: n, nc
        real(dp), allocatable, intent(out) :: d(:, :)
        character(len=*), intent(out) :: form
        integer, allocatable, intent(out) :: dof(:), dof2(:)
        character(len=:), allocatable, intent(out) :: file, path, absolute
        type(error_type), allocatable, intent(out) :: error
        logical :: has_dof, has_dof2, has_inline, has_file
        real(dp), allocatable :: values(:)
        integer, allocatable :: ivalues(:)
        integer :: j, nforms
        character(len=:), allocatable :: names
        form = ''
        call get_integers(nml, "friction", kind//"_dof", ivalues, has_dof, max_terms, error)
        if (allocated(error)) return
        call get_integers(nml, "friction", kind//"_dof2", ivalues, has_dof2, max_terms, error)
        if (allocated(error)) return
        call get_reals(nml, "friction", kind//"_direction", values, has_inline, &
                       max_dof*max_terms, error)
        if (allocated(error)) return
        call take_file_variable(nml, "friction", kind//"_file", file, path, absolute, error)
        if (allocated(error)) return
        has_file = allocated(path)
        nforms = count([has_dof .or. has_dof2, has_inline, has_file])
        if (nforms == 0) return
        if (nforms > 1) then
            names = ""
            if (has_dof) names = names//kind//"_dof, "
            if (has_dof2) names = names//kind//"_dof2, "
            if (has_inline) names = names//kind//"_direction, "
            if (has_file) names = names//kind//"_file, "
            call group_error(nml, error, "&friction "//names(1:len(names) - 2)// &
                             ": the "//kind//" directions given in more than one form "// &
                             "(give "//kind//"_dof/"//kind//"_dof2, or "//kind// &
                             "_direction, or "//kind//"_file)")
            return
        end if
        if (nc == 0) then
            call group_error(nml, error, "&friction "//form_variable(kind, &
                             merge('dof   ', 'inline', has_dof .or. has_dof2))// &
                             ": given without contacts (contact_dof or direction_file)")
            if (has_file) error%message = nml%path//": &friction "//kind// &
                "_file: given without contacts (contact_dof or direction_file)"
            return
        end if
        allocate (d(n, nc))
        d = 0.0_dp
        if (has_dof .or. has_dof2) then
            form = 'dof'
            call take_integers(nml, "friction", kind//"_dof", nc, 0, dof, error, per)
            if (allocated(error)) return
            call take_integers(nml, "friction", kind//"_dof2", nc, 0, dof2, error, per)
            if (allocated(error)) return
            do j = 1, nc
                if (dof(j) < 0 .or. dof(j) > n) then
                    call group_error(nml, error, "&friction "//kind//"_dof("//itoa(j)// &
                                     ") = "//itoa(dof(j))//": must be 0 (none) or a DOF in "// &
                                     "1.."//itoa(n)//" (ndof)")
                    return
                end if
                if (dof2(j) < 0 .or. dof2(j) > n) then
                    call group_error(nml, error, "&friction "//kind//"_dof2("//itoa(j)// &
                                     ") = "//itoa(dof2(j))//": must be 0 (the ground) or a "// &
                                     "DOF in 1.."//itoa(n)//" (ndof)")
                    return
                end if
                if (dof(j) == dof2(j) .and. dof(j) /= 0) then
                    call group_error(nml, error, "&friction "//kind//"_dof2("//itoa(j)// &
                                     ") = "//kind//"_dof("//itoa(j)//") = "//itoa(dof(j))// &
                                     ": the "//kind//" direction e_"//itoa(dof(j))//" - e_"// &
                                     itoa(dof(j))//" of contact "//itoa(j)//" is zero")
                    return
                end if
                if (dof(j) > 0) d(dof(j), j) = 1.0_dp
                if (dof2(j) > 0) d(dof2(j), j) = -1.0_dp
            end do
        else if (has_inline) then
            form = 'inline'
            if (size(values) /= n*nc) then
                call group_error(nml, error, "&friction "//kind//"_direction: "// &
                                 itoa(size(values))//" values given, expected ndof x "// &
                                 "contacts = "//itoa(n*nc)//" (ndof values per contact, "// &
                                 "column-major)")
                return
            end if
            d = reshape(values, [n, nc])
        else
            form = 'file'
            call read_column_file(nml, "friction", kind//"_file", path, n, .false., d, error)
            if (allocated(error)) return
            if (size(d, 2) /= nc) then
                call group_error(nml, error, "&friction "//kind//"_file '"//path//"': "// &
                                 itoa(size(d, 2))//" columns, expected one per contact ("// &
                                 itoa(nc)//")")
                return
            end if
        end if
    end subroutine read_directions
end module stickslip_case_friction
