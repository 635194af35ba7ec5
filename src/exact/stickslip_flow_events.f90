!> Events of the exact flow (stickslip_flow): their kinds, and the location of the earliest
!> one in a step of a contact mode (stickslip_flow_modes) on its exact solution.
!>
!> Events are zeros of the mode's event rows (stickslip_contact_modes: each element gives
!> its own, functions linear in y that stay positive while the mode lasts: a slip velocity,
!> a stuck force's margin to its limit, a normal force, a gap). They are bracketed on a grid
!> of `steps` per period (with the slopes of the event functions at both ends: a dip below
!> zero between two positive values is caught too) and located to roundoff by safeguarded
!> Newton iteration on the exact solution.
module stickslip_flow_events
    use stickslip_kinds, only: dp
    use stickslip_dense_products, only: mat_mul, mat_vec
    use stickslip_flow_modes, only: mode_t, flow_modes_t, propagate, propagate_jacobian
    implicit none
    private
    public :: event_stick, event_slip, event_reversal, event_graze, event_open, event_close, &
        event_impact, event_kind, event_name
    public :: find_event, row_crossing, quadratic_crossing, grid_step, event_guard, &
        dip_samples, dip_bracket, &
        end_monodromy, event_hit_t, hermite_root, root_bracket_t, pop_earliest

    !> Event kinds: a contact sticks; a stuck contact starts slipping; a slipping contact
    !> reverses without sticking; a slipping contact's velocity touches zero and it goes on;
    !> a unilateral contact opens, closes, or closes with a normal velocity (a plastic
    !> impact of a rigid normal).
    integer, parameter :: event_stick = 1, event_slip = 2, event_reversal = 3, event_graze = 4
    integer, parameter :: event_open = 10, event_close = 11, event_impact = 12

    !> An event found: its function (a row of the mode, kind 1; a quadratic event, kind 2;
    !> a row of the step, kind 3), the index among those, its element, code slot and action,
    !> and the gradient of its function at the event state (balanced).
    type :: event_hit_t
        integer :: kind = 0, index = 0, element = 0, slot = 0, action = 0
        real(dp), allocatable :: c(:)
    end type event_hit_t

    !> Safeguarded Newton iteration on a function g over a bracket (lo, hi], g > 0 at lo and
    !> g <= 0 at hi, by reverse communication: `next` gives the time to evaluate (or done),
    !> the caller evaluates g and its slope there in its own way (a propagation of the
    !> augmented state, a modal track) and hands them to `take`. The root of the cubic
    !> Hermite interpolant over the bracket first, then a Newton step from the last
    !> iterate, bisection when it leaves the bracket or does not halve it; once a Newton step
    !> is below tol, one evaluation a few ulps past the iterate closes the bracket. Ends
    !> when the bracket is at most tol wide, g is exactly 0, the bracket is closed or after
    !> 200 iterates. The root is hi (the side where g <= 0); a caller that needs the state
    !> there keeps the last one it evaluated with g <= 0.
    type :: root_bracket_t
        real(dp) :: lo = 0.0_dp, hi = 0.0_dp, tau = 0.0_dp, g = 0.0_dp, dg = 0.0_dp
        real(dp) :: tol = 0.0_dp, step = 0.0_dp, old_step = 0.0_dp, t2 = 0.0_dp
        integer :: iter = 0
        !> What the next `take` answers: 1 an iterate, 2 a probe after it, 3 one before it.
        integer :: pending = 0
        logical :: newton = .false., done = .false., hermite = .false.
    contains
        procedure :: start => root_start
        procedure :: next => root_next
        procedure :: take => root_take
    end type root_bracket_t

