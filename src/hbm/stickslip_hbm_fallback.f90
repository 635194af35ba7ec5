!> The fallbacks of the weighted-residual solve: what solve_condensed (stickslip_hbm) tries,
!> in this order, when its start and ladder (stickslip_hbm_strategy) end short of the
!> tolerance (doc/convergence.md, "When the solve fails"):
!>  1. semismooth Newton with its line search from the best point met (rescue_newton);
!>  2. a homotopy in the load (rescue_load): the periodic forcing scaled by s from 0 (the
!>     static state, every contact stuck or at its static gap) to 1, each step predicted by
!>     the secant of the last two and corrected by Newton (Powell's method where Newton's
!>     Jacobian is singular: a contact stuck all period), the step halved on failure;
!>  3. other weights rho (rescue_rho): the equations with rho x 1/4, 4, 1/16, 16, solved by
!>     the same start, ladder and load homotopy; a root there is a warm start at rho; when
!>     Newton and Powell cannot continue it to rho, it is kept as the answer (the projected
!>     equalities hold for any rho > 0 and their roots converge to the same orbit as H
!>     grows; its own rho is reported in hbm_solution_t%rho);
!>  4. the load homotopy at rho again, past the turning points of its path (a fold of the
!>     response in the load: the natural steps stall there) by pseudo-arclength steps
!>     (arclength_load) from where the natural steps of stage 2 stalled (load_stall_t; from
!>     s = 0 when they did not get two answers), with a budget of its own.
!> Each returns converged (sol%converged) or leaves y at its best point. The stage that
!> succeeded is named in hbm_solution_t%rescue. A NaN met in a stage fails that stage only.
module stickslip_hbm_fallback
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t, new_condensed_problem
    use stickslip_condensed_structure, only: condensed_structure_t
    use stickslip_contact_element, only: channel_t, kinematics_gap
    use stickslip_contact_law, only: state_open
    use stickslip_hbm_strategy, only: solve_stage, solve_primary, condensed_convergence_scale
    use stickslip_newton, only: newton_options_t, newton_report_t, solve_newton, &
        newton_converged, newton_singular
    use stickslip_lapack, only: dgetrf, dgetrs
    implicit none
    private
    public :: solve_fallbacks, rescue_newton, rescue_load, rigid_contact_opens

    !> Smallest load step of the homotopy (a fraction of the forcing).
    real(dp), parameter :: min_load_step = 1.0_dp/1024.0_dp
    !> Largest number of load steps tried (successful or not).
    integer, parameter :: max_load_steps = 80
    !> The fallbacks stop once they have evaluated this many Jacobians beyond those of the
    !> first attempt, or fallback_budget_factor times as many as it did, whichever is
    !> more (each is an LU or a QR of the same size: a bound on their cost in units of
    !> the first attempt's, independent of the machine).
    integer, parameter :: fallback_budget_min = 200
    integer, parameter :: fallback_budget_factor = 10
    !> Largest number of arclength steps of the load homotopy past a turning point, and the
    !> Newton iterations of each corrector.
    integer, parameter :: max_arc_steps = 120, max_arc_newton = 12
    !> The other weights tried, as factors of rho, in this order.
    real(dp), parameter :: rho_factors(4) = [0.25_dp, 4.0_dp, 0.0625_dp, 16.0_dp]

    !> Where the natural steps of a load homotopy stalled: its last two answers (ya at sa,
    !> yb at s; have = .false. when it did not get two), so that the arclength stage goes on
    !> from there instead of walking the natural steps again.
    type :: load_stall_t
        logical :: have = .false.
        real(dp) :: sa = 0.0_dp, s = 0.0_dp
        real(dp), allocatable :: ya(:), yb(:)
    end type load_stall_t

contains

    !> The fallbacks in order (module doc) after a failed first attempt whose last iterate
    !> is y. Converged: sol%converged, sol%rescue names the stage, y the answer; with
    !> 'rho_kept', prob is replaced by the equations at the weight `rho_used` (and
    !> sol%fscale by their scale). Not converged: y the best point met, sol%fnorm its
    !> residual. Nothing is tried when a rigid unilateral contact opens and closes at the
    !> last iterate (an impact: rigid_contact_opens), which no weight, start or homotopy
    !> makes a truncated series carry. Errors: as solve_stage.
    subroutine solve_fallbacks(s, o, prob, y, target_norm, sol, error, rho_used)
        !> The structure's data (forcing harmonics, automatic rho).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options in effect (rho > 0).
        type(hbm_options_t), intent(in) :: o
        !> The projected contact equations (replaced with 'rho_kept').
        type(hb_problem_t), intent(inout) :: prob
        !> Channel force coefficients [N]: the last iterate, then the answer or best point.
        real(dp), intent(inout) :: y(:)
        !> The residual to reach [m/s].
        real(dp), intent(in) :: target_norm
        !> Convergence report (sol%fscale set; counts accumulated).
        type(hbm_solution_t), intent(inout) :: sol
        !> Set on a NaN or misuse.
        type(error_type), allocatable, intent(out) :: error
        !> The weight of the answer [m/(N s)] (o%rho unless 'rho_kept').
        real(dp), intent(out) :: rho_used
        type(hb_problem_t) :: alt
        type(hbm_options_t) :: oa
        real(dp), allocatable :: ybest(:), ya(:), zero(:, :)
        real(dp) :: best, step_target, fscale_alt, target_alt, fnorm_alt
        integer :: k, last_njev, njev0
        type(load_stall_t) :: stall

        rho_used = o%rho
        if (rigid_contact_opens(prob, y)) return
        njev0 = sol%njev
        last_njev = sol%njev + max(fallback_budget_min, fallback_budget_factor*njev0)
        step_target = max(target_norm, 1.0e-6_dp*sol%fscale)
        ybest = y
        best = sol%fnorm
        call rescue_newton(prob, y, target_norm, sol, error)
        if (stage_failed()) return
        if (sol%converged) then
            sol%rescue = 'newton'
            return
        end if
        call keep_best()
        call rescue_load(prob, o, y, target_norm, step_target, sol, error, last_njev, &
                         stall=stall)
        if (stage_failed()) return
        if (sol%converged) then
            sol%rescue = 'load'
            return
        end if
        allocate (zero(prob%basis%nb, prob%nc))
        zero = 0.0_dp
        do k = 1, size(rho_factors)
            if (sol%njev >= last_njev) exit
            oa = o
            oa%rho = o%rho*rho_factors(k)
            call new_condensed_problem(alt, prob%dyn, prob%contacts, o%harmonics, o%odd_only, &
                                       o%samples, oa%rho, error, s%force_harmonic)
            if (allocated(error)) return
            fscale_alt = condensed_convergence_scale(alt, s%rho_auto)
            target_alt = o%tol*fscale_alt
            ya = reshape(zero, [alt%n])
            call solve_primary(s, oa, oa, alt, ya, zero, target_alt, sol, error, .false.)
            if (.not. allocated(error) .and. .not. sol%converged) &
                call rescue_load(alt, oa, ya, target_alt, max(target_alt, 1.0e-6_dp*fscale_alt), &
                                 sol, error, last_njev)
            if (stage_failed()) then
                call alt%destroy()
                return
            end if
            if (sol%converged) then
                fnorm_alt = sol%fnorm
                ! the root at the other weight as a start at rho
                y = ya
                call rescue_newton(prob, y, target_norm, sol, error)
                if (stage_failed()) then
                    call alt%destroy()
                    return
                end if
                if (sol%converged) then
                    sol%rescue = 'rho'
                    call alt%destroy()
                    return
                end if
                ! kept: the equations at the other weight become the problem
                call prob%destroy()
                prob = alt
                y = ya
                rho_used = oa%rho
                sol%fscale = fscale_alt
                sol%fnorm = fnorm_alt
                sol%converged = .true.
                sol%info = -1
                sol%rescue = 'rho_kept'
                return
            end if
            call alt%destroy()
        end do
        ! last: the load homotopy at rho again, past the turning points of its path, from
        ! where its natural steps stalled, with a budget of its own as large as the one spent
        y = ybest
        last_njev = sol%njev + max(fallback_budget_min, fallback_budget_factor*njev0)
        call rescue_load(prob, o, y, target_norm, step_target, sol, error, last_njev, &
                         arclength=.true., resume=stall)
        if (stage_failed()) return
        if (sol%converged) then
            sol%rescue = 'arclength'
            return
        end if
        y = ybest
        sol%fnorm = best

    contains

        !> An error other than a NaN ends the fallbacks (stat input, lapack: misuse); a NaN
        !> met on the way (a step of a homotopy or another weight too far) fails the stage
        !> only: y back to the best point, the error cleared.
        logical function stage_failed()
            stage_failed = .false.
            if (.not. allocated(error)) return
            if (error%stat == stickslip_stat%numerical) then
                deallocate (error)
                sol%converged = .false.
                y = ybest
                return
            end if
            stage_failed = .true.
        end function stage_failed

        subroutine keep_best()
            if (sol%fnorm < best) then
                best = sol%fnorm
                ybest = y
            else
                y = ybest
            end if
        end subroutine keep_best
    end subroutine solve_fallbacks

    !> Whether a rigid unilateral contact (a gap channel without compliance) is open at some
    !> samples and closed at others at the channel forces y: it closes with an impact,
    !> whose velocity jump a truncated Fourier series cannot carry.
    logical function rigid_contact_opens(prob, y) result(opens)
        !> The projected contact equations.
        type(hb_problem_t), intent(inout) :: prob
        !> Channel force coefficients [N].
        real(dp), intent(in) :: y(:)
        real(dp), allocatable :: r(:, :), u(:, :)
        integer, allocatable :: state(:, :)
        type(channel_t) :: ch
        integer :: j, c, nt
        logical :: rigid
        opens = .false.
        nt = prob%basis%nt
        allocate (r(nt, prob%nc), u(nt, prob%nc), state(nt, prob%contacts%ncontact))
        call prob%law_samples(y, r, u, state)
        do j = 1, prob%contacts%ncontact
            rigid = .false.
            do c = prob%contacts%first(j), prob%contacts%first(j) + prob%contacts%width(j) - 1
                ch = prob%contacts%channel(c)
                if (ch%kinematics == kinematics_gap .and. .not. (ch%compliance > 0.0_dp)) &
                    rigid = .true.
            end do
            if (.not. rigid) cycle
            if (any(state(:, j) == state_open) .and. any(state(:, j) /= state_open)) then
                opens = .true.
                return
            end if
        end do
    end function rigid_contact_opens

    !> Semismooth Newton with line search from `y` to `target_norm`; y is left at the best
    !> point met. Errors: as solve_newton (a NaN in the residual: stat numerical).
    subroutine rescue_newton(prob, y, target_norm, sol, error, singular)
        !> The projected contact equations.
        type(hb_problem_t), intent(inout) :: prob
        !> Channel force coefficients [N]: the start, then the best point.
        real(dp), intent(inout) :: y(:)
        !> The residual to reach [m/s].
        real(dp), intent(in) :: target_norm
        !> Convergence report (converged, fnorm, info; counts accumulated).
        type(hbm_solution_t), intent(inout) :: sol
        !> Set on a NaN or misuse.
        type(error_type), allocatable, intent(out) :: error
        !> Newton stopped at a singular Jacobian.
        logical, intent(out), optional :: singular
        type(newton_options_t) :: nopts
        type(newton_report_t) :: nrep
        nopts%ftarget = target_norm
        call solve_newton(prob, y, nopts, nrep, error)
        sol%nfev = sol%nfev + nrep%nfev
        sol%njev = sol%njev + nrep%njev
        sol%newton_calls = sol%newton_calls + 1
        if (present(singular)) singular = nrep%outcome == newton_singular
        if (allocated(error)) return
        sol%fnorm = nrep%fnorm
        sol%converged = nrep%outcome == newton_converged
        if (sol%converged) sol%info = -1
    end subroutine rescue_newton

    !> Homotopy in the periodic load: the contact velocities of the structure without
    !> contact forces (prob%dyn%v0, the forcing's) scaled by s from 0 to 1, the static loads
    !> (preloads, gaps, a static forcing) kept. At s = 0 the answer is the static state;
    !> each step starts from the secant through the last two answers and is corrected by
    !> Newton, or by Powell's method (opts: its evaluations per call) where Newton's
    !> Jacobian is singular; a failed step is halved (down to min_load_step), a good one
    !> lengthened. The intermediate answers are solved to `step_target`, the last to
    !> `target_norm`; it stops short once sol%njev reaches last_njev. y: the answer at s = 1
    !> when converged, else the start. prob%dyn%v0 is restored.
    subroutine rescue_load(prob, opts, y, target_norm, step_target, sol, error, last_njev, &
                           arclength, stall, resume)
        !> The projected contact equations.
        type(hb_problem_t), intent(inout) :: prob
        !> Solver options in effect (rho set).
        type(hbm_options_t), intent(in) :: opts
        !> Channel force coefficients [N].
        real(dp), intent(inout) :: y(:)
        !> The residual to reach at s = 1 [m/s].
        real(dp), intent(in) :: target_norm
        !> The residual to reach on the way [m/s].
        real(dp), intent(in) :: step_target
        !> Convergence report (counts accumulated).
        type(hbm_solution_t), intent(inout) :: sol
        !> Set on a NaN or misuse.
        type(error_type), allocatable, intent(out) :: error
        !> Stop (not converged) once sol%njev reaches this.
        integer, intent(in) :: last_njev
        !> Where the natural steps stall, follow the path in its arclength (arclength_load).
        logical, intent(in), optional :: arclength
        !> Where the natural steps stalled (their last two answers), when they did.
        type(load_stall_t), intent(out), optional :: stall
        !> Go on from there (no natural steps) when it holds two answers.
        type(load_stall_t), intent(in), optional :: resume
        complex(dp), allocatable :: v0(:, :)
        real(dp), allocatable :: ya(:), yb(:), yt(:), ystart(:)
        real(dp) :: s, sa, ds, st, tgt
        integer :: k
        logical :: have_two, ok, follow

        v0 = prob%dyn%v0
        ystart = y
        follow = .false.
        if (present(arclength)) follow = arclength
        if (present(resume)) then
            if (resume%have) then
                ya = resume%ya
                sa = resume%sa
                yb = resume%yb
                s = resume%s
                have_two = .true.
                ok = .false.
                if (follow) call arclength_load(prob, opts, v0, ya, sa, yb, s, target_norm, &
                                                step_target, sol, error, last_njev, ok)
                if (ok .and. .not. allocated(error)) s = 1.0_dp
                call finish(s >= 1.0_dp)
                return
            end if
        end if
        ! s = 0: the static state, from no contact force
        allocate (ya(size(y)))
        ya = 0.0_dp
        prob%dyn%v0 = (0.0_dp, 0.0_dp)
        call correct(ya, step_target, ok)
        if (allocated(error) .or. .not. ok) then
            call finish(.false.)
            return
        end if
        yb = ya
        s = 0.0_dp
        sa = 0.0_dp
        have_two = .false.
        ds = 0.125_dp
        do k = 1, max_load_steps
            if (sol%njev >= last_njev) exit
            st = min(1.0_dp, s + ds)
            yt = yb
            if (have_two) yt = yb + (st - s)/(s - sa)*(yb - ya)
            prob%dyn%v0 = st*v0
            tgt = step_target
            if (st >= 1.0_dp) tgt = target_norm
            call correct(yt, tgt, ok)
            if (allocated(error)) exit
            if (ok) then
                ya = yb
                sa = s
                yb = yt
                s = st
                have_two = .true.
                if (s >= 1.0_dp) exit
                ds = min(2.0_dp*ds, 0.5_dp)
            else
                ds = 0.5_dp*ds
                if (ds < min_load_step) exit
            end if
        end do
        ! stalled short of s = 1 (a turning point of the path in the load: a fold of the
        ! response): follow the path in its arclength from the last two answers
        if (present(stall) .and. s < 1.0_dp .and. have_two) then
            stall%have = .true.
            stall%ya = ya
            stall%sa = sa
            stall%yb = yb
            stall%s = s
        end if
        if (follow .and. s < 1.0_dp .and. have_two .and. .not. allocated(error)) then
            call arclength_load(prob, opts, v0, ya, sa, yb, s, target_norm, step_target, sol, &
                                error, last_njev, ok)
            if (ok) s = 1.0_dp
        end if
        call finish(s >= 1.0_dp)

    contains

        !> Newton from yc to tgt; Powell's method where its Jacobian is singular.
        subroutine correct(yc, tgt, ok)
            real(dp), intent(inout) :: yc(:)
            real(dp), intent(in) :: tgt
            logical, intent(out) :: ok
            logical :: singular
            real(dp), allocatable :: y0(:)
            y0 = yc
            call rescue_newton(prob, yc, tgt, sol, error, singular)
            if (allocated(error)) then
                ok = .false.
                return
            end if
            ok = sol%converged
            if (ok .or. .not. singular) return
            yc = y0
            call solve_stage(prob, yc, opts, tgt, sol, error)
            ok = sol%converged .and. .not. allocated(error)
        end subroutine correct

        !> Restore the load; the answer (converged) or the best point at s = 1.
        subroutine finish(done)
            logical, intent(in) :: done
            prob%dyn%v0 = v0
            sol%converged = done .and. .not. allocated(error)
            if (done) then
                y = yb
            else
                y = ystart
            end if
        end subroutine finish
    end subroutine rescue_load

    !> The load homotopy past turning points: pseudo-arclength continuation of F(y, s) = 0
    !> in the scaled coordinates (y / f_s, s), f_s the contacts' force scale, from the two
    !> answers (y0, s0), (y1, s1) of the natural steps, their secant the first direction.
    !> Each step predicts along the secant of the last two points and corrects by Newton on
    !> the bordered system [dF/dy, dF/ds; t] (dF/ds by a forward difference: F is affine in
    !> the load within a piece), backtracking on the residual; a step is halved when the
    !> corrector fails or turns back, lengthened after an easy one. Once s passes 1, the
    !> answer at s = 1 is corrected from the chord between the last two points (Newton, or
    !> Powell's method from there). ok: y1 holds the answer at s = 1 (prob%dyn%v0 = v0).
    subroutine arclength_load(prob, opts, v0, y0, s0, y1, s1, target_norm, step_target, sol, &
                              error, last_njev, ok)
        type(hb_problem_t), intent(inout) :: prob
        type(hbm_options_t), intent(in) :: opts
        complex(dp), intent(in) :: v0(:, :)
        real(dp), intent(inout) :: y0(:), y1(:)
        real(dp), intent(inout) :: s0, s1
        real(dp), intent(in) :: target_norm, step_target
        type(hbm_solution_t), intent(inout) :: sol
        type(error_type), allocatable, intent(out) :: error
        integer, intent(in) :: last_njev
        logical, intent(out) :: ok
        real(dp), allocatable :: t(:), z0(:), z1(:), zp(:), z(:), a(:, :), b(:), f(:), ft(:), &
                                 jac(:, :), fs(:), yc(:)
        integer, allocatable :: ipiv(:)
        integer :: n, k, it, info, stat, ls
        real(dp) :: fsc, h, tn, fn, fnt, g, lam, st, w
        logical :: done

        ok = .false.
        n = size(y1)
        fsc = max(prob%contacts%force_scale(), tiny(1.0_dp))
        allocate (a(n + 1, n + 1), b(n + 1), f(n), ft(n), jac(n, n), fs(n), ipiv(n + 1))
        z0 = [y0/fsc, s0]
        z1 = [y1/fsc, s1]
        if (.not. (norm2(z1 - z0) > 0.0_dp)) return
        h = max(norm2(z1 - z0), 1.0_dp/64.0_dp)
        do k = 1, max_arc_steps
            if (sol%njev >= last_njev) return
            t = (z1 - z0)/norm2(z1 - z0)
            zp = z1 + h*t
            z = zp
            done = .false.
            do it = 1, max_arc_newton
                call eval(z, f, stat)
                if (stat /= 0) exit
                g = dot_product(t, z - zp)
                fn = sqrt(sum(f**2) + (fsc*g)**2)
                if (norm2(f) <= step_target) then
                    done = .true.
                    exit
                end if
                ! the bordered Jacobian in the scaled unknowns
                prob%dyn%v0 = z(n + 1)*v0
                stat = 0
                call prob%jacobian(z(1:n)*fsc, jac, stat)
                sol%njev = sol%njev + 1
                if (stat /= 0) exit
                w = 1.0e-7_dp
                prob%dyn%v0 = (z(n + 1) + w)*v0
                call prob%residual(z(1:n)*fsc, ft, stat)
                sol%nfev = sol%nfev + 1
                fs = (ft - f)/w
                a(1:n, 1:n) = jac*fsc
                a(1:n, n + 1) = fs
                a(n + 1, :) = t
                b(1:n) = -f
                b(n + 1) = -g
                call dgetrf(n + 1, n + 1, a, n + 1, ipiv, info)
                if (info /= 0) exit
                call dgetrs('N', n + 1, 1, a, n + 1, ipiv, b, n + 1, info)
                if (info /= 0) exit
                ! backtracking on the bordered residual
                lam = 1.0_dp
                do ls = 1, 10
                    call eval(z + lam*b, ft, stat)
                    fnt = sqrt(sum(ft**2) + (fsc*dot_product(t, z + lam*b - zp))**2)
                    if (stat == 0 .and. fnt < (1.0_dp - 1.0e-4_dp*lam)*fn) exit
                    lam = 0.5_dp*lam
                end do
                if (ls > 10) exit
                z = z + lam*b
            end do
            if (done .and. dot_product(t, z - z1) > 0.0_dp) then
                z0 = z1
                z1 = z
                if (it <= 4) h = min(2.0_dp*h, 0.5_dp)
                if (z1(n + 1) >= 1.0_dp) exit
            else
                h = 0.5_dp*h
                if (h < min_load_step) return
            end if
        end do
        if (z1(n + 1) < 1.0_dp) return
        ! the answer at s = 1 from the chord between the last two points
        st = (1.0_dp - z0(n + 1))/(z1(n + 1) - z0(n + 1))
        yc = fsc*(z0(1:n) + st*(z1(1:n) - z0(1:n)))
        prob%dyn%v0 = v0
        call rescue_newton(prob, yc, target_norm, sol, error)
        if (allocated(error)) return
        if (.not. sol%converged) then
            call solve_stage(prob, yc, opts, target_norm, sol, error)
            if (allocated(error)) return
        end if
        ok = sol%converged
        if (ok) then
            y1 = yc
            s1 = 1.0_dp
        end if

    contains

        !> F at the scaled point zz (the load z(n+1)).
        subroutine eval(zz, ff, st)
            real(dp), intent(in) :: zz(:)
            real(dp), intent(out) :: ff(:)
            integer, intent(out) :: st
            st = 0
            prob%dyn%v0 = zz(n + 1)*v0
            call prob%residual(zz(1:n)*fsc, ff, st)
            sol%nfev = sol%nfev + 1
        end subroutine eval
    end subroutine arclength_load
end module stickslip_hbm_fallback
