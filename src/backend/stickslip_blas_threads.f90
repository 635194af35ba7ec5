!> Which BLAS/LAPACK the process linked, whether it may be called from several threads at
!> once, and how many threads stickslip's own parallel loops may use with it.
!>
!> stickslip links `-llapack -lblas`, whatever library the system provides under those names
!> (Debian's alternatives: reference LAPACK or a variant of OpenBLAS; MKL; a vendor's). The
!> library is asked at run time through the dynamic linker (`dlsym`, looking up OpenBLAS's own
!> entry points; nothing is linked that another BLAS lacks):
!> - OpenBLAS's serial build (Debian `libopenblas0-serial`, `openblas_get_parallel() == 0`) is
!>   compiled without locking: two threads calling LU or matrix products at once may share one
!>   work buffer and get wrong answers (measured: 56-102 of 4000 concurrent 60 x 60 `dgetrf` +
!>   `dgetrs` differed from the serial result on 2 threads, none with the pthreads build or
!>   the reference LAPACK). With it, every parallel loop of stickslip runs on one thread.
!> - OpenBLAS's pthreads build (Debian `libopenblas0-pthread`, what setup.sh installs) is
!>   thread-safe; it would itself start threads for every call, so `limit_blas_threads` sets
!>   it to one thread unless the environment sets OPENBLAS_NUM_THREADS, and stops the worker
!>   threads it started when loaded (they spin in sched_yield for a while otherwise: 0.09 s
!>   of system time in a 0.2 s run).
!> - OpenBLAS's OpenMP build runs single-threaded inside OpenMP parallel regions; safe.
!> - Any other BLAS (reference, MKL, ...) is taken as thread-safe.
!> OpenBLAS chooses its kernels for the CPU when it is loaded, and falls back to its generic
!> 'Prescott' (SSE3) kernels for a CPU it does not know: Debian 12's 0.3.21 on Intel
!> Sapphire/Emerald Rapids, where dgemm then runs 3-4 times slower than with the AVX-512
!> kernels. `blas_core_advice` tells the value of OPENBLAS_CORETYPE that fixes it (the stickslip
!> program restarts itself with it, app/stickslip_blas_restart.f90).
!> No state is kept: every function asks the dynamic linker again (a few microseconds).
module stickslip_blas_threads
    use, intrinsic :: iso_c_binding, only: c_ptr, c_funptr, c_null_ptr, c_null_char, c_char, &
        c_int, c_associated, c_f_procpointer, c_f_pointer
    !$ use omp_lib, only: omp_get_max_threads, omp_in_parallel
    implicit none
    private
    public :: blas_library, blas_thread_safe, limit_blas_threads, parallel_threads
    public :: blas_core_advice, advised_core

    interface
        !> glibc's symbol lookup (in libc itself since glibc 2.34).
        function c_dlsym(handle, name) bind(c, name='dlsym')
            import :: c_ptr, c_funptr, c_char
            type(c_ptr), value :: handle
            character(kind=c_char), intent(in) :: name(*)
            type(c_funptr) :: c_dlsym
        end function c_dlsym

        function c_strlen(s) bind(c, name='strlen')
            import :: c_ptr, c_int
            type(c_ptr), value :: s
            integer(c_int) :: c_strlen
        end function c_strlen
    end interface

    abstract interface
        !> int openblas_get_parallel(void), int blas_thread_shutdown_(void)
        function int_getter() bind(c)
            import :: c_int
            integer(c_int) :: int_getter
        end function int_getter
        !> char *openblas_get_config(void)
        function string_getter() bind(c)
            import :: c_ptr
            type(c_ptr) :: string_getter
        end function string_getter
        !> void openblas_set_num_threads(int)
        subroutine int_setter(n) bind(c)
            import :: c_int
            integer(c_int), value :: n
        end subroutine int_setter
    end interface

    !> openblas_get_parallel(): not OpenBLAS, serial, pthreads, OpenMP.
    integer, parameter :: not_openblas = -1, openblas_serial = 0, openblas_pthreads = 1, &
        openblas_openmp = 2

