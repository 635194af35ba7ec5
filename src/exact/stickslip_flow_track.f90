!> A linear phase of the exact flow in the modal coordinates of its contact mode: the state
!> and the event functions at any time of the phase in O(n) operations, and the earliest
!> event of a grid step located on them (stickslip_flow's period map, for the linear modes
!> whose modal form is usable; doc/methods.md, "Floquet stability").
!>
!> In a linear mode the balanced state obeys z' = B z + F y_e, y_e = se exo(t) the
!> exosystem of the harmonic forcing (stickslip_flow_modes). With the modal form B Pi =
!> V Lambda W (stickslip_flow_modal) and the state on the mode's velocity constraints, xi = W
!> z obeys xi' = Lambda xi + W F y_e, whose solution over a phase from t_a is
!>     xi(t_a + tau) = exp(Lambda tau) eta + tau phi_1(Lambda tau) d_0 + P y_e(t_a + tau),
!> P (n_z x n_e) the periodic particular solution of the harmonic inputs (Lambda P - P E =
!> -W F on the harmonic columns, E the exosystem's rotation; a 2 x 2 complex solve per
!> eigenvalue and harmonic), d_0 the constant input and eta = W z_a - P y_e(t_a). An event
!> function r . y is then rho . (exp(Lambda tau) eta + tau phi_1 d_0) + q . y_e(t), rho = V^T
!> r_z and q = P^T rho + r_e: O(n_z + n_e) per row and time instead of a propagation of the
!> augmented state (dozens of matrix-vector products of order n_a), and its slopes by
!> powers of Lambda and E. The events are bracketed and located as stickslip_flow_events'
!> find_event does (the same rules: rows ending a step non-positive in the order of their
!> Hermite estimates, dips between two positive values, ties to the lower row), to a few
!> ulps of the step.
!> Knows nothing of files; the caller keeps one track per thread.
module stickslip_flow_track
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_dense_products, only: mat_mul, mat_vec
    use stickslip_lapack, only: dgemm
    use stickslip_flow_modes, only: mode_t, flow_modes_t
    use stickslip_flow_modal, only: off_constraints, build_modal_form, on_constraints
    use stickslip_expm, only: expm
    use stickslip_hash, only: hash_t
    use stickslip_flow_events, only: event_hit_t, hermite_root, root_bracket_t, pop_earliest, &
        dip_samples, dip_bracket
    implicit none
    private
    public :: track_t, ensure_modal, track_usable, start_track, track_state, track_find_event

    !> One linear phase: its start t_a [s], eta, and the values and slopes of the mode's
    !> event rows at the last grid point (reused as the next step's start).
    type :: track_t
        real(dp) :: ta = 0.0_dp
        real(dp), allocatable :: eta(:)
        real(dp) :: tlast = -huge(1.0_dp)
        real(dp), allocatable :: glast(:), dlast(:)
        !> exp(lambda_j (tez - t_a)) at the last grid point tez (all_rows).
        real(dp) :: tez = -huge(1.0_dp)
        complex(dp), allocatable :: ez(:)
    end type track_t

contains

    !> Mode im's modal form (stickslip_flow_modal), made on first use: copied from a mode
    !> with the same state block and constraint directions (modes that differ only in a slip
    !> direction, i.e. in their inputs) when there is one, else computed (checked against
    !> exp(B delta): the ladder's when built, else a matrix exponential of the state block);
    !> and, when usable, its track coefficients at the flow's omega. Nothing for a nonlinear
    !> mode.
    subroutine ensure_modal(self, im)
        !> The dynamics; mode im's form and coefficients are set.
        class(flow_modes_t), intent(inout) :: self
        !> The mode.
        integer, intent(in) :: im
        real(dp), allocatable :: ed(:, :)
        type(hash_t) :: h
        integer :: nz, k, stat
        nz = self%nz
        if (self%modes(im)%m /= 0) return
        if (self%modes(im)%modal%status == 0) then
            associate (md => self%modes(im))
                call h%add(md%b(1:nz, 1:nz))
                call h%add(md%ctm)
                md%zkey = h%value()
                if (md%zkey == 0) md%zkey = 1
            end associate
            do k = 1, self%nmodes
                if (k == im) cycle
                associate (tw => self%modes(k), md => self%modes(im))
                    if (tw%zkey /= md%zkey .or. tw%modal%status == 0 .or. tw%m /= 0) cycle
                    if (any(shape(tw%ctm) /= shape(md%ctm))) cycle
                    if (any(tw%b(1:nz, 1:nz) /= md%b(1:nz, 1:nz))) cycle
                    if (any(tw%ctm /= md%ctm)) cycle
                    md%modal%status = tw%modal%status
                    if (tw%modal%status == 1) then
                        md%modal%v = tw%modal%v
                        md%modal%w = tw%modal%w
                        md%modal%re = tw%modal%re
                        md%modal%im = tw%modal%im
                    end if
                    exit
                end associate
            end do
        end if
        associate (md => self%modes(im))
            if (md%modal%status == 0) then
                if (allocated(md%ladder)) then
                    call build_modal_form(md%modal, md%b(1:nz, 1:nz), md%ctm, self%n, &
                                          self%delta, md%ladder(1:nz, 1:nz, 0))
                else
                    allocate (ed(nz, nz))
                    call expm(md%b(1:nz, 1:nz)*self%delta, ed, stat)
                    md%modal%status = -1
                    if (stat == 0) call build_modal_form(md%modal, md%b(1:nz, 1:nz), md%ctm, &
                                                         self%n, self%delta, ed)
                end if
            end if
            if (md%modal%status /= 1) return
            ! coef_omega = huge: the forcing is off the constraints, never tracked
            if (md%modal%coef_omega == huge(1.0_dp)) return
        end associate
        if (self%modes(im)%modal%coef_omega /= self%omega) call prepare(self, im)
    end subroutine ensure_modal

    !> Whether the phases of mode md can be tracked in modal coordinates at the flow's omega
    !> (after ensure_modal): a linear mode without quadratic events, its modal form usable,
    !> the forcing on its constraints and no undamped resonance of the forcing's harmonics.
    logical function track_usable(self, md) result(ok)
        !> The dynamics md belongs to.
        class(flow_modes_t), intent(in) :: self
        !> The contact mode.
        type(mode_t), intent(in) :: md
        ok = md%m == 0 .and. size(md%qc) == 0 .and. md%modal%status == 1 .and. &
             md%modal%coef_ok .and. md%modal%coef_omega == self%omega
    end function track_usable

    !> The mode's coefficients at the flow's omega: W F, rho = V^T r_z, the particular
    !> solution P and q = P^T rho + r_e.
    subroutine prepare(self, im)
        class(flow_modes_t), intent(inout) :: self
        integer, intent(in) :: im
        real(dp), allocatable :: f(:, :)
        complex(dp) :: r1, r2, x1, x2, det, s
        real(dp) :: a, b, hw, scale
        integer :: nz, ne, k, j, ic, is
        nz = self%nz
        ne = self%ne
        associate (md => self%modes(im), mf => self%modes(im)%modal)
            mf%coef_omega = self%omega
            mf%coef_ok = .false.
            if (.not. allocated(mf%wd)) then
                f = md%b(1:nz, nz + 1:nz + ne)
                if (off_constraints(md%ctm, self%n, f) > on_constraints) then
                    ! never usable: the forcing leaves the constraints
                    mf%coef_omega = huge(1.0_dp)
                    return
                end if
                mf%wd = mat_mul(mf%w, f)
                allocate (mf%inv_lam(nz), mf%edelta(nz))
                do j = 1, nz
                    ! exp(lambda delta) of each eigenvalue (a pair's at its first entry)
                    mf%edelta(j) = exp(cmplx(mf%re(j), max(mf%im(j), 0.0_dp), dp)*self%delta)
                    mf%inv_lam(j) = 0.0_dp
                    if (mf%re(j) /= 0.0_dp .or. mf%im(j) /= 0.0_dp) &
                        mf%inv_lam(j) = 1.0_dp/cmplx(mf%re(j), mf%im(j), dp)
                end do
                mf%rho_t = mat_mul(transpose(md%rows(1:nz, :)), mf%v)
            end if
            if (allocated(mf%pm)) deallocate (mf%pm)
            allocate (mf%pm(nz, ne))
            mf%pm = 0.0_dp
            do k = 1, size(self%eharm)
                ic = 2*k
                is = 2*k + 1
                hw = self%eharm(k)*self%omega
                j = 1
                do while (j <= nz)
                    if (mf%im(j) > 0.0_dp .and. j < nz) then
                        ! (Lambda - i h w) X = -(d_c - i d_s), X = A - i B, on the pair
                        a = mf%re(j)
                        b = mf%im(j)
                        s = cmplx(a, -hw, dp)
                        det = s*s + b*b
                        scale = (abs(a) + hw + b)**2
                        if (.not. abs(det) > 1.0e-12_dp*scale) return
                        r1 = -cmplx(mf%wd(j, ic), -mf%wd(j, is), dp)
                        r2 = -cmplx(mf%wd(j + 1, ic), -mf%wd(j + 1, is), dp)
                        x1 = (s*r1 - b*r2)/det
                        x2 = (s*r2 + b*r1)/det
                        mf%pm(j, ic) = real(x1, dp)
                        mf%pm(j, is) = -aimag(x1)
                        mf%pm(j + 1, ic) = real(x2, dp)
                        mf%pm(j + 1, is) = -aimag(x2)
                        j = j + 2
                    else
                        s = cmplx(mf%re(j), -hw, dp)
                        if (.not. abs(s) > 1.0e-12_dp*(abs(mf%re(j)) + hw)) return
                        x1 = -cmplx(mf%wd(j, ic), -mf%wd(j, is), dp)/s
                        mf%pm(j, ic) = real(x1, dp)
                        mf%pm(j, is) = -aimag(x1)
                        j = j + 1
                    end if
                end do
            end do
            mf%q_t = mat_mul(mf%rho_t, mf%pm) + transpose(md%rows(nz + 1:nz + ne, :))
            mf%coef_ok = all(ieee_is_finite(mf%pm)) .and. all(ieee_is_finite(mf%q_t))
        end associate
    end subroutine prepare

    !> Start a phase of mode md (track_usable) at t [s] in the balanced augmented state yb
    !> (on the mode's constraints). ok is false when the state is off them.
    subroutine start_track(self, md, t, yb, trk, ok)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        real(dp), intent(in) :: t, yb(:)
        type(track_t), intent(inout) :: trk
        logical, intent(out) :: ok
        real(dp) :: zz(self%nz, 1)
        zz(:, 1) = yb(1:self%nz)
        ok = off_constraints(md%ctm, self%n, zz) <= on_constraints
        if (.not. ok) return
        trk%ta = t
        trk%eta = mat_vec(md%modal%w, yb(1:self%nz)) - mat_vec(md%modal%pm, yb(self%nz + 1:))
        trk%tlast = -huge(1.0_dp)
        trk%tez = -huge(1.0_dp)
    end subroutine start_track

    !> The modal part xi(t) - P y_e(t) at t [s] differentiated `order` times (0 or 1) in
    !> u(:, 1) and order + 1 times in u(:, 2): the exponentials and trigonometric functions
    !> of each eigenvalue once for both.
    subroutine homogeneous(self, md, trk, t, order, u, ez_in, ez_out)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        type(track_t), intent(in) :: trk
        real(dp), intent(in) :: t
        integer, intent(in) :: order
        real(dp), intent(out) :: u(:, :)
        !> exp(lambda_j (t - t_a)) when the caller has it (a grid step's recurrence), and
        !> the values used (entry j of an eigenvalue or of a pair's first).
        complex(dp), intent(in), optional :: ez_in(:)
        complex(dp), intent(out), optional :: ez_out(:)
        real(dp) :: tau, g, a, b, p, q, d0p, d0q, u0, u1
        complex(dp) :: z, lam, w0, w1, ez, dw
        integer :: j, nz
        nz = self%nz
        tau = t - trk%ta
        associate (mf => md%modal)
            j = 1
            do while (j <= nz)
                d0p = mf%wd(j, 1)*self%se
                if (mf%im(j) > 0.0_dp .and. j < nz) then
                    ! a pair, on w = p - i q: exp(lambda tau) eta + (exp(lambda tau) - 1) /
                    ! lambda d_0, and its derivatives lambda exp eta + exp d_0, ...
                    a = mf%re(j)
                    b = mf%im(j)
                    d0q = mf%wd(j + 1, 1)*self%se
                    if (present(ez_in)) then
                        ez = ez_in(j)
                    else
                        g = exp(a*tau)
                        ez = cmplx(g*cos(b*tau), g*sin(b*tau), dp)
                    end if
                    if (present(ez_out)) ez_out(j) = ez
                    lam = cmplx(a, b, dp)
                    dw = cmplx(d0p, -d0q, dp)
                    w0 = ez*cmplx(trk%eta(j), -trk%eta(j + 1), dp)
                    w1 = lam*w0 + ez*dw
                    if (order == 0) then
                        z = lam*tau
                        if ((abs(a) + b)*tau < 1.0e-3_dp) then
                            w0 = w0 + tau*(1.0_dp + z/2.0_dp + z*z/6.0_dp + z**3/24.0_dp + &
                                           z**4/120.0_dp)*dw
                        else
                            ! (exp(lambda tau) - 1) / lambda: the cancellation costs at most
                            ! eps |d_0 / lambda|, roundoff of the quasi-static response
                            w0 = w0 + (ez - 1.0_dp)*mf%inv_lam(j)*dw
                        end if
                    else
                        w0 = w1
                        w1 = lam*w1
                    end if
                    u(j, 1) = real(w0, dp)
                    u(j + 1, 1) = -aimag(w0)
                    u(j, 2) = real(w1, dp)
                    u(j + 1, 2) = -aimag(w1)
                    j = j + 2
                else
                    a = mf%re(j)
                    if (present(ez_in)) then
                        g = real(ez_in(j), dp)
                    else
                        g = exp(a*tau)
                    end if
                    if (present(ez_out)) ez_out(j) = cmplx(g, 0.0_dp, dp)
                    p = g*trk%eta(j)
                    u1 = a*p + g*d0p
                    if (order == 0) then
                        if (abs(a*tau) < 1.0e-3_dp) then
                            q = tau*(1.0_dp + a*tau/2.0_dp + (a*tau)**2/6.0_dp + &
                                     (a*tau)**3/24.0_dp + (a*tau)**4/120.0_dp)
                        else
                            q = (g - 1.0_dp)/a
                        end if
                        u0 = p + q*d0p
                    else
                        u0 = u1
                        u1 = a*u1
                    end if
                    u(j, 1) = u0
                    u(j, 2) = u1
                    j = j + 1
                end if
            end do
        end associate
    end subroutine homogeneous

    !> The exosystem's state se exo(t) differentiated `order` times in e(:, 1) and order + 1
    !> times in e(:, 2).
    subroutine exo_part(self, t, order, e)
        class(flow_modes_t), intent(in) :: self
        real(dp), intent(in) :: t
        integer, intent(in) :: order
        real(dp), intent(out) :: e(:, :)
        integer :: m
        e(:, 1) = self%se*self%exo(t)
        do m = 1, order
            e(:, 1) = exo_rate(e(:, 1))
        end do
        e(:, 2) = exo_rate(e(:, 1))

    contains

        !> The exosystem's rate E y_e.
        function exo_rate(y) result(r)
            real(dp), intent(in) :: y(:)
            real(dp) :: r(size(y)), hw
            integer :: k
            r(1) = 0.0_dp
            do k = 1, size(self%eharm)
                hw = self%eharm(k)*self%omega
                r(2*k) = -hw*y(2*k + 1)
                r(2*k + 1) = hw*y(2*k)
            end do
        end function exo_rate
    end subroutine exo_part

    !> The balanced augmented state of the phase at t [s].
    function track_state(self, md, trk, t) result(y)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The phase's mode.
        type(mode_t), intent(in) :: md
        !> The phase.
        type(track_t), intent(in) :: trk
        !> Time [s].
        real(dp), intent(in) :: t
        real(dp) :: y(self%na), ye(self%ne, 2), u(self%nz, 2)
        call exo_part(self, t, 0, ye)
        call homogeneous(self, md, trk, t, 0, u)
        y(1:self%nz) = mat_vec(md%modal%v, u(:, 1) + mat_vec(md%modal%pm, ye(:, 1)))
        y(self%nz + 1:) = ye(:, 1)
    end function track_state

    !> All event rows of the mode at t: values (order 0) in g(:, 1) and slopes in g(:, 2).
    !> One grid step after the last call (t = trk%tez + delta) the exponentials come from
    !> the last ones times exp(lambda delta) (roundoff ~ steps x eps: the grid only
    !> brackets; events are located on direct evaluations).
    subroutine all_rows(self, md, trk, t, g)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        type(track_t), intent(inout) :: trk
        real(dp), intent(in) :: t
        real(dp), intent(out) :: g(:, :)
        real(dp) :: ye(self%ne, 2), u(self%nz, 2)
        call exo_part(self, t, 0, ye)
        if (.not. allocated(trk%ez)) allocate (trk%ez(self%nz))
        if (trk%tez > -huge(1.0_dp) .and. abs(t - trk%tez - self%delta) <= &
            1.0e-9_dp*self%delta) then
            trk%ez = trk%ez*md%modal%edelta
            call homogeneous(self, md, trk, t, 0, u, ez_in=trk%ez)
        else
            call homogeneous(self, md, trk, t, 0, u, ez_out=trk%ez)
        end if
        trk%tez = t
        ! BLAS directly: the products are below mat_mul's threshold, and the grid's hot spot
        call dgemm('N', 'N', size(g, 1), 2, self%nz, 1.0_dp, md%modal%rho_t, size(g, 1), u, &
                   self%nz, 0.0_dp, g, size(g, 1))
        call dgemm('N', 'N', size(g, 1), 2, self%ne, 1.0_dp, md%modal%q_t, size(g, 1), ye, &
                   self%ne, 1.0_dp, g, size(g, 1))
    end subroutine all_rows

    !> Row col of the mode at t, differentiated `order` times (0 or 1; g) and once more (dg).
    subroutine one_row(self, md, trk, col, t, order, g, dg)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        type(track_t), intent(in) :: trk
        integer, intent(in) :: col, order
        real(dp), intent(in) :: t
        real(dp), intent(out) :: g, dg
        real(dp) :: ye(self%ne, 2), u(self%nz, 2)
        call exo_part(self, t, order, ye)
        call homogeneous(self, md, trk, t, order, u)
        g = dot_product(md%modal%rho_t(col, :), u(:, 1)) + dot_product(md%modal%q_t(col, :), &
                                                                        ye(:, 1))
        dg = dot_product(md%modal%rho_t(col, :), u(:, 2)) + dot_product(md%modal%q_t(col, :), &
                                                                         ye(:, 2))
    end subroutine one_row

    !> The value of row col at t.
    real(dp) function row_value(self, md, trk, col, t) result(g)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        type(track_t), intent(in) :: trk
        integer, intent(in) :: col
        real(dp), intent(in) :: t
        real(dp) :: dg
        call one_row(self, md, trk, col, t, 0, g, dg)
    end function row_value

    !> The earliest event in (ta, tb] of the phase trk of mode md (tb - ta at most a grid
    !> step), as stickslip_flow_events' find_event: found, its time te [s], the balanced
    !> state ye there and the event (hit).
    subroutine track_find_event(self, md, trk, ta, tb, found, te, ye, hit)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The phase's mode.
        type(mode_t), intent(in) :: md
        !> The phase; its values at tb are kept for the next step.
        type(track_t), intent(inout) :: trk
        !> The step [s].
        real(dp), intent(in) :: ta, tb
        !> Whether an event lies in (ta, tb].
        logical, intent(out) :: found
        !> The event's time [s] and state.
        real(dp), intent(out) :: te, ye(:)
        !> The event.
        type(event_hit_t), intent(out) :: hit
        ! automatic arrays: no allocation per grid step
        real(dp) :: ga(size(md%row_scale)), da(size(md%row_scale)), gb(size(md%row_scale)), &
                    db(size(md%row_scale)), est(size(md%row_scale)), gab(size(md%row_scale), 2)
        integer :: cand(size(md%row_scale))
        real(dp) :: h, best, tau, thr, tmin
        integer :: nrow, col, k
        found = .false.
        h = tb - ta
        nrow = size(md%row_scale)
        if (trk%tlast == ta .and. allocated(trk%glast)) then
            ga = trk%glast
            da = trk%dlast
        else
            call all_rows(self, md, trk, ta, gab)
            ga = gab(:, 1)
            da = gab(:, 2)
        end if
        call all_rows(self, md, trk, tb, gab)
        gb = gab(:, 1)
        db = gab(:, 2)
        trk%tlast = tb
        trk%glast = gb
        trk%dlast = db
        best = huge(1.0_dp)
        k = 0
        do col = 1, nrow
            if (gb(col) <= 0.0_dp) then
                k = k + 1
                cand(k) = col
                est(k) = 0.0_dp
                if (ga(col) > 0.0_dp) est(k) = max(hermite_root(ga(col), da(col), gb(col), &
                                                                db(col), h), 0.0_dp)
            else
                thr = 1.0e-9_dp*md%row_scale(col)*self%omega
                if (ta == trk%ta .and. abs(ga(col)) <= 1.0e-9_dp*md%row_scale(col) .and. &
                    abs(da(col)) <= thr) then
                    ! a row at zero and flat at the phase's start (its element switched as its
                    ! rate vanished): a dip below zero soon after is sampled
                    tau = fresh_dip(self, md, trk, col, ta, h, ga(col))
                    if (tau < best) then
                        best = tau
                        found = .true.
                        hit%index = col
                    end if
                else if (ga(col) > 0.0_dp .and. da(col) < -thr .and. db(col) > thr) then
                    ! a dip between two positive values: its minimum, then the root before it
                    tmin = crossing(self, md, trk, col, 1, -1.0_dp, ta, 0.0_dp, h, -da(col), &
                                    -db(col))
                    if (row_value(self, md, trk, col, ta + tmin) > 0.0_dp) cycle
                    tau = crossing(self, md, trk, col, 0, 1.0_dp, ta, 0.0_dp, tmin, ga(col), &
                                   row_value(self, md, trk, col, ta + tmin))
                    if (tau < best) then
                        best = tau
                        found = .true.
                        hit%index = col
                    end if
                end if
            end if
        end do
        do while (k > 0)
            col = pop_earliest(cand, est, k)
            if (found) then
                ! crosses after the earliest event so far: not the first
                if (row_value(self, md, trk, col, ta + best) > 0.0_dp) cycle
                tau = crossing(self, md, trk, col, 0, 1.0_dp, ta, 0.0_dp, best, ga(col), &
                               row_value(self, md, trk, col, ta + best))
            else
                tau = crossing(self, md, trk, col, 0, 1.0_dp, ta, 0.0_dp, h, ga(col), gb(col))
            end if
            if (.not. found .or. tau < best .or. (tau == best .and. col < hit%index)) then
                best = tau
                found = .true.
                hit%index = col
            end if
        end do
        if (found) then
            te = ta + best
            ye = track_state(self, md, trk, te)
            ye(self%nz + 1:) = self%se*self%exo(te)
            hit%kind = 1
            hit%element = md%row_element(hit%index)
            hit%slot = md%row_slot(hit%index)
            hit%action = md%row_action(hit%index)
            hit%c = md%rows(:, hit%index)
        end if

    end subroutine track_find_event

    !> The first zero in (0, h] of row col after ta, the start of its phase, where the row
    !> starts at zero and flat (glo its value there) and ends the step positive: the row at
    !> stickslip_flow_events' dip_samples, the first sample below zero located from the last
    !> positive one before it (crossing), or that sample itself when none is positive before
    !> it (dip_bracket); huge when no sample is below zero.
    real(dp) function fresh_dip(self, md, trk, col, ta, h, glo) result(tau)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        type(track_t), intent(in) :: trk
        integer, intent(in) :: col
        real(dp), intent(in) :: ta, h, glo
        real(dp), allocatable :: ts(:), gs(:)
        real(dp) :: lo, gl, hi, gh
        integer :: k
        logical :: dips
        ts = dip_samples(h)
        allocate (gs(size(ts)))
        do k = 1, size(ts)
            gs(k) = row_value(self, md, trk, col, ta + ts(k))
        end do
        tau = huge(1.0_dp)
        call dip_bracket(ts, gs, glo, 1.0e-9_dp*md%row_scale(col), dips, lo, gl, hi, gh)
        if (.not. dips) return
        if (gl > 0.0_dp) then
            tau = crossing(self, md, trk, col, 0, 1.0_dp, ta, lo, hi, gl, gh)
        else
            tau = hi
        end if
    end function fresh_dip

    !> The end of a bracket a few ulps wide around the first zero in (lo0, hi0] of sgn *
    !> (row col of mode md differentiated `order` times) at ta + tau, positive at lo0 (value
    !> glo) and non-positive at hi0 (ghi), on the side where it is non-positive: the root of
    !> the cubic Hermite interpolant, then stickslip_flow_events' root_bracket_t (the ladder's
    !> event location, on evaluations of the track).
    real(dp) function crossing(self, md, trk, col, order, sgn, ta, lo0, hi0, glo, ghi) &
        result(hi)
        class(flow_modes_t), intent(in) :: self
        type(mode_t), intent(in) :: md
        type(track_t), intent(in) :: trk
        integer, intent(in) :: col, order
        real(dp), intent(in) :: sgn, ta, lo0, hi0, glo, ghi
        type(root_bracket_t) :: rb
        real(dp) :: lo, tol, g, dg, dlo, dhi, t
        logical :: done
        lo = lo0
        hi = hi0
        tol = 4.0_dp*epsilon(1.0_dp)*hi0 + tiny(1.0_dp)
        if (ghi > 0.0_dp .or. hi - lo <= tol) return
        call one_row(self, md, trk, col, ta + lo, order, g, dlo)
        call one_row(self, md, trk, col, ta + hi, order, g, dhi)
        call rb%start(lo, hi, glo, sgn*dlo, ghi, sgn*dhi, tol)
        do
            call rb%next(t, done)
            if (done) exit
            call one_row(self, md, trk, col, ta + t, order, g, dg)
            call rb%take(sgn*g, sgn*dg)
        end do
        hi = rb%hi
    end function crossing
end module stickslip_flow_track
