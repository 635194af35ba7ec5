!> The library called from several OpenMP threads at once: every thread must get the serial
!> answer (the solver's callback slot is threadprivate, the FFTW planner is serialized).
!> The concurrent solve is meaningful only when the tests and the library are built with OpenMP
!> (the default, fpm.toml's openmp metapackage); in a serial build the suite
!> says so on stdout and checks only that stickslip_thread_safe() reports a serial build.
module test_openmp
    use, intrinsic :: iso_fortran_env, only: output_unit
    use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
    !$ use omp_lib, only: omp_get_thread_num, omp_get_max_threads, omp_set_num_threads
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_version_info, only: stickslip_thread_safe
    use stickslip_blas_threads, only: blas_thread_safe, blas_library, parallel_threads, &
        advised_core
    use stickslip_lapack, only: dgetrf, dgetrs
    use stickslip_euler, only: euler_options_t
    use stickslip_reference_start, only: reference_start_options_t
    use stickslip_robustness, only: robustness_options_t, robustness_row_t, run_robustness
    use stickslip_study, only: study_options_t, study_result_t, run_study
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep
    use stickslip_reference, only: reference_options_t
    use stickslip_cli, only: string_t, run_cli
    use stickslip_files, only: make_directory
    use testing, only: test_counter_t, check, check_close, check_error
    use fixtures, only: seed_model, scratch, write_lines, enter_project_root
    implicit none
    private
    public :: run_openmp_tests

contains

    subroutine run_openmp_tests(t)
        type(test_counter_t), intent(inout) :: t
        logical :: openmp
        openmp = .false.
        !$ openmp = .true.
        call check(t, stickslip_thread_safe() .eqv. openmp, &
                   "openmp: stickslip_thread_safe() tells the build (tests and library built alike)")
        ! the studies and multi-case runs on 1 and 2 threads (also meaningful serially: the
        ! rows must not depend on the task order)
        call test_robustness_threads(t)
        call test_study_threads(t)
        call test_sweep_stability_threads(t)
        call test_multi_case(t)
        call test_advised_core(t)
        if (.not. openmp) then
            write (output_unit, '(a)') "openmp: built without -fopenmp, the concurrent solve " // &
                "is not tested (the default build, with OpenMP, tests it)"
            return
        end if
        call test_concurrent_solves(t)
        call test_concurrent_lapack(t)
    end subroutine run_openmp_tests

    !> The OpenBLAS kernels advised for a CPU from its /proc/cpuinfo flags, only when OpenBLAS
    !> fell back to its generic Prescott ones: AVX-512 SkylakeX, AVX2 + FMA Haswell, whole
    !> flags only (not a prefix of a longer one).
    subroutine test_advised_core(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: avx512 = 'fpu sse2 avx avx2 fma avx512f avx512dq '// &
            'avx512cd avx512bw avx512vl avx512_bf16'
        call check(t, advised_core('Prescott', avx512) == 'SkylakeX', &
                   "blas core: an AVX-512 CPU on generic kernels gets SkylakeX")
        call check(t, advised_core('Prescott', 'fpu sse2 avx avx2 fma bmi2') == 'Haswell', &
                   "blas core: an AVX2 + FMA CPU on generic kernels gets Haswell")
        call check(t, advised_core('Prescott', 'fpu sse2 avx avx512f avx512vl') == '', &
                   "blas core: no advice without AVX2 and FMA")
        call check(t, advised_core('Prescott', 'fpu avx2_x fmax avx512fx') == '', &
                   "blas core: flags are matched whole")
        call check(t, advised_core('Haswell', avx512) == '' .and. &
                   advised_core('SkylakeX', avx512) == '', &
                   "blas core: no advice when OpenBLAS recognised the CPU")
    end subroutine test_advised_core

    !> The linked BLAS/LAPACK from 2 threads at once: 3000 LU solves of one 60 x 60 system
    !> must all equal the serial solve bitwise whenever blas_thread_safe() says the BLAS is
    !> safe (OpenBLAS's serial build, which is not, gave 56-102 wrong solves in 4000), and
    !> parallel_threads() must then allow the threads; with an unsafe BLAS it must be 1.
    subroutine test_concurrent_lapack(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 60, nrep = 3000
        real(dp) :: a0(n, n), b0(n), xref(n)
        integer :: i, k, bad, saved
        do k = 1, n
            a0(:, k) = [(sin(real(7*k + 3*i, dp)), i=1, n)]
            a0(k, k) = a0(k, k) + real(n, dp)
        end do
        b0 = [(cos(real(k, dp)), k=1, n)]
        call lu_solve(a0, b0, xref)
        saved = max_threads()
        call set_threads(2)
        bad = 0
        !$omp parallel do schedule(static) reduction(+:bad) num_threads(2)
        do k = 1, nrep
            block
                real(dp) :: x(n)
                call lu_solve(a0, b0, x)
                if (any(x /= xref)) bad = bad + 1
            end block
        end do
        !$omp end parallel do
        if (blas_thread_safe()) then
            call check(t, bad == 0, "openmp: concurrent LU solves of the linked BLAS equal "// &
                       "the serial one ("//blas_library()//")")
            call check(t, parallel_threads() == 2, "openmp: a thread-safe BLAS lets the "// &
                       "studies use OMP_NUM_THREADS threads")
        else
            write (output_unit, '(a,i0,a,i0,a)') "openmp: the linked BLAS is not thread-safe ("// &
                blas_library()//"): ", bad, " of ", nrep, " concurrent LU solves differed"
            call check(t, parallel_threads() == 1, "openmp: an unsafe BLAS keeps the studies "// &
                       "on one thread")
        end if
        call set_threads(saved)
    contains
        subroutine lu_solve(a0, b0, x)
            real(dp), intent(in) :: a0(:, :), b0(:)
            real(dp), intent(out) :: x(:)
            real(dp) :: a(size(a0, 1), size(a0, 2))
            integer :: ipiv(size(a0, 1)), info
            a = a0
            x = b0
            call dgetrf(n, n, a, n, ipiv, info)
            call dgetrs('N', n, 1, a, n, ipiv, x, n, info)
        end subroutine lu_solve
    end subroutine test_concurrent_lapack

    !> The seed system at 24 forcing frequencies, solved serially and then by 4 threads at
    !> once (round-robin, so that every thread solves while the others do): the same
    !> amplitudes and evaluation counts.
    subroutine test_concurrent_solves(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: npoints = 24, nthreads = 4
        real(dp) :: serial(npoints), parallel(npoints)
        integer :: nfev_serial(npoints), nfev_parallel(npoints), thread(npoints), nerr
        integer :: i
        nerr = 0
        thread = 0
        call sweep(.false., serial, nfev_serial, thread, nerr)
        call sweep(.true., parallel, nfev_parallel, thread, nerr)
        call check(t, nerr == 0, "openmp: every solve converged without error")
        call check(t, count([(any(thread == i), i=0, nthreads - 1)]) >= 2, &
                   "openmp: the solves ran on several threads")
        call check_close(t, parallel, serial, "openmp: each thread gets the serial amplitude", &
                         rtol=1.0e-13_dp)
        call check(t, all(nfev_parallel == nfev_serial), "openmp: same evaluation counts")
    end subroutine test_concurrent_solves

    subroutine sweep(in_parallel, amp, nfev, thread, nerr)
        logical, intent(in) :: in_parallel
        real(dp), intent(out) :: amp(:)
        integer, intent(out) :: nfev(:)
        integer, intent(inout) :: thread(:), nerr
        type(model_t) :: m, seed
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        type(error_type), allocatable :: error
        integer :: i
        seed = seed_model()
        o%harmonics = 10
        o%samples = 128
        o%rho = 0.2_dp
        !$omp parallel do if(in_parallel) num_threads(4) schedule(static, 1) &
        !$omp& private(m, s, error) firstprivate(o) reduction(+:nerr)
        do i = 1, size(amp)
            m = seed
            m%omega = 3.0_dp + 3.0_dp*real(i - 1, dp)/real(size(amp) - 1, dp)
            call solve_periodic(m, o, s, error)
            amp(i) = -1.0_dp
            nfev(i) = -1
            if (allocated(error)) then
                nerr = nerr + 1
            else
                if (.not. s%converged) nerr = nerr + 1
                amp(i) = maxval(abs(s%x(:, 2)))
                nfev(i) = s%nfev
            end if
            !$ if (in_parallel) thread(i) = omp_get_thread_num()
        end do
        !$omp end parallel do
    end subroutine sweep

    !> Set the number of OpenMP threads (nothing in a serial build).
    subroutine set_threads(n)
        integer, intent(in) :: n
        !$ call omp_set_num_threads(n)
        if (.false.) write (output_unit, *) n
    end subroutine set_threads

    !> Threads of the next parallel region (1 in a serial build).
    integer function max_threads()
        max_threads = 1
        !$ max_threads = omp_get_max_threads()
    end function max_threads

    !> A small robustness grid (3 omegas x 2 mus, H = 5 and 10, rho = 0.2 and automatic,
    !> warm starts, Euler at 200 steps) on 1 and on 2 threads: every row the same, in the same
    !> order (cpu_seconds aside), bitwise: every row is computed from the same inputs by the
    !> same code on any thread. (With OpenBLAS's serial build, not safe from several threads,
    !> rows differed now and then; the studies now run it on one thread.) The
    !> contacts slip at every point: a contact stuck all period leaves its mean force
    !> undetermined, and there roundoff may pick a visibly different admissible solution.
    subroutine test_robustness_threads(t)
        type(test_counter_t), intent(inout) :: t
        type(robustness_options_t) :: r
        type(robustness_row_t), allocatable :: one(:), two(:)
        type(error_type), allocatable :: error
        type(hbm_options_t) :: ho
        type(euler_options_t) :: eo
        type(reference_start_options_t) :: ro
        integer :: k, saved
        logical :: same
        r%omegas = [3.0_dp, 4.0_dp, 4.5_dp]
        r%mus = [0.2_dp, 0.45_dp]
        r%harmonics = [5, 10]
        r%rhos = [0.2_dp, 0.0_dp]
        r%samples = [64]
        r%steps_per_period = [200]
        r%error_samples = 256
        eo%max_periods = 100
        saved = max_threads()
        call set_threads(1)
        call run_robustness(seed_model(), ho, eo, ro, r, one, error)
        call check_error(t, error, "openmp: robustness on 1 thread", .false.)
        if (allocated(error)) return
        call set_threads(2)
        call run_robustness(seed_model(), ho, eo, ro, r, two, error)
        call set_threads(saved)
        call check_error(t, error, "openmp: robustness on 2 threads", .false.)
        if (allocated(error)) return
        same = size(one) == size(two) .and. size(one) == 2*3*(1 + 2*2*2)
        if (same) then
            do k = 1, size(one)
                same = same .and. one(k)%method == two(k)%method .and. &
                       one(k)%omega == two(k)%omega .and. one(k)%mu == two(k)%mu .and. &
                       one(k)%harmonics == two(k)%harmonics .and. &
                       one(k)%samples == two(k)%samples .and. &
                       (one(k)%converged .eqv. two(k)%converged) .and. &
                       (one(k)%success .eqv. two(k)%success) .and. &
                       one(k)%iterations == two(k)%iterations .and. &
                       same_real(one(k)%rho, two(k)%rho) .and. &
                       same_real(one(k)%err_amplitude, two(k)%err_amplitude)
                if (.not. same) then
                    write (output_unit, '(a,i0,1x,a,1x,a,2es24.16,2i6,1x,a,1x,a)') "openmp: row ", k, &
                        one(k)%method, two(k)%method, one(k)%err_amplitude, two(k)%err_amplitude, &
                        one(k)%iterations, two(k)%iterations, one(k)%diagnosis, two(k)%diagnosis
                    exit
                end if
            end do
        end if
        call check(t, same, "openmp: robustness rows on 2 threads = on 1 thread (bitwise)")
        call check(t, count(one%converged) > size(one)/2 .and. all(one%cpu_seconds >= 0.0_dp) &
                   .and. all(two%cpu_seconds >= 0.0_dp), &
                   "openmp: robustness grid mostly converged, CPU times >= 0")
    end subroutine test_robustness_threads

    !> A sweep with stability on 1 thread (point by point, the cache of contact modes carried
    !> along the curve) and on 2 (the stability beside the curve, chunks of points on the
    !> other thread, the tracing thread backwards at the end): the same points, the same
    !> verdicts and multipliers to 1e-9.
    subroutine test_sweep_stability_threads(t)
        type(test_counter_t), intent(inout) :: t
        type(sweep_options_t) :: so
        type(sweep_result_t) :: one, two
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(error_type), allocatable :: error
        type(model_t) :: m
        integer :: k, saved, known
        logical :: same
        real(dp) :: worst
        m = seed_model()
        m%damping = 0.02_dp*m%stiffness
        ho%harmonics = 15
        ho%samples = 64
        ho%rho = 0.2_dp
        so%parameter = 'omega'
        so%start = 4.0_dp
        so%stop = 5.0_dp
        so%step = 0.1_dp
        so%max_step = 0.1_dp
        so%stability = .true.
        saved = max_threads()
        call set_threads(1)
        call run_sweep(m, ho, ro, so, one, error)
        call check_error(t, error, "openmp: sweep with stability on 1 thread", .false.)
        if (allocated(error)) then
            call set_threads(saved)
            return
        end if
        call set_threads(2)
        call run_sweep(m, ho, ro, so, two, error)
        call set_threads(saved)
        call check_error(t, error, "openmp: sweep with stability on 2 threads", .false.)
        if (allocated(error)) return
        same = one%npoints == two%npoints .and. one%npoints > 5
        worst = 0.0_dp
        known = 0
        if (same) then
            do k = 1, one%npoints
                same = same .and. one%points(k)%parameter == two%points(k)%parameter .and. &
                       one%points(k)%stable == two%points(k)%stable
                if (same .and. one%points(k)%stable /= -1) worst = max(worst, &
                    abs(one%points(k)%floquet_max - two%points(k)%floquet_max))
            end do
            known = 0
            do k = 1, one%npoints
                if (one%points(k)%stable /= -1) known = known + 1
            end do
        end if
        call check(t, same .and. worst <= 1.0e-9_dp .and. known > one%npoints/2, &
                   "openmp: sweep stability on 2 threads = on 1 thread (same points and "// &
                   "verdicts, multipliers to 1e-9)")
    end subroutine test_sweep_stability_threads

    !> The work-precision study (H = 2, 3, 5, 10, Euler at 100 and 200 steps) on 1 and on
    !> 2 threads: the same rows, bitwise (see test_robustness_threads).
    subroutine test_study_threads(t)
        type(test_counter_t), intent(inout) :: t
        type(study_options_t) :: so
        type(study_result_t) :: one, two
        type(error_type), allocatable :: error
        type(hbm_options_t) :: ho
        type(euler_options_t) :: eo
        type(reference_start_options_t) :: ro
        integer :: k, saved
        logical :: same
        so%harmonics = [2, 3, 5, 10]
        so%samples = [0]
        so%steps_per_period = [100, 200]
        so%error_samples = 512
        so%repeats = 1
        ho%rho = 0.2_dp
        eo%max_periods = 100
        saved = max_threads()
        call set_threads(1)
        call run_study(seed_model(), ho, eo, ro, so, one, error)
        call check_error(t, error, "openmp: study on 1 thread", .false.)
        if (allocated(error)) return
        call set_threads(2)
        call run_study(seed_model(), ho, eo, ro, so, two, error)
        call set_threads(saved)
        call check_error(t, error, "openmp: study on 2 threads", .false.)
        if (allocated(error)) return
        same = size(one%rows) == size(two%rows) .and. size(one%rows) == 6 .and. &
               one%skipped == two%skipped
        if (same) then
            do k = 1, size(one%rows)
                associate (a => one%rows(k), b => two%rows(k))
                    same = same .and. a%method == b%method .and. a%parameter == b%parameter &
                           .and. a%samples == b%samples .and. a%iterations == b%iterations &
                           .and. (a%converged .eqv. b%converged) .and. &
                           allocated(a%cmp%max_error) .and. allocated(b%cmp%max_error)
                    if (same) same = all(same_real(a%cmp%max_error, b%cmp%max_error)) .and. &
                                     all(same_real(a%cmp%rms_error, b%cmp%rms_error))
                end associate
            end do
        end if
        call check(t, same, "openmp: study rows on 2 threads = on 1 thread (bitwise)")
        call check(t, all(one%rows(1:4)%method == 'hbm') .and. &
                   all(one%rows(5:6)%method == 'euler') .and. &
                   all(one%rows%parameter == [2, 3, 5, 10, 100, 200]), &
                   "openmp: study rows in the serial order")
    end subroutine test_study_threads

    !> `stickslip a.nml bad.nml b.nml` on 2 threads: each good case writes its own
    !> directory, the output comes case by case in argument order, whole lines, and the exit
    !> code is the worst (1: bad.nml).
    subroutine test_multi_case(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: a = scratch//"/multi_a.nml", b = scratch//"/multi_b.nml", &
            bad = scratch//"/multi_bad.nml"
        type(string_t), allocatable :: args(:)
        character(len=:), allocatable :: out, err
        type(error_type), allocatable :: error
        integer :: code, saved, wanted, uo, ue, ka, kb
        call enter_project_root()
        call make_directory(scratch, error)
        call check_error(t, error, "openmp: scratch directory", .false.)
        if (allocated(error)) return
        call write_lines(a, [character(len=100) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 4.5, force_dof = 1, force_amplitude = 10.0 /", &
            "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /", &
            "&hbm harmonics = 10, samples = 64, rho = 0.2 /", &
            "&output directory = '"//scratch//"/multi_out_a' /"])
        call write_lines(b, [character(len=100) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /", &
            "&forcing omega = 3.0, force_dof = 1, force_amplitude = 10.0 /", &
            "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /", &
            "&hbm harmonics = 10, samples = 64, rho = 0.2 /", &
            "&output directory = '"//scratch//"/multi_out_b' /"])
        call write_lines(bad, [character(len=100) :: "&system ndof = -1 /"])
        allocate (args(3))
        args(1)%s = a
        args(2)%s = bad
        args(3)%s = b
        saved = max_threads()
        call set_threads(2)
        wanted = max_threads()
        open (newunit=uo, status='scratch')
        open (newunit=ue, status='scratch')
        code = run_cli(args, uo, ue)
        call set_threads(saved)
        out = slurp(uo)
        err = slurp(ue)
        close (uo)
        close (ue)
        ! an unsafe BLAS: one note first, that the cases run on one thread
        if (.not. blas_thread_safe() .and. wanted > 1) then
            call check(t, index(err, "stickslip: note: running on 1 thread") == 1, &
                       "openmp: multi-case with an unsafe BLAS says it runs on 1 thread", err)
            err = err(index(err, new_line('a')) + 1:)
        end if
        call check(t, code == 1, "openmp: multi-case exit code is the worst (1)")
        ka = index(out, "== "//a//new_line('a')//"stickslip ")
        kb = index(out, "== "//b//new_line('a')//"stickslip ")
        call check(t, ka == 1 .and. kb > ka .and. index(out, "== "//bad) > ka .and. &
                   index(out, "== "//bad) < kb, "openmp: multi-case summaries in case order", out)
        call check(t, index(err, new_line('a')//bad//": stickslip: error: "//bad// &
                   ": &system") > 0 .and. index(err, a//": stickslip: warning: ") == 1 .and. &
                   index(err, a//": ") < index(err, bad//": "), &
                   "openmp: multi-case stderr lines prefixed by their case, in case order", err)
        call check(t, summary_exists(scratch//"/multi_out_a") .and. &
                   summary_exists(scratch//"/multi_out_b"), &
                   "openmp: multi-case: each case wrote its own directory")
    end subroutine test_multi_case

    logical function summary_exists(dir)
        character(len=*), intent(in) :: dir
        inquire (file=dir//"/summary.nml", exist=summary_exists)
    end function summary_exists

    !> Every line of a scratch unit, new_line after each.
    function slurp(u) result(text)
        integer, intent(in) :: u
        character(len=:), allocatable :: text
        character(len=1024) :: chunk
        integer :: stat, n
        text = ""
        rewind (u)
        do
            read (u, '(a)', advance='no', iostat=stat, size=n) chunk
            if (is_iostat_end(stat)) exit
            text = text//chunk(1:n)
            if (is_iostat_eor(stat)) text = text//new_line('a')
            if (stat > 0) exit
        end do
    end function slurp

    !> Equal, or both NaN.
    elemental logical function same_real(x, y)
        real(dp), intent(in) :: x, y
        same_real = x == y .or. (ieee_is_nan(x) .and. ieee_is_nan(y))
    end function same_real
end module test_openmp
