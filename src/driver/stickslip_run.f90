!> The whole workflow of one case: case -> model -> method (weighted residual, implicit
!> Euler, the exact reference, all three, the work-precision study, a forced-response sweep
!> or the robustness study) -> result files.
!> What the CLI runs, and what a host code calls to run a case it read or built.
module stickslip_run
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_case, only: case_t
    use stickslip_solution, only: hbm_solution_t
    use stickslip_checks, only: hbm_checks_t, solve_and_check
    use stickslip_output, only: make_directory, write_hbm_csv, write_coefficients_csv, &
        write_summary, write_samples_csv, write_euler_summary, write_events_csv, &
        write_reference_summary, write_side_by_side_summary, write_study_csv, &
        write_study_summary
    use stickslip_euler, only: euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t
    use stickslip_reference_start, only: solve_reference_from_starts
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side
    use stickslip_study, only: study_options_t, study_result_t, run_study, default_study_options
    use stickslip_sweep, only: sweep_result_t, run_sweep
    use stickslip_checkpoint, only: checkpoint_writer_t, case_fingerprint, read_checkpoint, &
        remove_checkpoint
    use stickslip_output, only: write_frc_csv, write_sweep_summary, write_frc_plot_script, &
        write_robustness_csv, write_robustness_summary, write_robustness_plot_script
    use stickslip_robustness, only: robustness_options_t, robustness_row_t, run_robustness, &
        default_robustness_options
    implicit none
    private
    public :: run_case, run_euler_case, run_reference_case, run_side_by_side_case
    public :: run_study_case, run_sweep_case, run_robustness_case

