!> Pseudo-arclength continuation of the solutions y(s), lambda(s) of F(y, lambda) = 0, generic
!> in its residual: a tangent predictor, MINPACK hybrj as the corrector on the bordered system
!> (from powell_min_unknowns unknowns its algorithm on LAPACK's QR, stickslip_powell)
!>     F(y, lambda) = 0,   t_y . (y - y_p) / y_s^2 + t_l (lambda - lambda_p) / p_s^2 = 0
!> (the hyperplane through the predicted point orthogonal to the tangent, in the scaled
!> coordinates y / y_s, lambda / p_s), with the system's analytic dF/dy and dF/dlambda. Turning
!> points (folds) are passed because lambda is an unknown of the corrector.
!>
!> Step control: the arclength step grows after an easy point, shrinks after a hard one, is
!> halved after a failed corrector (or a point that jumped: correction longer than the step,
!> or a tangent that turned back); at the smallest step the system's own recovery is tried
!> at the predicted parameter (e.g. a harmonic ladder for the friction problem). The point
!> that would cross the end of the range is computed at the end exactly. With opts%yref > 0
!> the scale of the unknowns follows the size of the solution (yscale max(1, ||y|| / yref)),
!> so that a part of the curve where the unknowns grow tenfold (the contact forces at a
!> resonance) is passed in about as many points as one where they do not.
!>
!> The state of a continuation (continuation_state_t) is plain data: saving and restoring it
!> (stickslip_sweep's checkpoint) resumes the same curve.
module stickslip_continuation
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_minpack, only: hybrj_options_t, hybrj_report_t, solve_hybrj
    use stickslip_powell, only: solve_powell
    use stickslip_lapack, only: dgetrf, dgetrs
    implicit none
    private
    public :: parametric_system_t, continuation_options_t, continuation_state_t
    public :: continuation_report_t, start_continuation, continuation_step, resume_continuation
    public :: validate_continuation_options, point_status
    public :: reason_running, reason_end, reason_failures, reason_max_points, reason_left

    !> Fewest unknowns of the bordered system for which the corrector runs hybrj's algorithm
    !> on LAPACK's blocked QR (stickslip_powell: the same iterates up to roundoff) instead of
    !> MINPACK's hybrj: at the Rotor 37 blade's 481 unknowns hybrj's own unblocked qrfac and
    !> qform took half of the corrector's time. As the weighted residual's newton_min_unknowns.
    integer, parameter :: powell_min_unknowns = 48

    !> Why a continuation stopped (continuation_state_t%reason).
    integer, parameter :: reason_running = 0, reason_end = 1, reason_failures = 2, &
                          reason_max_points = 3, reason_left = 4

    !> A family of square systems F(y, lambda) = 0 in n unknowns y and one parameter lambda.
    !> Implementations own their work arrays: one instance per thread.
    type, abstract :: parametric_system_t
    contains
        procedure(par_residual_iface), deferred :: residual
        procedure(par_jacobian_iface), deferred :: jacobian
        procedure :: recover => no_recovery
        procedure :: residual_scale => unit_scale
        procedure :: anchor => no_anchor
    end type parametric_system_t

    abstract interface
        !> f = F(y, lambda). Set stat /= 0 to stop the corrector.
        subroutine par_residual_iface(self, y, lambda, f, stat)
            import :: parametric_system_t, dp
            class(parametric_system_t), intent(inout) :: self
            real(dp), intent(in) :: y(:), lambda
            real(dp), intent(out) :: f(:)
            integer, intent(inout) :: stat
        end subroutine par_residual_iface

        !> jy = dF/dy (n x n, an element of the generalized Jacobian), jl = dF/dlambda.
        subroutine par_jacobian_iface(self, y, lambda, jy, jl, stat)
            import :: parametric_system_t, dp
            class(parametric_system_t), intent(inout) :: self
            real(dp), intent(in) :: y(:), lambda
            real(dp), intent(out) :: jy(:, :), jl(:)
            integer, intent(inout) :: stat
        end subroutine par_jacobian_iface
    end interface

    !> Options of a continuation. Steps are in parameter units: on a part of the curve where
    !> the unknowns hardly change, one step moves the parameter by about `step`.
    type :: continuation_options_t
        !> Start and end of the parameter range.
        real(dp) :: start = 0.0_dp, stop = 1.0_dp
        !> First, smallest and largest step (parameter units, > 0).
        real(dp) :: step = 0.0_dp, min_step = 0.0_dp, max_step = 0.0_dp
        !> Most points (the start included).
        integer :: max_points = 1000
        !> Points given up after the smallest step and the recovery both failed, in a row,
        !> before the continuation stops.
        integer :: max_failures = 3
        !> Accept a point when ||F(y, lambda)||_2 <= tol * max(fscale, the system's
        !> residual_scale at lambda).
        real(dp) :: tol = 1.0e-9_dp, fscale = 1.0_dp
        !> Scale of the unknowns (one value, or one per unknown; > 0). The parameter's scale
        !> is |stop - start|.
        real(dp), allocatable :: yscale(:)
        !> > 0: the scale at a point y is yscale * max(1, ||y||_2 / yref) (relative steps
        !> where the unknowns are larger than yref); 0: yscale throughout.
        real(dp) :: yref = 0.0_dp
        !> Residual evaluations per corrector call (hybrj maxfev).
        integer :: maxfev = 100
        !> A point that took at most `easy` evaluations grows the step by `grow`; more than
        !> `hard` shrinks it by 1 / grow.
        integer :: easy = 6, hard = 20
        real(dp) :: grow = 1.5_dp
    end type continuation_options_t

    !> Where a continuation is: the last point and its tangent, the step, the counts.
    type :: continuation_state_t
        !> The last accepted point.
        real(dp), allocatable :: y(:)
        real(dp) :: lambda = 0.0_dp
        !> Unit tangent at the last point, in scaled coordinates (y / y_s, lambda / p_s).
        real(dp), allocatable :: ty(:)
        real(dp) :: tl = 0.0_dp
        !> Current step (parameter units), arclength so far (scaled units times p_s).
        real(dp) :: ds = 0.0_dp, arclength = 0.0_dp
        !> Accepted points, failed points in a row, all failed attempts.
        integer :: points = 0, failures = 0, rejected = 0
        !> reason_running, or why it stopped.
        integer :: reason = reason_running
    end type continuation_state_t

    !> What one continuation step did.
    type :: continuation_report_t
        !> A new point was accepted.
        logical :: accepted = .false.
        !> Corrector residual evaluations, step halvings, and whether the point came from
        !> the system's recovery.
        integer :: nfev = 0, halvings = 0
        logical :: recovered = .false.
        !> ||F|| at the accepted point.
        real(dp) :: fnorm = 0.0_dp
        !> Empty, or what went wrong (failed points, the end).
        character(len=:), allocatable :: message
    end type continuation_report_t

    !> The bordered system solved by hybrj: u = [y; lambda].
    type, extends(nonlinear_system_t) :: bordered_t
        class(parametric_system_t), pointer :: sys => null()
        !> .true.: the last equation is lambda = lfix; else the arclength hyperplane.
        logical :: fixed = .false.
        real(dp) :: lfix = 0.0_dp, lp = 0.0_dp, tl = 0.0_dp, ps = 1.0_dp, weight = 1.0_dp
        !> The size factor in ys (size_factor at the point the step starts from).
        real(dp) :: g = 1.0_dp
        real(dp), allocatable :: yp(:), ty(:), ys(:)
    contains
        procedure :: residual => bordered_residual
        procedure :: jacobian => bordered_jacobian
    end type bordered_t

contains

    !> Check continuation options. Errors (stat input) name the component
    !> ("opts%max_points = 1: must be >= 2").
    subroutine validate_continuation_options(opts, error)
        !> Options to check.
        type(continuation_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=200) :: buf
        if (.not. (ieee_is_finite(opts%start) .and. ieee_is_finite(opts%stop))) then
            buf = "opts%start, opts%stop: must be finite numbers"
        else if (opts%start == opts%stop) then
            buf = "opts%start = opts%stop: the range is empty"
        else if (.not. (opts%step > 0.0_dp .and. opts%min_step > 0.0_dp .and. &
                        opts%max_step > 0.0_dp)) then
            buf = "opts%step, opts%min_step, opts%max_step: must be > 0"
        else if (opts%min_step > opts%step .or. opts%step > opts%max_step) then
            write (buf, '(a,3(g0.4,a))') "opts%step: need opts%min_step <= opts%step <= "// &
                "opts%max_step (", &
                opts%min_step, " <= ", opts%step, " <= ", opts%max_step, ")"
        else if (opts%max_points < 2) then
            write (buf, '(a,i0,a)') "opts%max_points = ", opts%max_points, ": must be >= 2"
        else if (opts%max_failures < 1) then
            write (buf, '(a,i0,a)') "opts%max_failures = ", opts%max_failures, ": must be >= 1"
        else if (.not. (opts%tol > 0.0_dp .and. opts%tol < 1.0_dp)) then
            write (buf, '(a,g0.4,a)') "opts%tol = ", opts%tol, ": must be in (0, 1)"
        else if (.not. (opts%yref >= 0.0_dp .and. ieee_is_finite(opts%yref))) then
            write (buf, '(a,g0.4,a)') "opts%yref = ", opts%yref, ": must be >= 0"
        else
            return
        end if
        call fatal_error(error, trim(buf), stickslip_stat%input)
    end subroutine validate_continuation_options

    !> Correct the start y0 at lambda = opts%start and compute the tangent pointing toward
    !> opts%stop. Not converging is an outcome: state%reason = reason_failures and
    !> report%message. Errors: stat input (bad options or sizes), stat numerical (NaN).
    subroutine start_continuation(sys, opts, y0, state, report, error)
        !> The family of systems.
        class(parametric_system_t), target, intent(inout) :: sys
        !> Options.
        type(continuation_options_t), intent(in) :: opts
        !> Approximate solution at lambda = opts%start.
        real(dp), intent(in) :: y0(:)
        !> The new state.
        type(continuation_state_t), intent(out) :: state
        !> What happened.
        type(continuation_report_t), intent(out) :: report
        !> Set on misuse or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        type(bordered_t) :: b
        real(dp), allocatable :: u(:), ty0(:)
        logical :: ok
        integer :: n

        call validate_continuation_options(opts, error)
        if (allocated(error)) return
        n = size(y0)
        call setup_bordered(b, sys, opts, y0, error)
        if (allocated(error)) return
        b%fixed = .true.
        b%lfix = opts%start
        call sys%anchor(y0, opts%start)
        u = [y0, opts%start]
        call correct(b, opts, u, report, ok, error)
        if (allocated(error)) return
        if (.not. ok) then
            call sys%recover(u(1:n), opts%start, ok, error)
            if (allocated(error)) return
            report%recovered = ok
            if (ok) call check_point(b, opts, u, report, ok)
        end if
        if (.not. ok) then
            state%reason = reason_failures
            report%message = "no solution at the start of the range"
            return
        end if
        state%y = u(1:n)
        state%lambda = opts%start
        allocate (ty0(n))
        ty0 = 0.0_dp
        call tangent(b, state%y, state%lambda, ty0, sign(1.0_dp, opts%stop - opts%start), &
                     state%ty, state%tl, ok)
        if (.not. ok) then
            state%ty = ty0
            state%tl = sign(1.0_dp, opts%stop - opts%start)
        end if
        call rescale_tangent(b, opts, state%y, state%ty, state%tl)
        state%ds = opts%step
        state%points = 1
        report%accepted = .true.
    end subroutine start_continuation

    !> Resume a continuation that stopped on failed points (state%reason = reason_failures)
    !> on `sys`, another system of the same unknowns (e.g. the same equations on a finer
    !> quadrature): the last point corrected at its parameter, its tangent oriented as the
    !> old one, the step opts%step. report%accepted when the corrected point met the
    !> tolerance; the state then runs again (failures 0), else it is left as it was.
    !> Errors: as start_continuation.
    subroutine resume_continuation(sys, opts, state, report, error)
        !> The family of systems (the unknowns of the one that stopped).
        class(parametric_system_t), target, intent(inout) :: sys
        !> Options (the same as at the start).
        type(continuation_options_t), intent(in) :: opts
        !> The stopped state; running again from its corrected last point when accepted.
        type(continuation_state_t), intent(inout) :: state
        !> What happened.
        type(continuation_report_t), intent(out) :: report
        !> Set on misuse or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        type(bordered_t) :: b
        real(dp), allocatable :: u(:), ty(:)
        real(dp) :: tl
        logical :: ok
        integer :: n

        report%message = ""
        n = size(state%y)
        call setup_bordered(b, sys, opts, state%y, error)
        if (allocated(error)) return
        b%fixed = .true.
        b%lfix = state%lambda
        call sys%anchor(state%y, state%lambda)
        u = [state%y, state%lambda]
        call correct(b, opts, u, report, ok, error)
        if (allocated(error) .or. .not. ok) return
        call tangent(b, u(1:n), state%lambda, state%ty, state%tl, ty, tl, ok)
        if (ok) then
            call rescale_tangent(b, opts, u(1:n), ty, tl)
            state%ty = ty
            state%tl = tl
        end if
        state%y = u(1:n)
        state%ds = opts%step
        state%failures = 0
        state%reason = reason_running
        report%accepted = .true.
    end subroutine resume_continuation

    !> Advance the continuation by one point. Sets state%reason when it stops (the end of the
    !> range reached, too many failed points, max_points, or the branch left the range on
    !> the side of the start). Errors: stat numerical (NaN in the system), stat input.
    subroutine continuation_step(sys, opts, state, report, error)
        !> The family of systems.
        class(parametric_system_t), target, intent(inout) :: sys
        !> Options (the same as at the start).
        type(continuation_options_t), intent(in) :: opts
        !> The state, advanced.
        type(continuation_state_t), intent(inout) :: state
        !> What happened.
        type(continuation_report_t), intent(out) :: report
        !> Set on numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        type(bordered_t) :: b
        real(dp), allocatable :: u(:), typ(:)
        real(dp) :: ds, dsh, lp, dir, dist, tlp
        logical :: ok, at_end
        integer :: n
        character(len=200) :: buf

        report%message = ""
        if (state%reason /= reason_running) return
        if (state%points >= opts%max_points) then
            state%reason = reason_max_points
            return
        end if
        n = size(state%y)
        call setup_bordered(b, sys, opts, state%y, error)
        if (allocated(error)) return
        dir = sign(1.0_dp, opts%stop - opts%start)
        ds = state%ds
        call sys%anchor(state%y, state%lambda)
        do
            dsh = ds/b%ps
            lp = state%lambda + dsh*b%ps*state%tl
            at_end = (lp - opts%stop)*dir >= 0.0_dp
            b%yp = state%y + dsh*b%ys*state%ty
            b%lp = lp
            b%ty = state%ty
            b%tl = state%tl
            if (at_end) then
                ! the last point: at the end of the range exactly
                b%fixed = .true.
                b%lfix = opts%stop
                if (abs(state%tl) > 0.0_dp) b%yp = state%y + b%ys*state%ty* &
                    ((opts%stop - state%lambda)/(b%ps*state%tl))
                u = [b%yp, opts%stop]
            else
                b%fixed = .false.
                u = [b%yp, lp]
            end if
            call correct(b, opts, u, report, ok, error)
            if (allocated(error)) return
            if (ok .and. .not. at_end) then
                ! reject a jump: a correction much longer than the step (kinks of the
                ! nonsmooth curve make corrections of the order of the step normal)
                dist = sqrt(sum(((u(1:n) - b%yp)/b%ys)**2) + ((u(n + 1) - lp)/b%ps)**2)
                if (dist > 4.0_dp*dsh) ok = .false.
            end if
            if (ok) call direction(b, state, u, typ, tlp, ok)
            if (ok) exit
            state%rejected = state%rejected + 1
            if (ds <= opts%min_step*(1.0_dp + 1.0e-12_dp)) then
                ! the smallest step failed: the system's recovery at the predicted parameter
                u = [b%yp, merge(opts%stop, lp, at_end)]
                call sys%recover(u(1:n), u(n + 1), ok, error)
                if (allocated(error)) return
                if (ok) then
                    b%fixed = .true.
                    b%lfix = u(n + 1)
                    call check_point(b, opts, u, report, ok)
                end if
                if (ok) then
                    call direction(b, state, u, typ, tlp, ok)
                    if (.not. ok) then
                        typ = state%ty
                        tlp = state%tl
                        ok = .true.
                    end if
                    report%recovered = .true.
                    exit
                end if
                state%failures = state%failures + 1
                if (state%failures >= opts%max_failures) then
                    state%reason = reason_failures
                    write (buf, '(i0,a,g0.6,a)') state%failures, &
                        " failed points in a row after parameter ", state%lambda, &
                        " (the smallest step and the recovery both failed)"
                    report%message = trim(buf)
                    return
                end if
                ! try again with longer steps: a jump over the spot that failed
                ds = min(opts%max_step, opts%step*2.0_dp**state%failures)
                state%ds = ds
                cycle
            end if
            ds = max(0.5_dp*ds, opts%min_step)
            report%halvings = report%halvings + 1
        end do

        state%arclength = state%arclength + b%ps*sqrt(sum(((u(1:n) - state%y)/b%ys)**2) + &
                                                      ((u(n + 1) - state%lambda)/b%ps)**2)
        call rescale_tangent(b, opts, u(1:n), typ, tlp)
        state%y = u(1:n)
        state%lambda = u(n + 1)
        state%ty = typ
        state%tl = tlp
        state%points = state%points + 1
        state%failures = 0
        report%accepted = .true.
        if (report%halvings == 0 .and. report%nfev <= opts%easy) then
            ds = min(ds*opts%grow, opts%max_step)
        else if (report%nfev > opts%hard) then
            ds = max(ds/opts%grow, opts%min_step)
        end if
        state%ds = ds
        if (at_end) then
            state%reason = reason_end
        else if ((state%lambda - opts%start)*dir < -1.0e-12_dp*b%ps) then
            state%reason = reason_left
            report%message = "the branch turned back and left the range at its start"
        end if
    end subroutine continuation_step

    !> The status of a point a continuation step accepted: 'recovered' (by the system's
    !> recovery), 'end' (at the end of the range), 'halved' (after step halvings) or 'ok'.
    pure function point_status(report, state) result(status)
        !> What the step did.
        type(continuation_report_t), intent(in) :: report
        !> The state after it.
        type(continuation_state_t), intent(in) :: state
        character(len=:), allocatable :: status
        if (report%recovered) then
            status = "recovered"
        else if (state%reason == reason_end) then
            status = "end"
        else if (report%halvings > 0) then
            status = "halved"
        else
            status = "ok"
        end if
    end function point_status

    !> The direction of the curve at the new point u: the tangent of the generalized
    !> Jacobian, oriented along the secant from the last point; the secant itself where
    !> the two disagree by more than 60 degrees (a kink of the nonsmooth curve, where the
    !> one-sided tangent may point anywhere) or the tangent cannot be computed.
    subroutine direction(b, state, u, typ, tlp, ok)
        type(bordered_t), intent(inout) :: b
        type(continuation_state_t), intent(in) :: state
        real(dp), intent(in) :: u(:)
        real(dp), allocatable, intent(out) :: typ(:)
        real(dp), intent(out) :: tlp
        logical, intent(out) :: ok
        real(dp), allocatable :: sy(:)
        real(dp) :: sl, snorm, c
        integer :: n
        logical :: have_tangent
        n = size(u) - 1
        sy = (u(1:n) - state%y)/b%ys
        sl = (u(n + 1) - state%lambda)/b%ps
        snorm = sqrt(sum(sy**2) + sl**2)
        call tangent(b, u(1:n), u(n + 1), state%ty, state%tl, typ, tlp, have_tangent)
        if (.not. (snorm > 0.0_dp)) then
            ok = have_tangent
            return
        end if
        sy = sy/snorm
        sl = sl/snorm
        ok = .true.
        if (have_tangent) then
            c = dot_product(typ, sy) + tlp*sl
            if (c < 0.0_dp) then
                typ = -typ
                tlp = -tlp
                c = -c
            end if
            if (c >= 0.5_dp) return
        end if
        typ = sy
        tlp = sl
    end subroutine direction

    !> Fill the bordered system's scales, those of the unknowns at the point y.
    subroutine setup_bordered(b, sys, opts, y, error)
        type(bordered_t), intent(out) :: b
        class(parametric_system_t), target, intent(inout) :: sys
        type(continuation_options_t), intent(in) :: opts
        real(dp), intent(in) :: y(:)
        type(error_type), allocatable, intent(out) :: error
        integer :: n
        n = size(y)
        b%sys => sys
        allocate (b%ys(n), b%yp(n), b%ty(n))
        if (.not. allocated(opts%yscale)) then
            b%ys = 1.0_dp
        else if (size(opts%yscale) == 1) then
            b%ys = opts%yscale(1)
        else if (size(opts%yscale) == n) then
            b%ys = opts%yscale
        else
            call fatal_error(error, "opts%yscale: must have 1 or n entries", &
                             stickslip_stat%input)
            return
        end if
        if (any(.not. (b%ys > 0.0_dp))) then
            call fatal_error(error, "opts%yscale: must be > 0", stickslip_stat%input)
            return
        end if
        b%g = size_factor(opts, y)
        b%ys = b%ys*b%g
        b%ps = abs(opts%stop - opts%start)
        b%weight = opts%fscale
    end subroutine setup_bordered

    !> The factor max(1, ||y|| / opts%yref) on the scale of the unknowns (1 when yref = 0).
    pure real(dp) function size_factor(opts, y) result(g)
        type(continuation_options_t), intent(in) :: opts
        real(dp), intent(in) :: y(:)
        g = 1.0_dp
        if (opts%yref > 0.0_dp) then
            g = norm2(y)/opts%yref
            if (.not. (g > 1.0_dp .and. ieee_is_finite(g))) g = 1.0_dp
        end if
    end function size_factor

    !> Express the unit tangent (ty, tl), scaled by b%ys, in the scale of the unknowns at the
    !> point y (the same direction, normalized again).
    subroutine rescale_tangent(b, opts, y, ty, tl)
        type(bordered_t), intent(in) :: b
        type(continuation_options_t), intent(in) :: opts
        real(dp), intent(in) :: y(:)
        real(dp), intent(inout) :: ty(:), tl
        real(dp) :: r, nrm
        if (.not. (opts%yref > 0.0_dp)) return
        ! the unknowns' scale goes from base g_old to base g_new: their scaled components
        ! change by g_old / g_new, the parameter's do not
        r = b%g/size_factor(opts, y)
        ty = ty*r
        nrm = sqrt(sum(ty**2) + tl**2)
        if (nrm > 0.0_dp) then
            ty = ty/nrm
            tl = tl/nrm
        end if
    end subroutine rescale_tangent

    !> hybrj on the bordered system from u (its algorithm on LAPACK's QR from
    !> powell_min_unknowns unknowns); ok when ||F|| meets the tolerance.
    subroutine correct(b, opts, u, report, ok, error)
        type(bordered_t), intent(inout) :: b
        type(continuation_options_t), intent(in) :: opts
        real(dp), intent(inout) :: u(:)
        type(continuation_report_t), intent(inout) :: report
        logical, intent(out) :: ok
        type(error_type), allocatable, intent(out) :: error
        type(hybrj_options_t) :: hopts
        type(hybrj_report_t) :: hrep
        real(dp), allocatable :: u0(:)
        integer :: attempt
        hopts%maxfev = opts%maxfev
        hopts%ftarget = opts%tol*max(opts%fscale, b%sys%residual_scale(u(size(u))))
        u0 = u
        ok = .false.
        do attempt = 1, 2
            if (size(u) >= powell_min_unknowns) then
                call solve_powell(b, u, hopts, hrep, error)
            else
                call solve_hybrj(b, u, hopts, hrep, error)
            end if
            report%nfev = report%nfev + hrep%nfev
            if (allocated(error)) then
                if (error%stat /= stickslip_stat%callback) return
                ! a NaN at a trial point: a failed correction, not a failed continuation
                deallocate (error)
                u = u0
                return
            end if
            call check_point(b, opts, u, report, ok)
            if (ok .or. hrep%info == 2) return
        end do
    end subroutine correct

    !> ok when the point u meets the residual tolerance (and lies on the bordering equation).
    subroutine check_point(b, opts, u, report, ok)
        type(bordered_t), intent(inout) :: b
        type(continuation_options_t), intent(in) :: opts
        real(dp), intent(in) :: u(:)
        type(continuation_report_t), intent(inout) :: report
        logical, intent(out) :: ok
        real(dp) :: f(size(u))
        integer :: stat, n
        n = size(u) - 1
        stat = 0
        call b%sys%residual(u(1:n), u(n + 1), f(1:n), stat)
        report%nfev = report%nfev + 1
        report%fnorm = norm2(f(1:n))
        ok = stat == 0 .and. report%fnorm <= opts%tol*max(opts%fscale, &
                                                           b%sys%residual_scale(u(n + 1))) &
             .and. all(ieee_is_finite(u))
    end subroutine check_point

    !> Unit tangent (scaled coordinates) at (y, lambda): the null vector of [dF/dy dF/dl]
    !> normalized by the previous tangent (t0y, t0l): [J; t0^T] t = [0; 1]. ok = .false.
    !> when that bordered matrix is singular.
    subroutine tangent(b, y, lambda, t0y, t0l, ty, tl, ok)
        type(bordered_t), intent(inout) :: b
        real(dp), intent(in) :: y(:), lambda, t0y(:), t0l
        real(dp), allocatable, intent(out) :: ty(:)
        real(dp), intent(out) :: tl
        logical, intent(out) :: ok
        real(dp), allocatable :: a(:, :), rhs(:, :), jl(:)
        integer, allocatable :: ipiv(:)
        integer :: n, stat, info, k
        real(dp) :: nrm
        n = size(y)
        allocate (a(n + 1, n + 1), rhs(n + 1, 1), jl(n), ipiv(n + 1), ty(n))
        stat = 0
        call b%sys%jacobian(y, lambda, a(1:n, 1:n), jl, stat)
        ok = stat == 0
        if (.not. ok) return
        ! unknowns in scaled coordinates: columns times the scales
        do k = 1, n
            a(1:n, k) = a(1:n, k)*b%ys(k)
        end do
        a(1:n, n + 1) = jl*b%ps
        a(n + 1, 1:n) = t0y
        a(n + 1, n + 1) = t0l
        rhs = 0.0_dp
        rhs(n + 1, 1) = 1.0_dp
        call dgetrf(n + 1, n + 1, a, n + 1, ipiv, info)
        if (info /= 0) then
            ok = .false.
            return
        end if
        call dgetrs('N', n + 1, 1, a, n + 1, ipiv, rhs, n + 1, info)
        nrm = norm2(rhs(:, 1))
        ok = info == 0 .and. nrm > 0.0_dp .and. ieee_is_finite(nrm)
        if (.not. ok) return
        ty = rhs(1:n, 1)/nrm
        tl = rhs(n + 1, 1)/nrm
    end subroutine tangent

    !> [F(y, lambda); weight * (t . (u - u_p) scaled)] or [F; weight (lambda - lfix) / p_s].
    subroutine bordered_residual(self, x, f, stat)
        class(bordered_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        integer :: n
        n = size(x) - 1
        call self%sys%residual(x(1:n), x(n + 1), f(1:n), stat)
        if (self%fixed) then
            f(n + 1) = self%weight*(x(n + 1) - self%lfix)/self%ps
        else
            f(n + 1) = self%weight*(sum(self%ty*(x(1:n) - self%yp)/self%ys) + &
                                    self%tl*(x(n + 1) - self%lp)/self%ps)
        end if
    end subroutine bordered_residual

    !> The Jacobian of the bordered system.
    subroutine bordered_jacobian(self, x, jac, stat)
        class(bordered_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: jac(:, :)
        integer, intent(inout) :: stat
        integer :: n
        n = size(x) - 1
        call self%sys%jacobian(x(1:n), x(n + 1), jac(1:n, 1:n), jac(1:n, n + 1), stat)
        if (self%fixed) then
            jac(n + 1, 1:n) = 0.0_dp
            jac(n + 1, n + 1) = self%weight/self%ps
        else
            jac(n + 1, 1:n) = self%weight*self%ty/self%ys
            jac(n + 1, n + 1) = self%weight*self%tl/self%ps
        end if
    end subroutine bordered_jacobian

    !> The default residual scale: 0 (opts%fscale alone sets the tolerance).
    real(dp) function unit_scale(self, lambda) result(s)
        !> The family of systems.
        class(parametric_system_t), intent(inout) :: self
        !> Parameter.
        real(dp), intent(in) :: lambda
        s = 0.0_dp
    end function unit_scale

    !> The default anchor: none (every unknown is determined by the equations).
    subroutine no_anchor(self, y, lambda)
        !> The family of systems.
        class(parametric_system_t), intent(inout) :: self
        !> The point the next corrections start from (the last accepted one).
        real(dp), intent(in) :: y(:), lambda
    end subroutine no_anchor

    !> The default recovery: none.
    subroutine no_recovery(self, y, lambda, ok, error)
        !> The family of systems.
        class(parametric_system_t), intent(inout) :: self
        !> Start on entry; the solution on exit when ok.
        real(dp), intent(inout) :: y(:)
        !> Parameter (fixed).
        real(dp), intent(in) :: lambda
        !> A solution was found.
        logical, intent(out) :: ok
        !> Set on breakdown.
        type(error_type), allocatable, intent(out) :: error
        ok = .false.
    end subroutine no_recovery
end module stickslip_continuation
