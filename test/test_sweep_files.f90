!> Tests of the sweep end to end: the case group &sweep, the CLI, frc.csv and summary.nml,
!> the checkpoint of an interrupted run and its resumption, and bad &sweep input; the
!> robustness study through the CLI (&robustness, robustness.csv, the maps' script).
module test_sweep_files
    use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_diagnostics, only: diagnostics_t, level_untrusted
    use stickslip_sweep_point, only: point_tally_t
    use stickslip_case, only: case_t, read_case
    use stickslip_sweep, only: sweep_result_t, run_sweep
    use stickslip_driver, only: run_sweep_case
    use stickslip_checkpoint, only: checkpoint_writer_t, case_fingerprint, checkpoint_name
    use stickslip_files, only: make_directory, remove_file
    use test_cli, only: cli
    use fixtures, only: enter_project_root, scratch, write_lines, sweep_case, first_line, rt, &
        file_text
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_sweep_file_tests, killed_writer_t

    !> A checkpoint writer that stops the sweep after `stop_after` points, like a batch job
    !> killed at its wall-time limit (the checkpoint of that point is on disk).
    type, extends(checkpoint_writer_t) :: killed_writer_t
        integer :: stop_after = 0
    contains
        procedure :: observe => killed_observe
    end type killed_writer_t

    interface
        function c_symlink(target, path) bind(c, name='symlink') result(stat)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: target(*), path(*)
            integer(c_int) :: stat
        end function c_symlink
    end interface


contains

    subroutine run_sweep_file_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()
        call test_cli_sweep(t)
        call test_resume(t)
        call test_damaged_checkpoint(t)
        call test_bad_sweep_input(t)
        call test_cli_robustness(t)
        call test_point_trust(t)
    end subroutine run_sweep_file_tests

    !> Trust point by point (issue 24): the tally gives each point its worst level and check
    !> and makes the curve untrusted as soon as one point is (before: only when all were);
    !> a sweep at H = 2 (truncation estimates 0.2 .. 0.3 at every point: warnings) writes
    !> trusted = 1 and the check 'truncation' in every row, warns and exits 0.
    subroutine test_point_trust(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/sweep_trust"
        type(point_tally_t) :: tally
        type(diagnostics_t) :: bad, curve
        character(len=:), allocatable :: out, err, header, summary
        character(len=2000) :: line
        character(len=32) :: key
        integer :: level, code, u, stat, untrusted_rows, rows, c
        real(dp) :: nan
        nan = ieee_value(1.0_dp, ieee_quiet_nan)
        call bad%add(level_untrusted, "energy_balance", "x")
        call tally%add_point(diagnostics_t(), 0.01_dp, 1.0_dp, level, key)
        call check(t, level == 0 .and. key == "", "point trust: a good point")
        call tally%add_point(bad, 0.2_dp, 2.0_dp, level, key)
        call check(t, level == level_untrusted .and. key == "energy_balance", &
                   "point trust: the worst check named", key)
        call tally%add_point(diagnostics_t(), nan, 3.0_dp, level, key)
        call tally%report("omega", curve)
        call check(t, curve%worst() == level_untrusted .and. curve%has("points_energy_balance") &
                   .and. curve%has("points_truncation"), &
                   "point trust: one untrusted point of three makes the curve untrusted")
        call write_lines(dir//".nml", [sweep_case(1:3), &
            "&hbm harmonics = 2, rho = 0.2, samples = 64 /", sweep_case(5:6), &
            "&output directory = '"//dir//"' /" // repeat(' ', 0)])
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        open (newunit=u, file=dir//"/frc.csv", status='old', action='read', iostat=stat)
        call check(t, stat == 0, "point trust: frc.csv written")
        if (stat /= 0) return
        read (u, '(a)') line
        header = trim(line)
        rows = 0
        untrusted_rows = 0
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            rows = rows + 1
            ! the last two fields: trusted, check (every point warns: truncation 0.2 .. 0.3)
            c = index(line, ",", back=.true.)
            if (line(c - 1:c - 1) == "0") untrusted_rows = untrusted_rows + 1
            call check(t, line(c - 2:) == ",1,truncation", "point trust: a row's verdict", &
                       trim(line))
        end do
        close (u)
        call check(t, rows >= 11 .and. untrusted_rows == 0, "point trust: rows, none untrusted")
        summary = file_text(dir//"/summary.nml")
        call check(t, code == 0 .and. index(summary, "warning_points_truncation") > 0 .and. &
                   index(err, "stickslip: warning:") > 0, &
                   "point trust: warned points, a trusted curve, exit 0", err)
        ! a sweep that stops says what to change (issue 24): here max_points
        call write_lines(dir//".nml", [sweep_case(1:5), &
            "&sweep parameter = 'omega', start = 2.0, stop = 3.0, step = 0.1, max_step = 0.1, "// &
            "max_points = 3 /", "&output directory = '"//dir//"' /" // repeat(' ', 0)])
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 2 .and. index(err, "stopped at max_points") > 0 .and. &
                   index(err, "Raise &sweep max_points") > 0, &
                   "sweep stop: the message names the remedy", err)
    end subroutine test_point_trust

    !> method = 'robustness' on a tiny grid: exit 0, robustness.csv with one row per run,
    !> robustness.gp, the summary's counts; a bad &robustness entry names the variable.
    subroutine test_cli_robustness(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/robustness_cli"
        character(len=:), allocatable :: out, err, script
        character(len=2000) :: line
        integer :: code, u, stat, rows
        logical :: exists
        call write_lines(dir//".nml", [sweep_case(1:4), &
            "&run method = 'robustness' /" // repeat(' ', 0), &
            "&robustness omegas = 2.0, 4.5, mus = 0.45, harmonics = 5, rhos = 0.2, 0, "// &
            "steps_per_period = 500 /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 0, "robustness cli: exit 0", err)
        call check(t, index(out, "hbm-cold: 4 of 4 succeeded") > 0, "robustness cli: summary", out)
        open (newunit=u, file=dir//"/robustness.csv", status='old', action='read', iostat=stat)
        call check(t, stat == 0, "robustness cli: robustness.csv written")
        if (stat /= 0) return
        rows = -1
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            rows = rows + 1
        end do
        close (u)
        ! 2 omegas x (2 rho x (cold + warm) + 1 Euler)
        call check(t, rows == 10, "robustness cli: one row per run")
        inquire (file=dir//"/robustness.gp", exist=exists)
        call check(t, exists, "robustness cli: robustness.gp written")
        script = file_text(dir//"/robustness.gp")
        call check(t, index(script, "title 'converged to the right solution'") > 0 .and. &
                   index(script, "title 'converged to a wrong solution'") > 0 .and. &
                   index(script, "title 'not converged'") > 0, &
                   "robustness cli: the maps have a colour legend")
        call write_lines(dir//".nml", [sweep_case(1:4), &
            "&run method = 'robustness' /" // repeat(' ', 0), &
            "&robustness omegas = 2.0, -1.0 /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "&robustness omegas") > 0, &
                   "robustness cli: bad omegas named", err)
    end subroutine test_cli_robustness

    subroutine killed_observe(self, res, error)
        class(killed_writer_t), intent(inout) :: self
        type(sweep_result_t), intent(in) :: res
        type(error_type), allocatable, intent(out) :: error
        call self%checkpoint_writer_t%observe(res, error)
        if (allocated(error)) return
        if (res%npoints >= self%stop_after) call fatal_error(error, "killed", stickslip_stat%io)
    end subroutine killed_observe

    !> The CLI runs a sweep case: exit 0, frc.csv with its header and one row per point,
    !> summary.nml complete, no checkpoint left.
    subroutine test_cli_sweep(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/sweep_cli"
        character(len=:), allocatable :: out, err, header
        character(len=2000) :: line
        integer :: code, u, stat, rows
        logical :: exists
        call write_lines(dir//".nml", [sweep_case, &
            "&output directory = '"//dir//"' /" // repeat(' ', 0)])
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 0, "sweep cli: exit 0", err)
        call check(t, index(out, "forced-response curve in omega") > 0, "sweep cli: summary", out)
        open (newunit=u, file=dir//"/frc.csv", status='old', action='read', iostat=stat)
        call check(t, stat == 0, "sweep cli: frc.csv written")
        if (stat /= 0) return
        read (u, '(a)') line
        header = trim(line)
        rows = 0
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            rows = rows + 1
        end do
        close (u)
        call check(t, header == "parameter,amp_1,amp_2,dissipation,rmax_1,stick_1,harmonics,"// &
                   "residual,status,floquet_max,stable,truncation,arclength,diss_friction,"// &
                   "diss_damping,nfev,omega,frequency,vib_1,vib_2,h1_1,h1_2,trusted,check", &
                   "sweep cli: frc.csv header", header)
        call check(t, rows >= 11, "sweep cli: rows")
        inquire (file=dir//"/"//checkpoint_name, exist=exists)
        call check(t, .not. exists, "sweep cli: checkpoint removed when done")
        inquire (file=dir//"/frc.gp", exist=exists)
        call check(t, exists, "sweep cli: frc.gp written")
        open (newunit=u, file=dir//"/summary.nml", status='old', action='read', iostat=stat)
        call check(t, stat == 0, "sweep cli: summary.nml")
        if (stat /= 0) return
        exists = .false.
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (trim(adjustl(line)) == "complete = T") exists = .true.
        end do
        close (u)
        call check(t, exists, "sweep cli: summary says complete")
        call check(t, index(out, "frc_harmonics.csv") > 0, "sweep cli: the wrote line names "// &
                   "frc_harmonics.csv", out)
        call check_harmonics(t, dir)
    end subroutine test_cli_sweep

    !> frc_harmonics.csv of the seed sweep in `dir` (H = 10, 64 samples, contact on DOF 2)
    !> against frc.csv: 2H + 1 rows a point, the point's parameter; the displacement rebuilt
    !> from the coefficients at the solver's 64 sample times has frc.csv's amplitudes; the
    !> contact displacement u1 is x2; and the energy the friction force dissipates over a
    !> period, integrated exactly from the coefficients (-pi sum_h h (a_h^r b_h^u - b_h^r
    !> a_h^u)), is frc.csv's diss_friction, which the solver summed over its samples.
    subroutine check_harmonics(t, dir)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: dir
        real(dp), parameter :: pi = acos(-1.0_dp)
        character(len=4000) :: line
        character(len=40), allocatable :: f(:)
        real(dp), allocatable :: frc(:, :), c(:, :)
        real(dp) :: x(64, 2), tk, omega, work, worst_amp, worst_work, worst_u
        integer, allocatable :: h(:)
        integer :: u, stat, npt, k, m, i, d, rows
        character(len=:), allocatable :: header
        header = first_line(dir//"/frc_harmonics.csv")
        call check(t, header == "point,parameter,omega,harmonic,kind,x1,x2,r1,u1", &
                   "frc_harmonics.csv: header", header)
        ! frc.csv: parameter, amp_1, amp_2, diss_friction (column 14)
        allocate (frc(4, 0))
        open (newunit=u, file=dir//"/frc.csv", status='old', action='read', iostat=stat)
        if (stat /= 0) return
        read (u, '(a)', iostat=stat)
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            f = fields(line)
            frc = reshape([frc, real_of(f(1)), real_of(f(2)), real_of(f(3)), real_of(f(14))], &
                          [4, size(frc, 2) + 1])
        end do
        close (u)
        npt = size(frc, 2)
        open (newunit=u, file=dir//"/frc_harmonics.csv", status='old', action='read', iostat=stat)
        call check(t, stat == 0, "frc_harmonics.csv written")
        if (stat /= 0) return
        read (u, '(a)', iostat=stat)
        worst_amp = 0.0_dp
        worst_work = 0.0_dp
        worst_u = 0.0_dp
        rows = 0
        do k = 1, npt
            ! the 21 rows of point k: harmonic, then x1, x2, r1, u1
            allocate (c(21, 4), h(21))
            do m = 1, 21
                read (u, '(a)', iostat=stat) line
                if (stat /= 0) exit
                rows = rows + 1
                f = fields(line)
                if (int(real_of(f(1))) /= k .or. real_of(f(2)) /= frc(1, k)) stat = -99
                omega = real_of(f(3))
                h(m) = int(real_of(f(4)))
                c(m, :) = [(real_of(f(5 + i)), i=1, 4)]
            end do
            if (stat /= 0) exit
            ! x(t_j) at the solver's samples t_j = j T / 64
            do i = 1, 64
                tk = (i - 1)*2.0_dp*pi/omega/64.0_dp
                do d = 1, 2
                    x(i, d) = c(1, d)
                    do m = 2, 21, 2
                        x(i, d) = x(i, d) + c(m, d)*cos(h(m)*omega*tk) + &
                                  c(m + 1, d)*sin(h(m)*omega*tk)
                    end do
                end do
            end do
            do d = 1, 2
                worst_amp = max(worst_amp, abs(maxval(abs(x(:, d))) - frc(1 + d, k))/frc(1 + d, k))
            end do
            work = 0.0_dp
            do m = 2, 21, 2
                work = work - pi*h(m)*(c(m, 3)*c(m + 1, 4) - c(m + 1, 3)*c(m, 4))
            end do
            worst_work = max(worst_work, abs(work - frc(4, k))/max(frc(4, k), 1.0e-300_dp))
            worst_u = max(worst_u, maxval(abs(c(:, 4) - c(:, 2))))
            deallocate (c, h)
        end do
        close (u)
        call check(t, stat == 0 .and. rows == 21*npt, "frc_harmonics.csv: 21 rows for each "// &
                   "of the points of frc.csv, numbered, with their parameter")
        call check(t, worst_amp <= 1.0e-12_dp, "frc_harmonics.csv: x rebuilt at the samples "// &
                   "has frc.csv's amplitudes", rt(worst_amp))
        call check(t, worst_u == 0.0_dp, "frc_harmonics.csv: u1 = x2 (contact on DOF 2)")
        call check(t, worst_work <= 1.0e-9_dp, "frc_harmonics.csv: the friction work "// &
                   "integrated from the coefficients is diss_friction", rt(worst_work))
    contains
        !> The comma-separated fields of `text`.
        function fields(text) result(out)
            character(len=*), intent(in) :: text
            character(len=40), allocatable :: out(:)
            integer :: a, b
            allocate (out(0))
            a = 1
            do
                b = index(text(a:), ',')
                if (b == 0) then
                    out = [character(len=40) :: out, adjustl(text(a:))]
                    exit
                end if
                out = [character(len=40) :: out, adjustl(text(a:a + b - 2))]
                a = a + b
            end do
        end function fields
        real(dp) function real_of(text)
            character(len=*), intent(in) :: text
            read (text, *) real_of
        end function real_of
    end subroutine check_harmonics

    !> A run killed after 4 points leaves its checkpoint; running the case again resumes
    !> from it and ends with the same curve as an uninterrupted run. A checkpoint of another
    !> case is refused with a message; resume = .false. starts afresh.
    subroutine test_resume(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/sweep_resume"
        type(case_t) :: c, c2
        type(killed_writer_t) :: killer
        type(sweep_result_t) :: whole, cut, resumed
        type(error_type), allocatable :: error
        logical :: exists, same
        integer :: k
        call write_lines(dir//".nml", [sweep_case, "&output directory = '"//dir//"' /"])
        call read_case(dir//".nml", c, error)
        call check_error(t, error, "resume: read case", .false.)
        if (allocated(error)) return
        call make_directory(dir, error)
        call run_sweep(c%model, c%hbm, c%reference%reference_options_t, c%sweep%sweep_options_t, &
                       whole, error)
        call check_error(t, error, "resume: uninterrupted run", .false.)
        if (allocated(error)) return
        killer%directory = dir
        killer%fingerprint = case_fingerprint(c, error)
        killer%stop_after = 4
        ! a checkpoint after every point, so that the kill after point 4 finds 4 saved
        killer%interval = 0.0_dp
        call run_sweep(c%model, c%hbm, c%reference%reference_options_t, c%sweep%sweep_options_t, &
                       cut, error, observer=killer)
        call check_error(t, error, "resume: the killed run stops", .true.)
        inquire (file=dir//"/"//checkpoint_name, exist=exists)
        call check(t, exists, "resume: the checkpoint survives the kill")
        call run_sweep_case(c, resumed, error)
        call check_error(t, error, "resume: resumed run", .false.)
        if (allocated(error)) return
        call check(t, resumed%resumed_points == 4, "resume: continued from 4 points")
        same = resumed%npoints == whole%npoints
        if (same) then
            do k = 1, whole%npoints
                same = same .and. abs(resumed%points(k)%parameter - whole%points(k)%parameter) &
                       <= 1.0e-12_dp .and. all(abs(resumed%points(k)%amplitude - &
                       whole%points(k)%amplitude) <= 1.0e-10_dp*whole%points(k)%amplitude)
            end do
        end if
        call check(t, same, "resume: the same curve as an uninterrupted run")
        ! the resumed points carry their Fourier coefficients through the checkpoint
        same = resumed%npoints == whole%npoints
        if (same) then
            do k = 1, whole%npoints
                same = same .and. allocated(resumed%points(k)%xcoef)
                if (.not. same) exit
                same = all(resumed%points(k)%harmonic == whole%points(k)%harmonic) .and. &
                       all(abs(resumed%points(k)%xcoef - whole%points(k)%xcoef) <= &
                           1.0e-10_dp*maxval(abs(whole%points(k)%xcoef))) .and. &
                       all(abs(resumed%points(k)%ucoef - whole%points(k)%ucoef) <= &
                           1.0e-10_dp*maxval(abs(whole%points(k)%xcoef))) .and. &
                       resumed%points(k)%omega == whole%points(k)%omega
            end do
        end if
        call check(t, same, "resume: the resumed points keep their Fourier coefficients")
        ! a checkpoint of another case
        killer%stop_after = 2
        killer%last = -1
        call run_sweep(c%model, c%hbm, c%reference%reference_options_t, c%sweep%sweep_options_t, &
                       cut, error, observer=killer)
        c2 = c
        c2%model%mu = 0.5_dp
        call run_sweep_case(c2, resumed, error)
        call check_error(t, error, "resume: checkpoint of another case refused", .true.)
        if (allocated(error)) call check(t, index(error%message, "another case") > 0 .and. &
                                         error%stat == stickslip_stat%input, &
                                         "resume: the message says why", error%message)
        c2%sweep%resume = .false.
        call run_sweep_case(c2, resumed, error)
        call check_error(t, error, "resume: resume = .false. starts afresh", .false.)
        if (.not. allocated(error)) call check(t, resumed%resumed_points == 0, &
                                               "resume: no points taken from the checkpoint")
    end subroutine test_resume

    !> A checkpoint whose counts were damaged (huge, negative, not the case's, a truncated
    !> file, garbage) is refused with a message (stat input, exit 1) before anything is
    !> allocated: no crash; resume = .false. still starts afresh.
    subroutine test_damaged_checkpoint(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/sweep_damaged"
        type(case_t) :: c
        type(killed_writer_t) :: killer
        type(sweep_result_t) :: cut, resumed
        type(error_type), allocatable :: error
        character(len=4000), allocatable :: saved(:)
        character(len=4000) :: line
        character(len=24) :: fields(9)
        integer :: u, stat, n, k
        character(len=*), parameter :: names(16) = [character(len=24) :: "huge unknowns", &
            "huge points", "negative points", "other ndof", "negative count", "truncated", &
            "garbage counts", "fewer points", "a NaN value", "a link to /dev/zero", &
            "an empty file", "huge coefficient count", "a NaN coefficient", "a bad status", &
            "huge harmonics", "a bad stability flag"]
        character(len=24) :: pfields(6)
        call write_lines(dir//".nml", [sweep_case, "&output directory = '"//dir//"' /"])
        call read_case(dir//".nml", c, error)
        if (allocated(error)) return
        call make_directory(dir, error)
        killer%directory = dir
        killer%fingerprint = case_fingerprint(c, error)
        killer%stop_after = 3
        killer%interval = 0.0_dp
        call run_sweep(c%model, c%hbm, c%reference%reference_options_t, c%sweep%sweep_options_t, &
                       cut, error, observer=killer)
        ! the checkpoint's lines
        allocate (saved(0))
        open (newunit=u, file=dir//"/"//checkpoint_name, status='old', action='read', &
              iostat=stat)
        call check(t, stat == 0, "damaged checkpoint: written by the killed run")
        if (stat /= 0) return
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            saved = [character(len=4000) :: saved, line]
        end do
        close (u)
        n = size(saved)
        read (saved(3), *) fields
        do k = 1, size(names)
            line = saved(3)
            select case (k)
            case (1)
                line = "2147483647 "//join(fields(2:))
            case (2)
                line = join(fields(1:3))//" 999999999 "//join(fields(5:))
            case (3)
                line = join(fields(1:3))//" -5 "//join(fields(5:))
            case (4)
                line = join(fields(1:1))//" 7 "//join(fields(3:))
            case (5)
                line = join(fields(1:5))//" -1 "//join(fields(7:))
            case (7)
                line = "x y z"
            case (8)
                ! the point count lowered (3 -> 2) with the continuation state left at 3
                line = join(fields(1:3))//" 2 "//join(fields(5:))
            end select
            if (k == 6) then
                call write_lines(dir//"/"//checkpoint_name, saved(1:n - 1))
            else if (k == 9) then
                ! the first value of the continuation state (lambda) made NaN
                line = saved(4)
                line = "NaN "//line(index(adjustl(line), " ") + 1:)
                call write_lines(dir//"/"//checkpoint_name, [character(len=4000) :: saved(1:3), &
                                 line, saved(5:n)])
            else if (k == 10) then
                call remove_file(dir//"/"//checkpoint_name)
                call execute_symlink("/dev/zero", dir//"/"//checkpoint_name)
            else if (k == 11) then
                call remove_file(dir//"/"//checkpoint_name)
                call write_lines(dir//"/"//checkpoint_name, [character(len=1) ::])
            else if (k == 12) then
                ! point 1's coefficient counts (line 9: nb, channels, omega)
                line = saved(9)
                line = "2147483647 "//line(index(adjustl(line), " ") + 1:)
                call write_lines(dir//"/"//checkpoint_name, [character(len=4000) :: saved(1:8), &
                                 line, saved(10:n)])
            else if (k == 13) then
                ! point 1's first coefficient (line 11)
                line = saved(11)
                line = "NaN "//line(index(adjustl(line), " ") + 1:)
                call write_lines(dir//"/"//checkpoint_name, [character(len=4000) :: saved(1:10), &
                                 line, saved(12:n)])
            else if (k >= 14) then
                ! point 1's status line (line 7: 'status' harmonics nfev stable level 'check')
                read (saved(7), *) pfields
                select case (k)
                case (14)
                    line = "'bogus' "//join(pfields(2:5))//" '"//trim(pfields(6))//"'"
                case (15)
                    line = "'"//trim(pfields(1))//"' 99999999 "//join(pfields(3:5))//" '"// &
                           trim(pfields(6))//"'"
                case default
                    line = "'"//trim(pfields(1))//"' "//join(pfields(2:3))//" 7 "// &
                           trim(pfields(5))//" '"//trim(pfields(6))//"'"
                end select
                call write_lines(dir//"/"//checkpoint_name, [character(len=4000) :: saved(1:6), &
                                 line, saved(8:n)])
            else
                call write_lines(dir//"/"//checkpoint_name, [character(len=4000) :: saved(1:2), line, saved(4:n)])
            end if
            call run_sweep_case(c, resumed, error)
            call check_error(t, error, "damaged checkpoint refused: "//trim(names(k)), .true., &
                             [character(len=40) :: "frc.checkpoint: a damaged checkpoint", &
                              "delete it"])
            if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                             "damaged checkpoint: input error (exit 1): "// &
                                             trim(names(k)))
        end do
        ! a checkpoint of an earlier version (points without coefficients) is refused
        call remove_file(dir//"/"//checkpoint_name)
        call write_lines(dir//"/"//checkpoint_name, [character(len=4000) :: &
                         "stickslip sweep checkpoint 1", saved(2:n)])
        call run_sweep_case(c, resumed, error)
        call check_error(t, error, "checkpoint of an earlier version refused", .true., &
                         [character(len=40) :: "an earlier version of stickslip", &
                          "delete it"])
        ! the intact file still resumes
        call remove_file(dir//"/"//checkpoint_name)
        call write_lines(dir//"/"//checkpoint_name, saved)
        call run_sweep_case(c, resumed, error)
        call check_error(t, error, "damaged checkpoint: the intact one resumes", .false.)
        if (.not. allocated(error)) call check(t, resumed%resumed_points == 3, &
                                               "damaged checkpoint: 3 points resumed")
    contains
        !> A symbolic link `path` -> `target` (symlink(2)); the old file removed first.
        subroutine execute_symlink(target, path)
            character(len=*), intent(in) :: target, path
            integer(c_int) :: r
            r = c_symlink(target//c_null_char, path//c_null_char)
            call check(t, r == 0, "damaged checkpoint: symlink made")
        end subroutine execute_symlink
        function join(f) result(s)
            character(len=*), intent(in) :: f(:)
            character(len=:), allocatable :: s
            integer :: i
            s = ""
            do i = 1, size(f)
                s = s//" "//trim(f(i))
            end do
        end function join
    end subroutine test_damaged_checkpoint

    !> Bad &sweep input: a message naming the file, &sweep and the variable; exit code 1.
    subroutine test_bad_sweep_input(t)
        type(test_counter_t), intent(inout) :: t
        character(len=120) :: bad(7, 2)
        character(len=:), allocatable :: out, err
        character(len=*), parameter :: path = scratch//"/sweep_bad.nml"
        integer :: code, k
        bad(1, :) = [character(len=120) :: "&sweep parameter = 'stiffness', start = 1, stop = 2 /", &
                     "&sweep parameter"]
        bad(2, :) = [character(len=120) :: "&sweep start = 1 /", "&sweep stop: missing"]
        bad(3, :) = [character(len=120) :: "&sweep start = -1, stop = 2 /", "omega must stay > 0"]
        bad(4, :) = [character(len=120) :: "&sweep start = 1, stop = 2, step = -0.1 /", &
                     "&sweep step"]
        bad(5, :) = [character(len=120) :: "&sweep start = 1, stop = 2, max_points = 1 /", &
                     "&sweep max_points"]
        ! a step the range cannot be walked with (issue 17: 2000 points at the start before)
        bad(6, :) = [character(len=120) :: "&sweep start = 1, stop = 2, step = 1e-300 /", &
                     "&sweep step = 1.000E-300: must be 0 (automatic) or >="]
        bad(7, :) = [character(len=120) :: "&sweep start = 1, stop = 2, min_step = 1e-20 /", &
                     "&sweep min_step"]
        do k = 1, size(bad, 1)
            call write_lines(path, [sweep_case(1:5), bad(k, 1), &
                                    "&output directory = '"//scratch//"/sweep_bad' /"])
            call cli([character(len=200) :: path], code, out, err)
            call check(t, code == 1 .and. index(err, trim(bad(k, 2))) > 0 .and. &
                       index(err, path) > 0, "bad &sweep input "//trim(bad(k, 1)), err)
        end do
        call write_lines(path, [sweep_case(1:5), &
                                "&output directory = '"//scratch//"/sweep_bad' /"])
        call cli([character(len=200) :: path], code, out, err)
        call check(t, code == 1 .and. index(err, "&sweep: missing") > 0, &
                   "method 'sweep' without &sweep", err)
    end subroutine test_bad_sweep_input
end module test_sweep_files
