!> What every run of a case shares, whichever its method: its output directory (created and
!> locked before the method runs, cleared of an earlier run's results after a failure), the
!> wording of its errors in the case file's terms, and its values as the result writers take
!> them (with a reduction, the selected full-model DOFs recovered; the columns that hold the
!> selected DOFs), and the files of a converged reference (reference.csv, events.csv).
module stickslip_run_output
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_case, only: case_t, selected_dofs
    use stickslip_case_reduction, only: recover_outputs
    use stickslip_case_messages, only: case_message
    use stickslip_solution, only: hbm_solution_t
    use stickslip_reference, only: reference_result_t
    use stickslip_files, only: make_directory, directory_lock_t, acquire_lock, release_lock, &
        begin_staging, commit_staging, staging_name
    use stickslip_csv, only: write_samples_csv, write_events_csv
    use stickslip_sweep, only: sweep_options_t
    implicit none
    private
    public :: open_output, close_output, after_method, name_case_file
    public :: write_reference_files
    public :: sparse_columns, recovers, output_columns, boundary_columns, output_values, &
              output_solution, observed_sweep

contains

    !> reference.csv and events.csv of a converged reference.
    subroutine write_reference_files(case, dir, res, error)
        !> The case (its DOF selection).
        type(case_t), intent(in) :: case
        !> The directory written (the run's staging directory).
        character(len=*), intent(in) :: dir
        !> The converged reference.
        type(reference_result_t), intent(in) :: res
        !> Set on failure (stat io).
        type(error_type), allocatable, intent(out) :: error
        call write_samples_csv(dir, "reference.csv", res%t, &
                               output_values(case, res%x), output_values(case, res%v), res%r, &
                               error, output_columns(case), selected_dofs(case), &
                               res%contacts, res%gap)
        if (allocated(error)) return
        call write_events_csv(dir, res, error)
    end subroutine write_reference_files

    !> Before a method runs: create the output directory, take its lock and make the
    !> staging directory where the run writes its set of result files (close_output moves
    !> them into place together).
    subroutine open_output(case, lock, error, stage)
        !> The case (its &output directory).
        type(case_t), intent(in) :: case
        !> The directory's lock, held on return without an error.
        type(directory_lock_t), intent(inout) :: lock
        !> Set on failure: stat input (no directory set), stat io (not created, or locked by
        !> another run).
        type(error_type), allocatable, intent(out) :: error
        !> The staging directory: the run writes its result files there.
        character(len=:), allocatable, intent(out) :: stage
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
        if (allocated(error)) return
        call begin_staging(case%directory, error)
        if (allocated(error)) then
            call release_lock(lock)
            return
        end if
        stage = staging_name(case%directory)
    end subroutine open_output

    !> After a method ran in the staging directory: replace the directory's set of result
    !> files by the staged one (commit_staging: with a summary, all together and the summary
    !> last; after a numerical failure without one, the old set removed; after an input or
    !> io failure, the old set kept), name the real directory in `error`, give the lock back.
    subroutine close_output(case, lock, error)
        !> The case (its &output directory).
        type(case_t), intent(in) :: case
        !> The directory's lock, released on return.
        type(directory_lock_t), intent(inout) :: lock
        !> The run's error; set when the files cannot be moved into place (stat io).
        type(error_type), allocatable, intent(inout) :: error
        type(error_type), allocatable :: commit_error
        character(len=:), allocatable :: stage
        integer :: stat, k
        stat = 0
        if (allocated(error)) stat = error%stat
        call commit_staging(case%directory, stat, commit_error)
        if (allocated(commit_error) .and. .not. allocated(error)) &
            call move_alloc(commit_error, error)
        if (allocated(error)) then
            ! the files were written to the staging directory: name the real one
            stage = staging_name(case%directory)
            do
                k = index(error%message, stage)
                if (k == 0) exit
                error%message = error%message(1:k - 1)//case%directory// &
                                error%message(k + len(stage):)
            end do
        end if
        call release_lock(lock)
    end subroutine close_output

    !> After a method ran: whether its files are to be written (no error). What happens to
    !> the results of an earlier run is close_output's: an input error leaves the directory
    !> as it was; a numerical one without a result to write removes them, as they would
    !> otherwise pass for this run's.
    subroutine after_method(error, wanted)
        !> The method's error, if any.
        type(error_type), allocatable, intent(in) :: error
        !> Whether the method's files are to be written.
        logical, intent(out) :: wanted
        wanted = .not. allocated(error)
    end subroutine after_method

    !> Put an error of the library in the words of the case: the arguments of the method
    !> called (`arguments`, e.g. 'opts') become the case-file group and variable (`groups`,
    !> e.g. 'hbm'; model components map to &system, &forcing, &friction; 'basis', the harmonic
    !> basis a weighted-residual solve builds from its options, maps to &hbm), and an input
    !> error names the case file.
    subroutine name_case_file(case, error, arguments, groups)
        !> The case (its file's path, if read from one).
        type(case_t), intent(in) :: case
        !> The error to reword (nothing happens when not allocated).
        type(error_type), allocatable, intent(inout) :: error
        !> Argument names of the method called (optional, with `groups`).
        character(len=*), intent(in), optional :: arguments(:)
        !> The case-file group of each of `arguments`.
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
        !> The kept DOFs of the sparse solution, in its column order.
        integer, intent(in) :: kept(:)
        !> The DOFs wanted (each one among `kept`).
        integer, intent(in) :: dofs(:)
        integer :: cols(size(dofs))
        integer :: k
        do k = 1, size(dofs)
            cols(k) = findloc(kept, dofs(k), 1)
        end do
    end function sparse_columns

    !> Whether the case's model was reduced with output rows kept (the result files then hold
    !> recovered full-model DOFs).
    pure logical function recovers(case)
        !> The case.
        type(case_t), intent(in) :: case
        recovers = allocated(case%reduction%output_rows)
    end function recovers

    !> The &sweep options of `case` as run_sweep and run_family take them, and the number of
    !> amplitudes a point holds: one per DOF of the model, or with a reduction one per
    !> selected full-model DOF (the rows of the recovery, opts%observe).
    subroutine observed_sweep(case, opts, namp)
        !> The case (its &sweep and reduction).
        type(case_t), intent(in) :: case
        !> The sweep options.
        type(sweep_options_t), intent(out) :: opts
        !> Amplitudes per point.
        integer, intent(out) :: namp
        opts = case%sweep%sweep_options_t
        namp = case%model%ndof
        if (recovers(case)) then
            opts%observe = case%reduction%output_rows
            namp = size(opts%observe, 1)
        end if
    end subroutine observed_sweep

    !> The columns of the values given to the writers that hold the selected DOFs: the DOF
    !> numbers themselves, or 1..nsel for recovered values (output_values).
    function output_columns(case) result(cols)
        !> The case (its DOF selection and reduction).
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
        !> The case (its DOF selection and reduction).
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
        !> The case (its reduction).
        type(case_t), intent(in) :: case
        !> Samples of the model's DOFs (instants x ndof).
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
        !> The case (its reduction).
        type(case_t), intent(in) :: case
        !> The solution of the (reduced) model.
        type(hbm_solution_t), intent(in) :: sol
        type(hbm_solution_t) :: out
        out = sol
        if (.not. recovers(case)) return
        if (allocated(sol%x)) out%x = recover_outputs(case%reduction, sol%x)
        if (allocated(sol%v)) out%v = recover_outputs(case%reduction, sol%v)
        if (allocated(sol%xcoef)) out%xcoef = recover_outputs(case%reduction, sol%xcoef)
    end function output_solution
end module stickslip_run_output
