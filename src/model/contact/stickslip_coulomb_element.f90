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
    implicit none
    private
    public :: coulomb_element_t, new_coulomb_element

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
    subroutine coulomb_dissipation(self, r, u, state, period, diss, law_diss)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(in) :: r(:, :), u(:, :), period
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
    subroutine coulomb_settle_offset(self, r, mean, settled)
        class(coulomb_element_t), intent(in) :: self
        real(dp), intent(inout) :: r(:, :), mean(:)
        logical, intent(out) :: settled
        real(dp) :: lo, hi, shift
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
end module stickslip_coulomb_element
