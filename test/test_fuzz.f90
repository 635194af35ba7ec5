!> Regressions found by bench/fuzz_cases.py (generated and mutated case files run through the
!> command line): every run ends with a clear one-line message or a result, never a runtime
!> error, raw bytes on standard error or a temporary file left behind.
module test_fuzz
    use stickslip_cli, only: stderr_line, with_exponent_e
    use stickslip_kinds, only: dp
    use stickslip_files, only: make_directory
    use stickslip_error, only: error_type
    use test_cli, only: cli
    use testing, only: test_counter_t, check
    use fixtures, only: enter_project_root, write_lines, scratch
    implicit none
    private
    public :: run_fuzz_tests

contains

    subroutine run_fuzz_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(scratch, error)
        call check(t, .not. allocated(error), "fuzz: scratch directory")
        if (allocated(error)) return
        call test_stderr_line(t)
        call test_raw_bytes_in_string(t)
        call test_failed_picture_removed(t)
        call test_reference_energy_nan(t)
        call test_directory_is_a_file(t)
        call test_usage_lines(t)
        call test_exponent_e(t)
    end subroutine run_fuzz_tests

    !> stderr_line: bytes outside printable ASCII as \xNN, a long run without blanks cut in
    !> its middle, short messages unchanged.
    subroutine test_stderr_line(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: s
        call check(t, stderr_line("stickslip: error: a.nml: &hbm rho = 1") == &
                   "stickslip: error: a.nml: &hbm rho = 1", "fuzz: plain message unchanged")
        s = stderr_line("x 'a"//achar(143)//achar(13)//achar(27)//"b' y")
        call check(t, s == "x 'a\x8F\x0D\x1Bb' y", "fuzz: raw bytes shown as \xNN", s)
        s = stderr_line("stickslip: error: nl"//new_line('a')//"x.nml: &hbm")
        call check(t, s == "stickslip: error: nl\x0Ax.nml: &hbm", &
                   "fuzz: a line feed (in a file name) keeps the message on one line", s)
        s = stderr_line("cannot create "//repeat("d", 5000)//" : denied")
        call check(t, len(s) < 200 .and. index(s, "...(5000 characters)...") > 0 .and. &
                   index(s, ": denied") > 0 .and. index(s, "cannot create dddd") == 1, &
                   "fuzz: a 5000-character name cut in its middle", s)
    end subroutine test_stderr_line

    !> A string value holding a byte of a binary file (fuzz: random bytes inside
    !> `method = 'robustness'`) is quoted by the validator's message: it reaches standard
    !> error as \xNN, on one line.
    subroutine test_raw_bytes_in_string(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err
        integer :: code, k
        logical :: printable
        call write_lines(scratch//"/fuzz_bytes.nml", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 10.0 /", &
            "&run method = 'robustne"//achar(143)//achar(200)//"ss' /"])
        call cli([character(len=200) :: scratch//"/fuzz_bytes.nml"], code, out, err)
        printable = .true.
        do k = 1, len(err)
            if (err(k:k) /= new_line('a') .and. (iachar(err(k:k)) < 32 .or. &
                iachar(err(k:k)) > 126)) printable = .false.
        end do
        call check(t, code == 1 .and. printable .and. index(err, "stickslip: error:") == 1, &
                   "fuzz: a raw byte in a string is shown as \xNN on standard error", err)
    end subroutine test_raw_bytes_in_string

    !> A sweep whose picture gnuplot cannot draw (zero forcing: every amplitude 0) leaves no
    !> frc.png.tmp (fuzz: zero_force/sweep).
    subroutine test_failed_picture_removed(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/fuzz_zero_sweep"
        character(len=:), allocatable :: out, err
        integer :: code
        logical :: tmp
        call write_lines(scratch//"/fuzz_zero_sweep.nml", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 0 /", &
            "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /", &
            "&hbm harmonics = 10, rho = 0.2, samples = 64 /", &
            "&sweep parameter = 'mu', start = 4.0, stop = 1.2, max_points = 5 /", &
            "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/fuzz_zero_sweep.nml"], code, out, err)
        inquire (file=dir//"/frc.png.tmp", exist=tmp)
        call check(t, code == 2 .and. .not. tmp, &
                   "fuzz: no frc.png.tmp left when gnuplot fails", err)
    end subroutine test_failed_picture_removed

    !> An exact reference whose work integrals overflow (force 1e308 at omega 1e6: amplitudes
    !> near 1e296) has a NaN energy balance error: the answer cannot be trusted (exit 2), not
    !> exit 0 with NaN in the summary (fuzz: omega_huge/reference, force_amplitude = 1e308).
    subroutine test_reference_energy_nan(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/fuzz_reference_nan"
        character(len=:), allocatable :: out, err
        integer :: code
        call write_lines(scratch//"/fuzz_reference_nan.nml", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 1e6, force_dof = 1, force_amplitude = 1e308 /", &
            "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /", &
            "&hbm harmonics = 30, rho = 0.2, samples = 1024 /", &
            "&reference samples = 8, bracket_steps = 100 /", &
            "&run method = 'reference' /", &
            "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: scratch//"/fuzz_reference_nan.nml", "--quiet"], &
                 code, out, err)
        call check(t, code == 2 .and. index(err, "energy balance error") > 0 .and. &
                   index(err, "NaN") > 0, "fuzz: a NaN energy balance of the reference is "// &
                   "untrusted (exit 2)", err)
    end subroutine test_reference_energy_nan

    !> An output directory that is an existing file, or below one: exit 3 with a message
    !> naming the case file, the directory and the component in the way (it was
    !> "<directory>: cannot create the output directory", which reads as if the directory
    !> were the case file).
    subroutine test_directory_is_a_file(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: file = scratch//"/fuzz_plain_file"
        character(len=:), allocatable :: out, err
        integer :: code
        call write_lines(file, [character(len=10) :: "not a dir"])
        call write_lines(scratch//"/fuzz_dir_file.nml", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 10.0 /", &
            "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /", &
            "&output directory = '"//file//"/sub' /"])
        call cli([character(len=200) :: scratch//"/fuzz_dir_file.nml", "--quiet"], code, out, err)
        call check(t, code == 3 .and. index(err, "stickslip: error: "//scratch// &
                   "/fuzz_dir_file.nml: cannot create the output directory '"//file// &
                   "/sub': '"//file//"' exists and is not a directory") == 1, &
                   "fuzz: an output directory below a file: exit 3 naming both", err)
        call write_lines(scratch//"/fuzz_dir_file.nml", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 10.0 /", &
            "&output directory = '"//file//"' /"])
        call cli([character(len=200) :: scratch//"/fuzz_dir_file.nml", "--quiet"], code, out, err)
        call check(t, code == 3 .and. index(err, "'"//file//"': it exists and is not a "// &
                   "directory") > 0, "fuzz: an output directory that is a file: exit 3", err)
    end subroutine test_directory_is_a_file

    !> A usage error: one `stickslip: error:` line, then the usage text as it is (its own
    !> lines, not \x0A); `--` ends the options, so a case file named "-x.nml" can be run.
    subroutine test_usage_lines(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: out, err
        integer :: code
        call cli([character(len=20) :: "--bogus"], code, out, err)
        call check(t, code == 1 .and. index(err, "stickslip: error: unknown option '--bogus'"// &
                   new_line('a')//"usage: stickslip CASE.nml") == 1 .and. &
                   index(err, "\x0A") == 0, "fuzz: usage error on one line, usage below", err)
        call write_lines("-fuzz_dash.nml", [character(len=80) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 10.0 /", &
            "&friction contact_dof = 2, mu = -0.45, normal_load = 1.0 /"])
        call cli([character(len=20) :: "--quiet", "--", "-fuzz_dash.nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "stickslip: error: -fuzz_dash.nml: &friction") &
                   == 1, "fuzz: '--' ends the options", err)
        open (newunit=code, file="-fuzz_dash.nml", status='old')
        close (code, status='delete')
        call cli([character(len=20) :: "--", "a.nml", "b.nml"], code, out, err)
        ! two case files are a multi-case run: each missing file is its own error (I/O, 3)
        ! (after a `stickslip: note:` line when the linked BLAS keeps the run on one thread)
        call check(t, code == 3 .and. index(err, "a.nml: stickslip: error: a.nml") > 0 .and. &
                   index(err, "b.nml: stickslip: error: b.nml") > &
                   index(err, "a.nml: stickslip: error: a.nml") .and. &
                   index(err, "stickslip: error:") == index(err, "a.nml: stickslip: error:") + 7, &
                   "fuzz: '--' and two files: two cases, each an I/O error", err)
    end subroutine test_usage_lines

    !> The human summary puts back the E that ES drops from a three-digit exponent
    !> (fuzz: force_amplitude = 1e308 printed "friction  1.8000+284").
    subroutine test_exponent_e(t)
        type(test_counter_t), intent(inout) :: t
        character(len=40) :: buf
        write (buf, '(a,es11.4,a,es9.2)') "friction ", 1.8e284_dp, ", tol ", 9.0e-302_dp
        call check(t, with_exponent_e(trim(buf)) == "friction  1.8000E+284, tol  9.00E-302", &
                   "fuzz: E put back in three-digit exponents", with_exponent_e(trim(buf)))
        call check(t, with_exponent_e("H = 30-100, x 1.5E-02, t=.00001, 2.5-1234") == &
                   "H = 30-100, x 1.5E-02, t=.00001, 2.5-1234", "fuzz: other text unchanged")
    end subroutine test_exponent_e
end module test_fuzz
