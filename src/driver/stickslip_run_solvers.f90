!> The runs of a case by one solver, or the three of them side by side: &run method 'hbm'
!> (the weighted residual, with its checks), 'euler' (implicit Euler to the periodic
!> state), 'reference' (the exact event-driven shooting) and 'all'. Each solves for the
!> periodic state under the lock of the output directory and writes that state's result
!> files (hbm.csv and coefficients.csv, full_field.mtx, euler.csv, reference.csv and
!> events.csv) and summary.nml.
module stickslip_run_solvers
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_progress, only: progress_t
    use stickslip_case, only: case_t, selected_dofs
    use stickslip_case_reduction, only: recover_full_field
    use stickslip_full_field, only: write_full_field
    use stickslip_solution, only: hbm_solution_t
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic, disk_solution
    use stickslip_stability, only: periodic_stability
    use stickslip_wave_symmetry, only: wave_symmetry_t
    use stickslip_model, only: model_t
    use stickslip_truncation, only: estimate_truncation
    use stickslip_checks, only: hbm_checks_t, solve_and_check, sampling_notes, &
        truncation_findings, &
        sampling_diagnostics
    use stickslip_hbm_sparse, only: solve_periodic_sparse
    use stickslip_euler, only: euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t
    use stickslip_reference_start, only: solve_reference_from_starts
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side
    use stickslip_files, only: directory_lock_t
    use stickslip_csv, only: write_hbm_csv, write_coefficients_csv, write_samples_csv
    use stickslip_summary, only: write_summary, write_euler_summary, write_reference_summary, &
        write_side_by_side_summary
    use stickslip_run_findings, only: hbm_findings, side_by_side_findings
    use stickslip_run_output, only: open_output, close_output, after_method, name_case_file, &
        write_reference_files, sparse_columns, recovers, output_columns, output_values, &
        output_solution
    implicit none
    private
    public :: run_case, run_euler_case, run_reference_case, run_side_by_side_case