contains

    !> Solve `case` (with &hbm harmonics_tol: raising H until the truncation estimate meets
    !> it), check the solution (truncation estimate; with &hbm stability, its Floquet
    !> multipliers; with verify_periods, the periodicity defect of the exact flow from it)
    !> and write its results into case%directory (created if missing):
    !> hbm.csv, coefficients.csv and summary.nml when the solve converged; only summary.nml
    !> (converged = F, with the diagnosis) when it did not, and then an error with stat
    !> numerical is returned as well. Other errors: stat input (invalid case, prefixed with
    !> the case file), stat numerical (singular dynamic stiffness, NaN), stat io (files).
    subroutine run_case(case, sol, error, checks)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The solution.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The checks of the solution (truncation estimate, stability, periodicity defect).
        type(hbm_checks_t), intent(out), optional :: checks
        type(error_type), allocatable :: io_error
        type(hbm_checks_t) :: ch

        call solve_and_check(case%model, case%hbm, case%checks, case%reference, sol, ch, error)
        if (present(checks)) checks = ch
        call prepare_output(case, error)
        if (allocated(error)) return
        if (sol%converged) then
            call write_hbm_csv(case%directory, sol, error)
            if (allocated(error)) return
            call write_coefficients_csv(case%directory, sol, error)
            if (allocated(error)) return
        end if
        call write_summary(case%directory, case, sol, io_error, ch)
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (.not. sol%converged) call fatal_error(error, sol%diagnosis, stickslip_stat%numerical)
    end subroutine run_case

    !> Integrate `case` with implicit Euler until periodic and write euler.csv (the last
    !> period, in the format and phase convention of hbm.csv) and summary.nml into
    !> case%directory. With no periodic state, only summary.nml is written (periodic = F and
    !> the diagnosis) and an error with stat numerical is returned. Other errors: stat input,
    !> stat numerical (singular iteration matrix), stat io.
    subroutine run_euler_case(case, res, error)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The integration result.
        type(euler_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(error_type), allocatable :: io_error
        call integrate_euler(case%model, case%euler, res, error)
        call prepare_output(case, error)
        if (allocated(error)) return
        if (res%periodic) then
            call write_samples_csv(case%directory, "euler.csv", res%t, res%x, res%v, res%r, error)
            if (allocated(error)) return
        end if
        call write_euler_summary(case%directory, case, res, io_error)
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (.not. res%periodic) call fatal_error(error, res%diagnosis, stickslip_stat%numerical)
    end subroutine run_euler_case

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
        type(error_type), allocatable :: io_error
        call solve_reference_from_starts(case%model, case%reference, res, error, &
                                         hbm_opts=case%hbm, euler_opts=case%euler)
        call prepare_output(case, error)
        if (allocated(error)) return
        if (res%converged) then
            call write_reference_files(case, res, error)
            if (allocated(error)) return
        end if
        call write_reference_summary(case%directory, case, res, io_error)
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (.not. res%converged) call fatal_error(error, res%diagnosis, stickslip_stat%numerical)
    end subroutine run_reference_case

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
        type(error_type), allocatable :: io_error
        call solve_side_by_side(case%model, case%hbm, case%euler, case%reference, res, error)
        call prepare_output(case, error)
        if (allocated(error)) return
        if (res%hbm%converged) then
            call write_hbm_csv(case%directory, res%hbm, error)
            if (allocated(error)) return
            call write_coefficients_csv(case%directory, res%hbm, error)
            if (allocated(error)) return
        end if
        if (res%euler%periodic) then
            call write_samples_csv(case%directory, "euler.csv", res%euler%t, res%euler%x, &
                                   res%euler%v, res%euler%r, error)
            if (allocated(error)) return
        end if
        if (res%reference%converged) then
            call write_reference_files(case, res%reference, error)
            if (allocated(error)) return
        end if
        call write_side_by_side_summary(case%directory, case, res, io_error)
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (len(res%diagnosis) > 0) call fatal_error(error, res%diagnosis, &
                                                     stickslip_stat%numerical)
    end subroutine run_side_by_side_case

    !> Run the work-precision study of `case` (&study) and write study.csv, reference.csv,
    !> events.csv and summary.nml into case%directory. Errors: stat input (invalid case),
    !> stat numerical (no reference: nothing to measure errors against; summary.nml is
    !> written when the reference was attempted), stat io.
    subroutine run_study_case(case, res, error)
        !> The case to study.
        type(case_t), intent(in) :: case
        !> The study.
        type(study_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(error_type), allocatable :: io_error
        type(study_options_t) :: opts
        opts = case%study
        if (.not. allocated(opts%harmonics)) opts = default_study_options()
        call run_study(case%model, case%hbm, case%euler, case%reference, opts, res, error)
        if (allocated(error)) then
            if (error%stat /= stickslip_stat%numerical .or. &
                .not. allocated(res%reference%diagnosis)) then
                call prepare_output(case, error)
                return
            end if
            ! the reference failed: its report is still worth a summary
            call make_directory(case%directory, io_error)
            if (.not. allocated(io_error)) &
                call write_study_summary(case%directory, case, res, io_error)
            if (allocated(io_error)) call move_alloc(io_error, error)
            return
        end if
        call prepare_output(case, error)
        if (allocated(error)) return
        call write_study_csv(case%directory, res, case%model%ndof, case%model%ncontact(), error)
        if (allocated(error)) return
        call write_reference_files(case, res%reference, error)
        if (allocated(error)) return
        call write_study_summary(case%directory, case, res, error)
    end subroutine run_study_case

    !> Continue the periodic solution of `case` over the &sweep range and write frc.csv,
    !> frc.gp (the gnuplot script of frc.png) and summary.nml into case%directory. The curve is
    !> saved in frc.checkpoint after its first point, then at most once a second; with &sweep resume (the default) a run of
    !> the same case that finds a checkpoint goes on from it. The checkpoint is removed once
    !> the files are written. A curve that stopped before the end of the range is written
    !> too, and an error with stat numerical is returned with the diagnosis. Errors: stat
    !> input (invalid case, a checkpoint of another case), stat numerical (no solution at the
    !> start), stat io.
    subroutine run_sweep_case(case, res, error)
        !> The case (with its &sweep group).
        type(case_t), intent(in) :: case
        !> The curve.
        type(sweep_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(checkpoint_writer_t) :: writer
        type(sweep_result_t) :: saved
        logical :: found

        call prepare_output(case, error)
        if (allocated(error)) return
        writer%directory = case%directory
        writer%fingerprint = case_fingerprint(case)
        found = .false.
        if (case%sweep%resume) then
            call read_checkpoint(case%directory, writer%fingerprint, saved, found, error)
            if (allocated(error)) return
        end if
        if (found) then
            call run_sweep(case%model, case%hbm, case%reference, case%sweep, res, error, &
                           observer=writer, resume=saved)
        else
            call run_sweep(case%model, case%hbm, case%reference, case%sweep, res, error, &
                           observer=writer)
        end if
        if (allocated(error)) then
            call prepare_output(case, error)
            return
        end if
        call write_frc_csv(case%directory, res, error)
        if (allocated(error)) return
        call write_frc_plot_script(case%directory, trim(case%sweep%parameter), &
                                   case%model%ndof, error)
        if (allocated(error)) return
        call write_sweep_summary(case%directory, case, res, error)
        if (allocated(error)) return
        call remove_checkpoint(case%directory)
        if (.not. res%complete) call fatal_error(error, "sweep: "//res%diagnosis// &
                                                 " (frc.csv holds the points computed)", &
                                                 stickslip_stat%numerical)
    end subroutine run_sweep_case

    !> Run the robustness study of `case` (&robustness: omega x mu x H x rho x samples, cold
    !> and warm starts, Euler) and write robustness.csv, robustness.gp (the gnuplot script of
    !> the maps robustness_cold.png and robustness_warm.png) and summary.nml into
    !> case%directory. Failed runs are rows, not errors. Errors: stat input (invalid case),
    !> stat io.
    subroutine run_robustness_case(case, rows, error)
        !> The case (with its &robustness group, or the default grid).
        type(case_t), intent(in) :: case
        !> The runs.
        type(robustness_row_t), allocatable, intent(out) :: rows(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(robustness_options_t) :: opts
        opts = case%robustness
        if (.not. allocated(opts%omegas)) opts = default_robustness_options()
        call run_robustness(case%model, case%hbm, case%euler, case%reference, opts, rows, error)
        call prepare_output(case, error)
        if (allocated(error)) return
        call write_robustness_csv(case%directory, rows, error)
        if (allocated(error)) return
        call write_robustness_plot_script(case%directory, opts, error)
        if (allocated(error)) return
        call write_robustness_summary(case%directory, case, rows, error)
    end subroutine run_robustness_case

    !> reference.csv and events.csv of a converged reference.
    subroutine write_reference_files(case, res, error)
        type(case_t), intent(in) :: case
        type(reference_result_t), intent(in) :: res
        type(error_type), allocatable, intent(out) :: error
        call write_samples_csv(case%directory, "reference.csv", res%t, res%x, res%v, res%r, &
                               error)
        if (allocated(error)) return
        call write_events_csv(case%directory, res, error)
    end subroutine write_reference_files

    !> After a method ran: name the case file in an input error, or else create the output
    !> directory.
    subroutine prepare_output(case, error)
        type(case_t), intent(in) :: case
        type(error_type), allocatable, intent(inout) :: error
        if (allocated(error)) then
            if (error%stat == stickslip_stat%input .and. allocated(case%path)) then
                if (len(case%path) > 0) error%message = case%path//": "//error%message
            end if
            return
        end if
        call make_directory(case%directory, error)
    end subroutine prepare_output
end module stickslip_run
