!> The nonlinear solve strategy of the weighted-residual method on projected friction
!> equations already built: one stage on a fixed basis (solve_stage: semismooth Newton from a
!> warm start, Powell's hybrid method on LAPACK's QR or MINPACK's hybrj, restarts), a ladder
!> of warm starts from fewer harmonics (solve_ladder) on the doubling rungs of the hybrj path
!> (doubling_rungs) or the halving rungs of the Newton path (halving_rungs), and which path a
!> problem takes (use_newton).
!> Called by solve_condensed (stickslip_hbm), which chooses the start and judges the answer;
!> knows nothing of recovery, energies or checks (stickslip_hbm_finish).
module stickslip_hbm_strategy
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_rho, only: rho_fraction
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t, new_condensed_problem
    use stickslip_condensed_structure, only: condensed_structure_t
    use stickslip_minpack, only: hybrj_options_t, hybrj_report_t, solve_hybrj
    use stickslip_powell, only: solve_powell
    use stickslip_newton, only: newton_options_t, newton_report_t, solve_newton, &
        newton_converged
    implicit none
    private
    public :: newton_min_unknowns, ladder_first
    public :: use_newton, solve_stage, solve_ladder, doubling_rungs, halving_rungs
    public :: solve_primary, condensed_convergence_scale

    !> Number of unknowns (basis size x contacts) from which &hbm solver = 'auto' takes the
    !> semismooth Newton path (warm starts, LU) instead of hybrj: where it starts to win
    !> (bench/bench_solver.f90, doc/benchmarks.md).
    integer, parameter :: newton_min_unknowns = 48

    !> hybrj calls per stage: the first plus restarts from the last iterate.
    integer, parameter :: max_calls_per_stage = 4
    !> Lowest harmonic of the warm-start ladder.
    integer, parameter :: ladder_first = 3

contains

    !> The Newton path is taken for `n` unknowns (opts%solver; 'auto': n >=
    !> newton_min_unknowns).
    pure logical function use_newton(opts, n)
        !> Solver options (opts%solver).
        type(hbm_options_t), intent(in) :: opts
        !> Number of unknowns (basis size x contacts).
        integer, intent(in) :: n
        select case (opts%solver)
        case ('newton')
            use_newton = .true.
        case ('hybrj')
            use_newton = .false.
        case default
            use_newton = n >= newton_min_unknowns
        end select
    end function use_newton

    !> One solve on a fixed basis. With `warm` (y is a warm start) and the Newton path
    !> selected (use_newton), semismooth Newton first; when it does not meet the target,
    !> hybrj from its best point. hybrj restarts from its last iterate while it stops short
    !> of the target without exhausting its evaluations.
    subroutine solve_stage(prob, y, opts, target_norm, sol, error, warm)
        !> The projected friction equations on this basis.
        type(hb_problem_t), intent(inout) :: prob
        !> Friction-force coefficients [N]: the start on entry, the last iterate on return.
        real(dp), intent(inout) :: y(:)
        !> Solver options in effect.
        type(hbm_options_t), intent(in) :: opts
        !> The residual to reach, ||F||_2 <= target_norm [m/s].
        real(dp), intent(in) :: target_norm
        !> Its convergence report: converged, info, fnorm set; the counts accumulated.
        type(hbm_solution_t), intent(inout) :: sol
        !> Set on misuse or a NaN in the residual or Jacobian (stat numerical).
        type(error_type), allocatable, intent(out) :: error
        !> y is a warm start (Newton may run first); absent: a cold start.
        logical, intent(in), optional :: warm
        type(hybrj_options_t) :: hopts
        type(hybrj_report_t) :: report
        integer :: call_no

        sol%converged = .false.
        if (present(warm)) then
            if (warm .and. use_newton(opts, prob%n) .and. target_norm > 0.0_dp) then
                block
                    type(newton_options_t) :: nopts
                    type(newton_report_t) :: nrep
                    real(dp), allocatable :: y0(:)
                    integer :: attempt
                    nopts%ftarget = target_norm
                    y0 = y
                    ! a Newton run that used single-precision LUs and failed is run again
                    ! from the same start in double precision before Powell's method takes
                    ! over (measured: 1 warm start of 2760 in the robustness study, at an
                    ! extreme rho, failed with single-precision LUs and not without)
                    do attempt = 1, 2
                        call solve_newton(prob, y, nopts, nrep, error)
                        sol%nfev = sol%nfev + nrep%nfev
                        sol%njev = sol%njev + nrep%njev
                        sol%newton_calls = sol%newton_calls + 1
                        if (allocated(error)) then
                            if (error%stat == stickslip_stat%callback) then
                                error%message = "the residual or its Jacobian became NaN "// &
                                                "during the solve"
                                error%stat = stickslip_stat%numerical
                            end if
                            return
                        end if
                        sol%fnorm = nrep%fnorm
                        if (nrep%outcome == newton_converged) then
                            sol%info = -1
                            sol%converged = .true.
                            return
                        end if
                        if (nrep%single_lus == 0) exit
                        y = y0
                        nopts%single_min_unknowns = 0
                    end do
                    sol%newton_fallbacks = sol%newton_fallbacks + 1
                end block
            end if
        end if

        hopts%xtol = opts%xtol
        hopts%maxfev = opts%maxfev
        hopts%mode = 1
        if (opts%stop_at_tol) hopts%ftarget = target_norm
        do call_no = 1, max_calls_per_stage
            ! the Newton path's Powell stages run hybrj's algorithm on LAPACK's blocked QR
            if (use_newton(opts, prob%n)) then
                call solve_powell(prob, y, hopts, report, error)
            else
                call solve_hybrj(prob, y, hopts, report, error)
            end if
            sol%nfev = sol%nfev + report%nfev
            sol%njev = sol%njev + report%njev
            sol%hybrj_calls = sol%hybrj_calls + 1
            if (allocated(error)) then
                if (error%stat == stickslip_stat%callback) then
                    error%message = "the residual or its Jacobian became NaN during the solve"
                    error%stat = stickslip_stat%numerical
                end if
                return
            end if
            sol%info = report%info
            sol%fnorm = report%fnorm
            if (report%target_met .or. report%fnorm <= target_norm) then
                sol%converged = .true.
                return
            end if
            if (report%info == 2) return
        end do
    end subroutine solve_stage

    !> The first attempt of a solve (before any fallback, stickslip_hbm_fallback), by
    !> opts%start and the path (use_newton). Newton path: 'ladder' the halving ladder,
    !> 'direct' one stage (warm with a start), 'auto' one warm stage then the halving ladder
    !> from the start with a start, the halving ladder without. hybrj path: 'ladder' the
    !> doubling ladder; otherwise one cold stage, then with 'auto' the doubling ladder. y:
    !> the start (0 or `ystart`), then the answer or the last iterate. Errors: as
    !> solve_stage.
    subroutine solve_primary(s, opts, o, prob, y, ystart, target_norm, sol, error, have_start)
        !> The structure (its forcing harmonics).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options as given.
        type(hbm_options_t), intent(in) :: opts
        !> Solver options in effect (rho > 0).
        type(hbm_options_t), intent(in) :: o
        !> The projected contact equations.
        type(hb_problem_t), intent(inout) :: prob
        !> Channel force coefficients [N]: the start on entry, the answer or the last iterate.
        real(dp), intent(inout) :: y(:)
        !> The start given (nb x channels, zeros without one) [N].
        real(dp), intent(in) :: ystart(:, :)
        !> The residual to reach [m/s].
        real(dp), intent(in) :: target_norm
        !> Convergence report (sol%fscale set).
        type(hbm_solution_t), intent(inout) :: sol
        !> Set on a NaN or misuse.
        type(error_type), allocatable, intent(out) :: error
        !> A start was given (ystart).
        logical, intent(in) :: have_start
        if (use_newton(opts, prob%n) .and. target_norm > 0.0_dp) then
            ! Newton only from warm starts: the start, or the halving ladder H/2^k
            select case (opts%start)
            case ('ladder')
                call solve_ladder(s, o, prob, y, target_norm, sol, error, halving_rungs(s, o), &
                                  have_start)
            case ('direct')
                call solve_stage(prob, y, opts, target_norm, sol, error, have_start)
            case default
                if (have_start) then
                    call solve_stage(prob, y, opts, target_norm, sol, error, .true.)
                    if (.not. allocated(error) .and. .not. sol%converged .and. &
                        opts%harmonics > ladder_first) then
                        y = reshape(ystart, [prob%n])
                        call solve_ladder(s, o, prob, y, target_norm, sol, error, &
                                          halving_rungs(s, o), .true.)
                    end if
                else
                    call solve_ladder(s, o, prob, y, target_norm, sol, error, &
                                      halving_rungs(s, o), .false.)
                end if
            end select
        else
            select case (opts%start)
            case ('ladder')
                call solve_ladder(s, o, prob, y, target_norm, sol, error, doubling_rungs(s, o))
            case default
                call solve_stage(prob, y, opts, target_norm, sol, error)
                if (.not. allocated(error) .and. .not. sol%converged .and. opts%start == 'auto' &
                    .and. opts%harmonics > ladder_first) then
                    y = reshape(ystart, [prob%n])
                    call solve_ladder(s, o, prob, y, target_norm, sol, error, &
                                      doubling_rungs(s, o))
                end if
            end select
        end if
    end subroutine solve_primary

    !> The rungs of hybrj's ladder: from `ladder_first` harmonics (or the highest forcing
    !> harmonic when larger), doubling, below the requested count (3, 6, 12 for H = 15).
    pure function doubling_rungs(s, opts) result(rungs)
        !> The structure (its forcing harmonics).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options in effect (the requested harmonics).
        type(hbm_options_t), intent(in) :: opts
        integer, allocatable :: rungs(:)
        integer :: h
        allocate (rungs(0))
        h = max(ladder_first, maxval([0, s%force_harmonic]))
        do while (h < opts%harmonics)
            rungs = [rungs, h]
            h = 2*h
        end do
    end function doubling_rungs

    !> The rungs of the Newton path's ladder: H/2, H/4, ... (integer halving) down to
    !> `ladder_first` (or the highest forcing harmonic when larger), ascending (3, 7 for
    !> H = 15).
    pure function halving_rungs(s, opts) result(rungs)
        !> The structure (its forcing harmonics).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options in effect (the requested harmonics).
        type(hbm_options_t), intent(in) :: opts
        integer, allocatable :: rungs(:)
        integer :: h, hmin
        allocate (rungs(0))
        hmin = max(ladder_first, maxval([0, s%force_harmonic]))
        h = opts%harmonics
        do while (h > hmin)
            h = max(hmin, h/2)
            rungs = [h, rungs]
        end do
    end function halving_rungs

    !> A harmonic ladder: solve on the lower bases `rungs` (harmonic counts, ascending, all
    !> below the requested one; doubling_rungs or halving_rungs), each warm-started from the
    !> one below (a lower basis is a prefix of a higher one), to a looser target (they only
    !> need to be good starts), then on the requested basis. With `warm` (the Newton path):
    !> a stage is warm (Newton first) when a lower one was solved or y held a start, and the
    !> rungs use level_samples; without it (hybrj's path): Powell's method throughout, at
    !> the requested samples.
    subroutine solve_ladder(s, opts, prob, y, target_norm, sol, error, rungs, warm)
        !> The structure (its forcing harmonics).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options in effect (rho > 0).
        type(hbm_options_t), intent(in) :: opts
        !> The projected friction equations on the requested basis.
        type(hb_problem_t), intent(inout) :: prob
        !> Friction-force coefficients [N]: the start on entry, the last iterate on return.
        real(dp), intent(inout) :: y(:)
        !> The residual to reach on the requested basis [m/s].
        real(dp), intent(in) :: target_norm
        !> Its convergence report (sol%fscale set on entry).
        type(hbm_solution_t), intent(inout) :: sol
        !> Set as by solve_stage, or when a lower basis cannot be built.
        type(error_type), allocatable, intent(out) :: error
        !> The lower harmonic counts, ascending.
        integer, intent(in) :: rungs(:)
        !> Present on the Newton path: y holds a start.
        logical, intent(in), optional :: warm
        type(hb_problem_t) :: low
        real(dp), allocatable :: ylow(:), rfull(:, :)
        integer :: i, nbl, nb, nc, nt
        real(dp) :: low_target

        nb = prob%basis%nb
        nc = prob%nc
        allocate (rfull(nb, nc))
        rfull = reshape(y, [nb, nc])
        low_target = max(target_norm, 1.0e-6_dp*sol%fscale)
        do i = 1, size(rungs)
            nt = opts%samples
            if (present(warm)) nt = level_samples(opts%samples, opts%harmonics, rungs(i))
            ! the lower basis is a subset of prob's: its dynamics without a factorization
            call new_condensed_problem(low, prob%dyn, prob%contacts, rungs(i), &
                                       opts%odd_only, nt, opts%rho, error, s%force_harmonic)
            if (allocated(error)) return
            nbl = low%basis%nb
            ylow = reshape(rfull(1:nbl, :), [nbl*nc])
            if (present(warm)) then
                call solve_stage(low, ylow, opts, low_target, sol, error, warm .or. i > 1)
            else
                call solve_stage(low, ylow, opts, low_target, sol, error)
            end if
            call low%destroy()
            if (allocated(error)) return
            rfull(1:nbl, :) = reshape(ylow, [nbl, nc])
        end do
        y = reshape(rfull, [nb*nc])
        if (present(warm)) then
            call solve_stage(prob, y, opts, target_norm, sol, error, warm .or. size(rungs) > 0)
        else
            call solve_stage(prob, y, opts, target_norm, sol, error)
        end if
    end subroutine solve_ladder

    !> Samples of a lower level of the halving ladder: the requested samples per harmonic
    !> kept (samples h / H, up to a power of two, at least 64), never more than `samples`.
    !> A level is only a warm start; its cost goes with its samples (the residual, the
    !> Jacobian and, for the cold hybrj stage, every evaluation).
    pure integer function level_samples(samples, harmonics, h) result(nt)
        integer, intent(in) :: samples, harmonics, h
        nt = 64
        do while (real(nt, dp)*real(harmonics, dp) < real(samples, dp)*real(h, dp))
            nt = 2*nt
        end do
        nt = max(min(nt, samples), 2*h + 1)
    end function level_samples
    !> convergence_scale with the automatic rho of the structure given (`rho_auto`).
    !> With contact laws, V0 holds the free kinematic quantities of every channel (the
    !> slider velocities, omega times the free gaps with the preload) and the force scale is
    !> the largest of the constant limits mu N, the preloads and mu times the preloads.
    function condensed_convergence_scale(prob, rho_auto) result(fscale)
        !> The projected friction equations.
        type(hb_problem_t), intent(inout) :: prob
        !> The automatic rho of the structure [m/(N s)].
        real(dp), intent(in) :: rho_auto
        real(dp) :: fscale
        real(dp) :: rzero(prob%basis%nb, prob%nc), vfree(prob%basis%nb, prob%nc)
        real(dp) :: vnorm, rstop, rs, fmax
        fscale = 0.0_dp
        if (prob%nc == 0) return
        rzero = 0.0_dp
        call prob%kinematics(rzero, vfree)
        fmax = prob%contacts%force_scale()
        vnorm = norm2(vfree)
        rstop = vnorm*rho_fraction/rho_auto
        rs = max(min(fmax, rstop), 1.0e-6_dp*rstop)
        fscale = min(vnorm, prob%rho*rs)
    end function condensed_convergence_scale
end module stickslip_hbm_strategy
