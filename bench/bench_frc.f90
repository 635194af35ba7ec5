!> Benchmark of forced-response curves (a program that prints figures, not a test): the
!> seed system with light damping (examples/seed_frc.nml, C = 0.02 M + 0.02 K) over omega in
!> [0.2, 6] with the step set for about 400 points, with and without the Floquet stability
!> of every point, and with and without the truncation estimate; total CPU time, time per
!> point, points, folds, rejected steps. Medians over repeats; all variants in one process.
!> Then the cost of a sweep point against a cold solve (no stability, no truncation):
!> the seed case, the 4-DOF chain (examples/chain4.nml, omega 0.2 -> 2, step 0.0045) and
!> the 80-DOF beam (examples/beam_mm/beam.nml, omega 30 -> 60, step 0.1): the cold solve at
!> the start of the range (median of 7), ms per point, points per second, their ratio and
!> the factorizations of Z_h (sets over the basis) per point.
!> Run from the project root: fpm run --example bench_frc --profile release [-- repeats]
program bench_frc
    use, intrinsic :: iso_fortran_env, only: output_unit
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: median
    use stickslip_sweep, only: sweep_result_t, run_sweep
    use stickslip_hbm, only: solve_periodic
    use stickslip_solution, only: hbm_solution_t
    use stickslip_blas_threads, only: limit_blas_threads
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

    call limit_blas_threads()
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
    write (output_unit, '(/,a)') "case                    points  cold solve [ms]  per point [ms]"// &
        "  points/s  point/cold  factorizations/point"
    call point_cost("seed_frc", "examples/seed_frc.nml", 0.0_dp, 0.0_dp, 0.0_dp)
    call point_cost("chain4", "examples/chain4.nml", 0.2_dp, 2.0_dp, 0.0045_dp)
    call point_cost("beam_mm (80 DOFs)", "examples/beam_mm/beam.nml", 30.0_dp, 60.0_dp, 0.1_dp)

contains

    !> A sweep point against a cold solve at the start of the range (step = 0: the case's
    !> own &sweep).
    subroutine point_cost(name, file, start, stop, step)
        character(len=*), intent(in) :: name, file
        real(dp), intent(in) :: start, stop, step
        type(case_t) :: cv
        type(sweep_result_t) :: res
        type(hbm_solution_t) :: sol
        real(dp) :: t0, t1, cold(7), times(repeats)
        integer :: r
        call read_case(file, cv, error)
        if (allocated(error)) then
            write (output_unit, '(a)') name//": error: "//error%message
            return
        end if
        if (step > 0.0_dp) then
            cv%sweep%parameter = 'omega'
            cv%sweep%start = start
            cv%sweep%stop = stop
            cv%sweep%step = step
            cv%sweep%max_step = step
        end if
        cv%sweep%stability = .false.
        cv%sweep%truncation = .false.
        cv%sweep%max_points = 20000
        cv%model%omega = cv%sweep%start
        do r = 1, size(cold)
            call cpu_time(t0)
            call solve_periodic(cv%model, cv%hbm, sol, error)
            call cpu_time(t1)
            cold(r) = t1 - t0
        end do
        do r = 1, repeats
            call cpu_time(t0)
            call run_sweep(cv%model, cv%hbm, cv%reference%reference_options_t, &
                           cv%sweep%sweep_options_t, res, error)
            call cpu_time(t1)
            if (allocated(error)) then
                write (output_unit, '(a)') name//": error: "//error%message
                return
            end if
            times(r) = t1 - t0
        end do
        write (output_unit, '(a22,i8,f17.3,f16.3,f10.1,f12.2,f22.2)') name, res%npoints, &
            1.0e3_dp*median(cold), 1.0e3_dp*median(times)/res%npoints, &
            res%npoints/median(times), median(times)/res%npoints/median(cold), &
            real(res%factorizations, dp)/res%npoints
    end subroutine point_cost

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
