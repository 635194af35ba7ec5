!> Work-precision tables (a program that prints figures, not a test): the studies of
!> examples/seed_study.nml and examples/chain4_study.nml, each run's error against the exact
!> reference and its CPU time (median of repeats), then for a few accuracy targets the
!> cheapest weighted-residual run and the cheapest implicit Euler run that meet them, and
!> the ratio of their CPU times (CPU of the thread that ran each run). All cores: each study
!> runs on 1 OpenMP thread and then on n (`-- --threads n`, default 2) in this process; the
!> wall times, the speedup, the load average before each run and whether the rows are
!> identical are printed, and the tables are those of the n-thread run. Run from the project
!> root:
!>     fpm run --example bench_study --profile release [-- --threads n]
program bench_study
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    !$ use omp_lib, only: omp_set_num_threads
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: study_result_t, run_study
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    character(len=*), parameter :: cases(2) = [character(len=28) :: &
        "examples/seed_study.nml", "examples/chain4_study.nml"]
    real(dp), parameter :: targets(4) = [1.0e-1_dp, 3.0e-2_dp, 1.0e-2_dp, 3.0e-3_dp]
    type(case_t) :: c
    type(study_result_t) :: s, serial
    type(error_type), allocatable :: error
    character(len=64) :: arg
    character(len=:), allocatable :: load1, loadn
    real(dp) :: wall1, walln
    integer(int64) :: w0, w1, rate
    integer :: i, k, nthreads
    logical :: same

    call limit_blas_threads()
    nthreads = 2
    if (command_argument_count() >= 2) then
        call get_command_argument(1, arg)
        if (arg == '--threads') then
            call get_command_argument(2, arg)
            read (arg, *) nthreads
        end if
    end if
    do i = 1, size(cases)
        call read_case(trim(cases(i)), c, error)
        if (allocated(error)) then
            write (output_unit, '(a)') "error: "//error%message
            stop 1
        end if
        !$ call omp_set_num_threads(1)
        load1 = loadavg()
        call system_clock(w0, rate)
        call run_study(c%model, c%hbm, c%euler, c%reference, c%study, serial, error)
        call system_clock(w1)
        wall1 = real(w1 - w0, dp)/real(rate, dp)
        if (allocated(error)) then
            write (output_unit, '(a)') "error: "//error%message
            stop 1
        end if
        !$ call omp_set_num_threads(nthreads)
        loadn = loadavg()
        call system_clock(w0, rate)
        call run_study(c%model, c%hbm, c%euler, c%reference, c%study, s, error)
        call system_clock(w1)
        walln = real(w1 - w0, dp)/real(rate, dp)
        if (allocated(error)) then
            write (output_unit, '(a)') "error: "//error%message
            stop 1
        end if
        same = size(s%rows) == size(serial%rows)
        do k = 1, size(s%rows)
            if (.not. same) exit
            same = s%rows(k)%method == serial%rows(k)%method .and. &
                   s%rows(k)%parameter == serial%rows(k)%parameter .and. &
                   s%rows(k)%iterations == serial%rows(k)%iterations .and. &
                   (allocated(s%rows(k)%cmp%max_error) .eqv. &
                    allocated(serial%rows(k)%cmp%max_error))
            if (same .and. allocated(s%rows(k)%cmp%max_error)) same = &
                all(s%rows(k)%cmp%max_error == serial%rows(k)%cmp%max_error)
        end do
        write (output_unit, '(/,a,f0.2,a,i0,a,f0.2,a,f0.2,a,l1)') trim(cases(i))// &
            ": wall 1 thread ", wall1, " s (load "//load1//"), ", nthreads, " threads ", &
            walln, " s (load "//loadn//"), speedup ", wall1/walln, "; rows identical: ", same
        write (output_unit, '(a,f0.2,a,f0.2,a)') "  sum of per-run CPU: ", &
            sum(serial%rows%cpu_seconds*serial%rows%repeats), " s on 1 thread, ", &
            sum(s%rows%cpu_seconds*s%rows%repeats), " s on n threads (median x repeats)"
        write (output_unit, '(/,a)') trim(cases(i))//": reference in "// &
            fmt_ms(s%reference_seconds)//" CPU"
        write (output_unit, '(a)') "  method  parameter  samples   cpu [ms]   max err x"// &
            "   max err v   rms err r"
        do k = 1, size(s%rows)
            associate (r => s%rows(k))
                if (.not. (r%converged .and. allocated(r%cmp%max_error))) then
                    write (output_unit, '(2x,a6,i11,i9,a)') trim(r%method), r%parameter, &
                        r%samples, "   did not converge"
                    cycle
                end if
                write (output_unit, '(2x,a6,i11,i9,f11.3,3es12.2)') trim(r%method), &
                    r%parameter, r%samples, 1.0e3_dp*r%cpu_seconds, r%cmp%worst('x'), &
                    r%cmp%worst('v'), r%cmp%worst('r', .true.)
            end associate
        end do
        write (output_unit, '(a)') "  cheapest run meeting a target (max err x | rms err r):"
        do k = 1, size(targets)
            call cheapest('x', targets(k))
        end do
        do k = 1, size(targets)
            call cheapest('r', targets(k))
        end do
    end do

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

    !> The cheapest converged run of each method whose error (max x, or RMS r) meets tol.
    subroutine cheapest(kind, tol)
        character(len=1), intent(in) :: kind
        real(dp), intent(in) :: tol
        real(dp) :: best(2), e
        integer :: k, m, arg(2)
        character(len=8), parameter :: names(2) = [character(len=8) :: "hbm", "euler"]
        character(len=:), allocatable :: text
        best = huge(1.0_dp)
        arg = 0
        do k = 1, size(s%rows)
            associate (r => s%rows(k))
                if (.not. (r%converged .and. allocated(r%cmp%max_error))) cycle
                e = r%cmp%worst(kind, kind == 'r')
                m = findloc(names, r%method, 1)
                if (e <= tol .and. r%cpu_seconds < best(m)) then
                    best(m) = r%cpu_seconds
                    arg(m) = k
                end if
            end associate
        end do
        text = "    "//merge("max err x", "rms err r", kind == 'x')//" <= "//fmt_e(tol)//":"
        if (arg(1) > 0) then
            text = text//" hbm H="//itoa(s%rows(arg(1))%parameter)//"/"// &
                   itoa(s%rows(arg(1))%samples)//" "//fmt_ms(best(1))
        else
            text = text//" hbm not reached"
        end if
        if (arg(2) > 0) then
            text = text//", euler "//itoa(s%rows(arg(2))%parameter)//" steps "//fmt_ms(best(2))
        else
            text = text//", euler not reached"
        end if
        if (all(arg > 0)) text = text//", euler/hbm = "//fmt_r(best(2)/best(1))
        write (output_unit, '(a)') text
    end subroutine cheapest

    function fmt_ms(seconds) result(s)
        real(dp), intent(in) :: seconds
        character(len=:), allocatable :: s
        character(len=32) :: b
        write (b, '(f0.3,a)') 1.0e3_dp*seconds, " ms"
        s = trim(b)
    end function fmt_ms

    function fmt_e(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: b
        write (b, '(es8.1)') x
        s = trim(adjustl(b))
    end function fmt_e

    function fmt_r(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: b
        write (b, '(f0.1)') x
        s = trim(b)
    end function fmt_r

    function itoa(i) result(s)
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=16) :: b
        write (b, '(i0)') i
        s = trim(b)
    end function itoa
end program bench_study
