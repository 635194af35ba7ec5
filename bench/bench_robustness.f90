!> Robustness benchmark (a program that prints figures, not a test): the seed case of
!> examples/seed.nml over omega = 0.5 .. 6 rad/s x mu = 0.1, 0.45, 1, 3 x H = 10, 30, 100 x
!> rho = 0.02, 0.2, 1, 5 m/(N s) and automatic, cold and warm starts, implicit Euler beside,
!> every run checked against the exact reference (stickslip_robustness). Prints the success
!> rates per rho and H, the failures by mu and the CPU times. Run from the project root:
!>     fpm run --example bench_robustness --profile release [-- options]
!> Options: --start direct|auto|ladder (&hbm start of the runs, default direct: a bare cold
!> start; auto adds the harmonic ladder when it stalls), --step <omega step> (default 0.25),
!> --euler <steps per period> (default 1000, 0: none), --scale <s> (M, C, K, forces and
!> normal loads times s: a change of units), --csv <dir> (write robustness.csv there),
!> --threads <n> (default 2). All cores: the study runs twice in this process, on 1 OpenMP
!> thread and on n, and the wall times, the speedup, the load average of the machine
!> (/proc/loadavg) before each run and whether the rows are identical are printed first; the
!> tables below are those of the n-thread run (built with OpenMP, the default).
program bench_robustness
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
    !$ use omp_lib, only: omp_set_num_threads
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: median
    use stickslip_files, only: make_directory
    use stickslip_csv, only: write_robustness_csv
    use stickslip_robustness, only: robustness_options_t, robustness_row_t, run_robustness, &
        default_robustness_options
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    type(case_t) :: c
    type(robustness_options_t) :: r
    type(robustness_row_t), allocatable :: rows(:), serial(:)
    type(error_type), allocatable :: error
    character(len=256) :: arg, value, csv_dir
    character(len=8) :: start
    character(len=:), allocatable :: load1, loadn
    real(dp) :: step, scale, c0, c1, wall1, walln
    integer :: i, nstep, euler_steps, nthreads
    integer(int64) :: w0, w1, clock_rate
    integer :: ndiff, nflags
    real(dp) :: worst

    call limit_blas_threads()
    start = 'direct'
    step = 0.25_dp
    scale = 1.0_dp
    euler_steps = 1000
    csv_dir = ''
    nthreads = 2
    i = 1
    do while (i <= command_argument_count())
        call get_command_argument(i, arg)
        call get_command_argument(i + 1, value)
        select case (arg)
        case ('--start')
            start = value
        case ('--step')
            read (value, *) step
        case ('--scale')
            read (value, *) scale
        case ('--euler')
            read (value, *) euler_steps
        case ('--csv')
            csv_dir = value
        case ('--threads')
            read (value, *) nthreads
        case default
            write (output_unit, '(a)') "unknown option "//trim(arg)
            stop 1
        end select
        i = i + 2
    end do

    call read_case("examples/seed.nml", c, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    c%model%mass = scale*c%model%mass
    c%model%damping = scale*c%model%damping
    c%model%stiffness = scale*c%model%stiffness
    c%model%force_amplitude = scale*c%model%force_amplitude
    c%model%normal_load = scale*c%model%normal_load
    c%hbm%start = start
    ! the references start from the weighted residual with the automatic rho (the runs
    ! replace rho anyway), so that they do not depend on the units either
    c%hbm%rho = 0.0_dp
    r = default_robustness_options()
    nstep = nint((6.0_dp - 0.5_dp)/step)
    r%omegas = [(0.5_dp + step*i, i=0, nstep)]
    if (euler_steps > 0) r%steps_per_period = [euler_steps]
    ! 1 thread, then nthreads, in this process (wall time; CPU of every thread summed)
    !$ call omp_set_num_threads(1)
    load1 = loadavg()
    call system_clock(w0, clock_rate)
    call run_robustness(c%model, c%hbm, c%euler, c%reference, r, serial, error)
    call system_clock(w1)
    wall1 = real(w1 - w0, dp)/real(clock_rate, dp)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    !$ call omp_set_num_threads(nthreads)
    loadn = loadavg()
    call cpu_time(c0)
    call system_clock(w0, clock_rate)
    call run_robustness(c%model, c%hbm, c%euler, c%reference, r, rows, error)
    call system_clock(w1)
    call cpu_time(c1)
    walln = real(w1 - w0, dp)/real(clock_rate, dp)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    ! bitwise with the reference BLAS; OpenBLAS's kernels sum in an order that depends on
    ! the arrays' alignment (different heaps per thread), so a row may differ by roundoff,
    ! visibly only where the answer is not unique (a contact stuck all period)
    if (size(rows) /= size(serial)) error stop "bench_robustness: row counts differ"
    ndiff = 0
    nflags = 0
    worst = 0.0_dp
    do i = 1, size(rows)
        if (rows(i)%iterations /= serial(i)%iterations .or. &
            (rows(i)%converged .neqv. serial(i)%converged) .or. &
            (rows(i)%success .neqv. serial(i)%success)) nflags = nflags + 1
        if (rows(i)%err_amplitude == serial(i)%err_amplitude .or. &
            (ieee_is_nan(rows(i)%err_amplitude) .and. ieee_is_nan(serial(i)%err_amplitude))) cycle
        ndiff = ndiff + 1
        worst = max(worst, abs(rows(i)%err_amplitude - serial(i)%err_amplitude)/ &
                    max(abs(serial(i)%err_amplitude), tiny(1.0_dp)))
        write (output_unit, '(a,i0,1x,a,a,g0.4,a,g0.4,a,i0,a,g0.3,a,2es12.4)') "differs: row ", &
            i, trim(rows(i)%method), " omega ", rows(i)%omega, " mu ", rows(i)%mu, " H ", &
            rows(i)%harmonics, " rho ", rows(i)%rho, " err_amplitude n/1 threads ", &
            rows(i)%err_amplitude, serial(i)%err_amplitude
    end do
    write (output_unit, '(a,i0,a)') "| threads | wall [s] | speedup | sum of per-run CPU [s] "// &
        "| load average before (1, 5, 15 min) |"
    write (output_unit, '(a)') "|---|---|---|---|---|"
    write (output_unit, '(a,f0.2,a,f0.2,a)') "| 1 | ", wall1, " | 1 | ", &
        sum(serial%cpu_seconds), " | "//load1//" |"
    write (output_unit, '(a,i0,a,f0.2,a,f0.2,a,f0.2,a)') "| ", nthreads, " | ", walln, " | ", &
        wall1/walln, " | ", sum(rows%cpu_seconds), " | "//loadn//" |"
    write (output_unit, '(a,i0,a,i0,a,i0,a,es9.2)') "rows on 1 and n threads: ", &
        size(rows) - ndiff, " of ", size(rows), " identical bitwise (cpu_seconds aside); "// &
        "converged/success/iterations differ in ", nflags, "; largest relative difference "// &
        "of err_amplitude ", worst
    if (len_trim(csv_dir) > 0) then
        call make_directory(trim(csv_dir), error)
        if (.not. allocated(error)) call write_robustness_csv(trim(csv_dir), rows, error)
        if (allocated(error)) write (output_unit, '(a)') "error: "//error%message
    end if

    write (output_unit, '(a,i0,a,i0,a,a,a,g0.3,a,f0.1,a)') "seed case, ", size(r%omegas), &
        " omegas x ", size(r%mus), " mus, start = '", trim(start), "', units x ", scale, &
        ", total ", c1 - c0, " s CPU (all threads of the n-thread run)"
    call table('hbm-cold')
    call table('hbm-warm')
    call by_mu('hbm-cold')
    call by_mu('hbm-warm')
    call wrong()
    call timings()

contains

    !> The first three fields of /proc/loadavg ('?' where it cannot be read).
    function loadavg() result(text)
        character(len=:), allocatable :: text
        character(len=100) :: line
        integer :: u, stat, k
        text = "?"
        open (newunit=u, file="/proc/loadavg", action='read', status='old', iostat=stat)
        if (stat /= 0) return
        read (u, '(a)', iostat=stat) line
        close (u)
        if (stat /= 0) return
        k = index(line, ' ')
        k = k + index(line(k + 1:), ' ')
        k = k + index(line(k + 1:), ' ')
        text = trim(line(1:k - 1))
    end function loadavg

    !> Success rate (converged, error within wrong_tol) per rho (rows) and H (columns).
    subroutine table(method)
        character(len=*), intent(in) :: method
        integer :: ir, ih
        character(len=12) :: label
        write (output_unit, '(/,a)') method//": successes (converged, err <= wrong_tol) / runs"
        write (output_unit, '(a)', advance='no') "| rho "
        do ih = 1, size(r%harmonics)
            write (output_unit, '(a,i0,a)', advance='no') "| H = ", r%harmonics(ih), " "
        end do
        write (output_unit, '(a)') "| all |"
        write (output_unit, '(a)') "|---|"//repeat("---|", size(r%harmonics) + 1)
        do ir = 1, size(r%rhos)
            if (r%rhos(ir) == 0.0_dp) then
                label = "auto"
            else
                write (label, '(g0.3)') r%rhos(ir)
            end if
            write (output_unit, '(a)', advance='no') "| "//trim(label)//" "
            do ih = 1, size(r%harmonics)
                call rate(pick(method, r%rhos(ir), r%harmonics(ih)))
            end do
            call rate(pick(method, r%rhos(ir), 0))
            write (output_unit, '(a)') "|"
        end do
    end subroutine table

    !> Failures per mu and rho, all H together.
    subroutine by_mu(method)
        character(len=*), intent(in) :: method
        integer :: ir, k
        logical, allocatable :: sel(:)
        write (output_unit, '(/,a)') method//": failures per mu (rows) and rho (columns), all H"
        write (output_unit, '(a)', advance='no') "| mu "
        do ir = 1, size(r%rhos)
            if (r%rhos(ir) == 0.0_dp) then
                write (output_unit, '(a)', advance='no') "| auto "
            else
                write (output_unit, '(a,g0.3,a)', advance='no') "| ", r%rhos(ir), " "
            end if
        end do
        write (output_unit, '(a)') "|"
        write (output_unit, '(a)') "|---|"//repeat("---|", size(r%rhos))
        do k = 1, size(r%mus)
            write (output_unit, '(a,g0.3,a)', advance='no') "| ", r%mus(k), " "
            do ir = 1, size(r%rhos)
                sel = pick(method, r%rhos(ir), 0) .and. rows%mu == r%mus(k)
                write (output_unit, '(a,i0,a)', advance='no') "| ", &
                    count(sel .and. .not. rows%success), " "
            end do
            write (output_unit, '(a)') "|"
        end do
    end subroutine by_mu

    !> Converged runs whose error exceeds wrong_tol, and the largest error of a success.
    subroutine wrong()
        logical, allocatable :: hbm(:)
        integer :: k
        hbm = rows%method /= 'euler'
        write (output_unit, '(/,a,i0,a,es9.2)') "converged but err_amplitude > wrong_tol: ", &
            count(hbm .and. rows%converged .and. .not. rows%success), &
            "; largest err_amplitude of a success: ", &
            maxval(rows%err_amplitude, mask=hbm .and. rows%success)
        write (output_unit, '(a,i0,a,i0,a)') "euler: ", count(rows%method == 'euler' .and. &
            rows%success), " / ", count(rows%method == 'euler'), &
            " periodic within max_periods and close to the reference"
        ! one row per grid point: the cold runs with the first H and the automatic rho
        write (output_unit, '(a,i0)') "grid points without a reference: ", &
            count([(rows(k)%method == 'hbm-cold' .and. rows(k)%rho_auto .and. &
                    rows(k)%harmonics == r%harmonics(1) .and. &
                    index(rows(k)%diagnosis, "no reference") > 0, k=1, size(rows))])
    end subroutine wrong

    !> CPU time per run: median and total per method and H.
    subroutine timings()
        integer :: ih, im
        character(len=8), parameter :: methods(2) = [character(len=8) :: 'hbm-cold', 'hbm-warm']
        logical, allocatable :: sel(:)
        write (output_unit, '(/,a)') "| method | H | runs | median CPU [ms] | total CPU [s] "// &
            "| median evaluations (converged) |"
        write (output_unit, '(a)') "|---|---|---|---|---|---|"
        do im = 1, size(methods)
            do ih = 1, size(r%harmonics)
                sel = rows%method == methods(im) .and. rows%harmonics == r%harmonics(ih)
                write (output_unit, '(a,a,a,i0,a,i0,a,f0.2,a,f0.2,a,i0,a)') "| ", &
                    trim(methods(im)), " | ", r%harmonics(ih), " | ", count(sel), " | ", &
                    1.0e3_dp*median(pack(rows%cpu_seconds, sel)), " | ", &
                    sum(rows%cpu_seconds, mask=sel), " | ", &
                    nint(median(real(pack(rows%iterations, sel .and. rows%converged), dp))), " |"
            end do
        end do
        sel = rows%method == 'euler'
        if (any(sel)) write (output_unit, '(a,i0,a,i0,a,f0.2,a,f0.2,a,i0,a)') &
            "| euler (", r%steps_per_period(1), " steps) | - | ", count(sel), " | ", &
            1.0e3_dp*median(pack(rows%cpu_seconds, sel)), " | ", &
            sum(rows%cpu_seconds, mask=sel), " | ", &
            nint(median(real(pack(rows%iterations, sel .and. rows%converged), dp))), &
            " periods |"
    end subroutine timings

    !> Rows of a method with a rho option (0: automatic) and H (0: any).
    function pick(method, rho, h) result(sel)
        character(len=*), intent(in) :: method
        real(dp), intent(in) :: rho
        integer, intent(in) :: h
        logical :: sel(size(rows))
        integer :: k
        do k = 1, size(rows)
            sel(k) = rows(k)%method == method .and. (h == 0 .or. rows(k)%harmonics == h)
            if (rho == 0.0_dp) then
                sel(k) = sel(k) .and. rows(k)%rho_auto
            else
                sel(k) = sel(k) .and. .not. rows(k)%rho_auto .and. rows(k)%rho == rho
            end if
        end do
    end function pick

    !> Write "| successes / runs (percent) " for the selected rows.
    subroutine rate(sel)
        logical, intent(in) :: sel(:)
        integer :: n, ok
        n = count(sel)
        ok = count(sel .and. rows%success)
        write (output_unit, '(a,i0,a,i0,a,i0,a)', advance='no') "| ", ok, "/", n, " (", &
            nint(100.0_dp*ok/max(n, 1)), "%) "
    end subroutine rate
end program bench_robustness
