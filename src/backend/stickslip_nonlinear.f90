!> The solver-agnostic contract of a square nonlinear system F(x) = 0 with a Jacobian.
module stickslip_nonlinear
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: nonlinear_system_t

    !> A square system of n equations in n unknowns. Implementations own their work arrays,
    !> so one instance per thread.
    type, abstract :: nonlinear_system_t
    contains
        procedure(residual_iface), deferred :: residual
        procedure(jacobian_iface), deferred :: jacobian
    end type nonlinear_system_t

    abstract interface
        !> Evaluate f = F(x). Set stat /= 0 to ask the solver to stop.
        subroutine residual_iface(self, x, f, stat)
            import :: nonlinear_system_t, dp
            class(nonlinear_system_t), intent(inout) :: self
            real(dp), intent(in) :: x(:)
            real(dp), intent(out) :: f(:)
            integer, intent(inout) :: stat
        end subroutine residual_iface

        !> Evaluate jac = dF/dx (an element of the generalized Jacobian). stat /= 0 stops.
        subroutine jacobian_iface(self, x, jac, stat)
            import :: nonlinear_system_t, dp
            class(nonlinear_system_t), intent(inout) :: self
            real(dp), intent(in) :: x(:)
            real(dp), intent(out) :: jac(:, :)
            integer, intent(inout) :: stat
        end subroutine jacobian_iface
    end interface
end module stickslip_nonlinear
