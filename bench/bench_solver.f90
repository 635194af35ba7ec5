!> Benchmark of the nonlinear solve of the weighted residual at hundreds of unknowns (a
!> program that prints figures, not a test): every case solved by MINPACK's hybrj
!> (&hbm solver = 'hybrj', the cold start of start = 'auto') and by the Newton path
!> (solver = 'newton': semismooth Newton with LU from the halving ladder H/2^k, hybrj for
!> the cold lowest stage and as the fallback) in the same run; medians over repeats and
!> the ratio hybrj / newton. Cases: the seed case (examples/seed.nml's model, rho = 0.2 as
!> in bench_hbm) at H = 10 .. 256 (all harmonics; the small ones place the crossover used
!> by solver = 'auto'), a chain of 20 masses with a ground contact on each at H = 15
!> (620 unknowns) and H = 7, and a Craig-Bampton-reduced FE model at H = 15 (620 unknowns):
!> the cantilever steel plate of bench_reduction at its smallest mesh (44 x 11 Q4 elements,
!> N = 1056 DOFs; bench/bench_plate.f90) with 20 contacts, reduced for H = 15 by
!> bench_reduction's rule (every fixed-interface mode below 3 x 15 x 1.1 w1: 35 reduced
!> DOFs), 1024 samples and automatic rho like the chain, at omega = 0.3 w1 (at w1 every
!> contact slips over the whole period save the reversal instants; at 0.3 w1, with its third
!> harmonic near w1, every contact sticks over part of the period), with the stick fractions
!> of both solutions printed under the table. Then one factorization of a random dense
!> matrix by the LAPACK kernels the candidates use (dgetrf; dgeqrf + dorgqr for a Powell
!> hybrid on blocked QR).
!> Run from the project root: fpm run --example bench_solver --profile release
!> [-- --quick] (--quick: fewer repeats, skips H = 256 with hybrj; --plate-scan: only the
!> plate, over omega / w1 = 0.15 .. 1, both solvers; --profile-newton: only the
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
    use stickslip_bench_plate, only: reduced_plate
    implicit none
    integer, parameter :: seed_h(8) = [10, 20, 35, 50, 75, 100, 200, 256]
    !> The plate case: the smallest mesh of bench_reduction, contacts, omega / w1.
    integer, parameter :: plate_nx = 44, plate_ny = 11, plate_contacts = 20
    real(dp), parameter :: plate_omega = 0.3_dp
    type(case_t) :: c
    type(model_t) :: chain, plate
    type(hbm_solution_t) :: plate_hybrj, plate_newton
    type(error_type), allocatable :: error
    integer :: i, plate_n
    real(dp) :: plate_w1
    character(len=32) :: arg
    character(len=80) :: plate_name
    logical :: quick, profile, scan

    call limit_blas_threads()
    quick = .false.
    profile = .false.
    scan = .false.
    do i = 1, command_argument_count()
        call get_command_argument(i, arg)
        if (arg == '--quick') quick = .true.
        if (arg == '--profile-newton') profile = .true.
        if (arg == '--plate-scan') scan = .true.
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
    if (scan) then
        call plate_scan()
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
    call reduced_plate(plate_nx, plate_ny, plate_contacts, 15, plate_omega, plate, plate_w1, &
                       plate_n, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: plate: "//error%message
        stop 1
    end if
    write (plate_name, '(a,i0,a,i0,a)') "CB-reduced plate (N = ", plate_n, " DOFs), ", &
        plate_contacts, " contacts"
    call compare(trim(plate_name), plate, 15, 0.0_dp, plate_hybrj, plate_newton)
    write (output_unit, '(a)') ""
    write (output_unit, '(a,i0,a,f0.1,a,f4.2,a)') "plate: ", plate%ndof, &
        " reduced DOFs, w1 = ", plate_w1, " rad/s, omega = ", plate_omega, &
        " w1; stick fraction per contact (tip first):"
    call print_fractions("hybrj ", plate_hybrj)
    call print_fractions("newton", plate_newton)

    write (output_unit, '(a)') ""
    write (output_unit, '(a)') "one factorization of a dense n x n matrix (median over repeats)"
    write (output_unit, '(a)') "| n | dgetrf [ms] | dgeqrf + dorgqr [ms] | ratio |"
    write (output_unit, '(a)') "|---|---|---|---|"
    call kernels(201)
    call kernels(401)
    call kernels(620)

contains

    !> Solve `m` at `h` harmonics with both solvers; print medians and their ratio.
    subroutine compare(name, m, h, rho, hybrj_sol, newton_sol)
        character(len=*), intent(in) :: name
        type(model_t), intent(in) :: m
        integer, intent(in) :: h
        real(dp), intent(in) :: rho
        !> The solutions of hybrj and of the Newton path (last repeat), when wanted.
        type(hbm_solution_t), intent(out), optional :: hybrj_sol, newton_sol
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
        if (present(hybrj_sol)) hybrj_sol = sh
        if (present(newton_sol)) newton_sol = sn
    end subroutine compare

    !> One line: the solver, convergence, the contacts stuck all period / slipping all period
    !> (stick fraction 1 / at most 2 samples: the reversal instants) / stick-slip, and the
    !> stick fraction of every contact.
    subroutine print_fractions(solver, s)
        character(len=*), intent(in) :: solver
        type(hbm_solution_t), intent(in) :: s
        integer :: nc, stuck, slipping
        real(dp) :: eps
        nc = size(s%stick_fraction)
        eps = 2.5_dp/max(s%samples, 1)
        stuck = count(s%stick_fraction >= 1.0_dp - eps)
        slipping = count(s%stick_fraction <= eps)
        write (output_unit, '(2x,a,": converged ",l1,", stuck ",i0,", slipping ",i0, &
            &", stick-slip ",i0,":",*(1x,f4.2))') solver, s%converged, stuck, slipping, &
            nc - stuck - slipping, s%stick_fraction
    end subroutine print_fractions

    !> The plate with 20 contacts at H = 15 over omega / w1 = 0.15 .. 1 (each point reduced
    !> for its own omega, as bench_reduction does): both solvers side by side, one table.
    subroutine plate_scan()
        real(dp), parameter :: ratios(8) = [0.15_dp, 0.2_dp, 0.25_dp, 0.3_dp, 0.4_dp, &
                                            0.5_dp, 0.7_dp, 1.0_dp]
        type(model_t) :: m
        type(hbm_solution_t) :: sh, sn
        real(dp) :: w1
        integer :: k, n
        character(len=40) :: name
        write (output_unit, '(a)') "| omega / w1 | H | unknowns | hybrj [ms] | newton [ms] | "// &
            "ratio | hybrj njev | newton LUs (calls, fallbacks) | max |dr| / mu N |"
        write (output_unit, '(a)') "|---|---|---|---|---|---|---|---|---|"
        do k = 1, size(ratios)
            call reduced_plate(plate_nx, plate_ny, plate_contacts, 15, ratios(k), m, w1, n, &
                               error)
            if (allocated(error)) then
                write (output_unit, '(a)') "error: plate: "//error%message
                stop 1
            end if
            write (name, '(f4.2)') ratios(k)
            call compare(trim(name), m, 15, 0.0_dp, sh, sn)
        end do
    end subroutine plate_scan

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
