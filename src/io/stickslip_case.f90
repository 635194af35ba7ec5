!> The case file: namelist groups &system, &forcing, &friction, &hbm, &output read into a
!> `case_t` (the model, the solver options and the output directory), validated with messages
!> that name the file, the group, the variable and what is wrong. Also writes a case back as
!> namelist text (the effective case echoed into the summary). Knows nothing of the solver.
module stickslip_case
    use, intrinsic :: iso_fortran_env, only: iostat_end
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, validate_model
    use stickslip_solution, only: hbm_options_t
    use stickslip_hbm, only: validate_options
    use stickslip_checks, only: check_options_t, validate_check_options
    use stickslip_euler, only: euler_options_t
    use stickslip_reference, only: reference_options_t, validate_reference_options
    use stickslip_study, only: study_options_t, default_study_options, validate_study_options
    use stickslip_sweep, only: sweep_options_t, validate_sweep_options
    use stickslip_robustness, only: robustness_options_t, default_robustness_options, &
        validate_robustness_options
    implicit none
    private
    public :: case_t, read_case, write_case, max_dof, max_terms
    public :: put, rtoa, ltoa, rlist, ilist, llist

    !> Largest ndof a case file can hold (host codes calling the library have no limit).
    integer, parameter :: max_dof = 64
    !> Largest number of forcing terms or contacts a case file can hold.
    integer, parameter :: max_terms = 256

    real(dp), parameter :: unset = -huge(1.0_dp)
    integer, parameter :: iunset = -huge(1)

    !> A case: where it came from, the model, the solver options and where results go.
    type :: case_t
        !> Path of the case file ('' for a case built in memory).
        character(len=:), allocatable :: path
        !> The structure, its contacts and forcing.
        type(model_t) :: model
        !> Method: 'hbm' (weighted residual), 'euler' (implicit Euler time stepping),
        !> 'reference' (exact event-driven), 'all' (the three side by side) or 'study' (the
        !> work-precision study).
        character(len=16) :: method = 'hbm'
        !> Weighted-residual options (&hbm).
        type(hbm_options_t) :: hbm
        !> What to check about a weighted-residual solution (&hbm harmonics_tol,
        !> max_harmonics, stability, verify_periods).
        type(check_options_t) :: checks
        !> Time-stepping options (&euler).
        type(euler_options_t) :: euler
        !> Exact reference options (&reference).
        type(reference_options_t) :: reference
        !> Work-precision study options (&study).
        type(study_options_t) :: study = study_options_t()
        !> Forced-response curve options (&sweep; used by method 'sweep').
        type(sweep_options_t) :: sweep
        !> The &sweep group was given.
        logical :: has_sweep = .false.
        !> Robustness study options (&robustness; used by method 'robustness').
        type(robustness_options_t) :: robustness = robustness_options_t()
        !> Output directory (&output directory), created if missing.
        character(len=:), allocatable :: directory
    end type case_t

