!> The runs of a case that solve it many times: &run method 'study' (the work-precision
!> study: study.csv, with its reference's reference.csv and events.csv), 'sweep' (the
!> forced-response curve: frc.csv, frc_harmonics.csv, frc.gp, resumable from
!> frc.checkpoint) and
!> 'robustness' (the grid of cold and warm starts: robustness.csv, robustness.gp) and
!> 'modes' (the backbone of a nonlinear mode: modes.csv, modes_harmonics.csv, modes.gp). Each
!> runs under the lock of the output directory, with an optional progress hook, and writes
!> its table, plot script and summary.nml.
module stickslip_run_studies
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_progress, only: progress_t
    use stickslip_case, only: case_t, selected_dofs
    use stickslip_model, only: has_contact_laws
    use stickslip_hbm_sparse, only: kept_dofs
    use stickslip_study, only: study_options_t, study_result_t, run_study, default_study_options
    use stickslip_sweep, only: sweep_result_t, run_sweep, sweep_options_t
    use stickslip_robustness, only: robustness_options_t, robustness_row_t, run_robustness, &
        default_robustness_options
    use stickslip_checkpoint, only: checkpoint_writer_t, case_fingerprint, read_checkpoint, &
        remove_checkpoint
    use stickslip_files, only: directory_lock_t
    use stickslip_csv, only: write_study_csv, write_frc_csv, write_frc_harmonics_csv, &
        write_robustness_csv, write_modes_csv, write_modes_harmonics_csv
    use stickslip_modes, only: modes_options_t, modes_result_t, run_modes
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_summary, only: write_study_summary, write_sweep_summary, &
        write_robustness_summary, write_modes_summary
    use stickslip_plot_scripts, only: write_frc_plot_script, write_robustness_plot_script, &
        write_modes_plot_script, write_sector_modes_plot_script
    use stickslip_run_sector_modes, only: sector_backbones, sector_diameters
    use stickslip_case_studies, only: diameter_mode
    use stickslip_run_findings, only: study_findings
    use stickslip_case_messages, only: to_case_message
    use stickslip_sweep_family, only: family_result_t
    use stickslip_run_family, only: family_run, remove_family_checkpoints
    use stickslip_run_output, only: observed_sweep, open_output, close_output, after_method, &
        name_case_file, write_reference_files, sparse_columns, recovers, output_columns, boundary_columns
    implicit none
    private
    public :: run_study_case, run_sweep_case, run_robustness_case, run_modes_case