contains

    !> A one-line description of the BLAS the process linked: OpenBLAS's configuration string
    !> and its threading ("OpenBLAS 0.3.21 ... SkylakeX MAX_THREADS=64 (pthreads build)"), or
    !> "not OpenBLAS (reference, MKL or another)". No errors.
    function blas_library() result(text)
        character(len=:), allocatable :: text
        logical :: found
        call openblas_string("openblas_get_config", found, text)
        if (.not. found) then
            text = "not OpenBLAS (reference, MKL or another)"
            return
        end if
        if (len(text) == 0) text = "OpenBLAS"
        select case (openblas_threading())
        case (openblas_serial)
            text = text//" (serial build)"
        case (openblas_pthreads)
            text = text//" (pthreads build)"
        case (openblas_openmp)
            text = text//" (OpenMP build)"
        end select
    end function blas_library

    !> False when the linked BLAS is known to give wrong answers if called from several threads
    !> at once (OpenBLAS's serial build, compiled without locking, as Debian ships it); true
    !> otherwise. No errors.
    logical function blas_thread_safe()
        blas_thread_safe = openblas_threading() /= openblas_serial
    end function blas_thread_safe

    !> If the linked BLAS is OpenBLAS's pthreads build and the environment does not set
    !> OPENBLAS_NUM_THREADS, make its calls single-threaded (openblas_set_num_threads(1)):
    !> stickslip's matrices are small and its parallelism is its own (OpenMP over cases, study
    !> points), so BLAS threads only oversubscribe the cores. Process-wide; call it once before
    !> any parallel work (the stickslip program and the test driver do). Nothing for any other
    !> BLAS. No errors.
    subroutine limit_blas_threads()
        procedure(int_setter), pointer :: set_threads
        procedure(int_getter), pointer :: shutdown
        type(c_funptr) :: f
        integer :: length, stat
        if (openblas_threading() /= openblas_pthreads) return
        call get_environment_variable("OPENBLAS_NUM_THREADS", length=length, status=stat)
        if (stat == 0 .and. length > 0) return
        f = c_dlsym(c_null_ptr, "openblas_set_num_threads"//c_null_char)
        if (.not. c_associated(f)) return
        call c_f_procpointer(f, set_threads)
        call set_threads(1_c_int)
        ! the worker threads started when the library was loaded would otherwise spin
        ! (sched_yield) for a while with nothing to do: stop them (OpenBLAS starts them again
        ! if a call ever asks for threads)
        f = c_dlsym(c_null_ptr, "blas_thread_shutdown_"//c_null_char)
        if (.not. c_associated(f)) return
        call c_f_procpointer(f, shutdown)
        stat = int(shutdown())
    end subroutine limit_blas_threads

    !> Threads a parallel loop of stickslip may use: the OpenMP maximum
    !> (OMP_NUM_THREADS), or 1 when the linked BLAS is not thread-safe (see
    !> blas_thread_safe), the library is built without OpenMP or the caller is already in a
    !> parallel region (a nested one would get one thread). No errors.
    integer function parallel_threads()
        parallel_threads = 1
        !$ parallel_threads = omp_get_max_threads()
        ! inside a parallel region (the curves of a family) a nested one gets one thread
        !$ if (omp_in_parallel()) parallel_threads = 1
        if (parallel_threads > 1) then
            if (.not. blas_thread_safe()) parallel_threads = 1
        end if
    end function parallel_threads

    !> The value of OPENBLAS_CORETYPE that gives this CPU the OpenBLAS kernels it can run when
    !> the linked OpenBLAS did not recognise it and runs its generic 'Prescott' kernels:
    !> 'SkylakeX' (AVX-512), 'Haswell' (AVX2 and FMA). '' when there is nothing to fix: not
    !> OpenBLAS, OPENBLAS_CORETYPE already set, OpenBLAS found a core of its own, or the CPU's
    !> flags (/proc/cpuinfo) are unreadable or lack AVX2. OpenBLAS reads the variable only when
    !> it is loaded: acting on the advice takes a new process. No errors.
    function blas_core_advice() result(core)
        character(len=:), allocatable :: core
        character(len=:), allocatable :: detected
        integer :: length, stat
        logical :: found
        core = ''
        call get_environment_variable("OPENBLAS_CORETYPE", length=length, status=stat)
        if (stat /= 1) return
        call openblas_string("openblas_get_corename", found, detected)
        if (.not. found) return
        if (detected /= 'Prescott') return
        core = advised_core(detected, cpu_flags())
    end function blas_core_advice

    !> The OpenBLAS core for a CPU with the feature flags `flags` (as /proc/cpuinfo lists them,
    !> separated by blanks) when OpenBLAS detected the core `detected`: 'SkylakeX' when it
    !> detected its generic 'Prescott' and the CPU has avx512f, avx512cd, avx512bw, avx512dq
    !> and avx512vl; 'Haswell' when it has avx2 and fma; '' otherwise. No errors.
    pure function advised_core(detected, flags) result(core)
        !> OpenBLAS's core name (openblas_get_corename).
        character(len=*), intent(in) :: detected
        !> The CPU's feature flags, blank-separated.
        character(len=*), intent(in) :: flags
        character(len=:), allocatable :: core
        core = ''
        if (detected /= 'Prescott') return
        if (has('avx512f') .and. has('avx512cd') .and. has('avx512bw') .and. &
            has('avx512dq') .and. has('avx512vl')) then
            core = 'SkylakeX'
        else if (has('avx2') .and. has('fma')) then
            core = 'Haswell'
        end if
    contains
        pure logical function has(flag)
            character(len=*), intent(in) :: flag
            has = index(' '//flags//' ', ' '//flag//' ') > 0
        end function has
    end function advised_core

    !> The first 'flags' line of /proc/cpuinfo, after its colon (tabs as blanks); '' when the
    !> file cannot be read.
    function cpu_flags() result(flags)
        character(len=:), allocatable :: flags
        character(len=16384) :: line
        integer :: unit, ios, colon, i
        flags = ''
        open (newunit=unit, file='/proc/cpuinfo', status='old', action='read', iostat=ios)
        if (ios /= 0) return
        do
            read (unit, '(a)', iostat=ios) line
            if (ios /= 0) exit
            do i = 1, len_trim(line)
                if (line(i:i) == achar(9)) line(i:i) = ' '
            end do
            if (line(1:5) /= 'flags') cycle
            colon = index(line, ':')
            if (colon < 6) cycle
            if (colon > 6) then
                if (line(6:colon - 1) /= '') cycle
            end if
            flags = trim(line(colon + 1:))
            exit
        end do
        close (unit)
    end function cpu_flags

    !> The C string that OpenBLAS's `char *symbol(void)` returns (openblas_get_config,
    !> openblas_get_corename): found false when the process has no such symbol (not
    !> OpenBLAS), text '' when it returned NULL.
    subroutine openblas_string(symbol, found, text)
        character(len=*), intent(in) :: symbol
        logical, intent(out) :: found
        character(len=:), allocatable, intent(out) :: text
        procedure(string_getter), pointer :: getter
        type(c_funptr) :: f
        type(c_ptr) :: s
        character(kind=c_char), pointer :: chars(:)
        integer :: n, i
        text = ''
        f = c_dlsym(c_null_ptr, symbol//c_null_char)
        found = c_associated(f)
        if (.not. found) return
        call c_f_procpointer(f, getter)
        s = getter()
        if (.not. c_associated(s)) return
        n = c_strlen(s)
        call c_f_pointer(s, chars, [n])
        text = repeat(' ', n)
        do i = 1, n
            text(i:i) = chars(i)
        end do
    end subroutine openblas_string

    !> openblas_get_parallel() of the linked OpenBLAS, or not_openblas.
    integer function openblas_threading()
        procedure(int_getter), pointer :: get_parallel
        type(c_funptr) :: f
        openblas_threading = not_openblas
        f = c_dlsym(c_null_ptr, "openblas_get_parallel"//c_null_char)
        if (.not. c_associated(f)) return
        call c_f_procpointer(f, get_parallel)
        openblas_threading = int(get_parallel())
    end function openblas_threading
end module stickslip_blas_threads
