!> A forced-response curve: its points (frc_point_t), the curve with the continuation state
!> and how it ended (sweep_result_t), the observer called after every point (a checkpoint
!> writer extends it), and words for why the continuation stopped. Data only: run_sweep
!> (stickslip_sweep) fills them.
module stickslip_sweep_result
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp, two_pi
    use stickslip_diagnostics, only: diagnostics_t
    use stickslip_error, only: error_type
    use stickslip_continuation, only: continuation_state_t, reason_running, reason_end, &
        reason_failures, reason_max_points, reason_left
    implicit none
    private
    public :: frc_point_t, sweep_result_t, sweep_observer_t, reason_text, point_amplitudes
    public :: vibration_samples_t

    !> The basis functions of a harmonic set at the samples of a period, kept between the
    !> points of a curve that share it (point_vibration builds it when the set changes).
    type :: vibration_samples_t
        !> The harmonic of each basis function (frc_point_t%harmonic).
        integer, allocatable :: harmonic(:)
        !> The basis at the samples, samples x basis functions.
        real(dp), allocatable :: basis(:, :)
    end type vibration_samples_t

    !> One point of a forced-response curve.
    type :: frc_point_t
        !> Parameter value.
        real(dp) :: parameter = 0.0_dp
        !> Arclength from the start (parameter units).
        real(dp) :: arclength = 0.0_dp
        !> max_t |x_k(t)| per DOF [m].
        real(dp), allocatable :: amplitude(:)
        !> Energy dissipated per period: friction + viscous, and each [J].
        real(dp) :: dissipation = 0.0_dp, diss_friction = 0.0_dp, diss_damping = 0.0_dp
        !> max_t |r_j(t)| [N] (the friction force: with 2D friction its modulus) and stick
        !> fraction per contact.
        real(dp), allocatable :: rmax(:), stick(:)
        !> With contact laws, per contact: the open fraction and max_t lambda_j(t) [N]
        !> (unallocated for a model without contact laws).
        real(dp), allocatable :: open(:), normal_max(:)
        !> Harmonic count H of the point.
        integer :: harmonics = 0
        !> ||F|| / fscale of the point.
        real(dp) :: residual = 0.0_dp
        !> 'start', 'ok' (corrected in the first try), 'halved' (after step halvings),
        !> 'recovered' (harmonic ladder), 'end' (the end of the range).
        character(len=12) :: status = ''
        !> Corrector evaluations spent on the point.
        integer :: nfev = 0
        !> The worst level of the point's failed checks (0 none, level_warning or
        !> level_untrusted of stickslip_diagnostics) and the key of the first check failed at
        !> that level ('' when none): frc.csv's and modes.csv's trusted and check columns.
        integer :: check_level = 0
        character(len=32) :: check = ''
        !> Largest Floquet multiplier modulus (NaN when not computed).
        real(dp) :: floquet_max = 0.0_dp
        !> 1 stable, 0 unstable, -1 unknown or not computed.
        integer :: stable = -1
        !> Relative harmonic truncation error estimate (NaN when not computed).
        real(dp) :: truncation = 0.0_dp
        !> Fundamental angular frequency of the point [rad/s] (the parameter of a sweep in
        !> omega, the model's omega otherwise).
        real(dp) :: omega = 0.0_dp
        !> The point's Fourier coefficients, one row per basis function (harmonic(k): 0 for
        !> the constant, then cos and sin of each harmonic; u(t) = c0 + sum a_h cos(h omega
        !> t) + b_h sin(h omega t)): of the observed displacements (the columns of
        !> `amplitude`) [m], of every force channel (contact_set_t order: tangential, second
        !> tangential, normal) [N] and of the displacement along each channel's direction
        !> (w_j^T x, t2_j^T x, n_j^T x) [m]. Unallocated in a point read from an old
        !> checkpoint.
        integer, allocatable :: harmonic(:)
        real(dp), allocatable :: xcoef(:, :), rcoef(:, :), ucoef(:, :)
    contains
        procedure :: vibration => point_vibration
    end type frc_point_t

    !> A forced-response curve.
    type :: sweep_result_t
        !> The points, in continuation order (npoints of them are filled).
        type(frc_point_t), allocatable :: points(:)
        integer :: npoints = 0
        !> The continuation state at the end (or at the interruption).
        type(continuation_state_t) :: state
        !> The run resumed from a checkpoint with this many points.
        integer :: resumed_points = 0
        !> Why it stopped, in words; the end of the range is the only complete outcome.
        logical :: complete = .false.
        character(len=:), allocatable :: diagnosis
        !> CPU seconds: all, and the stability part.
        real(dp) :: seconds = 0.0_dp, stability_seconds = 0.0_dp
        !> Turning points passed (sign changes of the parameter's tangent component).
        integer :: folds = 0
        !> The weight rho of the friction equations along the curve (the start's: the
        !> automatic one when &hbm rho = 0) [m/(N s)].
        real(dp) :: rho = 0.0_dp
        !> Factorizations of the dynamic stiffnesses by the continuation of this run (see
        !> friction_family_t%factorizations; the points' own solves reuse them).
        integer :: factorizations = 0
        !> Warnings about the curve ('' when none): undamped_resonance_notes.
        character(len=:), allocatable :: notes
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type sweep_result_t

    !> Called after every point; a checkpoint writer extends it.
    type, abstract :: sweep_observer_t
    contains
        procedure(observe_iface), deferred :: observe
    end type sweep_observer_t

    abstract interface
        !> See the curve so far; an error stops the sweep.
        subroutine observe_iface(self, res, error)
            import :: sweep_observer_t, sweep_result_t, error_type
            !> The observer.
            class(sweep_observer_t), intent(inout) :: self
            !> The curve so far, its last point just added.
            type(sweep_result_t), intent(in) :: res
            !> Set to stop the sweep.
            type(error_type), allocatable, intent(out) :: error
        end subroutine observe_iface
    end interface

contains

    !> The vibration amplitudes of the point's observed displacements (the columns of
    !> `amplitude`), from its Fourier coefficients: half the peak-to-peak, (max_t x - min_t
    !> x) / 2, over max(128, 16 H) samples of the period (a preloaded contact's static offset left out,
    !> which max_t |x| includes), and the modulus sqrt(a_1^2 + b_1^2) of the first harmonic
    !> (0 when the basis has none) [m, the model's length unit]. NaN for a point without
    !> coefficients (read from an old checkpoint). No errors.
    subroutine point_vibration(self, half_range, first, samples)
        !> The point.
        class(frc_point_t), intent(in) :: self
        !> Half the peak-to-peak and the first harmonic's modulus, per observed displacement.
        real(dp), allocatable, intent(out) :: half_range(:), first(:)
        !> The basis at the samples, kept from the last point (rebuilt when this point's
        !> harmonics differ); default: built for this point alone.
        type(vibration_samples_t), intent(inout), optional, target :: samples
        type(vibration_samples_t), target :: own
        type(vibration_samples_t), pointer :: vs
        real(dp), allocatable :: u(:, :)
        integer :: nx, k
        nx = size(self%amplitude)
        allocate (half_range(nx), first(nx))
        if (.not. (allocated(self%harmonic) .and. allocated(self%xcoef))) then
            half_range = ieee_value(1.0_dp, ieee_quiet_nan)
            first = half_range
            return
        end if
        first = 0.0_dp
        do k = 1, size(self%harmonic)
            if (self%harmonic(k) == 1) first = first + self%xcoef(k, :)**2
        end do
        first = sqrt(first)
        vs => own
        if (present(samples)) vs => samples
        if (.not. allocated(vs%harmonic)) then
            call build_samples(self%harmonic, vs)
        else if (size(vs%harmonic) /= size(self%harmonic)) then
            call build_samples(self%harmonic, vs)
        else if (any(vs%harmonic /= self%harmonic)) then
            call build_samples(self%harmonic, vs)
        end if
        u = matmul(vs%basis, self%xcoef)
        half_range = 0.5_dp*(maxval(u, dim=1) - minval(u, dim=1))
    end subroutine point_vibration

    !> The basis of the harmonic set `harmonic` (each harmonic's first row its cosine, the
    !> second its sine) at max(128, 16 H) samples of the period: 16 a period of the highest
    !> harmonic, the first's peak to 1e-3 or better. exp(i h phase) by powers of
    !> exp(i phase), one sin and one cos per sample.
    subroutine build_samples(harmonic, vs)
        integer, intent(in) :: harmonic(:)
        type(vibration_samples_t), intent(inout) :: vs
        complex(dp), allocatable :: e(:)
        logical, allocatable :: sine(:)
        real(dp) :: phase
        integer :: nrow, ns, j, k, hmax
        nrow = size(harmonic)
        allocate (sine(nrow))
        do k = 1, nrow
            sine(k) = harmonic(k) > 0 .and. count(harmonic(1:k - 1) == harmonic(k)) == 1
        end do
        hmax = 1
        if (nrow > 0) hmax = max(1, maxval(harmonic))
        ns = max(128, 16*hmax)
        vs%harmonic = harmonic
        if (allocated(vs%basis)) deallocate (vs%basis)
        allocate (vs%basis(ns, nrow), e(0:hmax))
        do j = 1, ns
            phase = two_pi*real(j - 1, dp)/real(ns, dp)
            e(0) = (1.0_dp, 0.0_dp)
            e(1) = cmplx(cos(phase), sin(phase), dp)
            do k = 2, hmax
                e(k) = e(k - 1)*e(1)
            end do
            do k = 1, nrow
                if (harmonic(k) == 0) then
                    vs%basis(j, k) = 1.0_dp
                else if (sine(k)) then
                    vs%basis(j, k) = aimag(e(harmonic(k)))
                else
                    vs%basis(j, k) = real(e(harmonic(k)), dp)
                end if
            end do
        end do
    end subroutine build_samples

    !> The amplitudes of a point's observed displacements as `measure` asks:
    !> 'half_peak_to_peak' (the vibration amplitude, (max_t x - min_t x) / 2),
    !> 'first_harmonic' (the first harmonic's modulus) or 'max_abs' (max_t |x|, the static
    !> offset included) [model length unit]. No errors (NaN for a point without
    !> coefficients and a measure that needs them).
    function point_amplitudes(pt, measure, samples) result(a)
        !> The point.
        type(frc_point_t), intent(in) :: pt
        !> The measure.
        character(len=*), intent(in) :: measure
        !> The basis at the samples, kept between points (see point_vibration).
        type(vibration_samples_t), intent(inout), optional :: samples
        real(dp), allocatable :: a(:)
        real(dp), allocatable :: half_range(:), first(:)
        if (measure == 'max_abs') then
            a = pt%amplitude
            return
        end if
        call pt%vibration(half_range, first, samples)
        if (measure == 'first_harmonic') then
            a = first
        else
            a = half_range
        end if
    end function point_amplitudes

    !> Words for a continuation_state_t%reason.
    pure function reason_text(reason) result(text)
        !> reason_* of stickslip_continuation.
        integer, intent(in) :: reason
        character(len=:), allocatable :: text
        select case (reason)
        case (reason_running)
            text = "interrupted"
        case (reason_end)
            text = "reached the end of the range"
        case (reason_failures)
            text = "stopped after failed points"
        case (reason_max_points)
            text = "stopped at max_points before the end of the range"
        case (reason_left)
            text = "the branch left the range"
        case default
            text = "unknown"
        end select
    end function reason_text
end module stickslip_sweep_result
