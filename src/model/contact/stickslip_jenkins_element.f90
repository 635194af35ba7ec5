!> The Jenkins element (doc/contacts.md): a spring of stiffness k_t in series with a Coulomb
!> slider, in 1D (channel w) or 2D (channels [w, t2], the slider force in the disk), under a
!> constant normal load. Stuck, the contact is the spring; slipping, the force is on the
!> limit mu N and the slider moves. The channel's kinematic quantity is the slider velocity
!> w^T x' + r' / k_t (its compliance 1 / k_t).
!>
!> In the exact flow (1D) the slider position s is an internal state: the force on the
!> structure is r = -k_t (w^T x - s). Stuck (code 0): s' = 0, r is the spring's; slipping
!> with direction c: r = -c mu N, s' = w^T v. Events: stuck, mu N -/+ r (the spring reaches
!> the limit: it slips against the force); slipping, c w^T v (the slider stops: it sticks
!> unless the structure goes on accelerating the same way, a graze), decided alone: the force
!> is continuous at the event, so the structure's acceleration does not depend on it.
!> In 2D the slider s (2) and the force r = -k_t (P x - s) (P = [w^T; t2^T]) are linear in
!> the state in both modes; slipping (code 1), |r| = mu N and the slider moves along -r:
!> s' = r (r . P v) / (mu N)^2, not linear (nonlinear inputs of the slider rates: the flow
!> integrates the phase numerically). Events, quadratic in the state: stuck, (mu N)^2 - |r|^2
!> (it slips); slipping, -r . P v (the slider's speed reaches zero: it sticks unless the
!> speed turns up again).
module stickslip_jenkins_element
    use stickslip_kinds, only: dp
    use stickslip_friction_contact, only: friction_contact_t, init_friction_contact
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        action_decide
    implicit none
    private
    public :: jenkins_element_t, new_jenkins_element
    public :: slider_terms, slider_events, slider_start, slider_project, slider_decide, &
        disk_slider_terms, disk_slider_on_edge, slider_force_rows, slider_velocity_rows

    !> A spring k_t in series with a Coulomb slider, 1D or 2D, constant normal load.
    type, extends(friction_contact_t) :: jenkins_element_t
    contains
        procedure :: law_name => jenkins_name
        procedure :: exact_support => jenkins_exact_support
        procedure :: nstate => jenkins_nstate
        procedure :: state_scales => jenkins_state_scales
        procedure :: initial_states => jenkins_initial_states
        procedure :: mode_terms => jenkins_mode_terms
        procedure :: event_rows => jenkins_event_rows
        procedure :: start_code => jenkins_start_code
        procedure :: start_states => jenkins_start_states
        procedure :: local_decide => jenkins_local_decide
        procedure :: inputs => jenkins_inputs
    end type jenkins_element_t

