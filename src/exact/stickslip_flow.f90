!> The exact event-driven flow of the model with its contact elements over one forcing
!> period: the engine of the reference solution (DESIGN section 5, doc/contacts.md section 5).
!>
!> Between events every contact element is in one mode and the motion is linear: the
!> augmented state y = [x; v; s; e] (s the elements' internal states, e the exosystem of the
!> harmonic forcing) obeys y' = A y, solved exactly by the matrix exponential in balanced
!> modal coordinates (stickslip_flow_modes, stickslip_flow_algebra). The events that end a
!> phase are the zeros of the elements' event rows, bracketed on a grid of `steps` per
!> period and located to roundoff on the exact solution (stickslip_flow_events); at each,
!> the elements concerned get new codes (stickslip_flow_algebra: a code switch, a joint
!> decision of the rigid contacts, an elastic slider's own, an impact of a rigid normal).
!>
!> The period map z(t0) -> z(t0 + T) of z = [x; v; s] also returns its Jacobian (the
!> monodromy matrix): the product of the phase flows exp(A_zz tau), of the saltation
!> matrices J + (f+ - J f-) c^T / (c . f-) at the events (J the Jacobian of an impact's
!> jump, else the identity) and of the projections of the start onto its mode's
!> constraints. Knows nothing of files or of the other methods.
module stickslip_flow
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_expm, only: expm
    use stickslip_flow_modes, only: ngauss, mode_t, flow_modes_t, new_flow_modes, propagate, &
        gauss_exponentials, identity_matrix
    use stickslip_flow_algebra, only: mode_index, start_codes, decide_codes, impact_jump, &
        close_rigid_gaps, project_velocities
    use stickslip_flow_events, only: event_stick, event_slip, event_reversal, event_graze, &
        event_open, event_close, event_impact, event_kind, event_name, find_event, grid_step, &
        event_guard, add_saltation, end_monodromy
    use stickslip_flow_orbit, only: orbit_t
    use stickslip_contact_modes, only: action_decide, action_close
    use stickslip_contact_element, only: along_tangent, state_stick, state_open
    implicit none
    private
    public :: flow_t, new_flow, orbit_t
    public :: event_stick, event_slip, event_reversal, event_graze, event_open, event_close, &
        event_impact, event_name

    !> The exact flow of one model: the piecewise-linear dynamics and the cache of the modes
    !> met so far (the components of flow_modes_t, inherited), with the period map and the
    !> sampling of a recorded orbit. One instance per thread.
    type, extends(flow_modes_t) :: flow_t
    contains
        procedure :: period_map
        procedure :: sample
        procedure :: state_of
    end type flow_t

contains

    !> Build the flow of a validated `model`, bracketing events on `steps` steps per period,
    !> with velocity scales `vref` (one per contact, > 0) for the event tests. Errors: stat
    !> input (steps < 8, vref of the wrong size, a law the exact flow does not handle); stat
    !> numerical (M not positive definite).
    subroutine new_flow(self, model, steps, vref, error)
        !> The flow.
        type(flow_t), intent(out) :: self
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Bracketing steps per period.
        integer, intent(in) :: steps
        !> Velocity scale of each contact [m/s].
        real(dp), intent(in) :: vref(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        call new_flow_modes(self%flow_modes_t, model, steps, vref, error)
    end subroutine new_flow

    !> The contact state (state_open, state_stick, state_slip) of contact j in mode im.
    integer function state_of(self, im, j) result(state)
        !> The flow.
        class(flow_t), intent(in) :: self
        !> Mode and contact.
        integer, intent(in) :: im, j
        associate (code => self%modes(im)%code)
            state = self%cs%elements(j)%e%code_state(code(self%slot0(j) + 1:self%slot_hi(j)))
        end associate
    end function state_of

    !> The period map: integrate from state z0 = [x; v; s] at time t0 [s] over one period and
    !> return z1 at t0 + T. Optionally the monodromy matrix dz1/dz0 (nz x nz) and the
    !> recorded orbit (phases, events, energies). The start: a rigid normal at a zero or
    !> negative gap is put at zero gap, the elements' codes are those of the state
    !> (contact_element_t%start_code, the undecided ones jointly), and the velocities along
    !> the start mode's constraints are removed (projections whose Jacobian is in the
    !> monodromy). Errors (stat numerical): a non-finite state, no consistent mode,
    !> dependent constraints, more than `max_events` events (chattering) or repeated events
    !> at one instant.
    subroutine period_map(self, t0, z0, z1, error, mono, orbit, energies)
        !> The flow (its mode cache grows).
        class(flow_t), intent(inout) :: self
        !> Start time [s].
        real(dp), intent(in) :: t0
        !> Start state [x; v; s] [m, m/s, m].
        real(dp), intent(in) :: z0(:)
        !> State one period later.
        real(dp), intent(out) :: z1(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Monodromy matrix dz1/dz0.
        real(dp), intent(out), optional :: mono(:, :)
        !> The recorded period.
        type(orbit_t), intent(out), optional :: orbit
        !> With orbit: integrate the energies (default .true.; .false. leaves them 0).
        logical, intent(in), optional :: energies
        integer, parameter :: max_zero_length = 8
        integer :: n, nz, na, im, imnew, j, k, nevents, zero_length, stat, kev, max_events, &
                   jev, slot
        integer, allocatable :: code(:), oldcode(:), zset(:)
        real(dp), allocatable :: y(:), yb(:), ybb(:), yeb(:), ye(:), phi(:, :), jac(:, :), &
                                 sal(:, :), c(:), fm(:), fp(:), jump(:, :), pj(:, :)
        real(dp) :: t, tb, te, tp, tend, h, loss
        logical :: found, want_mono, want_orbit, full_step, want_energy, impact
        character(len=:), allocatable :: why

        n = self%n
        nz = self%nz
        na = self%na
        want_mono = present(mono)
        want_orbit = present(orbit)
        want_energy = want_orbit
        if (want_orbit .and. present(energies)) want_energy = energies
        max_events = 1000*(self%nslot + 1)
        tend = t0 + self%period
        allocate (y(na), yb(na), ybb(na), yeb(na), ye(na), c(na), fm(na), fp(na), &
                  code(self%nslot), oldcode(self%nslot), jump(nz, nz), pj(nz, nz))
        y(1:nz) = z0
        y(nz + 1:) = self%exo(t0)
        if (want_mono) allocate (phi(nz, nz), sal(nz, nz))
        yb = matmul(self%tb, y)
        ! the constraints of the start mode hold in the start state
        call close_rigid_gaps(self, yb, pj)
        call start_codes(self, yb, code, error)
        if (allocated(error)) return
        im = mode_index(self, code, error)
        if (allocated(error)) return
        call project_velocities(self, self%modes(im), yb, pj)
        if (want_mono) jac = pj
        y = matmul(self%tbi, yb)
        y(nz + 1:) = self%exo(t0)
        if (want_orbit) then
            call orbit%start(t0, na, self%nc)
            call orbit%add_phase(t0, y, im)
        end if

        ! the state is stepped in balanced coordinates (yb: y; ybb: the end of the step;
        ! yeb: at the event); y, ye in the model's coordinates at phase boundaries
        t = t0
        tp = t0
        nevents = 0
        zero_length = 0
        do
            if (t >= tend) exit
            call grid_step(self, self%modes(im), t, tend, yb, tb, ybb, full_step)
            if (.not. all(ieee_is_finite(ybb))) then
                call fail("the state is not finite (unbounded response)")
                return
            end if
            call find_event(self, self%modes(im), t, yb, tb, ybb, found, te, yeb, kev)
            if (.not. found) then
                ! a whole grid step: the cached exponentials at the Gauss points serve
                if (want_energy) then
                    if (full_step) call gauss_exponentials(self, self%modes(im))
                    call energy(self%modes(im), t, yb, tb, full_step)
                end if
                t = tb
                yb = ybb
                cycle
            end if

            ! an event at te: row kev of element jev, code slot `slot`
            jev = self%modes(im)%row_element(kev)
            slot = self%modes(im)%row_slot(kev)
            c = self%modes(im)%rows(:, kev)
            if (want_energy) call energy(self%modes(im), t, yb, te, .false.)
            if (want_orbit) call close_phase(im, te - tp)
            if (want_mono) then
                call expm(self%modes(im)%b(1:nz, 1:nz)*(te - tp), phi, stat)
                jac = matmul(phi, jac)
                fm = matmul(self%modes(im)%b, yeb)
            end if
            oldcode = code
            impact = .false.
            jump = identity_matrix(nz)
            select case (self%modes(im)%row_action(kev))
            case (action_decide)
                ! a velocity reaches zero: this element and every one holding a rigid
                ! constraint decide
                zset = [jev]
                do j = 1, self%nc
                    if (j /= jev .and. self%cs%elements(j)%e%holds_constraint( &
                        code(self%slot0(j) + 1:self%slot_hi(j)))) zset = [zset, j]
                end do
                call decide_codes(self, yeb, zset, code, error)
                if (allocated(error)) return
            case (action_close)
                zset = [jev]
                if (self%cs%elements(jev)%e%impacts(code(self%slot0(jev) + 1:self%slot_hi(jev)), &
                                                    self%geom(jev), &
                                                    yeb)) then
                    ! a rigid normal closing with a velocity: a plastic impact
                    call impact_jump(self, yeb, jev, code, jump, loss)
                    impact = .true.
                    if (want_orbit) orbit%impact_loss = orbit%impact_loss + loss
                    do j = 1, self%nc
                        if (j /= jev .and. self%cs%elements(j)%e%rigid_closed( &
                            code(self%slot0(j) + 1:self%slot_hi(j)))) zset = [zset, j]
                    end do
                end if
                call decide_codes(self, yeb, zset, code, error)
                if (allocated(error)) return
            case default
                code(slot) = self%modes(im)%row_action(kev)
            end select
            imnew = mode_index(self, code, error)
            if (allocated(error)) return
            ! constrained directions: clear the roundoff left in their velocities (in the
            ! balanced state: a round trip through [x; v] would cost the stiff components
            ! accuracy)
            call project_velocities(self, self%modes(imnew), yeb)
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
                    do k = 1, self%nslots(j)
                        slot = self%slot0(j) + k
                        if (code(slot) == oldcode(slot) .and. &
                            .not. (j == jev .and. slot == self%modes(im)%row_slot(kev))) cycle
                        call orbit%add_event(te, j, event_kind(oldcode(slot), code(slot), &
                                                               j == jev .and. impact), &
                                             merge(0, code(slot), code(slot) == 2), &
                                             tangential_force(imnew, j, ye), &
                                             dot_product(self%w(:, j), ye(n + 1:2*n)))
                    end do
                end do
                call orbit%add_phase(te, ye, imnew)
            end if
            why = event_guard(te, tp, self%period, max_zero_length + 3*self%nslot, &
                              max_events, "chattering", zero_length, nevents)
            if (len(why) > 0) then
                call fail(why)
                return
            end if
            im = imnew
            t = te
            yb = yeb
            tp = te
        end do
        y = matmul(self%tbi, yb)
        y(nz + 1:) = self%exo(tend)
        ! back to the model's coordinates: mono = tbi_zz (phase flow x jac) tb_zz
        if (want_mono) call end_monodromy(self, self%modes(im), tend - tp, jac, mono)
        if (want_orbit) call close_phase(im, tend - tp)
        z1 = y(1:nz)

    contains

        subroutine fail(message)
            character(len=*), intent(in) :: message
            call fatal_error(error, "reference: "//message, stickslip_stat%numerical)
        end subroutine fail

        !> The friction force of contact j along w in mode m at state ya (model coordinates):
        !> the sum of its channels along w.
        real(dp) function tangential_force(m, j, ya) result(f)
            integer, intent(in) :: m, j
            real(dp), intent(in) :: ya(:)
            integer :: cc
            f = 0.0_dp
            do cc = self%cs%first(j), self%cs%first(j) + self%cs%width(j) - 1
                if (self%cs%along(cc) == along_tangent) &
                    f = f + dot_product(self%modes(m)%force(cc, :), ya)
            end do
        end function tangential_force

        !> Time stuck and open over the phase just ended (mode m).
        subroutine close_phase(m, duration)
            integer, intent(in) :: m
            real(dp), intent(in) :: duration
            integer :: jj
            do jj = 1, self%nc
                select case (self%state_of(m, jj))
                case (state_stick)
                    orbit%stick_time(jj) = orbit%stick_time(jj) + duration
                case (state_open)
                    orbit%open_time(jj) = orbit%open_time(jj) + duration
                end select
            end do
        end subroutine close_phase

        !> Work of the forcing, viscous dissipation and the friction dissipation of every
        !> force channel over [ta, tz] in mode md (Gauss-Legendre on the exact solution).
        subroutine energy(md, ta, ya, tz, full)
            type(mode_t), intent(in) :: md
            real(dp), intent(in) :: ta, ya(:), tz
            logical, intent(in) :: full
            real(dp) :: yg(na), ygb(na), half, power, rch(size(md%force, 1)), fric, &
                        vch(size(md%force, 1))
            integer :: ig
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
                power = dot_product(matmul(self%hf(:, nz + 1:), yg(nz + 1:)), yg(n + 1:2*n))
                orbit%work_forcing = orbit%work_forcing + half*self%gw(ig)*power
                orbit%work_gross = orbit%work_gross + half*self%gw(ig)*abs(power)
                orbit%diss_damping = orbit%diss_damping + half*self%gw(ig)* &
                    dot_product(yg(n + 1:2*n), matmul(self%damping, yg(n + 1:2*n)))
                rch = matmul(md%force, yg)
                vch = matmul(yg(n + 1:2*n), self%d)
                fric = dot_product(rch, vch)
                orbit%diss_friction = orbit%diss_friction - half*self%gw(ig)*fric
            end do
        end subroutine energy
    end subroutine period_map

    !> Samples of the recorded orbit at t_k = k T / ng, k = 0..ng-1 (t = 0 is the phase of
    !> the forcing): displacements x(ng, N), velocities v(ng, N), channel forces r(ng,
    !> n_ch), and on request the contact states (state_open, state_stick, state_slip) and
    !> the internal states s(ng, n_s). Errors (stat numerical): the state is not finite.
    subroutine sample(self, orbit, ng, x, v, r, error, state, s)
        !> The flow whose orbit was recorded.
        class(flow_t), intent(in) :: self
        !> One recorded period.
        type(orbit_t), intent(in) :: orbit
        !> Number of samples.
        integer, intent(in) :: ng
        !> Displacements [m], velocities [m/s], channel forces [N].
        real(dp), intent(out) :: x(:, :), v(:, :), r(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Contact states at the samples, ng x n_c.
        integer, intent(out), optional :: state(:, :)
        !> Internal states at the samples, ng x n_s [m].
        real(dp), intent(out), optional :: s(:, :)
        real(dp) :: y(self%na), yb(self%na), tk, dt
        real(dp), allocatable :: step(:, :, :)
        logical, allocatable :: have_step(:)
        integer :: k, kk, p, kfirst, last_p, n, stat, im, j
        n = self%n
        dt = self%period/ng
        ! the first sample at or after t0; samples before t0 belong to the end of the period
        kfirst = modulo(ceiling(orbit%t0/dt - 1.0e-12_dp), ng)
        p = 1
        last_p = 0
        ! exp(b dt) of each mode met, built on first use
        allocate (step(self%na, self%na, self%nmodes), have_step(self%nmodes))
        have_step = .false.
        do kk = 0, ng - 1
            k = modulo(kfirst + kk, ng)
            tk = k*dt
            if (tk < orbit%t0 - 1.0e-12_dp*dt) tk = tk + self%period
            do while (p < orbit%nphase)
                if (orbit%phase_t(p + 1) > tk) exit
                p = p + 1
            end do
            im = orbit%phase_mode(p)
            associate (md => self%modes(im))
                if (p /= last_p) then
                    yb = matmul(self%tb, orbit%phase_y(:, p))
                    call propagate(md, self%delta, tk - orbit%phase_t(p), yb, y)
                    last_p = p
                else
                    if (.not. have_step(im)) then
                        call expm(md%b*dt, step(:, :, im), stat)
                        have_step(im) = .true.
                    end if
                    y = matmul(step(:, :, im), yb)
                end if
                yb = y
                yb(self%nz + 1:) = self%se*self%exo(tk)
                y = matmul(self%tbi, yb)
                if (.not. all(ieee_is_finite(y))) then
                    call fatal_error(error, "reference: the state is not finite while "// &
                                     "sampling", stickslip_stat%numerical)
                    return
                end if
                y(self%nz + 1:) = self%exo(tk)
                x(k + 1, :) = y(1:n)
                v(k + 1, :) = y(n + 1:2*n)
                r(k + 1, :) = matmul(md%force, y)
                if (present(s)) s(k + 1, :) = y(2*n + 1:self%nz)
                if (present(state)) then
                    do j = 1, self%nc
                        state(k + 1, j) = self%state_of(im, j)
                    end do
                end if
            end associate
        end do
    end subroutine sample
end module stickslip_flow
