!> The unilateral (Signorini) contact with friction (doc/contacts.md): the channels [w, (t2),
!> n]; gap g = gap + n^T x >= 0, normal force lambda >= 0, lambda g = 0 (elastic with a
!> normal stiffness k_n: lambda = max(0, -k_n g)); friction in 1D or in the disk with the
!> varying limit mu lambda(t), rigid or behind a tangential stiffness k_t; a static preload
!> -P n pressing it closed.
!>
!> In the exact flow (doc/contacts.md, section 5), with 1D friction its code is 0 (stuck), +1 /
!> -1 (slipping) or 2 (open). Closed, an elastic normal carries lambda =
!> -k_n (gap + n^T x) (an added stiffness and a constant); a rigid normal is the constraint
!> n^T v = 0 whose force lambda comes from the flow's projection, as a stuck friction force
!> does. A slipping contact's force is -s mu lambda: for a rigid normal the constraint's force
!> direction is then n - s mu w (Painleve's paradox when that makes the constraint matrix
!> singular: the mode fails). Event rows, positive while the mode lasts: stuck, mu lambda - r
!> and mu lambda + r (the limit); slipping, s w^T v; closed, lambda (opening); open, the gap
!> (closing: for a rigid normal with a closing velocity an impact, plastic, with Coulomb's
!> impulse law, solved by the flow with this element's law at velocity level).
!> With a tangential stiffness k_t (1D friction) the friction is a Jenkins element whose
!> slider s is an internal state: stuck, r = -k_t (w^T x - s), s' = 0; slipping, r = -s mu
!> lambda, s = w^T x + r / k_t, so s' = w^T v - s mu lambda' / k_t; open, r = 0 and the
!> slider follows (s' = w^T v). On an elastic normal lambda' = -k_n n^T v and there is no
!> constraint: its codes are decided alone (the slider stops: it sticks unless it
!> accelerates on; the gap closes: stuck with the spring unloaded). On a rigid normal lambda
!> is the constraint force, lambda' its rate in the mode (resolved by the flow once the
!> constraints are solved); the codes are decided jointly (the slider stops: stuck if the
!> spring's force stays within the limit); its impacts are frictionless.
!> With 2D friction (no tangential stiffness) its code is 0 (stuck: w^T v = t2^T v = 0), 1
!> (slipping: the friction force -mu lambda u/|u| against the disk of radius mu lambda, a
!> nonlinear input integrated numerically, stickslip_disk_slip; on a rigid normal lambda is
!> the constraint force, which responds to the friction force) or 2 (open); stuck, the event
!> (mu lambda)^2 - |r|^2 (quadratic in the state) starts the slip against the stuck force;
!> its impacts take the 2D impulse law.
module stickslip_unilateral_element
    use stickslip_kinds, only: dp
    use stickslip_contact_element, only: contact_element_t, accel_none, accel_box, &
        accel_alone, accel_keep
    use stickslip_coulomb_element, only: new_coulomb_element
    use stickslip_planar_element, only: new_planar_element
    use stickslip_friction_contact, only: friction_contact_t, init_friction_contact
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        action_decide, action_close
    use stickslip_disk_slip, only: rest_speed, slip_speed, disk_step_rows, disk_inputs, &
        disk_slip_direction
    implicit none
    private
    public :: unilateral_element_t, new_unilateral_element

    !> Tolerance of the consistency tests of a mode (relative to the scales).
    real(dp), parameter :: tol = 1.0e-9_dp

    !> A unilateral contact with 1D or 2D friction.
    type, extends(friction_contact_t) :: unilateral_element_t
    contains
        procedure :: law_name => unilateral_name
        procedure :: exact_support => unilateral_exact_support
        procedure :: mode_terms => unilateral_mode_terms
        procedure :: event_rows => unilateral_event_rows
        procedure :: start_code => unilateral_start_code
        procedure :: coupled => unilateral_coupled
        procedure :: holds_constraint => unilateral_holds_constraint
        procedure :: candidates => unilateral_candidates
        procedure :: consistent => unilateral_consistent
        procedure :: impacts => unilateral_impacts
        procedure :: impact_law => unilateral_impact_law
        procedure :: rigid_closed => unilateral_rigid_closed
        procedure :: start_gap => unilateral_start_gap
        procedure :: nstate => unilateral_nstate
        procedure :: state_scales => unilateral_state_scales
        procedure :: initial_states => unilateral_initial_states
        procedure :: start_states => unilateral_start_states
        procedure :: local_decide => unilateral_local_decide
        procedure :: step_rows => unilateral_step_rows
        procedure :: inputs => unilateral_inputs
        procedure :: slip_direction => unilateral_slip_direction
        procedure :: accel_law => unilateral_accel_law
    end type unilateral_element_t

contains

    !> The element with `ntangent` (1 or 2) tangential directions, friction coefficient mu
    !> >= 0, initial gap [m], preload >= 0 [N], normal and tangential stiffness >= 0 [N/m]
    !> (0: rigid).
    function new_unilateral_element(ntangent, mu, gap, preload, kn, kt) result(self)
        !> Tangential directions.
        integer, intent(in) :: ntangent
        !> Friction coefficient, gap [m], preload [N], stiffnesses [N/m].
        real(dp), intent(in) :: mu, gap, preload, kn, kt
        type(unilateral_element_t) :: self
        call init_friction_contact(self, ntangent, .true., mu, 0.0_dp, gap, preload, kn, kt)
    end function new_unilateral_element

    pure function unilateral_name(self) result(name)
        class(unilateral_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "unilateral"
    end function unilateral_name

    !> Handled: 1D friction, rigid tangentially or with a tangential stiffness, on an
    !> elastic or a rigid normal; 2D friction, rigid tangentially, on either. 2D friction
    !> behind a tangential stiffness is the lifting or the rigid Jenkins element's (the
    !> model builds those: stickslip_contact_set).
    function unilateral_exact_support(self) result(why)
        class(unilateral_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
        if (self%law%ntangent == 2 .and. self%kt > 0.0_dp) then
            why = "the exact reference takes 2D friction behind a tangential stiffness on a "// &
                  "unilateral contact as new_lifting_jenkins_element (elastic normal) or "// &
                  "new_rigid_jenkins_element (rigid normal), not as new_unilateral_element"
        end if
    end function unilateral_exact_support

    !> The slider of a Jenkins friction (k_t > 0): one state.
    pure integer function unilateral_nstate(self) result(k)
        class(unilateral_element_t), intent(in) :: self
        k = merge(1, 0, self%kt > 0.0_dp .and. self%law%ntangent == 1)
    end function unilateral_nstate

    !> sqrt(k_t): the slider scaled like the modal coordinates.
    pure subroutine unilateral_state_scales(self, c)
        class(unilateral_element_t), intent(in) :: self
        real(dp), intent(out) :: c(:)
        c = sqrt(max(self%kt, tiny(1.0_dp)))
    end subroutine unilateral_state_scales

    !> s = w^T x + r / k_t (the spring's force r = -k_t (w^T x - s)).
    pure subroutine unilateral_initial_states(self, dx, r, s)
        class(unilateral_element_t), intent(in) :: self
        real(dp), intent(in) :: dx(:), r(:)
        real(dp), intent(out) :: s(:)
        if (size(s) > 0) s(1) = dx(1) + r(1)/self%kt
    end subroutine unilateral_initial_states

    !> The rows of the spring's force -k_t (w^T x - s) and of the normal force lambda =
    !> -k_n (gap + n^T x) (Jenkins friction on an elastic normal).
    pure subroutine spring_rows(self, geom, fr, lrow)
        class(unilateral_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(out) :: fr(:), lrow(:)
        fr = -self%kt*geom%disp_row(1) + self%kt*geom%state_row(1)
        lrow = -self%kn*gap_row(self, geom)
    end subroutine spring_rows

    !> A Jenkins friction's slider at the start: open, unloaded (s = w^T x); slipping with
    !> code c, on its limit (r = -c mu lambda); stuck beyond the limit, on it (r = mu lambda
    !> sign r); lambda = -k_n g, or on a rigid normal the start mode's constraint force (fb).
    !> y (balanced) corrected in place, pj <- P pj.
    subroutine unilateral_start_states(self, code, geom, fb, y, pj)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        real(dp), intent(inout) :: y(:)
        real(dp), intent(inout) :: pj(:, :)
        real(dp) :: fr(geom%na), lrow(geom%na), target(geom%na), r, lam
        integer :: idx, nz
        if (self%nstate() == 0) return
        call spring_rows(self, geom, fr, lrow)
        ! a rigid normal: lambda is the constraint force of the start mode
        if (.not. self%kn > 0.0_dp) lrow = fb(2, :)
        r = dot_product(fr, y)
        lam = max(dot_product(lrow, y), 0.0_dp)
        ! the spring's target force as a row of y
        select case (code(1))
        case (2)
            target = 0.0_dp
        case (0)
            if (abs(r) <= self%law%mu*lam) return
            target = sign(1.0_dp, r)*self%law%mu*lrow
        case default
            target = -code(1)*self%law%mu*lrow
        end select
        ! s = w^T x + target / k_t
        nz = size(pj, 1)
        idx = 2*geom%n + geom%s0 + 1
        y(idx) = geom%cs(1)*dot_product(geom%disp_row(1) + target/self%kt, y)
        pj(idx, :) = geom%cs(1)*matmul(geom%disp_row(1) + target/self%kt, pj_full(pj))
    contains
        !> pj extended by zero rows to the na rows of y (the constant and the exosystem do
        !> not move with the start).
        function pj_full(p) result(pf)
            real(dp), intent(in) :: p(:, :)
            real(dp) :: pf(geom%na, size(p, 2))
            pf = 0.0_dp
            pf(1:size(p, 1), :) = p
        end function pj_full
    end subroutine unilateral_start_states

    !> A Jenkins friction, decided alone: a slipping slider whose velocity reached zero
    !> sticks unless it accelerates on (1e-9 of the scale); an open contact that closes
    !> sticks (its spring unloaded).
    subroutine unilateral_local_decide(self, code, geom, y, ydot)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(inout) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), ydot(:)
        real(dp) :: row(geom%na)
        select case (code(1))
        case (2)
            code(1) = 0
        case (1, -1)
            row = code(1)*geom%vel_row(1) + self%law%mu*self%kn/self%kt*geom%vel_row(3)
            if (dot_product(row, y) > 1.0e-9_dp*geom%vref) return
            if (.not. (dot_product(row, ydot) > 1.0e-9_dp*geom%vref*geom%omega)) code(1) = 0
        end select
    end subroutine unilateral_local_decide

    !> The gap gap + n^T x as a row of y [m].
    pure function gap_row(self, geom) result(row)
        class(unilateral_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp) :: row(geom%na)
        row = geom%disp_row(3) + geom%const_row(self%gap)
    end function gap_row

    !> Open: nothing. Elastic normal: lambda = -k_n g along n, the friction -s mu lambda along
    !> w when slipping, the constraint w^T v = 0 when stuck. Rigid normal: stuck, both
    !> directions constrained; slipping, n^T v = 0 held by lambda (n - s mu w).
    subroutine unilateral_mode_terms(self, code, geom, terms)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        real(dp) :: lrow(geom%na)
        integer :: c, cn
        c = geom%first
        cn = geom%first + 1
        associate (mu => self%law%mu, wt => geom%dt(:, 1), nt => geom%dt(:, 3))
            if (self%nstate() > 0) then
                call jenkins_terms()
                return
            end if
            if (code(1) == 2) return
            if (self%law%ntangent == 2) then
                call disk_terms()
                return
            end if
            if (self%kn > 0.0_dp) then
                lrow = -self%kn*gap_row(self, geom)
                terms%fb(cn, :) = lrow
                call terms%add_force(nt, lrow)
                if (code(1) == 0) then
                    call terms%constrain(wt, wt, c, 0, 0.0_dp)
                else
                    terms%fb(c, :) = -code(1)*mu*lrow
                    call terms%add_force(wt, terms%fb(c, :))
                end if
            else if (code(1) == 0) then
                call terms%constrain(wt, wt, c, 0, 0.0_dp)
                call terms%constrain(nt, nt, cn, 0, 0.0_dp)
            else
                call terms%constrain(nt, nt - code(1)*mu*wt, cn, c, -code(1)*mu)
            end if
        end associate
    contains
        !> Jenkins friction on an elastic normal: open, the slider follows; closed, the
        !> normal force, and stuck the spring, slipping the force on the limit with the
        !> slider's rate.
        subroutine jenkins_terms()
            real(dp) :: fr(geom%na), lrow2(geom%na)
            integer :: is
            is = geom%s0 + 1
            call spring_rows(self, geom, fr, lrow2)
            if (code(1) == 2) then
                terms%sb(is, :) = geom%cs(1)*geom%vel_row(1)
                return
            end if
            if (.not. self%kn > 0.0_dp) then
                call rigid_jenkins_terms(fr)
                return
            end if
            terms%fb(cn, :) = lrow2
            call terms%add_force(geom%dt(:, 3), lrow2)
            if (code(1) == 0) then
                terms%fb(c, :) = fr
            else
                terms%fb(c, :) = -code(1)*self%law%mu*lrow2
                terms%sb(is, :) = geom%cs(1)*(geom%vel_row(1) + code(1)*self%law%mu*self%kn/ &
                                              self%kt*geom%vel_row(3))
            end if
            call terms%add_force(geom%dt(:, 1), terms%fb(c, :))
        end subroutine jenkins_terms

        !> Jenkins friction on a rigid normal (closed): the normal constraint; stuck, the
        !> spring's force fr; slipping, the force on the limit -c mu lambda held with the
        !> normal (n - c mu w) and the slider's rate s' = w^T v - c mu lambda' / k_t (the
        !> spring follows the constraint force: its rate once the constraints are solved),
        !> whose zero is the slider's stop (decided jointly).
        subroutine rigid_jenkins_terms(fr)
            real(dp), intent(in) :: fr(:)
            integer :: is
            is = geom%s0 + 1
            if (code(1) == 0) then
                call terms%constrain(geom%dt(:, 3), geom%dt(:, 3), cn, 0, 0.0_dp)
                terms%fb(c, :) = fr
                call terms%add_force(geom%dt(:, 1), fr)
                return
            end if
            call terms%constrain(geom%dt(:, 3), geom%dt(:, 3) - code(1)*self%law%mu*geom%dt(:, 1), &
                                 cn, c, -code(1)*self%law%mu)
            terms%sb(is, :) = geom%cs(1)*geom%vel_row(1)
            call terms%add_force_rate(is, cn, -code(1)*self%law%mu*geom%cs(1)/self%kt)
            call terms%add_rate_event(geom%index, is, real(code(1), dp), geom%cs(1)*geom%vref, &
                                      1, action_decide)
        end subroutine rigid_jenkins_terms

        !> 2D friction (closed): on an elastic normal the normal force, on a rigid one the
        !> normal constraint; stuck the two tangential constraints, slipping the friction
        !> force as two nonlinear inputs (on a rigid normal the constraint force responds to
        !> them: unilateral_inputs).
        subroutine disk_terms()
            real(dp) :: scol(geom%ns), fcol(size(terms%fb, 1)), lrow2(geom%na)
            integer :: a
            if (self%kn > 0.0_dp) then
                lrow2 = -self%kn*gap_row(self, geom)
                terms%fb(c + 2, :) = lrow2
                call terms%add_force(geom%dt(:, 3), lrow2)
            else
                call terms%constrain(geom%dt(:, 3), geom%dt(:, 3), c + 2, 0, 0.0_dp)
            end if
            if (code(1) == 0) then
                call terms%constrain(geom%dt(:, 1), geom%dt(:, 1), c, 0, 0.0_dp)
                call terms%constrain(geom%dt(:, 2), geom%dt(:, 2), c + 1, 0, 0.0_dp)
                return
            end if
            scol = 0.0_dp
            do a = 1, 2
                fcol = 0.0_dp
                fcol(c + a - 1) = 1.0_dp
                call terms%add_input(geom%index, geom%dt(:, a), scol, fcol)
            end do
        end subroutine disk_terms
    end subroutine unilateral_mode_terms

    !> Stuck: mu lambda -/+ r (slip against the force), lambda (open); slipping: s w^T v
    !> (decide), lambda (open); open: the gap (close).
    subroutine unilateral_event_rows(self, code, geom, fb, events)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        real(dp) :: lrow(geom%na)
        associate (mu => self%law%mu)
            if (self%law%ntangent == 2) then
                ! 2D friction: stuck, (mu lambda)^2 - |r|^2 (slips); closed, lambda (opens)
                select case (code(1))
                case (0)
                    lrow = mu*fb(3, :)
                    call events%add_quadratic(spread(lrow, 2, geom%na)* &
                                              spread(lrow, 1, geom%na) - &
                                              matmul(transpose(fb(1:2, :)), fb(1:2, :)), 0.0_dp, &
                                              (geom%fref*max(mu, 1.0e-3_dp))**2, 1, 1)
                    call events%add(fb(3, :), geom%fref, 1, 2)
                case (2)
                    call events%add(gap_row(self, geom), geom%gref*geom%omega, 1, action_close)
                case default
                    call events%add(fb(3, :), geom%fref, 1, 2)
                end select
                return
            end if
            select case (code(1))
            case (0)
                call events%add(mu*fb(2, :) - fb(1, :), geom%fref*max(mu, 1.0e-3_dp), 1, -1)
                call events%add(mu*fb(2, :) + fb(1, :), geom%fref*max(mu, 1.0e-3_dp), 1, 1)
                call events%add(fb(2, :), geom%fref, 1, 2)
            case (2)
                call events%add(gap_row(self, geom), geom%gref*geom%omega, 1, action_close)
            case default
                if (self%nstate() > 0) then
                    ! the slider's velocity (on a rigid normal: a row on its rate,
                    ! rigid_jenkins_terms)
                    if (self%kn > 0.0_dp) call events%add(code(1)*geom%vel_row(1) + mu*self%kn/ &
                                                          self%kt*geom%vel_row(3), geom%vref, 1, &
                                                          action_decide)
                else
                    call events%add(code(1)*geom%vel_row(1), geom%vref, 1, action_decide)
                end if
                call events%add(fb(2, :), geom%fref, 1, 2)
            end select
        end associate
    end subroutine unilateral_event_rows

    !> Open when the gap exceeds 1e-9 of its scale; otherwise (closed or at zero gap) the
    !> joint decision settles it (slipping in the direction of a slip velocity above 1e-12
    !> of its scale).
    subroutine unilateral_start_code(self, geom, y, code, decide)
        class(unilateral_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        real(dp) :: v, fr(geom%na), lrow(geom%na), r, lam
        decide = .false.
        if (dot_product(gap_row(self, geom), y) > 1.0e-9_dp*geom%gref) then
            code(1) = 2
            return
        end if
        if (self%nstate() > 0 .and. .not. self%kn > 0.0_dp) then
            ! Jenkins friction on a rigid normal: decided jointly
            code(1) = 0
            decide = .true.
            return
        end if
        if (self%nstate() > 0) then
            ! Jenkins friction: stuck inside the limit (1e-9), else slipping against the
            ! force if the structure moves that way, else stuck (it unloads)
            call spring_rows(self, geom, fr, lrow)
            r = dot_product(fr, y)
            lam = max(dot_product(lrow, y), 0.0_dp)
            code(1) = 0
            if (abs(r) < self%law%mu*lam*(1.0_dp - 1.0e-9_dp)) return
            v = dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))
            if (-sign(1.0_dp, r)*v > 1.0e-12_dp*geom%vref) code(1) = -nint(sign(1.0_dp, r))
            return
        end if
        decide = .true.
        if (self%law%ntangent == 2) then
            ! 2D friction: slipping above 1.5 rest_speed of the scale (a slip that stopped
            ! is at rest_speed), else stuck (decided)
            code(1) = merge(1, 0, slip_speed(geom, y) > 1.5_dp*rest_speed*geom%vref)
            return
        end if
        v = dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))
        code(1) = 0
        if (abs(v) > 1.0e-12_dp*geom%vref) code(1) = nint(sign(1.0_dp, v))
    end subroutine unilateral_start_code

    !> Takes part in joint decisions (not a Jenkins friction on an elastic normal: no
    !> constraint).
    pure logical function unilateral_coupled(self) result(c)
        class(unilateral_element_t), intent(in) :: self
        c = .not. (self%kt > 0.0_dp .and. self%kn > 0.0_dp)
    end function unilateral_coupled

    !> Stuck: a constraint (with the normal when rigid; none for a Jenkins friction).
    pure logical function unilateral_holds_constraint(self, code) result(h)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        h = code(1) == 0 .and. self%coupled()
    end function unilateral_holds_constraint

    !> Moving: its slip direction or open; at rest: stuck, slipping either way, open.
    subroutine unilateral_candidates(self, code, geom, y, cand, ncand)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: cand(:, :)
        integer, intent(out) :: ncand
        real(dp) :: v
        if (self%nstate() > 0) then
            ! Jenkins friction on a rigid normal: its slider decides (consistent)
            ncand = 4
            cand(1, 1:4) = [0, 1, -1, 2]
            return
        end if
        if (self%law%ntangent == 2) then
            ! 2D friction: moving (above 1.5 rest_speed: a slip that stopped is at
            ! rest_speed), slipping or open; at rest, stuck, slipping (against the force it
            ! cannot hold) or open
            if (slip_speed(geom, y) > 1.5_dp*rest_speed*geom%vref) then
                ncand = 2
                cand(1, 1:2) = [1, 2]
            else
                ncand = 3
                cand(1, 1:3) = [0, 1, 2]
            end if
            return
        end if
        v = dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))
        if (abs(v) > 1.0e-12_dp*geom%vref) then
            ncand = 2
            cand(1, 1:2) = [nint(sign(1.0_dp, v)), 2]
        else
            ncand = 4
            cand(1, 1:4) = [0, 1, -1, 2]
        end if
    end subroutine unilateral_candidates

    !> lambda >= 0 when closed; stuck: |r| <= mu lambda; open: the gap does not close (gap
    !> velocity, then acceleration, >= 0); slipping from rest: accelerating in its direction.
    !> Tolerances 1e-9 of the scales.
    logical function unilateral_consistent(self, code, moving, geom, fb, y, ydot) result(ok)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        logical, intent(in) :: moving
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:), ydot(:)
        real(dp) :: lam, r, gvel, gacc, acc
        integer :: n, nt
        n = geom%n
        nt = self%law%ntangent
        ok = .true.
        lam = 0.0_dp
        if (code(1) /= 2) then
            lam = dot_product(fb(nt + 1, :), y)
            if (lam < -tol*geom%fref) ok = .false.
        end if
        if (self%nstate() > 0 .and. code(1) /= 2) then
            ok = ok .and. jenkins_consistent()
            return
        end if
        select case (code(1))
        case (0)
            r = norm2(matmul(fb(1:nt, :), y))
            if (abs(r) > self%law%mu*max(lam, 0.0_dp) + tol*geom%fref) ok = .false.
        case (2)
            gvel = dot_product(geom%dt(:, 3), y(n + 1:2*n))
            if (gvel < -tol*geom%gref*geom%omega) then
                ok = .false.
            else if (gvel <= tol*geom%gref*geom%omega) then
                gacc = dot_product(geom%dt(:, 3), ydot(n + 1:2*n))
                if (gacc < -tol*geom%gref*geom%omega**2) ok = .false.
            end if
        case default
            ! a 2D slip from rest takes the direction the dynamics give it
            if (.not. moving .and. nt == 1) then
                acc = code(1)*dot_product(geom%dt(:, 1), ydot(n + 1:2*n))
                if (acc < -tol*geom%vref*geom%omega) ok = .false.
            end if
        end select
    contains
        !> A Jenkins slider on a rigid normal: stuck, the spring's force within the limit, and
        !> not leaving it (on the limit, |r| - mu lambda not increasing); slipping, the
        !> spring's force on the limit against the slip.
        logical function jenkins_consistent() result(good)
            real(dp) :: fr(geom%na), lrow(geom%na), rs, slope
            call spring_rows(self, geom, fr, lrow)
            rs = dot_product(fr, y)
            good = .true.
            if (code(1) == 0) then
                if (abs(rs) > self%law%mu*max(lam, 0.0_dp) + tol*geom%fref) good = .false.
                if (good .and. abs(rs) >= self%law%mu*lam - tol*geom%fref) then
                    slope = self%law%mu*dot_product(fb(2, :), ydot) - &
                            sign(1.0_dp, rs)*dot_product(fb(1, :), ydot)
                    if (slope < -tol*geom%fref*geom%omega) good = .false.
                end if
            else
                if (-code(1)*rs < self%law%mu*max(lam, 0.0_dp) - tol*geom%fref) good = .false.
            end if
        end function jenkins_consistent
    end function unilateral_consistent

    !> A rigid normal closing with a normal velocity: a plastic impact.
    logical function unilateral_impacts(self, code, geom, y) result(imp)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        imp = self%kn == 0.0_dp .and. &
              dot_product(geom%dt(:, 3), y(geom%n + 1:2*geom%n)) < 0.0_dp
    end function unilateral_impacts

    !> The law of its impacts: itself; behind a tangential stiffness, frictionless (the
    !> spring carries no impulse).
    subroutine unilateral_impact_law(self, e)
        class(unilateral_element_t), intent(in) :: self
        class(contact_element_t), allocatable, intent(out) :: e
        if (self%kt > 0.0_dp) then
            allocate (e, source=new_unilateral_element(self%law%ntangent, 0.0_dp, self%gap, &
                                                       self%preload_force, 0.0_dp, 0.0_dp))
        else
            allocate (e, source=self)
        end if
    end subroutine unilateral_impact_law

    !> A rigid normal, closed.
    pure logical function unilateral_rigid_closed(self, code) result(c)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        c = self%kn == 0.0_dp .and. code(1) /= 2
    end function unilateral_rigid_closed

    !> A rigid normal at a gap below 1e-9 of its scale.
    subroutine unilateral_start_gap(self, geom, y, active, gap)
        class(unilateral_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        logical, intent(out) :: active
        real(dp), intent(out) :: gap
        gap = dot_product(gap_row(self, geom), y)
        active = self%kn == 0.0_dp .and. .not. gap > 1.0e-9_dp*geom%gref
    end subroutine unilateral_start_gap

    !> 2D friction, slipping: the rows of a slip's step (stickslip_disk_slip).
    subroutine unilateral_step_rows(self, code, geom, dir, events)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: dir(:)
        type(event_list_t), intent(inout) :: events
        if (self%law%ntangent == 2 .and. code(1) == 1) call disk_step_rows(geom, dir, events)
    end subroutine unilateral_step_rows

    !> 2D friction, slipping: the friction force against the disk of radius mu lambda
    !> (stickslip_disk_slip): lambda = -k_n (gap + n^T x) on an elastic normal; on a rigid
    !> one the constraint force, lambda = fb_n y + fq_n q (it responds to the friction force
    !> q through the structure: the limit mu lambda = mu fb_n y / (1 + mu fq_n . d)).
    subroutine unilateral_inputs(self, code, geom, y, dir, fb, fq, q, dq, yd0, dyd0, gj)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), dir(:), fb(:, :), fq(:, :)
        real(dp), intent(out) :: q(:), dq(:, :)
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        if (self%kn > 0.0_dp) then
            call disk_inputs(geom, -self%law%mu*self%kn*gap_row(self, geom), y, dir, q, dq, &
                             yd0, dyd0, gj)
        else
            call disk_inputs(geom, self%law%mu*fb(3, :), y, dir, q, dq, yd0, dyd0, gj, &
                             self%law%mu*fq(3, 1:2))
        end if
    end subroutine unilateral_inputs

    !> Rigid friction on an elastic normal: closed and loaded (lambda above 1e-9 of the
    !> force scale) and at rest, Coulomb's law (1D) or the disk (2D) with the limit mu
    !> lambda(y) on the tangential channels (lambda is continuous: it does not depend on the
    !> codes); loaded and moving, its code stands; unloaded (open, opening or closing), it
    !> carries no force and decides alone. A rigid normal or a Jenkins friction: the
    !> enumeration decides. No errors.
    subroutine unilateral_accel_law(self, code, geom, y, kind, box, chans)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: kind
        class(contact_element_t), allocatable, intent(out) :: box
        integer, allocatable, intent(out) :: chans(:)
        real(dp) :: lam
        logical :: moving
        kind = accel_none
        if (.not. self%kn > 0.0_dp .or. self%nstate() > 0) return
        lam = -self%kn*dot_product(gap_row(self, geom), y)
        if (lam <= tol*geom%fref) then
            kind = accel_alone
            return
        end if
        ! stuck, its velocity is held at zero (roundoff aside)
        moving = .false.
        if (code(1) /= 0) then
            if (self%law%ntangent == 2) then
                moving = slip_speed(geom, y) > 1.5_dp*rest_speed*geom%vref
            else
                moving = abs(dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))) > &
                         1.0e-12_dp*geom%vref
            end if
        end if
        if (moving) then
            ! slipping on: its force is known; open and moving while loaded: enumerated
            if (code(1) /= 2) kind = accel_keep
            return
        end if
        kind = accel_box
        if (self%law%ntangent == 2) then
            allocate (box, source=new_planar_element(self%law%mu, lam))
            chans = [1, 2]
        else
            allocate (box, source=new_coulomb_element(self%law%mu, lam))
            chans = [1]
        end if
    end subroutine unilateral_accel_law

    !> 2D friction, slipping: the memory of the slip (stickslip_disk_slip).
    subroutine unilateral_slip_direction(self, code, geom, fb, y, dir)
        class(unilateral_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:)
        real(dp), intent(inout) :: dir(:)
        if (self%law%ntangent == 2 .and. code(1) == 1) call disk_slip_direction(geom, fb, y, dir)
    end subroutine unilateral_slip_direction
end module stickslip_unilateral_element
