!> How small perturbations of an exact periodic orbit grow under the exact flow itself, not
!> under its linearization: the check of a Floquet verdict where the flow map is only
!> piecewise smooth.
!>
!> Where events of several contacts fall at one instant (sectors of a disk in phase:
!> orbit_t%simultaneous), a perturbation decides their order, and the period map has one
!> Jacobian per order (they differ by terms of rank one; measured on the damper disk: 1 to
!> 5 % of the response to a random perturbation, whatever its size from 1e-5 to 1e-9). The
!> monodromy of the orbit is the Jacobian of the order the flow took. The flow map is
!> continuous and positively homogeneous to first order, so a perturbation of 1e-7 of the
!> orbit's amplitude, followed by the flow and renormalized after each map (a power
!> iteration of the map itself), grows by the factor that decides the stability, whichever
!> orders the perturbations take. A complex multiplier's direction is followed as its two
!> real parts together (the real and imaginary part of the eigenvector, one flow each):
!> the norm of the complex perturbation grows by |mu| a period where the norm of either part
!> alone oscillates with its argument.
!> Knows nothing of files; never prints.
module stickslip_orbit_growth
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_reference, only: reference_result_t
    use stickslip_wave_symmetry, only: shifted
    implicit none
    private
    public :: orbit_growth_t, orbit_growth

    !> Relative size of the perturbation, root mean square over the states (of the orbit's
    !> amplitudes of x and v): far above the roundoff of a period map (~1e-12) and far
    !> below the size where the flow stops being homogeneous (the damper disk's growth is
    !> the same from 1e-5 to 1e-9).
    real(dp), parameter :: growth_eps = 1.0e-7_dp

    !> What following perturbations of the orbit found.
    type :: orbit_growth_t
        !> Growth of a perturbation per period (geometric mean over the periods measured,
        !> after those to settle); -1 when not measured.
        real(dp) :: rate = -1.0_dp
        !> Periods measured (after the settling ones), and maps of the flow evaluated.
        integer :: periods = 0, maps = 0
        !> CPU seconds.
        real(dp) :: seconds = 0.0_dp
    end type orbit_growth_t