contains

    !> Solve `case` (with &hbm harmonics_tol: raising H until the truncation estimate meets
    !> it), check the solution (truncation estimate; with &hbm stability, its Floquet
    !> multipliers; with verify_periods, the periodicity defect of the exact flow from it)
    !> and write its results into case%directory (created if missing):
    !> hbm.csv, coefficients.csv and summary.nml when the solve converged; only summary.nml
    !> (converged = F, with the diagnosis) when it did not, and then an error with stat
    !> numerical is returned as well. Other errors: stat input (invalid case, prefixed with
    !> the case file), stat numerical (singular dynamic stiffness, NaN), stat io (files, a
    !> directory another run is writing).
    subroutine run_case(case, sol, error, checks, progress)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The solution.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The checks of the solution (truncation estimate, stability, periodicity defect).
        type(hbm_checks_t), intent(out), optional :: checks
        !> Progress of long phases (the exact sparse condensation's harmonics).
        type(progress_t), intent(inout), optional :: progress
        type(hbm_checks_t) :: ch
        type(directory_lock_t) :: lock
        character(len=:), allocatable :: stage
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        call hbm_run(case, stage, sol, ch, error, progress)
        call close_output(case, lock, error)
        if (present(checks)) checks = ch
        call name_case_file(case, error, ['opts ', 'copts', 'ref  ', 'basis'], &
                            ['hbm      ', 'hbm      ', 'reference', 'hbm      '])
    end subroutine run_case

    subroutine hbm_run(case, dir, sol, ch, error, progress)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
        type(hbm_solution_t), intent(out) :: sol
        type(hbm_checks_t), intent(out) :: ch
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(error_type), allocatable :: io_error
        logical :: wanted
        integer, allocatable :: cols(:)
        integer :: i
        if (allocated(case%sparse_model)) then
            ! &reduction method = 'none' above the dense limit: the exact sparse condensation
            if (case%full_field) then
                ! every DOF kept (the selection first: the files' columns)
                call solve_periodic_sparse(case%sparse_model, case%hbm, [selected_dofs(case), &
                                           (i, i=1, case%sparse_model%model%ndof)], sol, error, &
                                           progress=progress)
            else
                call solve_periodic_sparse(case%sparse_model, case%hbm, selected_dofs(case), &
                                           sol, error, progress=progress)
            end if
            ch%notes = sampling_notes(case%hbm%samples, case%hbm%harmonics)
            call sampling_diagnostics(case%hbm%samples, ch%diagnostics)
            ch%truncation%note = "not estimated for &reduction method = 'none' on a sparse "// &
                                 "model"
        else if (case%cyclic%given .and. case%cyclic%model == 'sector') then
            ! one sector of a tuned disk: its travelling wave
            call solve_periodic_cyclic(case%model, case%cyclic%cyc, case%hbm, sol, error)
            ch%notes = sampling_notes(case%hbm%samples, case%hbm%harmonics)
            call sampling_diagnostics(case%hbm%samples, ch%diagnostics)
            if (.not. allocated(error)) then
                if (sol%converged) then
                    call estimate_truncation(case%model, case%hbm, sol, ch%truncation, error, &
                                             cyclic=case%cyclic%cyc)
                    if (.not. allocated(error)) call truncation_findings(ch)
                    if (.not. allocated(error) .and. case%checks%stability) then
                        ! the multipliers of the whole disk (every perturbation)
                        block
                            type(model_t) :: disk
                            type(hbm_solution_t) :: dsol
                            call disk_solution(case%model, case%cyclic%cyc, case%hbm, sol, &
                                               disk, dsol, error)
                            if (.not. allocated(error)) then
                                ch%stability = .true.
                                call periodic_stability(disk, dsol, &
                                                        case%reference%reference_options_t, &
                                                        ch%floquet, error, symmetry= &
                                                        wave_symmetry_t(case%cyclic%cyc% &
                                                        sectors, case%cyclic%cyc%engine_order))
                            end if
                        end block
                    end if
                end if
            end if
        else
            call solve_and_check(case%model, case%hbm, case%checks, &
                                 case%reference%reference_options_t, sol, ch, error)
        end if
        call after_method(error, wanted)
        if (.not. wanted) return
        if (sol%converged) then
            if (allocated(sol%dofs)) then
                ! the solution's columns are its kept DOFs: those of the selection
                cols = sparse_columns(sol%dofs, selected_dofs(case))
            else
                cols = output_columns(case)
            end if
            call write_hbm_csv(dir, output_solution(case, sol), error, &
                               cols, selected_dofs(case))
            if (allocated(error)) return
            call write_coefficients_csv(dir, output_solution(case, sol), error, &
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
                    call write_full_field(dir, coef, sol, error)
                    if (allocated(error)) return
                end block
            end if
        else
        end if
        call write_summary(dir, case, sol, io_error, ch, hbm_findings(sol, ch))
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
        character(len=:), allocatable :: stage
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        call euler_run(case, stage, res, error, progress)
        call close_output(case, lock, error)
        call name_case_file(case, error, ['opts'], ['euler'])
    end subroutine run_euler_case

    subroutine euler_run(case, dir, res, error, progress)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
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
        call after_method(error, wanted)
        if (.not. wanted) return
        if (res%periodic) then
            call write_samples_csv(dir, "euler.csv", res%t, &
                                   output_values(case, res%x), output_values(case, res%v), &
                                   res%r, error, output_columns(case), selected_dofs(case), &
                                   res%contacts, res%gap)
            if (allocated(error)) return
        else
        end if
        call write_euler_summary(dir, case, res, io_error)
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
        character(len=:), allocatable :: stage
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        call reference_run(case, stage, res, error)
        call close_output(case, lock, error)
        call name_case_file(case, error, ['opts      ', 'hbm_opts  ', 'euler_opts', 'basis     '], &
                            ['reference', 'hbm      ', 'euler    ', 'hbm      '])
    end subroutine run_reference_case

    subroutine reference_run(case, dir, res, error)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
        type(reference_result_t), intent(out) :: res
        type(error_type), allocatable, intent(out) :: error
        type(error_type), allocatable :: io_error
        logical :: wanted
        call solve_reference_from_starts(case%model, case%reference, res, error, hbm_opts=case%hbm, &
                             euler_opts=case%euler)
        call after_method(error, wanted)
        if (.not. wanted) return
        if (res%converged) then
            call write_reference_files(case, dir, res, error)
            if (allocated(error)) return
        else
        end if
        call write_reference_summary(dir, case, res, io_error)
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
        character(len=:), allocatable :: stage
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        call side_by_side_run(case, stage, res, error)
        call close_output(case, lock, error)
        call name_case_file(case, error, ['hbm  ', 'euler', 'ref  ', 'basis'], &
                            ['hbm      ', 'euler    ', 'reference', 'hbm      '])
    end subroutine run_side_by_side_case

    subroutine side_by_side_run(case, dir, res, error)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
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
        call after_method(error, wanted)
        if (.not. wanted) return
        files = [character(len=24) ::]
        if (res%hbm%converged) files = [character(len=24) :: files, "hbm.csv", "coefficients.csv"]
        if (res%euler%periodic) files = [character(len=24) :: files, "euler.csv"]
        if (res%reference%converged) files = [character(len=24) :: files, "reference.csv", &
                                              "events.csv"]
        if (res%hbm%converged) then
            call write_hbm_csv(dir, output_solution(case, res%hbm), error, &
                               output_columns(case), selected_dofs(case))
            if (allocated(error)) return
            call write_coefficients_csv(dir, output_solution(case, res%hbm), &
                                        error, output_columns(case), selected_dofs(case))
            if (allocated(error)) return
        end if
        if (res%euler%periodic) then
            call write_samples_csv(dir, "euler.csv", res%euler%t, &
                                   output_values(case, res%euler%x), &
                                   output_values(case, res%euler%v), res%euler%r, error, &
                                   output_columns(case), selected_dofs(case), &
                                   res%euler%contacts, res%euler%gap)
            if (allocated(error)) return
        end if
        if (res%reference%converged) then
            call write_reference_files(case, dir, res%reference, error)
            if (allocated(error)) return
        end if
        call write_side_by_side_summary(dir, case, res, io_error, &
                                        side_by_side_findings(res))
        if (allocated(io_error)) then
            call move_alloc(io_error, error)
            return
        end if
        if (len(res%diagnosis) > 0) call fatal_error(error, res%diagnosis, &
                                                     stickslip_stat%numerical)
    end subroutine side_by_side_run
end module stickslip_run_solvers
