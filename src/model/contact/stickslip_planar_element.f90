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
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        action_decide, action_memory
    implicit none
    private
    public :: planar_element_t, new_planar_element

    !> Tolerance of the consistency tests (relative to the limit).
    real(dp), parameter :: tol = 1.0e-9_dp
    !> Slip speed below which the contact counts as at rest (relative to the velocity
    !> scale): a slip stops there (the flow's threshold, 1e-9 of the stop row's scale
    !> rest_speed / 1e-9 vref), and a start that slow is decided at acceleration level.
    real(dp), parameter :: rest_speed = 1.0e-6_dp

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

    !> Slipping: d . u, d the slip direction at the start of the step: at zero the slip
    !> stops and the contacts decide. Its scale is 1e3 vref: the flow takes the slip to stop
    !> at 1e-9 of the scale, 1e-6 vref (near rest the slip direction turns without limit;
    !> what is left of the slip would carry the contact (1e-6 vref)^2 / 2a further, a
    !> roundoff-sized distance). A slip started from rest (the memory's regime 1) also:
    !> 3e-6 vref - d . u (the same scale), at whose zero (2e-6 vref) the memory is updated
    !> (it follows the slip velocity from then on: slower, the roundoff of u / |u| would be
    !> above 1e-9).
    subroutine planar_step_rows(self, code, geom, dir, events)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: dir(:)
        type(event_list_t), intent(inout) :: events
        real(dp) :: row(geom%na)
        if (code(1) /= 1 .or. .not. (limit(self) > 0.0_dp)) return
        row = dir(1)*geom%vel_row(1) + dir(2)*geom%vel_row(2)
        call events%add(row, rest_speed/1.0e-9_dp*geom%vref, 1, action_decide)
        if (dir(3) >= 0.5_dp) call events%add(geom%const_row(3.0_dp*rest_speed*geom%vref) - &
                                              row, rest_speed/1.0e-9_dp*geom%vref, 1, &
                                              action_memory)
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
        if (speed(geom, y) > rest_speed*geom%vref .or. .not. (limit(self) > 0.0_dp)) then
            code(1) = 1
        else
            code(1) = 0
            decide = .true.
        end if
    end subroutine planar_start_code

    !> The slip speed |(w^T v, t2^T v)| at y (balanced).
    pure real(dp) function speed(geom, y)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        speed = hypot(dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n)), &
                      dot_product(geom%dt(:, 2), y(geom%n + 1:2*geom%n)))
    end function speed

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
        if (speed(geom, y) > rest_speed*geom%vref) then
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

    !> Slipping: following the slip (the memory's regime 0), q = -g u / |u| (u the slip
    !> velocity) and its Jacobian -g (I - u u^T / |u|^2) / |u| on the velocity rows. A slip
    !> starting from rest (regime 1, its speed below 1e-9 of the scale): the direction d the
    !> slip takes, u' = a - g W d along d (u' = lambda d, lambda >= 0), a the slip
    !> acceleration without the element's force and W its compliance (from the mode's
    !> dynamics yd0, gj), q = -g d and its Jacobian through a; without them, q = -g times
    !> the memory's direction. The regime changes between steps only (slip_direction), so
    !> that q is smooth over a step.
    subroutine planar_inputs(self, code, geom, y, dir, q, dq, yd0, dyd0, gj)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), dir(:)
        real(dp), intent(out) :: q(:), dq(:, :)
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        real(dp) :: u(2), un, uh(2), g, vr(2, geom%na), d(2), dd(2, geom%na)
        integer :: a, b
        g = limit(self)
        vr(1, :) = geom%vel_row(1)
        vr(2, :) = geom%vel_row(2)
        u = matmul(vr, y)
        un = norm2(u)
        dq = 0.0_dp
        if (dir(3) < 0.5_dp .and. un > 0.0_dp) then
            uh = u/un
            q = -g*uh
            do a = 1, 2
                do b = 1, 2
                    dq(a, :) = dq(a, :) - g*(merge(1.0_dp, 0.0_dp, a == b) - uh(a)*uh(b))/un* &
                               vr(b, :)
                end do
            end do
        else if (dir(3) >= 0.5_dp .and. present(yd0) .and. present(dyd0) .and. &
                 present(gj)) then
            call start_direction(g, matmul(vr, yd0), matmul(vr, dyd0), matmul(vr, gj), &
                                 dir(1:2), d, dd)
            q = -g*d
            dq(1:2, :) = -g*dd
        else
            q = -g*dir(1:2)
        end if
    end subroutine planar_inputs

    !> The direction d of a slip starting from rest: (lambda I + g W) d = a, |d| = 1,
    !> lambda >= 0 (lambda = 0 and d = (g W)^-1 a normalized when |(g W)^-1 a| <= 1: the
    !> onset itself), and its Jacobian dd = d(d)/dy from da (2 x na). d0 the direction
    !> memory when a = 0.
    pure subroutine start_direction(g, acc, dacc, w, d0, d, dd)
        real(dp), intent(in) :: g, acc(2), dacc(:, :), w(2, 2), d0(2)
        real(dp), intent(out) :: d(2), dd(:, :)
        real(dp) :: k(2, 2), ki(2, 2), v(2), lam, phi, dphi, kd(2), det, vn
        integer :: it, a
        dd = 0.0_dp
        lam = 0.0_dp
        do it = 1, 60
            k = g*w
            k(1, 1) = k(1, 1) + lam
            k(2, 2) = k(2, 2) + lam
            det = k(1, 1)*k(2, 2) - k(1, 2)*k(2, 1)
            if (.not. (abs(det) > 0.0_dp)) then
                d = d0
                return
            end if
            ki = reshape([k(2, 2), -k(2, 1), -k(1, 2), k(1, 1)], [2, 2])/det
            v = matmul(ki, acc)
            phi = dot_product(v, v) - 1.0_dp
            if (it == 1 .and. phi <= 0.0_dp) exit
            if (abs(phi) <= 4.0_dp*epsilon(1.0_dp)) exit
            dphi = -2.0_dp*dot_product(v, matmul(ki, v))
            if (.not. (dphi < 0.0_dp)) exit
            lam = max(lam - phi/dphi, 0.0_dp)
        end do
        vn = norm2(v)
        if (.not. (vn > 0.0_dp)) then
            d = d0
            return
        end if
        d = v/vn
        if (lam > 0.0_dp) then
            ! dd = K^-1 (da - d dlambda), dlambda = d . K^-1 da / d . K^-1 d
            kd = matmul(ki, d)
            do a = 1, size(dd, 2)
                v = matmul(ki, dacc(:, a))
                dd(:, a) = v - kd*dot_product(d, v)/dot_product(d, kd)
            end do
        else
            do a = 1, size(dd, 2)
                v = matmul(ki, dacc(:, a))
                dd(:, a) = (v - d*dot_product(d, v))/vn
            end do
        end if
    end subroutine start_direction

    !> Slipping, the memory: a direction (1:2) and a regime (3: 1 while a slip that started
    !> from rest is slower than 1.5 rest_speed of its scale, its direction from the
    !> dynamics; 0 once it follows the slip velocity). Entering a slip from stuck (fb the
    !> stuck forces' rows): against the stuck force in the regime 1, unless it already moves
    !> faster than rest_speed (then along its velocity, regime 0). Otherwise (after a step,
    !> at a start or at the memory's event): in the regime 0, or once faster than 1.5
    !> rest_speed, along the slip velocity in the regime 0; else kept.
    subroutine planar_slip_direction(self, code, geom, fb, y, dir)
        class(planar_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:)
        real(dp), intent(inout) :: dir(:)
        real(dp) :: r(2), u(2), un
        if (code(1) /= 1) return
        u = [dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n)), &
             dot_product(geom%dt(:, 2), y(geom%n + 1:2*geom%n))]
        un = norm2(u)
        if (size(fb, 1) >= 2) then
            if (un > rest_speed*geom%vref) then
                dir(1:2) = u/un
                dir(3) = 0.0_dp
            else
                r = matmul(fb(1:2, :), y)
                if (norm2(r) > 0.0_dp) dir(1:2) = -r/norm2(r)
                dir(3) = 1.0_dp
            end if
        else if ((dir(3) < 0.5_dp .or. un >= 1.5_dp*rest_speed*geom%vref) .and. &
                 un > 0.0_dp) then
            dir(1:2) = u/un
            dir(3) = 0.0_dp
        end if
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