contains

    !> Follow a perturbation of the converged exact orbit `res` (its state at t_section,
    !> the map it is a fixed point of: reference_result_t%spans) with the exact flow for
    !> `settle` + `periods` periods: after each map the perturbation is measured (x, v and internal
    !> states each relative to their amplitude over the orbit; the 2-norm of both columns
    !> together) and scaled back to growth_eps times sqrt(n_z); g%rate is the growth per period over the
    !> last `periods` of them. `start` (n_z x 1, or n_z x 2: the real and imaginary parts
    !> of a complex direction, e.g. the monodromy's dominant eigenvector) is the first
    !> perturbation. res%flow's mode cache grows. Errors: stat input (no converged orbit,
    !> start of the wrong size or zero, periods < 1, settle < 0); stat numerical (the flow
    !> failed, the perturbation became non-finite).
    subroutine orbit_growth(res, start, periods, settle, g, error)
        !> A converged exact orbit (solve_reference), its flow and orbit recorded.
        type(reference_result_t), intent(inout) :: res
        !> Direction of the first perturbation, n_z x 1 or n_z x 2 (n_z = 2 N + n_s).
        real(dp), intent(in) :: start(:, :)
        !> Periods measured, and periods followed before them (to settle).
        integer, intent(in) :: periods, settle
        !> The growth per period.
        type(orbit_growth_t), intent(out) :: g
        !> Set as described.
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: zs(:), zb(:), z1(:), d(:, :), sc(:)
        real(dp) :: c0, ampx, ampv, logsum, size1, eps
        integer :: n, nz, k, kmax, kmeasure, col

        c0 = thread_cpu_seconds()
        if (.not. res%converged .or. res%orbit%nphase < 1 .or. .not. allocated(res%x)) then
            call fatal_error(error, "orbit_growth: no converged exact orbit", &
                             stickslip_stat%input)
            return
        end if
        n = res%flow%n
        nz = res%flow%nz
        if (size(start, 1) /= nz .or. size(start, 2) < 1 .or. size(start, 2) > 2 .or. &
            periods < 1 .or. settle < 0) then
            call fatal_error(error, "orbit_growth: the start must have "//itoa(nz)// &
                             " rows and 1 or 2 columns, periods be >= 1 and settle >= 0", &
                             stickslip_stat%input)
            return
        end if
        ampx = max(maxval(abs(res%x)), tiny(1.0_dp))
        ampv = max(maxval(abs(res%v)), tiny(1.0_dp))
        allocate (sc(nz), z1(nz))
        sc(1:n) = ampx
        sc(n + 1:2*n) = ampv
        sc(2*n + 1:) = ampx
        d = start
        if (.not. (measure(d) > 0.0_dp)) then
            call fatal_error(error, "orbit_growth: the start is zero or not finite", &
                             stickslip_stat%input)
            return
        end if
        d = d/measure(d)
        ! the orbit's state at its section, and its image (the fixed point to roundoff: the
        ! image is the reference the perturbed images are measured from)
        zs = res%orbit%phase_y(1:nz, 1)
        call span_map(zs, zb)
        if (allocated(error)) return
        eps = growth_eps*sqrt(real(nz, dp))
        kmeasure = periods*res%spans
        kmax = kmeasure + settle*res%spans
        logsum = 0.0_dp
        do k = 1, kmax
            do col = 1, size(d, 2)
                call span_map(zs + eps*d(:, col), z1)
                if (allocated(error)) return
                d(:, col) = (z1 - zb)/eps
            end do
            size1 = measure(d)
            if (.not. (size1 < huge(1.0_dp))) then
                call fatal_error(error, "orbit_growth: the perturbation is not finite after "// &
                                 itoa(k)//" maps", stickslip_stat%numerical)
                return
            end if
            if (size1 == 0.0_dp) then
                ! projected out (stick phases remove it): no growth at all
                logsum = -huge(1.0_dp)
                exit
            end if
            if (k > kmax - kmeasure) logsum = logsum + log(size1)
            d = d/size1
        end do
        g%periods = periods
        g%maps = min(k, kmax)*size(d, 2) + 1
        if (logsum == -huge(1.0_dp)) then
            g%rate = 0.0_dp
        else
            g%rate = exp(logsum/real(periods, dp))
        end if
        g%seconds = thread_cpu_seconds() - c0

    contains

        !> The perturbation's size: the 2-norm of its entries over their scales.
        real(dp) function measure(v)
            real(dp), intent(in) :: v(:, :)
            measure = norm2(v/spread(sc, 2, size(v, 2)))
            if (.not. ieee_is_finite(measure)) measure = huge(1.0_dp)
        end function measure

        !> The map the orbit is a fixed point of: the flow over T / spans, then the shift
        !> back by span_shift sectors.
        subroutine span_map(za, zo)
            real(dp), intent(in) :: za(:)
            real(dp), allocatable, intent(out) :: zo(:)
            integer :: nx, nsx
            allocate (zo(nz))
            call res%flow%period_map(res%t_section, za, zo, error, &
                                     duration=res%flow%period/res%spans)
            if (allocated(error)) then
                error%message = "orbit_growth: "//error%message
                return
            end if
            if (res%spans <= 1) return
            nx = n
            nsx = nz - 2*n
            zo(1:nx) = shifted(zo(1:nx), res%sectors, -res%span_shift)
            zo(nx + 1:2*nx) = shifted(zo(nx + 1:2*nx), res%sectors, -res%span_shift)
            if (nsx > 0) zo(2*nx + 1:) = shifted(zo(2*nx + 1:), res%sectors, -res%span_shift)
        end subroutine span_map
    end subroutine orbit_growth
end module stickslip_orbit_growth
