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
!>     next_tangent2_dof per 2D contact against the next sector: the next sector's DOF of
!>                      its second tangent (required with next_dof on a 2D contact)
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
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_error, only: error_type, itoa
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, assemble_disk, nodal_diameter
    use stickslip_cyclic_modal, only: prepare_cyclic_modes
    use stickslip_sparse, only: max_dense_entries, sparse_matrix_t
    use stickslip_cyclic_sparse, only: diameter_frequency_errors
    use stickslip_kinds, only: dp
    use stickslip_diagnostics, only: diagnostics_t, level_warning
    use stickslip_namelist, only: nml_file_t, lower
    use stickslip_namelist_values, only: check_names, get_integer, get_integers, get_string
    use stickslip_case_model, only: group_error, max_terms
    implicit none
    private
    public :: cyclic_case_t, read_cyclic_group, cyclic_case_model, cyclic_boundary_dofs, &
        set_cyclic_boundary_dofs, measure_diameter_errors, forced_diameters, diameter_findings

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
        !> A reduced FE sector: the nodal diameters its harmonics reach, and per diameter
        !> the largest relative error of the reduced sector's natural frequencies (up to
        !> the run's highest harmonic frequency) and the full sector's lowest one [rad/s]
        !> (measure_diameter_errors; unallocated when not measured).
        integer, allocatable :: diameters(:)
        real(dp), allocatable :: diameter_errors(:), diameter_lowest(:)
    end type cyclic_case_t

    !> The largest relative error of a reduced sector's natural frequencies per nodal
    !> diameter (up to the run's highest harmonic frequency) that passes without a warning.
    real(dp), parameter, public :: diameter_error_warning = 1.0e-2_dp

    !> Most DOF pairs of a boundary.
    integer, parameter :: max_boundary = 100000

contains

    !> Read &cyclic (optional). The sector (`model`, validated) is kept in cc%sector; with
    !> model = 'disk' `model` is replaced by the full disk. Errors (stat input) name the file,
    !> &cyclic and the variable: unknown variables, sectors or engine_order missing or out of
    !> range, the boundaries missing, of other sizes, with a DOF out of range, repeated or on
    !> both sides, a next DOF out of range, on the right boundary or for a contact without
    !> that direction, model other than 'disk' or 'sector'.
    subroutine read_cyclic_group(nml, model, cc, hmax, error, defer)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The sector; the disk on return with model = 'disk'.
        type(model_t), intent(inout) :: model
        !> The group as read.
        type(cyclic_case_t), intent(out) :: cc
        !> Highest harmonic of the runs (&hbm harmonics).
        integer, intent(in) :: hmax
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Read and check only (the sector of Matrix Market files, still to be reduced):
        !> cyclic_case_model finishes.
        logical, intent(in), optional :: defer
        character(len=*), parameter :: g = "cyclic"
        character(len=:), allocatable :: kind
        logical :: found
        integer, allocatable :: list(:)
        cc%given = nml%find(g) > 0
        if (.not. cc%given) return
        call check_names(nml, g, [character(len=17) :: "sectors", "engine_order", "left_dofs", &
                         "right_dofs", "next_dof", "next_normal_dof", "next_tangent2_dof", &
                         "model"], error)
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
        call get_integers(nml, g, "next_tangent2_dof", list, found, max_terms, error)
        if (allocated(error)) return
        if (found) cc%cyc%next_tangent2_dof = list
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
        if (present(defer)) then
            if (defer) return
        end if
        call cyclic_case_model(nml, model, cc, hmax, error)
    end subroutine read_cyclic_group

    !> The nodal diameters, increasing, that the harmonics of a run reach: 1..harmonics
    !> (odd ones only with odd_only) and 0 (the static term) unless odd_only.
    !> With `engine_orders`, the union of those the harmonics reach under each of them (a
    !> run of nonlinear modes: its nodal diameters are the engine orders of its waves)
    !> instead of cyc%engine_order's.
    pure function forced_diameters(cyc, harmonics, odd_only, engine_orders) result(nds)
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> &hbm harmonics and odd_only.
        integer, intent(in) :: harmonics
        logical, intent(in) :: odd_only
        !> The engine orders of the run's waves (>= 0; default cyc%engine_order).
        integer, intent(in), optional :: engine_orders(:)
        integer, allocatable :: nds(:), eos(:)
        logical :: hit(0:cyc%sectors/2)
        integer :: h, k
        eos = [cyc%engine_order]
        if (present(engine_orders)) eos = engine_orders
        hit = .false.
        do k = 1, size(eos)
            do h = merge(1, 0, odd_only), harmonics
                if (odd_only .and. mod(h, 2) == 0) cycle
                hit(nodal_diameter(h, eos(k), cyc%sectors)) = .true.
            end do
        end do
        nds = pack([(k, k=0, cyc%sectors/2)], hit)
    end function forced_diameters

    !> The error of a reduced FE sector per nodal diameter (stickslip_cyclic_sparse,
    !> diameter_frequency_errors) into cc: the diameters of forced_diameters (under
    !> `engine_orders` when given), the
    !> frequencies up to `band` [rad/s]. `kmat`, `mmat`: the full sector; `cyc_full` its
    !> boundaries in full numbers; cc%cyc and `reduced` the reduced sector. Errors: those
    !> of the eigensolvers, prefixed with the file and &cyclic.
    subroutine measure_diameter_errors(nml, cc, kmat, mmat, cyc_full, reduced, harmonics, &
                                       odd_only, band, error, engine_orders)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The &cyclic group read, in reduced numbers; the errors on return.
        type(cyclic_case_t), intent(inout) :: cc
        !> The full sector's stiffness and mass.
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        !> Its symmetry in full numbers.
        type(cyclic_t), intent(in) :: cyc_full
        !> The reduced sector.
        type(model_t), intent(in) :: reduced
        !> &hbm harmonics and odd_only.
        integer, intent(in) :: harmonics
        logical, intent(in) :: odd_only
        !> The highest frequency compared [rad/s].
        real(dp), intent(in) :: band
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The engine orders of the run's waves (forced_diameters; default the forcing's).
        integer, intent(in), optional :: engine_orders(:)
        cc%diameters = forced_diameters(cc%cyc, harmonics, odd_only, engine_orders)
        call diameter_frequency_errors(kmat, mmat, cyc_full, reduced, cc%cyc, cc%diameters, &
                                       band, cc%diameter_errors, cc%diameter_lowest, error)
        if (allocated(error)) then
            error%message = nml%path//": &cyclic: the reduction's error per nodal "// &
                            "diameter: "//error%message
            deallocate (cc%diameters)
        end if
    end subroutine measure_diameter_errors

    !> A warning 'reduction_error_nd' into `diagnostics` when a measured error per nodal
    !> diameter (measure_diameter_errors) exceeds diameter_error_warning.
    subroutine diameter_findings(cc, diagnostics)
        !> The &cyclic case, measured.
        type(cyclic_case_t), intent(in) :: cc
        !> Where the finding goes.
        type(diagnostics_t), intent(inout) :: diagnostics
        character(len=300) :: buf
        integer :: k
        if (.not. allocated(cc%diameters)) return
        k = maxloc(cc%diameter_errors, 1)
        if (cc%diameter_errors(k) <= diameter_error_warning) return
        write (buf, '(a,i0,a,es10.3,a,i0,a)') "reduction: at nodal diameter ", &
            cc%diameters(k), " the reduced sector's natural frequencies are off by ", &
            cc%diameter_errors(k), " > ", nint(100*diameter_error_warning), "% (relative, "// &
            "up to the run's highest harmonic frequency): keep more modes (&reduction modes, "// &
            "max_frequency)"
        call diagnostics%add(level_warning, "reduction_error_nd", trim(buf))
    end subroutine diameter_findings

    !> The DOFs of `cyc` a reduction must keep: the left and right boundaries, then the
    !> nonzero next_dof and next_normal_dof entries (set_cyclic_boundary_dofs puts them
    !> back in that order).
    pure function cyclic_boundary_dofs(cyc) result(dofs)
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        integer, allocatable :: dofs(:)
        dofs = [cyc%left, cyc%right]
        if (allocated(cyc%next_dof)) dofs = [dofs, pack(cyc%next_dof, cyc%next_dof > 0)]
        if (allocated(cyc%next_normal_dof)) dofs = [dofs, pack(cyc%next_normal_dof, &
                                                            cyc%next_normal_dof > 0)]
        if (allocated(cyc%next_tangent2_dof)) dofs = [dofs, pack(cyc%next_tangent2_dof, &
                                                              cyc%next_tangent2_dof > 0)]
    end function cyclic_boundary_dofs

    !> Put renumbered cyclic_boundary_dofs back into `cyc`.
    subroutine set_cyclic_boundary_dofs(cyc, dofs)
        !> The symmetry.
        type(cyclic_t), intent(inout) :: cyc
        !> cyclic_boundary_dofs(cyc), renumbered.
        integer, intent(in) :: dofs(:)
        integer :: k
        k = size(cyc%left)
        cyc%left = dofs(1:k)
        cyc%right = dofs(k + 1:2*k)
        k = 2*k
        if (allocated(cyc%next_dof)) call take(cyc%next_dof)
        if (allocated(cyc%next_normal_dof)) call take(cyc%next_normal_dof)
        if (allocated(cyc%next_tangent2_dof)) call take(cyc%next_tangent2_dof)
    contains
        !> The positive entries of `list` from the next ones of `dofs`.
        subroutine take(list)
            integer, intent(inout) :: list(:)
            integer :: j
            do j = 1, size(list)
                if (list(j) <= 0) cycle
                k = k + 1
                list(j) = dofs(k)
            end do
        end subroutine take
    end subroutine set_cyclic_boundary_dofs

    !> The models of a &cyclic case read by read_cyclic_group, `model` being the final
    !> sector (e.g. reduced, cc%cyc in its numbers): cc%sector is the sector, with its
    !> cyclic modes prepared for the harmonics 0..hmax (stickslip_cyclic_modal), and with
    !> model = 'disk' `model` becomes the assembled disk. Errors (stat input): the disk too
    !> large for a dense model; those of validate_cyclic and assemble_disk, prefixed with
    !> the file and &cyclic.
    subroutine cyclic_case_model(nml, model, cc, hmax, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The sector; the disk on return with model = 'disk'.
        type(model_t), intent(inout) :: model
        !> The &cyclic group read.
        type(cyclic_case_t), intent(inout) :: cc
        !> Highest harmonic of the runs (&hbm harmonics).
        integer, intent(in) :: hmax
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer(int64) :: disk_dofs
        call validate_cyclic(model, cc%cyc, error)
        if (allocated(error)) then
            error%message = nml%path//": "//cyclic_words(error%message)
            return
        end if
        cc%sector = model
        if (cc%model == 'sector') then
            call prepare_cyclic_modes(cc%sector, cc%cyc, hmax, error)
            if (allocated(error)) error%message = nml%path//": &cyclic: "//error%message
            return
        end if
        disk_dofs = int(cc%cyc%sectors, int64)*(model%ndof - size(cc%cyc%right))
        if (disk_dofs**2 > max_dense_entries) then
            call group_error(nml, error, "&cyclic model = 'disk': the assembled disk would "// &
                             "have "//itoa(int(disk_dofs))//" DOFs, too many for a dense "// &
                             "model; run it on one sector (model = 'sector')")
            return
        end if
        call assemble_disk(cc%sector, cc%cyc, model, error)
        if (allocated(error)) then
            error%message = nml%path//": &cyclic: "//error%message
        end if
    end subroutine cyclic_case_model

    !> A message of validate_cyclic in the case file's words (&cyclic left_dofs, ...).
    function cyclic_words(message) result(words)
        character(len=*), intent(in) :: message
        character(len=:), allocatable :: words
        character(len=28), parameter :: from(8) = [character(len=28) :: "cyc%sectors", &
            "cyc%engine_order", "cyc%left, cyc%right", "cyc%left", "cyc%right", &
            "cyc%next_normal_dof", "cyc%next_tangent2_dof", "cyc%next_dof"]
        character(len=28), parameter :: to(8) = [character(len=28) :: "sectors", &
            "engine_order", "left_dofs, right_dofs", "left_dofs", "right_dofs", &
            "next_normal_dof", "next_tangent2_dof", "next_dof"]
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
