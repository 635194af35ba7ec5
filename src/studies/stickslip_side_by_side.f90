!> The three methods on one model, side by side: the weighted residual, implicit Euler and
!> the exact event-driven reference, each one's CPU time, and the differences between them
!> on a common time grid (&run method = 'all').
module stickslip_side_by_side
    use stickslip_kinds, only: dp
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_diagnostics, only: diagnostics_t, level_note, level_warning, level_untrusted
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t, sample_reference, reference_handles
    use stickslip_reference_start, only: solve_reference_from_starts, reference_start_options_t
    use stickslip_compare, only: comparison_t, compare_samples, evaluate_series
    use stickslip_checks, only: sampling_diagnostics
    implicit none
    private
    public :: side_by_side_t, solve_side_by_side, disagreement, disagree_warning, &
        disagree_untrusted

    !> Displacement difference of a method against the reference (relative to the
    !> amplitude) above which 'all' warns / is untrusted (disagreement). On the examples
    !> the weighted residual and implicit Euler stay within 0.07 of the reference.
    real(dp), parameter :: disagree_warning = 0.1_dp, disagree_untrusted = 0.5_dp

    !> The three solutions, their CPU times and their differences.
    type :: side_by_side_t
        type(hbm_solution_t) :: hbm
        type(euler_result_t) :: euler
        type(reference_result_t) :: reference
        !> CPU seconds of each method [s]; the reference's start is the weighted-residual
        !> (or Euler) solution already computed, so its time is the shooting alone.
        real(dp) :: hbm_seconds = 0.0_dp, euler_seconds = 0.0_dp, reference_seconds = 0.0_dp
        !> Points per period of the common grid: the Euler steps when Euler reached a
        !> periodic state, else the weighted-residual samples.
        integer :: grid = 0
        !> The differences that could be computed, in the order hbm vs reference, euler vs
        !> reference, hbm vs euler (a pair is left out when one of its solutions failed).
        type(comparison_t), allocatable :: comparisons(:)
        !> Empty when all three succeeded, otherwise the diagnoses of those that did not.
        character(len=:), allocatable :: diagnosis
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type side_by_side_t

