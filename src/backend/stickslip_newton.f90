!> Semismooth Newton with a dense LU (LAPACK dgetrf/dgetrs on the linked BLAS) for a
!> `nonlinear_system_t` with an element of its generalized Jacobian: the fast path of the
!> weighted-residual solve at hundreds of unknowns (README, "Solvers").
!>
!> Newton steps x <- x - t J(x)^-1 F(x) with backtracking on ||F||: the full step t = 1
!> first, halved (at most max_halvings times) until ||F||^2 drops by Armijo's factor
!> (1 - 2e-4 t). On a piecewise-linear system started close to its root (a warm start: the
!> solution on fewer harmonics, a nearby continuation point) the full step is taken almost
!> always and the iteration ends after a few steps, as soon as ||F|| <= ftarget; the
!> backtracking only breaks the cycles of full steps between pieces (seen on the seed case
!> at H = 200: 25 full steps between ||F|| = 3e-5 and 0.2, against 5 LUs with it). It is
!> not meant for a cold start (measured: many more LUs, or failure): the caller falls back
!> to Powell's hybrid method (stickslip_minpack) when this returns without meeting ftarget,
!> which happens when the Jacobian is singular (a contact stuck over the whole period
!> leaves its mean force undetermined), when no step length lowers ||F|| (a roundoff floor
!> above ftarget) or after max_iterations steps. x returns the best point met.
!>
!> No module state: re-entrant and thread-safe (one system instance per thread).
module stickslip_newton
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_lapack, only: dgetrf, dgetrs, dgecon, dlange
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
    end type newton_options_t

    !> What one solve_newton call did.
    type :: newton_report_t
        !> newton_converged, newton_singular, newton_stalled or newton_max_iterations.
        integer :: outcome = newton_max_iterations
        !> Residual evaluations.
        integer :: nfev = 0
        !> Jacobian evaluations (= LU factorizations).
        integer :: njev = 0
        !> ||F||_2 at the returned point (the best met).
        real(dp) :: fnorm = huge(1.0_dp)
        !> Reciprocal condition estimate of the last Jacobian factorized (0: exactly
        !> singular).
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
        integer, allocatable :: ipiv(:), iwork(:)
        integer :: n, stat, info, it, ls
        real(dp) :: fnorm, best, anorm, rcond, t
        logical :: accepted
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
        allocate (f(n), ft(n), jac(n, n), xt(n), step(n), ipiv(n), work(4*n), iwork(n))
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
        do
            if (best <= opts%ftarget) then
                report%outcome = newton_converged
                exit
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
            if (.not. (rcond >= opts%rcond_min)) then
                report%outcome = newton_singular
                exit
            end if
            step = f
            call dgetrs('N', n, 1, jac, n, ipiv, step, n, info)
            ! backtracking on ||F|| (Armijo on ||F||^2/2, whose slope along the Newton step
            ! is -||F||^2): the full step first; halving breaks the cycles of full steps
            ! between pieces near a kink
            t = 1.0_dp
            accepted = .false.
            do ls = 0, opts%max_halvings
                xt = x - t*step
                call sys%residual(xt, ft, stat)
                report%nfev = report%nfev + 1
                if (stat /= 0) then
                    stat = 0
                    fnorm = huge(1.0_dp)
                else
                    fnorm = norm2(ft)
                end if
                if (fnorm <= sqrt(1.0_dp - 2.0e-4_dp*t)*best) then
                    accepted = .true.
                    exit
                end if
                t = 0.5_dp*t
            end do
            if (.not. accepted) then
                report%outcome = newton_stalled
                exit
            end if
            x = xt
            f = ft
            if (fnorm < best) then
                best = fnorm
                xbest = x
            end if
        end do
        x = xbest
        report%fnorm = best

    contains

        subroutine callback_error()
            call fatal_error(error, "solve_newton: the system's callback stopped the solve", &
                             stickslip_stat%callback)
        end subroutine callback_error
    end subroutine solve_newton
end module stickslip_newton
