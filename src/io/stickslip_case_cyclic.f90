!> The &cyclic group of a case file: the model of &system, &forcing and &friction is one
!> sector of a bladed disk of identical sectors (stickslip_cyclic, doc/cyclic.md).
!>
!>     sectors          N, the number of sectors (2 to 1000; required)
!>     engine_order     EO of the forcing (>= 0; required): sector s forced like sector 0
!>                      delayed by EO s / N of a period
!>     left_dofs        the sector's left boundary DOFs (required)
!>     right_dofs       its right boundary DOFs, paired with left_dofs one to one: right_dofs(k)
!>                      of sector s is left_dofs(k) of sector s + 1 (required)
!>     next_dof         per &friction contact (0: none): the DOF of the next sector the
!>                      contact slips against (v(contact_dof) - v_next(next_dof))
!>     next_normal_dof  per contact (0: none): the DOF of the next sector its normal
!>                      (normal_dof) acts against
!>     model            'sector' (the default): the weighted residual on one sector, the tuned
!>                      disk's travelling wave (methods 'hbm' and 'sweep'; their stability is
!>                      the assembled disk's); 'disk':
!>                      every method runs on the full disk assembled from the sector (N
!>                      copies, the boundaries merged, the forcing phased, the contacts
!>                      copied)
!> Every message names the case file, &cyclic and the variable.
module stickslip_case_cyclic
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, assemble_disk
    use stickslip_namelist, only: nml_file_t, lower
    use stickslip_namelist_values, only: check_names, get_integer, get_integers, get_string
    use stickslip_case_model, only: group_error, max_terms
    implicit none
    private
    public :: cyclic_case_t, read_cyclic_group

    !> &cyclic as read, and the sector (with model = 'disk' the case's model is the assembled
    !> disk; with 'sector' it is the sector itself).
    type :: cyclic_case_t
        !> The group was given.
        logical :: given = .false.
        !> 'sector' or 'disk'.
        character(len=8) :: model = 'sector'
        !> The symmetry.
        type(cyclic_t) :: cyc
        !> The sector's model (with model = 'disk': the case's model is the disk).
        type(model_t) :: sector
    end type cyclic_case_t

    !> Most DOF pairs of a boundary.
    integer, parameter :: max_boundary = 100000

contains

    !> Read &cyclic (optional). The sector (`model`, validated) is kept in cc%sector; with
    !> model = 'disk' `model` is replaced by the full disk. Errors (stat input) name the file,
    !> &cyclic and the variable: unknown variables, sectors or engine_order missing or out of
    !> range, the boundaries missing, of other sizes, with a DOF out of range, repeated or on
    !> both sides, a next DOF out of range, on the right boundary or for a contact without
    !> that direction, model other than 'disk' or 'sector'.
    subroutine read_cyclic_group(nml, model, cc, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The sector; the disk on return with model = 'disk'.
        type(model_t), intent(inout) :: model
        !> The group as read.
        type(cyclic_case_t), intent(out) :: cc
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=*), parameter :: g = "cyclic"
        character(len=:), allocatable :: kind
        logical :: found
        integer, allocatable :: list(:)
        cc%given = nml%find(g) > 0
        if (.not. cc%given) return
        call check_names(nml, g, [character(len=16) :: "sectors", "engine_order", "left_dofs", &
                         "right_dofs", "next_dof", "next_normal_dof", "model"], error)
        if (allocated(error)) return
        call get_integer(nml, g, "sectors", cc%cyc%sectors, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&cyclic sectors: missing (the number of sectors N)")
            return
        end if
        call get_integer(nml, g, "engine_order", cc%cyc%engine_order, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&cyclic engine_order: missing (the engine order "// &
                             "EO of the forcing, 0 for a standing load)")
            return
        end if
        call get_integers(nml, g, "left_dofs", list, found, max_boundary, error)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&cyclic left_dofs: missing (the sector's left "// &
                             "boundary DOFs, paired with right_dofs)")
            return
        end if
        cc%cyc%left = list
        call get_integers(nml, g, "right_dofs", list, found, max_boundary, error)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&cyclic right_dofs: missing (the sector's right "// &
                             "boundary DOFs: right_dofs(k) of sector s is left_dofs(k) of "// &
                             "sector s + 1)")
            return
        end if
        cc%cyc%right = list
        call get_integers(nml, g, "next_dof", list, found, max_terms, error)
        if (allocated(error)) return
        if (found) cc%cyc%next_dof = list
        call get_integers(nml, g, "next_normal_dof", list, found, max_terms, error)
        if (allocated(error)) return
        if (found) cc%cyc%next_normal_dof = list
        kind = trim(cc%model)
        call get_string(nml, g, "model", kind, error)
        if (allocated(error)) return
        kind = lower(trim(kind))
        call validate_cyclic(model, cc%cyc, error)
        if (allocated(error)) then
            error%message = nml%path//": "//cyclic_words(error%message)
            return
        end if
        select case (kind)
        case ('disk', 'sector')
        case default
            call group_error(nml, error, "&cyclic model = '"//kind//"': must be 'disk' or "// &
                             "'sector'")
            return
        end select
        cc%model = kind
        cc%sector = model
        if (kind == 'sector') return
        call assemble_disk(cc%sector, cc%cyc, model, error)
        if (allocated(error)) then
            error%message = nml%path//": &cyclic: "//error%message
        end if

    end subroutine read_cyclic_group

    !> A message of validate_cyclic in the case file's words (&cyclic left_dofs, ...).
    function cyclic_words(message) result(words)
        character(len=*), intent(in) :: message
        character(len=:), allocatable :: words
        character(len=28), parameter :: from(7) = [character(len=28) :: "cyc%sectors", &
            "cyc%engine_order", "cyc%left, cyc%right", "cyc%left", "cyc%right", &
            "cyc%next_normal_dof", "cyc%next_dof"]
        character(len=28), parameter :: to(7) = [character(len=28) :: "sectors", &
            "engine_order", "left_dofs, right_dofs", "left_dofs", "right_dofs", &
            "next_normal_dof", "next_dof"]
        integer :: k
        words = message
        do k = 1, size(from)
            if (index(words, trim(from(k))) == 1) then
                words = trim(to(k))//words(len_trim(from(k)) + 1:)
                exit
            end if
        end do
        words = "&cyclic "//words
    end function cyclic_words
end module stickslip_case_cyclic
