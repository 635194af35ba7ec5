!> The weighted residual with contact laws (doc/contacts.md) against independent truth: the
!> exact generalized Jacobian against central differences for every law (unilateral rigid
!> and elastic, 1D and 2D, Jenkins 1D and 2D, mixed with a plain contact), the dense and
!> the sparse condensation equal; a unilateral contact that never opens reproduces the
!> constant-load answer to roundoff; a contact that opens part of the period balances its
!> energy and keeps the normal law; the circular 2D slip of a point mass against its closed
!> form; the elliptical path's energy and force on the disk's edge; Jenkins: stuck, the
!> linear structure with the spring k_t; stiff, the rigid answer.
module test_contact_hbm
    use stickslip_kinds, only: dp, pi
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem, new_condensed_problem
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets
    use stickslip_sparse_model, only: sparse_model_t
    use stickslip_sparse_dynamics, only: new_sparse_dynamics
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_contact_law, only: state_open, state_stick, state_slip
    use stickslip_lapack, only: dgesv
    use fixtures, only: seed_model, unilateral_seed, liftoff_model, planar_model
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_contact_hbm_tests

contains

    subroutine run_contact_hbm_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_jacobians(t)
        call test_sparse_equals_dense(t)
        call test_never_opens(t)
        call test_liftoff(t)
        call test_circle(t)
        call test_ellipse(t)
        call test_jenkins(t)
    end subroutine run_contact_hbm_tests

    !> A model with two contacts: contact 1 plain on DOF 1, contact 2 on DOF 2 with the laws
    !> asked for (a second tangential direction on DOF 3, a normal on DOF 4).
    function mixed_model(planar, unilateral, kn, kt) result(m)
        logical, intent(in) :: planar, unilateral
        real(dp), intent(in) :: kn, kt
        type(model_t) :: m
        integer :: i
        m%ndof = 4
        allocate (m%mass(4, 4), m%stiffness(4, 4))
        m%mass = 0.0_dp
        m%stiffness = 0.0_dp
        do i = 1, 4
            m%mass(i, i) = 1.0_dp + 0.1_dp*i
            m%stiffness(i, i) = 2.0_dp + 0.5_dp*i
        end do
        m%stiffness(1, 2) = -0.7_dp
        m%stiffness(2, 1) = -0.7_dp
        m%stiffness(2, 4) = -0.4_dp
        m%stiffness(4, 2) = -0.4_dp
        m%stiffness(3, 4) = -0.3_dp
        m%stiffness(4, 3) = -0.3_dp
        m%damping = 0.03_dp*m%mass + 0.01_dp*m%stiffness
        m%omega = 1.3_dp
        m%force_dof = [1, 3, 4]
        m%force_harmonic = [1, 1, 2]
        m%force_amplitude = [1.0_dp, 0.7_dp, 0.9_dp]
        m%force_phase = [0.0_dp, 0.5_dp, 0.2_dp]
        m%contact_dof = [1, 2]
        m%contact_dof2 = [0, 0]
        m%mu = [0.3_dp, 0.5_dp]
        m%normal_load = [0.4_dp, merge(0.0_dp, 0.6_dp, unilateral)]
        allocate (m%normal_direction(4, 2), m%tangent2_direction(4, 2))
        m%normal_direction = 0.0_dp
        m%tangent2_direction = 0.0_dp
        if (unilateral) m%normal_direction(4, 2) = 1.0_dp
        if (planar) m%tangent2_direction(3, 2) = 1.0_dp
        m%preload = [0.0_dp, merge(0.8_dp, 0.0_dp, unilateral)]
        m%normal_stiffness = [0.0_dp, merge(kn, 0.0_dp, unilateral)]
        m%tangential_stiffness = [0.0_dp, kt]
    end function mixed_model

    !> Central differences of the residual against the exact Jacobian at random points whose
    !> samples visit the open, stick and slip states.
    subroutine test_jacobians(t)
        type(test_counter_t), intent(inout) :: t
        call jac_case(t, mixed_model(.false., .true., 0.0_dp, 0.0_dp), "unilateral rigid 1D")
        call jac_case(t, mixed_model(.false., .true., 8.0_dp, 0.0_dp), "unilateral elastic 1D")
        call jac_case(t, mixed_model(.true., .false., 0.0_dp, 0.0_dp), "planar constant load")
        call jac_case(t, mixed_model(.true., .true., 0.0_dp, 0.0_dp), "planar unilateral")
        call jac_case(t, mixed_model(.false., .false., 0.0_dp, 6.0_dp), "Jenkins 1D")
        call jac_case(t, mixed_model(.true., .true., 5.0_dp, 6.0_dp), &
                      "Jenkins 2D, elastic unilateral")
        call jac_at_solution(t, liftoff_model(10.0_dp, 0.0_dp), "lift-off")
        call jac_at_solution(t, liftoff_model(10.0_dp, 20.0_dp), "lift-off, Jenkins")
        call jac_at_solution(t, planar_liftoff(), "planar lift-off")
    end subroutine test_jacobians

    !> The lift-off platform with a third DOF: the second tangential direction of its
    !> contact (2D friction with a varying normal force), forced too.
    function planar_liftoff() result(m)
        type(model_t) :: m
        m = liftoff_model(10.0_dp, 0.0_dp)
        m%ndof = 3
        m%mass = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1]*1.0_dp, [3, 3])
        m%stiffness = reshape([1.3_dp, -0.3_dp, 0.0_dp, -0.3_dp, 1.8_dp, -0.2_dp, 0.0_dp, &
                               -0.2_dp, 1.2_dp], [3, 3])
        m%damping = 0.02_dp*m%mass + 0.002_dp*m%stiffness
        m%force_dof = [1, 2, 3]
        m%force_harmonic = [1, 1, 1]
        m%force_amplitude = [1.0_dp, 2.0_dp, 0.5_dp]
        m%force_phase = [0.0_dp, 0.4_dp, 1.2_dp]
        deallocate (m%normal_direction)
        allocate (m%normal_direction(3, 1), m%tangent2_direction(3, 1))
        m%normal_direction = 0.0_dp
        m%normal_direction(2, 1) = 1.0_dp
        m%tangent2_direction = 0.0_dp
        m%tangent2_direction(3, 1) = 1.0_dp
    end function planar_liftoff

    !> Central differences against the exact Jacobian near the solution of `m` (H = 20, 512
    !> samples; perturbed by 1e-6 of its size), where the contact opens, sticks and slips.
    subroutine jac_at_solution(t, m, name)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        character(len=*), intent(in) :: name
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(hb_problem_t) :: p
        type(error_type), allocatable :: error
        real(dp), allocatable :: x(:), dx(:), jac(:, :), fd(:, :), fp(:), fm(:), xp(:), &
                                 r(:, :), u(:, :)
        integer, allocatable :: state(:, :)
        integer :: n, q, stat
        real(dp) :: eps
        o%harmonics = 20
        o%samples = 512
        call solve_periodic(m, o, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged, &
                   "contact_hbm: solved for the Jacobian check: "//name)
        if (allocated(error) .or. .not. sol%converged) return
        call new_hb_problem(p, m, o%harmonics, .false., o%samples, sol%rho, error)
        if (allocated(error)) return
        n = p%n
        allocate (dx(n), jac(n, n), fd(n, n), fp(n), fm(n), xp(n), r(o%samples, p%nc), &
                  u(o%samples, p%nc), state(o%samples, 1))
        x = reshape(sol%rcoef, [n])
        call random_number(dx)
        x = x + 1.0e-6_dp*maxval(abs(x))*(dx - 0.5_dp)
        eps = 1.0e-8_dp*maxval(abs(x))
        stat = 0
        call p%jacobian(x, jac, stat)
        call p%law_samples(x, r, u, state)
        do q = 1, n
            xp = x
            xp(q) = x(q) + eps
            call p%residual(xp, fp, stat)
            xp(q) = x(q) - eps
            call p%residual(xp, fm, stat)
            fd(:, q) = (fp - fm)/(2*eps)
        end do
        call check(t, any(state == state_open) .and. any(state == state_stick) .and. &
                   any(state == state_slip), "contact_hbm: open, stick and slip samples: "//name)
        call check(t, stat == 0 .and. maxval(abs(jac - fd)) <= 1.0e-6_dp*max(1.0_dp, &
                   maxval(abs(fd))), "contact_hbm: Jacobian = central differences at the "// &
                   "solution: "//name)
        call p%destroy()
    end subroutine jac_at_solution

    subroutine jac_case(t, m, name)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        character(len=*), intent(in) :: name
        type(hb_problem_t) :: p
        type(error_type), allocatable :: error
        real(dp), allocatable :: x(:), jac(:, :), fd(:, :), fp(:), fm(:), xp(:), r(:, :), u(:, :)
        integer, allocatable :: state(:, :)
        integer :: n, q, stat, nb, c
        real(dp), parameter :: eps = 1.0e-7_dp
        type(model_t) :: mm
        mm = m
        ! a small forcing: slip velocities of the size of rho times the forces, so that the
        ! random forces below give stick as well as slip samples
        mm%force_amplitude = 0.05_dp*mm%force_amplitude
        call new_hb_problem(p, mm, 5, .false., 64, 0.4_dp, error)
        call check(t, .not. allocated(error), "contact_hbm: problem built: "//name)
        if (allocated(error)) return
        n = p%n
        nb = p%basis%nb
        allocate (x(n), jac(n, n), fd(n, n), fp(n), fm(n), xp(n), r(64, p%nc), u(64, p%nc), &
                  state(64, 2))
        call random_number(x)
        x = 0.3_dp*(x - 0.5_dp)
        ! channel means: the normal force near zero (open and closed), friction forces
        ! about the limit (stick and slip)
        do c = 1, p%nc
            x((c - 1)*nb + 1) = 0.05_dp
        end do
        stat = 0
        call p%jacobian(x, jac, stat)
        call p%law_samples(x, r, u, state)
        do q = 1, n
            xp = x
            xp(q) = x(q) + eps
            call p%residual(xp, fp, stat)
            xp(q) = x(q) - eps
            call p%residual(xp, fm, stat)
            fd(:, q) = (fp - fm)/(2*eps)
        end do
        call check(t, stat == 0 .and. maxval(abs(jac - fd)) <= 1.0e-6_dp*max(1.0_dp, &
                   maxval(abs(fd))), "contact_hbm: Jacobian = central differences: "//name)
        call p%destroy()
    end subroutine jac_case

    !> The same problem condensed densely and by the sparse path: equal residual and
    !> Jacobian (to roundoff) at a random point.
    subroutine test_sparse_equals_dense(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(sparse_model_t) :: sm
        type(hb_problem_t) :: pd, ps
        type(basis_t) :: basis
        type(dynamics_t) :: dyn
        type(contact_set_t) :: cs
        type(error_type), allocatable :: error
        real(dp), allocatable :: x(:), fd(:), fs(:), jd(:, :), js(:, :)
        integer :: stat
        m = mixed_model(.true., .true., 5.0_dp, 6.0_dp)
        call new_hb_problem(pd, m, 4, .false., 32, 0.4_dp, error)
        if (allocated(error)) return
        sm%model = m
        deallocate (sm%model%mass, sm%model%stiffness, sm%model%damping)
        call dense_to_sparse(m%mass, sm%mass)
        call dense_to_sparse(m%stiffness, sm%stiffness)
        call dense_to_sparse(m%damping, sm%damping)
        call new_basis(basis, 4, .false., 32, error)
        call new_sparse_dynamics(dyn, sm, basis, [1, 2, 3, 4], error)
        call basis%destroy()
        call check(t, .not. allocated(error), "contact_hbm: sparse dynamics built")
        if (allocated(error)) return
        call new_contact_set(cs, m)
        call new_condensed_problem(ps, dyn, cs, 4, .false., 32, 0.4_dp, error, &
                                   m%force_harmonic)
        call check(t, .not. allocated(error), "contact_hbm: sparse problem built")
        if (allocated(error)) return
        allocate (x(pd%n), fd(pd%n), fs(pd%n), jd(pd%n, pd%n), js(pd%n, pd%n))
        call random_number(x)
        x = x - 0.4_dp
        stat = 0
        call pd%residual(x, fd, stat)
        call ps%residual(x, fs, stat)
        call pd%jacobian(x, jd, stat)
        call ps%jacobian(x, js, stat)
        call check(t, ps%n == pd%n .and. maxval(abs(fs - fd)) <= 1.0e-12_dp*maxval(abs(fd)) &
                   .and. maxval(abs(js - jd)) <= 1.0e-12_dp*maxval(abs(jd)), &
                   "contact_hbm: sparse condensation = dense (residual and Jacobian)")
        call pd%destroy()
        call ps%destroy()
    contains
        subroutine dense_to_sparse(a, s)
            real(dp), intent(in) :: a(:, :)
            type(sparse_matrix_t), intent(out) :: s
            integer :: i, j
            integer, allocatable :: ri(:), ci(:)
            real(dp), allocatable :: v(:)
            type(error_type), allocatable :: err
            allocate (ri(0), ci(0), v(0))
            do j = 1, size(a, 2)
                do i = 1, size(a, 1)
                    if (a(i, j) == 0.0_dp) cycle
                    ri = [ri, i]
                    ci = [ci, j]
                    v = [v, a(i, j)]
                end do
            end do
            call new_sparse_from_triplets(s, size(a, 1), size(a, 2), ri, ci, v, err)
        end subroutine dense_to_sparse
    end subroutine test_sparse_equals_dense

    !> A unilateral contact that never opens (a decoupled normal DOF, grounded by a spring 5,
    !> pressed by the preload 1, gap 0): rigid, it carries lambda = 1, elastic (k_n = 50) the
    !> share k_n / (5 + k_n) of the preload (the spring carries the rest, x_3 = -1/55); in
    !> both cases the constant-load case with that normal load to roundoff, lambda constant,
    !> the gap 0 (rigid) or x_3 (elastic).
    subroutine test_never_opens(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: plain, uni
        type(model_t) :: m
        type(error_type), allocatable :: error
        real(dp) :: kn, load, tol
        integer :: k
        character(len=8) :: what
        o%harmonics = 30
        o%samples = 1024
        o%rho = 0.2_dp
        do k = 1, 2
            kn = merge(0.0_dp, 50.0_dp, k == 1)
            load = merge(1.0_dp, kn/(5.0_dp + kn), k == 1)
            what = merge("rigid  ", "elastic", k == 1)
            m = seed_model()
            m%normal_load = [load]
            call solve_periodic(m, o, plain, error)
            if (allocated(error)) return
            call solve_periodic(unilateral_seed(kn), o, uni, error)
            call check(t, .not. allocated(error), "contact_hbm: never opens: solved")
            if (allocated(error)) return
            ! rigid: the same iterates (roundoff); elastic: another path to the same root
            ! (the solver's tolerance)
            tol = merge(1.0e-12_dp, 1.0e-7_dp, k == 1)
            call check(t, uni%converged .and. maxval(abs(uni%x(:, 1:2) - plain%x)) <= &
                       tol*maxval(abs(plain%x)) .and. maxval(abs(uni%r(:, 1) - &
                       plain%r(:, 1))) <= tol, &
                       "contact_hbm: a contact that never opens is the constant-load case, "// &
                       trim(what))
            call check(t, maxval(abs(uni%normal(:, 1) - load)) <= 1.0e-12_dp .and. &
                       maxval(abs(uni%gap(:, 1) - merge(0.0_dp, -1.0_dp/55.0_dp, k == 1))) <= &
                       1.0e-12_dp .and. uni%open_fraction(1) == 0.0_dp, &
                       "contact_hbm: never opens: lambda constant, the gap of the static "// &
                       "solve, "//trim(what))
            call check(t, abs(uni%stick_fraction(1) - plain%stick_fraction(1)) <= 2.0_dp/1024, &
                       "contact_hbm: never opens: the same stick fraction, "//trim(what))
        end do
    end subroutine test_never_opens

    !> A damper-like contact that lifts off part of the period (elastic normal contact):
    !> converged, the energy balance to roundoff (forcing work = friction + viscous, the
    !> normal force's work zero over a period), the normal law within the ripple, lambda = 0
    !> where open, the friction force within mu lambda(t).
    subroutine test_liftoff(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: e
        o%harmonics = 40
        o%samples = 1024
        call solve_periodic(liftoff_model(10.0_dp, 0.0_dp), o, sol, error)
        call check(t, .not. allocated(error), "contact_hbm: lift-off solved")
        if (allocated(error)) return
        e = abs(sol%work_forcing - sol%diss_friction - sol%diss_damping)/abs(sol%work_forcing)
        call check(t, sol%converged .and. e <= 1.0e-9_dp, &
                   "contact_hbm: lift-off: converged, energy balance to roundoff")
        call check(t, sol%open_fraction(1) > 0.05_dp .and. sol%open_fraction(1) < 0.9_dp, &
                   "contact_hbm: lift-off: the contact opens part of the period")
        call check(t, sol%signorini_check < 0.1_dp .and. &
                   sol%diagnostics%worst() < 2, "contact_hbm: lift-off: the normal law "// &
                   "holds (pulling force and penetration within the ripple), no distrust")
        call check(t, maxval(abs(sol%r(:, 1)), mask=sol%state(:, 1) == state_open) < &
                   0.1_dp*0.5_dp*maxval(sol%normal(:, 1)), &
                   "contact_hbm: lift-off: no friction force where open")
        call check(t, abs(sol%diss_coulomb - sol%diss_friction) <= 0.05_dp*sol%diss_friction, &
                   "contact_hbm: lift-off: friction dissipates as Coulomb's law with mu lambda(t)")
    end subroutine test_liftoff

    !> 2D friction, a circular path: the point mass forced by a rotating force slips in full,
    !> the friction force a rotating force mu N opposite to the velocity; with the complex
    !> dynamic stiffness Z = k - m w^2 + i c w, the radius A solves |Z A + i mu N| = F:
    !> (Z^2 + c^2 w^2) A^2 + 2 c w mu N A + (mu N)^2 - F^2 = 0. The Fourier series is exact
    !> for it (one harmonic), so the weighted residual must give it to the solver's
    !> tolerance, with the force on the disk's edge.
    subroutine test_circle(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: z, cw, mun, f, a, radius(1024)
        f = 1.0_dp
        o%harmonics = 9
        o%samples = 1024
        call solve_periodic(planar_model(f, f, 0.0_dp), o, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged, "contact_hbm: circle solved")
        if (allocated(error)) return
        z = 1.0_dp - 1.7_dp**2
        cw = 0.1_dp*1.7_dp
        mun = 0.3_dp
        a = (-cw*mun + sqrt((cw*mun)**2 - (z**2 + cw**2)*(mun**2 - f**2)))/(z**2 + cw**2)
        radius = hypot(sol%x(:, 1), sol%x(:, 2))
        call check_close(t, maxval(radius), a, "contact_hbm: circle: the radius of the "// &
                         "closed form", rtol=1.0e-8_dp)
        call check(t, maxval(radius) - minval(radius) <= 1.0e-8_dp*a, &
                   "contact_hbm: circle: the path is a circle")
        call check(t, maxval(abs(hypot(sol%r(:, 1), sol%r(:, 2)) - mun)) <= 1.0e-8_dp .and. &
                   sol%slip_fraction(1) == 1.0_dp, &
                   "contact_hbm: circle: full slip, the force on the disk's edge")
    end subroutine test_circle

    !> 2D friction, an elliptical path (forces 1 and 0.5 along x and y): converged, energy
    !> balance to roundoff, the force on the disk's edge where slipping and opposite to the
    !> velocity, the path elliptical (its x and y amplitudes differ).
    subroutine test_ellipse(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: e, cosine
        integer :: k, bad
        o%harmonics = 40
        o%samples = 2048
        call solve_periodic(planar_model(1.0_dp, 0.5_dp, 0.0_dp), o, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged, "contact_hbm: ellipse solved")
        if (allocated(error)) return
        e = abs(sol%work_forcing - sol%diss_friction - sol%diss_damping)/abs(sol%work_forcing)
        call check(t, e <= 1.0e-9_dp, "contact_hbm: ellipse: energy balance to roundoff")
        call check(t, maxval(abs(sol%x(:, 1))) > 1.3_dp*maxval(abs(sol%x(:, 2))), &
                   "contact_hbm: ellipse: the path is elongated along x")
        ! where it slips fast, the force is -mu N v / |v| (the truncation ripple aside)
        bad = 0
        do k = 1, size(sol%t)
            if (sol%state(k, 1) /= state_slip) cycle
            if (hypot(sol%v(k, 1), sol%v(k, 2)) < 0.2_dp*maxval(hypot(sol%v(:, 1), sol%v(:, 2)))) &
                cycle
            cosine = -(sol%r(k, 1)*sol%v(k, 1) + sol%r(k, 2)*sol%v(k, 2))/ &
                     (hypot(sol%r(k, 1), sol%r(k, 2))*hypot(sol%v(k, 1), sol%v(k, 2)))
            if (cosine < 0.99_dp .or. abs(hypot(sol%r(k, 1), sol%r(k, 2)) - 0.3_dp) > 0.03_dp) &
                bad = bad + 1
        end do
        call check(t, bad == 0 .and. sol%slip_fraction(1) > 0.5_dp, &
                   "contact_hbm: ellipse: the force opposes the slip velocity, |r| = mu N")
        call check(t, abs(sol%diss_coulomb - sol%diss_friction) <= 0.02_dp*sol%diss_friction, &
                   "contact_hbm: ellipse: friction dissipates as Coulomb's law")
    end subroutine test_ellipse

    !> Jenkins: stuck (mu N huge), the contact is the spring k_t: with odd harmonics only (no
    !> undetermined slider offset) the response is the linear one of K + k_t w w^T, from a
    !> 2 x 2 solve; a very stiff k_t gives the rigid contact's answer to O(1/k_t).
    subroutine test_jenkins(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol, rigid
        type(model_t) :: m
        type(error_type), allocatable :: error
        real(dp) :: a(2, 2), b(2), kt
        integer :: ipiv(2), info
        kt = 3.0_dp
        m = seed_model()
        m%omega = 1.1_dp
        m%normal_load = [1.0e6_dp]
        m%tangential_stiffness = [kt]
        o%harmonics = 5
        o%odd_only = .true.
        o%samples = 256
        call solve_periodic(m, o, sol, error)
        call check(t, .not. allocated(error), "contact_hbm: Jenkins stuck solved")
        if (allocated(error)) return
        ! x = X cos(w t): (K + kt e2 e2^T - w^2 M) X = [10, 0]
        a = m%stiffness - m%omega**2*m%mass
        a(2, 2) = a(2, 2) + kt
        b = [10.0_dp, 0.0_dp]
        call dgesv(2, 1, a, 2, ipiv, b, 2, info)
        call check(t, sol%converged .and. sol%stick_fraction(1) == 1.0_dp .and. &
                   abs(sol%xcoef(1, 1) - b(1)) <= 1.0e-9_dp*abs(b(1)) .and. &
                   abs(sol%xcoef(1, 2) - b(2)) <= 1.0e-9_dp*abs(b(1)), &
                   "contact_hbm: Jenkins stuck = the structure with the spring k_t")
        ! stiff: the rigid answer
        m = seed_model()
        o = hbm_options_t()
        o%harmonics = 30
        o%samples = 1024
        o%rho = 0.2_dp
        call solve_periodic(m, o, rigid, error)
        m%tangential_stiffness = [1.0e6_dp]
        call solve_periodic(m, o, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged .and. &
                   maxval(abs(sol%x - rigid%x)) <= 1.0e-3_dp*maxval(abs(rigid%x)), &
                   "contact_hbm: Jenkins with k_t = 1e6 is the rigid contact")
    end subroutine test_jenkins
end module test_contact_hbm
