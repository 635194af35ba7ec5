!> Where one CLI run of a case solved by the weighted residual spends its time (a program that
!> prints figures, not a test), run once per process as the CLI is: bench/cli_time.sh calls
!> it N times and prints the medians of each column.
!>
!>   bench_cli parts CASE DIR   one cold run, in the CLI's order: read the case, solve,
!>                              truncation estimate, write hbm.csv, write coefficients.csv;
!>                              prints `parts <read> <solve> <estimate> <hbm.csv>
!>                              <coefficients.csv>` in ms (DIR must exist)
!>   bench_cli fft              FFT plans and execution in a fresh process: the first plan
!>                              pair of 1024 and 4096 points (FFTW's one-time set-up is in the
!>                              first), a second init of the same length, and one 1024-point
!>                              real transform (median of 2001) [us]
!>   bench_cli csv CASE DIR     hbm.csv of CASE's solution written 21 times: median [ms]
!>
!> Run from the project root: fpm run --example bench_cli --profile release -- fft
program bench_cli
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    use stickslip_kinds, only: dp
    use stickslip_sorting, only: sort_ascending
    use stickslip_error, only: error_type
    use stickslip_fft, only: fft_plan_t
    use stickslip_case, only: case_t, read_case
    use stickslip_solution, only: hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_dynamics, only: dynamics_t
    use stickslip_truncation, only: truncation_t, estimate_truncation
    use stickslip_csv, only: write_hbm_csv, write_coefficients_csv
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    character(len=512) :: mode, path, dir

    call limit_blas_threads()
    call get_command_argument(1, mode)
    call get_command_argument(2, path)
    call get_command_argument(3, dir)
    select case (trim(mode))
    case ('parts')
        call parts(trim(path), trim(dir))
    case ('fft')
        call fft_costs()
    case ('csv')
        call csv_costs(trim(path), trim(dir))
    case default
        write (output_unit, '(a)') "usage: bench_cli parts CASE DIR | fft | csv CASE DIR"
        stop 1
    end select

contains

    subroutine parts(path, dir)
        character(len=*), intent(in) :: path, dir
        type(case_t) :: c
        type(hbm_solution_t) :: sol
        type(dynamics_t) :: dyn
        type(truncation_t) :: est
        type(error_type), allocatable :: error
        real(dp) :: ms(5)
        integer(int64) :: t0, t1, rate

        call system_clock(t0, rate)
        call read_case(path, c, error)
        ms(1) = lap(t0, 1.0e3_dp)
        call check(error)
        call solve_periodic(c%model, c%hbm, sol, error, dyn_out=dyn)
        ms(2) = lap(t0, 1.0e3_dp)
        call check(error)
        call estimate_truncation(c%model, c%hbm, sol, est, error, dyn=dyn)
        ms(3) = lap(t0, 1.0e3_dp)
        call check(error)
        call write_hbm_csv(dir, sol, error)
        ms(4) = lap(t0, 1.0e3_dp)
        call check(error)
        call write_coefficients_csv(dir, sol, error)
        ms(5) = lap(t0, 1.0e3_dp)
        call check(error)
        write (output_unit, '(a,5(1x,f0.3))') "parts", ms
    end subroutine parts

    subroutine fft_costs()
        type(fft_plan_t) :: a, b, a2
        type(error_type), allocatable :: error
        real(dp), allocatable :: x(:)
        complex(dp), allocatable :: cw(:)
        real(dp) :: us(4), times(2001)
        integer(int64) :: t0, t1, rate
        integer :: k
        call system_clock(t0, rate)
        call a%init(1024, error)
        us(1) = lap(t0, 1.0e6_dp)
        call check(error)
        call b%init(4096, error)
        us(2) = lap(t0, 1.0e6_dp)
        call check(error)
        call a2%init(1024, error)
        us(3) = lap(t0, 1.0e6_dp)
        call check(error)
        allocate (x(1024), cw(513))
        call random_number(x)
        do k = 1, size(times)
            call system_clock(t0)
            call a%forward(x, cw)
            call system_clock(t1)
            times(k) = 1.0e6_dp*real(t1 - t0, dp)/real(rate, dp)
        end do
        us(4) = median(times)
        write (output_unit, '(a,4(1x,f0.2))') "fft", us
    end subroutine fft_costs

    subroutine csv_costs(path, dir)
        character(len=*), intent(in) :: path, dir
        type(case_t) :: c
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: times(21)
        integer(int64) :: t0, t1, rate
        integer :: k
        call read_case(path, c, error)
        call check(error)
        call solve_periodic(c%model, c%hbm, sol, error)
        call check(error)
        do k = 1, size(times)
            call system_clock(t0, rate)
            call write_hbm_csv(dir, sol, error)
            call system_clock(t1)
            call check(error)
            times(k) = 1.0e3_dp*real(t1 - t0, dp)/real(rate, dp)
        end do
        write (output_unit, '(a,1x,f0.3)') "csv", median(times)
    end subroutine csv_costs

    !> Time since t0 times `scale` (1e3: ms), and t0 moved to now.
    function lap(t0, scale) result(dt)
        integer(int64), intent(inout) :: t0
        real(dp), intent(in) :: scale
        real(dp) :: dt
        integer(int64) :: t1, rate
        call system_clock(t1, rate)
        dt = scale*real(t1 - t0, dp)/real(rate, dp)
        t0 = t1
    end function lap

    subroutine check(error)
        type(error_type), allocatable, intent(in) :: error
        if (allocated(error)) then
            write (output_unit, '(a)') "error: "//error%message
            stop 1
        end if
    end subroutine check

    function median(a) result(m)
        real(dp), intent(in) :: a(:)
        real(dp) :: m
        real(dp) :: s(size(a))
        s = a
        call sort_ascending(s)
        m = s((size(s) + 1)/2)
    end function median
end program bench_cli
