!> The automatic weight rho of the friction equality
!>     Psi(r, v) = v + min(0, rho (r + mu N) - v) + max(0, rho (r - mu N) - v),
!> taken from the problem data when hbm_options_t%rho = 0.
!>
!> rho converts a force into a velocity [m/(N s)]: it is a mobility. The natural one is the
!> contact's own: a friction force r changes the slip velocity by G r, with
!> G_h = i h omega W^T Z_h^{-1} W (stickslip_dynamics). With rho of the size of |G|,
!> - rho mu N is the slip velocity that the friction limit can cancel, so the stick interval
!>   rho (r - mu N) < v < rho (r + mu N) of Psi tests, at every iterate, whether friction can
!>   hold the motion: the physical stick criterion (from a cold start r = 0 the first stick
!>   set is |V0(t)| < rho mu N: where the free motion is slower than what friction stops);
!> - the two kinds of rows of the Jacobian, A G (stick) and rho (I - A) (slip), have the same
!>   size, so its conditioning does not jump by orders of magnitude when the stick set
!>   changes between iterations.
!> A rho much larger than the mobility declares every sample stuck at the start and aims
!> the first Newton step at the fully stuck response (forces far beyond mu N); that is why
!> rho = 1 or 5 stalls on the seed case (mobility 0.2 m/(N s)) where rho = 0.02 or 0.2
!> converges. A rho below the mobility errs on the side of slip, whose Newton step lands on
!> admissible forces |r| = mu N; far below it the stick rows dominate the Jacobian and the
!> slip rows fade, and the truncated force overshoots mu N more (the Galerkin solution at
!> finite H depends on rho). Measured with bare cold starts (&hbm start = 'direct') over
!> omega = 0.5 .. 6 rad/s x mu = 0.1 .. 3 x H = 10, 30, 100, on the seed case and on the
!> damped 4-DOF chain with two contacts (examples/chain4.nml): every run converged for
!> rho / mobility in 0.1 .. 0.5, while 0.03 and 1 .. 3 lost runs at H = 100; at the seed
!> point for H = 20 .. 200 and 512 .. 4096 samples, 0.1 .. 0.3 never failed and 0.5 failed
!> only for H >= 160 with fewer than 6.5 H samples. The overshoot of the friction force at
!> stick-slip transitions grows as rho / mobility falls (seed point, H = 30: 2.6 % of mu N
!> at 1, 3.5 % at 0.5, 5.0 % at 0.2). The automatic rho takes rho_fraction = 0.5 times the
!> mobility: inside the robust band, with the smallest overshoot there.
!>
!> |G_h| itself has poles at the natural frequencies and zeros at the antiresonances of the
!> contact (on the seed case: infinite at 0.618 and 1.618 rad/s, zero at 1.414 rad/s), which
!> would make rho useless right where the response is most interesting. The automatic rho
!> uses the resonance-free mobility
!>     rho_j = Omega w_j^T (K + Omega^2 M)^{-1} w_j,     Omega = h_f omega,
!> (w_j the contact direction, h_f the forcing harmonic of largest amplitude, 1 when the
!> forcing is static): for a single DOF it is Omega / (k + Omega^2 m), which follows the
!> stiffness line Omega / k below resonance and the mass line 1 / (Omega m) above, the
!> envelope of |G| away from resonance, and equals 1 / (2 sqrt(k m)) at resonance. Damping is
!> left out (it only lowers |G| near resonance). Several contacts share one rho: the
!> geometric mean of rho_j over the contacts that can hold a force (mu_j N_j > 0; all
!> contacts when none can), times rho_fraction. On the seed case at omega = 4.5 rad/s the
!> mobility is 0.212 m/(N s) and rho = 0.106 m/(N s). The choice is invariant under a change
!> of units: scaling M, C, K, the forces and the normal loads by s scales rho by 1 / s and
!> leaves every iterate of the solve unchanged.
!>
!> The held weight of a sector (cyclic_held_rho), the remedy of a nonlinear mode that stops:
!> each force channel taken in the travelling wave, D = d - e d_next (the neighbour's motion
!> the sector's own times the phase e), on the sector's cyclic dynamics, and with the other
!> channels held (the Schur complement 1 / [G^-1]_jj of the channels' mobility matrix G). A
!> damper pressed between two platforms is a light body whose own mobility is large (13.6
!> m/(N s) on examples/bladed_disk_damper.nml), but held at one contact it slips at the
!> other only as fast as one platform moves against the next (0.020 at nodal diameter 1,
!> 0.16 at 3, 0.95 at 12). It is not the automatic rho: on shrouds and platforms that touch
!> at several points, holding the others leaves each point only its local flexibility, and
!> the weight falls far below the band where the solve is fastest (doc/cyclic.md, "The
!> weight of a sector").
!> Knows nothing of the solver: only the model.
module stickslip_rho
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_model, only: model_t, force_direction
    use stickslip_contact_set, only: contact_set_t, new_contact_set, channel_directions
    use stickslip_contact_element, only: channel_t, kinematics_gap
    use stickslip_lapack, only: dgetrf, dgetrs, zgesv
    use stickslip_cyclic, only: cyclic_t, cyclic_directions, cyclic_basis, sector_phase, &
        nodal_diameter, structure_key, conjugate_shapes
    implicit none
    private
    public :: automatic_rho, contact_mobility, rho_fraction, rho_from_channels, &
        dominant_harmonic, cyclic_held_rho, cyclic_mobility_matrix, held_rho

    !> The automatic rho as a fraction of the contact mobility (see the module header).
    real(dp), parameter :: rho_fraction = 0.5_dp

    !> A channel whose mobility with the others held falls below this fraction of its own
    !> counts as dependent on them (two contacts measuring the same relative motion, e.g. a
    !> damper at nodal diameter 0, whose platforms move together): its own mobility is used.
    real(dp), parameter :: dependent_fraction = 1.0e-8_dp

contains

    !> The automatic weight rho of Psi for `model` [m/(N s)]: rho_fraction times the
    !> geometric mean over the force channels that can hold a force (all when none can) of
    !> their resonance-free mobility at the dominant forcing frequency (rho_from_channels).
    !> Always finite and > 0; 1 for a model without contacts (rho is then unused). `model`
    !> must be valid (validate_model); no error can occur. With `lambda` and `shapes`, the
    !> model's own modes (see contact_mobility), no factorization.
    function automatic_rho(model, lambda, shapes) result(rho)
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Optional: its modes, K Phi = M Phi Lambda, Phi^H M Phi = I (both or neither).
        real(dp), intent(in), optional :: lambda(:)
        complex(dp), intent(in), optional :: shapes(:, :)
        !> The weight rho > 0 [m/(N s)].
        real(dp) :: rho
        real(dp), allocatable :: mob(:)
        type(contact_set_t) :: cs
        rho = 1.0_dp
        if (model%ncontact() == 0) return
        mob = contact_mobility(model, lambda, shapes)
        call new_contact_set(cs, model)
        rho = rho_from_channels(mob, cs, model%omega, dominant_harmonic(model)*model%omega)
    end function automatic_rho

    !> The automatic rho from the resonance-free mobilities `mob` of the force channels
    !> (contact_mobility: Omega d^T (K + Omega^2 M)^-1 d), in the units of each channel's
    !> kinematic quantity: for a gap channel (omega times a gap) times omega / Omega, plus
    !> omega times its compliance; for a velocity channel plus Omega times its compliance
    !> (a contact stiffness in series); rho_fraction times their geometric mean over the
    !> channels that can hold a force (channel_t%holds; all when none can) [m/(N s)]. For
    !> rigid Coulomb contacts: the geometric mean of the contact mobilities over the contacts
    !> with mu N > 0.
    pure function rho_from_channels(mob, cs, omega, big_omega) result(rho)
        !> Mobility of each force channel [m/(N s)].
        real(dp), intent(in) :: mob(:)
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> Fundamental and dominant forcing angular frequencies [rad/s].
        real(dp), intent(in) :: omega, big_omega
        real(dp) :: rho
        real(dp) :: f(size(mob)), a(size(mob))
        logical :: holds(size(mob))
        rho = 1.0_dp
        if (size(mob) == 0) return
        call channel_units(cs, omega, big_omega, f, a, holds)
        rho = rho_fraction*exp(sum(log(mob*f + a), mask=holds)/real(count(holds), dp))
    end function rho_from_channels

    !> The held weight from the force channels' mobility matrix `g` (G_ij = Omega D_i^T
    !> (K + Omega^2 M)^-1 conj(D_j), Hermitian, nc x nc; cyclic_mobility_matrix), each channel
    !> in its kinematic quantity's units and with its compliance as rho_from_channels, taken
    !> with the other channels that hold a force held: 1 / [A^-1]_jj over those channels (A
    !> the channels' matrix in those units, all channels when none holds), rho_fraction times
    !> the geometric mean of these [m/(N s)]. A channel dependent on the others (its held
    !> mobility below dependent_fraction of its own, or the matrix singular) keeps its own.
    function held_rho(g, cs, omega, big_omega) result(rho)
        !> The channels' mobility matrix [m/(N s)].
        complex(dp), intent(in) :: g(:, :)
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> Fundamental and the mobility's angular frequencies [rad/s].
        real(dp), intent(in) :: omega, big_omega
        real(dp) :: rho
        real(dp) :: f(size(g, 1)), a(size(g, 1)), own(size(g, 1)), m(size(g, 1))
        logical :: holds(size(g, 1))
        complex(dp), allocatable :: sub(:, :), inv(:, :)
        integer, allocatable :: idx(:), ipiv(:)
        integer :: nc, i, j, nh, info
        nc = size(g, 1)
        rho = 1.0_dp
        if (nc == 0) return
        call channel_units(cs, omega, big_omega, f, a, holds)
        idx = pack([(i, i=1, nc)], holds)
        nh = size(idx)
        allocate (sub(nh, nh), inv(nh, nh), ipiv(nh))
        do j = 1, nh
            do i = 1, nh
                sub(i, j) = sqrt(f(idx(i))*f(idx(j)))*g(idx(i), idx(j))
            end do
            sub(j, j) = sub(j, j) + a(idx(j))
            own(idx(j)) = real(sub(j, j), dp)
        end do
        inv = (0.0_dp, 0.0_dp)
        do j = 1, nh
            inv(j, j) = (1.0_dp, 0.0_dp)
        end do
        call zgesv(nh, nh, sub, nh, ipiv, inv, nh, info)
        do j = 1, nh
            m(idx(j)) = own(idx(j))
            if (info /= 0) cycle
            associate (held => 1.0_dp/real(inv(j, j), dp))
                if (ieee_is_finite(held) .and. held > dependent_fraction*own(idx(j)) .and. &
                    held <= own(idx(j))) m(idx(j)) = held
            end associate
        end do
        rho = rho_fraction*exp(sum(log(m(idx)))/real(nh, dp))
    end function held_rho

    !> Per force channel: the factor `f` and the term `a` that make its mobility (Omega
    !> d^T (K + Omega^2 M)^-1 d) one in its kinematic quantity's units, f mob + a (a gap
    !> channel: omega times a gap, f = omega / Omega, a = omega times its compliance; a
    !> velocity channel: f = 1, a = Omega times its compliance, a contact stiffness in
    !> series), and whether it can hold a force (all when none can).
    pure subroutine channel_units(cs, omega, big_omega, f, a, holds)
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> Fundamental and the mobility's angular frequencies [rad/s].
        real(dp), intent(in) :: omega, big_omega
        !> Factor, added term [m/(N s)] and whether it holds, per channel.
        real(dp), intent(out) :: f(:), a(:)
        logical, intent(out) :: holds(:)
        type(channel_t) :: ch
        integer :: c
        do c = 1, size(f)
            ch = cs%channel(c)
            a(c) = 0.0_dp
            if (ch%kinematics == kinematics_gap) then
                f(c) = omega/big_omega
                if (ch%compliance > 0.0_dp) a(c) = omega*ch%compliance
            else
                f(c) = 1.0_dp
                if (ch%compliance > 0.0_dp) a(c) = big_omega*ch%compliance
            end if
            holds(c) = ch%holds
        end do
        if (.not. any(holds)) holds = .true.
    end subroutine channel_units

    !> The held weight rho of Psi for the sector `model` of the disk `cyc` [m/(N s)] (see
    !> the module header): held_rho of the channels' mobility matrix in the travelling wave
    !> of harmonic `harmonic` (default: the dominant forcing harmonic; a nonlinear mode
    !> passes 1, its fundamental) at Omega = harmonic x model%omega (cyclic_mobility_matrix).
    !> Falls back on automatic_rho (the free sector's contact mobility) when the sector's
    !> cyclic dynamic stiffness is singular. Always finite and > 0; 1 without contacts. `model` and
    !> `cyc` must be valid (validate_model, validate_cyclic); no error can occur.
    function cyclic_held_rho(model, cyc, harmonic) result(rho)
        !> A validated sector.
        type(model_t), intent(in) :: model
        !> Its disk (engine order: the wave's), optionally with its prepared cyclic modes.
        type(cyclic_t), intent(in) :: cyc
        !> Optional: the harmonic whose wave the mobility is taken in (>= 1).
        integer, intent(in), optional :: harmonic
        real(dp) :: rho
        type(contact_set_t) :: cs
        complex(dp), allocatable :: g(:, :)
        integer :: h, info
        rho = 1.0_dp
        if (model%ncontact() == 0) return
        h = dominant_harmonic(model)
        if (present(harmonic)) h = max(1, harmonic)
        call new_contact_set(cs, model)
        call cyclic_mobility_matrix(model, cyc, cs, h, g, info)
        if (info == 0) rho = held_rho(g, cs, model%omega, h*model%omega)
        if (info /= 0 .or. .not. (ieee_is_finite(rho) .and. rho > 0.0_dp)) &
            rho = automatic_rho(model)
    end function cyclic_held_rho

    !> The mobility matrix of the sector's force channels in the travelling wave of harmonic
    !> h: G = Omega D^T T (T^H (K + Omega^2 M) T)^-1 T^H conj(D) at Omega = h omega, with D
    !> = d - e d_next (cyclic_directions) and T the cyclic basis of the phase e of harmonic h
    !> (the resonance-free mobility of contact_mobility, in the wave) [m/(N s)], nc x nc
    !> Hermitian. From cyc's prepared cyclic modes (the modal sum Omega sum_k B_k B_k^H /
    !> (lambda_k + Omega^2), B = D^T T Phi) when they hold the diameter, else one complex
    !> factorization. info /= 0: that stiffness is singular (g undefined).
    subroutine cyclic_mobility_matrix(model, cyc, cs, h, g, info)
        !> A validated sector.
        type(model_t), intent(in) :: model
        !> Its disk.
        type(cyclic_t), intent(in) :: cyc
        !> The sector's contacts.
        type(contact_set_t), intent(in) :: cs
        !> The harmonic (>= 1).
        integer, intent(in) :: h
        !> The mobility matrix [m/(N s)].
        complex(dp), allocatable, intent(out) :: g(:, :)
        !> 0, or nonzero when the cyclic dynamic stiffness is singular.
        integer, intent(out) :: info
        complex(dp), allocatable :: dm(:, :), t(:, :), sc(:, :), b(:, :), y(:, :)
        complex(dp) :: e
        integer, allocatable :: ipiv(:)
        integer :: n, nd, j
        real(dp) :: big_omega
        n = model%ndof
        big_omega = h*model%omega
        e = exp(cmplx(0.0_dp, sector_phase(h, cyc%engine_order, cyc%sectors, 1), dp))
        dm = cyclic_directions(model, cyc, cs, e)
        nd = nodal_diameter(h, cyc%engine_order, cyc%sectors)
        info = 0
        if (modal()) then
            ! the prepared shapes T Phi of this phase
            associate (md => cyc%modes(nd))
                if (conjugate_shapes(h, cyc%engine_order, cyc%sectors)) then
                    b = matmul(transpose(dm), conjg(md%shapes))
                else
                    b = matmul(transpose(dm), md%shapes)
                end if
                do j = 1, size(b, 2)
                    b(:, j) = b(:, j)/sqrt(md%lambda(j) + big_omega**2)
                end do
            end associate
            g = big_omega*matmul(b, conjg(transpose(b)))
            return
        end if
        t = cyclic_basis(cyc, n, e)
        sc = matmul(conjg(transpose(t)), matmul(cmplx(model%stiffness + &
                                                      big_omega**2*model%mass, 0.0_dp, dp), t))
        b = matmul(transpose(dm), t)
        y = conjg(transpose(b))
        allocate (ipiv(size(sc, 1)))
        call zgesv(size(sc, 1), size(y, 2), sc, size(sc, 1), ipiv, y, size(y, 1), info)
        if (info == 0) g = big_omega*matmul(b, y)

    contains

        !> cyc's prepared modes belong to this sector, hold diameter nd, and make every
        !> lambda_k + Omega^2 positive.
        logical function modal()
            modal = .false.
            if (.not. allocated(cyc%modes)) return
            if (cyc%modes_key /= structure_key(model, cyc%sectors)) return
            if (nd > ubound(cyc%modes, 1)) return
            if (.not. allocated(cyc%modes(nd)%lambda)) return
            if (size(cyc%modes(nd)%shapes, 1) /= n) return
            modal = all(cyc%modes(nd)%lambda + big_omega**2 > 0.0_dp)
        end function modal
    end subroutine cyclic_mobility_matrix

    !> The harmonic of the forcing term of largest |amplitude| x max |load shape| (h > 0; 1
    !> when the forcing is static): Omega = h omega is where the contact mobility is taken.
    pure integer function dominant_harmonic(model) result(hf)
        !> A validated model.
        type(model_t), intent(in) :: model
        real(dp) :: big, fsize
        integer :: i
        hf = 1
        big = 0.0_dp
        do i = 1, model%nforce()
            ! the size of term i: |amplitude| x the largest entry of its load shape
            fsize = abs(model%force_amplitude(i))*maxval(abs(force_direction(model, i)))
            if (model%force_harmonic(i) > 0 .and. fsize > big) then
                big = fsize
                hf = model%force_harmonic(i)
            end if
        end do
    end function dominant_harmonic

    !> Resonance-free mobility of every contact (of every force channel, direction d, for a
    !> model with contact laws), Omega w_j^T (K + Omega^2 M)^{-1} w_j
    !> [m/(N s)], at Omega = h_f omega, h_f the harmonic of the forcing term of largest
    !> |amplitude| x max |load shape| (h > 0; 1 when the forcing is static). Falls back on
    !> the mass line w_j^T M^{-1} w_j / Omega when K + Omega^2 M is singular or the value
    !> is not positive (an indefinite K). `model` must be valid (validate_model); no error can occur.
    !> With the model's modes `lambda`, `shapes` (K Phi = M Phi Lambda, Phi^H M Phi = I), the
    !> same mobility as the modal sum Omega sum_k |Phi_k^H w_j|^2 / (lambda_k + Omega^2),
    !> O(n^2) instead of a factorization (the LU when a term is not positive).
    function contact_mobility(model, lambda, shapes) result(mob)
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Optional: its modes (both or neither).
        real(dp), intent(in), optional :: lambda(:)
        complex(dp), intent(in), optional :: shapes(:, :)
        !> Mobility of each contact (of each force channel with contact laws) [m/(N s)].
        real(dp), allocatable :: mob(:)
        real(dp), allocatable :: s(:, :), w(:, :), y(:, :)
        integer, allocatable :: ipiv(:)
        integer :: n, nc, j, info, hf
        type(contact_set_t) :: cs
        n = model%ndof
        call new_contact_set(cs, model)
        nc = cs%nchannel
        allocate (mob(nc))
        if (nc == 0) return
        hf = dominant_harmonic(model)
        w = channel_directions(model, cs)
        if (present(lambda) .and. present(shapes)) then
            if (size(lambda) == n .and. size(shapes, 1) == n .and. size(shapes, 2) == n) then
                associate (big_omega => hf*model%omega)
                    if (all(lambda + big_omega**2 > 0.0_dp)) then
                        do j = 1, nc
                            ! |Phi_k^H w| = |w^T Phi_k| for a real w
                            mob(j) = big_omega*sum(abs(matmul(w(:, j), shapes))**2/ &
                                                   (lambda + big_omega**2))
                        end do
                        if (all(mob > 0.0_dp .and. ieee_is_finite(mob))) return
                    end if
                end associate
            end if
        end if
        allocate (s(n, n), y(n, nc), ipiv(n))
        associate (big_omega => hf*model%omega)
            s = model%stiffness + big_omega**2*model%mass
            y = w
            call dgetrf(n, n, s, n, ipiv, info)
            if (info == 0) call dgetrs('N', n, nc, s, n, ipiv, y, n, info)
            do j = 1, nc
                mob(j) = -1.0_dp
                if (info == 0) mob(j) = big_omega*dot_product(w(:, j), y(:, j))
            end do
            if (all(mob > 0.0_dp .and. ieee_is_finite(mob))) return
            ! mass line: Omega w^T (Omega^2 M)^{-1} w
            s = model%mass
            y = w
            call dgetrf(n, n, s, n, ipiv, info)
            call dgetrs('N', n, nc, s, n, ipiv, y, n, info)
            do j = 1, nc
                if (mob(j) > 0.0_dp .and. ieee_is_finite(mob(j))) cycle
                mob(j) = dot_product(w(:, j), y(:, j))/big_omega
            end do
        end associate
    end function contact_mobility
end module stickslip_rho
