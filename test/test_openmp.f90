!> The library called from several OpenMP threads at once: every thread must get the serial
!> answer (the solver's callback slot is threadprivate, the FFTW planner is serialized).
!> Meaningful only when the tests and the library are built with OpenMP
!> (`fpm test --profile debug --flag -fopenmp`, as .ci/run does); in a serial build the suite
!> says so on stdout and checks only that stickslip_thread_safe() reports a serial build.
module test_openmp
    use, intrinsic :: iso_fortran_env, only: output_unit
    !$ use omp_lib, only: omp_get_thread_num
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_version_info, only: stickslip_thread_safe
    use testing, only: test_counter_t, check, check_close
    use fixtures, only: seed_model
    implicit none
    private
    public :: run_openmp_tests

contains

    subroutine run_openmp_tests(t)
        type(test_counter_t), intent(inout) :: t
        logical :: openmp
        openmp = .false.
        !$ openmp = .true.
        call check(t, stickslip_thread_safe() .eqv. openmp, &
                   "openmp: stickslip_thread_safe() tells the build (tests and library built alike)")
        if (.not. openmp) then
            write (output_unit, '(a)') "openmp: built without -fopenmp, the concurrent solve " // &
                "is not tested (.ci/run builds the tests with OpenMP too)"
            return
        end if
        call test_concurrent_solves(t)
    end subroutine run_openmp_tests

    !> The seed system at 24 forcing frequencies, solved serially and then by 4 threads at
    !> once (round-robin, so that every thread solves while the others do): the same
    !> amplitudes and evaluation counts.
    subroutine test_concurrent_solves(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: npoints = 24, nthreads = 4
        real(dp) :: serial(npoints), parallel(npoints)
        integer :: nfev_serial(npoints), nfev_parallel(npoints), thread(npoints), nerr
        integer :: i
        nerr = 0
        thread = 0
        call sweep(.false., serial, nfev_serial, thread, nerr)
        call sweep(.true., parallel, nfev_parallel, thread, nerr)
        call check(t, nerr == 0, "openmp: every solve converged without error")
        call check(t, count([(any(thread == i), i=0, nthreads - 1)]) >= 2, &
                   "openmp: the solves ran on several threads")
        call check_close(t, parallel, serial, "openmp: each thread gets the serial amplitude", &
                         rtol=1.0e-13_dp)
        call check(t, all(nfev_parallel == nfev_serial), "openmp: same evaluation counts")
    end subroutine test_concurrent_solves

    subroutine sweep(in_parallel, amp, nfev, thread, nerr)
        logical, intent(in) :: in_parallel
        real(dp), intent(out) :: amp(:)
        integer, intent(out) :: nfev(:)
        integer, intent(inout) :: thread(:), nerr
        type(model_t) :: m, seed
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        type(error_type), allocatable :: error
        integer :: i
        seed = seed_model()
        o%harmonics = 10
        o%samples = 128
        o%rho = 0.2_dp
        !$omp parallel do if(in_parallel) num_threads(4) schedule(static, 1) &
        !$omp& private(m, s, error) firstprivate(o) reduction(+:nerr)
        do i = 1, size(amp)
            m = seed
            m%omega = 3.0_dp + 3.0_dp*real(i - 1, dp)/real(size(amp) - 1, dp)
            call solve_periodic(m, o, s, error)
            amp(i) = -1.0_dp
            nfev(i) = -1
            if (allocated(error)) then
                nerr = nerr + 1
            else
                if (.not. s%converged) nerr = nerr + 1
                amp(i) = maxval(abs(s%x(:, 2)))
                nfev(i) = s%nfev
            end if
            !$ if (in_parallel) thread(i) = omp_get_thread_num()
        end do
        !$omp end parallel do
    end subroutine sweep
end module test_openmp
