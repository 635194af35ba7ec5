!> stickslip_contact_law against the laws themselves and against finite differences: Psi = 0
!> exactly on the Signorini-Coulomb set (closed with u_n = 0 and lambda >= 0, open with
!> lambda = 0 and u_n >= 0; stick with |r| <= mu lambda, slip opposite to the slider velocity
!> with |r| = mu lambda, in 1D and on the disk in 2D) and not off it; the Jacobians are the
!> derivatives of Psi away from the region boundaries; the 1D constant-load law is
!> stickslip_friction's psi bitwise.
module test_contact_law
    use stickslip_kinds, only: dp
    use stickslip_friction, only: psi
    use stickslip_contact_law, only: contact_law_t, contact_psi, contact_psi_jacobian, &
        contact_state, state_open, state_stick, state_slip
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t, validate_model
    use stickslip_contact_set, only: contact_set_t, new_contact_set, channel_directions
    use stickslip_contact_element, only: along_tangent, along_tangent2, along_normal
    use fixtures, only: seed_model
    use testing, only: test_counter_t, check
    implicit none
    private
    public :: run_contact_law_tests

contains

    subroutine run_contact_law_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_plain_is_psi(t)
        call test_zero_set(t)
        call test_jacobians(t)
        call test_states(t)
        call test_validation(t)
        call test_layout(t)
    end subroutine run_contact_law_tests

    !> validate_model on the contact-law data: each bad input is one message naming the
    !> variable (and the contact).
    subroutine test_validation(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: base, m
        type(error_type), allocatable :: error
        ! a 3-DOF model: DOF 1 and 2 tangential, DOF 3 normal, one contact
        base = seed_model()
        base%ndof = 3
        base%mass = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1]*1.0_dp, [3, 3])
        base%stiffness = reshape([2, -1, 0, -1, 2, 0, 0, 0, 1]*1.0_dp, [3, 3])
        base%damping = 0.0_dp*base%mass
        base%contact_dof = [1]
        base%contact_dof2 = [0]
        base%normal_load = [0.0_dp]
        allocate (base%normal_direction(3, 1))
        base%normal_direction = 0.0_dp
        base%normal_direction(3, 1) = 1.0_dp
        base%preload = [1.0_dp]
        m = base
        call validate_model(m, error)
        call check(t, .not. allocated(error), "contact_law: a unilateral contact validates")
        m = base
        m%normal_load = [1.0_dp]
        call expect(m, "model%normal_load(1) = 1", "is unilateral")
        m = base
        m%gap = [-1.0e-3_dp]
        m%preload = [0.0_dp]
        call expect(m, "model%gap(1) = ", "needs a preload")
        m = base
        m%normal_direction(1, 1) = 0.5_dp
        call expect(m, "model%normal_direction(:, 1)", "not orthogonal")
        m = base
        m%preload = [-1.0_dp]
        call expect(m, "model%preload(1) = -1", ">= 0")
        m = base
        m%tangential_stiffness = [1.0_dp, 2.0_dp]
        call expect(m, "model%tangential_stiffness: 2 entries", "one per contact")
        m = base
        allocate (m%tangent2_direction(3, 1))
        m%tangent2_direction = 0.0_dp
        m%tangent2_direction(2, 1) = 2.0_dp
        call expect(m, "model%tangent2_direction(:, 1): length 2", "equal")
        m%tangent2_direction(2, 1) = 1.0_dp
        m%tangent2_direction(1, 1) = 0.1_dp
        call expect(m, "model%tangent2_direction(:, 1)", "not orthogonal to the first")
        m = seed_model()
        m%gap = [0.1_dp]
        call expect(m, "model%gap(1): contact 1 has no normal direction", "normal_load")
        m = seed_model()
        m%normal_stiffness = [1.0e3_dp]
        call expect(m, "model%normal_stiffness(1): contact 1 has no normal", "normal_load")
    contains
        subroutine expect(model, head, part)
            type(model_t), intent(in) :: model
            character(len=*), intent(in) :: head, part
            type(error_type), allocatable :: err
            call validate_model(model, err)
            if (.not. allocated(err)) then
                call check(t, .false., "contact_law: rejected: "//head, "no error")
                return
            end if
            call check(t, index(err%message, head) == 1 .and. index(err%message, part) > 0, &
                       "contact_law: rejected: "//head, err%message)
        end subroutine expect
    end subroutine test_validation

    !> The channel layout: a plain model has one channel per contact; laws add channels in
    !> the order [w, t, n], and channel_directions holds their directions.
    subroutine test_layout(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(contact_set_t) :: cs
        type(error_type), allocatable :: error
        real(dp), allocatable :: d(:, :)
        integer :: i
        m = seed_model()
        call new_contact_set(cs, m)
        call check(t, cs%coulomb_only .and. cs%nchannel == 1 .and. cs%normal(1) == 0 .and. &
                   cs%elements(1)%e%law_name() == 'coulomb', &
                   "contact_law: a Coulomb contact is one channel")
        m%ndof = 4
        m%mass = 0.0_dp*reshape([(1.0_dp, i=1, 16)], [4, 4])
        do i = 1, 4
            m%mass(i, i) = 1.0_dp
        end do
        m%stiffness = 2.0_dp*m%mass
        m%damping = 0.0_dp*m%mass
        m%contact_dof = [1, 2]
        m%contact_dof2 = [0, 0]
        m%mu = [0.3_dp, 0.5_dp]
        m%normal_load = [1.0_dp, 0.0_dp]
        allocate (m%normal_direction(4, 2), m%tangent2_direction(4, 2))
        m%normal_direction = 0.0_dp
        m%normal_direction(4, 2) = -1.0_dp
        m%tangent2_direction = 0.0_dp
        m%tangent2_direction(3, 2) = 1.0_dp
        m%preload = [0.0_dp, 2.0_dp]
        m%tangential_stiffness = [0.0_dp, 10.0_dp]
        call validate_model(m, error)
        call check(t, .not. allocated(error), "contact_law: a mixed model validates")
        call new_contact_set(cs, m)
        d = channel_directions(m, cs)
        call check(t, .not. cs%coulomb_only .and. cs%nchannel == 4 .and. &
                   all(cs%first == [1, 2]) .and. all(cs%normal == [0, 4]) .and. &
                   all(cs%ntangent == [1, 2]) .and. &
                   all(cs%along == [along_tangent, along_tangent, along_tangent2, &
                                    along_normal]) .and. all(cs%contact_of == [1, 2, 2, 2]), &
                   "contact_law: the channels of a mixed model")
        call check(t, d(1, 1) == 1.0_dp .and. d(2, 2) == 1.0_dp .and. d(3, 3) == 1.0_dp .and. &
                   d(4, 4) == -1.0_dp .and. sum(abs(d)) == 4.0_dp, &
                   "contact_law: channel directions w, t, n")
        call check(t, cs%elements(1)%e%force_scale() == 0.3_dp .and. &
                   cs%elements(2)%e%force_scale() == 2.0_dp .and. &
                   cs%elements(2)%e%law_name() == 'unilateral' .and. &
                   cs%elements(2)%e%preload() == 2.0_dp .and. &
                   cs%elements(1)%e%law_name() == 'coulomb', &
                   "contact_law: limits and laws of the contacts")
    end subroutine test_layout

    !> One tangential channel under a constant load: contact_psi is psi, bitwise.
    subroutine test_plain_is_psi(t)
        type(test_counter_t), intent(inout) :: t
        type(contact_law_t) :: law
        real(dp) :: x(2), p(1)
        integer :: i, bad
        law%mu = 0.45_dp
        law%normal_load = 1.3_dp
        bad = 0
        do i = 1, 500
            call random_number(x)
            x = 2.0_dp*x - 1.0_dp
            call contact_psi(law, 0.2_dp, [x(1)], [x(2)], p)
            if (p(1) /= psi(x(1), x(2), law%mu*law%normal_load, 0.2_dp)) bad = bad + 1
        end do
        call check(t, bad == 0, "contact_law: 1D constant load is psi bitwise")
    end subroutine test_plain_is_psi

    !> Psi = 0 on the law's set, for several rho; nonzero off it.
    subroutine test_zero_set(t)
        type(test_counter_t), intent(inout) :: t
        type(contact_law_t) :: l1, l2, l1n, l2n
        real(dp), parameter :: mu = 0.6_dp, rhos(3) = [1.0e-3_dp, 0.3_dp, 40.0_dp]
        real(dp) :: x(6), lam, p(3), ang, speed, r(3), u(3)
        integer :: i, k, bad_on, bad_off
        l1%mu = mu
        l1%normal_load = 2.0_dp
        l2 = l1
        l2%ntangent = 2
        l1n%mu = mu
        l1n%unilateral = .true.
        l2n = l1n
        l2n%ntangent = 2
        bad_on = 0
        bad_off = 0
        do k = 1, size(rhos)
            do i = 1, 300
                call random_number(x)
                lam = 3.0_dp*x(1) + 1.0e-3_dp
                ang = 6.283185307179586_dp*x(2)
                speed = 5.0_dp*x(3) + 1.0e-3_dp
                ! 1D unilateral: closed and stuck, closed and slipping, open
                call contact_psi(l1n, rhos(k), [mu*lam*(2*x(4) - 1), lam], [0.0_dp, 0.0_dp], p)
                if (any(p(1:2) /= 0.0_dp)) bad_on = bad_on + 1
                call contact_psi(l1n, rhos(k), [-mu*lam, lam], [speed, 0.0_dp], p)
                if (any(p(1:2) /= 0.0_dp)) bad_on = bad_on + 1
                call contact_psi(l1n, rhos(k), [0.0_dp, 0.0_dp], [speed*(2*x(5) - 1), speed], p)
                if (any(p(1:2) /= 0.0_dp)) bad_on = bad_on + 1
                ! 2D constant load: stuck inside the disk, slipping on its edge
                r(1:2) = mu*2.0_dp*x(4)*[cos(ang), sin(ang)]
                call contact_psi(l2, rhos(k), r(1:2), [0.0_dp, 0.0_dp], p)
                if (any(p(1:2) /= 0.0_dp)) bad_on = bad_on + 1
                u(1:2) = speed*[cos(ang), sin(ang)]
                call contact_psi(l2, rhos(k), -mu*2.0_dp*[cos(ang), sin(ang)], u(1:2), p)
                if (maxval(abs(p(1:2))) > 1.0e-15_dp*rhos(k)*mu*2.0_dp + 1.0e-15_dp*speed) &
                    bad_on = bad_on + 1
                ! 2D unilateral, closed and slipping; open
                call contact_psi(l2n, rhos(k), [-mu*lam*cos(ang), -mu*lam*sin(ang), lam], &
                                 [u(1), u(2), 0.0_dp], p)
                if (maxval(abs(p)) > 1.0e-15_dp*(rhos(k)*mu*lam + speed)) bad_on = bad_on + 1
                call contact_psi(l2n, rhos(k), [0.0_dp, 0.0_dp, 0.0_dp], [u(1), u(2), x(6)], p)
                if (any(p /= 0.0_dp)) bad_on = bad_on + 1
                ! off the set: penetration, a pulling normal force, slip with a force below
                ! the limit, a force off the slip direction, a stuck force beyond the disk
                call contact_psi(l1n, rhos(k), [0.0_dp, lam], [0.0_dp, -speed], p)
                if (p(2) == 0.0_dp) bad_off = bad_off + 1
                call contact_psi(l1n, rhos(k), [0.0_dp, -lam], [0.0_dp, 0.0_dp], p)
                if (p(2) == 0.0_dp) bad_off = bad_off + 1
                call contact_psi(l1n, rhos(k), [-0.5_dp*mu*lam, lam], [speed, 0.0_dp], p)
                if (p(1) == 0.0_dp) bad_off = bad_off + 1
                call contact_psi(l2, rhos(k), -mu*2.0_dp*[cos(ang + 0.3_dp), &
                                 sin(ang + 0.3_dp)], u(1:2), p)
                if (all(p(1:2) == 0.0_dp)) bad_off = bad_off + 1
                call contact_psi(l2, rhos(k), (mu*2.0_dp*(1.0_dp + x(4)) + 1.0e-3_dp)* &
                                 [cos(ang), sin(ang)], [0.0_dp, 0.0_dp], p)
                if (all(p(1:2) == 0.0_dp)) bad_off = bad_off + 1
            end do
        end do
        call check(t, bad_on == 0, "contact_law: Psi = 0 on the Signorini-Coulomb set")
        call check(t, bad_off == 0, "contact_law: Psi /= 0 off the set")
    end subroutine test_zero_set

    !> Central differences of Psi in r and u at random points (every law, 1D/2D, constant
    !> load or unilateral) away from the region boundaries.
    subroutine test_jacobians(t)
        type(test_counter_t), intent(inout) :: t
        type(contact_law_t) :: law
        real(dp), parameter :: rho = 0.3_dp, h = 1.0e-7_dp
        real(dp) :: x(6), r(3), u(3), p(3), pp(3), pm(3), jr(3, 3), ju(3, 3), fd(3), err
        integer :: kind, i, m, c, bad, n, states(0:2)
        character(len=40) :: name
        do kind = 1, 4
            law = contact_law_t()
            law%mu = 0.5_dp
            law%normal_load = 1.0_dp
            law%ntangent = 1 + merge(1, 0, kind >= 3)
            law%unilateral = mod(kind, 2) == 0
            m = law%ntangent + merge(1, 0, law%unilateral)
            bad = 0
            n = 0
            states = 0
            do i = 1, 800
                call random_number(x)
                r(1:m) = 2.0_dp*(2.0_dp*x(1:m) - 1.0_dp)
                u(1:m) = 0.8_dp*(2.0_dp*x(4:3 + m) - 1.0_dp)
                if (law%unilateral) r(m) = 2.0_dp*x(m)
                if (near_kink(law, r(1:m), u(1:m))) cycle
                n = n + 1
                states(contact_state(law, rho, r(1:m), u(1:m))) = &
                    states(contact_state(law, rho, r(1:m), u(1:m))) + 1
                call contact_psi_jacobian(law, rho, r(1:m), u(1:m), p(1:m), jr(1:m, 1:m), &
                                          ju(1:m, 1:m))
                err = 0.0_dp
                do c = 1, m
                    r(c) = r(c) + h
                    call contact_psi(law, rho, r(1:m), u(1:m), pp(1:m))
                    r(c) = r(c) - 2*h
                    call contact_psi(law, rho, r(1:m), u(1:m), pm(1:m))
                    r(c) = r(c) + h
                    fd(1:m) = (pp(1:m) - pm(1:m))/(2*h)
                    err = max(err, maxval(abs(fd(1:m) - jr(1:m, c))))
                    u(c) = u(c) + h
                    call contact_psi(law, rho, r(1:m), u(1:m), pp(1:m))
                    u(c) = u(c) - 2*h
                    call contact_psi(law, rho, r(1:m), u(1:m), pm(1:m))
                    u(c) = u(c) + h
                    fd(1:m) = (pp(1:m) - pm(1:m))/(2*h)
                    err = max(err, maxval(abs(fd(1:m) - ju(1:m, c))))
                end do
                if (err > 1.0e-6_dp) bad = bad + 1
            end do
            write (name, '(a,i0,a,l1)') "ntangent ", law%ntangent, ", unilateral ", law%unilateral
            call check(t, bad == 0 .and. n > 300, "contact_law: Jacobian = central "// &
                       "differences, "//trim(name))
            ! every region visited
            call check(t, states(state_stick) > 10 .and. states(state_slip) > 10 .and. &
                       (states(state_open) > 10 .or. .not. law%unilateral), &
                       "contact_law: every region sampled, "//trim(name))
        end do
    end subroutine test_jacobians

    !> A point within 1e-5 of a region boundary of the law (where Psi has a kink).
    logical function near_kink(law, r, u)
        type(contact_law_t), intent(in) :: law
        real(dp), intent(in) :: r(:), u(:)
        real(dp), parameter :: rho = 0.3_dp, eps = 1.0e-5_dp
        real(dp) :: g
        integer :: m
        m = law%ntangent
        g = law%mu*law%normal_load
        if (law%unilateral) then
            g = law%mu*max(r(m + 1), 0.0_dp)
            near_kink = abs(u(m + 1) - rho*r(m + 1)) < eps .or. abs(r(m + 1)) < eps
            if (near_kink) return
        end if
        if (m == 1) then
            near_kink = min(abs(rho*(r(1) + g) - u(1)), abs(rho*(r(1) - g) - u(1))) < eps
        else
            near_kink = abs(norm2(rho*r(1:2) - u(1:2)) - rho*g) < eps .or. &
                        norm2(rho*r(1:2) - u(1:2)) < eps
        end if
    end function near_kink

    !> contact_state on the closed forms: open, stuck, slipping.
    subroutine test_states(t)
        type(test_counter_t), intent(inout) :: t
        type(contact_law_t) :: law
        law%mu = 0.5_dp
        law%unilateral = .true.
        law%ntangent = 2
        call check(t, contact_state(law, 0.3_dp, [0.0_dp, 0.0_dp, 0.0_dp], &
                                    [0.1_dp, 0.2_dp, 0.5_dp]) == state_open, &
                   "contact_law: an open contact is open")
        call check(t, contact_state(law, 0.3_dp, [0.1_dp, 0.1_dp, 1.0_dp], &
                                    [0.0_dp, 0.0_dp, 0.0_dp]) == state_stick, &
                   "contact_law: a closed contact inside the disk sticks")
        call check(t, contact_state(law, 0.3_dp, [-0.5_dp, 0.0_dp, 1.0_dp], &
                                    [1.0_dp, 0.0_dp, 0.0_dp]) == state_slip, &
                   "contact_law: a closed contact on the disk's edge slips")
    end subroutine test_states
end module test_contact_law
