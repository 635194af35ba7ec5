!> Tests of the case file reader, the CLI and the result files: every class of bad input is
!> rejected with a message naming the file, the group and the variable, and the right exit
!> code; the examples run end to end and write complete files.
module test_case
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_case, only: case_t, read_case, write_case
    use stickslip_files, only: make_directory
    use testing, only: test_counter_t, check, check_close, check_error
    use fixtures, only: enter_project_root, project_path, scratch, write_lines, good_system, &
        good_forcing, good_friction
    implicit none
    private
    public :: run_case_tests

    character(len=*), parameter :: good_hbm = "&hbm harmonics = 10, samples = 128 /"

contains

    subroutine run_case_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(scratch, error)
        call check_error(t, error, "scratch directory", .false.)
        if (allocated(error)) return
        call test_good_case(t)
        call test_bad_inputs(t)
        call test_strict_input(t)
        call test_size_limits(t)
        call test_method_inference(t)
        call test_unusual_valid(t)
        call test_round_trip(t)
        call test_round_trip_files(t)
        call test_examples_as_gfortran(t)
    end subroutine run_case_tests

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
        call expect_bad(t, "reduction_inline", [character(len=120) :: good_system, good_forcing, &
            good_friction, "&reduction method = 'craig-bampton' /"], inp, &
            [character(len=60) :: "&reduction method = 'craig-bampton'", "inline", &
             "never reduced"])
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

    !> Input once accepted silently or blamed on the wrong name (issue 10): every message
    !> names the group and the variable at fault.
    subroutine test_strict_input(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: inp = stickslip_stat%input
        character(len=120) :: base(4)
        base = [character(len=120) :: good_system, good_forcing, good_friction, good_hbm]
        call expect_bad(t, "unknown_group", [character(len=120) :: base, &
            "&solver tol = 1 /"], inp, [character(len=60) :: ":5:", "unknown group &solver", &
            "known: &system"])
        call expect_bad(t, "misspelled_group", [character(len=120) :: base(1:3), &
            "&hbmm harmonics = 10 /"], inp, [character(len=60) :: "unknown group &hbmm", &
            "did you mean &hbm?"])
        call expect_bad(t, "runs_group", [character(len=120) :: base, &
            "&runs method = 'euler' /"], inp, [character(len=60) :: "unknown group &runs", &
            "did you mean &run?"])
        call expect_bad(t, "duplicate_group", [character(len=120) :: base, good_system], inp, &
            [character(len=60) :: "group &system given twice (lines 1 and 5)"])
        call expect_bad(t, "misspelled_variable", [character(len=120) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffnesss = 2,-1,-1,1 /", good_forcing], inp, &
            [character(len=60) :: "&system stiffnesss: unknown variable", &
            "(did you mean stiffness?)"])
        call expect_bad(t, "bogus_variable", [character(len=120) :: base(1:3), &
            "&hbm harmonics = 10, bogus_variable = 3 /"], inp, &
            [character(len=60) :: "&hbm bogus_variable: unknown variable"])
        call expect_bad(t, "variable_twice", [character(len=120) :: base(1:3), &
            "&hbm harmonics = 10, samples = 64, harmonics = 12 /"], inp, &
            [character(len=60) :: "&hbm harmonics", "given twice"])
        call expect_bad(t, "nan_rho", [character(len=120) :: base(1:3), "&hbm rho = NaN /"], &
            inp, [character(len=60) :: "&hbm rho = NaN", "not a finite number"])
        call expect_bad(t, "inf_omega", [character(len=120) :: base(1), &
            "&forcing omega = Inf, force_dof = 1, force_amplitude = 10.0 /"], inp, &
            [character(len=60) :: "&forcing omega = Inf", "not a finite number"])
        call expect_bad(t, "string_for_real", [character(len=120) :: base(1), &
            "&forcing omega = 'fast', force_dof = 1, force_amplitude = 10.0 /"], inp, &
            [character(len=60) :: "&forcing omega = 'fast'", "a string"])
        call expect_bad(t, "unquoted_method", [character(len=120) :: base, &
            "&run method = hbm /"], inp, [character(len=60) :: "&run method = hbm", &
            "must be quoted"])
        call expect_bad(t, "long_method", [character(len=120) :: base, &
            "&run method = 'hbm             x' /"], inp, &
            [character(len=60) :: "&run method = 'hbm             x'", "must be 'hbm'"])
        call expect_bad(t, "long_start", [character(len=120) :: base(1:3), &
            "&hbm start = 'auto     x' /"], inp, [character(len=60) :: "&hbm start", "'ladder'"])
        call expect_bad(t, "too_many_values", [character(len=120) :: base(1), &
            "&forcing omega = 1, force_dof = 300*1, force_amplitude = 1 /"], inp, &
            [character(len=60) :: "&forcing force_dof", "too many values (at most 256"])
        call expect_bad(t, "integer_overflow", [character(len=120) :: base(1:3), &
            "&hbm harmonics = 10, maxfev = 99999999999 /"], inp, &
            [character(len=60) :: "&hbm maxfev = 99999999999", "out of range"])
        call expect_bad(t, "element_syntax", [character(len=120) :: &
            "&system ndof = 2, mass(1) = 1 /", good_forcing], inp, &
            [character(len=60) :: "&system mass(1)", "not supported"])
        call expect_bad(t, "comment_group_unclosed", [character(len=120) :: base, &
            "&euler steps_per_period = 100  ! closed below? no"], inp, &
            [character(len=60) :: "&euler", "not closed by '/'"])
        call expect_bad(t, "empty_directory", [character(len=120) :: base, &
            "&output directory = '  ' /"], inp, [character(len=60) :: "&output directory", &
            "must not be empty"])
        ! the units go into the pictures' gnuplot strings: no quotes, a known frequency axis
        call expect_bad(t, "quoted_unit", [character(len=120) :: base, &
            "&output length_unit = ""m'm"" /"], inp, [character(len=60) :: &
            "&output length_unit", "without quotes"])
        call expect_bad(t, "frequency_unit", [character(len=120) :: base, &
            "&output time_unit = 'ms', frequency_unit = 'rpm' /"], inp, &
            [character(len=60) :: "&output frequency_unit = 'rpm'", "'Hz'"])
        call expect_bad(t, "plot_amplitude", [character(len=120) :: base, &
            "&output plot_amplitude = 'peak' /"], inp, &
            [character(len=60) :: "&output plot_amplitude = 'peak'", "'half_peak_to_peak'"])
        ! binary garbage: never echoed raw
        block
            integer :: u, i
            type(case_t) :: c
            type(error_type), allocatable :: error
            character(len=*), parameter :: path = scratch//"/bad_binary.nml"
            logical :: printable
            open (newunit=u, file=path, access='stream', form='unformatted', &
                  status='replace', action='write')
            write (u) good_system//new_line('a')//"&forcing omega = 4.5"
            write (u) [(achar(mod(97*i + 3, 256)), i=1, 200)]
            close (u)
            call read_case(path, c, error)
            call check_error(t, error, "binary garbage rejected", .true., &
                             [character(len=40) :: path//":2:", "non-printable", "\x"])
            if (allocated(error)) then
                printable = all([(iachar(error%message(i:i)) >= 32 .and. &
                                  iachar(error%message(i:i)) <= 126, i=1, len(error%message))])
                call check(t, printable .and. len(error%message) < 200, &
                           "binary garbage: message printable and short", error%message)
                call check(t, error%stat == inp, "binary garbage: status input")
            end if
        end block
    end subroutine test_strict_input

    !> Sizes that cannot be honoured are input errors naming the variable and the limit.
    subroutine test_size_limits(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: inp = stickslip_stat%input
        character(len=120) :: base(3)
        type(case_t) :: c
        type(error_type), allocatable :: error
        base = [character(len=120) :: good_system, good_forcing, good_friction]
        call expect_bad(t, "huge_harmonics", [character(len=120) :: base, &
            "&hbm harmonics = 2147483647 /"], inp, &
            [character(len=60) :: "&hbm harmonics = 2147483647", "must be <= 4096"])
        call expect_bad(t, "huge_samples", [character(len=120) :: base, &
            "&hbm samples = 2147483647 /"], inp, &
            [character(len=60) :: "&hbm samples = 2147483647", "must be <= 1048576"])
        call expect_bad(t, "samples_over_limit", [character(len=120) :: base, &
            "&hbm harmonics = 10, samples = 1048577 /"], inp, &
            [character(len=60) :: "&hbm samples = 1048577", "must be <= 1048576"])
        call expect_bad(t, "huge_max_harmonics", [character(len=120) :: base, &
            "&hbm max_harmonics = 5000 /"], inp, &
            [character(len=60) :: "&hbm max_harmonics = 5000", "must be <= 4096"])
        call expect_bad(t, "huge_euler_steps", [character(len=120) :: base, &
            "&euler steps_per_period = 2000000000 /"], inp, &
            [character(len=60) :: "&euler steps_per_period = 2000000000", "must be <= 10000000"])
        call expect_bad(t, "euler_total_steps", [character(len=120) :: base, &
            "&euler steps_per_period = 10000000, max_periods = 2000 /"], inp, &
            [character(len=60) :: "&euler max_periods = 2000", "steps_per_period x max_periods"])
        call expect_bad(t, "huge_reference_samples", [character(len=120) :: base, &
            "&reference samples = 100000000 /"], inp, &
            [character(len=60) :: "&reference samples = 100000000", "must be <= 1000000"])
        call expect_bad(t, "huge_bracket_steps", [character(len=120) :: base, &
            "&reference bracket_steps = 2000000000 /"], inp, &
            [character(len=60) :: "&reference bracket_steps = 2000000000", "must be <= 100000"])
        call expect_bad(t, "hbm_unknowns", [character(len=120) :: base(1:2), &
            "&friction contact_dof = 1, 2, mu = 0.3, 0.3, normal_load = 1, 1 /", &
            "&hbm harmonics = 4096, samples = 16384 /"], inp, &
            [character(len=60) :: "&hbm harmonics = 4096", "16386 unknowns", "8193"])
        call expect_bad(t, "study_huge_harmonics", [character(len=120) :: base, &
            "&run method = 'study' /", "&study harmonics = 5, 99999 /"], inp, &
            [character(len=60) :: "&study harmonics", "<= 4096"])
        call expect_bad(t, "robustness_huge_grid", [character(len=120) :: base, &
            "&robustness omegas = 200*1.0, mus = 200*0.1, harmonics = 10 /"], inp, &
            [character(len=60) :: "&robustness", "runs, at most 100000"])
        call expect_bad(t, "sweep_max_points", [character(len=120) :: base, &
            "&sweep start = 1, stop = 2, max_points = 2000000000 /"], inp, &
            [character(len=60) :: "&sweep max_points = 2000000000", "must be <= 100000"])
        call expect_bad(t, "hbm_unknowns_auto_max", [character(len=120) :: base, &
            "&hbm harmonics = 1000, samples = 4096, harmonics_tol = 0.01 /"], inp, &
            [character(len=60) :: "&hbm max_harmonics = 0 (automatic", "16001 unknowns"])
        ! the unknowns count only for the methods that run the weighted residual
        call write_lines(scratch//"/euler_big_h.nml", [character(len=120) :: base(1:2), &
            "&friction contact_dof = 1, 2, mu = 0.3, 0.3, normal_load = 1, 1 /", &
            "&hbm harmonics = 4096, samples = 16384 /", "&run method = 'euler' /"])
        call read_case(scratch//"/euler_big_h.nml", c, error)
        call check_error(t, error, "&hbm harmonics unused by method euler: not limited", .false.)
        ! at the limit: accepted
        call write_lines(scratch//"/limit_samples.nml", [character(len=120) :: base, &
            "&hbm harmonics = 4096, samples = 1048576 /", &
            "&euler steps_per_period = 10000000, max_periods = 200 /", &
            "&reference samples = 1000000, bracket_steps = 100000 /"])
        call read_case(scratch//"/limit_samples.nml", c, error)
        call check_error(t, error, "sizes at their limits accepted", .false.)
        if (.not. allocated(error)) call check(t, c%hbm%samples == 2**20 .and. &
                                               c%hbm%harmonics == 4096, "sizes at the limit read")
    end subroutine test_size_limits

    !> &run method inferred from the one &study, &sweep or &robustness group; conflicts are
    !> errors naming both.
    subroutine test_method_inference(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: inp = stickslip_stat%input
        character(len=120) :: base(4)
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=60), parameter :: groups(3) = [character(len=60) :: &
            "&sweep start = 4, stop = 5 /", "&study harmonics = 3, 5 /", &
            "&robustness omegas = 4.5, mus = 0.45, harmonics = 10 /"]
        character(len=10), parameter :: methods(3) = [character(len=10) :: "sweep", "study", &
                                                      "robustness"]
        integer :: k
        base = [character(len=120) :: good_system, good_forcing, good_friction, good_hbm]
        do k = 1, 3
            call write_lines(scratch//"/infer.nml", [character(len=120) :: base, groups(k)])
            call read_case(scratch//"/infer.nml", c, error)
            call check_error(t, error, "method inferred from &"//trim(methods(k)), .false.)
            if (.not. allocated(error)) call check(t, c%method == methods(k), &
                                                   "method inferred: "//trim(methods(k)), c%method)
            call expect_bad(t, "conflict_"//trim(methods(k)), [character(len=120) :: base, &
                groups(k), "&run method = 'hbm' /"], inp, [character(len=80) :: "&"// &
                trim(methods(k))//" given but &run method = 'hbm'; set method = '"// &
                trim(methods(k))//"' or remove the group"])
        end do
        call expect_bad(t, "two_study_groups", [character(len=120) :: base, groups(1), &
            groups(2)], inp, [character(len=60) :: "&run method: missing", "&study", "&sweep"])
        call expect_bad(t, "method_all_with_study", [character(len=120) :: base, groups(2), &
            "&run method = 'all' /"], inp, [character(len=60) :: "&study given but", &
            "method = 'all'"])
    end subroutine test_method_inference

    !> Valid but unusual files: read exactly.
    subroutine test_unusual_valid(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=2100) :: long_dir
        integer :: i
        call write_lines(scratch//"/unusual.nml", [character(len=120) :: &
            "! the &euler group is not needed; neither is &sweep", &
            "&SYSTEM Ndof = 2,", &
            "  MASS = 1, 0,   ! comment after a comma inside an array", &
            "         0, 1,", &
            "  stiffness = 2 -1 -1 1   damping = 4*0.0", &
            "&END", &
            "&forcing omega = 4.5d0, force_dof = 1, force_amplitude = 1.0E+1 /", &
            "&friction contact_dof = 2, mu = .45, normal_load = 1 / ! &runs in a comment", &
            "&Hbm harmonics = 10, samples = 128, odd_only = .FALSE., stability = true /", &
            "&run method = ""euler"" /"])
        call read_case(scratch//"/unusual.nml", c, error)
        call check_error(t, error, "unusual valid file read", .false.)
        if (.not. allocated(error)) then
            call check(t, c%model%ndof == 2 .and. all(c%model%mass == reshape([1, 0, 0, 1], &
                       [2, 2])) .and. all(c%model%stiffness == reshape([2, -1, -1, 1], [2, 2])) &
                       .and. all(c%model%damping == 0.0_dp), "unusual file: matrices")
            call check(t, c%model%omega == 4.5_dp .and. c%model%force_amplitude(1) == 10.0_dp &
                       .and. c%model%mu(1) == 0.45_dp, "unusual file: reals")
            call check(t, c%hbm%harmonics == 10 .and. .not. c%hbm%odd_only .and. &
                       c%checks%stability .and. c%method == "euler", "unusual file: options")
        end if
        ! a directory of any length, kept whole
        long_dir = scratch//"/"
        do i = 1, 2000 - len(scratch) - 1
            long_dir(len(scratch) + 1 + i:len(scratch) + 1 + i) = achar(97 + mod(i, 26))
        end do
        call write_lines(scratch//"/long_dir.nml", [character(len=2200) :: good_system, &
            good_forcing, "&output directory = '"//trim(long_dir)//"' /"])
        call read_case(scratch//"/long_dir.nml", c, error)
        call check_error(t, error, "2000-character directory accepted", .false.)
        if (.not. allocated(error)) call check(t, c%directory == trim(long_dir), &
                                               "2000-character directory kept whole")
    end subroutine test_unusual_valid

    !> write_case output reads back as the same case, for every method and its groups.
    subroutine test_round_trip(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: a, b
        type(error_type), allocatable :: error
        integer :: u, stat, k
        character(len=200) :: msg
        character(len=120) :: extra(4)
        extra = [character(len=120) :: "&sweep parameter = 'mu', start = 0.4, stop = 0.5, "// &
                 "max_points = 50, plot = F /", "&study harmonics = 3, 1*5, samples = 0, "// &
                 "steps_per_period = 0 /", "&robustness omegas = 4, 5, mus = 0.3, "// &
                 "harmonics = 10, rhos = 0, steps_per_period = 100 /", &
                 "&run method = 'all' /  &euler steps_per_period = 500 /"]
        do k = 1, size(extra)
            call write_lines(scratch//"/trip_in.nml", [character(len=120) :: good_system, &
                "&forcing omega = 4.5, force_dof = 1, 2, force_amplitude = 10.0, 1, "// &
                "force_phase = 0.1, 0.3, force_harmonic = 1, 3 /", good_friction, &
                "&hbm harmonics = 12, samples = 64, rho = 0.2, tol = 1e-10, start = 'ladder' /", &
                extra(k)])
            call read_case(scratch//"/trip_in.nml", a, error)
            call check_error(t, error, "round trip: case read", .false.)
            if (allocated(error)) cycle
            open (newunit=u, file=scratch//"/trip_out.nml", status='replace', action='write')
            msg = ""
            call write_case(u, a, stat, msg)
            close (u)
            call read_case(scratch//"/trip_out.nml", b, error)
            call check_error(t, error, "round trip: write_case output reads back ("// &
                             trim(a%method)//")", .false.)
            if (allocated(error)) cycle
            call check(t, a%method == b%method .and. a%has_sweep .eqv. b%has_sweep, &
                       "round trip: method "//trim(a%method))
            call check(t, all(a%model%mass == b%model%mass) .and. &
                       all(a%model%force_phase == b%model%force_phase) .and. &
                       all(a%model%force_harmonic == b%model%force_harmonic) .and. &
                       a%model%omega == b%model%omega .and. all(a%model%mu == b%model%mu), &
                       "round trip: model exact ("//trim(a%method)//")")
            call check(t, a%hbm%harmonics == b%hbm%harmonics .and. a%hbm%rho == b%hbm%rho &
                       .and. a%hbm%tol == b%hbm%tol .and. a%hbm%start == b%hbm%start .and. &
                       a%euler%steps_per_period == b%euler%steps_per_period .and. &
                       a%directory == b%directory, "round trip: options ("//trim(a%method)//")")
            select case (a%method)
            case ('sweep')
                call check(t, b%sweep%parameter == 'mu' .and. b%sweep%start == 0.4_dp .and. &
                           b%sweep%max_points == 50 .and. .not. b%sweep%plot, &
                           "round trip: &sweep")
            case ('study')
                call check(t, all(b%study%harmonics == [3, 5]) .and. &
                           size(b%study%steps_per_period) == 0, "round trip: &study", "")
            case ('robustness')
                call check(t, all(b%robustness%omegas == [4.0_dp, 5.0_dp]) .and. &
                           all(b%robustness%steps_per_period == [100]), "round trip: &robustness")
            end select
        end do
    end subroutine test_round_trip

    !> write_case output reads back as the same model when &system uses Rayleigh factors
    !> (inline: the damping is echoed in full) and Matrix Market files (echoed as absolute
    !> paths, read back from the output directory of examples/beam_mm/beam.nml).
    subroutine test_round_trip_files(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: a, b
        type(error_type), allocatable :: error
        integer :: u, stat, k
        character(len=200) :: msg
        character(len=*), parameter :: inputs(2) = [character(len=40) :: &
            scratch//"/trip_rayleigh.nml", "examples/beam_mm/beam.nml"]
        call write_lines(inputs(1), [character(len=200) :: "&system ndof = 2, mass = 1,0,0,1, "// &
            "stiffness = 2,-1,-1,1, damping = 0.1,0,0,0, rayleigh_alpha = 0.3, "// &
            "rayleigh_beta = 0.01 /", good_forcing, good_friction])
        do k = 1, 2
            call read_case(trim(inputs(k)), a, error)
            call check_error(t, error, "round trip files: case read", .false.)
            if (allocated(error)) cycle
            call make_directory(scratch//"/trip_files", error)
            open (newunit=u, file=scratch//"/trip_files/echo.nml", status='replace', &
                  action='write')
            msg = ""
            call write_case(u, a, stat, msg)
            close (u)
            call read_case(scratch//"/trip_files/echo.nml", b, error)
            call check_error(t, error, "round trip files: echo reads back ("// &
                             trim(inputs(k))//")", .false.)
            if (allocated(error)) cycle
            call check(t, b%model%ndof == a%model%ndof .and. &
                       all(a%model%mass == b%model%mass) .and. &
                       all(a%model%stiffness == b%model%stiffness) .and. &
                       all(a%model%damping == b%model%damping), &
                       "round trip files: same M, K, C ("//trim(inputs(k))//")")
            call check(t, allocated(b%system_files%mass_file) .eqv. (k == 2), &
                       "round trip files: files echoed only for a model from files")
            if (k == 1) call check_close(t, [b%model%damping(1, 1), b%model%damping(2, 1), &
                b%model%damping(2, 2)], [0.1_dp + 0.3_dp + 0.01_dp*2, -0.01_dp, &
                0.3_dp + 0.01_dp], "round trip files: C = damping + alpha M + beta K", &
                rtol=1e-15_dp)
        end do
    end subroutine test_round_trip_files

    !> Every example reads as gfortran's own namelist read reads it (&system, &forcing,
    !> &friction, &hbm, &euler).
    subroutine test_examples_as_gfortran(t)
        type(test_counter_t), intent(inout) :: t
        character(len=20), parameter :: examples(9) = [character(len=20) :: "seed", &
            "mirrored", "chain4", "chain4_study", "many_sticks", "seed_euler", "seed_frc", &
            "seed_robustness", "seed_study"]
        integer, parameter :: big = 4096
        integer :: ndof, force_dof(256), force_harmonic(256), contact_dof(256), &
                   contact_dof2(256), harmonics, samples, maxfev, max_harmonics, &
                   verify_periods, steps_per_period, max_periods, k, u, stat, nf, nc, n
        real(dp) :: mass(big), stiffness(big), damping(big), omega, force_amplitude(256), &
                    force_phase(256), mu(256), normal_load(256), rho, tol, harmonics_tol
        logical :: odd_only, stability
        character(len=16) :: start
        namelist /system/ ndof, mass, stiffness, damping
        namelist /forcing/ omega, force_dof, force_harmonic, force_amplitude, force_phase
        namelist /friction/ contact_dof, contact_dof2, mu, normal_load
        namelist /hbm/ harmonics, odd_only, rho, samples, tol, start, maxfev, harmonics_tol, &
            max_harmonics, stability, verify_periods
        namelist /euler/ steps_per_period, max_periods, tol
        type(case_t) :: c
        type(error_type), allocatable :: error
        logical :: same
        do k = 1, size(examples)
            call read_case("examples/"//trim(examples(k))//".nml", c, error)
            call check_error(t, error, "example "//trim(examples(k))//" reads", .false.)
            if (allocated(error)) cycle
            damping = 0
            force_harmonic = 1
            force_phase = 0
            contact_dof = -1
            contact_dof2 = 0
            force_dof = 0
            ! the documented defaults
            harmonics = 30
            rho = 0
            samples = 1024
            odd_only = .false.
            steps_per_period = 1000
            open (newunit=u, file="examples/"//trim(examples(k))//".nml", status='old', &
                  action='read')
            read (u, nml=system)
            rewind (u)
            read (u, nml=forcing)
            rewind (u)
            read (u, nml=friction, iostat=stat)
            rewind (u)
            read (u, nml=hbm, iostat=stat)
            rewind (u)
            read (u, nml=euler, iostat=stat)
            close (u)
            n = ndof
            nf = count(force_dof > 0)
            nc = count(contact_dof > 0)
            same = c%model%ndof == n .and. all(reshape(c%model%mass, [n*n]) == mass(1:n*n)) &
                   .and. all(reshape(c%model%stiffness, [n*n]) == stiffness(1:n*n)) .and. &
                   all(reshape(c%model%damping, [n*n]) == damping(1:n*n))
            same = same .and. c%model%omega == omega .and. nf == size(c%model%force_dof) .and. &
                   all(c%model%force_dof == force_dof(1:nf)) .and. &
                   all(c%model%force_harmonic == force_harmonic(1:nf)) .and. &
                   all(c%model%force_amplitude == force_amplitude(1:nf)) .and. &
                   all(c%model%force_phase == force_phase(1:nf))
            same = same .and. nc == c%model%ncontact() .and. &
                   all(c%model%contact_dof == contact_dof(1:nc)) .and. &
                   all(c%model%contact_dof2 == contact_dof2(1:nc)) .and. &
                   all(c%model%mu == mu(1:nc)) .and. all(c%model%normal_load == normal_load(1:nc))
            same = same .and. c%hbm%harmonics == harmonics .and. c%hbm%rho == rho .and. &
                   c%hbm%samples == samples .and. (c%hbm%odd_only .eqv. odd_only) .and. &
                   c%euler%steps_per_period == steps_per_period
            call check(t, same, "example "//trim(examples(k))//": same values as gfortran's "// &
                       "namelist read")
        end do
    end subroutine test_examples_as_gfortran

end module test_case
