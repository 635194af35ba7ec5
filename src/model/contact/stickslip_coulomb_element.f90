!> The rigid Coulomb contact under a constant normal load (doc/contacts.md): one channel, the
!> friction force r along w and the slip velocity v = w^T x', Coulomb's law with the limit
!> g = mu N as the equality of stickslip_friction,
!>     Psi(r, v) = v + min(0, rho (r + g) - v) + max(0, rho (r - g) - v) = 0.
!> The contact of the seed case and of every model without the other laws. Its kernels are
!> the batched fast paths of before: the weighted-residual Jacobian from one FFT of the
!> stick indicator (A G + rho (I - A)), the closed-form step of implicit Euler, and, for a
!> set of Coulomb contacts only, the projected Gauss-Seidel of stickslip_contact_solve
!> (stickslip_contact_set) and the exact flow's acceleration-level mode decision.
module stickslip_coulomb_element
    use stickslip_kinds, only: dp
    use stickslip_basis, only: basis_t
    use stickslip_friction, only: psi, psi_stick
    use stickslip_contact_element, only: contact_element_t, channel_t, hb_work_t, &
        state_stick, state_slip
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        action_decide
    implicit none
    private
    public :: coulomb_element_t, new_coulomb_element

    !> A slip velocity below this share of the contact's velocity scale at the start of the
    !> exact flow is rest (decided jointly, at acceleration level): the start state comes
    !> from a weighted-residual solution, whose stuck velocities are roundoff of its
    !> transformation into the flow's coordinates (~1e-15 of the structure's velocity; a
    !> stuck ring of shrouds in a disk at rest or in engine order 0), not slips.
    real(dp), parameter :: start_rest = 1.0e-9_dp

    !> Rigid 1D Coulomb friction with a constant normal load.
    type, extends(contact_element_t) :: coulomb_element_t
        !> Friction coefficient (>= 0) and normal load [N] (>= 0).
        real(dp) :: mu = 0.0_dp, normal = 0.0_dp
        !> The friction limit mu N [N].
        real(dp) :: limit = 0.0_dp
    contains
        procedure :: law_name => coulomb_name
        procedure :: psi => coulomb_psi
        procedure :: psi_jacobian => coulomb_psi_jacobian
        procedure :: states => coulomb_states
        procedure :: step_states => coulomb_step_states
        procedure :: coulomb_dissipation => coulomb_dissipation
        procedure :: force_ratio => coulomb_force_ratio
        procedure :: force_scale => coulomb_force_scale
        procedure :: normal_load => coulomb_normal_load
        procedure :: set_parameter => coulomb_set_parameter
        procedure :: settle_offset => coulomb_settle_offset
        procedure :: step_forces => coulomb_step_forces
        procedure :: hb_jacobian => coulomb_hb_jacobian
        procedure :: exact_support => coulomb_exact_support
        procedure :: mode_terms => coulomb_mode_terms
        procedure :: event_rows => coulomb_event_rows
        procedure :: start_code => coulomb_start_code
        procedure :: coupled => coulomb_coupled
        procedure :: holds_constraint => coulomb_holds_constraint
        procedure :: candidates => coulomb_candidates
        procedure :: consistent => coulomb_consistent
        procedure :: accel_decision => coulomb_accel_decision
        procedure :: accel_code => coulomb_accel_code
    end type coulomb_element_t

