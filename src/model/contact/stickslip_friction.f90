!> Coulomb's law as an equality (Legrand & Pierre 2023): for rho > 0,
!>     Psi(r, v) = v + min(0, rho (r + mu N) - v) + max(0, rho (r - mu N) - v) = 0
!> holds exactly when (r, v) obeys Coulomb's law with limit mu N: |r| <= mu N when v = 0,
!> r = -mu N sign(v) otherwise. This is the one place that knows the three regions.
module stickslip_friction
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: psi, psi_stick, psi_limit_derivative

contains

    !> Psi(r, v) for friction force r [N], slip velocity v [m/s], limit g = mu N >= 0 [N] and
    !> weight rho > 0 [m/(N s)]. Same units as v.
    elemental real(dp) function psi(r, v, g, rho)
        !> Friction force [N].
        real(dp), intent(in) :: r
        !> Slip velocity [m/s].
        real(dp), intent(in) :: v
        !> Friction limit mu N [N].
        real(dp), intent(in) :: g
        !> Weight of the force against the velocity.
        real(dp), intent(in) :: rho
        psi = v + min(0.0_dp, rho*(r + g) - v) + max(0.0_dp, rho*(r - g) - v)
    end function psi

    !> Stick indicator s of the generalized derivative of Psi: 1 in the stick region
    !> rho (r - g) < v < rho (r + g), where dPsi/dv = 1 and dPsi/dr = 0; 0 in the two slip
    !> regions, where dPsi/dr = rho and dPsi/dv = 0. On a boundary the slip side is chosen
    !> (an element of Clarke's generalized Jacobian).
    elemental real(dp) function psi_stick(r, v, g, rho) result(s)
        !> Friction force [N].
        real(dp), intent(in) :: r
        !> Slip velocity [m/s].
        real(dp), intent(in) :: v
        !> Friction limit mu N [N].
        real(dp), intent(in) :: g
        !> Weight of the force against the velocity.
        real(dp), intent(in) :: rho
        if (rho*(r - g) - v < 0.0_dp .and. rho*(r + g) - v > 0.0_dp) then
            s = 1.0_dp
        else
            s = 0.0_dp
        end if
    end function psi_stick

    !> dPsi/dg, the derivative of Psi with respect to the friction limit g = mu N [m/(N s)]:
    !> +rho in the slip region rho (r + g) - v <= 0 (Psi = rho (r + g)), -rho in the slip
    !> region rho (r - g) - v >= 0 (Psi = rho (r - g)), 0 in the stick region (Psi = v).
    !> The same choice on the boundaries as psi_stick.
    elemental real(dp) function psi_limit_derivative(r, v, g, rho) result(d)
        !> Friction force [N].
        real(dp), intent(in) :: r
        !> Slip velocity [m/s].
        real(dp), intent(in) :: v
        !> Friction limit mu N [N].
        real(dp), intent(in) :: g
        !> Weight of the force against the velocity.
        real(dp), intent(in) :: rho
        if (psi_stick(r, v, g, rho) > 0.5_dp) then
            d = 0.0_dp
        else if (rho*(r + g) - v <= 0.0_dp) then
            d = rho
        else
            d = -rho
        end if
    end function psi_limit_derivative
end module stickslip_friction
