!> Tests of the command line (app/stickslip_cli.inc, run in-process as test_app_cli) and of
!> the result files end to end: the examples, usage errors and exit codes, every method's
!> files, headers and summary keys; warnings and distrust on standard error (exit 2);
!> progress lines; result files of an earlier run removed; the directory lock; unique
!> temporaries; a damaged sweep checkpoint; gnuplot started without a shell.
module test_cli
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat, itoa, real_text
    use stickslip_case, only: case_t, read_case
    use stickslip_cli, only: string_t, run_cli, report_run
    use stickslip_files, only: make_directory, open_temporary, close_and_rename, lock_name, &
        process_id, process_alive, directory_lock_t, acquire_lock, release_lock, &
        process_start_time, remove_file
    use stickslip_signals, only: register_output_directory, remove_own_files
    use stickslip_gnuplot, only: run_gnuplot
    use stickslip_diagnostics, only: level_note, level_warning, level_untrusted
    use stickslip_driver, only: run_result_t, run_method
    use stickslip_progress, only: progress_t
    use stickslip_summary, only: write_summary
    use stickslip_version_info, only: stickslip_version
    use testing, only: test_counter_t, check, check_close, check_error
    use fixtures, only: enter_project_root, first_line, project_path, scratch, write_lines, file_text, &
        good_system, good_forcing, good_friction, sweep_case
    implicit none
    private
    public :: run_cli_tests, cli, summary_value, count_lines, csv_rows, scratch_copy