contains

    !> Solve `model` with the three methods and compare them. A method that does not
    !> converge is an outcome (its flag, its diagnosis and res%diagnosis). Errors: stat
    !> input (invalid model or options), stat numerical (singular dynamic stiffness or
    !> iteration matrix), from whichever method meets it first. With `observe` (nobs x N), the
    !> differences are those of the observed combinations observe x, observe v (e.g. the
    !> full-model DOFs of a reduced model: rows of its basis) instead of the model's DOFs.
    subroutine solve_side_by_side(model, hbm, euler, ref, res, error, observe)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Weighted-residual options.
        type(hbm_options_t), intent(in) :: hbm
        !> Time-stepping options.
        type(euler_options_t), intent(in) :: euler
        !> Reference options.
        type(reference_start_options_t), intent(in) :: ref
        !> The three solutions and their differences.
        type(side_by_side_t), intent(out) :: res
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Observed combinations of DOFs, nobs x N (optional).
        real(dp), intent(in), optional :: observe(:, :)
        type(hbm_options_t) :: ho
        type(comparison_t) :: cmp
        real(dp), allocatable :: xh(:, :), vh(:, :), rh(:, :), xr(:, :), vr(:, :), rr(:, :), &
            xe(:, :), ve(:, :), re(:, :)
        real(dp) :: c0, c1
        logical :: hbm_ok, euler_ok, ref_ok, applicable
        character(len=:), allocatable :: why

        ho = hbm
        ho%want_samples = .true.
        c0 = thread_cpu_seconds()
        call solve_periodic(model, ho, res%hbm, error)
        c1 = thread_cpu_seconds()
        res%hbm_seconds = c1 - c0
        if (allocated(error)) return

        c0 = thread_cpu_seconds()
        call integrate_euler(model, euler, res%euler, error)
        c1 = thread_cpu_seconds()
        res%euler_seconds = c1 - c0
        if (allocated(error)) return

        ! contacts the exact reference does not handle (exact_support of their elements:
        ! 2D friction or a tangential stiffness on a rigid unilateral contact): implicit
        ! Euler is the yardstick, the reference is not run
        applicable = reference_handles(model, why)
        if (applicable) then
            call solve_reference_from_starts(model, ref, res%reference, error, hbm_opts=ho, &
                                             euler_opts=euler, hbm_start=res%hbm, &
                                             euler_start=res%euler)
            res%reference_seconds = res%reference%seconds + res%reference%start_seconds
            if (allocated(error)) return
        else
            res%reference%diagnosis = why
        end if

        hbm_ok = res%hbm%converged
        euler_ok = res%euler%periodic
        ref_ok = res%reference%converged
        res%diagnosis = ""
        if (.not. hbm_ok) res%diagnosis = "weighted residual: "//res%hbm%diagnosis
        if (.not. euler_ok) call add("implicit Euler: "//res%euler%diagnosis)
        if (.not. ref_ok .and. applicable) call add("reference: "//res%reference%diagnosis)

        if (euler_ok) then
            res%grid = euler%steps_per_period
        else
            res%grid = ho%samples
        end if
        allocate (res%comparisons(0))
        if (present(observe)) then
            if (size(observe, 2) /= model%ndof) then
                call fatal_error(error, "solve_side_by_side: observe must have N columns", &
                                 stickslip_stat%input)
                return
            end if
        end if
        if (hbm_ok) then
            call evaluate_series(res%hbm, res%grid, xh, vh, rh, error)
            if (allocated(error)) return
            call observed(xh, vh)
        end if
        if (ref_ok) then
            call sample_reference(res%reference, res%grid, xr, vr, rr, error)
            if (allocated(error)) return
            call observed(xr, vr)
        end if
        if (euler_ok) then
            xe = res%euler%x
            ve = res%euler%v
            call observed(xe, ve)
        end if
        ! the forces per contact and direction (a joint's sliders summed, as in the files)
        if (hbm_ok) rh = res%hbm%contacts%direction_forces(rh)
        if (ref_ok) rr = res%hbm%contacts%direction_forces(rr)
        if (euler_ok) re = res%hbm%contacts%direction_forces(res%euler%r)
        if (hbm_ok .and. ref_ok) then
            call compare_samples('hbm', xh, vh, rh, 'reference', xr, vr, rr, cmp, error)
            if (allocated(error)) return
            res%comparisons = [res%comparisons, cmp]
        end if
        if (euler_ok .and. ref_ok) then
            call compare_samples('euler', xe, ve, re, 'reference', xr, vr, rr, cmp, error)
            if (allocated(error)) return
            res%comparisons = [res%comparisons, cmp]
        end if
        if (hbm_ok .and. euler_ok) then
            call compare_samples('hbm', xh, vh, rh, 'euler', xe, ve, re, cmp, error)
            if (allocated(error)) return
            res%comparisons = [res%comparisons, cmp]
        end if

        ! every method's findings, then whether they agree
        call res%diagnostics%extend(res%hbm%diagnostics, "hbm_")
        call sampling_diagnostics(ho%samples, res%diagnostics, "hbm_")
        call res%diagnostics%extend(res%euler%diagnostics, "euler_")
        call res%diagnostics%extend(res%reference%diagnostics, "reference_")
        if (.not. applicable) call res%diagnostics%add(level_note, "reference_not_applicable", &
                                                       why)
        call disagreement(res%comparisons, ref_ok, res%diagnostics)

    contains

        !> Samples of the DOFs -> samples of the observed combinations (when observing).
        subroutine observed(x, v)
            real(dp), allocatable, intent(inout) :: x(:, :), v(:, :)
            if (.not. present(observe)) return
            x = matmul(x, transpose(observe))
            v = matmul(v, transpose(observe))
        end subroutine observed

        subroutine add(text)
            character(len=*), intent(in) :: text
            if (len(res%diagnosis) > 0) then
                res%diagnosis = res%diagnosis//"; "//text
            else
                res%diagnosis = text
            end if
        end subroutine add
    end subroutine solve_side_by_side

    !> Diagnostics items for methods that disagree, from the comparisons (doc/where-methods-fail.md, "Where
    !> each method fails"): the largest displacement difference of a method against the
    !> reference, relative to each DOF's amplitude (floored at 1e-3 of the largest
    !> amplitude: a DOF nearly at rest does not count alone), above disagree_warning gives
    !> a warning, above disagree_untrusted makes the run untrusted (keys 'hbm_disagrees',
    !> 'euler_disagrees'). Without a converged reference, the weighted residual against
    !> implicit Euler is judged the same way (key 'methods_disagree').
    subroutine disagreement(comparisons, ref_ok, diag)
        !> The comparisons of solve_side_by_side.
        type(comparison_t), intent(in) :: comparisons(:)
        !> The reference converged.
        logical, intent(in) :: ref_ok
        !> The findings, appended to.
        type(diagnostics_t), intent(inout) :: diag
        integer :: k
        real(dp) :: e
        character(len=300) :: buf
        character(len=:), allocatable :: key
        do k = 1, size(comparisons)
            associate (c => comparisons(k))
                if (c%against == 'reference') then
                    key = c%method//"_disagrees"
                else if (.not. ref_ok) then
                    key = "methods_disagree"
                else
                    cycle
                end if
                e = displacement_difference(c)
                write (buf, '(a,es10.2e3,a)') c%method//" and "//c%against//" differ by ", e, &
                    " of the displacement amplitude"
                if (.not. (e <= disagree_untrusted)) then
                    call diag%add(level_untrusted, key, trim(buf)//": at least one of them "// &
                                  "is wrong")
                else if (e > disagree_warning) then
                    call diag%add(level_warning, key, trim(buf))
                end if
            end associate
        end do
    end subroutine disagreement

    !> max over the DOFs p of max_t |x_p - x_p,against| / max(A_p, 1e-3 max_q A_q)
    !> (dimensionless), A_p the amplitude of x_p in the solution compared against.
    pure real(dp) function displacement_difference(c) result(e)
        type(comparison_t), intent(in) :: c
        real(dp) :: amax
        integer :: p
        e = 0.0_dp
        if (c%n < 1 .or. .not. allocated(c%max_error)) return
        amax = maxval(c%amplitude(1:c%n))
        do p = 1, c%n
            e = max(e, c%max_error(p)*c%amplitude(p)/max(c%amplitude(p), 1.0e-3_dp*amax, &
                                                         tiny(1.0_dp)))
        end do
        if (amax == 0.0_dp) e = maxval(c%max_error(1:c%n))
    end function displacement_difference
end module stickslip_side_by_side
