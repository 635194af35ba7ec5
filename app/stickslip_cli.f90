!> The command line: `stickslip CASE.nml [CASE.nml ...] [--quiet] [--help] [--version]`
!> (several case files: a multi-case run, run_cases). Parsing and the
!> whole run take the arguments as an array and write to units the caller gives, so tests run
!> them in-process. Part of the program (app/), not of the library: it turns errors and
!> findings into exit codes and stderr lines, prints progress, and draws the pictures
!> (stickslip_gnuplot, the only code that starts a process).
module stickslip_cli
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp
    use stickslip_version_info, only: stickslip_version
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, exit_code_of, itoa
    use stickslip_diagnostics, only: diagnostics_t, level_note, level_warning, level_untrusted
    use stickslip_progress, only: progress_t
    use stickslip_case, only: case_t, read_case
    use stickslip_case_reduction, only: write_reduction_cache_of
    use stickslip_solution, only: hbm_solution_t
    use stickslip_driver, only: run_result_t, run_method
    use stickslip_robustness, only: robustness_row_t
    use stickslip_sweep, only: sweep_result_t
    use stickslip_sweep_family, only: family_result_t
    use stickslip_checks, only: hbm_checks_t, sampling_notes
    use stickslip_euler, only: euler_result_t
    use stickslip_reference, only: reference_result_t
    use stickslip_side_by_side, only: side_by_side_t
    use stickslip_study, only: study_result_t
    use stickslip_modes, only: modes_result_t
    use stickslip_compare, only: comparison_t
    use stickslip_flow, only: event_name
    use stickslip_contact_set, only: contact_set_t
    use stickslip_contact_law, only: state_open, state_slip
    use stickslip_summary, only: energy_balance_error, reference_balance_error, sector_stability
    use stickslip_wave_symmetry, only: wave_symmetry_t, stability_spans
    use stickslip_gnuplot, only: run_gnuplot, rename_pictures
    use stickslip_files, only: remove_file
    use stickslip_blas_threads, only: limit_blas_threads, parallel_threads, blas_library
    use stickslip_signals, only: register_output_directory
    !$ use omp_lib, only: omp_get_max_threads
    implicit none
    private
    public :: string_t, cli_options_t, parse_args, run_cli, report_run, stderr_line, &
        with_exponent_e


    !> A string, for arrays of arguments of different lengths.
    type :: string_t
        character(len=:), allocatable :: s
    end type string_t

    !> What the command line asked for.
    type :: cli_options_t
        !> Case file path (the first when several are given).
        character(len=:), allocatable :: case_path
        !> Every case file path, in the order given (several: a multi-case run).
        type(string_t), allocatable :: case_paths(:)
        !> No summary on standard output.
        logical :: quiet = .false.
        !> Print usage and exit.
        logical :: help = .false.
        !> Print the version and exit.
        logical :: version = .false.
    end type cli_options_t

    !> A line of the human summary before emit writes it (one per thread: the cases of a
    !> multi-case run print their summaries at the same time).
    character(len=2000) :: buffer = ''
    !$omp threadprivate(buffer)

    character(len=*), parameter :: usage = &
        "usage: stickslip CASE.nml [CASE.nml ...] [--quiet] [--help] [--version]"// &
        new_line('a')// &
        "  Periodic response of a structure with Coulomb friction contacts by the"//new_line('a')// &
        "  weighted-residual (harmonic balance) method, implicit Euler or the exact"//new_line('a')// &
        "  event-driven reference (&run method = 'hbm', 'euler', 'reference', 'all',"// &
        new_line('a')//"  'study', 'sweep', 'robustness' or 'modes': nonlinear modes)."// &
        new_line('a')//"  Results go to &output directory:"// &
        new_line('a')//"  hbm.csv, coefficients.csv, euler.csv, reference.csv, events.csv,"// &
        new_line('a')//"  study.csv, frc.csv (+ frc_harmonics.csv, frc.gp, frc.png,"// &
        new_line('a')//"  frc_dissipation.png), robustness.csv (+ maps), modes.csv (+"// &
        new_line('a')//"  modes_harmonics.csv, modes.gp, modes.png),"// &
        new_line('a')//"  summary.nml. Warnings, errors and progress go to standard error;"// &
        new_line('a')//"  --quiet: no summary and no progress. Several case files run in"// &
        new_line('a')//"  parallel (OMP_NUM_THREADS), their output printed case by case;"// &
        new_line('a')//"  the exit code is the largest of theirs."// &
        new_line('a')// &
        "  Exit codes: 0 ok (also with warnings), 1 usage or input error, 2 numerical"// &
        new_line('a')//"  failure or an answer that cannot be trusted, 3 I/O error (or the"// &
        new_line('a')//"  directory is being written by another run)."



