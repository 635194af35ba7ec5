!> What the friction laws beyond the rigid 1D Coulomb contact share (doc/contacts.md): a
!> contact with the channels [tangent 1, (tangent 2), (normal)], friction in 1D or in the
!> disk of 2D, with the limit mu N (a constant normal load) or mu lambda(t) (a unilateral
!> contact), a tangential compliance 1 / k_t (the Jenkins element) and, unilateral, a normal
!> compliance 1 / k_n, a gap and a preload. Its equalities are stickslip_contact_law's. The
!> laws that extend it (planar, jenkins, unilateral: one file each) add their name and what
!> the exact reference needs of them.
module stickslip_friction_contact
    use stickslip_kinds, only: dp
    use stickslip_contact_law, only: contact_law_t, contact_psi, contact_psi_jacobian, &
        contact_state
    use stickslip_contact_element, only: contact_element_t, channel_t, kinematics_velocity, &
        kinematics_gap, along_tangent, along_tangent2, along_normal, state_stick, &
        element_step_forces
    implicit none
    private
    public :: friction_contact_t, init_friction_contact

    !> A contact with 1D or 2D friction, a constant or a varying normal force, compliances.
    type, abstract, extends(contact_element_t) :: friction_contact_t
        !> Its channels and friction parameters (stickslip_contact_law).
        type(contact_law_t) :: law
        !> Initial gap [m], preload [N], normal and tangential contact stiffness [N/m]
        !> (0: rigid).
        real(dp) :: gap = 0.0_dp, preload_force = 0.0_dp, kn = 0.0_dp, kt = 0.0_dp
    contains
        procedure :: psi => fc_psi
        procedure :: psi_jacobian => fc_psi_jacobian
        procedure :: states => fc_states
        procedure :: coulomb_dissipation => fc_dissipation
        procedure :: force_ratio => fc_force_ratio
        procedure :: force_scale => fc_force_scale
        procedure :: normal_load => fc_normal_load
        procedure :: rest_limit => fc_rest_limit
        procedure :: preload => fc_preload
        procedure :: set_parameter => fc_set_parameter
        procedure :: settle_offset => fc_settle_offset
        procedure :: project => fc_project
        procedure :: step_forces => fc_step_forces
        !> The friction limit at samples of the channel forces [N].
        procedure :: limit_samples => fc_limit_samples
    end type friction_contact_t

