!> Benchmark of the nonlinear solve of the weighted residual at hundreds of unknowns (a
!> program that prints figures, not a test): every case solved by MINPACK's hybrj
!> (&hbm solver = 'hybrj', the cold start of start = 'auto') and by the Newton path
!> (solver = 'newton': semismooth Newton with LU from the halving ladder H/2^k, hybrj for
!> the cold lowest stage and as the fallback) in the same run; medians over repeats and
!> the ratio hybrj / newton. Cases: the seed case (examples/seed.nml's model, rho = 0.2 as
!> in bench_hbm) at H = 10 .. 256 (all harmonics; the small ones place the crossover used
!> by solver = 'auto'), a chain of 20 masses with a ground contact on each at H = 15
!> (620 unknowns). Then one factorization of a random dense matrix by the LAPACK kernels
!> the candidates use (dgetrf; dgeqrf + dorgqr for a Powell hybrid on blocked QR).
!> Run from the project root: fpm run --example bench_solver --profile release
!> [-- --quick] (--quick: fewer repeats, skips H = 256 with hybrj; --profile-newton: only the
!> Newton path on the chain at H = 15, 20 times, for perf).
program bench_solver
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, newton_min_unknowns
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: median
    use stickslip_lapack, only: dgetrf, dgeqrf, dorgqr
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    integer, parameter :: seed_h(8) = [10, 20, 35, 50, 75, 100, 200, 256]
    type(case_t) :: c
    type(model_t) :: chain
    type(error_type), allocatable :: error
    integer :: i
    character(len=32) :: arg
    logical :: quick, profile

    call limit_blas_threads()
    quick = .false.
    profile = .false.
    do i = 1, command_argument_count()
        call get_command_argument(i, arg)
        if (arg == '--quick') quick = .true.
        if (arg == '--profile-newton') profile = .true.
    end do
    call read_case("examples/seed.nml", c, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    chain = contact_chain(20, 0.3_dp)
    if (profile) then
        call profile_newton(chain)
        stop
    end if

    write (output_unit, '(a,i0)') "solver = 'auto' takes Newton from unknowns >= ", &
        newton_min_unknowns
    write (output_unit, '(a)') "| case | H | unknowns | hybrj [ms] | newton [ms] | ratio | "// &
        "hybrj njev | newton LUs (calls, fallbacks) | max |dr| / mu N |"
    write (output_unit, '(a)') "|---|---|---|---|---|---|---|---|---|"
    do i = 1, size(seed_h)
        if (quick .and. seed_h(i) > 200) cycle
        call compare("seed", c%model, seed_h(i), 0.2_dp)
    end do
    call compare("chain, 20 contacts", chain, 15, 0.0_dp)
    call compare("chain, 20 contacts", chain, 7, 0.0_dp)

    write (output_unit, '(a)') ""
    write (output_unit, '(a)') "one factorization of a dense n x n matrix (median over repeats)"
    write (output_unit, '(a)') "| n | dgetrf [ms] | dgeqrf + dorgqr [ms] | ratio |"
    write (output_unit, '(a)') "|---|---|---|---|"
    call kernels(201)
    call kernels(401)
    call kernels(620)

contains

    !> Solve `m` at `h` harmonics with both solvers; print medians and their ratio.
    subroutine compare(name, m, h, rho)
        character(len=*), intent(in) :: name
        type(model_t), intent(in) :: m
        integer, intent(in) :: h
        real(dp), intent(in) :: rho
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sh, sn
        real(dp) :: th, tn, dr
        o%harmonics = h
        o%samples = max(1024, 4*h)
        o%rho = rho
        o%want_samples = .false.
        o%solver = 'hybrj'
        th = timed(m, o, sh)
        o%solver = 'newton'
        tn = timed(m, o, sn)
        dr = maxval(abs(sn%rcoef - sh%rcoef))/maxval(m%mu*m%normal_load)
        write (output_unit, '("| ",a," | ",i0," | ",i0," | ",f0.2," | ",f0.2," | ",f0.1, &
            &" | ",i0," | ",i0," (",i0,", ",i0,") | ",es8.1," |",a)') name, h, &
            sn%nb*size(m%mu), 1.0e3_dp*th, 1.0e3_dp*tn, th/tn, sh%njev, sn%njev, &
            sn%newton_calls, sn%newton_fallbacks, dr, note(sh%converged, sn%converged)
        flush (output_unit)
    end subroutine compare

    !> Only the Newton path on the 20-contact chain at H = 15, 20 times (for a profiler).
    subroutine profile_newton(m)
        type(model_t), intent(in) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        integer :: k
        o%harmonics = 15
        o%samples = 1024
        o%want_samples = .false.
        o%solver = 'newton'
        do k = 1, 20
            call solve_periodic(m, o, s, error)
            if (allocated(error)) stop 1
        end do
        write (output_unit, '(a,i0,a,l1)') "20 solves, ", s%njev, " Jacobians each, converged ", &
            s%converged
    end subroutine profile_newton

    !> What to add to a row when a solve did not converge.
    function note(hybrj_ok, newton_ok) result(text)
        logical, intent(in) :: hybrj_ok, newton_ok
        character(len=:), allocatable :: text
        text = ""
        if (.not. hybrj_ok) text = text//" NOT CONVERGED (hybrj)"
        if (.not. newton_ok) text = text//" NOT CONVERGED (newton)"
    end function note

    !> Median wall time [s] of solve_periodic over repeats (at least 3, about 2 s).
    real(dp) function timed(m, o, s) result(med)
        type(model_t), intent(in) :: m
        type(hbm_options_t), intent(in) :: o
        type(hbm_solution_t), intent(out) :: s
        real(dp) :: times(101)
        integer(int64) :: c0, c1, rate
        integer :: k, nrep
        real(dp) :: budget
        budget = merge(0.5_dp, 2.0_dp, quick)
        nrep = 0
        do k = 1, size(times)
            call system_clock(c0, rate)
            call solve_periodic(m, o, s, error)
            call system_clock(c1)
            if (allocated(error)) then
                write (output_unit, '(a)') "error: "//error%message
                stop 1
            end if
            nrep = k
            times(k) = real(c1 - c0, dp)/real(rate, dp)
            if (k >= 3 .and. sum(times(1:k)) > budget) exit
        end do
        med = median(times(1:nrep))
    end function timed

    !> Time one LU and one QR (with Q formed) of a random n x n matrix.
    subroutine kernels(n)
        integer, intent(in) :: n
        real(dp), allocatable :: a(:, :), w(:, :), tau(:), work(:)
        integer, allocatable :: ipiv(:)
        real(dp) :: tl(51), tq(51), q(1)
        integer(int64) :: c0, c1, rate
        integer :: k, info, lwork
        allocate (a(n, n), w(n, n), tau(n), ipiv(n))
        call random_number(a)
        call dgeqrf(n, n, w, n, tau, q, -1, info)
        lwork = int(q(1))
        call dorgqr(n, n, n, w, n, tau, q, -1, info)
        lwork = max(lwork, int(q(1)))
        allocate (work(lwork))
        do k = 1, size(tl)
            w = a
            call system_clock(c0, rate)
            call dgetrf(n, n, w, n, ipiv, info)
            call system_clock(c1)
            tl(k) = real(c1 - c0, dp)/real(rate, dp)
            w = a
            call system_clock(c0, rate)
            call dgeqrf(n, n, w, n, tau, work, lwork, info)
            call dorgqr(n, n, n, w, n, tau, work, lwork, info)
            call system_clock(c1)
            tq(k) = real(c1 - c0, dp)/real(rate, dp)
        end do
        write (output_unit, '("| ",i0," | ",f0.3," | ",f0.3," | ",f0.1," |")') n, &
            1.0e3_dp*median(tl), 1.0e3_dp*median(tq), median(tq)/median(tl)
    end subroutine kernels

    !> A chain of `n` unit masses (springs 1, the first to ground), Rayleigh damping
    !> 0.01 M + 0.01 K, forcing cos(omega t) + 0.3 cos(3 omega t + 0.4) on the last DOF,
    !> a ground contact on every DOF with mu N = 0.05 + 0.02 (j mod 5) (as test_solver).
    function contact_chain(n, omega) result(m)
        integer, intent(in) :: n
        real(dp), intent(in) :: omega
        type(model_t) :: m
        integer :: j
        m%ndof = n
        allocate (m%mass(n, n), m%stiffness(n, n))
        m%mass = 0.0_dp
        m%stiffness = 0.0_dp
        do j = 1, n
            m%mass(j, j) = 1.0_dp
            m%stiffness(j, j) = 2.0_dp
            if (j < n) then
                m%stiffness(j, j + 1) = -1.0_dp
                m%stiffness(j + 1, j) = -1.0_dp
            end if
        end do
        m%stiffness(n, n) = 1.0_dp
        m%damping = 0.01_dp*m%mass + 0.01_dp*m%stiffness
        m%omega = omega
        m%force_dof = [n, n]
        m%force_harmonic = [1, 3]
        m%force_amplitude = [1.0_dp, 0.3_dp]
        m%force_phase = [0.0_dp, 0.4_dp]
        m%contact_dof = [(j, j=1, n)]
        m%contact_dof2 = [(0, j=1, n)]
        m%mu = [(0.05_dp + 0.02_dp*mod(j, 5), j=1, n)]
        m%normal_load = [(1.0_dp, j=1, n)]
    end function contact_chain
end program bench_solver