contains

    !> The element of friction coefficient mu >= 0 and normal load >= 0 [N].
    function new_coulomb_element(mu, normal_load) result(self)
        !> Friction coefficient and normal load [N].
        real(dp), intent(in) :: mu, normal_load
        type(coulomb_element_t) :: self
        self%mu = mu
        self%normal = normal_load
        self%limit = mu*normal_load
        allocate (self%channel(1))
        self%channel(1) = channel_t(holds=self%limit > 0.0_dp)
    end function new_coulomb_element

    pure function coulomb_name(self) result(name)
        class(coulomb_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "coulomb"
    end function coulomb_name

    !> Psi at the samples (stickslip_friction's psi) [m/s].
    subroutine coulomb_psi(self, rho, r, u, p)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        real(dp), intent(out) :: p(:, :)
        p(:, 1) = psi(r(:, 1), u(:, 1), self%limit, rho)
    end subroutine coulomb_psi

    !> Psi and its Jacobians: dPsi/du = s, dPsi/dr = rho (1 - s), s the stick indicator.
    subroutine coulomb_psi_jacobian(self, rho, r, u, p, jr, ju)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        real(dp), intent(out) :: p(:, :), jr(:, :, :), ju(:, :, :)
        p(:, 1) = psi(r(:, 1), u(:, 1), self%limit, rho)
        ju(1, 1, :) = psi_stick(r(:, 1), u(:, 1), self%limit, rho)
        jr(1, 1, :) = rho*(1.0_dp - ju(1, 1, :))
    end subroutine coulomb_psi_jacobian

    !> Stick where the stick indicator is 1, slip elsewhere (never open).
    subroutine coulomb_states(self, rho, r, u, state)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        integer, intent(out) :: state(:)
        state = merge(state_stick, state_slip, psi_stick(r(:, 1), u(:, 1), self%limit, rho) > 0.5_dp)
    end subroutine coulomb_states

    !> After implicit steps: slip where the force is at the limit (to 1e-12), stick elsewhere
    !> (the force of a step is the clamped stick force).
    subroutine coulomb_step_states(self, rho, r, u, state)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        integer, intent(out) :: state(:)
        state = merge(state_slip, state_stick, abs(r(:, 1)) >= self%limit*(1.0_dp - 1.0e-12_dp))
    end subroutine coulomb_step_states

    !> mu N |v| over the period; what the law dissipates: mu N |v| where it slips, |r v|
    !> (<= mu N |v|, ~0) where it sticks (a stuck contact's roundoff slip times a huge mu N is
    !> no dissipation).
    subroutine coulomb_dissipation(self, rho, r, u, state, period, diss, law_diss)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :), period
        integer, intent(in) :: state(:)
        real(dp), intent(out) :: diss, law_diss
        integer :: nt
        nt = size(r, 1)
        diss = self%limit*period*sum(abs(u(:, 1)))/nt
        law_diss = period*sum(merge(abs(r(:, 1)*u(:, 1)), self%limit*abs(u(:, 1)), &
                                    state == state_stick))/nt
    end subroutine coulomb_dissipation

    !> max |r| / mu N (0 without a limit).
    real(dp) function coulomb_force_ratio(self, r) result(ratio)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: r(:, :)
        ratio = 0.0_dp
        if (self%limit > 0.0_dp) ratio = maxval(abs(r(:, 1)))/self%limit
    end function coulomb_force_ratio

    !> mu N [N].
    pure real(dp) function coulomb_force_scale(self) result(f)
        class(coulomb_element_t), intent(in) :: self
        f = self%limit
    end function coulomb_force_scale

    !> The constant normal load N [N].
    pure real(dp) function coulomb_normal_load(self) result(n)
        class(coulomb_element_t), intent(in) :: self
        n = self%normal
    end function coulomb_normal_load

    !> mu or the normal load.
    subroutine coulomb_set_parameter(self, name, value, done)
        class(coulomb_element_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: value
        logical, intent(out) :: done
        done = .true.
        select case (name)
        case ('mu')
            self%mu = value
        case ('normal_load')
            self%normal = value
        case default
            done = .false.
        end select
        self%limit = self%mu*self%normal
        self%channel(1)%holds = self%limit > 0.0_dp
    end subroutine coulomb_set_parameter

    !> A contact stuck over the whole period holds any mean force that keeps |r(t)| <= mu N:
    !> the admissible value closest to zero (minimum norm).
    subroutine coulomb_settle_offset(self, rho, r, u, mean, settled)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: rho
        real(dp), intent(inout) :: r(:, :), u(:, :), mean(:)
        logical, intent(out) :: settled
        real(dp) :: lo, hi, shift
        settled = .false.
        if (.not. all(psi_stick(r(:, 1), u(:, 1), self%limit, rho) > 0.5_dp)) return
        lo = -self%limit - minval(r(:, 1) - mean(1))
        hi = self%limit - maxval(r(:, 1) - mean(1))
        shift = min(max(0.0_dp, lo), hi) - mean(1)
        mean(1) = mean(1) + shift
        r(:, 1) = r(:, 1) + shift
        settled = .true.
    end subroutine coulomb_settle_offset

    !> The step's force in closed form: the stick force -q / a, clamped to the limit.
    subroutine coulomb_step_forces(self, a, q, r, scale)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: a(:, :), q(:)
        real(dp), intent(inout) :: r(:)
        real(dp), intent(in) :: scale
        r(1) = max(-self%limit, min(self%limit, -q(1)/a(1, 1)))
    end subroutine coulomb_step_forces

    !> The rows of the weighted-residual Jacobian, dF/dR_l = A G_l + delta rho (I - A), A =
    !> P diag(s) Q from one FFT of the stick indicator s (the receptance kap of the slip
    !> velocity is the condensed G).
    subroutine coulomb_hb_jacobian(self, basis, rho, rs, us, kap, kap0, first, jac, work)
        class(coulomb_element_t), intent(in) :: self
        type(basis_t), intent(in) :: basis
        real(dp), intent(in) :: rho, rs(:, :), us(:, :)
        complex(dp), intent(in) :: kap(:, :, :)
        real(dp), intent(in) :: kap0(:, :)
        integer, intent(in) :: first
        real(dp), intent(inout) :: jac(:, :)
        type(hb_work_t), intent(inout) :: work
        integer :: nb, l, cl, ih, k, i, rj
        real(dp) :: gr, gi
        nb = basis%nb
        work%w = psi_stick(rs(:, 1), us(:, 1), self%limit, rho)
        call basis%fft%forward(work%w, work%cw)
        work%cw = work%cw/real(basis%nt, dp)
        call basis%stick_product(work%cw, work%a)
        rj = (first - 1)*nb
        do l = 1, size(kap, 2)
            cl = (l - 1)*nb
            do ih = 1, basis%nharm
                k = basis%icos(ih)
                gr = real(kap(1, l, ih), dp)
                gi = aimag(kap(1, l, ih))
                jac(1:nb, cl + k) = gr*work%a(:, k) - gi*work%a(:, k + 1)
                jac(1:nb, cl + k + 1) = gi*work%a(:, k) + gr*work%a(:, k + 1)
            end do
        end do
        do i = 1, nb
            jac(1:nb, rj + i) = jac(1:nb, rj + i) - rho*work%a(:, i)
            jac(i, rj + i) = jac(i, rj + i) + rho
        end do
    end subroutine coulomb_hb_jacobian

    ! --- the exact flow: stuck, a constraint w^T v = 0 whose force is the friction force;
    ! slipping with direction c, the constant force -c mu N ---

    !> Handled by the exact flow.
    function coulomb_exact_support(self) result(why)
        class(coulomb_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
    end function coulomb_exact_support

    !> Stuck (code 0, a limit > 0): the constraint w^T v = 0; slipping with direction c: the
    !> force -c mu N along w.
    subroutine coulomb_mode_terms(self, code, geom, terms)
        class(coulomb_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        real(dp) :: row(geom%na)
        if (code(1) == 0 .and. self%limit > 0.0_dp) then
            call terms%constrain(geom%dt(:, 1), geom%dt(:, 1), geom%first, 0, 0.0_dp)
        else if (self%limit > 0.0_dp) then
            row = geom%const_row(-self%limit*code(1))
            call terms%add_force(geom%dt(:, 1), row)
            terms%fb(geom%first, :) = row
        end if
    end subroutine coulomb_mode_terms

    !> Stuck: the margins mu N - r and mu N + r (at zero the contact slips against the
    !> force); slipping with direction c: c w^T v (at zero the contacts decide).
    subroutine coulomb_event_rows(self, code, geom, fb, events)
        class(coulomb_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        if (.not. (self%limit > 0.0_dp)) return
        if (code(1) == 0) then
            call events%add(geom%const_row(self%limit) - fb(1, :), self%limit, 1, -1)
            call events%add(geom%const_row(self%limit) + fb(1, :), self%limit, 1, 1)
        else
            call events%add(code(1)*geom%vel_row(1), geom%vref, 1, action_decide)
        end if
    end subroutine coulomb_event_rows

    !> Slipping in the direction of a slip velocity above start_rest of its scale; at rest
    !> the joint decision settles it (no limit: slipping, no force).
    subroutine coulomb_start_code(self, geom, y, code, decide)
        class(coulomb_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        real(dp) :: v
        v = dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))
        decide = .false.
        if (abs(v) > start_rest*geom%vref) then
            code(1) = nint(sign(1.0_dp, v))
        else if (self%limit > 0.0_dp) then
            code(1) = 0
            decide = .true.
        else
            code(1) = 1
        end if
    end subroutine coulomb_start_code

    !> A contact with a limit takes part in joint decisions.
    pure logical function coulomb_coupled(self) result(c)
        class(coulomb_element_t), intent(in) :: self
        c = self%limit > 0.0_dp
    end function coulomb_coupled

    !> Stuck with a limit: a rigid constraint.
    pure logical function coulomb_holds_constraint(self, code) result(h)
        class(coulomb_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        h = code(1) == 0 .and. self%limit > 0.0_dp
    end function coulomb_holds_constraint

    !> Moving: its slip direction; at rest: stuck, then slipping either way.
    subroutine coulomb_candidates(self, code, geom, y, cand, ncand)
        class(coulomb_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: cand(:, :)
        integer, intent(out) :: ncand
        real(dp) :: v
        v = dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n))
        if (abs(v) > 1.0e-12_dp*geom%vref) then
            ncand = 1
            cand(1, 1) = nint(sign(1.0_dp, v))
        else
            ncand = 3
            cand(1, 1:3) = [0, 1, -1]
        end if
    end subroutine coulomb_candidates

    !> Stuck: the force within mu N (1e-9); slipping from rest: accelerating in its direction.
    logical function coulomb_consistent(self, code, moving, geom, fb, y, ydot) result(ok)
        class(coulomb_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        logical, intent(in) :: moving
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :), y(:), ydot(:)
        real(dp), parameter :: tol = 1.0e-9_dp
        real(dp) :: acc
        ok = .true.
        if (code(1) == 0) then
            ok = abs(dot_product(fb(1, :), y)) <= self%limit*(1.0_dp + tol)
        else if (.not. moving) then
            acc = code(1)*dot_product(geom%dt(:, 1), ydot(geom%n + 1:2*geom%n))
            ok = acc >= -tol*geom%vref*geom%omega
        end if
    end function coulomb_consistent

    !> Decided at acceleration level (Coulomb's law between the friction force and the slip
    !> acceleration).
    pure logical function coulomb_accel_decision(self) result(yes)
        class(coulomb_element_t), intent(in) :: self
        yes = self%limit > 0.0_dp
    end function coulomb_accel_decision

    !> Stuck where the force is inside the limit (1e-12), else slipping against it.
    subroutine coulomb_accel_code(self, r, u, code, dir)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: r(:), u(:)
        integer, intent(inout) :: code(:)
        real(dp), intent(inout) :: dir(:)
        if (abs(r(1)) < self%limit*(1.0_dp - 1.0e-12_dp)) then
            code(1) = 0
        else
            code(1) = -nint(sign(1.0_dp, r(1)))
        end if
    end subroutine coulomb_accel_code
end module stickslip_coulomb_element
