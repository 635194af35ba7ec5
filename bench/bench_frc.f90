!> Benchmark of forced-response curves (a program that prints figures, not a test): the
!> seed system with light damping (examples/seed_frc.nml, C = 0.02 M + 0.02 K) over omega in
!> [0.2, 6] with the step set for about 400 points, with and without the Floquet stability
!> of every point, and with and without the truncation estimate; total CPU time, time per
!> point, points, folds, rejected steps. Medians over repeats; all variants in one process.
!> Run from the project root: fpm run --example bench_frc --profile release [-- repeats]
program bench_frc
    use, intrinsic :: iso_fortran_env, only: output_unit
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: median
    use stickslip_sweep, only: sweep_result_t, run_sweep
    implicit none
    type(case_t) :: c
    type(error_type), allocatable :: error
    integer :: repeats, k
    character(len=32) :: arg
    integer, parameter :: nvar = 5
    character(len=40), parameter :: names(nvar) = [character(len=40) :: &
        "H=30, 128 samples, no stability", "H=30, 128 samples, + truncation", &
        "H=30, 128 samples, + stability", "H=30, 128 samples, + both", &
        "H=30, 1024 samples, no stability"]

    repeats = 3
    if (command_argument_count() > 0) then
        call get_command_argument(1, arg)
        read (arg, *) repeats
    end if
    call read_case("examples/seed_frc.nml", c, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    write (output_unit, '(a)') "seed system, C = 0.02 M + 0.02 K, omega 0.2 -> 6 rad/s, "// &
        "step = max_step = 0.0145 rad/s"
    write (output_unit, '(a)') "variant                                  points  folds rejected"// &
        "   total [s]  per point [ms]  complete"
    do k = 1, nvar
        call measure(k)
    end do

contains

    subroutine measure(variant)
        integer, intent(in) :: variant
        type(case_t) :: cv
        type(sweep_result_t) :: res
        real(dp) :: t0, t1, times(repeats)
        integer :: r
        cv = c
        cv%sweep%stability = variant == 3 .or. variant == 4
        cv%sweep%truncation = variant == 2 .or. variant == 4
        if (variant == 5) cv%hbm%samples = 1024
        cv%sweep%max_points = 20000
        do r = 1, repeats
            call cpu_time(t0)
            call run_sweep(cv%model, cv%hbm, cv%reference%reference_options_t, &
                           cv%sweep%sweep_options_t, res, error)
            call cpu_time(t1)
            if (allocated(error)) then
                write (output_unit, '(a)') trim(names(variant))//": error: "//error%message
                return
            end if
            times(r) = t1 - t0
        end do
        write (output_unit, '(a40,i7,i7,i9,f12.3,f16.3,l10)') names(variant), res%npoints, &
            res%folds, res%state%rejected, median(times), 1.0e3_dp*median(times)/res%npoints, &
            res%complete
    end subroutine measure
end program bench_frc
