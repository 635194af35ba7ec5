!> The only module that talks to MINPACK: Powell's hybrid method `hybrj` (system libminpack)
!> applied to a `nonlinear_system_t`.
!>
!> hybrj calls back a procedure with a fixed legacy signature and no user data. The system
!> being solved (and the state of the solve) is reached through one module-level pointer
!> that is `threadprivate` (each OpenMP thread has its own) and saved/restored around every
!> call (a solve inside a callback restores the outer one). Callers never see it. Without OpenMP the pointer is an
!> ordinary module variable: then `solve_hybrj` is re-entrant but must not be called from
!> several threads at once (build with -fopenmp for that).
module stickslip_minpack
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_nonlinear, only: nonlinear_system_t
    implicit none
    private
    public :: hybrj_options_t, hybrj_report_t, solve_hybrj, check_hybrj_options

    !> Options passed to hybrj.
    type :: hybrj_options_t
        !> Relative step tolerance (hybrj's xtol).
        real(dp) :: xtol = 1.0e-13_dp
        !> Maximum residual evaluations (hybrj's maxfev); 0 means 200 * (n + 1).
        integer :: maxfev = 0
        !> 1: hybrj scales the unknowns itself (column norms of the Jacobian);
        !> 2: use `diag` (1 / typical magnitude of each unknown).
        integer :: mode = 1
        !> Initial trust-region bound factor (hybrj's factor).
        real(dp) :: factor = 100.0_dp
        !> Scaling of the unknowns for mode 2.
        real(dp), allocatable :: diag(:)
        !> Stop as soon as a residual evaluation has ||F||_2 <= ftarget and return that
        !> point (0: let hybrj run to its own termination). On a piecewise-linear system the
        !> exact root is usually reached long before hybrj's step-size test ends the run.
        real(dp) :: ftarget = 0.0_dp
    end type hybrj_options_t

    !> What one hybrj call did.
    type :: hybrj_report_t
        !> hybrj's info: 1 xtol met, 2 maxfev reached, 3 xtol too small, 4 or 5 no progress,
        !> -1 stopped by the system's callback status.
        integer :: info = 0
        !> Residual evaluations.
        integer :: nfev = 0
        !> Jacobian evaluations.
        integer :: njev = 0
        !> Final ||F(x)||_2.
        real(dp) :: fnorm = huge(1.0_dp)
        !> Nonzero status returned by the system's callbacks.
        integer :: callback_stat = 0
        !> The run was stopped because a residual met ftarget (then info = -1 is hybrj's
        !> answer to that stop, and x is the point that met it).
        logical :: target_met = .false.
    end type hybrj_report_t

    !> State of one solve, reached from the legacy callback.
    type :: session_t
        class(nonlinear_system_t), pointer :: sys => null()
        integer :: stat = 0
        real(dp) :: ftarget = 0.0_dp
        logical :: hit = .false.
        real(dp), allocatable :: xhit(:), fhit(:)
    end type session_t

    !> The session of the solve running on this thread (saved and restored around calls).
    type(session_t), pointer :: active => null()
    !$omp threadprivate(active)

    interface
        !> MINPACK hybrj (legacy Fortran 77).
        subroutine hybrj(fcn, n, x, fvec, fjac, ldfjac, xtol, maxfev, diag, mode, factor, &
                         nprint, info, nfev, njev, r, lr, qtf, wa1, wa2, wa3, wa4)
            import :: dp
            interface
                subroutine fcn(n, x, fvec, fjac, ldfjac, iflag)
                    import :: dp
                    integer, intent(in) :: n, ldfjac
                    real(dp), intent(in) :: x(n)
                    real(dp), intent(inout) :: fvec(n)
                    real(dp), intent(inout) :: fjac(ldfjac, n)
                    integer, intent(inout) :: iflag
                end subroutine fcn
            end interface
            integer, intent(in) :: n, ldfjac, maxfev, mode, nprint, lr
            real(dp), intent(inout) :: x(n), fvec(n), fjac(ldfjac, n), diag(n)
            real(dp), intent(in) :: xtol, factor
            integer, intent(out) :: info, nfev, njev
            real(dp), intent(inout) :: r(lr), qtf(n), wa1(n), wa2(n), wa3(n), wa4(n)
        end subroutine hybrj
    end interface

contains

    !> Solve sys%residual(x) = 0 from the start x with hybrj and the system's exact Jacobian.
    !> A solve that does not converge is an outcome (report%info, report%fnorm), not an
    !> error. Errors: stat input for bad options or sizes, stat callback when the system's
    !> callback returned a nonzero status (hybrj info -1).
    subroutine solve_hybrj(sys, x, opts, report, error)
        !> The system F(x) = 0.
        class(nonlinear_system_t), target, intent(inout) :: sys
        !> Start on entry, last iterate on exit (hybrj returns its best point).
        real(dp), intent(inout) :: x(:)
        !> Options.
        type(hybrj_options_t), intent(in) :: opts
        !> What happened.
        type(hybrj_report_t), intent(out) :: report
        !> Set on misuse or callback failure.
        type(error_type), allocatable, intent(out) :: error
        type(session_t), pointer :: session, previous
        integer :: n, maxfev, info, nfev, njev, lr
        real(dp), allocatable :: fvec(:), fjac(:, :), diag(:), r(:), qtf(:), wa(:, :)

        n = size(x)
        call check_hybrj_options(opts, n, "solve_hybrj", error)
        if (allocated(error)) return
        maxfev = opts%maxfev
        if (maxfev <= 0) maxfev = 200*(n + 1)
        lr = n*(n + 1)/2
        allocate (fvec(n), fjac(n, n), diag(n), r(lr), qtf(n), wa(n, 4))
        if (opts%mode == 2) then
            diag = opts%diag
        else
            diag = 1.0_dp
        end if

        allocate (session)
        session%sys => sys
        session%ftarget = opts%ftarget
        allocate (session%xhit(n), session%fhit(n))
        previous => active
        active => session
        call hybrj(hybrj_thunk, n, x, fvec, fjac, n, opts%xtol, maxfev, diag, opts%mode, &
                   opts%factor, 0, info, nfev, njev, r, lr, qtf, wa(:, 1), wa(:, 2), &
                   wa(:, 3), wa(:, 4))
        active => previous

        report%callback_stat = session%stat
        report%info = info
        report%nfev = nfev
        report%njev = njev
        report%target_met = session%hit
        if (session%hit) then
            x = session%xhit
            fvec = session%fhit
        end if
        report%fnorm = norm2(fvec)
        if (session%hit) then
            deallocate (session)
            return
        else if (info == 0) then
            call fatal_error(error, "solve_hybrj: hybrj rejected its input (info 0)", &
                             stickslip_stat%internal)
        else if (info < 0 .or. report%callback_stat /= 0) then
            call fatal_error(error, "solve_hybrj: the system's callback stopped the solve", &
                             stickslip_stat%callback)
        end if
        deallocate (session)
    end subroutine solve_hybrj

    !> Errors (stat input, the message starting with `who`) for options Powell's hybrid
    !> method cannot run with on n unknowns: n < 1, xtol < 0, factor <= 0, mode 2 without n
    !> positive diag entries. Shared by solve_hybrj and solve_powell.
    subroutine check_hybrj_options(opts, n, who, error)
        !> The options.
        type(hybrj_options_t), intent(in) :: opts
        !> Number of unknowns.
        integer, intent(in) :: n
        !> The solver's name, for the message.
        character(len=*), intent(in) :: who
        !> Set when the options cannot be used.
        type(error_type), allocatable, intent(out) :: error
        if (n < 1) then
            call fatal_error(error, who//": no unknowns", stickslip_stat%input)
        else if (.not. (opts%xtol >= 0.0_dp .and. opts%factor > 0.0_dp)) then
            call fatal_error(error, who//": xtol must be >= 0 and factor > 0", &
                             stickslip_stat%input)
        else if (opts%mode == 2) then
            if (.not. allocated(opts%diag)) then
                call fatal_error(error, who//": mode 2 needs diag", stickslip_stat%input)
            else if (size(opts%diag) /= n .or. any(.not. (opts%diag > 0.0_dp))) then
                call fatal_error(error, who//": diag must have n positive entries", &
                                 stickslip_stat%input)
            end if
        end if
    end subroutine check_hybrj_options

    !> The legacy callback: dispatch to the active system.
    subroutine hybrj_thunk(n, x, fvec, fjac, ldfjac, iflag)
        integer, intent(in) :: n, ldfjac
        real(dp), intent(in) :: x(n)
        real(dp), intent(inout) :: fvec(n)
        real(dp), intent(inout) :: fjac(ldfjac, n)
        integer, intent(inout) :: iflag
        select case (iflag)
        case (1)
            call active%sys%residual(x, fvec, active%stat)
            if (active%stat == 0 .and. active%ftarget > 0.0_dp) then
                if (norm2(fvec) <= active%ftarget) then
                    active%hit = .true.
                    active%xhit = x
                    active%fhit = fvec
                    iflag = -1
                    return
                end if
            end if
        case (2)
            call active%sys%jacobian(x, fjac(1:n, 1:n), active%stat)
        case default
            return
        end select
        if (active%stat /= 0) iflag = -1
    end subroutine hybrj_thunk
end module stickslip_minpack
