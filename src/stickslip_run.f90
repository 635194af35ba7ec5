!> The whole workflow of one case: case -> model -> weighted-residual solve -> result files.
!> What the CLI runs, and what a host code calls to run a case it read or built.
module stickslip_run
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_case, only: case_t
    use stickslip_solution, only: hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_output, only: make_directory, write_hbm_csv, write_coefficients_csv, &
        write_summary, write_samples_csv, write_euler_summary
    use stickslip_euler, only: euler_result_t, integrate_euler
    implicit none
    private
    public :: run_case, run_euler_case

contains

    !> Solve `case` and write its results into case%directory (created if missing):
    !> hbm.csv, coefficients.csv and summary.nml when the solve converged; only summary.nml
    !> (converged = F, with the diagnosis) when it did not, and then an error with stat
    !> numerical is returned as well. Other errors: stat input (invalid case, prefixed with
    !> the case file), stat numerical (singular dynamic stiffness, NaN), stat io (files).
    subroutine run_case(case, sol, error)
        !> The case to run.
        type(case_t), intent(in) :: case
        !> The solution.
        type(hbm_solution_t), intent(out) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(error_type), allocatable :: io_error

        call solve_periodic(case%model, case%hbm, sol, error)
        call prepare_output(case, error)
        if (allocated(error)) return
        if (sol%converged) then
            call write_hbm_csv(case%directory, sol, error)
            if (allocated(error)) return
            call write_coefficients_csv(case%directory, sol, error)
            if (allocated(error)) return
        end if
        call write_summary(case%directory, case, sol, io_error)
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