contains

    !> Start on the bracket (lo, hi], g > 0 at lo and <= 0 at hi, with the values glo, ghi
    !> and slopes dlo, dhi of g at its ends, to a bracket width tol: the first iterate is the
    !> root of the cubic Hermite interpolant (no evaluation at lo), else Newton from hi.
    pure subroutine root_start(self, lo, hi, glo, dlo, ghi, dhi, tol)
        class(root_bracket_t), intent(inout) :: self
        real(dp), intent(in) :: lo, hi, glo, dlo, ghi, dhi, tol
        self%iter = 0
        self%pending = 0
        self%newton = .false.
        self%lo = lo
        self%hi = hi
        self%tol = tol
        self%g = ghi
        self%dg = dhi
        self%old_step = hi - lo
        self%step = self%old_step
        self%done = ghi == 0.0_dp
        self%tau = lo + hermite_root(glo, dlo, ghi, dhi, hi - lo)
        self%hermite = self%tau > lo .and. self%tau < hi
        if (.not. self%hermite) self%tau = hi
    end subroutine root_start

    !> The next time t to evaluate, or done.
    pure subroutine root_next(self, t, done)
        class(root_bracket_t), intent(inout) :: self
        real(dp), intent(out) :: t
        logical, intent(out) :: done
        t = self%hi
        if (self%pending >= 2) then
            t = self%t2
            done = .false.
            return
        end if
        if (self%done .or. self%hi - self%lo <= self%tol .or. self%iter >= 200) &
            self%done = .true.
        done = self%done
        if (done) return
        self%iter = self%iter + 1
        if (self%hermite) then
            ! the Hermite interpolant's root, the first iterate
            self%newton = .false.
            self%pending = 1
            t = self%tau
            return
        end if
        ! Newton from tau, unless it leaves (lo, hi) or does not halve the bracket
        self%newton = .false.
        if (self%dg /= 0.0_dp .and. abs(2.0_dp*self%g) < abs(self%old_step*self%dg)) then
            self%old_step = self%step
            self%step = self%g/self%dg
            self%tau = self%tau - self%step
            self%newton = .true.
            if (.not. (self%tau > self%lo .and. self%tau < self%hi)) then
                self%tau = 0.5_dp*(self%lo + self%hi)
                self%old_step = self%step
                self%step = self%hi - self%lo
                self%newton = .false.
            end if
        else
            self%old_step = self%step
            self%step = 0.5_dp*(self%hi - self%lo)
            self%tau = 0.5_dp*(self%lo + self%hi)
        end if
        self%pending = 1
        t = self%tau
    end subroutine root_next

    !> g and its slope at the time `next` gave.
    pure subroutine root_take(self, g, dg)
        class(root_bracket_t), intent(inout) :: self
        real(dp), intent(in) :: g, dg
        select case (self%pending)
        case (1)
            self%g = g
            self%dg = dg
            if (g > 0.0_dp) then
                self%lo = self%tau
            else
                self%hi = self%tau
            end if
            self%pending = 0
            if (self%hermite) then
                ! the Newton steps' history starts on the bracket the first iterate left
                self%hermite = .false.
                self%old_step = self%hi - self%lo
                self%step = self%old_step
            end if
            if (g == 0.0_dp) then
                self%done = .true.
            else if (self%newton .and. abs(self%step) <= self%tol) then
                ! converged: the root is within a few ulps of tau on the side Newton
                ! approaches from; close the bracket there
                if (g > 0.0_dp) then
                    self%t2 = min(self%tau + 2.0_dp*abs(self%step) + self%tol, self%hi)
                    self%done = self%t2 >= self%hi
                    if (.not. self%done) self%pending = 2
                else
                    self%t2 = max(self%tau - 2.0_dp*abs(self%step) - self%tol, self%lo)
                    self%done = self%t2 <= self%lo
                    if (.not. self%done) self%pending = 3
                end if
            end if
        case (2)
            self%pending = 0
            if (g <= 0.0_dp) then
                self%hi = self%t2
                self%done = .true.
            else
                self%lo = self%t2
            end if
        case (3)
            self%pending = 0
            if (g > 0.0_dp) then
                self%lo = self%t2
                self%done = .true.
            else
                self%hi = self%t2
            end if
        end select
    end subroutine root_take

    !> Kind of the change of one code slot at an event (0 stuck, +1 / -1 slipping, 2 open):
    !> event_open, event_close or event_impact (`impacted`) for the normal law, else
    !> event_stick, event_slip, event_reversal or event_graze.
    pure integer function event_kind(old, new, impacted)
        !> The slot's code before and after the event.
        integer, intent(in) :: old, new
        !> The contact closed with an impact.
        logical, intent(in) :: impacted
        if (new == 2) then
            event_kind = event_open
        else if (old == 2) then
            event_kind = merge(event_impact, event_close, impacted)
        else if (new == 0) then
            event_kind = event_stick
        else if (old == 0) then
            event_kind = event_slip
        else if (old == -new) then
            event_kind = event_reversal
        else
            event_kind = event_graze
        end if
    end function event_kind

    !> Name of an event kind, as written to events.csv.
    pure function event_name(kind) result(name)
        !> One of event_*.
        integer, intent(in) :: kind
        character(len=:), allocatable :: name
        select case (kind)
        case (event_stick)
            name = "stick"
        case (event_slip)
            name = "slip"
        case (event_reversal)
            name = "reversal"
        case (event_open)
            name = "open"
        case (event_close)
            name = "close"
        case (event_impact)
            name = "impact"
        case default
            name = "graze"
        end select
    end function event_name

    !> The earliest event in (ta, tb] of the (linear) mode md, if any: its time te, state ye
    !> and what it is (hit: a row or a quadratic event of the mode, with its gradient at
    !> ye). States and rows in balanced coordinates. Rows that end the step non-positive are
    !> located in the order of the roots of their cubic Hermite interpolants (a cheap
    !> estimate), each only when it is already non-positive at the earliest event located so
    !> far: with many contacts several rows cross in one step, and one or two of them need
    !> locating to roundoff instead of all.
    subroutine find_event(self, md, ta, ya, tb, yb, found, te, ye, hit, fresh)
        !> The dynamics md belongs to.
        class(flow_modes_t), intent(in) :: self
        !> The contact mode of the step.
        type(mode_t), intent(in) :: md
        !> Start time [s] and state of the step, end time [s] and state (exp(b (tb - ta)) ya).
        real(dp), intent(in) :: ta, ya(:), tb, yb(:)
        !> Whether an event lies in (ta, tb].
        logical, intent(out) :: found
        !> With found: the event's time [s] and state.
        real(dp), intent(out) :: te, ye(:)
        !> With found: the event.
        type(event_hit_t), intent(out) :: hit
        !> The step starts the phase (row_crossing samples its rows at zero and flat).
        logical, intent(in) :: fresh
        real(dp) :: tau, best, h, ga, gb, da, db, ytau(size(ya))
        real(dp), allocatable :: est(:)
        integer, allocatable :: cand(:)
        integer :: col, k, nrow
        found = .false.
        h = tb - ta
        best = huge(1.0_dp)
        nrow = size(md%row_scale)
        allocate (cand(nrow), est(nrow))
        k = 0
        do col = 1, nrow
            gb = dot_product(md%rows(:, col), yb)
            if (gb <= 0.0_dp) then
                ! a crossing: its estimate now, located below in the order of the estimates
                k = k + 1
                cand(k) = col
                ga = dot_product(md%rows(:, col), ya)
                da = dot_product(md%drows(:, col), ya)
                db = dot_product(md%drows(:, col), yb)
                est(k) = 0.0_dp
                if (ga > 0.0_dp) est(k) = max(hermite_root(ga, da, gb, db, h), 0.0_dp)
            else
                ! a dip below zero between two positive values, if any
                tau = row_crossing(self, md, col, md%row_scale(col), ta, ya, tb, yb, fresh)
                if (tau < best) then
                    best = tau
                    found = .true.
                    hit%kind = 1
                    hit%index = col
                end if
            end if
        end do
        do col = 1, size(md%qc)
            tau = quadratic_crossing(self, md, col, ta, ya, tb, yb)
            if (tau < best) then
                best = tau
                found = .true.
                hit%kind = 2
                hit%index = col
            end if
        end do
        if (found) call propagate(md, self%delta, best, ya, ye)
        do while (k > 0)
            col = pop_earliest(cand, est, k)
            if (found) then
                ! it crosses after the earliest event so far: not the first
                if (dot_product(md%rows(:, col), ye) > 0.0_dp) cycle
                tau = first_crossing(md, self%delta, ya, md%rows(:, col), 0, best, ye, ytau)
            else
                tau = first_crossing(md, self%delta, ya, md%rows(:, col), 0, h, yb, ytau)
            end if
            ! ties as a scan of the rows in order would break them: the lower row, rows
            ! before quadratic events
            if (.not. found .or. tau < best .or. &
                (tau == best .and. (hit%kind == 2 .or. col < hit%index))) then
                best = tau
                found = .true.
                hit%kind = 1
                hit%index = col
                ye = ytau
            end if
        end do
        if (found) then
            te = ta + best
            ye(self%nz + 1:) = self%se*self%exo(te)
            if (hit%kind == 1) then
                hit%element = md%row_element(hit%index)
                hit%slot = md%row_slot(hit%index)
                hit%action = md%row_action(hit%index)
                hit%c = md%rows(:, hit%index)
            else
                hit%element = md%q_element(hit%index)
                hit%slot = md%q_slot(hit%index)
                hit%action = md%q_action(hit%index)
                hit%c = 2.0_dp*matmul(md%qmat(:, :, hit%index), ye)
            end if
        end if
    end subroutine find_event

    !> The first time tau in (0, tb - ta] where quadratic event k of mode md, g(y) = y^T Q y
    !> + c, crosses zero from ya at ta (yb at tb), or huge: as row_crossing (a value that
    !> ends non-positive, or a dip below zero between two positive values), located by
    !> bisection safeguarding Newton steps on g(tau) = g(exp(b tau) ya).
    real(dp) function quadratic_crossing(self, md, k, ta, ya, tb, yb) result(tau)
        !> The dynamics md belongs to.
        class(flow_modes_t), intent(in) :: self
        !> The contact mode of the step.
        type(mode_t), intent(in) :: md
        !> The quadratic event.
        integer, intent(in) :: k
        !> Start time [s] and state, end time [s] and state of the step.
        real(dp), intent(in) :: ta, ya(:), tb, yb(:)
        real(dp) :: h, ga, gb, da, db, thr, lo, hi, tm
        integer :: it
        tau = huge(1.0_dp)
        h = tb - ta
        ga = gval(ya)
        gb = gval(yb)
        da = gdot(ya)
        db = gdot(yb)
        thr = 1.0e-9_dp*md%q_scale(k)*self%omega
        if (gb <= 0.0_dp) then
            tau = root(0.0_dp, h)
        else if (ga > 0.0_dp .and. da < -thr .and. db > thr) then
            ! a dip between two positive values: its minimum, where the slope changes sign
            lo = 0.0_dp
            hi = h
            do it = 1, 100
                tm = 0.5_dp*(lo + hi)
                if (slope_at(tm) < 0.0_dp) then
                    lo = tm
                else
                    hi = tm
                end if
                if (hi - lo <= 4.0_dp*epsilon(1.0_dp)*h) exit
            end do
            if (value_at(hi) > 0.0_dp) return
            tau = root(0.0_dp, hi)
        end if

    contains

        real(dp) function gval(y)
            real(dp), intent(in) :: y(:)
            gval = dot_product(y, matmul(md%qmat(:, :, k), y)) + md%qc(k)
        end function gval

        real(dp) function gdot(y)
            real(dp), intent(in) :: y(:)
            gdot = 2.0_dp*dot_product(matmul(md%qmat(:, :, k), y), matmul(md%b, y))
        end function gdot

        real(dp) function value_at(s)
            real(dp), intent(in) :: s
            real(dp) :: y(size(ya))
            call propagate(md, self%delta, s, ya, y)
            value_at = gval(y)
        end function value_at

        real(dp) function slope_at(s)
            real(dp), intent(in) :: s
            real(dp) :: y(size(ya))
            call propagate(md, self%delta, s, ya, y)
            slope_at = gdot(y)
        end function slope_at

        !> The end of the bracket (a, b] (g > 0 at a, <= 0 at b) where g <= 0, the bracket
        !> a few ulps of the step wide: Newton steps inside it, bisection otherwise.
        real(dp) function root(a, b) result(r)
            real(dp), intent(in) :: a, b
            real(dp) :: l, s, g, dg, y(size(ya)), step, old_step
            integer :: iter
            l = a
            r = b
            s = r
            call propagate(md, self%delta, s, ya, y)
            g = gval(y)
            dg = gdot(y)
            old_step = r - l
            step = old_step
            do iter = 1, 200
                if (r - l <= 4.0_dp*epsilon(1.0_dp)*h + tiny(1.0_dp)) exit
                ! Newton from s, unless it leaves (l, r) or does not halve the bracket
                if (dg /= 0.0_dp .and. abs(2.0_dp*g) < abs(old_step*dg)) then
                    old_step = step
                    step = g/dg
                    s = s - step
                    if (.not. (s > l .and. s < r)) then
                        s = 0.5_dp*(l + r)
                        old_step = step
                        step = r - l
                    end if
                else
                    old_step = step
                    step = 0.5_dp*(r - l)
                    s = 0.5_dp*(l + r)
                end if
                call propagate(md, self%delta, s, ya, y)
                g = gval(y)
                dg = gdot(y)
                if (g > 0.0_dp) then
                    l = s
                else
                    r = s
                end if
                if (g == 0.0_dp) exit
            end do
        end function root
    end function quadratic_crossing

    !> The first time tau in (0, tb - ta] where event row `col` of mode md crosses zero from
    !> the balanced state ya at ta (yb the state at tb), or huge when it does not: a row
    !> that ends non-positive, or dips below zero between two positive values (a minimum
    !> found when its slope changes sign by more than 1e-9 of gscale * omega), or, in the
    !> step that starts its phase at zero and flat, goes below zero at one of dip_samples.
    !> gscale is the scale of the row's values.
    real(dp) function row_crossing(self, md, col, gscale, ta, ya, tb, yb, fresh) result(tau)
        !> The dynamics md belongs to.
        class(flow_modes_t), intent(in) :: self
        !> The contact mode of the step.
        type(mode_t), intent(in) :: md
        !> The event row.
        integer, intent(in) :: col
        !> Scale of the row's values.
        real(dp), intent(in) :: gscale
        !> Start time [s] and state, end time [s] and state of the step.
        real(dp), intent(in) :: ta, ya(:), tb, yb(:)
        !> The step starts the row's phase (a row at zero and flat there is sampled for a
        !> dip, dip_samples).
        logical, intent(in) :: fresh
        real(dp) :: ga, gb, da, db, thr, tmin, h, lo, glo, hi, ghi, ylo(size(ya))
        real(dp), allocatable :: ts(:), gs(:)
        logical :: dips
        integer :: k
        tau = huge(1.0_dp)
        associate (r => md%rows(:, col))
            h = tb - ta
            ga = dot_product(r, ya)
            gb = dot_product(r, yb)
            da = dot_product(md%drows(:, col), ya)
            db = dot_product(md%drows(:, col), yb)
            thr = 1.0e-9_dp*gscale*self%omega
            if (gb <= 0.0_dp) then
                tau = first_crossing(md, self%delta, ya, r, 0, h, yb)
            else if (fresh .and. abs(ga) <= 1.0e-9_dp*gscale .and. abs(da) <= thr) then
                ! at zero and flat where its phase starts: a hump then a dip leaves both
                ! slopes of the step positive (the track's rule too, stickslip_flow_track)
                ts = dip_samples(h)
                gs = [(value_at(md, self%delta, ya, r, ts(k)), k=1, size(ts))]
                call dip_bracket(ts, gs, ga, 1.0e-9_dp*gscale, dips, lo, glo, hi, ghi)
                if (.not. dips) return
                if (glo > 0.0_dp) then
                    call propagate(md, self%delta, lo, ya, ylo)
                    tau = lo + first_crossing(md, self%delta, ylo, r, 0, hi - lo)
                else
                    tau = hi
                end if
            else if (ga > 0.0_dp .and. da < -thr .and. db > thr) then
                ! a dip between two positive values: does its minimum go below zero?
                tmin = first_crossing(md, self%delta, ya, -r, 1, h, yb)
                if (value_at(md, self%delta, ya, r, tmin) > 0.0_dp) return
                tau = first_crossing(md, self%delta, ya, r, 0, tmin)
            end if
        end associate
    end function row_crossing

    !> g(tau) = r . exp(b tau) y0.
    real(dp) function value_at(md, delta, y0, r, tau) result(g)
        type(mode_t), intent(in) :: md
        real(dp), intent(in) :: delta, y0(:), r(:), tau
        real(dp) :: y(size(y0))
        call propagate(md, delta, tau, y0, y)
        g = dot_product(r, y)
    end function value_at

    !> A crossing of zero of g(tau) = r . b^order exp(b tau) y0 in (0, hi], taken to be
    !> positive at 0 and known to be <= 0 at hi: safeguarded Newton iteration (bisection
    !> when a Newton step leaves the bracket or stalls) until the bracket is a few ulps of
    !> the period wide. Returns the end of the bracket where g <= 0. The first iterate is
    !> the root of the cubic Hermite interpolant of g over the bracket (g and its slope at
    !> both ends: no propagation at 0), then root_bracket_t (each propagation costs dozens
    !> of matrix-vector products: a stiff reduced model with many contacts spent most of its
    !> stability time here; hence the bracket closed by one propagation past the iterate).
    real(dp) function first_crossing(md, delta, y0, r, order, hi0, yhi, yout) result(hi)
        type(mode_t), intent(in) :: md
        real(dp), intent(in) :: delta, y0(:), r(:)
        integer, intent(in) :: order
        real(dp), intent(in) :: hi0
        !> The state at hi0 when the caller has it (exp(b hi0) y0).
        real(dp), intent(in), optional :: yhi(:)
        !> The state at the returned time (exp(b hi) y0).
        real(dp), intent(out), optional :: yout(:)
        real(dp) :: lo, tau, g, dg, tol, row(size(r)), row1(size(r)), t
        real(dp) :: y(size(y0)), g0, dg0, bnorm, tlast, ylast(size(y0)), yh(size(y0))
        type(root_bracket_t) :: rb
        integer :: k
        logical :: done
        row = r
        do k = 1, order
            row = matmul(row, md%b)
        end do
        row1 = matmul(row, md%b)
        lo = 0.0_dp
        hi = hi0
        tol = 4.0_dp*epsilon(1.0_dp)*hi0 + tiny(1.0_dp)
        g0 = dot_product(row, y0)
        dg0 = dot_product(row1, y0)
        bnorm = maxval(sum(abs(md%b), 2))
        tau = hi
        if (present(yhi)) then
            y = yhi
        else
            call propagate(md, delta, tau, y0, y)
        end if
        tlast = tau
        ylast = y
        yh = y
        g = dot_product(row, y)
        dg = dot_product(row1, y)
        if (g > 0.0_dp .or. hi - lo <= tol) then
            if (present(yout)) yout = yh
            return
        end if
        call rb%start(lo, hi, g0, dg0, g, dg, tol)
        do
            call rb%next(t, done)
            if (done) exit
            call state_at(t)
            g = dot_product(row, y)
            if (g <= 0.0_dp) yh = y
            call rb%take(g, dot_product(row1, y))
        end do
        hi = rb%hi
        if (present(yout)) yout = yh

    contains

        !> y = exp(b t) y0: from the last state computed by a Taylor series when t is within
        !> 1/16 of ||b||^-1 of it (a Newton step near the root: a few matrix-vector products,
        !> forward or back), else by propagate from y0.
        subroutine state_at(t)
            real(dp), intent(in) :: t
            real(dp) :: term(size(y0)), s
            integer :: kk
            s = t - tlast
            if (abs(s)*bnorm <= 0.0625_dp) then
                y = ylast
                term = ylast
                do kk = 1, 30
                    term = mat_vec(md%b, term)*(s/kk)
                    y = y + term
                    if (maxval(abs(term)) <= epsilon(1.0_dp)*maxval(abs(y))) exit
                end do
            else
                call propagate(md, delta, t, y0, y)
            end if
            tlast = t
            ylast = y
        end subroutine state_at

    end function first_crossing

    !> The candidate with the earliest estimate among the first k of cand (est their
    !> estimates), taken out of the list (k decreases by one; the last takes its place).
    integer function pop_earliest(cand, est, k) result(col)
        !> Candidate rows and their estimated crossing times.
        integer, intent(inout) :: cand(:)
        real(dp), intent(inout) :: est(:)
        !> Number of candidates left, >= 1.
        integer, intent(inout) :: k
        integer :: i
        i = minloc(est(1:k), 1)
        col = cand(i)
        cand(i) = cand(k)
        est(i) = est(k)
        k = k - 1
    end function pop_earliest

    !> A root in (0, h) of the cubic p with p(0) = ga, p'(0) = da, p(h) = gb, p'(h) = db
    !> (ga > 0 >= gb), by bisection on p to 1e-6 h; -1 when h <= 0.
    pure real(dp) function hermite_root(ga, da, gb, db, h) result(t)
        real(dp), intent(in) :: ga, da, gb, db, h
        real(dp) :: a, b, s
        integer :: it
        a = 0.0_dp
        b = h
        t = -1.0_dp
        if (.not. (h > 0.0_dp)) return
        do it = 1, 60
            s = 0.5_dp*(a + b)
            if (hermite_cubic(ga, da, gb, db, h, s/h) > 0.0_dp) then
                a = s
            else
                b = s
            end if
            if (b - a <= 1.0e-6_dp*h) exit
        end do
        t = 0.5_dp*(a + b)
    end function hermite_root

    !> The cubic Hermite interpolant of hermite_root at x = t / h in [0, 1].
    pure real(dp) function hermite_cubic(ga, da, gb, db, h, x) result(p)
        real(dp), intent(in) :: ga, da, gb, db, h, x
        p = (1.0_dp + 2.0_dp*x)*(1.0_dp - x)**2*ga + x*(1.0_dp - x)**2*h*da + &
            x*x*(3.0_dp - 2.0_dp*x)*gb + x*x*(x - 1.0_dp)*h*db
    end function hermite_cubic

    !> One grid step of the flow in mode md from t (balanced state yb): to t + delta by the
    !> cached exponential (full_step), or the remainder to tend; the exogenous part of ybb
    !> set at the step's end tb. The step of both period maps (plain and contact laws).
    subroutine grid_step(self, md, t, tend, yb, tb, ybb, full_step)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The contact mode of the step.
        type(mode_t), intent(in) :: md
        !> Start of the step and end of the period [s].
        real(dp), intent(in) :: t, tend
        !> State at t (balanced coordinates).
        real(dp), intent(in) :: yb(:)
        !> End of the step [s].
        real(dp), intent(out) :: tb
        !> State at tb.
        real(dp), intent(out) :: ybb(:)
        !> The step is a whole grid step (its cached exponentials apply).
        logical, intent(out) :: full_step
        if (tend - t <= self%delta*(1.0_dp + 1.0e-9_dp)) then
            tb = tend
            full_step = .false.
            call propagate(md, self%delta, tb - t, yb, ybb)
        else
            tb = t + self%delta
            full_step = .true.
            ybb = mat_vec(md%ladder(:, :, 0), yb)
        end if
        ybb(self%nz + 1:) = self%se*self%exo(tb)
    end subroutine grid_step

    !> Times in (0, h) [s] at which an event row that starts a phase at zero and flat is
    !> sampled for a dip below zero (its element switched as its rate vanished, and the
    !> slopes at the step's ends cannot tell a dip that follows a hump): h 2^-k, k = 1..30,
    !> and the other multiples h k / 16, k = 3, 5, 6, 7, 9, ..., 15, ascending. No errors.
    pure function dip_samples(h) result(ts)
        !> The step [s].
        real(dp), intent(in) :: h
        real(dp) :: ts(41)
        integer, parameter :: sixteenths(11) = [3, 5, 6, 7, 9, 10, 11, 12, 13, 14, 15]
        integer :: k, i, j
        do k = 1, 30
            ts(k) = h*0.5_dp**(31 - k)
        end do
        ts(31:) = h*real(sixteenths, dp)/16.0_dp
        ! insertion sort: the uniform part interleaves the ascending geometric one
        do i = 31, size(ts)
            j = i
            do while (j > 1)
                if (ts(j - 1) <= ts(j)) exit
                ts([j - 1, j]) = ts([j, j - 1])
                j = j - 1
            end do
        end do
    end function dip_samples

    !> Whether (dips) a row with value g0 at its phase's start and gs at the ascending times ts
    !> goes below zero: the first sample below -zero (the start's roundoff about zero is not a
    !> dip) is hi (value ghi), the last positive sample before it lo (value glo; lo = 0 and
    !> glo = g0 when there is none: then glo <= 0 and the row is below zero from the start).
    !> No errors.
    pure subroutine dip_bracket(ts, gs, g0, zero, dips, lo, glo, hi, ghi)
        !> Sample times [s] (ascending) and the row's values there.
        real(dp), intent(in) :: ts(:), gs(:)
        !> The row's value at the start, and the width of its roundoff about zero.
        real(dp), intent(in) :: g0, zero
        !> Whether a sample is below -zero.
        logical, intent(out) :: dips
        !> The bracket (lo, hi] of the first zero and the values at its ends.
        real(dp), intent(out) :: lo, glo, hi, ghi
        integer :: k
        dips = .false.
        lo = 0.0_dp
        glo = g0
        hi = 0.0_dp
        ghi = 0.0_dp
        do k = 1, size(ts)
            if (gs(k) > 0.0_dp) then
                lo = ts(k)
                glo = gs(k)
            else if (gs(k) < -zero) then
                hi = ts(k)
                ghi = gs(k)
                dips = .true.
                return
            end if
        end do
    end subroutine dip_bracket

    !> Count an event at te (the phase before it began at tp) and say whether the period map
    !> must stop: '' when it goes on; why, when the contacts switched again at the same
    !> instant more than max_zero times in a row (no consistent contact mode) or when there
    !> were more than max_events events in the period (`chattering` names what chatters).
    function event_guard(te, tp, period, max_zero, max_events, chattering, zero_length, &
                         nevents) result(message)
        !> Event time and start of the phase it ends [s], the period [s].
        real(dp), intent(in) :: te, tp, period
        !> Most zero-length phases in a row, most events per period.
        integer, intent(in) :: max_zero, max_events
        !> What chatters, for the message.
        character(len=*), intent(in) :: chattering
        !> Zero-length phases in a row so far, and events so far (both updated).
        integer, intent(inout) :: zero_length, nevents
        character(len=:), allocatable :: message
        character(len=200) :: buf
        message = ""
        nevents = nevents + 1
        if (te - tp <= 1.0e-12_dp*period) then
            zero_length = zero_length + 1
        else
            zero_length = 0
        end if
        if (zero_length > max_zero) then
            write (buf, '(a,es13.5e3,a)') "no consistent contact mode at t = ", te, &
                " s: the contacts switch again at the same instant"
            message = trim(buf)
        else if (nevents > max_events) then
            write (buf, '(a,i0,a)') "more than ", max_events, " events in one period ("// &
                chattering//")"
            message = trim(buf)
        end if
    end function event_guard

    !> The monodromy matrix of a period map in the model's coordinates, from the Jacobian
    !> `jac` of the balanced state up to the last phase's start and that phase (mode md,
    !> `duration` [s]): tbi_zz expm(B duration) jac tb_zz.
    subroutine end_monodromy(self, md, duration, jac, mono)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The last phase's mode.
        type(mode_t), intent(in) :: md
        !> Its duration [s].
        real(dp), intent(in) :: duration
        !> Jacobian of the balanced state at the last phase's start; on return, at the end.
        real(dp), intent(inout) :: jac(:, :)
        !> dz1/dz0.
        real(dp), intent(out) :: mono(:, :)
        real(dp), allocatable :: ti(:, :), t(:, :)
        integer :: nz
        nz = size(jac, 1)
        call propagate_jacobian(self, md, duration, jac)
        ! contiguous copies of the state blocks of the transformations (for BLAS)
        ti = self%tbi(1:nz, 1:nz)
        t = self%tb(1:nz, 1:nz)
        mono = mat_mul(ti, mat_mul(jac, t))
    end subroutine end_monodromy
end module stickslip_flow_events
