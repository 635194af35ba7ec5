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
module stickslip_driver
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_diagnostics, only: diagnostics_t
    use stickslip_progress, only: progress_t
    use stickslip_case, only: case_t, selected_dofs
    use stickslip_case_reduction, only: recover_outputs, recover_full_field
    use stickslip_full_field, only: write_full_field
    use stickslip_case_messages, only: case_message
    use stickslip_solution, only: hbm_solution_t
    use stickslip_checks, only: hbm_checks_t, solve_and_check, sampling_notes, &
        sampling_diagnostics
    use stickslip_hbm_sparse, only: solve_periodic_sparse, kept_dofs
    use stickslip_euler, only: euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t
    use stickslip_reference_start, only: solve_reference_from_starts
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side
    use stickslip_study, only: study_options_t, study_result_t, run_study, default_study_options
    use stickslip_sweep, only: sweep_result_t, run_sweep, sweep_options_t
    use stickslip_robustness, only: robustness_options_t, robustness_row_t, run_robustness, &
        default_robustness_options
    use stickslip_checkpoint, only: checkpoint_writer_t, case_fingerprint, read_checkpoint, &
        remove_checkpoint
    use stickslip_files, only: make_directory, directory_lock_t, acquire_lock, release_lock, &
        remove_stale_results
    use stickslip_csv, only: write_hbm_csv, write_coefficients_csv, write_samples_csv, &
        write_events_csv, write_study_csv, write_frc_csv, write_robustness_csv
    use stickslip_summary, only: write_summary, write_euler_summary, write_reference_summary, &
        write_side_by_side_summary, write_study_summary, write_sweep_summary, &
        write_robustness_summary
    use stickslip_plot_scripts, only: write_frc_plot_script, write_robustness_plot_script
    implicit none
    private
    public :: run_result_t, run_method, method_names
    public :: run_case, run_euler_case, run_reference_case, run_side_by_side_case
    public :: run_study_case, run_sweep_case, run_robustness_case
    public :: hbm_findings, side_by_side_findings, study_findings

    !> The values of &run method, in the order of the README.
    character(len=*), parameter :: method_names(7) = [character(len=10) :: 'hbm', 'euler', &
        'reference', 'all', 'study', 'sweep', 'robustness']

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
        !> method 'robustness': one row per run.
        type(robustness_row_t), allocatable :: robustness(:)
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
        select case (result%method)
        case ('hbm')
            call run_case(case, result%hbm, error, result%checks)
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
            call run_sweep_case(case, result%sweep, error, progress)
            result%diagnostics = result%sweep%diagnostics
            result%summary_written = result%sweep%npoints > 0
        case ('robustness')
            call run_robustness_case(case, result%robustness, error, progress)
            result%summary_written = allocated(result%robustness)
        case default
            call fatal_error(error, "&run method: unknown method '"//result%method// &
                             "' (hbm, euler, reference, all, study, sweep or robustness)", &
                             stickslip_stat%input)
            call name_case_file(case, error)
            return
        end select
        call add_new(result%diagnostics, case%reduction%diagnostics)
        if (allocated(error)) then
            if (error%stat == stickslip_stat%input) result%summary_written = .false.
        end if
    end subroutine run_method

    !> The findings of a weighted-residual solution and of its checks.
    function hbm_findings(sol, checks) result(found)
        !> The solution.
        type(hbm_solution_t), intent(in) :: sol
        !> Its checks.
        type(hbm_checks_t), intent(in) :: checks
        type(diagnostics_t) :: found
        call add_new(found, sol%diagnostics)
        call add_new(found, checks%diagnostics)
    end function hbm_findings

    !> The findings of the three methods side by side (keys prefixed hbm_, euler_,
    !> reference_) and of their comparison.
    function side_by_side_findings(res) result(found)
        !> The three solutions.
        type(side_by_side_t), intent(in) :: res
        type(diagnostics_t) :: found
        call add_new(found, res%diagnostics)
        call add_new(found, res%hbm%diagnostics, 'hbm_')
        call add_new(found, res%euler%diagnostics, 'euler_')
        call add_new(found, res%reference%diagnostics, 'reference_')
    end function side_by_side_findings

    !> The findings of a study and of its reference (keys prefixed reference_).
    function study_findings(res) result(found)
        !> The study.
        type(study_result_t), intent(in) :: res
        type(diagnostics_t) :: found
        call add_new(found, res%diagnostics)
        call add_new(found, res%reference%diagnostics, 'reference_')
    end function study_findings

    !> Append the findings of `other` (keys prefixed) whose key is not in `found` yet.
    subroutine add_new(found, other, prefix)
        type(diagnostics_t), intent(inout) :: found
        type(diagnostics_t), intent(in) :: other
        character(len=*), intent(in), optional :: prefix
        integer :: k
        if (.not. allocated(other%items)) return
        do k = 1, size(other%items)
            associate (item => other%items(k))
                if (present(prefix)) then
                    if (found%has(prefix//item%key) .or. found%has(item%key)) cycle
                    call found%add(item%level, prefix//item%key, item%message)
                else
                    if (found%has(item%key)) cycle
                    call found%add(item%level, item%key, item%message)
                end if
            end associate
        end do
    end subroutine add_new

    !> Solve `case` (with &hbm harmonics_tol: raising H until the truncation estimate meets
    !> it), check the solution (truncation estimate; with &hbm stability, its Floquet
    !> multipliers; with verify_periods, the periodicity defect of the exact flow from it)
    !> and write its results into case%directory (created if missing):
    !> hbm.csv, coefficients.csv and summary.nml when the solve converged; only summary.nml
    !> (converged = F, with the diagnosis) when it did not, and then an error with stat
    !> numerical is returned as well. Other errors: stat input (invalid case, prefixed with
    !> the case file), stat numerical (singular dynamic stiffness, NaN), stat io (files, a
    !> directory another run is writing).
    subroutine run_case(case, sol, error, checks)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The solution.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The checks of the solution (truncation estimate, stability, periodicity defect).
        type(hbm_checks_t), intent(out), optional :: checks
        type(hbm_checks_t) :: ch
        type(directory_lock_t) :: lock
        call open_output(case, lock, error)
        if (allocated(error)) return
        call hbm_run(case, sol, ch, error)
        call release_lock(lock)
        if (present(checks)) checks = ch
        call name_case_file(case, error, ['opts ', 'copts', 'ref  ', 'basis'], &
                            ['hbm      ', 'hbm      ', 'reference', 'hbm      '])
    end subroutine run_case

    subroutine hbm_run(case, sol, ch, error)
        type(case_t), intent(in) :: case
        type(hbm_solution_t), intent(out) :: sol
        type(hbm_checks_t), intent(out) :: ch
        type(error_type), allocatable, intent(out) :: error
        type(error_type), allocatable :: io_error
        logical :: wanted
        integer, allocatable :: cols(:)
        integer :: i
        if (allocated(case%sparse_model)) then
            ! &reduction method = 'none' above the dense limit: the exact sparse condensation
            if (case%full_field) then
                ! every DOF kept (the selection first: the files' columns)
                call solve_periodic_sparse(case%sparse_model, case%hbm, [selected_dofs(case), &
                                           (i, i=1, case%sparse_model%model%ndof)], sol, error)
            else
                call solve_periodic_sparse(case%sparse_model, case%hbm, selected_dofs(case), &
                                           sol, error)
            end if
            ch%notes = sampling_notes(case%hbm%samples, case%hbm%harmonics)
            call sampling_diagnostics(case%hbm%samples, ch%diagnostics)
            ch%truncation%note = "not estimated for &reduction method = 'none' on a sparse "// &
                                 "model"
        else
            call solve_and_check(case%model, case%hbm, case%checks, &
                                 case%reference%reference_options_t, sol, ch, error)
        end if
        call after_method(case, error, wanted)
        if (.not. wanted) return
        if (sol%converged) then
            call remove_stale_results(case%directory, [character(len=24) :: "hbm.csv", &
                                      "coefficients.csv", &
                                      merge("full_field.mtx", "hbm.csv       ", case%full_field)])
            if (allocated(sol%dofs)) then
                ! the solution's columns are its kept DOFs: those of the selection
                cols = sparse_columns(sol%dofs, selected_dofs(case))
            else
                cols = output_columns(case)
            end if
            call write_hbm_csv(case%directory, output_solution(case, sol), error, &
                               cols, selected_dofs(case))
            if (allocated(error)) return
            call write_coefficients_csv(case%directory, output_solution(case, sol), error, &
                                        cols, selected_dofs(case))
            if (allocated(error)) return
            if (case%full_field) then
                block
                    real(dp), allocatable :: coef(:, :)
                    if (allocated(sol%dofs)) then
                        ! the exact sparse condensation kept every DOF (above)
                        allocate (coef(case%sparse_model%model%ndof, sol%nb))
                        coef(sol%dofs, :) = transpose(sol%xcoef)
                    else
                        call recover_full_field(case%reduction, sol%xcoef, coef, error)
                        if (allocated(error)) return
                    end if
                    call write_full_field(case%directory, coef, sol, error)
                    if (allocated(error)) return
                end block
            end if
        else
            call remove_stale_results(case%directory, [character(len=24) ::])
        end if
        call write_summary(case%directory, case, sol, io_error, ch, hbm_findings(sol, ch))
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (.not. sol%converged) call fatal_error(error, sol%diagnosis, stickslip_stat%numerical)
    end subroutine hbm_run

    !> Integrate `case` with implicit Euler until periodic and write euler.csv (the last
    !> period, in the format and phase convention of hbm.csv) and summary.nml into
    !> case%directory. With no periodic state, only summary.nml is written (periodic = F and
    !> the diagnosis) and an error with stat numerical is returned. Other errors: stat input,
    !> stat numerical (singular iteration matrix), stat io. With `progress`, a line per
    !> period at most once a second.
    subroutine run_euler_case(case, res, error, progress)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The integration result.
        type(euler_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress of the periods (optional).
        type(progress_t), intent(inout), optional :: progress
        type(directory_lock_t) :: lock
        call open_output(case, lock, error)
        if (allocated(error)) return
        call euler_run(case, res, error, progress)
        call release_lock(lock)
        call name_case_file(case, error, ['opts'], ['euler'])
    end subroutine run_euler_case

    subroutine euler_run(case, res, error, progress)
        type(case_t), intent(in) :: case
        type(euler_result_t), intent(out) :: res
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(error_type), allocatable :: io_error
        logical :: wanted
        if (present(progress)) then
            progress%items = 'periods'
            call integrate_euler(case%model, case%euler, res, error, progress=progress)
        else
            call integrate_euler(case%model, case%euler, res, error)
        end if
        call after_method(case, error, wanted)
        if (.not. wanted) return
        if (res%periodic) then
            call remove_stale_results(case%directory, [character(len=24) :: "euler.csv"])
            call write_samples_csv(case%directory, "euler.csv", res%t, &
                                   output_values(case, res%x), output_values(case, res%v), &
                                   res%r, error, output_columns(case), selected_dofs(case))
            if (allocated(error)) return
        else
            call remove_stale_results(case%directory, [character(len=24) ::])
        end if
        call write_euler_summary(case%directory, case, res, io_error)
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (.not. res%periodic) call fatal_error(error, res%diagnosis, stickslip_stat%numerical)
    end subroutine euler_run

    !> Compute the exact reference of `case` and write reference.csv (&reference samples, the
    !> format of hbm.csv), events.csv and summary.nml into case%directory. When the shooting
    !> does not converge only summary.nml is written (converged = F and the diagnosis) and an
    !> error with stat numerical is returned. Other errors: stat input, stat numerical, io.
    subroutine run_reference_case(case, res, error)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The reference solution.
        type(reference_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(directory_lock_t) :: lock
        call open_output(case, lock, error)
        if (allocated(error)) return
        call reference_run(case, res, error)
        call release_lock(lock)
        call name_case_file(case, error, ['opts      ', 'hbm_opts  ', 'euler_opts', 'basis     '], &
                            ['reference', 'hbm      ', 'euler    ', 'hbm      '])
    end subroutine run_reference_case

    subroutine reference_run(case, res, error)
        type(case_t), intent(in) :: case
        type(reference_result_t), intent(out) :: res
        type(error_type), allocatable, intent(out) :: error
        type(error_type), allocatable :: io_error
        logical :: wanted
        call solve_reference_from_starts(case%model, case%reference, res, error, hbm_opts=case%hbm, &
                             euler_opts=case%euler)
        call after_method(case, error, wanted)
        if (.not. wanted) return
        if (res%converged) then
            call remove_stale_results(case%directory, [character(len=24) :: "reference.csv", &
                                      "events.csv"])
            call write_reference_files(case, res, error)
            if (allocated(error)) return
        else
            call remove_stale_results(case%directory, [character(len=24) ::])
        end if
        call write_reference_summary(case%directory, case, res, io_error)
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (.not. res%converged) call fatal_error(error, res%diagnosis, stickslip_stat%numerical)
    end subroutine reference_run

    !> Solve `case` with the weighted residual, implicit Euler and the exact reference and
    !> write each one's files (hbm.csv and coefficients.csv, euler.csv, reference.csv and
    !> events.csv; only for the methods that converged) and one summary.nml with each one's
    !> CPU seconds and their differences. When a method did not converge, an error with stat
    !> numerical naming it is returned after the files are written. Other errors: stat
    !> input, stat numerical (singular matrices), stat io.
    subroutine run_side_by_side_case(case, res, error)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The three solutions and their differences.
        type(side_by_side_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(directory_lock_t) :: lock
        call open_output(case, lock, error)
        if (allocated(error)) return
        call side_by_side_run(case, res, error)
        call release_lock(lock)
        call name_case_file(case, error, ['hbm  ', 'euler', 'ref  ', 'basis'], &
                            ['hbm      ', 'euler    ', 'reference', 'hbm      '])
    end subroutine run_side_by_side_case

    subroutine side_by_side_run(case, res, error)
        type(case_t), intent(in) :: case
        type(side_by_side_t), intent(out) :: res
        type(error_type), allocatable, intent(out) :: error
        type(error_type), allocatable :: io_error
        character(len=24), allocatable :: files(:)
        logical :: wanted
        if (recovers(case)) then
            call solve_side_by_side(case%model, case%hbm, case%euler, case%reference, res, &
                                    error, observe=case%reduction%output_rows)
        else
            call solve_side_by_side(case%model, case%hbm, case%euler, case%reference, res, &
                                    error)
        end if
        call after_method(case, error, wanted)
        if (.not. wanted) return
        files = [character(len=24) ::]
        if (res%hbm%converged) files = [character(len=24) :: files, "hbm.csv", "coefficients.csv"]
        if (res%euler%periodic) files = [character(len=24) :: files, "euler.csv"]
        if (res%reference%converged) files = [character(len=24) :: files, "reference.csv", &
                                              "events.csv"]
        call remove_stale_results(case%directory, files)
        if (res%hbm%converged) then
            call write_hbm_csv(case%directory, output_solution(case, res%hbm), error, &
                               output_columns(case), selected_dofs(case))
            if (allocated(error)) return
            call write_coefficients_csv(case%directory, output_solution(case, res%hbm), &
                                        error, output_columns(case), selected_dofs(case))
            if (allocated(error)) return
        end if
        if (res%euler%periodic) then
            call write_samples_csv(case%directory, "euler.csv", res%euler%t, &
                                   output_values(case, res%euler%x), &
                                   output_values(case, res%euler%v), res%euler%r, error, &
                                   output_columns(case), selected_dofs(case))
            if (allocated(error)) return
        end if
        if (res%reference%converged) then
            call write_reference_files(case, res%reference, error)
            if (allocated(error)) return
        end if
        call write_side_by_side_summary(case%directory, case, res, io_error, &
                                        side_by_side_findings(res))
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (len(res%diagnosis) > 0) call fatal_error(error, res%diagnosis, &
                                                     stickslip_stat%numerical)
    end subroutine side_by_side_run

    !> Run the work-precision study of `case` (&study) and write study.csv, reference.csv,
    !> events.csv and summary.nml into case%directory. Errors: stat input (invalid case),
    !> stat numerical (no reference: nothing to measure errors against; summary.nml is
    !> written when the reference was attempted), stat io.
    subroutine run_study_case(case, res, error, progress)
        !> The case to study.
        type(case_t), intent(in) :: case
        !> The study.
        type(study_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every run of the study.
        type(progress_t), intent(inout), optional :: progress
        type(directory_lock_t) :: lock
        call open_output(case, lock, error)
        if (allocated(error)) return
        call study_run(case, res, error, progress)
        call release_lock(lock)
        call name_case_file(case, error, &
                            ['hbm     ', 'euler   ', 'ref_opts', 'opts    ', 'basis   '], &
                            ['hbm      ', 'euler    ', 'reference', 'study    ', 'hbm      '])
    end subroutine run_study_case

    subroutine study_run(case, res, error, progress)
        type(case_t), intent(in) :: case
        type(study_result_t), intent(out) :: res
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(error_type), allocatable :: io_error
        type(study_options_t) :: opts
        opts = case%study
        if (.not. allocated(opts%harmonics)) opts = default_study_options()
        call run_study(case%model, case%hbm, case%euler, case%reference, opts, res, error, &
                       progress)
        if (allocated(error)) then
            if (error%stat == stickslip_stat%input) return
            if (error%stat /= stickslip_stat%numerical .or. &
                .not. allocated(res%reference%diagnosis)) then
                call remove_stale_results(case%directory, [character(len=24) ::])
                return
            end if
            ! the reference failed: its report is still worth a summary
            call remove_stale_results(case%directory, [character(len=24) ::])
            call write_study_summary(case%directory, case, res, io_error, study_findings(res))
            if (allocated(io_error)) call move_alloc(io_error, error)
            return
        end if
        call remove_stale_results(case%directory, [character(len=24) :: "study.csv", &
                                  "reference.csv", "events.csv"])
        call write_study_csv(case%directory, res, case%model%ndof, case%model%ncontact(), error, &
                             boundary_columns(case), selected_dofs(case))
        if (allocated(error)) return
        call write_reference_files(case, res%reference, error)
        if (allocated(error)) return
        call write_study_summary(case%directory, case, res, error, study_findings(res))
    end subroutine study_run

    !> Continue the periodic solution of `case` over the &sweep range and write frc.csv,
    !> frc.gp (the gnuplot script of frc.png) and summary.nml into case%directory. The curve
    !> is saved in frc.checkpoint after its first point, then at most once a second; with
    !> &sweep resume (the default) a run of the same case that finds a checkpoint goes on
    !> from it. The checkpoint is removed once the files are written. A curve that stopped
    !> before the end of the range is written too, and an error with stat numerical is
    !> returned with the diagnosis. Errors: stat input (invalid case, a checkpoint of
    !> another case or a damaged one), stat numerical (no solution at the start), stat io.
    subroutine run_sweep_case(case, res, error, progress)
        !> The case (with its &sweep group).
        type(case_t), intent(in) :: case
        !> The curve.
        type(sweep_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every point of the curve.
        type(progress_t), intent(inout), optional :: progress
        type(directory_lock_t) :: lock
        call open_output(case, lock, error)
        if (allocated(error)) return
        call sweep_run(case, res, error, progress)
        call release_lock(lock)
        call name_case_file(case, error, ['hbm  ', 'ref  ', 'opts ', 'basis'], &
                            ['hbm      ', 'reference', 'sweep    ', 'hbm      '])
    end subroutine run_sweep_case

    subroutine sweep_run(case, res, error, progress)
        type(case_t), intent(in) :: case
        type(sweep_result_t), intent(out) :: res
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(checkpoint_writer_t) :: writer
        type(sweep_result_t) :: saved
        logical :: found
        logical :: wanted
        integer, allocatable :: kept(:), cols(:)
        integer :: ncols

        type(sweep_options_t) :: opts
        integer :: namp

        ! a reduced model's amplitudes are those of the selected full-model DOFs
        opts = case%sweep%sweep_options_t
        namp = case%model%ndof
        if (recovers(case)) then
            opts%observe = case%reduction%output_rows
            namp = size(opts%observe, 1)
        end if
        writer%directory = case%directory
        writer%fingerprint = case_fingerprint(case)
        found = .false.
        ! the points hold an amplitude per DOF of the model, or per kept DOF of the exact
        ! sparse condensation (the selection, then the contact and forced DOFs)
        ncols = namp
        cols = output_columns(case)
        if (allocated(case%sparse_model)) then
            kept = kept_dofs(case%sparse_model, selected_dofs(case), error)
            if (allocated(error)) return
            ncols = size(kept)
            cols = sparse_columns(kept, selected_dofs(case))
        end if
        if (case%sweep%resume) then
            call read_checkpoint(case%directory, writer%fingerprint, ncols, &
                                 case%model%ncontact(), saved, found, error)
            if (allocated(error)) return
        end if
        if (allocated(case%sparse_model)) then
            if (found) then
                call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                               case%sweep%sweep_options_t, res, error, observer=writer, &
                               resume=saved, progress=progress, sparse=case%sparse_model, &
                               dofs=selected_dofs(case))
            else
                call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                               case%sweep%sweep_options_t, res, error, observer=writer, &
                               progress=progress, sparse=case%sparse_model, &
                               dofs=selected_dofs(case))
            end if
        else if (found) then
            call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                           opts, res, error, observer=writer, resume=saved, progress=progress)
        else
            call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                           opts, res, error, observer=writer, progress=progress)
        end if
        call after_method(case, error, wanted)
        if (.not. wanted) return
        call remove_stale_results(case%directory, [character(len=24) :: "frc.csv", "frc.gp"])
        call write_frc_csv(case%directory, res, error, cols, selected_dofs(case))
        if (allocated(error)) return
        call write_frc_plot_script(case%directory, trim(case%sweep%parameter), &
                                   ncols, error, cols, selected_dofs(case))
        if (allocated(error)) return
        call write_sweep_summary(case%directory, case, res, error)
        if (allocated(error)) return
        call remove_checkpoint(case%directory)
        if (.not. res%complete) call fatal_error(error, "sweep: "//res%diagnosis// &
                                                 " (frc.csv holds the points computed)", &
                                                 stickslip_stat%numerical)
    end subroutine sweep_run

    !> Run the robustness study of `case` (&robustness: omega x mu x H x rho x samples, cold
    !> and warm starts, Euler) and write robustness.csv, robustness.gp (the gnuplot script of
    !> the maps robustness_cold.png and robustness_warm.png) and summary.nml into
    !> case%directory. Failed runs are rows, not errors. Errors: stat input (invalid case),
    !> stat io.
    subroutine run_robustness_case(case, rows, error, progress)
        !> The case (with its &robustness group, or the default grid).
        type(case_t), intent(in) :: case
        !> The runs.
        type(robustness_row_t), allocatable, intent(out) :: rows(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every run of the grid.
        type(progress_t), intent(inout), optional :: progress
        type(directory_lock_t) :: lock
        call open_output(case, lock, error)
        if (allocated(error)) return
        call robustness_run(case, rows, error, progress)
        call release_lock(lock)
        call name_case_file(case, error, &
                            ['hbm_opts  ', 'euler_opts', 'ref_opts  ', 'opts      ', 'basis     '], &
                            ['hbm       ', 'euler     ', 'reference ', 'robustness', 'hbm       '])
    end subroutine run_robustness_case

    subroutine robustness_run(case, rows, error, progress)
        type(case_t), intent(in) :: case
        type(robustness_row_t), allocatable, intent(out) :: rows(:)
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(robustness_options_t) :: opts
        logical :: wanted
        opts = case%robustness
        if (.not. allocated(opts%omegas)) opts = default_robustness_options()
        call run_robustness(case%model, case%hbm, case%euler, case%reference, opts, rows, &
                            error, progress)
        call after_method(case, error, wanted)
        if (.not. wanted) return
        call remove_stale_results(case%directory, [character(len=24) :: "robustness.csv", &
                                  "robustness.gp"])
        call write_robustness_csv(case%directory, rows, error)
        if (allocated(error)) return
        call write_robustness_plot_script(case%directory, opts, error)
        if (allocated(error)) return
        call write_robustness_summary(case%directory, case, rows, error)
    end subroutine robustness_run

    !> reference.csv and events.csv of a converged reference.
    subroutine write_reference_files(case, res, error)
        type(case_t), intent(in) :: case
        type(reference_result_t), intent(in) :: res
        type(error_type), allocatable, intent(out) :: error
        call write_samples_csv(case%directory, "reference.csv", res%t, &
                               output_values(case, res%x), output_values(case, res%v), res%r, &
                               error, output_columns(case), selected_dofs(case))
        if (allocated(error)) return
        call write_events_csv(case%directory, res, error)
    end subroutine write_reference_files

    !> Before a method runs: create the output directory and take its lock.
    subroutine open_output(case, lock, error)
        type(case_t), intent(in) :: case
        type(directory_lock_t), intent(inout) :: lock
        type(error_type), allocatable, intent(out) :: error
        if (.not. allocated(case%directory)) then
            call fatal_error(error, "&output directory: not set", stickslip_stat%input)
            call name_case_file(case, error)
            return
        end if
        call make_directory(case%directory, error)
        if (allocated(error)) then
            ! an I/O error, but one the case file's &output directory asked for: name both
            if (allocated(case%path)) then
                if (len(case%path) > 0) error%message = case%path//": "//error%message
            end if
            return
        end if
        call acquire_lock(lock, case%directory, error)
    end subroutine open_output

    !> After a method ran: whether its files are to be written (no error). An input error
    !> leaves the directory as it was; any other error (the method failed without a result
    !> to write) removes the results of an earlier run, which would otherwise pass for this
    !> run's.
    subroutine after_method(case, error, wanted)
        type(case_t), intent(in) :: case
        type(error_type), allocatable, intent(in) :: error
        logical, intent(out) :: wanted
        wanted = .not. allocated(error)
        if (wanted) return
        if (error%stat /= stickslip_stat%input) &
            call remove_stale_results(case%directory, [character(len=24) ::])
    end subroutine after_method

    !> Put an error of the library in the words of the case: the arguments of the method
    !> called (`arguments`, e.g. 'opts') become the case-file group and variable (`groups`,
    !> e.g. 'hbm'; model components map to &system, &forcing, &friction; 'basis', the harmonic
    !> basis a weighted-residual solve builds from its options, maps to &hbm), and an input
    !> error names the case file.
    subroutine name_case_file(case, error, arguments, groups)
        type(case_t), intent(in) :: case
        type(error_type), allocatable, intent(inout) :: error
        character(len=*), intent(in), optional :: arguments(:)
        character(len=*), intent(in), optional :: groups(:)
        if (.not. allocated(error)) return
        if (present(arguments) .and. present(groups)) &
            error%message = case_message(error%message, arguments, groups)
        if (error%stat /= stickslip_stat%input .or. .not. allocated(case%path)) return
        if (len(case%path) == 0) return
        if (index(error%message, case%path//": ") == 1) return
        error%message = case%path//": "//error%message
    end subroutine name_case_file
    !> The columns of a sparse solution (columns = `kept` DOFs) holding the DOFs `dofs`.
    pure function sparse_columns(kept, dofs) result(cols)
        integer, intent(in) :: kept(:), dofs(:)
        integer :: cols(size(dofs))
        integer :: k
        do k = 1, size(dofs)
            cols(k) = findloc(kept, dofs(k), 1)
        end do
    end function sparse_columns

    !> Whether the case's model was reduced with output rows kept (the result files then hold
    !> recovered full-model DOFs).
    pure logical function recovers(case)
        type(case_t), intent(in) :: case
        recovers = allocated(case%reduction%output_rows)
    end function recovers

    !> The columns of the values given to the writers that hold the selected DOFs: the DOF
    !> numbers themselves, or 1..nsel for recovered values (output_values).
    function output_columns(case) result(cols)
        type(case_t), intent(in) :: case
        integer, allocatable :: cols(:)
        integer :: k
        if (recovers(case)) then
            cols = [(k, k=1, size(case%reduction%output_dofs))]
        else
            cols = selected_dofs(case)
        end if
    end function output_columns

    !> The columns of per-DOF values of the model's own DOFs (frc amplitudes, study errors):
    !> the selected DOFs, or with a reduction their reduced DOFs (read_case admits only
    !> contact and forced DOFs then).
    function boundary_columns(case) result(cols)
        type(case_t), intent(in) :: case
        integer, allocatable :: cols(:)
        if (recovers(case)) then
            cols = case%reduction%output_reduced
        else
            cols = selected_dofs(case)
        end if
    end function boundary_columns

    !> Samples (instants x ndof) as the writers take them: unchanged, or with a reduction the
    !> selected full-model DOFs recovered (instants x nsel).
    function output_values(case, x) result(y)
        type(case_t), intent(in) :: case
        real(dp), intent(in) :: x(:, :)
        real(dp), allocatable :: y(:, :)
        if (recovers(case)) then
            y = recover_outputs(case%reduction, x)
        else
            y = x
        end if
    end function output_values

    !> A solution as the writers take it: unchanged, or with its samples and coefficients of
    !> the selected full-model DOFs recovered.
    function output_solution(case, sol) result(out)
        type(case_t), intent(in) :: case
        type(hbm_solution_t), intent(in) :: sol
        type(hbm_solution_t) :: out
        out = sol
        if (.not. recovers(case)) return
        if (allocated(sol%x)) out%x = recover_outputs(case%reduction, sol%x)
        if (allocated(sol%v)) out%v = recover_outputs(case%reduction, sol%v)
        if (allocated(sol%xcoef)) out%xcoef = recover_outputs(case%reduction, sol%xcoef)
    end function output_solution
end module stickslip_driver
