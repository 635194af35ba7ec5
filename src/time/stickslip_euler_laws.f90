!> The steps of implicit Euler (stickslip_euler) for a model with contact laws
!> (doc/contacts.md, section 4): the contact forces of every force channel at the end of the
!> step, with the laws at the end of the step,
!>     tangential: slider velocity  d^T v_{n+1} + (r_{n+1} - r_n) / (h k_t),
!>     normal:     (g_{n+1} + lambda / k_n) / h >= 0 _|_ lambda >= 0,
!>                 g_{n+1} = gap + d^T (x_n + h v_{n+1})   (position level: impacts of a rigid
!>                 contact are plastic as h -> 0),
!> friction limit mu lambda_{n+1} (implicit) or mu N; with v_{n+1} = v_free + h S^-1 D r, all
!> kinematic quantities are u = q + A r (A the Delassus matrix h D^T S^-1 D plus the
!> compliances / h), solved per step by stickslip_contact_step.
module stickslip_euler_laws
    use stickslip_kinds, only: dp
    use stickslip_contact_set, only: contact_set_t, channel_normal
    use stickslip_contact_law, only: contact_law_t, contact_state
    use stickslip_contact_step, only: contact_step_forces
    use stickslip_lapack, only: dgetrs
    implicit none
    private
    public :: euler_laws_t, new_euler_laws, step_block_laws, free_velocity

    !> The contact laws of an implicit Euler run and the state they carry between steps.
    type :: euler_laws_t
        !> The contacts and their channels.
        type(contact_set_t) :: cs
        !> The law of each contact.
        type(contact_law_t), allocatable :: law(:)
        !> A = h D^T S^-1 D + diag(compliance / h), n_ch x n_ch [m/(N s)].
        real(dp), allocatable :: a(:, :)
        !> Per channel: a normal channel; its gap [m]; the tangential compliance / h
        !> [m/(N s)] (0: rigid or not tangential).
        logical, allocatable :: normal(:)
        real(dp), allocatable :: gap(:), ct_h(:)
        !> Per contact: the weight of its state test (the mean diagonal of its block of A).
        real(dp), allocatable :: rho(:)
        !> Force scale of the step solver's tolerance [N].
        real(dp) :: scale = 1.0_dp
        !> The contacts after the last step: state, normal force [N], gap [m].
        integer, allocatable :: state(:)
        real(dp), allocatable :: normal_force(:), gap_now(:)
        !> Free kinematic quantities and work (n_ch).
        real(dp), allocatable :: q(:), u(:)
        !> The largest relative residual of a step's contact laws (diagnostic).
        real(dp) :: worst_residual = 0.0_dp
    end type euler_laws_t

