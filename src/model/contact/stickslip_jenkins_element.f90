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
module stickslip_jenkins_element
    use stickslip_kinds, only: dp
    use stickslip_friction_contact, only: friction_contact_t, init_friction_contact
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        action_decide
    implicit none
    private
    public :: jenkins_element_t, new_jenkins_element
    public :: slider_terms, slider_events, slider_start, slider_decide

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
        procedure :: local_decide => jenkins_local_decide
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

    !> 1D: handled.
    function jenkins_exact_support(self) result(why)
        class(jenkins_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
        if (self%law%ntangent == 2) why = "the exact reference does not handle the 2D "// &
                                          "Jenkins element yet"
    end function jenkins_exact_support

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

    subroutine jenkins_mode_terms(self, code, geom, terms)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        call slider_terms(code(1), self%kt, self%law%mu*self%law%normal_load, 1, 1, &
                          geom%first, geom, terms)
    end subroutine jenkins_mode_terms

    subroutine jenkins_event_rows(self, code, geom, fb, events)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        call slider_events(code(1), self%law%mu*self%law%normal_load, 1, fb(1, :), geom, &
                           events)
    end subroutine jenkins_event_rows

    subroutine jenkins_start_code(self, geom, y, code, decide)
        class(jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        code(1) = slider_start(self%kt, self%law%mu*self%law%normal_load, 1, geom, y)
        decide = .false.
    end subroutine jenkins_start_code

    subroutine jenkins_local_decide(self, code, geom, y, ydot)
        class(jenkins_element_t), intent(in) :: self
        integer, intent(inout) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), ydot(:)
        call slider_decide(code(1), geom, y, ydot)
    end subroutine jenkins_local_decide

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
