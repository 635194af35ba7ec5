!> The period map of the exact flow with contact laws (doc/contacts.md, section 5): the
!> state stepped from event to event through the modes of stickslip_flow_laws, with the
!> events of the normal law beside the friction events: a closed contact opens when its
!> normal force (rigid) or its compression (elastic) reaches zero; an open one closes when
!> its gap reaches zero, smoothly for an elastic normal, with a plastic impact for a rigid
!> one (stickslip_flow_laws, impact_jump). The monodromy is the product of the phase flows
!> and of the saltation matrices I + (f+ - f-) c^T / (c . f-), with the Jacobian J of the
!> jump at an impact: J + (f+ - J f-) c^T / (c . f-). The energies are integrated by
!> Gauss-Legendre quadrature of the exact solution (the friction power of every force
!> channel), the impact losses added up.
module stickslip_flow_law_map
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_expm, only: expm
    use stickslip_lapack, only: dgesv
    use stickslip_flow_modes, only: ngauss, mode_t, flow_modes_t, propagate, &
        gauss_exponentials, identity_matrix
    use stickslip_flow_events, only: event_kind, event_name, row_crossing, grid_step, &
        event_guard, add_saltation, end_monodromy
    use stickslip_flow_laws, only: law_mode_index, law_modes_at, impact_jump, law_start_codes, &
        event_open, event_close
    use stickslip_flow_orbit, only: orbit_t
    implicit none
    private
    public :: law_period_map, law_event_name, event_impact

    !> Event kind of a rigid contact that closes with a normal velocity.
    integer, parameter :: event_impact = 12

