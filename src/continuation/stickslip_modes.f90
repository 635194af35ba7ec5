!> Nonlinear modal analysis (&run method = 'modes'): the backbone of one mode of a
!> friction-damped structure, its frequency, modal damping ratio and shape against the
!> modal amplitude, by the extended periodic motion concept on the equality formulation
!> (stickslip_modes_family) continued in ln a by the pseudo-arclength continuation of the
!> sweeps (stickslip_continuation).
!>
!> The family starts from the structure's linear mode `mode` with its contacts stuck (the
!> low-amplitude limit; with its contacts slipping when the stuck structure has no such
!> mode, e.g. a single mass on a friction contact): the start point at amplitude_start is
!> corrected from that linear motion, or from the slipping mode with Coulomb's first
!> harmonic when the stuck guess does not converge. Every point is then finished as a
!> weighted-residual solution (solution_from_forces: samples, stick statistics,
!> dissipation) and checked: the energy the negative modal damping feeds in per cycle must
!> equal what friction and viscous damping dissipate. With opts%error_estimate every point
!> is solved again on the basis of half the harmonics and half the samples (the same family
!> at the same modal amplitude, from the point's truncated forces): twice the differences of
!> omega and of the damping ratio D estimate their errors (a warning 'truncation' above
!> omega_error_warning, or above damping_error_warning of D).
module stickslip_modes
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp, pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_untrusted, level_note
    use stickslip_progress, only: progress_t
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_model, only: model_t, validate_model, preload_force, force_direction
    use stickslip_lapack, only: dgesv, dsygv, zgesv
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: validate_options, solution_from_forces, energy_warning, &
        energy_untrusted, force_excess_warning, force_excess_untrusted
    use stickslip_hbm_cyclic, only: cyclic_solution_from_forces
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, sector_phase, cyclic_basis, &
        cyclic_directions, cyclic_preload_force
    use stickslip_cyclic_limits, only: cyclic_limit_modes
    use stickslip_cyclic_modal, only: prepare_cyclic_modes
    use stickslip_rho, only: automatic_rho, cyclic_held_rho
    use stickslip_contact_set, only: contact_set_t, new_contact_set, channel_directions
    use stickslip_contact_element, only: channel_t, kinematics_gap, along_normal
    use stickslip_linear_modes, only: linear_modes
    use stickslip_continuation, only: continuation_options_t, continuation_state_t, &
        continuation_report_t, start_continuation, continuation_step, reason_running, &
        reason_end, reason_failures, resume_continuation, point_status
    use stickslip_modes_family, only: modes_family_t, new_modes_family, free_structure
    use stickslip_sweep_result, only: frc_point_t, reason_text
    use stickslip_sweep_point, only: point_tally_t, keep_coefficients, contact_point_values
    use stickslip_sweep_options, only: sweep_options_t
    implicit none
    private
    public :: modes_options_t, mode_point_t, modes_result_t, run_modes, validate_modes_options
    public :: modes_max_points

    !> Largest `points` accepted.
    integer, parameter :: modes_max_points = 100000

    !> A backbone that stops on failed points is continued on refine_factor times the
    !> samples (modes_options_t%refinements times at most), never beyond
    !> max_refined_samples; largest `refinements` accepted.
    integer, parameter, public :: refine_factor = 4, max_refined_samples = 16384, &
                                  modes_max_refinements = 4

    !> A point's estimated errors that make it a warning 'truncation': of omega (relative)
    !> and of D (relative to D, and at least damping_error_floor in D itself).
    real(dp), parameter, public :: omega_error_warning = 1.0e-3_dp, &
                                   damping_error_warning = 5.0e-2_dp, &
                                   damping_error_floor = 1.0e-4_dp

    !> Options of a nonlinear modal analysis.
    type :: modes_options_t
        !> Which linear mode the family starts from (1: the lowest of the stuck structure).
        integer :: mode = 1
        !> Range of the modal amplitude a = sqrt(c1^T M c1 + s1^T M s1) [m sqrt(kg)], > 0.
        real(dp) :: amplitude_start = 0.0_dp, amplitude_stop = 0.0_dp
        !> Points of the backbone over the range at the largest step (the continuation takes
        !> more where the curve bends); it stops after 20 x points.
        integer :: points = 100
        !> Observed combinations of the DOFs (rows), as a sweep's: the amplitude columns of a
        !> reduced model's recovered DOFs; unallocated: every DOF of the model.
        real(dp), allocatable :: observe(:, :)
        !> Estimate the truncation errors of omega and D at every point (a second solve on
        !> half the harmonics).
        logical :: error_estimate = .true.
        !> How many times a backbone that stops on failed points is continued from its
        !> last point on refine_factor times the samples (0: never).
        integer :: refinements = 2
    end type modes_options_t

    !> One point of a backbone.
    type :: mode_point_t
        !> Modal amplitude a [m sqrt(kg)] (the point's parameter), angular frequency omega
        !> [rad/s], negative modal damping xi [1/s] and modal damping ratio D = xi / (2
        !> omega); the frc_point_t part holds amplitudes per DOF, forces, stick shares,
        !> dissipations (diss_damping: the viscous part, C only) and coefficients, its
        !> parameter = a.
        type(frc_point_t) :: p
        real(dp) :: xi = 0.0_dp, damping_ratio = 0.0_dp
        !> Energy fed in per cycle by the negative modal damping [J], and the balance error
        !> |input - friction - viscous| / input.
        real(dp) :: energy_input = 0.0_dp, energy_error = 0.0_dp
        !> Estimated truncation errors: 2 |omega_H - omega_H/2| / omega_H and 2 |D_H - D_H/2|
        !> (NaN when not estimated or when the point was not found on half the harmonics;
        !> evaluate_mode_point sets them).
        real(dp) :: omega_error = 0.0_dp, damping_error = 0.0_dp
        !> On a sector of a disk: the nodal diameter of the point's backbone (-1: a whole
        !> structure; set by the caller that gathers several backbones).
        integer :: nodal_diameter = -1
    end type mode_point_t

    !> A backbone.
    type :: modes_result_t
        type(mode_point_t), allocatable :: points(:)
        integer :: npoints = 0
        !> The end of the range was reached.
        logical :: complete = .false.
        character(len=:), allocatable :: diagnosis
        !> The linear limits: frequencies of the mode with every contact stuck and slipping
        !> [rad/s] (0 when the structure has no such mode), and which start was taken
        !> ('stuck' or 'slipping').
        real(dp) :: omega_stuck = 0.0_dp, omega_slipping = 0.0_dp
        character(len=8) :: start = ''
        !> The mode neither moves nor loads a contact (the error then says so): its backbone
        !> is the linear mode at every amplitude.
        logical :: unloaded = .false.
        !> Weight rho in effect, harmonics of the family (odd only for plain contacts).
        real(dp) :: rho = 0.0_dp
        !> A sector's mode with the automatic weight: the held weight of its wave
        !> (cyclic_held_rho at the stuck frequency) [m/(N s)], 0 otherwise; and when the
        !> diameter was traced again with it (stickslip_run_sector_modes), what stopped the
        !> automatic weight's backbone.
        real(dp) :: rho_held = 0.0_dp
        character(len=:), allocatable :: first_try
        logical :: odd_only = .false.
        !> Samples per period of the backbone's last points, and the modal amplitudes [m
        !> sqrt(kg)] from which it was continued on refine_factor times the samples (one per
        !> refinement; empty when none was needed).
        integer :: samples = 0
        real(dp), allocatable :: refined_at(:)
        !> CPU seconds, factorizations of the dynamic stiffnesses, continuation counts.
        real(dp) :: seconds = 0.0_dp
        integer :: factorizations = 0, rejected = 0, folds = 0
        !> What the checks found.
        type(diagnostics_t) :: diagnostics
    end type modes_result_t

