!> One point of a forced-response curve, from the accepted state of the continuation: the
!> point solved for its outputs (amplitudes, dissipation, contact statistics) and checked
!> (harmonic truncation estimate, Floquet stability), and the tally of the checks the
!> points of a curve failed (the 'points_<key>' items of sweep_result_t%diagnostics).
module stickslip_sweep_point
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_untrusted
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hbm_sparse, only: solve_periodic_sparse
    use stickslip_continuation, only: continuation_state_t
    use stickslip_reference, only: reference_options_t, reference_cache_t
    use stickslip_stability, only: floquet_t, periodic_stability
    use stickslip_wave_symmetry, only: wave_symmetry_t
    use stickslip_truncation, only: truncation_t, estimate_truncation
    use stickslip_checks, only: truncation_warning, truncation_untrusted
    use stickslip_sweep_options, only: sweep_options_t, set_sweep_parameter
    use stickslip_sweep_result, only: frc_point_t
    use stickslip_friction_family, only: friction_family_t
    use stickslip_contact_set, only: channel_directions
    use stickslip_cyclic, only: cyclic_t, channel_displacements
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic, disk_solution
    use stickslip_dynamics, only: dynamics_t
    use stickslip_condensed_structure, only: condensed_structure_t
    implicit none
    private
    public :: point_tally_t, evaluate_point, keep_coefficients, contact_point_values
    public :: stability_block

    !> Which checks the points of a curve failed: per diagnostics key, how many points, the
    !> worst level and the parameter of the first (sweep_result_t%diagnostics gets one
    !> item per key, 'points_<key>').
    type :: point_tally_t
        !> The diagnostics keys of the failed checks ('truncation' for the estimate).
        character(len=48), allocatable :: key(:)
        !> Per key: points that failed the check, and the worst level (level_*).
        integer, allocatable :: count(:), level(:)
        !> Per key: the parameter of the first point that failed it.
        real(dp), allocatable :: first(:)
        !> Points counted.
        integer :: points = 0
    contains
        procedure :: add_point => tally_add_point
        procedure :: report => tally_report
    end type point_tally_t

    abstract interface
        !> Told that the stability of `pt` is done.
        subroutine point_done_interface(pt)
            import :: frc_point_t
            type(frc_point_t), intent(in) :: pt
        end subroutine point_done_interface
    end interface

