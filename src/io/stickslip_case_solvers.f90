!> Readers of the case-file groups of the solvers and the run: &hbm, &euler, &reference,
!> &run, &output. Each reads one group of a parsed namelist file into its options type
!> (defaults where a variable is absent) and validates it with the library's validator, whose
!> message names the argument ("opts%harmonics = ...") and is put in case-file words with the
!> file path ("<path>: &hbm harmonics = ...", stickslip_case_messages).
module stickslip_case_solvers
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_solution, only: hbm_options_t
    use stickslip_hbm, only: validate_options
    use stickslip_checks, only: check_options_t, validate_check_options
    use stickslip_euler, only: euler_options_t, validate_euler_options
    use stickslip_reference_start, only: reference_start_options_t, &
        validate_reference_start_options
    use stickslip_namelist, only: nml_file_t
    use stickslip_model, only: model_t
    use stickslip_namelist_values, only: check_names, get_integer, get_real, get_logical, &
        get_string, get_integers
    use stickslip_case_model, only: group_error, max_dof, max_file_dof
    use stickslip_case_messages, only: to_case_message
    use stickslip_plot_units, only: plot_units_t
    implicit none
    private
    public :: read_hbm_group, read_euler_group, read_reference_group, read_run_group
    public :: read_output_group, default_output_dofs, known_methods

    !> Methods of &run method.
    character(len=10), parameter :: known_methods(8) = [character(len=10) :: 'hbm', 'euler', &
        'reference', 'all', 'study', 'sweep', 'robustness', 'modes']

