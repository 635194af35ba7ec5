!> Tests of the case file reader: every class of bad input is rejected with a message naming
!> the file, the group and the variable. (The command line and the result files: test_cli.)
module test_case
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_case, only: case_t, read_case
    use stickslip_output, only: make_directory
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_case_tests, write_lines, scratch

    character(len=*), parameter :: scratch = "build/test-scratch"
    character(len=*), parameter :: good_system = &
        "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /"
    character(len=*), parameter :: good_forcing = "&forcing omega = 4.5, force_dof = 1, " // &
        "force_amplitude = 10.0 /"
    character(len=*), parameter :: good_friction = "&friction contact_dof = 2, mu = 0.45, " // &
        "normal_load = 1.0 /"
    character(len=*), parameter :: good_hbm = "&hbm harmonics = 10, samples = 128 /"

contains

    subroutine run_case_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call make_directory(scratch, error)
        call check_error(t, error, "scratch directory", .false.)
        if (allocated(error)) return
        call test_good_case(t)
        call test_bad_inputs(t)
    end subroutine run_case_tests

    subroutine write_lines(path, lines)
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: lines(:)
        integer :: u, i
        open (newunit=u, file=path, status='replace', action='write')
        do i = 1, size(lines)
            write (u, '(a)') trim(lines(i))
        end do
        close (u)
    end subroutine write_lines

    subroutine test_good_case(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/good.nml"
        call write_lines(path, [character(len=120) :: good_system, good_forcing, good_friction, &
                                good_hbm, "&output directory = '"//scratch//"/good' /"])
        call read_case(trim(path), c, error)
        call check_error(t, error, "good case read", .false.)
        if (allocated(error)) return
        call check(t, c%model%ndof == 2 .and. size(c%model%mu) == 1, "good case: sizes")
        call check_close(t, c%model%stiffness(1, 2), -1.0_dp, "good case: column-major stiffness")
        call check_close(t, c%model%damping(2, 2), 0.0_dp, "good case: damping defaults to 0")
        call check(t, c%model%force_harmonic(1) == 1, "good case: force_harmonic defaults to 1")
        call check_close(t, c%model%force_phase(1), 0.0_dp, "good case: force_phase defaults to 0")
        call check(t, c%model%contact_dof2(1) == 0, "good case: contact_dof2 defaults to ground")
        call check(t, c%hbm%harmonics == 10 .and. c%hbm%samples == 128 .and. &
                   .not. c%hbm%odd_only, "good case: &hbm values")
        call check_close(t, c%hbm%rho, 0.0_dp, "good case: rho default (automatic)")
        call check(t, c%directory == scratch//"/good", "good case: output directory")

        ! the last group closed on a last line without newline, and no &friction group
        block
            integer :: u
            character(len=*), parameter :: nl = new_line('a')
            open (newunit=u, file=scratch//"/no_newline.nml", access='stream', &
                  form='unformatted', status='replace', action='write')
            write (u) good_system//nl//good_forcing//nl//"&output directory = 'x' /"
            close (u)
        end block
        call read_case(scratch//"/no_newline.nml", c, error)
        call check_error(t, error, "case without final newline and without &friction", .false.)
        if (.not. allocated(error)) then
            call check(t, c%directory == "x", "case without final newline: last group read")
            call check(t, c%model%ncontact() == 0, "case without &friction: no contact")
        end if
    end subroutine test_good_case

    !> One bad case: the error must carry the status and every expected fragment.
    subroutine expect_bad(t, name, lines, stat, fragments)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: name
        character(len=*), intent(in) :: lines(:)
        integer, intent(in) :: stat
        character(len=*), intent(in) :: fragments(:)
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=200) :: path, expected(size(fragments) + 1)
        path = scratch//"/bad_"//name//".nml"
        call write_lines(trim(path), lines)
        call read_case(trim(path), c, error)
        expected(1) = path
        expected(2:) = fragments
        call check_error(t, error, "bad input rejected: "//name, .true., expected)
        if (allocated(error)) call check(t, error%stat == stat, "bad input status: "//name, &
                                         error%message)
    end subroutine expect_bad

    subroutine test_bad_inputs(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(error_type), allocatable :: error
        integer, parameter :: inp = stickslip_stat%input
        character(len=120) :: base(4)
        base = [character(len=120) :: good_system, good_forcing, good_friction, good_hbm]

        call read_case(scratch//"/no_such_file.nml", c, error)
        call check_error(t, error, "missing case file rejected", .true., &
                         [character(len=60) :: "no_such_file.nml", "cannot open"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%io, "missing file: io")

        call expect_bad(t, "unknown_variable", [character(len=120) :: good_system, &
            "&forcing omega = 4.5, kx = 3, force_dof = 1, force_amplitude = 10.0 /", &
            good_friction], inp, [character(len=60) :: "&forcing", "kx"])
        call expect_bad(t, "bad_value", [character(len=120) :: &
            "&system ndof = two, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", good_forcing], inp, &
            [character(len=60) :: "&system", "two"])
        call expect_bad(t, "missing_group", [character(len=120) :: good_system, good_friction], &
            inp, [character(len=60) :: "&forcing", "required group not found"])
        call expect_bad(t, "unterminated", [character(len=120) :: good_system, &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 10.0"], inp, &
            [character(len=60) :: "&forcing", "not closed"])
        call expect_bad(t, "negative_mass", [character(len=120) :: &
            "&system ndof = 2, mass = -1,0,0,1, stiffness = 2,-1,-1,1 /", good_forcing], inp, &
            [character(len=60) :: "&system", "mass(1,1)", "must be > 0"])
        call expect_bad(t, "nonsymmetric_mass", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0.5,0,1, stiffness = 2,-1,-1,1 /", good_forcing], inp, &
            [character(len=60) :: "&system", "mass", "not symmetric"])
        call expect_bad(t, "indefinite_mass", [character(len=120) :: &
            "&system ndof = 2, mass = 1,2,2,1, stiffness = 2,-1,-1,1 /", good_forcing], inp, &
            [character(len=60) :: "&system", "mass", "not positive definite"])
        call expect_bad(t, "short_matrix", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0, stiffness = 2,-1,-1,1 /", good_forcing], inp, &
            [character(len=60) :: "&system", "mass", "3 values given", "expected ndof**2 = 4"])
        call expect_bad(t, "nan_stiffness", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,NaN /", good_forcing], inp, &
            [character(len=60) :: "&system", "stiffness(4)", "not a finite number"])
        call expect_bad(t, "negative_mu", [character(len=120) :: base(1:2), &
            "&friction contact_dof = 2, mu = -0.2, normal_load = 1.0 /"], inp, &
            [character(len=60) :: "&friction", "mu(1)", "must be finite and >= 0"])
        call expect_bad(t, "nan_mu", [character(len=120) :: base(1:2), &
            "&friction contact_dof = 2, mu = NaN, normal_load = 1.0 /"], inp, &
            [character(len=60) :: "&friction", "mu(1)", "not a finite number"])
        call expect_bad(t, "mu_count", [character(len=120) :: base(1:2), &
            "&friction contact_dof = 2, 1, mu = 0.3, normal_load = 1.0, 1.0 /"], inp, &
            [character(len=60) :: "&friction", "mu", "1 values given, expected 2"])
        call expect_bad(t, "dof_range", [character(len=120) :: base(1:2), &
            "&friction contact_dof = 3, mu = 0.3, normal_load = 1.0 /"], inp, &
            [character(len=60) :: "&friction", "contact_dof(1) = 3", "1..2"])
        call expect_bad(t, "too_few_samples", [character(len=120) :: base(1:3), &
            "&hbm harmonics = 30, samples = 50 /"], inp, &
            [character(len=60) :: "&hbm", "samples = 50", "too few samples", "61"])
        call expect_bad(t, "bad_rho", [character(len=120) :: base(1:3), &
            "&hbm harmonics = 10, samples = 64, rho = -1 /"], inp, &
            [character(len=60) :: "&hbm", "rho", ">= 0"])
        call expect_bad(t, "bad_start", [character(len=120) :: base(1:3), &
            "&hbm start = 'quick' /"], inp, [character(len=60) :: "&hbm", "start", "'ladder'"])
        call expect_bad(t, "missing_omega", [character(len=120) :: base(1), &
            "&forcing force_dof = 1, force_amplitude = 10.0 /"], inp, &
            [character(len=60) :: "&forcing", "omega", "missing"])
        call expect_bad(t, "negative_omega", [character(len=120) :: base(1), &
            "&forcing omega = -1, force_dof = 1, force_amplitude = 10.0 /"], inp, &
            [character(len=60) :: "&forcing", "omega", "> 0"])
        call expect_bad(t, "missing_ndof", [character(len=120) :: &
            "&system mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", good_forcing], inp, &
            [character(len=60) :: "&system", "ndof", "missing"])
        call expect_bad(t, "bad_method", [character(len=120) :: base, "&run method = 'magic' /"], &
            inp, [character(len=60) :: "&run", "method", "'euler'"])
        call expect_bad(t, "bad_steps", [character(len=120) :: base, &
            "&euler steps_per_period = 1 /"], inp, [character(len=60) :: "&euler", &
            "steps_per_period = 1", ">= 2"])
        call expect_bad(t, "reference_samples", [character(len=120) :: base, &
            "&reference samples = 0 /"], inp, [character(len=60) :: "&reference", &
            "samples = 0", ">= 1"])
        call expect_bad(t, "reference_start", [character(len=120) :: base, &
            "&reference start = 'cold' /"], inp, [character(len=60) :: "&reference", "start", &
            "'euler'"])
        call expect_bad(t, "reference_tol", [character(len=120) :: base, &
            "&reference tol = NaN /"], inp, [character(len=60) :: "&reference", "tol", &
            "not a finite number"])
        call expect_bad(t, "study_harmonics", [character(len=120) :: base, &
            "&study harmonics = 5, -1 /"], inp, [character(len=60) :: "&study", "harmonics", &
            ">= 1"])
        call expect_bad(t, "study_repeats", [character(len=120) :: base, &
            "&study repeats = 0 /"], inp, [character(len=60) :: "&study", "repeats = 0"])
        call expect_bad(t, "study_unknown", [character(len=120) :: base, &
            "&study harmonic = 5 /"], inp, [character(len=60) :: "&study", "harmonic"])
        call expect_bad(t, "relative_same_dof", [character(len=120) :: base(1:2), &
            "&friction contact_dof = 2, contact_dof2 = 2, mu = 0.3, normal_load = 1.0 /"], inp, &
            [character(len=60) :: "&friction", "contact_dof2(1)"])
    end subroutine test_bad_inputs
end module test_case