contains

    !> The contact values of a curve's point from its solution: each contact's largest
    !> friction force (the modulus of the sum of its channels along w and t2); besides
    !> Coulomb contacts only, its open share and largest normal force (frc.csv's open_<j>,
    !> normal_max_<j> columns).
    subroutine contact_point_values(ps, pt)
        !> The point's weighted-residual solution (with samples).
        type(hbm_solution_t), intent(in) :: ps
        !> The point.
        type(frc_point_t), intent(inout) :: pt
        real(dp) :: f(size(ps%r, 1), 2), lambda(size(ps%r, 1))
        integer :: k
        associate (cs => ps%contacts)
            allocate (pt%rmax(cs%ncontact))
            do k = 1, cs%ncontact
                call cs%contact_forces(ps%r, k, f, lambda)
                if (cs%ntangent(k) == 2) then
                    pt%rmax(k) = maxval(hypot(f(:, 1), f(:, 2)))
                else
                    pt%rmax(k) = maxval(abs(f(:, 1)))
                end if
            end do
            if (.not. cs%coulomb_only) then
                pt%open = ps%open_fraction
                pt%normal_max = maxval(ps%normal, dim=1)
            end if
        end associate
    end subroutine contact_point_values

    !> Solve the accepted point `state` of the family's curve for its outputs (with
    !> opts%observe, the amplitudes of those combinations), with opts%truncation its harmonic
    !> truncation estimate (dense models only) and with opts%stability its Floquet
    !> multipliers from the exact reference (options `ref`); count its failed checks in
    !> `tally`. When the family is at the point's parameter, its dynamics are reused (no new
    !> factorization). Errors: those of the solve, the truncation estimate and the stability.
    subroutine evaluate_point(fam, opts, ref, state, status, nfev, pt, tally, &
                              stability_seconds, error, cache, defer_stability)
        !> The family of the curve (its sparse model, if any, is set to the point).
        type(friction_family_t), intent(inout) :: fam
        !> Sweep options.
        type(sweep_options_t), intent(in) :: opts
        !> Options of the exact reference used for the stability.
        type(reference_options_t), intent(in) :: ref
        !> The accepted continuation state (parameter, arclength, friction coefficients).
        type(continuation_state_t), intent(in) :: state
        !> The point's status ('start', 'ok', 'halved', 'recovered', 'end').
        character(len=*), intent(in) :: status
        !> Corrector evaluations spent on the point.
        integer, intent(in) :: nfev
        !> The point.
        type(frc_point_t), intent(out) :: pt
        !> The tally of the curve's failed checks, one point more.
        type(point_tally_t), intent(inout) :: tally
        !> CPU seconds of the stability so far [s], increased by this point's.
        real(dp), intent(inout) :: stability_seconds
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> What the stability of the previous point left (a sweep in omega only: the
        !> contact modes are those of the same model at a nearby omega).
        type(reference_cache_t), intent(inout), optional :: cache
        !> Leave the stability to stability_block (pt%stable = -1, floquet_max NaN).
        logical, intent(in), optional :: defer_stability
        logical :: defer
        type(truncation_t) :: est
        type(model_t) :: m
        type(dynamics_t) :: pdyn
        type(condensed_structure_t) :: setup
        type(hbm_solution_t) :: ps
        type(hbm_options_t) :: po
        integer :: k, nb, nc
        logical :: at_point
        nb = fam%prob%basis%nb
        nc = fam%prob%nc
        m = fam%model
        call set_sweep_parameter(m, opts%parameter, state%lambda, fam%amplitude0)
        po = fam%opts
        po%want_samples = .true.
        po%start = 'direct'
        ! the family's dynamics are at this parameter (the tangent was just computed
        ! there): the point and its truncation estimate need no new factorization
        at_point = fam%have_current .and. fam%current == state%lambda
        if (allocated(fam%cyclic) .and. at_point) then
            ! the family's dynamics at the point keep the channels only: one build with
            ! the displacements
            call fam%point_dynamics(pdyn, error)
            if (allocated(error)) return
            call solve_periodic_cyclic(m, fam%cyclic, po, ps, error, &
                                       r_start=reshape(state%y, [nb, nc]), dyn=pdyn, &
                                       structure=setup)
        else if (allocated(fam%cyclic)) then
            call solve_periodic_cyclic(m, fam%cyclic, po, ps, error, &
                                       r_start=reshape(state%y, [nb, nc]))
        else if (allocated(fam%sparse)) then
            fam%sparse%model = m
            if (at_point) then
                call solve_periodic_sparse(fam%sparse, po, fam%kept, ps, error, &
                                           r_start=reshape(state%y, [nb, nc]), &
                                           dyn=fam%prob%dyn)
            else
                call solve_periodic_sparse(fam%sparse, po, fam%kept, ps, error, &
                                           r_start=reshape(state%y, [nb, nc]))
            end if
        else if (at_point) then
            call solve_periodic(m, po, ps, error, &
                                r_start=reshape(state%y, [nb, nc]), dyn=fam%prob%dyn)
        else
            call solve_periodic(m, po, ps, error, &
                                r_start=reshape(state%y, [nb, nc]))
        end if
        if (allocated(error)) return
        pt%parameter = state%lambda
        pt%arclength = state%arclength
        if (allocated(opts%observe)) then
            pt%amplitude = maxval(abs(matmul(ps%x, transpose(opts%observe))), dim=1)
        else
            pt%amplitude = [(maxval(abs(ps%x(:, k))), k=1, size(ps%x, 2))]
        end if
        pt%diss_friction = ps%diss_friction
        pt%diss_damping = ps%diss_damping
        pt%dissipation = ps%diss_friction + ps%diss_damping
        call contact_point_values(ps, pt)
        pt%stick = ps%stick_fraction
        call keep_coefficients(m, ps, opts, pt, fam%cyclic)
        pt%harmonics = ps%harmonics
        pt%residual = ps%fnorm/max(ps%fscale, tiny(1.0_dp))
        pt%status = status
        pt%nfev = nfev
        pt%floquet_max = ieee_value(1.0_dp, ieee_quiet_nan)
        pt%stable = -1
        pt%truncation = ieee_value(1.0_dp, ieee_quiet_nan)
        if (opts%truncation .and. .not. allocated(fam%sparse)) then
            if (at_point .and. allocated(fam%cyclic)) then
                call estimate_truncation(m, po, ps, est, error, dyn=pdyn, &
                                         observe=opts%observe, cyclic=fam%cyclic, &
                                         structure=setup)
            else if (at_point) then
                call estimate_truncation(m, po, ps, est, error, dyn=fam%prob%dyn, &
                                         observe=opts%observe)
            else
                call estimate_truncation(m, po, ps, est, error, observe=opts%observe, &
                                         cyclic=fam%cyclic)
            end if
            if (allocated(error)) return
            if (est%available) pt%truncation = est%estimate
        end if
        call tally%add_point(ps%diagnostics, pt%truncation, pt%parameter, pt%check_level, &
                             pt%check)
        defer = .false.
        if (present(defer_stability)) defer = defer_stability
        if (opts%stability .and. .not. defer) then
            if (allocated(fam%cyclic)) then
                ! a sector's travelling wave: the multipliers of the whole disk
                block
                    type(model_t) :: disk
                    type(hbm_solution_t) :: dps
                    call disk_solution(m, fam%cyclic, po, ps, disk, dps, error)
                    if (allocated(error)) return
                    call stability_from(disk, dps, opts, ref, pt, stability_seconds, error, &
                                        cache, fam%opts, &
                                        wave_symmetry_t(fam%cyclic%sectors, &
                                                        fam%cyclic%engine_order))
                end block
            else
                call stability_from(m, ps, opts, ref, pt, stability_seconds, error, cache, &
                                    fam%opts)
            end if
        end if
    end subroutine evaluate_point

    !> The Floquet multipliers of the point `pt` from its weighted-residual solution `ps` of
    !> `m` (with samples): pt%floquet_max and pt%stable, unless the verdict is 'unknown'.
    !> `cache` (a sweep in omega only) carries the last point's flow. With `hopts` (the
    !> curve's hbm options), a point whose verdict is 'unknown' is tried once more from a
    !> fresh solve with the automatic rho (the curve keeps the rho of its start; at another
    !> rho the sampled equations give another approximation of the same orbit, which can be
    !> the better start for the shooting), without the cache. `symmetry`: m is a disk
    !> assembled from a sector, its wave's symmetry (periodic_stability). Errors: those of
    !> periodic_stability.
    subroutine stability_from(m, ps, opts, ref, pt, stability_seconds, error, cache, hopts, &
                              symmetry)
        type(model_t), intent(in) :: m
        type(hbm_solution_t), intent(in) :: ps
        type(sweep_options_t), intent(in) :: opts
        type(reference_options_t), intent(in) :: ref
        type(frc_point_t), intent(inout) :: pt
        !> CPU seconds of the stability so far [s], increased by this point's.
        real(dp), intent(inout) :: stability_seconds
        type(error_type), allocatable, intent(out) :: error
        type(reference_cache_t), intent(inout), optional :: cache
        type(hbm_options_t), intent(in), optional :: hopts
        type(wave_symmetry_t), intent(in), optional :: symmetry
        type(floquet_t) :: fl
        real(dp) :: s0
        s0 = thread_cpu_seconds()
        if (present(cache) .and. opts%parameter == 'omega') then
            call periodic_stability(m, ps, ref, fl, error, cache=cache, symmetry=symmetry)
        else
            call periodic_stability(m, ps, ref, fl, error, symmetry=symmetry)
        end if
        if (.not. allocated(error) .and. fl%verdict == 'unknown' .and. present(hopts)) &
            call fresh_start()
        stability_seconds = stability_seconds + (thread_cpu_seconds() - s0)
        if (allocated(error)) return
        if (fl%verdict /= 'unknown') then
            pt%floquet_max = fl%max_modulus
            pt%stable = merge(1, 0, fl%stable)
        end if

    contains

        !> The fresh solve (automatic rho, the usual start strategy) and its stability; a
        !> solve that fails leaves the verdict 'unknown'.
        subroutine fresh_start()
            type(hbm_options_t) :: fresh
            type(hbm_solution_t) :: ps2
            type(error_type), allocatable :: solve_error
            fresh = hopts
            fresh%rho = 0.0_dp
            fresh%start = 'auto'
            fresh%want_samples = .true.
            call solve_periodic(m, fresh, ps2, solve_error)
            if (allocated(solve_error)) return
            if (.not. ps2%converged) return
            call periodic_stability(m, ps2, ref, fl, error, symmetry=symmetry)
        end subroutine fresh_start
    end subroutine stability_from

    !> The Floquet stability of the `points` (of a curve of the dense family whose model,
    !> options and start amplitudes are `base`, `hopts`, `amplitude0`) that have no
    !> verdict (stable = -1), in order, on the calling thread with one reference_cache_t
    !> carried from one point to the next (a sweep in omega): each point is solved again
    !> from its kept force coefficients (converged already: one evaluation) for the samples
    !> the shooting starts from. `seconds` grows by the CPU time of the solves and the
    !> stability; `done` (optional) is called after each point; `cache` (optional) carries
    !> the reference cache from the caller's previous block. Errors: those of the solve
    !> and of periodic_stability (the block stops at the first).
    subroutine stability_block(base, hopts, amplitude0, opts, ref, points, seconds, error, &
                               done, cache)
        !> The curve's model (its parameter is set to each point's), the family's hbm
        !> options and the forcing amplitudes at the start (fam%model, fam%opts,
        !> fam%amplitude0: copies, so that the curve may go on while blocks run).
        type(model_t), intent(in) :: base
        type(hbm_options_t), intent(in) :: hopts
        real(dp), intent(in) :: amplitude0(:)
        !> Sweep options.
        type(sweep_options_t), intent(in) :: opts
        !> Options of the exact reference.
        type(reference_options_t), intent(in) :: ref
        !> The points, their stability filled.
        type(frc_point_t), intent(inout) :: points(:)
        !> CPU seconds [s], increased.
        real(dp), intent(inout) :: seconds
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Called after each point (with the point).
        procedure(point_done_interface), optional :: done
        !> The cache to carry on (from the caller's last block; one of its own otherwise).
        type(reference_cache_t), intent(inout), optional :: cache
        type(reference_cache_t) :: own
        type(model_t) :: m
        type(hbm_options_t) :: po
        type(hbm_solution_t) :: ps
        integer :: k
        real(dp) :: s0
        do k = 1, size(points)
            if (points(k)%stable /= -1) cycle
            associate (pt => points(k))
                m = base
                call set_sweep_parameter(m, opts%parameter, pt%parameter, amplitude0)
                po = hopts
                po%want_samples = .true.
                po%start = 'direct'
                ! the solve again is part of the stability's cost
                s0 = thread_cpu_seconds()
                if (allocated(pt%rcoef)) then
                    call solve_periodic(m, po, ps, error, r_start=pt%rcoef)
                else
                    call solve_periodic(m, po, ps, error)
                end if
                seconds = seconds + (thread_cpu_seconds() - s0)
                if (allocated(error)) return
                if (present(cache)) then
                    call stability_from(m, ps, opts, ref, pt, seconds, error, cache, hopts)
                else
                    call stability_from(m, ps, opts, ref, pt, seconds, error, own, hopts)
                end if
                if (allocated(error)) return
            end associate
            if (present(done)) call done(points(k))
        end do
    end subroutine stability_block

    !> Keep the Fourier coefficients of point `pt` (frc_point_t: harmonic, xcoef, rcoef,
    !> ucoef, omega) from its solution `ps` of `model`: the displacements observed as the
    !> amplitudes are (opts%observe, or the solution's columns), every force channel, and
    !> the displacement along each channel's direction.
    subroutine keep_coefficients(model, ps, opts, pt, cyclic)
        !> The model at the point's parameter.
        type(model_t), intent(in) :: model
        !> The point's solution.
        type(hbm_solution_t), intent(in) :: ps
        !> Sweep options (the observation matrix).
        type(sweep_options_t), intent(in) :: opts
        !> The point.
        type(frc_point_t), intent(inout) :: pt
        !> `model` is one sector of this disk: a channel against the next sector measures
        !> the relative displacement (stickslip_cyclic's channel_displacements).
        type(cyclic_t), intent(in), optional :: cyclic
        real(dp), allocatable :: d(:, :)
        pt%omega = ps%omega
        pt%harmonic = ps%harmonic
        if (allocated(opts%observe)) then
            pt%xcoef = matmul(ps%xcoef, transpose(opts%observe))
        else
            pt%xcoef = ps%xcoef
        end if
        pt%rcoef = ps%rcoef
        if (present(cyclic)) then
            pt%ucoef = channel_displacements(model, cyclic, ps%contacts, ps%harmonic, &
                                             ps%xcoef)
            return
        end if
        d = channel_directions(model, ps%contacts)
        ! the exact sparse condensation keeps some DOFs only, the contact DOFs among them
        if (allocated(ps%dofs)) d = d(ps%dofs, :)
        pt%ucoef = matmul(ps%xcoef, d)
    end subroutine keep_coefficients

    !> Count the failed checks of one point: its solution's diagnostics (warnings and
    !> distrust) and its truncation estimate (stickslip_checks thresholds; NaN: not
    !> computed).
    !> The point's own verdict: `level` the worst level of its failed checks (0 when none)
    !> and `key` the first check failed at that level.
    subroutine tally_add_point(self, diag, truncation, parameter, level, key)
        !> The tally, one point more.
        class(point_tally_t), intent(inout) :: self
        !> The diagnostics of the point's solution.
        type(diagnostics_t), intent(in) :: diag
        !> The point's relative truncation error estimate (NaN: not computed), and its
        !> parameter value.
        real(dp), intent(in) :: truncation, parameter
        !> The point's worst level and its check.
        integer, intent(out), optional :: level
        character(len=*), intent(out), optional :: key
        integer :: k, worst
        character(len=48) :: worst_key
        worst = 0
        worst_key = ''
        if (.not. allocated(self%key)) allocate (self%key(0), self%count(0), self%level(0), &
                                                 self%first(0))
        self%points = self%points + 1
        if (allocated(diag%items)) then
            do k = 1, size(diag%items)
                if (diag%items(k)%level >= level_warning) &
                    call count_key(diag%items(k)%key, diag%items(k)%level)
            end do
        end if
        if (ieee_is_finite(truncation)) then
            if (truncation > truncation_untrusted) then
                call count_key("truncation", level_untrusted)
            else if (truncation > truncation_warning) then
                call count_key("truncation", level_warning)
            end if
        end if
        if (present(level)) level = worst
        if (present(key)) key = worst_key

    contains

        subroutine count_key(key, level)
            character(len=*), intent(in) :: key
            integer, intent(in) :: level
            integer :: i
            i = findloc(self%key, key, 1)
            if (i == 0) then
                self%key = [character(len=48) :: self%key, key]
                self%count = [self%count, 0]
                self%level = [self%level, level]
                self%first = [self%first, parameter]
                i = size(self%key)
            end if
            self%count(i) = self%count(i) + 1
            self%level(i) = max(self%level(i), level)
            if (level > worst) then
                worst = level
                worst_key = key
            end if
        end subroutine count_key
    end subroutine tally_add_point

    !> One diagnostics item per failed check, key 'points_<key>': naming how many points
    !> failed it and where the first one is; untrusted (exit 2) when a point failed it at
    !> level untrusted, a warning otherwise (the points' trusted and check columns say which).
    subroutine tally_report(self, parameter, diag)
        !> The tally of the curve.
        class(point_tally_t), intent(in) :: self
        !> The swept parameter's name.
        character(len=*), intent(in) :: parameter
        !> The curve's diagnostics, added to.
        type(diagnostics_t), intent(inout) :: diag
        integer :: i, level
        character(len=300) :: buf
        if (.not. allocated(self%key)) return
        do i = 1, size(self%key)
            level = level_warning
            if (self%level(i) == level_untrusted) level = level_untrusted
            write (buf, '(i0,a,i0,a,es13.5e3,a)') self%count(i), " of ", self%points, &
                " points failed the check '"//trim(self%key(i))//"' (the first at "// &
                trim(parameter)//" = ", self%first(i), "): see the points' trusted and "// &
                "check columns"
            call diag%add(level, "points_"//trim(self%key(i)), trim(buf))
        end do
    end subroutine tally_report
end module stickslip_sweep_point
