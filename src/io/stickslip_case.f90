!> The case file: namelist groups &system, &forcing, &friction, &reduction, &hbm, &euler,
!> &reference, &run, &output, &study, &sweep, &robustness read into a `case_t` (the model, the solver
!> options and the output directory) by a strict parser (stickslip_namelist) and one reader
!> per group (stickslip_case_model, stickslip_case_solvers, stickslip_case_studies), with
!> messages that name the file, the line, the group and the variable. Also writes a case back
!> as namelist text (the effective case echoed into the summary). Knows nothing of the solver.
module stickslip_case
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, validate_model
    use stickslip_sparse_model, only: sparse_model_t, validate_sparse_model
    use stickslip_solution, only: hbm_options_t
    use stickslip_hbm, only: hbm_max_unknowns
    use stickslip_checks, only: check_options_t
    use stickslip_euler, only: euler_options_t
    use stickslip_reference_start, only: reference_start_options_t
    use stickslip_study, only: study_options_t
    use stickslip_robustness, only: robustness_options_t
    use stickslip_namelist, only: nml_file_t, read_namelist_file, edit_distance, lower
    use stickslip_namelist_values, only: get_logical, get_string, is_given, get_integers
    use stickslip_progress, only: progress_t
    use stickslip_case_model, only: read_system_group, read_forcing_group, &
        max_dof, max_terms, group_error, system_files_t, max_file_dof, &
        sparse_system_t, load_sparse_system
    use stickslip_case_reduction, only: reduction_case_t, read_reduction_group, &
        reduce_case_model, reduce_case_faces
    use stickslip_case_solvers, only: read_hbm_group, read_euler_group, read_reference_group, &
        read_run_group, read_output_group, default_output_dofs
    use stickslip_case_messages, only: to_case_message
    use stickslip_plot_units, only: plot_units_t
    use stickslip_case_friction, only: read_friction_group, friction_form_t
    use stickslip_case_microslip, only: read_microslip_group
    use stickslip_iwan_element, only: iwan_element_t
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_note
    use stickslip_case_cyclic, only: cyclic_case_t, read_cyclic_group, cyclic_case_model, &
        cyclic_boundary_dofs, set_cyclic_boundary_dofs, measure_diameter_errors, &
        diameter_findings, forced_diameters
    use stickslip_cyclic, only: cyclic_t, sector_phase, max_sectors
    use stickslip_wave_symmetry, only: wave_symmetry_t, stability_spans
    use stickslip_cyclic_limits, only: cyclic_limit_modes
    use stickslip_reduction, only: reduction_report_t
    use stickslip_case_studies, only: read_study_group, read_sweep_group, read_robustness_group, &
        sweep_run_options_t, read_modes_group, modes_run_options_t
    implicit none
    private
    public :: case_t, read_case, write_case, max_dof, max_terms, known_groups
    public :: system_files_t, max_file_dof, reduction_case_t
    public :: sweep_run_options_t, modes_run_options_t
    public :: max_sample_values
    public :: put, rtoa, ltoa, rlist, ilist, llist, quoted
    public :: selected_dofs, default_output_dofs, modes_band

    !> The groups of a case file.
    character(len=10), parameter :: known_groups(15) = [character(len=10) :: 'system', &
        'forcing', 'friction', 'microslip', 'hbm', 'output', 'run', 'euler', 'reference', &
        'study', 'sweep', 'robustness', 'reduction', 'modes', 'cyclic']
    !> Most doubles of the sampled results of one run (samples or steps per period times
    !> 2 ndof + 3 ncontact + 1): 2**27 doubles = 1 GiB.
    integer(int64), parameter :: max_sample_values = 2_int64**27
    !> Most DOFs of the assembled disk whose Floquet multipliers a sector's stability
    !> computes (&sweep or &hbm stability on one sector): its exact flow took 1.5 s a point
    !> on the 72-DOF shrouded disk (24 contacts) and over 200 s on the 168-DOF damper disk
    !> (48 contacts with lift-off), release build; it grows like the cube of the DOFs times
    !> the events a period.
    integer, parameter :: max_disk_stability_dof = 128
    !> The same where the wave's symmetry shortens the disk's flow to T / m with m >= 8
    !> (stickslip_wave_symmetry): 4 to 7 times less CPU, 1.6 to 2.3 s a point on 144 DOFs
    !> (the shrouded disk on 48 sectors, EO 1 and 2; bench_wave_stability), 8 s on 240.
    integer, parameter :: max_disk_stability_dof_wave = 192

    !> A case: where it came from, the model, the solver options and where results go.
    type :: case_t
        !> Path of the case file ('' for a case built in memory).
        character(len=:), allocatable :: path
        !> The structure, its contacts and forcing.
        type(model_t) :: model
        !> How &friction gave the contact-law directions (DOF lists in full-model numbers,
        !> inline, or file names), for the echo and messages.
        type(friction_form_t) :: friction_form
        !> What read_case found about the case itself (warning 'no_contact': no friction
        !> contact, the response is linear); every method's summary and the CLI report it.
        type(diagnostics_t) :: diagnostics
        !> &system mass_file, stiffness_file, damping_file, rayleigh_alpha, rayleigh_beta as
        !> read (the matrices themselves are in model; C includes the Rayleigh terms).
        type(system_files_t) :: system_files
        !> &reduction as read and what the reduction did (report%method 'none': the model is
        !> the full one). When reduced, `model` is the reduced model (contact and force DOFs in
        !> reduced numbering) and the full-model DOF numbers are kept here.
        type(reduction_case_t) :: reduction
        !> Method: 'hbm' (weighted residual), 'euler' (implicit Euler time stepping),
        !> 'reference' (exact event-driven), 'all' (the three side by side) or 'study' (the
        !> work-precision study).
        character(len=16) :: method = 'hbm'
        !> The full sparse model of &reduction method = 'none' for a model from files with
        !> N > max_file_dof (allocated only then): condensed exactly per harmonic by sparse
        !> LU (solve_periodic_sparse); only method 'hbm' runs on it. `model` then holds the
        !> same ndof, forcing and contacts without matrices.
        type(sparse_model_t), allocatable :: sparse_model
        !> Weighted-residual options (&hbm).
        type(hbm_options_t) :: hbm
        !> What to check about a weighted-residual solution (&hbm harmonics_tol,
        !> max_harmonics, stability, verify_periods).
        type(check_options_t) :: checks
        !> Time-stepping options (&euler).
        type(euler_options_t) :: euler
        !> Exact reference options and start strategy (&reference).
        type(reference_start_options_t) :: reference
        !> Work-precision study options (&study).
        type(study_options_t) :: study = study_options_t()
        !> Forced-response curve options with resume and plot (&sweep; used by method 'sweep').
        type(sweep_run_options_t) :: sweep
        !> The &sweep group was given.
        logical :: has_sweep = .false.
        !> Nonlinear modal analysis options with plot (&modes; used by method 'modes').
        type(modes_run_options_t) :: modes
        !> The &modes group was given.
        logical :: has_modes = .false.
        !> Robustness study options (&robustness; used by method 'robustness').
        type(robustness_options_t) :: robustness = robustness_options_t()
        !> Output directory (&output directory), created if missing.
        character(len=:), allocatable :: directory
        !> The DOFs the result files hold, in column order (&output dofs, or the default
        !> selection, default_output_dofs; unallocated in a case built in memory: see
        !> selected_dofs).
        integer, allocatable :: output_dofs(:)
        !> &output dofs was given (write_case echoes it).
        logical :: output_dofs_given = .false.
        !> &output full_field: method 'hbm' also writes full_field.mtx, the harmonic
        !> coefficients of every DOF of the model (of the full model from files, recovered
        !> through the reduction basis when it was reduced).
        logical :: full_field = .false.
        !> &output plot_amplitude: the amplitude frc.png draws ('half_peak_to_peak', the
        !> default; 'first_harmonic'; 'max_abs').
        character(len=:), allocatable :: plot_amplitude
        !> &output length_unit, force_unit, time_unit, frequency_unit: the units the pictures
        !> name (labels only).
        type(plot_units_t) :: units
        !> &cyclic: the model is a sector of a bladed disk (with model = 'disk', `model` is
        !> the assembled disk and the sector is kept here).
        type(cyclic_case_t) :: cyclic
    end type case_t

