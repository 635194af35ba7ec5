!> The exact event-driven flow of the friction model over one forcing period: the engine of
!> the reference solution (DESIGN section 5).
!>
!> Between events every contact sticks or slips and the motion is linear: the augmented state
!> y = [x; v; e] (e the exosystem of the harmonic forcing) obeys y' = A y in each contact
!> mode, solved exactly by the matrix exponential in balanced modal coordinates
!> (stickslip_flow_modes: the modes, their dynamics and exponentials). The events that end
!> a phase (stick, slip, reversal, graze) are bracketed on a grid of `steps` per period and
!> located to roundoff on the exact solution (stickslip_flow_events). This module steps the
!> state from event to event and records the period.
!>
!> The period map z(t0) -> z(t0 + T) also returns its Jacobian (the monodromy matrix): the
!> product of the phase flows exp(A_zz tau) and of the saltation matrices
!> I + (f+ - f-) c^T / (c . f-) at the events. Knows nothing of files or of the other methods.
module stickslip_flow
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_expm, only: expm
    use stickslip_flow_modes, only: ngauss, mode_t, flow_modes_t, new_flow_modes, mode_index, &
        zero_velocity_modes, propagate, gauss_exponentials, project_stuck, identity_matrix
    use stickslip_flow_events, only: event_stick, event_slip, event_reversal, event_graze, &
        event_kind, event_name, find_event, grid_step, event_guard, add_saltation, end_monodromy
    use stickslip_flow_orbit, only: orbit_t
    use stickslip_flow_law_map, only: law_period_map, law_event_name
    implicit none
    private
    public :: flow_t, new_flow, orbit_t
    public :: event_stick, event_slip, event_reversal, event_graze, event_name, &
        law_event_name

    !> The exact flow of one model: the piecewise-linear dynamics and the cache of the modes
    !> met so far (the components of flow_modes_t, inherited), with the period map and the
    !> sampling of a recorded orbit. One instance per thread.
    type, extends(flow_modes_t) :: flow_t
    contains
        procedure :: period_map
        procedure :: sample
    end type flow_t


