!> The exact event-driven reference: the periodic solution of the friction model, exact up
!> to root-finding and roundoff, that neither the weighted residual nor the time stepper
!> owns (DESIGN section 5).
!>
!> The periodic orbit is found by shooting on the period map, z(t0 + T) = z(t0) for the
!> state z = [x; v], with MINPACK hybrj and the exact Jacobian of the map (the monodromy
!> matrix with the saltation matrices at the events; stickslip_flow). The start is given by
!> the caller as samples of an approximate periodic orbit (solve_reference knows none of the
!> methods it judges; stickslip_reference_start computes a weighted-residual or implicit
!> Euler start and calls it). The section time t0 is taken where the contacts slip fastest
!> in the start, so that the shooting state is away from the stick-slip switching surfaces.
module stickslip_reference
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp, two_pi
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_untrusted
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, validate_model, contact_velocity_direction, &
        contact_normal_direction, contact_tangent2_direction
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_contact_element, only: channel_t, state_open, state_stick, state_slip
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_minpack, only: hybrj_options_t, hybrj_report_t, solve_hybrj
    use stickslip_flow, only: flow_t, new_flow, orbit_t
    use stickslip_flow_modes, only: mode_t, identity_matrix
    use stickslip_contact_measures, only: energy_balance_error
    use stickslip_wave_symmetry, only: wave_symmetry_t, wave_spans, stability_spans, shifted, &
        check_wave_symmetry
    use stickslip_dense_products, only: mat_mul
    implicit none
    private
    public :: reference_options_t, reference_result_t, solve_reference, sample_reference
    public :: validate_reference_options, reference_energy_error
    public :: energy_warning, energy_untrusted, coulomb_margin, reference_handles
    public :: reference_cache_t, keep_flow

    !> Energy balance error of a converged orbit above which a warning is given: the flow
    !> is exact up to root finding and roundoff (~1e-12 measured on the examples).
    real(dp), parameter :: energy_warning = 1.0e-6_dp
    !> Energy balance error above which the orbit cannot be trusted.
    real(dp), parameter :: energy_untrusted = 1.0e-2_dp
    !> Most samples of a light reference (solve_reference with light): a divisor of the
    !> start's samples, so that the light samples are every stride-th of the start's.
    integer, parameter :: light_samples = 128
    !> Relative margin of Coulomb's law |r| <= (1 + margin) mu N at the samples (the stuck
    !> force is solved to 1e-15; the margin is roundoff, not a truncation allowance).
    real(dp), parameter :: coulomb_margin = 1.0e-6_dp

    !> Options of the exact reference (&reference).
    type :: reference_options_t
        !> Output samples per period (reference.csv), t_k = k T / samples.
        integer :: samples = 1024
        !> Steps per period of the event bracketing grid (events closer than a step to each
        !> other are still found when the event function dips below zero between two grid
        !> points; more steps guard against grazing events).
        integer :: bracket_steps = 1000
        !> Periodicity defect accepted: the states one period apart differ by at most tol
        !> times the amplitude of the response (x and v separately).
        real(dp) :: tol = 1.0e-11_dp
        !> Period-map evaluations allowed per shooting attempt.
        integer :: maxfev = 200
        !> Tolerance of the numerical integration of the slip phases whose direction turns
        !> (2D friction): each collocation step's error estimate, relative to the state's
        !> size (stickslip_flow_nonlinear).
        real(dp) :: ode_tol = 1.0e-12_dp
    end type reference_options_t

    !> The reference solution: its report, its events, its energy balance and samples.
    type :: reference_result_t
        !> The periodicity defect met the tolerance.
        logical :: converged = .false.
        !> Periodicity defect of the final orbit (relative, the larger of x and v).
        real(dp) :: defect = huge(1.0_dp)
        !> Period-map evaluations and Jacobians (monodromy matrices), all attempts.
        integer :: nfev = 0, njev = 0
        !> CPU seconds of the shooting and sampling, and of computing the start (the latter
        !> filled by solve_reference_from_starts).
        real(dp) :: seconds = 0.0_dp, start_seconds = 0.0_dp
        !> The start used: 'hbm' or 'euler' ('' when none could be made).
        character(len=:), allocatable :: start
        !> Empty when converged, otherwise what went wrong and what to try.
        character(len=:), allocatable :: diagnosis
        !> Section time of the shooting [s].
        real(dp) :: t_section = 0.0_dp
        !> The map the orbit is a fixed point of: the flow over T / spans from t_section,
        !> its state then shifted back by span_shift sectors of `sectors` (a disk's
        !> travelling wave, stickslip_wave_symmetry; spans = 1: the period map).
        integer :: spans = 1, span_shift = 0, sectors = 1
        !> Work of the forcing, friction and viscous dissipation over one period [J].
        real(dp) :: work_forcing = 0.0_dp, diss_friction = 0.0_dp, diss_damping = 0.0_dp
        !> Gross work of the forcing over one period, integral |f . v| dt [J].
        real(dp) :: work_gross = 0.0_dp
        !> Share of the period each contact sticks, and its number of stick phases.
        real(dp), allocatable :: stick_fraction(:)
        integer, allocatable :: stick_phases(:)
        !> Events in one period, sorted by time in [0, T): time [s], contact, kind
        !> (stickslip_flow event_*), slip direction after (0 stuck), force [N] and slip
        !> velocity [m/s] at the event.
        integer :: nevent = 0
        real(dp), allocatable :: event_t(:), event_force(:), event_velocity(:)
        integer, allocatable :: event_contact(:), event_kind(:), event_direction(:)
        !> Samples at t_k = k T / samples: instants [s], x [m], v [m/s], r [N] (with
        !> contact laws the forces of every force channel, samples x n_ch,
        !> stickslip_contact_set's order).
        real(dp), allocatable :: t(:), x(:, :), v(:, :), r(:, :)
        !> The contacts and their force channels.
        type(contact_set_t) :: contacts
        !> Contact state at the samples, samples x n_c (state_open, state_stick, state_slip
        !> of stickslip_contact_law); normal force [N] (the constant load of a plain
        !> contact) and gap [m] (0 for a plain contact), samples x n_c.
        integer, allocatable :: state(:, :)
        real(dp), allocatable :: normal(:, :), gap(:, :)
        !> Share of the period each contact is open (contact laws; 0 otherwise).
        real(dp), allocatable :: open_fraction(:)
        !> Kinetic energy lost in the plastic impacts of rigid unilateral contacts over one
        !> period [J] (part of the energy balance).
        real(dp) :: impact_loss = 0.0_dp
        !> Sum over one period of the error estimates of the numerically integrated slip
        !> steps, relative to the state's size (0: every phase solved exactly).
        real(dp) :: integration_error = 0.0_dp
        !> The internal states of the elements at the samples (slider positions [m]),
        !> samples x n_s (n_s = 0 without).
        real(dp), allocatable :: s(:, :)
        !> The flow and the recorded orbit, to sample the solution on other grids.
        type(flow_t) :: flow
        type(orbit_t) :: orbit
        !> Monodromy matrix of the final orbit at t_section: the Jacobian dz(t_section + T) /
        !> dz(t_section) of the period map of z = [x; v] (2N x 2N; phase flows times
        !> saltation matrices). When contacts are stuck at t_section it includes the
        !> M-orthogonal projection of the start perturbation onto zero slip velocity of
        !> those contacts (a velocity kick at a stuck contact is absorbed in a vanishing
        !> slip), so its zero eigenvalues are the projected directions. Allocated once the
        !> recording pass ran (also for an orbit that did not meet the tolerance).
        real(dp), allocatable :: monodromy(:, :)
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type reference_result_t

    !> What one shooting leaves for the next one on the same model at a nearby omega (the
    !> points of a sweep in omega): the flow with its cache of contact modes, whose
    !> exponentials are retuned to the new omega instead of being rebuilt
    !> (stickslip_flow_modes, retune_modes), and the last converged monodromy, hybrj's
    !> first Jacobian when the section falls on the same sample (Broyden updates correct it;
    !> hybrj asks for an exact one when they do not suffice). The multipliers are those of
    !> the final orbit's own monodromy either way. One cache per sequence of solves (per
    !> thread); the caller keeps it and must not change the model except its omega.
    type :: reference_cache_t
        !> A flow is held, built for contact velocity scales vref.
        logical :: have_flow = .false.
        type(flow_t) :: flow
        real(dp), allocatable :: vref(:)
        !> The last converged monodromy (model coordinates), the section's sample and the
        !> number of samples of its start.
        real(dp), allocatable :: mono(:, :)
        integer :: ksec = 0, ns = 0
        !> That orbit's state at the section, and the start's state there (the shooting
        !> starts from the last orbit moved by the change of the start: the truncation
        !> error of a weighted-residual start changes little from one point to the next).
        real(dp), allocatable :: zorbit(:), zstart(:)
        !> The omega of that orbit, and the orbit and monodromy before it at the same
        !> section (omega_before = 0: none): the secant through the two monodromies is the
        !> first Jacobian (a secant through the orbits as first iterate found another
        !> periodic orbit next to an unstable one: the iterate stays zorbit moved by the
        !> start's change).
        real(dp) :: omega = 0.0_dp, omega_before = 0.0_dp
        real(dp), allocatable :: mono_before(:, :), zorbit_before(:)
        !> The spans per period of the map whose Jacobian `mono` is (1: the period map; m:
        !> the map over T / m of a disk's travelling wave, stickslip_wave_symmetry).
        integer :: spans = 1
    end type reference_cache_t

    !> The shooting equations F(u) = (P(D u) - D u) / D, D the scales of x and v, for hybrj.
    type, extends(nonlinear_system_t) :: shooting_t
        type(flow_t) :: flow
        real(dp) :: t0 = 0.0_dp
        real(dp), allocatable :: scale(:), mono(:, :)
        !> A monodromy to use as the first Jacobian instead of computing one.
        real(dp), allocatable :: mono0(:, :)
        type(error_type), allocatable :: error
        !> Record the monodromy and the orbit with the residual when the norm predicted from
        !> the last two residuals, last^2 / previous, is at most record_below (hybrj's target:
        !> the next residual is then likely the last): the recording pass is saved when hybrj
        !> stops there. u_rec is that iterate (have_rec).
        logical :: record = .false., have_rec = .false.
        real(dp) :: record_below = 0.0_dp, fnorm_last = huge(1.0_dp), &
                    fnorm_prev = huge(1.0_dp)
        real(dp), allocatable :: u_rec(:), z1_rec(:), mono_rec(:, :)
        type(orbit_t) :: orbit_rec
        !> A disk's travelling wave (stickslip_wave_symmetry): the map is z0 -> S^-1 z(t0 +
        !> T / spans), S the shift of `shift` sectors of `sectors` (spans = 1: the period
        !> map); nx, nsx: DOFs and internal states per sector.
        integer :: spans = 1, shift = 0, sectors = 1, nx = 0, nsx = 0
    contains
        procedure :: map => shooting_map
        procedure :: residual => shooting_residual
        procedure :: jacobian => shooting_jacobian
    end type shooting_t

contains

    !> Whether the exact reference handles the contacts of `model`: every contact element's
    !> law (contact_element_t%exact_support). `why` is empty when it does; otherwise it
    !> names the contact and the law, and the yardstick (implicit Euler at small steps).
    logical function reference_handles(model, why) result(ok)
        !> The model.
        type(model_t), intent(in) :: model
        !> Empty when handled; otherwise the reason.
        character(len=:), allocatable, intent(out) :: why
        type(contact_set_t) :: cs
        integer :: j
        ok = .true.
        why = ""
        call new_contact_set(cs, model)
        do j = 1, cs%ncontact
            why = cs%elements(j)%e%exact_support()
            if (len(why) > 0) then
                why = why//" (contact "//itoa(j)//"): the yardstick for it is implicit "// &
                      "Euler at small steps"
                ok = .false.
                return
            end if
        end do
    end function reference_handles

    !> Check reference options. Errors (stat input) name the
    !> component ("opts%samples = 0: must be >= 1").
    subroutine validate_reference_options(opts, error)
        !> Options to check.
        type(reference_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Largest samples (the result holds samples x (2 ndof + ncontact + 1) doubles).
        integer, parameter :: reference_max_samples = 10**6
        !> Largest bracket_steps (event-search steps per period, each a matrix update).
        integer, parameter :: reference_max_bracket_steps = 10**5
        character(len=200) :: buf
        if (opts%samples < 1) then
            write (buf, '(a,i0,a)') "opts%samples = ", opts%samples, ": must be >= 1"
        else if (opts%samples > reference_max_samples) then
            write (buf, '(a,i0,a,i0)') "opts%samples = ", opts%samples, &
                ": must be <= ", reference_max_samples
        else if (opts%bracket_steps < 8) then
            write (buf, '(a,i0,a)') "opts%bracket_steps = ", opts%bracket_steps, &
                ": must be >= 8"
        else if (opts%bracket_steps > reference_max_bracket_steps) then
            write (buf, '(a,i0,a,i0)') "opts%bracket_steps = ", opts%bracket_steps, &
                ": must be <= ", reference_max_bracket_steps
        else if (.not. (opts%tol > 0.0_dp .and. opts%tol < 1.0_dp)) then
            write (buf, '(a,g0.6,a)') "opts%tol = ", opts%tol, ": must be in (0, 1)"
        else if (opts%maxfev < 1) then
            write (buf, '(a,i0,a)') "opts%maxfev = ", opts%maxfev, ": must be >= 1"
        else if (.not. (opts%ode_tol >= 1.0e-15_dp .and. opts%ode_tol <= 1.0e-3_dp)) then
            write (buf, '(a,g0.6,a)') "opts%ode_tol = ", opts%ode_tol, &
                ": must be in [1e-15, 1e-3]"
        else
            return
        end if
        call fatal_error(error, trim(buf), stickslip_stat%input)
    end subroutine validate_reference_options

    !> The exact periodic solution of `model`, shot from an approximate periodic orbit: the
    !> samples x_start, v_start of one period at t_k = k T / ns, k = 0..ns-1 (ns x N [m],
    !> [m/s]; e.g. a weighted-residual or implicit Euler solution). The section time is
    !> taken where the contacts slip fastest in the start, the scales of x and v from its
    !> amplitudes (the start strategy, reference_start_options_t%start, is that of
    !> stickslip_reference_start, solve_reference_from_starts). Not converging is an outcome
    !> (res%converged = F and res%diagnosis, with a diagnostics item 'not_converged'); the
    !> checks of a converged orbit (energy balance, Coulomb's law) go to res%diagnostics.
    !> Errors: stat input (invalid model or options, start samples of the wrong shape or not
    !> finite, a symmetry without light or that the model does not have); stat numerical
    !> (stuck contact constraints that no force holds: Painleve's paradox).
    subroutine solve_reference(model, opts, x_start, v_start, res, error, start_name, light, &
                               r_start, cache, symmetry, rest_scale)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Reference options.
        type(reference_options_t), intent(in) :: opts
        !> Displacements of the start over one period, ns x N [m].
        real(dp), intent(in) :: x_start(:, :)
        !> Velocities of the start over one period, ns x N [m/s].
        real(dp), intent(in) :: v_start(:, :)
        !> The reference solution.
        type(reference_result_t), intent(out) :: res
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Name of the start, reported in res%start and the diagnosis (default 'given').
        character(len=*), intent(in), optional :: start_name
        !> Only what a stability verdict needs (default .false.): the orbit, its monodromy
        !> and its samples on the start's grid or every stride-th of them (t_k = k T / m,
        !> m the largest divisor of ns up to 128, instead of opts%samples);
        !> no energy integrals and no checks of the converged orbit (res%diagnostics holds
        !> only a failure to converge).
        logical, intent(in), optional :: light
        !> The channel forces of the start, ns x n_ch [N]: the internal states of elements
        !> with one (the slider of a Jenkins or microslip element) come from them (absent:
        !> the springs of the sliders unloaded).
        real(dp), intent(in), optional :: r_start(:, :)
        !> What the last solve of this model left (reference_cache_t), updated: the flow
        !> goes into res%flow (hand it back with keep_flow), the monodromy stays.
        type(reference_cache_t), intent(inout), optional :: cache
        !> With light only: `model` is a disk assembled from a sector, forced in engine
        !> order (stickslip_wave_symmetry, checked): the orbit is shot with the map over T /
        !> m (m = N / gcd(EO, N)) and its monodromy over the period is S^m G^m, the same
        !> multipliers for m times less flow; res%orbit, events and fractions then cover
        !> that m-th of the period only (the samples cover the period). Where m does not
        !> divide the start's samples, the period map as without it.
        type(wave_symmetry_t), intent(in), optional :: symmetry
        !> A start at rest (the contacts hold the forcing: the weighted residual's at_rest):
        !> the velocity scale of the shooting [m/s] (its displacement scale this over omega),
        !> e.g. the weighted residual's fscale; the start's own amplitudes are roundoff
        !> then, and the flow's roundoff over a period would not meet the tolerance on them.
        real(dp), intent(in), optional :: rest_scale
        character(len=:), allocatable :: name
        logical :: is_light
        type(wave_symmetry_t) :: sym

        call validate_model(model, error)
        if (allocated(error)) return
        call validate_reference_options(opts, error)
        if (allocated(error)) return
        name = "given"
        if (present(start_name)) name = start_name
        if (size(x_start, 1) < 1 .or. size(x_start, 2) /= model%ndof .or. &
            any(shape(v_start) /= shape(x_start))) then
            call fatal_error(error, "solve_reference: x_start and v_start must both be "// &
                             "ns x N (ns >= 1 samples of one period, N = ndof)", &
                             stickslip_stat%input)
            return
        end if
        if (.not. (all(ieee_is_finite(x_start)) .and. all(ieee_is_finite(v_start)))) then
            call fatal_error(error, "solve_reference: the start ("//name//") is not finite", &
                             stickslip_stat%input)
            return
        end if
        res%start = name
        is_light = .false.
        if (present(light)) is_light = light
        if (present(symmetry)) then
            if (symmetry%sectors > 0) then
                if (.not. is_light) then
                    call fatal_error(error, "solve_reference: a wave symmetry needs light = "// &
                                     ".true. (the orbit is recorded over a part of the "// &
                                     "period)", stickslip_stat%input)
                    return
                end if
                call check_wave_symmetry(model, symmetry, error)
                if (allocated(error)) then
                    error%message = "solve_reference: "//error%message
                    return
                end if
                sym = symmetry
            end if
        end if
        call shoot_from(model, opts, name, x_start, v_start, res, error, is_light, sym, &
                        r_start, cache, rest_scale)
        if (allocated(error)) return
        if (res%converged .and. is_light) then
            continue
        else if (res%converged) then
            call check_reference(model, res)
        else
            call res%diagnostics%add(level_untrusted, "not_converged", res%diagnosis)
        end if
    end subroutine solve_reference

    !> Checks of a converged reference orbit, as diagnostics items (doc/where-methods-fail.md,
    !> "Where each method fails"): the energy balance over one period; every element's force
    !> within its limits at the samples (the force-limit ratio, stickslip_contact_measures,
    !> at most 1 + coulomb_margin); the normal law of every gap channel: lambda >= 0, and
    !> for its gap (with the compliance) u = g + c lambda >= 0 and min(u, lambda) = 0
    !> (margins coulomb_margin of the contact's force and gap scales).
    subroutine check_reference(model, res)
        type(model_t), intent(in) :: model
        type(reference_result_t), intent(inout) :: res
        real(dp) :: e, ratio, fscale, gscale, un
        integer :: j, c0, m, c, k
        type(channel_t) :: ch
        character(len=300) :: buf
        e = reference_energy_error(res)
        ! NaN (work integrals that overflowed) fails the check too
        if (.not. (e <= energy_untrusted)) then
            write (buf, '(a,es10.2e3,a,es10.2e3,a)') "reference: energy balance error ", e, &
                " > ", energy_untrusted, " of the work per period: the orbit is not a "// &
                "solution of the model"
            call res%diagnostics%add(level_untrusted, "energy_balance", trim(buf))
        else if (e > energy_warning) then
            write (buf, '(a,es10.2e3,a,es10.2e3,a)') "reference: energy balance error ", e, &
                " > ", energy_warning, " of the work per period"
            call res%diagnostics%add(level_warning, "energy_balance", trim(buf))
        end if
        if (.not. allocated(res%r)) return
        associate (cs => res%contacts)
            do j = 1, cs%ncontact
                c0 = cs%first(j)
                m = cs%width(j)
                ratio = cs%elements(j)%e%force_ratio(res%r(:, c0:c0 + m - 1))
                if (ratio > 1.0_dp + coulomb_margin) then
                    write (buf, '(a,i0,a,es12.4e3,a)') "reference: contact ", j, &
                        " breaks Coulomb's law: its friction force reaches ", ratio, &
                        " of its limit"
                    call res%diagnostics%add(level_untrusted, "coulomb_law", trim(buf))
                    return
                end if
                c = cs%normal(j)
                if (c == 0) cycle
                ch = cs%channel(c)
                fscale = max(maxval(abs(res%normal(:, j))), maxval(abs(res%r(:, c0))), &
                             tiny(1.0_dp))
                gscale = max(maxval(abs(res%gap(:, j))), maxval(abs(res%x)), tiny(1.0_dp))
                do k = 1, size(res%t)
                    un = res%gap(k, j) + ch%compliance*res%normal(k, j)
                    if (res%normal(k, j) < -coulomb_margin*fscale .or. &
                        un < -coulomb_margin*gscale .or. &
                        min(abs(un)/gscale, max(res%normal(k, j), 0.0_dp)/fscale) > &
                        coulomb_margin) then
                        write (buf, '(a,i0,a,es12.4e3,a,es12.4e3,a,es12.4e3,a)') &
                            "reference: contact ", j, " breaks the normal law at t = ", &
                            res%t(k), " s: normal force ", res%normal(k, j), " N, gap ", &
                            res%gap(k, j), " m"
                        call res%diagnostics%add(level_untrusted, "signorini", trim(buf))
                        return
                    end if
                end do
            end do
        end associate
    end subroutine check_reference

    !> Relative energy balance error of a reference orbit over one period:
    !> |work_forcing - diss_friction - diss_damping - impact_loss| / max(|work_forcing|,
    !> 1e-6 work_gross, tiny) (dimensionless; the gross work is the scale when the net
    !> work is ~0).
    pure real(dp) function reference_energy_error(res) result(e)
        !> A reference solution.
        type(reference_result_t), intent(in) :: res
        e = energy_balance_error(res%work_forcing, res%diss_friction, res%diss_damping, &
                                 res%impact_loss, res%work_gross)
    end function reference_energy_error

    !> One shooting attempt from samples xs, vs (t_k = k T / size(xs, 1)) of an approximate
    !> periodic solution (rs its channel forces, for the internal states), then the recording
    !> pass, the events and the samples.
    subroutine shoot_from(model, opts, name, xs, vs, res, error, light, sym, rs, cache, &
                          rest_scale)
        type(model_t), intent(in) :: model
        type(reference_options_t), intent(in) :: opts
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: xs(:, :), vs(:, :)
        type(reference_result_t), intent(inout) :: res
        type(error_type), allocatable, intent(out) :: error
        logical, intent(in) :: light
        !> A disk's wave symmetry (sectors = 0: none).
        type(wave_symmetry_t), intent(in) :: sym
        real(dp), intent(in), optional :: rs(:, :)
        type(reference_cache_t), intent(inout), optional :: cache
        !> A start at rest: the shooting's velocity scale [m/s] (solve_reference).
        real(dp), intent(in), optional :: rest_scale
        type(shooting_t) :: shooting
        type(mode_t), allocatable :: modes(:)
        type(hybrj_options_t) :: hopts
        type(hybrj_report_t) :: report
        real(dp), allocatable :: vref(:), u(:), z0(:), z1(:), speed(:), w(:), gs(:), ss(:), &
                                 rk(:), zs(:), zp(:), jmap(:, :)
        real(dp) :: c0, c1, period, xscale, vscale, ampx, ampv, ampz, gamp, dx(3), vfloor, ratio
        logical :: rest_start
        integer :: n, nc, ns, j, k, ksec, nsamp, nz, nstate, s0, m, ushift, kfirst
        logical :: reused
        type(channel_t) :: ch
        character(len=400) :: buf

        c0 = thread_cpu_seconds()
        n = model%ndof
        nc = model%ncontact()
        ns = size(xs, 1)
        period = two_pi/model%omega
        res%start = name
        ! scales of the state and of each contact's slip velocity, from the start
        xscale = maxval(abs(xs))
        vscale = maxval(abs(vs))
        if (.not. (xscale > 0.0_dp)) xscale = 1.0_dp
        if (.not. (vscale > 0.0_dp)) vscale = 1.0_dp
        allocate (vref(nc), speed(ns))
        speed = huge(1.0_dp)
        call new_contact_set(res%contacts, model)
        ! a contact's velocity scale: its slip velocity's amplitude, at least 1e-3 of the
        ! structure's or of the forcing's static velocity omega |f| / max K_ii (a contact
        ! stuck all period slips at roundoff speeds in the start, which must count as rest)
        vfloor = 1.0e-3_dp*max(maxval(abs(vs)), maxval(abs(xs))*model%omega)
        if (allocated(model%force_amplitude) .and. allocated(model%stiffness)) &
            vfloor = max(vfloor, 1.0e-3_dp*model%omega*sum(abs(model%force_amplitude))/ &
                         max(maxval([(abs(model%stiffness(k, k)), k=1, n)]), tiny(1.0_dp)))
        if (.not. (vfloor > 0.0_dp .and. vfloor <= huge(1.0_dp))) vfloor = 1.0_dp
        ! a start at rest (the contacts hold the forcing, its motion is roundoff): the
        ! caller's scale, on which the flow's roundoff over a period meets the tolerance
        rest_start = .false.
        if (present(rest_scale)) rest_start = rest_scale > 0.0_dp .and. &
                                              rest_scale <= huge(1.0_dp)
        if (rest_start) then
            vscale = max(vscale, rest_scale)
            xscale = max(xscale, rest_scale/model%omega)
        end if
        do j = 1, nc
            w = contact_velocity_direction(model, j)
            vref(j) = max(maxval(abs(matmul(vs, w))), vfloor)
            if (res%contacts%normal(j) > 0) then
                ! a unilateral contact is away from its switching surfaces where it is
                ! clearly open or slips fast
                ch = res%contacts%channel(res%contacts%normal(j))
                gs = ch%gap + matmul(xs, contact_normal_direction(model, j))
                gamp = max(maxval(abs(gs)), tiny(1.0_dp))
                speed = min(speed, max(abs(matmul(vs, w))/vref(j), gs/gamp))
            else if (res%contacts%elements(j)%e%force_scale() > 0.0_dp) then
                speed = min(speed, abs(matmul(vs, w))/vref(j))
            end if
        end do
        ! section: where the contacts slip fastest (away from the switching surfaces)
        ksec = maxloc(speed, 1)
        if (all(speed == huge(1.0_dp))) ksec = 1
        if (present(cache)) then
            ! the last orbit's section while the contacts still slip fast there (its
            ! monodromy is then a first Jacobian for this one)
            if (cache%ns == ns .and. cache%ksec >= 1 .and. cache%ksec <= ns) then
                if (speed(cache%ksec) >= 0.5_dp*speed(ksec)) ksec = cache%ksec
            end if
        end if
        res%t_section = period*real(ksec - 1, dp)/real(ns, dp)

        reused = .false.
        if (present(cache)) call reuse_flow(cache, model, opts, vref, shooting%flow, reused)
        if (.not. reused) then
            call new_flow(shooting%flow, model, opts%bracket_steps, vref, error, opts%ode_tol)
            if (allocated(error)) return
            if (present(cache)) then
                cache%vref = vref
                if (allocated(cache%mono)) deallocate (cache%mono)
            end if
        end if
        nz = shooting%flow%nz
        nstate = shooting%flow%ns
        ! the grid of the samples; a disk's travelling wave is shot over T / m when that
        ! grid holds whole spans (stickslip_wave_symmetry)
        nsamp = opts%samples
        if (light) nsamp = light_grid(ns, 1)
        if (light .and. sym%sectors > 0) then
            call wave_spans(sym, m, ushift)
            m = stability_spans(sym, ns)
            if (m > 1 .and. modulo(nstate, sym%sectors) == 0) then
                nsamp = light_grid(ns, m)
                shooting%spans = m
                shooting%shift = ushift
                shooting%sectors = sym%sectors
                shooting%nx = n/sym%sectors
                shooting%nsx = nstate/sym%sectors
            end if
        end if
        ! the elements' internal states at the section, from the start's displacements and
        ! channel forces
        allocate (ss(nstate))
        s0 = 0
        do j = 1, nc
            associate (e => res%contacts%elements(j)%e, c0j => res%contacts%first(j), &
                       m => res%contacts%width(j))
                if (e%nstate() == 0) cycle
                dx(1) = dot_product(xs(ksec, :), shooting%flow%w(:, j))
                dx(2) = dot_product(xs(ksec, :), contact_tangent2_direction(model, j))
                dx(3) = dot_product(xs(ksec, :), contact_normal_direction(model, j))
                rk = [(0.0_dp, k=1, m)]
                if (present(rs)) then
                    if (size(rs, 1) == ns .and. size(rs, 2) == res%contacts%nchannel) &
                        rk = rs(ksec, c0j:c0j + m - 1)
                end if
                call e%initial_states(dx, rk, ss(s0 + 1:s0 + e%nstate()))
                s0 = s0 + e%nstate()
            end associate
        end do
        shooting%t0 = res%t_section
        res%spans = shooting%spans
        res%span_shift = shooting%shift
        res%sectors = shooting%sectors
        shooting%scale = [(xscale, k=1, n), (vscale, k=1, n), (xscale, k=1, nstate)]
        allocate (shooting%mono(nz, nz))
        zs = [xs(ksec, :), vs(ksec, :), ss]
        ! at rest the start's velocities are the solve's noise: the orbit's are zero (a
        ! noise velocity would start a stuck contact slipping)
        if (rest_start) zs(n + 1:2*n) = 0.0_dp
        u = zs/shooting%scale
        if (present(cache)) then
            ! the last orbit at the same section: its monodromy is hybrj's first Jacobian,
            ! and it moved by the change of the start is the first iterate (unless that
            ! lands farther from the start than a tenth of its amplitude)
            if (allocated(cache%mono)) then
                if (cache%ksec == ksec .and. cache%ns == ns .and. size(cache%mono, 1) == nz &
                    .and. cache%spans == shooting%spans) then
                    shooting%mono0 = cache%mono
                    zp = cache%zorbit + (zs - cache%zstart)
                    if (cache%omega_before /= 0.0_dp .and. cache%omega /= cache%omega_before) then
                        ! the secant through the last two orbits (same section)
                        ratio = (model%omega - cache%omega)/(cache%omega - cache%omega_before)
                        if (abs(ratio) <= 2.0_dp) then
                            shooting%mono0 = cache%mono + ratio*(cache%mono - cache%mono_before)
                        end if
                    end if
                    if (maxval(abs(zp - zs)/shooting%scale) <= 0.1_dp) u = zp/shooting%scale
                end if
            end if
        end if
        hopts%mode = 1
        hopts%maxfev = opts%maxfev
        hopts%xtol = 1.0e-15_dp
        hopts%ftarget = opts%tol
        ! a light reference (a stability verdict) records its orbit with the residual that
        ! will likely be the last; a full one integrates energies on the grid (its phases on
        ! the ladder): its shooting steps the same way, so that its recording pass repeats
        ! the last residual's map (the tracked and the ladder's maps differ by roundoff,
        ! ~1e-11 of the state over a period on a stiff reduced model)
        shooting%flow%use_track = light
        shooting%record = light
        shooting%record_below = opts%tol
        call solve_hybrj(shooting, u, hopts, report, error)
        res%nfev = res%nfev + report%nfev
        res%njev = res%njev + report%njev
        if (allocated(error)) then
            if (allocated(shooting%error)) then
                ! the flow failed at some iterate: an outcome of this start, not of the model
                res%diagnosis = "shooting from the "//name//" start stopped: "// &
                                shooting%error%message//"."
                deallocate (error)
            end if
            return
        end if

        ! the recording pass over the final orbit (the period map projects its start onto
        ! the constraints of the start mode; the monodromy includes the projection)
        z0 = u*shooting%scale
        allocate (z1(nz))
        if (allocated(res%monodromy)) deallocate (res%monodromy)
        allocate (res%monodromy(nz, nz))
        if (shooting%have_rec .and. allocated(shooting%u_rec)) then
            if (all(shooting%u_rec == u)) then
                ! the last residual recorded the orbit: no recording pass
                res%monodromy = shooting%mono_rec
                res%orbit = shooting%orbit_rec
                z1 = shooting%z1_rec
            else
                call shooting%map(z0, z1, error, res%monodromy, res%orbit, .not. light)
            end if
        else
            call shooting%map(z0, z1, error, res%monodromy, res%orbit, .not. light)
        end if
        if (allocated(error)) then
            res%diagnosis = "shooting from the "//name//" start: "//error%message//"."
            deallocate (error, res%monodromy)
            return
        end if
        ! the map's Jacobian (for the next shooting) and the monodromy over the period
        jmap = res%monodromy
        if (shooting%spans > 1) res%monodromy = wave_monodromy(shooting, jmap)
        allocate (res%t(nsamp), res%x(nsamp, n), res%v(nsamp, n), &
                  res%r(nsamp, res%contacts%nchannel), res%state(nsamp, nc), &
                  res%s(nsamp, nstate))
        res%t = [(period*real(k, dp)/real(nsamp, dp), k=0, nsamp - 1)]
        if (shooting%spans > 1) then
            ! one span sampled, the others its shifts: z(t + j T / m) = S^j z(t)
            call shooting%flow%sample(res%orbit, nsamp, res%x, res%v, res%r, error, &
                                      res%state, res%s, count=nsamp/shooting%spans, &
                                      first=kfirst)
            if (allocated(error)) return
            call unfold_samples(shooting, res, kfirst)
        else
            call shooting%flow%sample(res%orbit, nsamp, res%x, res%v, res%r, error, &
                                      res%state, res%s)
            if (allocated(error)) return
        end if
        call contact_samples(model, res)
        ampx = max(maxval(abs(res%x)), maxval(abs(z0(1:n))))
        ampv = max(maxval(abs(res%v)), maxval(abs(z0(n + 1:2*n))))
        if (rest_start) then
            ! on the caller's scale, as the shooting
            ampx = max(ampx, xscale)
            ampv = max(ampv, vscale)
        end if
        res%defect = max(maxval(abs(z1(1:n) - z0(1:n)))/max(ampx, tiny(1.0_dp)), &
                         maxval(abs(z1(n + 1:2*n) - z0(n + 1:2*n)))/max(ampv, tiny(1.0_dp)))
        if (nstate > 0) then
            ! the sliders, on the scale of the displacements
            ampz = max(ampx, maxval(abs(z0(2*n + 1:))))
            res%defect = max(res%defect, maxval(abs(z1(2*n + 1:) - z0(2*n + 1:)))/ &
                             max(ampz, tiny(1.0_dp)))
        end if
        if (ampx == 0.0_dp .and. ampv == 0.0_dp) res%defect = 0.0_dp
        res%converged = res%defect <= opts%tol .and. all(ieee_is_finite(z1))
        if (present(cache)) then
            if (res%converged .and. all(ieee_is_finite(res%monodromy))) then
                cache%omega_before = 0.0_dp
                if (allocated(cache%mono) .and. cache%ksec == ksec .and. cache%ns == ns) then
                    if (size(cache%mono, 1) == nz .and. cache%spans == shooting%spans) then
                        call move_alloc(cache%mono, cache%mono_before)
                        call move_alloc(cache%zorbit, cache%zorbit_before)
                        cache%omega_before = cache%omega
                    end if
                end if
                cache%mono = jmap
                cache%spans = shooting%spans
                cache%ksec = ksec
                cache%ns = ns
                cache%zorbit = z0
                cache%zstart = zs
                cache%omega = model%omega
            else if (allocated(cache%mono)) then
                deallocate (cache%mono)
            end if
        end if
        ! the flow to the result without a deep copy of its mode cache (every mode's
        ! exponentials: megabytes on a reduced FE model with many contacts)
        call move_alloc(shooting%flow%modes, modes)
        res%flow = shooting%flow
        call move_alloc(modes, res%flow%modes)
        call finish_events(res, period)
        res%work_forcing = res%orbit%work_forcing
        res%work_gross = res%orbit%work_gross
        res%diss_friction = res%orbit%diss_friction
        res%diss_damping = res%orbit%diss_damping
        res%stick_fraction = res%orbit%stick_time/period
        res%impact_loss = res%orbit%impact_loss
        res%integration_error = res%orbit%integration_error
        res%open_fraction = res%orbit%open_time/period
        res%stick_phases = count_stick_phases(res, nc)
        if (res%converged) then
            res%diagnosis = ""
        else
            write (buf, '(a,es10.2e3,a,es10.2e3,a,i0,a,i0,a)') "shooting from the "//name// &
                " start did not converge: periodicity defect ", res%defect, " > tol ", &
                opts%tol, " (hybrj info ", report%info, ", ", report%nfev, &
                " period maps). The start may be too far from the orbit or the orbit may "// &
                "graze a switching surface: try &reference start = 'euler' or more "// &
                "bracket_steps"
            res%diagnosis = trim(buf)
        end if
        c1 = thread_cpu_seconds()
        res%seconds = res%seconds + (c1 - c0)
    end subroutine shoot_from

    !> The contacts' normal forces and gaps at the samples of res: a normal channel's force
    !> and its gap + n^T x; without one the constant normal load and 0.
    subroutine contact_samples(model, res)
        type(model_t), intent(in) :: model
        type(reference_result_t), intent(inout) :: res
        integer :: j, ns
        type(channel_t) :: ch
        ns = size(res%t)
        allocate (res%normal(ns, res%contacts%ncontact), res%gap(ns, res%contacts%ncontact))
        do j = 1, res%contacts%ncontact
            if (res%contacts%normal(j) > 0) then
                ch = res%contacts%channel(res%contacts%normal(j))
                res%normal(:, j) = res%r(:, res%contacts%normal(j))
                res%gap(:, j) = ch%gap + matmul(res%x, contact_normal_direction(model, j))
            else
                res%normal(:, j) = res%contacts%elements(j)%e%normal_load()
                res%gap(:, j) = 0.0_dp
            end if
        end do
    end subroutine contact_samples

    !> Events of the recorded orbit, mapped to [0, T) and sorted by time.
    subroutine finish_events(res, period)
        type(reference_result_t), intent(inout) :: res
        real(dp), intent(in) :: period
        integer :: m, i, k
        integer, allocatable :: order(:)
        real(dp), allocatable :: tm(:)
        m = res%orbit%nevent
        res%nevent = m
        allocate (tm(m), order(m))
        tm = modulo(res%orbit%event_t(1:m), period)
        ! insertion sort: a handful of events per period
        order = [(i, i=1, m)]
        do i = 2, m
            k = i
            do while (k > 1)
                if (tm(order(k - 1)) <= tm(order(k))) exit
                order([k - 1, k]) = order([k, k - 1])
                k = k - 1
            end do
        end do
        res%event_t = tm(order)
        res%event_contact = res%orbit%event_contact(order)
        res%event_kind = res%orbit%event_kind(order)
        res%event_direction = res%orbit%event_direction(order)
        res%event_force = res%orbit%event_force(order)
        res%event_velocity = res%orbit%event_velocity(order)
    end subroutine finish_events

    !> Stick phases per contact: runs of stuck phases of positive duration, counted
    !> cyclically over the period.
    function count_stick_phases(res, nc) result(phases)
        type(reference_result_t), intent(in) :: res
        integer, intent(in) :: nc
        integer :: phases(nc)
        integer :: j, p, m, prev
        logical, allocatable :: stuck(:)
        real(dp) :: tend, dur
        m = res%orbit%nphase
        tend = res%orbit%t0 + res%flow%period
        do j = 1, nc
            stuck = [logical ::]
            do p = 1, m
                if (p < m) then
                    dur = res%orbit%phase_t(p + 1) - res%orbit%phase_t(p)
                else
                    dur = tend - res%orbit%phase_t(p)
                end if
                if (dur <= 0.0_dp) cycle
                stuck = [stuck, res%flow%state_of(res%orbit%phase_mode(p), j) == state_stick]
            end do
            phases(j) = 0
            if (size(stuck) == 0) cycle
            if (all(stuck)) then
                phases(j) = 1
                cycle
            end if
            prev = size(stuck)
            do p = 1, size(stuck)
                if (stuck(p) .and. .not. stuck(prev)) phases(j) = phases(j) + 1
                prev = p
            end do
        end do
    end function count_stick_phases

    !> The reference solution sampled at t_k = k T / ng, k = 0..ng-1 (any grid size, e.g.
    !> the steps of an implicit Euler run): x(ng, N) [m], v(ng, N) [m/s], r(ng, n_c) [N]
    !> (with contact laws r(ng, n_ch), every force channel).
    !> Errors: stat input (no orbit: the solve did not get that far), stat numerical.
    subroutine sample_reference(res, ng, x, v, r, error)
        !> A reference solution.
        type(reference_result_t), intent(in) :: res
        !> Number of samples per period.
        integer, intent(in) :: ng
        !> Samples.
        real(dp), allocatable, intent(out) :: x(:, :), v(:, :), r(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        if (res%orbit%nphase < 1 .or. ng < 1) then
            call fatal_error(error, "sample_reference: no recorded orbit or ng < 1", &
                             stickslip_stat%input)
            return
        end if
        allocate (x(ng, res%flow%n), v(ng, res%flow%n), r(ng, res%contacts%nchannel))
        call res%flow%sample(res%orbit, ng, x, v, r, error)
    end subroutine sample_reference

    !> The map the shooting solves, from z0 at its section: the period map, or for a disk's
    !> travelling wave z0 -> S^-1 z(t0 + T / spans) (stickslip_wave_symmetry), with its
    !> Jacobian and the orbit over that span on request. Errors: those of period_map.
    subroutine shooting_map(self, z0, z1, error, mono, orbit, energies)
        class(shooting_t), intent(inout) :: self
        real(dp), intent(in) :: z0(:)
        real(dp), intent(out) :: z1(:)
        type(error_type), allocatable, intent(out) :: error
        real(dp), intent(out), optional :: mono(:, :)
        type(orbit_t), intent(out), optional :: orbit
        logical, intent(in), optional :: energies
        if (self%spans <= 1) then
            call self%flow%period_map(self%t0, z0, z1, error, mono, orbit, energies)
            return
        end if
        call self%flow%period_map(self%t0, z0, z1, error, mono, orbit, energies, &
                                  duration=self%flow%period/self%spans)
        if (allocated(error)) return
        z1 = state_shift(self, z1, -self%shift)
        if (present(mono)) mono = state_shift_rows(self, mono, -self%shift)
    end subroutine shooting_map

    !> The rows of `a` (states of the disk) shifted by k sectors, column by column.
    function state_shift_rows(self, a, k) result(w)
        type(shooting_t), intent(in) :: self
        real(dp), intent(in) :: a(:, :)
        integer, intent(in) :: k
        real(dp) :: w(size(a, 1), size(a, 2))
        integer :: j
        do j = 1, size(a, 2)
            w(:, j) = state_shift(self, a(:, j), k)
        end do
    end function state_shift_rows

    !> The state z = [x; v; s] shifted by k sectors (S^k with a shift of one sector per
    !> unit of k).
    function state_shift(self, z, k) result(w)
        type(shooting_t), intent(in) :: self
        real(dp), intent(in) :: z(:)
        integer, intent(in) :: k
        real(dp) :: w(size(z))
        integer :: nx, nsx
        nx = self%nx*self%sectors
        nsx = self%nsx*self%sectors
        w(1:nx) = shifted(z(1:nx), self%sectors, k)
        w(nx + 1:2*nx) = shifted(z(nx + 1:2*nx), self%sectors, k)
        if (nsx > 0) w(2*nx + 1:2*nx + nsx) = shifted(z(2*nx + 1:2*nx + nsx), self%sectors, k)
    end function state_shift

    !> The monodromy over the period from the Jacobian G of the shooting's map over T / m:
    !> S^m G^m (m = spans; G^m by repeated squaring).
    function wave_monodromy(self, g) result(mono)
        type(shooting_t), intent(in) :: self
        real(dp), intent(in) :: g(:, :)
        real(dp) :: mono(size(g, 1), size(g, 2))
        real(dp), allocatable :: p(:, :), q(:, :)
        integer :: e
        p = g
        e = self%spans
        q = identity_matrix(size(g, 1))
        do while (e > 0)
            if (modulo(e, 2) == 1) q = mat_mul(q, p)
            e = e/2
            if (e > 0) p = mat_mul(p, p)
        end do
        mono = state_shift_rows(self, q, self%spans*self%shift)
    end function wave_monodromy

    !> The samples of res outside the span sampled (nsamp / m rows from row kfirst + 1 on)
    !> from those in it: z(t + j T / m) = S^j z(t) for x, v, the channel forces, the
    !> contact states and the internal states (each in sector blocks).
    subroutine unfold_samples(self, res, kfirst)
        type(shooting_t), intent(in) :: self
        type(reference_result_t), intent(inout) :: res
        integer, intent(in) :: kfirst
        integer :: nsamp, nk, kk, j, k0, kj, ns
        real(dp), allocatable :: st(:)
        nsamp = size(res%t)
        nk = nsamp/self%spans
        ns = self%sectors
        do kk = 0, nk - 1
            k0 = modulo(kfirst + kk, nsamp) + 1
            do j = 1, self%spans - 1
                kj = modulo(kfirst + kk + j*nk, nsamp) + 1
                res%x(kj, :) = shifted(res%x(k0, :), ns, j*self%shift)
                res%v(kj, :) = shifted(res%v(k0, :), ns, j*self%shift)
                res%r(kj, :) = shifted(res%r(k0, :), ns, j*self%shift)
                if (size(res%s, 2) > 0) res%s(kj, :) = shifted(res%s(k0, :), ns, j*self%shift)
                st = shifted(real(res%state(k0, :), dp), ns, j*self%shift)
                res%state(kj, :) = nint(st)
            end do
        end do
    end subroutine unfold_samples

    !> The light grid of a start of ns samples: the largest divisor of ns that is a
    !> multiple of m and at most max(light_samples, m) (m divides ns: m itself is one).
    pure integer function light_grid(ns, m) result(nsamp)
        integer, intent(in) :: ns, m
        integer :: k
        nsamp = ns
        do k = 1, ns
            if (mod(ns, k) == 0 .and. ns/k <= max(light_samples, m) .and. &
                mod(ns/k, m) == 0) then
                nsamp = ns/k
                return
            end if
        end do
    end function light_grid

    !> F(u) = (P(D u) - D u) / D. The period map without its monodromy: hybrj asks for
    !> few Jacobians (Broyden updates in between), each computed in shooting_jacobian.
    subroutine shooting_residual(self, x, f, stat)
        class(shooting_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: f(:)
        integer, intent(inout) :: stat
        real(dp) :: z0(size(x)), z1(size(x))
        z0 = x*self%scale
        self%have_rec = .false.
        ! the next norm predicted from the last two (the convergence is superlinear)
        if (self%record .and. self%fnorm_last < huge(1.0_dp) .and. &
            self%fnorm_prev < huge(1.0_dp) .and. self%fnorm_prev > 0.0_dp .and. &
            self%fnorm_last**2/self%fnorm_prev <= self%record_below) then
            if (.not. allocated(self%mono_rec)) allocate (self%mono_rec(size(x), size(x)))
            call self%map(z0, z1, self%error, self%mono_rec, self%orbit_rec, .false.)
            self%have_rec = .not. allocated(self%error)
            self%u_rec = x
            self%z1_rec = z1
        else
            call self%map(z0, z1, self%error)
        end if
        if (allocated(self%error)) then
            stat = 1
            f = 0.0_dp
            return
        end if
        f = (z1 - z0)/self%scale
        self%fnorm_last = norm2(f)
        if (.not. all(ieee_is_finite(f))) then
            call fatal_error(self%error, "reference: the state became unbounded over one "// &
                             "period", stickslip_stat%numerical)
            stat = 1
            return
        end if
    end subroutine shooting_residual

    !> dF/du = D^{-1} (monodromy - I) D.
    subroutine shooting_jacobian(self, x, jac, stat)
        class(shooting_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: jac(:, :)
        integer, intent(inout) :: stat
        real(dp) :: z0(size(x)), z1(size(x))
        integer :: i, k
        if (allocated(self%mono0)) then
            ! a neighbouring orbit's monodromy, once (then exact ones)
            call move_alloc(self%mono0, self%mono)
        else if (self%have_rec .and. allocated(self%u_rec)) then
            ! the residual at this iterate recorded its monodromy
            if (all(self%u_rec == x)) then
                self%mono = self%mono_rec
            else
                z0 = x*self%scale
                call self%map(z0, z1, self%error, self%mono)
            end if
        else
            z0 = x*self%scale
            call self%map(z0, z1, self%error, self%mono)
        end if
        if (allocated(self%error)) then
            stat = 1
            jac = 0.0_dp
            return
        end if
        if (.not. all(ieee_is_finite(self%mono))) then
            call fatal_error(self%error, "reference: the monodromy matrix is not finite", &
                             stickslip_stat%numerical)
            stat = 1
            jac = 0.0_dp
            return
        end if
        do k = 1, size(x)
            do i = 1, size(x)
                jac(i, k) = self%mono(i, k)*self%scale(k)/self%scale(i)
            end do
            jac(k, k) = jac(k, k) - 1.0_dp
        end do
    end subroutine shooting_jacobian

    !> The cache's flow for a shooting of `model` with contact velocity scales vref, retuned
    !> to model%omega (moved out of the cache: `flow` holds it and `reused` is true), when
    !> it fits: the same numbers of DOFs and contacts (the same model, by the caller's
    !> contract: only omega changes), the same bracketing
    !> steps and integration tolerance, omega within 10 % and every velocity scale within a
    !> factor 4 of those it was built for (its grid step and event scales stay fit), and
    !> only linear contact modes (retune_modes). Otherwise the cache is emptied.
    subroutine reuse_flow(cache, model, opts, vref, flow, reused)
        type(reference_cache_t), intent(inout) :: cache
        type(model_t), intent(in) :: model
        type(reference_options_t), intent(in) :: opts
        real(dp), intent(in) :: vref(:)
        type(flow_t), intent(inout) :: flow
        logical, intent(out) :: reused
        type(mode_t), allocatable :: modes(:)
        reused = .false.
        if (.not. cache%have_flow) return
        cache%have_flow = .false.
        if (.not. allocated(cache%vref)) return
        if (cache%flow%n /= model%ndof .or. cache%flow%nc /= model%ncontact() .or. &
            size(cache%vref) /= size(vref) .or. cache%flow%steps /= opts%bracket_steps .or. &
            cache%flow%ode_tol /= opts%ode_tol) return
        if (abs(model%omega/cache%flow%omega - 1.0_dp) > 0.1_dp) return
        if (any(vref > 4.0_dp*cache%vref .or. cache%vref > 4.0_dp*vref)) return
        call move_alloc(cache%flow%modes, modes)
        flow = cache%flow
        call move_alloc(modes, flow%modes)
        call flow%retune(model%omega, reused)
    end subroutine reuse_flow

    !> Hand the flow of a shooting (res%flow, with its mode cache) to `cache` for the next
    !> solve of the same model (solve_reference with cache), without copying its modes;
    !> res%flow is left without modes (res cannot be sampled on other grids afterwards).
    subroutine keep_flow(cache, res)
        !> The cache of a sequence of solves.
        type(reference_cache_t), intent(inout) :: cache
        !> A result of solve_reference with that cache.
        type(reference_result_t), intent(inout) :: res
        type(mode_t), allocatable :: modes(:)
        if (.not. allocated(res%flow%modes) .or. .not. allocated(cache%vref)) return
        call move_alloc(res%flow%modes, modes)
        cache%flow = res%flow
        call move_alloc(modes, cache%flow%modes)
        cache%have_flow = .true.
    end subroutine keep_flow
end module stickslip_reference
