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
    use stickslip_namelist_values, only: check_names, get_integer, get_real, get_logical, get_string
    use stickslip_case_model, only: group_error
    use stickslip_case_messages, only: to_case_message
    implicit none
    private
    public :: read_hbm_group, read_euler_group, read_reference_group, read_run_group
    public :: read_output_group, known_methods

    !> Methods of &run method.
    character(len=10), parameter :: known_methods(7) = [character(len=10) :: 'hbm', 'euler', &
        'reference', 'all', 'study', 'sweep', 'robustness']

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
        character(len=:), allocatable :: start
        character(len=*), parameter :: g = "hbm"
        call check_names(nml, g, [character(len=14) :: "harmonics", "odd_only", "rho", &
                             "samples", "tol", "start", "maxfev", "harmonics_tol", &
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

    !> Read &reference (optional): samples, bracket_steps, tol, maxfev, start; validate.
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
                                 "maxfev", "start"], error)
        if (allocated(error)) return
        call get_integer(nml, g, "samples", opts%samples, error)
        if (allocated(error)) return
        call get_integer(nml, g, "bracket_steps", opts%bracket_steps, error)
        if (allocated(error)) return
        call get_real(nml, g, "tol", opts%tol, error)
        if (allocated(error)) return
        call get_integer(nml, g, "maxfev", opts%maxfev, error)
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
                             "'euler', 'reference', 'all', 'study', 'sweep' or 'robustness'")
            return
        end if
        method = trim(method)
    end subroutine read_run_group

    !> Read &output (optional): directory (any length, not empty; default 'out').
    subroutine read_output_group(nml, directory, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The output directory.
        character(len=:), allocatable, intent(out) :: directory
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        directory = 'out'
        call check_names(nml, "output", [character(len=9) :: "directory"], error)
        if (allocated(error)) return
        call get_string(nml, "output", "directory", directory, error)
        if (allocated(error)) return
        if (len_trim(directory) == 0) then
            call group_error(nml, error, "&output directory: must not be empty")
            return
        end if
        directory = trim(directory)
    end subroutine read_output_group
end module stickslip_case_solvers
