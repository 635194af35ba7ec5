!> What follows a weighted-residual solve once its friction-force coefficients are found:
!> settling an undetermined mean force, recovery of every DOF, the energy balance over one
!> period, stick statistics and samples (finish_solution), and the checks of the answer as
!> diagnostics with their thresholds (check_solution). Knows nothing of how the coefficients
!> were found (stickslip_hbm_strategy); called by solve_condensed (stickslip_hbm).
module stickslip_hbm_finish
    use stickslip_kinds, only: dp, two_pi
    use stickslip_diagnostics, only: level_warning, level_untrusted
    use stickslip_model, only: model_t, contact_velocity_direction
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t
    use stickslip_dynamics, only: near_singular_threshold
    use stickslip_condensed_structure, only: condensed_structure_t, rho_ratio, &
        rho_out_of_band, rho_ratio_min, rho_ratio_max
    use stickslip_contact_set, only: channel_directions
    use stickslip_contact_law, only: state_stick
    use stickslip_hbm_finish_laws, only: laws_samples_settled, laws_fractions, laws_coulomb, &
        laws_normal
    implicit none
    private
    public :: finish_solution, check_solution

    !> Thresholds of the checks of a solution (check_solution; doc/where-methods-fail.md, "Where each method
    !> fails"). Energy balance error: exact for the truncated series up to roundoff.
    real(dp), parameter, public :: energy_warning = 1.0e-6_dp, energy_untrusted = 1.0e-2_dp
    !> |friction - Coulomb dissipation| / (the larger of Coulomb's and the whole dissipation
    !> per period): ~1% on the examples (the truncated force is not exactly -mu N sign(v)
    !> near the events).
    real(dp), parameter, public :: dissipation_warning = 0.1_dp, dissipation_untrusted = 0.5_dp
    !> max |r| / mu N - 1: the Gibbs overshoot of the truncated force at the stick-slip
    !> events is 2.6-5% on the seed case (stickslip_rho), up to 9% of a jump of 2 mu N
    !> (18%) at a reversal; 20% is reached on the damped 4-DOF chain at omega = 0.27.
    real(dp), parameter, public :: force_excess_warning = 0.5_dp, force_excess_untrusted = 1.0_dp
    !> The normal law of unilateral contacts (sol%signorini_check): a pulling normal force
    !> or a penetration beyond the Gibbs ripple of the truncated series.
    real(dp), parameter, public :: signorini_warning = 0.2_dp, signorini_untrusted = 0.5_dp
    !> A rigid unilateral contact closing with this share of its normal velocity amplitude
    !> (sol%impact_check) is an impact.
    real(dp), parameter, public :: impact_warning = 0.05_dp

contains

    !> Settle undetermined mean forces, recover every DOF, energies, stick statistics and
    !> samples.
    subroutine finish_solution(s, opts, prob, y, sol, model)
        !> The structure's data (omega, forcing).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options as given (harmonics, want_samples).
        type(hbm_options_t), intent(in) :: opts
        !> The projected friction equations the solve used.
        type(hb_problem_t), intent(inout) :: prob
        !> Friction-force coefficients [N] found; an undetermined mean force is settled.
        real(dp), intent(inout) :: y(:)
        !> The solution: recovery, energies, stick statistics and samples filled in.
        type(hbm_solution_t), intent(inout) :: sol
        !> The dense model (dense path only: W^T v and its C for the energies).
        type(model_t), intent(in), optional :: model
        real(dp), allocatable :: rs(:, :), vs(:, :), ss(:, :), fcoef(:, :), vc(:, :), work(:)
        real(dp), allocatable :: dirs(:, :), ucoef(:, :)
        integer, allocatable :: state(:, :)
        complex(dp), allocatable :: cw(:)
        integer :: nb, nc, nt, n, j, i, k, p, q, i0, ncontact
        real(dp) :: period, lo, hi, shift, coulomb_slip, max_force_ratio

        max_force_ratio = 0.0_dp
        nb = prob%basis%nb
        nc = prob%nc
        nt = prob%basis%nt
        n = size(prob%dyn%x0, 1)
        i0 = prob%basis%i0
        period = two_pi/s%omega
        ! contacts (nc counts the force channels of contact laws)
        ncontact = s%ncontact
        sol%contacts = s%contacts
        allocate (rs(nt, nc), vs(nt, nc), ss(nt, ncontact), sol%offset_undetermined(ncontact), &
                  state(nt, ncontact))
        sol%offset_undetermined = .false.
        if (.not. prob%plain) then
            ! the force channels, their kinematic quantities and the contact states
            call laws_samples_settled(prob, y, rs, vs, state, sol%offset_undetermined)
            ss = merge(1.0_dp, 0.0_dp, state == state_stick)
        else if (nc > 0) then
            call prob%contact_samples(y, rs, vs, ss)
            state = merge(1, 2, ss > 0.5_dp)
        end if

        ! A contact stuck over the whole period holds any mean force in an interval:
        ! choose the admissible value closest to zero (minimum norm), never an arbitrary one.
        if (prob%basis%has_zero .and. prob%plain) then
            do j = 1, nc
                if (all(ss(:, j) > 0.5_dp)) then
                    sol%offset_undetermined(j) = .true.
                    k = (j - 1)*nb + i0
                    lo = -prob%limit(j) - minval(rs(:, j) - y(k))
                    hi = prob%limit(j) - maxval(rs(:, j) - y(k))
                    shift = min(max(0.0_dp, lo), hi) - y(k)
                    y(k) = y(k) + shift
                    rs(:, j) = rs(:, j) + shift
                end if
            end do
        end if

        sol%rcoef = reshape(y, [nb, nc])
        allocate (sol%xcoef(nb, n), sol%vcoef(nb, n))
        call prob%dyn%displacement(prob%basis, sol%rcoef, sol%xcoef)
        do p = 1, n
            call prob%basis%derivative(sol%xcoef(:, p), s%omega, sol%vcoef(:, p))
        end do

        allocate (sol%stick_fraction(ncontact), sol%stick_phases(ncontact), &
                  sol%open_fraction(ncontact), sol%slip_fraction(ncontact))
        do j = 1, ncontact
            sol%stick_fraction(j) = sum(ss(:, j))/real(nt, dp)
            sol%stick_phases(j) = count_phases(ss(:, j) > 0.5_dp, &
                                               max(1, nt/max(1, opts%harmonics)))
        end do
        if (prob%plain) then
            sol%open_fraction = 0.0_dp
            sol%slip_fraction = 1.0_dp - sol%stick_fraction
        else
            call laws_fractions(state, sol%open_fraction, sol%stick_fraction, &
                                sol%slip_fraction)
        end if

        ! energy balance over one period, exact for the truncated series (Parseval)
        allocate (fcoef(nb, n), vc(nb, nc))
        fcoef = 0.0_dp
        do i = 1, size(s%force_harmonic)
            if (s%force_harmonic(i) == 0) then
                fcoef(i0, :) = fcoef(i0, :) + s%force_amplitude(i)*cos(s%force_phase(i))* &
                               s%force_rows(:, i)
            else
                k = prob%basis%icos(findloc(prob%basis%harm, s%force_harmonic(i), 1))
                fcoef(k, :) = fcoef(k, :) + s%force_amplitude(i)*cos(s%force_phase(i))* &
                              s%force_rows(:, i)
                fcoef(k + 1, :) = fcoef(k + 1, :) - s%force_amplitude(i)*sin(s%force_phase(i))* &
                                  s%force_rows(:, i)
            end if
        end do
        if (present(model) .and. .not. prob%plain) then
            ! the velocities along the channel directions (the normal channels' too)
            dirs = channel_directions(model, s%contacts)
            vc = matmul(sol%vcoef, dirs)
        else if (present(model)) then
            do j = 1, nc
                vc(:, j) = matmul(sol%vcoef, contact_velocity_direction(model, j))
            end do
        else if (nc > 0) then
            call prob%dyn%contact_velocity(prob%basis, sol%rcoef, vc)
        end if
        sol%work_forcing = 0.0_dp
        if (present(model)) then
            do p = 1, n
                sol%work_forcing = sol%work_forcing + inner(fcoef(:, p), sol%vcoef(:, p))
            end do
        else
            sol%work_forcing = gram_energy(.true.)
        end if
        ! the gross work, integral |f . v| dt: the scale of the energy balance
        block
            real(dp) :: fs(nt), vt(nt), pw(nt)
            complex(dp) :: cwork(nt/2 + 1)
            pw = 0.0_dp
            do p = 1, n
                if (all(fcoef(:, p) == 0.0_dp)) cycle
                call prob%basis%synthesize(fcoef(:, p), fs, cwork)
                call prob%basis%synthesize(sol%vcoef(:, p), vt, cwork)
                pw = pw + fs*vt
            end do
            sol%work_gross = period*sum(abs(pw))/nt
        end block
        sol%diss_friction = 0.0_dp
        sol%diss_coulomb = 0.0_dp
        coulomb_slip = 0.0_dp
        if (.not. prob%plain) then
            ! every channel's work (the normal forces' is zero over a period for an exact
            ! solution); Coulomb's with the varying limit and the slider velocities
            do j = 1, nc
                sol%diss_friction = sol%diss_friction - inner(sol%rcoef(:, j), vc(:, j))
            end do
            call laws_coulomb(s%contacts, rs, vs, state, period, sol%diss_coulomb, &
                              coulomb_slip, max_force_ratio)
        end if
        do j = 1, merge(nc, 0, prob%plain)
            sol%diss_friction = sol%diss_friction - inner(sol%rcoef(:, j), vc(:, j))
            sol%diss_coulomb = sol%diss_coulomb + prob%limit(j)*period*sum(abs(vs(:, j)))/nt
            ! what Coulomb's law dissipates: mu N |v| where the contact slips, |r v| (<= mu
            ! N |v|, ~0) where it sticks (a stuck contact's roundoff slip times a huge mu N
            ! is no dissipation)
            coulomb_slip = coulomb_slip + period*sum(merge(abs(rs(:, j)*vs(:, j)), &
                prob%limit(j)*abs(vs(:, j)), ss(:, j) > 0.5_dp))/nt
            if (prob%limit(j) > 0.0_dp) max_force_ratio = max(max_force_ratio, &
                                                              maxval(abs(rs(:, j)))/prob%limit(j))
        end do
        sol%diss_damping = 0.0_dp
        if (present(model)) then
            do q = 1, n
                do p = 1, n
                    sol%diss_damping = sol%diss_damping + &
                        model%damping(p, q)*inner(sol%vcoef(:, p), sol%vcoef(:, q))
                end do
            end do
        else
            sol%diss_damping = gram_energy(.false.)
        end if

        sol%coulomb_check = abs(coulomb_slip - sol%diss_friction)/ &
                            max(coulomb_slip, abs(sol%diss_friction) + abs(sol%diss_damping), &
                                1.0e-6_dp*sol%work_gross, tiny(1.0_dp))
        sol%max_force_ratio = max_force_ratio

        if (opts%want_samples) then
            allocate (sol%t(nt), sol%x(nt, n), sol%v(nt, n), work(nt), cw(nt/2 + 1))
            sol%t = [(period*real(k, dp)/real(nt, dp), k=0, nt - 1)]
            do p = 1, n
                call prob%basis%synthesize(sol%xcoef(:, p), sol%x(:, p), cw)
                call prob%basis%synthesize(sol%vcoef(:, p), sol%v(:, p), cw)
            end do
            sol%r = rs
            sol%stick = ss
            sol%state = state
        end if
        ! normal forces, gaps and the checks of the normal law
        allocate (sol%normal(nt, ncontact), sol%gap(nt, ncontact))
        if (prob%plain) then
            do j = 1, ncontact
                sol%normal(:, j) = s%contacts%normal_load(j)
            end do
            sol%gap = 0.0_dp
        else
            allocate (ucoef(nb, nc))
            call prob%laws%kinematics(prob%basis, prob%dyn, sol%rcoef, ucoef)
            call laws_normal(prob, rs, vs, state, ucoef, sol%normal, sol%gap, &
                             sol%signorini_check, sol%impact_check)
        end if

    contains

        !> Energy per period from the Gram matrices of a sparse condensation, with
        !> u_h = [1; R_h] (R_h = r_cos - i r_sin of each contact): the forcing work
        !> (`forcing`; q_h = forcing_gram) sum_h (T/2) Re(i h omega q_h u_h), or the viscous
        !> dissipation (P_h = damping_gram) sum_h (T/2) (h omega)^2 u_h^H P_h u_h.
        real(dp) function gram_energy(forcing) result(e)
            logical, intent(in) :: forcing
            complex(dp) :: u(nc + 1)
            real(dp) :: homega
            integer :: ih, kk
            e = 0.0_dp
            do ih = 1, prob%basis%nharm
                kk = prob%basis%icos(ih)
                homega = prob%basis%harm(ih)*s%omega
                u(1) = (1.0_dp, 0.0_dp)
                u(2:) = cmplx(sol%rcoef(kk, :), -sol%rcoef(kk + 1, :), dp)
                if (forcing) then
                    e = e + 0.5_dp*period*homega* &
                        real((0.0_dp, 1.0_dp)*sum(prob%dyn%forcing_gram(:, ih)*u), dp)
                else
                    e = e + 0.5_dp*period*homega**2* &
                        real(dot_product(u, matmul(prob%dyn%damping_gram(:, :, ih), u)), dp)
                end if
            end do
        end function gram_energy

        !> integral over one period of the product of two functions given by coefficients
        pure real(dp) function inner(a, b)
            real(dp), intent(in) :: a(:), b(:)
            inner = 0.5_dp*period*dot_product(a, b)
            if (i0 > 0) inner = inner + 0.5_dp*period*a(i0)*b(i0)
        end function inner
    end subroutine finish_solution

    !> The checks of a solution as diagnostics items (doc/where-methods-fail.md):
    !> not_converged; rho_out_of_range (rho / contact mobility outside [rho_ratio_min,
    !> rho_ratio_max]: the friction equality loses its digits); near_resonance (Z_h nearly
    !> singular); and, once converged, energy_balance, coulomb_dissipation and coulomb_law.
    subroutine check_solution(s, opts, prob, sol)
        !> The structure's data (omega, automatic rho).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options in effect (rho > 0).
        type(hbm_options_t), intent(in) :: opts
        !> The projected friction equations the solve used (its dynamics' conditioning).
        type(hb_problem_t), intent(in) :: prob
        !> The finished solution; its checks go to sol%diagnostics.
        type(hbm_solution_t), intent(inout) :: sol
        real(dp) :: e
        character(len=400) :: buf
        if (.not. sol%converged) &
            call sol%diagnostics%add(level_untrusted, "not_converged", sol%diagnosis)
        if (prob%nc > 0 .and. rho_out_of_band(s, opts%rho)) then
            write (buf, '(a,es10.2e3,a,es10.2e3,a,es9.1e3,a,es9.1e3,a)') "rho = ", opts%rho, &
                " is ", rho_ratio(s, opts%rho), " times the contact mobility (outside ", &
                rho_ratio_min, " .. ", rho_ratio_max, "): the friction equality cannot "// &
                "resolve the forces; use &hbm rho = 0 (automatic)"
            call sol%diagnostics%add(level_untrusted, "rho_out_of_range", trim(buf))
        end if
        if (prob%dyn%relative_conditioning < near_singular_threshold) then
            write (buf, '(a,i0,a,g0.6,a,es10.2e3,a,es9.1e3,a)') "near an undamped resonance at "// &
                "harmonic h = ", prob%dyn%worst_harmonic, " (h omega = ", &
                prob%dyn%worst_harmonic*s%omega, " rad/s): the dynamic stiffness is "// &
                "nearly singular (relative conditioning ", prob%dyn%relative_conditioning, &
                " < ", near_singular_threshold, "), the response hangs on the last digits "// &
                "of omega, M and K; add damping or move omega"
            call sol%diagnostics%add(level_untrusted, "near_resonance", trim(buf))
        end if
        if (.not. sol%converged .or. prob%nc == 0) return
        e = abs(sol%work_forcing - sol%diss_friction - sol%diss_damping)/ &
            max(abs(sol%work_forcing), 1.0e-6_dp*sol%work_gross, tiny(1.0_dp))
        call graded("energy_balance", e, energy_warning, energy_untrusted, &
                    "energy balance error (forcing work - friction - viscous dissipation, "// &
                    "relative to the work per period)")
        call graded("coulomb_dissipation", sol%coulomb_check, dissipation_warning, &
                    dissipation_untrusted, "friction dissipation differs from Coulomb's "// &
                    "(mu N |v| where the contacts slip), relative difference")
        call graded("coulomb_law", sol%max_force_ratio - 1.0_dp, force_excess_warning, &
                    force_excess_untrusted, "friction force exceeds mu N (max |r| / mu N "// &
                    "- 1, beyond the Gibbs overshoot of a truncated series)")
        if (prob%plain) return
        call graded("signorini", sol%signorini_check, signorini_warning, signorini_untrusted, &
                    "the normal contact law is broken beyond the ripple of a truncated "// &
                    "series (a pulling normal force relative to the largest one, or a "// &
                    "penetration relative to the normal displacement amplitude)")
        if (sol%impact_check > impact_warning) then
            write (buf, '(a,es10.2e3,a)') "weighted residual: a rigid unilateral contact "// &
                "closes with a normal velocity (", sol%impact_check, " of its normal "// &
                "velocity amplitude): an impact, whose velocity jump a truncated Fourier "// &
                "series cannot carry; give the contact a normal_stiffness (the measured "// &
                "contact stiffness), or check the answer against &run method = 'euler'"
            call sol%diagnostics%add(level_warning, "impact", trim(buf))
        end if

    contains

        subroutine graded(key, value, warn, untrusted, what)
            character(len=*), intent(in) :: key, what
            real(dp), intent(in) :: value, warn, untrusted
            character(len=300) :: text
            if (.not. (value <= untrusted)) then
                write (text, '(a,es10.2e3,a,es10.2e3)') "weighted residual: "//what//" ", value, &
                    " > ", untrusted
                call sol%diagnostics%add(level_untrusted, key, trim(text))
            else if (value > warn) then
                write (text, '(a,es10.2e3,a,es10.2e3)') "weighted residual: "//what//" ", value, &
                    " > ", warn
                call sol%diagnostics%add(level_warning, key, trim(text))
            end if
        end subroutine graded
    end subroutine check_solution

    !> Number of stick phases in one period of the cyclic stick indicator `stick`, counted at
    !> the resolution of the basis: slip gaps and stick phases shorter than `minlen` samples
    !> (one period of the highest harmonic) are ripples of the truncated series around the
    !> friction limit, not phases: gaps are closed, then short phases are not counted.
    pure integer function count_phases(stick, minlen) result(phases)
        !> Stick indicator at the samples.
        logical, intent(in) :: stick(:)
        !> Shortest run, in samples, the basis can resolve.
        integer, intent(in) :: minlen
        logical :: s(size(stick))
        integer :: nt, k, first, len
        nt = size(stick)
        phases = 0
        if (all(stick)) phases = 1
        if (all(stick) .or. .not. any(stick)) return
        first = 1
        do k = 1, nt
            if (stick(k) .neqv. stick(modulo(k - 2, nt) + 1)) then
                first = k
                exit
            end if
        end do
        s = cshift(stick, first - 1)
        ! close short slip gaps
        k = 1
        do while (k <= nt)
            len = run_length(k)
            if (.not. s(k) .and. len < minlen) s(k:k + len - 1) = .true.
            k = k + len
        end do
        if (all(s)) then
            phases = 1
            return
        end if
        ! count the stick runs the basis resolves (a run may now wrap around the end)
        ! (one rotation to the first slip sample: linear in nt)
        if (s(1)) s = cshift(s, findloc(s, .false., 1) - 1)
        k = 1
        do while (k <= nt)
            len = run_length(k)
            if (s(k) .and. len >= minlen) phases = phases + 1
            k = k + len
        end do

    contains

        pure integer function run_length(k0)
            integer, intent(in) :: k0
            run_length = 1
            do while (k0 + run_length <= nt)
                if (s(k0 + run_length) .neqv. s(k0)) exit
                run_length = run_length + 1
            end do
        end function run_length
    end function count_phases
end module stickslip_hbm_finish
