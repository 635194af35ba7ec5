!> Tests of stickslip_case_messages: the library names the arguments of the procedure that
!> failed (model%..., opts%...), the case reader names the file, group and variable; the
!> same bad input gives both forms with the same stat code.
module test_case_messages
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_model, only: model_t, validate_model
    use stickslip_solution, only: hbm_options_t
    use stickslip_hbm, only: validate_options
    use stickslip_sweep, only: sweep_options_t, validate_sweep_options
    use stickslip_reference, only: reference_options_t, validate_reference_options
    use stickslip_reference_start, only: reference_start_options_t, &
        validate_reference_start_options
    use stickslip_study, only: study_options_t, default_study_options, validate_study_options
    use stickslip_case, only: case_t, read_case, sweep_run_options_t
    use stickslip_case_messages, only: case_message, model_group
    use stickslip_files, only: make_directory
    use testing, only: test_counter_t, check, check_error
    use fixtures, only: enter_project_root, damped_seed, scratch, write_lines, good_system, &
        good_forcing, good_friction
    implicit none
    private
    public :: run_case_messages_tests


contains

    subroutine run_case_messages_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(scratch, error)
        call check_error(t, error, "case messages: scratch directory", .false.)
        if (allocated(error)) return
        call test_translation(t)
        call test_host_and_case_model(t)
        call test_host_and_case_options(t)
        call test_host_and_case_sweep(t)
        call test_moved_options(t)
        call test_host_and_case_study(t)
    end subroutine run_case_messages_tests

    subroutine expect(t, got, want, name)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: got, want, name
        call check(t, got == want, name, "got '"//got//"', want '"//want//"'")
    end subroutine expect

    !> The translation itself, on texts of each shape the library writes.
    subroutine test_translation(t)
        type(test_counter_t), intent(inout) :: t
        call expect(t, case_message("opts%harmonics = 5000: must be <= 4096", ['opts'], ['hbm ']), &
                    "&hbm harmonics = 5000: must be <= 4096", "translate: one option")
        call expect(t, case_message("opts%step, opts%min_step, opts%max_step: must be > 0", &
                                    ['opts'], ['sweep']), &
                    "&sweep step, min_step, max_step: must be > 0", "translate: a list")
        call expect(t, case_message("opts%step: need opts%min_step <= opts%step", ['opts'], &
                                    ['sweep']), "&sweep step: need min_step <= step", &
                    "translate: repeated names lose the argument")
        call expect(t, case_message("model%mu(2) = -0.100000: must be finite and >= 0", &
                                    [character(len=1) ::], [character(len=1) ::]), &
                    "&friction mu(2) = -0.100000: must be finite and >= 0", "translate: model%mu")
        call expect(t, case_message("model%mass: not symmetric: model%mass(2,1) = 1 but "// &
                                    "model%mass(1,2) = 0", [character(len=1) ::], &
                                    [character(len=1) ::]), &
                    "&system mass: not symmetric: mass(2,1) = 1 but mass(1,2) = 0", &
                    "translate: model%mass twice")
        call expect(t, case_message("model%force_dof(1) = 3: must be a DOF in 1..2 (ndof)", &
                                    [character(len=1) ::], [character(len=1) ::]), &
                    "&forcing force_dof(1) = 3: must be a DOF in 1..2 (ndof)", &
                    "translate: model%force_dof")
        call expect(t, case_message("opts: the grid asks for 9 runs", ['opts'], ['robustness']), &
                    "&robustness: the grid asks for 9 runs", "translate: the whole argument")
        call expect(t, case_message("copts%max_harmonics = 3: must be >= harmonics = 5 "// &
                                    "(ref%tol)", ['copts', 'ref  '], ['hbm      ', 'reference']), &
                    "&hbm max_harmonics = 3: must be >= harmonics = 5 (&reference tol)", &
                    "translate: two arguments, two groups")
        call expect(t, case_message("the options (xopts%tol, model%unknown, 'opts'): kept", &
                                    ['opts'], ['hbm ']), &
                    "the options (xopts%tol, model%unknown, 'opts'): kept", &
                    "translate: other names are kept")
        call check(t, model_group('normal_load') == 'friction' .and. model_group('ndof') == &
                   'system' .and. model_group('omega') == 'forcing' .and. &
                   model_group('nothing') == '', "model_group: groups of the components")
    end subroutine test_translation

    !> A bad friction coefficient: model%mu(2) from the host, &friction mu(2) from a case file.
    subroutine test_host_and_case_model(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/messages_mu.nml"
        m = damped_seed()
        m%contact_dof = [2, 1]
        m%contact_dof2 = [0, 0]
        m%mu = [0.45_dp, -0.1_dp]
        m%normal_load = [1.0_dp, 1.0_dp]
        call validate_model(m, error)
        call check_error(t, error, "host model: mu(2) < 0 rejected", .true., &
                         [character(len=40) :: "model%mu(2) = -0.1"])
        if (allocated(error)) then
            call check(t, index(error%message, "model%mu(2)") == 1 .and. &
                       index(error%message, "&") == 0 .and. &
                       error%stat == stickslip_stat%input, &
                       "host model: the message starts with the argument, no group", error%message)
        end if
        call write_lines(path, [character(len=120) :: good_system, good_forcing, &
                                "&friction contact_dof = 2, 1, mu = 0.45, -0.1, "// &
                                "normal_load = 1.0, 1.0 /", &
                                "&output directory = 'out' /"])
        call read_case(path, c, error)
        call check_error(t, error, "case model: mu(2) < 0 rejected", .true., &
                         [character(len=60) :: path//": &friction mu(2) = -0.1"])
        if (allocated(error)) then
            call check(t, index(error%message, "model%") == 0 .and. &
                       error%stat == stickslip_stat%input, &
                       "case model: no argument name, stat input", error%message)
        end if
        ! a matrix component: model%mass(1,1) against &system mass(1,1)
        m = damped_seed()
        m%mass(1, 1) = -1.0_dp
        call validate_model(m, error)
        call check_error(t, error, "host model: mass(1,1) < 0 rejected", .true., &
                         [character(len=40) :: "model%mass(1,1) = -1"])
        call write_lines(path, [character(len=120) :: &
                                "&system ndof = 2, mass = -1,0,0,1, stiffness = 2,-1,-1,1 /", &
                                good_forcing, good_friction, "&output directory = 'out' /"])
        call read_case(path, c, error)
        call check_error(t, error, "case model: mass(1,1) < 0 rejected", .true., &
                         [character(len=60) :: path//": &system mass(1,1) = -1"])
    end subroutine test_host_and_case_model

    !> Too many harmonics: opts%harmonics from the host, &hbm harmonics from a case file.
    subroutine test_host_and_case_options(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/messages_hbm.nml"
        o%harmonics = 5000
        o%samples = 16384
        call validate_options(o, error)
        call check_error(t, error, "host options: harmonics = 5000 rejected", .true., &
                         [character(len=40) :: "opts%harmonics = 5000: must be <= 4096"])
        if (allocated(error)) call check(t, index(error%message, "opts%harmonics") == 1 .and. &
                                         error%stat == stickslip_stat%input, &
                                         "host options: starts with opts%harmonics, stat input", &
                                         error%message)
        call write_lines(path, [character(len=120) :: good_system, good_forcing, good_friction, &
                                "&hbm harmonics = 5000, samples = 16384 /", &
                                "&output directory = 'out' /"])
        call read_case(path, c, error)
        call check_error(t, error, "case options: harmonics = 5000 rejected", .true., &
                         [character(len=80) :: path//": &hbm harmonics = 5000: must be <= 4096"])
        if (allocated(error)) call check(t, index(error%message, "opts%") == 0 .and. &
                                         error%stat == stickslip_stat%input, &
                                         "case options: no argument name, stat input", &
                                         error%message)
    end subroutine test_host_and_case_options

    !> A list of sweep variables: opts%step, opts%min_step, ... against &sweep step, min_step.
    subroutine test_host_and_case_sweep(t)
        type(test_counter_t), intent(inout) :: t
        type(sweep_options_t) :: so
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/messages_sweep.nml"
        so%start = 4.0_dp
        so%stop = 5.0_dp
        so%step = -1.0_dp
        call validate_sweep_options(damped_seed(), so, error)
        call check_error(t, error, "host sweep: step < 0 rejected", .true., &
                         [character(len=60) :: "opts%step, opts%min_step, opts%max_step: must"])
        call write_lines(path, [character(len=120) :: good_system, good_forcing, good_friction, &
                                "&sweep start = 4.0, stop = 5.0, step = -1 /", &
                                "&output directory = 'out' /"])
        call read_case(path, c, error)
        call check_error(t, error, "case sweep: step < 0 rejected", .true., &
                         [character(len=80) :: path//": &sweep step, min_step, max_step: must"])
    end subroutine test_host_and_case_sweep

    !> The start strategy lives in reference_start_options_t, resume and plot in
    !> sweep_run_options_t; the case file still reads and checks them under their names.
    subroutine test_moved_options(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_start_options_t) :: rs
        type(reference_options_t) :: ro
        type(sweep_run_options_t) :: sw
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/messages_moved.nml"
        call check(t, rs%start == 'auto' .and. sw%resume .and. sw%plot, &
                   "moved options: defaults auto, resume, plot")
        rs%start = 'cold'
        call validate_reference_start_options(rs, error)
        call check_error(t, error, "host start = 'cold' rejected", .true., &
                         [character(len=40) :: "opts%start = 'cold'", "'euler'"])
        ro = rs%reference_options_t
        call validate_reference_options(ro, error)
        call check_error(t, error, "the options of solve_reference know no start", .false.)
        rs%start = 'euler'
        rs%samples = 0
        call validate_reference_start_options(rs, error)
        call check_error(t, error, "host start: the base options still checked", .true., &
                         [character(len=40) :: "opts%samples = 0"])
        call write_lines(path, [character(len=120) :: good_system, good_forcing, good_friction, &
                                "&reference start = 'euler', samples = 64 /", &
                                "&sweep start = 4.0, stop = 5.0, resume = .false., plot = .false. /", &
                                "&output directory = 'out' /"])
        call read_case(path, c, error)
        call check_error(t, error, "moved options: case read", .false.)
        if (.not. allocated(error)) call check(t, c%reference%start == 'euler' .and. &
                                               c%reference%samples == 64 .and. &
                                               .not. c%sweep%resume .and. .not. c%sweep%plot &
                                               .and. c%sweep%stop == 5.0_dp, &
                                               "moved options: read from &reference, &sweep")
        call write_lines(path, [character(len=120) :: good_system, good_forcing, good_friction, &
                                "&reference samples = 0 /", "&output directory = 'out' /"])
        call read_case(path, c, error)
        call check_error(t, error, "case: &reference samples = 0 rejected", .true., &
                         [character(len=60) :: path//": &reference samples = 0: must be >= 1"])
    end subroutine test_moved_options

    !> A message that names two arguments: opts%samples of the study and hbm%samples of
    !> run_study's weighted-residual options, &study samples and &hbm samples in a case file.
    subroutine test_host_and_case_study(t)
        type(test_counter_t), intent(inout) :: t
        type(study_options_t) :: so
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/messages_study.nml"
        so = default_study_options()
        so%samples = [-1]
        call validate_study_options(so, error)
        call check_error(t, error, "host study: samples = -1 rejected", .true., &
                         [character(len=70) :: "opts%samples: every entry must be >= 0 (0: the "// &
                          "hbm%samples)"])
        call write_lines(path, [character(len=120) :: good_system, good_forcing, good_friction, &
                                "&study harmonics = 5, samples = -1 /", &
                                "&output directory = 'out' /"])
        call read_case(path, c, error)
        call check_error(t, error, "case study: samples = -1 rejected", .true., &
                         [character(len=90) :: path//": &study samples: every entry must be "// &
                          ">= 0 (0: the &hbm samples)"])
    end subroutine test_host_and_case_study
end module test_case_messages
