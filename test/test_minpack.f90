!> stickslip_minpack (solve_hybrj on the system's libminpack) on systems with known roots: a
!> circle meeting a line; a nested solve inside a residual (the outer solve's callback slot
!> must be restored: the outer root is then exact); a callback that asks to stop (an error of
!> category callback); the ftarget early stop; bad sizes and options.
module test_minpack
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_minpack, only: hybrj_options_t, hybrj_report_t, solve_hybrj
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_minpack_tests

    !> x^2 + y^2 = 4, x = y; stops (stat 1) at evaluation `stop_at` when > 0.
    type, extends(nonlinear_system_t) :: circle_t
        integer :: evaluations = 0
        integer :: stop_at = 0
    contains
        procedure :: residual => circle_residual
        procedure :: jacobian => circle_jacobian
    end type circle_t

    !> z^3 = a (the inner system of the nested solve).
    type, extends(nonlinear_system_t) :: cube_root_t
        real(dp) :: a = 0.0_dp
    contains
        procedure :: residual => cube_residual
        procedure :: jacobian => cube_jacobian
    end type cube_root_t

    !> cbrt(x) - 2 = 0, with cbrt computed by a nested solve_hybrj: root x = 8.
    type, extends(nonlinear_system_t) :: nested_t
        integer :: inner_failures = 0
    contains
        procedure :: residual => nested_residual
        procedure :: jacobian => nested_jacobian
    end type nested_t

contains

    subroutine run_minpack_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_circle(t)
        call test_nested(t)
        call test_stop_and_target(t)
        call test_bad_input(t)
    end subroutine run_minpack_tests

    subroutine test_circle(t)
        type(test_counter_t), intent(inout) :: t
        type(circle_t) :: sys
        type(hybrj_options_t) :: o
        type(hybrj_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: x(2)
        x = [1.0_dp, 0.5_dp]
        call solve_hybrj(sys, x, o, rep, error)
        call check_error(t, error, "minpack: circle solved", .false.)
        call check(t, rep%info == 1, "minpack: circle, info 1 (xtol met)")
        call check_close(t, x, [sqrt(2.0_dp), sqrt(2.0_dp)], "minpack: circle root (sqrt 2, sqrt 2)", &
                         rtol=1.0e-14_dp)
        call check(t, rep%fnorm < 1.0e-13_dp .and. rep%nfev == sys%evaluations .and. &
                   rep%njev >= 1, "minpack: circle report (fnorm, counts)")
    end subroutine test_circle

    subroutine test_nested(t)
        type(test_counter_t), intent(inout) :: t
        type(nested_t) :: sys
        type(hybrj_options_t) :: o
        type(hybrj_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: x(1)
        x = [3.0_dp]
        call solve_hybrj(sys, x, o, rep, error)
        call check_error(t, error, "minpack: nested solve", .false.)
        call check(t, sys%inner_failures == 0, "minpack: every inner solve succeeded")
        call check_close(t, x(1), 8.0_dp, "minpack: nested solve, outer root cbrt(x) = 2 -> 8", &
                         rtol=1.0e-12_dp)
    end subroutine test_nested

    subroutine test_stop_and_target(t)
        type(test_counter_t), intent(inout) :: t
        type(circle_t) :: sys
        type(hybrj_options_t) :: o
        type(hybrj_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: x(2), f(2)
        integer :: stat
        sys%stop_at = 3
        x = [1.0_dp, 0.5_dp]
        call solve_hybrj(sys, x, o, rep, error)
        call check_error(t, error, "minpack: a callback's stop is an error", .true.)
        if (allocated(error)) call check(t, error%stat == stickslip_stat%callback .and. &
                                         rep%callback_stat == 1 .and. rep%info == -1, &
                                         "minpack: ... of category callback, info -1")
        ! ftarget: stop at the first evaluation with ||F|| <= 1e-3, and return that point
        sys = circle_t()
        o%ftarget = 1.0e-3_dp
        x = [1.0_dp, 0.5_dp]
        call solve_hybrj(sys, x, o, rep, error)
        call check_error(t, error, "minpack: ftarget stop is not an error", .false.)
        stat = 0
        call sys%residual(x, f, stat)
        call check(t, rep%target_met .and. norm2(f) <= 1.0e-3_dp .and. &
                   abs(rep%fnorm - norm2(f)) <= 1.0e-15_dp, "minpack: ftarget met at the returned x")
    end subroutine test_stop_and_target

    subroutine test_bad_input(t)
        type(test_counter_t), intent(inout) :: t
        type(circle_t) :: sys
        type(hybrj_options_t) :: o
        type(hybrj_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: x0(0), x(2)
        call solve_hybrj(sys, x0, o, rep, error)
        call check_error(t, error, "minpack: no unknowns refused", .true., &
                         [character(len=16) :: "no unknowns"])
        o%mode = 2
        x = 1.0_dp
        call solve_hybrj(sys, x, o, rep, error)
        call check_error(t, error, "minpack: mode 2 without diag refused", .true., &
                         [character(len=16) :: "diag"])
        o%diag = [1.0_dp, -1.0_dp]
        call solve_hybrj(sys, x, o, rep, error)
        call check_error(t, error, "minpack: a negative diag refused", .true., &
                         [character(len=16) :: "positive"])
    end subroutine test_bad_input

    subroutine circle_residual(self, x, f, stat)
        class(circle_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        self%evaluations = self%evaluations + 1
        f = [x(1)**2 + x(2)**2 - 4.0_dp, x(1) - x(2)]
        if (self%evaluations == self%stop_at) stat = 1
    end subroutine circle_residual

    subroutine circle_jacobian(self, x, jac, stat)
        class(circle_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: jac(:, :)
        integer, intent(inout) :: stat
        jac = reshape([2.0_dp*x(1), 1.0_dp, 2.0_dp*x(2), -1.0_dp], [2, 2])
    end subroutine circle_jacobian

    subroutine cube_residual(self, x, f, stat)
        class(cube_root_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        f(1) = x(1)**3 - self%a
    end subroutine cube_residual

    subroutine cube_jacobian(self, x, jac, stat)
        class(cube_root_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: jac(:, :)
        integer, intent(inout) :: stat
        jac(1, 1) = 3.0_dp*x(1)**2
    end subroutine cube_jacobian

    !> cbrt(x) by an inner hybrj solve started at 1.
    real(dp) function inner_cbrt(self, a)
        class(nested_t), intent(inout) :: self
        real(dp), intent(in) :: a
        type(cube_root_t), target :: inner
        type(hybrj_options_t) :: o
        type(hybrj_report_t) :: rep
        type(error_type), allocatable :: error
        real(dp) :: z(1)
        inner%a = a
        z = [max(1.0_dp, a/3.0_dp)]
        call solve_hybrj(inner, z, o, rep, error)
        if (allocated(error) .or. rep%fnorm > 1.0e-12_dp*max(1.0_dp, abs(a))) &
            self%inner_failures = self%inner_failures + 1
        inner_cbrt = z(1)
    end function inner_cbrt

    subroutine nested_residual(self, x, f, stat)
        class(nested_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        if (.not. (x(1) > 0.0_dp)) then
            f(1) = x(1) - 2.0_dp    ! keep the iterate in x > 0 (a smooth continuation)
            return
        end if
        f(1) = inner_cbrt(self, x(1)) - 2.0_dp
    end subroutine nested_residual

    subroutine nested_jacobian(self, x, jac, stat)
        class(nested_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: jac(:, :)
        integer, intent(inout) :: stat
        real(dp) :: z
        if (.not. (x(1) > 0.0_dp)) then
            jac(1, 1) = 1.0_dp
            return
        end if
        z = inner_cbrt(self, x(1))
        jac(1, 1) = 1.0_dp/(3.0_dp*z**2)
    end subroutine nested_jacobian
end module test_minpack
