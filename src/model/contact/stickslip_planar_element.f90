!> 2D (in-plane) Coulomb friction under a constant normal load (doc/contacts.md): the
!> channels [w, t2], the friction force r = (r_1, r_2) in the disk of radius g = mu N,
!> following the slip direction as it turns (the projection onto the disk,
!> stickslip_contact_law). Rigid.
!>
!> In the exact flow its code is 0 (stuck: the two constraints w^T v = t2^T v = 0, their
!> forces the friction force) or 1 (slipping: r = -g u/|u|, u = (w^T v, t2^T v) the slip
!> velocity, a force not linear in the state: the flow integrates the phase numerically,
!> stickslip_flow_nonlinear). Events: stuck, g^2 - |r|^2 (the force reaches the circle: it
!> slips against the force); slipping, d . u with d the slip direction at the start of the
!> step (the slip stops: the contacts decide anew). At rest the decision is Coulomb's law at
!> acceleration level (the disk: stuck inside, else slipping against the force).
module stickslip_planar_element
    use stickslip_kinds, only: dp
    use stickslip_friction_contact, only: friction_contact_t, init_friction_contact
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t
    use stickslip_disk_slip, only: rest_speed, slip_speed, disk_step_rows, disk_inputs, &
        disk_slip_direction
    implicit none
    private
    public :: planar_element_t, new_planar_element

    !> Tolerance of the consistency tests (relative to the limit).
    real(dp), parameter :: tol = 1.0e-9_dp
    !> 2D friction, constant normal load, rigid.
    type, extends(friction_contact_t) :: planar_element_t
    contains
        procedure :: law_name => planar_name
        procedure :: exact_support => planar_exact_support
        procedure :: mode_terms => planar_mode_terms
        procedure :: event_rows => planar_event_rows
        procedure :: step_rows => planar_step_rows
        procedure :: start_code => planar_start_code
        procedure :: coupled => planar_coupled
        procedure :: holds_constraint => planar_holds_constraint
        procedure :: candidates => planar_candidates
        procedure :: consistent => planar_consistent
        procedure :: inputs => planar_inputs
        procedure :: slip_direction => planar_slip_direction
        procedure :: accel_decision => planar_accel_decision
        procedure :: accel_code => planar_accel_code
    end type planar_element_t

