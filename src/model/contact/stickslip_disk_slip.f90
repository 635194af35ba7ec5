!> A slip in the plane against a disk of friction (2D Coulomb friction) in the exact flow,
!> shared by the elements that have one (the planar element: a constant limit mu N; the
!> unilateral element with 2D friction on an elastic normal: the varying limit mu lambda(y)).
!>
!> Slipping, the friction force r = -g u/|u| (u = (w^T v, t2^T v) the slip velocity, g the
!> limit, an affine function of the state) is a nonlinear input of the flow
!> (stickslip_flow_nonlinear). A slip that starts from rest (the memory's regime 1: its speed
!> below 1.5 rest_speed of its scale) takes the direction the dynamics give it (u' = a - g W d
!> along d); once faster it follows its velocity (regime 0). The memory (dir: a direction
!> and a regime) changes between steps only, so that the input is smooth over a step.
module stickslip_disk_slip
    use stickslip_kinds, only: dp
    use stickslip_contact_modes, only: element_geometry_t, event_list_t, action_decide, &
        action_memory
    implicit none
    private
    public :: rest_speed, slip_speed, disk_step_rows, disk_inputs, disk_slip_direction

    !> Slip speed below which a contact counts as at rest (relative to the velocity scale):
    !> a slip stops there (the flow's threshold, 1e-9 of the stop row's scale rest_speed /
    !> 1e-9 vref), and a start that slow is decided at acceleration level or from its forces.
    real(dp), parameter :: rest_speed = 1.0e-6_dp

