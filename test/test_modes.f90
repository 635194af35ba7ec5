!> Nonlinear modes (EPMC, &run method = 'modes') against independent truth: the 1-DOF
!> friction oscillator's describing-function damping at H = 1 (D = 2 mu N / (pi k a)); the
!> linear limits (at small amplitude the stuck linear mode, its frequency and viscous
!> damping ratio; at large amplitude the slipping linear mode, its frequency and the
!> damping 2 mu N |w^T phi| / (pi omega^2 a) of Coulomb's first harmonic); the energy
!> balance at every point; the family's Jacobian against central differences; the forced
!> response near resonance synthesized from the backbone (single nonlinear mode) against
!> separate forced solves; a contact law (a unilateral elastic contact under a preload)
!> whose stuck limit is the linear mode with the normal spring; the command line with the
!> example and bad &modes input.
module test_modes
    use stickslip_kinds, only: dp, pi
    use stickslip_error, only: error_type, real_text, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_linear_modes, only: linear_modes
    use stickslip_modes, only: modes_options_t, modes_result_t, mode_point_t, run_modes
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep
    use stickslip_reference, only: reference_options_t
    use stickslip_modes_family, only: modes_family_t, new_modes_family, free_structure
    use test_cli, only: cli
    use fixtures, only: liftoff_model, planar_model, scratch, write_lines, first_line, count_commas
    use testing, only: test_counter_t, check, check_error
    implicit none
    private
    public :: run_modes_tests, jacobian_errors

contains

    subroutine run_modes_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(modes_result_t) :: seed_backbone
        call test_describing_function(t)
        call test_linear_limits(t, seed_backbone)
        call test_viscous_limit(t)
        call test_jacobian(t)
        call test_synthesis(t)
        call test_unilateral(t)
        call test_jenkins_planar(t)
        call test_cli_modes(t)
        call test_unloaded_mode(t)
        call test_error_estimate(t, seed_backbone)
        call test_degenerate(t)
    end subroutine run_modes_tests

    !> A stuck frequency equal to a free one (issue 24, examples/degenerate_modes.nml): the
    !> symmetric 3-DOF chain rubbing at its middle DOF, Rayleigh damping C = 0.01 (M + K).
    !> Pinned, the chain has the double frequency sqrt 2; the combination (1, 0, -1) leaves
    !> the contact unloaded and is the free chain's second mode, with the damping of the
    !> backbone's start (C - xi M singular on it). Mode 1 is the loaded combination (1, 0, 1)
    !> / sqrt 2 whatever basis LAPACK returns, and its backbone completes: at small amplitude
    !> the stuck mode (omega = sqrt 2, D = (0.01 + 0.02) / (2 sqrt 2), the shape symmetric),
    !> at large amplitude the free mode 3 (omega^2 = 2 + sqrt 2), the energy balance at every
    !> point. Before: no start. Mode 2, the unloaded one, is refused as an input error.
    subroutine test_degenerate(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(error_type), allocatable :: error
        integer :: n
        ! the seed's contact (DOF 2, mu N = 0.45) on the 3-DOF chain
        m = seed(0.0_dp, 0.0_dp)
        m%ndof = 3
        m%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, &
                          1.0_dp], [3, 3])
        m%stiffness = reshape([2.0_dp, -1.0_dp, 0.0_dp, -1.0_dp, 2.0_dp, -1.0_dp, 0.0_dp, &
                               -1.0_dp, 2.0_dp], [3, 3])
        m%damping = 0.01_dp*(m%mass + m%stiffness)
        m%force_amplitude = [0.0_dp]
        ho%harmonics = 7
        ho%samples = 512
        mo%amplitude_start = 0.01_dp
        mo%amplitude_stop = 100.0_dp
        mo%points = 41
        mo%error_estimate = .false.
        call run_modes(m, ho, mo, res, error)
        call check_error(t, error, "modes: degenerate: the loaded mode's backbone", .false.)
        if (allocated(error)) return
        n = res%npoints
        call check(t, res%complete .and. res%start == 'stuck', "modes: degenerate: "// &
                   "complete, started stuck", res%diagnosis)
        call check(t, abs(res%points(1)%p%omega - sqrt(2.0_dp)) <= 1.0e-10_dp .and. &
                   abs(res%points(1)%damping_ratio - 0.03_dp/(2.0_dp*sqrt(2.0_dp))) <= &
                   1.0e-8_dp .and. abs(res%points(1)%p%amplitude(1) - &
                                       res%points(1)%p%amplitude(3)) <= &
                   1.0e-8_dp*res%points(1)%p%amplitude(1), "modes: degenerate: small "// &
                   "amplitude = the loaded stuck mode (1, 0, 1), its viscous damping", &
                   real_text(res%points(1)%p%omega))
        call check(t, abs(res%points(n)%p%omega - sqrt(2.0_dp + sqrt(2.0_dp))) <= 1.0e-4_dp &
                   .and. abs(res%omega_slipping - sqrt(2.0_dp + sqrt(2.0_dp))) <= 1.0e-10_dp, &
                   "modes: degenerate: large amplitude -> the free mode 3", &
                   real_text(res%points(n)%p%omega))
        call check(t, maxval(res%points(1:n)%energy_error) <= 1.0e-10_dp, &
                   "modes: degenerate: energy balance at every point", &
                   real_text(maxval(res%points(1:n)%energy_error)))
        call check_refinements(t, m, ho, mo)
        mo%mode = 2
        call run_modes(m, ho, mo, res, error)
        call check_error(t, error, "modes: degenerate: the unloaded combination refused", &
                         .true., [character(len=40) :: "does not load the contacts"])
        ! mu = 0: the contacts carry no force; every mode is linear: an input error
        m%mu = [0.0_dp]
        mo%mode = 1
        call run_modes(m, ho, mo, res, error)
        call check_error(t, error, "modes: mu = 0 refused with why", .true., &
                         [character(len=40) :: "&friction mu = 0", "linear mode at every"])
    end subroutine test_degenerate

    !> &modes refinements on a whole structure (the chain of test_degenerate, H = 7): over
    !> samples 32 to 256, a backbone that stops without refinements is continued on 4 times
    !> the samples and completes, its last point at the free mode 3 (sqrt(2 + sqrt 2), the
    !> analytic large-amplitude limit, to 1e-4 as at 512 samples), balancing its energy;
    !> samples_end and refined_at say what was done, one point has the status 'refined'
    !> (or, traced again from the start, refined_at begins at amplitude_start). At least one
    !> of those sample counts must stop without refinements, or the check tests nothing.
    subroutine check_refinements(t, m, ho, mo)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(hbm_options_t), intent(in) :: ho
        type(modes_options_t), intent(in) :: mo
        integer, parameter :: counts(4) = [32, 64, 128, 256]
        type(hbm_options_t) :: hs
        type(modes_options_t) :: none
        type(modes_result_t) :: plain, refined
        type(error_type), allocatable :: error
        integer :: k, stopped, n
        logical :: ok
        character(len=:), allocatable :: detail
        stopped = 0
        ok = .true.
        detail = ""
        do k = 1, size(counts)
            hs = ho
            hs%samples = counts(k)
            none = mo
            none%refinements = 0
            call run_modes(m, hs, none, plain, error)
            if (.not. allocated(error)) call run_modes(m, hs, mo, refined, error)
            if (allocated(error)) then
                ok = .false.
                detail = detail//" "//error%message
                exit
            end if
            detail = detail//" "//itoa(counts(k))//": "//merge("complete", "stopped ", &
                                                                plain%complete)
            if (plain%complete) then
                ok = ok .and. refined%samples == counts(k) .and. size(refined%refined_at) == 0
                cycle
            end if
            stopped = stopped + 1
            n = refined%npoints
            detail = detail//", refined to "//itoa(refined%samples)//" from a = "// &
                     real_text(refined%refined_at(1))//", end omega "// &
                     real_text(refined%points(n)%p%omega)
            ok = ok .and. refined%complete .and. refined%samples > counts(k) .and. &
                 size(refined%refined_at) >= 1 .and. &
                 abs(refined%points(n)%p%omega - sqrt(2.0_dp + sqrt(2.0_dp))) <= 1.0e-4_dp .and. &
                 maxval(refined%points(1:n)%energy_error) <= 1.0e-10_dp .and. &
                 (count(refined%points(1:n)%p%status == 'refined') == 1 .or. &
                  refined%refined_at(size(refined%refined_at)) == mo%amplitude_start)
        end do
        call check(t, ok .and. stopped > 0, "modes: refinements: a backbone that stops on "// &
                   "too few samples is continued on more and ends at the free mode 3", detail)
    end subroutine check_refinements

    !> The per-point error estimates of omega and D (issue 24, item 3) against the backbone at
    !> 4x the harmonics (H = 60, 1024 samples) on the seed: every point the estimate leaves
    !> unflagged is within the warning thresholds of the truth (omega to omega_error_warning,
    !> D to damping_error_warning of D or damping_error_floor), the stick-slip transition is
    !> flagged 'truncation', and the points crowd where D changes: no step of D larger
    !> than 0.01 (with points = 41: 0.046 before, between a = 0.53 and 0.64).
    subroutine test_error_estimate(t, res)
        type(test_counter_t), intent(inout) :: t
        !> The seed backbone of test_linear_limits (H = 15, 256 samples, a = 0.01 .. 1000,
        !> points = 41, with its error estimates).
        type(modes_result_t), intent(in) :: res
        type(hbm_options_t) :: hi
        type(modes_options_t) :: mo
        type(modes_result_t) :: ref
        type(error_type), allocatable :: error
        real(dp) :: la, w, ew, ed, dt, wt
        integer :: k, j, unflagged_out, flagged, n
        call check(t, res%npoints >= 2, "modes: estimate: the seed backbone at H = 15")
        if (res%npoints < 2) return
        mo%amplitude_start = 0.01_dp
        mo%amplitude_stop = 1000.0_dp
        mo%points = 41
        hi%harmonics = 60
        hi%samples = 1024
        mo%error_estimate = .false.
        call run_modes(seed(0.0_dp, 0.0_dp), hi, mo, ref, error)
        call check_error(t, error, "modes: estimate: backbone at H = 60", .false.)
        if (allocated(error)) return
        unflagged_out = 0
        flagged = 0
        n = 0
        do k = 1, res%npoints
            associate (p => res%points(k))
                if (index(p%p%check, 'truncation') > 0) flagged = flagged + 1
                ! (the end points' amplitudes agree to roundoff: exp(ln a) at the end of
                ! the range, 1000 within a few ulps either way)
                la = log(p%p%parameter)
                if (abs(la - log(ref%points(1)%p%parameter)) <= 1.0e-12_dp) &
                    la = log(ref%points(1)%p%parameter)
                if (abs(la - log(ref%points(ref%npoints)%p%parameter)) <= 1.0e-12_dp) &
                    la = log(ref%points(ref%npoints)%p%parameter)
                do j = 1, ref%npoints - 1
                    associate (a => ref%points(j), b => ref%points(j + 1))
                        if ((log(a%p%parameter) - la)*(log(b%p%parameter) - la) > 0.0_dp) cycle
                        w = (la - log(a%p%parameter))/(log(b%p%parameter) - log(a%p%parameter))
                        wt = (1.0_dp - w)*a%p%omega + w*b%p%omega
                        ! D ~ 1 / a at large amplitude: interpolated in log D
                        if (a%damping_ratio > 0.0_dp .and. b%damping_ratio > 0.0_dp) then
                            dt = exp((1.0_dp - w)*log(a%damping_ratio) + &
                                     w*log(b%damping_ratio))
                        else
                            dt = (1.0_dp - w)*a%damping_ratio + w*b%damping_ratio
                        end if
                    end associate
                    n = n + 1
                    ew = abs(p%p%omega - wt)/wt
                    ed = abs(p%damping_ratio - dt)
                    if ((ew > 1.0e-3_dp .or. ed > max(5.0e-2_dp*abs(p%damping_ratio), &
                                                      1.0e-4_dp)) .and. &
                        index(p%p%check, 'truncation') == 0) unflagged_out = unflagged_out + 1
                    exit
                end do
            end associate
        end do
        call check(t, n == res%npoints .and. unflagged_out == 0 .and. flagged > 0, &
                   "modes: estimate: every point off the 4x-harmonics backbone beyond the "// &
                   "thresholds is flagged 'truncation' ("//real_text(real(flagged, dp))// &
                   " flagged)", real_text(real(unflagged_out, dp))//" unflagged beyond; "// &
                   itoa(n)//" of "//itoa(res%npoints)//" points within the reference's range")
        call check(t, maxval(abs(res%points(2:res%npoints)%damping_ratio - &
                                 res%points(1:res%npoints - 1)%damping_ratio)) <= 0.01_dp, &
                   "modes: estimate: the points follow the change of D")
    end subroutine test_error_estimate

    !> A mode that leaves the contact unloaded (issue 24): DOF 1 on its own spring (k = 2),
    !> the contact on DOF 2, uncoupled: the stuck mode 1 (omega = sqrt 2) is also a mode
    !> without the contact (the stuck and free frequencies coincide). The equations, driven by
    !> the contact forces, cannot follow it: an input error that says why and what to do
    !> (before: "no periodic motion found ... try &hbm rho = 0", the default already).
    subroutine test_unloaded_mode(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(error_type), allocatable :: error
        m = seed(0.01_dp, 0.0_dp)
        m%stiffness = reshape([2.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        ho%harmonics = 7
        ho%samples = 128
        mo%amplitude_start = 0.01_dp
        mo%amplitude_stop = 10.0_dp
        mo%points = 10
        call run_modes(m, ho, mo, res, error)
        call check_error(t, error, "modes: unloaded mode refused", .true., &
                         [character(len=40) :: "does not load the contacts", &
                          "frequencies coincide", "Choose another &modes mode"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "modes: unloaded mode: an input error")
    end subroutine test_unloaded_mode

    !> The seed structure (M = I, K = [2 -1; -1 1], DOF 2 on the ground, mu N = 0.45),
    !> damping c_m M + c_k K.
    function seed(cm, ck) result(m)
        real(dp), intent(in) :: cm, ck
        type(model_t) :: m
        m%ndof = 2
        m%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        m%stiffness = reshape([2.0_dp, -1.0_dp, -1.0_dp, 1.0_dp], [2, 2])
        m%damping = cm*m%mass + ck*m%stiffness
        m%omega = 1.0_dp
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [1.0_dp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [2]
        m%contact_dof2 = [0]
        m%mu = [0.45_dp]
        m%normal_load = [1.0_dp]
    end function seed

    !> One mass m = 2 on a spring k = 8 rubbing on the ground (mu N = 0.3), at H = 1: the
    !> weighted residual of Coulomb's law at one harmonic is the describing function as
    !> soon as the force reverses in a small share of the period, so D(a) = 2 mu N / (pi k
    !> a_x) with a_x = a / sqrt(m), at omega = sqrt(k / m); the stuck structure has no
    !> motion: the family starts from the slipping mode.
    subroutine test_describing_function(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(error_type), allocatable :: error
        real(dp) :: worst_d, worst_w, worst_e, expected
        integer :: k
        m%ndof = 1
        m%mass = reshape([2.0_dp], [1, 1])
        m%stiffness = reshape([8.0_dp], [1, 1])
        m%damping = reshape([0.0_dp], [1, 1])
        m%omega = 1.0_dp
        m%force_dof = [integer ::]
        m%force_harmonic = [integer ::]
        m%force_amplitude = [real(dp) ::]
        m%force_phase = [real(dp) ::]
        m%contact_dof = [1]
        m%contact_dof2 = [0]
        m%mu = [0.3_dp]
        m%normal_load = [1.0_dp]
        ho%harmonics = 1
        ho%samples = 512
        mo%amplitude_start = 1.0_dp
        mo%amplitude_stop = 100.0_dp
        mo%points = 11
        call run_modes(m, ho, mo, res, error)
        call check_error(t, error, "modes: 1 DOF: backbone", .false.)
        if (allocated(error)) return
        call check(t, res%complete .and. res%start == 'slipping' .and. res%npoints >= 11, &
                   "modes: 1 DOF: complete, started slipping", res%start)
        worst_d = 0.0_dp
        worst_w = 0.0_dp
        worst_e = 0.0_dp
        do k = 1, res%npoints
            associate (p => res%points(k))
                expected = 2.0_dp*0.3_dp/(pi*8.0_dp*p%p%parameter/sqrt(2.0_dp))
                worst_d = max(worst_d, abs(p%damping_ratio - expected)/expected)
                worst_w = max(worst_w, abs(p%p%omega - 2.0_dp))
                worst_e = max(worst_e, p%energy_error)
            end associate
        end do
        call check(t, worst_d <= 1.0e-4_dp, "modes: 1 DOF: D = 2 mu N / (pi k a_x) (the "// &
                   "describing function) at H = 1", "worst relative error "//real_text(worst_d))
        call check(t, worst_w <= 1.0e-10_dp, "modes: 1 DOF: omega = sqrt(k / m)", &
                   real_text(worst_w))
        call check(t, worst_e <= 1.0e-12_dp, "modes: 1 DOF: energy balance", real_text(worst_e))
    end subroutine test_describing_function

    !> The seed structure without damping from a = 0.01 (stuck) to 1000 (slipping): the
    !> first points are the pinned structure's mode (omega = sqrt 2, D = 0); the last is
    !> the free structure's mode most like it (omega_2 = 1.6180, phi_2) with Coulomb's
    !> damping 2 mu N |phi_2(2)| / (pi omega_2^2 a); the energy balance holds at every
    !> point; the frequency rises monotonically between the limits.
    subroutine test_linear_limits(t, res)
        type(test_counter_t), intent(inout) :: t
        !> The seed backbone (for test_error_estimate).
        type(modes_result_t), intent(out) :: res
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(error_type), allocatable :: error
        real(dp), allocatable :: wf(:), phif(:, :)
        real(dp) :: expected, worst_e
        integer :: n, k
        logical :: monotone
        ho%harmonics = 15
        ho%samples = 256
        mo%amplitude_start = 0.01_dp
        mo%amplitude_stop = 1000.0_dp
        mo%points = 41
        call run_modes(seed(0.0_dp, 0.0_dp), ho, mo, res, error)
        call check_error(t, error, "modes: seed: backbone", .false.)
        if (allocated(error)) return
        n = res%npoints
        call check(t, res%complete .and. res%start == 'stuck' .and. res%odd_only, &
                   "modes: seed: complete, started stuck, odd harmonics", res%diagnosis)
        call check(t, abs(res%points(1)%p%omega - sqrt(2.0_dp)) <= 1.0e-12_dp .and. &
                   abs(res%points(1)%damping_ratio) <= 1.0e-14_dp .and. &
                   res%points(1)%p%stick(1) == 1.0_dp, "modes: seed: small amplitude = "// &
                   "the stuck linear mode (omega = sqrt 2, D = 0, stuck all period)", &
                   real_text(res%points(1)%p%omega))
        call linear_modes(free_structure(seed(0.0_dp, 0.0_dp)), .false., wf, phif, error)
        if (allocated(error)) return
        expected = 2.0_dp*0.45_dp*abs(phif(2, 2))/(pi*wf(2)**2*res%points(n)%p%parameter)
        call check(t, abs(res%omega_slipping - wf(2)) <= 1.0e-12_dp .and. &
                   abs(res%points(n)%p%omega - wf(2)) <= 1.0e-5_dp, "modes: seed: large "// &
                   "amplitude -> the slipping linear mode's frequency", &
                   real_text(res%points(n)%p%omega - wf(2)))
        call check(t, abs(res%points(n)%damping_ratio - expected) <= 2.0e-3_dp*expected, &
                   "modes: seed: large amplitude -> Coulomb's damping 2 mu N |w^T phi| / "// &
                   "(pi omega^2 a)", real_text(res%points(n)%damping_ratio/expected - 1.0_dp))
        worst_e = maxval(res%points(1:n)%energy_error)
        monotone = all([(res%points(k + 1)%p%omega >= res%points(k)%p%omega - 1.0e-9_dp, &
                         k=1, n - 1)])
        call check(t, worst_e <= 1.0e-10_dp, "modes: seed: energy balance at every point", &
                   real_text(worst_e))
        call check(t, monotone .and. maxval(res%points(1:n)%damping_ratio) > 0.05_dp, &
                   "modes: seed: omega rises monotonically; D peaks in between")
    end subroutine test_linear_limits

    !> With viscous damping C = 0.02 K the stuck limit's damping ratio is the linear mode's,
    !> phi^T C phi / (2 omega) = 0.01 omega.
    subroutine test_viscous_limit(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(error_type), allocatable :: error
        ho%harmonics = 7
        ho%samples = 128
        mo%amplitude_start = 0.01_dp
        mo%amplitude_stop = 0.1_dp
        mo%points = 3
        call run_modes(seed(0.0_dp, 0.02_dp), ho, mo, res, error)
        call check_error(t, error, "modes: viscous: backbone", .false.)
        if (allocated(error)) return
        call check(t, abs(res%points(1)%damping_ratio - 0.01_dp*sqrt(2.0_dp)) <= 1.0e-12_dp &
                   .and. abs(res%points(1)%p%omega - sqrt(2.0_dp)) <= 1.0e-12_dp, &
                   "modes: viscous: stuck limit D = phi^T C phi / (2 omega)", &
                   real_text(res%points(1)%damping_ratio))
    end subroutine test_viscous_limit

    !> The family's Jacobian (exact in R, analytic normalization rows, central differences
    !> in omega and xi) and dF/dlambda against central differences of its residual, at a
    !> stuck, a stick-slip and a slipping point of the seed's backbone.
    subroutine test_jacobian(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(modes_family_t) :: fam
        type(model_t) :: free
        type(error_type), allocatable :: error
        real(dp), allocatable :: ws(:), phis(:, :), y(:)
        real(dp) :: lambda, worst, worst_l, e_y, e_l
        integer :: which(3), i, stat
        ho%harmonics = 7
        ho%samples = 128
        mo%amplitude_start = 0.1_dp
        mo%amplitude_stop = 10.0_dp
        mo%points = 21
        free = free_structure(seed(0.0_dp, 0.02_dp))
        call run_modes(free, ho, mo, res, error)
        call check_error(t, error, "modes: jacobian: backbone", .false.)
        if (allocated(error)) return
        call linear_modes(free, .true., ws, phis, error)
        if (allocated(error)) return
        ho%rho = res%rho
        call new_modes_family(fam, free, ho, cmplx(phis(:, 1), 0.0_dp, dp), ws(1), error)
        if (allocated(error)) return
        ! a stuck point, one that sticks part of the period, one that slips all period
        which = [1, minloc([(abs(res%points(i)%p%stick(1) - 0.5_dp), i=1, res%npoints)], 1), &
                 res%npoints]
        worst = 0.0_dp
        worst_l = 0.0_dp
        do i = 1, 3
            associate (p => res%points(which(i)))
                y = [reshape(p%p%rcoef, [size(p%p%rcoef)]), p%p%omega, p%xi]
                lambda = log(p%p%parameter)
            end associate
            stat = 0
            call jacobian_errors(fam, y, lambda, e_y, e_l, stat)
            worst = max(worst, e_y)
            worst_l = max(worst_l, e_l)
        end do
        call fam%destroy()
        call check(t, stat == 0 .and. worst <= 1.0e-5_dp .and. worst_l <= 1.0e-6_dp, &
                   "modes: jacobian: dF/dy and dF/dlambda against central differences "// &
                   "(stuck, stick-slip, slipping)", "dF/dy "//real_text(worst)// &
                   ", dF/dlambda "//real_text(worst_l))
    end subroutine test_jacobian

    !> The largest errors of a family's Jacobian at (y, lambda) against central differences
    !> of its residual, relative to the largest entry: dF/dy (steps 1e-6 of each unknown, at
    !> least 1e-9 of the largest force) and dF/dlambda (step 1e-6). stat nonzero when the
    !> family has no equations there.
    subroutine jacobian_errors(fam, y, lambda, e_y, e_l, stat)
        type(modes_family_t), intent(inout) :: fam
        real(dp), intent(in) :: y(:), lambda
        real(dp), intent(out) :: e_y, e_l
        integer, intent(inout) :: stat
        real(dp), allocatable :: jy(:, :), jl(:), fp(:), fm(:), yp(:), fd(:, :), fdl(:)
        real(dp) :: h
        integer :: j, n
        n = size(y)
        allocate (jy(n, n), jl(n), fp(n), fm(n), fd(n, n), fdl(n))
        call fam%jacobian(y, lambda, jy, jl, stat)
        do j = 1, n
            h = 1.0e-6_dp*max(abs(y(j)), 1.0e-3_dp*maxval(abs(y(1:n - 2))))
            yp = y
            yp(j) = y(j) + h
            call fam%residual(yp, lambda, fp, stat)
            yp(j) = y(j) - h
            call fam%residual(yp, lambda, fm, stat)
            fd(:, j) = (fp - fm)/(2.0_dp*h)
        end do
        call fam%residual(y, lambda + 1.0e-6_dp, fp, stat)
        call fam%residual(y, lambda - 1.0e-6_dp, fm, stat)
        fdl = (fp - fm)/2.0e-6_dp
        e_y = maxval(abs(jy - fd))/maxval(abs(jy))
        e_l = maxval(abs(jl - fdl))/maxval(abs(jl))
    end subroutine jacobian_errors

    !> Single-nonlinear-mode synthesis: the seed structure with light damping (C = 0.01 M)
    !> forced by f = 0.05 cos(Omega t) on DOF 1 (resonant peak at a = 0.56, where the
    !> contact sticks a third of the period and D = 0.02). For the backbone points where the
    !> contact slips part of the period (a, omega, D, x1) the
    !> forced response of the mode is a at the Omega where
    !> (omega^2 - Omega^2)^2 + (2 D omega Omega)^2 = |phi1^H f|^2, phi1 = (c1 - i s1) / a;
    !> separate forced solves at those Omega (both sides of the resonance) must respond with
    !> that modal amplitude.
    subroutine test_synthesis(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho, fo
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(hbm_solution_t) :: sol
        type(model_t) :: m
        type(error_type), allocatable :: error
        type(sweep_options_t) :: so
        type(reference_options_t) :: ro
        type(sweep_result_t) :: curve
        real(dp) :: a, w, d, g, disc, q, big_omega, af, worst, c1(2), s1(2), f(2), peak, d1, &
                    d2, swept
        integer :: k, side, ic, is, checked, i
        ho%harmonics = 15
        ho%samples = 256
        mo%amplitude_start = 0.05_dp
        mo%amplitude_stop = 5.0_dp
        mo%points = 41
        m = seed(0.01_dp, 0.0_dp)
        call run_modes(m, ho, mo, res, error)
        call check_error(t, error, "modes: synthesis: backbone", .false.)
        if (allocated(error)) return
        f = [0.05_dp, 0.0_dp]
        m%force_amplitude = [0.05_dp]
        fo = ho
        fo%odd_only = .true.
        worst = 0.0_dp
        checked = 0
        do k = 1, res%npoints
            ! the stick-slip points: the stuck ones are the linear structure's (exact)
            if (res%points(k)%p%stick(1) >= 1.0_dp) cycle
            associate (p => res%points(k))
                a = p%p%parameter
                w = p%p%omega
                d = p%damping_ratio
                ic = findloc(p%p%harmonic, 1, 1)
                is = ic + 1
                c1 = p%p%xcoef(ic, :)
                s1 = p%p%xcoef(is, :)
            end associate
            g = sqrt(dot_product(c1, f)**2 + dot_product(s1, f)**2)/a**2
            disc = w**4*(1.0_dp - 2.0_dp*d*d)**2 - w**4 + g*g
            if (disc < 0.0_dp) cycle
            do side = -1, 1, 2
                q = w*w*(1.0_dp - 2.0_dp*d*d) + side*sqrt(disc)
                if (q <= 0.0_dp) cycle
                big_omega = sqrt(q)
                m%omega = big_omega
                call solve_periodic(m, fo, sol, error)
                if (allocated(error)) return
                if (.not. sol%converged) cycle
                ic = findloc(sol%harmonic, 1, 1)
                af = sqrt(sum([(sol%xcoef(ic, i)**2 + sol%xcoef(ic + 1, i)**2, i=1, 2)]))
                worst = max(worst, abs(af - a)/a)
                checked = checked + 1
            end do
        end do
        ! the peak: the synthesized one (where the two Omega meet, disc = 0, interpolated
        ! between the backbone points around it) against the forced sweep's largest modal
        ! amplitude over 1.30 .. 1.55 rad/s
        peak = 0.0_dp
        do k = 1, res%npoints - 1
            d1 = peak_disc(res%points(k))
            d2 = peak_disc(res%points(k + 1))
            if (d1 >= 0.0_dp .and. d2 < 0.0_dp) then
                peak = res%points(k)%p%parameter + (res%points(k + 1)%p%parameter - &
                       res%points(k)%p%parameter)*d1/(d1 - d2)
                exit
            end if
        end do
        so%parameter = 'omega'
        so%start = 1.30_dp
        so%stop = 1.55_dp
        so%step = 0.002_dp
        so%max_step = 0.002_dp
        so%stability = .false.
        call run_sweep(m, fo, ro, so, curve, error)
        call check_error(t, error, "modes: synthesis: forced sweep", .false.)
        if (allocated(error)) return
        swept = 0.0_dp
        do k = 1, curve%npoints
            ic = findloc(curve%points(k)%harmonic, 1, 1)
            swept = max(swept, sqrt(sum(curve%points(k)%xcoef(ic:ic + 1, :)**2)))
        end do
        call check(t, peak > 0.0_dp .and. abs(swept - peak) <= 0.02_dp*peak, "modes: "// &
                   "synthesis: the peak synthesized from the backbone = the forced sweep's", &
                   "synthesized "//real_text(peak)//", swept "//real_text(swept))
        call check(t, checked >= 8 .and. worst <= 0.02_dp, "modes: synthesis: the forced "// &
                   "response near resonance follows the backbone (single nonlinear mode)", &
                   "points "//real_text(real(checked, dp))//", worst relative amplitude "// &
                   "difference "//real_text(worst))
    contains

        !> The discriminant of the synthesis at a backbone point: >= 0 where the forced
        !> response reaches that modal amplitude.
        real(dp) function peak_disc(p) result(dd)
            type(mode_point_t), intent(in) :: p
            integer :: j1
            real(dp) :: gg
            j1 = findloc(p%p%harmonic, 1, 1)
            gg = sqrt(dot_product(p%p%xcoef(j1, :), f)**2 + &
                      dot_product(p%p%xcoef(j1 + 1, :), f)**2)/p%p%parameter**2
            dd = p%p%omega**4*(1.0_dp - 2.0_dp*p%damping_ratio**2)**2 - p%p%omega**4 + gg*gg
        end function peak_disc
    end subroutine test_synthesis

    !> A contact law: tangential friction on DOF 1 with a unilateral elastic contact (k_n =
    !> 10) on DOF 2 pressed by a preload of 1 N (liftoff_model). At small amplitude the
    !> contact is stuck and closed: the mode is the linear one with DOF 1 pinned and the
    !> normal spring on DOF 2; the energy balance holds along the backbone.
    subroutine test_unilateral(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(error_type), allocatable :: error
        real(dp) :: expected
        ho%harmonics = 10
        ho%samples = 256
        mo%amplitude_start = 0.001_dp
        mo%amplitude_stop = 1.0_dp
        mo%points = 21
        call run_modes(liftoff_model(10.0_dp, 0.0_dp), ho, mo, res, error)
        call check_error(t, error, "modes: unilateral: backbone", .false.)
        if (allocated(error)) return
        ! DOF 1 pinned: DOF 2 alone, k = 1.8 + 10
        expected = sqrt(11.8_dp)
        call check(t, res%start == 'stuck' .and. .not. res%odd_only .and. &
                   abs(res%points(1)%p%omega - expected) <= 1.0e-9_dp*expected, &
                   "modes: unilateral: stuck limit = the linear mode with the normal spring", &
                   real_text(res%points(1)%p%omega))
        call check(t, res%npoints >= 2 .and. maxval(res%points(1:res%npoints)%energy_error) &
                   <= 1.0e-9_dp, "modes: unilateral: energy balance along the backbone", &
                   res%diagnosis)
    end subroutine test_unilateral

    !> 2D friction with a contact stiffness: a unit mass on unit springs in the plane,
    !> held by a Jenkins element (k_t = 3, mu N = 0.3). At small amplitude the slider sticks:
    !> omega = sqrt(1 + 3) = 2 (the viscous D = 0.1 / (2 omega)); at large amplitude it
    !> slips: omega -> 1; the energy balance holds along the backbone.
    subroutine test_jenkins_planar(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(error_type), allocatable :: error
        integer :: n
        ho%harmonics = 9
        ho%samples = 128
        mo%amplitude_start = 0.01_dp
        mo%amplitude_stop = 100.0_dp
        mo%points = 21
        call run_modes(planar_model(1.0_dp, 1.0_dp, 3.0_dp), ho, mo, res, error)
        call check_error(t, error, "modes: planar Jenkins: backbone", .false.)
        if (allocated(error)) return
        n = res%npoints
        call check(t, res%complete .and. res%start == 'stuck' .and. &
                   abs(res%points(1)%p%omega - 2.0_dp) <= 1.0e-10_dp .and. &
                   abs(res%points(1)%damping_ratio - 0.025_dp) <= 1.0e-10_dp, &
                   "modes: planar Jenkins: stuck limit omega = sqrt(k + k_t), viscous D", &
                   res%diagnosis)
        call check(t, abs(res%points(n)%p%omega - 1.0_dp) <= 1.0e-2_dp .and. &
                   maxval(res%points(1:n)%energy_error) <= 1.0e-9_dp, "modes: planar "// &
                   "Jenkins: slipping limit omega -> 1, energy balance", &
                   real_text(res%points(n)%p%omega))
    end subroutine test_jenkins_planar

    !> The command line runs examples/seed_modes.nml (exit 0, modes.csv with its header, no
    !> warning); bad &modes input is one error naming the group and variable (exit 1); a
    !> case of method 'modes' without &modes or without contacts is refused.
    subroutine test_cli_modes(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/modes_cli"
        character(len=:), allocatable :: out, err
        integer :: code
        character(len=120) :: lines(6)
        lines(1) = "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /"
        lines(2) = "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /"
        lines(3) = "&hbm harmonics = 7, samples = 128 /"
        lines(4) = "&run method = 'modes' /"
        lines(5) = "&modes amplitude_start = 0.1, amplitude_stop = 10, points = 11 /"
        lines(6) = "&output directory = '"//dir//"' /"
        call write_lines(dir//".nml", lines)
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        ! H = 7 does not resolve the stick-slip transition: the error estimate says so
        call check(t, code == 0 .and. index(err, "stickslip: warning:") == 1 .and. &
                   index(err, "'truncation'") > 0, "modes cli: exit 0, a truncation warning "// &
                   "on stderr at H = 7", err)
        call check(t, index(first_line(dir//"/modes.csv"), ",trusted,check,omega_error,"// &
                   "damping_error") > 0 .and. fields_agree(dir//"/modes.csv"), &
                   "modes cli: the estimates' columns", first_line(dir//"/modes.csv"))
        lines(5) = "&modes amplitude_start = 0.1, amplitude_stop = 10, points = 11, "// &
                   "error_estimate = .false. /"
        call write_lines(dir//".nml", lines)
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 0 .and. len(err) == 0, "modes cli: error_estimate = .false.: "// &
                   "exit 0, nothing on stderr", err)
        lines(5) = "&modes amplitude_start = 0.1, amplitude_stop = 10, points = 11 /"
        call write_lines(dir//".nml", lines)
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, index(out, "nonlinear mode 1") > 0 .and. index(out, "modes.csv") > 0, &
                   "modes cli: summary", out)
        call check(t, index(first_line(dir//"/modes.csv"), "amplitude,omega,frequency,xi,"// &
                   "damping_ratio,amp_1,amp_2,dissipation,diss_friction,diss_viscous,"// &
                   "energy_error,rmax_1,stick_1,harmonics,residual,status,nfev") == 1, &
                   "modes cli: modes.csv header", first_line(dir//"/modes.csv"))
        call check(t, first_line(dir//"/modes_harmonics.csv") == &
                   "point,amplitude,omega,harmonic,kind,x1,x2,r1,u1", &
                   "modes cli: modes_harmonics.csv header", first_line(dir//"/modes_harmonics.csv"))
        lines(5) = "&modes amplitude_start = -0.1, amplitude_stop = 10 /"
        call write_lines(dir//".nml", lines)
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "&modes amplitude_start") > 0 .and. &
                   index(err, dir//".nml") > 0, "modes cli: a negative amplitude_start named", err)
        lines(5) = "&modes amplitude_start = 0.1, amplitude_stop = 10, mode = 7 /"
        call write_lines(dir//".nml", lines)
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "&modes mode = 7: no such mode") > 0 .and. &
                   index(err, dir//".nml") > 0, "modes cli: a mode the structure does not "// &
                   "have, named with its file, group and variable", err)
        lines(5) = "! no &modes group"
        call write_lines(dir//".nml", lines)
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 1 .and. index(err, "&modes: missing") > 0, &
                   "modes cli: method 'modes' without &modes", err)
        ! a contact law (a tangential stiffness): its columns, as many fields in every row as
        ! in the header
        lines(2) = "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0, "// &
                   "tangential_stiffness = 50 /"
        lines(5) = "&modes amplitude_start = 0.1, amplitude_stop = 10, points = 11 /"
        call write_lines(dir//".nml", lines)
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 0 .and. index(first_line(dir//"/modes.csv"), &
                                            ",open_1,slip_1,normal_max_1") > 0 .and. &
                   fields_agree(dir//"/modes.csv"), "modes cli, a contact law: its columns, "// &
                   "every row as long as the header", err)
    end subroutine test_cli_modes

    !> Every line of a CSV file has as many comma-separated fields as its header.
    logical function fields_agree(path) result(ok)
        character(len=*), intent(in) :: path
        character(len=4000) :: line
        integer :: u, stat, nh, nrow
        ok = .false.
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        read (u, '(a)', iostat=stat) line
        if (stat /= 0) return
        nh = count_commas(line)
        nrow = 0
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            nrow = nrow + 1
            if (count_commas(line) /= nh) then
                close (u)
                return
            end if
        end do
        close (u)
        ok = nrow > 0
    end function fields_agree
end module test_modes