contains

    !> The element of friction coefficient mu >= 0 and normal load >= 0 [N].
    function new_planar_element(mu, normal_load) result(self)
        !> Friction coefficient and normal load [N].
        real(dp), intent(in) :: mu, normal_load
        type(planar_element_t) :: self
        call init_friction_contact(self, 2, .false., mu, normal_load, 0.0_dp, 0.0_dp, &
                                   0.0_dp, 0.0_dp)
    end function new_planar_element

    pure function planar_name(self) result(name)
        class(planar_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "planar"
    end function planar_name

    !> Handled (its slipping phases integrated numerically).
    function planar_exact_support(self) result(why)
        class(planar_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
    end function planar_exact_support

    !> The limit mu N [N].
    pure real(dp) function limit(self)
        class(planar_element_t), intent(in) :: self
        limit = self%law%mu*self%law%normal_load
    end function limit

    !> Stuck: both directions constrained; slipping: the two friction components as
    !> nonlinear inputs along w and t2.
    subroutine planar_mode_terms(self, code, geom, terms)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        real(dp) :: scol(geom%ns), fcol(size(terms%fb, 1))
        integer :: a
        if (.not. (limit(self) > 0.0_dp)) return
        if (code(1) == 0) then
            call terms%constrain(geom%dt(:, 1), geom%dt(:, 1), geom%first, 0, 0.0_dp)
            call terms%constrain(geom%dt(:, 2), geom%dt(:, 2), geom%first + 1, 0, 0.0_dp)
            return
        end if
        scol = 0.0_dp
        do a = 1, 2
            fcol = 0.0_dp
            fcol(geom%first + a - 1) = 1.0_dp
            call terms%add_input(geom%index, geom%dt(:, a), scol, fcol)
        end do
    end subroutine planar_mode_terms

    !> Stuck: g^2 - |r|^2, at zero it slips.
    subroutine planar_event_rows(self, code, geom, fb, events)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        real(dp) :: g
        g = limit(self)
        if (.not. (g > 0.0_dp) .or. code(1) /= 0) return
        call events%add_quadratic(-matmul(transpose(fb(1:2, :)), fb(1:2, :)), g*g, g*g, 1, 1)
    end subroutine planar_event_rows

    !> Slipping: the rows of a slip's step (stickslip_disk_slip).
    subroutine planar_step_rows(self, code, geom, dir, events)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: dir(:)
        type(event_list_t), intent(inout) :: events
        if (code(1) /= 1 .or. .not. (limit(self) > 0.0_dp)) return
        call disk_step_rows(geom, dir, events)
    end subroutine planar_step_rows

    !> Slipping when the slip speed exceeds rest_speed of its scale; at rest the joint
    !> decision (a contact without limit slips).
    subroutine planar_start_code(self, geom, y, code, decide)
        class(planar_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        decide = .false.
        if (slip_speed(geom, y) > rest_speed*geom%vref .or. .not. (limit(self) > 0.0_dp)) then
            code(1) = 1
        else
            code(1) = 0
            decide = .true.
        end if
    end subroutine planar_start_code

    pure logical function planar_coupled(self) result(c)
        class(planar_element_t), intent(in) :: self
        c = limit(self) > 0.0_dp
    end function planar_coupled

    pure logical function planar_holds_constraint(self, code) result(h)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        h = code(1) == 0 .and. limit(self) > 0.0_dp
    end function planar_holds_constraint

    !> Moving (above rest_speed of the scale): slipping; at rest: stuck, then slipping.
    subroutine planar_candidates(self, code, geom, y, cand, ncand)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: cand(:, :)
        integer, intent(out) :: ncand
        if (slip_speed(geom, y) > rest_speed*geom%vref) then
            ncand = 1
            cand(1, 1) = 1
        else
            ncand = 2
            cand(1, 1:2) = [0, 1]
        end if
    end subroutine planar_candidates

    !> Stuck: the force inside the disk (1e-9); slipping: accepted (its direction from the
    !> stuck force, planar_slip_direction).
    logical function planar_consistent(self, code, moving, geom, fb, y, ydot) result(ok)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        logical, intent(in) :: moving
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:), ydot(:)
        ok = .true.
        if (code(1) == 0) ok = hypot(dot_product(fb(1, :), y), dot_product(fb(2, :), y)) <= &
                               limit(self)*(1.0_dp + tol)
    end function planar_consistent

    !> Slipping: the friction force of the slip against the disk of radius mu N
    !> (stickslip_disk_slip).
    subroutine planar_inputs(self, code, geom, y, dir, fb, fq, q, dq, yd0, dyd0, gj)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), dir(:), fb(:, :), fq(:, :)
        real(dp), intent(out) :: q(:), dq(:, :)
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        call disk_inputs(geom, geom%const_row(limit(self)), y, dir, q, dq, yd0, dyd0, gj)
    end subroutine planar_inputs

    !> Slipping, the memory of the slip (stickslip_disk_slip).
    subroutine planar_slip_direction(self, code, geom, fb, y, dir)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:)
        real(dp), intent(inout) :: dir(:)
        if (code(1) == 1) call disk_slip_direction(geom, fb, y, dir)
    end subroutine planar_slip_direction

    pure logical function planar_accel_decision(self) result(yes)
        class(planar_element_t), intent(in) :: self
        yes = limit(self) > 0.0_dp
    end function planar_accel_decision

    !> Stuck where the force is inside the disk (1e-12), else slipping against it.
    subroutine planar_accel_code(self, r, u, code, dir)
        class(planar_element_t), intent(in) :: self
        real(dp), intent(in) :: r(:), u(:)
        integer, intent(inout) :: code(:)
        real(dp), intent(inout) :: dir(:)
        if (norm2(r(1:2)) < limit(self)*(1.0_dp - 1.0e-12_dp)) then
            code(1) = 0
        else
            code(1) = 1
            dir(1:2) = -r(1:2)/norm2(r(1:2))
            dir(3) = 1.0_dp
        end if
    end subroutine planar_accel_code
end module stickslip_planar_element
