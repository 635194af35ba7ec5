!> Tests of the implicit Euler (Moreau-Jean) time stepper: the per-step friction solve in
!> stick, slip and with several contacts; first-order convergence to a known periodic
!> solution; steady-state detection, including a case that must report no periodic state;
!> agreement with the weighted-residual solution on the seed case.
module test_euler
    use, intrinsic :: ieee_arithmetic, only: ieee_support_underflow_control, &
        ieee_get_underflow_mode, ieee_set_underflow_mode
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t, contact_velocity_direction, force_direction
    use stickslip_lapack, only: dgetrf, dgetrs
    use stickslip_case, only: case_t, read_case
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_contact_solve, only: contact_forces
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_progress, only: progress_t
    use fixtures, only: seed_model, one_dof_model, chain_model, project_path
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_euler_tests

contains

    subroutine run_euler_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_contact_forces(t)
        call test_first_order(t)
        call test_no_periodic_state(t)
        call test_seed_against_hbm(t)
        call test_progress(t)
        call test_same_as_before(t)
        call test_start_size(t)
        call test_underflow_mode(t)
    end subroutine run_euler_tests

    !> The step loop flushes subnormal numbers to zero; the caller's gradual underflow is
    !> back afterwards (a subnormal quotient stays nonzero).
    subroutine test_underflow_mode(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(error_type), allocatable :: error
        logical :: gradual
        real(dp) :: x
        if (.not. ieee_support_underflow_control(1.0_dp)) return
        call ieee_set_underflow_mode(.true.)
        o%steps_per_period = 100
        o%max_periods = 2
        call integrate_euler(seed_model(), o, res, error)
        call ieee_get_underflow_mode(gradual)
        x = tiny(1.0_dp)
        x = x/real(res%periods*4, dp)
        call check(t, gradual .and. x > 0.0_dp, "euler: the caller's underflow mode restored")
    end subroutine test_underflow_mode

    !> The step loop of issue 12 (inverse of the iteration matrix formed once, written-out
    !> loops) against the loop it replaced (per-step products and dgetrs, frozen below as
    !> legacy_euler): same periods, same last period to 1e-12 of the amplitude, through the
    !> inverse and through the LU path (inverse_max_ndof = 0), on the seed case, the 4-DOF
    !> chain (two contacts, one relative; two forcing terms), many_sticks.nml and general
    !> directions and load shapes, from rest and from a given start.
    subroutine test_same_as_before(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: m
        type(error_type), allocatable :: error
        type(euler_options_t) :: o
        o%steps_per_period = 1000
        call compare_with_legacy(t, seed_model(), o, "seed")
        ! the seed with a second, zero forcing term (the 2-DOF kernel with two forcing terms)
        m = seed_model()
        m%force_dof = [1, 2]
        m%force_harmonic = [1, 3]
        m%force_amplitude = [10.0_dp, 0.0_dp]
        m%force_phase = [0.0_dp, 0.0_dp]
        call compare_with_legacy(t, m, o, "seed, two forcing terms")
        call compare_with_legacy(t, chain_model(), o, "chain4")
        call read_case(project_path("examples/many_sticks.nml"), c, error)
        call check_error(t, error, "same as before: read many_sticks.nml", .false.)
        if (.not. allocated(error)) call compare_with_legacy(t, c%model, o, "many_sticks")
        ! directions and load shapes as full vectors (no DOF lists)
        m = chain_model()
        allocate (m%contact_direction(4, 2), m%force_shape(4, 2))
        m%contact_direction(:, 1) = [0.0_dp, 1.0_dp, 0.2_dp, 0.0_dp]
        m%contact_direction(:, 2) = [0.0_dp, 0.0_dp, -1.0_dp, 1.0_dp]
        m%force_shape(:, 1) = [1.0_dp, 0.5_dp, 0.0_dp, 0.0_dp]
        m%force_shape(:, 2) = [0.0_dp, 0.0_dp, 1.0_dp, -0.3_dp]
        deallocate (m%contact_dof, m%contact_dof2, m%force_dof)
        allocate (m%contact_dof(0), m%contact_dof2(0), m%force_dof(0))
        call compare_with_legacy(t, m, o, "directions")
        o%steps_per_period = 300
        o%max_periods = 7
        call compare_with_legacy(t, seed_model(), o, "seed, 7 periods from a start", &
                                 [0.3_dp, -0.2_dp], [1.0_dp, 0.5_dp])
    end subroutine test_same_as_before

    subroutine compare_with_legacy(t, m, o, name, x0, v0)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(euler_options_t), intent(in) :: o
        character(len=*), intent(in) :: name
        real(dp), intent(in), optional :: x0(:), v0(:)
        type(euler_options_t) :: lu
        type(euler_result_t) :: new, old
        type(error_type), allocatable :: error
        integer :: path
        call legacy_euler(m, o, old, x0, v0)
        lu = o
        lu%inverse_max_ndof = 0
        do path = 1, 2
            if (path == 1) then
                call integrate_euler(m, o, new, error, x0, v0)
            else
                call integrate_euler(m, lu, new, error, x0, v0)
            end if
            call check_error(t, error, "same as before: "//name, .false.)
            if (allocated(error)) return
            call check(t, new%periods == old%periods .and. (new%periodic .eqv. old%periodic), &
                       "same as before: "//name//": periods")
            if (new%periods /= old%periods) cycle
            call check_close(t, reshape(new%x, [size(new%x)]), reshape(old%x, [size(old%x)]), &
                             "same as before: "//name//": x", rtol=0.0_dp, &
                             atol=1.0e-12_dp*maxval(abs(old%x)))
            call check_close(t, reshape(new%v, [size(new%v)]), reshape(old%v, [size(old%v)]), &
                             "same as before: "//name//": v", rtol=0.0_dp, &
                             atol=1.0e-12_dp*maxval(abs(old%v)))
            ! a stuck force is -u_free / D with D ~ h W^T M^{-1} W: it carries the roundoff
            ! of the velocities times 1/h (~700 at 1000 steps per period), hence 1e-10
            call check_close(t, reshape(new%r, [size(new%r)]), reshape(old%r, [size(old%r)]), &
                             "same as before: "//name//": r", rtol=0.0_dp, &
                             atol=1.0e-10_dp*maxval(abs(old%r)))
            ! the defect is a difference of states 1e-8 apart: it agrees in absolute terms
            call check(t, abs(new%defect - old%defect) <= 1.0e-11_dp, &
                       "same as before: "//name//": defect")
        end do
    end subroutine compare_with_legacy

    !> x0 or v0 of the wrong size: an input error, not a silent reallocation.
    subroutine test_start_size(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(error_type), allocatable :: error
        o%max_periods = 1
        call integrate_euler(seed_model(), o, res, error, x0=[1.0_dp])
        call check_error(t, error, "euler: x0 of the wrong size", .true.)
        call integrate_euler(seed_model(), o, res, error, v0=[1.0_dp, 2.0_dp, 3.0_dp])
        call check_error(t, error, "euler: v0 of the wrong size", .true.)
    end subroutine test_start_size

    !> The step loop as it was before issue 12 (commit 502f373), frozen as the reference:
    !> per step b = M v - h K x + h f, a dgetrs with the LU factors of S, the friction forces
    !> and v = S^{-1} b + h S^{-1} W r; the periodicity test of integrate_euler.
    subroutine legacy_euler(model, opts, res, x0, v0)
        type(model_t), intent(in) :: model
        type(euler_options_t), intent(in) :: opts
        type(euler_result_t), intent(out) :: res
        real(dp), intent(in), optional :: x0(:), v0(:)
        integer :: n, nc, ns, info, j, k, period, step, sweeps, i
        real(dp) :: h, period_t, tt, ampx, ampv, dx, dv
        real(dp), allocatable :: s(:, :), sw(:, :), d(:, :), w(:, :), b(:), wk(:), x(:), v(:), &
                                 xstart(:), vstart(:), r(:), ufree(:), limit(:), famp(:), fph(:), &
                                 fshape(:, :)
        integer, allocatable :: ipiv(:), fh(:)
        n = model%ndof
        nc = model%ncontact()
        ns = opts%steps_per_period
        period_t = two_pi/model%omega
        h = period_t/ns
        allocate (s(n, n), sw(n, nc), d(nc, nc), w(n, nc), b(n), wk(n), x(n), v(n), xstart(n), &
                  vstart(n), r(nc), ufree(nc), limit(nc), ipiv(n))
        s = model%mass + h*model%damping + h*h*model%stiffness
        call dgetrf(n, n, s, n, ipiv, info)
        do j = 1, nc
            w(:, j) = contact_velocity_direction(model, j)
        end do
        sw = w
        if (nc > 0) call dgetrs('N', n, nc, s, n, ipiv, sw, n, info)
        d = h*matmul(transpose(w), sw)
        limit = model%mu*model%normal_load
        allocate (fshape(n, model%nforce()))
        do i = 1, model%nforce()
            fshape(:, i) = force_direction(model, i)
        end do
        fh = model%force_harmonic
        famp = model%force_amplitude
        fph = model%force_phase
        allocate (res%t(ns), res%x(ns, n), res%v(ns, n), res%r(ns, nc))
        x = 0.0_dp
        v = 0.0_dp
        if (present(x0)) x = x0
        if (present(v0)) v = v0
        r = 0.0_dp
        res%max_sweeps = 0
        do period = 1, opts%max_periods
            xstart = x
            vstart = v
            do step = 1, ns
                res%x(step, :) = x
                res%v(step, :) = v
                res%r(step, :) = r
                tt = period_t*(real(period - 1, dp) + real(step, dp)/real(ns, dp))
                b = matmul(model%mass, v)
                wk = matmul(model%stiffness, x)
                b = b - h*wk
                do i = 1, size(fh)
                    b = b + (h*famp(i)*cos(fh(i)*model%omega*tt + fph(i)))*fshape(:, i)
                end do
                call dgetrs('N', n, 1, s, n, ipiv, b, n, info)
                v = b
                if (nc > 0) then
                    ufree = matmul(v, w)
                    call contact_forces(d, ufree, limit, r, opts%contact_tol, &
                                        opts%contact_max_sweeps, sweeps)
                    res%max_sweeps = max(res%max_sweeps, sweeps)
                    wk = matmul(sw, r)
                    v = v + h*wk
                end if
                x = x + h*v
            end do
            res%periods = period
            ampx = maxval(abs(res%x))
            ampv = maxval(abs(res%v))
            dx = maxval(abs(x - xstart))/max(ampx, tiny(1.0_dp))
            dv = maxval(abs(v - vstart))/max(ampv, tiny(1.0_dp))
            res%defect = max(dx, dv)
            if (res%defect <= opts%tol) then
                res%periodic = .true.
                exit
            end if
        end do
    end subroutine legacy_euler

    !> Progress of the periods: with a unit, no delay and no interval, one line per period
    !> not yet periodic, counting periods; the result is the same as without progress.
    subroutine test_progress(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: opts
        type(euler_result_t) :: a, b
        type(error_type), allocatable :: error
        type(progress_t) :: p
        integer :: u, stat, lines
        character(len=200) :: line
        logical :: worded
        opts%steps_per_period = 200
        opts%max_periods = 5
        open (newunit=u, status='scratch', action='readwrite')
        p = progress_t(unit=u, delay=0.0_dp, interval=0.0_dp)
        p%label = 'euler'
        p%items = 'periods'
        call p%begin()
        call integrate_euler(seed_model(), opts, a, error, progress=p)
        if (allocated(error)) deallocate (error)
        call integrate_euler(seed_model(), opts, b, error)
        if (allocated(error)) deallocate (error)
        rewind (u)
        lines = 0
        worded = .true.
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            lines = lines + 1
            worded = worded .and. index(line, "stickslip: euler ") == 1 .and. &
                     index(line, "/5 periods, periodicity defect") > 0
        end do
        close (u)
        call check(t, lines == a%periods .and. .not. a%periodic .and. worded, &
                   "euler: one progress line per period", line)
        call check(t, a%periods == b%periods .and. all(a%x == b%x), &
                   "euler: progress does not change the result")
    end subroutine test_progress

    !> Coulomb's law between r and u = u_free + D r, up to tol.
    logical function coulomb_holds(d, ufree, limit, r, tol) result(ok)
        real(dp), intent(in) :: d(:, :), ufree(:), limit(:), r(:), tol
        real(dp) :: u(size(r))
        integer :: j
        u = ufree + matmul(d, r)
        ok = all(abs(r) <= limit*(1.0_dp + 1.0e-12_dp))
        do j = 1, size(r)
            if (abs(r(j)) < limit(j)*(1.0_dp - 1.0e-9_dp)) then
                ok = ok .and. abs(u(j)) <= tol
            else if (r(j) > 0.0_dp) then
                ok = ok .and. u(j) <= tol
            else
                ok = ok .and. u(j) >= -tol
            end if
        end do
    end function coulomb_holds

    subroutine test_contact_forces(t)
        type(test_counter_t), intent(inout) :: t
        real(dp) :: d1(1, 1), r1(1), a(4, 4), d(4, 4), uf(4), lim(4), r(4)
        integer :: sweeps, trial, nstick, nslip
        ! one contact: stick when |u_free / D| <= limit, slip otherwise
        d1 = 2.0_dp
        r1 = 0.0_dp
        call contact_forces(d1, [0.5_dp], [1.0_dp], r1, 1e-14_dp, 100, sweeps)
        call check_close(t, r1(1), -0.25_dp, "one contact: stick force -u_free/D")
        call contact_forces(d1, [5.0_dp], [1.0_dp], r1, 1e-14_dp, 100, sweeps)
        call check_close(t, r1(1), -1.0_dp, "one contact: slip at the limit opposing u")
        call contact_forces(d1, [-5.0_dp], [1.0_dp], r1, 1e-14_dp, 100, sweeps)
        call check_close(t, r1(1), 1.0_dp, "one contact: slip the other way")
        ! several contacts: random SPD D, states from all-stick to all-slip
        nstick = 0
        nslip = 0
        do trial = 1, 40
            call random_number(a)
            d = matmul(transpose(a), a) + 0.1_dp*identity(4)
            call random_number(uf)
            uf = (uf - 0.5_dp)*0.2_dp*trial
            lim = [0.3_dp, 0.5_dp, 1.0_dp, 0.7_dp]
            r = 0.0_dp
            call contact_forces(d, uf, lim, r, 1e-14_dp, 100000, sweeps)
            call check(t, coulomb_holds(d, uf, lim, r, 1e-10_dp), &
                       "several contacts: projected Gauss-Seidel gives Coulomb's law")
            nstick = nstick + count(abs(r) < lim*(1 - 1e-9_dp))
            nslip = nslip + count(abs(r) >= lim*(1 - 1e-9_dp))
        end do
        call check(t, nstick > 10 .and. nslip > 10, "several contacts: stick and slip both seen")
    end subroutine test_contact_forces

    function identity(n) result(e)
        integer, intent(in) :: n
        real(dp) :: e(n, n)
        integer :: i
        e = 0.0_dp
        do i = 1, n
            e(i, i) = 1.0_dp
        end do
    end function identity

    !> A damped oscillator (mu = 0 contact): the periodic solution is known in closed form;
    !> halving the step halves the error.
    subroutine test_first_order(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(error_type), allocatable :: error
        complex(dp) :: x
        real(dp) :: err(3)
        integer :: i, k
        m = one_dof_model(mass=1.0_dp, stiffness=1.0_dp, damping=0.3_dp, omega=1.3_dp, &
                          force=1.0_dp, mu=0.0_dp, normal_load=1.0_dp)
        x = 1.0_dp/cmplx(1.0_dp - m%omega**2, 0.3_dp*m%omega, dp)
        do i = 1, 3
            o%steps_per_period = 200*2**(i - 1)
            o%tol = 1.0e-10_dp
            call integrate_euler(m, o, res, error)
            call check_error(t, error, "first order: integrate", .false.)
            if (allocated(error)) return
            call check(t, res%periodic, "first order: periodic state reached")
            err(i) = 0.0_dp
            do k = 1, o%steps_per_period
                err(i) = max(err(i), abs(res%x(k, 1) - real(x*exp(cmplx(0.0_dp, &
                    m%omega*res%t(k), dp)), dp)))
            end do
        end do
        call check(t, err(1)/err(2) > 1.8_dp .and. err(1)/err(2) < 2.2_dp .and. &
                   err(2)/err(3) > 1.8_dp .and. err(2)/err(3) < 2.2_dp, &
                   "first order: error halves with the step")
    end subroutine test_first_order

    !> Undamped, frictionless: the free vibration excited by the start never dies out
    !> (only Euler's numerical damping acts): no periodic state within 20 periods.
    subroutine test_no_periodic_state(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(error_type), allocatable :: error
        m = seed_model()
        m%mu = 0.0_dp
        o%steps_per_period = 400
        o%max_periods = 20
        call integrate_euler(m, o, res, error)
        call check_error(t, error, "no periodic state: integrate", .false.)
        call check(t, .not. res%periodic .and. res%periods == 20, &
                   "no periodic state: reported, not a silent last period")
        call check(t, index(res%diagnosis, "no periodic state") > 0, &
                   "no periodic state: diagnosis", res%diagnosis)
    end subroutine test_no_periodic_state

    !> The seed case: Euler on the grid of the weighted residual agrees with it, and the
    !> agreement improves with the step.
    subroutine test_seed_against_hbm(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: e(2)
        integer :: i
        m = seed_model()
        ho%harmonics = 30
        ho%samples = 1024
        call solve_periodic(m, ho, sol, error)
        if (allocated(error)) return
        do i = 1, 2
            o%steps_per_period = 1024*4**(i - 1)
            call integrate_euler(m, o, res, error)
            call check_error(t, error, "seed Euler", .false.)
            if (allocated(error)) return
            call check(t, res%periodic, "seed Euler: periodic state reached", res%diagnosis)
            call check(t, maxval(abs(res%r)) <= 0.45_dp*(1 + 1e-12_dp), "seed Euler: |r| <= mu N")
            e(i) = maxval(abs(res%x(1:size(res%x, 1):4**(i - 1), 1) - sol%x(:, 1)))/ &
                   maxval(abs(sol%x(:, 1)))
        end do
        call check(t, e(1) < 0.05_dp, "seed Euler vs weighted residual: x1 within 5%")
        call check(t, e(2) < e(1), "seed Euler vs weighted residual: closer with a smaller step")
    end subroutine test_seed_against_hbm
end module test_euler