contains

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
        character(len=:), allocatable :: stage
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        call study_run(case, stage, res, error, progress)
        call close_output(case, lock, error)
        call name_case_file(case, error, &
                            ['hbm     ', 'euler   ', 'ref_opts', 'opts    ', 'basis   '], &
                            ['hbm      ', 'euler    ', 'reference', 'study    ', 'hbm      '])
    end subroutine run_study_case

    subroutine study_run(case, dir, res, error, progress)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
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
                return
            end if
            ! the reference failed: its report is still worth a summary
            call write_study_summary(dir, case, res, io_error, study_findings(res))
            if (allocated(io_error)) call move_alloc(io_error, error)
            return
        end if
        call write_study_csv(dir, res, case%model%ndof, case%model%ncontact(), error, &
                             boundary_columns(case), selected_dofs(case))
        if (allocated(error)) return
        call write_reference_files(case, dir, res%reference, error)
        if (allocated(error)) return
        call write_study_summary(dir, case, res, error, study_findings(res))
    end subroutine study_run

    !> Continue the periodic solution of `case` over the &sweep range and write frc.csv,
    !> frc_harmonics.csv (each point's Fourier coefficients), frc.gp (the gnuplot script of
    !> frc.png and frc_dissipation.png) and summary.nml into case%directory. The curve
    !> is saved in frc.checkpoint after its first point, then at most once a second; with
    !> &sweep resume (the default) a run of the same case that finds a checkpoint goes on
    !> from it. The checkpoint is removed once the files are written. A curve that stopped
    !> before the end of the range is written too, and an error with stat numerical is
    !> returned with the diagnosis. Errors: stat input (invalid case, a checkpoint of
    !> another case or a damaged one), stat numerical (no solution at the start), stat io.
    subroutine run_sweep_case(case, res, error, progress, family)
        !> The case (with its &sweep group).
        type(case_t), intent(in) :: case
        !> The curve (a family's: every curve's points, curve after curve).
        type(sweep_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every point of the curve (every curve of a family).
        type(progress_t), intent(inout), optional :: progress
        !> The family, when &sweep gives one (family_values): frc.csv with the columns curve
        !> and family_value, family.csv, family.gp; one checkpoint per curve.
        type(family_result_t), intent(out), optional :: family
        type(directory_lock_t) :: lock
        character(len=:), allocatable :: stage
        logical :: summary_written, is_family
        type(family_result_t) :: fam
        is_family = allocated(case%sweep%family%family_values)
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        if (is_family) then
            call family_run(case, stage, res, fam, summary_written, error, progress)
            if (present(family)) family = fam
        else
            call sweep_run(case, stage, res, summary_written, error, progress)
        end if
        call close_output(case, lock, error)
        ! the curve's files are in place: its checkpoint has served (a sweep stopped short
        ! has written what it computed, with exit code 2)
        if (summary_written) then
            if (.not. allocated(error)) then
                call remove_done()
            else if (error%stat == stickslip_stat%numerical) then
                call remove_done()
            end if
        end if
        call name_case_file(case, error, ['hbm  ', 'ref  ', 'opts ', 'basis'], &
                            ['hbm      ', 'reference', 'sweep    ', 'hbm      '])

    contains

        subroutine remove_done()
            if (is_family) then
                call remove_family_checkpoints(case)
            else
                call remove_checkpoint(case%directory)
            end if
        end subroutine remove_done
    end subroutine run_sweep_case

    subroutine sweep_run(case, dir, res, summary_written, error, progress)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
        type(sweep_result_t), intent(out) :: res
        !> summary.nml was written.
        logical, intent(out) :: summary_written
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(checkpoint_writer_t) :: writer
        type(sweep_result_t) :: saved
        logical :: found
        logical :: wanted
        integer, allocatable :: kept(:), cols(:)
        integer :: ncols

        type(sweep_options_t) :: opts
        type(contact_set_t) :: contacts
        integer :: namp

        ! a reduced model's amplitudes are those of the selected full-model DOFs
        call observed_sweep(case, opts, namp)
        summary_written = .false.
        writer%directory = case%directory
        writer%fingerprint = case_fingerprint(case, error)
        if (allocated(error)) return
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
                                 case%model%ncontact(), saved, found, error, &
                                 laws=has_contact_laws(case%model))
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
        else if (case%cyclic%given .and. case%cyclic%model == 'sector') then
            ! one sector of a tuned disk: the curve of its travelling wave
            if (found) then
                call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                               opts, res, error, observer=writer, resume=saved, &
                               progress=progress, cyclic=case%cyclic%cyc)
            else
                call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                               opts, res, error, observer=writer, progress=progress, &
                               cyclic=case%cyclic%cyc)
            end if
        else if (found) then
            call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                           opts, res, error, observer=writer, resume=saved, progress=progress)
        else
            call run_sweep(case%model, case%hbm, case%reference%reference_options_t, &
                           opts, res, error, observer=writer, progress=progress)
        end if
        call after_method(error, wanted)
        if (.not. wanted) return
        call write_frc_csv(dir, res, error, cols, selected_dofs(case))
        if (allocated(error)) return
        call new_contact_set(contacts, case%model)
        call write_frc_harmonics_csv(dir, res, error, cols, selected_dofs(case), contacts)
        if (allocated(error)) return
        if (allocated(case%plot_amplitude)) then
            call write_frc_plot_script(dir, trim(case%sweep%parameter), &
                                       ncols, error, cols, selected_dofs(case), &
                                       case%plot_amplitude, case%units, case%sweep%stability)
        else
            call write_frc_plot_script(dir, trim(case%sweep%parameter), &
                                       ncols, error, cols, selected_dofs(case), &
                                       units=case%units, stability=case%sweep%stability)
        end if
        if (allocated(error)) return
        call write_sweep_summary(dir, case, res, error)
        if (allocated(error)) return
        summary_written = .true.
        if (.not. res%complete) call fatal_error(error, "sweep: "//res%diagnosis// &
                                                 " (frc.csv holds the points computed)", &
                                                 stickslip_stat%numerical)
    end subroutine sweep_run

    !> Compute the backbone of the nonlinear mode of `case` (&modes) and write modes.csv,
    !> modes_harmonics.csv, modes.gp (the gnuplot script of modes.png) and summary.nml into
    !> case%directory. A backbone that stopped before amplitude_stop is written too, and an
    !> error with stat numerical is returned with the diagnosis. Errors: stat input (invalid
    !> case, no such mode), stat numerical (no solution at the start), stat io.
    subroutine run_modes_case(case, res, error, progress)
        !> The case (with its &modes group).
        type(case_t), intent(in) :: case
        !> The backbone.
        type(modes_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every point.
        type(progress_t), intent(inout), optional :: progress
        type(directory_lock_t) :: lock
        character(len=:), allocatable :: stage
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        call modes_run(case, stage, res, error, progress)
        call close_output(case, lock, error)
        call name_case_file(case, error, ['hbm  ', 'opts ', 'basis'], &
                            ['hbm      ', 'modes    ', 'hbm      '])
    end subroutine run_modes_case

    subroutine modes_run(case, dir, res, error, progress)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
        type(modes_result_t), intent(out) :: res
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(modes_options_t) :: opts
        type(contact_set_t) :: contacts
        type(modes_result_t), allocatable :: per(:)
        integer, allocatable :: cols(:), diameters(:)
        logical :: wanted, sector
        integer :: i
        opts = case%modes%modes_options_t
        if (recovers(case)) opts%observe = case%reduction%output_rows
        sector = case%cyclic%given .and. case%cyclic%model == 'sector'
        if (sector) then
            ! one backbone per nodal diameter on the sector
            diameters = sector_diameters(case)
            call sector_backbones(case, opts, diameters, res, per, error, progress)
        else
            call run_modes(case%model, case%hbm, opts, res, error, progress)
        end if
        ! a mode the structure does not have: named as the case file's variable
        if (allocated(error)) then
            if (error%stat == stickslip_stat%input) call to_case_message(error, "", ['opts'], &
                                                                         ['modes'])
        end if
        call after_method(error, wanted)
        if (.not. wanted) return
        cols = output_columns(case)
        call write_modes_csv(dir, res, error, cols, selected_dofs(case))
        if (allocated(error)) return
        call new_contact_set(contacts, case%model)
        call write_modes_harmonics_csv(dir, res, error, cols, selected_dofs(case), contacts)
        if (allocated(error)) return
        if (sector) then
            call write_sector_modes_plot_script(dir, pack([(diameter_mode(case%modes, i), &
                                                      i=1, size(diameters))], &
                                                    per%npoints > 0), &
                                                pack(diameters, per%npoints > 0), error, &
                                                case%units)
        else
            call write_modes_plot_script(dir, case%modes%mode, res%omega_stuck, &
                                         res%omega_slipping, error, case%units)
        end if
        if (allocated(error)) return
        if (sector) then
            call write_modes_summary(dir, case, res, error, per, diameters)
        else
            call write_modes_summary(dir, case, res, error)
        end if
        if (allocated(error)) return
        if (.not. res%complete) call fatal_error(error, "modes: "//res%diagnosis// &
                                                 " (modes.csv holds the points computed)", &
                                                 stickslip_stat%numerical)
    end subroutine modes_run

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
        character(len=:), allocatable :: stage
        call open_output(case, lock, error, stage)
        if (allocated(error)) return
        call robustness_run(case, stage, rows, error, progress)
        call close_output(case, lock, error)
        call name_case_file(case, error, &
                            ['hbm_opts  ', 'euler_opts', 'ref_opts  ', 'opts      ', 'basis     '], &
                            ['hbm       ', 'euler     ', 'reference ', 'robustness', 'hbm       '])
    end subroutine run_robustness_case

    subroutine robustness_run(case, dir, rows, error, progress)
        type(case_t), intent(in) :: case
        !> The directory the results are written to (the run's staging directory).
        character(len=*), intent(in) :: dir
        type(robustness_row_t), allocatable, intent(out) :: rows(:)
        type(error_type), allocatable, intent(out) :: error
        type(progress_t), intent(inout), optional :: progress
        type(robustness_options_t) :: opts
        logical :: wanted
        opts = case%robustness
        if (.not. allocated(opts%omegas)) opts = default_robustness_options()
        call run_robustness(case%model, case%hbm, case%euler, case%reference, opts, rows, &
                            error, progress)
        call after_method(error, wanted)
        if (.not. wanted) return
        call write_robustness_csv(dir, rows, error)
        if (allocated(error)) return
        call write_robustness_plot_script(dir, opts, error)
        if (allocated(error)) return
        call write_robustness_summary(dir, case, rows, error)
    end subroutine robustness_run
end module stickslip_run_studies