contains

    !> Read and validate the case file `path`. Errors: stat io if the file cannot be opened;
    !> stat input for a missing required group, a malformed group, an unknown variable, a
    !> missing, inconsistent, non-finite or out-of-range value. Every message starts with
    !> "<path>: &<group> <variable>: ".
    subroutine read_case(path, case, error)
        !> Path of the namelist file.
        character(len=*), intent(in) :: path
        !> The case read.
        type(case_t), intent(out) :: case
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat
        character(len=512) :: msg
        ! &system
        integer :: ndof
        real(dp) :: mass(max_dof**2), stiffness(max_dof**2), damping(max_dof**2)
        ! &forcing
        real(dp) :: omega
        integer :: force_dof(max_terms), force_harmonic(max_terms)
        real(dp) :: force_amplitude(max_terms), force_phase(max_terms)
        ! &friction
        integer :: contact_dof(max_terms), contact_dof2(max_terms)
        real(dp) :: mu(max_terms), normal_load(max_terms)
        ! &hbm
        integer :: harmonics, samples, maxfev, max_harmonics, verify_periods
        logical :: odd_only, stability
        real(dp) :: rho, tol, harmonics_tol
        character(len=16) :: start
        ! &output
        character(len=1024) :: directory
        ! &run, &euler
        character(len=16) :: method
        integer :: steps_per_period, max_periods
        real(dp) :: euler_tol
        namelist /system/ ndof, mass, stiffness, damping
        namelist /forcing/ omega, force_dof, force_harmonic, force_amplitude, force_phase
        namelist /friction/ contact_dof, contact_dof2, mu, normal_load
        namelist /hbm/ harmonics, odd_only, rho, samples, tol, start, maxfev, harmonics_tol, &
            max_harmonics, stability, verify_periods
        namelist /output/ directory
        namelist /run/ method
        integer :: n, nf, nc
        type(hbm_options_t) :: defaults
        type(check_options_t) :: check_defaults
        type(euler_options_t) :: euler_defaults

        case%path = path
        call open_copy(path, u, error)
        if (allocated(error)) return

        ndof = iunset
        mass = unset
        stiffness = unset
        damping = unset
        rewind (u)
        read (u, nml=system, iostat=stat, iomsg=msg)
        call group_status("system", .true.)
        if (allocated(error)) return

        omega = unset
        force_dof = iunset
        force_harmonic = iunset
        force_amplitude = unset
        force_phase = unset
        rewind (u)
        read (u, nml=forcing, iostat=stat, iomsg=msg)
        call group_status("forcing", .true.)
        if (allocated(error)) return

        contact_dof = iunset
        contact_dof2 = iunset
        mu = unset
        normal_load = unset
        rewind (u)
        read (u, nml=friction, iostat=stat, iomsg=msg)
        call group_status("friction", .false.)
        if (allocated(error)) return

        harmonics = defaults%harmonics
        odd_only = defaults%odd_only
        rho = defaults%rho
        samples = defaults%samples
        tol = defaults%tol
        start = defaults%start
        maxfev = defaults%maxfev
        harmonics_tol = check_defaults%harmonics_tol
        max_harmonics = check_defaults%max_harmonics
        stability = check_defaults%stability
        verify_periods = check_defaults%verify_periods
        rewind (u)
        read (u, nml=hbm, iostat=stat, iomsg=msg)
        call group_status("hbm", .false.)
        if (allocated(error)) return

        directory = 'out'
        rewind (u)
        read (u, nml=output, iostat=stat, iomsg=msg)
        call group_status("output", .false.)
        if (allocated(error)) return

        method = 'hbm'
        rewind (u)
        read (u, nml=run, iostat=stat, iomsg=msg)
        call group_status("run", .false.)
        if (allocated(error)) return

        steps_per_period = euler_defaults%steps_per_period
        max_periods = euler_defaults%max_periods
        euler_tol = euler_defaults%tol
        call read_euler_group()
        call group_status("euler", .false.)
        if (allocated(error)) return

        call read_reference_group()
        call group_status("reference", .false.)
        if (allocated(error)) return

        call read_study_group()
        call group_status("study", .false.)
        if (allocated(error)) return

        call read_sweep_group()
        call group_status("sweep", .false.)
        if (allocated(error)) return

        call read_robustness_group()
        call group_status("robustness", .false.)
        if (allocated(error)) return
        close (u)

        ! &system
        if (ndof == iunset) then
            call input_error("&system ndof: missing (number of degrees of freedom)")
            return
        end if
        if (ndof < 1 .or. ndof > max_dof) then
            call input_error("&system ndof = "//itoa(ndof)//": must be in 1.."//itoa(max_dof)// &
                             " in a case file (larger models: call the library)")
            return
        end if
        n = ndof
        case%model%ndof = n
        call take_matrix("mass", mass, .true., case%model%mass)
        if (allocated(error)) return
        call take_matrix("stiffness", stiffness, .true., case%model%stiffness)
        if (allocated(error)) return
        call take_matrix("damping", damping, .false., case%model%damping)
        if (allocated(error)) return

        ! &forcing
        if (omega == unset) then
            call input_error("&forcing omega: missing (angular frequency of the forcing, rad/s)")
            return
        end if
        case%model%omega = omega
        nf = count_given_int(force_dof)
        if (nf < 0) then
            call input_error("&forcing force_dof: entries must be given without gaps")
            return
        end if
        if (nf == 0) then
            call input_error("&forcing force_dof: missing (at least one forcing term)")
            return
        end if
        call take_real("&forcing", "force_amplitude", force_amplitude, nf, .true., 0.0_dp, &
                       case%model%force_amplitude)
        if (allocated(error)) return
        call take_real("&forcing", "force_phase", force_phase, nf, .false., 0.0_dp, &
                       case%model%force_phase)
        if (allocated(error)) return
        call take_int("&forcing", "force_harmonic", force_harmonic, nf, 1, &
                      case%model%force_harmonic)
        if (allocated(error)) return
        case%model%force_dof = force_dof(1:nf)

        ! &friction
        nc = count_given_int(contact_dof)
        if (nc < 0) then
            call input_error("&friction contact_dof: entries must be given without gaps")
            return
        end if
        call take_real("&friction", "mu", mu, nc, .true., 0.0_dp, case%model%mu)
        if (allocated(error)) return
        call take_real("&friction", "normal_load", normal_load, nc, .true., 0.0_dp, &
                       case%model%normal_load)
        if (allocated(error)) return
        call take_int("&friction", "contact_dof2", contact_dof2, nc, 0, case%model%contact_dof2)
        if (allocated(error)) return
        case%model%contact_dof = contact_dof(1:nc)

        ! &hbm, &output
        if (.not. ieee_is_finite(rho)) then
            call input_error("&hbm rho: not a finite number")
            return
        end if
        if (.not. ieee_is_finite(tol)) then
            call input_error("&hbm tol: not a finite number")
            return
        end if
        case%hbm%harmonics = harmonics
        case%hbm%odd_only = odd_only
        case%hbm%rho = rho
        case%hbm%samples = samples
        case%hbm%tol = tol
        if (len_trim(start) > len(case%hbm%start)) then
            call input_error("&hbm start = '"//trim(start)// &
                             "': must be 'auto', 'direct' or 'ladder'")
            return
        end if
        case%hbm%start = trim(start)
        case%hbm%maxfev = maxfev
        if (.not. ieee_is_finite(harmonics_tol)) then
            call input_error("&hbm harmonics_tol: not a finite number")
            return
        end if
        case%checks%harmonics_tol = harmonics_tol
        case%checks%max_harmonics = max_harmonics
        case%checks%stability = stability
        case%checks%verify_periods = verify_periods
        if (len_trim(directory) == 0) then
            call input_error("&output directory: must not be empty")
            return
        end if
        case%directory = trim(directory)

        select case (method)
        case ('hbm', 'euler', 'reference', 'all', 'study', 'sweep', 'robustness')
        case default
            call input_error("&run method = '"//trim(method)//"': must be 'hbm', 'euler', "// &
                             "'reference', 'all', 'study', 'sweep' or 'robustness'")
            return
        end select
        if (method == 'sweep' .and. .not. case%has_sweep) then
            call input_error("&sweep: missing (method = 'sweep' needs the group with at "// &
                             "least start and stop)")
            return
        end if
        case%method = method
        if (steps_per_period < 2) then
            call input_error("&euler steps_per_period = "//itoa(steps_per_period)// &
                             ": must be >= 2")
            return
        end if
        if (max_periods < 1) then
            call input_error("&euler max_periods = "//itoa(max_periods)//": must be >= 1")
            return
        end if
        if (.not. (euler_tol > 0.0_dp .and. euler_tol < 1.0_dp)) then
            call input_error("&euler tol: must be in (0, 1)")
            return
        end if
        case%euler%steps_per_period = steps_per_period
        case%euler%max_periods = max_periods
        case%euler%tol = euler_tol

        call validate_model(case%model, error)
        if (allocated(error)) then
            error%message = path//": "//error%message
            return
        end if
        call validate_options(case%hbm, error)
        if (allocated(error)) then
            error%message = path//": "//error%message
            return
        end if
        call validate_check_options(case%checks, case%hbm, error)
        if (allocated(error)) then
            error%message = path//": "//error%message
            return
        end if
        call validate_reference_options(case%reference, error)
        if (allocated(error)) then
            error%message = path//": "//error%message
            return
        end if
        call validate_study_options(case%study, error)
        if (allocated(error)) then
            error%message = path//": "//error%message
            return
        end if
        call validate_robustness_options(case%robustness, error)
        if (allocated(error)) then
            error%message = path//": "//error%message
            return
        end if
        if (case%has_sweep) then
            call validate_sweep_options(case%model, case%sweep, error)
            if (allocated(error)) then
                error%message = path//": "//error%message
                return
            end if
        end if

    contains

        !> &euler has its own `tol` (the &hbm one is another variable): read it here.
        subroutine read_euler_group()
            real(dp) :: tol
            namelist /euler/ steps_per_period, max_periods, tol
            tol = euler_tol
            rewind (u)
            read (u, nml=euler, iostat=stat, iomsg=msg)
            euler_tol = tol
        end subroutine read_euler_group

        !> &reference shares variable names with &hbm: read it with its own variables.
        subroutine read_reference_group()
            integer :: samples, bracket_steps, maxfev
            real(dp) :: tol
            character(len=16) :: start
            namelist /reference/ samples, bracket_steps, tol, maxfev, start
            samples = case%reference%samples
            bracket_steps = case%reference%bracket_steps
            tol = case%reference%tol
            maxfev = case%reference%maxfev
            start = case%reference%start
            rewind (u)
            read (u, nml=reference, iostat=stat, iomsg=msg)
            if (stat /= 0) return
            if (.not. ieee_is_finite(tol)) then
                call input_error("&reference tol: not a finite number")
                return
            end if
            if (len_trim(start) > len(case%reference%start)) then
                call input_error("&reference start = '"//trim(start)// &
                                 "': must be 'auto', 'hbm' or 'euler'")
                return
            end if
            case%reference%samples = samples
            case%reference%bracket_steps = bracket_steps
            case%reference%tol = tol
            case%reference%maxfev = maxfev
            case%reference%start = trim(start)
        end subroutine read_reference_group

        !> &study holds lists named like &hbm and &euler variables: its own variables.
        subroutine read_study_group()
            integer :: harmonics(max_terms), samples(max_terms), steps_per_period(max_terms)
            integer :: error_samples, repeats, nh, ns, ne
            real(dp) :: repeat_below
            namelist /study/ harmonics, samples, steps_per_period, error_samples, repeats, &
                repeat_below
            case%study = default_study_options()
            harmonics = iunset
            samples = iunset
            steps_per_period = iunset
            error_samples = case%study%error_samples
            repeats = case%study%repeats
            repeat_below = case%study%repeat_below
            rewind (u)
            read (u, nml=study, iostat=stat, iomsg=msg)
            if (stat /= 0) return
            nh = count_given_int(harmonics)
            ns = count_given_int(samples)
            ne = count_given_int(steps_per_period)
            if (nh < 0) then
                call input_error("&study harmonics: entries must be given without gaps")
            else if (ns < 0) then
                call input_error("&study samples: entries must be given without gaps")
            else if (ne < 0) then
                call input_error("&study steps_per_period: entries must be given without gaps")
            end if
            if (allocated(error)) return
            if (.not. ieee_is_finite(repeat_below)) then
                call input_error("&study repeat_below: not a finite number")
                return
            end if
            ! a single 0 asks for no runs of that method
            if (nh > 0) case%study%harmonics = pack(harmonics(1:nh), .not. (nh == 1 .and. &
                                                                         harmonics(1) == 0))
            if (ns > 0) case%study%samples = samples(1:ns)
            if (ne > 0) case%study%steps_per_period = pack(steps_per_period(1:ne), &
                                                           .not. (ne == 1 .and. steps_per_period(1) == 0))
            case%study%error_samples = error_samples
            case%study%repeats = repeats
            case%study%repeat_below = repeat_below
        end subroutine read_study_group

        !> &sweep shares names with &hbm (tol) and is read with its own variables.
        subroutine read_sweep_group()
            character(len=32) :: parameter
            real(dp) :: start, stop, step, min_step, max_step
            integer :: max_points, max_failures
            logical :: stability, truncation, resume, plot
            namelist /sweep/ parameter, start, stop, step, min_step, max_step, max_points, &
                max_failures, stability, truncation, resume, plot
            case%has_sweep = group_present(u, "sweep")
            parameter = case%sweep%parameter
            start = unset
            stop = unset
            step = case%sweep%step
            min_step = case%sweep%min_step
            max_step = case%sweep%max_step
            max_points = case%sweep%max_points
            max_failures = case%sweep%max_failures
            stability = case%sweep%stability
            truncation = case%sweep%truncation
            resume = case%sweep%resume
            plot = case%sweep%plot
            rewind (u)
            read (u, nml=sweep, iostat=stat, iomsg=msg)
            if (stat /= 0 .or. .not. case%has_sweep) return
            if (start == unset) then
                call input_error("&sweep start: missing (first value of the parameter)")
            else if (stop == unset) then
                call input_error("&sweep stop: missing (last value of the parameter)")
            else if (.not. all(ieee_is_finite([start, stop, step, min_step, max_step]))) then
                call input_error("&sweep start, stop, step, min_step, max_step: not finite numbers")
            else if (len_trim(parameter) > len(case%sweep%parameter)) then
                call input_error("&sweep parameter = '"//trim(parameter)//"': must be "// &
                                 "'omega', 'force_amplitude', 'mu' or 'normal_load'")
            end if
            if (allocated(error)) return
            case%sweep%parameter = lower(trim(parameter))
            case%sweep%start = start
            case%sweep%stop = stop
            case%sweep%step = step
            case%sweep%min_step = min_step
            case%sweep%max_step = max_step
            case%sweep%max_points = max_points
            case%sweep%max_failures = max_failures
            case%sweep%stability = stability
            case%sweep%truncation = truncation
            case%sweep%resume = resume
            case%sweep%plot = plot
        end subroutine read_sweep_group

        !> &robustness holds lists named like &hbm and &euler variables: its own variables.
        subroutine read_robustness_group()
            real(dp) :: omegas(max_terms), mus(max_terms), rhos(max_terms)
            integer :: harmonics(max_terms), samples(max_terms), steps_per_period(max_terms)
            integer :: error_samples, no, nm, nr, nh, ns, ne
            logical :: warm
            real(dp) :: wrong_tol
            namelist /robustness/ omegas, mus, harmonics, rhos, samples, steps_per_period, &
                warm, error_samples, wrong_tol
            case%robustness = default_robustness_options()
            omegas = unset
            mus = unset
            rhos = unset
            harmonics = iunset
            samples = iunset
            steps_per_period = iunset
            warm = case%robustness%warm
            error_samples = case%robustness%error_samples
            wrong_tol = case%robustness%wrong_tol
            rewind (u)
            read (u, nml=robustness, iostat=stat, iomsg=msg)
            if (stat /= 0) return
            no = count_given_real(omegas)
            nm = count_given_real(mus)
            nr = count_given_real(rhos)
            nh = count_given_int(harmonics)
            ns = count_given_int(samples)
            ne = count_given_int(steps_per_period)
            if (min(no, nm, nr, nh, ns, ne) < 0) then
                call input_error("&robustness omegas, mus, rhos, harmonics, samples, "// &
                                 "steps_per_period: entries must be given without gaps")
                return
            end if
            if (.not. all(ieee_is_finite([omegas(1:max(no, 0)), mus(1:max(nm, 0)), &
                                          rhos(1:max(nr, 0)), wrong_tol]))) then
                call input_error("&robustness omegas, mus, rhos, wrong_tol: not finite numbers")
                return
            end if
            if (no > 0) case%robustness%omegas = omegas(1:no)
            if (nm > 0) case%robustness%mus = mus(1:nm)
            if (nr > 0) case%robustness%rhos = rhos(1:nr)
            if (nh > 0) case%robustness%harmonics = harmonics(1:nh)
            if (ns > 0) case%robustness%samples = samples(1:ns)
            ! a single 0 asks for no Euler runs (the default)
            if (ne > 0) case%robustness%steps_per_period = pack(steps_per_period(1:ne), &
                                                                .not. (ne == 1 .and. steps_per_period(1) == 0))
            case%robustness%warm = warm
            case%robustness%error_samples = error_samples
            case%robustness%wrong_tol = wrong_tol
        end subroutine read_robustness_group

        subroutine input_error(message)
            character(len=*), intent(in) :: message
            call fatal_error(error, path//": "//message, stickslip_stat%input)
        end subroutine input_error

        !> Turn the iostat of one group's read into an error (or nothing).
        subroutine group_status(group, required)
            character(len=*), intent(in) :: group
            logical, intent(in) :: required
            if (stat == 0) return
            if (stat == iostat_end) then
                if (group_present(u, group)) then
                    call input_error("&"//group//": the group is not closed by '/'")
                else if (required) then
                    call input_error("&"//group//": required group not found")
                end if
            else
                call input_error("&"//group//": "//trim(msg)// &
                                 " (an unknown variable, a bad value or too many values)")
            end if
            if (allocated(error)) close (u)
        end subroutine group_status

        subroutine take_matrix(name, values, required, a)
            character(len=*), intent(in) :: name
            real(dp), intent(in) :: values(:)
            logical, intent(in) :: required
            real(dp), allocatable, intent(out) :: a(:, :)
            integer :: given, i
            given = count_given_real(values)
            if (given == 0 .and. .not. required) then
                allocate (a(n, n))
                a = 0.0_dp
                return
            end if
            if (given /= n*n) then
                if (given < 0) then
                    call input_error("&system "//name//": entries must be given without gaps")
                else
                    call input_error("&system "//name//": "//itoa(given)// &
                                     " values given, expected ndof**2 = "//itoa(n*n)// &
                                     " (column-major)")
                end if
                return
            end if
            do i = 1, n*n
                if (.not. ieee_is_finite(values(i))) then
                    call input_error("&system "//name//"("//itoa(i)// &
                                     "): not a finite number (NaN or Inf)")
                    return
                end if
            end do
            a = reshape(values(1:n*n), [n, n])
        end subroutine take_matrix

        subroutine take_real(group, name, values, count, required, default, a)
            character(len=*), intent(in) :: group, name
            real(dp), intent(in) :: values(:)
            integer, intent(in) :: count
            logical, intent(in) :: required
            real(dp), intent(in) :: default
            real(dp), allocatable, intent(out) :: a(:)
            integer :: given, i
            given = count_given_real(values)
            if (given == 0 .and. .not. required) then
                allocate (a(count))
                a = default
                return
            end if
            if (given /= count) then
                call input_error(group//" "//name//": "//itoa(max(given, 0))// &
                                 " values given, expected "//itoa(count)// &
                                 " (one per entry of "//merge("force_dof  ", "contact_dof", &
                                 group == "&forcing")//")")
                return
            end if
            do i = 1, count
                if (.not. ieee_is_finite(values(i))) then
                    call input_error(group//" "//name//"("//itoa(i)// &
                                     "): not a finite number (NaN or Inf)")
                    return
                end if
            end do
            a = values(1:count)
        end subroutine take_real

        subroutine take_int(group, name, values, count, default, a)
            character(len=*), intent(in) :: group, name
            integer, intent(in) :: values(:)
            integer, intent(in) :: count
            integer, intent(in) :: default
            integer, allocatable, intent(out) :: a(:)
            integer :: given
            given = count_given_int(values)
            if (given == 0) then
                allocate (a(count))
                a = default
                return
            end if
            if (given /= count) then
                call input_error(group//" "//name//": "//itoa(max(given, 0))// &
                                 " values given, expected "//itoa(count)// &
                                 " (one per entry of "//merge("force_dof  ", "contact_dof", &
                                 group == "&forcing")//")")
                return
            end if
            a = values(1:count)
        end subroutine take_int
    end subroutine read_case

    !> Open the case file and copy it line by line into a scratch unit `u`, which the
    !> namelist reads use: gfortran cannot read a group closed on a last line that has no
    !> newline, and the copy always ends its lines. Error (stat io) if the file is unreadable.
    subroutine open_copy(path, u, error)
        character(len=*), intent(in) :: path
        integer, intent(out) :: u
        type(error_type), allocatable, intent(out) :: error
        integer :: uin, stat, nread
        character(len=512) :: msg
        character(len=1024) :: chunk
        open (newunit=uin, file=path, status='old', action='read', iostat=stat, iomsg=msg)
        if (stat /= 0) then
            call fatal_error(error, path//": cannot open the case file: "//trim(msg), &
                             stickslip_stat%io)
            return
        end if
        open (newunit=u, status='scratch', action='readwrite')
        do
            read (uin, '(a)', advance='no', size=nread, iostat=stat, iomsg=msg) chunk
            if (stat > 0) then
                call fatal_error(error, path//": cannot read the case file: "//trim(msg), &
                                 stickslip_stat%io)
                close (uin)
                close (u)
                return
            end if
            if (stat == iostat_end) exit
            if (is_iostat_eor(stat)) then
                write (u, '(a)') chunk(1:nread)
            else
                write (u, '(a)', advance='no') chunk(1:nread)
            end if
        end do
        if (nread > 0) write (u, '(a)') ""
        close (uin)
    end subroutine open_copy

    !> Number of leading entries that were given (not the sentinel); -1 if there is a gap.
    pure integer function count_given_real(values) result(given)
        real(dp), intent(in) :: values(:)
        integer :: last
        given = 0
        do last = size(values), 1, -1
            if (values(last) /= unset) exit
        end do
        if (last < 1) return
        given = last
        if (any(values(1:last) == unset)) given = -1
    end function count_given_real

    pure integer function count_given_int(values) result(given)
        integer, intent(in) :: values(:)
        integer :: last
        given = 0
        do last = size(values), 1, -1
            if (values(last) /= iunset) exit
        end do
        if (last < 1) return
        given = last
        if (any(values(1:last) == iunset)) given = -1
    end function count_given_int

    !> Whether the text of the file on unit u holds '&group' (case-insensitive).
    logical function group_present(u, group)
        integer, intent(in) :: u
        character(len=*), intent(in) :: group
        character(len=4096) :: line
        integer :: stat, k
        group_present = .false.
        rewind (u)
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            k = index(lower(line), "&"//lower(group))
            if (k > 0) then
                group_present = .true.
                exit
            end if
        end do
    end function group_present

    pure function lower(s) result(t)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: t
        integer :: i
        t = s
        do i = 1, len(s)
            if (s(i:i) >= 'A' .and. s(i:i) <= 'Z') t(i:i) = achar(iachar(s(i:i)) + 32)
        end do
    end function lower

    !> Write `case` as namelist text that read_case reads back (full precision), to `unit`.
    !> I/O errors do not stop the program: stat /= 0 and msg say what failed.
    subroutine write_case(unit, case, stat, msg)
        !> An open formatted unit.
        integer, intent(in) :: unit
        !> The case.
        type(case_t), intent(in) :: case
        !> 0, or the iostat of the first failed write.
        integer, intent(out) :: stat
        !> The iomsg of the first failed write.
        character(len=*), intent(inout) :: msg
        integer :: i
        stat = 0
        associate (m => case%model, o => case%hbm)
            call put(unit, "&system", stat, msg)
            call put(unit, "  ndof = "//itoa(m%ndof), stat, msg)
            call put(unit, "  mass = "//rlist(reshape(m%mass, [m%ndof**2])), stat, msg)
            call put(unit, "  stiffness = "//rlist(reshape(m%stiffness, [m%ndof**2])), stat, msg)
            call put(unit, "  damping = "//rlist(reshape(m%damping, [m%ndof**2])), stat, msg)
            call put(unit, "/", stat, msg)
            call put(unit, "&forcing", stat, msg)
            call put(unit, "  omega = "//rtoa(m%omega), stat, msg)
            call put(unit, "  force_dof = "//ilist(m%force_dof), stat, msg)
            call put(unit, "  force_harmonic = "//ilist(m%force_harmonic), stat, msg)
            call put(unit, "  force_amplitude = "//rlist(m%force_amplitude), stat, msg)
            call put(unit, "  force_phase = "//rlist(m%force_phase), stat, msg)
            call put(unit, "/", stat, msg)
            call put(unit, "&friction", stat, msg)
            if (m%ncontact() > 0) then
                call put(unit, "  contact_dof = "//ilist(m%contact_dof), stat, msg)
                call put(unit, "  contact_dof2 = "//ilist(m%contact_dof2), stat, msg)
                call put(unit, "  mu = "//rlist(m%mu), stat, msg)
                call put(unit, "  normal_load = "//rlist(m%normal_load), stat, msg)
            end if
            call put(unit, "/", stat, msg)
            call put(unit, "&hbm", stat, msg)
            call put(unit, "  harmonics = "//itoa(o%harmonics), stat, msg)
            call put(unit, "  odd_only = "//ltoa(o%odd_only), stat, msg)
            call put(unit, "  rho = "//rtoa(o%rho), stat, msg)
            call put(unit, "  samples = "//itoa(o%samples), stat, msg)
            call put(unit, "  tol = "//rtoa(o%tol), stat, msg)
            call put(unit, "  start = '"//trim(o%start)//"'", stat, msg)
            call put(unit, "  maxfev = "//itoa(o%maxfev), stat, msg)
            call put(unit, "  harmonics_tol = "//rtoa(case%checks%harmonics_tol), stat, msg)
            call put(unit, "  max_harmonics = "//itoa(case%checks%max_harmonics), stat, msg)
            call put(unit, "  stability = "//ltoa(case%checks%stability), stat, msg)
            call put(unit, "  verify_periods = "//itoa(case%checks%verify_periods), stat, msg)
            call put(unit, "/", stat, msg)
            call put(unit, "&output", stat, msg)
            call put(unit, "  directory = '"//case%directory//"'", stat, msg)
            call put(unit, "/", stat, msg)
            call put(unit, "&run", stat, msg)
            call put(unit, "  method = '"//trim(case%method)//"'", stat, msg)
            call put(unit, "/", stat, msg)
            call put(unit, "&euler", stat, msg)
            call put(unit, "  steps_per_period = "//itoa(case%euler%steps_per_period), stat, msg)
            call put(unit, "  max_periods = "//itoa(case%euler%max_periods), stat, msg)
            call put(unit, "  tol = "//rtoa(case%euler%tol), stat, msg)
            call put(unit, "/", stat, msg)
            call put(unit, "&reference", stat, msg)
            call put(unit, "  samples = "//itoa(case%reference%samples), stat, msg)
            call put(unit, "  bracket_steps = "//itoa(case%reference%bracket_steps), stat, msg)
            call put(unit, "  tol = "//rtoa(case%reference%tol), stat, msg)
            call put(unit, "  maxfev = "//itoa(case%reference%maxfev), stat, msg)
            call put(unit, "  start = '"//trim(case%reference%start)//"'", stat, msg)
            call put(unit, "/", stat, msg)
            if (allocated(case%study%harmonics)) then
                call put(unit, "&study", stat, msg)
                ! an empty list is written as the single 0 that asks for it
                call put(unit, "  harmonics = "//ilist([case%study%harmonics, &
                         (0, i=1, merge(1, 0, size(case%study%harmonics) == 0))]), stat, msg)
                if (size(case%study%samples) > 0) &
                    call put(unit, "  samples = "//ilist(case%study%samples), stat, msg)
                call put(unit, "  steps_per_period = "//ilist([case%study%steps_per_period, &
                         (0, i=1, merge(1, 0, size(case%study%steps_per_period) == 0))]), &
                         stat, msg)
                call put(unit, "  error_samples = "//itoa(case%study%error_samples), stat, msg)
                call put(unit, "  repeats = "//itoa(case%study%repeats), stat, msg)
                call put(unit, "  repeat_below = "//rtoa(case%study%repeat_below), stat, msg)
                call put(unit, "/", stat, msg)
            end if
            if (case%method == 'robustness') then
                associate (b => case%robustness)
                    call put(unit, "&robustness", stat, msg)
                    call put(unit, "  omegas = "//rlist(b%omegas), stat, msg)
                    call put(unit, "  mus = "//rlist(b%mus), stat, msg)
                    call put(unit, "  harmonics = "//ilist(b%harmonics), stat, msg)
                    call put(unit, "  rhos = "//rlist(b%rhos), stat, msg)
                    call put(unit, "  samples = "//ilist(b%samples), stat, msg)
                    call put(unit, "  steps_per_period = "//ilist([b%steps_per_period, &
                             (0, i=1, merge(1, 0, size(b%steps_per_period) == 0))]), stat, msg)
                    call put(unit, "  warm = "//ltoa(b%warm), stat, msg)
                    call put(unit, "  error_samples = "//itoa(b%error_samples), stat, msg)
                    call put(unit, "  wrong_tol = "//rtoa(b%wrong_tol), stat, msg)
                    call put(unit, "/", stat, msg)
                end associate
            end if
            if (case%has_sweep) then
                associate (w => case%sweep)
                    call put(unit, "&sweep", stat, msg)
                    call put(unit, "  parameter = '"//trim(w%parameter)//"'", stat, msg)
                    call put(unit, "  start = "//rtoa(w%start), stat, msg)
                    call put(unit, "  stop = "//rtoa(w%stop), stat, msg)
                    call put(unit, "  step = "//rtoa(w%step), stat, msg)
                    call put(unit, "  min_step = "//rtoa(w%min_step), stat, msg)
                    call put(unit, "  max_step = "//rtoa(w%max_step), stat, msg)
                    call put(unit, "  max_points = "//itoa(w%max_points), stat, msg)
                    call put(unit, "  max_failures = "//itoa(w%max_failures), stat, msg)
                    call put(unit, "  stability = "//ltoa(w%stability), stat, msg)
                    call put(unit, "  truncation = "//ltoa(w%truncation), stat, msg)
                    call put(unit, "  resume = "//ltoa(w%resume), stat, msg)
                    call put(unit, "  plot = "//ltoa(w%plot), stat, msg)
                    call put(unit, "/", stat, msg)
                end associate
            end if
        end associate
    end subroutine write_case

    !> Write one line to `unit` unless an earlier write failed (stat /= 0); record the first
    !> failure in stat and msg. Never stops the program.
    subroutine put(unit, line, stat, msg)
        !> An open formatted unit.
        integer, intent(in) :: unit
        !> The line.
        character(len=*), intent(in) :: line
        !> 0 so far, or the first failure's iostat.
        integer, intent(inout) :: stat
        !> The first failure's iomsg.
        character(len=*), intent(inout) :: msg
        if (stat /= 0) return
        write (unit, '(a)', iostat=stat, iomsg=msg) line
    end subroutine put

    !> A real as text with 17 significant digits.
    pure function rtoa(x) result(s)
        !> The value.
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: buf
        write (buf, '(es25.17e3)') x
        s = trim(adjustl(buf))
    end function rtoa

    !> A logical as namelist text, T or F.
    pure function ltoa(l) result(s)
        !> The value.
        logical, intent(in) :: l
        character(len=1) :: s
        s = merge("T", "F", l)
    end function ltoa

    !> Reals as a comma-separated list.
    pure function rlist(x) result(s)
        !> The values.
        real(dp), intent(in) :: x(:)
        character(len=:), allocatable :: s
        integer :: i
        s = ""
        do i = 1, size(x)
            s = s//rtoa(x(i))
            if (i < size(x)) s = s//", "
        end do
    end function rlist

    !> Integers as a comma-separated list.
    pure function ilist(x) result(s)
        !> The values.
        integer, intent(in) :: x(:)
        character(len=:), allocatable :: s
        integer :: i
        s = ""
        do i = 1, size(x)
            s = s//itoa(x(i))
            if (i < size(x)) s = s//", "
        end do
    end function ilist

    !> Logicals as a comma-separated list of T and F.
    pure function llist(x) result(s)
        !> The values.
        logical, intent(in) :: x(:)
        character(len=:), allocatable :: s
        integer :: i
        s = ""
        do i = 1, size(x)
            s = s//ltoa(x(i))
            if (i < size(x)) s = s//", "
        end do
    end function llist
end module stickslip_case
