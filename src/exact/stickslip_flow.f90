!> The exact event-driven flow of the model with its contact elements over one forcing
!> period: the engine of the reference solution (DESIGN section 5, doc/contacts.md section 5).
!>
!> Between events every contact element is in one mode and the motion is linear: the
!> augmented state y = [x; v; s; e] (s the elements' internal states, e the exosystem of the
!> harmonic forcing) obeys y' = A y, solved exactly by the matrix exponential in balanced
!> modal coordinates (stickslip_flow_modes, stickslip_flow_algebra); except in a 2D slip,
!> whose force turns with the state: y' = A y + G q(y), integrated by exponential
!> collocation under the tolerance ode_tol (stickslip_flow_nonlinear). The events that end
!> a phase are the zeros of the elements' event rows, bracketed on a grid of `steps` per
!> period and located to roundoff on the exact solution (stickslip_flow_events; in a
!> nonlinear phase on the collocation steps, stickslip_flow_nonlinear); at each,
!> the elements concerned get new codes (stickslip_flow_algebra: a code switch, a joint
!> decision of the rigid contacts, an elastic slider's own, an impact of a rigid normal).
!>
!> The period map z(t0) -> z(t0 + T) of z = [x; v; s] also returns its Jacobian (the
!> monodromy matrix): the product of the phase flows exp(A_zz tau) (of the collocation
!> steps in a nonlinear phase), of the saltation matrices P J + (f+ - P J f-) c^T / (c . f-)
!> at the events (J the Jacobian of a jump: an impact's, or of an element's internal states
!> at a switch, else the identity; P the projection of the velocities onto the new mode's
!> constraints) and of the projections of the start onto its mode's constraints and its
!> elements' admissible states. Knows nothing of files or of the other methods.
module stickslip_flow
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_expm, only: expm
    use stickslip_dense_products, only: mat_mul
    use stickslip_flow_modal, only: project_velocity_rows
    use stickslip_flow_track, only: track_t, ensure_modal, track_usable, start_track, &
        track_state, track_find_event
    use stickslip_flow_modes, only: ngauss, mode_t, flow_modes_t, new_flow_modes, propagate, &
        propagate_matrix, gauss_exponentials, identity_matrix, propagate_jacobian, tune_ladder
    use stickslip_flow_algebra, only: mode_index, start_codes, decide_codes, impact_jump, &
        close_rigid_gaps, project_velocities, eval_inputs
    use stickslip_flow_events, only: event_stick, event_slip, event_reversal, event_graze, &
        event_open, event_close, event_impact, event_kind, event_name, find_event, grid_step, &
        event_guard, end_monodromy, event_hit_t
    use stickslip_flow_nonlinear, only: nodes, node, gauss_weight, max_level, nl_step_t, &
        nl_prepare, nl_step, nl_checked_step, nl_state_at, nl_exponentials, nl_dense, &
        nl_dense_jacobian, nl_input_at
    use stickslip_flow_orbit, only: orbit_t
    use stickslip_contact_modes, only: action_decide, action_close, action_memory, event_list_t, &
        code_unloaded
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
    !> with velocity scales `vref` (one per contact, > 0) for the event tests; `ode_tol` the
    !> tolerance of the numerical integration of nonlinear phases (a 2D slip; default
    !> 1e-10). Errors: stat input (steps < 8, vref of the wrong size, a law the exact flow
    !> does not handle); stat numerical (M not positive definite).
    subroutine new_flow(self, model, steps, vref, error, ode_tol)
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
        !> Tolerance of nonlinear phases (relative).
        real(dp), intent(in), optional :: ode_tol
        call new_flow_modes(self%flow_modes_t, model, steps, vref, error)
        if (present(ode_tol)) self%ode_tol = ode_tol
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
    !> return z1 at t0 + T (or over `duration` [s], 0 < duration <= T: the map to t0 +
    !> duration, its Jacobian and orbit over that span). Optionally the monodromy matrix
    !> dz1/dz0 (nz x nz) and the recorded orbit (phases, events, energies). The start: a
    !> rigid normal at a zero or negative gap is put at zero gap, the elements' codes are
    !> those of the state (contact_element_t%start_code, the undecided ones jointly), and
    !> the velocities along the start mode's constraints are removed (projections whose
    !> Jacobian is in the monodromy). Linear modes step by their exponentials, nonlinear ones
    !> (a 2D slip) by exponential collocation (stickslip_flow_nonlinear). Errors: stat input
    !> (a duration outside (0, T]); stat numerical: a non-finite state, no consistent mode,
    !> dependent constraints, a nonlinear phase that does not meet its tolerance, more than
    !> `max_events` events (chattering) or repeated events at one instant.
    subroutine period_map(self, t0, z0, z1, error, mono, orbit, energies, duration)
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
        !> Length of the span [s] (default the period).
        real(dp), intent(in), optional :: duration
        integer, parameter :: max_zero_length = 8
        !> Fewest states n_z for the modal track: on smaller models a ladder step (a
        !> matrix-vector product of order n_a) costs less than the track's exponentials
        !> (the seed's stability ran 2.4 times slower tracked).
        integer, parameter :: track_min_states = 24
        integer :: n, nz, na, im, imnew, j, k, nevents, zero_length, max_events, level, &
                   last_element
        integer, allocatable :: code(:), oldcode(:), zset(:)
        real(dp), allocatable :: y(:), yb(:), ybb(:), yeb(:), ye(:), jac(:, :), &
                                 fm(:), fp(:), jump(:, :), pj(:, :), dirs(:, :), &
                                 eye(:, :), fmc(:, :), cj(:)
        real(dp) :: t, tb, te, tp, tend, h, loss
        logical :: found, want_mono, want_orbit, full_step, want_energy, impact, fresh, tracked
        type(track_t) :: trk
        logical, allocatable :: armed(:, :)
        type(event_hit_t) :: hit
        type(nl_step_t) :: st
        type(event_list_t) :: rows
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
        if (present(duration)) then
            if (.not. (duration > 0.0_dp .and. duration <= self%period)) then
                call fatal_error(error, "period_map: the span must be in (0, T]", &
                                 stickslip_stat%input)
                return
            end if
            tend = t0 + duration
        end if
        allocate (y(na), yb(na), ybb(na), yeb(na), ye(na), fm(na), fp(na), &
                  code(self%nslot), oldcode(self%nslot), jump(nz, nz), pj(nz, nz), &
                  dirs(3, self%nc))
        dirs = 0.0_dp
        ! the identity, made once: each event starts its jump and projection from it
        eye = identity_matrix(nz)
        y(1:nz) = z0
        y(nz + 1:) = self%exo(t0)
        if (want_mono) allocate (fmc(nz, 1))
        yb = matmul(self%tb, y)
        ! the constraints of the start mode hold in the start state
        call close_rigid_gaps(self, yb, pj)
        call start_codes(self, yb, code, dirs, error)
        if (allocated(error)) return
        im = mode_index(self, code, error)
        if (allocated(error)) return
        call project_velocities(self, self%modes(im), yb, pj)
        do j = 1, self%nc
            associate (c0 => self%cs%first(j), c1 => self%cs%first(j) + self%cs%width(j) - 1)
                call self%cs%elements(j)%e%start_states( &
                    code(self%slot0(j) + 1:self%slot_hi(j)), self%geom(j), &
                    self%modes(im)%fbal(c0:c1, :), yb, pj)
            end associate
        end do
        if (want_mono) jac = pj
        y = matmul(self%tbi, yb)
        y(nz + 1:) = self%exo(t0)
        if (want_orbit) then
            call orbit%start(t0, na, self%nc)
            if (self%modes(im)%m == 0) call orbit%add_phase(t0, y, im)
        end if

        ! the state is stepped in balanced coordinates (yb: y; ybb: the end of the step;
        ! yeb: at the event); y, ye in the model's coordinates at phase boundaries
        t = t0
        tp = t0
        call begin_phase()
        if (allocated(error)) return
        level = 0
        fresh = .true.
        nevents = 0
        zero_length = 0
        last_element = 0
        do
            if (t >= tend) exit
            if (self%modes(im)%m > 0) then
                ! a nonlinear phase: one collocation step (to an event if one falls in it)
                call nonlinear_step(found)
                if (allocated(error)) return
                if (.not. found) cycle
            else if (tracked) then
                ! a linear phase in modal coordinates: the grid step's event rows and the
                ! event in O(n) per time (stickslip_flow_track)
                tb = t + self%delta
                if (tend - t <= self%delta*(1.0_dp + 1.0e-9_dp)) tb = tend
                call track_find_event(self, self%modes(im), trk, t, tb, found, te, yeb, hit)
                if (.not. found) then
                    t = tb
                    if (t >= tend) then
                        yb = track_state(self, self%modes(im), trk, tend)
                        if (.not. all(ieee_is_finite(yb))) then
                            call fail("the state is not finite (unbounded response)")
                            return
                        end if
                    end if
                    cycle
                end if
                if (.not. all(ieee_is_finite(yeb))) then
                    call fail("the state is not finite (unbounded response)")
                    return
                end if
                if (want_mono) then
                    call propagate_jacobian(self, self%modes(im), te - tp, jac)
                    fm = matmul(self%modes(im)%b, yeb)
                end if
            else
                call grid_step(self, self%modes(im), t, tend, yb, tb, ybb, full_step)
                if (.not. all(ieee_is_finite(ybb))) then
                    call fail("the state is not finite (unbounded response)")
                    return
                end if
                call find_event(self, self%modes(im), t, yb, tb, ybb, found, te, yeb, hit, &
                                t == tp)
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
                if (want_energy) call energy(self%modes(im), t, yb, te, .false.)
                if (want_mono) then
                    call propagate_jacobian(self, self%modes(im), te - tp, jac)
                    fm = matmul(self%modes(im)%b, yeb)
                end if
            end if

            ! an event at te: event function `hit` of element hit%element, code slot hit%slot
            if (want_orbit) call close_phase(im, te - tp)
            oldcode = code
            impact = .false.
            jump = eye
            select case (hit%action)
            case (action_decide)
                ! a velocity reaches zero: this element and every one holding a rigid
                ! constraint decide
                zset = [hit%element]
                do j = 1, self%nc
                    if (j /= hit%element .and. self%cs%elements(j)%e%holds_constraint( &
                        code(self%slot0(j) + 1:self%slot_hi(j)))) zset = [zset, j]
                end do
                call decide_codes(self, yeb, zset, code, dirs, error)
                if (allocated(error)) return
            case (action_close)
                j = hit%element
                zset = [j]
                if (self%cs%elements(j)%e%impacts(code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                  self%geom(j), yeb)) then
                    ! a rigid normal closing with a velocity: a plastic impact
                    call impact_jump(self, yeb, j, code, jump, loss)
                    impact = .true.
                    if (want_orbit) orbit%impact_loss = orbit%impact_loss + loss
                    do k = 1, self%nc
                        if (k /= j .and. self%cs%elements(k)%e%rigid_closed( &
                            code(self%slot0(k) + 1:self%slot_hi(k)))) zset = [zset, k]
                    end do
                end if
                call decide_codes(self, yeb, zset, code, dirs, error)
                if (allocated(error)) return
            case (action_memory)
                ! the element's slip memory follows the state, its codes kept
                j = hit%element
                call self%cs%elements(j)%e%slip_direction( &
                    code(self%slot0(j) + 1:self%slot_hi(j)), self%geom(j), &
                    reshape([real(dp) ::], [0, na]), yeb, dirs(:, j))
            case default
                code(hit%slot) = hit%action
                ! an element entering a 2D slip from stuck: against its stuck force
                j = hit%element
                associate (c0 => self%cs%first(j), w => self%cs%width(j))
                    call self%cs%elements(j)%e%slip_direction( &
                        code(self%slot0(j) + 1:self%slot_hi(j)), self%geom(j), &
                        matmul(self%modes(im)%force(c0:c0 + w - 1, :), self%tbi), yeb, &
                        dirs(:, j))
                end associate
            end select
            imnew = mode_index(self, code, error)
            if (allocated(error)) return
            ! the internal states of the elements whose codes switched (a slider unloaded as
            ! its contact opens: part of the event's jump)
            do j = 1, self%nc
                associate (s0 => self%slot0(j) + 1, s1 => self%slot_hi(j), &
                           c0 => self%cs%first(j), w => self%cs%width(j))
                    if (all(code(s0:s1) == oldcode(s0:s1))) cycle
                    call self%cs%elements(j)%e%event_states( &
                        oldcode(s0:s1), code(s0:s1), self%geom(j), &
                        self%modes(imnew)%fbal(c0:c0 + w - 1, :), yeb, jump)
                end associate
            end do
            ! constrained directions: clear the roundoff left in their velocities (in the
            ! balanced state: a round trip through [x; v] would cost the stiff components
            ! accuracy)
            call project_velocities(self, self%modes(imnew), yeb)
            yeb(nz + 1:) = self%se*self%exo(te)
            ye = matmul(self%tbi, yeb)
            ye(nz + 1:) = self%exo(te)
            if (want_mono) then
                ! dy+ = P J (I - f- c^T / c.f-) dy- + f+ c^T / c.f- dy-, P the projection onto
                ! the new constraints (a 2D stick removes the slip velocity the event row
                ! does not see), J the jump of an impact: jac <- P J jac + (f+ - P J f-) (c^T
                ! jac) / c.f-, P applied to the velocity rows (low rank), J only where there
                ! is a jump
                fp = rate(imnew, yeb)
                h = dot_product(hit%c, fm)
                cj = matmul(hit%c(1:nz), jac)
                if (.not. all(jump == eye)) then
                    jac = mat_mul(jump, jac)
                    fm(1:nz) = matmul(jump, fm(1:nz))
                end if
                call project_velocity_rows(self%modes(imnew)%ctm, n, jac)
                fmc(:, 1) = fm(1:nz)
                call project_velocity_rows(self%modes(imnew)%ctm, n, fmc)
                if (abs(h) > 1.0e-300_dp) then
                    fm(1:nz) = (fp(1:nz) - fmc(:, 1))/h
                    do k = 1, nz
                        jac(:, k) = jac(:, k) + fm(1:nz)*cj(k)
                    end do
                end if
            end if
            if (want_orbit) then
                do j = 1, self%nc
                    do k = 1, self%nslots(j)
                        associate (slot => self%slot0(j) + k, &
                                   newc => reported(code(self%slot0(j) + k)), &
                                   oldc => reported(oldcode(self%slot0(j) + k)))
                            if (newc == oldc .and. &
                                (hit%action == action_memory .or. &
                                 .not. (j == hit%element .and. slot == hit%slot))) cycle
                            if (newc == oldc .and. newc == 2) cycle
                            call orbit%add_event(te, j, event_kind(oldc, newc, &
                                                                   j == hit%element .and. &
                                                                   impact), &
                                                 merge(0, newc, newc == 2), &
                                                 tangential_force(imnew, j, ye), &
                                                 dot_product(self%w(:, j), ye(n + 1:2*n)))
                        end associate
                    end do
                end do
                if (self%modes(imnew)%m == 0) call orbit%add_phase(te, ye, imnew)
            end if
            if (want_orbit .and. nevents > 0 .and. te - tp <= 1.0e-12_dp*self%period .and. &
                hit%element /= last_element) then
                if (orbit%simultaneous == 0) then
                    orbit%simultaneous_t = te
                    orbit%simultaneous_contacts = [last_element, hit%element]
                end if
                orbit%simultaneous = orbit%simultaneous + 1
            end if
            last_element = hit%element
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
            ! a new phase: its nonlinear steps start coarse, its events unarmed
            level = 0
            fresh = .true.
            call begin_phase()
            if (allocated(error)) return
        end do
        y = matmul(self%tbi, yb)
        y(nz + 1:) = self%exo(tend)
        ! back to the model's coordinates: mono = tbi_zz (phase flow x jac) tb_zz
        if (want_mono) call end_monodromy(self, self%modes(im), tend - tp, jac, mono)
        if (want_orbit) call close_phase(im, tend - tp)
        z1 = y(1:nz)

    contains

        !> A phase of mode im begins at t in state yb: tracked in modal coordinates when the
        !> mode allows it (no energy integrals asked: they step the grid).
        subroutine begin_phase()
            logical :: ok, may_track
            tracked = .false.
            if (self%modes(im)%m > 0) return
            may_track = .not. want_energy .and. self%use_track .and. self%nz >= track_min_states
            ! the modal form: the monodromy's propagators and the track
            if (want_mono .or. may_track) call ensure_modal(self, im)
            if (may_track) then
                if (track_usable(self, self%modes(im))) then
                    call start_track(self, self%modes(im), t, yb, trk, ok)
                    tracked = ok
                end if
            end if
            ! stepped on the ladder: built or retuned to this omega
            if (.not. tracked) call tune_ladder(self, self%modes(im), error)
        end subroutine begin_phase

        subroutine fail(message)
            character(len=*), intent(in) :: message
            call fatal_error(error, "reference: "//message, stickslip_stat%numerical)
        end subroutine fail

        !> A code as events report it: closed below an element's force floor is open.
        pure integer function reported(c)
            integer, intent(in) :: c
            reported = merge(2, c, c == code_unloaded)
        end function reported

        !> y' of mode m at yb: its linear dynamics and its nonlinear inputs.
        function rate(m, ya) result(yd)
            integer, intent(in) :: m
            real(dp), intent(in) :: ya(:)
            real(dp) :: yd(na), q(self%modes(m)%m), dq(self%modes(m)%m, na)
            yd = matmul(self%modes(m)%b, ya)
            if (self%modes(m)%m == 0) return
            call eval_inputs(self, code, self%modes(m)%in_elem, ya, dirs, self%modes(m)%fbal, &
                             self%modes(m)%fin, q, dq, self%modes(m)%b, self%modes(m)%gin)
            yd = yd + matmul(self%modes(m)%gin, q)
        end function rate

        !> One step of the nonlinear mode im from t (state yb): the collocation step at the
        !> current level, refined until its error estimate meets ode_tol (coarsened after a
        !> step 64 times below it); its events (the mode's rows and quadratic events, the
        !> elements' rows of the step) at the nodes and the end; without one the step is
        !> taken (energies, monodromy, a phase of the orbit, the slip directions), with one
        !> the state at the event (`found`: te, yeb, hit, fm set; the monodromy to te).
        subroutine nonlinear_step(found)
            logical, intent(out) :: found
            real(dp) :: sig, hnext, hlim, gv, gd
            real(dp), allocatable :: djac(:, :), yd(:)
            integer :: jj, kk
            found = .false.
            call nl_prepare(self, self%modes(im), error)
            if (allocated(error)) return
            ! the events of the step: rows of the step (a 2D slip's direction) and the mode's
            call rows%clear(na)
            do jj = 1, size(self%modes(im)%nl_elements)
                associate (e => self%cs%elements(self%modes(im)%nl_elements(jj))%e, &
                           jel => self%modes(im)%nl_elements(jj))
                    call e%step_rows(code(self%slot0(jel) + 1:self%slot_hi(jel)), &
                                     self%geom(jel), dirs(:, jel), rows)
                end associate
            end do
            if (fresh) call arm_events()
            ! a slip slowing down to rest: the step ends before its speed is predicted
            ! (linearly) to reach half its threshold, where its direction turns without limit
            hlim = tend - t
            if (rows%count > 0) yd = rate(im, yb)
            do kk = 1, rows%count
                if (.not. armed(3, kk)) cycle
                gv = gfun(3, kk, yb)
                gd = dot_product(rows%rows(:, kk), yd)
                if (gd < 0.0_dp) hlim = min(hlim, (gv - 0.5_dp*threshold(3, kk))/(-gd))
            end do
            do
                hnext = self%delta*0.5_dp**level
                if (hnext >= hlim*(1.0_dp - 1.0e-12_dp)) then
                    call nl_checked_step(self, self%modes(im), code, dirs, yb, level, want_mono, &
                                         st, h_given=hlim)
                else
                    call nl_checked_step(self, self%modes(im), code, dirs, yb, level, want_mono, &
                                         st)
                end if
                if (st%ok .and. st%err <= self%ode_tol) exit
                level = level + 1
                if (level > max_level) then
                    call fail("a nonlinear phase (a 2D slip) does not meet its tolerance "// &
                              "(ode_tol) even at the finest step")
                    return
                end if
            end do
            call step_events(found, sig)
            if (found) call land_on_event(sig)
            if (want_orbit) call orbit%add_phase(t, model_state(yb, t), im, &
                                                [st%b, reshape(dirs, [size(dirs)])])
            if (want_orbit) orbit%integration_error = orbit%integration_error + st%err
            if (.not. found) then
                if (want_energy) call nl_energy(st%h)
                if (want_mono) jac = matmul(st%jac(1:nz, 1:nz), jac)
                t = t + st%h
                yb = st%y1
                yb(nz + 1:) = self%se*self%exo(t)
                tp = t
                if (.not. all(ieee_is_finite(yb))) call fail("the state is not finite "// &
                                                             "(unbounded response)")
                ! the slip directions follow the slip
                do jj = 1, size(self%modes(im)%nl_elements)
                    associate (jel => self%modes(im)%nl_elements(jj))
                        call self%cs%elements(jel)%e%slip_direction( &
                            code(self%slot0(jel) + 1:self%slot_hi(jel)), self%geom(jel), &
                            reshape([real(dp) ::], [0, na]), yb, dirs(:, jel))
                    end associate
                end do
                if (st%err < self%ode_tol/128.0_dp .and. level > 0) level = level - 1
                return
            end if
            te = t + sig
            if (sig == st%h) then
                yeb = st%y1
            else
                yeb = nl_dense(self, self%modes(im), st, sig)
            end if
            yeb(nz + 1:) = self%se*self%exo(te)
            if (want_energy) call nl_energy(sig)
            if (want_mono) then
                if (sig == st%h) then
                    jac = matmul(st%jac(1:nz, 1:nz), jac)
                else
                    djac = nl_dense_jacobian(self, self%modes(im), st, sig)
                    jac = matmul(djac(1:nz, :), jac)
                end if
                fm = rate(im, yeb)
            end if
            tp = t
        end subroutine nonlinear_step

        !> The event at sig into the step, located on the dense output (whose error inside a
        !> step is of a lower order than at its end): the step is taken again with the
        !> length sig, corrected by Newton's method on the event function at the end (at
        !> most 4 times, until the correction is below 4 ulps of the step), so that the
        !> state at the event is a step's end. Kept as it was if a retaken step fails.
        subroutine land_on_event(sig)
            real(dp), intent(inout) :: sig
            type(nl_step_t) :: st2
            real(dp) :: gv, gd, ds, c(na)
            integer :: iter
            do iter = 1, 4
                call nl_step(self, self%modes(im), code, dirs, yb, level, want_mono, st2, &
                             h_given=sig)
                if (.not. st2%ok) return
                st2%err = st%err
                st = st2
                gv = efun(hit%kind, hit%index, st%y1)
                c = gradient(hit%kind, hit%index, st%y1)
                gd = dot_product(c, rate(im, st%y1))
                if (.not. (gd /= 0.0_dp)) exit
                ds = -gv/gd
                if (abs(ds) <= 4.0_dp*epsilon(1.0_dp)*sig .or. .not. (sig + ds > 0.0_dp)) exit
                sig = sig + ds
            end do
            hit%c = gradient(hit%kind, hit%index, st%y1)
        end subroutine land_on_event

        !> The first event of the step: the earliest zero of the step's rows and the
        !> mode's events, bracketed between the nodes and the end (c_i h, h) and located
        !> by bisection on the dense output (to 4 ulps of the step). An event function
        !> counts its zero once it has been above 2e-9 of its scale in the phase (armed);
        !> before that, only a fall below -1e-9 of its scale (a slip that starts from
        !> rest, its speed at roundoff level, does not stop at once).
        subroutine step_events(found, sig)
            logical, intent(out) :: found
            real(dp), intent(out) :: sig
            real(dp) :: theta(nodes + 1), lo, hi, best, sl, sh, g
            real(dp), allocatable :: ys(:, :)
            integer :: p, kk, kind, iter
            found = .false.
            sig = huge(1.0_dp)
            theta(1:nodes) = node
            theta(nodes + 1) = 1.0_dp
            allocate (ys(na, nodes + 1))
            ys(:, 1:nodes) = st%ynode
            ys(:, nodes + 1) = st%y1
            best = huge(1.0_dp)
            do p = 1, nodes + 1
                do kind = 1, 3
                    do kk = 1, nevents_of(kind)
                        if (.not. (efun(kind, kk, ys(:, p)) <= 0.0_dp)) then
                            if (gfun(kind, kk, ys(:, p)) > 2.0_dp*threshold(kind, kk)) &
                                armed(kind, kk) = .true.
                            cycle
                        end if
                        ! the zero in (theta(p - 1) h, theta(p) h]
                        sl = 0.0_dp
                        if (p > 1) sl = theta(p - 1)*st%h
                        sh = theta(p)*st%h
                        if (sl >= best) cycle
                        lo = sl
                        hi = sh
                        do iter = 1, 200
                            if (hi - lo <= 4.0_dp*epsilon(1.0_dp)*st%h) exit
                            g = efun(kind, kk, nl_dense(self, self%modes(im), st, &
                                                         0.5_dp*(lo + hi)))
                            if (g > 0.0_dp) then
                                lo = 0.5_dp*(lo + hi)
                            else
                                hi = 0.5_dp*(lo + hi)
                            end if
                        end do
                        if (hi < best) then
                            best = hi
                            found = .true.
                            call set_hit(kind, kk)
                        end if
                    end do
                end do
                if (found) exit
            end do
            if (found) then
                sig = best
                hit%c = gradient(hit%kind, hit%index, nl_dense(self, self%modes(im), st, sig))
            end if
        end subroutine step_events

        !> Arm the events of a new phase: those above 2e-9 of their scale at its start.
        subroutine arm_events()
            integer :: kind, kk
            if (allocated(armed)) deallocate (armed)
            allocate (armed(3, max(nevents_of(1), nevents_of(2), nevents_of(3))))
            do kind = 1, 3
                do kk = 1, nevents_of(kind)
                    armed(kind, kk) = gfun(kind, kk, yb) > 2.0_dp*threshold(kind, kk)
                end do
            end do
            fresh = .false.
        end subroutine arm_events

        !> The event function as it counts: g + its threshold while not armed; armed, g,
        !> or for a row of the step (a 2D slip's speed) g - its threshold: the slip stops
        !> when its speed falls to 1e-9 of its scale (the element sets the scale; the slip
        !> direction turns without limit as the speed goes to zero; what is left of the
        !> slip is removed by the projection onto the stuck mode's constraints).
        real(dp) function efun(kind, kk, ya)
            integer, intent(in) :: kind, kk
            real(dp), intent(in) :: ya(:)
            efun = gfun(kind, kk, ya)
            if (.not. armed(kind, kk)) then
                efun = efun + threshold(kind, kk)
            else if (kind == 3) then
                efun = efun - threshold(kind, kk)
            end if
        end function efun

        !> 1e-9 of the scale of event function kk of a kind.
        real(dp) function threshold(kind, kk)
            integer, intent(in) :: kind, kk
            select case (kind)
            case (1)
                threshold = 1.0e-9_dp*self%modes(im)%row_scale(kk)
            case (2)
                threshold = 1.0e-9_dp*self%modes(im)%q_scale(kk)
            case default
                threshold = 1.0e-9_dp*rows%scale(kk)
            end select
        end function threshold

        integer function nevents_of(kind)
            integer, intent(in) :: kind
            select case (kind)
            case (1)
                nevents_of = size(self%modes(im)%row_scale)
            case (2)
                nevents_of = size(self%modes(im)%qc)
            case default
                nevents_of = rows%count
            end select
        end function nevents_of

        real(dp) function gfun(kind, kk, ya)
            integer, intent(in) :: kind, kk
            real(dp), intent(in) :: ya(:)
            associate (md => self%modes(im))
                select case (kind)
                case (1)
                    gfun = dot_product(md%rows(:, kk), ya)
                case (2)
                    gfun = dot_product(ya, matmul(md%qmat(:, :, kk), ya)) + md%qc(kk)
                case default
                    gfun = dot_product(rows%rows(:, kk), ya)
                end select
            end associate
        end function gfun

        function gradient(kind, kk, ya) result(c)
            integer, intent(in) :: kind, kk
            real(dp), intent(in) :: ya(:)
            real(dp) :: c(na)
            associate (md => self%modes(im))
                select case (kind)
                case (1)
                    c = md%rows(:, kk)
                case (2)
                    c = 2.0_dp*matmul(md%qmat(:, :, kk), ya)
                case default
                    c = rows%rows(:, kk)
                end select
            end associate
        end function gradient

        subroutine set_hit(kind, kk)
            integer, intent(in) :: kind, kk
            hit%kind = kind
            hit%index = kk
            associate (md => self%modes(im))
                select case (kind)
                case (1)
                    hit%element = md%row_element(kk)
                    hit%slot = md%row_slot(kk)
                    hit%action = md%row_action(kk)
                case (2)
                    hit%element = md%q_element(kk)
                    hit%slot = md%q_slot(kk)
                    hit%action = md%q_action(kk)
                case default
                    ! a row of the step: its element is the nonlinear one that gave it
                    hit%element = step_row_element(kk)
                    hit%slot = self%slot0(hit%element) + rows%slot(kk)
                    hit%action = rows%action(kk)
                end select
            end associate
        end subroutine set_hit

        !> The element of row kk of the step (the elements' rows in their order).
        integer function step_row_element(kk) result(jel)
            integer, intent(in) :: kk
            type(event_list_t) :: probe
            integer :: q2
            jel = self%modes(im)%nl_elements(1)
            call probe%clear(na)
            do q2 = 1, size(self%modes(im)%nl_elements)
                jel = self%modes(im)%nl_elements(q2)
                call self%cs%elements(jel)%e%step_rows( &
                    code(self%slot0(jel) + 1:self%slot_hi(jel)), self%geom(jel), &
                    dirs(:, jel), probe)
                if (probe%count >= kk) return
            end do
        end function step_row_element

        !> The energies over [t, t + s] of the step (Gauss-Legendre at the collocation
        !> nodes of that interval, on the dense output and the input polynomial).
        subroutine nl_energy(s)
            real(dp), intent(in) :: s
            real(dp) :: yg(na), ygb(na), power, fric, rch(self%cs%nchannel), &
                        vch(self%cs%nchannel), sg
            integer :: ig
            do ig = 1, nodes
                sg = node(ig)*s
                if (s == st%h) then
                    ygb = st%ynode(:, ig)
                else
                    ygb = nl_dense(self, self%modes(im), st, sg)
                end if
                yg = matmul(self%tbi, ygb)
                yg(nz + 1:) = self%exo(t + sg)
                power = dot_product(matmul(self%hf(:, nz + 1:), yg(nz + 1:)), yg(n + 1:2*n))
                orbit%work_forcing = orbit%work_forcing + s*gauss_weight(ig)*power
                orbit%work_gross = orbit%work_gross + s*gauss_weight(ig)*abs(power)
                orbit%diss_damping = orbit%diss_damping + s*gauss_weight(ig)* &
                    dot_product(yg(n + 1:2*n), matmul(self%damping, yg(n + 1:2*n)))
                rch = matmul(self%modes(im)%force, yg) + &
                      matmul(self%modes(im)%fin, nl_input_at(self%modes(im), st, sg))
                vch = matmul(yg(n + 1:2*n), self%d)
                fric = dot_product(rch, vch)
                orbit%diss_friction = orbit%diss_friction - s*gauss_weight(ig)*fric
            end do
        end subroutine nl_energy

        !> The model-coordinates state of the balanced one ya at time tt.
        function model_state(ya, tt) result(ym)
            real(dp), intent(in) :: ya(:), tt
            real(dp) :: ym(na)
            ym = matmul(self%tbi, ya)
            ym(nz + 1:) = self%exo(tt)
        end function model_state

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
    !> the internal states s(ng, n_s). With `count`, only the first `count` samples at or
    !> after the orbit's start (an orbit recorded over a part of the period; the other rows
    !> are not set). Errors (stat numerical): the state is not finite.
    subroutine sample(self, orbit, ng, x, v, r, error, state, s, count, first)
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
        !> Samples to compute (default ng).
        integer, intent(in), optional :: count
        !> The first sample computed is row first + 1 (0 <= first < ng).
        integer, intent(out), optional :: first
        real(dp) :: y(self%na), yb(self%na), tk, dt, nl_t, nl_y(self%na)
        real(dp), allocatable :: step(:, :, :), edt(:, :, :), edt1(:, :)
        type(track_t) :: trk
        logical :: tracked
        integer :: nl_p, nl_mode
        logical, allocatable :: have_step(:)
        integer :: k, kk, p, kfirst, last_p, n, stat, im, nk
        n = self%n
        nk = ng
        if (present(count)) nk = min(max(count, 0), ng)
        dt = self%period/ng
        ! the first sample at or after t0; samples before t0 belong to the end of the period
        kfirst = ceiling(orbit%t0/dt - 1.0e-12_dp)
        if (present(first)) first = modulo(kfirst, ng)
        p = 1
        last_p = 0
        ! exp(b dt) of each mode met, built on first use
        allocate (step(self%na, self%na, self%nmodes), have_step(self%nmodes))
        have_step = .false.
        nl_p = 0
        nl_mode = 0
        nl_t = 0.0_dp
        do kk = 0, nk - 1
            ! the samples from the first at or after t0 on, by index (a time test cannot
            ! tell t0 from a sample within roundoff of it)
            k = modulo(kfirst + kk, ng)
            tk = (kfirst + kk)*dt
            do while (p < orbit%nphase)
                if (orbit%phase_t(p + 1) > tk) exit
                p = p + 1
            end do
            im = orbit%phase_mode(p)
            associate (md => self%modes(im))
                if (md%m > 0) then
                    ! a step of a nonlinear phase: its dense output and input polynomial
                    call nonlinear_sample()
                    if (allocated(error)) return
                    cycle
                end if
                if (p /= last_p) then
                    yb = matmul(self%tb, orbit%phase_y(:, p))
                    ! a phase the period map tracked in modal coordinates is sampled on them
                    tracked = .false.
                    if (self%use_track .and. md%modal%status == 1 .and. md%modal%coef_ok .and. &
                        md%modal%coef_omega == self%omega) then
                        call start_track(self, md, orbit%phase_t(p), yb, trk, tracked)
                    end if
                    if (tracked) then
                        y = track_state(self, md, trk, tk)
                    else if (md%omega_ladder == self%omega) then
                        call propagate(md, self%delta, tk - orbit%phase_t(p), yb, y)
                    else
                        ! its ladder not tuned to this omega (not stepped on it)
                        call expm(md%b*(tk - orbit%phase_t(p)), edt1, stat)
                        y = matmul(edt1, yb)
                    end if
                    last_p = p
                else if (tracked) then
                    y = track_state(self, md, trk, tk)
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
                call store(matmul(md%force, y))
            end associate
        end do

    contains

        !> Sample k of phase p, a step of a nonlinear mode: the end of a collocation step
        !> from its start to the sample, or from the previous sample of the phase
        !> (nl_state_at; the dense output [exp(sigma A) (y_p, b_p)]_y, A the mode's augmented
        !> dynamics, if it fails), channel forces with the law's inputs at that state (the
        !> slip memories of the step recorded after b_p).
        subroutine nonlinear_sample()
            real(dp), allocatable :: z(:), z1(:), mem(:, :), dq(:, :)
            real(dp) :: sg, qv(self%modes(im)%m)
            integer :: nb
            logical :: ok
            associate (md => self%modes(im))
                nb = size(md%aug, 1) - self%na
                allocate (z(size(md%aug, 1)), z1(size(md%aug, 1)), dq(md%m, self%na))
                z(1:self%na) = matmul(self%tb, orbit%phase_y(:, p))
                z(self%na + 1:) = orbit%phase_b(1:nb, p)
                mem = reshape(orbit%phase_b(nb + 1:nb + 3*self%nc, p), [3, self%nc])
                sg = tk - orbit%phase_t(p)
                ! the end of a step of length sg from the phase's start, or of one sample
                ! step dt from the previous sample in the same phase (its exponentials kept);
                ! the dense output if that step fails
                if (p == nl_p .and. abs(tk - nl_t - dt) <= 1.0e-9_dp*dt) then
                    if (nl_mode /= im) then
                        call nl_exponentials(md, dt, edt)
                        nl_mode = im
                    end if
                    call nl_state_at(self, md, md%code, mem, nl_y, dt, z1(1:self%na), ok, edt)
                else
                    call nl_state_at(self, md, md%code, mem, z(1:self%na), sg, &
                                     z1(1:self%na), ok)
                end if
                if (.not. ok) call propagate_matrix(md%aug, md%aug_ladder, md%aug_nl, &
                                                    self%delta, sg, z, z1)
                nl_p = p
                nl_t = tk
                nl_y = z1(1:self%na)
                y = matmul(self%tbi, z1(1:self%na))
                if (.not. all(ieee_is_finite(y))) then
                    call fatal_error(error, "reference: the state is not finite while "// &
                                     "sampling", stickslip_stat%numerical)
                    return
                end if
                y(2*n + self%ns + 1:) = self%exo(tk)
                call eval_inputs(self, md%code, md%in_elem, z1(1:self%na), mem, md%fbal, md%fin, &
                                 qv, dq, md%b, md%gin)
                call store(matmul(md%force, y) + matmul(md%fin, qv))
            end associate
            last_p = 0
        end subroutine nonlinear_sample

        !> Sample k + 1: the state y of mode im, its channel forces rk.
        subroutine store(rk)
            real(dp), intent(in) :: rk(:)
            integer :: j
            x(k + 1, :) = y(1:n)
            v(k + 1, :) = y(n + 1:2*n)
            r(k + 1, :) = rk
            if (present(s)) s(k + 1, :) = y(2*n + 1:self%nz)
            if (present(state)) then
                do j = 1, self%nc
                    state(k + 1, j) = self%state_of(im, j)
                end do
            end if
        end subroutine store
    end subroutine sample
end module stickslip_flow
