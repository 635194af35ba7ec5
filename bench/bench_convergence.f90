!> Convergence table of the weighted residual (issue 24; a program that prints figures, not a
!> test): every case file given, solved by solve_periodic at every harmonic count H from
!> --hmin to --hmax in steps of --hstep (default 10 .. 150 by 5), from a cold start with the
!> case's &hbm options (samples raised to 2 H + 1 where the case's are too few). One row per
!> case: a character per H
!>     .  converged, no check of the answer distrusts it
!>     w  converged, a warning (the check's key in the list below)
!>     u  converged, untrusted by a check (energy balance, Coulomb law, truncation, ...)
!>     F  not converged
!>     R  refused with a diagnosis (an impact on a rigid contact: not_converged with 'impact')
!>     E  an error (stat and message in the list below)
!> then the converged count and the CPU seconds of the row; then every F, u, R and E with
!> its residual against the target (or the message). The (case, H) pairs are shared among
!> the OpenMP threads (--threads, default 2); each solve is single-threaded, its CPU time
!> taken on its own thread.
!> Run from the project root:
!>     fpm run --example bench_convergence --profile release -- bench/convergence/*.nml
program bench_convergence
    use, intrinsic :: iso_fortran_env, only: output_unit
    !$ use omp_lib, only: omp_set_num_threads
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_case, only: case_t, read_case
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_diagnostics, only: level_warning, level_untrusted
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    type(case_t), allocatable :: cases(:)
    character(len=256), allocatable :: files(:)
    character(len=256) :: arg, value
    character(len=1), allocatable :: mark(:, :)
    character(len=300), allocatable :: detail(:, :)
    real(dp), allocatable :: cpu(:, :)
    integer, allocatable :: hs(:)
    type(error_type), allocatable :: error
    integer :: hmin, hmax, hstep, nthreads, i, j, k, nh, ncase, nconv, nall
    character(len=:), allocatable :: name

    call limit_blas_threads()
    hmin = 10
    hmax = 150
    hstep = 5
    nthreads = 2
    allocate (files(0))
    i = 1
    do while (i <= command_argument_count())
        call get_command_argument(i, arg)
        call get_command_argument(i + 1, value)
        select case (arg)
        case ('--hmin')
            read (value, *) hmin
            i = i + 2
        case ('--hmax')
            read (value, *) hmax
            i = i + 2
        case ('--hstep')
            read (value, *) hstep
            i = i + 2
        case ('--threads')
            read (value, *) nthreads
            i = i + 2
        case default
            files = [files, arg]
            i = i + 1
        end select
    end do
    ncase = size(files)
    if (ncase == 0) then
        write (output_unit, '(a)') "usage: bench_convergence [--hmin H] [--hmax H] "// &
            "[--hstep dH] [--threads n] case.nml ..."
        stop 1
    end if
    hs = [(k, k=hmin, hmax, hstep)]
    nh = size(hs)
    allocate (cases(ncase), mark(nh, ncase), detail(nh, ncase), cpu(nh, ncase))
    do j = 1, ncase
        call read_case(trim(files(j)), cases(j), error)
        if (allocated(error)) then
            write (output_unit, '(a)') "error: "//error%message
            stop 1
        end if
    end do
    !$ call omp_set_num_threads(nthreads)

    !$omp parallel do schedule(dynamic) default(shared) private(i, j)
    do k = 1, nh*ncase
        j = (k - 1)/nh + 1
        i = k - (j - 1)*nh
        call one_solve(cases(j), hs(i), mark(i, j), detail(i, j), cpu(i, j))
    end do
    !$omp end parallel do

    write (output_unit, '(a,i0,a,i0,a,i0)') "H from ", hmin, " to ", hmax, " by ", hstep
    write (output_unit, '(a)') "| case | "//ruler()//" | converged | CPU [s] |"
    write (output_unit, '(a)') "|---|---|---|---|"
    nall = 0
    do j = 1, ncase
        name = case_name(files(j))
        nconv = count(mark(:, j) == '.' .or. mark(:, j) == 'w' .or. mark(:, j) == 'u')
        if (all(mark(:, j) == 'R')) nconv = -1
        nall = nall + max(nconv, 0)
        write (output_unit, '(a)', advance='no') "| "//name//" | `"
        do i = 1, nh
            write (output_unit, '(a)', advance='no') mark(i, j)
        end do
        if (nconv >= 0) then
            write (output_unit, '(a,i0,a,i0,a,f0.2,a)') "` | ", nconv, "/", nh, " | ", &
                sum(cpu(:, j)), " |"
        else
            write (output_unit, '(a,f0.2,a)') "` | refused | ", sum(cpu(:, j)), " |"
        end if
    end do
    write (output_unit, '(a,i0,a,i0)') "converged in all: ", nall, " of ", &
        nh*count([(.not. all(mark(:, j) == 'R'), j=1, ncase)])
    write (output_unit, '(a)') ""
    do j = 1, ncase
        do i = 1, nh
            if (mark(i, j) == '.' .and. len_trim(detail(i, j)) == 0) cycle
            write (output_unit, '(a,a,i0,a)') case_name(files(j)), " H = ", hs(i), &
                ": "//mark(i, j)//" "//trim(detail(i, j))
        end do
    end do

contains

    !> Solve `c` at `h` harmonics from a cold start; its mark, a detail and the CPU time.
    subroutine one_solve(c, h, m, text, seconds)
        type(case_t), intent(in) :: c
        integer, intent(in) :: h
        character(len=1), intent(out) :: m
        character(len=300), intent(out) :: text
        real(dp), intent(out) :: seconds
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: err
        real(dp) :: t0
        integer :: k
        character(len=60) :: buf
        opts = c%hbm
        opts%harmonics = h
        opts%samples = max(opts%samples, 2*h + 1)
        t0 = thread_cpu_seconds()
        call solve_periodic(c%model, opts, sol, err)
        seconds = thread_cpu_seconds() - t0
        text = ""
        if (allocated(err)) then
            m = 'E'
            text = err%message
            return
        end if
        if (.not. sol%converged) then
            m = 'F'
            if (index(sol%diagnosis, 'impact') > 0) m = 'R'
            write (buf, '(a,es9.2,a,es9.2,a)') "||F|| = ", sol%fnorm, " (target ", &
                sol%fscale*opts%tol, ")"
            text = trim(buf)//" "//sol%diagnosis
            return
        end if
        m = '.'
        if (sol%rescue /= 'none') text = "rescued by '"//trim(sol%rescue)//"'"
        if (.not. allocated(sol%diagnostics%items)) return
        if (sol%diagnostics%worst() >= level_untrusted) then
            m = 'u'
        else if (sol%diagnostics%worst() >= level_warning) then
            m = 'w'
        else
            return
        end if
        do k = 1, size(sol%diagnostics%items)
            if (sol%diagnostics%items(k)%level >= level_warning) &
                text = trim(text)//" "//sol%diagnostics%items(k)%key
        end do
    end subroutine one_solve

    !> A header: the tens of each H, one character per H.
    function ruler() result(s)
        character(len=:), allocatable :: s
        character(len=8) :: buf
        integer :: i
        s = "H "
        do i = 1, nh, 4
            write (buf, '(i0)') hs(i)
            s = s//trim(buf)//repeat(' ', max(0, 4 - len_trim(buf)))
        end do
    end function ruler

    !> The file name without folder and extension.
    function case_name(path) result(s)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: s
        integer :: a, b
        a = index(path, '/', back=.true.) + 1
        b = index(path, '.nml', back=.true.) - 1
        if (b < a) b = len_trim(path)
        s = path(a:b)
    end function case_name
end program bench_convergence
