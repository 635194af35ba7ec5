!> The whole workflow of one case: case -> method (weighted residual, implicit Euler, the
!> exact reference, all three, the work-precision study, a forced-response sweep or the
!> robustness study) -> result files. `run_method` is the one place that maps a method name
!> (&run method) to its run; the run_*_case procedures run one method each, for host codes
!> that read or built a case.
!> Every run of a case holds the lock of its output directory (stickslip_files) from before
!> it computes until its files are written, and leaves in the directory only the result
!> files of its own summary: before it writes, the results of an earlier run that this run
!> does not write are removed, and so is the earlier summary.nml, written last (not the
!> checkpoint of a sweep, nor any other file). An input error leaves the
!> directory's files untouched. The findings (diagnostics) of the methods are gathered into
!> the summary (trusted, warnings) and into run_result_t for the caller to report. An error
!> of a method names the method's arguments ("opts%tol = ...", "model%mu(1) = ..."); the
!> run_*_case procedures put it in case-file words ("&sweep tol = ...", "&friction mu(1)"),
!> an input error with the case file's path.
!> The runs themselves are in stickslip_run_solvers ('hbm', 'euler', 'reference', 'all') and
!> stickslip_run_studies ('study', 'sweep', 'robustness'), built on what every run shares
!> (stickslip_run_output: the output directory, error wording, values for the writers) and
!> on the gathering of findings (stickslip_run_findings); this module keeps run_result_t
!> and run_method and re-exports the run_*_case procedures and the *_findings functions.
module stickslip_driver
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_diagnostics, only: diagnostics_t
    use stickslip_progress, only: progress_t
    use stickslip_case, only: case_t
    use stickslip_reference, only: reference_handles
    use stickslip_solution, only: hbm_solution_t
    use stickslip_checks, only: hbm_checks_t
    use stickslip_euler, only: euler_result_t
    use stickslip_reference, only: reference_result_t
    use stickslip_side_by_side, only: side_by_side_t
    use stickslip_study, only: study_result_t
    use stickslip_sweep, only: sweep_result_t
    use stickslip_sweep_family, only: family_result_t
    use stickslip_robustness, only: robustness_row_t
    use stickslip_run_findings, only: hbm_findings, side_by_side_findings, study_findings, &
        add_new
    use stickslip_run_output, only: name_case_file
    use stickslip_run_solvers, only: run_case, run_euler_case, run_reference_case, &
        run_side_by_side_case
    use stickslip_run_studies, only: run_study_case, run_sweep_case, run_robustness_case, &
        run_modes_case
    use stickslip_modes, only: modes_result_t
    implicit none
    private
    public :: run_result_t, run_method, method_names
    public :: run_case, run_euler_case, run_reference_case, run_side_by_side_case
    public :: run_study_case, run_sweep_case, run_robustness_case, run_modes_case
    public :: hbm_findings, side_by_side_findings, study_findings

    !> The values of &run method, in the order of doc/case-file.md.
    character(len=*), parameter :: method_names(8) = [character(len=10) :: 'hbm', 'euler', &
        'reference', 'all', 'study', 'sweep', 'robustness', 'modes']

    !> The result of whichever method ran (only the component of that method is set).
    type :: run_result_t
        !> The method that ran (&run method).
        character(len=:), allocatable :: method
        !> method 'hbm': the solution and its checks.
        type(hbm_solution_t) :: hbm
        !> method 'hbm': truncation estimate, stability, periodicity defect.
        type(hbm_checks_t) :: checks
        !> method 'euler'.
        type(euler_result_t) :: euler
        !> method 'reference'.
        type(reference_result_t) :: reference
        !> method 'all'.
        type(side_by_side_t) :: side_by_side
        !> method 'study'.
        type(study_result_t) :: study
        !> method 'sweep'.
        type(sweep_result_t) :: sweep
        !> method 'sweep' with a family (&sweep family_values; family%values unallocated
        !> otherwise).
        type(family_result_t) :: family
        !> method 'robustness': one row per run.
        type(robustness_row_t), allocatable :: robustness(:)
        !> method 'modes'.
        type(modes_result_t) :: modes
        !> The findings of the run (its result's and its parts'), as in summary.nml.
        type(diagnostics_t) :: diagnostics
        !> Whether summary.nml was written.
        logical :: summary_written = .false.
    end type run_result_t

