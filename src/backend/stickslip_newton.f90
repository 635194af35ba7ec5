!> Semismooth Newton with a dense LU (LAPACK dgetrf/dgetrs on the linked BLAS) for a
!> `nonlinear_system_t` with an element of its generalized Jacobian: the fast path of the
!> weighted-residual solve at hundreds of unknowns (doc/benchmarks.md, "The nonlinear solve at hundreds of unknowns").
!>
!> Newton steps x <- x - t J(x)^-1 F(x) with backtracking on ||F||: the full step t = 1
!> first, halved (at most max_halvings times) until ||F||^2 drops by Armijo's factor
!> (1 - 2e-4 t). On a piecewise-linear system started close to its root (a warm start: the
!> solution on fewer harmonics, a nearby continuation point) the full step is taken almost
!> always and the iteration ends after a few steps, as soon as ||F|| <= ftarget; the
!> backtracking only breaks the cycles of full steps between pieces (seen on the seed case
!> at H = 200: 25 full steps between ||F|| = 3e-5 and 0.2, against 5 LUs with it). It is
!> not meant for a cold start (measured: many more LUs, or failure): the caller falls back
!> to Powell's hybrid method (stickslip_powell, stickslip_minpack) when this returns without
!> meeting ftarget, which happens when the Jacobian is singular (a contact stuck over the
!> whole period leaves its mean force undetermined), when no step length lowers ||F|| (a
!> roundoff floor above ftarget) or after max_iterations steps. x returns the best point
!> met.
!>
!> Chord steps (a Shamanskii-type reuse of the factorization): after a Newton step, the next
!> step first tries the LU of the last Jacobian, x <- x - J_old^-1 F(x) (one triangular
!> solve and one residual, no Jacobian, no factorization), and keeps it when ||F|| drops
!> below chord_ratio times its value before the step; otherwise the step is thrown away and
!> a Newton step is taken at the same point. On a piecewise-linear system the Jacobian
!> changes only where a sample crosses a kink, so late in the iteration J_old is J or close
!> to it and the chord steps converge as Newton's (measured on a 20-contact chain at 620
!> unknowns: 7 factorizations of 6.8 ms became 4, plus 11 chord steps of 0.4 ms).
!>
!> Mixed precision: from single_min_unknowns on, the Jacobian is factorized in single
!> precision (sgetrf: 1.9x faster than dgetrf at n = 620, 1.6x at 300 with OpenBLAS here)
!> unless its pivots span more than 1 / single_pivot_min (a cheap screen: LAPACK's
!> condition estimate would cost another 27% of the factorization); the step then carries
!> a relative error of about cond x 6e-8, which the iteration corrects like any inexact
!> Newton step: every residual, every iterate and the convergence test stay in double
!> precision, so the answer does not change. When a step from a single-precision
!> factorization does not lower ||F|| (a Jacobian too ill-conditioned for single
!> precision), the Jacobian is factorized again in double precision, with the condition
!> estimate and the singularity test, before the iteration counts as stalled.
!>
!> No module state: re-entrant and thread-safe (one system instance per thread).
module stickslip_newton
    use stickslip_kinds, only: dp, sp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_lapack, only: dgetrf, dgetrs, dgecon, dlange, sgetrf, sgetrs
    implicit none
    private
    public :: newton_options_t, newton_report_t, solve_newton
    public :: newton_converged, newton_singular, newton_stalled, newton_max_iterations

    !> Outcomes (newton_report_t%outcome).
    integer, parameter :: newton_converged = 0, newton_singular = 1, newton_stalled = 2, &
        newton_max_iterations = 3

    !> Options of solve_newton.
    type :: newton_options_t
        !> Stop when ||F(x)||_2 <= ftarget (> 0).
        real(dp) :: ftarget = 0.0_dp
        !> Largest number of Newton steps (LU factorizations).
        integer :: max_iterations = 25
        !> Step halvings tried before a Newton direction counts as a stall (no decrease
        !> of ||F|| along it: a roundoff floor above ftarget, or a wrong piece).
        integer :: max_halvings = 10
        !> The Jacobian counts as singular when LAPACK's estimate of its reciprocal
        !> 1-norm condition number is below this.
        real(dp) :: rcond_min = 1.0e-13_dp
        !> A chord step (the last LU reused) is kept when it lowers ||F|| below this
        !> fraction of its value; 0: Newton steps only.
        real(dp) :: chord_ratio = 0.5_dp
        !> Largest number of chord steps in all.
        integer :: max_chord_steps = 60
        !> From this many unknowns on, factorize in single precision first (0: never).
        integer :: single_min_unknowns = 200
        !> A single-precision factorization is used when its smallest pivot is at least this
        !> fraction of its largest; else the Jacobian is factorized in double precision.
        real(dp) :: single_pivot_min = 1.0e-5_dp
    end type newton_options_t

    !> What one solve_newton call did.
    type :: newton_report_t
        !> newton_converged, newton_singular, newton_stalled or newton_max_iterations.
        integer :: outcome = newton_max_iterations
        !> Residual evaluations.
        integer :: nfev = 0
        !> Jacobian evaluations (= LU factorizations).
        integer :: njev = 0
        !> Chord steps kept (solves with an earlier LU).
        integer :: chord_steps = 0
        !> Factorizations done in single precision (of njev).
        integer :: single_lus = 0
        !> Steps from a single-precision factorization that failed and were taken again
        !> with a double-precision factorization of the same Jacobian.
        integer :: double_retries = 0
        !> ||F||_2 at the returned point (the best met).
        real(dp) :: fnorm = huge(1.0_dp)
        !> Reciprocal condition estimate of the last Jacobian factorized in double precision
        !> (0: exactly singular; not estimated for single-precision factorizations).
        real(dp) :: rcond = 0.0_dp
    end type newton_report_t

