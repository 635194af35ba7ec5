!> Tests of the implicit Euler (Moreau-Jean) time stepper: the per-step friction solve in
!> stick, slip and with several contacts; first-order convergence to a known periodic
!> solution; steady-state detection, including a case that must report no periodic state;
!> agreement with the weighted-residual solution on the seed case.
module test_euler
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_contact_solve, only: contact_forces
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_progress, only: progress_t
    use fixtures, only: seed_model, one_dof_model
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
    end subroutine run_euler_tests

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