contains

    !> Name of an event kind (those of stickslip_flow_events and open, close, impact), as
    !> written to events.csv.
    pure function law_event_name(kind) result(name)
        !> The kind.
        integer, intent(in) :: kind
        character(len=:), allocatable :: name
        select case (kind)
        case (event_open)
            name = "open"
        case (event_close)
            name = "close"
        case (event_impact)
            name = "impact"
        case default
            name = event_name(kind)
        end select
    end function law_event_name

    !> The period map from state z0 = [x; v] at t0 [s] to z1 at t0 + T, with its monodromy
    !> and the recorded orbit on request (as stickslip_flow's period_map). Errors (stat
    !> numerical): a non-finite state, no consistent mode, dependent constraints, too many
    !> events.
    subroutine law_period_map(self, t0, z0, z1, error, mono, orbit, energies)
        !> The dynamics (their mode cache grows).
        class(flow_modes_t), intent(inout) :: self
        !> Start time [s].
        real(dp), intent(in) :: t0
        !> Start state [x; v] [m, m/s].
        real(dp), intent(in) :: z0(:)
        !> State one period later.
        real(dp), intent(out) :: z1(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Monodromy matrix dz1/dz0.
        real(dp), intent(out), optional :: mono(:, :)
        !> The recorded period.
        type(orbit_t), intent(out), optional :: orbit
        !> With orbit: integrate the energies (default .true.).
        logical, intent(in), optional :: energies
        integer, parameter :: max_zero_length = 8
        integer :: n, nz, na, im, imnew, j, k, nevents, zero_length, stat, jev, kev, max_events
        integer, allocatable :: code(:), oldcode(:), zset(:)
        real(dp), allocatable :: y(:), yb(:), ybb(:), yeb(:), ye(:), yp(:), phi(:, :), &
                                 jac(:, :), sal(:, :), c(:), fm(:), fp(:), jump(:, :), &
                                 pj(:, :)
        real(dp) :: t, tb, te, tp, tend, h, loss, vn
        logical :: found, want_mono, want_orbit, full_step, want_energy, impact
        character(len=:), allocatable :: why

        n = self%n
        nz = 2*n
        na = self%na
        want_mono = present(mono)
        want_orbit = present(orbit)
        want_energy = want_orbit
        if (want_orbit .and. present(energies)) want_energy = energies
        max_events = 1000*(self%nc + 1)
        tend = t0 + self%period
        allocate (y(na), yb(na), ybb(na), yeb(na), ye(na), c(na), fm(na), fp(na), &
                  code(self%nc), oldcode(self%nc), jump(nz, nz))
        y(1:nz) = z0
        y(nz + 1:) = self%exo(t0)
        if (want_mono) allocate (phi(nz, nz), sal(nz, nz))
        yb = matmul(self%tb, y)
        ! the constraints of the start mode hold in the start state: a rigid contact at a
        ! zero or negative gap is put at zero gap, then the velocities along the stuck and
        ! closed rigid directions are removed (projections; the monodromy includes their
        ! Jacobian, as the reference's does for the stuck contacts of a plain model)
        allocate (pj(nz, nz))
        call close_rigid_gaps(self, yb, pj)
        call law_start_codes(self, yb, code, error)
        if (allocated(error)) return
        im = law_mode_index(self, code, error)
        if (allocated(error)) return
        call project_velocities(self, code, yb, pj)
        if (want_mono) jac = pj
        y = matmul(self%tbi, yb)
        y(nz + 1:) = self%exo(t0)
        if (want_orbit) then
            call orbit%start(t0, na, self%nc)
            call orbit%add_phase(t0, y, im)
        end if

        t = t0
        tp = t0
        yp = y
        nevents = 0
        zero_length = 0
        do
            if (t >= tend) exit
            call grid_step(self, self%modes(im), t, tend, yb, tb, ybb, full_step)
            if (.not. all(ieee_is_finite(ybb))) then
                call fail("the state is not finite (unbounded response)")
                return
            end if
            call find_law_event(self, self%modes(im), t, yb, tb, ybb, found, te, yeb, jev, kev, c)
            if (.not. found) then
                if (want_energy) then
                    if (full_step) call gauss_exponentials(self, self%modes(im))
                    call energy(self%modes(im), t, yb, tb, full_step)
                end if
                t = tb
                yb = ybb
                cycle
            end if

            ye = matmul(self%tbi, yeb)
            ye(nz + 1:) = self%exo(te)
            if (want_energy) call energy(self%modes(im), t, yb, te, .false.)
            if (want_orbit) call close_phase(self%modes(im), te - tp)
            if (want_mono) then
                call expm(self%modes(im)%b(1:nz, 1:nz)*(te - tp), phi, stat)
                jac = matmul(phi, jac)
                fm = matmul(self%modes(im)%b, yeb)
            end if
            oldcode = code
            impact = .false.
            jump = identity_matrix(nz)
            if (kev == 0) then
                ! a slip velocity reaches zero: the modes of the contacts at zero velocity
                zset = [integer ::]
                do j = 1, self%nc
                    if (j == jev) cycle
                    if (code(j) == 0 .and. (self%limit(j) > 0.0_dp .or. &
                                            self%cs%normal(j) > 0)) zset = [zset, j]
                end do
                zset = [zset, jev]
                call law_modes_at(self, yeb, zset, code, error)
                if (allocated(error)) return
            else if (kev == event_open) then
                code(jev) = 2
            else if (kev == event_close) then
                vn = dot_product(self%nt(:, jev), yeb(n + 1:nz))
                if (self%ckn(jev) == 0.0_dp .and. vn < 0.0_dp) then
                    ! a rigid contact closing with a normal velocity: a plastic impact
                    call impact_jump(self, yeb, jev, code, jump, loss)
                    impact = .true.
                    if (want_orbit) orbit%impact_loss = orbit%impact_loss + loss
                end if
                ! the closed contact's mode (and after a jump the other rigid closed ones')
                zset = [jev]
                if (impact) then
                    do j = 1, self%nc
                        if (j /= jev .and. code(j) /= 2 .and. self%cs%normal(j) > 0 .and. &
                            self%ckn(j) == 0.0_dp) zset = [zset, j]
                    end do
                end if
                call law_modes_at(self, yeb, zset, code, error)
                if (allocated(error)) return
            else
                code(jev) = kev
            end if
            imnew = law_mode_index(self, code, error)
            if (allocated(error)) return
            call project_velocities(self, code, yeb)
            yeb(nz + 1:) = self%se*self%exo(te)
            ye = matmul(self%tbi, yeb)
            ye(nz + 1:) = self%exo(te)
            if (want_mono) then
                fp = matmul(self%modes(imnew)%b, yeb)
                h = dot_product(c, fm)
                sal = jump
                if (abs(h) > 1.0e-300_dp) then
                    fm(1:nz) = matmul(jump, fm(1:nz))
                    call add_saltation(sal, fp, fm, c, h)
                end if
                jac = matmul(sal, jac)
            end if
            if (want_orbit) then
                do j = 1, self%nc
                    if (code(j) == oldcode(j) .and. j /= jev) cycle
                    call orbit%add_event(te, j, law_kind(oldcode(j), code(j), j == jev .and. impact), &
                                   merge(0, code(j), code(j) == 2), &
                                   dot_product(self%modes(imnew)%force(self%cs%first(j), :), ye), &
                                   dot_product(self%w(:, j), ye(n + 1:nz)))
                end do
                call orbit%add_phase(te, ye, imnew)
            end if
            why = event_guard(te, tp, self%period, max_zero_length + 3*self%nc, max_events, &
                              "chattering", zero_length, nevents)
            if (len(why) > 0) then
                call fail(why)
                return
            end if
            im = imnew
            t = te
            yb = yeb
            tp = te
            yp = ye
        end do
        y = matmul(self%tbi, yb)
        y(nz + 1:) = self%exo(tend)
        if (want_mono) call end_monodromy(self, self%modes(im), tend - tp, jac, mono)
        if (want_orbit) call close_phase(self%modes(im), tend - tp)
        z1 = y(1:nz)

    contains

        subroutine fail(message)
            character(len=*), intent(in) :: message
            call fatal_error(error, "reference: "//message, stickslip_stat%numerical)
        end subroutine fail

        !> The event kind of a contact's change: the normal law's (open, close, impact) or
        !> the friction's (stickslip_flow_events' event_kind).
        integer function law_kind(old, new, impacted)
            integer, intent(in) :: old, new
            logical, intent(in) :: impacted
            if (new == 2) then
                law_kind = event_open
            else if (old == 2) then
                law_kind = merge(event_impact, event_close, impacted)
            else
                law_kind = event_kind(old, new)
            end if
        end function law_kind

        !> Time stuck and open over the phase just ended.
        subroutine close_phase(md, duration)
            type(mode_t), intent(in) :: md
            real(dp), intent(in) :: duration
            integer :: jj
            do jj = 1, self%nc
                if (md%code(jj) == 0) orbit%stick_time(jj) = orbit%stick_time(jj) + duration
                if (md%code(jj) == 2) orbit%open_time(jj) = orbit%open_time(jj) + duration
            end do
        end subroutine close_phase

        !> Work of the forcing, viscous dissipation and the friction dissipation of every
        !> force channel over [ta, tz] in mode md (Gauss-Legendre on the exact solution).
        subroutine energy(md, ta, ya, tz, full)
            type(mode_t), intent(in) :: md
            real(dp), intent(in) :: ta, ya(:), tz
            logical, intent(in) :: full
            real(dp) :: yg(na), ygb(na), half, power, rch(size(md%force, 1)), fric
            integer :: ig, jj
            half = 0.5_dp*(tz - ta)
            if (half <= 0.0_dp) return
            do ig = 1, ngauss
                if (full) then
                    ygb = matmul(md%gauss(:, :, ig), ya)
                else
                    call propagate(md, self%delta, half*(1.0_dp + self%gx(ig)), ya, ygb)
                end if
                yg = matmul(self%tbi, ygb)
                yg(nz + 1:) = self%exo(ta + half*(1.0_dp + self%gx(ig)))
                power = dot_product(matmul(self%hf(:, nz + 1:), yg(nz + 1:)), yg(n + 1:nz))
                orbit%work_forcing = orbit%work_forcing + half*self%gw(ig)*power
                orbit%work_gross = orbit%work_gross + half*self%gw(ig)*abs(power)
                orbit%diss_damping = orbit%diss_damping + half*self%gw(ig)* &
                    dot_product(yg(n + 1:nz), matmul(self%damping, yg(n + 1:nz)))
                rch = matmul(md%force, yg)
                fric = 0.0_dp
                do jj = 1, self%nc
                    fric = fric + rch(self%cs%first(jj))*dot_product(self%w(:, jj), yg(n + 1:nz))
                    if (self%cs%normal(jj) > 0) fric = fric + rch(self%cs%normal(jj))* &
                        dot_product(self%dn(:, jj), yg(n + 1:nz))
                end do
                orbit%diss_friction = orbit%diss_friction - half*self%gw(ig)*fric
            end do
        end subroutine energy

    end subroutine law_period_map

    !> The earliest event in (ta, tb] of mode md: its time te, state ye, contact jev and
    !> kind kev (0: a slip velocity reaches zero; +1 / -1: a stuck force reaches -/+
    !> the limit, the slip direction that follows; event_open, event_close), the row c
    !> of its event function (balanced coordinates).
    subroutine find_law_event(self, md, ta, ya, tb, yb2, found, te, ye, jev, kev, c)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        real(dp), intent(in) :: ta, ya(:), tb, yb2(:)
        logical, intent(out) :: found
        real(dp), intent(out) :: te, ye(:)
        integer, intent(out) :: jev, kev
        real(dp), intent(out) :: c(:)
        real(dp) :: tau, best, gscale
        integer :: jj, side
        found = .false.
        best = huge(1.0_dp)
        jev = 0
        kev = 0
        do jj = 1, self%nc
            if (self%cs%normal(jj) == 0) then
                if (self%limit(jj) <= 0.0_dp) cycle
                if (md%code(jj) /= 0) then
                    gscale = self%vref(jj)
                    call test(3*jj - 2, 0)
                else
                    gscale = self%limit(jj)
                    do side = 1, 2
                        call test(3*jj - 3 + side, 2*side - 3)
                    end do
                end if
                cycle
            end if
            select case (md%code(jj))
            case (2)
                gscale = self%gref(jj)*self%omega
                call test(3*jj, event_close)
            case (0)
                gscale = self%fref(jj)*max(self%cmu(jj), 1.0e-3_dp)
                do side = 1, 2
                    call test(3*jj - 3 + side, 2*side - 3)
                end do
                gscale = self%fref(jj)
                call test(3*jj, event_open)
            case default
                gscale = self%vref(jj)
                call test(3*jj - 2, 0)
                gscale = self%fref(jj)
                call test(3*jj, event_open)
            end select
        end do
        if (found) then
            te = ta + best
            call propagate(md, self%delta, best, ya, ye)
            ye(2*self%n + 1:) = self%se*self%exo(te)
        end if

    contains

        subroutine test(col, kind)
            integer, intent(in) :: col, kind
            tau = row_crossing(self, md, col, gscale, ta, ya, tb, yb2)
            if (tau < best) then
                best = tau
                found = .true.
                jev = jj
                kev = kind
                c = md%rows(:, col)
            end if
        end subroutine test
    end subroutine find_law_event

    !> Put every rigid unilateral contact whose gap is zero or negative (below 1e-9 of its
    !> scale) at zero gap: the M-orthogonal projection of the displacement, in balanced
    !> coordinates p = S q (x = Phi q): q <- q - Nt G^-1 (Nt^T q + gap), G = Nt^T Nt.
    !> pj (2N x 2N) is set to the Jacobian of the map of [p; u].
    subroutine close_rigid_gaps(self, yb, pj)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> Balanced state, corrected in place.
        real(dp), intent(inout) :: yb(:)
        !> The Jacobian of the correction.
        real(dp), intent(out) :: pj(:, :)
        real(dp), allocatable :: nt(:, :), rhs(:, :), q(:), x(:, :)
        integer :: j, n, m, k
        logical :: ok
        n = self%n
        pj = identity_matrix(2*n)
        allocate (nt(n, 0))
        rhs = reshape([real(dp) ::], [0, 1])
        q = yb(1:n)/self%s
        do j = 1, self%nc
            if (self%cs%normal(j) == 0 .or. self%ckn(j) > 0.0_dp) cycle
            if (dot_product(self%nt(:, j), q) + self%cgap(j) > 1.0e-9_dp*self%gref(j)) cycle
            nt = reshape([nt, self%nt(:, j)], [n, size(nt, 2) + 1])
            rhs = reshape([rhs(:, 1), dot_product(self%nt(:, j), q) + self%cgap(j)], &
                          [size(nt, 2), 1])
        end do
        m = size(nt, 2)
        if (m == 0) return
        ! X = G^-1 [Nt^T q + gap, Nt^T]
        call gram_solve(nt, reshape([rhs(:, 1), transpose(nt)], [m, n + 1]), x, ok)
        if (.not. ok) return
        q = q - matmul(nt, x(:, 1))
        yb(1:n) = q*self%s
        ! d p_new / d p = S (I - Nt G^-1 Nt^T) S^-1
        do k = 1, n
            pj(1:n, k) = pj(1:n, k) - self%s*matmul(nt, x(:, k + 1))/self%s(k)
        end do
    end subroutine close_rigid_gaps

    !> Remove from the balanced state the velocity along the constraint directions of the
    !> mode `code` (stuck contacts, closed rigid normals): u <- u - Ct (Ct^T Ct)^-1 Ct^T u
    !> (a roundoff-sized correction after an event; at the start, the projection of a
    !> perturbation off the constraints). With pj: pj <- P pj, P the Jacobian on [p; u].
    subroutine project_velocities(self, code, yb, pj)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> Codes of the contacts.
        integer, intent(in) :: code(:)
        !> Balanced state, corrected in place.
        real(dp), intent(inout) :: yb(:)
        !> Jacobian of the start corrections, composed with this one's.
        real(dp), intent(inout), optional :: pj(:, :)
        real(dp), allocatable :: ctm(:, :), x(:, :)
        integer :: jj, m, n
        logical :: ok
        n = self%n
        allocate (ctm(n, 0))
        do jj = 1, self%nc
            if (code(jj) == 0 .and. (self%limit(jj) > 0.0_dp .or. self%cs%normal(jj) > 0)) &
                ctm = reshape([ctm, self%wt(:, jj)], [n, size(ctm, 2) + 1])
            if (self%cs%normal(jj) > 0) then
                if (code(jj) /= 2 .and. self%ckn(jj) == 0.0_dp) &
                    ctm = reshape([ctm, self%nt(:, jj)], [n, size(ctm, 2) + 1])
            end if
        end do
        m = size(ctm, 2)
        if (m == 0) return
        ! X = G^-1 [Ct^T u, Ct^T]
        call gram_solve(ctm, reshape([matmul(yb(n + 1:2*n), ctm), transpose(ctm)], &
                                     [m, n + 1]), x, ok)
        if (.not. ok) return
        yb(n + 1:2*n) = yb(n + 1:2*n) - matmul(ctm, x(:, 1))
        ! P = I - Ct G^-1 Ct^T on the velocities
        if (present(pj)) pj(n + 1:2*n, :) = matmul(identity_matrix(n) - &
                                                   matmul(ctm, x(:, 2:)), pj(n + 1:2*n, :))
    end subroutine project_velocities

    !> x = (C^T C)^-1 b for the m columns of c (n x m) and b (m x k) (LAPACK dgesv); ok =
    !> .false. when C^T C is singular (dependent constraint directions).
    subroutine gram_solve(c, b, x, ok)
        !> The directions, n x m.
        real(dp), intent(in) :: c(:, :)
        !> Right-hand sides, m x k.
        real(dp), intent(in) :: b(:, :)
        !> The solutions, m x k.
        real(dp), allocatable, intent(out) :: x(:, :)
        !> The system was solved.
        logical, intent(out) :: ok
        real(dp) :: g(size(c, 2), size(c, 2))
        integer :: ipiv(size(c, 2)), info, m
        m = size(c, 2)
        g = matmul(transpose(c), c)
        x = b
        call dgesv(m, size(b, 2), g, m, ipiv, x, m, info)
        ok = info == 0 .and. all(ieee_is_finite(x))
    end subroutine gram_solve
end module stickslip_flow_law_map