contains

    !> Solve sys%residual(x) = 0 by semismooth Newton from the (warm) start x. Not meeting
    !> ftarget is an outcome (report%outcome), not an error. Errors: stat input for no
    !> unknowns or ftarget <= 0; stat callback when the system's callback returned a
    !> nonzero status at the start or in a Jacobian (a NaN); stat lapack for a LAPACK
    !> argument error.
    subroutine solve_newton(sys, x, opts, report, error)
        !> The system F(x) = 0.
        class(nonlinear_system_t), intent(inout) :: sys
        !> Start on entry; on exit the point of least ||F|| met.
        real(dp), intent(inout) :: x(:)
        !> Options.
        type(newton_options_t), intent(in) :: opts
        !> What happened.
        type(newton_report_t), intent(out) :: report
        !> Set on misuse, callback failure or a LAPACK argument error.
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: f(:), ft(:), jac(:, :), xt(:), xbest(:), step(:), work(:)
        real(sp), allocatable :: jac_s(:, :), step_s(:)
        integer, allocatable :: ipiv(:), iwork(:)
        integer :: n, stat, info, it, ls, tries
        real(dp) :: fnorm, best, anorm, rcond, t
        logical :: accepted, have_lu, lu_single, retry
        character(len=80) :: buf

        n = size(x)
        if (n < 1) then
            call fatal_error(error, "solve_newton: no unknowns", stickslip_stat%input)
            return
        end if
        if (.not. (opts%ftarget > 0.0_dp)) then
            call fatal_error(error, "solve_newton: ftarget must be > 0", stickslip_stat%input)
            return
        end if
        if (.not. (opts%chord_ratio >= 0.0_dp .and. opts%chord_ratio < 1.0_dp)) then
            call fatal_error(error, "solve_newton: chord_ratio must be in [0, 1)", &
                             stickslip_stat%input)
            return
        end if
        allocate (f(n), ft(n), jac(n, n), xt(n), step(n), ipiv(n), work(4*n), iwork(n))
        if (opts%single_min_unknowns > 0 .and. n >= opts%single_min_unknowns) &
            allocate (jac_s(n, n), step_s(n))
        lu_single = .false.
        stat = 0
        call sys%residual(x, f, stat)
        report%nfev = 1
        if (stat /= 0) then
            call callback_error()
            return
        end if
        best = norm2(f)
        xbest = x
        it = 0
        tries = 0
        have_lu = .false.
        do
            if (best <= opts%ftarget) then
                report%outcome = newton_converged
                exit
            end if
            ! a chord step with the last LU: kept if ||F|| drops enough, else a Newton step
            if (have_lu .and. opts%chord_ratio > 0.0_dp .and. &
                tries < opts%max_chord_steps) then
                tries = tries + 1
                call lu_solve()
                xt = x - step
                fnorm = trial_norm()
                if (fnorm <= opts%chord_ratio*norm2(f)) then
                    report%chord_steps = report%chord_steps + 1
                    call move_to_trial()
                    cycle
                end if
            end if
            if (it >= opts%max_iterations) then
                report%outcome = newton_max_iterations
                exit
            end if
            it = it + 1
            ! the Jacobian at the current iterate x, where f = F(x)
            call sys%jacobian(x, jac, stat)
            report%njev = report%njev + 1
            if (stat /= 0) then
                call callback_error()
                return
            end if
            ! single precision first when it pays and its pivots look sound
            lu_single = .false.
            if (allocated(jac_s)) then
                jac_s = real(jac, sp)
                call sgetrf(n, n, jac_s, n, ipiv, info)
                if (info == 0) lu_single = pivot_ratio() >= opts%single_pivot_min
                if (lu_single) then
                    report%single_lus = report%single_lus + 1
                    have_lu = .true.
                end if
            end if
            retry = lu_single
            if (.not. lu_single) then
                call factorize_double()
                if (allocated(error)) return
                if (.not. have_lu) then
                    report%outcome = newton_singular
                    exit
                end if
            end if
            call lu_solve()
            call backtrack()
            if (.not. accepted .and. retry) then
                ! the single-precision step failed: the same Newton step in double precision
                ! (jac still holds the Jacobian: only its single-precision copy was factorized)
                lu_single = .false.
                report%double_retries = report%double_retries + 1
                call factorize_double()
                if (allocated(error)) return
                if (.not. have_lu) then
                    report%outcome = newton_singular
                    exit
                end if
                call lu_solve()
                call backtrack()
            end if
            if (.not. accepted) then
                report%outcome = newton_stalled
                exit
            end if
            call move_to_trial()
        end do
        x = xbest
        report%fnorm = best

    contains

        !> LU of jac in double precision, its condition estimate (report%rcond); have_lu
        !> when not singular (rcond >= rcond_min). error on a LAPACK argument error.
        subroutine factorize_double()
            anorm = dlange('1', n, n, jac, n, work)
            call dgetrf(n, n, jac, n, ipiv, info)
            if (info < 0) then
                write (buf, '(a,i0)') "solve_newton: dgetrf rejected argument ", -info
                call fatal_error(error, trim(buf), stickslip_stat%lapack)
                return
            end if
            rcond = 0.0_dp
            if (info == 0 .and. anorm > 0.0_dp) then
                call dgecon('1', n, jac, n, anorm, rcond, work, iwork, info)
                if (info /= 0) rcond = 0.0_dp
            end if
            report%rcond = rcond
            have_lu = rcond >= opts%rcond_min
        end subroutine factorize_double

        !> Backtracking on ||F|| along -step (Armijo on ||F||^2/2, whose slope along the
        !> Newton step is -||F||^2): the full step first, halved at most max_halvings times;
        !> halving breaks the cycles of full steps between pieces near a kink. accepted,
        !> xt, ft and fnorm tell the outcome.
        subroutine backtrack()
            t = 1.0_dp
            accepted = .false.
            do ls = 0, opts%max_halvings
                xt = x - t*step
                fnorm = trial_norm()
                if (fnorm <= sqrt(1.0_dp - 2.0e-4_dp*t)*best) then
                    accepted = .true.
                    return
                end if
                t = 0.5_dp*t
            end do
        end subroutine backtrack

        !> The iterate moves to the trial point xt (F = ft, ||F|| = fnorm); the best point
        !> met is kept.
        subroutine move_to_trial()
            x = xt
            f = ft
            if (fnorm < best) then
                best = fnorm
                xbest = x
            end if
        end subroutine move_to_trial

        !> ft = F(xt) and its norm, counted in report%nfev; huge when the system's callback
        !> refuses the point (a NaN there: a step too far, not an error).
        real(dp) function trial_norm()
            call sys%residual(xt, ft, stat)
            report%nfev = report%nfev + 1
            if (stat /= 0) then
                stat = 0
                trial_norm = huge(1.0_dp)
            else
                trial_norm = norm2(ft)
            end if
        end function trial_norm

        !> Smallest over largest |pivot| of the single-precision factors.
        real(dp) function pivot_ratio()
            real(dp) :: lo, hi, p
            integer :: k
            lo = huge(1.0_dp)
            hi = 0.0_dp
            do k = 1, n
                p = abs(real(jac_s(k, k), dp))
                lo = min(lo, p)
                hi = max(hi, p)
            end do
            pivot_ratio = 0.0_dp
            if (hi > 0.0_dp .and. hi <= real(huge(1.0_sp), dp)) pivot_ratio = lo/hi
        end function pivot_ratio

        !> step = J^-1 f with the factors in store (single or double precision; f scaled to
        !> a largest entry of 1 for the single-precision solve, so that no entry underflows).
        subroutine lu_solve()
            real(dp) :: fs
            if (lu_single) then
                fs = maxval(abs(f))
                if (.not. (fs > 0.0_dp)) fs = 1.0_dp
                step_s = real(f/fs, sp)
                call sgetrs('N', n, 1, jac_s, n, ipiv, step_s, n, info)
                step = fs*real(step_s, dp)
            else
                step = f
                call dgetrs('N', n, 1, jac, n, ipiv, step, n, info)
            end if
        end subroutine lu_solve

        subroutine callback_error()
            call fatal_error(error, "solve_newton: the system's callback stopped the solve", &
                             stickslip_stat%callback)
        end subroutine callback_error
    end subroutine solve_newton
end module stickslip_newton
