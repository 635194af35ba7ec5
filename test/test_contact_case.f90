!> The &friction variables of the contact laws (stickslip_case_friction): each form of the
!> normal and second tangential directions builds the same model; the echo in summary.nml
!> reads back as the same model; bad input is one message naming the variable and the
!> contact.
module test_contact_case
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_case, only: case_t, read_case, write_case
    use fixtures, only: enter_project_root, scratch, write_lines
    use testing, only: test_counter_t, check, check_error
    implicit none
    private
    public :: run_contact_case_tests

    !> A 4-DOF structure: DOFs 1, 2 in the contact plane, 3 normal, 4 a second body.
    character(len=*), parameter :: system4 = "&system ndof = 4, mass = 1,0,0,0, 0,1,0,0, "// &
        "0,0,1,0, 0,0,0,1, stiffness = 2,0,0,-1, 0,2,0,0, 0,0,3,0, -1,0,0,2 /"
    character(len=*), parameter :: forcing4 = "&forcing omega = 1.3, force_dof = 1, 3, "// &
        "force_amplitude = 1.0, 0.5 /"

contains

    subroutine run_contact_case_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()
        call test_forms(t)
        call test_echo(t)
        call test_bad(t)
    end subroutine run_contact_case_tests

    !> Read `lines` as a case; error on failure.
    subroutine read_lines(name, lines, c, error)
        character(len=*), intent(in) :: name
        character(len=*), intent(in) :: lines(:)
        type(case_t), intent(out) :: c
        type(error_type), allocatable, intent(out) :: error
        call write_lines(scratch//"/contact_"//name//".nml", lines)
        call read_case(scratch//"/contact_"//name//".nml", c, error)
    end subroutine read_lines

    !> The DOF form, the inline form and a file give the same directions; gap, preload and
    !> the stiffnesses are read per contact; normal_load may be left out when every contact
    !> is unilateral.
    subroutine test_forms(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: a, b, c
        type(error_type), allocatable :: error
        call read_lines("dof", [character(len=200) :: system4, forcing4, &
            "&friction contact_dof = 1, mu = 0.3, normal_dof = 0, normal_dof2 = 3, "// &
            "tangent2_dof = 2, gap = 1e-3, preload = 2, normal_stiffness = 50, "// &
            "tangential_stiffness = 20 /"], a, error)
        call check(t, .not. allocated(error), "contact_case: DOF form read", msg(error))
        if (allocated(error)) return
        call check(t, allocated(a%model%normal_direction) .and. &
                   allocated(a%model%tangent2_direction), "contact_case: directions built")
        if (.not. allocated(a%model%normal_direction)) return
        call check(t, all(a%model%normal_direction(:, 1) == [0.0_dp, 0.0_dp, -1.0_dp, 0.0_dp]) &
                   .and. all(a%model%tangent2_direction(:, 1) == [0.0_dp, 1.0_dp, 0.0_dp, &
                   0.0_dp]) .and. all(a%model%normal_load == 0.0_dp) .and. &
                   all(a%model%gap == 1.0e-3_dp) .and. all(a%model%preload == 2.0_dp) .and. &
                   all(a%model%normal_stiffness == 50.0_dp) .and. &
                   all(a%model%tangential_stiffness == 20.0_dp), &
                   "contact_case: DOF form values")
        call read_lines("inline", [character(len=200) :: system4, forcing4, &
            "&friction contact_dof = 1, mu = 0.3, normal_direction = 0, 0, -1, 0, "// &
            "tangent2_direction = 0, 1, 0, 0, gap = 1e-3, preload = 2, normal_stiffness = 50,"// &
            " tangential_stiffness = 20 /"], b, error)
        call check(t, .not. allocated(error), "contact_case: inline form read", msg(error))
        if (allocated(error)) return
        call check(t, all(b%model%normal_direction == a%model%normal_direction) .and. &
                   all(b%model%tangent2_direction == a%model%tangent2_direction), &
                   "contact_case: inline form = DOF form")
        call write_lines(scratch//"/contact_normal.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real general", "4 1 1", "3 1 -1"])
        call read_lines("file", [character(len=200) :: system4, forcing4, &
            "&friction contact_dof = 1, mu = 0.3, normal_file = 'contact_normal.mtx', "// &
            "tangent2_dof = 2, gap = 1e-3, preload = 2 /"], c, error)
        call check(t, .not. allocated(error), "contact_case: file form read", msg(error))
        if (allocated(error)) return
        call check(t, all(c%model%normal_direction == a%model%normal_direction), &
                   "contact_case: file form = DOF form")
        ! a plain contact beside a unilateral one: its normal_load is needed
        call read_lines("mixed", [character(len=200) :: system4, forcing4, &
            "&friction contact_dof = 1, 4, mu = 0.3, 0.2, normal_dof = 0, 0, normal_dof2 = 3,"// &
            " 0, normal_load = 0, 1.5, preload = 2, 0 /"], c, error)
        call check(t, .not. allocated(error), "contact_case: mixed contacts read", msg(error))
    end subroutine test_forms

    !> write_case's &friction reads back as the same model (every form).
    subroutine test_echo(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: a, b
        type(error_type), allocatable :: error
        character(len=*), parameter :: lines(3) = [character(len=200) :: system4, forcing4, &
            "&friction contact_dof = 1, mu = 0.3, normal_dof = 0, normal_dof2 = 3, "// &
            "tangent2_direction = 0, 1, 0, 0, gap = 1e-3, preload = 2, normal_stiffness = 50,"// &
            " tangential_stiffness = 20 /"]
        integer :: u, stat
        character(len=200) :: iomsg
        call read_lines("echo", lines, a, error)
        call check(t, .not. allocated(error), "contact_case: echo source read", msg(error))
        if (allocated(error)) return
        open (newunit=u, file=scratch//"/contact_echo_back.nml", status='replace', &
              action='write')
        call write_case(u, a, stat, iomsg)
        close (u)
        call read_case(scratch//"/contact_echo_back.nml", b, error)
        call check(t, .not. allocated(error), "contact_case: the echo reads back", msg(error))
        if (allocated(error)) return
        call check(t, all(b%model%normal_direction == a%model%normal_direction) .and. &
                   all(b%model%tangent2_direction == a%model%tangent2_direction) .and. &
                   all(b%model%gap == a%model%gap) .and. all(b%model%preload == a%model%preload) &
                   .and. all(b%model%normal_stiffness == a%model%normal_stiffness) .and. &
                   all(b%model%tangential_stiffness == a%model%tangential_stiffness) .and. &
                   b%friction_form%normal == 'dof' .and. b%friction_form%tangent2 == 'inline', &
                   "contact_case: the echo is the same model")
    end subroutine test_echo

    !> Bad input: one message naming the variable and the contact.
    subroutine test_bad(t)
        type(test_counter_t), intent(inout) :: t
        call bad("negative_gap", "contact_dof = 1, mu = 0.3, normal_dof2 = 3, gap = -1e-3", &
                 [character(len=60) :: "&friction gap(1) = ", "needs a preload"])
        call bad("zero_normal", "contact_dof = 1, mu = 0.3, normal_dof = 3, normal_dof2 = 3", &
                 [character(len=60) :: "&friction normal_dof2(1) = normal_dof(1) = 3", "zero"])
        call bad("not_orthogonal", "contact_dof = 1, mu = 0.3, normal_dof = 1, preload = 1", &
                 [character(len=60) :: "&friction normal_dof(1)", "not orthogonal"])
        call bad("t2_not_orthogonal", "contact_dof = 1, mu = 0.3, normal_load = 1, "// &
                 "tangent2_dof = 1, tangent2_dof2 = 2", &
                 [character(len=60) :: "&friction tangent2_dof(1)", "not orthogonal"])
        call bad("t2_on_normal", "contact_dof = 1, mu = 0.3, normal_dof = 3, tangent2_dof = 3", &
                 [character(len=60) :: "&friction tangent2_dof(1)", "normal direction"])
        call bad("mu_n_and_normal", "contact_dof = 1, mu = 0.3, normal_load = 1, "// &
                 "normal_dof = 3", &
                 [character(len=60) :: "&friction normal_load(1) = 1", "unilateral"])
        call bad("two_forms", "contact_dof = 1, mu = 0.3, normal_dof = 3, "// &
                 "normal_direction = 0,0,1,0", &
                 [character(len=60) :: "&friction normal_dof, normal_direction", &
                  "more than one form"])
        call bad("inline_count", "contact_dof = 1, mu = 0.3, normal_direction = 0,0,1", &
                 [character(len=60) :: "&friction normal_direction: 3 values", "expected"])
        call bad("zero_inline", "contact_dof = 1, mu = 0.3, normal_direction = 0,0,0,0", &
                 [character(len=60) :: "&friction normal_direction: column 1 is zero", &
                  "neither"])
        call bad("load_missing", "contact_dof = 1, 2, mu = 0.3, 0.3, normal_dof = 3, 0", &
                 [character(len=60) :: "&friction normal_load: missing", "contact 2"])
        call bad("dof_range", "contact_dof = 1, mu = 0.3, normal_dof = 9", &
                 [character(len=60) :: "&friction normal_dof(1) = 9", "1..4"])
        call bad("preload_plain", "contact_dof = 1, mu = 0.3, normal_load = 1, preload = 1", &
                 [character(len=60) :: "&friction preload(1): contact 1 has no normal", &
                  "normal_load"])
        call bad("negative_kt", "contact_dof = 1, mu = 0.3, normal_load = 1, "// &
                 "tangential_stiffness = -5", &
                 [character(len=60) :: "&friction tangential_stiffness(1) = -5", ">= 0"])
        call bad("gap_count", "contact_dof = 1, mu = 0.3, normal_dof = 3, gap = 0, 0", &
                 [character(len=60) :: "&friction gap: 2 values given, expected 1"])
        call bad("misspelled", "contact_dof = 1, mu = 0.3, normal_dof = 3, prelaod = 1", &
                 [character(len=60) :: "&friction prelaod: unknown variable", "preload"])
    contains
        subroutine bad(name, friction, fragments)
            character(len=*), intent(in) :: name, friction
            character(len=*), intent(in) :: fragments(:)
            type(case_t) :: c
            type(error_type), allocatable :: error
            character(len=200) :: expected(size(fragments))
            call read_lines("bad_"//name, [character(len=200) :: system4, forcing4, &
                            "&friction "//friction//" /"], c, error)
            expected = fragments
            call check_error(t, error, "contact_case: bad input "//name, .true., expected)
            if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                             "contact_case: bad input status "//name)
        end subroutine bad
    end subroutine test_bad

    function msg(error) result(text)
        type(error_type), allocatable, intent(in) :: error
        character(len=:), allocatable :: text
        text = ""
        if (allocated(error)) text = error%message
    end function msg
end module test_contact_case