contains

    !> Check modal-analysis options. Errors (stat input) name the component.
    subroutine validate_modes_options(opts, error)
        !> The options.
        type(modes_options_t), intent(in) :: opts
        !> Set on the first problem.
        type(error_type), allocatable, intent(out) :: error
        if (opts%mode < 1) then
            call fatal_error(error, "opts%mode = "//itoa(opts%mode)//": must be >= 1", &
                             stickslip_stat%input)
        else if (.not. (opts%amplitude_start > 0.0_dp .and. &
                        ieee_is_finite(opts%amplitude_start))) then
            call fatal_error(error, "opts%amplitude_start: must be finite and > 0", &
                             stickslip_stat%input)
        else if (.not. (opts%amplitude_stop > 0.0_dp .and. &
                        ieee_is_finite(opts%amplitude_stop))) then
            call fatal_error(error, "opts%amplitude_stop: must be finite and > 0", &
                             stickslip_stat%input)
        else if (opts%amplitude_start == opts%amplitude_stop) then
            call fatal_error(error, "opts%amplitude_start = opts%amplitude_stop: the range "// &
                             "is empty", stickslip_stat%input)
        else if (opts%points < 2 .or. opts%points > modes_max_points) then
            call fatal_error(error, "opts%points = "//itoa(opts%points)//": must be in 2.."// &
                             itoa(modes_max_points), stickslip_stat%input)
        else if (opts%refinements < 0 .or. opts%refinements > modes_max_refinements) then
            call fatal_error(error, "opts%refinements = "//itoa(opts%refinements)// &
                             ": must be in 0.."//itoa(modes_max_refinements), &
                             stickslip_stat%input)
        end if
    end subroutine validate_modes_options

    !> The backbone of mode opts%mode of `model` (its forcing ignored; dense M, C, K: a
    !> reduced FE model is dense) on the basis of `hbm` (rho = 0: automatic, at the mode's
    !> linear frequency), from amplitude_start to amplitude_stop. A backbone that stops
    !> early (the continuation failed) is returned with complete = .false. and a
    !> diagnosis. With `cyclic`, `model` is one sector of that tuned disk and the backbone is
    !> the travelling wave of nodal diameter cyclic%engine_order (0 .. N/2, its fundamental's
    !> inter-sector phase exp(-i 2 pi nd / N)), started from the sector's cyclic modes with
    !> its contacts stuck or slipping (stickslip_cyclic_limits); amplitudes, energies and
    !> shapes are the sector's (sector 0's). Errors: stat input (bad options, no contact, no
    !> such mode, a diameter outside 0 .. N/2), stat numerical (no solution at the start,
    !> singular dynamics at the linear frequency).
    subroutine run_modes(model, hbm, opts, res, error, progress, cyclic)
        !> A validated model with contacts.
        type(model_t), intent(in) :: model
        !> Basis and tolerance options.
        type(hbm_options_t), intent(in) :: hbm
        !> Modal-analysis options.
        type(modes_options_t), intent(in) :: opts
        !> The backbone.
        type(modes_result_t), intent(out) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every point.
        type(progress_t), intent(inout), optional :: progress
        !> The disk of which `model` is a sector (engine order: the nodal diameter).
        type(cyclic_t), intent(in), optional :: cyclic
        type(cyclic_t) :: cyc
        type(modes_family_t) :: fam, low
        type(continuation_options_t) :: copts
        logical :: have_low
        type(continuation_state_t) :: state, stopped
        type(continuation_report_t) :: rep
        type(hbm_options_t) :: ho
        type(model_t) :: free
        type(point_tally_t) :: tally
        real(dp), allocatable :: ws(:), rphis(:, :), rphif(:, :), wfv(:)
        complex(dp), allocatable :: phis(:, :), phif(:, :), phi(:), phi_slip(:)
        logical, allocatable :: unloaded(:)
        real(dp), allocatable :: c_orig(:, :)
        real(dp) :: omega_ref, c0, fscale, last_tl
        integer :: k, rejected
        type(error_type), allocatable :: err_stuck, err_slip
        character(len=32) :: buf, rho_text
        character(len=:), allocatable :: how
        logical :: continued

        c0 = thread_cpu_seconds()
        call validate_model(model, error)
        if (allocated(error)) return
        call validate_options(hbm, error)
        if (allocated(error)) return
        call validate_modes_options(opts, error)
        if (allocated(error)) return
        if (model%ncontact() == 0) then
            call fatal_error(error, "nonlinear modes: the model has no friction contact", &
                             stickslip_stat%input)
            return
        end if
        free = free_structure(model)
        if (frictionless(free)) then
            call fatal_error(error, "nonlinear modes: &friction mu = 0 (mu N = 0) at every "// &
                             "contact and no normal law: the contacts carry no force, so "// &
                             "every mode is the free structure's linear mode at every "// &
                             "amplitude (frequency and "// &
                             "damping constant: the linear modes, e.g. &run method = 'hbm' "// &
                             "or a sweep with mu = 0); give a friction coefficient > 0", &
                             stickslip_stat%input)
            return
        end if
        ! the linear limits: mode `mode` of the stuck structure, and the slipping mode most
        ! like it (largest |phi_f^T M phi_s|)
        if (present(cyclic)) then
            call validate_cyclic(model, cyclic, error)
            if (allocated(error)) return
            if (cyclic%engine_order > cyclic%sectors/2) then
                call fatal_error(error, "nonlinear modes: nodal diameter "// &
                                 itoa(cyclic%engine_order)//": must be 0 to "// &
                                 itoa(cyclic%sectors/2), stickslip_stat%input)
                return
            end if
            ! the sector's cyclic modes of the diameter, its contacts stuck and slipping
            call cyclic_limit_modes(free, cyclic, fundamental_phase(cyclic), .true., ws, phis, &
                                    err_stuck)
            call cyclic_limit_modes(free, cyclic, fundamental_phase(cyclic), .false., wfv, &
                                    phif, err_slip)
            if (allocated(err_stuck)) allocate (ws(0), phis(model%ndof, 0))
            if (allocated(err_slip)) allocate (wfv(0), phif(model%ndof, 0))
            allocate (unloaded(size(wfv)))
            unloaded = .false.
        else
            call linear_modes(free, .true., ws, rphis, err_stuck)
            call linear_modes(free, .false., wfv, rphif, err_slip)
            if (allocated(err_stuck)) allocate (ws(0), rphis(model%ndof, 0))
            if (allocated(err_slip)) allocate (wfv(0), rphif(model%ndof, 0))
            ! the free structure's modes that neither move nor load a contact: the contact
            ! forces never excite them, but where one has the frequency (and damping) of the
            ! backbone the dynamic stiffness is singular; and a stuck frequency shared by such
            ! a mode is a double one, whose loaded combinations come first
            unloaded = unloaded_free_modes(free, rphif)
            if (size(ws) >= opts%mode) call loaded_first(free, ws, rphis, opts%mode)
            phis = cmplx(rphis, 0.0_dp, dp)
            phif = cmplx(rphif, 0.0_dp, dp)
        end if
        if (size(ws) >= opts%mode) then
            phi = phis(:, opts%mode)
            omega_ref = ws(opts%mode)
            res%omega_stuck = omega_ref
            if (count(.not. unloaded) > 0) then
                k = maxloc(abs(matmul(conjg(transpose(phif)), matmul(free%mass, phi))), 1, &
                           mask=.not. unloaded)
                phi_slip = phif(:, k)
                res%omega_slipping = wfv(k)
            end if
        else if (size(wfv) >= opts%mode) then
            phi = phif(:, opts%mode)
            phi_slip = phi
            omega_ref = wfv(opts%mode)
            res%omega_slipping = omega_ref
        else
            call fatal_error(error, "opts%mode = "//itoa(opts%mode)//": no such mode (the "// &
                             "structure has "//itoa(max(size(ws), size(wfv)))// &
                             " modes with its contacts stuck or slipping)", stickslip_stat%input)
            return
        end if
        ho = hbm
        if (ho%rho == 0.0_dp) then
            free%omega = omega_ref
            ho%rho = automatic_rho(free)
        end if
        ! the structure's own damping: the energies of the points (the added one acts on
        ! modes the points do not move)
        c_orig = free%damping
        if (any(unloaded)) call damp_unloaded(free, rphif(:, pack([(k, k=1, size(wfv))], &
                                                                 unloaded)), omega_ref)
        if (present(cyclic)) then
            ! the sector's cyclic modes of the diameters the harmonics reach: each omega and
            ! xi then costs a modal sum (C - xi M stays proportional), not a factorization
            cyc = cyclic
            call prepare_cyclic_modes(free, cyc, ho%harmonics, error)
            if (allocated(error)) return
            ! the held weight of the wave's fundamental (from the prepared modes): the
            ! remedy of a stop (stickslip_run_sector_modes)
            if (hbm%rho == 0.0_dp) res%rho_held = cyclic_held_rho(free, cyc, 1)
        end if
        call build_families()
        if (allocated(error)) return
        res%rho = ho%rho
        res%odd_only = fam%opts%odd_only
        ! the continuation in lambda = ln a, at most (points - 1) steps over the range
        copts%start = log(opts%amplitude_start)
        copts%stop = log(opts%amplitude_stop)
        copts%max_step = abs(copts%stop - copts%start)/real(opts%points - 1, dp)
        copts%step = copts%max_step
        copts%min_step = 1.0e-3_dp*copts%max_step
        copts%max_points = 20*opts%points
        copts%tol = hbm%tol
        copts%fscale = tiny(1.0_dp)
        copts%maxfev = max(100, 20*(fam%n + 2))
        ! the scales of the unknowns, times the parameter's range: the arclength then
        ! follows ln a (evenly spaced points), shortened only where the mode changes fast
        ! (the stick-slip transition), not where the stuck reactions grow like a
        fscale = force_scale(free)
        ! (xi's scale, 0.02 omega_ref: a step changes D by at most about 1 / (points - 1)
        ! of 0.01 times the range of ln a, so the points crowd where D changes fast)
        copts%yscale = abs(copts%stop - copts%start)*[spread(fscale, 1, fam%n), omega_ref, &
                                                      0.02_dp*omega_ref]
        call start_backbone()
        if (allocated(error)) then
            call fam%destroy()
            return
        end if
        if (.not. rep%accepted) then
            call fam%destroy()
            write (buf, '(es12.4e3)') opts%amplitude_start
            if (unloaded_mode(free, phi, omega_ref, cyclic)) then
                res%unloaded = .true.
                ! the contacts neither move nor carry a force in this mode: it is a mode of
                ! the structure with and without them (its stuck and free frequencies
                ! coincide), which the equations, driven by the contact forces, cannot reach
                write (buf, '(g0.6)') omega_ref
                call fatal_error(error, "nonlinear modes: mode "//itoa(opts%mode)//" (omega "// &
                                 trim(buf)//" rad/s) does not load the contacts: they "// &
                                 "neither move nor carry a force in it, so it is also a mode "// &
                                 "of the structure without them (its stuck and free "// &
                                 "frequencies coincide) and its backbone is that linear mode "// &
                                 "at every amplitude (frequency and damping constant); the "// &
                                 "nonlinear-mode equations, driven by the contact forces, "// &
                                 "cannot follow it. Choose another &modes mode", &
                                 stickslip_stat%input)
                return
            end if
            call fatal_error(error, "nonlinear modes: no periodic motion found at "// &
                             "amplitude_start = "//trim(adjustl(buf))//" (modal amplitude, "// &
                             "in the model's length unit times sqrt of its mass unit) from "// &
                             "the stuck or the slipping linear mode (try another "// &
                             "amplitude_start, or more harmonics)", stickslip_stat%numerical)
            return
        end if
        allocate (res%points(64))
        call add_point('start')
        if (allocated(error)) return
        last_tl = state%tl
        call trace('')
        ! a stop on failed points: the rest of the backbone on 4 times the samples, from
        ! its last point (the stick-slip instants then fall between closer samples and the
        ! sampled friction equations' kinks are smaller) or, when that point is no solution
        ! there or the backbone stops again, the whole backbone on those samples from its
        ! start (the continuation of a nonsmooth family depends on its path: started
        ! afresh, as a run with those samples, rather than from its first point)
        res%samples = ho%samples
        rejected = 0
        allocate (res%refined_at(0))
        do while (.not. allocated(error) .and. state%reason == reason_failures .and. &
                  size(res%refined_at) < opts%refinements .and. &
                  ho%samples <= max_refined_samples/refine_factor)
            call free_families()
            ho%samples = refine_factor*ho%samples
            call build_families()
            if (allocated(error)) exit
            continued = resumed()
            if (continued) then
                res%samples = ho%samples
                res%refined_at = [res%refined_at, exp(state%lambda)]
                call trace('refined')
                if (allocated(error) .or. state%reason /= reason_failures) exit
            end if
            ! the whole backbone again
            stopped = state
            call start_backbone()
            if (allocated(error)) exit
            if (.not. rep%accepted) then
                state = stopped
                exit
            end if
            rejected = rejected + stopped%rejected
            res%npoints = 0
            res%folds = 0
            tally = point_tally_t()
            res%samples = ho%samples
            if (continued) then
                res%refined_at(size(res%refined_at)) = opts%amplitude_start
            else
                res%refined_at = [res%refined_at, opts%amplitude_start]
            end if
            call add_point('start')
            if (allocated(error)) exit
            last_tl = state%tl
            call trace('')
        end do
        call free_families()
        res%rejected = rejected + state%rejected
        if (size(res%refined_at) > 0 .and. .not. allocated(error)) then
            ! "; continued on .." -> "the backbone stopped on 384 samples; continued on .."
            how = refined_text()
            call res%diagnostics%add(level_note, "refined", "the backbone stopped on "// &
                                     itoa(hbm%samples)//" samples"//how// &
                                     trim(merge(" to the end", "           ", &
                                                state%reason == reason_end)))
        end if
        if (allocated(error)) return
        res%complete = state%reason == reason_end
        if (res%complete) then
            res%diagnosis = ""
        else
            res%diagnosis = reason_text(state%reason)
            if (state%reason == reason_failures) then
                ! the continuation's parameter is ln a: say the amplitude, in its unit
                write (buf, '(g0.6)') exp(state%lambda)
                write (rho_text, '(g0.3)') ho%rho
                if (hbm%rho == 0.0_dp) rho_text = trim(adjustl(rho_text))//", automatic"
                res%diagnosis = itoa(state%failures)//" failed points in a row after "// &
                                "modal amplitude a = "//trim(adjustl(buf))//" (the model's "// &
                                "length unit times the square root of its mass unit; the "// &
                                "smallest step and the recovery both failed"// &
                                refined_text()//"): try "
                if (size(res%refined_at) < opts%refinements .or. opts%refinements == 0) &
                    res%diagnosis = res%diagnosis//"more &hbm samples (now "// &
                                    itoa(res%samples)//"; 4 times as many carried such "// &
                                    "stops to the end on the lumped disks of doc/cyclic.md), "
                if (size(res%refined_at) == opts%refinements .and. opts%refinements > 0 .and. &
                    opts%refinements < modes_max_refinements) &
                    res%diagnosis = res%diagnosis//"more &modes refinements (now "// &
                                    itoa(opts%refinements)//"), "
                res%diagnosis = res%diagnosis//"a smaller &hbm rho (now "// &
                                trim(adjustl(rho_text))//"), or other harmonics"
            else if (allocated(rep%message)) then
                if (len(rep%message) > 0) res%diagnosis = rep%message
            end if
        end if
        call tally%report("amplitude", res%diagnostics)
        res%seconds = thread_cpu_seconds() - c0

    contains

        !> The family on ho (fam) and, for the truncation estimate, on half its harmonics
        !> (low, have_low).
        subroutine build_families()
            if (present(cyclic)) then
                call new_modes_family(fam, free, ho, phi, omega_ref, error, cyc)
            else
                call new_modes_family(fam, free, ho, phi, omega_ref, error)
            end if
            if (allocated(error)) return
            ! the truncation estimate: the same family on half the harmonics
            have_low = .false.
            if (opts%error_estimate .and. fam%opts%harmonics >= 2) then
                block
                    type(hbm_options_t) :: hl
                    hl = ho
                    hl%harmonics = fam%opts%harmonics/2
                    ! half the samples as well (when they still resolve H/2): the difference
                    ! then holds the quadrature's error (stick-slip instants on the grid of
                    ! samples) with the truncation's
                    if (hl%samples/2 > 4*hl%harmonics) hl%samples = hl%samples/2
                    if (present(cyclic)) then
                        call new_modes_family(low, free, hl, phi, omega_ref, error, cyc)
                    else
                        call new_modes_family(low, free, hl, phi, omega_ref, error)
                    end if
                end block
                if (allocated(error)) then
                    call fam%destroy()
                    return
                end if
                have_low = .true.
            end if
        end subroutine build_families

        !> Destroy the families, their factorizations counted in res.
        subroutine free_families()
            res%factorizations = res%factorizations + fam%factorizations
            call fam%destroy()
            if (have_low) then
                res%factorizations = res%factorizations + low%factorizations
                call low%destroy()
            end if
            have_low = .false.
        end subroutine free_families

        !> Continue the backbone to its end or its stop, a point per step; the first new
        !> point's status `first` when not empty.
        subroutine trace(first)
            character(len=*), intent(in) :: first
            logical :: fresh
            fresh = len(first) > 0
            do while (state%reason == reason_running)
                call continuation_step(fam, copts, state, rep, error)
                if (allocated(error)) exit
                if (.not. rep%accepted) exit
                if (state%tl*last_tl < 0.0_dp) res%folds = res%folds + 1
                last_tl = state%tl
                if (fresh) then
                    call add_point(first)
                else
                    call add_point(point_status(rep, state))
                end if
                fresh = .false.
                if (allocated(error)) exit
            end do
        end subroutine trace

        !> The backbone's first point at amplitude_start on fam (state; rep%accepted when
        !> found, res%start says from which linear limit).
        subroutine start_backbone()
            real(dp), allocatable :: guess(:, :)
            character(len=16) :: names(2)
            integer :: nguess, g
            ! the start: the stuck guess first when the stuck contacts hold (the reaction of the
            ! linear motion within the friction limits), else the slipping one first
            allocate (guess(fam%n + 2, 0))
            nguess = 0
            if (res%omega_stuck > 0.0_dp) then
                guess = reshape([guess, stuck_guess(fam, free, phi, omega_ref, &
                                                    opts%amplitude_start, cyclic)], [fam%n + 2, 1])
                names(1) = 'stuck'
                nguess = 1
            end if
            if (allocated(phi_slip)) then
                if (res%omega_stuck > 0.0_dp .and. &
                    .not. stuck_holds(free, phi, omega_ref, opts%amplitude_start, cyclic)) then
                    guess = reshape([slip_guess(fam, free, phi_slip, res%omega_slipping, &
                                                opts%amplitude_start, cyclic), guess], &
                                    [fam%n + 2, 2])
                    names = [character(len=16) :: 'slipping', 'stuck']
                else
                    guess = reshape([guess, slip_guess(fam, free, phi_slip, res%omega_slipping, &
                                                       opts%amplitude_start, cyclic)], &
                                    [fam%n + 2, nguess + 1])
                    names(nguess + 1) = 'slipping'
                end if
                nguess = nguess + 1
            end if
            do g = 1, nguess
                call start_continuation(fam, copts, guess(:, g), state, rep, error)
                if (allocated(error)) return
                if (rep%accepted) then
                    res%start = names(g)
                    exit
                end if
            end do
        end subroutine start_backbone

        !> Whether the stopped continuation was resumed on fam (resume_continuation) from
        !> its last point.
        logical function resumed()
            call resume_continuation(fam, copts, state, rep, error)
            resumed = .not. allocated(error) .and. rep%accepted
            if (resumed) last_tl = state%tl
        end function resumed

        !> "; continued on S samples from a = ..": where the backbone was continued on more
        !> samples (empty when it was not).
        function refined_text() result(t)
            character(len=:), allocatable :: t
            character(len=16) :: w
            integer :: j
            t = ""
            if (size(res%refined_at) == 0) return
            t = "; continued"
            do j = 1, size(res%refined_at)
                write (w, '(g0.4)') res%refined_at(j)
                if (j > 1) t = t//","
                t = t//" on "//itoa(hbm%samples*refine_factor**j)//" samples from a = "// &
                    trim(adjustl(w))
            end do
        end function refined_text

        !> Finish the continuation's current point as a solution and add it.
        subroutine add_point(status)
            character(len=*), intent(in) :: status
            type(mode_point_t) :: mp
            type(mode_point_t), allocatable :: grown(:)
            if (have_low) then
                call evaluate_mode_point(fam, state, opts, status, rep%nfev, c_orig, mp, tally, &
                                         error, low, copts)
            else
                call evaluate_mode_point(fam, state, opts, status, rep%nfev, c_orig, mp, tally, &
                                         error)
            end if
            if (allocated(error)) return
            if (res%npoints == size(res%points)) then
                allocate (grown(2*res%npoints))
                grown(1:res%npoints) = res%points(1:res%npoints)
                call move_alloc(grown, res%points)
            end if
            res%npoints = res%npoints + 1
            res%points(res%npoints) = mp
            if (present(progress)) then
                write (buf, '(g0.6)') exp(state%lambda)
                call progress%report(res%npoints, 0, "amplitude = "//trim(adjustl(buf)))
            end if
        end subroutine add_point
    end subroutine run_modes

    !> Whether no contact of `model` can carry a force: every friction limit 0 (mu = 0, or
    !> mu N = 0; an Iwan element's sliders count) and no channel along a normal (a
    !> unilateral contact's normal law acts without friction).
    logical function frictionless(model)
        type(model_t), intent(in) :: model
        type(contact_set_t) :: cs
        call new_contact_set(cs, model)
        frictionless = .not. (cs%force_scale() > 0.0_dp) .and. &
                       .not. any(cs%along == along_normal)
    end function frictionless

    !> Which of the free structure's modes `phif` (mass-normalized, N x m) neither move nor
    !> load a contact channel: d^T phi = 0 for every channel direction d (to 1e-8 of the
    !> mode's size; a free mode then carries no contact force either).
    function unloaded_free_modes(model, phif) result(unloaded)
        type(model_t), intent(in) :: model
        real(dp), intent(in) :: phif(:, :)
        logical :: unloaded(size(phif, 2))
        type(contact_set_t) :: cs
        real(dp), allocatable :: d(:, :)
        integer :: k
        call new_contact_set(cs, model)
        d = channel_directions(model, cs)
        do k = 1, size(phif, 2)
            unloaded(k) = maxval(abs(matmul(transpose(d), phif(:, k)))) <= &
                          1.0e-8_dp*maxval(abs(phif(:, k)))*max(maxval(abs(d)), tiny(1.0_dp))
        end do
    end function unloaded_free_modes

    !> Within the cluster of stuck modes of mode `mode`'s frequency (equal to 1e-8), the
    !> combinations that load the contacts (their stuck reactions D^T (K - omega^2 M) phi,
    !> by singular value) first, those that leave them unloaded last: the basis LAPACK
    !> returns for a double frequency is any; mode `mode` is then a loaded one when the
    !> cluster has one. The shapes stay mass-normalized (an orthogonal change of basis).
    subroutine loaded_first(model, ws, phis, mode)
        type(model_t), intent(in) :: model
        real(dp), intent(in) :: ws(:)
        real(dp), intent(inout) :: phis(:, :)
        integer, intent(in) :: mode
        type(contact_set_t) :: cs
        real(dp), allocatable :: d(:, :), r(:, :), g(:, :), b(:, :), ev(:), work(:)
        integer, allocatable :: idx(:)
        integer :: m, info, k
        idx = pack([(k, k=1, size(ws))], abs(ws - ws(mode)) <= 1.0e-8_dp*ws(mode))
        m = size(idx)
        if (m < 2) return
        call new_contact_set(cs, model)
        d = channel_directions(model, cs)
        r = matmul(transpose(d), matmul(model%stiffness, phis(:, idx)) - &
                   ws(mode)**2*matmul(model%mass, phis(:, idx)))
        ! the right singular vectors of r: the eigenvectors of r^T r, largest first
        g = matmul(transpose(r), r)
        allocate (b(m, m), ev(m), work(max(1, 3*m)))
        b = 0.0_dp
        do k = 1, m
            b(k, k) = 1.0_dp
        end do
        call dsygv(1, 'V', 'U', m, g, m, b, m, ev, work, size(work), info)
        if (info /= 0) return
        phis(:, idx) = matmul(phis(:, idx), g(:, m:1:-1))
    end subroutine loaded_first

    !> Add damping gamma M U U^T M to the modes U (mass-normalized free modes that neither
    !> move nor load a contact), gamma = 10 omega_ref plus their own: the contact forces
    !> never excite them (U^T W = 0), so the backbone does not change, and their dynamic
    !> stiffness k - (h omega)^2 + i h omega (c + gamma - xi) can no longer vanish where one
    !> has the frequency of the backbone and C - xi M = 0 on it (a stuck frequency equal to
    !> a free one, with proportional damping or none). Only when C leaves them decoupled
    !> (C U = M U U^T C U to 1e-9 of C): otherwise nothing is changed.
    subroutine damp_unloaded(model, u, omega_ref)
        type(model_t), intent(inout) :: model
        real(dp), intent(in) :: u(:, :), omega_ref
        real(dp), allocatable :: mu(:, :), cu(:, :), cuu(:, :)
        real(dp) :: gamma, scale
        mu = matmul(model%mass, u)
        cu = matmul(model%damping, u)
        cuu = matmul(transpose(u), cu)
        scale = max(maxval(abs(model%damping)), tiny(1.0_dp))
        if (maxval(abs(cu - matmul(mu, cuu))) > 1.0e-9_dp*scale*max(maxval(abs(u)), 1.0_dp)) &
            return
        gamma = 10.0_dp*omega_ref + maxval(abs(cuu))
        model%damping = model%damping + gamma*matmul(mu, transpose(mu))
    end subroutine damp_unloaded

    !> Whether the linear mode `phi` (frequency `omega` [rad/s]) of `model` (a sector of
    !> `cyclic`) leaves every contact channel still and unloaded: D^T phi = 0 and the
    !> reactions that hold it (reactions) 0, relative to the mode's own size (1e-8).
    logical function unloaded_mode(model, phi, omega, cyclic) result(unloaded)
        type(model_t), intent(in) :: model
        complex(dp), intent(in) :: phi(:)
        real(dp), intent(in) :: omega
        type(cyclic_t), intent(in), optional :: cyclic
        type(contact_set_t) :: cs
        complex(dp), allocatable :: dm(:, :), r(:)
        real(dp) :: scale
        call new_contact_set(cs, model)
        dm = directions(model, cs, cyclic)
        r = reactions(model, cs, phi, omega, 1.0_dp, cyclic)
        scale = maxval(abs(matmul(model%stiffness, phi)))
        unloaded = maxval(abs(r)) <= 1.0e-8_dp*scale .and. &
                   maxval(abs(matmul(transpose(dm), phi))) <= 1.0e-8_dp*maxval(abs(phi))* &
                   maxval(abs(dm))
    end function unloaded_mode

    !> The outputs of the continuation's point `state`: the weighted-residual solution of
    !> the free structure with damping C - xi M at omega (solution_from_forces), the modal
    !> quantities, the energy balance (input by -xi M = friction + viscous) and the
    !> point's coefficients; with `low` (the family on half the harmonics, continued with
    !> `copts`) the truncation estimates of omega and D; its failed checks counted in
    !> `tally`.
    subroutine evaluate_mode_point(fam, state, opts, status, nfev, damping, mp, tally, error, &
                                   low, copts)
        type(modes_family_t), intent(inout) :: fam
        type(continuation_state_t), intent(in) :: state
        type(modes_options_t), intent(in) :: opts
        character(len=*), intent(in) :: status
        integer, intent(in) :: nfev
        !> The structure's viscous damping C (the family's may hold damping added to modes
        !> the contacts do not load, damp_unloaded).
        real(dp), intent(in) :: damping(:, :)
        type(mode_point_t), intent(out) :: mp
        type(point_tally_t), intent(inout) :: tally
        type(error_type), allocatable, intent(out) :: error
        type(modes_family_t), intent(inout), optional :: low
        type(continuation_options_t), intent(in), optional :: copts
        type(model_t) :: m
        type(hbm_solution_t) :: ps
        type(sweep_options_t) :: so
        type(diagnostics_t) :: diag
        real(dp) :: omega, xi, kinetic, viscous, period
        integer :: n, nb, k
        character(len=300) :: buf
        n = fam%n
        nb = fam%prob%basis%nb
        omega = state%y(n + 1)
        xi = state%y(n + 2)
        m = fam%model
        m%omega = omega
        m%damping = m%damping - xi*m%mass
        if (allocated(fam%cyclic)) then
            ! C - xi M through the prepared modes (m's damping is C)
            m%damping = fam%model%damping
            call cyclic_solution_from_forces(m, fam%cyclic, fam%opts, &
                                             reshape(state%y(1:n), [nb, fam%prob%nc]), ps, &
                                             error, mass_damping=xi)
        else
            call solution_from_forces(m, fam%opts, reshape(state%y(1:n), [nb, fam%prob%nc]), &
                                      ps, error)
        end if
        if (allocated(error)) return
        associate (p => mp%p)
            p%parameter = exp(state%lambda)
            p%arclength = state%arclength
            p%status = status
            p%nfev = nfev
            p%harmonics = ps%harmonics
            p%residual = ps%fnorm/max(fam%vref*p%parameter, tiny(1.0_dp))
            if (allocated(opts%observe)) then
                p%amplitude = maxval(abs(matmul(ps%x, transpose(opts%observe))), dim=1)
            else
                p%amplitude = [(maxval(abs(ps%x(:, k))), k=1, size(ps%x, 2))]
            end if
            call contact_point_values(ps, p)
            p%stick = ps%stick_fraction
            if (allocated(opts%observe)) so%observe = opts%observe
            call keep_coefficients(m, ps, so, p, fam%cyclic)
            ! the energies per cycle: viscous (C) and the input of -xi M, from the velocity
            ! coefficients (the integral of v^T A v over a period)
            period = 2.0_dp*pi/omega
            viscous = quadratic_mean(ps, damping)*period
            kinetic = quadratic_mean(ps, fam%model%mass)*period
            mp%energy_input = xi*kinetic
            p%diss_friction = ps%diss_friction
            p%diss_damping = viscous
            p%dissipation = ps%diss_friction + viscous
            ! relative to the larger of the two, and at least to what a damping ratio of
            ! 1e-6 would dissipate (a stuck, undamped mode dissipates nothing: its roundoff
            ! energies are no error)
            mp%energy_error = abs(mp%energy_input - p%dissipation)/ &
                              max(abs(mp%energy_input), abs(p%dissipation), &
                                  2.0e-6_dp*omega*kinetic, tiny(1.0_dp))
            p%floquet_max = 0.0_dp
            p%stable = -1
            p%truncation = 0.0_dp
        end associate
        mp%xi = xi
        mp%damping_ratio = xi/(2.0_dp*omega)
        mp%omega_error = ieee_value(1.0_dp, ieee_quiet_nan)
        mp%damping_error = mp%omega_error
        if (present(low) .and. present(copts)) call ladder_errors(fam, low, copts, state, mp)
        if (mp%omega_error > omega_error_warning .or. mp%damping_error > &
            max(damping_error_warning*abs(mp%damping_ratio), damping_error_floor)) then
            write (buf, '(a,2(es10.2e3,a))') "nonlinear mode: truncation error estimate "// &
                "(vs half the harmonics) of omega ", mp%omega_error, " (relative), of D ", &
                mp%damping_error, " (absolute): more &hbm harmonics"
            call diag%add(level_warning, "truncation", trim(buf))
        end if
        ! the checks: the energy balance and Coulomb's law
        if (mp%energy_error > energy_untrusted) then
            write (buf, '(a,es10.2e3)') "nonlinear mode: energy balance error (input of the "// &
                "negative modal damping - friction - viscous dissipation, relative) ", &
                mp%energy_error
            call diag%add(level_untrusted, "energy_balance", trim(buf))
        else if (mp%energy_error > energy_warning) then
            write (buf, '(a,es10.2e3)') "nonlinear mode: energy balance error ", mp%energy_error
            call diag%add(level_warning, "energy_balance", trim(buf))
        end if
        if (ps%max_force_ratio - 1.0_dp > force_excess_warning) then
            write (buf, '(a,es10.2e3)') "nonlinear mode: friction force exceeds mu N (max "// &
                "|r| / mu N - 1 = ", ps%max_force_ratio - 1.0_dp
            call diag%add(merge(level_untrusted, level_warning, ps%max_force_ratio - 1.0_dp > &
                                force_excess_untrusted), "coulomb_law", trim(buf))
        end if
        call tally%add_point(diag, 0.0_dp, mp%p%parameter, mp%p%check_level, mp%p%check)
    end subroutine evaluate_mode_point

    !> The truncation estimates of the point `state` of `fam`: the point solved again by
    !> `low` (the family on half the harmonics) at the same modal amplitude, from its
    !> truncated forces, omega and xi, on half the samples too when they resolve it;
    !> mp%omega_error = 2 |omega - omega_low| / omega and mp%damping_error = 2 |D - D_low|.
    !> Left NaN when that solve fails.
    subroutine ladder_errors(fam, low, copts, state, mp)
        type(modes_family_t), intent(inout) :: fam, low
        type(continuation_options_t), intent(in) :: copts
        type(continuation_state_t), intent(in) :: state
        type(mode_point_t), intent(inout) :: mp
        type(continuation_options_t) :: co
        type(continuation_state_t) :: st
        type(continuation_report_t) :: rp
        type(error_type), allocatable :: err
        real(dp), allocatable :: r(:, :)
        real(dp) :: omega_low, d_low
        integer :: n, nb, nbl, nc
        n = fam%n
        nb = fam%prob%basis%nb
        nc = fam%prob%nc
        nbl = low%prob%basis%nb
        r = reshape(state%y(1:n), [nb, nc])
        co = copts
        co%start = state%lambda
        co%stop = state%lambda + (copts%stop - copts%start)
        co%yscale = [spread(copts%yscale(1), 1, low%n), copts%yscale(n + 1:n + 2)]
        call start_continuation(low, co, [reshape(r(1:nbl, :), [nbl*nc]), state%y(n + 1), &
                                          state%y(n + 2)], st, rp, err)
        if (allocated(err)) return
        if (.not. rp%accepted) return
        omega_low = st%y(low%n + 1)
        if (.not. (omega_low > 0.0_dp)) return
        d_low = st%y(low%n + 2)/(2.0_dp*omega_low)
        ! twice the differences: the error of H when the ladder converges like H^-0.6 or
        ! faster (the stick-slip transition converges about like H^-0.5 to H^-1)
        mp%omega_error = 2.0_dp*abs(mp%p%omega - omega_low)/mp%p%omega
        mp%damping_error = 2.0_dp*abs(mp%damping_ratio - d_low)
    end subroutine ladder_errors

    !> (1/T) integral over a period of v^T A v for the solution's velocity coefficients:
    !> v0^T A v0 + (1/2) sum_h (a_h^T A a_h + b_h^T A b_h).
    real(dp) function quadratic_mean(ps, a) result(q)
        type(hbm_solution_t), intent(in) :: ps
        real(dp), intent(in) :: a(:, :)
        integer :: k
        q = 0.0_dp
        do k = 1, ps%nb
            if (ps%harmonic(k) == 0) then
                q = q + dot_product(ps%vcoef(k, :), matmul(a, ps%vcoef(k, :)))
            else
                q = q + 0.5_dp*dot_product(ps%vcoef(k, :), matmul(a, ps%vcoef(k, :)))
            end if
        end do
    end function quadratic_mean

    !> The force scale of the unknowns: the largest friction limit mu N, preload or mu
    !> times a preload [N] (1 when all are 0).
    real(dp) function force_scale(model) result(s)
        type(model_t), intent(in) :: model
        type(contact_set_t) :: cs
        call new_contact_set(cs, model)
        s = cs%force_scale()
        if (.not. (s > 0.0_dp)) s = 1.0_dp
    end function force_scale

    !> Whether the stuck contacts hold the linear stuck motion Re(a phi exp(i omega t)):
    !> every tangential reaction within its friction limit mu N (mu times the preload for a
    !> unilateral contact); with `cyclic` on the sector `model` of that disk.
    logical function stuck_holds(model, phi, omega, a, cyclic) result(holds)
        type(model_t), intent(in) :: model
        complex(dp), intent(in) :: phi(:)
        real(dp), intent(in) :: omega, a
        type(cyclic_t), intent(in), optional :: cyclic
        complex(dp), allocatable :: r(:)
        type(contact_set_t) :: cs
        integer :: c, j
        call new_contact_set(cs, model)
        r = reactions(model, cs, phi, omega, a, cyclic)
        holds = .true.
        do c = 1, cs%nchannel
            if (cs%along(c) == along_normal) cycle
            j = cs%contact_of(c)
            if (abs(r(c)) > cs%elements(j)%e%rest_limit(c - cs%first(j) + 1)) holds = .false.
        end do
    end function stuck_holds

    !> The channel forces (complex amplitudes R, r(t) = Re(R exp(i omega t))) that hold the
    !> stuck linear motion Re(a phi exp(i omega t)): the least-squares solution of D R = (K -
    !> omega^2 M) a phi (exact when phi is a stuck mode); on a sector (`cyclic`) of T^H
    !> conj(D) R = T^H (K - omega^2 M) a phi on its cyclic motions T, D = d - e d_next.
    function reactions(model, cs, phi, omega, a, cyclic) result(r)
        type(model_t), intent(in) :: model
        type(contact_set_t), intent(in) :: cs
        complex(dp), intent(in) :: phi(:)
        real(dp), intent(in) :: omega, a
        type(cyclic_t), intent(in), optional :: cyclic
        complex(dp), allocatable :: r(:), dm(:, :), b(:), g(:, :), t(:, :)
        integer, allocatable :: ipiv(:)
        integer :: info
        dm = directions(model, cs, cyclic)
        b = a*(matmul(model%stiffness, phi) - omega**2*matmul(model%mass, phi))
        dm = conjg(dm)
        if (present(cyclic)) then
            t = cyclic_basis(cyclic, model%ndof, fundamental_phase(cyclic))
            dm = matmul(conjg(transpose(t)), dm)
            b = matmul(conjg(transpose(t)), b)
        end if
        r = matmul(conjg(transpose(dm)), b)
        g = matmul(conjg(transpose(dm)), dm)
        allocate (ipiv(cs%nchannel))
        call zgesv(cs%nchannel, 1, g, cs%nchannel, ipiv, r, cs%nchannel, info)
        if (info /= 0 .or. .not. (all(ieee_is_finite(real(r, dp))) .and. &
                                  all(ieee_is_finite(aimag(r))))) r = (0.0_dp, 0.0_dp)
    end function reactions

    !> The static normal force of every channel (0 for a tangential one) [N]: the linear
    !> statics of the structure under its preloads and static loads with every closed
    !> unilateral contact a spring k_n (an elastic one: lambda = -k_n (gap + n^T x)) or a
    !> constraint n^T x = -gap (a rigid one: lambda its reaction); the tangential channels
    !> carry no mean force.
    !> On a sector (`cyclic`) on its in-phase motions (the static pattern of the disk).
    function static_normal_forces(model, cs, cyclic) result(lambda)
        type(model_t), intent(in) :: model
        type(contact_set_t), intent(in) :: cs
        type(cyclic_t), intent(in), optional :: cyclic
        real(dp) :: lambda(cs%nchannel)
        real(dp), allocatable :: d(:, :), a(:, :), b(:), kk(:, :), f0(:), t(:, :)
        integer, allocatable :: ipiv(:), rigid(:)
        integer :: n, c, nr, info, k
        type(channel_t) :: ch
        lambda = 0.0_dp
        ! the static loads (force_harmonic = 0) beside the preloads
        f0 = 0.0_dp*preload_force(model)
        do k = 1, model%nforce()
            if (model%force_harmonic(k) == 0) f0 = f0 + model%force_amplitude(k)* &
                cos(model%force_phase(k))*force_direction(model, k)
        end do
        if (present(cyclic)) then
            t = real(cyclic_basis(cyclic, model%ndof, (1.0_dp, 0.0_dp)), dp)
            kk = matmul(transpose(t), matmul(model%stiffness, t))
            d = matmul(transpose(t), real(cyclic_directions(model, cyclic, cs, &
                                                            (1.0_dp, 0.0_dp)), dp))
            f0 = matmul(transpose(t), f0 + cyclic_preload_force(model, cyclic))
        else
            kk = model%stiffness
            d = channel_directions(model, cs)
            f0 = f0 + preload_force(model)
        end if
        n = size(kk, 1)
        allocate (rigid(0))
        do c = 1, cs%nchannel
            ch = cs%channel(c)
            if (.not. closed_at_rest(c, ch)) cycle
            if (ch%compliance <= 0.0_dp) rigid = [rigid, c]
        end do
        nr = size(rigid)
        allocate (a(n + nr, n + nr), b(n + nr), ipiv(n + nr))
        a = 0.0_dp
        a(1:n, 1:n) = kk
        b = 0.0_dp
        b(1:n) = f0
        do c = 1, cs%nchannel
            ch = cs%channel(c)
            if (.not. closed_at_rest(c, ch) .or. ch%compliance <= 0.0_dp) cycle
            a(1:n, 1:n) = a(1:n, 1:n) + spread(d(:, c), 2, n)*spread(d(:, c), 1, n)/ &
                          ch%compliance
            b(1:n) = b(1:n) - ch%gap*d(:, c)/ch%compliance
        end do
        do k = 1, nr
            a(1:n, n + k) = d(:, rigid(k))
            a(n + k, 1:n) = d(:, rigid(k))
            ch = cs%channel(rigid(k))
            b(n + k) = -ch%gap
        end do
        call dgesv(n + nr, 1, a, n + nr, ipiv, b, n + nr, info)
        if (info /= 0) return
        do c = 1, cs%nchannel
            ch = cs%channel(c)
            if (ch%kinematics /= kinematics_gap) cycle
            if (ch%compliance > 0.0_dp) then
                lambda(c) = max(0.0_dp, -(ch%gap + dot_product(d(:, c), b(1:n)))/ch%compliance)
            else if (findloc(rigid, c, 1) > 0) then
                lambda(c) = max(0.0_dp, -b(n + findloc(rigid, c, 1)))
            end if
        end do

    contains

        !> A gap channel closed at rest: preloaded, or without an initial gap.
        logical function closed_at_rest(c, ch)
            integer, intent(in) :: c
            type(channel_t), intent(in) :: ch
            closed_at_rest = ch%kinematics == kinematics_gap .and. &
                             (cs%elements(cs%contact_of(c))%e%preload() > 0.0_dp .or. &
                              ch%gap <= 0.0_dp)
        end function closed_at_rest
    end function static_normal_forces

    !> The start guess from the stuck linear mode: x = Re(a phi exp(i omega t)), the channel
    !> forces that hold it (the fundamental; the preload as the mean of a normal channel),
    !> xi = phi^H C phi (its viscous damping); on a sector with `cyclic`.
    function stuck_guess(fam, model, phi, omega, a, cyclic) result(y)
        type(modes_family_t), intent(in) :: fam
        type(model_t), intent(in) :: model
        complex(dp), intent(in) :: phi(:)
        real(dp), intent(in) :: omega, a
        type(cyclic_t), intent(in), optional :: cyclic
        real(dp) :: y(fam%n + 2)
        type(contact_set_t) :: cs
        complex(dp), allocatable :: r(:)
        real(dp), allocatable :: lambda(:)
        integer :: c, nb
        call new_contact_set(cs, model)
        nb = fam%prob%basis%nb
        r = reactions(model, cs, phi, omega, a, cyclic)
        lambda = static_normal_forces(model, cs, cyclic)
        y = 0.0_dp
        do c = 1, cs%nchannel
            ! R = r_cos - i r_sin
            y((c - 1)*nb + fam%ic1) = real(r(c), dp)
            y((c - 1)*nb + fam%is1) = -aimag(r(c))
            if (cs%along(c) == along_normal .and. fam%prob%basis%i0 > 0) &
                y((c - 1)*nb + fam%prob%basis%i0) = lambda(c)
        end do
        y(fam%n + 1) = omega
        y(fam%n + 2) = real(dot_product(phi, matmul(model%damping, phi)), dp)
    end function stuck_guess

    !> The start guess from the slipping linear mode: x = Re(a phi exp(i omega t)), each
    !> tangential channel's force the fundamental of Coulomb's -mu N sign(v) (amplitude 4 mu
    !> N / pi, a quarter period behind the channel's displacement U = a D^T phi), xi from the
    !> energy balance 4 mu N |U| per cycle (+ the viscous phi^H C phi); on a sector with
    !> `cyclic`.
    function slip_guess(fam, model, phi, omega, a, cyclic) result(y)
        type(modes_family_t), intent(in) :: fam
        type(model_t), intent(in) :: model
        complex(dp), intent(in) :: phi(:)
        real(dp), intent(in) :: omega, a
        type(cyclic_t), intent(in), optional :: cyclic
        real(dp) :: y(fam%n + 2)
        type(contact_set_t) :: cs
        complex(dp), allocatable :: dm(:, :)
        real(dp), allocatable :: lambda(:)
        real(dp) :: limit, dissipated
        complex(dp) :: u, r
        integer :: c, nb, j
        call new_contact_set(cs, model)
        dm = directions(model, cs, cyclic)
        nb = fam%prob%basis%nb
        y = 0.0_dp
        dissipated = 0.0_dp
        lambda = static_normal_forces(model, cs, cyclic)
        do c = 1, cs%nchannel
            j = cs%contact_of(c)
            if (cs%along(c) == along_normal) then
                if (fam%prob%basis%i0 > 0) y((c - 1)*nb + fam%prob%basis%i0) = lambda(c)
                cycle
            end if
            limit = cs%elements(j)%e%rest_limit(c - cs%first(j) + 1)
            u = a*sum(dm(:, c)*phi)
            if (abs(u) > 0.0_dp) then
                r = cmplx(0.0_dp, -4.0_dp*limit/pi, dp)*u/abs(u)
            else
                r = cmplx(0.0_dp, -4.0_dp*limit/pi, dp)
            end if
            y((c - 1)*nb + fam%ic1) = real(r, dp)
            y((c - 1)*nb + fam%is1) = -aimag(r)
            dissipated = dissipated + 4.0_dp*limit*abs(u)
        end do
        y(fam%n + 1) = omega
        y(fam%n + 2) = dissipated/(pi*omega*a*a) + &
                       real(dot_product(phi, matmul(model%damping, phi)), dp)
    end function slip_guess

    !> The channels' measuring directions, N x channels (complex): d, or on a sector of
    !> `cyclic` D = d - e d_next at the fundamental's inter-sector phase e.
    function directions(model, cs, cyclic) result(dm)
        type(model_t), intent(in) :: model
        type(contact_set_t), intent(in) :: cs
        type(cyclic_t), intent(in), optional :: cyclic
        complex(dp), allocatable :: dm(:, :)
        if (present(cyclic)) then
            dm = cyclic_directions(model, cyclic, cs, fundamental_phase(cyclic))
        else
            dm = cmplx(channel_directions(model, cs), 0.0_dp, dp)
        end if
    end function directions

    !> The next sector's phase factor at the fundamental of a wave of nodal diameter
    !> cyc%engine_order: exp(-i 2 pi nd / N).
    complex(dp) function fundamental_phase(cyc) result(e)
        type(cyclic_t), intent(in) :: cyc
        e = exp(cmplx(0.0_dp, sector_phase(1, cyc%engine_order, cyc%sectors, 1), dp))
    end function fundamental_phase
end module stickslip_modes