contains

    !> The laws of `cs` for steps of length h [s]: `d` = h D^T S^-1 D [m/(N s)], the
    !> channel directions' gaps and compliances from `cs`.
    subroutine new_euler_laws(self, cs, d, h)
        !> The laws.
        type(euler_laws_t), intent(out) :: self
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> The Delassus matrix of the step, n_ch x n_ch [m/(N s)].
        real(dp), intent(in) :: d(:, :)
        !> Time step [s].
        real(dp), intent(in) :: h
        integer :: j, c, nch
        self%cs = cs
        nch = cs%nchannel
        self%a = d
        allocate (self%normal(nch), self%gap(nch), self%ct_h(nch), self%rho(cs%ncontact), &
                  self%law(cs%ncontact), self%state(cs%ncontact), &
                  self%normal_force(cs%ncontact), self%gap_now(cs%ncontact), self%q(nch), &
                  self%u(nch))
        self%normal = cs%kind == channel_normal
        self%gap = 0.0_dp
        self%ct_h = 0.0_dp
        self%scale = tiny(1.0_dp)
        do j = 1, cs%ncontact
            self%law(j) = cs%law(j)
            do c = cs%first(j), cs%first(j) + cs%width(j) - 1
                if (self%normal(c)) then
                    self%gap(c) = cs%gap(j)
                    if (cs%kn(j) > 0.0_dp) self%a(c, c) = self%a(c, c) + 1.0_dp/(h*cs%kn(j))
                else if (cs%kt(j) > 0.0_dp) then
                    self%ct_h(c) = 1.0_dp/(h*cs%kt(j))
                    self%a(c, c) = self%a(c, c) + self%ct_h(c)
                end if
            end do
            self%rho(j) = 0.0_dp
            do c = cs%first(j), cs%first(j) + cs%width(j) - 1
                self%rho(j) = self%rho(j) + self%a(c, c)/cs%width(j)
            end do
            self%scale = max(self%scale, cs%mu(j)*cs%normal_load(j), cs%preload(j), &
                             cs%mu(j)*cs%preload(j))
            self%state(j) = 1
            self%normal_force(j) = cs%normal_load(j)
            self%gap_now(j) = 0.0_dp
        end do
    end subroutine new_euler_laws

    !> Steps first..last of a period (the kernel of integrate_euler for contact laws): from
    !> the state y = [v; x; c] and the channel forces r, store each step's starting state in
    !> xs, vs, rs (and the contacts' state, normal force and gap after the step before in
    !> sts, nrm, gps), set the forcing coefficients from fc, form the free velocity A y, the
    !> channel forces, and the new v and x.
    subroutine step_block_laws(self, n, nch, nf, ns, first, last, h, inverse, amat, s, ipiv, &
                               w, sw, tol, max_sweeps, fc, y, vf, r, xs, vs, rs, sts, nrm, &
                               gps, max_sweeps_used)
        !> The laws and their state.
        type(euler_laws_t), intent(inout) :: self
        !> Degrees of freedom, channels, forcing terms (with the preload), steps per period.
        integer, intent(in) :: n, nch, nf, ns
        !> First and last step of the block (1..ns).
        integer, intent(in) :: first, last
        !> Time step [s].
        real(dp), intent(in) :: h
        !> amat holds S^{-1} [M, -h K, F] (else [M, -h K, F] and s the LU factors of S).
        logical, intent(in) :: inverse
        !> The free-velocity matrix, N x (2N + n_f).
        real(dp), intent(in) :: amat(n, 2*n + nf)
        !> LU factors of S and their pivots.
        real(dp), intent(in) :: s(n, n)
        integer, intent(in) :: ipiv(n)
        !> Channel directions D and S^{-1} D, N x n_ch.
        real(dp), intent(in) :: w(n, nch), sw(n, nch)
        !> Relative tolerance and most sweeps of the step solver.
        real(dp), intent(in) :: tol
        integer, intent(in) :: max_sweeps
        !> Forcing coefficients of the block's steps, n_f x (last - first + 1).
        real(dp), intent(in) :: fc(nf, *)
        !> State [v; x; c]: start of the block on entry, end on exit.
        real(dp), intent(inout) :: y(2*n + nf)
        !> Work: the free velocity.
        real(dp), intent(inout) :: vf(n)
        !> Channel forces: of the last step on entry, updated [N].
        real(dp), intent(inout) :: r(nch)
        !> The samples of the period: displacements, velocities (ns x N), channel forces (ns x
        !> n_ch), contact states, normal forces and gaps (ns x n_c).
        real(dp), intent(inout) :: xs(ns, n), vs(ns, n), rs(ns, nch), nrm(ns, *), gps(ns, *)
        integer, intent(inout) :: sts(ns, *)
        !> Most sweeps of a step so far.
        integer, intent(inout) :: max_sweeps_used
        integer :: i, j, k, step, ny, sweeps, info, c0, m
        real(dp) :: acc, resid, scale
        ny = 2*n + nf
        do step = first, last
            do k = 1, n
                vs(step, k) = y(k)
                xs(step, k) = y(n + k)
            end do
            rs(step, :) = r
            do j = 1, self%cs%ncontact
                sts(step, j) = self%state(j)
                nrm(step, j) = self%normal_force(j)
                gps(step, j) = self%gap_now(j)
            end do
            do i = 1, nf
                y(2*n + i) = fc(i, step - first + 1)
            end do
            call free_velocity(n, ny, amat, y, inverse, s, ipiv, vf)
            ! free kinematic quantities: slider velocities (with the slider's last force),
            ! gaps / h at the end of the step
            do j = 1, nch
                acc = 0.0_dp
                do k = 1, n
                    acc = acc + w(k, j)*vf(k)
                end do
                self%q(j) = acc
                if (self%normal(j)) then
                    acc = self%gap(j)
                    do k = 1, n
                        acc = acc + w(k, j)*y(n + k)
                    end do
                    self%q(j) = self%q(j) + acc/h
                else
                    self%q(j) = self%q(j) - self%ct_h(j)*r(j)
                end if
            end do
            scale = max(self%scale, maxval(abs(r)))
            call contact_step_forces(self%cs, self%law, self%a, self%q, r, scale, tol, &
                                     max_sweeps, sweeps, resid)
            max_sweeps_used = max(max_sweeps_used, sweeps)
            self%worst_residual = max(self%worst_residual, resid)
            do k = 1, n
                acc = 0.0_dp
                do j = 1, nch
                    acc = acc + sw(k, j)*r(j)
                end do
                y(k) = vf(k) + h*acc
            end do
            do k = 1, n
                y(n + k) = y(n + k) + h*y(k)
            end do
            ! the contacts after the step: state, normal force, gap
            self%u = self%q + matmul(self%a, r)
            do j = 1, self%cs%ncontact
                c0 = self%cs%first(j)
                m = self%cs%width(j)
                self%state(j) = contact_state(self%law(j), self%rho(j), r(c0:c0 + m - 1), &
                                              self%u(c0:c0 + m - 1))
                if (self%cs%normal(j) > 0) then
                    i = self%cs%normal(j)
                    self%normal_force(j) = r(i)
                    acc = self%gap(i)
                    do k = 1, n
                        acc = acc + w(k, i)*y(n + k)
                    end do
                    self%gap_now(j) = acc
                end if
            end do
        end do
    end subroutine step_block_laws
    !> The free velocity of a step, vf = S^-1 A y: the written-out product A y (no array
    !> temporary), then solved with the LU factors of S unless A already holds S^-1 [M,
    !> -h K, F] (`inverse`). Shared by the plain and the contact-law step kernels.
    subroutine free_velocity(n, ny, a, y, inverse, s, ipiv, vf)
        !> DOFs and the size of y.
        integer, intent(in) :: n, ny
        !> [M, -h K, F] or S^-1 times it, n x ny.
        real(dp), intent(in) :: a(n, ny)
        !> [v; x; forcing terms].
        real(dp), intent(in) :: y(ny)
        !> a holds S^-1 [M, -h K, F].
        logical, intent(in) :: inverse
        !> LU factors of S and their pivots (used when not inverse).
        real(dp), intent(in) :: s(n, n)
        integer, intent(in) :: ipiv(n)
        !> The free velocity [m/s].
        real(dp), intent(out) :: vf(n)
        integer :: j, k, info
        do k = 1, n
            vf(k) = a(k, 1)*y(1)
        end do
        do j = 2, ny
            do k = 1, n
                vf(k) = vf(k) + a(k, j)*y(j)
            end do
        end do
        if (.not. inverse) call dgetrs('N', n, 1, s, n, ipiv, vf, n, info)
    end subroutine free_velocity
end module stickslip_euler_laws
