!> Tests of the reuse of the factorized dynamic stiffnesses Z_h: a continuation at fixed
!> omega never factorizes again, one in omega factorizes once per distinct omega (the
!> family's cache gives back a dynamics met before, bit for bit), the dynamics of a
!> smaller basis restricted from a larger one equal those built on it, and a solve given
!> ready dynamics equals one that builds them.
module test_factorizations
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t, new_dynamics, restrict_dynamics
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_truncation, only: truncation_t, estimate_truncation
    use stickslip_continuation, only: continuation_options_t, continuation_state_t, &
        continuation_report_t, start_continuation, continuation_step
    use stickslip_sweep, only: friction_family_t, new_friction_family, dynamics_cache_size
    use testing, only: test_counter_t, check, check_error
    use fixtures, only: damped_seed, chain_model
    implicit none
    private
    public :: run_factorizations_tests

contains

    subroutine run_factorizations_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_steps(t)
        call test_cache(t)
        call test_restrict(t)
        call test_solve_with_dynamics(t)
        call test_truncation_with_dynamics(t)
    end subroutine run_factorizations_tests

    !> The truncation estimate given the solve's dynamics (dyn_out) equals the one that
    !> factorizes the coarse basis itself.
    subroutine test_truncation_with_dynamics(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(dynamics_t) :: dyn
        type(truncation_t) :: a, b
        type(error_type), allocatable :: error
        m = chain_model()
        ho%harmonics = 20
        ho%samples = 256
        ho%rho = 0.2_dp
        call solve_periodic(m, ho, sol, error, dyn_out=dyn)
        call check_error(t, error, "truncation with dynamics: solve", .false.)
        if (allocated(error)) return
        call check(t, sol%converged .and. allocated(dyn%v0), &
                   "truncation with dynamics: dyn_out set")
        call estimate_truncation(m, ho, sol, a, error)
        call check_error(t, error, "truncation with dynamics: plain", .false.)
        call estimate_truncation(m, ho, sol, b, error, dyn=dyn)
        call check_error(t, error, "truncation with dynamics: given", .false.)
        if (allocated(error)) return
        call check(t, a%available .and. a%coarse_harmonics > 0 .and. &
                   a%estimate == b%estimate .and. a%coarse_harmonics == b%coarse_harmonics, &
                   "truncation with dynamics: the same estimate, bit for bit")
    end subroutine test_truncation_with_dynamics

    !> Continuation steps of the chain in mu, the normal load and the force amplitude leave
    !> Z_h alone; a step in omega factorizes at least once and at most once per evaluation.
    subroutine test_steps(t)
        type(test_counter_t), intent(inout) :: t
        character(len=16), parameter :: names(4) = [character(len=16) :: 'mu', &
            'normal_load', 'force_amplitude', 'omega']
        real(dp), parameter :: p0(4) = [0.3_dp, 1.5_dp, 2.0_dp, 0.5_dp], &
                               p1(4) = [0.6_dp, 3.0_dp, 4.0_dp, 0.8_dp]
        type(friction_family_t) :: fam
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(continuation_options_t) :: co
        type(continuation_state_t) :: st
        type(continuation_report_t) :: rep
        type(error_type), allocatable :: error
        integer :: k, n0, n1, step, nfev
        m = chain_model()
        ho%harmonics = 9
        ho%samples = 128
        ho%rho = 0.2_dp
        do k = 1, 4
            m = chain_model()
            call solve_periodic(m, ho, sol, error)
            call check_error(t, error, "steps: start solve "//trim(names(k)), .false.)
            if (allocated(error)) return
            call new_friction_family(fam, m, ho, names(k), p0(k), 0.2_dp, error)
            call check_error(t, error, "steps: family "//trim(names(k)), .false.)
            if (allocated(error)) return
            co%start = p0(k)
            co%stop = p1(k)
            co%step = (p1(k) - p0(k))/50.0_dp
            co%min_step = co%step*1.0e-3_dp
            co%max_step = co%step
            co%tol = ho%tol
            co%fscale = 0.2_dp*1.5_dp
            co%yscale = [1.5_dp]
            call start_continuation(fam, co, reshape(sol%rcoef, [fam%prob%n]), st, rep, error)
            call check_error(t, error, "steps: start "//trim(names(k)), .false.)
            if (allocated(error)) return
            n0 = fam%factorizations
            ! the start: the problem's Z_h (and the unit forcing's, or those with d/domega)
            call check(t, n0 == merge(2, 1, k >= 3), "steps: "//trim(names(k))// &
                       " factorizations at the start", itoa(n0))
            nfev = 0
            do step = 1, 3
                call continuation_step(fam, co, st, rep, error)
                call check_error(t, error, "steps: step "//trim(names(k)), .false.)
                if (allocated(error)) return
                call check(t, rep%accepted, "steps: "//trim(names(k))//" step accepted")
                nfev = nfev + rep%nfev
            end do
            n1 = fam%factorizations
            if (k <= 3) then
                call check(t, n1 == n0, "steps: "//trim(names(k))//": no factorization "// &
                           "while omega is fixed", itoa(n1 - n0)//" new")
            else
                ! every evaluation moves omega in pseudo-arclength, but the tangent, the
                ! check of the point and the residual scale come back to omega values met
                call check(t, n1 - n0 >= 3 .and. n1 - n0 <= nfev, "steps: omega: one "// &
                           "factorization per distinct omega", itoa(n1 - n0)// &
                           " factorizations, "//itoa(nfev)//" evaluations")
            end if
            call fam%destroy()
        end do
    end subroutine test_steps

    !> Evaluations alternating between omega values: one factorization per distinct value
    !> while they fit in the cache, and the residual from the cache is bit for bit that of a
    !> fresh family.
    subroutine test_cache(t)
        type(test_counter_t), intent(inout) :: t
        type(friction_family_t) :: fam, fresh
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        real(dp), allocatable :: y(:), f(:), g(:)
        real(dp) :: om(3)
        integer :: stat, i, n0
        ho%harmonics = 7
        ho%samples = 64
        ho%rho = 0.2_dp
        om = [1.1_dp, 1.3_dp, 1.7_dp]
        call new_friction_family(fam, damped_seed(), ho, 'omega', om(1), 0.2_dp, error)
        call check_error(t, error, "cache: family", .false.)
        if (allocated(error)) return
        n0 = fam%factorizations
        allocate (y(fam%prob%n), f(fam%prob%n), g(fam%prob%n))
        y = [(0.1_dp*sin(real(i, dp)), i=1, fam%prob%n)]
        stat = 0
        do i = 1, 12
            call fam%residual(y, om(mod(i - 1, 3) + 1), f, stat)
        end do
        call check(t, stat == 0, "cache: evaluations")
        call check(t, fam%factorizations - n0 == 2 .and. dynamics_cache_size >= 3, &
                   "cache: 3 omega values, 2 new factorizations", &
                   itoa(fam%factorizations - n0))
        ! om(3) was the last; om(2) comes from the cache
        call fam%residual(y, om(2), f, stat)
        call new_friction_family(fresh, damped_seed(), ho, 'omega', om(2), 0.2_dp, error)
        call check_error(t, error, "cache: fresh family", .false.)
        if (allocated(error)) return
        call fresh%residual(y, om(2), g, stat)
        call check(t, all(f == g), "cache: residual from the cache = fresh, bit for bit")
        call fam%destroy()
        call fresh%destroy()
    end subroutine test_cache

    !> The chain's dynamics on H = 3 restricted from H = 12 equal those built on H = 3.
    subroutine test_restrict(t)
        type(test_counter_t), intent(inout) :: t
        type(basis_t) :: big, small
        type(dynamics_t) :: dbig, dsmall, dres
        type(model_t) :: m
        type(error_type), allocatable :: error
        m = chain_model()
        m%force_harmonic = [1, 2]     ! a harmonic the odd basis lacks
        call new_basis(big, 12, .false., 64, error)
        if (allocated(error)) return
        call new_basis(small, 3, .false., 64, error)
        if (allocated(error)) return
        call new_dynamics(dbig, m, big, error, with_omega_derivative=.true.)
        call check_error(t, error, "restrict: big", .false.)
        call new_dynamics(dsmall, m, small, error, with_omega_derivative=.true.)
        call check_error(t, error, "restrict: small", .false.)
        if (allocated(error)) return
        call restrict_dynamics(dbig, m, small, dres, error)
        call check_error(t, error, "restrict: no error", .false.)
        if (allocated(error)) return
        call check(t, all(dres%x0 == dsmall%x0) .and. all(dres%y == dsmall%y) .and. &
                   all(dres%v0 == dsmall%v0) .and. all(dres%g == dsmall%g) .and. &
                   all(dres%dv0 == dsmall%dv0) .and. all(dres%dg == dsmall%dg) .and. &
                   all(dres%x0_static == dsmall%x0_static) .and. &
                   all(dres%y_static == dsmall%y_static), "restrict: = built on the basis")
        call check(t, dres%relative_conditioning == dsmall%relative_conditioning .and. &
                   dres%worst_harmonic == dsmall%worst_harmonic, &
                   "restrict: relative conditioning over the subset")
        call big%destroy()
        call small%destroy()
        ! a basis with a harmonic the dynamics lack; a forcing harmonic the basis lacks
        call new_basis(big, 15, .false., 64, error)
        if (allocated(error)) return
        call restrict_dynamics(dsmall, m, big, dres, error)
        call check_error(t, error, "restrict: harmonic not built", .true.)
        call big%destroy()
        call new_basis(small, 5, .true., 64, error)
        if (allocated(error)) return
        call restrict_dynamics(dbig, m, small, dres, error)
        call check_error(t, error, "restrict: forcing harmonic outside", .true., &
                         ["force_harmonic(2)"])
        call small%destroy()
    end subroutine test_restrict

    !> solve_periodic given the dynamics (same basis, and a larger one for the ladder and
    !> a subset) equals the solve that builds them; dynamics of another omega are refused.
    subroutine test_solve_with_dynamics(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: a, b
        type(hb_problem_t) :: p
        type(error_type), allocatable :: error
        m = chain_model()
        ho%harmonics = 15
        ho%samples = 128
        ho%rho = 0.2_dp
        ho%start = 'ladder'
        call new_hb_problem(p, m, 30, .false., 128, 0.2_dp, error)
        call check_error(t, error, "solve with dynamics: problem", .false.)
        if (allocated(error)) return
        call solve_periodic(m, ho, a, error)
        call check_error(t, error, "solve with dynamics: plain", .false.)
        call solve_periodic(m, ho, b, error, dyn=p%dyn)
        call check_error(t, error, "solve with dynamics: given", .false.)
        if (allocated(error)) return
        call check(t, a%converged .and. b%converged .and. all(a%rcoef == b%rcoef) .and. &
                   a%nfev == b%nfev, "solve with dynamics: ladder, bit for bit")
        m%omega = 0.6_dp
        call solve_periodic(m, ho, b, error, dyn=p%dyn)
        call check_error(t, error, "solve with dynamics: other omega refused", .true., &
                         ["omega"])
        if (allocated(error)) then
            call check(t, error%stat == stickslip_stat%input, "solve with dynamics: stat input")
        end if
        call p%destroy()
    end subroutine test_solve_with_dynamics
end module test_factorizations
