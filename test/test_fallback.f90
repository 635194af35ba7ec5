!> The fallbacks of the weighted-residual solve (stickslip_hbm_fallback, issue 24) and the
!> settling of a contact stuck all period on an elastic normal: a closed contact whose
!> normal load follows the slip (bench/convergence/coupled_elastic.nml), which the first
!> attempt alone never solves, converges with the fallbacks and balances its energy; a
!> rigid contact that lands with an impact is refused with the impact's remedy; a damper
!> stuck all period keeps its normal law in the mean (lambda_0 = -k_n g_0, which the mean
!> friction force chosen by the settling moves) and agrees with a run at half the
!> harmonics to roundoff.
module test_fallback
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_case, only: case_t, read_case
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_diagnostics, only: level_untrusted
    use fixtures, only: project_path
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_fallback_tests

contains

    subroutine run_fallback_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_coupled(t)
        call test_impact(t)
        call test_stuck_normal(t)
    end subroutine run_fallback_tests

    !> Read a case of bench/convergence.
    subroutine load(name, c, t)
        character(len=*), intent(in) :: name
        type(case_t), intent(out) :: c
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call read_case(project_path("bench/convergence/"//name//".nml"), c, error)
        call check(t, .not. allocated(error), "fallback: read "//name)
    end subroutine load

    !> The closed contact whose normal load follows the slip: not solved by the first
    !> attempt (the start and the ladder: sol%rescue names a fallback), solved with the
    !> fallbacks at three harmonic counts; no check distrusts the answers, whose forcing
    !> work equals the dissipation.
    subroutine test_coupled(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        integer :: k
        integer, parameter :: hs(3) = [15, 20, 45]
        call load("coupled_elastic", c, t)
        do k = 1, size(hs)
            opts = c%hbm
            opts%harmonics = hs(k)
            call solve_periodic(c%model, opts, sol, error)
            call check(t, .not. allocated(error), "fallback: coupled, no error")
            if (allocated(error)) return
            call check(t, sol%converged .and. sol%rescue /= 'none' .and. &
                       sol%diagnostics%count(level_untrusted) == 0, &
                       "fallback: coupled, converged by a fallback, trusted")
            call check_close(t, sol%work_forcing, sol%diss_friction + sol%diss_damping, &
                             "fallback: coupled, energy balance", rtol=1.0e-9_dp)
        end do
    end subroutine test_coupled

    !> A rigid unilateral contact that lands with an impact: refused with the diagnosis and
    !> its remedies (a normal stiffness, or the time-domain methods).
    subroutine test_impact(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        call load("impact", c, t)
        opts = c%hbm
        opts%harmonics = 30
        call solve_periodic(c%model, opts, sol, error)
        call check(t, .not. allocated(error), "fallback: impact, no error")
        if (allocated(error)) return
        call check(t, .not. sol%converged .and. index(sol%diagnosis, "impact") > 0 .and. &
                   index(sol%diagnosis, "normal_stiffness") > 0 .and. &
                   index(sol%diagnosis, "'euler'") > 0, &
                   "fallback: impact refused with its remedies", sol%diagnosis)
    end subroutine test_impact

    !> The lift-off damper pressed by a preload of 10: stuck and closed all period. Its mean
    !> normal force and mean gap obey the elastic law (lambda_0 = -k_n g_0; before the
    !> settling solved the mean gap again, lambda_0 was 8.43 for -k_n g_0 = 9.08), and the
    !> answers at H = 40 and 20 agree to roundoff (the motion is linear).
    subroutine test_stuck_normal(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sol, half
        type(error_type), allocatable :: error
        real(dp) :: lambda0, g0, kn
        call load("liftoff_stuck", c, t)
        opts = c%hbm
        opts%harmonics = 40
        call solve_periodic(c%model, opts, sol, error)
        call check(t, .not. allocated(error), "fallback: stuck damper, no error")
        if (allocated(error)) return
        call check(t, sol%converged .and. sol%offset_undetermined(1), &
                   "fallback: stuck damper, converged, offset undetermined")
        kn = c%model%normal_stiffness(1)
        ! the constant term is the first coefficient; DOF 2 is the normal (gap 0)
        g0 = sol%xcoef(1, 2)
        lambda0 = sol%rcoef(1, 2)
        call check_close(t, lambda0, -kn*g0, "fallback: stuck damper, lambda_0 = -k_n g_0", &
                         rtol=1.0e-10_dp)
        opts%harmonics = 20
        call solve_periodic(c%model, opts, half, error)
        call check(t, .not. allocated(error), "fallback: stuck damper at H = 20, no error")
        if (allocated(error)) return
        call check_close(t, half%xcoef(1, 1), sol%xcoef(1, 1), &
                         "fallback: stuck damper, mean offset at H = 20 and 40", rtol=1.0e-10_dp)
        call check_close(t, half%rcoef(1, 2), lambda0, &
                         "fallback: stuck damper, mean normal force at H = 20 and 40", &
                         rtol=1.0e-10_dp)
    end subroutine test_stuck_normal
end module test_fallback
