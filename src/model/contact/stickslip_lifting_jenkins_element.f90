!> A 2D Jenkins element on an elastic unilateral contact (doc/contacts.md): a tangential
!> spring k_t in series with a slider in the disk of radius g = mu lambda, the normal force
!> lambda = max(0, -k_n (gap + n^T x)) varying with the motion, the slider unloaded while the
!> contact is open. Its equalities, its implicit-Euler step and its weighted residual are the
!> unilateral contact's (stickslip_unilateral_element); this file adds what the exact
!> event-driven reference needs.
!>
!> The sliders s (2) are internal states; closed, the spring's force r = -k_t (P x - s) (P =
!> [w^T; t2^T]) and lambda are linear in the state. Stuck (code 0), s' = 0; slipping (code
!> 1), |r| = g and the slider moves along -r:
!>     s' = r (r . P v) / g^2 + r g' / (k_t g)
!> (the first term as under a constant load, the second keeps |r| on the moving edge), a
!> nonlinear input; open (code 2), r = 0 and s' = P v. While slipping the force's direction
!> relaxes towards the slip at the rate k_t |P v| / g, without bound as g -> 0: the contact
!> is taken closed only while lambda >= lambda_min = floor_fraction times the force scale, so
!> that the slip phases never reach g = 0 (the force missed where 0 < lambda < lambda_min
!> is below lambda_min for a time of order lambda_min / lambda', an impulse of order
!> lambda_min^2: 1e-14 of the scales' product at floor_fraction = 1e-7). Events, positive
!> while the mode lasts: stuck, g^2 - |r|^2 (it slips) and lambda - lambda_min (it opens);
!> slipping, the slider's speed -(r . P v) - g g' / k_t (it sticks unless the speed turns
!> up again) and lambda - lambda_min; open, gap + lambda_min / k_n (it closes: stuck with
!> the spring unloaded, or slipping at once, the spring on the edge against the slip, when
!> k_t |P v| > g' there). On opening the slider is put on the structure (s = P x: the spring
!> unloads, event_states). Every decision is the element's alone (no constraint). Without
!> friction (mu = 0) a closed contact slips freely (code 1, the sliders follow, r = 0).
module stickslip_lifting_jenkins_element
    use stickslip_kinds, only: dp
    use stickslip_unilateral_element, only: unilateral_element_t, new_unilateral_element
    use stickslip_jenkins_element, only: disk_slider_terms, disk_slider_on_edge, &
        slider_force_rows, slider_velocity_rows
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        action_decide, action_close
    implicit none
    private
    public :: lifting_jenkins_element_t, new_lifting_jenkins_element, floor_fraction
    public :: lambda_min, edge_rates, unload_sliders

    !> lambda_min as a fraction of the element's force scale.
    real(dp), parameter :: floor_fraction = 1.0e-7_dp

    !> A 2D Jenkins element on an elastic unilateral contact.
    type, extends(unilateral_element_t) :: lifting_jenkins_element_t
    contains
        procedure :: exact_support => lj_exact_support
        procedure :: nstate => lj_nstate
        procedure :: state_scales => lj_state_scales
        procedure :: initial_states => lj_initial_states
        procedure :: mode_terms => lj_mode_terms
        procedure :: event_rows => lj_event_rows
        procedure :: start_code => lj_start_code
        procedure :: start_states => lj_start_states
        procedure :: event_states => lj_event_states
        !> The friction is loaded in a code (stuck or slipping, with friction).
        procedure :: loaded => lj_loaded
        !> The friction limit mu lambda as a row of y, from the mode's channel forces.
        procedure :: limit_row => lj_limit_row
        procedure :: local_decide => lj_local_decide
        procedure :: coupled => lj_coupled
        procedure :: step_rows => lj_step_rows
        procedure :: inputs => lj_inputs
        procedure :: slip_direction => lj_slip_direction
    end type lifting_jenkins_element_t

contains

    !> The element: friction coefficient mu >= 0, initial gap [m], preload >= 0 [N], normal
    !> stiffness k_n >= 0 and tangential stiffness k_t > 0 [N/m] (k_n = 0, a rigid normal,
    !> is not handled by the exact reference: exact_support says so).
    function new_lifting_jenkins_element(mu, gap, preload, kn, kt) result(self)
        !> Friction coefficient, gap [m], preload [N], stiffnesses [N/m].
        real(dp), intent(in) :: mu, gap, preload, kn, kt
        type(lifting_jenkins_element_t) :: self
        self%unilateral_element_t = new_unilateral_element(2, mu, gap, preload, kn, kt)
    end function new_lifting_jenkins_element

    !> Handled on an elastic normal; on a rigid one, not (the threshold lambda_min cannot
    !> open a constraint that still pushes).
    function lj_exact_support(self) result(why)
        class(lifting_jenkins_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
        if (.not. self%kn > 0.0_dp) why = "the exact reference does not handle 2D friction "// &
            "behind a tangential stiffness on a rigid unilateral contact (give the contact a "// &
            "normal stiffness)"
    end function lj_exact_support

    !> The two slider positions.
    pure integer function lj_nstate(self) result(k)
        class(lifting_jenkins_element_t), intent(in) :: self
        k = 2
    end function lj_nstate

    !> sqrt(k_t): the sliders scaled like the modal coordinates.
    pure subroutine lj_state_scales(self, c)
        class(lifting_jenkins_element_t), intent(in) :: self
        real(dp), intent(out) :: c(:)
        c = sqrt(self%kt)
    end subroutine lj_state_scales

    !> s = P x + r / k_t (the spring's force r = -k_t (P x - s)).
    pure subroutine lj_initial_states(self, dx, r, s)
        class(lifting_jenkins_element_t), intent(in) :: self
        real(dp), intent(in) :: dx(:), r(:)
        real(dp), intent(out) :: s(:)
        s = dx(1:2) + r(1:2)/self%kt
    end subroutine lj_initial_states

    !> The rows of y of the spring force f (2 x na), of P v (2 x na), of the limit g = mu
    !> lambda and of its rate g' (closed: lambda = -k_n (gap + n^T x)).
    pure subroutine rows_of(self, geom, f, v, g, gd)
        class(lifting_jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(out) :: f(2, geom%na), v(2, geom%na), g(geom%na), gd(geom%na)
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        g = lj_limit_row(self, geom, reshape([real(dp) ::], [0, geom%na]))
        gd = -self%law%mu*self%kn*geom%vel_row(3)
    end subroutine rows_of

    !> The force floor lambda_min [N] of an element's geometry.
    pure real(dp) function lambda_min(geom)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        lambda_min = floor_fraction*geom%fref
    end function lambda_min

    !> A 2D slider on the edge of its varying disk: the rates a = r (r . P v) / g^2 + r g' /
    !> (k_t g) at y and their Jacobian da (2 x na), from the rows f and v
    !> (slider_force_rows, slider_velocity_rows), the limit's row g, the value of g' and its
    !> gradient dgd (na).
    pure subroutine edge_rates(kt, f, v, g, gdv, dgd, y, a, da)
        !> The spring's stiffness [N/m].
        real(dp), intent(in) :: kt
        !> Rows of the spring force and of P v (2 x na), of the limit (na).
        real(dp), intent(in) :: f(:, :), v(:, :), g(:)
        !> g' at y and its gradient.
        real(dp), intent(in) :: gdv, dgd(:)
        !> The state (balanced).
        real(dp), intent(in) :: y(:)
        !> The rates and their Jacobian.
        real(dp), intent(out) :: a(2), da(:, :)
        real(dp) :: r(2), pv(2), gv, rv, drv(size(y))
        integer :: k
        r = matmul(f, y)
        pv = matmul(v, y)
        gv = dot_product(g, y)
        rv = dot_product(r, pv)
        drv = matmul(pv, f) + matmul(r, v)
        do k = 1, 2
            a(k) = r(k)*rv/gv**2 + r(k)*gdv/(kt*gv)
            da(k, :) = (f(k, :)*rv + r(k)*drv)/gv**2 - 2.0_dp*r(k)*rv/gv**3*g + &
                       (f(k, :)*gdv + r(k)*dgd)/(kt*gv) - r(k)*gdv/(kt*gv**2)*g
        end do
    end subroutine edge_rates

    !> Open: the sliders follow (s' = P v). Closed: the normal force and the spring's force;
    !> slipping, the slider rates as nonlinear inputs.
    subroutine lj_mode_terms(self, code, geom, terms)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na), gd(geom%na)
        integer :: a
        call rows_of(self, geom, f, v, g, gd)
        if (code(1) /= 2) then
            terms%fb(geom%first + 2, :) = -self%kn*(geom%disp_row(3) + geom%const_row(self%gap))
            call terms%add_force(geom%dt(:, 3), terms%fb(geom%first + 2, :))
        end if
        if (code(1) == 2 .or. .not. self%law%mu > 0.0_dp) then
            ! open or frictionless: the sliders follow, the springs carry nothing
            do a = 1, 2
                terms%sb(geom%s0 + a, :) = geom%cs(a)*v(a, :)
            end do
            return
        end if
        call disk_slider_terms(f, code(1) == 1, geom, terms)
    end subroutine lj_mode_terms

    !> Slipping: the slider rates s' = r (r . P v) / g^2 + r g' / (k_t g) and their Jacobian.
    subroutine lj_inputs(self, code, geom, y, dir, fb, fq, q, dq, yd0, dyd0, gj)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), dir(:), fb(:, :), fq(:, :)
        real(dp), intent(out) :: q(:), dq(:, :)
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na), gd(geom%na)
        call rows_of(self, geom, f, v, g, gd)
        call edge_rates(self%kt, f, v, g, dot_product(gd, y), gd, y, q, dq)
    end subroutine lj_inputs

    !> Stuck: g^2 - |r|^2 (slips), lambda - lambda_min (opens); slipping: the slider's speed
    !> -(r . P v) - g g' / k_t (decided alone), lambda - lambda_min; open: gap + lambda_min /
    !> k_n (closes).
    subroutine lj_event_rows(self, code, geom, fb, events)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na), gd(geom%na), gscale
        call rows_of(self, geom, f, v, g, gd)
        gscale = geom%fref*max(self%law%mu, 1.0e-3_dp)
        ! frictionless: only the normal's events (the code stays 1 while closed)
        if (.not. self%law%mu > 0.0_dp .and. code(1) /= 2) then
            call events%add(fb(3, :) - geom%const_row(lambda_min(geom)), geom%fref, 1, 2)
            return
        end if
        select case (code(1))
        case (2)
            call events%add(geom%disp_row(3) + geom%const_row(self%gap + lambda_min(geom)/ &
                                                               self%kn), &
                            geom%gref*geom%omega, 1, action_close)
            return
        case (0)
            call events%add_quadratic(spread(g, 2, geom%na)*spread(g, 1, geom%na) - &
                                      matmul(transpose(f), f), 0.0_dp, gscale**2, 1, 1)
        case default
            call events%add_quadratic(-0.5_dp*(matmul(transpose(f), v) + &
                                               matmul(transpose(v), f)) - &
                                      0.5_dp*(spread(g, 2, geom%na)*spread(gd, 1, geom%na) + &
                                              spread(gd, 2, geom%na)*spread(g, 1, geom%na))/ &
                                      self%kt, 0.0_dp, gscale*geom%vref, 1, action_decide)
        end select
        call events%add(fb(3, :) - geom%const_row(lambda_min(geom)), geom%fref, 1, 2)
    end subroutine lj_event_rows

    !> Open when lambda < lambda_min; closed, stuck inside the disk (1e-9), else slipping
    !> when the structure moves the spring outward (the slider's speed above 1e-12 of its
    !> scale), else stuck.
    subroutine lj_start_code(self, geom, y, code, decide)
        class(lifting_jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na), gd(geom%na), r(2), gv
        decide = .false.
        call rows_of(self, geom, f, v, g, gd)
        if (-self%kn*dot_product(geom%disp_row(3) + geom%const_row(self%gap), y) < &
            lambda_min(geom)) then
            code(1) = 2
            return
        end if
        code(1) = 0
        if (.not. self%law%mu > 0.0_dp) then
            code(1) = 1
            return
        end if
        r = matmul(f, y)
        gv = dot_product(g, y)
        if (norm2(r) < gv*(1.0_dp - 1.0e-9_dp)) return
        if (-dot_product(r, matmul(v, y)) - gv*dot_product(gd, y)/self%kt > &
            1.0e-12_dp*gv*geom%vref) code(1) = 1
    end subroutine lj_start_code

    !> Open: the sliders on the structure (s = P x). Closed, slipping or stuck beyond the
    !> limit: the spring put radially on the edge |r| = g. y (balanced) corrected in place,
    !> pj <- P pj.
    subroutine lj_start_states(self, code, geom, fb, y, pj)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        real(dp), intent(inout) :: y(:)
        real(dp), intent(inout) :: pj(:, :)
        real(dp) :: f(2, geom%na), g(geom%na)
        if (.not. self%loaded(code(1))) then
            call unload_sliders(geom, y, pj)
            return
        end if
        f = slider_force_rows(self%kt, geom)
        g = self%limit_row(geom, fb)
        if (code(1) == 0 .and. norm2(matmul(f, y)) <= dot_product(g, y)) return
        call disk_slider_on_edge(self%kt, geom, f, g, y, pj)
    end subroutine lj_start_states

    !> Leaving the loaded codes (open, or closed below the force floor), the sliders are put
    !> on the structure, s = P x: the spring, on the edge of the disk of radius mu
    !> lambda_min, unloads. Loaded into a slip, the spring is put on that edge against the
    !> slip (along -P v).
    subroutine lj_event_states(self, old, code, geom, fb, y, jump)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: old(:), code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        real(dp), intent(inout) :: y(:)
        real(dp), intent(inout) :: jump(:, :)
        if (self%loaded(old(1)) .and. .not. self%loaded(code(1))) then
            call unload_sliders(geom, y, jump)
        else if (.not. self%loaded(old(1)) .and. self%loaded(code(1)) .and. code(1) == 1) then
            call disk_slider_on_edge(self%kt, geom, -slider_velocity_rows(geom), &
                                     self%limit_row(geom, fb), y, jump)
        end if
    end subroutine lj_event_states

    !> The friction is loaded: stuck or slipping, with friction.
    pure logical function lj_loaded(self, code) result(yes)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code
        yes = (code == 0 .or. code == 1) .and. self%law%mu > 0.0_dp
    end function lj_loaded

    !> The friction limit g = mu lambda as a row of y [N] (closed): lambda = -k_n (gap + n^T
    !> x); fb, the element's channel forces in the mode, unused.
    pure function lj_limit_row(self, geom, fb) result(g)
        class(lifting_jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        real(dp) :: g(geom%na)
        g = -self%law%mu*self%kn*(geom%disp_row(3) + geom%const_row(self%gap))
    end function lj_limit_row

    !> A 2D slider's spring unloaded: s = P x in y (balanced), pj <- P pj.
    subroutine unload_sliders(geom, y, pj)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The state (balanced), corrected in place.
        real(dp), intent(inout) :: y(:)
        !> The Jacobian of the corrections (nz x nz), composed.
        real(dp), intent(inout) :: pj(:, :)
        real(dp) :: drow(geom%na)
        integer :: a, nz, idx
        nz = size(pj, 1)
        do a = 1, 2
            idx = 2*geom%n + geom%s0 + a
            drow = geom%disp_row(a)
            y(idx) = geom%cs(a)*dot_product(drow, y)
            pj(idx, :) = geom%cs(a)*matmul(drow(1:nz), pj)
        end do
    end subroutine unload_sliders

    !> Decided alone: closing, stuck or slipping at once (event_states); a slider whose speed
    !> reached zero sticks, unless the speed turns up again (its rate above 1e-9 of the
    !> scale).
    subroutine lj_local_decide(self, code, geom, y, ydot)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(inout) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), ydot(:)
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na), gd(geom%na), speed, rate, &
                    gscale
        select case (code(1))
        case (2)
            ! closing with the spring unloaded: it slips at once when the spring's force
            ! would grow faster than the limit (k_t |P v| > g'), else sticks
            code(1) = 1
            if (.not. self%law%mu > 0.0_dp) return
            call rows_of(self, geom, f, v, g, gd)
            if (.not. self%kt*norm2(matmul(v, y)) > dot_product(gd, y)) code(1) = 0
        case (1)
            if (.not. self%law%mu > 0.0_dp) return
            call rows_of(self, geom, f, v, g, gd)
            gscale = geom%fref*max(self%law%mu, 1.0e-3_dp)
            speed = -dot_product(matmul(f, y), matmul(v, y)) - &
                    dot_product(g, y)*dot_product(gd, y)/self%kt
            if (speed > 1.0e-9_dp*gscale*geom%vref) return
            rate = -dot_product(matmul(f, ydot), matmul(v, y)) - &
                   dot_product(matmul(f, y), matmul(v, ydot)) - &
                   (dot_product(g, ydot)*dot_product(gd, y) + &
                    dot_product(g, y)*dot_product(gd, ydot))/self%kt
            if (.not. (rate > 1.0e-9_dp*gscale*geom%vref*geom%omega)) code(1) = 0
        end select
    end subroutine lj_local_decide

    !> No constraint: decided alone.
    pure logical function lj_coupled(self) result(c)
        class(lifting_jenkins_element_t), intent(in) :: self
        c = .false.
    end function lj_coupled

    !> No rows of a slip direction (the sliders are states).
    subroutine lj_step_rows(self, code, geom, dir, events)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: dir(:)
        type(event_list_t), intent(inout) :: events
    end subroutine lj_step_rows

    !> No slip memory (the sliders are states).
    subroutine lj_slip_direction(self, code, geom, fb, y, dir)
        class(lifting_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:)
        real(dp), intent(inout) :: dir(:)
    end subroutine lj_slip_direction
end module stickslip_lifting_jenkins_element
