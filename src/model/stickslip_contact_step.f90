!> The contact forces of one implicit time step with contact laws (doc/contacts.md): the
!> force channels' forces r (contact after contact: [w, (t), (n)]) such that every contact's
!> law holds between its forces and its kinematic quantities, affine in all the forces,
!>     u = q + A r,
!> Psi_j(r_j, u_j) = 0 for every contact j (stickslip_contact_law). A is the Delassus
!> matrix of the step plus the contact compliances (symmetric positive definite for a
!> symmetric structure); q holds the free slider velocities and the gaps of the step.
!> Solved by block Gauss-Seidel over the contacts, each contact's block (1 to 3 unknowns)
!> by a semismooth Newton iteration on its equalities (exact generalized Jacobian, damped by
!> backtracking), with a projection iteration as the fallback. Pure numerics: no model, no
!> files; stickslip_contact_solve keeps the box solver of the plain contacts.
module stickslip_contact_step
    use stickslip_kinds, only: dp
    use stickslip_contact_set, only: contact_set_t
    use stickslip_contact_law, only: contact_law_t, contact_psi, contact_psi_jacobian
    implicit none
    private
    public :: contact_step_forces

    !> Newton iterations per contact block and backtracking halvings per iteration.
    integer, parameter :: max_newton = 30, max_halvings = 30

