!> The forced response of a model's structure in its two friction limits, every contact stuck
!> or slipping freely (the structures of stickslip_linear_modes' limit_structure), harmonic
!> by harmonic: X_h = T (T^T Z_h T)^-1 T^T F_h, Z_h = K_lim - (h omega)^2 M + i h omega C,
!> and its peak over a range of omega. These are the horizontal references of a family of
!> forced-response curves over a normal load or a friction coefficient: the curves' peaks
!> tend to the slipping limit's as the friction limit goes to zero and to the stuck limit's
!> as it grows. The static part (preload) is left out: the amplitudes are those of the
!> vibration. Dense: for the models the weighted residual solves densely. On one sector of
!> a tuned disk (`cyclic`) the limit structure of harmonic h is the sector's on its cyclic
!> motions at that harmonic's inter-sector phase (stickslip_cyclic_limits), complex.
module stickslip_linear_response
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t, force_direction
    use stickslip_linear_modes, only: limit_structure, linear_modes
    use stickslip_cyclic, only: cyclic_t, sector_phase
    use stickslip_cyclic_limits, only: cyclic_limit_structure, cyclic_limit_modes
    use stickslip_lapack, only: zgetrf, zgetrs
    use stickslip_golden, only: golden_search_t
    use stickslip_sorting, only: sort_ascending
    implicit none
    private
    public :: limit_peak_t, linear_limit_peaks

    !> The peak of one observed displacement's linear response over a range.
    type :: limit_peak_t
        !> The amplitude [model length unit] and the omega [rad/s] where it is reached (NaN:
        !> unbounded, an undamped resonance in the range, or no forcing).
        real(dp) :: amplitude = 0.0_dp, omega = 0.0_dp
    end type limit_peak_t

    !> The limit structure of one harmonic: K with the elastic channels' springs (N x N) and a
    !> basis of the motions the rigid channels allow (N x m).
    type :: limit_t
        complex(dp), allocatable :: kk(:, :), t(:, :)
    end type limit_t

    !> Grid of omega values the peak search starts from (beside the limit's natural
    !> frequencies in the range).
    integer, parameter :: grid_points = 240

contains

    !> The peaks over omega in [lo, hi] of the vibration amplitudes of the observed
    !> displacements of `model` (its forcing terms at their amplitudes; its omega is ignored)
    !> with every contact stuck (`stuck`) or slipping, measured as `measure`:
    !> 'half_peak_to_peak' or 'max_abs' (the same without the static part), or
    !> 'first_harmonic'. Observed: the rows of `observe` (nobs x N), or every DOF. A grid of
    !> omega values with the limit's natural frequencies in the range, then a golden-section
    !> search around each DOF's largest value (to 1e-9 of the range). Undamped resonances in
    !> the range give NaN. With `cyclic`, `model` is one sector of that disk under its
    !> engine-order forcing: sector 0's response. Errors: those of limit_structure and
    !> cyclic_limit_structure (stat numerical).
    subroutine linear_limit_peaks(model, stuck, lo, hi, measure, peaks, error, observe, cyclic)
        !> A validated model (dense M, K, C).
        type(model_t), intent(in) :: model
        !> Contacts stuck (.true.) or slipping (.false.).
        logical, intent(in) :: stuck
        !> The range of omega [rad/s], 0 < lo <= hi.
        real(dp), intent(in) :: lo, hi
        !> 'half_peak_to_peak', 'first_harmonic' or 'max_abs'.
        character(len=*), intent(in) :: measure
        !> The peak per observed displacement.
        type(limit_peak_t), allocatable, intent(out) :: peaks(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Observed combinations of DOFs, nobs x N (default: every DOF).
        real(dp), intent(in), optional :: observe(:, :)
        !> The disk of which `model` is a sector.
        type(cyclic_t), intent(in), optional :: cyclic
        real(dp), allocatable :: kk(:, :), t(:, :), grid(:), values(:, :), wn(:), &
                                 shapes(:, :), a(:)
        complex(dp), allocatable :: cshapes(:, :)
        type(limit_t), allocatable :: lim(:)
        integer, allocatable :: hs(:)
        type(error_type), allocatable :: modes_error
        type(golden_search_t) :: search
        integer :: nobs, i, j, k, ng, m
        real(dp) :: x, best, best_x
        ! the limit structure of each forced harmonic (one for all without `cyclic`)
        hs = unique_harmonics(model%force_harmonic)
        allocate (lim(size(hs)))
        do m = 1, size(hs)
            if (present(cyclic)) then
                call cyclic_limit_structure(model, cyclic, phase_factor(hs(m)), stuck, &
                                            lim(m)%kk, lim(m)%t, error)
            else
                if (m == 1) call limit_structure(model, stuck, kk, t, error)
                if (.not. allocated(error)) then
                    lim(m)%kk = cmplx(kk, 0.0_dp, dp)
                    lim(m)%t = cmplx(t, 0.0_dp, dp)
                end if
            end if
            if (allocated(error)) return
        end do
        if (present(observe)) then
            nobs = size(observe, 1)
        else
            nobs = model%ndof
        end if
        allocate (peaks(nobs))
        if (all(model%damping == 0.0_dp) .or. model%nforce() == 0) then
            ! no viscous damping: an undamped resonance in the range has no finite peak
            peaks%amplitude = ieee_value(1.0_dp, ieee_quiet_nan)
            peaks%omega = peaks%amplitude
            return
        end if
        ! the grid and the natural frequencies of the limit inside the range
        grid = [(lo + (hi - lo)*real(j, dp)/real(grid_points - 1, dp), j=0, grid_points - 1)]
        do k = 1, size(model%force_harmonic)
            if (model%force_harmonic(k) < 1) cycle
            if (present(cyclic)) then
                call cyclic_limit_modes(model, cyclic, phase_factor(model%force_harmonic(k)), &
                                        stuck, wn, cshapes, modes_error)
            else if (k == 1 .or. .not. allocated(wn)) then
                call linear_modes(model, stuck, wn, shapes, modes_error)
            end if
            if (allocated(modes_error)) then
                deallocate (modes_error)
                cycle
            end if
            grid = [grid, pack(wn/model%force_harmonic(k), &
                               wn/model%force_harmonic(k) > lo .and. &
                               wn/model%force_harmonic(k) < hi)]
        end do
        call sort_ascending(grid)
        ! one entry per value: a double natural frequency (a disk's pair of waves) must not
        ! leave a search bracket empty on one side
        grid = pack(grid, [.true., grid(2:) - grid(:size(grid) - 1) > 1.0e-12_dp*(hi - lo)])
        ng = size(grid)
        allocate (values(nobs, ng))
        do j = 1, ng
            values(:, j) = response(grid(j))
        end do
        do i = 1, nobs
            if (any(values(i, :) >= huge(1.0_dp))) then
                peaks(i)%amplitude = ieee_value(1.0_dp, ieee_quiet_nan)
                peaks(i)%omega = peaks(i)%amplitude
                cycle
            end if
            k = maxloc(values(i, :), 1)
            best = values(i, k)
            best_x = grid(k)
            if (hi > lo) then
                call search%begin(grid(max(1, k - 1)), grid(min(ng, k + 1)), &
                                  1.0e-9_dp*(hi - lo))
                do while (.not. search%done())
                    x = search%next()
                    a = response(x)
                    call search%tell(a(i))
                    if (a(i) > best) then
                        best = a(i)
                        best_x = x
                    end if
                end do
            end if
            peaks(i)%amplitude = best
            peaks(i)%omega = best_x
        end do

    contains

        !> The measured amplitudes of the observed displacements at `w` (+huge where the
        !> dynamic stiffness is singular).
        function response(w) result(amp)
            real(dp), intent(in) :: w
            real(dp) :: amp(nobs)
            complex(dp), allocatable :: z(:, :), f(:, :), xh(:, :), th(:, :)
            integer, allocatable :: ipiv(:)
            integer :: nf, h, m, info, s, ns
            real(dp), allocatable :: u(:, :)
            real(dp) :: phase
            allocate (xh(nobs, size(hs)))
            do m = 1, size(hs)
                h = hs(m)
                nf = size(lim(m)%t, 2)
                th = conjg(transpose(lim(m)%t))
                z = matmul(th, matmul(lim(m)%kk - cmplx((h*w)**2*model%mass, &
                                                        -h*w*model%damping, dp), lim(m)%t))
                allocate (f(nf, 1), ipiv(nf))
                f(:, 1) = (0.0_dp, 0.0_dp)
                do k = 1, model%nforce()
                    if (model%force_harmonic(k) == h) f(:, 1) = f(:, 1) + &
                        model%force_amplitude(k)*exp(cmplx(0.0_dp, model%force_phase(k), dp))* &
                        matmul(th, force_direction(model, k))
                end do
                call zgetrf(nf, nf, z, nf, ipiv, info)
                if (info /= 0) then
                    amp = huge(1.0_dp)
                    return
                end if
                call zgetrs('N', nf, 1, z, nf, ipiv, f, nf, info)
                if (present(observe)) then
                    xh(:, m) = matmul(observe, matmul(lim(m)%t, f(:, 1)))
                else
                    xh(:, m) = matmul(lim(m)%t, f(:, 1))
                end if
                deallocate (f, ipiv)
            end do
            if (measure == 'first_harmonic') then
                amp = 0.0_dp
                do m = 1, size(hs)
                    if (hs(m) == 1) amp = abs(xh(:, m))
                end do
            else if (size(hs) == 1) then
                amp = abs(xh(:, 1))
            else
                ! several harmonics: sample the period
                ns = max(128, 16*maxval(hs))
                allocate (u(nobs, ns))
                do s = 1, ns
                    phase = two_pi*real(s - 1, dp)/real(ns, dp)
                    u(:, s) = 0.0_dp
                    do m = 1, size(hs)
                        u(:, s) = u(:, s) + real(xh(:, m)*exp(cmplx(0.0_dp, hs(m)*phase, dp)), dp)
                    end do
                end do
                if (measure == 'max_abs') then
                    amp = maxval(abs(u), dim=2)
                else
                    amp = 0.5_dp*(maxval(u, dim=2) - minval(u, dim=2))
                end if
            end if
            where (.not. ieee_is_finite(amp)) amp = huge(1.0_dp)
        end function response

        !> The next sector's phase factor at harmonic h of the engine-order forcing.
        complex(dp) function phase_factor(h)
            integer, intent(in) :: h
            phase_factor = exp(cmplx(0.0_dp, sector_phase(h, cyclic%engine_order, &
                                                          cyclic%sectors, 1), dp))
        end function phase_factor
    end subroutine linear_limit_peaks

    !> The distinct positive harmonics of a forcing, increasing.
    pure function unique_harmonics(h) result(u)
        integer, intent(in) :: h(:)
        integer, allocatable :: u(:)
        integer :: k
        allocate (u(0))
        do k = 1, size(h)
            if (h(k) >= 1 .and. .not. any(u == h(k))) u = [u, h(k)]
        end do
    end function unique_harmonics
end module stickslip_linear_response
