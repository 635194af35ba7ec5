!> Concurrency check and throughput of solve_periodic under OpenMP (a program that prints
!> figures). Solves the seed system at 64 forcing frequencies serially and then in an OpenMP
!> parallel loop, and prints the largest difference between the two (expected: 0) and both
!> wall times. Build with OpenMP:
!>   fpm run --example bench_omp --profile release --flag -fopenmp
!> The model is read from examples/seed.nml (run from the project root).
!> Without -fopenmp the loop runs serially (and the check is trivially met).
program bench_omp
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_case, only: case_t, read_case
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    integer, parameter :: npoints = 64
    type(case_t) :: c
    type(error_type), allocatable :: read_error
    real(dp) :: serial(npoints), parallel(npoints)
    integer :: nfail
    integer(int64) :: c0, c1, c2, rate

    call limit_blas_threads()
    call read_case("examples/seed.nml", c, read_error)
    if (allocated(read_error)) then
        write (output_unit, '(a)') "error: "//read_error%message
        stop 1
    end if
    call system_clock(c0, rate)
    call sweep(serial, .false., nfail)
    call system_clock(c1)
    call sweep(parallel, .true., nfail)
    call system_clock(c2)
    write (output_unit, '(a,i0,a)') "seed system at ", npoints, " frequencies in [3, 6] rad/s, H = 15"
    write (output_unit, '(a,f0.1,a)') "serial:   ", 1.0e3_dp*real(c1 - c0, dp)/rate, " ms"
    write (output_unit, '(a,f0.1,a,i0,a)') "parallel: ", 1.0e3_dp*real(c2 - c1, dp)/rate, &
        " ms (", nfail, " not converged)"
    write (output_unit, '(a,es9.2)') "largest |serial - parallel| of max|x1|: ", &
        maxval(abs(serial - parallel))

contains

    subroutine sweep(amp, in_parallel, nfail)
        real(dp), intent(out) :: amp(:)
        logical, intent(in) :: in_parallel
        integer, intent(out) :: nfail
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        type(error_type), allocatable :: error
        integer :: i
        nfail = 0
        o%harmonics = 15
        o%samples = 256
        o%rho = c%hbm%rho
        !$omp parallel do if(in_parallel) private(m, s, error) firstprivate(o) &
        !$omp& reduction(+:nfail) schedule(dynamic)
        do i = 1, size(amp)
            m = c%model
            m%omega = 3.0_dp + 3.0_dp*real(i - 1, dp)/real(size(amp) - 1, dp)
            call solve_periodic(m, o, s, error)
            if (allocated(error)) then
                nfail = nfail + 1
                amp(i) = -1.0_dp
            else
                if (.not. s%converged) nfail = nfail + 1
                amp(i) = maxval(abs(s%x(:, 1)))
            end if
        end do
        !$omp end parallel do
    end subroutine sweep

end program bench_omp