contains

    !> Read &hbm (optional) into the solver options and the check options; validate both.
    subroutine read_hbm_group(nml, hbm_opts, check_opts, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> Weighted-residual options (defaults for absent variables).
        type(hbm_options_t), intent(out) :: hbm_opts
        !> Check options: harmonics_tol, max_harmonics, stability, verify_periods.
        type(check_options_t), intent(out) :: check_opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: start, solver
        character(len=*), parameter :: g = "hbm"
        call check_names(nml, g, [character(len=14) :: "harmonics", "odd_only", "rho", &
                             "samples", "tol", "start", "solver", "maxfev", "harmonics_tol", &
                             "max_harmonics", "stability", "verify_periods"], error)
        if (allocated(error)) return
        call get_integer(nml, g, "harmonics", hbm_opts%harmonics, error)
        if (allocated(error)) return
        call get_logical(nml, g, "odd_only", hbm_opts%odd_only, error)
        if (allocated(error)) return
        call get_real(nml, g, "rho", hbm_opts%rho, error)
        if (allocated(error)) return
        call get_integer(nml, g, "samples", hbm_opts%samples, error)
        if (allocated(error)) return
        call get_real(nml, g, "tol", hbm_opts%tol, error)
        if (allocated(error)) return
        start = trim(hbm_opts%start)
        call get_string(nml, g, "start", start, error)
        if (allocated(error)) return
        if (start /= 'auto' .and. start /= 'direct' .and. start /= 'ladder') then
            call group_error(nml, error, "&hbm start = '"//start// &
                             "': must be 'auto', 'direct' or 'ladder'")
            return
        end if
        hbm_opts%start = trim(start)
        solver = trim(hbm_opts%solver)
        call get_string(nml, g, "solver", solver, error)
        if (allocated(error)) return
        if (solver /= 'auto' .and. solver /= 'hybrj' .and. solver /= 'newton') then
            call group_error(nml, error, "&hbm solver = '"//solver// &
                             "': must be 'auto', 'hybrj' or 'newton'")
            return
        end if
        hbm_opts%solver = trim(solver)
        call get_integer(nml, g, "maxfev", hbm_opts%maxfev, error)
        if (allocated(error)) return
        call get_real(nml, g, "harmonics_tol", check_opts%harmonics_tol, error)
        if (allocated(error)) return
        call get_integer(nml, g, "max_harmonics", check_opts%max_harmonics, error)
        if (allocated(error)) return
        call get_logical(nml, g, "stability", check_opts%stability, error)
        if (allocated(error)) return
        call get_integer(nml, g, "verify_periods", check_opts%verify_periods, error)
        if (allocated(error)) return
        call validate_options(hbm_opts, error)
        if (allocated(error)) then
            call to_case_message(error, nml%path, ['opts'], ['hbm '])
            return
        end if
        call validate_check_options(check_opts, hbm_opts, error)
        if (allocated(error)) call to_case_message(error, nml%path, ['copts', 'opts '], &
                                                   ['hbm', 'hbm'])
    end subroutine read_hbm_group

    !> Read &euler (optional): steps_per_period, max_periods, tol; validate.
    subroutine read_euler_group(nml, opts, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> Time-stepping options (defaults for absent variables).
        type(euler_options_t), intent(out) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=*), parameter :: g = "euler"
        call check_names(nml, g, [character(len=16) :: "steps_per_period", "max_periods", &
                                 "tol"], error)
        if (allocated(error)) return
        call get_integer(nml, g, "steps_per_period", opts%steps_per_period, error)
        if (allocated(error)) return
        call get_integer(nml, g, "max_periods", opts%max_periods, error)
        if (allocated(error)) return
        call get_real(nml, g, "tol", opts%tol, error)
        if (allocated(error)) return
        call validate_euler_options(opts, error)
        if (allocated(error)) call to_case_message(error, nml%path, ['opts'], ['euler'])
    end subroutine read_euler_group

    !> Read &reference (optional): samples, bracket_steps, tol, maxfev, ode_tol, start;
    !> validate.
    subroutine read_reference_group(nml, opts, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> Reference options and start strategy (defaults for absent variables).
        type(reference_start_options_t), intent(out) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: start
        character(len=*), parameter :: g = "reference"
        call check_names(nml, g, [character(len=13) :: "samples", "bracket_steps", "tol", &
                                 "maxfev", "ode_tol", "start"], error)
        if (allocated(error)) return
        call get_integer(nml, g, "samples", opts%samples, error)
        if (allocated(error)) return
        call get_integer(nml, g, "bracket_steps", opts%bracket_steps, error)
        if (allocated(error)) return
        call get_real(nml, g, "tol", opts%tol, error)
        if (allocated(error)) return
        call get_integer(nml, g, "maxfev", opts%maxfev, error)
        if (allocated(error)) return
        call get_real(nml, g, "ode_tol", opts%ode_tol, error)
        if (allocated(error)) return
        start = trim(opts%start)
        call get_string(nml, g, "start", start, error)
        if (allocated(error)) return
        if (start /= 'auto' .and. start /= 'hbm' .and. start /= 'euler') then
            call group_error(nml, error, "&reference start = '"//start// &
                             "': must be 'auto', 'hbm' or 'euler'")
            return
        end if
        opts%start = trim(start)
        call validate_reference_start_options(opts, error)
        if (allocated(error)) call to_case_message(error, nml%path, ['opts'], ['reference'])
    end subroutine read_reference_group

    !> Read &run (optional): method, one of known_methods. `given` tells whether the file
    !> set it (read_case infers it from &study, &sweep or &robustness otherwise).
    subroutine read_run_group(nml, method, given, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The method ('hbm' when absent).
        character(len=:), allocatable, intent(out) :: method
        !> &run method was given.
        logical, intent(out) :: given
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        method = 'hbm'
        given = .false.
        call check_names(nml, "run", [character(len=6) :: "method"], error)
        if (allocated(error)) return
        call get_string(nml, "run", "method", method, error, given)
        if (allocated(error)) return
        if (.not. any(known_methods == method) .or. len_trim(method) == 0) then
            call group_error(nml, error, "&run method = '"//method//"': must be 'hbm', "// &
                             "'euler', 'reference', 'all', 'study', 'sweep', 'robustness' or "// &
                             "'modes'")
            return
        end if
        method = trim(method)
    end subroutine read_run_group

    !> Read &output (optional): directory (any length, not empty; default 'out') and dofs,
    !> the DOFs the result files hold, in the order given (each in 1..N, no duplicates;
    !> absent: default_output_dofs(model)). Errors (stat input) name &output and the
    !> variable, for dofs its element: "&output dofs(2) = 0: ...".
    subroutine read_output_group(nml, model, directory, dofs, dofs_given, full_field, &
                                 plot_amplitude, units, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model read (its ndof, contacts and forcing give the default selection).
        type(model_t), intent(in) :: model
        !> The output directory.
        character(len=:), allocatable, intent(out) :: directory
        !> The selected DOFs (the default selection when not given).
        integer, allocatable, intent(out) :: dofs(:)
        !> &output dofs was given.
        logical, intent(out) :: dofs_given
        !> &output full_field: write the harmonic coefficients of every DOF (full_field.mtx).
        logical, intent(out) :: full_field
        !> &output plot_amplitude: the amplitude the pictures draw, 'half_peak_to_peak'
        !> (default), 'first_harmonic' or 'max_abs'.
        character(len=:), allocatable, intent(out) :: plot_amplitude
        !> &output length_unit, force_unit, time_unit, frequency_unit: the units the
        !> pictures' labels name.
        type(plot_units_t), intent(out) :: units
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: text
        integer :: k2
        character(len=10), parameter :: unit_names(3) = [character(len=10) :: &
            "length", "force", "time"]
        integer :: k
        directory = 'out'
        dofs_given = .false.
        full_field = .false.
        plot_amplitude = 'half_peak_to_peak'
        call check_names(nml, "output", [character(len=14) :: "directory", "dofs", &
                                          "full_field", "plot_amplitude", "length_unit", &
                                          "force_unit", "time_unit", "frequency_unit"], error)
        if (allocated(error)) return
        do k = 1, 3
            select case (k)
            case (1)
                text = trim(units%length)
            case (2)
                text = trim(units%force)
            case default
                text = trim(units%time)
            end select
            call get_string(nml, "output", trim(unit_names(k))//"_unit", text, error)
            if (allocated(error)) return
            ! the label goes into a gnuplot string: plain printable text, no quotes
            if (len_trim(text) == 0 .or. len_trim(text) > len(units%length) .or. &
                scan(text, "'""\`") > 0 .or. any([(iachar(text(k2:k2)) < 32 .or. &
                                                  iachar(text(k2:k2)) > 126, &
                                                  k2=1, len(text))])) then
                call group_error(nml, error, "&output "//trim(unit_names(k))//"_unit = '"// &
                                 text//"': 1 to "//itoa(len(units%length))//" printable "// &
                                 "characters without quotes or backslashes, e.g. 'mm'")
                return
            end if
            select case (k)
            case (1)
                units%length = text
            case (2)
                units%force = text
            case default
                units%time = text
            end select
        end do
        text = 'rad/s'
        call get_string(nml, "output", "frequency_unit", text, error)
        if (allocated(error)) return
        select case (text)
        case ('rad/s')
            units%cycles = .false.
        case ('Hz')
            units%cycles = .true.
        case default
            call group_error(nml, error, "&output frequency_unit = '"//text// &
                             "': not 'rad/s' (omega) or 'Hz' (omega / 2 pi)")
            return
        end select
        call get_string(nml, "output", "plot_amplitude", plot_amplitude, error)
        if (allocated(error)) return
        select case (plot_amplitude)
        case ('half_peak_to_peak', 'first_harmonic', 'max_abs')
        case default
            call group_error(nml, error, "&output plot_amplitude = '"//plot_amplitude// &
                             "': not one of 'half_peak_to_peak', 'first_harmonic', 'max_abs'")
            return
        end select
        call get_logical(nml, "output", "full_field", full_field, error)
        if (allocated(error)) return
        call get_string(nml, "output", "directory", directory, error)
        if (allocated(error)) return
        if (len_trim(directory) == 0) then
            call group_error(nml, error, "&output directory: must not be empty")
            return
        end if
        directory = trim(directory)
        call get_integers(nml, "output", "dofs", dofs, dofs_given, max_file_dof, error)
        if (allocated(error)) return
        if (.not. dofs_given) then
            dofs = default_output_dofs(model)
            return
        end if
        do k = 1, size(dofs)
            if (dofs(k) < 1 .or. dofs(k) > model%ndof) then
                call group_error(nml, error, "&output dofs("//itoa(k)//") = "// &
                                 itoa(dofs(k))//": not a DOF of the model (1.."// &
                                 itoa(model%ndof)//")")
                return
            end if
            if (any(dofs(1:k - 1) == dofs(k))) then
                call group_error(nml, error, "&output dofs("//itoa(k)//") = "// &
                                 itoa(dofs(k))//": given twice (also dofs("// &
                                 itoa(findloc(dofs(1:k - 1), dofs(k), 1))//"))")
                return
            end if
        end do
    end subroutine read_output_group

    !> The DOFs the result files hold when &output dofs is absent: every DOF, 1..N, when
    !> N <= max_dof (64, the inline limit: the files of small models are unchanged);
    !> otherwise the contact DOFs (contact_dof and the nonzero contact_dof2, or every DOF
    !> where a column of contact_direction is nonzero, and the DOFs of the normal and second
    !> tangential directions) and the forced DOFs (force_dof; none
    !> for the load shapes of force_shape), in increasing order without duplicates.
    pure function default_output_dofs(model) result(dofs)
        !> The model.
        type(model_t), intent(in) :: model
        integer, allocatable :: dofs(:)
        logical, allocatable :: touched(:)
        integer :: i
        if (model%ndof <= max_dof) then
            dofs = [(i, i=1, model%ndof)]
            return
        end if
        allocate (touched(model%ndof))
        touched = .false.
        touched = marked(touched, model%contact_dof)
        touched = marked(touched, model%contact_dof2)
        touched = marked(touched, model%force_dof)
        if (allocated(model%contact_direction)) then
            if (size(model%contact_direction, 1) == model%ndof) touched = touched .or. &
                any(model%contact_direction /= 0.0_dp, dim=2)
        end if
        touched = touched .or. nonzero_rows(model%normal_direction)
        touched = touched .or. nonzero_rows(model%tangent2_direction)
        dofs = pack([(i, i=1, model%ndof)], touched)

    contains

        !> The rows of an N x m matrix with a nonzero entry (none when not allocated or of
        !> another size).
        pure function nonzero_rows(a) result(rows)
            real(dp), allocatable, intent(in) :: a(:, :)
            logical :: rows(model%ndof)
            rows = .false.
            if (.not. allocated(a)) return
            if (size(a, 1) /= model%ndof) return
            rows = any(a /= 0.0_dp, dim=2)
        end function nonzero_rows

        !> `flags` with the entries of `list` in range set (0: no second DOF).
        pure function marked(flags, list) result(out)
            logical, intent(in) :: flags(:)
            integer, allocatable, intent(in) :: list(:)
            logical :: out(size(flags))
            integer :: j
            out = flags
            if (.not. allocated(list)) return
            do j = 1, size(list)
                if (list(j) >= 1 .and. list(j) <= size(flags)) out(list(j)) = .true.
            end do
        end function marked
    end function default_output_dofs
end module stickslip_case_solvers