contains

    !> The element with `ntangent` (1 or 2) tangential directions, friction coefficient mu >=
    !> 0, normal load >= 0 [N] and tangential stiffness k_t > 0 [N/m].
    function new_jenkins_element(ntangent, mu, normal_load, kt) result(self)
        !> Tangential directions.
        integer, intent(in) :: ntangent
        !> Friction coefficient, normal load [N], tangential stiffness [N/m].
        real(dp), intent(in) :: mu, normal_load, kt
        type(jenkins_element_t) :: self
        call init_friction_contact(self, ntangent, .false., mu, normal_load, 0.0_dp, 0.0_dp, &
                                   0.0_dp, kt)
    end function new_jenkins_element

    pure function jenkins_name(self) result(name)
        class(jenkins_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "jenkins"
    end function jenkins_name

    !> Handled, in 1D and 2D.
    function jenkins_exact_support(self) result(why)
        class(jenkins_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
    end function jenkins_exact_support

    !> The rows of y of a 2D slider's spring force r_a = -k_t (d_a^T x - s_a) (a = 1, 2).
    pure function slider_force_rows(kt, geom) result(f)
        !> The spring's stiffness [N/m].
        real(dp), intent(in) :: kt
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        real(dp) :: f(2, geom%na)
        integer :: a
        do a = 1, 2
            f(a, :) = -kt*geom%disp_row(a) + kt*geom%state_row(a)
        end do
    end function slider_force_rows

    !> The rows of y of P v = (w^T v, t2^T v).
    pure function slider_velocity_rows(geom) result(v)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        real(dp) :: v(2, geom%na)
        v(1, :) = geom%vel_row(1)
        v(2, :) = geom%vel_row(2)
    end function slider_velocity_rows

    !> One slider position per tangential direction.
    pure integer function jenkins_nstate(self) result(k)
        class(jenkins_element_t), intent(in) :: self
        k = self%law%ntangent
    end function jenkins_nstate

    !> sqrt(k_t): the slider scaled like the modal coordinates.
    pure subroutine jenkins_state_scales(self, c)
        class(jenkins_element_t), intent(in) :: self
        real(dp), intent(out) :: c(:)
        c = sqrt(self%kt)
    end subroutine jenkins_state_scales

    !> s = w^T x + r / k_t (the spring's force r = -k_t (w^T x - s)).
    pure subroutine jenkins_initial_states(self, dx, r, s)
        class(jenkins_element_t), intent(in) :: self
        real(dp), intent(in) :: dx(:), r(:)
        real(dp), intent(out) :: s(:)
        integer :: k
        do k = 1, self%law%ntangent
            s(k) = dx(k) + r(k)/self%kt
        end do
    end subroutine jenkins_initial_states

    !> 1D: the slider's terms (slider_terms). 2D: the spring force along w and t2 in both
    !> modes; slipping, the slider rates as nonlinear inputs.
    subroutine jenkins_mode_terms(self, code, geom, terms)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        if (self%law%ntangent == 1) then
            call slider_terms(code(1), self%kt, self%law%mu*self%law%normal_load, 1, 1, &
                              geom%first, geom, terms)
            return
        end if
        call disk_slider_terms(slider_force_rows(self%kt, geom), code(1) == 1, geom, terms)
    end subroutine jenkins_mode_terms

    !> A 2D slider's terms: the spring's force (rows f, 2 x na) along w and t2 on the first
    !> two channels; slipping, the two slider rates as nonlinear inputs (the element's
    !> `inputs`).
    subroutine disk_slider_terms(f, slipping, geom, terms)
        !> The spring's force as rows of y.
        real(dp), intent(in) :: f(:, :)
        !> Whether the slider slips.
        logical, intent(in) :: slipping
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The mode's terms.
        type(mode_terms_t), intent(inout) :: terms
        real(dp) :: ucol(geom%n), scol(geom%ns), fcol(size(terms%fb, 1))
        integer :: a
        do a = 1, 2
            call terms%add_force(geom%dt(:, a), f(a, :))
            terms%fb(geom%first + a - 1, :) = f(a, :)
        end do
        if (.not. slipping) return
        ucol = 0.0_dp
        fcol = 0.0_dp
        do a = 1, 2
            scol = 0.0_dp
            scol(geom%s0 + a) = geom%cs(a)
            call terms%add_input(geom%index, ucol, scol, fcol)
        end do
    end subroutine disk_slider_terms

    !> 2D slipping: the slider rates s' = r (r . P v) / g^2 and their Jacobian.
    subroutine jenkins_inputs(self, code, geom, y, dir, fb, fq, q, dq, yd0, dyd0, gj)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), dir(:), fb(:, :), fq(:, :)
        real(dp), intent(out) :: q(:), dq(:, :)
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        real(dp) :: f(2, geom%na), v(2, geom%na), r(2), pv(2), g2, rv
        integer :: a
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        r = matmul(f, y)
        pv = matmul(v, y)
        g2 = (self%law%mu*self%law%normal_load)**2
        rv = dot_product(r, pv)
        q = r*rv/g2
        do a = 1, 2
            dq(a, :) = (rv*f(a, :) + r(a)*(matmul(pv, f) + matmul(r, v)))/g2
        end do
    end subroutine jenkins_inputs

    !> 1D: the slider's events. 2D: stuck, g^2 - |r|^2 (it slips); slipping, -r . P v (the
    !> slider stops: decided alone).
    subroutine jenkins_event_rows(self, code, geom, fb, events)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        real(dp) :: f(2, geom%na), v(2, geom%na), g
        g = self%law%mu*self%law%normal_load
        if (self%law%ntangent == 1) then
            call slider_events(code(1), g, 1, fb(1, :), geom, events)
            return
        end if
        if (.not. (g > 0.0_dp)) return
        f = slider_force_rows(self%kt, geom)
        if (code(1) == 0) then
            call events%add_quadratic(-matmul(transpose(f), f), g*g, g*g, 1, 1)
        else
            v = slider_velocity_rows(geom)
            call events%add_quadratic(-0.5_dp*(matmul(transpose(f), v) + &
                                               matmul(transpose(v), f)), 0.0_dp, &
                                      g*geom%vref, 1, action_decide)
        end if
    end subroutine jenkins_event_rows

    !> 1D: slider_start. 2D: stuck inside the circle (1e-9), else slipping when the
    !> structure moves the spring outward (-r . P v above 1e-12 of its scale), else stuck.
    subroutine jenkins_start_code(self, geom, y, code, decide)
        class(jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        real(dp) :: r(2), g
        decide = .false.
        g = self%law%mu*self%law%normal_load
        if (self%law%ntangent == 1) then
            code(1) = slider_start(self%kt, g, 1, geom, y)
            return
        end if
        code(1) = 0
        if (.not. (g > 0.0_dp)) then
            code(1) = 1
            return
        end if
        r = matmul(slider_force_rows(self%kt, geom), y)
        if (norm2(r) < g*(1.0_dp - 1.0e-9_dp)) return
        if (-dot_product(r, matmul(slider_velocity_rows(geom), y)) > 1.0e-12_dp*g*geom%vref) &
            code(1) = 1
    end subroutine jenkins_start_code

    !> 1D: slider_project. 2D: a slipping slider's spring, or a stuck one's beyond the
    !> limit, put radially on the circle |r| = mu N (disk_slider_on_edge).
    subroutine jenkins_start_states(self, code, geom, fb, y, pj)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        real(dp), intent(inout) :: y(:)
        real(dp), intent(inout) :: pj(:, :)
        real(dp) :: f(2, geom%na), g
        g = self%law%mu*self%law%normal_load
        if (self%law%ntangent == 1) then
            call slider_project(self%kt, g, code(1), 1, geom, y, pj)
            return
        end if
        if (.not. (g > 0.0_dp)) return
        f = slider_force_rows(self%kt, geom)
        if (code(1) == 0 .and. norm2(matmul(f, y)) <= g) return
        call disk_slider_on_edge(self%kt, geom, f, geom%const_row(g), y, pj)
    end subroutine jenkins_start_states

    !> 1D: slider_decide. 2D: a slipping slider whose speed -r . P v reached zero sticks,
    !> unless the speed turns up again (its rate above 1e-9 of the scale).
    subroutine jenkins_local_decide(self, code, geom, y, ydot)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(inout) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), ydot(:)
        real(dp) :: f(2, geom%na), v(2, geom%na), g, speed, rate
        if (self%law%ntangent == 1) then
            call slider_decide(code(1), geom, y, ydot)
            return
        end if
        if (code(1) /= 1) return
        g = self%law%mu*self%law%normal_load
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        speed = -dot_product(matmul(f, y), matmul(v, y))
        if (speed > 1.0e-9_dp*g*geom%vref) return
        rate = -dot_product(matmul(f, ydot), matmul(v, y)) - &
               dot_product(matmul(f, y), matmul(v, ydot))
        if (.not. (rate > 1.0e-9_dp*g*geom%vref*geom%omega)) code(1) = 0
    end subroutine jenkins_local_decide

    !> A 2D slider's spring put on the edge |r| = g of its disk along the direction of u =
    !> urows y: s = P x + g u / (k_t |u|), and the Jacobian ds = P dx + (u^ dg + (g / |u|) (I
    !> - u^ u^T) du) / k_t (u^ = u / |u|). Nothing when u = 0.
    subroutine disk_slider_on_edge(kt, geom, urows, g, y, pj)
        !> The spring's stiffness [N/m].
        real(dp), intent(in) :: kt
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The rows of u (2 x na) and of the limit g [N] (na).
        real(dp), intent(in) :: urows(:, :), g(:)
        !> The state (balanced), corrected in place.
        real(dp), intent(inout) :: y(:)
        !> The Jacobian of the corrections (nz x nz), composed: pj <- P pj.
        real(dp), intent(inout) :: pj(:, :)
        real(dp) :: u(2), un, gv, uh(2), du(2, size(pj, 1)), d(2, size(pj, 1)), &
                    dg(size(pj, 1)), drow(geom%na), prow(size(pj, 1))
        integer :: a, b, nz, idx
        u = matmul(urows, y)
        un = norm2(u)
        if (.not. un > 0.0_dp) return
        gv = dot_product(g, y)
        uh = u/un
        nz = size(pj, 1)
        do a = 1, 2
            drow = geom%disp_row(a)
            d(a, :) = matmul(drow(1:nz), pj)
            du(a, :) = matmul(urows(a, 1:nz), pj)
        end do
        dg = matmul(g(1:nz), pj)
        do a = 1, 2
            idx = 2*geom%n + geom%s0 + a
            y(idx) = geom%cs(a)*(dot_product(geom%disp_row(a), y) + gv*uh(a)/kt)
            prow = d(a, :) + uh(a)*dg/kt
            do b = 1, 2
                prow = prow + gv/un*(merge(1.0_dp, 0.0_dp, a == b) - uh(a)*uh(b))*du(b, :)/ &
                       kt
            end do
            pj(idx, :) = geom%cs(a)*prow
        end do
    end subroutine disk_slider_on_edge

    ! --- one slider (k, limit g) along w with internal state k_state: shared by the Jenkins
    ! and the microslip elements ---

    !> A slider's mode: stuck (code 0), the spring's force -k (w^T x - s) on channel ch and
    !> s' = 0; slipping with direction c, the force -c g and s' = w^T v.
    subroutine slider_terms(code, k, g, state, slot, ch, geom, terms)
        !> The slider's code.
        integer, intent(in) :: code
        !> Its stiffness [N/m] and limit [N].
        real(dp), intent(in) :: k, g
        !> Its internal state and code slot in the element, its channel among all.
        integer, intent(in) :: state, slot, ch
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The mode's terms.
        type(mode_terms_t), intent(inout) :: terms
        real(dp) :: row(geom%na)
        if (code == 0) then
            row = -k*geom%disp_row(1) + k*geom%state_row(state)
        else
            row = geom%const_row(-code*g)
            terms%sb(geom%s0 + state, :) = geom%cs(state)*geom%vel_row(1)
        end if
        call terms%add_force(geom%dt(:, 1), row)
        terms%fb(ch, :) = row
    end subroutine slider_terms

    !> A slider's events: stuck, g - r (slips with direction -1) and g + r (+1); slipping
    !> with direction c, c w^T v (decided alone). `fb` its force's row.
    subroutine slider_events(code, g, slot, fb, geom, events)
        !> The slider's code, limit [N] and code slot in the element.
        integer, intent(in) :: code
        real(dp), intent(in) :: g
        integer, intent(in) :: slot
        !> Its force as a row of y.
        real(dp), intent(in) :: fb(:)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The events.
        type(event_list_t), intent(inout) :: events
        if (.not. (g > 0.0_dp)) return
        if (code == 0) then
            call events%add(geom%const_row(g) - fb, g, slot, -1)
            call events%add(geom%const_row(g) + fb, g, slot, 1)
        else
            call events%add(code*geom%vel_row(1), geom%vref, slot, action_decide)
        end if
    end subroutine slider_events

    !> A slider's code at a start: stuck when its spring's force is inside the limit (1e-9),
    !> else slipping against the force if the structure moves that way (above 1e-12 of the
    !> velocity scale), else stuck (it unloads). A slider without limit slips.
    integer function slider_start(k, g, state, geom, y) result(code)
        !> Stiffness [N/m], limit [N].
        real(dp), intent(in) :: k, g
        !> The slider's internal state.
        integer, intent(in) :: state
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The start (balanced).
        real(dp), intent(in) :: y(:)
        real(dp) :: r, v
        code = 0
        if (.not. (g > 0.0_dp)) then
            code = 1
            return
        end if
        r = dot_product(-k*geom%disp_row(1) + k*geom%state_row(state), y)
        if (abs(r) < g*(1.0_dp - 1.0e-9_dp)) return
        v = dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))
        if (-sign(1.0_dp, r)*v > 1.0e-12_dp*geom%vref) code = -nint(sign(1.0_dp, r))
    end function slider_start

    !> A slider's spring put on its limit at a start when it slips (r = -c g, c its code) or
    !> is beyond the limit stuck (r = g sign r): s = w^T x + r / k in y (balanced), and
    !> the Jacobian of the correction composed into pj (nz x nz): pj <- P pj.
    subroutine slider_project(k, g, code, state, geom, y, pj)
        !> Stiffness [N/m], limit [N].
        real(dp), intent(in) :: k, g
        !> The slider's code and internal state.
        integer, intent(in) :: code, state
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The start (balanced), corrected in place.
        real(dp), intent(inout) :: y(:)
        !> The Jacobian of the start's corrections.
        real(dp), intent(inout) :: pj(:, :)
        real(dp) :: r, target, drow(geom%na)
        integer :: idx, nz
        if (.not. (g > 0.0_dp)) return
        drow = geom%disp_row(1)
        r = dot_product(-k*drow + k*geom%state_row(state), y)
        if (code /= 0) then
            target = -code*g
        else if (abs(r) > g) then
            target = sign(g, r)
        else
            return
        end if
        nz = size(pj, 1)
        idx = 2*geom%n + geom%s0 + state
        y(idx) = geom%cs(state)*(dot_product(drow, y) + target/k)
        pj(idx, :) = geom%cs(state)*matmul(drow(1:nz), pj)
    end subroutine slider_project

    !> A slipping slider whose slip velocity w^T v reached zero: it sticks, unless the
    !> structure accelerates on in its direction (a graze, above 1e-9 of the scale).
    subroutine slider_decide(code, geom, y, ydot)
        !> The slider's code, updated.
        integer, intent(inout) :: code
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The state and its rate (balanced).
        real(dp), intent(in) :: y(:), ydot(:)
        real(dp) :: v, acc
        if (code == 0) return
        v = dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))
        if (code*v > 1.0e-9_dp*geom%vref) return
        acc = code*dot_product(geom%dt(:, 1), ydot(geom%n + 1:2*geom%n))
        if (.not. (acc > 1.0e-9_dp*geom%vref*geom%omega)) code = 0
    end subroutine slider_decide
end module stickslip_jenkins_element
