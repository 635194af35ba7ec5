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
    use stickslip_flow_modes, only: ngauss, mode_t, flow_modes_t, propagate, &
        gauss_exponentials, identity_matrix
    use stickslip_flow_events, only: event_kind, event_name, first_crossing, value_at
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
        character(len=200) :: buf

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
            orbit%t0 = t0
            allocate (orbit%phase_t(16), orbit%phase_y(na, 16), orbit%phase_mode(16))
            allocate (orbit%event_t(16), orbit%event_force(16), orbit%event_velocity(16), &
                      orbit%event_contact(16), orbit%event_kind(16), orbit%event_direction(16))
            allocate (orbit%stick_time(self%nc), orbit%open_time(self%nc))
            orbit%stick_time = 0.0_dp
            orbit%open_time = 0.0_dp
            orbit%impact_loss = 0.0_dp
            call add_phase(t0, y, im)
        end if

        t = t0
        tp = t0
        yp = y
        nevents = 0
        zero_length = 0
        do
            if (t >= tend) exit
            if (tend - t <= self%delta*(1.0_dp + 1.0e-9_dp)) then
                tb = tend
                full_step = .false.
                call propagate(self%modes(im), self%delta, tb - t, yb, ybb)
            else
                tb = t + self%delta
                full_step = .true.
                ybb = matmul(self%modes(im)%ladder(:, :, 0), yb)
            end if
            ybb(nz + 1:) = self%se*self%exo(tb)
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
                if (self%cs%kn(jev) == 0.0_dp .and. vn < 0.0_dp) then
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
                            self%cs%kn(j) == 0.0_dp) zset = [zset, j]
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
                    do k = 1, nz
                        sal(:, k) = sal(:, k) + (fp(1:nz) - fm(1:nz))*c(k)/h
                    end do
                end if
                jac = matmul(sal, jac)
            end if
            if (want_orbit) then
                do j = 1, self%nc
                    if (code(j) == oldcode(j) .and. j /= jev) cycle
                    call add_event(te, j, law_kind(oldcode(j), code(j), j == jev .and. impact), &
                                   merge(0, code(j), code(j) == 2), &
                                   dot_product(self%modes(imnew)%force(self%cs%first(j), :), ye), &
                                   dot_product(self%w(:, j), ye(n + 1:nz)))
                end do
                call add_phase(te, ye, imnew)
            end if
            nevents = nevents + 1
            if (te - tp <= 1.0e-12_dp*self%period) then
                zero_length = zero_length + 1
            else
                zero_length = 0
            end if
            if (zero_length > max_zero_length + 3*self%nc) then
                write (buf, '(a,es13.5e3,a)') "no consistent contact mode at t = ", te, &
                    " s: the contacts switch again at the same instant"
                call fail(trim(buf))
                return
            end if
            if (nevents > max_events) then
                write (buf, '(a,i0,a)') "more than ", max_events, " events in one period "// &
                    "(chattering)"
                call fail(trim(buf))
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
        if (want_mono) then
            call expm(self%modes(im)%b(1:nz, 1:nz)*(tend - tp), phi, stat)
            mono = matmul(self%tbi(1:nz, 1:nz), matmul(matmul(phi, jac), self%tb(1:nz, 1:nz)))
        end if
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

        subroutine add_phase(ts, ys, imode)
            real(dp), intent(in) :: ts, ys(:)
            integer, intent(in) :: imode
            real(dp), allocatable :: rt(:), ry(:, :)
            integer, allocatable :: im2(:)
            integer :: m
            m = orbit%nphase
            if (m == size(orbit%phase_t)) then
                allocate (rt(2*m), ry(na, 2*m), im2(2*m))
                rt(1:m) = orbit%phase_t
                ry(:, 1:m) = orbit%phase_y
                im2(1:m) = orbit%phase_mode
                call move_alloc(rt, orbit%phase_t)
                call move_alloc(ry, orbit%phase_y)
                call move_alloc(im2, orbit%phase_mode)
            end if
            orbit%nphase = m + 1
            orbit%phase_t(m + 1) = ts
            orbit%phase_y(:, m + 1) = ys
            orbit%phase_mode(m + 1) = imode
        end subroutine add_phase

        subroutine add_event(ts, contact, kind, direction, force, velocity)
            real(dp), intent(in) :: ts, force, velocity
            integer, intent(in) :: contact, kind, direction
            integer :: m
            m = orbit%nevent
            if (m == size(orbit%event_t)) then
                orbit%event_t = [orbit%event_t, orbit%event_t]
                orbit%event_force = [orbit%event_force, orbit%event_force]
                orbit%event_velocity = [orbit%event_velocity, orbit%event_velocity]
                orbit%event_contact = [orbit%event_contact, orbit%event_contact]
                orbit%event_kind = [orbit%event_kind, orbit%event_kind]
                orbit%event_direction = [orbit%event_direction, orbit%event_direction]
            end if
            orbit%nevent = m + 1
            orbit%event_t(m + 1) = ts
            orbit%event_contact(m + 1) = contact
            orbit%event_kind(m + 1) = kind
            orbit%event_direction(m + 1) = direction
            orbit%event_force(m + 1) = force
            orbit%event_velocity(m + 1) = velocity
        end subroutine add_event

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
                gscale = self%fref(jj)*max(self%cs%mu(jj), 1.0e-3_dp)
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
            real(dp) :: ga, gb, da, db, thr, tmin, hh
            associate (r => md%rows(:, col))
                hh = tb - ta
                ga = dot_product(r, ya)
                gb = dot_product(r, yb2)
                da = dot_product(md%drows(:, col), ya)
                db = dot_product(md%drows(:, col), yb2)
                thr = 1.0e-9_dp*gscale*self%omega
                if (gb <= 0.0_dp) then
                    tau = first_crossing(md, self%delta, ya, r, 0, hh)
                else if (ga > 0.0_dp .and. da < -thr .and. db > thr) then
                    tmin = first_crossing(md, self%delta, ya, -r, 1, hh)
                    if (value_at(md, self%delta, ya, r, tmin) > 0.0_dp) return
                    tau = first_crossing(md, self%delta, ya, r, 0, tmin)
                else
                    return
                end if
                if (tau < best) then
                    best = tau
                    found = .true.
                    jev = jj
                    kev = kind
                    c = r
                end if
            end associate
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
        real(dp), allocatable :: nt(:, :), g(:, :), rhs(:, :), q(:), gi(:, :)
        integer :: j, n, m, k, info
        n = self%n
        pj = identity_matrix(2*n)
        allocate (nt(n, 0))
        rhs = reshape([real(dp) ::], [0, 1])
        q = yb(1:n)/self%s
        do j = 1, self%nc
            if (self%cs%normal(j) == 0 .or. self%cs%kn(j) > 0.0_dp) cycle
            if (dot_product(self%nt(:, j), q) + self%cs%gap(j) > 1.0e-9_dp*self%gref(j)) cycle
            nt = reshape([nt, self%nt(:, j)], [n, size(nt, 2) + 1])
            rhs = reshape([rhs(:, 1), dot_product(self%nt(:, j), q) + self%cs%gap(j)], &
                          [size(nt, 2), 1])
        end do
        m = size(nt, 2)
        if (m == 0) return
        g = matmul(transpose(nt), nt)
        call dgesv_small(m, g, rhs, info)
        if (info /= 0) return
        q = q - matmul(nt, rhs(:, 1))
        yb(1:n) = q*self%s
        ! d p_new / d p = S (I - Nt G^-1 Nt^T) S^-1
        gi = transpose(nt)
        do k = 1, n
            rhs(:, 1) = gi(:, k)
            call dgesv_small(m, g, rhs, info)
            pj(1:n, k) = pj(1:n, k) - self%s*matmul(nt, rhs(:, 1))/self%s(k)
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
        real(dp), allocatable :: ctm(:, :), g(:, :), u(:, :), pu(:, :)
        integer :: jj, info, m, n, k
        n = self%n
        allocate (ctm(n, 0))
        do jj = 1, self%nc
            if (code(jj) == 0 .and. (self%limit(jj) > 0.0_dp .or. self%cs%normal(jj) > 0)) &
                ctm = reshape([ctm, self%wt(:, jj)], [n, size(ctm, 2) + 1])
            if (self%cs%normal(jj) > 0) then
                if (code(jj) /= 2 .and. self%cs%kn(jj) == 0.0_dp) &
                    ctm = reshape([ctm, self%nt(:, jj)], [n, size(ctm, 2) + 1])
            end if
        end do
        m = size(ctm, 2)
        if (m == 0) return
        g = matmul(transpose(ctm), ctm)
        allocate (u(m, 1))
        u(:, 1) = matmul(yb(n + 1:2*n), ctm)
        call dgesv_small(m, g, u, info)
        if (info /= 0) return
        yb(n + 1:2*n) = yb(n + 1:2*n) - matmul(ctm, u(:, 1))
        if (.not. present(pj)) return
        ! P = I - Ct G^-1 Ct^T on the velocities
        allocate (pu(n, n))
        pu = identity_matrix(n)
        do k = 1, n
            u(:, 1) = ctm(k, :)
            call dgesv_small(m, g, u, info)
            pu(:, k) = pu(:, k) - matmul(ctm, u(:, 1))
        end do
        pj(n + 1:2*n, :) = matmul(pu, pj(n + 1:2*n, :))
    end subroutine project_velocities

    !> Solve g x = b (m x m, one right-hand side) by Gaussian elimination with partial
    !> pivoting; info = 1 when a pivot vanishes.
    pure subroutine dgesv_small(m, g, b, info)
        integer, intent(in) :: m
        real(dp), intent(in) :: g(:, :)
        real(dp), intent(inout) :: b(:, :)
        integer, intent(out) :: info
        real(dp) :: w(m, m), f, t
        integer :: i, k, p, q
        w = g
        info = 0
        do k = 1, m
            p = k - 1 + maxloc(abs(w(k:m, k)), 1)
            if (.not. (abs(w(p, k)) > 1.0e-300_dp)) then
                info = 1
                return
            end if
            if (p /= k) then
                do q = 1, m
                    t = w(k, q)
                    w(k, q) = w(p, q)
                    w(p, q) = t
                end do
                t = b(k, 1)
                b(k, 1) = b(p, 1)
                b(p, 1) = t
            end if
            do i = k + 1, m
                f = w(i, k)/w(k, k)
                w(i, k:m) = w(i, k:m) - f*w(k, k:m)
                b(i, 1) = b(i, 1) - f*b(k, 1)
            end do
        end do
        do i = m, 1, -1
            b(i, 1) = (b(i, 1) - dot_product(w(i, i + 1:m), b(i + 1:m, 1)))/w(i, i)
        end do
    end subroutine dgesv_small
end module stickslip_flow_law_map