contains

    !> Read and validate the case file `path`. Errors: stat io if the file cannot be opened or
    !> read; stat input for a syntax error, an unknown or repeated group or variable, a
    !> missing required group or variable, a value of the wrong type, a non-finite, out of
    !> range or inconsistent value, a size above its limit, or a method that contradicts the
    !> study groups given. Every message starts with "<path>: " or "<path>:<line>: " and
    !> names the group and the variable. A model from Matrix Market files is reduced here
    !> when &reduction asks for it (stickslip_case_reduction): case%model is then the reduced
    !> model and case%reduction holds the report, the full-model DOF numbers and the rows of
    !> the basis for &output dofs (full-model numbers, checked against the full N; when given
    !> they are boundary DOFs of the reduction). The reduction's cache (&reduction cache) is
    !> read there; a model reduced here waits in case%reduction (cache_status 'pending') for
    !> write_reduction_cache_of, which the command line calls once the case is read (read_case
    !> itself writes nothing). `progress` reports the reading of large Matrix Market files
    !> (read_matrix_market) and the phases of a reduction that take a second or more
    !> (progress_t%phase); absent: quiet.
    subroutine read_case(path, case, error, progress)
        !> Path of the namelist file.
        character(len=*), intent(in) :: path
        !> The case read.
        type(case_t), intent(out) :: case
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Progress of long reads of matrix files and of the reduction's phases (optional).
        type(progress_t), intent(inout), optional :: progress
        type(nml_file_t) :: nml
        character(len=:), allocatable :: method
        logical :: method_given
        type(sparse_system_t) :: sparse
        integer :: k, j
        integer, allocatable :: keep(:)
        type(cyclic_t) :: cyc_full
        real(dp) :: band

        case%path = path
        call read_namelist_file(path, nml, error)
        if (allocated(error)) return
        call check_groups(nml, error)
        if (allocated(error)) return

        call read_reduction_group(nml, case%reduction, error)
        if (allocated(error)) return
        ! the entries of large matrix files are read when the reduction needs them (not on
        ! a cache hit)
        call read_system_group(nml, case%model, case%system_files, error, &
                               case%reduction%method, sparse, defer=.true., &
                               progress=progress)
        if (allocated(error)) return
        if (.not. sparse%read .and. case%reduction%method == 'craig-bampton') then
            ! asked for explicitly, a reduction of inline matrices would be ignored silently
            call group_error(nml, error, "&reduction method = 'craig-bampton': reduces a "// &
                             "model from &system mass_file / stiffness_file, but this case's "// &
                             "matrices are inline (&system mass, stiffness) and inline "// &
                             "matrices are never reduced: remove the &reduction group or give "// &
                             "the matrices as Matrix Market files")
            return
        end if
        if (case%reduction%interface_modes > 0 .and. (.not. sparse%read .or. &
                                                      nml%find("cyclic") == 0)) then
            call group_error(nml, error, "&reduction interface_modes = "// &
                             itoa(case%reduction%interface_modes)//": reduces the cyclic "// &
                             "faces of a sector of a bladed disk (&cyclic) given by Matrix "// &
                             "Market files; this case has no &cyclic group or inline matrices")
            return
        end if
        call read_forcing_group(nml, case%model, error, case%system_files, &
                                optional_group=modes_case(nml))
        if (allocated(error)) return
        call read_friction_group(nml, case%model, error, case%system_files, case%friction_form)
        if (allocated(error)) return
        call read_microslip_group(nml, case%model, error)
        if (allocated(error)) return
        call read_hbm_group(nml, case%hbm, case%checks, error)
        if (allocated(error)) return
        if (sparse%read) then
            ! &output dofs in full numbers, checked against the full N before the reduction
            call read_output_group(nml, case%model, case%directory, case%output_dofs, &
                                   case%output_dofs_given, case%full_field, &
                                   case%plot_amplitude, case%units, error)
            if (allocated(error)) return
            if (case%reduction%method == 'none' .and. nml%find("cyclic") > 0) then
                call group_error(nml, error, "&reduction method = 'none': a sector of a "// &
                                 "bladed disk (&cyclic) from Matrix Market files of more "// &
                                 "than 2000 DOFs is reduced (Craig-Bampton keeping its "// &
                                 "cyclic boundaries): use method = 'craig-bampton' or 'auto'")
                return
            else if (case%reduction%method == 'none') then
                ! the exact sparse condensation: no reduction, the matrices kept sparse
                call load_sparse_system(nml, case%system_files, case%model%ndof, sparse, error)
                if (allocated(error)) return
                allocate (case%sparse_model)
                case%sparse_model%model = case%model
                case%sparse_model%mass = sparse%mass
                case%sparse_model%stiffness = sparse%stiffness
                if (sparse%has_damping) case%sparse_model%damping = sparse%damping
                case%reduction%report%full_dof = case%model%ndof
                case%reduction%report%reduced_dof = case%model%ndof
            else if (nml%find("cyclic") > 0) then
                ! a sector of a bladed disk: its cyclic boundaries and next-sector DOFs kept
                ! by the reduction, then renumbered
                call read_cyclic_group(nml, case%model, case%cyclic, case%hbm%harmonics, &
                                       error, defer=.true.)
                if (allocated(error)) return
                call check_mode_list_early(nml, case%cyclic, error)
                if (allocated(error)) return
                keep = cyclic_boundary_dofs(case%cyclic%cyc)
                case%reduction%keep_basis = case%full_field
                call reduce_case_model(nml, case%reduction, sparse, case%system_files, &
                                       case%hbm%harmonics, case%model, case%output_dofs, &
                                       case%output_dofs_given, case%directory, error, &
                                       progress, keep)
                if (allocated(error)) return
                cyc_full = case%cyclic%cyc
                call set_cyclic_boundary_dofs(case%cyclic%cyc, keep)
                ! the run's highest harmonic frequency (a run of modes: of its backbones)
                band = abs(case%model%omega)*case%hbm%harmonics
                band = max(band, modes_band(nml, case%model, case%cyclic%cyc, &
                                            case%hbm%harmonics))
                if (allocated(case%reduction%report%error_frequencies)) band = &
                    max(band, maxval(case%reduction%report%error_frequencies))
                ! the faces by interface modes (measured below with the rest)
                if (case%reduction%interface_modes > 0) then
                    call reduce_case_faces(nml, case%reduction, case%model, &
                                           case%cyclic%cyc, band, error)
                    if (allocated(error)) return
                end if
                ! the reduction's error per nodal diameter (the full matrices are at hand
                ! unless the reduced model came from the cache)
                if (case%reduction%error_estimate .and. sparse%loaded) then
                    call measure_diameter_errors(nml, case%cyclic, sparse%stiffness, &
                                                 sparse%mass, cyc_full, case%model, &
                                                 case%hbm%harmonics, case%hbm%odd_only, &
                                                 band, error, run_engine_orders(nml, &
                                                 case%cyclic%cyc))
                    if (allocated(error)) return
                    call diameter_findings(case%cyclic, case%reduction%diagnostics)
                    ! kept with the model by the cache, for the runs that read it
                    if (allocated(case%cyclic%diameters)) call keep_diameter_errors( &
                        case%reduction%report, case%cyclic, band, &
                        case%reduction%interface_modes)
                else if (case%reduction%error_estimate) then
                    ! a cache hit: the errors measured when the cache was written, when they
                    ! cover this run's diameters and band
                    call restore_diameter_errors(case%reduction%report, case%cyclic, band, &
                                                 case%reduction%interface_modes, &
                                                 forced_diameters(case%cyclic%cyc, &
                                                                  case%hbm%harmonics, &
                                                                  case%hbm%odd_only, &
                                                                  run_engine_orders(nml, &
                                                                  case%cyclic%cyc)))
                    if (allocated(case%cyclic%diameters)) then
                        call diameter_findings(case%cyclic, case%reduction%diagnostics)
                    else
                        call case%reduction%diagnostics%add(level_note, &
                            "reduction_error_nd_cached", "reduction: the error per nodal "// &
                            "diameter is not measured in this run: the reduced model came "// &
                            "from the cache, whose measure covers other diameters or a "// &
                            "lower band (&reduction cache = 'off' measures it)")
                    end if
                end if
            else
                case%reduction%keep_basis = case%full_field
                call reduce_case_model(nml, case%reduction, sparse, case%system_files, &
                                       case%hbm%harmonics, case%model, case%output_dofs, &
                                       case%output_dofs_given, case%directory, error, progress)
                if (allocated(error)) return
            end if
            if (allocated(case%reduction%output_rows)) then
                ! the truncation estimate judges the output DOFs, not modal coordinates
                case%checks%observe = case%reduction%output_rows
            end if
        end if
        if (allocated(case%sparse_model)) then
            call validate_sparse_model(case%sparse_model, error)
            if (allocated(error)) then
                error%message = replace_prefix(error%message, "smodel%", "model%")
            end if
        else
            call validate_model(case%model, error)
        end if
        if (allocated(error)) then
            call to_case_message(error, nml%path, [character(len=1) ::], [character(len=1) ::])
            call name_matrix_file(error, "mass", case%system_files%mass_path)
            call name_matrix_file(error, "stiffness", case%system_files%stiffness_path)
            call name_matrix_file(error, "damping", case%system_files%damping_path)
            call name_column_file(error, "&friction contact_direction", "&friction "// &
                                  "direction_file", case%system_files%direction_path)
            call name_column_file(error, "&forcing force_shape", "&forcing force_file", &
                                  case%system_files%force_path)
            call name_direction_form(error, "normal", case%friction_form%normal, &
                                     case%friction_form%normal_path)
            call name_direction_form(error, "tangent2", case%friction_form%tangent2, &
                                     case%friction_form%tangent2_path)
            return
        end if

        ! a sector of a bladed disk: with &cyclic model = 'disk' the model becomes the disk
        if (case%cyclic%given) then
            call cyclic_case_model(nml, case%model, case%cyclic, case%hbm%harmonics, error)
        else
            call read_cyclic_group(nml, case%model, case%cyclic, case%hbm%harmonics, error)
        end if
        if (allocated(error)) return
        if (.not. sparse%read) then
            call read_output_group(nml, case%model, case%directory, case%output_dofs, &
                                   case%output_dofs_given, case%full_field, &
                                   case%plot_amplitude, case%units, error)
            if (allocated(error)) return
        end if
        if (case%model%ncontact() == 0) call case%diagnostics%add(level_warning, "no_contact", &
            "the case has no friction contact (no &friction group, or no contact_dof or "// &
            "direction_file in it): stickslip solves the linear response")
        if (allocated(error)) return
        call read_run_group(nml, method, method_given, error)
        if (allocated(error)) return
        call read_euler_group(nml, case%euler, error)
        if (allocated(error)) return
        call read_reference_group(nml, case%reference, error)
        if (allocated(error)) return
        call read_study_group(nml, case%study, error)
        if (allocated(error)) return
        call read_sweep_group(nml, case%model, case%sweep, case%has_sweep, error)
        if (allocated(error)) return
        call read_robustness_group(nml, case%robustness, error)
        if (allocated(error)) return
        call read_modes_group(nml, case%modes, case%has_modes, error)
        if (allocated(error)) return
        call check_modes_diameters(nml, case, error)
        if (allocated(error)) return

        call choose_method(nml, method, method_given, error)
        if (allocated(error)) return
        case%method = method
        if (method == 'sweep' .and. .not. case%has_sweep) then
            call group_error(nml, error, "&sweep: missing (method = 'sweep' needs the group "// &
                             "with at least start and stop)")
            return
        end if
        if (method == 'modes' .and. .not. case%has_modes) then
            call group_error(nml, error, "&modes: missing (method = 'modes' needs the group "// &
                             "with at least amplitude_start and amplitude_stop)")
            return
        end if
        if (method == 'modes' .and. case%model%ncontact() == 0) then
            call group_error(nml, error, "&run method = 'modes': the model has no friction "// &
                             "contact (give &friction)")
            return
        end if
        call check_sizes(nml, case, error)
        if (allocated(error)) return
        if (case%cyclic%given .and. case%cyclic%model == 'sector') then
            call check_sector_methods(nml, case, error)
            if (allocated(error)) return
        end if
        if (case%full_field .and. method /= 'hbm') then
            call group_error(nml, error, "&output full_field = T: only method = 'hbm' "// &
                             "writes full_field.mtx (this case runs method = '"//method//"')")
            return
        end if
        if (allocated(case%sparse_model)) then
            ! a sweep of the exact sparse condensation has no stability check: off by default
            if (method == 'sweep') then
                block
                    logical :: given_t, given_f
                    given_t = .true.
                    given_f = .false.
                    call get_logical(nml, "sweep", "stability", given_t, error)
                    if (allocated(error)) return
                    call get_logical(nml, "sweep", "stability", given_f, error)
                    if (allocated(error)) return
                    if (given_t .and. .not. given_f) case%sweep%stability = .false.
                end block
            end if
            call check_sparse_methods(nml, case, error)
            if (allocated(error)) return
            if (method == 'sweep' .and. allocated(case%sweep%family%family_values)) then
                call group_error(nml, error, "&sweep family_values: a family of curves "// &
                                 "needs a dense or reduced model (&reduction method = "// &
                                 "'none' keeps this one sparse: reduce it, method = "// &
                                 "'craig-bampton' or 'auto')")
                return
            end if
        end if
    end subroutine read_case

    !> The engine orders of the waves a sector's run computes: the forcing's, or in a run
    !> of nonlinear modes (&run method = 'modes') its &modes nodal_diameters (default every
    !> diameter 0..N/2; values out of range left to the checks of &modes).
    function run_engine_orders(nml, cyc) result(eos)
        type(nml_file_t), intent(in) :: nml
        type(cyclic_t), intent(in) :: cyc
        integer, allocatable :: eos(:)
        character(len=:), allocatable :: method
        type(error_type), allocatable :: error
        integer, allocatable :: given(:)
        logical :: found
        integer :: k
        eos = [cyc%engine_order]
        method = ''
        call get_string(nml, "run", "method", method, error)
        if (allocated(error)) return
        if (lower(trim(method)) /= 'modes') return
        eos = [(k, k=0, cyc%sectors/2)]
        call get_integers(nml, "modes", "nodal_diameters", given, found, cyc%sectors, error)
        if (allocated(error) .or. .not. found) return
        eos = pack(given, given >= 0 .and. given <= cyc%sectors/2)
    end function run_engine_orders

    !> Keep a sector's measured error per nodal diameter (cc, measured up to `band` with
    !> `faces` interface modes a face) in the reduction's report, which the cache stores.
    subroutine keep_diameter_errors(report, cc, band, faces)
        type(reduction_report_t), intent(inout) :: report
        type(cyclic_case_t), intent(in) :: cc
        real(dp), intent(in) :: band
        integer, intent(in) :: faces
        report%diameters = cc%diameters
        report%diameter_errors = cc%diameter_errors
        report%diameter_lowest = cc%diameter_lowest
        report%diameter_band = band
        report%diameter_faces = faces
    end subroutine keep_diameter_errors

    !> On a cache hit: the error per nodal diameter of the diameters `wanted` into cc from
    !> the cached report, when it measured each of them up to at least `band` [rad/s] (with
    !> interface modes, exactly `band`: their shapes depend on it) with the same `faces`
    !> interface modes a face; cc%diameters stays unallocated otherwise.
    subroutine restore_diameter_errors(report, cc, band, faces, wanted)
        type(reduction_report_t), intent(in) :: report
        type(cyclic_case_t), intent(inout) :: cc
        real(dp), intent(in) :: band
        integer, intent(in) :: faces, wanted(:)
        integer :: k, j
        integer, allocatable :: at(:)
        if (.not. allocated(report%diameters)) return
        if (report%diameter_faces /= faces .or. report%diameter_band < band) return
        ! interface modes take their shapes from the band: the same band, the same sector
        if (faces > 0 .and. report%diameter_band /= band) return
        allocate (at(size(wanted)))
        do k = 1, size(wanted)
            at(k) = 0
            do j = 1, size(report%diameters)
                if (report%diameters(j) == wanted(k)) at(k) = j
            end do
            if (at(k) == 0) return
        end do
        cc%diameters = wanted
        cc%diameter_errors = report%diameter_errors(at)
        cc%diameter_lowest = report%diameter_lowest(at)
    end subroutine restore_diameter_errors

    !> The highest harmonic frequency a sector's run of modes reaches [rad/s]: H times the
    !> highest stuck frequency (stickslip_cyclic_limits) of the modes it traces, &modes mode
    !> (one, or one per diameter) in each diameter of run_engine_orders; its backbones start
    !> there and their frequencies fall as the contacts slip (they may rise, as a damper's
    !> diameter 1, to its slipping one: the larger of the two then). 0 for another method,
    !> or when `model` is not valid or has no such mode (the errors come later, from the
    !> checks of the model and of &modes).
    function modes_band(nml, model, cyc, harmonics) result(band)
        type(nml_file_t), intent(in) :: nml
        !> The sector (reduced).
        type(model_t), intent(in) :: model
        !> Its disk.
        type(cyclic_t), intent(in) :: cyc
        !> The harmonics H.
        integer, intent(in) :: harmonics
        real(dp) :: band
        type(cyclic_t) :: one
        type(error_type), allocatable :: error
        integer, allocatable :: eos(:), modes(:)
        real(dp), allocatable :: ws(:), wf(:)
        complex(dp), allocatable :: phis(:, :), phif(:, :)
        complex(dp) :: e
        logical :: found
        integer :: i, k, mode
        band = 0.0_dp
        if (.not. modes_case(nml)) return
        call validate_model(model, error)
        if (allocated(error)) return
        eos = run_engine_orders(nml, cyc)
        call get_integers(nml, "modes", "mode", modes, found, max_sectors/2 + 1, error)
        if (allocated(error)) return
        if (.not. found) modes = [1]
        if (size(modes) /= 1 .and. size(modes) /= size(eos)) return
        one = cyc
        do i = 1, size(eos)
            mode = modes(min(i, size(modes)))
            one%engine_order = eos(i)
            e = exp(cmplx(0.0_dp, sector_phase(1, eos(i), cyc%sectors, 1), dp))
            ! the diameter's stuck mode, and the slipping one most like it (as run_modes)
            call cyclic_limit_modes(model, one, e, .true., ws, phis, error)
            if (allocated(error)) return
            if (mode < 1 .or. mode > size(ws)) cycle
            band = max(band, harmonics*ws(mode))
            call cyclic_limit_modes(model, one, e, .false., wf, phif, error)
            if (allocated(error)) return
            if (size(wf) == 0) cycle
            k = maxloc(abs(matmul(conjg(transpose(phif)), matmul(model%mass, phis(:, mode)))), 1)
            band = max(band, harmonics*wf(k))
        end do
    end function modes_band

    !> Whether the case computes nonlinear modes (a &modes group or &run method = 'modes'),
    !> which need no &forcing. A bad &run method is left to read_run_group.
    logical function modes_case(nml)
        type(nml_file_t), intent(in) :: nml
        character(len=:), allocatable :: method
        type(error_type), allocatable :: error
        method = ''
        modes_case = nml%find("modes") > 0
        if (modes_case .or. nml%find("run") == 0) return
        call get_string(nml, "run", "method", method, error)
        if (.not. allocated(error)) modes_case = lower(trim(method)) == 'modes'
    end function modes_case

    !> &reduction method = 'none' on a model above max_file_dof runs only the weighted
    !> residual (method 'hbm', and 'sweep' with &sweep stability = .false.) without the
    !> checks that integrate in time: anything else is one error naming &run method (or the
    !> check) and &reduction method.
    subroutine check_sparse_methods(nml, case, error)
        type(nml_file_t), intent(in) :: nml
        type(case_t), intent(in) :: case
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: what
        what = weighted_residual_only(case, .true.)
        if (len(what) == 0) return
        call group_error(nml, error, what//": needs the dense matrices of a small or "// &
                         "reduced model, but &reduction method = 'none' keeps this model "// &
                         "from files (N = "//itoa(case%model%ndof)//" > "// &
                         itoa(max_file_dof)//" DOFs) sparse, where only the weighted "// &
                         "residual runs (&run method = 'hbm' without stability, "// &
                         "verify_periods, harmonics_tol; 'sweep' with &sweep stability = "// &
                         ".false.); use &reduction method = 'craig-bampton' (or 'auto')")
    end subroutine check_sparse_methods

    !> What runs on one sector of a disk (&cyclic model = 'sector'): the weighted residual
    !> (method 'hbm' without verify_periods, harmonics_tol; 'sweep', families included; the
    !> stability of either is the assembled disk's); anything else is an input error naming
    !> what asked for it and the remedy, model = 'disk'.
    subroutine check_sector_methods(nml, case, error)
        type(nml_file_t), intent(in) :: nml
        type(case_t), intent(in) :: case
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: what
        integer(int64) :: disk_dofs
        integer :: spans, limit
        if (case%method == 'modes') return
        what = weighted_residual_only(case, .false.)
        if (len(what) == 0) then
            ! the stability is the assembled disk's: only where that is affordable
            what = weighted_residual_only(case, .true.)
            disk_dofs = int(case%cyclic%cyc%sectors, int64)* &
                        (case%model%ndof - size(case%cyclic%cyc%right))
            spans = stability_spans(wave_symmetry_t(case%cyclic%cyc%sectors, &
                                                    case%cyclic%cyc%engine_order), &
                                    case%hbm%samples)
            limit = max_disk_stability_dof
            if (spans >= 8) limit = max_disk_stability_dof_wave
            if (len(what) == 0 .or. disk_dofs <= limit) return
            if (case%method == 'sweep' .and. .not. is_given(nml, 'sweep', 'stability')) &
                what = what//" (the default)"
            call group_error(nml, error, what//": the stability of a sector's travelling "// &
                             "wave is the assembled disk's Floquet multipliers (every "// &
                             "perturbation), and that disk would have "// &
                             itoa(int(disk_dofs))//" DOFs: more than the "// &
                             itoa(limit)//" for which its exact flow "// &
                             flow_span(spans)//"costs seconds a point (minutes to hours "// &
                             "beyond); set "// &
                             what(1:index(what, " = ") - 1)//" = .false., or &cyclic "// &
                             "model = 'disk' to run the assembled disk with its stability "// &
                             "knowingly")
            return
        end if
        call group_error(nml, error, what//": on one sector of a disk (&cyclic model = "// &
                         "'sector') only the weighted residual runs in this version "// &
                         "(&run method = 'hbm' without verify_periods, harmonics_tol; "// &
                         "'sweep', families included, their stability the assembled disk's; "// &
                         "'modes', the backbones per nodal diameter); set &cyclic model = "// &
                         "'disk' to run it on the assembled full disk")

    contains

        !> "(over T/m by the wave's symmetry) " for m > 1, else "".
        function flow_span(m) result(text)
            integer, intent(in) :: m
            character(len=:), allocatable :: text
            text = ""
            if (m > 1) text = "(over T/"//itoa(m)//" by the wave's symmetry) "
        end function flow_span
    end subroutine check_sector_methods

    !> &modes nodal_diameters: only on one sector of a disk, each in 0 .. N/2 and given once;
    !> &modes mode as a list (one per diameter): only on one sector, as many as the
    !> diameters traced; an input error naming the variable (and its element) otherwise.
    subroutine check_modes_diameters(nml, case, error)
        type(nml_file_t), intent(in) :: nml
        type(case_t), intent(in) :: case
        type(error_type), allocatable, intent(out) :: error
        integer :: k, n
        if (allocated(case%modes%diameter_modes)) then
            if (.not. (case%cyclic%given .and. case%cyclic%model == 'sector')) then
                call group_error(nml, error, "&modes mode: "// &
                                 itoa(size(case%modes%diameter_modes))//" values, one per "// &
                                 "nodal diameter, only on one sector of a bladed disk "// &
                                 "(&cyclic with model = 'sector'); give one mode")
                return
            end if
            call check_mode_count(nml, size(case%modes%diameter_modes), &
                                  case%cyclic%cyc%sectors, error, case%modes%nodal_diameters)
            if (allocated(error)) return
        end if
        if (.not. allocated(case%modes%nodal_diameters)) return
        if (.not. (case%cyclic%given .and. case%cyclic%model == 'sector')) then
            call group_error(nml, error, "&modes nodal_diameters: only on one sector of a "// &
                             "bladed disk (&cyclic with model = 'sector'); this case has "// &
                             "no &cyclic group or assembles the disk")
            return
        end if
        n = case%cyclic%cyc%sectors
        do k = 1, size(case%modes%nodal_diameters)
            associate (nd => case%modes%nodal_diameters(k))
                if (nd < 0 .or. nd > n/2) then
                    call group_error(nml, error, "&modes nodal_diameters("//itoa(k)//") = "// &
                                     itoa(nd)//": must be 0 to N/2 = "//itoa(n/2)// &
                                     " (&cyclic sectors = "//itoa(n)//")")
                    return
                end if
                if (any(case%modes%nodal_diameters(1:k - 1) == nd)) then
                    call group_error(nml, error, "&modes nodal_diameters("//itoa(k)//") = "// &
                                     itoa(nd)//": given twice")
                    return
                end if
            end associate
        end do
    end subroutine check_modes_diameters

    !> A &modes mode list of `nvalues` values (more than one) on a disk of `sectors`
    !> sectors: an error naming &modes mode unless there is one value per nodal diameter
    !> traced (`diameters`, &modes nodal_diameters when given, else every diameter 0..N/2).
    subroutine check_mode_count(nml, nvalues, sectors, error, diameters)
        type(nml_file_t), intent(in) :: nml
        integer, intent(in) :: nvalues, sectors
        type(error_type), allocatable, intent(out) :: error
        integer, intent(in), optional :: diameters(:)
        integer :: traced
        character(len=:), allocatable :: which
        traced = sectors/2 + 1
        which = "every diameter 0..N/2"
        if (present(diameters)) then
            traced = size(diameters)
            which = "&modes nodal_diameters"
        end if
        if (nvalues /= traced) call group_error(nml, error, "&modes mode: "//itoa(nvalues)// &
                                                " values, but "//itoa(traced)//" nodal "// &
                                                "diameters are traced ("//which//"): give "// &
                                                "one mode, or one per diameter in their order")
    end subroutine check_mode_count

    !> A sector's run of modes whose &modes mode list has not one value per nodal diameter
    !> traced: the error of check_modes_diameters, before the reduction (which takes
    !> seconds on an FE sector) rather than after it. A bad value is left to the group's
    !> own reading.
    subroutine check_mode_list_early(nml, cc, error)
        type(nml_file_t), intent(in) :: nml
        !> The &cyclic group as read.
        type(cyclic_case_t), intent(in) :: cc
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: modes(:), diameters(:)
        type(error_type), allocatable :: ignored
        logical :: found, given
        if (.not. modes_case(nml) .or. cc%model /= 'sector') return
        call get_integers(nml, "modes", "mode", modes, found, max_sectors/2 + 1, ignored)
        if (allocated(ignored) .or. .not. found) return
        if (size(modes) <= 1) return
        call get_integers(nml, "modes", "nodal_diameters", diameters, given, &
                          max_sectors/2 + 1, ignored)
        if (allocated(ignored)) return
        if (given) then
            call check_mode_count(nml, size(modes), cc%cyc%sectors, error, diameters)
        else
            call check_mode_count(nml, size(modes), cc%cyc%sectors, error)
        end if
    end subroutine check_mode_list_early

    !> For a model on which only the weighted residual runs (&run method 'hbm' or 'sweep',
    !> no &hbm verify_periods or harmonics_tol, and with `no_stability` no &hbm or &sweep
    !> stability): the first setting of `case` asking for more, as the case file writes it
    !> ('' when none).
    function weighted_residual_only(case, no_stability) result(what)
        type(case_t), intent(in) :: case
        logical, intent(in) :: no_stability
        character(len=:), allocatable :: what
        what = ""
        if (case%method == 'sweep') then
            if (no_stability .and. case%sweep%stability) what = "&sweep stability = .true."
        else if (case%method /= 'hbm') then
            what = "&run method = '"//trim(case%method)//"'"
        else if (no_stability .and. case%checks%stability) then
            what = "&hbm stability = .true."
        else if (case%checks%verify_periods > 0) then
            what = "&hbm verify_periods = "//itoa(case%checks%verify_periods)
        else if (case%checks%harmonics_tol > 0.0_dp) then
            what = "&hbm harmonics_tol = "//rtoa(case%checks%harmonics_tol)
        end if
    end function weighted_residual_only

    !> `text` with its first `old` replaced by `new`.
    pure function replace_prefix(text, old, new) result(out)
        character(len=*), intent(in) :: text, old, new
        character(len=:), allocatable :: out
        integer :: k
        out = text
        k = index(text, old)
        if (k > 0) out = text(1:k - 1)//new//text(k + len(old):)
    end function replace_prefix

    !> A model message about &system `name` names the file the matrix came from.
    subroutine name_matrix_file(error, name, path)
        type(error_type), intent(inout) :: error
        character(len=*), intent(in) :: name
        character(len=:), allocatable, intent(in) :: path
        integer :: k
        if (.not. allocated(path)) return
        k = index(error%message, "&system "//name)
        if (k == 0) return
        k = k + len("&system "//name)
        error%message = error%message(1:k - 1)//" (from "//name//"_file '"//path//"')"// &
                        error%message(k:)
    end subroutine name_matrix_file

    !> A model message about `component` (the model_t name of a matrix read from a file) is
    !> about the file variable `variable` and names its file.
    subroutine name_column_file(error, component, variable, path)
        type(error_type), intent(inout) :: error
        character(len=*), intent(in) :: component, variable
        character(len=:), allocatable, intent(in) :: path
        integer :: k
        integer :: e
        if (.not. allocated(path)) return
        k = index(error%message, component)
        if (k == 0) return
        ! "<component>(:, j)" is column j of the file
        if (index(error%message(k + len(component):), "(:, ") == 1) then
            e = index(error%message(k + len(component):), ")")
            error%message = error%message(1:k - 1)//variable//" '"//path//"' column "// &
                            error%message(k + len(component) + 4:k + len(component) + e - 2)// &
                            error%message(k + len(component) + e:)
            return
        end if
        error%message = error%message(1:k - 1)//variable//" '"//path//"'"// &
                        error%message(k + len(component):)
    end subroutine name_column_file

    !> In a message about "<kind>_direction(:, j)" name the variable the case gave:
    !> "<kind>_dof(j)" (form 'dof'), "<kind>_file '<path>' column j" (form 'file'); the
    !> inline form keeps its name.
    subroutine name_direction_form(error, kind, form, path)
        type(error_type), intent(inout) :: error
        character(len=*), intent(in) :: kind, form
        character(len=:), allocatable, intent(in) :: path
        character(len=:), allocatable :: head
        integer :: k, e
        head = kind//"_direction(:, "
        k = index(error%message, head)
        if (k == 0) return
        e = index(error%message(k + len(head):), ")")
        if (e == 0) return
        e = k + len(head) + e - 1
        select case (form)
        case ('dof')
            error%message = error%message(1:k - 1)//kind//"_dof("// &
                            error%message(k + len(head):e)//error%message(e + 1:)
        case ('file')
            if (.not. allocated(path)) return
            error%message = error%message(1:k - 1)//kind//"_file '"//path//"' column "// &
                            error%message(k + len(head):e - 1)//error%message(e + 1:)
        end select
    end subroutine name_direction_form

    !> Every group known and given once (groups named summary* are the results echoed in
    !> a summary.nml: ignored). Errors name the group (and suggest the closest known one)
    !> or both lines of a repeated group.
    subroutine check_groups(nml, error)
        type(nml_file_t), intent(in) :: nml
        type(error_type), allocatable, intent(out) :: error
        integer :: g, k, best, kbest, d
        character(len=:), allocatable :: hint
        do g = 1, nml%ngroups
            associate (name => nml%groups(g)%name)
                ! the result groups of a summary.nml, which reads back as its case
                if (index(name, "summary") == 1) cycle
                if (.not. any(known_groups == name)) then
                    best = huge(1)
                    kbest = 0
                    do k = 1, size(known_groups)
                        d = edit_distance(name, trim(known_groups(k)))
                        if (d < best) then
                            best = d
                            kbest = k
                        end if
                    end do
                    if (best <= 2 .and. best < len(name)) then
                        hint = " (did you mean &"//trim(known_groups(kbest))//"?)"
                    else
                        hint = " (known: "
                        do k = 1, size(known_groups)
                            hint = hint//"&"//trim(known_groups(k))
                            if (k < size(known_groups)) hint = hint//", "
                        end do
                        hint = hint//")"
                    end if
                    call fatal_error(error, nml%path//":"//itoa(nml%groups(g)%line)// &
                                     ": unknown group &"//name//hint, stickslip_stat%input)
                    return
                end if
                do k = 1, g - 1
                    if (nml%groups(k)%name == name) then
                        call fatal_error(error, nml%path//":"//itoa(nml%groups(g)%line)// &
                                         ": group &"//name//" given twice (lines "// &
                                         itoa(nml%groups(k)%line)//" and "// &
                                         itoa(nml%groups(g)%line)//")", stickslip_stat%input)
                        return
                    end if
                end do
            end associate
        end do
    end subroutine check_groups

    !> The method: &run method when given, which must then agree with any &study, &sweep or
    !> &robustness group present; otherwise the method of the one such group present
    !> ('hbm' when none). Errors name the groups and the method.
    subroutine choose_method(nml, method, given, error)
        type(nml_file_t), intent(in) :: nml
        character(len=:), allocatable, intent(inout) :: method
        logical, intent(in) :: given
        type(error_type), allocatable, intent(out) :: error
        character(len=10), parameter :: studies(4) = [character(len=10) :: 'study', 'sweep', &
                                                      'robustness', 'modes']
        logical :: present(4)
        character(len=:), allocatable :: names
        integer :: k
        present = [(nml%find(trim(studies(k))) > 0, k=1, 4)]
        if (given) then
            do k = 1, 4
                if (present(k) .and. method /= trim(studies(k))) then
                    call group_error(nml, error, "&"//trim(studies(k))//" given but &run "// &
                                     "method = '"//method//"'; set method = '"// &
                                     trim(studies(k))//"' or remove the group")
                    return
                end if
            end do
        else if (count(present) == 1) then
            method = trim(studies(findloc(present, .true., 1)))
        else if (count(present) > 1) then
            names = ""
            do k = 1, 4
                if (present(k)) names = names//" &"//trim(studies(k))
            end do
            call group_error(nml, error, "&run method: missing, and"//names//" are given: "// &
                             "set &run method to the one to run and remove the others")
        end if
    end subroutine choose_method

    !> Sizes the library validators cannot judge alone (they depend on the model): the
    !> unknowns of the weighted residual and the memory of the sampled results.
    subroutine check_sizes(nml, case, error)
        type(nml_file_t), intent(in) :: nml
        type(case_t), intent(in) :: case
        type(error_type), allocatable, intent(out) :: error
        integer(int64) :: per_sample, nc
        integer :: h
        character(len=:), allocatable :: what
        nc = case%model%ncontact()
        per_sample = 2_int64*case%model%ndof + 3_int64*nc + 1
        ! the exact sparse condensation recovers only the selected, contact and forced DOFs
        if (allocated(case%sparse_model)) per_sample = 2_int64*(size(selected_dofs(case)) + &
            2_int64*nc + case%model%nforce()) + 3_int64*nc + 1
        ! the highest H the method's weighted-residual solves reach
        h = -1
        select case (case%method)
        case ('hbm', 'all', 'sweep', 'reference', 'modes')
            if (case%method /= 'reference' .or. case%reference%start /= 'euler') then
                h = case%hbm%harmonics
                what = "&hbm harmonics = "//itoa(h)
                if (case%method == 'hbm' .and. case%checks%harmonics_tol > 0.0_dp) then
                    ! the harmonics_tol loop climbs to max_harmonics (0: 8 x harmonics)
                    h = case%checks%max_harmonics
                    what = "&hbm max_harmonics = "//itoa(h)
                    if (h == 0) then
                        h = int(min(8_int64*case%hbm%harmonics, int(huge(1), int64)))
                        what = "&hbm max_harmonics = 0 (automatic: 8 x harmonics = "// &
                               itoa(h)//")"
                    end if
                end if
            end if
        case ('study')
            h = maxval([0, case%study%harmonics])
            what = "&study harmonics up to "//itoa(h)
        case ('robustness')
            h = maxval([0, case%robustness%harmonics])
            what = "&robustness harmonics up to "//itoa(h)
        end select
        if (h >= 0 .and. nc > 0 .and. (2_int64*h + 1)*nc > hbm_max_unknowns) then
            call group_error(nml, error, what//": (2 H + 1) x "//itoa(int(nc))// &
                             " contacts = "//itoa(int(min((2_int64*h + 1)*nc, &
                             int(huge(1), int64))))//" unknowns, at most "// &
                             itoa(hbm_max_unknowns)//" (the Jacobian is dense)")
            return
        end if
        call sample_limit("&hbm samples", case%hbm%samples)
        if (allocated(error)) return
        call sample_limit("&euler steps_per_period", case%euler%steps_per_period)
        if (allocated(error)) return
        call sample_limit("&reference samples", case%reference%samples)
        if (allocated(error)) return
        if (case%method == 'study') then
            call sample_limit("&study samples", maxval([0, case%study%samples]))
            if (allocated(error)) return
            call sample_limit("&study steps_per_period", maxval([0, case%study%steps_per_period]))
        else if (case%method == 'robustness') then
            call sample_limit("&robustness samples", maxval([0, case%robustness%samples]))
            if (allocated(error)) return
            call sample_limit("&robustness steps_per_period", &
                              maxval([0, case%robustness%steps_per_period]))
        end if

    contains

        subroutine sample_limit(what, count)
            character(len=*), intent(in) :: what
            integer, intent(in) :: count
            if (int(count, int64)*per_sample <= max_sample_values) return
            call group_error(nml, error, what//" = "//itoa(count)//": the results would "// &
                             "hold "//itoa(count)//" x "//itoa(int(per_sample))// &
                             " doubles (2 ndof + 3 contacts + 1 per sample), more than "// &
                             "2**27 (1 GiB); at most "//itoa(int(max_sample_values/per_sample))// &
                             " for this model")
        end subroutine sample_limit
    end subroutine check_sizes

    !> The DOFs the result files of `case` hold, in column order: case%output_dofs, or the
    !> default selection of its model (default_output_dofs) when that is not set.
    function selected_dofs(case) result(dofs)
        !> The case.
        type(case_t), intent(in) :: case
        integer, allocatable :: dofs(:)
        if (allocated(case%output_dofs)) then
            dofs = case%output_dofs
        else
            dofs = default_output_dofs(case%model)
        end if
    end function selected_dofs

    !> The model a case file describes: the case's model, or with &cyclic model = 'disk' the
    !> sector it was assembled from.
    function echoed_model(case) result(m)
        type(case_t), intent(in) :: case
        type(model_t) :: m
        if (case%cyclic%given) then
            m = case%cyclic%sector
        else
            m = case%model
        end if
    end function echoed_model

    !> Write `case` as namelist text that read_case reads back (full precision), to `unit`.
    !> A model read from Matrix Market files is echoed as its file variables with ABSOLUTE
    !> paths (the echo is read from another folder: the output directory) and the Rayleigh
    !> factors; an inline model as its matrices, the damping written in full (Rayleigh terms
    !> included, so rayleigh_alpha and rayleigh_beta are not repeated). Contact directions and
    !> load shapes from files are echoed as direction_file and force_file (absolute paths);
    !> set in memory (no file), as a comment saying so (the echo then does not read back).
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
        type(model_t) :: echo
        stat = 0
        ! (a variable, not an associate-name on the function: gfortran 12 frees that twice)
        echo = echoed_model(case)
        associate (m => echo, o => case%hbm)
            call put(unit, "&system", stat, msg)
            if (case%reduction%report%method == 'craig-bampton') then
                call put(unit, "  ndof = "//itoa(case%reduction%report%full_dof), stat, msg)
            else
                call put(unit, "  ndof = "//itoa(m%ndof), stat, msg)
            end if
            associate (f => case%system_files)
                if (allocated(f%mass_absolute) .and. allocated(f%stiffness_absolute)) then
                    call put(unit, "  mass_file = "//quoted(f%mass_absolute), stat, msg)
                    call put(unit, "  stiffness_file = "//quoted(f%stiffness_absolute), stat, &
                             msg)
                    if (allocated(f%damping_absolute)) call put(unit, "  damping_file = "// &
                        quoted(f%damping_absolute), stat, msg)
                    call put(unit, "  rayleigh_alpha = "//rtoa(f%rayleigh_alpha), stat, msg)
                    call put(unit, "  rayleigh_beta = "//rtoa(f%rayleigh_beta), stat, msg)
                else
                    call put(unit, "  mass = "//rlist(reshape(m%mass, [m%ndof**2])), stat, msg)
                    call put(unit, "  stiffness = "//rlist(reshape(m%stiffness, [m%ndof**2])), &
                             stat, msg)
                    call put(unit, "  damping = "//rlist(reshape(m%damping, [m%ndof**2])), stat, &
                             msg)
                end if
            end associate
            call put(unit, "/", stat, msg)
            if (m%nforce() > 0) call put(unit, "&forcing", stat, msg)
            if (m%nforce() > 0) call put(unit, "  omega = "//rtoa(m%omega), stat, msg)
            if (m%nforce() == 0) then
                ! a case without forcing (method 'modes'): no &forcing group
                continue
            else if (allocated(case%system_files%force_absolute)) then
                call put(unit, "  force_file = "//quoted(case%system_files%force_absolute), &
                         stat, msg)
            else if (allocated(m%force_shape)) then
                ! a case built in memory: a matrix has no namelist form
                call put(unit, "  ! force_shape ("//itoa(size(m%force_shape, 1))//" x "// &
                         itoa(size(m%force_shape, 2))//") set in memory: give it as "// &
                         "force_file", stat, msg)
            else if (allocated(case%reduction%force_dof)) then
                call put(unit, "  force_dof = "//ilist(case%reduction%force_dof), stat, msg)
            else
                call put(unit, "  force_dof = "//ilist(m%force_dof), stat, msg)
            end if
            if (m%nforce() > 0) then
                call put(unit, "  force_harmonic = "//ilist(m%force_harmonic), stat, msg)
                call put(unit, "  force_amplitude = "//rlist(m%force_amplitude), stat, msg)
                call put(unit, "  force_phase = "//rlist(m%force_phase), stat, msg)
                call put(unit, "/", stat, msg)
            end if
            call put(unit, "&friction", stat, msg)
            if (m%ncontact() > 0) then
                if (allocated(case%system_files%direction_absolute)) then
                    call put(unit, "  direction_file = "// &
                             quoted(case%system_files%direction_absolute), stat, msg)
                else if (allocated(m%contact_direction)) then
                    call put(unit, "  ! contact_direction ("// &
                             itoa(size(m%contact_direction, 1))//" x "// &
                             itoa(size(m%contact_direction, 2))//") set in memory: give "// &
                             "it as direction_file", stat, msg)
                else if (allocated(case%reduction%contact_dof)) then
                    call put(unit, "  contact_dof = "//ilist(case%reduction%contact_dof), stat, &
                             msg)
                    call put(unit, "  contact_dof2 = "//ilist(case%reduction%contact_dof2), &
                             stat, msg)
                else
                    call put(unit, "  contact_dof = "//ilist(m%contact_dof), stat, msg)
                    call put(unit, "  contact_dof2 = "//ilist(m%contact_dof2), stat, msg)
                end if
                call put(unit, "  mu = "//rlist(m%mu), stat, msg)
                call put(unit, "  normal_load = "//rlist(m%normal_load), stat, msg)
                call put_directions("normal", case%friction_form%normal, &
                                    case%friction_form%normal_dof, &
                                    case%friction_form%normal_dof2, &
                                    case%friction_form%normal_absolute, m%normal_direction)
                call put_directions("tangent2", case%friction_form%tangent2, &
                                    case%friction_form%tangent2_dof, &
                                    case%friction_form%tangent2_dof2, &
                                    case%friction_form%tangent2_absolute, &
                                    m%tangent2_direction)
                if (allocated(m%gap)) call put(unit, "  gap = "//rlist(m%gap), stat, msg)
                if (allocated(m%preload)) call put(unit, "  preload = "//rlist(m%preload), &
                                                   stat, msg)
                if (allocated(m%normal_stiffness)) call put(unit, "  normal_stiffness = "// &
                                                            rlist(m%normal_stiffness), stat, msg)
                if (allocated(m%tangential_stiffness)) call put(unit, &
                    "  tangential_stiffness = "//rlist(m%tangential_stiffness), stat, msg)
            end if
            call put(unit, "/", stat, msg)
            call put_microslip()
            call put(unit, "&reduction", stat, msg)
            call put(unit, "  method = '"//trim(case%reduction%method)//"'", stat, msg)
            call put(unit, "  modes = "//itoa(case%reduction%modes), stat, msg)
            call put(unit, "  max_frequency = "//rtoa(case%reduction%max_frequency), stat, msg)
            call put(unit, "  damping_ratio = "//rtoa(case%reduction%damping_ratio), stat, msg)
            call put(unit, "  error_estimate = "//ltoa(case%reduction%error_estimate), stat, msg)
            if (case%reduction%interface_modes > 0) call put(unit, "  interface_modes = "// &
                itoa(case%reduction%interface_modes), stat, msg)
            if (allocated(case%reduction%cache)) call put(unit, "  cache = "// &
                quoted(case%reduction%cache), stat, msg)
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
            if (case%output_dofs_given .and. allocated(case%output_dofs)) &
                call put(unit, "  dofs = "//ilist(case%output_dofs), stat, msg)
            if (case%full_field) call put(unit, "  full_field = T", stat, msg)
            if (allocated(case%plot_amplitude)) call put(unit, "  plot_amplitude = '"// &
                                                         case%plot_amplitude//"'", stat, msg)
            call put(unit, "  length_unit = '"//trim(case%units%length)//"'", stat, msg)
            call put(unit, "  force_unit = '"//trim(case%units%force)//"'", stat, msg)
            call put(unit, "  time_unit = '"//trim(case%units%time)//"'", stat, msg)
            call put(unit, "  frequency_unit = '"// &
                     trim(merge('Hz   ', 'rad/s', case%units%cycles))//"'", stat, msg)
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
            call put(unit, "  ode_tol = "//rtoa(case%reference%ode_tol), stat, msg)
            call put(unit, "  start = '"//trim(case%reference%start)//"'", stat, msg)
            call put(unit, "/", stat, msg)
            ! only the groups of the method: read_case rejects a study group beside another
            ! method
            if (case%method == 'study' .and. allocated(case%study%harmonics)) then
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
            if (case%has_modes .and. case%method == 'modes') then
                associate (w => case%modes)
                    call put(unit, "&modes", stat, msg)
                    if (allocated(w%diameter_modes)) then
                        call put(unit, "  mode = "//ilist(w%diameter_modes), stat, msg)
                    else
                        call put(unit, "  mode = "//itoa(w%mode), stat, msg)
                    end if
                    call put(unit, "  amplitude_start = "//rtoa(w%amplitude_start), stat, msg)
                    call put(unit, "  amplitude_stop = "//rtoa(w%amplitude_stop), stat, msg)
                    call put(unit, "  points = "//itoa(w%points), stat, msg)
                    call put(unit, "  plot = "//ltoa(w%plot), stat, msg)
                    call put(unit, "  error_estimate = "//ltoa(w%error_estimate), stat, msg)
                    call put(unit, "  refinements = "//itoa(w%refinements), stat, msg)
                    if (allocated(w%nodal_diameters)) call put(unit, "  nodal_diameters = "// &
                                                               ilist(w%nodal_diameters), stat, msg)
                    call put(unit, "/", stat, msg)
                end associate
            end if
            if (case%cyclic%given) then
                associate (c => case%cyclic%cyc)
                    call put(unit, "&cyclic", stat, msg)
                    call put(unit, "  sectors = "//itoa(c%sectors), stat, msg)
                    call put(unit, "  engine_order = "//itoa(c%engine_order), stat, msg)
                    call put(unit, "  left_dofs = "//ilist(c%left), stat, msg)
                    call put(unit, "  right_dofs = "//ilist(c%right), stat, msg)
                    if (allocated(c%next_dof)) call put(unit, "  next_dof = "// &
                                                        ilist(c%next_dof), stat, msg)
                    if (allocated(c%next_tangent2_dof)) call put(unit, &
                        "  next_tangent2_dof = "//ilist(c%next_tangent2_dof), stat, msg)
                    if (allocated(c%next_normal_dof)) call put(unit, "  next_normal_dof = "// &
                                                               ilist(c%next_normal_dof), stat, msg)
                    call put(unit, "  model = '"//trim(case%cyclic%model)//"'", stat, msg)
                    call put(unit, "/", stat, msg)
                end associate
            end if
            if (case%has_sweep .and. case%method == 'sweep') then
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
                    if (allocated(w%family%family_values)) then
                        call put(unit, "  family_parameter = '"// &
                                 trim(w%family%family_parameter)//"'", stat, msg)
                        call put(unit, "  family_values = "//rlist(w%family%family_values), &
                                 stat, msg)
                    end if
                    call put(unit, "/", stat, msg)
                end associate
            end if
        end associate

    contains

        !> The normal or second tangential directions in the form the case gave them; a
        !> matrix set in memory (no form) as a comment.
        subroutine put_directions(kind, form, dof, dof2, absolute, d)
            character(len=*), intent(in) :: kind, form
            integer, allocatable, intent(in) :: dof(:), dof2(:)
            character(len=:), allocatable, intent(in) :: absolute
            real(dp), allocatable, intent(in) :: d(:, :)
            select case (form)
            case ('dof')
                call put(unit, "  "//kind//"_dof = "//ilist(dof), stat, msg)
                call put(unit, "  "//kind//"_dof2 = "//ilist(dof2), stat, msg)
            case ('file')
                call put(unit, "  "//kind//"_file = "//quoted(absolute), stat, msg)
            case ('inline')
                call put(unit, "  "//kind//"_direction = "//rlist(reshape(d, [size(d)])), &
                         stat, msg)
            case default
                if (allocated(d)) then
                    if (any(d /= 0.0_dp)) call put(unit, "  ! "//kind//"_direction ("// &
                                                   itoa(size(d, 1))//" x "//itoa(size(d, 2))// &
                                                   ") set in memory: give it as "//kind// &
                                                   "_file", stat, msg)
                end if
            end select
        end subroutine put_directions

        !> &microslip, when some contact is a microslip joint: its contacts and either the
        !> 4-parameter model (stiffness, chi, beta, sliders; F_S = mu N from &friction) or
        !> the explicit sliders.
        subroutine put_microslip()
            integer, allocatable :: contact(:), sliders(:)
            real(dp), allocatable :: kt(:), chi(:), beta(:), ks(:), fs(:)
            logical :: explicit
            integer :: jj
            associate (m => echo)
                if (.not. allocated(m%laws)) return
                allocate (contact(0), sliders(0), kt(0), chi(0), beta(0), ks(0), fs(0))
                explicit = .false.
                do jj = 1, size(m%laws)
                    if (.not. allocated(m%laws(jj)%e)) cycle
                    select type (e => m%laws(jj)%e)
                    type is (iwan_element_t)
                        contact = [contact, jj]
                        sliders = [sliders, e%n]
                        kt = [kt, e%kt]
                        chi = [chi, e%chi]
                        beta = [beta, e%beta]
                        ks = [ks, e%k]
                        fs = [fs, e%f]
                        if (.not. e%mu_n) explicit = .true.
                    end select
                end do
                if (size(contact) == 0) return
                call put(unit, "&microslip", stat, msg)
                call put(unit, "  contact = "//ilist(contact), stat, msg)
                if (explicit) then
                    call put(unit, "  slider_stiffness = "//rlist(ks), stat, msg)
                    call put(unit, "  slider_force = "//rlist(fs), stat, msg)
                else
                    call put(unit, "  stiffness = "//rlist(kt), stat, msg)
                    call put(unit, "  chi = "//rlist(chi), stat, msg)
                    call put(unit, "  beta = "//rlist(beta), stat, msg)
                end if
                call put(unit, "  sliders = "//ilist(sliders), stat, msg)
                call put(unit, "/", stat, msg)
            end associate
        end subroutine put_microslip
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

    !> s as a namelist string: in single quotes, a quote doubled.
    pure function quoted(s) result(q)
        !> The text.
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: q
        integer :: i
        q = "'"
        do i = 1, len(s)
            q = q//s(i:i)
            if (s(i:i) == "'") q = q//"'"
        end do
        q = q//"'"
    end function quoted

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
