!> The microslip joint (the discrete Iwan element, stickslip_iwan_element: n Jenkins sliders
!> in parallel on one direction) against independent truth:
!> - the 4-parameter discretization keeps K_T and F_S, its slip displacements increase;
!> - the element's implicit step driven by a prescribed displacement (no structure) traces
!>   the virgin curve and Masing's hysteresis loops of its backbone, to roundoff; with a
!>   structure feedback (D > 0) its exact step solves Coulomb's law of every slider and
!>   agrees with the generic Newton step;
!> - the dissipation per cycle of many sliders follows the continuous 4-parameter model's
!>   power law 4 R A^(3 + chi) / ((chi + 2)(chi + 3)) at small amplitude;
!> - on a 2-DOF structure: all sliders stuck at tiny forcing (the linear structure with K_T
!>   added), Coulomb's contact of mu N = F_S at huge forcing;
!> - a 6-slider joint that slips whole each period: the exact reference (energy balance, each
!>   slider's Coulomb and spring law), implicit Euler converging to it at first order, the
!>   weighted residual as H grows, the monodromy matrix of [x; v; s_1..s_6] against
!>   differences of the period map;
!> - bad &microslip input in case files: an input error naming the file, the group and the
!>   variable.
module test_microslip
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, stickslip_stat, real_text, itoa
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference, reference_energy_error
    use stickslip_flow, only: flow_t
    use stickslip_contact_law, only: state_stick
    use stickslip_contact_element, only: element_step_forces
    use stickslip_iwan_element, only: iwan_element_t, new_iwan_element_4p, iwan_discretize
    use stickslip_case, only: case_t, read_case, write_case
    use fixtures, only: enter_project_root, scratch, scratch_dir, write_lines, file_text
    use test_jenkins, only: linear_response, central_differences
    use testing, only: test_counter_t, check, check_error
    implicit none
    private
    public :: run_microslip_tests

    !> The joint of the structure tests: F_S = 0.3 N, K_T = 2 N/m, chi = -0.5, beta = 0.5 (its
    !> phi_max = 0.27 m), 6 sliders.
    real(dp), parameter :: fs = 0.3_dp, kt = 2.0_dp, chi = -0.5_dp, beta = 0.5_dp
    integer, parameter :: nsl = 6

contains

    subroutine run_microslip_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_discretization(t)
        call test_masing(t)
        call test_exact_step(t)
        call test_power_law(t)
        call test_stuck_limit(t)
        call test_coulomb_limit(t)
        call test_methods(t)
        call enter_project_root()
        call test_bad_input(t)
    end subroutine run_microslip_tests

    !> The 2-DOF structure (M = I, K = [2 -1; -1 1], C = `damping` I) forced by `amp` cos(1.2
    !> t) on DOF 1, its DOF 2 on the ground through the joint (fs, kt, chi, beta, nsl).
    function iwan_model(amp, damping) result(m)
        real(dp), intent(in) :: amp, damping
        type(model_t) :: m
        m%ndof = 2
        m%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        m%stiffness = reshape([2.0_dp, -1.0_dp, -1.0_dp, 1.0_dp], [2, 2])
        m%damping = damping*m%mass
        m%omega = 1.2_dp
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [amp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [2]
        m%contact_dof2 = [0]
        m%mu = [0.0_dp]
        m%normal_load = [0.0_dp]
        allocate (m%laws(1))
        allocate (m%laws(1)%e, source=new_iwan_element_4p(fs, kt, chi, beta, nsl))
    end function iwan_model

    !> The joint's sliders (k_i, f_i) of iwan_model.
    subroutine joint_sliders(k, f)
        real(dp), allocatable, intent(out) :: k(:), f(:)
        call iwan_discretize(fs, kt, chi, beta, nsl, k, f)
    end subroutine joint_sliders

    !> The slip displacement of the 4-parameter model's last node [m].
    pure real(dp) function phi_max(f_s, k_t, x, b)
        real(dp), intent(in) :: f_s, k_t, x, b
        phi_max = f_s*(1.0_dp + b)/(k_t*(b + (x + 1.0_dp)/(x + 2.0_dp)))
    end function phi_max

    !> The backbone of the sliders (the spring force under a monotone displacement u from
    !> the unloaded state): sum_i sign(u) min(k_i |u|, f_i) [N].
    pure real(dp) function backbone(k, f, u)
        real(dp), intent(in) :: k(:), f(:), u
        backbone = sign(1.0_dp, u)*sum(min(k*abs(u), f))
    end function backbone

    !> iwan_discretize keeps K_T and F_S (1e-12), gives positive sliders of increasing slip
    !> displacement, the last one phi_max when beta > 0, one slider (K_T, F_S) when n = 1;
    !> the element of new_iwan_element_4p holds the same sliders and validates.
    subroutine test_discretization(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: chis(6) = [-0.5_dp, -0.5_dp, -0.9_dp, 0.0_dp, -0.2_dp, -0.99_dp]
        real(dp), parameter :: betas(6) = [0.0_dp, 0.5_dp, 2.0_dp, 0.1_dp, 0.0_dp, 0.0_dp]
        integer, parameter :: ns(6) = [10, 6, 50, 3, 1, 200]
        real(dp), allocatable :: k(:), f(:), phi(:)
        type(iwan_element_t) :: e
        type(error_type), allocatable :: error
        real(dp) :: dk, df, dl
        integer :: c
        character(len=:), allocatable :: name
        do c = 1, size(ns)
            name = "microslip: discretization chi = "//real_text(chis(c))//", beta = "// &
                   real_text(betas(c))//", n = "//itoa(ns(c))
            call iwan_discretize(1.7_dp, 35.0_dp, chis(c), betas(c), ns(c), k, f)
            dk = abs(sum(k) - 35.0_dp)/35.0_dp
            df = abs(sum(f) - 1.7_dp)/1.7_dp
            call check(t, size(k) == ns(c) .and. size(f) == ns(c) .and. dk <= 1.0e-12_dp .and. &
                       df <= 1.0e-12_dp, name//": sum k = K_T, sum f = F_S", &
                       "relative "//real_text(dk)//", "//real_text(df))
            phi = f/k
            call check(t, all(k > 0.0_dp) .and. all(f > 0.0_dp) .and. &
                       all(phi(2:) > phi(:size(phi) - 1)), name//": slip displacements "// &
                       "positive and increasing")
            if (betas(c) > 0.0_dp) then
                dl = abs(phi(ns(c))/phi_max(1.7_dp, 35.0_dp, chis(c), betas(c)) - 1.0_dp)
                call check(t, dl <= 1.0e-12_dp, name//": the last slider slips at phi_max", &
                           real_text(dl))
            end if
            e = new_iwan_element_4p(1.7_dp, 35.0_dp, chis(c), betas(c), ns(c))
            call e%validate(1, error)
            call check(t, .not. allocated(error) .and. e%n == ns(c) .and. &
                       all(e%k == k) .and. all(e%f == f) .and. e%nchannel() == ns(c), &
                       name//": the element holds the sliders and validates")
        end do
        call iwan_discretize(1.7_dp, 35.0_dp, -0.5_dp, 0.3_dp, 1, k, f)
        call check(t, size(k) == 1 .and. k(1) == 35.0_dp .and. f(1) == 1.7_dp, &
                   "microslip: discretization n = 1 is the Jenkins element (K_T, F_S)")
    end subroutine test_discretization

    !> Drive the element's implicit step through a prescribed displacement u (no structure:
    !> its block A = diag(c_i / h), c_i = 1 / k_i, q_i = V - (c_i / h) r_i,prev with V = (u_n+1
    !> - u_n) / h): from the unloaded state along the virgin curve to u = A, then two periods
    !> of u = A cos(theta) in 400 steps each. The spring force P = -sum r_i must follow the
    !> backbone F_b, then Masing's branches: descending F_b(A) - 2 F_b((A - u) / 2),
    !> ascending -F_b(A) + 2 F_b((A + u) / 2), to roundoff (the return mapping is exact on
    !> linear increments), for A inside the microslip range and beyond phi_max (macroslip).
    !> The area of the second loop (trapezoids on 20000 steps) is the dissipation per cycle
    !> sum over phi_i < A of 4 f_i (A - phi_i).
    subroutine test_masing(t)
        type(test_counter_t), intent(inout) :: t
        type(iwan_element_t) :: e
        real(dp), allocatable :: r(:), a(:, :), q(:)
        real(dp), parameter :: rel_amp(3) = [0.3_dp, 2.0_dp, 0.3_dp]
        real(dp) :: amp, h, u0, u1, p, pm, worst_virgin, worst_loop, pmax, area, closed, &
                    pprev, pfirst
        integer :: c, n, i, nper, nv
        e = new_iwan_element_4p(1.0_dp, 10.0_dp, -0.5_dp, 0.3_dp, 12)
        allocate (r(e%n), a(e%n, e%n), q(e%n))
        h = 0.01_dp
        a = 0.0_dp
        do i = 1, e%n
            a(i, i) = 1.0_dp/(e%k(i)*h)
        end do
        do c = 1, 3
            amp = rel_amp(c)*phi_max(1.0_dp, 10.0_dp, -0.5_dp, 0.3_dp)
            nper = merge(20000, 400, c == 3)
            nv = 50
            r = 0.0_dp
            u0 = 0.0_dp
            worst_virgin = 0.0_dp
            worst_loop = 0.0_dp
            pmax = 0.0_dp
            area = 0.0_dp
            pprev = 0.0_dp
            do n = 1, nv + 2*nper
                if (n <= nv) then
                    u1 = amp*real(n, dp)/nv
                else
                    u1 = amp*cos(two_pi*real(n - nv, dp)/nper)
                end if
                q = (u1 - u0)/h - matmul(a, r)
                call e%step_forces(a, q, r, e%force_scale())
                p = -sum(r)
                if (n <= nv) then
                    worst_virgin = max(worst_virgin, abs(p - backbone(e%k, e%f, u1)))
                else
                    if (modulo(n - nv - 1, nper) < nper/2) then
                        pm = backbone(e%k, e%f, amp) - 2.0_dp*backbone(e%k, e%f, (amp - u1)/2)
                    else
                        pm = -backbone(e%k, e%f, amp) + 2.0_dp*backbone(e%k, e%f, (amp + u1)/2)
                    end if
                    worst_loop = max(worst_loop, abs(p - pm))
                    pmax = max(pmax, abs(p))
                    ! the second loop's area, P du by trapezoids
                    if (n > nv + nper) area = area + 0.5_dp*(p + pprev)*(u1 - u0)
                    if (n == nv + nper) pfirst = p
                end if
                pprev = p
                u0 = u1
            end do
            if (c < 3) then
                call check(t, worst_virgin <= 1.0e-12_dp*e%force_scale() .and. &
                           worst_loop <= 1.0e-12_dp*e%force_scale() .and. pmax > 0.0_dp, &
                           "microslip: the element's steps trace the virgin curve and "// &
                           "Masing's loop, A = "//real_text(amp/phi_max(1.0_dp, 10.0_dp, &
                           -0.5_dp, 0.3_dp))//" phi_max", "virgin "//real_text(worst_virgin)// &
                           ", loop "//real_text(worst_loop)//" N of F_S = 1 N")
            else
                closed = sum(4.0_dp*e%f*max(0.0_dp, amp - e%f/e%k))
                ! the loop is closed: the area is the work of the spring force over a cycle
                call check(t, abs(area - closed) <= 1.0e-5_dp*closed .and. &
                           abs(p - pfirst) <= 1.0e-12_dp, "microslip: the area of the "// &
                           "element's loop is sum 4 f_i (A - phi_i)", real_text(area)//" vs "// &
                           real_text(closed)//", relative "//real_text(abs(area/closed - 1.0_dp)))
            end if
        end do
    end subroutine test_masing

    !> The exact implicit step (structure feedback D > 0: A = D 1 1^T + diag(c_i / h)) on 200
    !> random free velocities q: every slider obeys Coulomb's law with u = q + A r (|r_i| <=
    !> f_i; |r_i| < f_i => u_i = 0; |r_i| = f_i => r_i u_i <= 0), and the generic Newton step
    !> of contact_element_t gives the same forces.
    subroutine test_exact_step(t)
        type(test_counter_t), intent(inout) :: t
        type(iwan_element_t) :: e
        real(dp), allocatable :: a(:, :), q(:), r(:), r2(:), u(:), rnd(:)
        real(dp) :: h, d, worst_law, worst_newton, uscale, viol
        integer :: i, trial, nstick, nslip
        e = new_iwan_element_4p(1.0_dp, 10.0_dp, -0.5_dp, 0.3_dp, 12)
        allocate (a(e%n, e%n), q(e%n), r(e%n), r2(e%n), u(e%n), rnd(e%n + 1))
        h = 0.01_dp
        worst_law = 0.0_dp
        worst_newton = 0.0_dp
        nstick = 0
        nslip = 0
        do trial = 1, 200
            call random_number(rnd)
            d = 0.05_dp + rnd(e%n + 1)
            a = d
            do i = 1, e%n
                a(i, i) = a(i, i) + 1.0_dp/(e%k(i)*h)
            end do
            ! free velocities of the size of the sliders' slip limits over a step
            q = (2.0_dp*rnd(1:e%n) - 1.0_dp)*3.0_dp*maxval(e%f/(e%k*h))
            call random_number(rnd)
            r = (2.0_dp*rnd(1:e%n) - 1.0_dp)*e%f
            r2 = r
            call e%step_forces(a, q, r, e%force_scale())
            call element_step_forces(e, a, q, r2, e%force_scale())
            u = q + matmul(a, r)
            uscale = maxval(abs(q))
            do i = 1, e%n
                if (abs(r(i)) < e%f(i)*(1.0_dp - 1.0e-12_dp)) then
                    viol = abs(u(i))/uscale
                    nstick = nstick + 1
                else
                    viol = max(0.0_dp, r(i)*u(i)/(e%f(i)*uscale), &
                               abs(r(i))/e%f(i) - 1.0_dp)
                    nslip = nslip + 1
                end if
                worst_law = max(worst_law, viol)
            end do
            worst_newton = max(worst_newton, maxval(abs(r - r2)/e%f))
        end do
        call check(t, worst_law <= 1.0e-12_dp .and. nstick > 100 .and. nslip > 100, &
                   "microslip: the exact implicit step obeys Coulomb's law for every slider", &
                   "worst "//real_text(worst_law)//" ("//itoa(nstick)//" stuck, "// &
                   itoa(nslip)//" slipping)")
        call check(t, worst_newton <= 1.0e-10_dp, "microslip: the exact implicit step = the "// &
                   "generic Newton step", "worst "//real_text(worst_newton)//" of f_i")
    end subroutine test_exact_step

    !> The dissipation per cycle of the discretized joint under amplitude A < phi_max, the
    !> closed form sum over phi_i < A of 4 f_i (A - phi_i), against the continuous
    !> 4-parameter model's 4 R A^(chi + 3) / ((chi + 2)(chi + 3)), R = F_S (chi + 1) /
    !> (phi_max^(chi + 2) (beta + (chi + 1) / (chi + 2))), with 100 sliders for A from 1e-2 to
    !> 3e-1 phi_max: within 3% (measured ratios 0.9985 to 1.0017 for chi = -0.5, 0.9991 to
    !> 1.0050 for chi = -0.8), and the log-log slope over that range within 0.01 of 3 + chi
    !> (measured 2.4997, 2.1987).
    subroutine test_power_law(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: chis(2) = [-0.5_dp, -0.8_dp]
        integer, parameter :: na = 12
        real(dp), allocatable :: k(:), f(:)
        real(dp) :: pm, rr, amp(na), dd(na), dc(na), slope, lo, hi
        integer :: c, i
        do c = 1, 2
            call iwan_discretize(1.0_dp, 10.0_dp, chis(c), 0.4_dp, 100, k, f)
            pm = phi_max(1.0_dp, 10.0_dp, chis(c), 0.4_dp)
            rr = (chis(c) + 1.0_dp)/(pm**(chis(c) + 2.0_dp)*(0.4_dp + (chis(c) + 1.0_dp)/ &
                                                               (chis(c) + 2.0_dp)))
            do i = 1, na
                amp(i) = pm*1.0e-2_dp*30.0_dp**(real(i - 1, dp)/(na - 1))
                dd(i) = sum(4.0_dp*f*max(0.0_dp, amp(i) - f/k))
                dc(i) = 4.0_dp*rr*amp(i)**(chis(c) + 3.0_dp)/((chis(c) + 2.0_dp)* &
                                                               (chis(c) + 3.0_dp))
            end do
            lo = minval(dd/dc)
            hi = maxval(dd/dc)
            slope = log(dd(na)/dd(1))/log(amp(na)/amp(1))
            call check(t, lo > 0.97_dp .and. hi < 1.03_dp, "microslip: dissipation per cycle "// &
                       "= the continuous power law, chi = "//real_text(chis(c)), &
                       "ratios "//real_text(lo)//" to "//real_text(hi))
            call check(t, abs(slope - (3.0_dp + chis(c))) < 0.01_dp, "microslip: "// &
                       "dissipation ~ A^(3 + chi), chi = "//real_text(chis(c)), &
                       "slope "//real_text(slope))
        end do
    end subroutine test_power_law

    !> Tiny forcing (1e-6: the contact moves 1e-6 of phi_max, well inside the first slider's
    !> slip displacement): every slider sticks all period and the weighted residual gives the
    !> linear structure with K_T added on DOF 2 (closed form, harmonic 1) to 1e-6.
    subroutine test_stuck_limit(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp), allocatable :: x(:, :), stiffness(:, :)
        real(dp) :: d
        m = iwan_model(1.0e-6_dp, 0.1_dp)
        o%harmonics = 5
        o%samples = 64
        call solve_periodic(m, o, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged, &
                   "microslip: tiny forcing: weighted residual converged")
        if (allocated(error) .or. .not. sol%converged) return
        stiffness = m%stiffness
        stiffness(2, 2) = stiffness(2, 2) + kt
        x = linear_response(m%mass, m%damping, stiffness, m%omega, [1.0e-6_dp, 0.0_dp], sol%t)
        d = maxval(abs(sol%x - x))/maxval(abs(x))
        call check(t, d <= 1.0e-6_dp .and. sol%stick_fraction(1) == 1.0_dp, &
                   "microslip: tiny forcing: all sliders stuck, the structure with K_T", &
                   "relative "//real_text(d)//", stick share "//real_text(sol%stick_fraction(1)))
    end subroutine test_stuck_limit

    !> Huge forcing: the contact travels far beyond phi_max, the joint slips whole nearly all
    !> the time and tends to Coulomb's contact with mu N = F_S. Weighted residual (H = 40) of
    !> both at forcing 10 and 30 (contact amplitude 29 and 88 phi_max): the displacement
    !> difference relative to the amplitude falls with the forcing and is below 3e-3 at 30
    !> (measured 8.0e-3, 1.4e-3), the friction dissipation within 1% at 30 (measured -0.67%:
    !> the sliders' loops lack sum f_i phi_i / (F_S A) of Coulomb's).
    subroutine test_coulomb_limit(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m, mc
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: si, sc
        type(error_type), allocatable :: error
        real(dp), parameter :: forcing(2) = [10.0_dp, 30.0_dp]
        real(dp) :: d(2), ddiss, travel
        integer :: k
        o%harmonics = 40
        o%samples = 1024
        do k = 1, 2
            m = iwan_model(forcing(k), 0.1_dp)
            mc = m
            deallocate (mc%laws)
            mc%mu = [fs]
            mc%normal_load = [1.0_dp]
            call solve_periodic(m, o, si, error)
            if (.not. allocated(error)) call solve_periodic(mc, o, sc, error)
            call check(t, .not. allocated(error) .and. si%converged .and. sc%converged, &
                       "microslip: huge forcing: weighted residual converged (joint, Coulomb)")
            if (allocated(error) .or. .not. (si%converged .and. sc%converged)) return
            d(k) = maxval(abs(si%x - sc%x))/maxval(abs(sc%x))
        end do
        travel = maxval(abs(si%x(:, 2)))/phi_max(fs, kt, chi, beta)
        ddiss = si%diss_friction/sc%diss_friction - 1.0_dp
        call check(t, travel > 50.0_dp .and. d(2) < d(1) .and. d(2) < 3.0e-3_dp .and. &
                   abs(ddiss) < 1.0e-2_dp, "microslip: huge forcing: the joint tends to "// &
                   "Coulomb's contact of mu N = F_S", "differences "//real_text(d(1))//", "// &
                   real_text(d(2))//", dissipation "//real_text(ddiss)//", travel "// &
                   real_text(travel)//" phi_max")
    end subroutine test_coulomb_limit

    !> The joint on the structure with the three methods (forcing 0.3, damping 0.1: the
    !> contact travels 0.34 against phi_max = 0.27, so every slider slips each period and the
    !> periodic state is unique).
    subroutine test_methods(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(reference_result_t) :: res
        m = iwan_model(0.3_dp, 0.1_dp)
        call test_reference(t, m, res)
        if (.not. res%converged) return
        call test_monodromy(t, res)
        call test_euler(t, m, res)
        call test_hbm(t, m, res)
    end subroutine test_methods

    !> The exact reference, shot from the weighted residual (H = 20) with its slider forces
    !> clamped to the slip forces (the truncated series overshoots them: a slider beyond its
    !> limit at the start would be carried in the flow as an excess): converged, energy
    !> balance within 1e-9, at every sample each slider within its slip force (1e-9) and on
    !> it somewhere (every slider slips), the spring law r_i = -k_i (x_2 - s_i), the joint's
    !> force within F_S.
    subroutine test_reference(t, m, res)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(out) :: res
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(reference_options_t) :: o
        type(error_type), allocatable :: error
        real(dp), allocatable :: k(:), f(:)
        real(dp) :: ratio_hi, ratio_lo, spring
        integer :: i
        call joint_sliders(k, f)
        ho%harmonics = 20
        ho%samples = 256
        call solve_periodic(m, ho, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged, &
                   "microslip: the weighted-residual start converged")
        if (allocated(error) .or. .not. sol%converged) return
        do i = 1, nsl
            sol%r(:, i) = max(-f(i), min(f(i), sol%r(:, i)))
        end do
        o%samples = 1024
        call solve_reference(m, o, sol%x, sol%v, res, error, r_start=sol%r)
        call check_error(t, error, "microslip: reference: no error", .false.)
        if (allocated(error)) return
        call check(t, res%converged, "microslip: reference converged", res%diagnosis)
        if (.not. res%converged) return
        call check(t, res%work_forcing > 0.0_dp .and. reference_energy_error(res) < 1.0e-9_dp, &
                   "microslip: reference: energy balance within 1e-9", &
                   "error "//real_text(reference_energy_error(res)))
        ratio_hi = 0.0_dp
        ratio_lo = huge(1.0_dp)
        spring = 0.0_dp
        do i = 1, nsl
            ratio_hi = max(ratio_hi, maxval(abs(res%r(:, i)))/f(i))
            ratio_lo = min(ratio_lo, maxval(abs(res%r(:, i)))/f(i))
            spring = max(spring, maxval(abs(res%r(:, i) + k(i)*(res%x(:, 2) - res%s(:, i))))/ &
                         f(i))
        end do
        call check(t, size(res%r, 2) == nsl .and. size(res%s, 2) == nsl .and. &
                   ratio_hi <= 1.0_dp + 1.0e-9_dp .and. ratio_lo >= 1.0_dp - 1.0e-9_dp .and. &
                   maxval(abs(sum(res%r, 2))) <= fs*(1.0_dp + 1.0e-9_dp), &
                   "microslip: reference: every slider within its slip force and on it", &
                   "max |r_i| / f_i from "//real_text(ratio_lo)//" to "//real_text(ratio_hi))
        call check(t, spring <= 1.0e-8_dp, "microslip: reference: r_i = -k_i (x_2 - s_i)", &
                   "worst "//real_text(spring)//" of f_i")
    end subroutine test_reference

    !> The monodromy matrix of z = [x; v; s_1..s_6] against differences of the period map
    !> (see test_jenkins, test_monodromy): at the sample where every slider sticks farthest
    !> from its limits, central differences; at the shooting section (sliders 1-5 slipping,
    !> slider 6 stuck), central differences along x_1, v_1, v_2, x_2 + sum s_i and the stuck
    !> sliders' s_i, one-sided second-order differences towards the loading side along the
    !> slipping sliders' s_i (the excess is carried until the slider sticks; central
    !> differences of the plain coordinates are off by 0.27 of the largest entry there).
    !> Steps 1e-6 of max(|z_k|, 1e-2): the period map's roundoff (~1e-14) stays below 4e-7
    !> of the largest entry in the small columns of the weak sliders.
    subroutine test_monodromy(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(flow_t) :: flow
        type(error_type), allocatable :: error
        real(dp), allocatable :: k(:), f(:), z0(:), z1(:), zp(:), zq(:), fd(:, :), mono(:, :), &
                                 dirs(:, :), md(:, :), margin(:), rs(:)
        real(dp) :: h, worst
        integer :: nz, i, j, ks
        logical, allocatable :: slipping(:)
        call joint_sliders(k, f)
        flow = res%flow
        nz = flow%nz
        call check(t, nz == 4 + nsl .and. all(shape(res%monodromy) == [nz, nz]), &
                   "microslip: monodromy of [x; v; s] is (2 N + n) square", itoa(nz))
        if (nz /= 4 + nsl) return
        ! every slider stuck: the sample of largest margin (in displacement) to the limits
        allocate (margin(size(res%t)))
        margin = -huge(1.0_dp)
        do j = 1, size(res%t)
            if (res%state(j, 1) == state_stick) margin(j) = minval((f - abs(res%r(j, :)))/k)
        end do
        ks = maxloc(margin, 1)
        h = 1.0e-6_dp*max(maxval(abs([res%x(ks, :), res%v(ks, :), res%s(ks, :)])), 1.0e-2_dp)
        call check(t, margin(ks) > 100.0_dp*h, "microslip: a sample with every slider "// &
                   "stuck, away from the limits", "margin "//real_text(margin(ks))//" m")
        if (margin(ks) <= 100.0_dp*h) return
        z0 = [res%x(ks, :), res%v(ks, :), res%s(ks, :)]
        allocate (z1(nz), mono(nz, nz))
        call flow%period_map(res%t(ks), z0, z1, error, mono=mono)
        call check_error(t, error, "microslip: period map from the stuck sample", .false.)
        if (allocated(error)) return
        call central_differences(flow, res%t(ks), z0, fd, error)
        call check_error(t, error, "microslip: perturbed period maps (stuck)", .false.)
        if (allocated(error)) return
        worst = maxval(abs(fd - mono))/maxval(abs(mono))
        call check(t, worst <= 1.0e-5_dp, "microslip: monodromy where every slider sticks "// &
                   "= central differences of the period map", "relative "//real_text(worst))

        ! the section
        z0 = res%orbit%phase_y(1:nz, 1)
        rs = -k*(z0(2) - z0(5:))
        slipping = abs(abs(rs) - f) <= 1.0e-9_dp*f
        call check(t, count(slipping) >= 1 .and. count(slipping) < nsl, &
                   "microslip: sliders slip and stick at the section", &
                   itoa(count(slipping))//" slipping")
        allocate (dirs(nz, nz), md(nz, nz))
        dirs = 0.0_dp
        dirs(1, 1) = 1.0_dp
        dirs(3, 2) = 1.0_dp
        dirs(4, 3) = 1.0_dp
        dirs(2, 4) = 1.0_dp
        dirs(5:, 4) = 1.0_dp
        do i = 1, nsl
            dirs(4 + i, 4 + i) = 1.0_dp
            if (slipping(i)) dirs(4 + i, 4 + i) = sign(1.0_dp, rs(i))
        end do
        allocate (zp(nz), zq(nz))
        call flow%period_map(res%t_section, z0, z1, error)
        do j = 1, nz
            if (allocated(error)) exit
            h = 1.0e-6_dp*max(maxval(abs(z0)*abs(dirs(:, j))), 1.0e-2_dp)
            if (j > 4) then
                if (slipping(j - 4)) then
                    call flow%period_map(res%t_section, z0 + h*dirs(:, j), zp, error)
                    if (.not. allocated(error)) call flow%period_map(res%t_section, &
                                                                     z0 + 2.0_dp*h*dirs(:, j), zq, error)
                    md(:, j) = (-3.0_dp*z1 + 4.0_dp*zp - zq)/(2.0_dp*h)
                    cycle
                end if
            end if
            call flow%period_map(res%t_section, z0 + h*dirs(:, j), zp, error)
            if (.not. allocated(error)) call flow%period_map(res%t_section, z0 - h*dirs(:, j), &
                                                             zq, error)
            md(:, j) = (zp - zq)/(2.0_dp*h)
        end do
        call check_error(t, error, "microslip: perturbed period maps (section)", .false.)
        if (allocated(error)) return
        worst = maxval(abs(md - matmul(res%monodromy, dirs)))/maxval(abs(res%monodromy))
        call check(t, worst <= 1.0e-5_dp, "microslip: monodromy at the section = differences "// &
                   "of the period map along directions where it is differentiable", &
                   "relative "//real_text(worst))
    end subroutine test_monodromy

    !> Implicit Euler converges to the reference at first order: started from the reference's
    !> x, v at t = 0 (its sliders unloaded there: a transient, integrated out to the
    !> periodicity tolerance 1e-6, some 40 periods), the max displacement error of the
    !> periodic state at 2000 and 20000 steps per period falls by 5 to 20 (measured 5.5e-3,
    !> 5.5e-4).
    subroutine test_euler(t, m, res)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(in) :: res
        type(euler_options_t) :: o
        type(euler_result_t) :: e
        type(error_type), allocatable :: error
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: err(2)
        integer :: k
        o%tol = 1.0e-6_dp
        o%max_periods = 200
        do k = 1, 2
            o%steps_per_period = 2000*10**(k - 1)
            call integrate_euler(m, o, e, error, x0=res%x(1, :), v0=res%v(1, :))
            call check_error(t, error, "microslip: Euler integrated", .false.)
            if (allocated(error)) return
            call check(t, e%periodic, "microslip: Euler periodic at "// &
                       itoa(o%steps_per_period)//" steps", e%diagnosis)
            if (.not. e%periodic) return
            call sample_reference(res, o%steps_per_period, xr, vr, rr, error)
            if (allocated(error)) return
            err(k) = maxval(abs(e%x - xr))/maxval(abs(xr))
        end do
        call check(t, err(1)/err(2) > 5.0_dp .and. err(1)/err(2) < 20.0_dp .and. &
                   err(2) < 1.0e-3_dp, "microslip: implicit Euler converges to the "// &
                   "reference at first order", "errors at 2000, 20000 steps: "// &
                   real_text(err(1))//", "//real_text(err(2)))
    end subroutine test_euler

    !> The weighted residual converges to the reference as H grows: the max displacement
    !> error falls at each of H = 10, 20, 40, by more than 3 from 10 to 40 (measured 2.0e-2,
    !> 8.0e-3, 4.0e-3; H = 80 gives 1.6e-3 but costs 3.6 s in the debug build: 966 unknowns,
    !> on which the semismooth Newton stalls and hybrj takes over).
    subroutine test_hbm(t, m, res)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(in) :: res
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: e(3)
        integer :: k
        call sample_reference(res, 1024, xr, vr, rr, error)
        if (allocated(error)) return
        do k = 1, 3
            o%harmonics = 10*2**(k - 1)
            o%samples = 1024
            call solve_periodic(m, o, sol, error)
            if (allocated(error) .or. .not. sol%converged) then
                call check(t, .false., "microslip: weighted residual H = "// &
                           itoa(o%harmonics)//" converged")
                return
            end if
            e(k) = maxval(abs(sol%x - xr))/maxval(abs(xr))
        end do
        call check(t, e(2) < e(1) .and. e(3) < e(2) .and. e(3) < e(1)/3.0_dp, &
                   "microslip: the weighted residual converges to the reference as H grows", &
                   "errors at H = 10, 20, 40: "//real_text(e(1))//", "//real_text(e(2))// &
                   ", "//real_text(e(3)))
    end subroutine test_hbm

    !> &microslip in case files: a good 4-parameter and a good explicit joint are read into
    !> the model's law; each bad input is an input error (no crash) whose message names the
    !> file, &microslip and the variable.
    subroutine test_bad_input(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: system = "&system ndof = 2, mass = 1,0,0,1, "// &
            "stiffness = 2,-1,-1,1, damping = 0.1,0,0,0.1 /"
        character(len=*), parameter :: forcing = "&forcing omega = 1.2, force_dof = 1, "// &
            "force_amplitude = 0.3 /"
        character(len=*), parameter :: friction = "&friction contact_dof = 2, mu = 0.3, "// &
            "normal_load = 1 /"
        character(len=*), parameter :: free = "&friction contact_dof = 2, mu = 0, "// &
            "normal_load = 0 /"
        character(len=*), parameter :: two = "&friction contact_dof = 2, 1, mu = 0.3, 0.3, "// &
            "normal_load = 1, 1 /"
        type(case_t) :: c
        type(error_type), allocatable :: error
        real(dp), allocatable :: k(:), f(:)
        character(len=:), allocatable :: dir
        logical :: ok
        dir = scratch_dir()
        ! good input
        call read_lines("good_4p", friction, "contact = 1, stiffness = 2, chi = -0.5, "// &
                        "beta = 0.5, sliders = 6", c, error)
        call check_error(t, error, "microslip: a good 4-parameter joint is read", .false.)
        if (.not. allocated(error)) then
            call joint_sliders(k, f)
            ok = .false.
            if (allocated(c%model%laws)) then
                if (allocated(c%model%laws(1)%e)) then
                    select type (e => c%model%laws(1)%e)
                    type is (iwan_element_t)
                        ok = e%n == nsl .and. maxval(abs(e%k - k)) <= 1.0e-15_dp*kt .and. &
                             maxval(abs(e%f - f)) <= 1.0e-15_dp*fs
                    end select
                end if
            end if
            call check(t, ok, "microslip: the case's joint is the discretized 4-parameter model")
        end if
        call read_lines("good_explicit", free, "contact = 1, slider_stiffness = 1, 2, "// &
                        "slider_force = 0.1, 0.3", c, error)
        call check_error(t, error, "microslip: a good explicit joint is read", .false.)
        if (.not. allocated(error)) then
            ok = .false.
            if (allocated(c%model%laws)) then
                if (allocated(c%model%laws(1)%e)) then
                    select type (e => c%model%laws(1)%e)
                    type is (iwan_element_t)
                        ok = all(e%k == [1.0_dp, 2.0_dp]) .and. all(e%f == [0.1_dp, 0.3_dp])
                    end select
                end if
            end if
            call check(t, ok, "microslip: the case's explicit sliders")
        end if
        call echo("4p", friction, "contact = 1, stiffness = 2, chi = -0.5, beta = 0.5, "// &
                  "sliders = 6", "stiffness = ")
        call echo("explicit", free, "contact = 1, slider_stiffness = 1, 2, slider_force = "// &
                  "0.1, 0.3", "slider_force = ")
        ! bad input
        call bad("negative_stiffness", friction, "contact = 1, stiffness = -2", &
                 [character(len=40) :: "&microslip stiffness(1) = -2", "> 0"])
        call bad("chi_minus_one", friction, "contact = 1, stiffness = 2, chi = -1", &
                 [character(len=40) :: "&microslip chi(1) = -1", "(-1, 0]"])
        call bad("chi_positive", friction, "contact = 1, stiffness = 2, chi = 0.5", &
                 [character(len=40) :: "&microslip chi(1) = 0.5", "(-1, 0]"])
        call bad("beta_negative", friction, "contact = 1, stiffness = 2, beta = -0.1", &
                 [character(len=40) :: "&microslip beta(1) = -0.1", ">= 0"])
        call bad("no_sliders", friction, "contact = 1, stiffness = 2, sliders = 0", &
                 [character(len=40) :: "&microslip sliders(1) = 0", "1..10000"])
        call bad("force_not_increasing", free, "contact = 1, slider_stiffness = 1, 2, 3, "// &
                 "slider_force = 0.1, 0.3, 0.2", &
                 [character(len=40) :: "&microslip slider_force(3) = 0.2", "increase"])
        call bad("zero_slider_stiffness", free, "contact = 1, slider_stiffness = 1, 0, "// &
                 "slider_force = 0.1, 0.2", &
                 [character(len=40) :: "&microslip slider_stiffness(2) = 0", "> 0"])
        call bad("negative_slider_stiffness", free, "contact = 1, slider_stiffness = -1, "// &
                 "slider_force = 0.1", &
                 [character(len=40) :: "&microslip slider_stiffness(1) = -1", "> 0"])
        call bad("contact_range", friction, "contact = 3, stiffness = 2", &
                 [character(len=40) :: "&microslip contact(1) = 3", "not a contact"])
        call bad("contact_zero", friction, "contact = 0, stiffness = 2", &
                 [character(len=40) :: "&microslip contact(1) = 0", "not a contact"])
        call bad("contact_twice", two, "contact = 2, 2, stiffness = 2, 2", &
                 [character(len=40) :: "&microslip contact(1) = 2", "listed twice"])
        call bad("misspelled", friction, "contact = 1, stifness = 2", &
                 [character(len=40) :: "&microslip stifness", "unknown variable", &
                  "stiffness"])
        call bad("explicit_with_mu", friction, "contact = 1, slider_stiffness = 1, 2, "// &
                 "slider_force = 0.1, 0.3", &
                 [character(len=40) :: "&microslip contact(1) = 1", "mu = 0"])
        call bad("four_parameters_without_mu", free, "contact = 1, stiffness = 2", &
                 [character(len=40) :: "&microslip contact(1) = 1", "mu > 0"])

    contains

        !> write_case's &microslip (the form of the case, `key` in it) reads back as the same
        !> joint.
        subroutine echo(name, fr, ms, key)
            character(len=*), intent(in) :: name, fr, ms, key
            type(case_t) :: a, b
            type(error_type), allocatable :: error
            integer :: u, stat
            character(len=200) :: iomsg
            logical :: same
            call read_lines("echo_"//name, fr, ms, a, error)
            if (allocated(error)) return
            open (newunit=u, file=scratch//"/microslip_echo_"//name//"_back.nml", &
                  status='replace', action='write')
            call write_case(u, a, stat, iomsg)
            close (u)
            call read_case(scratch//"/microslip_echo_"//name//"_back.nml", b, error)
            call check_error(t, error, "microslip: the echo ("//name//") reads back", .false.)
            if (allocated(error)) return
            same = .false.
            select type (ea => a%model%laws(1)%e)
            type is (iwan_element_t)
                select type (eb => b%model%laws(1)%e)
                type is (iwan_element_t)
                    same = eb%n == ea%n .and. all(eb%k == ea%k) .and. all(eb%f == ea%f) .and. &
                           (eb%mu_n .eqv. ea%mu_n) .and. eb%mu == ea%mu .and. &
                           eb%normal == ea%normal
                end select
            end select
            call check(t, same .and. index(file_text(scratch//"/microslip_echo_"//name// &
                                                     "_back.nml"), key) > 0, &
                       "microslip: the echo ("//name//") is the same joint, in its form")
        end subroutine echo

        !> Write the case of the &friction line `fr` and `&microslip ms /` and read it.
        subroutine read_lines(name, fr, ms, c, error)
            character(len=*), intent(in) :: name, fr, ms
            type(case_t), intent(out) :: c
            type(error_type), allocatable, intent(out) :: error
            call write_lines(scratch//"/microslip_"//name//".nml", &
                             [character(len=200) :: system, forcing, fr, "&microslip "// &
                             ms//" /", "&run method = 'hbm' /"])
            call read_case(scratch//"/microslip_"//name//".nml", c, error)
        end subroutine read_lines

        subroutine bad(name, fr, ms, fragments)
            character(len=*), intent(in) :: name, fr, ms
            character(len=*), intent(in) :: fragments(:)
            type(case_t) :: c
            type(error_type), allocatable :: error
            character(len=200) :: expected(size(fragments) + 1)
            call read_lines("bad_"//name, fr, ms, c, error)
            expected(1) = "microslip_bad_"//name//".nml"
            expected(2:) = fragments
            call check_error(t, error, "microslip: bad input "//name, .true., expected)
            if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                             "microslip: bad input "//name//": stat input", &
                                             itoa(error%stat))
        end subroutine bad
    end subroutine test_bad_input
end module test_microslip
