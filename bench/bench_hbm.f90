!> Benchmark of the weighted-residual solve on the seed case (a program that prints figures,
!> not a test). Prints, for each harmonic count, all and odd-only: median wall time of
!> solve_periodic over repeats, nfev, njev, hybrj calls and the residual.
!> With --sweep it also solves every harmonic count 5..256 from a cold start (all and odd)
!> and prints how many converged and the worst case.
!> The model is read from examples/seed.nml (run from the project root).
!> Run: fpm run --example bench_hbm --profile release [-- --sweep]
program bench_hbm
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: median
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    integer, parameter :: hs(8) = [5, 10, 20, 30, 50, 100, 200, 256]
    type(model_t) :: m
    type(case_t) :: c
    type(hbm_options_t) :: o
    type(hbm_solution_t) :: s
    type(error_type), allocatable :: error
    integer :: i, io, nrep, k, h, nconv, worst_h, worst_nfev
    real(dp) :: times(201), med
    character(len=32) :: arg
    logical :: sweep

    call limit_blas_threads()
    sweep = .false.
    do i = 1, command_argument_count()
        call get_command_argument(i, arg)
        if (arg == '--sweep') sweep = .true.
    end do
    call read_case("examples/seed.nml", c, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    m = c%model
    write (output_unit, '(a)') "seed case, samples = 1024, rho = 0.2, cold start (start = 'auto')"
    write (output_unit, '(a)') "| H | basis | unknowns | median solve [ms] | repeats | nfev | njev "// &
        "| hybrj calls | converged | residual |"
    write (output_unit, '(a)') "|---|---|---|---|---|---|---|---|---|---|"
    do io = 0, 1
        do i = 1, size(hs)
            o = hbm_options_t()
            o%odd_only = io == 1
            o%harmonics = hs(i) - merge(1, 0, o%odd_only .and. mod(hs(i), 2) == 0)
            o%samples = 1024
            o%rho = 0.2_dp
            o%want_samples = .false.
            nrep = 0
            do k = 1, size(times)
                call solve_periodic(m, o, s, error)
                if (allocated(error)) then
                    write (output_unit, '(a)') "error: "//error%message
                    stop 1
                end if
                nrep = k
                times(k) = s%seconds
                if (sum(times(1:k)) > 1.0_dp .and. k >= 5) exit
            end do
            med = median(times(1:nrep))
            write (output_unit, '("| ",i0," | ",a," | ",i0," | ",f0.3," | ",i0," | ",i0," | ",i0, &
                &" | ",i0," | ",l1," | ",es9.2," |")') o%harmonics, &
                trim(merge("odd", "all", o%odd_only)), s%nb, 1.0e3_dp*med, nrep, s%nfev, s%njev, &
                s%hybrj_calls, s%converged, s%fnorm
        end do
    end do

    if (sweep) then
        do io = 0, 1
            nconv = 0
            worst_nfev = 0
            worst_h = 0
            do h = 5, 256
                o = hbm_options_t()
                o%odd_only = io == 1
                if (o%odd_only .and. mod(h, 2) == 0) cycle
                o%harmonics = h
                o%samples = 1024
                o%rho = 0.2_dp
                o%want_samples = .false.
                call solve_periodic(m, o, s, error)
                if (.not. allocated(error)) then
                    if (s%converged .and. s%stick_phases(1) == 2) nconv = nconv + 1
                    if (.not. s%converged) write (output_unit, '(a,i0)') "  not converged: H = ", h
                    if (s%stick_phases(1) /= 2) write (output_unit, '(a,i0,a,i0)') &
                        "  stick phases: ", s%stick_phases(1), " at H = ", h
                end if
                if (s%nfev > worst_nfev) then
                    worst_nfev = s%nfev
                    worst_h = h
                end if
            end do
            write (output_unit, '(a,a,a,i0,a,i0,a,i0,a,i0)') "sweep H = 5..256 (", &
                trim(merge("odd", "all", io == 1)), "): ", nconv, " converged with two stick "// &
                "phases of ", merge(126, 252, io == 1), "; most evaluations: ", worst_nfev, &
                " at H = ", worst_h
        end do
    end if
end program bench_hbm