contains

    !> Set the law and the channels of a friction contact: ntangent (1 or 2) tangential
    !> channels, a normal channel when `unilateral`; mu, the constant normal load [N] (0 when
    !> unilateral), gap [m], preload [N], normal and tangential stiffness [N/m] (0: rigid).
    subroutine init_friction_contact(self, ntangent, unilateral, mu, normal_load, gap, &
                                     preload, kn, kt)
        !> The contact.
        class(friction_contact_t), intent(inout) :: self
        !> Tangential channels.
        integer, intent(in) :: ntangent
        !> A normal channel.
        logical, intent(in) :: unilateral
        !> Parameters.
        real(dp), intent(in) :: mu, normal_load, gap, preload, kn, kt
        integer :: k
        real(dp) :: ct, cn
        self%law = contact_law_t(ntangent=ntangent, unilateral=unilateral, mu=mu, &
                                 normal_load=normal_load)
        self%gap = gap
        self%preload_force = preload
        self%kn = kn
        self%kt = kt
        ct = 0.0_dp
        if (kt > 0.0_dp) ct = 1.0_dp/kt
        cn = 0.0_dp
        if (kn > 0.0_dp) cn = 1.0_dp/kn
        if (allocated(self%channel)) deallocate (self%channel)
        allocate (self%channel(ntangent + merge(1, 0, unilateral)))
        do k = 1, ntangent
            self%channel(k) = channel_t(along=merge(along_tangent, along_tangent2, k == 1), &
                                        kinematics=kinematics_velocity, compliance=ct, &
                                        holds=mu > 0.0_dp .and. &
                                        (unilateral .or. normal_load > 0.0_dp))
        end do
        if (unilateral) self%channel(ntangent + 1) = &
            channel_t(along=along_normal, kinematics=kinematics_gap, compliance=cn, gap=gap, &
                      holds=.true.)
    end subroutine init_friction_contact

    !> Psi at the samples [m/s].
    subroutine fc_psi(self, rho, r, u, p)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        real(dp), intent(out) :: p(:, :)
        integer :: k
        do k = 1, size(r, 1)
            call contact_psi(self%law, rho, r(k, :), u(k, :), p(k, :))
        end do
    end subroutine fc_psi

    !> Psi and its generalized Jacobians at the samples.
    subroutine fc_psi_jacobian(self, rho, r, u, p, jr, ju)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        real(dp), intent(out) :: p(:, :), jr(:, :, :), ju(:, :, :)
        integer :: k
        do k = 1, size(r, 1)
            call contact_psi_jacobian(self%law, rho, r(k, :), u(k, :), p(k, :), jr(:, :, k), &
                                      ju(:, :, k))
        end do
    end subroutine fc_psi_jacobian

    !> Open, stick or slip at the samples (stickslip_contact_law's contact_state).
    subroutine fc_states(self, rho, r, u, state)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        integer, intent(out) :: state(:)
        integer :: k
        do k = 1, size(r, 1)
            state(k) = contact_state(self%law, rho, r(k, :), u(k, :))
        end do
    end subroutine fc_states

    !> The friction limit at the samples [N]: mu N, or mu max(lambda(t), 0).
    function fc_limit_samples(self, r) result(g)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: r(:, :)
        real(dp) :: g(size(r, 1))
        if (self%law%unilateral) then
            g = self%law%mu*max(r(:, self%law%ntangent + 1), 0.0_dp)
        else
            g = self%law%mu*self%law%normal_load
        end if
    end function fc_limit_samples

    !> g |u_t| over the period (u_t the slider velocity, its modulus in 2D); what the law
    !> dissipates: that where the contact does not stick, |r . u_t| where it sticks.
    subroutine fc_dissipation(self, rho, r, u, state, period, diss, law_diss)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :), period
        integer, intent(in) :: state(:)
        real(dp), intent(out) :: diss, law_diss
        real(dp) :: g(size(r, 1)), speed(size(r, 1)), power(size(r, 1))
        integer :: nt
        nt = size(r, 1)
        g = self%limit_samples(r)
        if (self%law%ntangent == 2) then
            speed = hypot(u(:, 1), u(:, 2))
            power = abs(r(:, 1)*u(:, 1) + r(:, 2)*u(:, 2))
        else
            speed = abs(u(:, 1))
            power = abs(r(:, 1)*u(:, 1))
        end if
        diss = period*sum(g*speed)/nt
        law_diss = period*sum(merge(power, g*speed, state == state_stick))/nt
    end subroutine fc_dissipation

    !> max_t (|r_t| - g) / max_t g + 1 (0 when the limit is 0 throughout).
    real(dp) function fc_force_ratio(self, r) result(ratio)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: r(:, :)
        real(dp) :: g(size(r, 1)), rmag(size(r, 1))
        g = self%limit_samples(r)
        if (self%law%ntangent == 2) then
            rmag = hypot(r(:, 1), r(:, 2))
        else
            rmag = abs(r(:, 1))
        end if
        ratio = 0.0_dp
        if (maxval(g) > 0.0_dp) ratio = maxval(rmag - g)/maxval(g) + 1.0_dp
    end function fc_force_ratio

    !> The largest of mu N, the preload and mu times it [N].
    pure real(dp) function fc_force_scale(self) result(f)
        class(friction_contact_t), intent(in) :: self
        f = max(self%law%mu*self%law%normal_load, self%preload_force, &
                self%law%mu*self%preload_force)
    end function fc_force_scale

    !> The friction limit of a tangential channel at rest, mu max(N, preload) [N]; 0 for the
    !> normal channel.
    pure real(dp) function fc_rest_limit(self, k) result(g)
        class(friction_contact_t), intent(in) :: self
        integer, intent(in) :: k
        g = 0.0_dp
        if (k <= self%law%ntangent) g = self%law%mu*max(self%law%normal_load, self%preload_force)
    end function fc_rest_limit

    !> The constant normal load [N] (0 for a unilateral contact).
    pure real(dp) function fc_normal_load(self) result(n)
        class(friction_contact_t), intent(in) :: self
        n = self%law%normal_load
    end function fc_normal_load

    !> The preload [N].
    pure real(dp) function fc_preload(self) result(p)
        class(friction_contact_t), intent(in) :: self
        p = self%preload_force
    end function fc_preload

    !> mu; the normal load of a contact under a constant load; the preload of a unilateral one.
    subroutine fc_set_parameter(self, name, value, done)
        class(friction_contact_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: value
        logical, intent(out) :: done
        done = .false.
        select case (name)
        case ('mu')
            self%law%mu = value
            done = .true.
        case ('normal_load')
            if (.not. self%law%unilateral) then
                self%law%normal_load = value
                done = .true.
            end if
        case ('preload')
            if (self%law%unilateral) then
                self%preload_force = value
                done = .true.
            end if
        end select
        self%channel(1:self%law%ntangent)%holds = self%law%mu > 0.0_dp .and. &
            (self%law%unilateral .or. self%law%normal_load > 0.0_dp)
    end subroutine fc_set_parameter

    !> The mean friction force of a contact stuck over the whole period, the admissible value
    !> closest to zero: in 1D the interval of shifts keeping |r(t)| <= g(t) at every sample;
    !> in 2D the largest step of the mean toward zero that keeps |r(t)| <= g(t) (bisection).
    subroutine fc_settle_offset(self, rho, r, u, mean, settled)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: rho
        real(dp), intent(inout) :: r(:, :), u(:, :), mean(:)
        logical, intent(out) :: settled
        real(dp) :: g(size(r, 1)), lo, hi, shift, t, tlo, thi, r0(2)
        integer :: it, m, state(size(r, 1))
        settled = .false.
        call self%states(rho, r, u, state)
        if (.not. all(state == state_stick)) return
        g = self%limit_samples(r)
        settled = .true.
        if (self%law%ntangent == 1) then
            lo = maxval(-g - (r(:, 1) - mean(1)))
            hi = minval(g - (r(:, 1) - mean(1)))
            shift = min(max(0.0_dp, lo), hi) - mean(1)
            mean(1) = mean(1) + shift
            r(:, 1) = r(:, 1) + shift
            return
        end if
        ! the step t in [0, 1] toward a zero mean: admissible at t = 0
        r0 = mean(1:2)
        tlo = 0.0_dp
        thi = 1.0_dp
        if (.not. inside(1.0_dp)) then
            do it = 1, 60
                t = 0.5_dp*(tlo + thi)
                if (inside(t)) then
                    tlo = t
                else
                    thi = t
                end if
            end do
        else
            tlo = 1.0_dp
        end if
        do m = 1, 2
            mean(m) = (1.0_dp - tlo)*r0(m)
            r(:, m) = r(:, m) - tlo*r0(m)
        end do

    contains

        !> The force with its mean moved by t toward zero stays in the disks.
        logical function inside(t)
            real(dp), intent(in) :: t
            inside = all(hypot(r(:, 1) - t*r0(1), r(:, 2) - t*r0(2)) <= g)
        end function inside
    end subroutine fc_settle_offset

    !> The forces of one implicit step: in 1D under a constant load (a rigid contact or a
    !> Jenkins slider) in closed form, the stick force -q / a clamped to the limit;
    !> otherwise the semismooth Newton iteration of contact_element_t (with fc_project as
    !> its fallback).
    subroutine fc_step_forces(self, a, q, r, scale)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: a(:, :), q(:)
        real(dp), intent(inout) :: r(:)
        real(dp), intent(in) :: scale
        real(dp) :: g
        if (self%law%ntangent == 1 .and. .not. self%law%unilateral) then
            g = self%law%mu*self%law%normal_load
            r(1) = max(-g, min(g, -q(1)/a(1, 1)))
            return
        end if
        call element_step_forces(self, a, q, r, scale)
    end subroutine fc_step_forces

    !> The projection iteration, the fallback of the step's Newton iteration: the normal force
    !> max(0, lambda - u_n / A_nn), then the friction force z_t - u_t / A_tt projected on the
    !> limit's interval or disk, until the forces settle.
    subroutine fc_project(self, a, q, r, scale)
        class(friction_contact_t), intent(in) :: self
        real(dp), intent(in) :: a(:, :), q(:)
        real(dp), intent(inout) :: r(:)
        real(dp), intent(in) :: scale
        real(dp) :: u(size(r)), g, zt(2), zn, old(size(r))
        integer :: it, nt, k, m
        m = size(r)
        nt = self%law%ntangent
        do it = 1, 2000
            old = r
            if (self%law%unilateral) then
                u = q + matmul(a, r)
                r(m) = max(0.0_dp, r(m) - u(m)/a(m, m))
                g = self%law%mu*r(m)
            else
                g = self%law%mu*self%law%normal_load
            end if
            u = q + matmul(a, r)
            do k = 1, nt
                zt(k) = r(k) - u(k)/a(k, k)
            end do
            if (nt == 1) then
                r(1) = max(-g, min(g, zt(1)))
            else
                zn = norm2(zt)
                if (zn > g) then
                    r(1:2) = g*zt/zn
                else
                    r(1:2) = zt
                end if
            end if
            if (maxval(abs(r - old)) <= 1.0e-15_dp*max(scale, maxval(abs(r)))) exit
        end do
    end subroutine fc_project
end module stickslip_friction_contact