contains

    subroutine run_cli_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(scratch, error)
        call check_error(t, error, "cli: scratch directory", .false.)
        if (allocated(error)) return
        call test_version_line(t)
        call test_cli_examples(t)
        call test_cli_sector_stability(t)
        call test_cli_figures(t)
        call test_methods_cli(t)
        call test_stale_results(t)
        call test_lock(t)
        call test_unique_temporaries(t)
        call test_findings(t)
        call test_progress(t)
        call test_odd_directory(t)
        call test_no_contact(t)
        call test_contact_examples(t)
    end subroutine run_cli_tests

    !> The contact-law examples from the command line: the damper that lifts off (weighted
    !> residual: the normal force and gap columns, the open share on stdout and in the
    !> summary; the exact reference: open and close events), the 2D elliptical slip (the
    !> three methods; the reference alone with its integration error), the microslip joint
    !> and the 2D damper with contact stiffnesses that lifts off (the reference: its events
    !> and columns).
    subroutine test_contact_examples(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err, dir, text
        character(len=200) :: path
        integer :: code
        path = scratch_copy("damper_liftoff")
        dir = scratch//"/out_damper_liftoff"
        call cli([path], code, out, err)
        call check(t, code == 0 .and. index(out, "(open ") > 0, "cli damper_liftoff: exit 0, "// &
                   "the open share printed", err)
        text = file_text(dir//"/hbm.csv")
        call check(t, index(text, "t,x1,x2,v1,v2,r1,normal1,gap1"//new_line('a')) == 1, &
                   "cli damper_liftoff: hbm.csv has the normal force and gap columns")
        call check(t, len(summary_value(dir//"/summary.nml", "open_fraction")) > 0, &
                   "cli damper_liftoff: the summary has the open fraction")
        call replace_in_file(trim(path), "method = 'hbm'", "method = 'reference'")
        call cli([path], code, out, err)
        text = file_text(dir//"/events.csv")
        call check(t, code == 0 .and. index(text, ",open,") > 0 .and. index(text, ",close,") > 0, &
                   "cli damper_liftoff, reference: exit 0, open and close events", err)
        path = scratch_copy("planar_ellipse")
        dir = scratch//"/out_planar_ellipse"
        call replace_in_file(trim(path), "steps_per_period = 20000", "steps_per_period = 2000")
        call cli([path], code, out, err)
        call check(t, code == 0 .and. index(out, "hbm vs reference") > 0 .and. &
                   index(out, "euler vs reference") > 0 .and. &
                   index(out, "integrated numerically: error estimate") > 0, &
                   "cli planar_ellipse: exit 0, the three methods side by side, the "// &
                   "reference's integration error stated", err)
        call check(t, index(file_text(dir//"/hbm.csv"), "t,x1,x2,v1,v2,r1,r1_2") == 1, &
                   "cli planar_ellipse: hbm.csv has both tangential force columns")
        call replace_in_file(trim(path), "method = 'all'", "method = 'reference'")
        call cli([path], code, out, err)
        call check(t, code == 0 .and. &
                   len(summary_value(dir//"/summary.nml", "integration_error")) > 0 .and. &
                   index(file_text(dir//"/reference.csv"), "t,x1,x2,v1,v2,r1,r1_2") == 1, &
                   "cli planar_ellipse, reference: exit 0, reference.csv and the "// &
                   "integration error in the summary", err)
        path = scratch_copy("microslip_joint")
        dir = scratch//"/out_microslip_joint"
        call replace_in_file(trim(path), "steps_per_period = 10000", "steps_per_period = 2000")
        call cli([path], code, out, err)
        text = file_text(dir//"/events.csv")
        call check(t, code == 0 .and. index(out, "euler vs reference") > 0 .and. &
                   index(text, ",slip,") > 0 .and. &
                   index(file_text(dir//"/hbm.csv"), "t,x1,x2,v1,v2,r1"//new_line('a')) == 1 &
                   .and. index(file_text(dir//"/reference.csv"), "t,x1,x2,v1,v2,r1"// &
                               new_line('a')) == 1, "cli microslip_joint: exit 0, the three "// &
                   "methods, one force column (the joint's), slip events", err)
        call check(t, index(file_text(dir//"/summary.nml"), "&microslip") > 0, &
                   "cli microslip_joint: the joint echoed in the summary's case")
        path = scratch_copy("damper_2d_liftoff")
        dir = scratch//"/out_damper_2d_liftoff"
        call replace_in_file(trim(path), "method = 'all'", "method = 'reference'")
        call cli([path], code, out, err)
        text = file_text(dir//"/events.csv")
        call check(t, code == 0 .and. index(text, ",open,") > 0 .and. &
                   index(text, ",close,") > 0 .and. index(text, ",stick,") > 0 .and. &
                   index(file_text(dir//"/reference.csv"), &
                         "t,x1,x2,x3,v1,v2,v3,r1,r1_2,normal1,gap1"//new_line('a')) == 1, &
                   "cli damper_2d_liftoff, reference: exit 0, open, close and stick events, "// &
                   "both tangential forces and the normal's columns", err)
    end subroutine test_contact_examples

    !> Replace the first occurrence of `old` by `new` in the text file `path`.
    subroutine replace_in_file(path, old, new)
        character(len=*), intent(in) :: path, old, new
        character(len=:), allocatable :: text
        integer :: k, u
        text = file_text(path)
        k = index(text, old)
        if (k == 0) return
        text = text(1:k - 1)//new//text(k + len(old):)
        open (newunit=u, file=path, status='replace', action='write', access='stream', &
              form='unformatted')
        write (u) text
        close (u)
    end subroutine replace_in_file

    !> A case without contacts solves the linear problem, and says so: a warning on
    !> standard error and in the summary (key no_contact), exit code 0.
    subroutine test_no_contact(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/out_no_contact"
        character(len=:), allocatable :: out, err
        integer :: code
        call write_lines(scratch//"/no_contact.nml", [character(len=120) :: good_system, &
            good_forcing, "&hbm harmonics = 3, samples = 16 /", &
            "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/no_contact.nml"], code, out, err)
        call check(t, code == 0 .and. index(err, "stickslip: warning: the case has no "// &
                   "friction contact") > 0, "cli: a case without contacts warns", err)
        call check(t, index(file_text(dir//"/summary.nml"), "warnings = 'no_contact'") > 0, &
                   "cli: no_contact in the summary's warnings")
    end subroutine test_no_contact

    !> `--version`: exit 0, `stickslip <version>`, then the BLAS/LAPACK line (nothing on
    !> stderr).
    subroutine test_version_line(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err
        integer :: code
        call cli([character(len=20) :: "--version"], code, out, err)
        call check(t, code == 0 .and. len(err) == 0 .and. &
                   index(out, "stickslip "//stickslip_version//new_line('a')// &
                         "BLAS/LAPACK: ") == 1, "cli: --version names the version and the BLAS", &
                   out)
    end subroutine test_version_line

    !> A second run into the same directory leaves only its own result files: a run that
    !> fails (summary only) removes the first run's hbm.csv and coefficients.csv; a run of
    !> another method removes the files of the first method; other files and a sweep
    !> checkpoint are never touched.
    subroutine test_stale_results(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/out_stale"
        character(len=:), allocatable :: out, err
        integer :: code
        call write_lines(scratch//"/stale_good.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 10, samples = 128 /", &
            "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/stale_good.nml"], code, out, err)
        call check(t, code == 0 .and. exists(dir//"/hbm.csv") .and. &
                   exists(dir//"/coefficients.csv"), "stale: first run writes hbm.csv", err)
        call write_lines(dir//"/notes.txt", [character(len=20) :: "mine"])
        call write_lines(dir//"/frc.checkpoint", [character(len=20) :: "not mine"])
        call write_lines(dir//"/euler.csv", [character(len=20) :: "t,x1"])
        ! a second run that does not converge: only its summary is left
        call write_lines(scratch//"/stale_starved.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 30, samples = 256, maxfev = 3, "// &
            "start = 'direct' /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/stale_starved.nml"], code, out, err)
        call check(t, code == 2, "stale: the second run fails (exit 2)", err)
        call check(t, .not. exists(dir//"/hbm.csv") .and. .not. exists(dir//"/coefficients.csv") &
                   .and. .not. exists(dir//"/euler.csv"), &
                   "stale: the first run's results are removed")
        call check(t, summary_value(dir//"/summary.nml", "converged") == "F", &
                   "stale: the summary is the failed run's")
        call check(t, exists(dir//"/notes.txt") .and. exists(dir//"/frc.checkpoint"), &
                   "stale: other files and the checkpoint are kept")
        ! a run of another method: the hbm files go, euler.csv comes
        call cli([character(len=200) :: scratch//"/stale_good.nml"], code, out, err)
        call write_lines(scratch//"/stale_euler.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&run method = 'euler' /", &
            "&euler steps_per_period = 200 /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/stale_euler.nml"], code, out, err)
        call check(t, code == 0 .and. exists(dir//"/euler.csv") .and. &
                   .not. exists(dir//"/hbm.csv") .and. .not. exists(dir//"/coefficients.csv"), &
                   "stale: another method's results replace the first", err)
        call check(t, .not. exists(dir//"/"//lock_name), "stale: no lock left")
        ! an input error leaves the directory as it was
        call write_lines(scratch//"/stale_bad.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&run method = 'euler' /", &
            "&euler steps_per_period = -3 /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/stale_bad.nml"], code, out, err)
        call check(t, code == 1 .and. exists(dir//"/euler.csv"), &
                   "stale: an input error touches nothing", err)
    end subroutine test_stale_results

    !> The directory lock: a run is refused (exit 3, the message names the directory and the
    !> pid) while a live process holds the lock, and leaves it in place; a lock whose process
    !> is gone is taken over; the lock is removed at the end of a run, also a failed one.
    subroutine test_lock(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/out_lock"
        character(len=:), allocatable :: out, err
        character(len=24) :: pid
        character(len=48) :: lock_line
        integer :: code
        type(directory_lock_t) :: lock, other
        type(error_type), allocatable :: error
        call check(t, process_alive(process_id()), "lock: this process is alive")
        call check(t, .not. process_alive(999999999) .and. .not. process_alive(0) .and. &
                   .not. process_alive(-1), "lock: no process 999999999, 0 or -1")
        call make_directory(dir, error)
        write (pid, '(i0)') process_id()
        write (lock_line, '(i0,1x,i0)') process_id(), process_start_time(process_id())
        call write_lines(scratch//"/lock.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 10, samples = 128 /", &
            "&output directory = '"//dir//"' /"])
        call write_lines(dir//"/"//lock_name, [lock_line])
        call cli([character(len=200) :: scratch//"/lock.nml"], code, out, err)
        call check(t, code == 3 .and. index(err, "directory "//dir//" is being written by "// &
                   "another stickslip run (pid "//trim(pid)//")") > 0, &
                   "lock: a held directory is refused with exit 3", err)
        call check(t, .not. exists(dir//"/hbm.csv") .and. exists(dir//"/"//lock_name), &
                   "lock: the refused run writes nothing and keeps the lock")
        call write_lines(dir//"/"//lock_name, [character(len=24) :: "999999999"])
        call write_lines(dir//"/hbm.csv.999999999.1.tmp", [character(len=24) :: "t,x1"])
        call write_lines(dir//"/frc.checkpoint.999999999.1.tmp", [character(len=24) :: "x"])
        call cli([character(len=200) :: scratch//"/lock.nml"], code, out, err)
        call check(t, code == 0 .and. exists(dir//"/hbm.csv"), "lock: a stale lock is taken over", &
                   err)
        call check(t, .not. exists(dir//"/hbm.csv.999999999.1.tmp") .and. &
                   .not. exists(dir//"/frc.checkpoint.999999999.1.tmp"), &
                   "lock: the killed run's temporaries removed")
        call check(t, .not. exists(dir//"/"//lock_name), "lock: removed at the end")
        call write_lines(dir//"/"//lock_name, [character(len=24) :: "garbage"])
        call cli([character(len=200) :: scratch//"/lock.nml"], code, out, err)
        call check(t, code == 0, "lock: a damaged lock is taken over", err)
        ! a lock that is not a run's: a live process that did not write it (pid 1, a pid
        ! reused by another process: its start time differs) or a lock without the start
        ! time of its writer; none refuses the next run forever
        call write_lines(dir//"/"//lock_name, [character(len=24) :: "1"])
        call cli([character(len=200) :: scratch//"/lock.nml"], code, out, err)
        call check(t, code == 0, "lock: a lock naming a live unrelated pid is taken over", err)
        write (lock_line, '(i0,1x,i0)') process_id(), process_start_time(process_id()) + 7
        call write_lines(dir//"/"//lock_name, [lock_line])
        call cli([character(len=200) :: scratch//"/lock.nml"], code, out, err)
        call check(t, code == 0, "lock: a live pid with another start time is taken over", err)
        ! a failed run removes its lock too
        call write_lines(scratch//"/lock_starved.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 30, samples = 256, maxfev = 3, "// &
            "start = 'direct' /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/lock_starved.nml"], code, out, err)
        call check(t, code == 2 .and. .not. exists(dir//"/"//lock_name), &
                   "lock: removed after a failed run", err)
        ! in-process: a second taker is refused while the first holds it
        call acquire_lock(lock, dir, error)
        call check_error(t, error, "lock: acquired", .false.)
        call acquire_lock(other, dir, error)
        call check_error(t, error, "lock: a second taker is refused", .true., &
                         [character(len=40) :: "is being written by another"])
        call check(t, error%stat == stickslip_stat%io, "lock: refusal is an I/O error (exit 3)")
        call release_lock(other)
        call check(t, exists(dir//"/"//lock_name), "lock: releasing a lock not held does nothing")
        call release_lock(lock)
        call check(t, .not. exists(dir//"/"//lock_name), "lock: released")
        ! what the SIGINT/SIGTERM/SIGHUP handler of the program removes: this process's lock
        ! and temporaries in a registered directory, never another run's lock
        call register_output_directory(dir)
        call acquire_lock(lock, dir, error)
        write (pid, '(i0)') process_id()
        call write_lines(dir//"/hbm.csv."//trim(pid)//".2.tmp", [character(len=8) :: "t,x1"])
        call write_lines(dir//"/frc.checkpoint."//trim(pid)//".1.tmp", [character(len=8) :: "x"])
        call make_directory(dir//"/.stickslip.staging."//trim(pid), error)
        call write_lines(dir//"/.stickslip.staging."//trim(pid)//"/hbm.csv", &
                         [character(len=8) :: "t,x1"])
        call remove_own_files()
        call check(t, .not. exists(dir//"/.stickslip.staging."//trim(pid)//"/."), &
                   "lock: a signal removes this run's staging directory")
        call check(t, .not. exists(dir//"/"//lock_name) .and. &
                   .not. exists(dir//"/hbm.csv."//trim(pid)//".2.tmp") .and. &
                   .not. exists(dir//"/frc.checkpoint."//trim(pid)//".1.tmp"), &
                   "lock: a signal removes this run's lock and temporaries")
        call write_lines(dir//"/"//lock_name, [character(len=24) :: "1 24"])
        call remove_own_files()
        call check(t, exists(dir//"/"//lock_name), "lock: a signal keeps another run's lock")
        call remove_file(dir//"/"//lock_name)
    end subroutine test_lock

    !> Temporaries have unique names (two open at once for one file; a leftover of the
    !> first candidate name is skipped) and the last one renamed wins; none is left.
    subroutine test_unique_temporaries(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/out_temporaries"
        integer :: u1, u2, stat
        character(len=1000) :: n1, n2, line
        type(error_type), allocatable :: error
        call make_directory(dir, error)
        call write_lines(dir//"/a.csv."//itoa(process_id())//".1.tmp", &
                         [character(len=20) :: "leftover"])
        call open_temporary(dir, "a.csv", u1, error)
        call check_error(t, error, "temporaries: first opened", .false.)
        call open_temporary(dir, "a.csv", u2, error)
        call check_error(t, error, "temporaries: second opened", .false.)
        if (allocated(error)) return
        inquire (unit=u1, name=n1)
        inquire (unit=u2, name=n2)
        call check(t, n1 /= n2 .and. index(n1, ".1.tmp") == 0 .and. index(n2, ".1.tmp") == 0, &
                   "temporaries: unique names, the leftover skipped", trim(n1)//" "//trim(n2))
        write (u1, '(a)') "first"
        write (u2, '(a)') "second"
        call close_and_rename(dir, "a.csv", u1, 0, "", error)
        call close_and_rename(dir, "a.csv", u2, 0, "", error)
        call check_error(t, error, "temporaries: renamed", .false.)
        open (newunit=u1, file=dir//"/a.csv", status='old', action='read', iostat=stat)
        line = ""
        if (stat == 0) read (u1, '(a)', iostat=stat) line
        if (stat == 0) close (u1)
        call check(t, line == "second", "temporaries: the last renamed wins", trim(line))
        call check(t, .not. exists(trim(n1)) .and. .not. exists(trim(n2)), &
                   "temporaries: none left")
    end subroutine test_unique_temporaries

    !> Findings of a run: a warning is one `stickslip: warning:` line on stderr (exit 0), a
    !> distrust is `stickslip: error: the answer cannot be trusted:` and exit 2, the result
    !> still printed; summary.nml says trusted = T/F and lists the keys.
    subroutine test_findings(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/out_findings"
        type(case_t) :: c
        type(run_result_t) :: res
        type(error_type), allocatable :: error
        character(len=:), allocatable :: out, err, v
        integer :: code
        call write_lines(scratch//"/findings.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 30, samples = 256 /", &
            "&output directory = '"//dir//"' /"])
        call read_case(scratch//"/findings.nml", c, error)
        call check_error(t, error, "findings: case read", .false.)
        if (allocated(error)) return
        call run_method(c, res, error)
        call check_error(t, error, "findings: run", .false.)
        if (allocated(error)) return
        call check(t, res%method == 'hbm' .and. res%hbm%converged, "findings: hbm ran")
        call check(t, summary_value(dir//"/summary.nml", "trusted") == "T" .and. &
                   summary_value(dir//"/summary.nml", "warnings") == "''", &
                   "findings: summary trusted = T, warnings = ''", &
                   summary_value(dir//"/summary.nml", "warnings"))
        call res%diagnostics%add(level_note, 'sampling', 'a note for people')
        call res%diagnostics%add(level_warning, 'energy_balance', 'energy balance off by 5%')
        call report(code, out, err)
        call check(t, code == 0, "findings: a warning keeps exit 0")
        call check(t, err == "stickslip: warning: energy balance off by 5%"//new_line('a'), &
                   "findings: one warning line on stderr", err)
        call check(t, index(out, "  note: a note for people") > 0 .and. &
                   index(err, "note") == 0, "findings: notes on stdout", out)
        call res%diagnostics%add(level_untrusted, 'no_solution', 'no bounded periodic solution')
        call report(code, out, err)
        call check(t, code == 2, "findings: distrust gives exit 2")
        call check(t, index(err, "stickslip: error: the answer cannot be trusted: no "// &
                   "bounded periodic solution") > 0 .and. count_lines(err) == 2, &
                   "findings: the distrust line on stderr", err)
        call check(t, index(out, "converged") > 0, "findings: the result is still printed")
        ! the summary of such a result
        call write_summary(dir, c, res%hbm, error, res%checks, res%diagnostics)
        call check_error(t, error, "findings: summary written", .false.)
        call check(t, summary_value(dir//"/summary.nml", "trusted") == "F", &
                   "findings: summary trusted = F")
        v = summary_value(dir//"/summary.nml", "warnings")
        call check(t, v == "'energy_balance', 'no_solution'", "findings: summary warnings", v)
        v = summary_value(dir//"/summary.nml", "warning_energy_balance")
        call check(t, v == "'energy balance off by 5%'", "findings: warning_<key>", v)
        v = summary_value(dir//"/summary.nml", "untrusted_no_solution")
        call check(t, v == "'no bounded periodic solution'", "findings: untrusted_<key>", v)
        call read_case(dir//"/summary.nml", c, error)
        call check_error(t, error, "findings: the summary still reads back as the case", .false.)
    contains
        subroutine report(code, out, err)
            integer, intent(out) :: code
            character(len=:), allocatable, intent(out) :: out, err
            integer :: uo, ue
            type(error_type), allocatable :: none
            open (newunit=uo, status='scratch', action='readwrite')
            open (newunit=ue, status='scratch', action='readwrite')
            code = report_run(c, res, none, .false., uo, ue)
            out = slurp(uo)
            err = slurp(ue)
            close (uo)
            close (ue)
        end subroutine report
    end subroutine test_findings

    !> Progress: nothing before `delay`, then at most one line per `interval`; the CLI prints
    !> progress lines of a sweep on stderr (zero interval here), none with --quiet.
    subroutine test_progress(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/out_progress"
        type(progress_t) :: p
        integer :: u, k, code
        character(len=:), allocatable :: text, out, err
        character(len=400) :: case_lines(7)
        open (newunit=u, status='scratch', action='readwrite')
        p%unit = u
        p%label = 'sweep'
        p%delay = 0.0_dp
        p%interval = 0.0_dp
        call p%begin()
        do k = 1, 3
            call p%report(k, 3, "omega = 2")
        end do
        text = slurp(u)
        call check(t, p%lines == 3 .and. count_lines(text) == 3 .and. &
                   index(text, "stickslip: sweep 2/3 points, omega = 2, ") > 0 .and. &
                   index(text, " s"//new_line('a')) > 0, "progress: one line per report", text)
        close (u)
        open (newunit=u, status='scratch', action='readwrite')
        p = progress_t(unit=u, interval=1000.0_dp, delay=0.0_dp)
        call p%begin()
        do k = 1, 50
            call p%report(k, 0, "x")
        end do
        call check(t, p%lines == 1, "progress: at most one line per interval")
        p = progress_t(unit=u)
        call p%begin()
        do k = 1, 50
            call p%report(k, 0, "x")
        end do
        call check(t, p%lines == 0, "progress: a short run prints nothing")
        p = progress_t(interval=0.0_dp, delay=0.0_dp)
        call p%report(1, 1, "x")
        call check(t, p%lines == 0, "progress: off by default (unit -1)")
        close (u)
        call write_lines(scratch//"/progress.nml", [character(len=120) :: sweep_case, &
            "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/progress.nml"], code, out, err, &
                 progress_interval=0.0_dp)
        call check(t, code == 0 .and. count_substring(err, "stickslip: sweep ") >= 3 .and. &
                   index(err, " points, omega = ") > 0, "progress: the CLI's sweep lines", err)
        call cli([character(len=200) :: "--quiet", scratch//"/progress.nml"], code, out, err, &
                 progress_interval=0.0_dp)
        call check(t, code == 0 .and. index(err, "stickslip: sweep") == 0, &
                   "progress: none with --quiet", err)
        ! the reading of the Matrix Market files of a case (a second in the command line,
        ! no delay here)
        ! (the lines one by one: gfortran 12 corrupted the heap on a typed array
        ! constructor [character(len=200) :: ...] holding these longer concatenations)
        case_lines(1) = "&system mass_file = '"//project_path("examples/beam_mm/mass.mtx")//"',"
        case_lines(2) = "  stiffness_file = '"//project_path("examples/beam_mm/stiffness.mtx")// &
                        "' /"
        case_lines(3) = "&forcing omega = 40.0, force_dof = 77, force_amplitude = 5.0 /"
        case_lines(4) = "&friction contact_dof = 79, mu = 0.5, normal_load = 4.0 /"
        case_lines(5) = "&hbm harmonics = 5, odd_only = T, samples = 64 /"
        case_lines(6) = "&run method = 'hbm' /"
        case_lines(7) = "&output directory = '"//dir//"_mm' /"
        call write_lines(scratch//"/progress_mm.nml", case_lines)
        call cli([character(len=200) :: scratch//"/progress_mm.nml"], code, out, err, &
                 progress_interval=0.0_dp)
        call check(t, code == 0 .and. index(err, "stickslip: reading ") > 0 .and. &
                   index(err, "beam_mm/stiffness.mtx, ") > 0, &
                   "progress: the CLI's reading lines", err)
        call cli([character(len=200) :: "--quiet", scratch//"/progress_mm.nml"], code, out, &
                 err, progress_interval=0.0_dp)
        call check(t, code == 0 .and. index(err, "stickslip: reading") == 0, &
                   "progress: no reading lines with --quiet", err)
    end subroutine test_progress

    !> The output directory of the shell-injection report: no command runs (no PWNED file
    !> anywhere), the files and (when gnuplot exists) the pictures are in that directory.
    subroutine test_odd_directory(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/q'; touch PWNED; echo '"
        character(len=:), allocatable :: out, err
        integer :: code
        logical :: drawn
        call write_lines(scratch//"/odd_sweep.nml", [character(len=160) :: sweep_case, &
            '&output directory = "'//dir//'" /'])
        call cli([character(len=200) :: scratch//"/odd_sweep.nml"], code, out, err)
        call check(t, code == 0 .and. exists(dir//"/frc.csv"), "odd directory: sweep written", err)
        drawn = index(err, "pictures not drawn") == 0
        if (drawn) then
            call check(t, exists(dir//"/frc.png") .and. .not. exists(dir//"/frc.png.tmp"), &
                       "odd directory: frc.png drawn there")
        else
            call check(t, count_substring(err, "stickslip: warning: pictures not drawn") == 1, &
                       "odd directory: one warning without gnuplot", err)
        end if
        call write_lines(scratch//"/odd_robustness.nml", [character(len=160) :: &
            sweep_case(1:4), "&run method = 'robustness' /", &
            "&robustness omegas = 2.0, 4.5, mus = 0.45, harmonics = 5, rhos = 0.2, "// &
            "steps_per_period = 200 /", '&output directory = "'//dir//'" /'])
        call cli([character(len=200) :: scratch//"/odd_robustness.nml"], code, out, err)
        call check(t, code == 0 .and. exists(dir//"/robustness.csv") .and. &
                   .not. exists(dir//"/frc.csv"), "odd directory: robustness written", err)
        if (drawn) call check(t, exists(dir//"/robustness_cold.png") .and. &
                              exists(dir//"/robustness_warm.png"), &
                              "odd directory: the maps drawn there", err)
        call check(t, .not. (exists("PWNED") .or. exists(scratch//"/PWNED") .or. &
                   exists(dir//"/PWNED") .or. exists("build/PWNED")), &
                   "odd directory: no command ran (no PWNED)")
    end subroutine test_odd_directory

    logical function exists(path)
        character(len=*), intent(in) :: path
        inquire (file=path, exist=exists)
    end function exists

    integer function count_substring(s, sub) result(n)
        character(len=*), intent(in) :: s, sub
        integer :: k, start
        n = 0
        start = 1
        do
            k = index(s(start:), sub)
            if (k == 0) exit
            n = n + 1
            start = start + k + len(sub) - 1
            if (start > len(s)) exit
        end do
    end function count_substring

    !> Run the CLI in-process; return its exit code and what it wrote to each unit.
    subroutine cli(args, code, out, err, progress_interval)
        character(len=*), intent(in) :: args(:)
        integer, intent(out) :: code
        character(len=:), allocatable, intent(out) :: out, err
        real(dp), intent(in), optional :: progress_interval
        type(string_t), allocatable :: a(:)
        integer :: i, uo, ue
        allocate (a(size(args)))
        do i = 1, size(args)
            a(i)%s = trim(args(i))
        end do
        if (size(args) == 1) then
            if (len_trim(args(1)) == 0) deallocate (a)
            if (.not. allocated(a)) allocate (a(0))
        end if
        open (newunit=uo, status='scratch', action='readwrite')
        open (newunit=ue, status='scratch', action='readwrite')
        code = run_cli(a, uo, ue, progress_interval)
        out = slurp(uo)
        err = slurp(ue)
        close (uo)
        close (ue)
    end subroutine cli

    function slurp(u) result(text)
        integer, intent(in) :: u
        character(len=:), allocatable :: text
        character(len=1000) :: line
        integer :: stat
        text = ""
        rewind (u)
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            text = text//trim(line)//new_line('a')
        end do
    end function slurp

    !> A copy of examples/<example>.nml in the scratch area, <tag><flat name>.nml (tag
    !> default 'out_'; calculix_beam/case: calculix_beam_case): its output directory moved to
    !> the scratch directory <tag><flat name>, its matrix and direction files named by
    !> absolute paths.
    function scratch_copy(example, tag) result(copy)
        character(len=*), intent(in) :: example
        character(len=*), intent(in), optional :: tag
        character(len=:), allocatable :: copy, folder, name
        integer :: ui, uo, stat, a, b
        character(len=1000) :: line
        name = "out_"
        if (present(tag)) name = tag
        name = name//flat(example)
        copy = scratch//"/"//name//".nml"
        folder = ""
        if (index(example, "/", back=.true.) > 0) &
            folder = example(1:index(example, "/", back=.true.))
        open (newunit=ui, file=project_path("examples/"//example//".nml"), status='old', &
              action='read')
        open (newunit=uo, file=copy, status='replace', action='write')
        do
            read (ui, '(a)', iostat=stat) line
            if (stat /= 0) exit
            a = index(line, "directory = '")
            if (a > 0) then
                b = index(line(a + 13:), "'") + a + 12
                line = line(1:a + 12)//scratch//"/"//name//line(b:)
            end if
            a = index(line, "_file = '")
            if (a > 0) line = line(1:a + 8)//project_path("examples/"//folder)//line(a + 9:)
            write (uo, '(a)') trim(line)
        end do
        close (ui)
        close (uo)
    end function scratch_copy

    !> An example's name as one path component (calculix_beam/case: calculix_beam_case).
    pure function flat(name) result(f)
        character(len=*), intent(in) :: name
        character(len=len(name)) :: f
        integer :: j
        f = name
        do j = 1, len(f)
            if (f(j:j) == '/') f(j:j) = '_'
        end do
    end function flat

    !> The pictures of every example that draws (sweeps, families, backbones, the robustness
    !> maps, the CalculiX strip's curve and backbone, the CalculiX
    !> bladed-disk sector's curve and backbones per nodal diameter, the lumped bladed disks'
    !> underplatform-damper curve and shroud backbones; and the example gnuplot scripts of
    !> Figure 3 and the work-precision charts on the runs they draw), rendered by gnuplot as
    !> the command line runs them: each exists and is non-trivial (over 10 kB: a PNG of axes
    !> alone is about 6 kB). Skipped, saying so, where gnuplot is not installed (status 127).
    subroutine test_cli_figures(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 15
        character(len=24), parameter :: examples(n) = [character(len=24) :: "seed_frc", &
            "seed_modes", "degenerate_modes", "designer_damper", "damper_family", &
            "seed_robustness", "calculix_beam/case", "calculix_beam/modes", "seed", &
            "seed_study", "chain4_study", "calculix_sector/case", "calculix_sector/modes", &
            "bladed_disk_damper", "bladed_disk_modes"]
        ! the pictures of each, and the example script that draws them ('': the program)
        character(len=24), parameter :: pictures(2, n) = reshape([character(len=24) :: &
            "frc.png", "frc_dissipation.png", "modes.png", "", "modes.png", "", &
            "frc.png", "frc_dissipation.png", "frc_family.png", "family.png", &
            "robustness_cold.png", "robustness_warm.png", "frc.png", "frc_dissipation.png", &
            "modes.png", "", "figure3.png", "", "work_precision.png", "", &
            "work_precision.png", "", "frc.png", "frc_dissipation.png", "modes.png", "", &
            "frc.png", "frc_dissipation.png", "modes.png", ""], [2, n])
        character(len=24), parameter :: scripts(n) = [character(len=24) :: "", "", "", "", &
            "", "", "", "", "figure3.gp", "work_precision.gp", "work_precision.gp", "", "", &
            "", ""]
        character(len=:), allocatable :: out, err, dir
        character(len=200) :: path
        integer :: code, i, k, u
        integer(int64) :: bytes
        logical :: exists
        if (run_gnuplot(scratch, "no_such_script.gp") == 127) then
            write (output_unit, '(a)') "cli figures: gnuplot is not installed, the pictures "// &
                "are not tested"
            return
        end if
        do i = 1, n
            path = scratch_copy(trim(examples(i)), "fig_")
            dir = scratch//"/fig_"//flat(trim(examples(i)))
            call cli([character(len=200) :: path], code, out, err)
            call check(t, code == 0 .or. code == 2, "cli figures "//trim(examples(i))// &
                       ": ran", err)
            if (len_trim(scripts(i)) > 0) then
                ! the example script on this run: dir is the run's directory
                open (newunit=u, file=dir//"/draw.gp", status='replace', action='write')
                write (u, '(a)') "dir = '.'"
                write (u, '(a)') "load '"//project_path("examples/"//trim(scripts(i)))//"'"
                close (u)
                call check(t, run_gnuplot(dir, "draw.gp") == 0, "cli figures "// &
                           trim(examples(i))//": "//trim(scripts(i))//" ran")
            end if
            do k = 1, 2
                if (len_trim(pictures(k, i)) == 0) cycle
                inquire (file=dir//"/"//trim(pictures(k, i)), exist=exists, size=bytes)
                call check(t, exists .and. bytes > 10000_int64, "cli figures "// &
                           trim(examples(i))//": "//trim(pictures(k, i))//" drawn", &
                           itoa(int(bytes))//" bytes")
            end do
        end do

    end subroutine test_cli_figures

    !> The stability of a sector's travelling wave (examples/bladed_disk.nml with &hbm
    !> stability) says on stdout and in summary.nml that it is the assembled disk's, its
    !> exact flow over T / 8 by the wave's symmetry (24 sectors, EO 3); its contacts switch
    !> at one instant (sectors 8 apart in phase), so summary.nml has the growth of the
    !> perturbed flow that checked the verdict, equal to floquet_max to 1e-3.
    subroutine test_cli_sector_stability(t)
        type(test_counter_t), intent(inout) :: t
        integer :: code, ui, uo, stat
        real(dp) :: growth, fmax
        character(len=:), allocatable :: text
        character(len=:), allocatable :: out, err, path
        character(len=200) :: edited
        character(len=1000) :: line
        path = scratch_copy("bladed_disk", "stab_")
        ! fixed length: gfortran 12 overruns a deferred-length string in a typed constructor
        edited = scratch//"/stab_edited.nml"
        open (newunit=ui, file=path, status='old', action='read')
        open (newunit=uo, file=trim(edited), status='replace', action='write')
        do
            read (ui, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (index(line, "&hbm ") == 1) then
                write (uo, '(a)') "&hbm stability = .true.,"//trim(line(5:))
            else
                write (uo, '(a)') trim(line)
            end if
        end do
        close (ui)
        close (uo)
        call cli([character(len=200) :: edited], code, out, err)
        call check(t, code == 0 .and. index(out, "stability (the assembled 72-DOF disk's "// &
                   "Floquet multipliers: every perturbation") > 0 .and. &
                   summary_value(scratch//"/stab_bladed_disk/summary.nml", &
                                 "stability_scope") == "'disk'" .and. &
                   summary_value(scratch//"/stab_bladed_disk/summary.nml", &
                                 "stability_spans") == "8" .and. &
                   index(out, "its exact flow over T/8 by that symmetry") > 0, &
                   "cli sector stability: stdout and summary say it is the disk's", err)
        ! sectors 8 apart switch together: the perturbed flow's growth checks the verdict
        growth = -1.0_dp
        fmax = -2.0_dp
        text = summary_value(scratch//"/stab_bladed_disk/summary.nml", "stability_flow_growth")
        read (text, *, iostat=stat) growth
        text = summary_value(scratch//"/stab_bladed_disk/summary.nml", "floquet_max")
        read (text, *, iostat=stat) fmax
        call check(t, abs(growth - fmax) <= 1.0e-3_dp*fmax, &
                   "cli sector stability: summary's stability_flow_growth = floquet_max", &
                   "stability_flow_growth "//real_text(growth)//", floquet_max "// &
                   real_text(fmax))
        ! engine order 6: every shroud stuck, the disk at rest (the batch contract: exit 0,
        ! nothing on stderr, summary at_rest = T; the stuck ring's stability 'marginal')
        open (newunit=ui, file=trim(edited), status='old', action='read')
        open (newunit=uo, file=scratch//"/stab_rest.nml", status='replace', action='write')
        do
            read (ui, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (index(line, "engine_order = 3") > 0) line = line(1:index(line, &
                "engine_order = 3") - 1)//"engine_order = 6"//line(index(line, &
                "engine_order = 3") + 16:)
            write (uo, '(a)') trim(line)
        end do
        close (ui)
        close (uo)
        edited = scratch//"/stab_rest.nml"
        call cli([character(len=200) :: edited], code, out, err)
        call check(t, code == 0 .and. len_trim(err) == 0 .and. index(out, "at rest:") > 0 .and. &
                   summary_value(scratch//"/stab_bladed_disk/summary.nml", "at_rest") == "T" &
                   .and. summary_value(scratch//"/stab_bladed_disk/summary.nml", &
                                       "engine_order") == "6" .and. &
                   summary_value(scratch//"/stab_bladed_disk/summary.nml", "stability") == &
                   "'marginal'", &
                   "cli sector stability: EO 6, the disk at rest, trusted, exit 0", &
                   "exit "//itoa(code)//"; "//err)
    end subroutine test_cli_sector_stability

    subroutine test_cli_examples(t)
        type(test_counter_t), intent(inout) :: t
        integer :: code, i, nrows, u, stat
        character(len=:), allocatable :: out, err
        character(len=200) :: path, dir
        character(len=20), parameter :: examples(6) = [character(len=20) :: "seed", "mirrored", &
                                                        "chain4", "seed_euler", "many_sticks", &
                                                        "bladed_disk"]
        character(len=20) :: samples_file
        character(len=4000) :: line
        type(case_t) :: c
        type(error_type), allocatable :: error
        logical :: exists

        do i = 1, size(examples)
            path = scratch_copy(trim(examples(i)))
            dir = scratch//"/out_"//trim(examples(i))
            call cli([character(len=200) :: path], code, out, err)
            call check(t, code == 0, "cli example "//trim(examples(i))//": exit 0", err)
            samples_file = merge("euler.csv", "hbm.csv  ", examples(i) == "seed_euler")
            call check(t, index(out, "converged") > 0 .or. index(out, "periodic after") > 0, &
                       "cli example "//trim(examples(i))//": summary printed")
            open (newunit=u, file=trim(dir)//"/"//trim(samples_file), status='old', &
                  action='read', iostat=stat)
            call check(t, stat == 0, "cli example "//trim(examples(i))//": "// &
                       trim(samples_file)//" written")
            if (stat /= 0) cycle
            read (u, '(a)') line
            call read_case(trim(path), c, error)
            call check(t, trim(line) == expected_header(c%model%ndof, c%model%ncontact()), &
                       "cli example "//trim(examples(i))//": hbm.csv header", trim(line))
            nrows = 0
            do
                read (u, '(a)', iostat=stat) line
                if (stat /= 0) exit
                nrows = nrows + 1
            end do
            close (u)
            if (examples(i) == "seed_euler") then
                call check(t, nrows == c%euler%steps_per_period, "cli example "// &
                           trim(examples(i))//": one row per step of the last period")
                call check(t, summary_value(trim(dir)//"/summary.nml", "periodic") == "T", &
                           "cli example "//trim(examples(i))//": summary says periodic")
                cycle
            end if
            call check(t, nrows == c%hbm%samples, "cli example "//trim(examples(i))// &
                       ": one row per sample")
            inquire (file=trim(dir)//"/coefficients.csv", exist=exists)
            call check(t, exists, "cli example "//trim(examples(i))//": coefficients.csv written")
            inquire (file=trim(dir)//"/hbm.csv.tmp", exist=exists)
            call check(t, .not. exists, "cli example "//trim(examples(i))//": no temporary left")
            ! the summary is itself a case file holding the effective case
            call read_case(trim(dir)//"/summary.nml", c, error)
            call check_error(t, error, "cli example "//trim(examples(i))// &
                             ": summary.nml reads back as the case", .false.)
            call check(t, summary_value(trim(dir)//"/summary.nml", "converged") == "T", &
                       "cli example "//trim(examples(i))//": summary says converged")
        end do

        call cli([character(len=200) :: "--help"], code, out, err)
        call check(t, code == 0 .and. index(out, "usage") > 0, "cli --help")
        call cli([character(len=200) :: "--bogus", "x.nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "unknown option '--bogus'") > 0, &
                   "cli unknown option: exit 1", err)
        call cli([character(len=200) :: ""], code, out, err)
        call check(t, code == 1, "cli no case file: exit 1")
        call cli([character(len=200) :: scratch//"/no_such.nml"], code, out, err)
        call check(t, code == 3 .and. index(err, "no_such.nml") > 0, "cli missing file: exit 3", err)
        call write_lines(scratch//"/cli_negative_mu.nml", [character(len=120) :: good_system, &
            good_forcing, "&friction contact_dof = 2, mu = -0.2, normal_load = 1.0 /"])
        call cli([character(len=200) :: scratch//"/cli_negative_mu.nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "&friction mu(1)") > 0 .and. &
                   count_lines(err) == 1, "cli bad input: exit 1, one line naming the variable", err)
        ! a forcing harmonic outside the basis: rejected, naming the file
        call write_lines(scratch//"/bad_harmonic.nml", [character(len=120) :: good_system, &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 1.0, force_harmonic = 2 /", &
            good_friction, "&hbm harmonics = 9, odd_only = .true., samples = 64 /", &
            "&output directory = '"//scratch//"/out_bad' /"])
        call cli([character(len=200) :: scratch//"/bad_harmonic.nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "bad_harmonic.nml: &forcing force_harmonic(1)") &
                   > 0, "cli forcing harmonic outside the basis: exit 1", err)
        ! an undamped resonance: numerical failure, exit 2, no result files
        call write_lines(scratch//"/resonance.nml", [character(len=120) :: good_system, &
            "&forcing omega = 0.6180339887498949, force_dof = 1, force_amplitude = 1.0 /", &
            good_friction, "&hbm harmonics = 5, samples = 64 /", &
            "&output directory = '"//scratch//"/out_resonance' /"])
        call cli([character(len=200) :: scratch//"/resonance.nml"], code, out, err)
        call check(t, code == 2 .and. index(err, "singular") > 0, "cli undamped resonance: exit 2", &
                   err)
        inquire (file=scratch//"/out_resonance/hbm.csv", exist=exists)
        call check(t, .not. exists, "cli undamped resonance: no result written")
        ! a solve that cannot converge in the evaluations allowed: exit 2, summary only
        call write_lines(scratch//"/starved.nml", [character(len=120) :: good_system, &
            good_forcing, good_friction, "&hbm harmonics = 30, samples = 256, maxfev = 3, "// &
            "start = 'direct' /", "&output directory = '"//scratch//"/out_starved' /"])
        call cli([character(len=200) :: scratch//"/starved.nml"], code, out, err)
        call check(t, code == 2 .and. index(err, "not converged") > 0, &
                   "cli non-converged: exit 2 with diagnosis", err)
        inquire (file=scratch//"/out_starved/hbm.csv", exist=exists)
        call check(t, .not. exists, "cli non-converged: no hbm.csv")
        call check(t, summary_value(scratch//"/out_starved/summary.nml", "converged") == "F", &
                   "cli non-converged: summary says converged = F")
    end subroutine test_cli_examples

    !> &run method = 'reference', 'all' and 'study' end to end: the files, their rows and
    !> headers, the summary fields, and the differences recomputed from the CSV files.
    subroutine test_methods_cli(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/out_methods"
        character(len=120) :: base(4)
        character(len=:), allocatable :: out, err, v
        integer :: code, nrows, nev, u, stat, k
        real(dp), allocatable :: eu(:, :), rf(:, :)
        real(dp) :: summary_err(5), e1, amp
        type(case_t) :: c
        type(error_type), allocatable :: error
        logical :: ok
        character(len=400) :: line
        character(len=16) :: kind
        character(len=24), parameter :: cpu_keys(3) = [character(len=24) :: "hbm_cpu_seconds", &
                                                       "euler_cpu_seconds", "reference_cpu_seconds"]

        base = [character(len=120) :: good_system, good_forcing, good_friction, &
                "&hbm harmonics = 20, samples = 256 /"]
        ! all three methods; the reference sampled on the Euler grid so that the CSV files
        ! give the Euler-vs-reference difference independently of the comparison code
        call write_lines(scratch//"/all.nml", [character(len=120) :: base, &
            "&run method = 'all' /", "&euler steps_per_period = 400 /", &
            "&reference samples = 400 /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/all.nml"], code, out, err)
        call check(t, code == 0, "method all: exit 0", err)
        call check(t, index(out, "euler vs reference") > 0 .and. &
                   index(out, "hbm vs reference") > 0, "method all: differences printed", out)
        call check(t, csv_rows(dir//"/hbm.csv") == 256, "method all: hbm.csv rows")
        call check(t, csv_rows(dir//"/euler.csv") == 400, "method all: euler.csv rows")
        call check(t, csv_rows(dir//"/reference.csv") == 400, "method all: reference.csv rows")
        call check(t, first_line(dir//"/reference.csv") == expected_header(2, 1), &
                   "method all: reference.csv header")
        call check(t, first_line(dir//"/events.csv") == "t,contact,kind,direction,force,velocity", &
                   "method all: events.csv header")
        ! events: at least one stick and one slip per period, kinds from the documented set
        nev = 0
        ok = .true.
        open (newunit=u, file=dir//"/events.csv", status='old', action='read', iostat=stat)
        if (stat == 0) then
            read (u, '(a)') line
            do
                read (u, '(a)', iostat=stat) line
                if (stat /= 0) exit
                nev = nev + 1
                kind = line(index(line, ",1,") + 3:)
                kind = kind(1:index(kind, ",") - 1)
                ok = ok .and. any(kind == [character(len=16) :: "stick", "slip", "reversal", &
                                           "graze"])
            end do
            close (u)
        end if
        call check(t, nev >= 2 .and. ok, "method all: events.csv holds valid events")
        v = summary_value(dir//"/summary.nml", "method")
        call check(t, v == "'all'", "method all: summary method", v)
        do k = 1, 3
            v = summary_value(dir//"/summary.nml", trim(cpu_keys(k)))
            read (v, *, iostat=stat) e1
            call check(t, stat == 0 .and. e1 > 0.0_dp, "method all: "//trim(cpu_keys(k)), v)
        end do
        call check(t, summary_value(dir//"/summary.nml", "grid") == "400", "method all: grid")
        call check(t, summary_value(dir//"/summary.nml", "quantities") == &
                   "'x1', 'x2', 'v1', 'v2', 'r1'", "method all: quantities")
        v = summary_value(dir//"/summary.nml", "euler_vs_reference_max")
        read (v, *, iostat=stat) summary_err
        call check(t, stat == 0, "method all: euler_vs_reference_max has 5 values", v)
        ! the x1 difference recomputed from euler.csv and reference.csv
        eu = read_csv(dir//"/euler.csv", 400, 6)
        rf = read_csv(dir//"/reference.csv", 400, 6)
        if (size(eu, 1) == 400 .and. size(rf, 1) == 400) then
            call check_close(t, maxval(abs(rf(:, 1) - eu(:, 1))), 0.0_dp, &
                             "method all: euler.csv and reference.csv on the same instants", &
                             atol=1.0e-12_dp)
            amp = maxval(abs(rf(:, 2)))
            e1 = maxval(abs(eu(:, 2) - rf(:, 2)))/amp
            call check_close(t, summary_err(1), e1, "method all: x1 difference from the CSVs", &
                             rtol=1.0e-9_dp)
            ! first order at 400 steps: a visible but small difference
            call check(t, e1 > 1.0e-4_dp .and. e1 < 0.2_dp, "method all: Euler error plausible")
        else
            call check(t, .false., "method all: CSV files readable")
        end if
        v = summary_value(dir//"/summary.nml", "hbm_vs_reference_rms")
        call check(t, len(v) > 0, "method all: hbm_vs_reference_rms present")
        v = summary_value(dir//"/summary.nml", "hbm_vs_euler_max")
        call check(t, len(v) > 0, "method all: hbm_vs_euler_max present")
        call read_case(dir//"/summary.nml", c, error)
        call check_error(t, error, "method all: summary.nml reads back as the case", .false.)
        if (.not. allocated(error)) call check(t, c%method == 'all' .and. &
                                               c%reference%samples == 400, &
                                               "method all: effective case echoed")

        ! the reference alone
        call write_lines(scratch//"/ref.nml", [character(len=120) :: base, &
            "&run method = 'reference' /", "&reference samples = 300 /", &
            "&output directory = '"//scratch//"/out_ref' /"])
        call cli([character(len=200) :: scratch//"/ref.nml"], code, out, err)
        call check(t, code == 0, "method reference: exit 0", err)
        call check(t, csv_rows(scratch//"/out_ref/reference.csv") == 300, &
                   "method reference: reference.csv rows")
        call check(t, summary_value(scratch//"/out_ref/summary.nml", "converged") == "T", &
                   "method reference: summary converged")
        v = summary_value(scratch//"/out_ref/summary.nml", "energy_balance_error")
        read (v, *, iostat=stat) e1
        call check(t, stat == 0 .and. e1 < 1.0e-9_dp, "method reference: energy balance", v)

        ! a small study
        call write_lines(scratch//"/study.nml", [character(len=120) :: base, &
            "&run method = 'study' /", "&study harmonics = 5, 20, samples = 0, " // &
            "steps_per_period = 200, 400, repeats = 1 /", &
            "&output directory = '"//scratch//"/out_study' /"])
        call cli([character(len=200) :: scratch//"/study.nml"], code, out, err)
        call check(t, code == 0, "method study: exit 0", err)
        call check(t, csv_rows(scratch//"/out_study/study.csv") == 4, "method study: 4 rows")
        call check(t, first_line(scratch//"/out_study/study.csv") == &
                   "method,parameter,samples,converged,cpu_seconds,repeats,iterations,"// &
                   "err_x,err_v,err_r,rms_x,rms_v,rms_r,err_x1,err_x2,err_v1,err_v2,err_r1", &
                   "method study: study.csv header")
        call check(t, summary_value(scratch//"/out_study/summary.nml", "rows") == "4", &
                   "method study: summary rows")
        block
            real(dp) :: ex(4)
            character(len=8) :: m(4)
            integer :: p(4), i
            open (newunit=u, file=scratch//"/out_study/study.csv", status='old', &
                  action='read', iostat=stat)
            if (stat /= 0) return
            read (u, '(a)') line
            do i = 1, 4
                read (u, '(a)') line
                call split_row(line, m(i), p(i), ex(i))
            end do
            close (u)
            call check(t, all(m == [character(len=8) :: "hbm", "hbm", "euler", "euler"]) .and. &
                       all(p == [5, 20, 200, 400]), "method study: row order and parameters")
            call check(t, ex(2) < ex(1), "method study: more harmonics, smaller error")
            call check(t, ex(4)/ex(3) > 0.4_dp .and. ex(4)/ex(3) < 0.6_dp, &
                       "method study: Euler error halves with the step (first order)")
        end block
    end subroutine test_methods_cli

    !> method, parameter and err_x (the 8th field) of a study.csv row.
    subroutine split_row(line, method, parameter, err_x)
        character(len=*), intent(in) :: line
        character(len=*), intent(out) :: method
        integer, intent(out) :: parameter
        real(dp), intent(out) :: err_x
        character(len=64) :: f(8)
        integer :: i, k, start
        start = 1
        do i = 1, 8
            k = index(line(start:), ",")
            f(i) = line(start:start + k - 2)
            start = start + k
        end do
        method = f(1)
        read (f(2), *) parameter
        read (f(8), *) err_x
    end subroutine split_row

    !> Data rows of a CSV file (-1 if it cannot be opened).
    integer function csv_rows(path)
        character(len=*), intent(in) :: path
        integer :: u, stat
        character(len=10) :: line
        csv_rows = -1
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        csv_rows = 0
        read (u, '(a)', iostat=stat) line
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            csv_rows = csv_rows + 1
        end do
        close (u)
    end function csv_rows


    !> The numeric rows of a CSV file with a header: rows x cols (0 rows on failure).
    function read_csv(path, rows, cols) result(a)
        character(len=*), intent(in) :: path
        integer, intent(in) :: rows, cols
        real(dp), allocatable :: a(:, :)
        integer :: u, stat, k
        allocate (a(rows, cols))
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat == 0) read (u, '(a)', iostat=stat)
        do k = 1, rows
            if (stat /= 0) exit
            read (u, *, iostat=stat) a(k, :)
        end do
        if (stat /= 0) deallocate (a)
        if (stat /= 0) allocate (a(0, cols))
        close (u)
    end function read_csv

    function expected_header(n, nc) result(h)
        integer, intent(in) :: n, nc
        character(len=:), allocatable :: h
        integer :: i
        character(len=12) :: b
        h = "t"
        do i = 1, n
            write (b, '(i0)') i
            h = h//",x"//trim(b)
        end do
        do i = 1, n
            write (b, '(i0)') i
            h = h//",v"//trim(b)
        end do
        do i = 1, nc
            write (b, '(i0)') i
            h = h//",r"//trim(b)
        end do
    end function expected_header

    integer function count_lines(s)
        character(len=*), intent(in) :: s
        integer :: i
        count_lines = 0
        do i = 1, len(s)
            if (s(i:i) == new_line('a')) count_lines = count_lines + 1
        end do
    end function count_lines

    !> The value of `key` in a summary.nml (text after "key = "), '' if absent.
    function summary_value(path, key) result(v)
        character(len=*), intent(in) :: path, key
        character(len=:), allocatable :: v
        character(len=1000) :: line
        integer :: u, stat, k
        v = ""
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            k = index(line, " "//key//" = ")
            if (k > 0) then
                v = trim(adjustl(line(k + len(key) + 4:)))
                exit
            end if
        end do
        close (u)
    end function summary_value
end module test_cli
