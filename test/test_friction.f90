!> stickslip_friction against Coulomb's law itself and against finite differences: Psi = 0
!> exactly on the Coulomb set (stick with |r| <= g, slip with r = -g sign v) and nowhere else;
!> psi_stick and psi_limit_derivative are the derivatives of Psi away from the region
!> boundaries; Psi is invariant under the scaling of its units.
module test_friction
    use stickslip_kinds, only: dp
    use stickslip_friction, only: psi, psi_stick, psi_limit_derivative
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_friction_tests

contains

    subroutine run_friction_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_zero_set(t)
        call test_derivatives(t)
        call test_scaling(t)
    end subroutine run_friction_tests

    !> On the Coulomb set Psi = 0 for every rho > 0; off it Psi /= 0 (random points, several
    !> rho). Also the three closed forms: v in stick, rho (r + g) and rho (r - g) in slip.
    subroutine test_zero_set(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: g = 0.45_dp, rhos(3) = [1.0e-3_dp, 0.2_dp, 50.0_dp]
        real(dp) :: u(3), r, v, p
        integer :: i, k, bad_on, bad_off
        bad_on = 0
        bad_off = 0
        do k = 1, size(rhos)
            do i = 1, 400
                call random_number(u)
                r = g*(2.0_dp*u(1) - 1.0_dp)          ! |r| <= g: stuck, any admissible r
                if (psi(r, 0.0_dp, g, rhos(k)) /= 0.0_dp) bad_on = bad_on + 1
                v = 10.0_dp*(u(2) + 1.0e-3_dp)            ! slipping: r = -g sign(v)
                if (psi(-g, v, g, rhos(k)) /= 0.0_dp) bad_on = bad_on + 1
                if (psi(g, -v, g, rhos(k)) /= 0.0_dp) bad_on = bad_on + 1
                ! off the set: sliding with a force other than -g sign(v), or stuck beyond g
                if (abs(psi(-g + 0.5_dp*g*u(3) + 1.0e-3_dp, v, g, rhos(k))) == 0.0_dp) &
                    bad_off = bad_off + 1
                if (abs(psi(g*(1.0_dp + u(3)) + 1.0e-3_dp, 0.0_dp, g, rhos(k))) == 0.0_dp) &
                    bad_off = bad_off + 1
            end do
        end do
        call check(t, bad_on == 0, "friction: Psi = 0 on the Coulomb set")
        call check(t, bad_off == 0, "friction: Psi /= 0 off the Coulomb set")
        r = 0.1_dp
        v = 0.01_dp
        p = psi(r, v, g, 0.2_dp)           ! stick: rho (r - g) < v < rho (r + g)
        call check_close(t, p, v, "friction: Psi = v in the stick region", rtol=0.0_dp)
        call check_close(t, psi(r, 5.0_dp, g, 0.2_dp), 0.2_dp*(r + g), &
                         "friction: Psi = rho (r + g) in forward slip", rtol=1.0e-14_dp)
        call check_close(t, psi(r, -5.0_dp, g, 0.2_dp), 0.2_dp*(r - g), &
                         "friction: Psi = rho (r - g) in backward slip", rtol=1.0e-14_dp)
        call check_close(t, psi(0.3_dp, 2.0_dp, 0.0_dp, 0.2_dp), 0.2_dp*0.3_dp, &
                         "friction: g = 0 leaves Psi = rho r", rtol=1.0e-15_dp)
    end subroutine test_zero_set

    !> Central differences of Psi in r, v and g at random points away from the kinks:
    !> dPsi/dv = s, dPsi/dr = rho (1 - s), dPsi/dg = psi_limit_derivative.
    subroutine test_derivatives(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: g = 0.45_dp, rho = 0.3_dp, h = 1.0e-6_dp
        real(dp) :: u(2), r, v, s, dv, dr, dg
        integer :: i, n, bad, regions(0:2)
        bad = 0
        n = 0
        regions = 0
        do i = 1, 600
            call random_number(u)
            r = 3.0_dp*g*(2.0_dp*u(1) - 1.0_dp)
            v = 0.6_dp*(2.0_dp*u(2) - 1.0_dp)
            ! skip points within 10 h of a kink
            if (min(abs(rho*(r + g) - v), abs(rho*(r - g) - v)) < 10.0_dp*h) cycle
            n = n + 1
            s = psi_stick(r, v, g, rho)
            dv = (psi(r, v + h, g, rho) - psi(r, v - h, g, rho))/(2.0_dp*h)
            dr = (psi(r + h, v, g, rho) - psi(r - h, v, g, rho))/(2.0_dp*h)
            dg = (psi(r, v, g + h, rho) - psi(r, v, g - h, rho))/(2.0_dp*h)
            if (abs(dv - s) > 1.0e-8_dp) bad = bad + 1
            if (abs(dr - rho*(1.0_dp - s)) > 1.0e-8_dp) bad = bad + 1
            if (abs(dg - psi_limit_derivative(r, v, g, rho)) > 1.0e-8_dp) bad = bad + 1
            if (s > 0.5_dp) then
                regions(0) = regions(0) + 1
            else if (v > rho*r) then
                regions(1) = regions(1) + 1
            else
                regions(2) = regions(2) + 1
            end if
        end do
        call check(t, bad == 0 .and. n > 500, "friction: psi_stick and psi_limit_derivative "// &
                   "are the derivatives of Psi")
        call check(t, all(regions > 50), "friction: the three regions were all sampled")
    end subroutine test_derivatives

    !> Psi(c r, d v; c g, rho d / c) = d Psi(r, v; g, rho): a change of force unit c and
    !> velocity unit d rescales Psi and keeps the region (exactly, with powers of 2).
    subroutine test_scaling(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: c = 2.0_dp**20, d = 2.0_dp**(-12), g = 0.45_dp, rho = 0.2_dp
        real(dp) :: u(2), r, v
        integer :: i, bad
        bad = 0
        do i = 1, 200
            call random_number(u)
            r = 2.0_dp*g*(2.0_dp*u(1) - 1.0_dp)
            v = 0.3_dp*(2.0_dp*u(2) - 1.0_dp)
            if (psi(c*r, d*v, c*g, rho*d/c) /= d*psi(r, v, g, rho)) bad = bad + 1
            if (psi_stick(c*r, d*v, c*g, rho*d/c) /= psi_stick(r, v, g, rho)) bad = bad + 1
        end do
        call check(t, bad == 0, "friction: Psi scales with the units, regions unchanged")
    end subroutine test_scaling
end module test_friction
