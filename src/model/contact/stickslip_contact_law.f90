!> The contact laws of one contact at one instant as equalities Psi(r, u) = 0 and their
!> generalized Jacobians (doc/contacts.md): the extension of stickslip_friction to
!> unilateral contact, a varying normal force, 2D friction and contact stiffness.
!>
!> A contact has the channels [tangent 1, (tangent 2), (normal)]; r holds their forces
!> (friction forces [N], normal force lambda >= 0 [N]) and u their kinematic quantities, all
!> in velocity units [m/s]:
!> - tangential channel: the slider velocity u_t = w^T x' + r'/k_t (w^T x' when rigid);
!> - normal channel: u_n = omega (g + lambda / k_n), g = gap + n^T x (omega g when rigid):
!>   the gap measured in velocity units by the fundamental angular frequency.
!> The equalities, with the same weight rho [m/(N s)] as Coulomb's:
!> - normal (Signorini): Psi_n = u_n - max(0, u_n - rho lambda) = min(u_n, rho lambda),
!>   zero exactly when u_n >= 0, lambda >= 0, u_n lambda = 0;
!> - friction with limit g_f = mu N (constant load) or mu max(lambda, 0):
!>   Psi_t = rho r_t - proj_{B(rho g_f)}(rho r_t - u_t), B the interval (1D) or the disk (2D);
!>   in 1D this is stickslip_friction's psi.
!> Jacobians: dPsi/dr (jr) and dPsi/du (ju), m x m, m the contact's channels; elements of
!> Clarke's generalized Jacobian, the slip (open) side chosen on region boundaries.
module stickslip_contact_law
    use stickslip_kinds, only: dp
    use stickslip_friction, only: psi, psi_stick, psi_limit_derivative
    implicit none
    private
    public :: contact_law_t, contact_psi, contact_psi_jacobian, contact_state
    public :: state_open, state_stick, state_slip

    !> Contact states at an instant (contact_state).
    integer, parameter :: state_open = 0, state_stick = 1, state_slip = 2

    !> The law of one contact: its channels and parameters.
    type :: contact_law_t
        !> Tangential channels (1 or 2).
        integer :: ntangent = 1
        !> Has a normal channel (unilateral contact), the last of its channels.
        logical :: unilateral = .false.
        !> Friction coefficient.
        real(dp) :: mu = 0.0_dp
        !> Constant normal load [N] (without a normal channel).
        real(dp) :: normal_load = 0.0_dp
    end type contact_law_t

contains

    !> The friction limit [N] and its derivative d limit / d lambda at forces `r`.
    pure subroutine friction_limit(law, r, g, dg)
        type(contact_law_t), intent(in) :: law
        real(dp), intent(in) :: r(:)
        real(dp), intent(out) :: g, dg
        if (law%unilateral) then
            g = law%mu*max(r(law%ntangent + 1), 0.0_dp)
            dg = 0.0_dp
            if (r(law%ntangent + 1) > 0.0_dp) dg = law%mu
        else
            g = law%mu*law%normal_load
            dg = 0.0_dp
        end if
    end subroutine friction_limit

    !> Psi(r, u) of one contact [m/s]: forces r [N] and kinematic quantities u [m/s] of its
    !> channels, weight rho [m/(N s)].
    pure subroutine contact_psi(law, rho, r, u, p)
        !> The contact's law.
        type(contact_law_t), intent(in) :: law
        !> Weight of the forces against the velocities [m/(N s)].
        real(dp), intent(in) :: rho
        !> Channel forces [N].
        real(dp), intent(in) :: r(:)
        !> Channel kinematic quantities [m/s].
        real(dp), intent(in) :: u(:)
        !> The equalities [m/s].
        real(dp), intent(out) :: p(:)
        real(dp) :: g, dg, z(2), zn
        integer :: m
        call friction_limit(law, r, g, dg)
        m = law%ntangent
        if (m == 1) then
            p(1) = psi(r(1), u(1), g, rho)
        else
            z = rho*r(1:2) - u(1:2)
            zn = norm2(z)
            if (zn < rho*g) then
                p(1:2) = u(1:2)
            else if (zn > 0.0_dp) then
                p(1:2) = rho*r(1:2) - rho*g*z/zn
            else
                p(1:2) = rho*r(1:2)
            end if
        end if
        if (law%unilateral) p(m + 1) = u(m + 1) - max(0.0_dp, u(m + 1) - rho*r(m + 1))
    end subroutine contact_psi

    !> Psi(r, u) of one contact and its generalized Jacobians jr = dPsi/dr [m/(N s)] and
    !> ju = dPsi/du (dimensionless), m x m with m = ntangent (+ 1 when unilateral).
    pure subroutine contact_psi_jacobian(law, rho, r, u, p, jr, ju)
        !> The contact's law.
        type(contact_law_t), intent(in) :: law
        !> Weight of the forces against the velocities [m/(N s)].
        real(dp), intent(in) :: rho
        !> Channel forces [N].
        real(dp), intent(in) :: r(:)
        !> Channel kinematic quantities [m/s].
        real(dp), intent(in) :: u(:)
        !> The equalities [m/s].
        real(dp), intent(out) :: p(:)
        !> dPsi/dr and dPsi/du.
        real(dp), intent(out) :: jr(:, :), ju(:, :)
        real(dp) :: g, dg, z(2), zn, zh(2), q
        integer :: m, i
        call contact_psi(law, rho, r, u, p)
        call friction_limit(law, r, g, dg)
        m = law%ntangent
        jr = 0.0_dp
        ju = 0.0_dp
        if (m == 1) then
            if (psi_stick(r(1), u(1), g, rho) > 0.5_dp) then
                ju(1, 1) = 1.0_dp
            else
                jr(1, 1) = rho
                if (law%unilateral) jr(1, 2) = psi_limit_derivative(r(1), u(1), g, rho)*dg
            end if
        else
            z = rho*r(1:2) - u(1:2)
            zn = norm2(z)
            if (zn < rho*g) then
                ju(1, 1) = 1.0_dp
                ju(2, 2) = 1.0_dp
            else if (zn > 0.0_dp) then
                zh = z/zn
                q = rho*g/zn
                ! dp/dz = q (I - zh zh^T): ju = dp/dz, jr = rho (I - dp/dz)
                do i = 1, 2
                    ju(1:2, i) = -q*zh*zh(i)
                    ju(i, i) = ju(i, i) + q
                end do
                jr(1:2, 1:2) = -rho*ju(1:2, 1:2)
                jr(1, 1) = jr(1, 1) + rho
                jr(2, 2) = jr(2, 2) + rho
                if (law%unilateral) jr(1:2, 3) = -rho*zh*dg
            else
                jr(1, 1) = rho
                jr(2, 2) = rho
            end if
        end if
        if (law%unilateral) then
            if (u(m + 1) - rho*r(m + 1) < 0.0_dp) then
                ju(m + 1, m + 1) = 1.0_dp
            else
                jr(m + 1, m + 1) = rho
            end if
        end if
    end subroutine contact_psi_jacobian

    !> The state of one contact at an instant: state_open (unilateral and the normal
    !> equality is on its open side, u_n > rho lambda), state_stick (the friction equality
    !> in its stick region) or state_slip.
    pure integer function contact_state(law, rho, r, u) result(state)
        !> The contact's law.
        type(contact_law_t), intent(in) :: law
        !> Weight of the forces against the velocities [m/(N s)].
        real(dp), intent(in) :: rho
        !> Channel forces [N].
        real(dp), intent(in) :: r(:)
        !> Channel kinematic quantities [m/s].
        real(dp), intent(in) :: u(:)
        real(dp) :: g, dg
        integer :: m
        m = law%ntangent
        if (law%unilateral) then
            if (.not. (u(m + 1) - rho*r(m + 1) < 0.0_dp)) then
                state = state_open
                return
            end if
        end if
        call friction_limit(law, r, g, dg)
        if (m == 1) then
            state = state_slip
            if (psi_stick(r(1), u(1), g, rho) > 0.5_dp) state = state_stick
        else
            state = state_slip
            if (norm2(rho*r(1:2) - u(1:2)) < rho*g) state = state_stick
        end if
    end function contact_state
end module stickslip_contact_law
