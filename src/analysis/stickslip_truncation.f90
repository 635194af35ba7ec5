!> Harmonic truncation error of a weighted-residual solution: estimated, and controlled by
!> raising the number of harmonics until a requested tolerance is met (issue 4, part 4).
!>
!> Two independent indicators, both relative (dimensionless):
!> - the Coulomb defect: the residual Psi(r(t), v(t)) of the friction law evaluated from the
!>   coefficients on a grid truncation_oversample times finer than the quadrature, each
!>   sample measured in the unit of its region: where Psi says stick, Psi = v is a slip
!>   velocity, divided by the contact's peak slip velocity; where it says slip,
!>   Psi = rho (r -/+ mu N) is rho times a force error, divided by rho mu N (rho only picks
!>   the region, not the size). Its RMS over the period costs no solve. (The max is reported
!>   too, but it is the Gibbs overshoot of r at the stick onsets and does not decrease.)
!> - the change from a coarser harmonic set H_c = H/2 (same samples; the coarse solve is
!>   warm-started from the fine coefficients truncated to the coarse basis, a prefix of the
!>   fine one, so it is cheap): of the displacement history of every DOF,
!>   max_t |x_p(t; H) - x_p(t; H_c)| relative to the amplitude A_p = max_t |x_p(t)| (at least
!>   1e-3 of the largest A_p: a DOF that hardly moves does not make the estimate), and of
!>   the friction dissipation per period relative to the forcing work per period. For an
!>   error decaying like C H^-p this change is (2^p - 1) times the error at H; it also sees
!>   what a residual cannot (an ill-conditioned response). The sup norm, not the change of
!>   A_p itself (also reported), because two maxima can agree by coincidence.
!> estimate = max(Coulomb defect RMS, displacement changes, dissipation change): the two
!> indicators fail differently (the change can be small by coincidence when the errors at H
!> and H/2 agree; the defect decays like 1/H, slower than the displacement error of a
!> well-damped response), so their max is the safe side of both. Measured against the exact
!> reference: within a factor 0.5 to 5 of the true relative error in amplitude and
!> dissipation on the seed case for 5 <= H <= 224 (test_truncation); on the damped 4-DOF
!> chain with two contacts (test_hbm) 1.6 to 2.6 for H <= 112, rising to 13 at H = 300,
!> where the displacement error falls like H^-2 and the defect like H^-1 (conservative).
!>
!> Knows the solution's coefficients and the model; solves only through solve_periodic.
!> Writes nothing: the summary and frc.csv are written by the output modules.
module stickslip_truncation
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp, pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, contact_velocity_direction, force_direction
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_hbm, only: solve_periodic, condensed_structure_t
    use stickslip_dynamics, only: dynamics_t
    use stickslip_contact_set, only: channel_directions
    use stickslip_cyclic, only: cyclic_t, channel_displacements
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic
    use stickslip_contact_element, only: channel_t, kinematics_gap, along_normal, state_stick, &
        state_open
    implicit none
    private
    public :: truncation_t, estimate_truncation, solve_to_tolerance, coarse_harmonics
    public :: truncation_oversample

    !> Fine-grid factor: the Coulomb defect and the amplitudes are evaluated at
    !> truncation_oversample * samples points per period.
    integer, parameter :: truncation_oversample = 4
    !> A DOF's displacement change is relative to its amplitude, at least this share of the
    !> largest amplitude.
    real(dp), parameter :: amplitude_floor = 1.0e-3_dp
    !> Velocity floor of the Coulomb defect, relative to the peak velocity of the structure:
    !> a contact stuck all period (slip velocity ~ solver tolerance) is not divided by ~0;
    !> never below the solve's velocity resolution (hbm_solution_t%velocity_resolution).
    real(dp), parameter :: velocity_floor = 1.0e-4_dp

    !> Truncation error estimate of one solution, and the record of an adaptive solve.
    type :: truncation_t
        !> The solution converged, so `estimate` is defined (otherwise it is huge and `note`
        !> says why).
        logical :: available = .false.
        !> The relative truncation error estimate (dimensionless): the largest of psi_rms,
        !> maxval(displacement_change_rel) and dissipation_change_rel. This is what
        !> solve_to_tolerance compares with the tolerance.
        real(dp) :: estimate = huge(1.0_dp)
        !> Highest harmonic H of the solution estimated.
        integer :: harmonics = 0
        !> Highest harmonic H_c of the coarser set compared with (H/2, at least the highest
        !> forcing harmonic); 0 when no comparison was made (no coarser set holds the
        !> forcing, or the coarse solve did not converge): then the changes below are 0 and
        !> the estimate is the Coulomb defect alone.
        integer :: coarse_harmonics = 0
        !> Quadrature samples per period of the solution (and of the coarse solve).
        integer :: samples = 0
        !> Points per period of the fine grid (truncation_oversample * samples).
        integer :: fine_samples = 0
        !> Coulomb defect, RMS over the fine grid, worst contact (dimensionless): Psi divided
        !> by max(max_t |v_j(t)|, 1e-4 max_p max_t |v_p(t)|) where the contact sticks, by
        !> max(rho mu_j N_j, the same velocity floor) where it slips.
        real(dp) :: psi_rms = 0.0_dp
        !> The same defect, max over the fine grid (dimensionless; O(1) at any H: the Gibbs
        !> overshoot of the friction force; a diagnostic, not part of the estimate).
        real(dp) :: psi_max = 0.0_dp
        !> Amplitude per DOF of the solution, A_p = max_t |x_p(t)| on the fine grid [m].
        real(dp), allocatable :: amplitude(:)
        !> Change of the amplitude per DOF from the coarse set, |A_p(H) - A_p(H_c)| [m].
        real(dp), allocatable :: amplitude_change(:)
        !> amplitude_change / A_p(H) (dimensionless; a DOF whose amplitude is below 1e-12 of
        !> the largest one is measured against 1e-12 times the largest instead).
        real(dp), allocatable :: amplitude_change_rel(:)
        !> Change of the whole displacement history per DOF from the coarse set,
        !> max_t |x_p(t; H) - x_p(t; H_c)| / A_p(H) (same floor; dimensionless). It bounds
        !> amplitude_change_rel and, unlike it, cannot vanish by a coincidence of the two
        !> maxima (a phase shift, another peak): this is the part of the estimate.
        real(dp), allocatable :: displacement_change_rel(:)
        !> Friction dissipation per period of the solution, diss_friction [J].
        real(dp) :: dissipation = 0.0_dp
        !> Change of the friction dissipation per period from the coarse set [J].
        real(dp) :: dissipation_change = 0.0_dp
        !> dissipation_change / E, E the forcing work per period (= friction + viscous
        !> dissipation), floored at 1e-12 pi sum_i |f_i| max_p A_p (dimensionless).
        real(dp) :: dissipation_change_rel = 0.0_dp
        !> Wall-clock seconds spent on this estimate (coarse solve and fine-grid evaluation;
        !> small when solve_to_tolerance reused the previous level as the coarse solution) [s].
        real(dp) :: seconds = 0.0_dp
        !> Tolerance asked of solve_to_tolerance (0 for a plain estimate).
        real(dp) :: tolerance = 0.0_dp
        !> solve_to_tolerance: estimate <= tolerance was reached.
        logical :: met = .false.
        !> solve_to_tolerance: the highest harmonic of each level tried, in order.
        integer, allocatable :: history_harmonics(:)
        !> solve_to_tolerance: the quadrature samples of each level.
        integer, allocatable :: history_samples(:)
        !> solve_to_tolerance: whether each level's solve converged.
        logical, allocatable :: history_converged(:)
        !> solve_to_tolerance: the estimate of each level (huge when not converged).
        real(dp), allocatable :: history_estimate(:)
        !> Empty, or what limited the estimate / why the tolerance was not met.
        character(len=:), allocatable :: note
    end type truncation_t

    !> The fine grid t_j = j T / (m nt), j = 0 .. m nt - 1, of a basis sampled nt times per
    !> period, evaluated without a transform of length m nt: the samples t_k + s T / (m nt)
    !> (s = 0 .. m-1) are those on the basis's own grid of the series advanced by s T/(m nt),
    !> whose coefficients are the harmonics rotated by the phases 2 pi h s / (m nt). The
    !> same values up to roundoff, from the transforms (and cached FFT plans) of length nt.
    type :: fine_grid_t
        !> Oversampling factor m.
        integer :: m = 1
        !> cos and sin of 2 pi h_i s / (m nt), harmonic i of the basis, shift s = 1 .. m-1.
        real(dp), allocatable :: c(:, :), s(:, :)
        !> Rotated coefficients (length nb).
        real(dp), allocatable :: rotated(:)
        !> Transform work array (length nt/2 + 1).
        complex(dp), allocatable :: cw(:)
    contains
        procedure :: synthesize => fine_synthesize
    end type fine_grid_t

