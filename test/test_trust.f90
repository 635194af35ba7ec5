!> No crash, no answer without a diagnosis (issue 10): the exact reference when its starts
!> fail, the convergence test of the weighted residual against huge or tiny mu N and rho and
!> scaled units (checked against the stuck system solved independently), resonances of the
!> undamped structure, and every check turning into a diagnostics item when it fails.
module test_trust
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, stickslip_stat, itoa
    use stickslip_diagnostics, only: diagnostics_t, level_note, level_warning, level_untrusted
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_lapack, only: dsygv
    use stickslip_euler, only: euler_options_t
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference
    use stickslip_reference_start, only: solve_reference_from_starts, reference_start_options_t
    use stickslip_checks, only: check_options_t, hbm_checks_t, solve_and_check
    use stickslip_compare, only: comparison_t
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side, disagreement
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep
    use test_hbm, only: seed_model, chain_model
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_trust_tests

contains

    subroutine run_trust_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_reference_failed_starts(t)
        call test_reference_given_start(t)
        call test_huge_friction_is_stuck(t)
        call test_extreme_rho(t)
        call test_scaled_units(t)
        call test_one_dof_resonance(t)
        call test_two_dof_resonance(t)
        call test_odd_samples(t)
        call test_sound_cases_quiet(t)
        call test_disagreement(t)
        call test_sweep_tally(t)
        call test_fine_mesh_not_resonant(t)
    end subroutine run_trust_tests

    !> A fixed-free chain of 60 masses whose springs span 12 decades (cond(K) ~ 1e14, like a
    !> badly graded FE mesh), forced between two natural frequencies: not a resonance, and
    !> no 'near_resonance' finding; forced at a natural frequency (LAPACK dsygv): an error
    !> naming the harmonic. The singularity test must measure the distance to a mode, not
    !> the conditioning of K.
    subroutine test_fine_mesh_not_resonant(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 60
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: kk(n), a(n, n), b(n, n), w(n), work(10*n)
        integer :: i, info
        do i = 1, n
            kk(i) = 10.0_dp**(12.0_dp*real(i - 1, dp)/real(n - 1, dp) - 6.0_dp)
        end do
        m%ndof = n
        allocate (m%stiffness(n, n), m%mass(n, n), m%damping(n, n))
        m%stiffness = 0.0_dp
        m%mass = 0.0_dp
        m%damping = 0.0_dp
        do i = 1, n
            m%mass(i, i) = 1.0_dp
            m%stiffness(i, i) = kk(i)
            if (i < n) m%stiffness(i, i) = m%stiffness(i, i) + kk(i + 1)
            if (i < n) then
                m%stiffness(i, i + 1) = -kk(i + 1)
                m%stiffness(i + 1, i) = -kk(i + 1)
            end if
        end do
        a = m%stiffness
        b = m%mass
        call dsygv(1, 'N', 'U', n, a, n, b, n, w, work, size(work), info)
        call check(t, info == 0, "fine mesh: eigenvalues")
        if (info /= 0) return
        m%omega = sqrt(sqrt(w(10)*w(11)))
        m%force_dof = [n]
        m%force_harmonic = [1]
        m%force_amplitude = [1.0_dp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [n]
        m%contact_dof2 = [0]
        m%mu = [0.3_dp]
        m%normal_load = [1.0_dp]
        o%harmonics = 1
        o%odd_only = .true.
        o%samples = 64
        call solve_periodic(m, o, sol, error)
        call check_error(t, error, "fine mesh between modes: solved", .false.)
        if (allocated(error)) return
        call check(t, .not. sol%diagnostics%has('near_resonance'), &
                   "fine mesh between modes (cond(K) ~ 1e14): no near_resonance finding")
        m%omega = sqrt(w(10))
        call solve_periodic(m, o, sol, error)
        if (.not. allocated(error)) then
            call check(t, sol%diagnostics%has('near_resonance'), &
                       "fine mesh at a natural frequency: near_resonance (untrusted)")
        else
            call check(t, index(error%message, "resonance at harmonic h = 1") > 0, &
                       "fine mesh at a natural frequency: the message names the harmonic", &
                       error%message)
        end if
    end subroutine test_fine_mesh_not_resonant

    !> A sweep counts the points whose checks fail: at H = 5 (64 samples) the seed case's
    !> truncation estimate is far above 10%, so the curve carries 'points_truncation'.
    subroutine test_sweep_tally(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(reference_start_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(model_t) :: m
        type(error_type), allocatable :: error
        integer :: k, bad
        m = seed_model()
        m%damping = 0.02_dp*m%mass + 0.02_dp*m%stiffness
        ho%harmonics = 5
        ho%samples = 64
        ho%rho = 0.2_dp
        so%parameter = 'omega'
        so%start = 4.0_dp
        so%stop = 4.5_dp
        so%max_points = 8
        so%stability = .false.
        so%truncation = .true.
        call run_sweep(m, ho, ro%reference_options_t, so, res, error)
        call check_error(t, error, "sweep tally: no error", .false.)
        if (allocated(error)) return
        bad = 0
        do k = 1, res%npoints
            if (res%points(k)%truncation > 0.1_dp) bad = bad + 1
        end do
        call check(t, bad > 0, "sweep tally: coarse points exist")
        call check(t, res%diagnostics%has("points_truncation") .and. &
                   res%diagnostics%worst() >= level_warning, &
                   "sweep tally: 'points_truncation'", keys(res%diagnostics))
        if (allocated(res%diagnostics%items)) &
            call check(t, index(res%diagnostics%items(1)%message, itoa(bad)//" of "// &
                       itoa(res%npoints)) == 1, "sweep tally: the count of points", &
                       res%diagnostics%items(1)%message)
    end subroutine test_sweep_tally

    !> A 20-DOF clamped-free chain ("beam") with one contact to the ground at its tip.
    function beam_model() result(m)
        type(model_t) :: m
        integer :: i, n
        n = 20
        m%ndof = n
        allocate (m%mass(n, n), m%stiffness(n, n))
        m%mass = 0.0_dp
        m%stiffness = 0.0_dp
        do i = 1, n
            m%mass(i, i) = 1.0_dp
            m%stiffness(i, i) = 2.0_dp
            if (i < n) then
                m%stiffness(i, i + 1) = -1.0_dp
                m%stiffness(i + 1, i) = -1.0_dp
            end if
        end do
        m%stiffness(n, n) = 1.0_dp
        m%damping = 0.01_dp*m%stiffness
        m%omega = 0.3_dp
        m%force_dof = [n/2]
        m%force_harmonic = [1]
        m%force_amplitude = [1.0_dp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [n]
        m%contact_dof2 = [0]
        m%mu = [0.3_dp]
        m%normal_load = [1.0_dp]
    end function beam_model

    !> A reference whose starts both fail (or whose shootings both fail) is an outcome:
    !> no error, converged = F, a diagnosis and an untrusted 'not_converged' item. These
    !> crashed with "Attempting to allocate already allocated variable 'res'".
    subroutine test_reference_failed_starts(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_start_options_t) :: o
        type(reference_result_t) :: res
        type(model_t) :: m
        type(error_type), allocatable :: error

        o%maxfev = 1
        call solve_reference_from_starts(seed_model(), o, res, error)
        call outcome("maxfev = 1")

        o = reference_start_options_t()
        o%tol = 1.0e-300_dp
        call solve_reference_from_starts(seed_model(), o, res, error)
        call outcome("tol = 1e-300")

        o = reference_start_options_t()
        m = seed_model()
        m%omega = 1.0e-5_dp
        o%maxfev = 1
        call solve_reference_from_starts(m, o, res, error)
        call check(t, .not. allocated(error), "reference omega = 1e-5: no error")
        call check(t, .not. res%converged .eqv. res%diagnostics%has("not_converged"), &
                   "reference omega = 1e-5: not converged <=> diagnosis")

        o = reference_start_options_t()
        o%maxfev = 1
        o%samples = 64
        call solve_reference_from_starts(beam_model(), o, res, error)
        call outcome("20-DOF beam, maxfev = 1")
        ! the same result variable again: no stale allocation
        call solve_reference_from_starts(beam_model(), o, res, error)
        call outcome("20-DOF beam again into the same result")

    contains

        subroutine outcome(name)
            character(len=*), intent(in) :: name
            call check_error(t, error, "reference "//name//": an outcome, no error", .false.)
            if (allocated(error)) return
            call check(t, .not. res%converged, "reference "//name//": not converged")
            call check(t, len(res%diagnosis) > 0, "reference "//name//": a diagnosis")
            call check(t, res%diagnostics%has("not_converged") .and. &
                       res%diagnostics%worst() == level_untrusted, &
                       "reference "//name//": untrusted 'not_converged'")
            call check(t, res%nfev >= 1, "reference "//name//": the period maps are counted")
        end subroutine outcome
    end subroutine test_reference_failed_starts

    !> solve_reference takes its start as an argument: from the weighted-residual samples it
    !> gives the orbit solve_reference_from_starts gives; a start of the wrong shape is an
    !> input error.
    subroutine test_reference_given_start(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(reference_start_options_t) :: o
        type(reference_result_t) :: a, b
        type(error_type), allocatable :: error
        ho%rho = 0.2_dp
        call solve_periodic(seed_model(), ho, sol, error)
        if (allocated(error)) return
        o%samples = 256
        call solve_reference(seed_model(), o%reference_options_t, sol%x, sol%v, a, error, start_name='hbm')
        call check_error(t, error, "solve_reference from given samples: no error", .false.)
        if (allocated(error)) return
        call solve_reference_from_starts(seed_model(), o, b, error, hbm_opts=ho)
        if (allocated(error)) return
        call check(t, a%converged .and. b%converged .and. a%start == 'hbm', &
                   "solve_reference from given samples: converged")
        if (a%converged .and. b%converged) &
            call check_close(t, reshape(a%x, [size(a%x)]), reshape(b%x, [size(b%x)]), &
                             "solve_reference = solve_reference_from_starts", &
                             atol=1.0e-9_dp*maxval(abs(b%x)))
        call check(t, .not. (a%diagnostics%worst() >= level_warning), &
                   "converged reference: energy balance and Coulomb's law pass")
        call solve_reference(seed_model(), o%reference_options_t, sol%x(:, 1:1), sol%v, a, error)
        call check_error(t, error, "solve_reference: a start of the wrong shape", .true., &
                         [character(len=8) :: "ns x N"])
    end subroutine test_reference_given_start

    !> Seed case with mu = 1e10: the contact cannot slip, so the answer is the stuck
    !> system: x2 = 0 (the mean force closest to zero) and x1 = f cos(omega t) / (k11 -
    !> omega^2 m1), solved here by hand. It used to converge at the zero start with r = 0
    !> (the frictionless response). Automatic rho and rho = 0.2.
    subroutine test_huge_friction_is_stuck(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: x1, amp1, amp2
        integer :: pass
        m = seed_model()
        m%mu = [1.0e10_dp]
        x1 = 10.0_dp/(2.0_dp - m%omega**2)
        do pass = 1, 2
            ho = hbm_options_t()
            if (pass == 2) ho%rho = 0.2_dp
            call solve_periodic(m, ho, sol, error)
            call check_error(t, error, "mu = 1e10: no error", .false.)
            if (allocated(error)) return
            call check(t, sol%converged, "mu = 1e10: converged")
            amp1 = maxval(abs(sol%x(:, 1)))
            amp2 = maxval(abs(sol%x(:, 2)))
            call check_close(t, amp1, abs(x1), "mu = 1e10: x1 of the stuck system", rtol=1.0e-8_dp)
            call check(t, amp2 <= 1.0e-8_dp*abs(x1), "mu = 1e10: x2 stuck")
            call check(t, sol%diagnostics%worst() < level_warning, &
                       "mu = 1e10: the stuck answer raises no warning")
        end do
    end subroutine test_huge_friction_is_stuck

    !> rho = 1e300 and 1e-300 (fixed): never a wrong answer without a diagnosis. The right
    !> answer at that basis is the solve with the automatic rho.
    subroutine test_extreme_rho(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: good, sol
        type(error_type), allocatable :: error
        real(dp) :: rhos(2)
        integer :: k
        call solve_periodic(seed_model(), ho, good, error)
        if (allocated(error)) return
        rhos = [1.0e300_dp, 1.0e-300_dp]
        do k = 1, 2
            ho = hbm_options_t()
            ho%rho = rhos(k)
            call solve_periodic(seed_model(), ho, sol, error)
            call check(t, flagged_or_right(sol, error, good, 1.0e-3_dp), &
                       "extreme rho: error, not converged, untrusted or right")
            if (.not. allocated(error)) call check(t, sol%diagnostics%has("rho_out_of_range"), &
                                                   "extreme rho: 'rho_out_of_range'")
        end do
    end subroutine test_extreme_rho

    !> The seed case in units scaled by 1e-9 (M, K, forces and normal load): with the
    !> automatic rho the displacements are the unscaled ones (the whole solve is invariant);
    !> with rho = 0.2 fixed (1e-9 of the contact mobility) the answer is right or flagged.
    subroutine test_scaled_units(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: good, sol
        type(error_type), allocatable :: error
        real(dp), parameter :: s = 1.0e-9_dp
        call solve_periodic(seed_model(), ho, good, error)
        if (allocated(error)) return
        m = seed_model()
        m%mass = s*m%mass
        m%stiffness = s*m%stiffness
        m%force_amplitude = s*m%force_amplitude
        m%normal_load = s*m%normal_load
        call solve_periodic(m, ho, sol, error)
        call check_error(t, error, "scaled units: no error", .false.)
        if (allocated(error)) return
        call check(t, sol%converged, "scaled units, automatic rho: converged")
        call check_close(t, reshape(sol%x, [size(sol%x)]), reshape(good%x, [size(good%x)]), &
                         "scaled units, automatic rho: the same displacements", &
                         atol=1.0e-6_dp*maxval(abs(good%x)))
        ho%rho = 0.2_dp
        call solve_periodic(m, ho, sol, error)
        call check(t, flagged_or_right(sol, error, good, 1.0e-3_dp), &
                   "scaled units, rho = 0.2: error, not converged, untrusted or right")
    end subroutine test_scaled_units

    !> 1 DOF, m = 1, k = 2, C = 0, forced at omega = sqrt(2) with 0.5 < mu N = 1: the true
    !> answer is stuck, x = 0. The weighted residual must not return x ~ 1e15 (the rcond of
    !> a 1 x 1 is 1): stat numerical naming the resonance; method 'all' fails too.
    subroutine test_one_dof_resonance(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(euler_options_t) :: eo
        type(reference_start_options_t) :: ro
        type(reference_result_t) :: ref
        type(side_by_side_t) :: all
        type(error_type), allocatable :: error
        m%ndof = 1
        m%mass = reshape([1.0_dp], [1, 1])
        m%stiffness = reshape([2.0_dp], [1, 1])
        m%damping = reshape([0.0_dp], [1, 1])
        m%omega = sqrt(2.0_dp)
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [0.5_dp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [1]
        m%contact_dof2 = [0]
        m%mu = [1.0_dp]
        m%normal_load = [1.0_dp]
        ho%harmonics = 10
        ho%samples = 256
        call solve_periodic(m, ho, sol, error)
        call check_error(t, error, "1-DOF resonance: weighted residual refuses", .true., &
                         [character(len=40) :: "undamped resonance at harmonic h = 1"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%numerical, &
                                         "1-DOF resonance: stat numerical")
        eo%steps_per_period = 200
        call solve_side_by_side(m, ho, eo, ro, all, error)
        call check(t, allocated(error) .or. all%diagnostics%worst() == level_untrusted, &
                   "1-DOF resonance: method 'all' fails or is untrusted")
        ! the reference: the hbm start fails, implicit Euler finds the stuck state
        call solve_reference_from_starts(m, ro, ref, error, hbm_opts=ho, euler_opts=eo)
        call check_error(t, error, "1-DOF resonance: reference, no error", .false.)
        if (allocated(error)) return
        if (ref%converged .and. ref%diagnostics%worst() < level_untrusted) then
            call check(t, maxval(abs(ref%x)) <= 1.0e-6_dp, "1-DOF resonance: reference x = 0")
        else
            call check(t, len(ref%diagnosis) > 0 .or. ref%diagnostics%worst() == &
                       level_untrusted, "1-DOF resonance: reference flagged")
        end if
    end subroutine test_one_dof_resonance

    !> Undamped seed structure at its natural frequency 0.618034 rad/s, force 1, mu N 0.45:
    !> the response hangs on the 7th digit of omega. Never a plain answer with exit 0:
    !> error, not converged or untrusted ('near_resonance').
    subroutine test_two_dof_resonance(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        integer :: pass
        m = seed_model()
        m%omega = 0.618034_dp
        m%force_amplitude = [1.0_dp]
        do pass = 1, 2
            ho = hbm_options_t()
            if (pass == 2) ho%rho = 0.2_dp
            call solve_periodic(m, ho, sol, error)
            if (allocated(error)) then
                call check(t, error%stat == stickslip_stat%numerical, &
                           "2-DOF resonance: a numerical error")
            else
                call check(t, .not. sol%converged .or. sol%diagnostics%worst() == &
                           level_untrusted, "2-DOF resonance: flagged untrusted")
                call check(t, sol%diagnostics%has("near_resonance"), &
                           "2-DOF resonance: 'near_resonance'")
            end if
        end do
    end subroutine test_two_dof_resonance

    !> H = 15 with samples = 2H + 1 = 31 (odd): x2 is off by 590%. The checks warn about the
    !> odd count and the truncation estimate (88%) makes the solution untrusted; method
    !> 'all' sees the disagreement with the reference.
    subroutine test_odd_samples(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(check_options_t) :: co
        type(reference_start_options_t) :: ro
        type(euler_options_t) :: eo
        type(hbm_solution_t) :: sol
        type(hbm_checks_t) :: checks
        type(side_by_side_t) :: all
        type(error_type), allocatable :: error
        ho%harmonics = 15
        ho%samples = 31
        ho%rho = 0.2_dp
        call solve_and_check(seed_model(), ho, co, ro%reference_options_t, sol, checks, error)
        call check_error(t, error, "odd samples: no error", .false.)
        if (allocated(error)) return
        call check(t, checks%diagnostics%has("odd_samples"), "odd samples: 'odd_samples'")
        call check(t, checks%diagnostics%has("truncation") .and. &
                   checks%diagnostics%worst() == level_untrusted, &
                   "odd samples: the truncation estimate makes it untrusted", &
                   "estimate "//real_text(checks%truncation%estimate))
        eo%steps_per_period = 400
        call solve_side_by_side(seed_model(), ho, eo, ro, all, error)
        call check_error(t, error, "odd samples, all: no error", .false.)
        if (allocated(error)) return
        call check(t, all%diagnostics%has("hbm_disagrees") .and. &
                   all%diagnostics%worst() == level_untrusted, &
                   "odd samples, all: the weighted residual disagrees, untrusted")
        call check(t, all%diagnostics%has("hbm_odd_samples"), "odd samples, all: prefixed key")
    end subroutine test_odd_samples

    !> No false alarms: the seed case and the damped 4-DOF chain raise no warning, with
    !> solve_and_check and with the three methods side by side (seed).
    subroutine test_sound_cases_quiet(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(check_options_t) :: co
        type(reference_start_options_t) :: ro
        type(euler_options_t) :: eo
        type(hbm_solution_t) :: sol
        type(hbm_checks_t) :: checks
        type(side_by_side_t) :: all
        type(error_type), allocatable :: error
        ho%rho = 0.2_dp
        call solve_and_check(seed_model(), ho, co, ro%reference_options_t, sol, checks, error)
        if (allocated(error)) return
        call check(t, sol%diagnostics%worst() < level_warning .and. &
                   checks%diagnostics%worst() < level_warning, "seed: no warning", &
                   keys(sol%diagnostics)//keys(checks%diagnostics))
        call check(t, sol%coulomb_check < 0.05_dp .and. sol%max_force_ratio < 1.1_dp, &
                   "seed: Coulomb dissipation and force limit within the margins")
        ho = hbm_options_t()
        call solve_and_check(chain_model(), ho, co, ro%reference_options_t, sol, checks, error)
        if (allocated(error)) return
        call check(t, sol%diagnostics%worst() < level_warning .and. &
                   checks%diagnostics%worst() < level_warning, "chain: no warning", &
                   keys(sol%diagnostics)//keys(checks%diagnostics))
        ho%rho = 0.2_dp
        eo%steps_per_period = 2000
        call solve_side_by_side(seed_model(), ho, eo, ro, all, error)
        if (allocated(error)) return
        call check(t, all%diagnostics%worst() < level_warning, "seed, all: no warning", &
                   keys(all%diagnostics))
    end subroutine test_sound_cases_quiet

    !> The disagreement rule on made-up comparisons: 0.05 nothing, 0.2 a warning, 2 untrusted;
    !> a DOF nearly at rest does not count alone; hbm vs euler only counts without a
    !> reference.
    subroutine test_disagreement(t)
        type(test_counter_t), intent(inout) :: t
        type(comparison_t) :: c(2)
        type(diagnostics_t) :: d
        c(1) = made('hbm', 'reference', [0.05_dp, 0.05_dp], [1.0_dp, 1.0_dp])
        c(2) = made('hbm', 'euler', [5.0_dp, 5.0_dp], [1.0_dp, 1.0_dp])
        call disagreement(c, .true., d)
        call check(t, d%worst() == 0, "disagreement 0.05: nothing; hbm vs euler ignored")
        d = diagnostics_t()
        c(1) = made('hbm', 'reference', [0.2_dp, 0.0_dp], [1.0_dp, 1.0_dp])
        call disagreement(c(1:1), .true., d)
        call check(t, d%worst() == level_warning .and. d%has("hbm_disagrees"), &
                   "disagreement 0.2: warning")
        d = diagnostics_t()
        c(1) = made('euler', 'reference', [0.0_dp, 2.0_dp], [1.0_dp, 1.0_dp])
        call disagreement(c(1:1), .true., d)
        call check(t, d%worst() == level_untrusted .and. d%has("euler_disagrees"), &
                   "disagreement 2: untrusted")
        d = diagnostics_t()
        c(1) = made('hbm', 'reference', [0.0_dp, 100.0_dp], [1.0_dp, 1.0e-6_dp])
        call disagreement(c(1:1), .true., d)
        call check(t, d%worst() == 0, "disagreement on a DOF at rest: nothing")
        d = diagnostics_t()
        call disagreement(c(2:2), .false., d)
        call check(t, d%has("methods_disagree") .and. d%worst() == level_untrusted, &
                   "no reference: hbm vs euler judged")

    contains

        function made(method, against, maxerr, amplitude) result(cmp)
            character(len=*), intent(in) :: method, against
            real(dp), intent(in) :: maxerr(:), amplitude(:)
            type(comparison_t) :: cmp
            cmp%method = method
            cmp%against = against
            cmp%n = size(maxerr)
            cmp%nc = 0
            cmp%max_error = [maxerr, maxerr]
            cmp%rms_error = [maxerr, maxerr]
            cmp%amplitude = [amplitude, amplitude]
        end function made
    end subroutine test_disagreement

    !> The answer is flagged (error, not converged or untrusted) or right (the displacements
    !> of `good` within rtol of their amplitude).
    logical function flagged_or_right(sol, error, good, rtol) result(ok)
        type(hbm_solution_t), intent(in) :: sol, good
        type(error_type), allocatable, intent(in) :: error
        real(dp), intent(in) :: rtol
        ok = .true.
        if (allocated(error)) return
        if (.not. sol%converged) return
        if (sol%diagnostics%worst() == level_untrusted) return
        ok = maxval(abs(sol%x - good%x)) <= rtol*maxval(abs(good%x))
    end function flagged_or_right

    !> The keys of a diagnostics list, for failure messages.
    function keys(d) result(text)
        type(diagnostics_t), intent(in) :: d
        character(len=:), allocatable :: text
        integer :: k
        text = ""
        if (.not. allocated(d%items)) return
        do k = 1, size(d%items)
            text = text//" "//d%items(k)%key//": "//d%items(k)%message
        end do
    end function keys

    function real_text(x) result(text)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: text
        character(len=24) :: buf
        write (buf, '(es12.4)') x
        text = trim(adjustl(buf))
    end function real_text
end module test_trust
