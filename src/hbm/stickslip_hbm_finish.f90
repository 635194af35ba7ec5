!> What follows a weighted-residual solve once its friction-force coefficients are found:
!> settling an undetermined mean force, recovery of every DOF, the energy balance over one
!> period, stick statistics and samples (finish_solution), and the checks of the answer as
!> diagnostics with their thresholds (check_solution). Knows nothing of how the coefficients
!> were found (stickslip_hbm_strategy); called by solve_condensed (stickslip_hbm).
module stickslip_hbm_finish
    use stickslip_kinds, only: dp, two_pi
    use stickslip_diagnostics, only: level_warning, level_untrusted
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hb_residual, only: hb_problem_t
    use stickslip_dynamics, only: near_singular_threshold
    use stickslip_condensed_structure, only: condensed_structure_t, rho_ratio, &
        rho_out_of_band, rho_ratio_min, rho_ratio_max
    use stickslip_contact_set, only: channel_directions
    use stickslip_contact_element, only: state_stick, state_open, channel_t, kinematics_gap
    use stickslip_lapack, only: dgesv
    use stickslip_contact_measures, only: contact_measures_t, measure_contacts, coulomb_check, &
        energy_balance_error
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
    !> The velocity resolution of a solution is resolution_margin * max(tol,
    !> resolution_min) * fscale: velocities below it are the solve's noise (at_rest).
    real(dp), parameter :: resolution_margin = 100.0_dp, resolution_min = 1.0e-12_dp

