!> summary.nml, one writer per method: a namelist group &summary (one `key = value` per
!> line: the method, whether the answer can be trusted, the keys of its warnings, the
!> convergence report and the checks), for several methods groups &summary_<method>, then
!> the effective case as namelist groups (read_case reads the file back as a case). Keys are
!> contracts (doc/outputs.md). Written under a unique temporary name and renamed.
module stickslip_summary
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_untrusted
    use stickslip_solution, only: hbm_solution_t
    use stickslip_euler, only: euler_result_t
    use stickslip_case, only: case_t, write_case, put, rtoa, ltoa, rlist, ilist, llist, quoted
    use stickslip_case_studies, only: diameter_mode
    use stickslip_reference, only: reference_result_t, reference_energy_error
    use stickslip_contact_measures, only: contact_energy_error => energy_balance_error
    use stickslip_compare, only: comparison_t, quantity_names
    use stickslip_side_by_side, only: side_by_side_t
    use stickslip_study, only: study_result_t
    use stickslip_modes, only: modes_result_t
    use stickslip_sweep, only: sweep_result_t
    use stickslip_sweep_family, only: family_result_t
    use stickslip_checks, only: hbm_checks_t
    use stickslip_robustness, only: robustness_row_t
    use stickslip_files, only: open_temporary, close_and_rename
    use stickslip_cyclic, only: nodal_diameter, cyclic_frequencies
    use stickslip_wave_symmetry, only: wave_symmetry_t, stability_spans
    implicit none
    private
    public :: write_summary, write_euler_summary, write_reference_summary
    public :: write_side_by_side_summary, write_study_summary, write_sweep_summary
    public :: write_robustness_summary, write_modes_summary, write_family_summary
    public :: energy_balance_error, reference_balance_error, sector_stability