contains

    !> The slip speed |(w^T v, t2^T v)| at y (balanced) [m/s].
    pure real(dp) function slip_speed(geom, y)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> State (balanced).
        real(dp), intent(in) :: y(:)
        slip_speed = hypot(dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n)), &
                           dot_product(geom%dt(:, 2), y(geom%n + 1:2*geom%n)))
    end function slip_speed

    !> The rows of a slipping step: d . u, d the memory's direction at the start of the step
    !> (at zero the slip stops and the contacts decide; its scale 1e3 vref: the flow takes the
    !> slip to stop at 1e-9 of it, 1e-6 vref, where what is left of the slip carries the
    !> contact a roundoff-sized distance); in the regime 1 also 3e-6 vref - d . u (the same
    !> scale), at whose zero (2e-6 vref) the memory follows the slip velocity.
    subroutine disk_step_rows(geom, dir, events)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The memory: direction (1:2), regime (3).
        real(dp), intent(in) :: dir(:)
        !> The list the rows go to (slot 1).
        type(event_list_t), intent(inout) :: events
        real(dp) :: row(geom%na)
        row = dir(1)*geom%vel_row(1) + dir(2)*geom%vel_row(2)
        call events%add(row, rest_speed/1.0e-9_dp*geom%vref, 1, action_decide)
        if (dir(3) >= 0.5_dp) call events%add(geom%const_row(3.0_dp*rest_speed*geom%vref) - &
                                              row, rest_speed/1.0e-9_dp*geom%vref, 1, &
                                              action_memory)
    end subroutine disk_step_rows

    !> The friction force q = -g d [N] of a slip and its Jacobian dq (2 x na) for the limit g
    !> = glim . y + kappa . q (glim an affine row of y, > 0; kappa the limit's response to
    !> the force itself, a rigid normal's constraint force: then g = glim . y / (1 + kappa .
    !> d); default 0). Regime 0: d = u/|u|, dd = (I - d d^T)/|u| du. Regime 1 (with the
    !> mode's dynamics yd0, dyd0 without this input and its columns gj): the direction d the
    !> slip takes, (lambda I + g W) d = a, |d| = 1, lambda >= 0 (a the slip acceleration
    !> without the force, W = its compliance); without them, the memory's direction.
    subroutine disk_inputs(geom, glim, y, dir, q, dq, yd0, dyd0, gj, kappa)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The limit as a row of y [N].
        real(dp), intent(in) :: glim(:)
        !> State (balanced), the memory.
        real(dp), intent(in) :: y(:), dir(:)
        !> The force and its Jacobian.
        real(dp), intent(out) :: q(:), dq(:, :)
        !> The mode's rate without this input, its Jacobian, this input's columns.
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        !> The limit per unit of the force (2).
        real(dp), intent(in), optional :: kappa(:)
        real(dp) :: u(2), un, d(2), g, g0, gnew, kap(2), den, vr(2, geom%na), dd(2, geom%na), &
                    dg(geom%na), ddg(2), m(2, 2), rhs(2, geom%na), det, acc(2), &
                    dacc(2, geom%na), wmat(2, 2)
        integer :: a, b, it
        kap = 0.0_dp
        if (present(kappa)) kap = kappa
        g0 = dot_product(glim, y)
        vr(1, :) = geom%vel_row(1)
        vr(2, :) = geom%vel_row(2)
        u = matmul(vr, y)
        un = norm2(u)
        dd = 0.0_dp
        ddg = 0.0_dp
        if (dir(3) < 0.5_dp .and. un > 0.0_dp) then
            d = u/un
            do a = 1, 2
                do b = 1, 2
                    dd(a, :) = dd(a, :) + (merge(1.0_dp, 0.0_dp, a == b) - d(a)*d(b))/un* &
                               vr(b, :)
                end do
            end do
            g = g0/(1.0_dp + dot_product(kap, d))
        else if (dir(3) >= 0.5_dp .and. present(yd0) .and. present(dyd0) .and. &
                 present(gj)) then
            ! the direction at the limit g(d) = g0 / (1 + kappa . d): a fixed point
            acc = matmul(vr, yd0)
            dacc = matmul(vr, dyd0)
            wmat = matmul(vr, gj)
            g = g0
            do it = 1, 50
                call start_direction(g, acc, dacc, wmat, dir(1:2), d, dd, ddg)
                gnew = g0/(1.0_dp + dot_product(kap, d))
                if (abs(gnew - g) <= 4.0_dp*epsilon(1.0_dp)*abs(g0)) exit
                g = gnew
            end do
            g = g0/(1.0_dp + dot_product(kap, d))
        else
            d = dir(1:2)
            g = g0/(1.0_dp + dot_product(kap, d))
        end if
        den = 1.0_dp + dot_product(kap, d)
        if (any(kap /= 0.0_dp)) then
            ! dd_total = dd + ddg dg, dg = (glim - g kappa^T dd_total) / den
            m = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
            do a = 1, 2
                m(a, :) = m(a, :) + g*ddg(a)*kap/den
            end do
            do a = 1, 2
                rhs(a, :) = dd(a, :) + ddg(a)*glim/den
            end do
            det = m(1, 1)*m(2, 2) - m(1, 2)*m(2, 1)
            dd(1, :) = (m(2, 2)*rhs(1, :) - m(1, 2)*rhs(2, :))/det
            dd(2, :) = (m(1, 1)*rhs(2, :) - m(2, 1)*rhs(1, :))/det
            dg = (glim - g*matmul(kap, dd))/den
        else
            dd = dd + spread(ddg, 2, geom%na)*spread(glim, 1, 2)
            dg = glim
        end if
        q = -g*d
        dq(1, :) = -g*dd(1, :) - d(1)*dg
        dq(2, :) = -g*dd(2, :) - d(2)*dg
    end subroutine disk_inputs

    !> The direction d of a slip starting from rest: (lambda I + g W) d = a, |d| = 1,
    !> lambda >= 0 (lambda = 0 and d = (g W)^-1 a normalized when |(g W)^-1 a| <= 1: the
    !> onset itself), its Jacobian dd = d(d)/dy from da (2 x na) at fixed g and its
    !> derivative ddg = d(d)/dg. d0 the direction memory when a = 0.
    pure subroutine start_direction(g, acc, dacc, w, d0, d, dd, ddg)
        real(dp), intent(in) :: g, acc(2), dacc(:, :), w(2, 2), d0(2)
        real(dp), intent(out) :: d(2), dd(:, :), ddg(2)
        real(dp) :: k(2, 2), ki(2, 2), v(2), lam, phi, dphi, kd(2), det, vn, kwd(2)
        integer :: it, a
        dd = 0.0_dp
        ddg = 0.0_dp
        lam = 0.0_dp
        do it = 1, 60
            k = g*w
            k(1, 1) = k(1, 1) + lam
            k(2, 2) = k(2, 2) + lam
            det = k(1, 1)*k(2, 2) - k(1, 2)*k(2, 1)
            if (.not. (abs(det) > 0.0_dp)) then
                d = d0
                return
            end if
            ki = reshape([k(2, 2), -k(2, 1), -k(1, 2), k(1, 1)], [2, 2])/det
            v = matmul(ki, acc)
            phi = dot_product(v, v) - 1.0_dp
            if (it == 1 .and. phi <= 0.0_dp) exit
            if (abs(phi) <= 4.0_dp*epsilon(1.0_dp)) exit
            dphi = -2.0_dp*dot_product(v, matmul(ki, v))
            if (.not. (dphi < 0.0_dp)) exit
            lam = max(lam - phi/dphi, 0.0_dp)
        end do
        vn = norm2(v)
        if (.not. (vn > 0.0_dp)) then
            d = d0
            return
        end if
        d = v/vn
        if (lam > 0.0_dp) then
            ! dd = K^-1 (da - d dlambda - W d dg), dlambda from d . dd = 0
            kd = matmul(ki, d)
            do a = 1, size(dd, 2)
                v = matmul(ki, dacc(:, a))
                dd(:, a) = v - kd*dot_product(d, v)/dot_product(d, kd)
            end do
            kwd = matmul(ki, matmul(w, d))
            ddg = -kwd + kd*dot_product(d, kwd)/dot_product(d, kd)
        else
            ! d = (g W)^-1 a normalized does not depend on g
            do a = 1, size(dd, 2)
                v = matmul(ki, dacc(:, a))
                dd(:, a) = (v - d*dot_product(d, v))/vn
            end do
        end if
    end subroutine start_direction

    !> The memory of a slip: entering it from stuck (fb the stuck forces' rows, at least 2):
    !> against the stuck force in the regime 1, unless it already moves faster than 1.5
    !> rest_speed (then along its velocity, regime 0; a slip that stopped is at rest_speed).
    !> Otherwise (after a step, at a start or at the memory's event): in the regime 0, or
    !> once faster than 1.5 rest_speed, along the slip velocity in the regime 0; else kept.
    subroutine disk_slip_direction(geom, fb, y, dir)
        !> The element's geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The stuck forces' rows (2 x na) or none.
        real(dp), intent(in) :: fb(:, :)
        !> State (balanced).
        real(dp), intent(in) :: y(:)
        !> The memory.
        real(dp), intent(inout) :: dir(:)
        real(dp) :: r(2), u(2), un
        u = [dot_product(geom%dt(:, 1), y(geom%n + 1:2*geom%n)), &
             dot_product(geom%dt(:, 2), y(geom%n + 1:2*geom%n))]
        un = norm2(u)
        if (size(fb, 1) >= 2) then
            if (un > 1.5_dp*rest_speed*geom%vref) then
                dir(1:2) = u/un
                dir(3) = 0.0_dp
            else
                r = matmul(fb(1:2, :), y)
                if (norm2(r) > 0.0_dp) dir(1:2) = -r/norm2(r)
                dir(3) = 1.0_dp
            end if
        else if ((dir(3) < 0.5_dp .or. un >= 1.5_dp*rest_speed*geom%vref) .and. &
                 un > 0.0_dp) then
            dir(1:2) = u/un
            dir(3) = 0.0_dp
        end if
    end subroutine disk_slip_direction
end module stickslip_disk_slip
