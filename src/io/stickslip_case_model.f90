!> Readers of the case-file groups that build the model: &system, &forcing, &friction. Each
!> reads one group of a parsed namelist file into `model_t`, with messages that start
!> "<path>[:<line>]: &<group> <variable>: ". The whole-model checks (symmetry, definiteness,
!> DOF ranges) are validate_model's, called by read_case once the three groups are read.
module stickslip_case_model
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_namelist, only: nml_file_t
    use stickslip_namelist_values, only: check_names, get_integer, get_real, get_integers, get_reals
    implicit none
    private
    public :: read_system_group, read_forcing_group, read_friction_group
    public :: max_dof, max_terms, group_error

    !> Largest ndof a case file can hold (host codes calling the library have no limit).
    integer, parameter :: max_dof = 64
    !> Largest number of forcing terms or contacts (and of entries of a list) in a case file.
    integer, parameter :: max_terms = 256

contains

    !> Read &system (required): ndof (1..max_dof), mass, stiffness (ndof**2 values each,
    !> column-major, required) and damping (default 0). Errors (stat input) name the variable.
    subroutine read_system_group(nml, model, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model: ndof, mass, stiffness, damping set.
        type(model_t), intent(inout) :: model
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer :: n
        logical :: found
        if (nml%find("system") == 0) then
            call group_error(nml, error, "&system: required group not found")
            return
        end if
        call check_names(nml, "system", [character(len=9) :: "ndof", "mass", "stiffness", &
                                        "damping"], error)
        if (allocated(error)) return
        n = 0
        call get_integer(nml, "system", "ndof", n, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&system ndof: missing (number of degrees of freedom)")
            return
        end if
        if (n < 1 .or. n > max_dof) then
            call group_error(nml, error, "&system ndof = "//itoa(n)//": must be in 1.."// &
                             itoa(max_dof)//" in a case file (larger models: call the library)")
            return
        end if
        model%ndof = n
        call take_matrix("mass", .true., model%mass)
        if (allocated(error)) return
        call take_matrix("stiffness", .true., model%stiffness)
        if (allocated(error)) return
        call take_matrix("damping", .false., model%damping)

    contains

        subroutine take_matrix(name, required, a)
            character(len=*), intent(in) :: name
            logical, intent(in) :: required
            real(dp), allocatable, intent(out) :: a(:, :)
            real(dp), allocatable :: values(:)
            logical :: given
            call get_reals(nml, "system", name, values, given, max_dof**2, error)
            if (allocated(error)) return
            if (.not. given) then
                if (required) then
                    call group_error(nml, error, "&system "//name//": missing ("// &
                                     "ndof**2 = "//itoa(n*n)//" values, column-major)")
                    return
                end if
                allocate (a(n, n))
                a = 0.0_dp
                return
            end if
            if (size(values) /= n*n) then
                call group_error(nml, error, "&system "//name//": "//itoa(size(values))// &
                                 " values given, expected ndof**2 = "//itoa(n*n)// &
                                 " (column-major)")
                return
            end if
            a = reshape(values, [n, n])
        end subroutine take_matrix
    end subroutine read_system_group

    !> Read &forcing (required): omega (required), force_dof (at least one), force_amplitude
    !> (one per force_dof), force_harmonic (default 1), force_phase (default 0).
    subroutine read_forcing_group(nml, model, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model: omega and the forcing terms set.
        type(model_t), intent(inout) :: model
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        logical :: found
        integer :: nf
        real(dp) :: omega
        if (nml%find("forcing") == 0) then
            call group_error(nml, error, "&forcing: required group not found")
            return
        end if
        call check_names(nml, "forcing", [character(len=15) :: "omega", "force_dof", &
                             "force_harmonic", "force_amplitude", "force_phase"], error)
        if (allocated(error)) return
        omega = 0.0_dp
        call get_real(nml, "forcing", "omega", omega, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, &
                             "&forcing omega: missing (angular frequency of the forcing, rad/s)")
            return
        end if
        model%omega = omega
        call get_integers(nml, "forcing", "force_dof", model%force_dof, found, max_terms, error)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&forcing force_dof: missing (at least one forcing term)")
            return
        end if
        nf = size(model%force_dof)
        call take_reals(nml, "forcing", "force_amplitude", nf, .true., 0.0_dp, &
                        model%force_amplitude, error)
        if (allocated(error)) return
        call take_reals(nml, "forcing", "force_phase", nf, .false., 0.0_dp, &
                        model%force_phase, error)
        if (allocated(error)) return
        call take_integers(nml, "forcing", "force_harmonic", nf, 1, model%force_harmonic, error)
    end subroutine read_forcing_group

    !> Read &friction (optional: no group, no contact): contact_dof, mu and normal_load (one
    !> per contact, required with contact_dof), contact_dof2 (default 0: the ground).
    subroutine read_friction_group(nml, model, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model: the contacts set (none when the group or contact_dof is absent).
        type(model_t), intent(inout) :: model
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        logical :: found
        integer :: nc
        call check_names(nml, "friction", [character(len=12) :: "contact_dof", "contact_dof2", &
                                          "mu", "normal_load"], error)
        if (allocated(error)) return
        call get_integers(nml, "friction", "contact_dof", model%contact_dof, found, max_terms, &
                              error)
        if (allocated(error)) return
        if (.not. found) allocate (model%contact_dof(0))
        nc = size(model%contact_dof)
        call take_reals(nml, "friction", "mu", nc, .true., 0.0_dp, model%mu, error)
        if (allocated(error)) return
        call take_reals(nml, "friction", "normal_load", nc, .true., 0.0_dp, model%normal_load, &
                        error)
        if (allocated(error)) return
        call take_integers(nml, "friction", "contact_dof2", nc, 0, model%contact_dof2, error)
    end subroutine read_friction_group

    !> `count` reals of a per-term list (one per force_dof or contact_dof); `default` for
    !> each when absent and not required.
    subroutine take_reals(nml, group, name, count, required, default, a, error)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name
        integer, intent(in) :: count
        logical, intent(in) :: required
        real(dp), intent(in) :: default
        real(dp), allocatable, intent(out) :: a(:)
        type(error_type), allocatable, intent(out) :: error
        logical :: given
        call get_reals(nml, group, name, a, given, max_terms, error)
        if (allocated(error)) return
        if (.not. given) then
            allocate (a(count))
            a = default
            if (.not. required .or. count == 0) return
            call count_error(nml, group, name, 0, count, error)
            return
        end if
        if (size(a) /= count) call count_error(nml, group, name, size(a), count, error)
    end subroutine take_reals

    !> `count` integers of a per-term list; `default` for each when absent.
    subroutine take_integers(nml, group, name, count, default, a, error)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name
        integer, intent(in) :: count
        integer, intent(in) :: default
        integer, allocatable, intent(out) :: a(:)
        type(error_type), allocatable, intent(out) :: error
        logical :: given
        call get_integers(nml, group, name, a, given, max_terms, error)
        if (allocated(error)) return
        if (.not. given) then
            allocate (a(count))
            a = default
            return
        end if
        if (size(a) /= count) call count_error(nml, group, name, size(a), count, error)
    end subroutine take_integers

    subroutine count_error(nml, group, name, given, count, error)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name
        integer, intent(in) :: given, count
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: per
        per = "contact_dof"
        if (group == "forcing") per = "force_dof"
        call group_error(nml, error, "&"//group//" "//name//": "//itoa(given)// &
                         " values given, expected "//itoa(count)//" (one per entry of "// &
                         per//")")
    end subroutine count_error

    !> An input error "<path>: <message>".
    subroutine group_error(nml, error, message)
        !> The parsed case file (its path).
        type(nml_file_t), intent(in) :: nml
        !> The error made.
        type(error_type), allocatable, intent(out) :: error
        !> "&group variable: what is wrong".
        character(len=*), intent(in) :: message
        call fatal_error(error, nml%path//": "//message, stickslip_stat%input)
    end subroutine group_error
end module stickslip_case_model