contains

    !> The channel forces r of one step with u = q + A r and every contact's law. `r` holds
    !> the start (the last step's forces) on entry. Sweeps over the contacts until no force
    !> changes by more than tol times the force scale `scale` [N], at most max_sweeps;
    !> `sweeps` the sweeps made, `residual` the largest |Psi| left relative to the velocity
    !> and force scales (diagnostic; ~1e-15 when solved).
    subroutine contact_step_forces(cs, law, a, q, r, scale, tol, max_sweeps, sweeps, residual)
        !> The contacts and their channels.
        type(contact_set_t), intent(in) :: cs
        !> The law of each contact.
        type(contact_law_t), intent(in) :: law(:)
        !> Delassus matrix with the compliances, n_ch x n_ch [m/(N s)].
        real(dp), intent(in) :: a(:, :)
        !> Free kinematic quantities, n_ch [m/s].
        real(dp), intent(in) :: q(:)
        !> Channel forces: start on entry, solution on exit [N].
        real(dp), intent(inout) :: r(:)
        !> Force scale [N] (> 0) and relative tolerance of the sweeps.
        real(dp), intent(in) :: scale, tol
        !> Sweeps at most.
        integer, intent(in) :: max_sweeps
        !> Sweeps made.
        integer, intent(out) :: sweeps
        !> Largest relative |Psi| left.
        real(dp), intent(out) :: residual
        integer :: j, c0, m
        real(dp) :: change, old(3)
        sweeps = 0
        do sweeps = 1, max_sweeps
            change = 0.0_dp
            do j = 1, cs%ncontact
                c0 = cs%first(j)
                m = cs%width(j)
                old(1:m) = r(c0:c0 + m - 1)
                call solve_block(j, c0, m)
                change = max(change, maxval(abs(r(c0:c0 + m - 1) - old(1:m))))
            end do
            if (change <= tol*scale .or. cs%ncontact == 1) exit
        end do
        sweeps = min(sweeps, max_sweeps)
        residual = 0.0_dp
        do j = 1, cs%ncontact
            residual = max(residual, block_residual(cs%first(j), cs%width(j), j))
        end do

    contains

        !> Contact j's forces, the others fixed: semismooth Newton on Psi_j(z, qj + Ajj z),
        !> qj = q_j + sum_{l /= j} A_jl r_l; the projection iteration when Newton fails.
        subroutine solve_block(j, c0, m)
            integer, intent(in) :: j, c0, m
            real(dp) :: qj(m), ajj(m, m), z(m), p(m), jr(m, m), ju(m, m), jac(m, m), dz(m), &
                        zt(m), pt(m), rho, f0, ft, step, vscale
            integer :: it, k, info
            logical :: done
            ajj = a(c0:c0 + m - 1, c0:c0 + m - 1)
            qj = q(c0:c0 + m - 1) + matmul(a(c0:c0 + m - 1, :), r) - matmul(ajj, r(c0:c0 + m - 1))
            rho = 0.0_dp
            do k = 1, m
                rho = rho + ajj(k, k)
            end do
            rho = max(rho/m, tiny(1.0_dp))
            vscale = max(maxval(abs(qj)), rho*scale, tiny(1.0_dp))
            z = r(c0:c0 + m - 1)
            call contact_psi(law(j), rho, z, qj + matmul(ajj, z), p)
            f0 = norm2(p)
            done = f0 <= 1.0e-15_dp*vscale
            do it = 1, max_newton
                if (done) exit
                call contact_psi_jacobian(law(j), rho, z, qj + matmul(ajj, z), p, jr, ju)
                jac = jr + matmul(ju, ajj)
                dz = -p
                call small_solve(m, jac, dz, info)
                if (info /= 0) exit
                step = 1.0_dp
                do k = 1, max_halvings
                    zt = z + step*dz
                    call contact_psi(law(j), rho, zt, qj + matmul(ajj, zt), pt)
                    ft = norm2(pt)
                    if (ft <= (1.0_dp - 1.0e-4_dp*step)*f0) exit
                    step = 0.5_dp*step
                end do
                if (.not. (ft < f0)) exit
                z = zt
                f0 = ft
                done = f0 <= 1.0e-15_dp*vscale
            end do
            if (.not. done) call project(m, j, qj, ajj, z)
            r(c0:c0 + m - 1) = z
        end subroutine solve_block

        !> The projection iteration (the fallback of the Newton iteration): the normal force
        !> max(0, lambda - u_n / A_nn), then the friction force z_t - u_t / A_tt projected on
        !> the limit's interval or disk, until the forces settle.
        subroutine project(m, j, qj, ajj, z)
            integer, intent(in) :: m, j
            real(dp), intent(in) :: qj(m), ajj(m, m)
            real(dp), intent(inout) :: z(m)
            real(dp) :: u(m), g, zt(2), zn, old(m)
            integer :: it, nt, k
            nt = law(j)%ntangent
            do it = 1, 2000
                old = z
                if (law(j)%unilateral) then
                    u = qj + matmul(ajj, z)
                    z(m) = max(0.0_dp, z(m) - u(m)/ajj(m, m))
                    g = law(j)%mu*z(m)
                else
                    g = law(j)%mu*law(j)%normal_load
                end if
                u = qj + matmul(ajj, z)
                do k = 1, nt
                    zt(k) = z(k) - u(k)/ajj(k, k)
                end do
                if (nt == 1) then
                    z(1) = max(-g, min(g, zt(1)))
                else
                    zn = norm2(zt)
                    if (zn > g) then
                        z(1:2) = g*zt/zn
                    else
                        z(1:2) = zt
                    end if
                end if
                if (maxval(abs(z - old)) <= 1.0e-15_dp*max(scale, maxval(abs(z)))) exit
            end do
        end subroutine project

        !> |Psi| of contact j at the current forces, relative to its velocity and force
        !> scales.
        real(dp) function block_residual(c0, m, j) result(res)
            integer, intent(in) :: c0, m, j
            real(dp) :: u(m), p(m), rho
            integer :: k
            rho = 0.0_dp
            do k = 0, m - 1
                rho = rho + a(c0 + k, c0 + k)
            end do
            rho = max(rho/m, tiny(1.0_dp))
            u = q(c0:c0 + m - 1) + matmul(a(c0:c0 + m - 1, :), r)
            call contact_psi(law(j), rho, r(c0:c0 + m - 1), u, p)
            res = maxval(abs(p))/max(maxval(abs(q(c0:c0 + m - 1))), rho*scale, tiny(1.0_dp))
        end function block_residual
    end subroutine contact_step_forces

    !> Solve the small system a x = b (m <= 3) by Gaussian elimination with partial pivoting;
    !> info = 1 when a pivot vanishes.
    pure subroutine small_solve(m, a, b, info)
        integer, intent(in) :: m
        real(dp), intent(in) :: a(m, m)
        real(dp), intent(inout) :: b(m)
        integer, intent(out) :: info
        real(dp) :: w(m, m), f, t
        integer :: i, k, p
        w = a
        info = 0
        do k = 1, m
            p = k - 1 + maxloc(abs(w(k:m, k)), 1)
            if (.not. (abs(w(p, k)) > 1.0e-300_dp)) then
                info = 1
                return
            end if
            if (p /= k) then
                do i = 1, m
                    t = w(k, i)
                    w(k, i) = w(p, i)
                    w(p, i) = t
                end do
                t = b(k)
                b(k) = b(p)
                b(p) = t
            end if
            do i = k + 1, m
                f = w(i, k)/w(k, k)
                w(i, k:m) = w(i, k:m) - f*w(k, k:m)
                b(i) = b(i) - f*b(k)
            end do
        end do
        do i = m, 1, -1
            b(i) = (b(i) - dot_product(w(i, i + 1:m), b(i + 1:m)))/w(i, i)
        end do
    end subroutine small_solve
end module stickslip_contact_step
