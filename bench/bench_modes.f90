!> Benchmark of nonlinear modal analysis (a program that prints figures, not a test): the
!> backbone of a mode by EPMC (&run method = 'modes') on the seed structure (examples/
!> seed_modes.nml: 2 DOF, a = 0.01 -> 1000, H = 15) and on the CalculiX strip with its tip
!> damper (examples/calculix_beam/modes.nml: 2412 DOFs reduced by Craig-Bampton to 8, 200
!> points requested over a = 1e-2 -> 3e-6, H = 15), against the forced-response sweep of the
!> same strip (examples/calculix_beam/case.nml without stability, the same H) in the same
!> process: CPU of the whole backbone (the case read and reduced once, outside the timing),
!> points, ms per point, factorizations of Z_h. Medians over repeats.
!> Run from the project root: fpm run --example bench_modes --profile release [-- repeats]
program bench_modes
    use, intrinsic :: iso_fortran_env, only: output_unit
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: median
    use stickslip_modes, only: modes_result_t, run_modes
    use stickslip_sweep, only: sweep_result_t, run_sweep
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    integer :: repeats
    character(len=32) :: arg

    call limit_blas_threads()
    repeats = 5
    if (command_argument_count() > 0) then
        call get_command_argument(1, arg)
        read (arg, *) repeats
    end if
    write (output_unit, '(a)') "case                                   points  total [s]  "// &
        "per point [ms]  factorizations  complete"
    call measure("seed_modes (2 DOF)", "examples/seed_modes.nml", .true.)
    call measure("calculix_beam/modes (2412 -> 8 DOF)", "examples/calculix_beam/modes.nml", &
                 .true.)
    call measure("calculix_beam/case sweep, no stability", "examples/calculix_beam/case.nml", &
                 .false.)

contains

    !> The median CPU time over `repeats` runs of the backbone of case `path` (`modes`), or
    !> of its forced sweep without stability.
    subroutine measure(name, path, modes)
        character(len=*), intent(in) :: name, path
        logical, intent(in) :: modes
        type(case_t) :: c
        type(modes_result_t) :: backbone
        type(sweep_result_t) :: curve
        type(error_type), allocatable :: error
        real(dp) :: t(repeats), t0
        integer :: r, points, factorizations
        logical :: complete
        call read_case(path, c, error)
        c%sweep%stability = .false.
        do r = 1, repeats
            if (allocated(error)) exit
            t0 = thread_cpu_seconds()
            if (modes) then
                call run_modes(c%model, c%hbm, c%modes%modes_options_t, backbone, error)
            else
                call run_sweep(c%model, c%hbm, c%reference%reference_options_t, &
                               c%sweep%sweep_options_t, curve, error)
            end if
            t(r) = thread_cpu_seconds() - t0
        end do
        if (allocated(error)) then
            write (output_unit, '(a)') "error: "//error%message
            return
        end if
        if (modes) then
            points = backbone%npoints
            factorizations = backbone%factorizations
            complete = backbone%complete
        else
            points = curve%npoints
            factorizations = curve%factorizations
            complete = curve%complete
        end if
        write (output_unit, '(a38,i7,f11.3,f16.3,i16,l10)') name, points, median(t), &
            1.0e3_dp*median(t)/points, factorizations, complete
    end subroutine measure
end program bench_modes