contains

    !> Parse the arguments (`--` ends the options: what follows are case files). Errors
    !> (stat input): an unknown option, no case file.
    subroutine parse_args(args, opts, error)
        !> The arguments (without the program name).
        type(string_t), intent(in) :: args(:)
        !> What they ask for.
        type(cli_options_t), intent(out) :: opts
        !> Set on a usage error.
        type(error_type), allocatable, intent(out) :: error
        integer :: i
        logical :: options_end
        options_end = .false.
        allocate (opts%case_paths(0))
        do i = 1, size(args)
            if (options_end) then
                ! after "--" every argument is a file name (a case file named "-x.nml")
                opts%case_paths = [opts%case_paths, args(i)]
                cycle
            end if
            select case (args(i)%s)
            case ("--")
                options_end = .true.
            case ("--quiet", "-q")
                opts%quiet = .true.
            case ("--help", "-h")
                opts%help = .true.
            case ("--version")
                opts%version = .true.
            case default
                if (len(args(i)%s) > 0) then
                    if (args(i)%s(1:1) == "-") then
                        call fatal_error(error, "unknown option '"//args(i)%s//"'"// &
                                         new_line('a')//usage, stickslip_stat%input)
                        return
                    end if
                end if
                opts%case_paths = [opts%case_paths, args(i)]
            end select
        end do
        if (size(opts%case_paths) > 0) opts%case_path = opts%case_paths(1)%s
        if (.not. (opts%help .or. opts%version .or. allocated(opts%case_path))) then
            call fatal_error(error, "no case file given"//new_line('a')//usage, &
                             stickslip_stat%input)
        end if
    end subroutine parse_args

    !> Everything the program does: parse, read the case, run its method (stickslip_driver),
    !> draw the pictures, print a short summary on `out_unit` (unless --quiet), and on
    !> `err_unit` one line per warning (`stickslip: warning: ...`), the distrust of the
    !> answer (`stickslip: error: the answer cannot be trusted: ...`), errors, and the
    !> progress of a long sweep, study or robustness study, and of the reading of large
    !> Matrix Market files (after a second; unless --quiet). Returns the exit
    !> code: 0 ok (warnings included), 1 usage or input error, 2 numerical failure (not
    !> converged, singular dynamic stiffness) or an answer that cannot be trusted (its files
    !> are written), 3 I/O error (including a directory another run is writing).
    integer function run_cli(args, out_unit, err_unit, progress_interval) result(code)
        !> The arguments (without the program name).
        type(string_t), intent(in) :: args(:)
        !> Unit for the human summary.
        integer, intent(in) :: out_unit
        !> Unit for warnings, errors and progress.
        integer, intent(in) :: err_unit
        !> Seconds before the first progress line and between two (default 2 and 1 s; 1
        !> and 1 s for the reading of matrix files).
        real(dp), intent(in), optional :: progress_interval
        type(cli_options_t) :: opts
        type(error_type), allocatable :: error
        type(case_t) :: case
        type(run_result_t) :: result
        type(progress_t) :: progress, reading
        integer :: k

        code = 0
        call limit_blas_threads()
        call parse_args(args, opts, error)
        if (.not. allocated(error)) then
            if (opts%help) then
                write (out_unit, '(a)') usage
                return
            end if
            if (opts%version) then
                write (out_unit, '(a)') "stickslip "//stickslip_version
                write (out_unit, '(a)') "BLAS/LAPACK: "//blas_library()
                return
            end if
            if (size(opts%case_paths) > 1) then
                call note_serial_blas(err_unit)
                code = run_cases(opts%case_paths, opts%quiet, out_unit, err_unit)
                return
            end if
            ! a long read of large matrix files reports its progress after about a second,
            ! and the phases of a reduction that take a second or more as they finish
            if (.not. opts%quiet) reading%unit = err_unit
            reading%delay = 1.0_dp
            reading%interval = 1.0_dp
            if (present(progress_interval)) then
                reading%delay = progress_interval
                reading%interval = progress_interval
            end if
            call read_case(opts%case_path, case, error, reading)
            if (.not. allocated(error)) then
                call register_output_directory(case%directory)
                ! a model reduced for this run goes to the reduction cache
                call write_reduction_cache_of(case%reduction, reading)
            end if
        end if
        if (allocated(error)) then
            ! a usage error carries the usage text (our own, several lines) after its message
            k = index(error%message, new_line('a')//usage)
            if (k > 0) then
                write (err_unit, '(a)') stderr_line("stickslip: error: "//error%message(1:k - 1))
                write (err_unit, '(a)') usage
            else
                write (err_unit, '(a)') stderr_line("stickslip: error: "//error%message)
            end if
            code = exit_code_of(error%stat)
            return
        end if
        if (.not. opts%quiet) progress%unit = err_unit
        if (present(progress_interval)) then
            progress%delay = progress_interval
            progress%interval = progress_interval
        end if
        progress%label = trim(case%method)
        if (case%method == 'study' .or. case%method == 'robustness') &
            call note_serial_blas(err_unit)
        call progress%begin()
        call run_method(case, result, error, progress)
        code = report_run(case, result, error, opts%quiet, out_unit, err_unit)
    end function run_cli

    !> A `stickslip: note:` line on `err_unit` when OMP_NUM_THREADS asks for several threads
    !> but the linked BLAS is not safe from several threads at once (OpenBLAS's serial
    !> build), so that the parallel loops run on one thread (parallel_threads); nothing
    !> otherwise.
    subroutine note_serial_blas(err_unit)
        !> Unit for the note.
        integer, intent(in) :: err_unit
        integer :: wanted
        character(len=12) :: buf
        wanted = 1
        !$ wanted = omp_get_max_threads()
        if (wanted <= 1 .or. parallel_threads() == wanted) return
        write (buf, '(i0)') wanted
        write (err_unit, '(a)') "stickslip: note: running on 1 thread instead of "//trim(buf)// &
            ": the linked BLAS/LAPACK, "//blas_library()//", gives wrong answers when "// &
            "called from several threads at once (install libopenblas0-pthread; "// &
            "doc/library.md, 'BLAS/LAPACK')"
    end subroutine note_serial_blas

    !> A multi-case run: every case of `paths` read and run as `stickslip <path>` would, the
    !> cases in parallel when built with OpenMP (OMP_NUM_THREADS threads, one case per thread
    !> at a time; each writes its own &output directory). The output of each case is kept
    !> apart and printed after all ran, in the order of `paths`: on `out_unit` (unless
    !> `quiet`) a line `== <path>` and the case's summary; on `err_unit` the case's lines,
    !> each prefixed by `<path>: `. No progress lines. Returns the largest exit code of the
    !> cases (0 ok, 1 input, 2 numerical or untrusted, 3 I/O).
    integer function run_cases(paths, quiet, out_unit, err_unit) result(code)
        !> The case files.
        type(string_t), intent(in) :: paths(:)
        !> No summaries.
        logical, intent(in) :: quiet
        !> Unit for the summaries.
        integer, intent(in) :: out_unit
        !> Unit for warnings and errors.
        integer, intent(in) :: err_unit
        type(string_t), allocatable :: outs(:), errs(:)
        integer, allocatable :: codes(:)
        integer :: i, j, k
        integer :: nthreads
        allocate (outs(size(paths)), errs(size(paths)), codes(size(paths)))
        nthreads = parallel_threads()
        !$omp parallel do schedule(dynamic, 1) default(shared) private(i) num_threads(nthreads)
        do i = 1, size(paths)
            call run_buffered(paths(i)%s, quiet, codes(i), outs(i)%s, errs(i)%s)
        end do
        !$omp end parallel do
        do i = 1, size(paths)
            if (.not. quiet) write (out_unit, '(a)') stderr_line("== "//paths(i)%s)
            if (len(outs(i)%s) > 0) write (out_unit, '(a)', advance='no') outs(i)%s
            ! every line of the case's standard error, prefixed by its path
            j = 1
            do while (j <= len(errs(i)%s))
                k = index(errs(i)%s(j:), new_line('a'))
                if (k == 0) k = len(errs(i)%s) - j + 2
                write (err_unit, '(a)') stderr_line(paths(i)%s)//": "//errs(i)%s(j:j + k - 2)
                j = j + k
            end do
        end do
        code = maxval(codes)
    end function run_cases

    !> One case of a multi-case run, its summary and its standard-error lines written to
    !> scratch files and returned as text (lines ended by new_line).
    subroutine run_buffered(path, quiet, code, out, err)
        character(len=*), intent(in) :: path
        logical, intent(in) :: quiet
        integer, intent(out) :: code
        character(len=:), allocatable, intent(out) :: out, err
        type(error_type), allocatable :: error
        type(case_t) :: case
        type(run_result_t) :: result
        type(progress_t) :: progress
        integer :: uo, ue
        open (newunit=uo, status='scratch', action='readwrite', form='formatted')
        open (newunit=ue, status='scratch', action='readwrite', form='formatted')
        call read_case(path, case, error)
        if (allocated(error)) then
            write (ue, '(a)') stderr_line("stickslip: error: "//error%message)
            code = exit_code_of(error%stat)
        else
            call register_output_directory(case%directory)
            call write_reduction_cache_of(case%reduction)
            progress%label = trim(case%method)
            call run_method(case, result, error, progress)
            code = report_run(case, result, error, quiet, uo, ue)
        end if
        out = slurp(uo)
        err = slurp(ue)
        close (uo)
        close (ue)
    end subroutine run_buffered

    !> Every line of the scratch file on unit `u`, each ended by new_line.
    function slurp(u) result(text)
        integer, intent(in) :: u
        character(len=:), allocatable :: text
        character(len=1024) :: chunk
        integer :: stat, n
        text = ""
        rewind (u)
        do
            read (u, '(a)', advance='no', iostat=stat, size=n) chunk
            if (is_iostat_end(stat)) exit
            text = text//chunk(1:n)
            if (is_iostat_eor(stat)) text = text//new_line('a')
            if (stat > 0) exit
        end do
    end function slurp

    !> After the method of `case` ran (run_method): draw its pictures, write one line on
    !> `err_unit` per warning and per distrust of the answer, then the error if any (and
    !> where its summary is), or else (unless `quiet`) the human summary on `out_unit`.
    !> Returns the exit code: that of the error; else 2 when a finding says the answer
    !> cannot be trusted; else 0.
    integer function report_run(case, result, error, quiet, out_unit, err_unit) result(code)
        !> The case that ran.
        type(case_t), intent(in) :: case
        !> What its method produced.
        type(run_result_t), intent(in) :: result
        !> The error of the run, if any.
        type(error_type), allocatable, intent(in) :: error
        !> No human summary.
        logical, intent(in) :: quiet
        !> Unit for the human summary.
        integer, intent(in) :: out_unit
        !> Unit for warnings and errors.
        integer, intent(in) :: err_unit
        code = 0
        call draw_pictures(case, result, error, err_unit)
        if (allocated(error)) then
            ! an input error stops the run before any answer: nothing to report about one
            if (error%stat /= stickslip_stat%input) &
                call report_findings(result%diagnostics, err_unit, code, error%message)
        else
            call report_findings(result%diagnostics, err_unit, code)
        end if
        if (allocated(error)) then
            write (err_unit, '(a)') stderr_line("stickslip: error: "//error%message)
            code = exit_code_of(error%stat)
            if (error%stat == stickslip_stat%numerical .and. allocated(case%directory) .and. &
                result%summary_written) write (err_unit, '(a)') stderr_line( &
                "stickslip: the summary was written to "//case%directory//"/summary.nml")
            return
        end if
        if (.not. quiet) then
            select case (result%method)
            case ('euler')
                call print_euler_summary(out_unit, case, result%euler)
            case ('reference')
                call print_reference_summary(out_unit, case, result%reference)
            case ('all')
                call print_side_by_side_summary(out_unit, case, result%side_by_side)
            case ('study')
                call print_study_summary(out_unit, case, result%study)
            case ('sweep')
                if (allocated(result%family%values)) then
                    call print_family_summary(out_unit, case, result%family, result%sweep)
                else
                    call print_sweep_summary(out_unit, case, result%sweep)
                end if
            case ('robustness')
                call print_robustness_summary(out_unit, case, result%robustness)
            case ('modes')
                call print_modes_summary(out_unit, case, result%modes)
            case default
                call print_summary(out_unit, case, result%hbm, result%checks)
            end select
            call print_notes(out_unit, result)
        end if
    end function report_run

    !> One line on `u` per warning (`stickslip: warning: <message>`) and per finding that
    !> the answer cannot be trusted (`stickslip: error: the answer cannot be trusted:
    !> <message>`, exit code 2). A distrust whose message the run's error already says
    !> (`said`: a solve that did not converge) is not printed twice.
    subroutine report_findings(found, u, code, said)
        type(diagnostics_t), intent(in) :: found
        integer, intent(in) :: u
        integer, intent(inout) :: code
        character(len=*), intent(in), optional :: said
        integer :: k
        if (.not. allocated(found%items)) return
        do k = 1, size(found%items)
            if (found%items(k)%level == level_warning) write (u, '(a)') &
                stderr_line("stickslip: warning: "//found%items(k)%message)
        end do
        do k = 1, size(found%items)
            if (found%items(k)%level >= level_untrusted) then
                code = 2
                if (present(said)) then
                    if (index(said, found%items(k)%message) > 0) cycle
                end if
                write (u, '(a)') stderr_line("stickslip: error: the answer cannot be "// &
                    "trusted: "//found%items(k)%message)
            end if
        end do
    end subroutine report_findings

    !> The notes among the findings that the method's summary has not printed already.
    subroutine print_notes(u, result)
        integer, intent(in) :: u
        type(run_result_t), intent(in) :: result
        character(len=:), allocatable :: printed
        integer :: k
        if (.not. allocated(result%diagnostics%items)) return
        printed = ""
        if (allocated(result%checks%notes)) printed = printed//result%checks%notes
        if (allocated(result%sweep%notes)) printed = printed//result%sweep%notes
        do k = 1, size(result%diagnostics%items)
            associate (item => result%diagnostics%items(k))
                if (item%level /= level_note) cycle
                if (len(item%message) == 0) cycle
                if (index(printed, item%message) > 0) cycle
                write (u, '(a)') "  note: "//item%message
            end associate
        end do
    end subroutine print_notes

    !> Draw the pictures whose scripts the run wrote: frc.png of a sweep (&sweep plot, more
    !> than one point, also of a curve that stopped early) and the robustness maps.
    subroutine draw_pictures(case, result, error, err_unit)
        type(case_t), intent(in) :: case
        type(run_result_t), intent(in) :: result
        type(error_type), allocatable, intent(in) :: error
        integer, intent(in) :: err_unit
        select case (result%method)
        case ('sweep')
            if (.not. (case%sweep%plot .and. result%sweep%npoints > 1)) return
            if (allocated(error)) then
                if (error%stat /= stickslip_stat%numerical) return
            end if
            if (allocated(result%family%values)) then
                call draw(case%directory, "family.gp", &
                          [character(len=20) :: "frc_family.png", "family.png"], err_unit)
            else
                call draw(case%directory, "frc.gp", &
                          [character(len=20) :: "frc.png", "frc_dissipation.png"], err_unit)
            end if
        case ('modes')
            if (.not. (case%modes%plot .and. result%modes%npoints > 1)) return
            if (allocated(error)) then
                if (error%stat /= stickslip_stat%numerical) return
            end if
            call draw(case%directory, "modes.gp", [character(len=20) :: "modes.png"], err_unit)
        case ('robustness')
            if (allocated(error)) return
            call draw(case%directory, "robustness.gp", &
                      [character(len=20) :: "robustness_cold.png", "robustness_warm.png"], &
                      err_unit)
        end select
    end subroutine draw_pictures

    !> Run gnuplot on `script` in `directory` (no shell: stickslip_gnuplot), its PNGs
    !> written under the names `pngs` + '.tmp' and renamed when complete. Without gnuplot,
    !> or when it fails, one warning: the results are complete without pictures.
    subroutine draw(directory, script, pngs, err_unit)
        character(len=*), intent(in) :: directory, script, pngs(:)
        integer, intent(in) :: err_unit
        integer :: status, k
        ! one gnuplot at a time (the cases of a multi-case run draw from several threads)
        !$omp critical (stickslip_cli_gnuplot)
        status = run_gnuplot(directory, script)
        !$omp end critical (stickslip_cli_gnuplot)
        if (status == 0) then
            call rename_pictures(directory, pngs)
        else
            ! a gnuplot that failed may have left a partial picture under its temporary name
            do k = 1, size(pngs)
                call remove_file(directory//'/'//trim(pngs(k))//'.tmp')
            end do
            write (err_unit, '(a)') stderr_line("stickslip: warning: pictures not drawn "// &
                "(gnuplot not found or it failed); draw them later with: cd "//directory// &
                " && gnuplot "//script)
        end if
    end subroutine draw

    subroutine print_summary(u, case, sol, checks)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(hbm_solution_t), intent(in) :: sol
        type(hbm_checks_t), intent(in) :: checks
        integer :: j
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        write (buffer, '(a,es9.2,a,i0,a,i0,a,i0,a,f0.3,a)') "  converged: residual ", sol%fnorm, &
            " (hybrj info ", sol%info, ", ", sol%nfev, " evaluations, ", sol%njev, &
            " Jacobians) in ", 1.0e3_dp*sol%seconds, " ms"
        call emit(u)
        write (u, '(a,i0,a,a,a,i0,a,g0.4)') "  basis: harmonics ", sol%harmonics, " (", &
            trim(merge("odd only", "all     ", sol%odd_only)), "), samples ", sol%samples, &
            ", rho ", sol%rho
        if (allocated(sol%dofs)) then
            write (buffer, '(a,i0,a,f0.3,a)') "  model: N = ", case%model%ndof, " DOFs kept "// &
                "sparse (&reduction method = 'none'), condensed exactly in ", &
                sol%condensation_seconds, " s"
            call emit(u)
        end if
        do j = 1, size(sol%stick_fraction)
            write (u, '(a,i0,a,a,a,g0.4,a)', advance='no') "  contact ", j, &
                ": sticks ", stick_text(sol%stick_fraction(j), sol%stick_phases(j)), &
                "; max |r| ", &
                maxval(abs(sol%r(:, sol%contacts%first(j)))), &
                limit_text(case, sol%contacts, j, sol%normal(:, j), sol%state(:, j))
            if (sol%offset_undetermined(j)) write (u, '(a)', advance='no') &
                "; stuck all period: mean force set to the admissible value closest to 0"
            write (u, '(a)') ""
        end do
        if (sol%at_rest) then
            write (buffer, '(a,es9.2,a)') "  at rest: every DOF's velocity is below the "// &
                "solve's resolution (", sol%velocity_resolution, " m/s): the contacts hold "// &
                "the forcing, every work is roundoff"
            call emit(u)
        end if
        write (buffer, '(a,es11.4,a,es11.4,a,es11.4,a,es8.1,a)') &
            "  energy per period [J]: forcing ", &
            sol%work_forcing, ", friction ", sol%diss_friction, ", damping ", sol%diss_damping, &
            " (balance error ", energy_balance_error(sol), ")"
        call emit(u)
        if (checks%truncation%available) then
            write (buffer, '(a,es9.2,a,i0,a)') &
                "  truncation error estimate ", checks%truncation%estimate, " (relative; vs H = ", &
                checks%truncation%coarse_harmonics, " and the oversampled Coulomb defect)"
            call emit(u)
        end if
        if (checks%truncation%tolerance > 0.0_dp) then
            write (buffer, '(a,es9.2,a)') &
                "  harmonics_tol ", checks%truncation%tolerance, &
                trim(merge(" met                                  ", &
                           " NOT met: max_harmonics reached       ", checks%truncation%met))
            call emit(u)
        end if
        if (checks%stability) write (u, '(a)') "  stability"//trim(disk_scope(case))//": "// &
            checks%floquet%diagnosis
        if (allocated(checks%notes)) then
            if (len(checks%notes) > 0) write (u, '(a)') "  note: "//checks%notes
        end if
        if (allocated(checks%defect)) then
            if (size(checks%defect) > 0) then
                write (buffer, '(a,i0,a,es9.2)') &
                    "  periodicity defect of the exact flow after ", size(checks%defect), &
                    " period(s): ", checks%defect(size(checks%defect))
                call emit(u)
            end if
        end if
        write (u, '(a)') "  wrote "//case%directory//"/{hbm.csv, coefficients.csv, summary.nml}"
    end subroutine print_summary

    !> The end of a contact's line: its limit, " (mu N 0.45)" for a constant normal load;
    !> for a unilateral contact its open and slip shares and normal force range
    !> " (open 69.1%, slip 18.9%; normal force 0 .. 5.79 N, mu 0.5)".
    function limit_text(case, cs, j, normal, state) result(text)
        type(case_t), intent(in) :: case
        type(contact_set_t), intent(in) :: cs
        integer, intent(in) :: j
        real(dp), intent(in) :: normal(:)
        integer, intent(in) :: state(:)
        character(len=:), allocatable :: text
        character(len=160) :: buf
        if (cs%normal(j) == 0) then
            write (buf, '(a,g0.4,a)') " (mu N ", case%model%mu(j)*case%model%normal_load(j), ")"
        else
            write (buf, '(a,f0.1,a,f0.1,a,g0.4,a,g0.4,a,g0.4,a)') " (open ", &
                100.0_dp*count(state == state_open)/max(size(state), 1), "%, slip ", &
                100.0_dp*count(state == state_slip)/max(size(state), 1), &
                "%; normal force ", minval(normal), " .. ", maxval(normal), " N, mu ", &
                case%model%mu(j), ")"
        end if
        text = trim(buf)
    end function limit_text

    subroutine print_euler_summary(u, case, res)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(euler_result_t), intent(in) :: res
        integer :: j
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        write (buffer, '(a,i0,a,i0,a,es9.2,a,f0.3,a)') "  implicit Euler: periodic after ", &
            res%periods, " periods of ", case%euler%steps_per_period, " steps (defect ", &
            res%defect, ") in ", 1.0e3_dp*res%seconds, " ms"
        call emit(u)
        do j = 1, res%contacts%ncontact
            write (u, '(a,i0,a,g0.4,a)') "  contact ", j, ": max |r| ", &
                maxval(abs(res%r(:, res%contacts%first(j)))), &
                limit_text(case, res%contacts, j, res%normal(:, j), res%state(:, j))
        end do
        write (u, '(a)') "  wrote "//case%directory//"/{euler.csv, summary.nml}"
    end subroutine print_euler_summary

    subroutine print_reference_summary(u, case, ref)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(reference_result_t), intent(in) :: ref
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        call print_reference_lines(u, case, ref)
        write (u, '(a)') "  wrote "//case%directory//"/{reference.csv, events.csv, summary.nml}"
    end subroutine print_reference_summary

    subroutine print_reference_lines(u, case, ref)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(reference_result_t), intent(in) :: ref
        integer :: j, k
        write (buffer, '(a,es9.2,a,i0,a,i0,a,a,a,f0.3,a,f0.3,a)') "  exact reference: periodic "// &
            "(defect ", ref%defect, ", ", ref%nfev, " period maps, ", ref%njev, &
            " monodromies) from the ", ref%start, " start in ", 1.0e3_dp*ref%seconds, &
            " ms CPU (start ", 1.0e3_dp*ref%start_seconds, " ms)"
        call emit(u)
        do j = 1, size(ref%stick_fraction)
            write (u, '(a,i0,a,a,a)', advance='no') "  contact ", j, ": sticks ", &
                stick_text(ref%stick_fraction(j), ref%stick_phases(j)), "; events"
            do k = 1, ref%nevent
                if (ref%event_contact(k) == j) write (u, '(a,a,a,f0.5)', advance='no') " ", &
                    trim(event_name(ref%event_kind(k))), " t=", ref%event_t(k)
            end do
            write (u, '(a)') limit_text(case, ref%contacts, j, ref%normal(:, j), ref%state(:, j))
        end do
        write (buffer, '(a,es11.4,a,es11.4,a,es11.4,a,es8.1,a)') &
            "  energy per period [J]: forcing ", &
            ref%work_forcing, ", friction ", ref%diss_friction, ", damping ", ref%diss_damping, &
            " (balance error ", reference_balance_error(ref), ")"
        call emit(u)
        if (ref%impact_loss > 0.0_dp) then
            write (buffer, '(a,es11.4,a)') "  impacts of the rigid unilateral contacts: ", &
                ref%impact_loss, " J lost per period (in the balance)"
            call emit(u)
        end if
        if (ref%integration_error > 0.0_dp) then
            write (buffer, '(a,es8.1,a,es8.1,a)') "  slip phases with a turning direction "// &
                "integrated numerically: error estimate ", ref%integration_error, &
                " of the state per period (ode_tol ", case%reference%ode_tol, " per step)"
            call emit(u)
        end if
    end subroutine print_reference_lines

    subroutine print_side_by_side_summary(u, case, sbs)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(side_by_side_t), intent(in) :: sbs
        integer :: k
        character(len=:), allocatable :: files
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        write (buffer, '(a,i0,a,i0,a,es9.2,a,f0.3,a)') "  weighted residual: H = ", &
            sbs%hbm%harmonics, ", ", sbs%hbm%nfev, " evaluations, residual ", sbs%hbm%fnorm, &
            ", ", 1.0e3_dp*sbs%hbm_seconds, " ms CPU"
        call emit(u)
        write (buffer, '(a,i0,a,i0,a,es9.2,a,f0.3,a)') "  implicit Euler: ", &
            case%euler%steps_per_period, " steps/period, periodic after ", sbs%euler%periods, &
            " periods (defect ", sbs%euler%defect, "), ", 1.0e3_dp*sbs%euler_seconds, " ms CPU"
        call emit(u)
        if (sbs%reference%converged) then
            call print_reference_lines(u, case, sbs%reference)
        else
            ! not run (contacts it does not handle) or not converged: the diagnosis, and
            ! the contacts as implicit Euler saw them
            write (u, '(a)') "  exact reference: "//sbs%reference%diagnosis
            if (sbs%euler%periodic) then
                do k = 1, sbs%euler%contacts%ncontact
                    write (u, '(a,i0,a,g0.4,a)') "  contact ", k, " (implicit Euler): max |r| ", &
                        maxval(abs(sbs%euler%r(:, sbs%euler%contacts%first(k)))), &
                        limit_text(case, sbs%euler%contacts, k, sbs%euler%normal(:, k), &
                                   sbs%euler%state(:, k))
                end do
            end if
        end if
        write (u, '(a,i0,a)') "  differences on the common grid (", sbs%grid, &
            " points per period), relative to each quantity's amplitude, worst DOF/contact:"
        write (u, '(a)') "                            max x     max v     max r     rms x"// &
            "     rms v     rms r"
        do k = 1, size(sbs%comparisons)
            call print_comparison(u, sbs%comparisons(k))
        end do
        files = ""
        if (sbs%hbm%converged) files = files//"hbm.csv, coefficients.csv, "
        if (sbs%euler%periodic) files = files//"euler.csv, "
        if (sbs%reference%converged) files = files//"reference.csv, events.csv, "
        write (u, '(a)') "  wrote "//case%directory//"/{"//files//"summary.nml}"
    end subroutine print_side_by_side_summary

    subroutine print_comparison(u, cmp)
        integer, intent(in) :: u
        type(comparison_t), intent(in) :: cmp
        character(len=26) :: label
        label = "    "//cmp%method//" vs "//cmp%against
        write (buffer, '(a,6es10.2)') label, cmp%worst('x'), cmp%worst('v'), cmp%worst('r'), &
            cmp%worst('x', .true.), cmp%worst('v', .true.), cmp%worst('r', .true.)
        call emit(u)
    end subroutine print_comparison

    subroutine print_study_summary(u, case, study)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(study_result_t), intent(in) :: study
        integer :: k
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        call print_reference_lines(u, case, study%reference)
        write (u, '(a)') "  work-precision study, errors relative to the reference amplitude:"
        write (u, '(a)') "    method  parameter  samples  conv   cpu [s]     max x     max v"// &
            "     max r"
        do k = 1, size(study%rows)
            associate (row => study%rows(k))
                if (allocated(row%cmp%max_error)) then
                    write (buffer, '(4x,a6,i11,i9,a6,es10.2,3es10.2)') trim(row%method), &
                        row%parameter, row%samples, merge("   yes", "    no", row%converged), &
                        row%cpu_seconds, row%cmp%worst('x'), row%cmp%worst('v'), &
                        row%cmp%worst('r')
                    call emit(u)
                else
                    write (buffer, '(4x,a6,i11,i9,a6,es10.2,a)') trim(row%method), row%parameter, &
                        row%samples, merge("   yes", "    no", row%converged), &
                        row%cpu_seconds, "  (no solution)"
                    call emit(u)
                end if
            end associate
        end do
        if (study%skipped > 0) write (u, '(a,i0,a)') "  skipped ", study%skipped, &
            " (harmonics, samples) pair(s) with samples < 2 H + 1 or a forcing harmonic > H"
        write (u, '(a)') "  wrote "//case%directory//"/{study.csv, reference.csv, events.csv, "// &
            "summary.nml}"
    end subroutine print_study_summary

    subroutine print_sweep_summary(u, case, res)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(sweep_result_t), intent(in) :: res
        integer :: n
        n = res%npoints
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        write (u, '(a,i0,a,g0.6,a,g0.6,a)') "  forced-response curve in "// &
            trim(case%sweep%parameter)//": ", n, " points from ", res%points(1)%parameter, &
            " to ", res%points(n)%parameter, merge(" (complete)  ", " (incomplete)", res%complete)
        if (res%resumed_points > 0) write (u, '(a,i0,a)') "  resumed from a checkpoint with ", &
            res%resumed_points, " points"
        write (u, '(a,i0,a,i0,a,i0)') "  folds passed ", res%folds, ", unstable points ", &
            count(res%points(1:n)%stable == 0), ", stability unknown ", &
            count(res%points(1:n)%stable == -1)
        write (u, '(a,f0.3,a,f0.3,a)') "  CPU ", res%seconds, " s (stability ", &
            res%stability_seconds, " s)"
        if (sector_stability(case)) write (u, '(a)') "  stability"//trim(disk_scope(case))
        if (len(sampling_notes(case%hbm%samples, case%hbm%harmonics)) > 0) write (u, '(a)') &
            "  note: "//sampling_notes(case%hbm%samples, case%hbm%harmonics)
        if (allocated(res%notes)) then
            if (len(res%notes) > 0) write (u, '(a)') "  note: "//res%notes
        end if
        write (u, '(a)') "  wrote "//case%directory//"/{frc.csv, frc_harmonics.csv, frc.gp, "// &
            pictures(case%directory, [character(len=20) :: "frc.png", "frc_dissipation.png"])// &
            "summary.nml}"
    end subroutine print_sweep_summary

    subroutine print_family_summary(u, case, fam, res)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(family_result_t), intent(in) :: fam
        type(sweep_result_t), intent(in) :: res
        integer :: k, n
        n = size(fam%values)
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        write (u, '(a,i0,a,i0,a,g0.6,a,g0.6,a)') "  family of ", n, &
            " forced-response curves in omega from ", n, " values of "// &
            trim(fam%family_parameter)//", ", fam%values(1), " to ", fam%values(n), &
            merge(" (complete)  ", " (incomplete)", fam%complete)
        write (u, '(a,i0,a,i0,a,i0)') "  points ", res%npoints, ", resumed ", &
            res%resumed_points, ", unstable ", count(res%points(1:res%npoints)%stable == 0)
        if (size(fam%peaks, 1) > 0) then
            write (u, '(a)') "  curve  value            peak (first observed DOF)  at omega"
            do k = 1, n
                if (fam%curves(k)%npoints == 0) then
                    write (u, '(i7,2x,g15.6,a)') k, fam%values(k), "  no solution at the start"
                else
                    write (u, '(i7,2x,g15.6,2x,g15.6,12x,g15.6)') k, fam%values(k), &
                        fam%peaks(1, k)%amplitude, fam%peaks(1, k)%omega
                end if
            end do
        end if
        write (u, '(a,f0.3,a,f0.3,a,i0,a)') "  CPU ", res%seconds, " s, wall ", &
            fam%wall_seconds, " s on ", fam%threads, " thread(s)"
        write (u, '(a)') "  wrote "//case%directory//"/{frc.csv, frc_harmonics.csv, "// &
            "family.csv, family.gp, "// &
            pictures(case%directory, [character(len=20) :: "frc_family.png", "family.png"])// &
            "summary.nml}"
    end subroutine print_family_summary

    subroutine print_modes_summary(u, case, res)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(modes_result_t), intent(in) :: res
        integer :: n, k
        n = res%npoints
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        write (u, '(a,i0,a,i0,a,g0.6,a,g0.6,a)') "  nonlinear mode ", case%modes%mode, ": ", &
            n, " points, modal amplitude ", res%points(1)%p%parameter, " to ", &
            res%points(n)%p%parameter, merge(" (complete)  ", " (incomplete)", res%complete)
        if (any(res%points(1:n)%nodal_diameter >= 0)) then
            ! the backbones of a disk's sector: one per nodal diameter
            write (u, '(a)') "  nodal diameters (one backbone each, on the sector; their "// &
                "linear limits per diameter in summary.nml): "// &
                diameter_list(res%points(1:n)%nodal_diameter)
        else
            write (u, '(a,g0.7,a,g0.7,a,a,a)') "  linear limits: contacts stuck ", &
                res%omega_stuck, " rad/s, slipping ", res%omega_slipping, " rad/s (the "// &
                "free structure's mode most like the stuck one; started ", trim(res%start), ")"
        end if
        k = maxloc(res%points(1:n)%damping_ratio, 1)
        write (u, '(a,g0.7,a,g0.7,a,g0.5,a,g0.5)') "  frequency ", &
            minval(res%points(1:n)%p%omega), " .. ", maxval(res%points(1:n)%p%omega), &
            " rad/s; largest damping ratio ", res%points(k)%damping_ratio, &
            " at amplitude ", res%points(k)%p%parameter
        write (u, '(a,es9.2,a,f0.3,a,i0,a)') "  energy balance error at most ", &
            maxval(res%points(1:n)%energy_error), "; CPU ", res%seconds, " s (", &
            res%factorizations, " factorizations)"
        if (case%modes%error_estimate) write (u, '(a,es9.2,a,es9.2,a,i0,a)') &
            "  error estimate (vs half the harmonics) at most: omega ", &
            max_finite([(res%points(k)%omega_error, k=1, n)]), " (relative), D ", &
            max_finite([(res%points(k)%damping_error, k=1, n)]), "; ", &
            count([(index(res%points(k)%p%check, 'truncation') > 0, k=1, n)]), &
            " points flagged"

        write (u, '(a)') "  wrote "//case%directory//"/{modes.csv, modes_harmonics.csv, "// &
            "modes.gp, "//pictures(case%directory, [character(len=20) :: "modes.png"])// &
            "summary.nml}"
    end subroutine print_modes_summary

    !> The distinct values of `nd` in their order (runs of equal values), as a list.
    function diameter_list(nd) result(text)
        integer, intent(in) :: nd(:)
        character(len=:), allocatable :: text
        character(len=12) :: buf
        integer :: k
        text = ""
        do k = 1, size(nd)
            if (k > 1) then
                if (nd(k) == nd(k - 1)) cycle
            end if
            write (buf, '(i0)') nd(k)
            text = text//merge(", ", "  ", len(text) > 0)//trim(buf)
        end do
        text = trim(adjustl(text))
    end function diameter_list

    !> The largest finite entry of x (NaN when none is).
    real(dp) function max_finite(x) result(m)
        real(dp), intent(in) :: x(:)
        m = ieee_value(1.0_dp, ieee_quiet_nan)
        if (any(ieee_is_finite(x))) m = maxval(x, mask=ieee_is_finite(x))
    end function max_finite

    subroutine print_robustness_summary(u, case, rows)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(robustness_row_t), intent(in) :: rows(:)
        character(len=8), parameter :: methods(3) = [character(len=8) :: 'hbm-cold', &
                                                     'hbm-warm', 'euler']
        integer :: k, n
        write (u, '(a)') "stickslip "//stickslip_version//": "//case%path
        write (u, '(a,i0,a)') "  robustness study: ", size(rows), " runs"
        do k = 1, 3
            n = count(rows%method == methods(k))
            if (n == 0) cycle
            write (u, '(4x,a8,a,i0,a,i0,a,f0.1,a)') methods(k), ": ", &
                count(rows%method == methods(k) .and. rows%success), " of ", n, &
                " succeeded (", 100.0_dp*count(rows%method == methods(k) .and. rows%success)/n, &
                "%)"
        end do
        write (u, '(a)') "  wrote "//case%directory//"/{robustness.csv, robustness.gp, "// &
            pictures(case%directory, [character(len=20) :: "robustness_cold.png", &
                                      "robustness_warm.png"])//"summary.nml}"
    end subroutine print_robustness_summary

    !> The pictures of `pngs` that stand in `directory` (drawn by this run: the old ones
    !> were removed with the old result set), each followed by ", ".
    function pictures(directory, pngs) result(list)
        character(len=*), intent(in) :: directory, pngs(:)
        character(len=:), allocatable :: list
        integer :: k
        logical :: exists
        list = ""
        do k = 1, size(pngs)
            inquire (file=directory//'/'//trim(pngs(k)), exist=exists)
            if (exists) list = list//trim(pngs(k))//", "
        end do
    end function pictures

    !> `text` made fit for one line of standard error: every byte outside printable ASCII
    !> (control characters, a line feed in a file name, bytes of a binary or non-ASCII file
    !> that a message quotes) shown as \xNN, and every run of more than 120 characters
    !> without a blank (a 5000-character directory name) cut to its first and last 50
    !> characters around "...(<n> characters)...". Messages stay one readable line whatever
    !> the case file held.
    pure function stderr_line(text) result(line)
        !> The message.
        character(len=*), intent(in) :: text
        character(len=:), allocatable :: line
        character(len=*), parameter :: hex = '0123456789ABCDEF'
        character(len=:), allocatable :: escaped
        character(len=12) :: count
        integer :: i, j, k, n
        escaped = ""
        do i = 1, len(text)
            k = modulo(iachar(text(i:i)), 256)
            if (k >= 32 .and. k <= 126) then
                escaped = escaped//text(i:i)
            else
                escaped = escaped//"\x"//hex(k/16 + 1:k/16 + 1)// &
                    hex(mod(k, 16) + 1:mod(k, 16) + 1)
            end if
        end do
        line = ""
        n = len(escaped)
        i = 1
        do while (i <= n)
            if (escaped(i:i) == ' ') then
                line = line//' '
                i = i + 1
                cycle
            end if
            j = i
            do while (j < n)
                if (escaped(j + 1:j + 1) == ' ') exit
                j = j + 1
            end do
            if (j - i + 1 > 120) then
                write (count, '(i0)') j - i + 1
                line = line//escaped(i:i + 49)//"...("//trim(count)//" characters)..."// &
                    escaped(j - 49:j)
            else
                line = line//escaped(i:j)
            end if
            i = j + 1
        end do
    end function stderr_line
    !> Write `buffer` (a line of the human summary) on unit `u`, with the `E` that an ES edit
    !> descriptor drops from a three-digit exponent put back: `1.80+284` becomes `1.80E+284`.
    subroutine emit(u)
        integer, intent(in) :: u
        write (u, '(a)') with_exponent_e(trim(buffer))
    end subroutine emit

    !> `s` with an `E` inserted in every number of the form `<digit>.<digits><sign><3 digits>`
    !> (what `ESw.d` prints for |exponent| > 99); other text unchanged.
    pure function with_exponent_e(s) result(t)
        !> A formatted line.
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: t
        integer :: i, k
        logical :: mantissa
        t = ""
        do i = 1, len(s)
            if ((s(i:i) == '+' .or. s(i:i) == '-') .and. i > 3 .and. i + 3 <= len(s)) then
                mantissa = is_digit(s(i - 1:i - 1))
                k = i - 1
                do while (k > 1 .and. mantissa)
                    if (.not. is_digit(s(k:k))) exit
                    k = k - 1
                end do
                mantissa = mantissa .and. s(k:k) == '.' .and. k > 1
                if (mantissa) mantissa = is_digit(s(k - 1:k - 1))
                if (mantissa .and. is_digit(s(i + 1:i + 1)) .and. is_digit(s(i + 2:i + 2)) .and. &
                    is_digit(s(i + 3:i + 3))) then
                    if (i + 4 > len(s)) then
                        t = t//'E'
                    else if (.not. is_digit(s(i + 4:i + 4))) then
                        t = t//'E'
                    end if
                end if
            end if
            t = t//s(i:i)
        end do
    contains
        pure logical function is_digit(c)
            character(len=1), intent(in) :: c
            is_digit = c >= '0' .and. c <= '9'
        end function is_digit
    end function with_exponent_e
    !> "12.5% of the period in 2 phase(s)" for a stick share `fraction` (0..1) and `phases`
    !> stick phases; a share without a counted phase (isolated samples, phases shorter
    !> than the harmonics resolve) is said so instead of "in 0 phase(s)".
    function stick_text(fraction, phases) result(text)
        !> Share of the period stuck and the stick phases counted.
        real(dp), intent(in) :: fraction
        integer, intent(in) :: phases
        character(len=:), allocatable :: text
        character(len=32) :: pct
        write (pct, '(f8.1)') 100.0_dp*fraction
        text = trim(adjustl(pct))//"% of the period"
        if (phases > 0) then
            text = text//" in "//itoa(phases)//" phase(s)"
        else if (fraction > 0.0_dp) then
            text = text//" in samples too few for a stick phase the harmonics resolve"
        end if
    end function stick_text

    !> For the stability of a sector's wave: " (the assembled <n>-DOF disk's Floquet
    !> multipliers: every perturbation, not only the wave's symmetry; its exact flow over
    !> T/<m> by that symmetry)"; '' otherwise.
    function disk_scope(case) result(text)
        !> The case.
        type(case_t), intent(in) :: case
        character(len=:), allocatable :: text
        integer :: m
        text = ""
        if (.not. sector_stability(case)) return
        associate (c => case%cyclic%cyc)
            m = stability_spans(wave_symmetry_t(c%sectors, c%engine_order), case%hbm%samples)
            text = " (the assembled "//itoa(c%sectors*(case%cyclic%sector%ndof - &
                                                     size(c%right)))// &
                   "-DOF disk's Floquet multipliers: every perturbation, not only the "// &
                   "wave's symmetry"
            if (m > 1) text = text//"; its exact flow over T/"//itoa(m)//" by that symmetry"
            text = text//")"
        end associate
    end function disk_scope

end module stickslip_cli
