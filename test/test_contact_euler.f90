!> Implicit Euler with contact laws (doc/contacts.md, section 4) against independent truth:
!> a unilateral contact that never opens gives the constant-load trajectory to roundoff; a
!> preloaded elastic contact at rest carries the static share of its preload; the circular
!> 2D slip converges to its closed form at first order; a stuck Jenkins contact is the
!> structure with the spring k_t; a contact that lifts off agrees with the weighted
!> residual; a rigid contact (impacts) keeps the Signorini law at every step and converges
!> at first order in h.
module test_contact_euler
    use stickslip_kinds, only: dp, pi
    use stickslip_error, only: error_type, real_text
    use stickslip_model, only: model_t
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_contact_law, only: state_open
    use fixtures, only: seed_model, unilateral_seed, liftoff_model, planar_model
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_contact_euler_tests

contains

    subroutine run_contact_euler_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_never_opens(t)
        call test_static_preload(t)
        call test_circle(t)
        call test_jenkins_stuck(t)
        call test_liftoff(t)
    end subroutine run_contact_euler_tests

    !> The seed structure with its contact made unilateral (never opening, preload 1): the
    !> trajectory of the constant-load case (normal_load 1) to roundoff, lambda = 1.
    subroutine test_never_opens(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: o
        type(euler_result_t) :: plain, uni
        type(error_type), allocatable :: error
        o%steps_per_period = 500
        call integrate_euler(seed_model(), o, plain, error)
        if (allocated(error)) return
        call integrate_euler(unilateral_seed(0.0_dp), o, uni, error)
        call check(t, .not. allocated(error), "contact_euler: never opens: integrated")
        if (allocated(error)) return
        call check(t, uni%periodic .and. uni%periods == plain%periods .and. &
                   maxval(abs(uni%x(:, 1:2) - plain%x)) <= 1.0e-12_dp*maxval(abs(plain%x)) &
                   .and. maxval(abs(uni%r(:, 1) - plain%r(:, 1))) <= 1.0e-12_dp, &
                   "contact_euler: a contact that never opens is the constant-load case")
        call check(t, maxval(abs(uni%normal(:, 1) - 1.0_dp)) <= 1.0e-12_dp .and. &
                   maxval(abs(uni%gap(:, 1))) <= 1.0e-12_dp .and. &
                   .not. any(uni%state(:, 1) == state_open), &
                   "contact_euler: never opens: lambda = 1, gap 0, closed")
    end subroutine test_never_opens

    !> No forcing: the elastic contact (k_n = 50) pressed by the preload 1 on a DOF grounded
    !> by a spring 5 settles where both springs share the preload: lambda = 50 / 55, the gap
    !> -1 / 55 (the contact spring's compression).
    subroutine test_static_preload(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(model_t) :: m
        type(error_type), allocatable :: error
        m = unilateral_seed(50.0_dp)
        m%force_amplitude = [0.0_dp]
        m%damping = 0.5_dp*m%mass
        o%steps_per_period = 200
        call integrate_euler(m, o, res, error)
        call check(t, .not. allocated(error), "contact_euler: static preload: integrated")
        if (allocated(error)) return
        call check_close(t, res%normal(1, 1), 50.0_dp/55.0_dp, &
                         "contact_euler: static preload: lambda = k_n / (k + k_n) P", &
                         rtol=1.0e-8_dp)
        call check_close(t, res%gap(1, 1), -1.0_dp/55.0_dp, &
                         "contact_euler: static preload: the gap is the spring's compression", &
                         rtol=1.0e-8_dp)
    end subroutine test_static_preload

    !> 2D friction, the circular path of the point mass forced by a rotating force: the
    !> radius converges to the closed form (see test_contact_hbm) at first order in h (the
    !> error halves when the steps double).
    subroutine test_circle(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(error_type), allocatable :: error
        real(dp) :: z, cw, mun, a, e(2)
        integer :: k
        z = 1.0_dp - 1.7_dp**2
        cw = 0.1_dp*1.7_dp
        mun = 0.3_dp
        a = (-cw*mun + sqrt((cw*mun)**2 - (z**2 + cw**2)*(mun**2 - 1.0_dp)))/(z**2 + cw**2)
        do k = 1, 2
            o%steps_per_period = 500*2**k
            call integrate_euler(planar_model(1.0_dp, 1.0_dp, 0.0_dp), o, res, error)
            call check(t, .not. allocated(error), "contact_euler: circle: integrated")
            if (allocated(error)) return
            e(k) = abs(maxval(hypot(res%x(:, 1), res%x(:, 2))) - a)/a
        end do
        call check(t, res%periodic .and. e(2) < 1.0e-2_dp .and. e(1)/e(2) > 1.7_dp .and. &
                   e(1)/e(2) < 2.3_dp, "contact_euler: circle: the closed-form radius at "// &
                   "first order in h", "errors "//real_text(e(1))//", "//real_text(e(2)))
        call check(t, maxval(abs(hypot(res%r(:, 1), res%r(:, 2)) - mun)) <= 1.0e-10_dp, &
                   "contact_euler: circle: the force on the disk's edge")
    end subroutine test_circle

    !> A stuck Jenkins contact (k_t = 3, mu N huge) is the spring k_t: the periodic response
    !> is the linear one of K + k_t e2 e2^T, to O(h).
    subroutine test_jenkins_stuck(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: o
        type(euler_result_t) :: res
        type(model_t) :: m
        type(error_type), allocatable :: error
        real(dp) :: a(2, 2), amp
        m = seed_model()
        m%omega = 1.1_dp
        m%damping = 0.05_dp*m%mass
        m%normal_load = [1.0e6_dp]
        m%tangential_stiffness = [3.0_dp]
        o%steps_per_period = 4000
        call integrate_euler(m, o, res, error)
        call check(t, .not. allocated(error), "contact_euler: Jenkins stuck: integrated")
        if (allocated(error)) return
        a = m%stiffness - m%omega**2*m%mass
        a(2, 2) = a(2, 2) + 3.0_dp
        ! with the damping 0.05: the amplitude of the complex solve, |X_1|
        block
            complex(dp) :: za(2, 2), zb(2), det
            za = cmplx(a, m%omega*m%damping, dp)
            det = za(1, 1)*za(2, 2) - za(1, 2)*za(2, 1)
            zb = [za(2, 2)*10.0_dp, -za(2, 1)*10.0_dp]/det
            amp = abs(zb(1))
        end block
        call check(t, res%periodic .and. abs(maxval(abs(res%x(:, 1))) - amp) <= 1.0e-2_dp*amp, &
                   "contact_euler: Jenkins stuck = the structure with the spring k_t", &
                   real_text(maxval(abs(res%x(:, 1))))//" vs "//real_text(amp))
    end subroutine test_jenkins_stuck

    !> The damper-like contact that lifts off: Euler (2000 steps per period) and the weighted
    !> residual agree on the displacements and the normal force within the Euler error; the
    !> contact opens. Rigid: the Signorini law holds at every step and the trajectory
    !> converges at first order in h.
    subroutine test_liftoff(t)
        type(test_counter_t), intent(inout) :: t
        type(euler_options_t) :: o
        type(euler_result_t) :: e, stiff, stiffer, rigid
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: dx, dn, d1, d2
        integer :: k, kk
        o%steps_per_period = 2000
        call integrate_euler(liftoff_model(10.0_dp, 0.0_dp), o, e, error)
        call check(t, .not. allocated(error) .and. e%periodic, "contact_euler: lift-off periodic")
        if (allocated(error)) return
        ho%harmonics = 40
        ho%samples = 2000
        call solve_periodic(liftoff_model(10.0_dp, 0.0_dp), ho, sol, error)
        if (allocated(error)) return
        ! the same instants: the Euler grid is the quadrature grid (2000 per period)
        dx = 0.0_dp
        dn = 0.0_dp
        do k = 1, 2000
            kk = k
            dx = max(dx, maxval(abs(e%x(k, :) - sol%x(kk, :))))
            dn = max(dn, abs(e%normal(k, 1) - sol%normal(kk, 1)))
        end do
        call check(t, dx <= 0.02_dp*maxval(abs(sol%x)) .and. &
                   dn <= 0.03_dp*maxval(sol%normal(:, 1)), &
                   "contact_euler: lift-off agrees with the weighted residual", &
                   "x "//real_text(dx)//", normal "//real_text(dn))
        call check(t, count(e%state(:, 1) == state_open) > 100, &
                   "contact_euler: lift-off: the contact opens")
        ! a rigid contact (impacts, plastic as h -> 0; a stiff elastic contact is not its
        ! limit: its impacts are nearly elastic): the position-level law at every step
        ! (lambda >= 0, gap >= 0, lambda gap = 0) and first-order convergence in h
        o%steps_per_period = 2000
        call integrate_euler(liftoff_model(0.0_dp, 0.0_dp), o, rigid, error)
        o%steps_per_period = 4000
        call integrate_euler(liftoff_model(0.0_dp, 0.0_dp), o, stiffer, error)
        o%steps_per_period = 8000
        call integrate_euler(liftoff_model(0.0_dp, 0.0_dp), o, stiff, error)
        call check(t, .not. allocated(error) .and. stiff%periodic .and. stiffer%periodic .and. &
                   rigid%periodic, "contact_euler: rigid lift-off periodic")
        if (.not. (stiff%periodic .and. stiffer%periodic .and. rigid%periodic)) return
        call check(t, minval(rigid%normal(:, 1)) >= 0.0_dp .and. minval(rigid%gap(:, 1)) >= &
                   -1.0e-12_dp*maxval(abs(rigid%x)) .and. maxval(rigid%normal(:, 1)* &
                   rigid%gap(:, 1)) <= 1.0e-12_dp*maxval(rigid%normal(:, 1))* &
                   maxval(abs(rigid%x)), "contact_euler: rigid: lambda >= 0, gap >= 0, "// &
                   "lambda gap = 0 at every step")
        ! the same instants of the three grids: every 2nd and 4th sample of the finer ones
        d1 = maxval(abs(rigid%x - stiffer%x(1:4000:2, :)))
        d2 = maxval(abs(stiffer%x(1:4000:2, :) - stiff%x(1:8000:4, :)))
        call check(t, d1/d2 > 1.5_dp .and. d1/d2 < 2.6_dp, &
                   "contact_euler: rigid lift-off converges at first order in h", &
                   real_text(d1)//", "//real_text(d2))
    end subroutine test_liftoff

end module test_contact_euler