contains

    !> Relative energy balance error over one period: |work_forcing - diss_friction -
    !> diss_damping| / max(|work_forcing|, 1e-6 work_gross, work_resolution): relative to the
    !> net work, or to the gross work integral |f . v| dt when the net work is ~0 (a contact
    !> stuck all period, undamped: nothing dissipates, and the balance is 0 = 0 to
    !> roundoff), or to the work the solve cannot resolve (a structure at rest).
    pure real(dp) function energy_balance_error(sol) result(e)
        !> The solution.
        type(hbm_solution_t), intent(in) :: sol
        e = contact_energy_error(sol%work_forcing, sol%diss_friction, sol%diss_damping, &
                                 0.0_dp, sol%work_gross, sol%work_resolution)
    end function energy_balance_error

    !> Relative energy balance error of a reference over one period (the impact losses of
    !> rigid unilateral contacts included): stickslip_reference's reference_energy_error.
    pure real(dp) function reference_balance_error(ref) result(e)
        !> A reference solution.
        type(reference_result_t), intent(in) :: ref
        e = reference_energy_error(ref)
    end function reference_balance_error

    !> Write `dir`/summary.nml: a namelist group &summary (one `key = value` per line) with
    !> the convergence report and diagnostics, followed by the effective case as namelist
    !> groups (read_case reads the file back as a case).
    subroutine write_summary(dir, case, sol, error, checks, diagnostics)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case solved.
        type(case_t), intent(in) :: case
        !> The solution (converged or not).
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Truncation estimate, stability and periodicity defect of the solution.
        type(hbm_checks_t), intent(in), optional :: checks
        !> The findings to report (keys trusted, warnings, warning_<key>, untrusted_<key>);
        !> default: the result's own diagnostics.
        type(diagnostics_t), intent(in), optional :: diagnostics
        type(diagnostics_t) :: found
        integer :: u, stat
        character(len=512) :: msg

        if (present(diagnostics)) then
            found = diagnostics
        else
            found = sol%diagnostics
            if (present(checks)) call found%extend(checks%diagnostics)
        end if
        call begin_summary(dir, "hbm", case, found, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put_hbm_keys(u, sol, stat, msg)
        if (present(checks)) call put_check_keys(u, checks, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_summary

    !> The keys of the checks of a solution (doc/outputs.md, "summary.nml").
    subroutine put_check_keys(u, checks, stat, msg)
        integer, intent(in) :: u
        type(hbm_checks_t), intent(in) :: checks
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        associate (e => checks%truncation)
            if (e%available) then
                call put(u, "  truncation_estimate = "//rtoa(e%estimate), stat, msg)
                call put(u, "  truncation_psi_rms = "//rtoa(e%psi_rms), stat, msg)
                call put(u, "  truncation_coarse_harmonics = "//itoa(e%coarse_harmonics), &
                         stat, msg)
                if (allocated(e%displacement_change_rel)) call put(u, &
                    "  truncation_displacement_change = "//rlist(e%displacement_change_rel), &
                    stat, msg)
                call put(u, "  truncation_dissipation_change = "// &
                         rtoa(e%dissipation_change_rel), stat, msg)
            end if
            if (e%tolerance > 0.0_dp) then
                call put(u, "  harmonics_tol_met = "//ltoa(e%met), stat, msg)
                if (allocated(e%history_harmonics)) then
                    call put(u, "  harmonics_tried = "//ilist(e%history_harmonics), stat, msg)
                    call put(u, "  estimates_tried = "//rlist(e%history_estimate), stat, msg)
                end if
            end if
        end associate
        if (checks%stability) then
            associate (f => checks%floquet)
                call put(u, "  stability = '"//f%verdict//"'", stat, msg)
                call put(u, "  stable = "//ltoa(f%stable), stat, msg)
                if (f%verdict /= 'unknown') then
                    call put(u, "  floquet_max = "//rtoa(f%max_modulus), stat, msg)
                    call put(u, "  floquet_multipliers_re = "//rlist(real(f%multipliers, dp)), &
                             stat, msg)
                    call put(u, "  floquet_multipliers_im = "//rlist(aimag(f%multipliers)), &
                             stat, msg)
                end if
                if (f%flow_growth >= 0.0_dp) call put(u, "  stability_flow_growth = "// &
                                                      rtoa(f%flow_growth), stat, msg)
                if (allocated(f%diagnosis)) call put(u, "  stability_diagnosis = '"// &
                                                     quote(f%diagnosis)//"'", stat, msg)
            end associate
        end if
        if (allocated(checks%defect)) then
            if (size(checks%defect) > 0) then
                call put(u, "  periodicity_defect = "//rlist(checks%defect), stat, msg)
            end if
        end if
        if (allocated(checks%notes)) call put(u, "  notes = '"//quote(checks%notes)//"'", &
                                              stat, msg)
    end subroutine put_check_keys

    !> Write `dir`/summary.nml for a time integration: a group &summary (method = 'euler',
    !> periodic, periods, defect, seconds, max_sweeps, diagnosis), then the effective case.
    subroutine write_euler_summary(dir, case, res, error, diagnostics)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case integrated.
        type(case_t), intent(in) :: case
        !> The integration result.
        type(euler_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The findings to report (keys trusted, warnings, warning_<key>, untrusted_<key>);
        !> default: the result's own diagnostics.
        type(diagnostics_t), intent(in), optional :: diagnostics
        type(diagnostics_t) :: found
        integer :: u, stat
        character(len=512) :: msg
        if (present(diagnostics)) then
            found = diagnostics
        else
            found = res%diagnostics
        end if
        call begin_summary(dir, "euler", case, found, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put_euler_keys(u, case, res, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_euler_summary

    !> The keys of a weighted-residual solution (doc/outputs.md, "summary.nml").
    subroutine put_hbm_keys(u, sol, stat, msg)
        integer, intent(in) :: u
        type(hbm_solution_t), intent(in) :: sol
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        integer :: nc
        nc = 0
        if (allocated(sol%stick_fraction)) nc = size(sol%stick_fraction)
        call put(u, "  converged = "//ltoa(sol%converged), stat, msg)
        call put(u, "  info = "//itoa(sol%info), stat, msg)
        call put(u, "  nfev = "//itoa(sol%nfev), stat, msg)
        call put(u, "  njev = "//itoa(sol%njev), stat, msg)
        call put(u, "  hybrj_calls = "//itoa(sol%hybrj_calls), stat, msg)
        call put(u, "  rescue = '"//trim(sol%rescue)//"'", stat, msg)
        call put(u, "  fnorm = "//rtoa(sol%fnorm), stat, msg)
        call put(u, "  fscale = "//rtoa(sol%fscale), stat, msg)
        call put(u, "  solve_seconds = "//rtoa(sol%seconds), stat, msg)
        if (allocated(sol%dofs)) call put(u, "  condensation_seconds = "// &
                                          rtoa(sol%condensation_seconds), stat, msg)
        call put(u, "  harmonics = "//itoa(sol%harmonics), stat, msg)
        call put(u, "  odd_only = "//ltoa(sol%odd_only), stat, msg)
        call put(u, "  samples = "//itoa(sol%samples), stat, msg)
        call put(u, "  rho = "//rtoa(sol%rho), stat, msg)
        call put(u, "  ncontact = "//itoa(nc), stat, msg)
        if (nc > 0) then
            call put(u, "  stick_fraction = "//rlist(sol%stick_fraction), stat, msg)
            call put(u, "  stick_phases = "//ilist(sol%stick_phases), stat, msg)
            call put(u, "  offset_undetermined = "//llist(sol%offset_undetermined), stat, msg)
            call put(u, "  at_rest = "//ltoa(sol%at_rest), stat, msg)
        end if
        if (nc > 0 .and. .not. sol%contacts%coulomb_only) then
            ! contact laws: the open and slip shares, the normal law's checks
            call put(u, "  open_fraction = "//rlist(sol%open_fraction), stat, msg)
            call put(u, "  slip_fraction = "//rlist(sol%slip_fraction), stat, msg)
            call put(u, "  signorini_check = "//rtoa(sol%signorini_check), stat, msg)
            call put(u, "  impact_check = "//rtoa(sol%impact_check), stat, msg)
        end if
        call put(u, "  work_forcing = "//rtoa(sol%work_forcing), stat, msg)
        call put(u, "  work_gross = "//rtoa(sol%work_gross), stat, msg)
        call put(u, "  work_resolution = "//rtoa(sol%work_resolution), stat, msg)
        call put(u, "  diss_friction = "//rtoa(sol%diss_friction), stat, msg)
        call put(u, "  diss_damping = "//rtoa(sol%diss_damping), stat, msg)
        call put(u, "  diss_coulomb = "//rtoa(sol%diss_coulomb), stat, msg)
        call put(u, "  energy_balance_error = "//rtoa(energy_balance_error(sol)), stat, msg)
        call put(u, "  diagnosis = '"//quote(sol%diagnosis)//"'", stat, msg)
    end subroutine put_hbm_keys

    !> The keys of an implicit Euler integration.
    subroutine put_euler_keys(u, case, res, stat, msg)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(euler_result_t), intent(in) :: res
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        call put(u, "  periodic = "//ltoa(res%periodic), stat, msg)
        call put(u, "  periods = "//itoa(res%periods), stat, msg)
        call put(u, "  defect = "//rtoa(res%defect), stat, msg)
        call put(u, "  euler_seconds = "//rtoa(res%seconds), stat, msg)
        call put(u, "  steps_per_period = "//itoa(case%euler%steps_per_period), stat, msg)
        call put(u, "  max_sweeps = "//itoa(res%max_sweeps), stat, msg)
        if (allocated(res%stick_fraction)) then
            if (size(res%stick_fraction) > 0) then
                call put(u, "  stick_fraction = "//rlist(res%stick_fraction), stat, msg)
                call put(u, "  slip_fraction = "//rlist(res%slip_fraction), stat, msg)
                call put(u, "  open_fraction = "//rlist(res%open_fraction), stat, msg)
                call put(u, "  stick_phases = "//ilist(res%stick_phases), stat, msg)
            end if
            call put(u, "  work_forcing = "//rtoa(res%work_forcing), stat, msg)
            call put(u, "  diss_friction = "//rtoa(res%diss_friction), stat, msg)
            call put(u, "  diss_damping = "//rtoa(res%diss_damping), stat, msg)
            call put(u, "  diss_coulomb = "//rtoa(res%diss_coulomb), stat, msg)
            call put(u, "  max_force_ratio = "//rtoa(res%max_force_ratio), stat, msg)
            call put(u, "  energy_balance_error = "//rtoa(contact_energy_error( &
                     res%work_forcing, res%diss_friction, res%diss_damping, 0.0_dp, &
                     res%work_gross)), stat, msg)
        end if
        call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
    end subroutine put_euler_keys

    !> The keys of a reference solution.
    subroutine put_reference_keys(u, ref, stat, msg)
        integer, intent(in) :: u
        type(reference_result_t), intent(in) :: ref
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        integer :: nc
        nc = 0
        if (allocated(ref%stick_fraction)) nc = size(ref%stick_fraction)
        call put(u, "  converged = "//ltoa(ref%converged), stat, msg)
        call put(u, "  defect = "//rtoa(ref%defect), stat, msg)
        call put(u, "  nfev = "//itoa(ref%nfev), stat, msg)
        call put(u, "  njev = "//itoa(ref%njev), stat, msg)
        call put(u, "  start = '"//ref%start//"'", stat, msg)
        call put(u, "  shooting_seconds = "//rtoa(ref%seconds), stat, msg)
        call put(u, "  start_seconds = "//rtoa(ref%start_seconds), stat, msg)
        call put(u, "  t_section = "//rtoa(ref%t_section), stat, msg)
        call put(u, "  ncontact = "//itoa(nc), stat, msg)
        if (nc > 0) then
            call put(u, "  stick_fraction = "//rlist(ref%stick_fraction), stat, msg)
            call put(u, "  stick_phases = "//ilist(ref%stick_phases), stat, msg)
        end if
        call put(u, "  nevent = "//itoa(ref%nevent), stat, msg)
        call put(u, "  work_forcing = "//rtoa(ref%work_forcing), stat, msg)
        call put(u, "  diss_friction = "//rtoa(ref%diss_friction), stat, msg)
        call put(u, "  diss_damping = "//rtoa(ref%diss_damping), stat, msg)
        if (.not. ref%contacts%coulomb_only .and. allocated(ref%open_fraction)) then
            call put(u, "  impact_loss = "//rtoa(ref%impact_loss), stat, msg)
            call put(u, "  open_fraction = "//rlist(ref%open_fraction), stat, msg)
            call put(u, "  slip_fraction = "//rlist(1.0_dp - ref%open_fraction - &
                                                    ref%stick_fraction), stat, msg)
        end if
        call put(u, "  energy_balance_error = "//rtoa(reference_balance_error(ref)), stat, msg)
        call put(u, "  integration_error = "//rtoa(ref%integration_error), stat, msg)
        call put(u, "  diagnosis = '"//quote(ref%diagnosis)//"'", stat, msg)
    end subroutine put_reference_keys

    !> Write `dir`/summary.nml for the reference: a group &summary (method = 'reference',
    !> converged, defect, nfev, njev, start, shooting_seconds, start_seconds, t_section,
    !> ncontact, stick_fraction, stick_phases, nevent, energies, diagnosis), then the case.
    subroutine write_reference_summary(dir, case, ref, error, diagnostics)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case solved.
        type(case_t), intent(in) :: case
        !> The reference (converged or not).
        type(reference_result_t), intent(in) :: ref
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The findings to report (keys trusted, warnings, warning_<key>, untrusted_<key>);
        !> default: the result's own diagnostics.
        type(diagnostics_t), intent(in), optional :: diagnostics
        type(diagnostics_t) :: found
        integer :: u, stat
        character(len=512) :: msg
        if (present(diagnostics)) then
            found = diagnostics
        else
            found = ref%diagnostics
        end if
        call begin_summary(dir, "reference", case, found, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put_reference_keys(u, ref, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_reference_summary

    !> The keys of the differences: for each comparison `<method>_vs_<against>_max` and
    !> `_rms`, one value per quantity in the order of `quantities`.
    subroutine put_comparison_keys(u, cmp, stat, msg)
        integer, intent(in) :: u
        type(comparison_t), intent(in) :: cmp
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        call put(u, "  "//cmp%method//"_vs_"//cmp%against//"_max = "//rlist(cmp%max_error), &
                 stat, msg)
        call put(u, "  "//cmp%method//"_vs_"//cmp%against//"_rms = "//rlist(cmp%rms_error), &
                 stat, msg)
    end subroutine put_comparison_keys

    !> Write `dir`/summary.nml for the three methods side by side: a group &summary
    !> (method = 'all', the CPU seconds of each method, the common grid, the quantity names
    !> and the relative max and RMS differences per quantity), then the groups
    !> &summary_hbm, &summary_euler and &summary_reference with each method's own keys,
    !> then the effective case.
    subroutine write_side_by_side_summary(dir, case, res, error, diagnostics)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case solved.
        type(case_t), intent(in) :: case
        !> The three solutions.
        type(side_by_side_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The findings to report (keys trusted, warnings, warning_<key>, untrusted_<key>);
        !> default: the result's own diagnostics.
        type(diagnostics_t), intent(in), optional :: diagnostics
        type(diagnostics_t) :: found
        integer :: u, stat, k
        character(len=512) :: msg
        character(len=12), allocatable :: names(:)
        character(len=:), allocatable :: line
        if (present(diagnostics)) then
            found = diagnostics
        else
            found = res%diagnostics
        end if
        call begin_summary(dir, "all", case, found, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put(u, "  hbm_cpu_seconds = "//rtoa(res%hbm_seconds), stat, msg)
        call put(u, "  euler_cpu_seconds = "//rtoa(res%euler_seconds), stat, msg)
        call put(u, "  reference_cpu_seconds = "//rtoa(res%reference_seconds), stat, msg)
        call put(u, "  grid = "//itoa(res%grid), stat, msg)
        if (allocated(case%reduction%output_rows)) then
            ! a reduced model is compared on the selected full-model DOFs
            names = [character(len=12) :: ("x"//itoa(case%reduction%output_dofs(k)), &
                                            k=1, size(case%reduction%output_dofs)), &
                     ("v"//itoa(case%reduction%output_dofs(k)), &
                      k=1, size(case%reduction%output_dofs)), &
                     ("r"//itoa(k), k=1, case%model%ncontact())]
        else
            names = quantity_names(case%model%ndof, case%model%ncontact())
        end if
        line = "  quantities = "
        do k = 1, size(names)
            line = line//"'"//trim(names(k))//"'"
            if (k < size(names)) line = line//", "
        end do
        call put(u, line, stat, msg)
        do k = 1, size(res%comparisons)
            call put_comparison_keys(u, res%comparisons(k), stat, msg)
        end do
        call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_hbm", stat, msg)
        call put_hbm_keys(u, res%hbm, stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_euler", stat, msg)
        call put_euler_keys(u, case, res%euler, stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_reference", stat, msg)
        call put_reference_keys(u, res%reference, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_side_by_side_summary

    !> Write `dir`/summary.nml for a study: a group &summary (method = 'study', rows,
    !> skipped, reference_cpu_seconds), the group &summary_reference, then the case.
    subroutine write_study_summary(dir, case, study, error, diagnostics)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case studied.
        type(case_t), intent(in) :: case
        !> The study.
        type(study_result_t), intent(in) :: study
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The findings to report (keys trusted, warnings, warning_<key>, untrusted_<key>);
        !> default: the result's own diagnostics.
        type(diagnostics_t), intent(in), optional :: diagnostics
        type(diagnostics_t) :: found
        integer :: u, stat, nrow
        character(len=512) :: msg
        nrow = 0
        if (allocated(study%rows)) nrow = size(study%rows)
        if (present(diagnostics)) then
            found = diagnostics
        else
            found = study%diagnostics
        end if
        call begin_summary(dir, "study", case, found, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put(u, "  rows = "//itoa(nrow), stat, msg)
        call put(u, "  skipped = "//itoa(study%skipped), stat, msg)
        call put(u, "  reference_cpu_seconds = "//rtoa(study%reference_seconds), stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_reference", stat, msg)
        call put_reference_keys(u, study%reference, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_study_summary

    !> Write `dir`/summary.nml for a sweep: &summary (method = 'sweep', complete, points,
    !> the parameter's range covered, folds, unstable points, CPU seconds, diagnosis), then
    !> the effective case. Error: stat io.
    subroutine write_sweep_summary(dir, case, res, error, diagnostics)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case.
        type(case_t), intent(in) :: case
        !> The curve.
        type(sweep_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The findings to report (keys trusted, warnings, warning_<key>, untrusted_<key>);
        !> default: the result's own diagnostics.
        type(diagnostics_t), intent(in), optional :: diagnostics
        type(diagnostics_t) :: found
        integer :: u, stat
        character(len=512) :: msg
        if (present(diagnostics)) then
            found = diagnostics
        else
            found = res%diagnostics
        end if
        call begin_summary(dir, "sweep", case, found, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put(u, "  complete = "//ltoa(res%complete), stat, msg)
        call put(u, "  points = "//itoa(res%npoints), stat, msg)
        call put(u, "  resumed_points = "//itoa(res%resumed_points), stat, msg)
        if (res%npoints > 0) then
            call put(u, "  parameter_first = "//rtoa(res%points(1)%parameter), stat, msg)
            call put(u, "  parameter_last = "//rtoa(res%points(res%npoints)%parameter), &
                     stat, msg)
            call put(u, "  parameter_min = "//rtoa(minval(res%points(1:res%npoints)%parameter)), &
                     stat, msg)
            call put(u, "  parameter_max = "//rtoa(maxval(res%points(1:res%npoints)%parameter)), &
                     stat, msg)
            call put(u, "  unstable_points = "//itoa(count(res%points(1:res%npoints)%stable == 0)), &
                     stat, msg)
            call put(u, "  unknown_stability_points = "// &
                     itoa(count(res%points(1:res%npoints)%stable == -1)), stat, msg)
            call put(u, "  max_residual = "//rtoa(maxval(res%points(1:res%npoints)%residual)), &
                     stat, msg)
        end if
        call put(u, "  folds = "//itoa(res%folds), stat, msg)
        call put(u, "  rejected_steps = "//itoa(res%state%rejected), stat, msg)
        call put(u, "  cpu_seconds = "//rtoa(res%seconds), stat, msg)
        call put(u, "  stability_cpu_seconds = "//rtoa(res%stability_seconds), stat, msg)
        if (allocated(res%diagnosis)) then
            call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
        end if
        if (allocated(res%notes)) then
            call put(u, "  notes = '"//quote(res%notes)//"'", stat, msg)
        end if
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_sweep_summary

    !> Write `dir`/summary.nml for a family of forced-response curves: &summary (method =
    !> 'sweep', family_parameter, curves, curves_complete, complete, points (all curves),
    !> resumed_points, unstable_points, unknown_stability_points, folds, the values and each
    !> curve's points and completeness (family_values, curve_points, curve_complete), the
    !> first selected observed DOF's peaks (peak_first_dof, peak_omega_first_dof), the
    !> smallest of them and its value (best_peak, best_value), threads, cpu_seconds,
    !> wall_seconds, diagnosis), then the effective case. Error: stat io.
    subroutine write_family_summary(dir, case, fam, res, first, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case.
        type(case_t), intent(in) :: case
        !> The family.
        type(family_result_t), intent(in) :: fam
        !> Every curve's points in one curve.
        type(sweep_result_t), intent(in) :: res
        !> The observed displacement of the first selected DOF (a row of fam%peaks).
        integer, intent(in) :: first
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, n, k, best
        character(len=512) :: msg
        real(dp), allocatable :: peak(:), where(:)
        n = size(fam%values)
        call begin_summary(dir, "sweep", case, res%diagnostics, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put(u, "  family_parameter = '"//trim(fam%family_parameter)//"'", stat, msg)
        call put(u, "  curves = "//itoa(n), stat, msg)
        call put(u, "  curves_complete = "//itoa(count([(fam%curves(k)%complete, k=1, n)])), &
                 stat, msg)
        call put(u, "  complete = "//ltoa(fam%complete), stat, msg)
        call put(u, "  points = "//itoa(res%npoints), stat, msg)
        call put(u, "  resumed_points = "//itoa(res%resumed_points), stat, msg)
        if (res%npoints > 0) then
            call put(u, "  unstable_points = "// &
                     itoa(count(res%points(1:res%npoints)%stable == 0)), stat, msg)
            call put(u, "  unknown_stability_points = "// &
                     itoa(count(res%points(1:res%npoints)%stable == -1)), stat, msg)
        end if
        call put(u, "  folds = "//itoa(res%folds), stat, msg)
        call put(u, "  family_values = "//rlist(fam%values), stat, msg)
        call put(u, "  curve_points = "//ilist([(fam%curves(k)%npoints, k=1, n)]), stat, msg)
        call put(u, "  curve_complete = "//llist([(fam%curves(k)%complete, k=1, n)]), stat, msg)
        if (size(fam%peaks, 1) >= first .and. first >= 1) then
            ! the first DOF of the selection (family.csv's first peak column)
            k = first
            peak = fam%peaks(k, :)%amplitude
            where = fam%peaks(k, :)%omega
            do best = 1, n
                if (fam%curves(best)%npoints == 0) then
                    peak(best) = ieee_value(1.0_dp, ieee_quiet_nan)
                    where(best) = peak(best)
                end if
            end do
            call put(u, "  peak_first_dof = "//rlist(peak), stat, msg)
            call put(u, "  peak_omega_first_dof = "//rlist(where), stat, msg)
            best = minloc(peak, 1, mask=ieee_is_finite(peak))
            if (best > 0) then
                call put(u, "  best_peak = "//rtoa(peak(best)), stat, msg)
                call put(u, "  best_value = "//rtoa(fam%values(best)), stat, msg)
            end if
        end if
        call put(u, "  threads = "//itoa(fam%threads), stat, msg)
        call put(u, "  cpu_seconds = "//rtoa(res%seconds), stat, msg)
        call put(u, "  stability_cpu_seconds = "//rtoa(res%stability_seconds), stat, msg)
        call put(u, "  wall_seconds = "//rtoa(fam%wall_seconds), stat, msg)
        if (allocated(fam%diagnosis)) then
            if (len(fam%diagnosis) > 0) call put(u, "  diagnosis = '"//quote(fam%diagnosis)// &
                                                 "'", stat, msg)
        end if
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_family_summary

    !> Write `dir`/summary.nml for a nonlinear modal analysis: &summary (method = 'modes',
    !> complete, points, the linear limits omega_stuck and omega_slipping [rad/s], start,
    !> rho, odd_only, amplitude_first/last, omega_min/max, damping_ratio_max and the
    !> amplitude where it is reached, max_energy_error, folds, rejected_steps,
    !> factorizations, cpu_seconds, diagnosis), then the effective case. With the backbones
    !> `per` of a sector's nodal `diameters` (res gathers their points): nodal_diameters and
    !> per diameter d mode_nd<d> (the mode traced there), complete_nd<d>, points_nd<d>,
    !> unloaded_nd<d>, omega_stuck_nd<d>, omega_slipping_nd<d>, start_nd<d>, rho_nd<d> (the
    !> weight of its points), samples_end_nd<d> and refined_at_nd<d> (samples_end and
    !> refined_at of a whole structure: the samples of the last points and the amplitudes
    !> from which the backbone was continued on more), first_try_nd<d> when it was traced
    !> again with its wave's held weight or on more samples, with points omega_min_nd<d>,
    !> omega_max_nd<d>, damping_ratio_max_nd<d>, and diagnosis_nd<d> when there is one.
    !> Error: stat io.
    subroutine write_modes_summary(dir, case, res, error, per, diameters)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case.
        type(case_t), intent(in) :: case
        !> The backbone.
        type(modes_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The backbones per nodal diameter of a sector.
        type(modes_result_t), intent(in), optional :: per(:)
        !> Their nodal diameters.
        integer, intent(in), optional :: diameters(:)
        integer :: u, stat, n, k, i
        character(len=512) :: msg
        character(len=:), allocatable :: d
        n = res%npoints
        call begin_summary(dir, "modes", case, res%diagnostics, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put(u, "  complete = "//ltoa(res%complete), stat, msg)
        call put(u, "  points = "//itoa(n), stat, msg)
        call put(u, "  omega_stuck = "//rtoa(res%omega_stuck), stat, msg)
        call put(u, "  omega_slipping = "//rtoa(res%omega_slipping), stat, msg)
        call put(u, "  start = '"//trim(res%start)//"'", stat, msg)
        call put(u, "  rho = "//rtoa(res%rho), stat, msg)
        call put(u, "  odd_only = "//ltoa(res%odd_only), stat, msg)
        if (.not. present(per)) call put_refinement(u, "", res, stat, msg)
        if (n > 0) then
            associate (pts => res%points(1:n))
                call put(u, "  amplitude_first = "//rtoa(pts(1)%p%parameter), stat, msg)
                call put(u, "  amplitude_last = "//rtoa(pts(n)%p%parameter), stat, msg)
                call put(u, "  omega_min = "//rtoa(minval(pts%p%omega)), stat, msg)
                call put(u, "  omega_max = "//rtoa(maxval(pts%p%omega)), stat, msg)
                k = maxloc(pts%damping_ratio, 1)
                call put(u, "  damping_ratio_max = "//rtoa(pts(k)%damping_ratio), stat, msg)
                call put(u, "  damping_ratio_max_amplitude = "//rtoa(pts(k)%p%parameter), &
                         stat, msg)
                call put(u, "  max_energy_error = "//rtoa(maxval(pts%energy_error)), stat, msg)
                call put(u, "  max_residual = "//rtoa(maxval(pts%p%residual)), stat, msg)
                ! the largest truncation estimates (NaN where none was made)
                call put(u, "  max_omega_error = "// &
                         rtoa(finite_max([(pts(k)%omega_error, k=1, n)])), stat, msg)
                call put(u, "  max_damping_error = "// &
                         rtoa(finite_max([(pts(k)%damping_error, k=1, n)])), stat, msg)
            end associate
        end if
        call put(u, "  folds = "//itoa(res%folds), stat, msg)
        call put(u, "  rejected_steps = "//itoa(res%rejected), stat, msg)
        call put(u, "  factorizations = "//itoa(res%factorizations), stat, msg)
        call put(u, "  cpu_seconds = "//rtoa(res%seconds), stat, msg)
        if (allocated(res%diagnosis)) then
            call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
        end if
        if (present(per) .and. present(diameters)) then
            call put(u, "  nodal_diameters = "//ilist(diameters), stat, msg)
            do i = 1, size(per)
                d = itoa(diameters(i))
                associate (b => per(i))
                    call put(u, "  mode_nd"//d//" = "//itoa(diameter_mode(case%modes, i)), &
                             stat, msg)
                    call put(u, "  complete_nd"//d//" = "//ltoa(b%complete), stat, msg)
                    call put(u, "  points_nd"//d//" = "//itoa(b%npoints), stat, msg)
                    call put(u, "  unloaded_nd"//d//" = "//ltoa(b%unloaded), stat, msg)
                    call put(u, "  omega_stuck_nd"//d//" = "//rtoa(b%omega_stuck), stat, msg)
                    call put(u, "  omega_slipping_nd"//d//" = "//rtoa(b%omega_slipping), &
                             stat, msg)
                    call put(u, "  start_nd"//d//" = '"//trim(b%start)//"'", stat, msg)
                    call put(u, "  rho_nd"//d//" = "//rtoa(b%rho), stat, msg)
                    call put_refinement(u, "_nd"//d, b, stat, msg)
                    if (allocated(b%first_try)) call put(u, "  first_try_nd"//d//" = '"// &
                                                         quote(b%first_try)//"'", stat, msg)
                    if (b%npoints > 0) then
                        associate (pts => b%points(1:b%npoints))
                            call put(u, "  omega_min_nd"//d//" = "//rtoa(minval(pts%p%omega)), &
                                     stat, msg)
                            call put(u, "  omega_max_nd"//d//" = "//rtoa(maxval(pts%p%omega)), &
                                     stat, msg)
                            call put(u, "  damping_ratio_max_nd"//d//" = "// &
                                     rtoa(maxval(pts%damping_ratio)), stat, msg)
                        end associate
                    end if
                    if (allocated(b%diagnosis)) then
                        if (len(b%diagnosis) > 0) call put(u, "  diagnosis_nd"//d//" = '"// &
                                                           quote(b%diagnosis)//"'", stat, msg)
                    end if
                end associate
            end do
        end if
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_modes_summary

    !> The keys samples_end<suffix> (the samples of the backbone's last points) and, when
    !> it was continued on more samples, refined_at<suffix> (the modal amplitudes from
    !> which, one per refinement).
    subroutine put_refinement(u, suffix, b, stat, msg)
        integer, intent(in) :: u
        character(len=*), intent(in) :: suffix
        type(modes_result_t), intent(in) :: b
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        if (b%samples > 0) call put(u, "  samples_end"//suffix//" = "//itoa(b%samples), stat, msg)
        if (allocated(b%refined_at)) then
            if (size(b%refined_at) > 0) call put(u, "  refined_at"//suffix//" = "// &
                                                 rlist(b%refined_at), stat, msg)
        end if
    end subroutine put_refinement

    !> The largest finite value of x (NaN when none is).
    real(dp) function finite_max(x) result(m)
        real(dp), intent(in) :: x(:)
        if (any(ieee_is_finite(x))) then
            m = maxval(x, mask=ieee_is_finite(x))
        else
            m = ieee_value(1.0_dp, ieee_quiet_nan)
        end if
    end function finite_max

    !> Write `dir`/summary.nml for a robustness study: &summary (method = 'robustness', rows,
    !> then per method runs_<m> and successes_<m>, m = hbm_cold, hbm_warm, euler), then the
    !> effective case. Error: stat io.
    subroutine write_robustness_summary(dir, case, rows, error, diagnostics)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case.
        type(case_t), intent(in) :: case
        !> The runs.
        type(robustness_row_t), intent(in) :: rows(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The findings to report (keys trusted, warnings, warning_<key>, untrusted_<key>);
        !> default: the result's own diagnostics.
        type(diagnostics_t), intent(in), optional :: diagnostics
        type(diagnostics_t) :: found
        character(len=8), parameter :: methods(3) = [character(len=8) :: 'hbm-cold', &
                                                     'hbm-warm', 'euler']
        character(len=8), parameter :: keys(3) = [character(len=8) :: 'hbm_cold', &
                                                  'hbm_warm', 'euler']
        integer :: u, stat, k
        character(len=512) :: msg
        if (present(diagnostics)) found = diagnostics
        call begin_summary(dir, "robustness", case, found, u, stat, msg, error)
        call put_reduction_keys(u, case, stat, msg)
        if (allocated(error)) return
        call put(u, "  rows = "//itoa(size(rows)), stat, msg)
        do k = 1, 3
            call put(u, "  runs_"//trim(keys(k))//" = "//itoa(count(rows%method == methods(k))), &
                     stat, msg)
            call put(u, "  successes_"//trim(keys(k))//" = "// &
                     itoa(count(rows%method == methods(k) .and. rows%success)), stat, msg)
        end do
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_robustness_summary

    !> Open the temporary summary.nml and write its first lines: the method, then
    !> `trusted` (F when a finding is level_untrusted), `warnings` (the keys of the warning
    !> and untrusted findings, '' when none) and one `warning_<key>` or `untrusted_<key>`
    !> line with the message of each.
    subroutine begin_summary(dir, method, case, found_in, u, stat, msg, error)
        character(len=*), intent(in) :: dir, method
        type(case_t), intent(in) :: case
        type(diagnostics_t), intent(in) :: found_in
        integer, intent(out) :: u, stat
        character(len=*), intent(out) :: msg
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: keys
        type(diagnostics_t) :: found
        integer :: k
        stat = 0
        msg = ""
        ! the method's findings, then those of the case itself and of the model's reduction
        ! (read_case)
        found = found_in
        call add_absent(case%diagnostics)
        call add_absent(case%reduction%diagnostics)
        call open_temporary(dir, "summary.nml", u, error)
        if (allocated(error)) return
        call put(u, "! stickslip summary: the group &summary (and for several methods "// &
                 "&summary_<method>), then the effective case (&system ... &study)", stat, msg)
        call put(u, "&summary", stat, msg)
        call put(u, "  method = '"//method//"'", stat, msg)
        call put(u, "  trusted = "//ltoa(found%worst() < level_untrusted), stat, msg)
        keys = ""
        if (allocated(found%items)) then
            do k = 1, size(found%items)
                if (found%items(k)%level < level_warning) cycle
                if (len(keys) > 0) keys = keys//", "
                keys = keys//"'"//found%items(k)%key//"'"
            end do
        end if
        if (len(keys) == 0) keys = "''"
        call put(u, "  warnings = "//keys, stat, msg)
        if (allocated(found%items)) then
            do k = 1, size(found%items)
                associate (item => found%items(k))
                    if (item%level == level_warning) then
                        call put(u, "  warning_"//item%key//" = '"//quote(item%message)//"'", &
                                 stat, msg)
                    else if (item%level >= level_untrusted) then
                        call put(u, "  untrusted_"//item%key//" = '"//quote(item%message)// &
                                 "'", stat, msg)
                    end if
                end associate
            end do
        end if
        if (case%cyclic%given) call put_cyclic_keys(u, case, stat, msg)

    contains

        subroutine add_absent(more)
            type(diagnostics_t), intent(in) :: more
            if (.not. allocated(more%items)) return
            do k = 1, size(more%items)
                associate (item => more%items(k))
                    if (.not. found%has(item%key)) call found%add(item%level, item%key, &
                                                                  item%message)
                end associate
            end do
        end subroutine add_absent
    end subroutine begin_summary

    !> The keys of a bladed disk (&cyclic): cyclic_model ('disk'), sectors, engine_order,
    !> disk_dof, stability_scope = 'disk' when a sector's stability was asked for (the
    !> assembled disk's multipliers: every perturbation) with stability_spans (its exact
    !> flow over T / stability_spans by the wave's symmetry), and for the forced harmonics h the
    !> nodal diameter (cyclic_nodal_diameters)
    !> and the sector's lowest linear frequencies in that diameter (at most
    !> max_cyclic_frequencies), contacts carrying nothing (cyclic_frequencies_nd<k>
    !> [rad/s]); for a reduced FE sector the diameters its run's harmonics reach
    !> (reduction_error_diameters) and its frequencies' largest relative error in each
    !> (reduction_error_nd<k>, stickslip_cyclic_sparse).
    subroutine put_cyclic_keys(u, case, stat, msg)
        integer, parameter :: max_cyclic_frequencies = 20
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        integer, allocatable :: nds(:)
        real(dp), allocatable :: w(:)
        type(error_type), allocatable :: e
        integer :: k, nd
        associate (c => case%cyclic%cyc, sector => case%cyclic%sector)
            call put(u, "  cyclic_model = '"//trim(case%cyclic%model)//"'", stat, msg)
            call put(u, "  sectors = "//itoa(c%sectors), stat, msg)
            call put(u, "  engine_order = "//itoa(c%engine_order), stat, msg)
            call put(u, "  disk_dof = "//itoa(c%sectors*(sector%ndof - size(c%right))), &
                     stat, msg)
            if (sector_stability(case)) then
                call put(u, "  stability_scope = 'disk'", stat, msg)
                call put(u, "  stability_spans = "// &
                         itoa(stability_spans(wave_symmetry_t(c%sectors, c%engine_order), &
                                              case%hbm%samples)), stat, msg)
            end if
            allocate (nds(0))
            do k = 1, sector%nforce()
                nd = nodal_diameter(sector%force_harmonic(k), c%engine_order, c%sectors)
                if (.not. any(nds == nd)) nds = [nds, nd]
            end do
            if (size(nds) == 0) return
            call put(u, "  cyclic_nodal_diameters = "//ilist(nds), stat, msg)
            do k = 1, size(nds)
                call cyclic_frequencies(sector, c, nds(k), w, e)
                if (allocated(e)) cycle
                call put(u, "  cyclic_frequencies_nd"//itoa(nds(k))//" = "// &
                         rlist(w(1:min(size(w), max_cyclic_frequencies))), stat, msg)
            end do
        end associate
        ! a reduced FE sector: its error per nodal diameter
        if (allocated(case%cyclic%diameters)) then
            call put(u, "  reduction_error_diameters = "//ilist(case%cyclic%diameters), &
                     stat, msg)
            do k = 1, size(case%cyclic%diameters)
                call put(u, "  reduction_error_nd"//itoa(case%cyclic%diameters(k))//" = "// &
                         rtoa(case%cyclic%diameter_errors(k)), stat, msg)
            end do
        end if
    end subroutine put_cyclic_keys

    !> The reduction keys of &summary (only when the model was reduced): reduction_method,
    !> reduced_dof, full_dof, reduction_modes, reduction_load_vectors (static load-correction
    !> vectors of a force_file), reduction_highest_mode_frequency [rad/s], reduction_seconds,
    !> reduction_error (-1: not measured, e.g. no contact or &reduction error_estimate =
    !> .false.), reduction_error_frequencies [rad/s] (where it was measured; absent when not
    !> asked for), reduction_error_method ('enriched', 'sparse LU', 'off', 'none'),
    !> reduction_error_seconds, reduction_read_seconds (the matrix files), reduction_cache
    !> ('off', 'hit', 'written', 'not written'), reduction_cache_file,
    !> reduction_cache_seconds; with &reduction interface_modes on a sector,
    !> reduction_interface_modes, reduction_face_dofs (each face's DOFs reduced),
    !> reduction_interface_dof (the sector's DOFs after; reduced_dof stays the Craig-Bampton
    !> model's), reduction_interface_band_modes (the cyclic modes whose face motion shaped
    !> them) and reduction_interface_left_out (the share of that motion left out). For the
    !> exact sparse condensation (&reduction method
    !> = 'none', N > max_file_dof): reduction_method = 'none', reduced_dof = full_dof = N and
    !> reduction_error = 0 (exact); the time of the sparse factorizations is the hbm key
    !> condensation_seconds.
    subroutine put_reduction_keys(u, case, stat, msg)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        associate (r => case%reduction%report)
            if (r%method == 'craig-bampton') then
                call put(u, "  reduction_method = '"//trim(r%method)//"'", stat, msg)
                call put(u, "  reduced_dof = "//itoa(r%reduced_dof), stat, msg)
                call put(u, "  full_dof = "//itoa(r%full_dof), stat, msg)
                call put(u, "  reduction_modes = "//itoa(r%modes), stat, msg)
                call put(u, "  reduction_load_vectors = "//itoa(r%load_vectors), stat, msg)
                call put(u, "  reduction_highest_mode_frequency = "// &
                         rtoa(r%highest_mode_frequency), stat, msg)
                call put(u, "  reduction_seconds = "//rtoa(r%seconds), stat, msg)
                call put(u, "  reduction_error = "//rtoa(r%error), stat, msg)
                if (allocated(r%error_frequencies) .and. r%error_method /= 'off') then
                    if (size(r%error_frequencies) > 0) call put(u, &
                        "  reduction_error_frequencies = "//rlist(r%error_frequencies), &
                        stat, msg)
                end if
                call put(u, "  reduction_error_method = '"//trim(r%error_method)//"'", stat, &
                         msg)
                call put(u, "  reduction_error_seconds = "//rtoa(r%error_seconds), stat, msg)
                call put(u, "  reduction_read_seconds = "//rtoa(case%reduction%read_seconds), &
                         stat, msg)
                call put(u, "  reduction_cache = '"//trim(case%reduction%cache_status)//"'", &
                         stat, msg)
                if (allocated(case%reduction%cache_path)) then
                    if (len(case%reduction%cache_path) > 0) call put(u, &
                        "  reduction_cache_file = "//quoted(case%reduction%cache_path), &
                        stat, msg)
                end if
                call put(u, "  reduction_cache_seconds = "// &
                         rtoa(case%reduction%cache_seconds), stat, msg)
                if (allocated(case%reduction%faces)) then
                    associate (f => case%reduction%faces)
                        call put(u, "  reduction_interface_modes = "//itoa(f%modes), stat, msg)
                        call put(u, "  reduction_face_dofs = "//itoa(f%face_dofs), stat, msg)
                        call put(u, "  reduction_interface_dof = "// &
                                 itoa(size(f%basis, 2)), stat, msg)
                        call put(u, "  reduction_interface_band_modes = "// &
                                 itoa(f%modes_in_band), stat, msg)
                        call put(u, "  reduction_interface_left_out = "// &
                                 rtoa(f%share_left_out), stat, msg)
                    end associate
                end if
            else if (allocated(case%sparse_model)) then
                ! &reduction method = 'none' on a sparse model: exact, nothing reduced
                call put(u, "  reduction_method = 'none'", stat, msg)
                call put(u, "  reduced_dof = "//itoa(r%reduced_dof), stat, msg)
                call put(u, "  full_dof = "//itoa(r%full_dof), stat, msg)
                call put(u, "  reduction_error = 0.0", stat, msg)
            end if
        end associate
    end subroutine put_reduction_keys

    !> Close the group &summary, echo the effective case, close and rename summary.nml.
    subroutine end_summary(dir, case, u, stat, msg, error)
        character(len=*), intent(in) :: dir
        type(case_t), intent(in) :: case
        integer, intent(in) :: u
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        type(error_type), allocatable, intent(out) :: error
        call put(u, "/", stat, msg)
        if (stat == 0) call write_case(u, case, stat, msg)
        call close_and_rename(dir, "summary.nml", u, stat, msg, error)
    end subroutine end_summary

    !> Double the single quotes of a string for a namelist character value.
    pure function quote(s) result(t)
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: t
        integer :: i
        t = ""
        do i = 1, len(s)
            if (s(i:i) == "'") then
                t = t//"''"
            else
                t = t//s(i:i)
            end if
        end do
    end function quote

    !> Whether `case` computes the stability of a sector's travelling wave (method 'hbm'
    !> with &hbm stability or 'sweep' with &sweep stability, on &cyclic model = 'sector'):
    !> the assembled disk's multipliers.
    logical function sector_stability(case)
        !> The case.
        type(case_t), intent(in) :: case
        sector_stability = .false.
        if (.not. (case%cyclic%given .and. case%cyclic%model == 'sector')) return
        if (case%method == 'sweep') sector_stability = case%sweep%stability
        if (case%method == 'hbm') sector_stability = case%checks%stability
    end function sector_stability
end module stickslip_summary