contains

    !> Run `case` with its method (case%method; '' or 'hbm': the weighted residual) and
    !> write its files into case%directory. `result` holds the method's result and the
    !> gathered findings also when an error is returned (a method that ran but failed:
    !> stat numerical, with its summary written). Errors: stat input (invalid case, an
    !> unknown method), stat numerical, stat io (files, a directory another run holds).
    subroutine run_method(case, result, error, progress)
        !> The case.
        type(case_t), intent(in) :: case
        !> What the method produced.
        type(run_result_t), intent(out) :: result
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook of the long methods (sweep, study, robustness).
        type(progress_t), intent(inout), optional :: progress
        character(len=:), allocatable :: why
        result%method = trim(case%method)
        if (len(result%method) == 0) result%method = 'hbm'
        if (allocated(case%sparse_model) .and. result%method /= 'hbm' .and. &
            result%method /= 'sweep') then
            call fatal_error(error, "&run method = '"//result%method//"': needs the dense "// &
                             "matrices of a small or reduced model, but &reduction method = "// &
                             "'none' keeps this model sparse (only methods 'hbm' and 'sweep' run on it); "// &
                             "use &reduction method = 'craig-bampton'", stickslip_stat%input)
            call name_case_file(case, error)
            return
        end if
        ! 2D friction and a tangential stiffness (doc/contacts.md): not in the exact reference
        if ((result%method == 'reference' .or. result%method == 'study' .or. &
             result%method == 'robustness') .and. .not. reference_handles(case%model, why)) then
            ! these methods measure against the exact reference
            call fatal_error(error, "&run method = '"//result%method//"': "//why// &
                             " (&run method = 'euler'; method 'all' compares the weighted "// &
                             "residual with it)", stickslip_stat%input)
            call name_case_file(case, error)
            return
        end if
        select case (result%method)
        case ('hbm')
            call run_case(case, result%hbm, error, result%checks, progress)
            result%diagnostics = hbm_findings(result%hbm, result%checks)
            result%summary_written = allocated(result%hbm%diagnosis)
        case ('euler')
            call run_euler_case(case, result%euler, error, progress)
            result%diagnostics = result%euler%diagnostics
            result%summary_written = allocated(result%euler%diagnosis)
        case ('reference')
            call run_reference_case(case, result%reference, error)
            result%diagnostics = result%reference%diagnostics
            result%summary_written = allocated(result%reference%diagnosis)
        case ('all')
            call run_side_by_side_case(case, result%side_by_side, error)
            result%diagnostics = side_by_side_findings(result%side_by_side)
            result%summary_written = allocated(result%side_by_side%diagnosis)
        case ('study')
            call run_study_case(case, result%study, error, progress)
            result%diagnostics = study_findings(result%study)
            result%summary_written = allocated(result%study%reference%diagnosis)
        case ('sweep')
            call run_sweep_case(case, result%sweep, error, progress, result%family)
            result%diagnostics = result%sweep%diagnostics
            result%summary_written = result%sweep%npoints > 0
        case ('robustness')
            call run_robustness_case(case, result%robustness, error, progress)
            result%summary_written = allocated(result%robustness)
        case ('modes')
            call run_modes_case(case, result%modes, error, progress)
            result%diagnostics = result%modes%diagnostics
            result%summary_written = result%modes%npoints > 0
        case default
            call fatal_error(error, "&run method: unknown method '"//result%method// &
                             "' (hbm, euler, reference, all, study, sweep, robustness or modes)", &
                             stickslip_stat%input)
            call name_case_file(case, error)
            return
        end select
        call add_new(result%diagnostics, case%diagnostics)
        call add_new(result%diagnostics, case%reduction%diagnostics)
        if (allocated(error)) then
            if (error%stat == stickslip_stat%input) result%summary_written = .false.
        end if
    end subroutine run_method
end module stickslip_driver
