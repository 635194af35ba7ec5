!> stickslip_compare against hand computations: the relative max and RMS errors of known
!> perturbations, the zero-amplitude fallback, worst() per kind, the quantity names, shape
!> errors, and evaluate_series against the Fourier series summed directly (including a grid
!> coarser than the harmonics, where aliasing must be exact, not smoothed).
module test_compare
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_solution, only: hbm_solution_t
    use stickslip_compare, only: comparison_t, compare_samples, evaluate_series, quantity_names
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_compare_tests

contains

    subroutine run_compare_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_compare_samples(t)
        call test_roundoff_amplitude(t)
        call test_evaluate_series(t)
    end subroutine run_compare_tests

    !> Two DOF, one contact, 8 points: x1 off by a constant 0.1 on amplitude 2, x2 exact,
    !> v2 identically zero in both (measured against the largest v amplitude), r off at one
    !> point by 0.3 on amplitude 1.5.
    subroutine test_compare_samples(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: ng = 8
        real(dp) :: xa(ng, 2), va(ng, 2), ra(ng, 1), x(ng, 2), v(ng, 2), r(ng, 1), th(ng)
        type(comparison_t) :: cmp
        type(error_type), allocatable :: error
        character(len=12), allocatable :: names(:)
        integer :: k
        th = [(two_pi*k/ng, k=0, ng - 1)]
        xa(:, 1) = 2.0_dp*cos(th)
        xa(:, 2) = 0.5_dp*sin(th)
        va(:, 1) = -4.0_dp*sin(th)
        va(:, 2) = 0.0_dp
        ra(:, 1) = 1.5_dp*cos(2.0_dp*th)
        x = xa
        x(:, 1) = x(:, 1) + 0.1_dp
        v = va
        v(:, 1) = v(:, 1) - 0.2_dp
        v(:, 2) = 0.04_dp
        r = ra
        r(3, 1) = r(3, 1) + 0.3_dp
        call compare_samples("hbm", x, v, r, "reference", xa, va, ra, cmp, error)
        call check_error(t, error, "compare: compare_samples", .false.)
        if (allocated(error)) return
        call check(t, cmp%method == "hbm" .and. cmp%against == "reference" .and. cmp%grid == ng &
                   .and. cmp%n == 2 .and. cmp%nc == 1, "compare: names and sizes")
        call check_close(t, cmp%amplitude, [2.0_dp, 0.5_dp, 4.0_dp, 0.0_dp, 1.5_dp], &
                         "compare: amplitudes", rtol=1.0e-15_dp, atol=1.0e-15_dp)
        call check_close(t, cmp%max_error, [0.05_dp, 0.0_dp, 0.05_dp, 0.01_dp, 0.2_dp], &
                         "compare: max errors (a zero amplitude falls back to the kind's)", &
                         rtol=1.0e-13_dp, atol=1.0e-16_dp)
        call check_close(t, cmp%rms_error, [0.05_dp, 0.0_dp, 0.05_dp, 0.01_dp, &
                         0.3_dp/sqrt(real(ng, dp))/1.5_dp], "compare: RMS errors", &
                         rtol=1.0e-13_dp, atol=1.0e-16_dp)
        call check_close(t, cmp%worst('x'), 0.05_dp, "compare: worst x", rtol=1.0e-13_dp)
        call check_close(t, cmp%worst('r'), 0.2_dp, "compare: worst r", rtol=1.0e-13_dp)
        call check_close(t, cmp%worst('v', rms=.true.), 0.05_dp, "compare: worst RMS v", &
                         rtol=1.0e-13_dp)
        names = quantity_names(2, 1)
        call check(t, all(names == [character(len=12) :: "x1", "x2", "v1", "v2", "r1"]), &
                   "compare: quantity names x1 x2 v1 v2 r1")
        call compare_samples("a", x(1:4, :), v, r, "b", xa, va, ra, cmp, error)
        call check_error(t, error, "compare: different grids refused", .true., &
                         [character(len=16) :: "same grid"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "compare: different grids is an input error")
    end subroutine test_compare_samples

    !> A DOF at rest up to roundoff (amplitude 1e-14 against 1 for the other DOF), where the
    !> two solutions differ by roundoff: measured against the kind's largest amplitude, the
    !> error is roundoff too, not 100% (the fuzzing found 'all' reporting 1.0 there).
    subroutine test_roundoff_amplitude(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: ng = 8
        real(dp) :: xa(ng, 2), va(ng, 2), ra(ng, 1), x(ng, 2), th(ng)
        type(comparison_t) :: cmp
        type(error_type), allocatable :: error
        integer :: k
        th = [(two_pi*k/ng, k=0, ng - 1)]
        xa(:, 1) = cos(th)
        xa(:, 2) = 1.0e-14_dp*sin(th)
        x = xa
        x(:, 2) = -1.0e-14_dp*sin(th)
        va = 1.0_dp
        ra = 1.0_dp
        call compare_samples("hbm", x, va, ra, "reference", xa, va, ra, cmp, error)
        call check_error(t, error, "compare: roundoff amplitude", .false.)
        if (allocated(error)) return
        call check(t, cmp%worst('x') < 1.0e-12_dp, "compare: a DOF at rest up to roundoff "// &
                   "is measured against the largest x amplitude")
    end subroutine test_roundoff_amplitude

    !> A hand-made solution u = c0 + a1 cos wt + b1 sin wt + a3 cos 3wt + b3 sin 3wt, its
    !> derivative as v and a friction force r = d0 + e3 sin 3wt, evaluated on 16 and on 4
    !> points per period.
    subroutine test_evaluate_series(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_solution_t) :: sol, empty
        real(dp), allocatable :: x(:, :), v(:, :), r(:, :)
        type(error_type), allocatable :: error
        real(dp), parameter :: c0 = 0.25_dp, a1 = 1.0_dp, b1 = -0.5_dp, a3 = 0.2_dp, &
            b3 = 0.1_dp, w = 2.0_dp, d0 = -0.3_dp, e3 = 0.7_dp
        real(dp), allocatable :: th(:)
        integer :: k, ng, trial
        sol%nb = 5
        sol%harmonic = [0, 1, 1, 3, 3]
        sol%xcoef = reshape([c0, a1, b1, a3, b3], [5, 1])
        sol%vcoef = reshape([0.0_dp, w*b1, -w*a1, 3*w*b3, -3*w*a3], [5, 1])
        sol%rcoef = reshape([d0, 0.0_dp, 0.0_dp, 0.0_dp, e3], [5, 1])
        do trial = 1, 2
            ng = merge(16, 4, trial == 1)
            th = [(two_pi*k/ng, k=0, ng - 1)]
            call evaluate_series(sol, ng, x, v, r, error)
            call check_error(t, error, "compare: evaluate_series", .false.)
            if (allocated(error)) return
            call check_close(t, x(:, 1), c0 + a1*cos(th) + b1*sin(th) + a3*cos(3*th) + &
                             b3*sin(3*th), "compare: series x on the grid", rtol=0.0_dp, &
                             atol=1.0e-14_dp)
            call check_close(t, v(:, 1), w*(-a1*sin(th) + b1*cos(th) - 3*a3*sin(3*th) + &
                             3*b3*cos(3*th)), "compare: series v on the grid", rtol=0.0_dp, &
                             atol=1.0e-14_dp)
            call check_close(t, r(:, 1), d0 + e3*sin(3*th), "compare: series r on the grid", &
                             rtol=0.0_dp, atol=1.0e-14_dp)
        end do
        call evaluate_series(empty, 8, x, v, r, error)
        call check_error(t, error, "compare: a solution without coefficients refused", .true.)
    end subroutine test_evaluate_series
end module test_compare
