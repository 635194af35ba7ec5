!> Readers of the case-file groups of the studies: &study, &sweep, &robustness. Each reads one
!> group of a parsed namelist file into its options type (defaults where a variable or the
!> group is absent) and validates it with the library's validator, whose message names the
!> argument ("opts%step, opts%min_step ...") and is put in case-file words with the file path
!> ("<path>: &sweep step, min_step ...", stickslip_case_messages). &sweep is read into a
!> sweep_run_options_t: the options of run_sweep plus resume and plot, which only the run of
!> a case uses.
module stickslip_case_studies
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_model, only: model_t
    use stickslip_study, only: study_options_t, default_study_options, validate_study_options
    use stickslip_sweep, only: sweep_options_t, validate_sweep_options
    use stickslip_robustness, only: robustness_options_t, default_robustness_options, &
        validate_robustness_options
    use stickslip_modes, only: modes_options_t, validate_modes_options
    use stickslip_sweep_family, only: family_options_t, validate_family_options, &
        max_family_curves
    use stickslip_namelist, only: nml_file_t, lower
    use stickslip_cyclic, only: max_sectors
    use stickslip_namelist_values, only: check_names, get_integer, get_real, get_logical, get_string, &
        get_integers, get_reals
    use stickslip_case_model, only: group_error, max_terms
    use stickslip_case_messages, only: to_case_message
    implicit none
    private
    public :: read_study_group, read_sweep_group, read_robustness_group, read_modes_group
    public :: sweep_run_options_t, modes_run_options_t, diameter_mode

    !> The &sweep group of a case: the options of run_sweep and what the run of a case does
    !> around it (the checkpoint, the picture), which run_sweep does not use.
    type, extends(sweep_options_t) :: sweep_run_options_t
        !> Resume from the checkpoint of an interrupted run of the same case (the driver).
        logical :: resume = .true.
        !> Draw frc.png with gnuplot (the command-line program).
        logical :: plot = .true.
        !> A family of curves (&sweep family_parameter, family_values): one curve per value
        !> (family_parameter = '' when the sweep is one curve).
        type(family_options_t) :: family
    end type sweep_run_options_t

    !> The &modes group of a case: the options of run_modes and whether the program draws
    !> modes.png.
    type, extends(modes_options_t) :: modes_run_options_t
        !> Draw modes.png with gnuplot (the command-line program).
        logical :: plot = .true.
        !> On one sector of a disk (&cyclic model = 'sector'): the nodal diameters whose
        !> backbones are traced (unallocated: every diameter 0 .. N/2).
        integer, allocatable :: nodal_diameters(:)
        !> On one sector, &modes mode given as a list: the mode of each diameter traced (one
        !> per diameter, in their order; unallocated: `mode` in every diameter).
        integer, allocatable :: diameter_modes(:)
    end type modes_run_options_t

