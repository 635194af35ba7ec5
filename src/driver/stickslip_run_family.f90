!> The run of a case whose &sweep gives a family (family_parameter, family_values): the
!> curves (stickslip_sweep_family) with one checkpoint per curve in the output directory
!> (frc_family_<k>.checkpoint, resumed like a sweep's), then frc.csv and frc_harmonics.csv
!> (every curve's points, with the columns curve and family_value), family.csv (one row per
!> curve: its peaks and the linear limits'), family.gp (frc_family.png, family.png) and
!> summary.nml, written into the run's staging directory.
module stickslip_run_family
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_progress, only: progress_t
    use stickslip_case, only: case_t, selected_dofs, put, rtoa, ltoa
    use stickslip_model, only: has_contact_laws
    use stickslip_sweep, only: sweep_result_t, sweep_options_t
    use stickslip_sweep_result, only: frc_point_t
    use stickslip_sweep_family, only: family_options_t, family_result_t, run_family, &
        observer_slot_t
    use stickslip_checkpoint, only: checkpoint_writer_t, case_fingerprint, read_checkpoint, &
        remove_checkpoint, family_checkpoint_name
    use stickslip_csv, only: write_frc_csv, write_frc_harmonics_csv
    use stickslip_family_csv, only: write_family_csv
    use stickslip_plot_scripts, only: write_family_plot_script
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_summary, only: write_family_summary
    use stickslip_run_output, only: observed_sweep, after_method, output_columns
    implicit none
    private
    public :: family_run, remove_family_checkpoints

contains

    !> Run the family of `case` and write its files into `dir`. `res` gets every curve's
    !> points in one curve (curves in order; complete when all are), `fam` the family.
    !> Errors: stat input (invalid case, a checkpoint of another case), stat numerical (a
    !> curve stopped short or had no start: the files are written, the message names the
    !> curves), stat io.
    subroutine family_run(case, dir, res, fam, summary_written, error, progress)
        !> The case (&sweep with family_values).
        type(case_t), intent(in) :: case
        !> The staging directory.
        character(len=*), intent(in) :: dir
        !> All the points, curve after curve.
        type(sweep_result_t), intent(out) :: res
        !> The family.
        type(family_result_t), intent(out) :: fam
        !> summary.nml was written.
        logical, intent(out) :: summary_written
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every curve.
        type(progress_t), intent(inout), optional :: progress
        type(sweep_options_t) :: opts
        type(family_options_t) :: fopts
        type(checkpoint_writer_t), allocatable :: writers(:)
        type(observer_slot_t), allocatable :: slots(:)
        type(sweep_result_t), allocatable :: saved(:)
        logical, allocatable :: found(:)
        character(len=16) :: fingerprint
        integer :: n, k, namp, total, i
        integer, allocatable :: cols(:), curve(:)
        real(dp), allocatable :: value(:)
        type(contact_set_t) :: contacts
        logical :: wanted
        summary_written = .false.
        call observed_sweep(case, opts, namp)
        fopts = case%sweep%family
        if (allocated(case%plot_amplitude)) fopts%measure = case%plot_amplitude
        n = size(fopts%family_values)
        fingerprint = case_fingerprint(case, error)
        if (allocated(error)) return
        allocate (writers(n), saved(n), found(n), slots(n))
        found = .false.
        do k = 1, n
            writers(k)%directory = case%directory
            writers(k)%fingerprint = fingerprint
            writers(k)%name = family_checkpoint_name(k)
            if (case%sweep%resume) then
                call read_checkpoint(case%directory, fingerprint, namp, case%model%ncontact(), &
                                     saved(k), found(k), error, &
                                     laws=has_contact_laws(case%model), &
                                     name=writers(k)%name)
                if (allocated(error)) return
            end if
            allocate (slots(k)%observer, source=writers(k))
        end do
        if (case%cyclic%given .and. case%cyclic%model == 'sector') then
            ! one sector of a tuned disk: every curve its travelling wave
            call run_family(case%model, case%hbm, case%reference%reference_options_t, opts, &
                            fopts, fam, error, observers=slots, resumes=saved, resumed=found, &
                            progress=progress, cyclic=case%cyclic%cyc)
        else
            call run_family(case%model, case%hbm, case%reference%reference_options_t, opts, &
                            fopts, fam, error, observers=slots, resumes=saved, resumed=found, &
                            progress=progress)
        end if
        call after_method(error, wanted)
        if (.not. wanted) return
        ! every curve's points in one table
        total = sum([(fam%curves(k)%npoints, k=1, n)])
        allocate (res%points(total), curve(total), value(total))
        i = 0
        do k = 1, n
            associate (c => fam%curves(k))
                if (c%npoints > 0) then
                    res%points(i + 1:i + c%npoints) = c%points(1:c%npoints)
                    curve(i + 1:i + c%npoints) = k
                    value(i + 1:i + c%npoints) = fam%values(k)
                end if
                i = i + c%npoints
                res%seconds = res%seconds + c%seconds
                res%stability_seconds = res%stability_seconds + c%stability_seconds
                res%folds = res%folds + c%folds
                res%resumed_points = res%resumed_points + c%resumed_points
            end associate
        end do
        res%npoints = total
        res%complete = fam%complete
        res%diagnosis = fam%diagnosis
        res%diagnostics = fam%diagnostics
        res%notes = ""
        cols = output_columns(case)
        call write_frc_csv(dir, res, error, cols, selected_dofs(case), curve=curve, &
                           family_value=value)
        if (allocated(error)) return
        call new_contact_set(contacts, case%model)
        call write_frc_harmonics_csv(dir, res, error, cols, selected_dofs(case), contacts)
        if (allocated(error)) return
        call write_family_csv(dir, fam, error, cols, selected_dofs(case))
        if (allocated(error)) return
        call write_family_plot_script(dir, trim(fopts%family_parameter), fam%values, namp, &
                                      error, cols, selected_dofs(case), fopts%measure, &
                                      case%units)
        if (allocated(error)) return
        call write_family_summary(dir, case, fam, res, cols(1), error)
        if (allocated(error)) return
        summary_written = .true.
        if (.not. fam%complete) call fatal_error(error, "sweep: family: "//fam%diagnosis// &
                                                 " (frc.csv and family.csv hold what was "// &
                                                 "computed)", stickslip_stat%numerical)
    end subroutine family_run

    !> Delete the curves' checkpoints of the family of `case` (the family is written).
    subroutine remove_family_checkpoints(case)
        !> The case (&sweep with family_values).
        type(case_t), intent(in) :: case
        integer :: k
        do k = 1, size(case%sweep%family%family_values)
            call remove_checkpoint(case%directory, family_checkpoint_name(k))
        end do
    end subroutine remove_family_checkpoints
end module stickslip_run_family
