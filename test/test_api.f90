!> The two public umbrellas as a host code uses them: `stickslip` (model in memory, methods,
!> results, findings) and `stickslip_io` (a case file read and run through the one dispatch
!> of &run method). Checks that the names a host needs are there and agree with each other.
module test_api
    use stickslip, only: dp, error_type, model_t, hbm_options_t, hbm_solution_t, &
        solve_periodic, check_options_t, hbm_checks_t, solve_and_check, &
        reference_start_options_t, reference_result_t, solve_reference_from_starts, level_warning, level_untrusted, &
        stickslip_version, stickslip_thread_safe
    use stickslip_io, only: case_t, read_case, run_result_t, run_method, method_names
    use fixtures, only: seed_model, enter_project_root, project_path, scratch
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_api_tests

contains

    subroutine run_api_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()
        call test_host_api(t)
        call test_io_api(t)
    end subroutine run_api_tests

    !> The seed model built in memory: the weighted residual and the exact reference through
    !> the umbrella agree to the weighted residual's accuracy, and the checks find nothing
    !> doubtful about a well-resolved solution.
    subroutine test_host_api(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: model
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sol
        type(check_options_t) :: copts
        type(hbm_checks_t) :: checks
        type(reference_start_options_t) :: ropts
        type(reference_result_t) :: ref
        type(error_type), allocatable :: error
        real(dp) :: amp_hbm, amp_ref
        model = seed_model()
        opts%harmonics = 60
        opts%samples = 1024
        call solve_periodic(model, opts, sol, error)
        call check_error(t, error, "api: solve_periodic", .false.)
        if (allocated(error)) return
        call check(t, sol%converged, "api: seed converged")
        call solve_and_check(model, opts, copts, ropts%reference_options_t, sol, checks, error)
        call check_error(t, error, "api: solve_and_check", .false.)
        if (allocated(error)) return
        call check(t, max(sol%diagnostics%worst(), checks%diagnostics%worst()) < level_warning, &
                   "api: no warning on the well-resolved seed case")
        call solve_reference_from_starts(model, ropts, ref, error, hbm_opts=opts, hbm_start=sol)
        call check_error(t, error, "api: reference", .false.)
        if (allocated(error)) return
        call check(t, ref%converged, "api: reference converged")
        amp_hbm = maxval(sol%x(:, 2)) - minval(sol%x(:, 2))
        amp_ref = maxval(ref%x(:, 2)) - minval(ref%x(:, 2))
        call check_close(t, amp_hbm, amp_ref, "api: x2 peak-to-peak, hbm vs exact", rtol=2.0e-2_dp)
        call check(t, len(stickslip_version) > 0, "api: version")
        call check(t, stickslip_thread_safe() .eqv. openmp_build(), "api: thread safety flag")
    end subroutine test_host_api

    !> The seed example read and run through stickslip_io's dispatch into a scratch
    !> directory; every method name the dispatch knows is a documented one.
    subroutine test_io_api(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(run_result_t) :: res
        type(error_type), allocatable :: error
        call read_case(project_path("examples/chain4.nml"), c, error)
        call check_error(t, error, "api: read chain4.nml", .false.)
        if (allocated(error)) return
        c%directory = scratch//"/out_api"
        call run_method(c, res, error)
        call check_error(t, error, "api: run_method", .false.)
        if (allocated(error)) return
        call check(t, res%method == c%method, "api: the result names the method run")
        call check(t, res%diagnostics%worst() < level_untrusted, "api: chain4 trusted")
        call check(t, size(method_names) == 8 .and. any(method_names == 'robustness') .and. &
                   any(method_names == 'modes'), "api: eight methods dispatched")

    end subroutine test_io_api

    logical function openmp_build()
        openmp_build = .false.
        !$ openmp_build = .true.
    end function openmp_build
end module test_api
