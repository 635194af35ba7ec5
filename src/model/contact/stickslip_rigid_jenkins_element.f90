!> A 2D Jenkins element on a rigid unilateral contact (doc/contacts.md): a tangential spring
!> k_t in series with a slider in the disk of radius g = mu lambda, lambda the force of the
!> closed normal's constraint n^T v = 0. Its equalities, its implicit-Euler step and its
!> weighted residual are the unilateral contact's; this file adds what the exact reference
!> needs, as the elastic variant does (stickslip_lifting_jenkins_element), with the normal a
!> constraint:
!> - closed (codes 0 stuck, 1 slipping, code_unloaded): the constraint, its force lambda a
!>   row of y once the constraints are solved; stuck and slipping, the spring's force r =
!>   -k_t (P x - s) along w and t2 (linear in y); slipping, the slider rates s' = r (r . P
!>   v) / g^2 + r g' / (k_t g) with g' = mu lambda', lambda' = f_lambda . y' (the sliders'
!>   motion moves lambda too: s' = a + r (c . s') with c = mu f_lambda . G / (k_t g), G the
!>   sliders' columns of y', solved for s');
!> - the friction is taken loaded only while lambda >= lambda_min (floor_fraction of the
!>   force scale; below, code_unloaded: closed, the springs unloaded, the sliders following,
!>   reported as open), so no slip phase reaches g = 0, where the direction's relaxation
!>   rate k_t |P v| / g is unbounded; the constraint itself holds down to lambda = 0;
!> - events, positive while the mode lasts: stuck, g^2 - |r|^2 (slips) and lambda -
!>   lambda_min (unloads); slipping, lambda - lambda_min and the slider's speed -(r . P v) -
!>   g g'_0 / k_t (g'_0 = mu f_lambda . b y from the mode's linear dynamics: the speed's sign
!>   while 1 - c . r > 0; decided jointly); unloaded, lambda (opens) and lambda_min - lambda
!>   (loads: decided jointly); open, the gap (closes: an impact when with a velocity,
!>   frictionless, as the spring carries no impulse);
!> - decisions are joint with the other rigid contacts (it holds the normal constraint): the
!>   candidates stuck, slipping, unloaded, open, each tried against the law (stuck: the
!>   spring inside the disk and not leaving it; slipping: on its edge moving outward; a
!>   spring just loaded, r = 0 at g ~ mu lambda_min, slips at once when k_t |P v| > g', its
!>   spring put on the edge against the slip; unloaded: lambda in [0, lambda_min] and not
!>   rising past it).
module stickslip_rigid_jenkins_element
    use stickslip_kinds, only: dp
    use stickslip_lifting_jenkins_element, only: lifting_jenkins_element_t, &
        new_lifting_jenkins_element, lambda_min, edge_rates
    use stickslip_jenkins_element, only: disk_slider_terms, &
        slider_force_rows, slider_velocity_rows
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        action_decide, action_close, code_unloaded
    implicit none
    private
    public :: rigid_jenkins_element_t, new_rigid_jenkins_element

    !> Tolerance of the consistency tests (relative to the scales).
    real(dp), parameter :: tol = 1.0e-9_dp

    !> A 2D Jenkins element on a rigid unilateral contact.
    type, extends(lifting_jenkins_element_t) :: rigid_jenkins_element_t
    contains
        procedure :: exact_support => rj_exact_support
        procedure :: mode_terms => rj_mode_terms
        procedure :: inputs => rj_inputs
        procedure :: event_rows => rj_event_rows
        procedure :: dynamics_events => rj_dynamics_events
        procedure :: start_code => rj_start_code
        procedure :: limit_row => rj_limit_row
        procedure :: local_decide => rj_local_decide
        procedure :: coupled => rj_coupled
        procedure :: holds_constraint => rj_holds_constraint
        procedure :: candidates => rj_candidates
        procedure :: consistent => rj_consistent
    end type rigid_jenkins_element_t

