!> The exact event-driven reference with contact laws (doc/contacts.md, section 5) against
!> independent truth: a unilateral contact that never opens gives the constant-load
!> reference (rigid: the seed's; elastic: the load of the static spring share); a contact
!> that lifts off keeps the energy balance over a period (with the impact losses of a rigid
!> contact), the normal law and Coulomb's law with the varying limit at every sample; its
!> monodromy matrix is the central difference of the period map; the weighted residual
!> converges to it as harmonics are added (elastic contact) and implicit Euler at first
!> order (rigid contact, impacts; a Jenkins element on it). What it handles is said (2D
!> friction: test_reference_2d, on a rigid unilateral contact: test_impacts_2d, behind a
!> tangential stiffness on an elastic one: test_reference_2d, on a rigid one:
!> test_impacts_2d): every law, none refused.
module test_contact_reference
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, real_text
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_result_t, sample_reference, reference_handles, &
        reference_energy_error
    use stickslip_reference_start, only: solve_reference_from_starts, reference_start_options_t
    use stickslip_flow, only: flow_t
    use stickslip_contact_law, only: state_open, state_stick, state_slip
    use stickslip_diagnostics, only: level_warning
    use fixtures, only: seed_model, unilateral_seed, liftoff_model, planar_model, &
        liftoff_2d_model
    use testing, only: test_counter_t, check, check_error
    use test_jenkins, only: central_differences
    use test_reference_2d, only: test_euler_first_order_2d => test_euler_first_order, &
        compare_monodromy
    implicit none
    private
    public :: run_contact_reference_tests

contains

    subroutine run_contact_reference_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: elastic, rigid
        call test_never_opens(t)
        call solved(t, liftoff_model(10.0_dp, 0.0_dp), elastic, "elastic lift-off", 'hbm')
        if (elastic%converged) then
            call test_monodromy(t, elastic, "elastic lift-off")
            call test_hbm_converges(t, elastic)
        end if
        call solved(t, liftoff_model(0.0_dp, 0.0_dp), rigid, "rigid lift-off", 'euler')
        if (rigid%converged) then
            call check(t, rigid%impact_loss > 0.01_dp*rigid%work_forcing .and. &
                       any(rigid%event_kind(1:rigid%nevent) == 12), &
                       "contact_reference: rigid lift-off: an impact, its loss in the balance")
            call test_monodromy(t, rigid, "rigid lift-off")
            call test_euler_first_order(t, rigid)
        end if
        call test_jenkins_liftoff(t)
        call test_jenkins_rigid(t)
        call test_support(t)
    end subroutine run_contact_reference_tests

    !> A tangential stiffness on the elastic lift-off (k_n = 2, k_t = 5: a Jenkins element
    !> that lifts off, its slider a state of the flow; at k_n = 10 the orbit is flip-unstable,
    !> multiplier -4.0, and Euler from rest never settles): converged with the energy balance;
    !> at every sample the spring's law where stuck (r = -k_t (x_1 - s)), the force on the
    !> limit mu lambda where slipping and zero where open; the monodromy of [x; v; s]
    !> against central differences at the most open instant (there the slider is unloaded:
    !> the period map is smooth); implicit Euler converging to it at first order (from
    !> rest, 1000, 4000, 16000 steps: the error falls by more than 2.5 per step); the weighted
    !> residual converging as H grows (10, 20, 40).
    subroutine test_jenkins_liftoff(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        type(flow_t) :: flow
        type(error_type), allocatable :: error
        type(euler_options_t) :: eo
        type(euler_result_t) :: e
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        real(dp), allocatable :: z0(:), z1(:), fd(:, :), mono(:, :), xr(:, :), vr(:, :), &
                                 rr(:, :)
        real(dp) :: worst, err(3), eh(3)
        integer :: k, nz
        character(len=120) :: buf
        call solved(t, liftoff_model(2.0_dp, 5.0_dp), res, "Jenkins lift-off", 'hbm')
        if (.not. res%converged) return
        worst = jenkins_law_error(res, .false.)
        call check(t, worst <= 1.0e-9_dp .and. any(res%state(:, 1) == state_stick) .and. &
                   any(res%state(:, 1) == state_slip), "contact_reference: Jenkins "// &
                   "lift-off: the spring where stuck, the limit where slipping, 0 where open", &
                   real_text(worst))
        ! the monodromy at the most open instant
        flow = res%flow
        nz = flow%nz
        call check(t, nz == 5, "contact_reference: Jenkins lift-off: the slider in the state")
        k = maxloc(res%gap(:, 1), 1)
        z0 = [res%x(k, :), res%v(k, :), res%s(k, :)]
        allocate (z1(nz), mono(nz, nz))
        call flow%period_map(res%t(k), z0, z1, error, mono=mono)
        if (.not. allocated(error)) call central_differences(flow, res%t(k), z0, fd, error)
        call check_error(t, error, "contact_reference: Jenkins lift-off: period maps", .false.)
        if (allocated(error)) return
        worst = maxval(abs(fd - mono))/maxval(abs(mono))
        call check(t, worst <= 1.0e-5_dp, "contact_reference: Jenkins lift-off: monodromy "// &
                   "= central differences of the period map", real_text(worst))
        ! implicit Euler, from rest
        do k = 1, 3
            eo%steps_per_period = 1000*4**(k - 1)
            call integrate_euler(liftoff_model(2.0_dp, 5.0_dp), eo, e, error)
            if (allocated(error)) then
                call check_error(t, error, "contact_reference: Jenkins lift-off: Euler", .false.)
                return
            end if
            if (.not. e%periodic) then
                call check(t, .false., "contact_reference: Jenkins lift-off: Euler periodic", &
                           e%diagnosis)
                return
            end if
            call sample_reference(res, eo%steps_per_period, xr, vr, rr, error)
            if (allocated(error)) return
            err(k) = maxval(abs(e%x - xr))/maxval(abs(xr))
        end do
        write (buf, '(3es10.2)') err
        call check(t, err(2) < err(1)/2.5_dp .and. err(3) < err(2)/2.5_dp, &
                   "contact_reference: Jenkins lift-off: implicit Euler converges to the "// &
                   "reference at first order", buf)
        ! the weighted residual
        call sample_reference(res, 512, xr, vr, rr, error)
        if (allocated(error)) return
        do k = 1, 3
            ho%harmonics = 10*2**(k - 1)
            ho%samples = 512
            call solve_periodic(liftoff_model(2.0_dp, 5.0_dp), ho, sol, error)
            if (allocated(error) .or. .not. sol%converged) then
                call check(t, .false., "contact_reference: Jenkins lift-off: weighted "// &
                           "residual converged")
                return
            end if
            eh(k) = maxval(abs(sol%x - xr))/maxval(abs(xr))
        end do
        write (buf, '(3es10.2)') eh
        call check(t, eh(2) < eh(1) .and. eh(3) < eh(2), "contact_reference: Jenkins "// &
                   "lift-off: the weighted residual converges to the reference", buf)
    end subroutine test_jenkins_liftoff

    !> A tangential stiffness on the rigid lift-off (k_t = 5: a Jenkins element on a rigid
    !> normal; its impacts frictionless, the spring carrying no impulse; slipping, the spring
    !> follows the constraint force, s' = w^T v - c mu lambda' / k_t): converged with the
    !> energy balance (impact losses included); at every sample the spring's law where
    !> stuck, the force on the limit where slipping, none where open; the monodromy of [x;
    !> v; s] against central differences at the section; implicit Euler started on the
    !> orbit converging to it at first order (1000, 10000, 100000 steps: the error falls by
    !> 5 to 20 per decade).
    subroutine test_jenkins_rigid(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        type(flow_t) :: flow
        real(dp) :: worst
        call solved(t, liftoff_model(0.0_dp, 5.0_dp), res, "Jenkins rigid lift-off", 'euler')
        if (.not. res%converged) return
        worst = jenkins_law_error(res, .true.)
        call check(t, worst <= 1.0e-9_dp .and. any(res%state(:, 1) == state_stick) .and. &
                   any(res%state(:, 1) == state_slip) .and. res%impact_loss > 0.0_dp, &
                   "contact_reference: Jenkins rigid lift-off: impacts; the spring where "// &
                   "stuck, on the limit where slipping, 0 where open", real_text(worst))
        flow = res%flow
        call check(t, flow%nz == 5, "contact_reference: Jenkins rigid lift-off: the slider "// &
                   "in the state")
        call compare_monodromy(t, flow, res%t_section, res%orbit%phase_y(1:flow%nz, 1), &
                               "Jenkins rigid lift-off, at the section", res%monodromy)
        ! implicit Euler started on the orbit at t = 0, where the contact is open (the
        ! spring unloaded, as Euler starts it), over two periods
        call check(t, res%state(1, 1) == state_open, "contact_reference: Jenkins rigid "// &
                   "lift-off: open at t = 0")
        call test_euler_first_order_2d(t, res, liftoff_model(0.0_dp, 5.0_dp), &
                                       "Jenkins rigid lift-off")
    end subroutine test_jenkins_rigid

    !> The worst violation of the Jenkins element's law (k_t = 5, mu = 0.5) at the samples
    !> of a lift-off reference: open, no force; stuck, the spring r = -k_t (x_1 - s);
    !> slipping, the spring on the limit mu lambda; on a rigid normal the gap zero when
    !> closed [N or m].
    real(dp) function jenkins_law_error(res, rigid) result(worst)
        type(reference_result_t), intent(in) :: res
        logical, intent(in) :: rigid
        real(dp) :: spring
        integer :: k
        worst = 0.0_dp
        do k = 1, size(res%t)
            spring = abs(res%r(k, 1) + 5.0_dp*(res%x(k, 1) - res%s(k, 1)))
            select case (res%state(k, 1))
            case (state_open)
                worst = max(worst, abs(res%r(k, 1)), abs(res%normal(k, 1)))
                cycle
            case (state_stick)
                worst = max(worst, spring)
            case default
                worst = max(worst, abs(abs(res%r(k, 1)) - 0.5_dp*res%normal(k, 1)), spring)
            end select
            if (rigid) worst = max(worst, abs(res%gap(k, 1)))
        end do
    end function jenkins_law_error

    !> Solve the reference of `m`: converged, the energy balance (impact losses included),
    !> no finding above a warning (the normal law, Coulomb's law with the varying limit),
    !> the contact open part of the period.
    subroutine solved(t, m, res, name, start)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(out) :: res
        character(len=*), intent(in) :: name, start
        type(reference_start_options_t) :: o
        type(error_type), allocatable :: error
        o%samples = 512
        o%start = start
        call solve_reference_from_starts(m, o, res, error)
        call check_error(t, error, "contact_reference: "//name//": no error", .false.)
        if (allocated(error)) return
        call check(t, res%converged .and. res%defect <= o%tol, "contact_reference: "// &
                   name//": converged", res%diagnosis)
        if (.not. res%converged) return
        call check(t, res%work_forcing > 0.0_dp .and. &
                   reference_energy_error(res) < 1.0e-9_dp, &
                   "contact_reference: "//name//": energy balance over a period")
        call check(t, res%diagnostics%worst() < level_warning, "contact_reference: "// &
                   name//": normal law and Coulomb's law hold at the samples")
        call check(t, res%open_fraction(1) > 0.3_dp .and. res%open_fraction(1) < 0.9_dp .and. &
                   any(res%state(:, 1) == state_open) .and. &
                   abs(real(count(res%state(:, 1) == state_open), dp)/size(res%t) - &
                       res%open_fraction(1)) < 0.01_dp, &
                   "contact_reference: "//name//": open part of the period")
    end subroutine solved

    !> A unilateral contact pressed by a preload 1 on a normal DOF of its own (spring 5)
    !> never opens: rigid, it carries lambda = 1 and the reference is the seed's; elastic
    !> (k_n = 20) it carries the spring share 20 / 25 of the preload and the reference is
    !> the seed's with that normal load.
    subroutine test_never_opens(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: plain
        real(dp) :: kn
        integer :: k
        do k = 1, 2
            kn = merge(0.0_dp, 20.0_dp, k == 1)
            plain = seed_model()
            if (kn > 0.0_dp) plain%normal_load = [kn/(5.0_dp + kn)]
            call compare(plain, unilateral_seed(kn), merge("rigid  ", "elastic", k == 1))
        end do

    contains

        subroutine compare(plain, uni, name)
            type(model_t), intent(in) :: plain, uni
            character(len=*), intent(in) :: name
            type(reference_start_options_t) :: o
            type(reference_result_t) :: rp, ru
            type(error_type), allocatable :: error
            o%samples = 256
            call solve_reference_from_starts(plain, o, rp, error)
            if (allocated(error)) return
            call solve_reference_from_starts(uni, o, ru, error)
            call check_error(t, error, "contact_reference: never opens ("//trim(name)// &
                             "): solved", .false.)
            if (allocated(error)) return
            call check(t, rp%converged .and. ru%converged .and. &
                       maxval(abs(ru%x(:, 1:2) - rp%x)) <= 1.0e-8_dp*maxval(abs(rp%x)) .and. &
                       maxval(abs(ru%r(:, 1) - rp%r(:, 1))) <= 1.0e-8_dp* &
                       maxval(abs(rp%r(:, 1))), "contact_reference: a contact that never "// &
                       "opens ("//trim(name)//") is the constant-load reference", ru%diagnosis)
            call check(t, maxval(abs(ru%normal(:, 1) - plain%normal_load(1))) <= 1.0e-8_dp &
                       .and. ru%open_fraction(1) == 0.0_dp .and. ru%impact_loss == 0.0_dp, &
                       "contact_reference: never opens ("//trim(name)//"): the normal force "// &
                       "of the static share, closed all period")
        end subroutine compare
    end subroutine test_never_opens

    !> The monodromy matrix of the shooting's recording pass against central differences
    !> of the period map from the section state (saltation matrices at open, close and slip
    !> events; the jump Jacobian at an impact).
    subroutine test_monodromy(t, res, name)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        character(len=*), intent(in) :: name
        type(flow_t) :: flow
        type(error_type), allocatable :: error
        real(dp), allocatable :: z0(:), fd(:, :)
        integer :: nz
        flow = res%flow
        nz = 2*flow%n
        z0 = res%orbit%phase_y(1:nz, 1)
        call central_differences(flow, res%t_section, z0, fd, error)
        call check_error(t, error, "contact_reference: "//name//": perturbed period maps", &
                         .false.)
        if (allocated(error)) return
        call check(t, maxval(abs(fd - res%monodromy)) <= 1.0e-5_dp*maxval(abs(res%monodromy)), &
                   "contact_reference: "//name//": monodromy = central differences of the "// &
                   "period map")
    end subroutine test_monodromy

    !> The weighted residual on the elastic lift-off converges to the reference: the
    !> displacement error falls as H goes 10, 20, 40 and is below 2% at H = 40.
    subroutine test_hbm_converges(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: e(3)
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        integer :: k
        call sample_reference(res, 512, xr, vr, rr, error)
        if (allocated(error)) return
        do k = 1, 3
            o%harmonics = 10*2**(k - 1)
            o%samples = 512
            o%want_samples = .true.
            call solve_periodic(liftoff_model(10.0_dp, 0.0_dp), o, sol, error)
            if (allocated(error) .or. .not. sol%converged) then
                call check(t, .false., "contact_reference: weighted residual H = 10, 20, 40 "// &
                           "converged")
                return
            end if
            e(k) = maxval(abs(sol%x - xr))/maxval(abs(xr))
        end do
        call check(t, e(2) < e(1) .and. e(3) < e(2) .and. e(3) < 0.02_dp, &
                   "contact_reference: the weighted residual converges to the reference "// &
                   "as harmonics are added (elastic lift-off)")
    end subroutine test_hbm_converges

    !> Implicit Euler on the rigid lift-off (plastic impacts) converges to the reference at
    !> first order: its max displacement error falls by at least 2.5 when the step is
    !> divided by 4 (measured: 1.4e-2 and 3.4e-3 at 1000 and 4000 steps; the bound 5e-3 on
    !> the second only catches a wrong limit).
    subroutine test_euler_first_order(t, res)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        type(euler_options_t) :: o
        type(euler_result_t) :: e
        type(error_type), allocatable :: error
        real(dp) :: err(2)
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        integer :: k
        character(len=80) :: buf
        do k = 1, 2
            o%steps_per_period = 1000*4**(k - 1)
            call integrate_euler(liftoff_model(0.0_dp, 0.0_dp), o, e, error)
            if (allocated(error) .or. .not. e%periodic) then
                call check(t, .false., "contact_reference: rigid lift-off: Euler periodic")
                return
            end if
            call sample_reference(res, o%steps_per_period, xr, vr, rr, error)
            if (allocated(error)) return
            err(k) = maxval(abs(e%x - xr))/maxval(abs(xr))
        end do
        write (buf, '(2es10.2)') err
        call check(t, err(2) < err(1)/2.5_dp .and. err(2) < 5.0e-3_dp, &
                   "contact_reference: implicit Euler converges to the rigid lift-off "// &
                   "reference at first order", buf)
    end subroutine test_euler_first_order

    !> What the exact reference handles: 2D friction (its slip phases integrated
    !> numerically, test_reference_2d), on a unilateral contact too, 1D unilateral contacts,
    !> a tangential stiffness on an elastic or a rigid one, 2D friction behind a tangential
    !> stiffness on either.
    subroutine test_support(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: why
        type(model_t) :: m
        call check(t, reference_handles(planar_model(1.0_dp, 0.5_dp, 0.0_dp), why) .and. &
                   len(why) == 0, "contact_reference: 2D friction is handled", why)
        call check(t, reference_handles(planar_model(1.0_dp, 0.5_dp, 2.0_dp), why) .and. &
                   len(why) == 0, "contact_reference: a 2D Jenkins element is handled", why)
        call check(t, reference_handles(liftoff_model(10.0_dp, 5.0_dp), why) .and. &
                   len(why) == 0, "contact_reference: a tangential stiffness on an elastic "// &
                   "unilateral contact is handled", why)
        call check(t, reference_handles(liftoff_model(0.0_dp, 5.0_dp), why) .and. &
                   len(why) == 0, "contact_reference: a tangential stiffness on a rigid "// &
                   "unilateral contact is handled", why)
        call check(t, reference_handles(liftoff_model(10.0_dp, 0.0_dp), why) .and. &
                   len(why) == 0, "contact_reference: 1D unilateral contacts are handled")
        m = liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp)
        call check(t, reference_handles(m, why) .and. len(why) == 0, "contact_reference: "// &
                   "2D friction on an elastic unilateral contact is handled", why)
        m%normal_stiffness = [0.0_dp]
        call check(t, reference_handles(m, why) .and. len(why) == 0, "contact_reference: "// &
                   "2D friction on a rigid unilateral contact (impacts) is handled", why)
        m = liftoff_2d_model(0.3_dp, 0.15_dp, 1.0_dp)
        m%tangential_stiffness = [5.0_dp]
        call check(t, reference_handles(m, why) .and. len(why) == 0, "contact_reference: "// &
                   "2D friction behind a tangential stiffness on an elastic unilateral "// &
                   "contact is handled", why)
        m%normal_stiffness = [0.0_dp]
        call check(t, reference_handles(m, why) .and. len(why) == 0, "contact_reference: "// &
                   "2D friction behind a tangential stiffness on a rigid unilateral contact "// &
                   "is handled", why)
    end subroutine test_support
end module test_contact_reference
