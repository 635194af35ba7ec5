!> What follows a weighted-residual solve with contact laws (doc/contacts.md), beside what
!> stickslip_hbm_finish does for every solve: the samples of the force channels, their
!> kinematic quantities and the contact states; an undetermined mean friction force settled;
!> open, stick and slip fractions; Coulomb's dissipation and the force excess over the
!> varying limit; normal forces and gaps; the checks of the normal law (signorini) and of
!> impacts of rigid contacts.
module stickslip_hbm_finish_laws
    use stickslip_kinds, only: dp
    use stickslip_hb_residual, only: hb_problem_t
    use stickslip_contact_set, only: contact_set_t
    use stickslip_contact_law, only: state_open, state_stick, state_slip
    implicit none
    private
    public :: laws_samples_settled, laws_fractions, laws_coulomb, laws_normal

contains

    !> Samples of the channel forces rs and kinematic quantities us (nt x n_ch) and the
    !> contact states (nt x n_c) of the unknowns y, after settling the mean friction force
    !> of every contact stuck over the whole period (the basis holding the constant): the
    !> admissible value closest to zero. 1D: the interval of shifts keeping |r(t)| within
    !> the limit g(t) at every sample; 2D: the largest step of the mean force toward zero
    !> that keeps |r(t)| <= g(t) (bisection). `offset_undetermined` flags those contacts.
    subroutine laws_samples_settled(prob, y, rs, us, state, offset_undetermined)
        !> The problem (with contact laws).
        type(hb_problem_t), intent(inout) :: prob
        !> Channel force coefficients [N]; mean friction forces settled on return.
        real(dp), intent(inout) :: y(:)
        !> Channel forces [N] and kinematic quantities [m/s], nt x n_ch.
        real(dp), intent(out) :: rs(:, :), us(:, :)
        !> Contact states, nt x n_c.
        integer, intent(out) :: state(:, :)
        !> Per contact: its mean friction force was settled.
        logical, intent(out) :: offset_undetermined(:)
        integer :: j, nb, i0, c, k, m, it
        real(dp), allocatable :: g(:)
        real(dp) :: lo, hi, shift, t, tlo, thi, r0(2)
        nb = prob%basis%nb
        i0 = prob%basis%i0
        offset_undetermined = .false.
        call prob%law_samples(y, rs, us, state)
        if (.not. prob%basis%has_zero) return
        associate (cs => prob%laws%cs)
            allocate (g(size(rs, 1)))
            do j = 1, cs%ncontact
                if (.not. all(state(:, j) == state_stick)) cycle
                offset_undetermined(j) = .true.
                c = cs%first(j)
                g = limit_samples(cs, j, rs)
                if (cs%ntangent(j) == 1) then
                    k = (c - 1)*nb + i0
                    lo = maxval(-g - (rs(:, c) - y(k)))
                    hi = minval(g - (rs(:, c) - y(k)))
                    shift = min(max(0.0_dp, lo), hi) - y(k)
                    y(k) = y(k) + shift
                    rs(:, c) = rs(:, c) + shift
                else
                    ! the step t in [0, 1] toward a zero mean: admissible at t = 0
                    r0 = [y((c - 1)*nb + i0), y(c*nb + i0)]
                    tlo = 0.0_dp
                    thi = 1.0_dp
                    if (.not. inside(1.0_dp)) then
                        do it = 1, 60
                            t = 0.5_dp*(tlo + thi)
                            if (inside(t)) then
                                tlo = t
                            else
                                thi = t
                            end if
                        end do
                    else
                        tlo = 1.0_dp
                    end if
                    do m = 0, 1
                        y((c + m - 1)*nb + i0) = (1.0_dp - tlo)*r0(m + 1)
                        rs(:, c + m) = rs(:, c + m) - tlo*r0(m + 1)
                    end do
                end if
            end do
        end associate

    contains

        !> The 2D friction force with its mean moved by t toward zero stays in the disks.
        logical function inside(t)
            real(dp), intent(in) :: t
            inside = all(hypot(rs(:, c) - t*r0(1), rs(:, c + 1) - t*r0(2)) <= g)
        end function inside
    end subroutine laws_samples_settled

    !> The friction limit of contact j at the samples [N]: mu N, or mu max(lambda(t), 0).
    function limit_samples(cs, j, rs) result(g)
        type(contact_set_t), intent(in) :: cs
        integer, intent(in) :: j
        real(dp), intent(in) :: rs(:, :)
        real(dp) :: g(size(rs, 1))
        if (cs%normal(j) > 0) then
            g = cs%mu(j)*max(rs(:, cs%normal(j)), 0.0_dp)
        else
            g = cs%mu(j)*cs%normal_load(j)
        end if
    end function limit_samples

    !> Open, stick and slip fractions of every contact (shares of the samples).
    pure subroutine laws_fractions(state, open_fraction, stick_fraction, slip_fraction)
        !> Contact states, nt x n_c.
        integer, intent(in) :: state(:, :)
        !> The fractions, per contact.
        real(dp), intent(out) :: open_fraction(:), stick_fraction(:), slip_fraction(:)
        integer :: j, nt
        nt = size(state, 1)
        do j = 1, size(state, 2)
            open_fraction(j) = count(state(:, j) == state_open)/real(nt, dp)
            stick_fraction(j) = count(state(:, j) == state_stick)/real(nt, dp)
            slip_fraction(j) = count(state(:, j) == state_slip)/real(nt, dp)
        end do
    end subroutine laws_fractions

    !> Coulomb's dissipation over one period [J], integral of g(t) |u_t(t)| over the slip
    !> samples (u_t the slider velocity, g the limit); what Coulomb's law dissipates
    !> (that, and |r . u_t| where the contact sticks) `coulomb_slip` [J]; and the largest
    !> force excess max_t (|r(t)| - g(t)) / max_t g(t) + 1 over the contacts that can hold
    !> a force (1 at the limit; the plain contacts' max |r| / mu N).
    subroutine laws_coulomb(cs, rs, us, state, period, diss_coulomb, coulomb_slip, force_ratio)
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> Channel forces [N] and kinematic quantities [m/s], nt x n_ch.
        real(dp), intent(in) :: rs(:, :), us(:, :)
        !> Contact states, nt x n_c.
        integer, intent(in) :: state(:, :)
        !> The period [s].
        real(dp), intent(in) :: period
        !> Coulomb's dissipation and what Coulomb's law dissipates [J].
        real(dp), intent(out) :: diss_coulomb, coulomb_slip
        !> The largest force excess ratio (dimensionless).
        real(dp), intent(out) :: force_ratio
        integer :: j, c, nt
        real(dp), allocatable :: g(:), speed(:), rmag(:), power(:)
        nt = size(rs, 1)
        diss_coulomb = 0.0_dp
        coulomb_slip = 0.0_dp
        force_ratio = 0.0_dp
        do j = 1, cs%ncontact
            c = cs%first(j)
            g = limit_samples(cs, j, rs)
            if (cs%ntangent(j) == 2) then
                speed = hypot(us(:, c), us(:, c + 1))
                rmag = hypot(rs(:, c), rs(:, c + 1))
                power = abs(rs(:, c)*us(:, c) + rs(:, c + 1)*us(:, c + 1))
            else
                speed = abs(us(:, c))
                rmag = abs(rs(:, c))
                power = abs(rs(:, c)*us(:, c))
            end if
            diss_coulomb = diss_coulomb + period*sum(merge(g*speed, 0.0_dp, &
                                                           state(:, j) /= state_stick))/nt
            coulomb_slip = coulomb_slip + period*sum(merge(power, g*speed, &
                                                           state(:, j) == state_stick))/nt
            if (maxval(g) > 0.0_dp) force_ratio = max(force_ratio, &
                                                      maxval(rmag - g)/maxval(g) + 1.0_dp)
        end do
    end subroutine laws_coulomb

    !> The normal force and gap samples of every contact (nt x n_c), and the checks of the
    !> normal law: `signorini` the largest pulling normal force relative to the largest one,
    !> or penetration of the gap + lambda / k_n relative to the normal displacement amplitude;
    !> `impact` the largest normal velocity of a rigid contact where it closes, relative to
    !> its normal velocity amplitude. `ucoef` holds the kinematic coefficients of the
    !> channels (omega times the gap of a normal channel).
    subroutine laws_normal(prob, rs, us, state, ucoef, normal, gap, signorini, impact)
        !> The problem (with contact laws).
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
        integer :: j, n, nt, k, kprev
        real(dp) :: omega, lmax, amp, vamp, kn
        real(dp), allocatable :: geff(:), dcoef(:), vn(:)
        complex(dp), allocatable :: cw(:)
        nt = size(rs, 1)
        omega = prob%laws%omega
        signorini = 0.0_dp
        impact = 0.0_dp
        allocate (dcoef(size(ucoef, 1)), vn(nt), cw(nt/2 + 1))
        associate (cs => prob%laws%cs)
            do j = 1, cs%ncontact
                n = cs%normal(j)
                if (n == 0) then
                    normal(:, j) = cs%normal_load(j)
                    gap(:, j) = 0.0_dp
                    cycle
                end if
                kn = cs%kn(j)
                normal(:, j) = rs(:, n)
                geff = us(:, n)/omega
                gap(:, j) = geff
                if (kn > 0.0_dp) gap(:, j) = geff - rs(:, n)/kn
                lmax = maxval(rs(:, n))
                amp = maxval(gap(:, j)) - minval(gap(:, j))
                if (lmax > 0.0_dp) signorini = max(signorini, -minval(rs(:, n))/lmax)
                if (amp > 0.0_dp) signorini = max(signorini, -minval(geff)/amp)
                if (kn > 0.0_dp) cycle
                ! a rigid contact: its normal velocity where it closes (open -> closed)
                call prob%basis%derivative(ucoef(:, n), omega, dcoef)
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
    end subroutine laws_normal
end module stickslip_hbm_finish_laws