contains

    !> The element: friction coefficient mu >= 0, initial gap [m], preload >= 0 [N] and
    !> tangential stiffness k_t > 0 [N/m]; the normal rigid.
    function new_rigid_jenkins_element(mu, gap, preload, kt) result(self)
        !> Friction coefficient, gap [m], preload [N], tangential stiffness [N/m].
        real(dp), intent(in) :: mu, gap, preload, kt
        type(rigid_jenkins_element_t) :: self
        self%lifting_jenkins_element_t = new_lifting_jenkins_element(mu, gap, preload, 0.0_dp, kt)
    end function new_rigid_jenkins_element

    !> Handled.
    function rj_exact_support(self) result(why)
        class(rigid_jenkins_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
    end function rj_exact_support

    !> The scale of the friction forces [N].
    pure real(dp) function friction_scale(self, geom)
        class(rigid_jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        friction_scale = geom%fref*max(self%law%mu, 1.0e-3_dp)
    end function friction_scale

    !> Open: the sliders follow. Closed: the normal constraint; unloaded (or without
    !> friction), the sliders follow; stuck or slipping, the springs, slipping the slider
    !> rates as nonlinear inputs.
    subroutine rj_mode_terms(self, code, geom, terms)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        real(dp) :: f(2, geom%na), v(2, geom%na)
        integer :: a
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        if (code(1) /= 2) call terms%constrain(geom%dt(:, 3), geom%dt(:, 3), geom%first + 2, 0, &
                                               0.0_dp)
        if (.not. self%loaded(code(1))) then
            do a = 1, 2
                terms%sb(geom%s0 + a, :) = geom%cs(a)*v(a, :)
            end do
            return
        end if
        call disk_slider_terms(f, code(1) == 1, geom, terms)
    end subroutine rj_mode_terms

    !> Slipping: the slider rates s' = a + r (c . s') (module header) and their Jacobian;
    !> without yd0 (a first pass) the rate of lambda is left out.
    subroutine rj_inputs(self, code, geom, y, dir, fb, fq, q, dq, yd0, dyd0, gj)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), dir(:), fb(:, :), fq(:, :)
        real(dp), intent(out) :: q(:), dq(:, :)
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na), r(2), gv, g0d, dg0d(geom%na), &
                    a(2), da(2, geom%na), c(2), dc(2, geom%na), ca, cr, den, s, dca(geom%na), &
                    dcr(geom%na), ds(geom%na)
        integer :: k
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        g = self%limit_row(geom, fb)
        r = matmul(f, y)
        gv = dot_product(g, y)
        g0d = 0.0_dp
        dg0d = 0.0_dp
        c = 0.0_dp
        if (present(yd0) .and. present(dyd0) .and. present(gj)) then
            g0d = dot_product(g, yd0)
            dg0d = matmul(g, dyd0)
            c = matmul(g, gj)/(self%kt*gv)
        end if
        call edge_rates(self%kt, f, v, g, g0d, dg0d, y, a, da)
        do k = 1, 2
            dc(k, :) = -c(k)/gv*g
        end do
        ca = dot_product(c, a)
        cr = dot_product(c, r)
        den = 1.0_dp - cr
        s = ca/den
        dca = matmul(a, dc) + matmul(c, da)
        dcr = matmul(r, dc) + matmul(c, f)
        ds = (dca + s*dcr)/den
        do k = 1, 2
            q(k) = a(k) + r(k)*s
            dq(k, :) = da(k, :) + f(k, :)*s + r(k)*ds
        end do
    end subroutine rj_inputs

    !> Open: the gap (closes). Unloaded: lambda (opens), lambda_min - lambda (loads,
    !> decided). Stuck: g^2 - |r|^2 (slips), lambda - lambda_min (unloads). Slipping: lambda -
    !> lambda_min (the slider's stop: dynamics_events). Without friction, only lambda (opens).
    subroutine rj_event_rows(self, code, geom, fb, events)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na)
        if (code(1) == 2) then
            call events%add(geom%disp_row(3) + geom%const_row(self%gap), geom%gref*geom%omega, &
                            1, action_close)
            return
        end if
        if (.not. self%law%mu > 0.0_dp .or. code(1) == code_unloaded) then
            call events%add(fb(3, :), geom%fref, 1, 2)
            if (self%law%mu > 0.0_dp) call events%add(geom%const_row(lambda_min(geom)) - &
                                                      fb(3, :), geom%fref, 1, action_decide)
            return
        end if
        call events%add(fb(3, :) - geom%const_row(lambda_min(geom)), geom%fref, 1, code_unloaded)
        if (code(1) /= 0) return
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        g = self%limit_row(geom, fb)
        call events%add_quadratic(spread(g, 2, geom%na)*spread(g, 1, geom%na) - &
                                  matmul(transpose(f), f), 0.0_dp, friction_scale(self, geom)**2, &
                                  1, 1)
    end subroutine rj_event_rows

    !> Slipping: the slider's speed -(r . P v) - g g'_0 / k_t, g'_0 = mu f_lambda . b y (it
    !> stops: decided jointly).
    subroutine rj_dynamics_events(self, code, geom, fb, b, events)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), b(:, :)
        type(event_list_t), intent(inout) :: events
        real(dp) :: f(2, geom%na), v(2, geom%na), g(geom%na), gd(geom%na)
        if (.not. (code(1) == 1 .and. self%law%mu > 0.0_dp)) return
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        g = self%limit_row(geom, fb)
        gd = matmul(g, b)
        call events%add_quadratic(-0.5_dp*(matmul(transpose(f), v) + matmul(transpose(v), f)) - &
                                  0.5_dp*(spread(g, 2, geom%na)*spread(gd, 1, geom%na) + &
                                          spread(gd, 2, geom%na)*spread(g, 1, geom%na))/self%kt, &
                                  0.0_dp, friction_scale(self, geom)*geom%vref, 1, action_decide)
    end subroutine rj_dynamics_events

    !> Open when the gap exceeds 1e-9 of its scale; otherwise decided jointly (from stuck).
    subroutine rj_start_code(self, geom, y, code, decide)
        class(rigid_jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        decide = .false.
        code(1) = 2
        if (dot_product(geom%disp_row(3) + geom%const_row(self%gap), y) > 1.0e-9_dp*geom%gref) &
            return
        code(1) = 0
        decide = .true.
    end subroutine rj_start_code

    !> The friction limit mu lambda, lambda the constraint force of the mode (fb).
    pure function rj_limit_row(self, geom, fb) result(g)
        class(rigid_jenkins_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        real(dp) :: g(geom%na)
        g = self%law%mu*fb(3, :)
    end function rj_limit_row

    !> Nothing decided alone (joint decisions).
    subroutine rj_local_decide(self, code, geom, y, ydot)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(inout) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), ydot(:)
    end subroutine rj_local_decide

    !> A rigid normal: decided jointly.
    pure logical function rj_coupled(self) result(c)
        class(rigid_jenkins_element_t), intent(in) :: self
        c = .true.
    end function rj_coupled

    !> Closed: the normal constraint.
    pure logical function rj_holds_constraint(self, code) result(h)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        h = code(1) /= 2
    end function rj_holds_constraint

    !> Open: unloaded, stuck, slipping, open (a closing); closed: stuck, slipping, unloaded,
    !> open. Without friction: slipping (closed), open.
    subroutine rj_candidates(self, code, geom, y, cand, ncand)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: cand(:, :)
        integer, intent(out) :: ncand
        if (.not. self%law%mu > 0.0_dp) then
            ncand = 2
            cand(1, 1:2) = [1, 2]
        else if (code(1) == 2) then
            ncand = 4
            cand(1, 1:4) = [code_unloaded, 0, 1, 2]
        else
            ncand = 4
            cand(1, 1:4) = [0, 1, code_unloaded, 2]
        end if
    end subroutine rj_candidates

    !> Closed: lambda >= 0; loaded, lambda >= lambda_min (not falling below it), unloaded
    !> lambda <= lambda_min (not rising above it); stuck, the spring inside the disk and not
    !> leaving it, and a spring just loaded (r = 0, g < 2 mu lambda_min) not outgrowing the
    !> limit (k_t |P v| <= g'); slipping, the spring on the edge moving outward (the slider's
    !> speed >= 0) or just loaded and outgrowing the limit; open: the parent's test (the gap
    !> does not close). Tolerances 1e-9 of the scales.
    logical function rj_consistent(self, code, moving, geom, fb, y, ydot) result(ok)
        class(rigid_jenkins_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        logical, intent(in) :: moving
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:), ydot(:)
        real(dp) :: f(2, geom%na), v(2, geom%na), lam, ldot, lmin, g, gd, r(2), rn, fs, &
                    pv(2), speed
        logical :: fresh
        if (code(1) == 2) then
            ok = self%lifting_jenkins_element_t%unilateral_element_t%consistent(code, moving, &
                                                                                 geom, fb, y, &
                                                                                 ydot)
            return
        end if
        lam = dot_product(fb(3, :), y)
        ldot = dot_product(fb(3, :), ydot)
        lmin = lambda_min(geom)
        ok = lam >= -tol*geom%fref
        if (.not. ok) return
        if (.not. self%law%mu > 0.0_dp) return
        if (code(1) == code_unloaded) then
            ok = lam <= lmin + tol*geom%fref
            if (ok .and. lam >= lmin - tol*geom%fref) ok = ldot <= tol*geom%fref*geom%omega
            return
        end if
        ok = lam >= lmin - tol*geom%fref
        if (ok .and. lam <= lmin + tol*geom%fref) ok = ldot >= -tol*geom%fref*geom%omega
        if (.not. ok) return
        f = slider_force_rows(self%kt, geom)
        v = slider_velocity_rows(geom)
        fs = friction_scale(self, geom)
        g = self%law%mu*lam
        gd = self%law%mu*ldot
        r = matmul(f, y)
        rn = norm2(r)
        pv = matmul(v, y)
        fresh = rn <= tol*fs .and. g <= 2.0_dp*self%law%mu*lmin
        if (code(1) == 0) then
            ok = rn <= g + tol*fs
            if (ok .and. rn >= g - tol*fs .and. .not. fresh) &
                ok = dot_product(r, matmul(f, ydot)) - g*gd <= tol*fs**2*geom%omega
            if (ok .and. fresh) ok = self%kt*norm2(pv) <= gd + tol*fs*geom%omega
        else
            if (fresh) then
                ok = self%kt*norm2(pv) > gd + tol*fs*geom%omega
            else
                speed = -dot_product(r, pv) - g*gd/self%kt
                ok = rn >= g - tol*fs .and. speed >= -tol*fs*geom%vref
            end if
        end if
    end function rj_consistent
end module stickslip_rigid_jenkins_element