contains

    !> The phase tables of the fine grid m times finer than the grid of basis b.
    subroutine new_fine_grid(self, b, m)
        type(fine_grid_t), intent(out) :: self
        type(basis_t), intent(in) :: b
        integer, intent(in) :: m
        integer :: i, sh
        real(dp) :: phi
        self%m = m
        allocate (self%c(b%nharm, m - 1), self%s(b%nharm, m - 1), self%rotated(b%nb), &
                  self%cw(b%nt/2 + 1))
        do sh = 1, m - 1
            do i = 1, b%nharm
                ! the phase reduced mod the period first: h s < m nt, so the angle is exact
                phi = 2.0_dp*pi*real(mod(b%harm(i)*sh, m*b%nt), dp)/real(m*b%nt, dp)
                self%c(i, sh) = cos(phi)
                self%s(i, sh) = sin(phi)
            end do
        end do
    end subroutine new_fine_grid

    !> u(1 : m nt) = the series `coef` of basis b at the fine grid's instants, in the order
    !> of the shifts (u(s nt + k + 1) is the instant t_k + s T/(m nt)): the order does not
    !> matter to the maxima and RMS values taken of it.
    subroutine fine_synthesize(self, b, coef, u)
        class(fine_grid_t), intent(inout) :: self
        type(basis_t), intent(in) :: b
        real(dp), intent(in) :: coef(:)
        real(dp), intent(out) :: u(:)
        integer :: sh, i, k, nt
        nt = b%nt
        call b%synthesize(coef, u(1:nt), self%cw)
        do sh = 1, self%m - 1
            ! u(t + tau) = (a cos phi + b sin phi) cos(h w t) + (b cos phi - a sin phi) sin(h w t)
            if (b%has_zero) self%rotated(b%i0) = coef(b%i0)
            do i = 1, b%nharm
                k = b%icos(i)
                self%rotated(k) = coef(k)*self%c(i, sh) + coef(k + 1)*self%s(i, sh)
                self%rotated(k + 1) = coef(k + 1)*self%c(i, sh) - coef(k)*self%s(i, sh)
            end do
            call b%synthesize(self%rotated, u(sh*nt + 1:(sh + 1)*nt), self%cw)
        end do
    end subroutine fine_synthesize

    !> Highest harmonic of the coarser set used to estimate the truncation error at
    !> `harmonics`: harmonics / 2, raised to the highest forcing harmonic (which every basis
    !> must hold) and to 1 with odd_only. Returns 0 when that set is not smaller.
    pure integer function coarse_harmonics(model, harmonics, odd_only) result(hc)
        !> The model (its forcing harmonics).
        type(model_t), intent(in) :: model
        !> Highest harmonic H of the fine set.
        integer, intent(in) :: harmonics
        !> Odd harmonics only.
        logical, intent(in) :: odd_only
        integer :: hforce
        hforce = 0
        if (model%nforce() > 0) hforce = maxval(model%force_harmonic)
        hc = max(harmonics/2, hforce, merge(1, 0, odd_only))
        if (odd_only) then
            ! the highest odd harmonics <= hc and <= harmonics must differ
            if (hc - mod(hc + 1, 2) >= harmonics - mod(harmonics + 1, 2)) hc = 0
        else if (hc >= harmonics) then
            hc = 0
        end if
    end function coarse_harmonics

    !> Truncation error estimate `est` of the solution `sol` of `model` solved with options
    !> `opts`: the Coulomb defect on a grid truncation_oversample times finer than the
    !> quadrature, and the changes from one coarse solve at coarse_harmonics(H) warm-started
    !> from sol. An unconverged sol (est%available = .false.), no coarser set or an
    !> unconverged coarse solve (est%coarse_harmonics = 0) are outcomes, told in est%note.
    !> Errors: stat input when sol was not solved with opts (harmonics, odd_only, samples)
    !> or holds no coefficients; the errors of solve_periodic on the coarse set.
    !> With `dyn` (the condensed dynamics sol was solved with, e.g. a continuation's), the
    !> coarse solve restricts them instead of factorizing Z_h again. With `observe` (nobs x
    !> ndof), the amplitudes and displacement changes are those of the observed combinations
    !> observe x (e.g. the full-model DOFs of a reduced model, rows of its basis: the
    !> amplitudes of its tiny high-mode coordinates would otherwise decide the estimate),
    !> one per row, instead of one per DOF.
    subroutine estimate_truncation(model, opts, sol, est, error, dyn, observe, cyclic, &
                                   structure)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> The options sol was solved with.
        type(hbm_options_t), intent(in) :: opts
        !> The solution whose truncation error is estimated.
        type(hbm_solution_t), intent(in) :: sol
        !> The estimate.
        type(truncation_t), intent(out) :: est
        !> Set on misuse or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> The condensed dynamics of `model` on the basis of `opts`, already built.
        type(dynamics_t), intent(in), optional :: dyn
        !> Observed combinations of DOFs, nobs x ndof.
        real(dp), intent(in), optional :: observe(:, :)
        !> `model` is one sector of this tuned disk (sol its travelling wave): the channels
        !> against the next sector measure relative motion, the coarse solve is the
        !> sector's.
        type(cyclic_t), intent(in), optional :: cyclic
        !> With `cyclic`: the sector's data set by sol's own solve at this omega
        !> (solve_periodic_cyclic), reused by the coarse solve.
        type(condensed_structure_t), intent(inout), optional :: structure
        type(hbm_options_t) :: copts
        type(hbm_solution_t) :: coarse
        integer(int64) :: c0, c1, rate
        integer :: hc, nbc

        call system_clock(c0, rate)
        call check_match(opts, sol, error)
        if (allocated(error)) return
        call check_observe(model, error, observe)
        if (allocated(error)) return
        call diagnose(model, opts, sol, est, error, observe, cyclic)
        if (allocated(error)) return
        hc = coarse_harmonics(model, sol%harmonics, sol%odd_only)
        if (est%available .and. hc > 0) then
            copts = opts
            copts%harmonics = hc
            copts%rho = sol%rho      ! the same weight as the fine solution
            copts%want_samples = .false.
            nbc = count(sol%harmonic <= hc)
            if (present(cyclic)) then
                call solve_periodic_cyclic(model, cyclic, copts, coarse, error, &
                                           r_start=sol%rcoef(1:nbc, :), dyn=dyn, &
                                           structure=structure)
            else
                call solve_periodic(model, copts, coarse, error, r_start=sol%rcoef(1:nbc, :), &
                                    dyn=dyn)
            end if
            if (allocated(error)) then
                error%message = "truncation estimate, coarse solve at H = "//itoa(hc)// &
                                ": "//error%message
                return
            end if
            call compare_with_coarse(model, sol, coarse, est, error, observe)
            if (allocated(error)) return
        else if (est%available) then
            est%note = "no coarser harmonic set holds the forcing: the estimate is the "// &
                       "Coulomb defect alone"
        end if
        call system_clock(c1)
        est%seconds = real(c1 - c0, dp)/real(rate, dp)
    end subroutine estimate_truncation

    !> Solve `model` with as few harmonics as the tolerance asks: start at opts%harmonics,
    !> estimate the truncation error, and double H (samples raised to the smallest power of
    !> two >= 4 H when opts%samples is fewer), each level warm-started from the one before,
    !> until est%estimate <= tol or H = max_harmonics (the last step is clipped to it).
    !> The previous level is the coarse solution of the estimate when it is exactly
    !> coarse_harmonics(H) with the same samples, so after the first level an estimate costs
    !> no extra solve. Returns the last converged level. Not meeting tol (est%met = .false.)
    !> or a level that does not converge is an outcome told in est%note, not an error;
    !> est%history_* record every level tried. Errors: stat input for tol not in (0, 1) or
    !> max_harmonics < opts%harmonics; the errors of solve_periodic and estimate_truncation.
    subroutine solve_to_tolerance(model, opts, tol, max_harmonics, sol, est, error, observe)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Solver options; opts%harmonics is the first level (small for the fewest harmonics).
        type(hbm_options_t), intent(in) :: opts
        !> Requested relative truncation error, compared with est%estimate.
        real(dp), intent(in) :: tol
        !> Highest harmonic allowed.
        integer, intent(in) :: max_harmonics
        !> The solution of the last converged level (of the first level if none converged).
        type(hbm_solution_t), intent(out) :: sol
        !> Its truncation estimate, the outcome and the history of the levels.
        type(truncation_t), intent(out) :: est
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Observed combinations of DOFs, nobs x ndof (see estimate_truncation).
        real(dp), intent(in), optional :: observe(:, :)
        type(hbm_options_t) :: lopts
        type(hbm_solution_t) :: prev, cur
        type(truncation_t) :: lest
        integer, allocatable :: hist_h(:), hist_s(:)
        logical, allocatable :: hist_c(:)
        real(dp), allocatable :: hist_e(:)
        integer :: h
        logical :: have_prev
        type(dynamics_t) :: dyn
        integer(int64) :: c0, c1, rate
        character(len=200) :: buf

        if (.not. (tol > 0.0_dp .and. tol < 1.0_dp)) then
            write (buf, '(a,g0.6,a)') "tol = ", tol, ": must be in (0, 1)"
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        if (max_harmonics < opts%harmonics) then
            write (buf, '(a,i0,a,i0,a)') "max_harmonics = ", max_harmonics, &
                ": must be >= harmonics = ", opts%harmonics, " (the first level)"
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        call check_observe(model, error, observe)
        if (allocated(error)) return
        allocate (hist_h(0), hist_s(0), hist_c(0), hist_e(0))
        have_prev = .false.
        lopts = opts
        h = opts%harmonics
        do
            lopts%harmonics = h
            lopts%samples = max(opts%samples, power_of_two_at_least(4*h))
            if (have_prev) then
                call solve_periodic(model, lopts, cur, error, r_start=prev%rcoef, dyn_out=dyn)
            else
                call solve_periodic(model, lopts, cur, error, dyn_out=dyn)
            end if
            if (allocated(error)) return
            if (have_prev .and. cur%converged .and. prev%samples == cur%samples .and. &
                prev%harmonics == coarse_harmonics(model, h, opts%odd_only)) then
                call system_clock(c0, rate)
                call diagnose(model, lopts, cur, lest, error, observe)
                if (allocated(error)) return
                call compare_with_coarse(model, cur, prev, lest, error, observe)
                if (allocated(error)) return
                call system_clock(c1)
                lest%seconds = real(c1 - c0, dp)/real(rate, dp)
            else
                call estimate_truncation(model, lopts, cur, lest, error, dyn=dyn, &
                                         observe=observe)
                if (allocated(error)) return
            end if
            hist_h = [hist_h, h]
            hist_s = [hist_s, lopts%samples]
            hist_c = [hist_c, cur%converged]
            hist_e = [hist_e, lest%estimate]
            if (.not. cur%converged) then
                if (have_prev) then
                    sol = prev          ! est still holds the estimate of prev
                    est%note = "the solve at H = "//itoa(h)//" did not converge: the "// &
                               "previous level is returned"
                else
                    sol = cur
                    est = lest
                end if
                exit
            end if
            est = lest
            if (est%estimate <= tol) then
                est%met = .true.
                sol = cur
                exit
            end if
            if (h >= max_harmonics) then
                sol = cur
                write (buf, '(a,es10.2e3,a,i0,a,es10.2e3)') "tolerance ", tol, &
                    " not met at max_harmonics = ", h, ": estimate ", est%estimate
                est%note = trim(buf)
                exit
            end if
            prev = cur
            have_prev = .true.
            h = min(max(2*h, 1), max_harmonics)
        end do
        est%tolerance = tol
        est%history_harmonics = hist_h
        est%history_samples = hist_s
        est%history_converged = hist_c
        est%history_estimate = hist_e
        if (.not. allocated(est%note)) est%note = ""
    end subroutine solve_to_tolerance

    !> The parts of the estimate that need only the solution: sizes, amplitudes and the
    !> Coulomb defect; the estimate is the defect until a coarse comparison is added.
    subroutine diagnose(model, opts, sol, est, error, observe, cyclic)
        type(model_t), intent(in) :: model
        type(hbm_options_t), intent(in) :: opts
        type(hbm_solution_t), intent(in) :: sol
        type(truncation_t), intent(out) :: est
        type(error_type), allocatable, intent(out) :: error
        real(dp), intent(in), optional :: observe(:, :)
        type(cyclic_t), intent(in), optional :: cyclic
        type(basis_t) :: fb
        type(fine_grid_t) :: grid
        real(dp), allocatable :: rt(:), vt(:), pt(:), st(:), vc(:), xt(:)
        real(dp) :: vstruct, vfloor, vslip, limit, rho, vlow
        integer :: nf, j, p, nobs, plow

        est%harmonics = sol%harmonics
        est%samples = sol%samples
        est%fine_samples = truncation_oversample*sol%samples
        est%coarse_harmonics = 0
        est%dissipation = sol%diss_friction
        est%dissipation_change = 0.0_dp
        est%dissipation_change_rel = 0.0_dp
        est%psi_rms = 0.0_dp
        est%psi_max = 0.0_dp
        est%note = ""
        nf = est%fine_samples
        call new_basis(fb, sol%harmonics, sol%odd_only, sol%samples, error)
        if (allocated(error)) return
        call new_fine_grid(grid, fb, truncation_oversample)
        allocate (rt(nf), vt(nf), pt(nf), st(nf), xt(nf), vc(sol%nb))
        nobs = observed_count(model, observe)
        allocate (est%amplitude(nobs), est%amplitude_change(nobs), &
                  est%amplitude_change_rel(nobs), est%displacement_change_rel(nobs))
        est%amplitude_change = 0.0_dp
        est%amplitude_change_rel = 0.0_dp
        est%displacement_change_rel = 0.0_dp
        ! the structure's largest velocity on the fine grid. The fine grid holds the
        ! quadrature's samples (sol%v, when kept): a DOF whose bound sum_h |V_h| does not
        ! exceed the largest of them cannot raise the maximum and is not synthesized
        vlow = 0.0_dp
        plow = 0
        if (allocated(sol%v)) then
            if (size(sol%v, 2) == model%ndof .and. size(sol%v, 1) == sol%samples) then
                plow = maxloc(maxval(abs(sol%v), 1), 1)
                vlow = maxval(abs(sol%v(:, plow)))
            end if
        end if
        vstruct = 0.0_dp
        do p = 1, model%ndof
            if (p /= plow .and. modulus_sum(fb, sol%vcoef(:, p)) <= vlow) cycle
            call grid%synthesize(fb, sol%vcoef(:, p), xt)
            vstruct = max(vstruct, maxval(abs(xt)))
        end do
        do p = 1, nobs
            call grid%synthesize(fb, observed(sol%xcoef, p, observe), xt)
            est%amplitude(p) = maxval(abs(xt))
        end do
        ! below the solve's velocity resolution a channel's motion is roundoff (at rest)
        vfloor = max(velocity_floor*vstruct, sol%velocity_resolution)
        ! the weight the solution was solved with (opts%rho = 0 asks for the automatic one)
        rho = sol%rho
        if (.not. (rho > 0.0_dp)) rho = opts%rho
        if (model%ncontact() > 0) call coulomb_defect(model, sol, fb, grid, rho, vfloor, est, &
                                                      cyclic)
        call fb%destroy()
        est%available = sol%converged
        if (est%available) then
            est%estimate = est%psi_rms
        else
            est%estimate = huge(1.0_dp)
            est%note = "the solution did not converge: no truncation estimate"
        end if
    end subroutine diagnose

    !> The Coulomb defect (doc/contacts.md): every element's Psi on the fine grid, each
    !> channel's kinematic quantity rebuilt from the solution (velocity channels d^T v +
    !> c r', gap channels omega (gap + d^T x + c r), c the compliance); a sample in stick
    !> (or at a closed normal) divided by the channel's peak kinematic quantity, one in slip
    !> (open) by rho times the contact's force scale (its largest normal force when it has a
    !> normal channel); psi_rms and psi_max of `est` set.
    subroutine coulomb_defect(model, sol, fb, grid, rho, vfloor, est, cyclic)
        type(model_t), intent(in) :: model
        type(hbm_solution_t), intent(in) :: sol
        type(basis_t), intent(in) :: fb
        type(fine_grid_t), intent(inout) :: grid
        real(dp), intent(in) :: rho, vfloor
        type(truncation_t), intent(inout) :: est
        !> One sector of a disk: channels against the next sector measure relative motion.
        type(cyclic_t), intent(in), optional :: cyclic
        real(dp), allocatable :: d(:, :), r(:, :), u(:, :), p(:, :), coef(:), dr(:), &
                                 uscale(:), gmax(:), ux(:, :), uv(:, :)
        integer, allocatable :: state(:)
        integer :: j, c, k, m, c0, nf
        real(dp) :: q
        type(channel_t) :: ch
        associate (cs => sol%contacts)
            nf = est%fine_samples
            d = channel_directions(model, cs)
            ! the channels' displacement and velocity coefficients
            if (present(cyclic)) then
                ux = channel_displacements(model, cyclic, cs, sol%harmonic, sol%xcoef)
                uv = channel_displacements(model, cyclic, cs, sol%harmonic, sol%vcoef)
            else
                ux = matmul(sol%xcoef, d)
                uv = matmul(sol%vcoef, d)
            end if
            allocate (r(nf, cs%nchannel), u(nf, cs%nchannel), coef(sol%nb), dr(sol%nb), &
                      uscale(cs%nchannel), gmax(cs%ncontact), state(nf))
            do c = 1, cs%nchannel
                ch = cs%channel(c)
                if (ch%kinematics == kinematics_gap) then
                    coef = model%omega*ux(:, c)
                    if (fb%has_zero) coef(fb%i0) = coef(fb%i0) + model%omega*ch%gap
                    if (ch%compliance > 0.0_dp) coef = coef + model%omega*ch%compliance* &
                                                       sol%rcoef(:, c)
                else
                    coef = uv(:, c)
                    if (ch%compliance > 0.0_dp) then
                        call fb%derivative(sol%rcoef(:, c), model%omega, dr)
                        coef = coef + ch%compliance*dr
                    end if
                end if
                call grid%synthesize(fb, coef, u(:, c))
                call grid%synthesize(fb, sol%rcoef(:, c), r(:, c))
                uscale(c) = max(maxval(abs(u(:, c))), vfloor, tiny(1.0_dp))
            end do
            do j = 1, cs%ncontact
                c0 = cs%first(j)
                m = cs%width(j)
                if (cs%normal(j) > 0) then
                    gmax(j) = max(maxval(r(:, cs%normal(j))), tiny(1.0_dp))
                else
                    gmax(j) = max(cs%elements(j)%e%force_scale(), tiny(1.0_dp))
                end if
                allocate (p(nf, m))
                call cs%elements(j)%e%psi(rho, r(:, c0:c0 + m - 1), u(:, c0:c0 + m - 1), p)
                call cs%elements(j)%e%states(rho, r(:, c0:c0 + m - 1), u(:, c0:c0 + m - 1), &
                                             state)
                do c = 1, m
                    do k = 1, nf
                        if (state(k) == state_stick .or. (cs%along(c0 + c - 1) == along_normal &
                                                          .and. state(k) /= state_open)) then
                            p(k, c) = p(k, c)/uscale(c0 + c - 1)
                        else
                            p(k, c) = p(k, c)/max(rho*gmax(j), vfloor, tiny(1.0_dp))
                        end if
                    end do
                    q = sqrt(sum(p(:, c)**2)/nf)
                    est%psi_rms = max(est%psi_rms, q)
                    est%psi_max = max(est%psi_max, maxval(abs(p(:, c))))
                end do
                deallocate (p)
            end do
        end associate
    end subroutine coulomb_defect

    !> Add to est (already diagnosed for `fine`) the changes from the solution `coarse` on
    !> a prefix basis of fine's, and fold them into the estimate.
    subroutine compare_with_coarse(model, fine, coarse, est, error, observe)
        type(model_t), intent(in) :: model
        type(hbm_solution_t), intent(in) :: fine
        type(hbm_solution_t), intent(in) :: coarse
        type(truncation_t), intent(inout) :: est
        type(error_type), allocatable, intent(out) :: error
        real(dp), intent(in), optional :: observe(:, :)
        type(basis_t) :: fb
        type(fine_grid_t) :: grid
        real(dp), allocatable :: xt(:), xc(:)
        real(dp) :: amax, floor_amp, energy, floor_energy
        integer :: nf, nbc, p, i

        if (.not. coarse%converged) then
            est%note = "the coarse solve at H = "//itoa(coarse%harmonics)//" did not "// &
                       "converge: the estimate is the Coulomb defect alone"
            return
        end if
        nbc = coarse%nb
        if (nbc > fine%nb .or. (coarse%odd_only .neqv. fine%odd_only)) then
            call fatal_error(error, "truncation estimate: the coarse basis is not a prefix "// &
                             "of the fine one", stickslip_stat%internal)
            return
        end if
        est%coarse_harmonics = coarse%harmonics
        nf = est%fine_samples
        call new_basis(fb, fine%harmonics, fine%odd_only, fine%samples, error)
        if (allocated(error)) return
        call new_fine_grid(grid, fb, truncation_oversample)
        allocate (xt(nf), xc(fine%nb))
        amax = maxval(est%amplitude)
        ! a DOF that hardly moves (a contact DOF stuck but for tiny slips, 1e-6 of the
        ! response) is measured against 1e-3 of the largest amplitude, not its own: its
        ! relative change can be large while the response's error is not
        ! and the displacement the solve's velocity resolution allows (a structure at rest)
        floor_amp = max(amplitude_floor*amax, fine%velocity_resolution/model%omega, &
                        tiny(1.0_dp))
        do p = 1, observed_count(model, observe)
            ! the coarse series, embedded in the fine basis, and the difference
            xc = 0.0_dp
            xc(1:nbc) = observed(coarse%xcoef, p, observe)
            call grid%synthesize(fb, xc, xt)
            est%amplitude_change(p) = abs(est%amplitude(p) - maxval(abs(xt)))
            est%amplitude_change_rel(p) = est%amplitude_change(p)/max(est%amplitude(p), floor_amp)
            xc = observed(fine%xcoef, p, observe) - xc
            call grid%synthesize(fb, xc, xt)
            est%displacement_change_rel(p) = maxval(abs(xt))/max(est%amplitude(p), floor_amp)
        end do
        call fb%destroy()

        est%dissipation_change = abs(fine%diss_friction - coarse%diss_friction)
        floor_energy = 0.0_dp
        do i = 1, model%nforce()
            ! |amplitude| x the largest entry of the load shape (1 for a forced DOF)
            floor_energy = floor_energy + abs(model%force_amplitude(i))* &
                           maxval(abs(force_direction(model, i)))
        end do
        floor_energy = 1.0e-12_dp*pi*floor_energy*amax
        energy = max(abs(fine%work_forcing), fine%diss_friction + fine%diss_damping, &
                     floor_energy, fine%work_resolution, tiny(1.0_dp))
        est%dissipation_change_rel = est%dissipation_change/energy
        est%estimate = max(est%psi_rms, maxval(est%displacement_change_rel), &
                           est%dissipation_change_rel)
    end subroutine compare_with_coarse

    !> Error (stat input) unless `observe` (when present) has ndof columns of finite values.
    subroutine check_observe(model, error, observe)
        type(model_t), intent(in) :: model
        type(error_type), allocatable, intent(out) :: error
        real(dp), intent(in), optional :: observe(:, :)
        if (.not. present(observe)) return
        if (size(observe, 2) /= model%ndof .or. size(observe, 1) < 1) then
            call fatal_error(error, "estimate_truncation: observe must be nobs x ndof "// &
                             "(nobs >= 1)", stickslip_stat%input)
        else if (.not. all(abs(observe) <= huge(1.0_dp))) then
            call fatal_error(error, "estimate_truncation: observe: not finite", &
                             stickslip_stat%input)
        end if
    end subroutine check_observe

    !> Number of observed series: the rows of `observe`, or every DOF.
    pure integer function observed_count(model, observe) result(n)
        type(model_t), intent(in) :: model
        real(dp), intent(in), optional :: observe(:, :)
        n = model%ndof
        if (present(observe)) n = size(observe, 1)
    end function observed_count

    !> Coefficients (nb) of observed series p: sum_q observe(p, q) xcoef(:, q), or DOF p.
    pure function observed(xcoef, p, observe) result(c)
        real(dp), intent(in) :: xcoef(:, :)
        integer, intent(in) :: p
        real(dp), intent(in), optional :: observe(:, :)
        real(dp) :: c(size(xcoef, 1))
        if (present(observe)) then
            c = matmul(xcoef, observe(p, :))
        else
            c = xcoef(:, p)
        end if
    end function observed

    !> Error (stat input) unless sol was solved with the basis of opts and holds coefficients.
    subroutine check_match(opts, sol, error)
        type(hbm_options_t), intent(in) :: opts
        type(hbm_solution_t), intent(in) :: sol
        type(error_type), allocatable, intent(out) :: error
        if (.not. (allocated(sol%rcoef) .and. allocated(sol%xcoef) .and. &
                   allocated(sol%vcoef) .and. allocated(sol%harmonic))) then
            call fatal_error(error, "truncation estimate: the solution holds no coefficients", &
                             stickslip_stat%input)
        else if (sol%harmonics /= opts%harmonics .or. (sol%odd_only .neqv. opts%odd_only) &
                 .or. sol%samples /= opts%samples) then
            call fatal_error(error, "truncation estimate: the solution (H = "// &
                             itoa(sol%harmonics)//", samples = "//itoa(sol%samples)// &
                             ") was not solved with these options (H = "// &
                             itoa(opts%harmonics)//", samples = "//itoa(opts%samples)//")", &
                             stickslip_stat%input)
        end if
    end subroutine check_match

    !> Smallest power of two >= n.
    pure integer function power_of_two_at_least(n) result(m)
        integer, intent(in) :: n
        m = 1
        do while (m < n)
            m = 2*m
        end do
    end function power_of_two_at_least

    !> sum_h |c_h| of a real Fourier series on basis b (its constant and each harmonic's
    !> modulus): a bound of |u(t)| at every t.
    pure real(dp) function modulus_sum(b, coef) result(bound)
        type(basis_t), intent(in) :: b
        real(dp), intent(in) :: coef(:)
        integer :: i, k
        bound = 0.0_dp
        if (b%has_zero) bound = abs(coef(b%i0))
        do i = 1, b%nharm
            k = b%icos(i)
            bound = bound + hypot(coef(k), coef(k + 1))
        end do
    end function modulus_sum
end module stickslip_truncation