contains

    !> The mode traced in the i-th nodal diameter a sector's run of modes traces: `mode`, or
    !> its i-th value when &modes mode gives one per diameter.
    pure integer function diameter_mode(opts, i) result(mode)
        !> The &modes group.
        type(modes_run_options_t), intent(in) :: opts
        !> Position among the diameters traced.
        integer, intent(in) :: i
        mode = opts%mode
        if (allocated(opts%diameter_modes)) mode = opts%diameter_modes(i)
    end function diameter_mode

    !> Read &modes (optional; `given` tells whether it is present): mode, amplitude_start and
    !> amplitude_stop (both required with the group), points, plot, error_estimate,
    !> refinements, nodal_diameters (checked against the disk by the caller); validate.
    subroutine read_modes_group(nml, opts, given, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> Modal-analysis options with plot (defaults for absent variables).
        type(modes_run_options_t), intent(out) :: opts
        !> The group is present.
        logical, intent(out) :: given
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        logical :: found
        integer, allocatable :: list(:)
        integer :: k
        character(len=*), parameter :: g = "modes"
        given = nml%find(g) > 0
        if (.not. given) return
        call check_names(nml, g, [character(len=16) :: "mode", "amplitude_start", &
                             "amplitude_stop", "points", "plot", "error_estimate", &
                             "nodal_diameters", "refinements"], error)
        if (allocated(error)) return
        ! one mode, or on a sector one per nodal diameter (checked by the caller)
        call get_integers(nml, g, "mode", list, found, max_sectors/2 + 1, error)
        if (allocated(error)) return
        if (found) then
            do k = 1, size(list)
                if (list(k) < 1) then
                    call group_error(nml, error, "&modes mode("//itoa(k)//") = "// &
                                     itoa(list(k))//": must be >= 1 (1: the lowest mode "// &
                                     "with the contacts stuck)")
                    return
                end if
            end do
            opts%mode = list(1)
            if (size(list) > 1) opts%diameter_modes = list
        end if
        call get_real(nml, g, "amplitude_start", opts%amplitude_start, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&modes amplitude_start: missing (the smallest "// &
                             "modal amplitude, > 0)")
            return
        end if
        call get_real(nml, g, "amplitude_stop", opts%amplitude_stop, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&modes amplitude_stop: missing (the largest "// &
                             "modal amplitude, > 0)")
            return
        end if
        call get_integer(nml, g, "points", opts%points, error)
        if (allocated(error)) return
        call get_logical(nml, g, "plot", opts%plot, error)
        if (allocated(error)) return
        call get_logical(nml, g, "error_estimate", opts%error_estimate, error)
        if (allocated(error)) return
        call get_integer(nml, g, "refinements", opts%refinements, error)
        if (allocated(error)) return
        ! checked against the disk by the caller (check_modes_diameters)
        call get_integers(nml, g, "nodal_diameters", list, found, max_sectors/2 + 1, error)
        if (allocated(error)) return
        if (found) opts%nodal_diameters = list
        call validate_modes_options(opts%modes_options_t, error)
        if (allocated(error)) call to_case_message(error, nml%path, ['opts'], ['modes'])
    end subroutine read_modes_group

    !> Read &study (optional): lists harmonics, samples, steps_per_period (at most max_terms
    !> each; a single 0 asks for no run of that method), error_samples, repeats,
    !> repeat_below; validate.
    subroutine read_study_group(nml, opts, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> Study options (default_study_options for absent variables).
        type(study_options_t), intent(out) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: list(:)
        logical :: found
        character(len=*), parameter :: g = "study"
        opts = default_study_options()
        call check_names(nml, g, [character(len=16) :: "harmonics", "samples", &
                             "steps_per_period", "error_samples", "repeats", "repeat_below"], &
                             error)
        if (allocated(error)) return
        call get_integers(nml, g, "harmonics", list, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%harmonics = drop_single_zero(list)
        call get_integers(nml, g, "samples", list, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%samples = list
        call get_integers(nml, g, "steps_per_period", list, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%steps_per_period = drop_single_zero(list)
        call get_integer(nml, g, "error_samples", opts%error_samples, error)
        if (allocated(error)) return
        call get_integer(nml, g, "repeats", opts%repeats, error)
        if (allocated(error)) return
        call get_real(nml, g, "repeat_below", opts%repeat_below, error)
        if (allocated(error)) return
        call validate_study_options(opts, error)
        if (allocated(error)) call to_case_message(error, nml%path, ['opts', 'hbm '], &
                                                   ['study', 'hbm  '])
    end subroutine read_study_group

    !> Read &sweep (optional; `given` tells whether it is present): parameter, start and stop
    !> (both required with the group), step, min_step, max_step, max_points, max_failures,
    !> stability, truncation, resume, plot, family_parameter and family_values (a family of
    !> curves: both or neither); validate against `model`.
    subroutine read_sweep_group(nml, model, opts, given, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model swept (for the checks of the parameter).
        type(model_t), intent(in) :: model
        !> Sweep options with resume and plot (defaults for absent variables).
        type(sweep_run_options_t), intent(out) :: opts
        !> The group is present.
        logical, intent(out) :: given
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: parameter, family
        real(dp), allocatable :: values(:)
        logical :: found
        character(len=*), parameter :: g = "sweep"
        given = nml%find(g) > 0
        if (.not. given) return
        call check_names(nml, g, [character(len=16) :: "parameter", "start", "stop", "step", &
                             "min_step", "max_step", "max_points", "max_failures", &
                             "stability", "truncation", "resume", "plot", &
                             "family_parameter", "family_values"], error)
        if (allocated(error)) return
        parameter = trim(opts%parameter)
        call get_string(nml, g, "parameter", parameter, error)
        if (allocated(error)) return
        parameter = lower(trim(parameter))
        select case (parameter)
        case ('omega', 'force_amplitude', 'mu', 'normal_load', 'preload')
        case default
            call group_error(nml, error, "&sweep parameter = '"//parameter//"': must be "// &
                             "'omega', 'force_amplitude', 'mu', 'normal_load' or 'preload'")
            return
        end select
        opts%parameter = parameter
        call get_real(nml, g, "start", opts%start, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&sweep start: missing (first value of the parameter)")
            return
        end if
        call get_real(nml, g, "stop", opts%stop, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, "&sweep stop: missing (last value of the parameter)")
            return
        end if
        call get_real(nml, g, "step", opts%step, error)
        if (allocated(error)) return
        call get_real(nml, g, "min_step", opts%min_step, error)
        if (allocated(error)) return
        call get_real(nml, g, "max_step", opts%max_step, error)
        if (allocated(error)) return
        call get_integer(nml, g, "max_points", opts%max_points, error)
        if (allocated(error)) return
        call get_integer(nml, g, "max_failures", opts%max_failures, error)
        if (allocated(error)) return
        call get_logical(nml, g, "stability", opts%stability, error)
        if (allocated(error)) return
        call get_logical(nml, g, "truncation", opts%truncation, error)
        if (allocated(error)) return
        call get_logical(nml, g, "resume", opts%resume, error)
        if (allocated(error)) return
        call get_logical(nml, g, "plot", opts%plot, error)
        if (allocated(error)) return
        call validate_sweep_options(model, opts%sweep_options_t, error)
        if (allocated(error)) then
            call to_case_message(error, nml%path, ['opts'], ['sweep'])
            return
        end if
        ! a family: the second parameter and its values, both or neither
        family = ''
        call get_string(nml, g, "family_parameter", family, error)
        if (allocated(error)) return
        call get_reals(nml, g, "family_values", values, found, max_family_curves, error)
        if (allocated(error)) return
        if (len_trim(family) == 0 .and. .not. found) return
        if (len_trim(family) == 0) then
            call group_error(nml, error, "&sweep family_parameter: missing (family_values "// &
                             "are the values of which parameter: 'normal_load', 'preload', "// &
                             "'mu' or 'force_amplitude')")
            return
        end if
        if (.not. found) then
            call group_error(nml, error, "&sweep family_values: missing (the values of "// &
                             "family_parameter, one curve each)")
            return
        end if
        opts%family%family_parameter = lower(trim(family))
        opts%family%family_values = values
        call validate_family_options(model, opts%sweep_options_t, opts%family, error)
        if (allocated(error)) call to_case_message(error, nml%path, ['family', 'sweep '], &
                                                   ['sweep', 'sweep'])
    end subroutine read_sweep_group

    !> Read &robustness (optional): lists omegas, mus, rhos, harmonics, samples,
    !> steps_per_period (at most max_terms each; a single 0 steps_per_period asks for no
    !> Euler run), warm, error_samples, wrong_tol; validate.
    subroutine read_robustness_group(nml, opts, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> Robustness options (default_robustness_options for absent variables).
        type(robustness_options_t), intent(out) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: ilist(:)
        real(dp), allocatable :: rlist(:)
        logical :: found
        character(len=*), parameter :: g = "robustness"
        opts = default_robustness_options()
        call check_names(nml, g, [character(len=16) :: "omegas", "mus", "harmonics", "rhos", &
                             "samples", "steps_per_period", "warm", "error_samples", &
                             "wrong_tol"], error)
        if (allocated(error)) return
        call get_reals(nml, g, "omegas", rlist, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%omegas = rlist
        call get_reals(nml, g, "mus", rlist, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%mus = rlist
        call get_reals(nml, g, "rhos", rlist, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%rhos = rlist
        call get_integers(nml, g, "harmonics", ilist, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%harmonics = ilist
        call get_integers(nml, g, "samples", ilist, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%samples = ilist
        call get_integers(nml, g, "steps_per_period", ilist, found, max_terms, error)
        if (allocated(error)) return
        if (found) opts%steps_per_period = drop_single_zero(ilist)
        call get_logical(nml, g, "warm", opts%warm, error)
        if (allocated(error)) return
        call get_integer(nml, g, "error_samples", opts%error_samples, error)
        if (allocated(error)) return
        call get_real(nml, g, "wrong_tol", opts%wrong_tol, error)
        if (allocated(error)) return
        call validate_robustness_options(opts, error)
        if (allocated(error)) call to_case_message(error, nml%path, ['opts    ', 'hbm_opts'], &
                                                   ['robustness', 'hbm       '])
    end subroutine read_robustness_group

    !> The list, or an empty one for the single value 0 ("no runs of that method").
    pure function drop_single_zero(list) result(kept)
        integer, intent(in) :: list(:)
        integer, allocatable :: kept(:)
        if (size(list) == 1) then
            if (list(1) == 0) then
                allocate (kept(0))
                return
            end if
        end if
        kept = list
    end function drop_single_zero
end module stickslip_case_studies
