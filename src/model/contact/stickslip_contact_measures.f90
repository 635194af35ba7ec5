!> The derived quantities of a periodic solution's contacts, one definition each for every
!> method (doc/outputs.md, "Derived quantities"): from the samples of the channel forces r,
!> kinematic quantities u and contact states over one period (uniform samples),
!> - the shares of the period each contact is open, sticks and slips (they add up to 1) and
!>   its number of stick phases at the resolution of the samples (count_phases);
!> - Coulomb's dissipation, the integral over the period of g(t) |u_t(t)| (g the friction
!>   limit, u_t the slip or slider velocity; every slider of a microslip element), what
!>   Coulomb's law dissipates at the computed velocities: it equals the friction
!>   dissipation -integral r . d^T x' dt of an exact solution;
!> - what the law dissipates (g |u_t| where a contact slips, |r . u_t| where it sticks), the
!>   scale of the Coulomb check (coulomb_check);
!> - the force-limit ratio, max over contacts of max_t (|r_t| - g) / max_t g + 1 (1 at the
!>   limit; max |r| / mu N under a constant load);
!> - the energy balance error over one period (energy_balance_error).
!> Each element gives its share of the sums (contact_element_t%coulomb_dissipation,
!> force_ratio, states); this module adds them up.
module stickslip_contact_measures
    use stickslip_kinds, only: dp
    use stickslip_contact_set, only: contact_set_t
    use stickslip_contact_element, only: state_open, state_stick, state_slip
    implicit none
    private
    public :: contact_measures_t, measure_contacts, count_phases, energy_balance_error, &
        coulomb_check

    !> The derived quantities of a solution's contacts.
    type :: contact_measures_t
        !> Shares of the period each contact is open, stuck and slipping (dimensionless).
        real(dp), allocatable :: open_fraction(:), stick_fraction(:), slip_fraction(:)
        !> Stick phases per period, per contact.
        integer, allocatable :: stick_phases(:)
        !> Coulomb's dissipation over one period [J].
        real(dp) :: diss_coulomb = 0.0_dp
        !> What the laws dissipate over one period [J] (coulomb_check's scale).
        real(dp) :: diss_law = 0.0_dp
        !> The force-limit ratio (dimensionless).
        real(dp) :: force_ratio = 0.0_dp
    end type contact_measures_t

contains

    !> The measures of the contacts `cs` from the samples of one period of `period` [s]:
    !> channel forces r and kinematic quantities u (nt x n_ch), contact states (nt x n_c).
    !> Stick phases shorter than `minlen` samples are not counted (count_phases).
    subroutine measure_contacts(cs, rho, r, u, state, period, minlen, m)
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> The weight of the states [m/(N s)].
        real(dp), intent(in) :: rho
        !> Channel forces [N] and kinematic quantities [m/s] at the samples.
        real(dp), intent(in) :: r(:, :), u(:, :)
        !> Contact states at the samples.
        integer, intent(in) :: state(:, :)
        !> The period [s].
        real(dp), intent(in) :: period
        !> Shortest stick phase counted, in samples.
        integer, intent(in) :: minlen
        !> The measures.
        type(contact_measures_t), intent(out) :: m
        integer :: j, nt, c0, w
        real(dp) :: d, dl
        nt = size(r, 1)
        allocate (m%open_fraction(cs%ncontact), m%stick_fraction(cs%ncontact), &
                  m%slip_fraction(cs%ncontact), m%stick_phases(cs%ncontact))
        do j = 1, cs%ncontact
            m%open_fraction(j) = count(state(:, j) == state_open)/real(nt, dp)
            m%stick_fraction(j) = count(state(:, j) == state_stick)/real(nt, dp)
            m%slip_fraction(j) = count(state(:, j) == state_slip)/real(nt, dp)
            m%stick_phases(j) = count_phases(state(:, j) == state_stick, minlen)
            c0 = cs%first(j)
            w = cs%width(j)
            call cs%elements(j)%e%coulomb_dissipation(rho, r(:, c0:c0 + w - 1), &
                                                      u(:, c0:c0 + w - 1), state(:, j), &
                                                      period, d, dl)
            m%diss_coulomb = m%diss_coulomb + d
            m%diss_law = m%diss_law + dl
            m%force_ratio = max(m%force_ratio, cs%elements(j)%e%force_ratio(r(:, c0:c0 + w - 1)))
        end do
    end subroutine measure_contacts

    !> Relative mismatch of the friction dissipation and what the laws dissipate:
    !> |diss_law - diss_friction| / max(diss_law, |diss_friction| + |diss_damping|, 1e-6
    !> work_gross, work_floor) (dimensionless; ~1% for a sound weighted-residual solution,
    !> O(1) when the forces and velocities do not obey the laws).
    pure real(dp) function coulomb_check(diss_law, diss_friction, diss_damping, work_gross, &
                                         work_floor)
        !> What the laws dissipate, the friction and viscous dissipation, the gross work [J].
        real(dp), intent(in) :: diss_law, diss_friction, diss_damping, work_gross
        !> The work the solve cannot resolve (hbm_solution_t%work_resolution) [J]; 0 when
        !> absent.
        real(dp), intent(in), optional :: work_floor
        coulomb_check = abs(diss_law - diss_friction)/ &
                        max(diss_law, abs(diss_friction) + abs(diss_damping), &
                            1.0e-6_dp*work_gross, given_floor(work_floor), tiny(1.0_dp))
    end function coulomb_check

    !> An optional work floor [J], 0 when absent.
    pure real(dp) function given_floor(work_floor) result(floor)
        real(dp), intent(in), optional :: work_floor
        floor = 0.0_dp
        if (present(work_floor)) floor = work_floor
    end function given_floor

    !> Relative energy balance error over one period: |work_forcing - diss_friction -
    !> diss_damping - impact_loss| / max(|work_forcing|, 1e-6 work_gross, work_floor):
    !> relative to the net work, or to the gross work integral |f . v| dt when the net work
    !> is ~0 (a contact stuck all period, undamped: nothing dissipates, and the balance is
    !> 0 = 0 to roundoff), or to the work the solve cannot resolve when the structure is at
    !> rest (every work is roundoff then).
    pure real(dp) function energy_balance_error(work_forcing, diss_friction, diss_damping, &
                                                impact_loss, work_gross, work_floor) result(e)
        !> Work of the forcing, friction and viscous dissipation, kinetic energy lost in
        !> impacts, gross work of the forcing, all over one period [J].
        real(dp), intent(in) :: work_forcing, diss_friction, diss_damping, impact_loss, &
                                work_gross
        !> The work the solve cannot resolve (hbm_solution_t%work_resolution) [J]; 0 when
        !> absent.
        real(dp), intent(in), optional :: work_floor
        e = abs(work_forcing - diss_friction - diss_damping - impact_loss)/ &
            max(abs(work_forcing), 1.0e-6_dp*work_gross, given_floor(work_floor), &
                tiny(1.0_dp))
    end function energy_balance_error

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
end module stickslip_contact_measures