contains

    !> Settle undetermined mean forces, recover every DOF, energies, contact measures
    !> (stickslip_contact_measures), samples, normal forces and gaps with the checks of the
    !> normal law.
    subroutine finish_solution(s, opts, prob, y, sol, model)
        !> The structure's data (omega, forcing).
        type(condensed_structure_t), intent(in) :: s
        !> Solver options as given (harmonics, want_samples).
        type(hbm_options_t), intent(in) :: opts
        !> The projected contact equations the solve used.
        type(hb_problem_t), intent(inout) :: prob
        !> Channel-force coefficients [N] found; an undetermined mean force is settled.
        real(dp), intent(inout) :: y(:)
        !> The solution: recovery, energies, contact measures and samples filled in.
        type(hbm_solution_t), intent(inout) :: sol
        !> The dense model (dense path only: the velocities along the channel directions and
        !> its C for the energies).
        type(model_t), intent(in), optional :: model
        real(dp), allocatable :: rs(:, :), vs(:, :), fcoef(:, :), vc(:, :), work(:), &
                                 dirs(:, :), ucoef(:, :), mean(:)
        integer, allocatable :: state(:, :)
        complex(dp), allocatable :: cw(:)
        integer :: nb, nc, nt, n, j, i, k, p, q, i0, ncontact, c0, m
        real(dp) :: period
        logical :: settled
        type(contact_measures_t) :: cm

        nb = prob%basis%nb
        nc = prob%nc
        nt = prob%basis%nt
        n = size(prob%dyn%x0, 1)
        i0 = prob%basis%i0
        period = two_pi/s%omega
        ncontact = prob%contacts%ncontact
        sol%contacts = prob%contacts
        allocate (rs(nt, nc), vs(nt, nc), sol%offset_undetermined(ncontact), &
                  state(nt, ncontact))
        sol%offset_undetermined = .false.
        if (nc > 0) call prob%law_samples(y, rs, vs, state)

        ! A contact stuck over the whole period holds any mean force in an admissible set:
        ! its element chooses the admissible value closest to zero (minimum norm), never an
        ! arbitrary one. A new mean friction force moves the static displacement, hence the
        ! mean gap of the normal channels closed all period (a static coupling, g_static):
        ! their mean forces are solved again (the mean gap equations, linear in them) and the
        ! choice repeated against the new limits until both hold (settle_means).
        if (prob%basis%has_zero .and. nc > 0) call settle_means(prob, y, rs, vs, state, &
                                                                sol%offset_undetermined)

        sol%rcoef = reshape(y, [nb, nc])
        allocate (sol%xcoef(nb, n), sol%vcoef(nb, n))
        call prob%dyn%displacement(prob%basis, sol%rcoef, sol%xcoef)
        do p = 1, n
            call prob%basis%derivative(sol%xcoef(:, p), s%omega, sol%vcoef(:, p))
        end do

        ! shares, stick phases, Coulomb's dissipation, the force-limit ratio
        call measure_contacts(prob%contacts, prob%rho, rs, vs, state, period, &
                              max(1, nt/max(1, opts%harmonics)), cm)
        sol%open_fraction = cm%open_fraction
        sol%stick_fraction = cm%stick_fraction
        sol%slip_fraction = cm%slip_fraction
        sol%stick_phases = cm%stick_phases

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
        if (present(model)) then
            ! the velocities along the channel directions (the normal channels' too)
            dirs = channel_directions(model, prob%contacts)
            do j = 1, nc
                vc(:, j) = matmul(sol%vcoef, dirs(:, j))
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
        ! the gross work, integral |f . v| dt: the scale of the energy balance; and the
        ! work on a velocity error of the solve's resolution tol * fscale at every forced
        ! DOF: the floor of that scale (a structure at rest does roundoff work only)
        ! (the residual's norm bounds its velocities' noise up to the sum over the
        ! coefficients and the dynamics' condition: a margin of resolution_margin; never
        ! below 1e-12 fscale, roundoff of the velocities, whatever tol asks)
        sol%velocity_resolution = resolution_margin*max(opts%tol, resolution_min)*sol%fscale
        block
            real(dp) :: fs(nt), vt(nt), pw(nt), fsum
            complex(dp) :: cwork(nt/2 + 1)
            pw = 0.0_dp
            fsum = 0.0_dp
            do p = 1, n
                if (all(fcoef(:, p) == 0.0_dp)) cycle
                call prob%basis%synthesize(fcoef(:, p), fs, cwork)
                call prob%basis%synthesize(sol%vcoef(:, p), vt, cwork)
                pw = pw + fs*vt
                fsum = fsum + maxval(abs(fs))
            end do
            sol%work_gross = period*sum(abs(pw))/nt
            sol%work_resolution = period*sol%velocity_resolution*fsum
        end block
        sol%at_rest = sol%velocity_resolution > 0.0_dp
        do p = 1, n
            if (sum(abs(sol%vcoef(:, p))) > sol%velocity_resolution) sol%at_rest = .false.
        end do
        ! every channel's work (a normal force's is zero over a period for an exact solution)
        sol%diss_friction = 0.0_dp
        do j = 1, nc
            sol%diss_friction = sol%diss_friction - inner(sol%rcoef(:, j), vc(:, j))
        end do
        sol%diss_coulomb = cm%diss_coulomb
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

        sol%coulomb_check = coulomb_check(cm%diss_law, sol%diss_friction, sol%diss_damping, &
                                          sol%work_gross, sol%work_resolution)
        sol%max_force_ratio = cm%force_ratio

        if (opts%want_samples) then
            allocate (sol%t(nt), sol%x(nt, n), sol%v(nt, n), work(nt), cw(nt/2 + 1))
            sol%t = [(period*real(k, dp)/real(nt, dp), k=0, nt - 1)]
            do p = 1, n
                call prob%basis%synthesize(sol%xcoef(:, p), sol%x(:, p), cw)
                call prob%basis%synthesize(sol%vcoef(:, p), sol%v(:, p), cw)
            end do
            sol%r = rs
            sol%stick = merge(1.0_dp, 0.0_dp, state == state_stick)
            sol%state = state
        end if
        ! normal forces, gaps and the checks of the normal law
        allocate (sol%normal(nt, ncontact), sol%gap(nt, ncontact), ucoef(nb, nc))
        if (nc > 0) call prob%kinematics(sol%rcoef, ucoef)
        call normal_samples(prob, rs, vs, state, ucoef, sol%normal, sol%gap, &
                            sol%signorini_check, sol%impact_check)

    contains

        !> Energy per period from the Gram matrices of a sparse condensation, with
        !> u_h = [1; R_h] (R_h = r_cos - i r_sin of each channel): the forcing work
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

    !> The normal force and gap samples of every contact (nt x n_c), and the checks of the
    !> normal law: `signorini` the largest pulling normal force relative to the largest one,
    !> or penetration of the gap + lambda / k_n relative to the normal displacement amplitude
    !> (for an elastic contact at least its largest compression lambda / k_n);
    !> `impact` the largest normal velocity of a rigid contact where it closes, relative to
    !> its normal velocity amplitude. A contact without a normal channel: its constant normal
    !> load and a zero gap. `ucoef` holds the kinematic coefficients of the channels (omega
    !> times the gap of a normal channel).
    subroutine normal_samples(prob, rs, us, state, ucoef, normal, gap, signorini, impact)
        !> The problem.
        type(hb_problem_t), intent(inout) :: prob
        !> Channel forces [N] and kinematic quantities [m/s], nt x n_ch.
        real(dp), intent(in) :: rs(:, :), us(:, :)
        !> Contact states, nt x n_c.
        integer, intent(in) :: state(:, :)
        !> Kinematic coefficients of the channels, nb x n_ch [m/s].
        real(dp), intent(in) :: ucoef(:, :)
        !> Normal force [N] and gap [m] samples, nt x n_c.
        real(dp), intent(out) :: normal(:, :), gap(:, :)
        !> The checks (dimensionless).
        real(dp), intent(out) :: signorini, impact
        integer :: j, c, nt, k, kprev
        real(dp) :: omega, lmax, amp, vamp, cn
        real(dp), allocatable :: geff(:), dcoef(:), vn(:)
        complex(dp), allocatable :: cw(:)
        type(channel_t) :: ch
        nt = size(normal, 1)
        omega = prob%dyn%omega
        signorini = 0.0_dp
        impact = 0.0_dp
        allocate (dcoef(size(ucoef, 1)), vn(nt), cw(nt/2 + 1))
        associate (cs => prob%contacts)
            do j = 1, cs%ncontact
                c = cs%normal(j)
                if (c == 0) then
                    normal(:, j) = cs%elements(j)%e%normal_load()
                    gap(:, j) = 0.0_dp
                    cycle
                end if
                ch = cs%channel(c)
                cn = ch%compliance
                normal(:, j) = rs(:, c)
                geff = us(:, c)/omega
                gap(:, j) = geff
                if (cn > 0.0_dp) gap(:, j) = geff - cn*rs(:, c)
                lmax = maxval(rs(:, c))
                ! penetration relative to the normal motion, or for an elastic contact to
                ! its largest compression lambda / k_n if larger: a contact closed all period
                ! that hardly moves (stuck with it) has a normal motion of roundoff size
                amp = max(maxval(gap(:, j)) - minval(gap(:, j)), cn*max(lmax, 0.0_dp))
                if (lmax > 0.0_dp) signorini = max(signorini, -minval(rs(:, c))/lmax)
                if (amp > 0.0_dp) signorini = max(signorini, -minval(geff)/amp)
                if (cn > 0.0_dp) cycle
                ! a rigid contact: its normal velocity where it closes (open -> closed)
                call prob%basis%derivative(ucoef(:, c), omega, dcoef)
                call prob%basis%synthesize(dcoef, vn, cw)
                vn = vn/omega
                vamp = maxval(abs(vn))
                if (.not. (vamp > 0.0_dp)) cycle
                do k = 1, nt
                    kprev = modulo(k - 2, nt) + 1
                    if (state(kprev, j) == state_open .and. state(k, j) /= state_open) &
                        impact = max(impact, abs(vn(kprev))/vamp)
                end do
            end do
        end associate
    end subroutine normal_samples

    !> The mean forces of the contacts stuck all period (offset_undetermined set for them):
    !> each element's admissible value closest to zero (settle_offset); then the mean forces
    !> of the gap channels closed at every sample solved from their mean gap equations
    !> (u_0 = omega (gap + u_static + g_static R_0 + c R_0) = 0, linear), which the new
    !> friction means moved; repeated (at most 20 times) until the mean gaps hold to
    !> roundoff. y, r, u and state are updated.
    subroutine settle_means(prob, y, r, u, state, undetermined)
        !> The projected contact equations (has_zero).
        type(hb_problem_t), intent(inout) :: prob
        !> Channel force coefficients [N].
        real(dp), intent(inout) :: y(:)
        !> Samples of the channel forces and kinematic quantities, nt x channels.
        real(dp), intent(inout) :: r(:, :), u(:, :)
        !> Contact states, nt x contacts.
        integer, intent(inout) :: state(:, :)
        !> Set for the contacts stuck all period.
        logical, intent(inout) :: undetermined(:)
        real(dp), allocatable :: mean(:), uc(:, :), a(:, :), b(:)
        integer, allocatable :: closed(:), ipiv(:)
        integer :: nb, i0, j, k, c0, m, it, nclosed, info, p, q
        real(dp) :: omega, ushift
        logical :: settled, any_settled
        type(channel_t) :: ch
        nb = prob%basis%nb
        i0 = prob%basis%i0
        omega = prob%dyn%omega
        allocate (uc(nb, prob%nc))
        do it = 1, 20
            any_settled = .false.
            do j = 1, prob%contacts%ncontact
                c0 = prob%contacts%first(j)
                m = prob%contacts%width(j)
                mean = [(y((c0 + k - 2)*nb + i0), k=1, m)]
                call prob%contacts%elements(j)%e%settle_offset(prob%rho, r(:, c0:c0 + m - 1), &
                                                               u(:, c0:c0 + m - 1), mean, &
                                                               settled)
                if (.not. settled) cycle
                any_settled = .true.
                undetermined(j) = .true.
                do k = 1, m
                    y((c0 + k - 2)*nb + i0) = mean(k)
                end do
            end do
            if (.not. any_settled) return
            ! the gap channels of the settled contacts closed at every sample
            allocate (closed(0))
            do j = 1, prob%contacts%ncontact
                if (.not. undetermined(j)) cycle
                c0 = prob%contacts%first(j)
                do k = c0, c0 + prob%contacts%width(j) - 1
                    ch = prob%contacts%channel(k)
                    if (ch%kinematics == kinematics_gap) closed = [closed, k]
                end do
            end do
            nclosed = size(closed)
            if (nclosed == 0) return
            call prob%kinematics(reshape(y, [nb, prob%nc]), uc)
            b = -uc(i0, closed)
            ushift = maxval(abs(b))
            if (.not. (ushift > 1.0e-13_dp*max(maxval(abs(u)), tiny(1.0_dp)))) then
                deallocate (closed)
                return
            end if
            allocate (a(nclosed, nclosed), ipiv(nclosed))
            do q = 1, nclosed
                do p = 1, nclosed
                    a(p, q) = omega*prob%dyn%g_static(closed(p), closed(q))
                end do
                ch = prob%contacts%channel(closed(q))
                a(q, q) = a(q, q) + omega*ch%compliance
            end do
            call dgesv(nclosed, 1, a, nclosed, ipiv, b, nclosed, info)
            if (info /= 0) return
            do p = 1, nclosed
                y((closed(p) - 1)*nb + i0) = y((closed(p) - 1)*nb + i0) + b(p)
            end do
            deallocate (closed, a, ipiv)
            call prob%law_samples(y, r, u, state)
        end do
    end subroutine settle_means

    !> The checks of a solution as diagnostics items (doc/where-methods-fail.md):
    !> not_converged; rho_out_of_range (rho / contact mobility outside [rho_ratio_min,
    !> rho_ratio_max]: the friction equality loses its digits); near_resonance (Z_h nearly
    !> singular); and, once converged, energy_balance, coulomb_dissipation (not at rest:
    !> every work is then roundoff) and coulomb_law.
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
        ! at rest every work is roundoff of the solve: the balance 0 = 0 has nothing to
        ! measure (the Coulomb law, the stuck forces within mu N, is still checked)
        if (.not. sol%at_rest) then
            e = energy_balance_error(sol%work_forcing, sol%diss_friction, sol%diss_damping, &
                                     0.0_dp, sol%work_gross, sol%work_resolution)
            call graded("energy_balance", e, energy_warning, energy_untrusted, &
                        "energy balance error (forcing work - friction - viscous "// &
                        "dissipation, relative to the work per period)")
            call graded("coulomb_dissipation", sol%coulomb_check, dissipation_warning, &
                        dissipation_untrusted, "friction dissipation differs from "// &
                        "Coulomb's (mu N |v| where the contacts slip), relative difference")
        end if
        call graded("coulomb_law", sol%max_force_ratio - 1.0_dp, force_excess_warning, &
                    force_excess_untrusted, "friction force exceeds mu N (max |r| / mu N "// &
                    "- 1, beyond the Gibbs overshoot of a truncated series)")
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
end module stickslip_hbm_finish
