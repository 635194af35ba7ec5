!> Floquet stability of periodic solutions, and an a-posteriori check of a weighted-residual
!> solution against the exact flow.
!>
!> The multipliers are the eigenvalues of the monodromy matrix, the Jacobian of the exact
!> period map of z = [x; v] at the periodic orbit (stickslip_flow: phase flows times
!> saltation matrices; stickslip_reference: the orbit and its monodromy). A periodic
!> solution of the weighted residual is assessed on the exact orbit found by shooting from
!> it, never on the harmonic approximation itself (a truncated Fourier series cannot carry
!> the saltation at the stick-slip events).
!>
!> What the multipliers look like with dry friction:
!> - each slip -> stick event projects the slip velocity of the contact out of the
!>   perturbation: the monodromy is singular and has (numerically) zero multipliers;
!> - a contact stuck over the whole period keeps any offset of its stuck position (a
!>   family of periodic orbits): multiplier exactly 1;
!> - with C = 0 the slip phases are conservative (the friction force of a slipping contact
!>   does not depend on the state), so the multipliers not removed by sticking can sit on
!>   the unit circle to roundoff;
!> - the forced system is non-autonomous: there is no trivial multiplier 1 from a phase
!>   shift along the orbit.
!> Knows nothing of files; never prints.
module stickslip_stability
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp, two_pi
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_lapack, only: dgeev
    use stickslip_model, only: model_t, validate_model, contact_velocity_direction, &
        contact_tangent2_direction, contact_normal_direction
    use stickslip_solution, only: hbm_solution_t
    use stickslip_flow, only: flow_t, new_flow
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference, reference_cache_t, keep_flow
    use stickslip_wave_symmetry, only: wave_symmetry_t
    use stickslip_orbit_growth, only: orbit_growth_t, orbit_growth
    implicit none
    private
    public :: floquet_t, floquet_multipliers, periodic_stability, verify_periodicity
    public :: default_floquet_tol, max_orbit_distance

    !> Default half-width of the band |mu| in [1 - tol, 1 + tol] called 'marginal'. The
    !> monodromy is exact to about 1e-13 relative (matrix exponentials, events located to
    !> roundoff); a simple multiplier is then accurate to roundoff times its condition
    !> number, a double one on the unit circle (a Jordan block) only to about the square
    !> root of that, ~1e-7. 1e-6 keeps both out of the verdicts 'stable' and 'unstable'.
    real(dp), parameter :: default_floquet_tol = 1.0e-6_dp
    !> Largest relative distance (max over x and v of |difference| / amplitude) between a
    !> weighted-residual solution and the exact orbit shot from it for the orbit to count
    !> as the same periodic solution in periodic_stability.
    real(dp), parameter :: max_orbit_distance = 0.25_dp
    !> Where the orbit has simultaneous events, periodic_stability follows a perturbation
    !> along the dominant multiplier's direction with the exact flow for a period: a growth
    !> within growth_match (relative) of its modulus confirms the verdict. Otherwise the
    !> growth is measured over growth_periods periods after growth_settle, and one that
    !> contradicts the verdict by more than growth_margin in |log(growth)| (1 % a period)
    !> makes it 'unknown'.
    integer, parameter :: growth_periods = 4, growth_settle = 2
    real(dp), parameter :: growth_match = 1.0e-3_dp, growth_margin = 0.01_dp

    !> Floquet multipliers of a periodic solution and the verdict drawn from them.
    type :: floquet_t
        !> Eigenvalues of the monodromy matrix, by decreasing modulus (a complex-conjugate
        !> pair: positive imaginary part first). Empty when none could be computed.
        complex(dp), allocatable :: multipliers(:)
        !> Largest modulus (the spectral radius of the monodromy matrix); huge when unknown.
        real(dp) :: max_modulus = huge(1.0_dp)
        !> Linearly stable: no multiplier outside the unit circle beyond the tolerance
        !> (verdict 'stable' or 'marginal'). False when unstable or unknown.
        logical :: stable = .false.
        !> Asymptotically stable: every multiplier inside the circle |mu| < 1 - tol.
        logical :: asymptotic = .false.
        !> 'stable' (asymptotically), 'marginal' (the largest modulus is 1 within tol),
        !> 'unstable' or 'unknown' (no periodic orbit to assess).
        character(len=:), allocatable :: verdict
        !> A sentence for a person: the largest multiplier, the zero multipliers, caveats.
        character(len=:), allocatable :: diagnosis
        !> Tolerance of the classification used.
        real(dp) :: tol = default_floquet_tol
        !> Number of multipliers that are zero to roundoff (|mu| <= sqrt(eps) max(1, |M|)):
        !> directions projected out by stick phases.
        integer :: nzero = 0
        !> Multipliers on the unit circle within tol.
        integer :: nmarginal = 0
        !> periodic_stability: relative distance between the weighted-residual solution and
        !> the exact orbit shot from it (-1 when not computed).
        real(dp) :: distance = -1.0_dp
        !> CPU seconds: eigenvalues only (floquet_multipliers) or shooting + eigenvalues
        !> (periodic_stability).
        real(dp) :: seconds = 0.0_dp
        !> periodic_stability, where events of several contacts fall at one instant: the
        !> growth per period of perturbations followed by the exact flow
        !> (stickslip_orbit_growth); -1 when not measured.
        real(dp) :: flow_growth = -1.0_dp
    end type floquet_t