contains

    !> Build the flow of a validated `model`, bracketing events on `steps` steps per period,
    !> with velocity scales `vref` (one per contact, > 0) for the event tests. Errors: stat
    !> input (steps < 8, vref of the wrong size); stat numerical (M not positive definite).
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

    !> The period map: integrate from state z0 = [x; v] at time t0 [s] over one period and
    !> return z1 = [x; v] at t0 + T. Optionally the monodromy matrix dz1/dz0 (2N x 2N) and
    !> the recorded orbit (phases, events, energies). The modes at t0: contacts with
    !> |slip velocity| above 1e-12 vref slip, the others follow Coulomb's law at acceleration
    !> level. Errors (stat numerical): a non-finite state, dependent stuck contact
    !> directions, more than `max_events` events (chattering) or repeated events at one
    !> instant (no consistent mode).
    subroutine period_map(self, t0, z0, z1, error, mono, orbit, energies)
        !> The flow (its mode cache grows).
        class(flow_t), intent(inout) :: self
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
        !> With orbit: integrate the energies (default .true.; .false. leaves them 0).
        logical, intent(in), optional :: energies
        integer, parameter :: max_zero_length = 8
        integer :: n, nz, na, im, imnew, j, k, nevents, zero_length, stat, jev, kev, max_events
        integer, allocatable :: code(:), oldcode(:), zset(:)
        real(dp), allocatable :: y(:), yb(:), ybb(:), yeb(:), ye(:), yp(:), phi(:, :), &
                                 jac(:, :), sal(:, :), c(:), fm(:), fp(:)
        real(dp) :: t, tb, te, tp, tend, h
        logical :: found, want_mono, want_orbit, full_step, want_energy
        character(len=:), allocatable :: why

        if (self%laws) then
            ! contact laws: unilateral contacts, impacts (stickslip_flow_law_map)
            call law_period_map(self%flow_modes_t, t0, z0, z1, error, mono, orbit, energies)
            return
        end if
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
                  code(self%nc), oldcode(self%nc))
        y(1:nz) = z0
        y(nz + 1:) = self%exo(t0)
        if (want_mono) then
            allocate (jac(nz, nz), phi(nz, nz), sal(nz, nz))
            jac = identity_matrix(nz)
        end if
        ! the modes at the start
        code = 0
        do j = 1, self%nc
            h = dot_product(self%w(:, j), y(n + 1:nz))
            if (abs(h) > 1.0e-12_dp*self%vref(j)) code(j) = nint(sign(1.0_dp, h))
        end do
        zset = pack([(j, j=1, self%nc)], code == 0 .and. self%limit > 0.0_dp)
        code = merge(1, code, code == 0 .and. self%limit <= 0.0_dp)
        call zero_velocity_modes(self, matmul(self%tb, y), zset, code, error)
        if (allocated(error)) return
        im = mode_index(self, code, error)
        if (allocated(error)) return
        if (want_orbit) then
            call orbit%start(t0, na, self%nc)
            call orbit%add_phase(t0, y, im)
        end if

        ! the state is stepped in balanced coordinates (yb: y; ybb: the end of the step;
        ! yeb: at the event); y, ye, yp in the model's coordinates at phase boundaries
        yb = matmul(self%tb, y)
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
            call find_event(self, self%modes(im), t, yb, tb, ybb, found, te, yeb, jev, kev, c)
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

            ! an event at te for contact jev (kev: 0 velocity, +1 / -1 force at +/- limit)
            ye = matmul(self%tbi, yeb)
            ye(nz + 1:) = self%exo(te)
            if (want_energy) call energy(self%modes(im), t, yb, te, .false.)
            if (want_orbit) call close_phase(self%modes(im), yp, ye, te - tp)
            if (want_mono) then
                call expm(self%modes(im)%b(1:nz, 1:nz)*(te - tp), phi, stat)
                jac = matmul(phi, jac)
                fm = matmul(self%modes(im)%b, yeb)
            end if
            oldcode = code
            if (kev == 0) then
                zset = pack([(j, j=1, self%nc)], code == 0 .and. self%limit > 0.0_dp)
                zset = [zset, jev]
                call zero_velocity_modes(self, yeb, zset, code, error)
                if (allocated(error)) return
            else
                code(jev) = kev
            end if
            imnew = mode_index(self, code, error)
            if (allocated(error)) return
            ! stuck contacts: clear the roundoff left in their slip velocity (in the balanced
            ! state: a round trip through [x; v] would cost the stiff components accuracy)
            call project_stuck(self, code, yeb)
            yeb(nz + 1:) = self%se*self%exo(te)
            ye = matmul(self%tbi, yeb)
            ye(nz + 1:) = self%exo(te)
            if (want_mono) then
                fp = matmul(self%modes(imnew)%b, yeb)
                h = dot_product(c, fm)
                if (abs(h) > 1.0e-300_dp) then
                    sal = identity_matrix(nz)
                    call add_saltation(sal, fp, fm, c, h)
                    jac = matmul(sal, jac)
                end if
            end if
            if (want_orbit) then
                do j = 1, self%nc
                    if (code(j) == oldcode(j) .and. j /= jev) cycle
                    call orbit%add_event(te, j, event_kind(oldcode(j), code(j)), code(j), &
                                   dot_product(self%modes(imnew)%force(j, :), ye), &
                                   dot_product(self%w(:, j), ye(n + 1:nz)))
                end do
                call orbit%add_phase(te, ye, imnew)
            end if
            why = event_guard(te, tp, self%period, max_zero_length + 2*self%nc, max_events, &
                              "chattering between stick and slip", zero_length, nevents)
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
        ! back to the model's coordinates: mono = tbi_zz (phase flow x jac) tb_zz
        if (want_mono) call end_monodromy(self, self%modes(im), tend - tp, jac, mono)
        if (want_orbit) call close_phase(self%modes(im), yp, y, tend - tp)
        z1 = y(1:nz)

    contains

        subroutine fail(message)
            character(len=*), intent(in) :: message
            call fatal_error(error, "reference: "//message, stickslip_stat%numerical)
        end subroutine fail

        !> Friction dissipation of the phase (exact: mu N |change of w^T x| in slip) and
        !> time in stick.
        subroutine close_phase(md, ya, yz, duration)
            type(mode_t), intent(in) :: md
            real(dp), intent(in) :: ya(:), yz(:), duration
            integer :: jj
            do jj = 1, self%nc
                if (md%code(jj) == 0) then
                    orbit%stick_time(jj) = orbit%stick_time(jj) + duration
                else
                    orbit%diss_friction = orbit%diss_friction + self%limit(jj)*md%code(jj)* &
                                          dot_product(self%w(:, jj), yz(1:n) - ya(1:n))
                end if
            end do
        end subroutine close_phase

        !> Work of the forcing and viscous dissipation over [ta, tz] in mode md, by
        !> Gauss-Legendre quadrature of the exact solution (smooth within a phase).
        subroutine energy(md, ta, ya, tz, full_step)
            type(mode_t), intent(in) :: md
            real(dp), intent(in) :: ta, ya(:), tz
            logical, intent(in) :: full_step
            real(dp) :: yg(na), ygb(na), half, power
            integer :: ig
            half = 0.5_dp*(tz - ta)
            if (half <= 0.0_dp) return
            do ig = 1, ngauss
                ! ya is balanced; yg in the model's coordinates
                if (full_step) then
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
            end do
        end subroutine energy
    end subroutine period_map

    !> Samples of the recorded orbit at t_k = k T / ng, k = 0..ng-1 (t = 0 is the phase of
    !> the forcing): displacements x(ng, N), velocities v(ng, N), friction forces r(ng, n_c)
    !> (with contact laws: the forces of every force channel, r(ng, n_ch)), and on request
    !> the contact codes of the mode at each sample (0 stuck, +1 / -1 slipping, 2 open).
    !> Errors (stat numerical): the matrix exponential failed.
    subroutine sample(self, orbit, ng, x, v, r, error, code)
        !> The flow whose orbit was recorded.
        class(flow_t), intent(in) :: self
        !> One recorded period.
        type(orbit_t), intent(in) :: orbit
        !> Number of samples.
        integer, intent(in) :: ng
        !> Displacements [m], velocities [m/s], friction forces [N].
        real(dp), intent(out) :: x(:, :), v(:, :), r(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Contact codes at the samples, ng x n_c.
        integer, intent(out), optional :: code(:, :)
        real(dp) :: y(self%na), yb(self%na), tk, dt
        real(dp), allocatable :: step(:, :, :)
        logical, allocatable :: have_step(:)
        integer :: k, kk, p, kfirst, last_p, n, stat, im
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
                yb(2*n + 1:) = self%se*self%exo(tk)
                y = matmul(self%tbi, yb)
                if (.not. all(ieee_is_finite(y))) then
                    call fatal_error(error, "reference: the state is not finite while "// &
                                     "sampling", stickslip_stat%numerical)
                    return
                end if
                y(2*n + 1:) = self%exo(tk)
                x(k + 1, :) = y(1:n)
                v(k + 1, :) = y(n + 1:2*n)
                r(k + 1, :) = matmul(md%force, y)
                if (present(code)) code(k + 1, :) = md%code
            end associate
        end do
    end subroutine sample


end module stickslip_flow
