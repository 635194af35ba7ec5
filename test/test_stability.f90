!> Tests of the Floquet stability against independent truth: the linear damped system
!> (multipliers exp(lambda T) from the eigenvalues of the first-order system), a contact
!> stuck all period (the reduced system plus the stuck offset and the projected slip
!> velocity), negative damping (unstable), the seed case with light damping (stable, and
!> perturbations integrated with the exact flow decay as the multipliers say), and the
!> a-posteriori periodicity check of weighted-residual solutions.
module test_stability
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_lapack, only: dgeev
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_reference, only: reference_options_t, reference_result_t, sample_reference, &
        reference_cache_t
    use stickslip_stability, only: floquet_t, floquet_multipliers, periodic_stability, &
        verify_periodicity
    use fixtures, only: seed_model, chain_model
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_stability_tests

contains

    subroutine run_stability_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_classification(t)
        call test_linear_damped(t)
        call test_negative_damping(t)
        call test_stuck(t)
        call test_seed_damped(t)
        call test_verify_periodicity(t)
        call test_misuse(t)
        call test_cache(t)
    end subroutine run_stability_tests

    !> A sweep's stability with reference_cache_t (the contact modes retuned to the next
    !> omega, the last monodromy as first Jacobian, the last orbit as first iterate) gives
    !> the multipliers of a solve without it, to roundoff: the chain (two contacts, forcing
    !> at harmonics 1 and 3, a relative contact) at omega 0.50, 0.51, 0.52, then at 0.70
    !> (beyond the 10 % the cache keeps its modes for: a new flow).
    subroutine test_cache(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: omegas(4) = [0.50_dp, 0.51_dp, 0.52_dp, 0.70_dp]
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(reference_options_t) :: ro
        type(reference_cache_t) :: cache
        type(floquet_t) :: fa, fb
        type(error_type), allocatable :: error
        integer :: k
        character(len=60) :: name
        m = chain_model()
        ho%harmonics = 25
        ho%samples = 512
        ho%want_samples = .true.
        do k = 1, size(omegas)
            write (name, '(a,f4.2)') "stability cache: omega = ", omegas(k)
            m%omega = omegas(k)
            call solve_periodic(m, ho, sol, error)
            call check(t, .not. allocated(error) .and. sol%converged, trim(name)//": solved")
            if (allocated(error) .or. .not. sol%converged) return
            call periodic_stability(m, sol, ro, fa, error)
            call check_error(t, error, trim(name)//": without the cache", .false.)
            if (allocated(error)) return
            call periodic_stability(m, sol, ro, fb, error, cache=cache)
            call check_error(t, error, trim(name)//": with the cache", .false.)
            if (allocated(error)) return
            call check(t, cache%have_flow .and. allocated(cache%mono), &
                       trim(name)//": the cache holds the flow and the monodromy")
            call check(t, fa%verdict == fb%verdict .and. fa%verdict /= 'unknown', &
                       trim(name)//": same verdict", fa%verdict//" / "//fb%verdict)
            if (size(fa%multipliers) /= size(fb%multipliers)) then
                call check(t, .false., trim(name)//": same number of multipliers")
                cycle
            end if
            call check_close(t, [real(fb%multipliers, dp), aimag(fb%multipliers)], &
                             [real(fa%multipliers, dp), aimag(fa%multipliers)], &
                             trim(name)//": same multipliers", rtol=0.0_dp, atol=1.0e-9_dp)
        end do
    end subroutine test_cache

    !> floquet_multipliers on matrices with known eigenvalues: sorting, the three verdicts,
    !> zero multipliers.
    subroutine test_classification(t)
        type(test_counter_t), intent(inout) :: t
        type(floquet_t) :: fl
        type(error_type), allocatable :: error
        real(dp) :: a(4, 4), q(4, 4), qinv(4, 4), c, s
        c = cos(0.3_dp)
        s = sin(0.3_dp)
        ! a rotation by 0.3 rad scaled by 0.9, 0.5 and 0 on the diagonal, in a skewed basis
        a = 0.0_dp
        a(1:2, 1:2) = 0.9_dp*reshape([c, s, -s, c], [2, 2])
        a(3, 3) = 0.5_dp
        q = reshape([1.0_dp, 0.2_dp, 0.0_dp, 0.1_dp, 0.0_dp, 1.0_dp, 0.3_dp, 0.0_dp, &
                     0.0_dp, 0.0_dp, 1.0_dp, 0.4_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [4, 4])
        ! q is unit lower triangular: its inverse by forward substitution on the identity
        qinv = lower_inverse(q)
        call floquet_multipliers(matmul(q, matmul(a, qinv)), fl, error)
        call check_error(t, error, "floquet: no error", .false.)
        if (allocated(error)) return
        call check_close(t, [real(fl%multipliers), aimag(fl%multipliers)], &
                         [0.9_dp*c, 0.9_dp*c, 0.5_dp, 0.0_dp, &
                          0.9_dp*s, -0.9_dp*s, 0.0_dp, 0.0_dp], &
                         "floquet: known multipliers, sorted", atol=1.0e-13_dp)
        call check(t, fl%verdict == 'stable' .and. fl%stable .and. fl%asymptotic .and. &
                   fl%nzero == 1, "floquet: rho = 0.9 is stable, one zero multiplier", &
                   fl%diagnosis)
        a(1:2, 1:2) = a(1:2, 1:2)/0.9_dp
        call floquet_multipliers(matmul(q, matmul(a, qinv)), fl, error)
        call check(t, fl%verdict == 'marginal' .and. fl%stable .and. .not. fl%asymptotic &
                   .and. fl%nmarginal == 2, "floquet: a rotation is marginal (stable, not "// &
                   "asymptotically)", fl%diagnosis)
        a(3, 3) = -1.01_dp
        call floquet_multipliers(matmul(q, matmul(a, qinv)), fl, error)
        call check(t, fl%verdict == 'unstable' .and. .not. fl%stable, &
                   "floquet: a multiplier -1.01 is unstable", fl%diagnosis)
        call check_close(t, real(fl%multipliers(1)), -1.01_dp, "floquet: -1.01 sorted first")
        call floquet_multipliers(a(1:3, :), fl, error)
        call check_error(t, error, "floquet: non-square monodromy rejected", .true.)
    end subroutine test_classification

    !> mu = 0 with damping C = 0.05 K + 0.02 M: the multipliers are exp(lambda_k T),
    !> lambda_k the eigenvalues of [[0, I], [-M^-1 K, -M^-1 C]] (M = I here); with C = 0
    !> they lie on the unit circle (marginal).
    subroutine test_linear_damped(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(floquet_t) :: fl
        complex(dp), allocatable :: expected(:)
        m = seed_model()
        m%damping = 0.05_dp*m%stiffness + 0.02_dp*m%mass
        m%mu = [0.0_dp]
        call stability_of(t, m, 3, fl, "mu = 0 damped")
        if (.not. allocated(fl%verdict)) return
        expected = linear_multipliers(m%stiffness, m%damping, two_pi/m%omega)
        call compare_sets(t, fl%multipliers, expected, 1.0e-11_dp, &
                          "mu = 0 damped: multipliers = exp(lambda T)")
        call check(t, fl%verdict == 'stable' .and. fl%stable .and. fl%nzero == 0, &
                   "mu = 0 damped: stable", fl%diagnosis)
        ! C = 0: multipliers exp(+-i w_k T) on the unit circle, Lyapunov-stable only
        m%damping = 0.0_dp*m%mass
        call stability_of(t, m, 3, fl, "mu = 0 undamped")
        if (.not. allocated(fl%verdict)) return
        expected = linear_multipliers(m%stiffness, m%damping, two_pi/m%omega)
        call compare_sets(t, fl%multipliers, expected, 1.0e-11_dp, &
                          "mu = 0 undamped: multipliers = exp(i w_k T)")
        call check(t, fl%verdict == 'marginal' .and. fl%stable .and. .not. fl%asymptotic &
                   .and. fl%nmarginal == 4, "mu = 0 undamped: marginal", fl%diagnosis)
    end subroutine test_linear_damped

    !> mu = 0 with negative damping C = -0.05 M: lambda = 0.025 +/- i sqrt(w_k^2 - 0.025^2)
    !> for both modes, so every multiplier has modulus exp(0.025 T) > 1.
    subroutine test_negative_damping(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(floquet_t) :: fl
        real(dp) :: period
        m = seed_model()
        m%damping = -0.05_dp*m%mass
        m%mu = [0.0_dp]
        period = two_pi/m%omega
        call stability_of(t, m, 3, fl, "negative damping")
        if (.not. allocated(fl%verdict)) return
        call check_close(t, abs(fl%multipliers), spread(exp(0.025_dp*period), 1, 4), &
                         "negative damping: |multipliers| = exp(0.025 T)", rtol=1.0e-11_dp)
        call check(t, fl%verdict == 'unstable' .and. .not. fl%stable .and. &
                   fl%max_modulus > 1.0_dp, "negative damping: unstable", fl%diagnosis)
    end subroutine test_negative_damping

    !> mu = 100: the contact is stuck all period. DOF 1 moves as the reduced system
    !> (x2 held): multipliers exp(lambda T), lambda the eigenvalues of [[0, 1], [-2, -c11]];
    !> the stuck slip velocity is projected out (multiplier 0); the stuck position keeps any
    !> offset (multiplier 1: a family of periodic orbits), so the verdict is 'marginal'.
    subroutine test_stuck(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(floquet_t) :: fl
        complex(dp), allocatable :: expected(:)
        m = seed_model()
        m%damping = 0.05_dp*m%stiffness + 0.02_dp*m%mass
        m%mu = [100.0_dp]
        call stability_of(t, m, 3, fl, "stuck")
        if (.not. allocated(fl%verdict)) return
        expected = [linear_multipliers(m%stiffness(1:1, 1:1), m%damping(1:1, 1:1), &
                                       two_pi/m%omega), (1.0_dp, 0.0_dp), (0.0_dp, 0.0_dp)]
        call compare_sets(t, fl%multipliers, expected, 1.0e-11_dp, &
                          "stuck: multipliers = reduced system, 1 (stuck offset), 0 (projected)")
        call check(t, fl%verdict == 'marginal' .and. fl%stable .and. .not. fl%asymptotic &
                   .and. fl%nzero == 1 .and. fl%nmarginal == 1, &
                   "stuck: marginal, one zero multiplier", fl%diagnosis)
    end subroutine test_stuck

    !> The seed case with light damping C = 0.02 K: stable; a perturbation of the periodic
    !> state integrated over kmax periods with the exact flow is the monodromy power applied
    !> to it (the linearization, saltations included), and decays like max_modulus^k.
    subroutine test_seed_damped(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: kmax = 40
        type(model_t) :: m
        type(floquet_t) :: fl
        type(reference_result_t) :: ref
        type(error_type), allocatable :: error
        real(dp), allocatable :: xs(:, :), vs(:, :), rs(:, :)
        real(dp) :: z(4), zp(4), z1(4), d0(4), lin(4), amp(4), ratio, rate, dhalf
        integer :: k
        character(len=120) :: buf
        m = seed_model()
        m%damping = 0.02_dp*m%stiffness
        call stability_of(t, m, 30, fl, "seed damped", ref)
        if (.not. allocated(fl%verdict)) return
        call check(t, fl%verdict == 'stable' .and. fl%stable .and. fl%max_modulus < 1.0_dp &
                   .and. fl%nzero >= 1, "seed damped: stable, stick phases give a zero "// &
                   "multiplier", fl%diagnosis)
        ! the periodic state at the section time: the start of the recorded orbit
        z = ref%orbit%phase_y(1:4, 1)
        call sample_reference(ref, 512, xs, vs, rs, error)
        call check_error(t, error, "seed damped: sampling", .false.)
        if (allocated(error)) return
        amp = [maxval(abs(xs), 1), maxval(abs(vs), 1)]
        d0 = 1.0e-6_dp*amp*[0.6_dp, -0.8_dp, 0.5_dp, 0.7_dp]
        zp = z + d0
        lin = d0
        do k = 1, kmax
            call ref%flow%period_map(ref%t_section, z, z1, error)
            if (allocated(error)) exit
            z = z1
            call ref%flow%period_map(ref%t_section, zp, z1, error)
            if (allocated(error)) exit
            zp = z1
            lin = matmul(ref%monodromy, lin)
            if (k == kmax/2) dhalf = norm2(zp - z)
        end do
        call check_error(t, error, "seed damped: perturbed periods", .false.)
        if (allocated(error)) return
        ! the perturbation after kmax periods is the monodromy power applied to it
        call check_close(t, zp - z, lin, "seed damped: perturbation = monodromy^k d0", &
                         rtol=1.0e-4_dp, atol=1.0e-4_dp*maxval(abs(lin)))
        ! it decays, at the rate of the largest multiplier once the transient (non-normal
        ! growth, the other multipliers) has passed: rate over periods kmax/2..kmax
        ratio = norm2(zp - z)/norm2(d0)
        rate = (norm2(zp - z)/dhalf)**(1.0_dp/(kmax - kmax/2))
        write (buf, '(a,es10.3,a,es10.3,a,es10.3)') "|d_k|/|d_0| ", ratio, &
            ", decay per period ", rate, ", max_modulus ", fl%max_modulus
        call check(t, ratio < 0.2_dp .and. rate <= 1.1_dp*fl%max_modulus .and. &
                   rate >= 0.85_dp*fl%max_modulus, &
                   "seed damped: the perturbation decays like max_modulus^k", trim(buf))
    end subroutine test_seed_damped

    !> The H = 30 weighted-residual solution of the seed case is not exactly periodic under
    !> the exact flow (small, nonzero defect); H = 150 does better (the defect of the state
    !> at t = 0 falls slowly with H: 5e-5, 3e-5, 1.7e-5 at H = 30, 90, 150); the exact
    !> orbit's own state repeats to the shooting tolerance.
    subroutine test_verify_periodicity(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: s30, s150, sref
        type(floquet_t) :: fl
        type(reference_options_t) :: ro
        type(reference_result_t) :: ref
        type(error_type), allocatable :: error
        real(dp), allocatable :: d30(:), d150(:), dref(:)
        character(len=160) :: buf
        m = seed_model()
        ho%harmonics = 30
        ho%samples = 512
        call solve_periodic(m, ho, s30, error)
        if (allocated(error) .or. .not. s30%converged) then
            call check(t, .false., "verify: H = 30 solved")
            return
        end if
        ho%harmonics = 150
        ho%odd_only = .true.
        ho%samples = 1200
        call solve_periodic(m, ho, s150, error)
        if (allocated(error) .or. .not. s150%converged) then
            call check(t, .false., "verify: H = 150 solved")
            return
        end if
        call verify_periodicity(m, s30, 2, d30, error)
        call check_error(t, error, "verify: H = 30 no error", .false.)
        if (allocated(error)) return
        call verify_periodicity(m, s150, 2, d150, error)
        if (allocated(error)) return
        ! the exact orbit (shot from H = 30), its state at t = 0 in place of the harmonic one
        call periodic_stability(m, s30, ro, fl, error, ref=ref)
        if (allocated(error) .or. .not. ref%converged) then
            call check(t, .false., "verify: reference solved")
            return
        end if
        sref = s30
        sref%x(1, :) = ref%x(1, :)
        sref%v(1, :) = ref%v(1, :)
        call verify_periodicity(m, sref, 2, dref, error)
        if (allocated(error)) return
        write (buf, '(a,2es10.2,a,2es10.2,a,2es10.2)') "H=30 ", d30, " H=150 ", d150, " ref ", &
            dref
        call check(t, all(d30 > 1.0e-6_dp) .and. all(d30 < 5.0e-2_dp), &
                   "verify: H = 30 defect small but nonzero", trim(buf))
        call check(t, d150(1) < 0.5_dp*d30(1), "verify: H = 150 defect below half H = 30's", &
                   trim(buf))
        call check(t, all(dref < 1.0e-9_dp), "verify: the exact orbit repeats", trim(buf))
        call verify_periodicity(m, s30, 0, d30, error)
        call check_error(t, error, "verify: periods = 0 rejected", .true.)
    end subroutine test_verify_periodicity

    !> Misuse and outcomes: no samples is an input error; a non-converged solution is an
    !> 'unknown' verdict, not an error.
    subroutine test_misuse(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_solution_t) :: sol
        type(reference_options_t) :: ro
        type(floquet_t) :: fl
        type(error_type), allocatable :: error
        call periodic_stability(seed_model(), sol, ro, fl, error)
        call check_error(t, error, "stability: a solution without samples rejected", .true., &
                         [character(len=12) :: "no samples"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "stability: no samples is stat input")
        allocate (sol%x(8, 2), sol%v(8, 2))
        sol%x = 0.0_dp
        sol%v = 0.0_dp
        sol%converged = .false.
        call periodic_stability(seed_model(), sol, ro, fl, error)
        call check_error(t, error, "stability: non-converged solution is no error", .false.)
        call check(t, fl%verdict == 'unknown' .and. .not. fl%stable .and. &
                   size(fl%multipliers) == 0, "stability: non-converged solution -> unknown")
    end subroutine test_misuse

    !> Weighted-residual solution of m with H harmonics, then its Floquet multipliers.
    subroutine stability_of(t, m, h, fl, name, ref)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        integer, intent(in) :: h
        type(floquet_t), intent(out) :: fl
        character(len=*), intent(in) :: name
        type(reference_result_t), intent(out), optional :: ref
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(reference_options_t) :: ro
        type(error_type), allocatable :: error
        ho%harmonics = h
        ho%samples = max(64, 16*h)
        call solve_periodic(m, ho, sol, error)
        call check(t, .not. allocated(error) .and. sol%converged, name//": weighted residual")
        if (allocated(error) .or. .not. sol%converged) return
        ro%samples = 64
        call periodic_stability(m, sol, ro, fl, error, ref=ref)
        call check_error(t, error, name//": periodic_stability no error", .false.)
        if (allocated(error)) return
        call check(t, fl%verdict /= 'unknown' .and. fl%distance >= 0.0_dp .and. &
                   fl%distance < 0.05_dp, name//": exact orbit found near the solution", &
                   fl%diagnosis)
        if (fl%verdict == 'unknown') deallocate (fl%verdict)
    end subroutine stability_of

    !> exp(lambda T) for the eigenvalues lambda of [[0, I], [-K, -C]] (unit masses).
    function linear_multipliers(k, c, period) result(mult)
        real(dp), intent(in) :: k(:, :), c(:, :), period
        complex(dp), allocatable :: mult(:)
        real(dp), allocatable :: a(:, :), wr(:), wi(:), work(:)
        real(dp) :: vl(1, 1), vr(1, 1)
        integer :: n, i, info
        n = size(k, 1)
        allocate (a(2*n, 2*n), wr(2*n), wi(2*n), work(64*n))
        a = 0.0_dp
        do i = 1, n
            a(i, n + i) = 1.0_dp
        end do
        a(n + 1:, 1:n) = -k
        a(n + 1:, n + 1:) = -c
        call dgeev('N', 'N', 2*n, a, 2*n, wr, wi, vl, 1, vr, 1, work, size(work), info)
        mult = exp(cmplx(wr, wi, dp)*period)
    end function linear_multipliers

    !> The two sets of complex numbers agree within atol: every element of each is within
    !> atol of a distinct element of the other (greedy matching, sets of a few elements).
    subroutine compare_sets(t, actual, expected, atol, name)
        type(test_counter_t), intent(inout) :: t
        complex(dp), intent(in) :: actual(:), expected(:)
        real(dp), intent(in), value :: atol
        character(len=*), intent(in) :: name
        logical :: used(size(actual)), ok
        real(dp) :: worst, d
        integer :: i, j, best
        character(len=200) :: buf
        ok = size(actual) == size(expected)
        worst = 0.0_dp
        used = .false.
        if (ok) then
            do i = 1, size(expected)
                best = 0
                d = huge(1.0_dp)
                do j = 1, size(actual)
                    if (used(j)) cycle
                    if (abs(actual(j) - expected(i)) < d) then
                        d = abs(actual(j) - expected(i))
                        best = j
                    end if
                end do
                used(best) = .true.
                worst = max(worst, d)
            end do
            ok = worst <= atol
        end if
        write (buf, '(a,i0,a,i0,a,es10.3)') "sizes ", size(actual), " / ", size(expected), &
            ", worst distance ", worst
        call check(t, ok, name, trim(buf))
    end subroutine compare_sets

    !> Inverse of a unit lower triangular matrix.
    function lower_inverse(q) result(qi)
        real(dp), intent(in) :: q(:, :)
        real(dp) :: qi(size(q, 1), size(q, 2))
        integer :: i, j, n
        n = size(q, 1)
        qi = 0.0_dp
        do j = 1, n
            qi(j, j) = 1.0_dp
            do i = j + 1, n
                qi(i, j) = -dot_product(q(i, j:i - 1), qi(j:i - 1, j))
            end do
        end do
    end function lower_inverse
end module test_stability