contains

    !> Floquet multipliers of the monodromy matrix `mono` (n x n, dimensionless) by LAPACK
    !> dgeev, sorted by decreasing modulus, and their classification with tolerance `tol`
    !> (default default_floquet_tol = 1e-6), on rho = max |mu|:
    !> - rho > 1 + tol: 'unstable', stable = F;
    !> - rho < 1 - tol: 'stable', stable = T, asymptotic = T (perturbations decay like rho^k
    !>   over k periods);
    !> - otherwise: 'marginal', stable = T, asymptotic = F.
    !> Marginal counts as stable: a multiplier on the unit circle is what an undamped mode
    !> untouched by friction, or the stuck position of a contact that never slips, gives:
    !> Lyapunov-stable, not asymptotically (perturbations neither grow nor decay at first
    !> order); a loss of stability is a multiplier leaving the circle. The linearization
    !> cannot decide for a repeated multiplier on the circle (a Jordan block grows linearly):
    !> the diagnosis then says so. Use `asymptotic` (or verdict == 'stable') when decay is
    !> required. Errors: stat input (not square, empty, tol outside (0, 1)); stat numerical
    !> (non-finite entries, the QR algorithm failed); stat lapack (argument error).
    subroutine floquet_multipliers(mono, fl, error, tol)
        !> Monodromy matrix (n x n).
        real(dp), intent(in) :: mono(:, :)
        !> The multipliers and the verdict.
        type(floquet_t), intent(out) :: fl
        !> Set on invalid input or numerical failure.
        type(error_type), allocatable, intent(out) :: error
        !> Half-width of the marginal band about |mu| = 1 (default 1e-6).
        real(dp), intent(in), optional :: tol
        real(dp), allocatable :: a(:, :), wr(:), wi(:), work(:), modulus(:)
        real(dp) :: vl(1, 1), vr(1, 1), query(1), c0, c1, zero_level, anorm
        integer :: n, info, lwork, i, k
        complex(dp) :: z
        character(len=240) :: buf

        c0 = thread_cpu_seconds()
        if (present(tol)) fl%tol = tol
        allocate (fl%multipliers(0))
        fl%verdict = 'unknown'
        fl%diagnosis = ''
        n = size(mono, 1)
        if (n < 1 .or. size(mono, 2) /= n) then
            call fatal_error(error, "floquet_multipliers: the monodromy matrix must be square "// &
                             "and not empty, got "//itoa(size(mono, 1))//" x "// &
                             itoa(size(mono, 2)), stickslip_stat%input)
            return
        end if
        if (.not. (fl%tol > 0.0_dp .and. fl%tol < 1.0_dp)) then
            call fatal_error(error, "floquet_multipliers: tol must be in (0, 1)", &
                             stickslip_stat%input)
            return
        end if
        if (.not. all(ieee_is_finite(mono))) then
            call fatal_error(error, "floquet_multipliers: the monodromy matrix is not finite", &
                             stickslip_stat%numerical)
            return
        end if
        a = mono
        allocate (wr(n), wi(n))
        call dgeev('N', 'N', n, a, n, wr, wi, vl, 1, vr, 1, query, -1, info)
        lwork = max(4*n, int(query(1)))
        allocate (work(lwork))
        call dgeev('N', 'N', n, a, n, wr, wi, vl, 1, vr, 1, work, lwork, info)
        if (info < 0) then
            call fatal_error(error, "dgeev: argument "//itoa(-info)//" is invalid", &
                             stickslip_stat%lapack)
            return
        else if (info > 0) then
            call fatal_error(error, "dgeev: the QR algorithm failed to compute all the "// &
                             "eigenvalues of the monodromy matrix", stickslip_stat%numerical)
            return
        end if

        ! sort: decreasing modulus, then decreasing imaginary part (insertion sort, n small)
        deallocate (fl%multipliers)
        allocate (fl%multipliers(n), modulus(n))
        fl%multipliers = cmplx(wr, wi, dp)
        do i = 2, n
            z = fl%multipliers(i)
            k = i - 1
            do while (k >= 1)
                if (.not. before(z, fl%multipliers(k))) exit
                fl%multipliers(k + 1) = fl%multipliers(k)
                k = k - 1
            end do
            fl%multipliers(k + 1) = z
        end do
        modulus = abs(fl%multipliers)
        fl%max_modulus = modulus(1)
        anorm = maxval(sum(abs(mono), 1))
        zero_level = sqrt(epsilon(1.0_dp))*max(1.0_dp, anorm)
        fl%nzero = count(modulus <= zero_level)
        fl%nmarginal = count(abs(modulus - 1.0_dp) <= fl%tol)

        if (fl%max_modulus > 1.0_dp + fl%tol) then
            fl%verdict = 'unstable'
            fl%stable = .false.
            fl%asymptotic = .false.
            write (buf, '(a,i0,a,es13.5e3,a,f9.5,a)') "unstable: ", &
                count(modulus > 1.0_dp + fl%tol), &
                " multiplier(s) outside the unit circle, the largest of modulus ", &
                fl%max_modulus, " (argument ", atan2(aimag(fl%multipliers(1)), &
                real(fl%multipliers(1), dp))/two_pi, " turns)"
            fl%diagnosis = trim(buf)
        else if (fl%max_modulus < 1.0_dp - fl%tol) then
            fl%verdict = 'stable'
            fl%stable = .true.
            fl%asymptotic = .true.
            write (buf, '(a,es13.5e3,a)') "asymptotically stable: largest multiplier modulus ", &
                fl%max_modulus, " < 1"
            fl%diagnosis = trim(buf)
        else
            fl%verdict = 'marginal'
            fl%stable = .true.
            fl%asymptotic = .false.
            write (buf, '(a,i0,a,es10.2e3,a)') "marginal: ", fl%nmarginal, &
                " multiplier(s) on the unit circle within ", fl%tol, &
                " (an undamped mode, or a contact stuck all period); Lyapunov-stable to "// &
                "first order, not asymptotically"
            fl%diagnosis = trim(buf)
            if (repeated_on_circle()) fl%diagnosis = fl%diagnosis// &
                "; a repeated multiplier on the circle: a Jordan block would grow "// &
                "linearly, the linearization does not decide"
        end if
        if (fl%nzero > 0) fl%diagnosis = fl%diagnosis//"; "//itoa(fl%nzero)// &
            " zero multiplier(s): directions removed by stick phases"
        c1 = thread_cpu_seconds()
        fl%seconds = c1 - c0

    contains

        !> Order of the multipliers: decreasing modulus, then decreasing imaginary part.
        logical function before(p, q)
            complex(dp), intent(in) :: p, q
            if (abs(p) /= abs(q)) then
                before = abs(p) > abs(q)
            else
                before = aimag(p) > aimag(q)
            end if
        end function before

        !> Two multipliers on the unit circle closer to each other than sqrt(tol).
        logical function repeated_on_circle()
            integer :: p, q
            repeated_on_circle = .false.
            do p = 1, n
                if (abs(modulus(p) - 1.0_dp) > fl%tol) cycle
                do q = p + 1, n
                    if (abs(modulus(q) - 1.0_dp) > fl%tol) cycle
                    if (abs(fl%multipliers(p) - fl%multipliers(q)) <= sqrt(fl%tol)) then
                        repeated_on_circle = .true.
                        return
                    end if
                end do
            end do
        end function repeated_on_circle
    end subroutine floquet_multipliers

    !> Floquet stability of the weighted-residual periodic solution `sol` of `model` (a
    !> converged hbm_solution_t with samples): the exact orbit is shot from it
    !> (solve_reference from the samples of sol whatever opts%start says: an implicit Euler
    !> start would find an attractor, possibly another orbit), and the
    !> multipliers of its monodromy matrix (reference_result_t%monodromy) are classified as
    !> in floquet_multipliers with `tol`. Outcomes, not errors: sol not converged, the
    !> shooting not converging, or converging to an orbit farther than max_orbit_distance
    !> from sol (up to a static offset where a contact sticks all period, whose mean force
    !> is undetermined): fl%verdict = 'unknown', fl%stable = F, fl%diagnosis says why (in the last
    !> case the multipliers of that other orbit are kept). fl%seconds is the CPU time of the
    !> shooting and the eigenvalues. `ref` returns the exact orbit (with its monodromy).
    !> With `symmetry` (a disk assembled from a sector and forced in engine order, its
    !> travelling wave: stickslip_wave_symmetry) and without `ref`, the orbit is shot with
    !> the flow over T / m, m = N / gcd(EO, N), and the multipliers are those of the same
    !> monodromy S^m G^m over the period (every perturbation of the disk), for m times less
    !> flow. Errors: stat input (invalid model or options, sol without samples, a model
    !> without the symmetry given); stat numerical (dependent stuck contact directions,
    !> non-finite monodromy).
    subroutine periodic_stability(model, sol, opts, fl, error, ref, tol, cache, symmetry)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> A weighted-residual solution of `model` with samples (want_samples).
        type(hbm_solution_t), intent(in) :: sol
        !> Options of the exact reference (shooting tolerance, bracketing steps).
        type(reference_options_t), intent(in) :: opts
        !> Multipliers and verdict.
        type(floquet_t), intent(out) :: fl
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> The exact orbit shot from `sol`.
        type(reference_result_t), intent(out), optional :: ref
        !> Half-width of the marginal band about |mu| = 1 (default 1e-6).
        real(dp), intent(in), optional :: tol
        !> What the stability of the previous point of a sweep in omega left (the contact
        !> modes and the monodromy: reference_cache_t), updated for the next point. The
        !> multipliers are the same with or without it, to roundoff.
        type(reference_cache_t), intent(inout), optional :: cache
        !> The model's travelling-wave symmetry (used without `ref` only).
        type(wave_symmetry_t), intent(in), optional :: symmetry
        type(reference_result_t) :: res
        type(wave_symmetry_t) :: sym
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :), xs(:, :), vs(:, :)
        real(dp) :: c0, c1, ampx, ampv, distance, ftol, rest
        integer :: stride
        logical :: finer
        character(len=400) :: buf

        c0 = thread_cpu_seconds()
        ftol = default_floquet_tol
        if (present(tol)) ftol = tol
        if (.not. (allocated(sol%x) .and. allocated(sol%v))) then
            call fatal_error(error, "periodic_stability: the weighted-residual solution has "// &
                             "no samples (solve it with want_samples = .true.)", &
                             stickslip_stat%input)
            return
        end if
        if (.not. sol%converged) then
            call unknown("the weighted-residual solution did not converge: no periodic "// &
                         "solution to assess")
            return
        end if
        ! the full reference (energies, checks, opts%samples) only when the caller wants it;
        ! a light one uses the symmetry of a disk's wave
        if (present(symmetry) .and. .not. present(ref)) sym = symmetry
        ! a solution at rest shoots on the scale of the solve's residual (its own motion
        ! is roundoff)
        rest = 0.0_dp
        if (sol%at_rest) rest = sol%fscale
        call solve_reference(model, opts, sol%x, sol%v, res, error, start_name='hbm', &
                             light=.not. present(ref), r_start=sol%r, cache=cache, &
                             symmetry=sym, rest_scale=rest)
        if (present(cache) .and. .not. allocated(error)) then
            if (.not. res%converged .or. .not. allocated(res%monodromy)) then
                ! the last orbit's start or Jacobian may have led the shooting astray: once
                ! more from the weighted-residual solution alone, the cache emptied
                cache = reference_cache_t()
                call solve_reference(model, opts, sol%x, sol%v, res, error, start_name='hbm', &
                                     light=.not. present(ref), r_start=sol%r, symmetry=sym, &
                                     rest_scale=rest)
            end if
        end if
        finer = .false.
        if (.not. allocated(error)) then
            if (.not. res%converged .or. .not. allocated(res%monodromy)) then
                ! an iterate met contacts switching again at one instant on the bracketing
                ! grid (a degenerate event the grid's placement decides): once more on a grid
                ! 1.5 times finer, not kept for the next point
                call solve_reference(model, finer_grid(opts), sol%x, sol%v, res, error, &
                                     start_name='hbm', light=.not. present(ref), &
                                     r_start=sol%r, symmetry=sym, rest_scale=rest)
                finer = .true.
            end if
        end if
        if (allocated(error)) then
            error%message = "periodic_stability: "//error%message
            return
        end if
        if (.not. res%converged .or. .not. allocated(res%monodromy)) then
            call unknown("no exact periodic orbit was found near the weighted-residual "// &
                         "solution: "//res%diagnosis)
            call give_ref()
            return
        end if
        call floquet_multipliers(res%monodromy, fl, error, ftol)
        if (allocated(error)) then
            error%message = "periodic_stability: "//error%message
            return
        end if
        ! the same orbit? compare on the grid of the weighted-residual samples (a light
        ! reference has every stride-th of them)
        stride = 0
        if (size(res%x, 1) > 0) then
            if (mod(size(sol%x, 1), size(res%x, 1)) == 0) stride = size(sol%x, 1)/size(res%x, 1)
        end if
        if (stride > 0) then
            xs = sol%x(1::stride, :)
            vs = sol%v(1::stride, :)
            xr = res%x
            vr = res%v
        else
            xs = sol%x
            vs = sol%v
            call sample_reference(res, size(sol%x, 1), xr, vr, rr, error)
            if (allocated(error)) return
        end if
        ! (at least what the weighted residual resolves: a structure at rest moves by
        ! roundoff, which the two solutions need not share)
        ampv = max(maxval(abs(vr)), sol%velocity_resolution, tiny(1.0_dp))
        ampx = max(maxval(abs(xr)), sol%velocity_resolution/model%omega, tiny(1.0_dp))
        distance = max(maxval(abs(xs - xr))/ampx, maxval(abs(vs - vr))/ampv)
        if (allocated(sol%offset_undetermined)) then
            if (any(sol%offset_undetermined)) then
                ! a contact stuck all period: the orbits of every admissible mean force are
                ! periodic (the shooting may land on another one than the settled value);
                ! they differ by a static offset and share their multipliers
                distance = max(maxval(abs(xs - spread(sum(xs, 1)/size(xs, 1), 1, &
                                                          size(xs, 1)) - &
                                          (xr - spread(sum(xr, 1)/size(xr, 1), 1, &
                                                       size(xr, 1)))))/ampx, &
                               maxval(abs(vs - vr))/ampv)
            end if
        end if
        fl%distance = distance
        if (distance > max_orbit_distance) then
            write (buf, '(a,es10.2e3,a)') "the exact orbit shot from the weighted-residual "// &
                "solution differs from it by ", distance, " of its amplitude: possibly "// &
                "another periodic solution; the multipliers are that orbit's: "
            fl%diagnosis = trim(buf)//" "//fl%diagnosis
            fl%verdict = 'unknown'
            fl%stable = .false.
            fl%asymptotic = .false.
        end if
        if (res%orbit%simultaneous > 0 .and. (fl%verdict == 'unstable' .or. &
                                              fl%verdict == 'stable')) call check_by_flow()
        call give_ref()
        c1 = thread_cpu_seconds()
        fl%seconds = c1 - c0

    contains

        subroutine unknown(why)
            character(len=*), intent(in) :: why
            fl%tol = ftol
            allocate (fl%multipliers(0))
            fl%verdict = 'unknown'
            fl%stable = .false.
            fl%asymptotic = .false.
            fl%diagnosis = why
            c1 = thread_cpu_seconds()
            fl%seconds = c1 - c0
        end subroutine unknown

        !> The orbit has events of several contacts at one instant: its monodromy is the
        !> Jacobian of one order of them (stickslip_orbit_growth). A perturbation along the
        !> dominant multiplier's direction followed by the exact flow over one period grows
        !> by its modulus (to growth_match): confirmed. Otherwise it is followed for
        !> growth_settle + growth_periods periods: the verdict stands when it grows or
        !> decays as the verdict says, becomes 'unknown' when it clearly does the opposite
        !> (by more than growth_margin a period), and says "not confirmed" within that
        !> margin of 1 or when the flow fails.
        subroutine check_by_flow()
            type(orbit_growth_t) :: g
            type(error_type), allocatable :: gerr
            character(len=:), allocatable :: instant
            real(dp), allocatable :: d(:, :)
            logical :: grows
            write (buf, '(a,i0,a,i0,a,es12.5e2,a)') "; contacts ", &
                res%orbit%simultaneous_contacts(1), " and ", &
                res%orbit%simultaneous_contacts(2), " switch at one instant (t = ", &
                res%orbit%simultaneous_t, " s), where the period map is only piecewise "// &
                "smooth and the monodromy is that of one order of such events"
            instant = trim(buf)
            ! one period from the dominant multiplier's direction: where the order of the
            ! events does not matter along it, the perturbation grows by its modulus;
            ! otherwise it is followed longer, from where the flow takes it
            d = dominant_direction(res%monodromy)
            call orbit_growth(res, d, 1, 0, g, gerr)
            if (.not. allocated(gerr)) then
                if (abs(g%rate - fl%max_modulus) <= growth_match*fl%max_modulus) then
                    fl%flow_growth = g%rate
                    write (buf, '(a,f9.5,a)') "; a perturbation along the dominant "// &
                        "multiplier's direction followed by the exact flow grows by", g%rate, &
                        " a period, its modulus: confirmed (doc/cyclic.md)"
                    fl%diagnosis = fl%diagnosis//instant//trim(buf)
                    return
                end if
                call orbit_growth(res, d, growth_periods, growth_settle, g, gerr)
            end if
            fl%flow_growth = g%rate
            if (allocated(gerr)) then
                fl%diagnosis = fl%diagnosis//instant//"; not confirmed: the perturbed "// &
                               "exact flow failed ("//gerr%message//") (doc/cyclic.md)"
                return
            end if
            grows = g%rate > 1.0_dp
            write (buf, '(a,a,a,f9.5,a,i0,a,i0,a)') "; perturbations followed by the exact "// &
                "flow ", trim(merge("grow  ", "decay ", grows)), " by a factor", g%rate, &
                " a period (over ", g%periods, " periods after ", growth_settle, &
                "), not by the dominant multiplier's modulus"
            if (grows .eqv. fl%verdict == 'unstable') then
                fl%diagnosis = fl%diagnosis//instant//trim(buf)//": confirmed (doc/cyclic.md)"
            else if (abs(log(max(g%rate, tiny(1.0_dp)))) > growth_margin) then
                fl%diagnosis = "unknown: the multipliers say "//fl%verdict// &
                               " (largest modulus "//trim(adjustl(fmt_g(fl%max_modulus)))// &
                               ")"//instant//trim(buf)//" (doc/cyclic.md); "//fl%diagnosis
                fl%verdict = 'unknown'
                fl%stable = .false.
                fl%asymptotic = .false.
            else
                fl%diagnosis = fl%diagnosis//instant//trim(buf)//": not confirmed, "// &
                               "within 1 % of 1 (doc/cyclic.md)"
            end if
        end subroutine check_by_flow

        subroutine give_ref()
            if (present(ref)) ref = res
            if (present(cache) .and. .not. finer) call keep_flow(cache, res)
        end subroutine give_ref

        !> The options with 1.5 times the bracketing steps.
        function finer_grid(o) result(f)
            type(reference_options_t), intent(in) :: o
            type(reference_options_t) :: f
            f = o
            f%bracket_steps = (3*o%bracket_steps)/2
        end function finer_grid
    end subroutine periodic_stability

    !> The eigenvector of the dominant multiplier of `mono` by LAPACK dgeev: n x 1 (a real
    !> multiplier) or n x 2 (the real and imaginary parts of a complex one's); a vector of
    !> ones when dgeev fails (the power iteration of orbit_growth then finds it).
    function dominant_direction(mono) result(d)
        real(dp), intent(in) :: mono(:, :)
        real(dp), allocatable :: d(:, :)
        real(dp), allocatable :: a(:, :), wr(:), wi(:), vr(:, :), work(:)
        real(dp) :: vl(1, 1), query(1)
        integer :: n, info, k
        n = size(mono, 1)
        allocate (d(n, 1))
        d = 1.0_dp
        a = mono
        allocate (wr(n), wi(n), vr(n, n))
        call dgeev('N', 'V', n, a, n, wr, wi, vl, 1, vr, n, query, -1, info)
        if (info /= 0) return
        allocate (work(max(4*n, int(query(1)))))
        call dgeev('N', 'V', n, a, n, wr, wi, vl, 1, vr, n, work, size(work), info)
        if (info /= 0) return
        k = maxloc(hypot(wr, wi), 1)
        ! a complex pair's vectors are columns k (real part) and k + 1 (imaginary part), the
        ! first of the pair carrying the positive imaginary part
        if (wi(k) < 0.0_dp .and. k > 1) k = k - 1
        if (wi(k) > 0.0_dp .and. k < n) then
            d = vr(:, k:k + 1)
        else
            d = vr(:, k:k)
        end if
    end function dominant_direction

    !> A real number as text, 6 significant digits.
    function fmt_g(x) result(s)
        real(dp), intent(in) :: x
        character(len=16) :: s
        write (s, '(es12.5e2)') x
    end function fmt_g

    !> A-posteriori check of a weighted-residual solution: integrate `periods` periods of the
    !> exact event-driven flow of `model` from the solution's state at t = 0 and return the
    !> relative periodicity defect after each, defect(k) = max(|x(kT) - x(0)|_inf / A_x,
    !> |v(kT) - v(0)|_inf / A_v) (dimensionless; A_x, A_v the largest |x|, |v| of the
    !> samples). An exact periodic orbit gives roundoff; a harmonic approximation gives its
    !> error, which grows over the periods toward the distance to the attracting orbit when
    !> that is stable and without bound when it is unstable. `bracket_steps` is the event
    !> bracketing grid (default 1000 per period). Errors: stat input (invalid model, no
    !> samples, periods < 1, bracket_steps < 8); stat numerical (the flow failed: unbounded
    !> state, chattering).
    subroutine verify_periodicity(model, sol, periods, defect, error, bracket_steps)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> A weighted-residual solution of `model` with samples (the first at t = 0).
        type(hbm_solution_t), intent(in) :: sol
        !> Number of periods to integrate (>= 1).
        integer, intent(in) :: periods
        !> Relative periodicity defect after each period, size `periods`.
        real(dp), allocatable, intent(out) :: defect(:)
        !> Set on invalid input or when the flow fails.
        type(error_type), allocatable, intent(out) :: error
        !> Event bracketing steps per period (default 1000).
        integer, intent(in), optional :: bracket_steps
        type(flow_t) :: flow
        real(dp), allocatable :: vref(:), w(:), z0(:), z(:), z1(:)
        real(dp) :: ampx, ampv, vscale
        integer :: n, nc, j, k, steps

        call validate_model(model, error)
        if (allocated(error)) return
        if (.not. (allocated(sol%x) .and. allocated(sol%v))) then
            call fatal_error(error, "verify_periodicity: the weighted-residual solution has "// &
                             "no samples (solve it with want_samples = .true.)", &
                             stickslip_stat%input)
            return
        end if
        n = model%ndof
        nc = model%ncontact()
        if (size(sol%x, 2) /= n .or. size(sol%v, 2) /= n .or. size(sol%x, 1) < 1) then
            call fatal_error(error, "verify_periodicity: the solution does not match the "// &
                             "model (number of DOFs)", stickslip_stat%input)
            return
        end if
        if (periods < 1) then
            call fatal_error(error, "verify_periodicity: periods must be >= 1", &
                             stickslip_stat%input)
            return
        end if
        steps = 1000
        if (present(bracket_steps)) steps = bracket_steps
        ampx = maxval(abs(sol%x))
        ampv = maxval(abs(sol%v))
        vscale = ampv
        if (.not. (vscale > 0.0_dp)) vscale = 1.0_dp
        allocate (vref(nc))
        do j = 1, nc
            w = contact_velocity_direction(model, j)
            vref(j) = maxval(abs(matmul(sol%v, w)))
            if (.not. (vref(j) > 0.0_dp)) vref(j) = vscale
        end do
        call new_flow(flow, model, steps, vref, error)
        if (allocated(error)) return
        allocate (defect(periods), z1(flow%nz))
        z0 = [sol%x(1, :), sol%v(1, :), start_states(flow, sol)]
        z = z0
        do k = 1, periods
            call flow%period_map(0.0_dp, z, z1, error)
            if (allocated(error)) then
                error%message = "verify_periodicity: period "//itoa(k)//": "//error%message
                return
            end if
            z = z1
            defect(k) = max(rel(z(1:n) - z0(1:n), ampx), rel(z(n + 1:2*n) - z0(n + 1:2*n), ampv))
        end do

    contains

        !> The elements' internal states at the solution's first sample (from its
        !> displacements and channel forces).
        function start_states(flow, sol) result(ss)
            type(flow_t), intent(in) :: flow
            type(hbm_solution_t), intent(in) :: sol
            real(dp) :: ss(flow%ns), dx(3)
            integer :: jj, s0, c0, m
            s0 = 0
            do jj = 1, flow%nc
                associate (e => flow%cs%elements(jj)%e)
                    if (e%nstate() == 0) cycle
                    c0 = flow%cs%first(jj)
                    m = flow%cs%width(jj)
                    dx = [dot_product(sol%x(1, :), flow%w(:, jj)), &
                          dot_product(sol%x(1, :), contact_tangent2_direction(model, jj)), &
                          dot_product(sol%x(1, :), contact_normal_direction(model, jj))]
                    call e%initial_states(dx, sol%r(1, c0:c0 + m - 1), &
                                          ss(s0 + 1:s0 + e%nstate()))
                    s0 = s0 + e%nstate()
                end associate
            end do
        end function start_states

        !> max |d| / a, or max |d| when a = 0.
        pure real(dp) function rel(d, a)
            real(dp), intent(in) :: d(:), a
            rel = maxval(abs(d))
            if (a > 0.0_dp) rel = rel/a
        end function rel
    end subroutine verify_periodicity
end module stickslip_stability
