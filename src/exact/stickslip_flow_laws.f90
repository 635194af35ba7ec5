!> The contact modes of the exact flow with contact laws (doc/contacts.md, section 5):
!> unilateral contacts with 1D friction, rigid or elastic normal, beside plain contacts.
!>
!> A contact's code is 0 (stuck), +1 / -1 (slipping, the sign of its slip velocity) or 2
!> (open: no force). Closed, an elastic normal carries lambda = -k_n g(y), g = gap + n^T x (an
!> added stiffness and a constant); a rigid normal is the constraint n^T v = 0 whose force
!> lambda comes from the projection, as a stuck friction force does. A slipping contact's
!> force is -s mu lambda: for a rigid normal the constraint's force direction is then
!> n - s mu w (a non-symmetric projection; Painleve's paradox when n^T M^-1 (n - s mu w) <= 0
!> makes the mode fail). In modal coordinates (M = I) every mode is u' = hb y + Ft Lambda(y),
!> Lambda = -(Ct^T Ft)^-1 Ct^T hb y for the constraint directions Ct and force directions Ft.
!> Event rows, three per contact (positive while the mode lasts): stuck, mu lambda - r and
!> mu lambda + r (the limit), slipping, s w^T v; closed, lambda (opening); open, g (closing:
!> for a rigid normal an impact, plastic, with Coulomb's impulse law: impact_jump).
module stickslip_flow_laws
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_lapack, only: dgesv
    use stickslip_flow_modes, only: mode_t, flow_modes_t, mode_index, build_ladder
    use stickslip_contact_law, only: contact_law_t
    use stickslip_contact_set, only: contact_set_t
    use stickslip_contact_element, only: along_tangent, along_normal
    use stickslip_unilateral_element, only: new_unilateral_element
    implicit none
    private
    public :: law_mode_index, law_modes_at, impact_jump, law_start_codes
    public :: event_open, event_close

    !> Event kinds of the normal law, beside stickslip_flow_events' (kev of find_event).
    integer, parameter :: event_open = 10, event_close = 11

contains

    !> Index of the mode with codes `code` in the cache, built on first use (as mode_index
    !> for a plain model). Errors (stat numerical): dependent constraints (Painleve), a
    !> non-finite exponential.
    integer function law_mode_index(self, code, error) result(im)
        !> The dynamics (its mode cache grows).
        class(flow_modes_t), intent(inout) :: self
        !> Codes of the mode: 0 stuck, +1 / -1 slipping, 2 open.
        integer, intent(in) :: code(:)
        !> Set on failure.
        type(error_type), allocatable, intent(inout) :: error
        real(dp), allocatable :: hb(:, :), fb(:, :)
        integer :: n, na, j, c, k
        logical :: ok
        do im = 1, self%nmodes
            if (all(self%modes(im)%code == code)) return
        end do
        im = mode_index(self, code, error)
        if (allocated(error)) return
        n = self%n
        na = self%na
        call law_algebra(self, code, hb, fb, ok)
        if (.not. ok) then
            call fatal_error(error, "reference: a contact mode has dependent constraints "// &
                             "(the stuck and closed contact directions are not independent, "// &
                             "or Painleve's paradox: a slipping rigid contact whose friction "// &
                             "pushes it closed harder than it holds)", stickslip_stat%numerical)
            self%nmodes = self%nmodes - 1
            return
        end if
        associate (md => self%modes(im))
            allocate (md%b(na, na), md%rows(na, 3*self%nc))
            md%b = 0.0_dp
            do j = 1, n
                md%b(j, n + j) = self%s(j)
            end do
            md%b(n + 1:2*n, :) = hb
            do k = 1, size(self%eharm)
                md%b(2*n + 2*k, 2*n + 2*k + 1) = -self%eharm(k)*self%omega
                md%b(2*n + 2*k + 1, 2*n + 2*k) = self%eharm(k)*self%omega
            end do
            md%force = matmul(fb, self%tb)
            md%rows = 0.0_dp
            do j = 1, self%nc
                c = self%cs%first(j)
                if (self%cs%normal(j) == 0) then
                    if (code(j) == 0) then
                        md%rows(:, 3*j - 2) = -fb(c, :)
                        md%rows(:, 3*j - 1) = fb(c, :)
                        md%rows(2*n + 1, 3*j - 2) = md%rows(2*n + 1, 3*j - 2) + &
                                                    self%limit(j)/self%se
                        md%rows(2*n + 1, 3*j - 1) = md%rows(2*n + 1, 3*j - 1) + &
                                                    self%limit(j)/self%se
                    else
                        md%rows(n + 1:2*n, 3*j - 2) = code(j)*self%wt(:, j)
                    end if
                    cycle
                end if
                associate (cn => self%cs%normal(j), mu => self%cmu(j))
                    select case (code(j))
                    case (0)
                        md%rows(:, 3*j - 2) = mu*fb(cn, :) - fb(c, :)
                        md%rows(:, 3*j - 1) = mu*fb(cn, :) + fb(c, :)
                        md%rows(:, 3*j) = fb(cn, :)
                    case (2)
                        md%rows(:, 3*j) = gap_row(self, j)
                    case default
                        md%rows(n + 1:2*n, 3*j - 2) = code(j)*self%wt(:, j)
                        md%rows(:, 3*j) = fb(cn, :)
                    end select
                end associate
            end do
            md%drows = matmul(transpose(md%b), md%rows)
            call build_ladder(self, md, error)
        end associate
        if (allocated(error)) self%nmodes = self%nmodes - 1
    end function law_mode_index

    !> The row of contact j's gap g = gap + n^T x in balanced coordinates (x = Phi S^-1 p,
    !> the exosystem's constant se).
    function gap_row(self, j) result(row)
        class(flow_modes_t), intent(in) :: self
        integer, intent(in) :: j
        real(dp) :: row(self%na)
        row = 0.0_dp
        row(1:self%n) = self%nt(:, j)/self%s
        row(2*self%n + 1) = self%cgap(j)/self%se
    end function gap_row

    !> The algebra of a mode in balanced coordinates: the modal accelerations u' = hb y
    !> (n x na) and the channel forces fb y (n_ch x na). ok = .false. when the constraint
    !> matrix Ct^T Ft is singular.
    subroutine law_algebra(self, code, hb, fb, ok)
        class(flow_modes_t), intent(in) :: self
        integer, intent(in) :: code(:)
        real(dp), allocatable, intent(out) :: hb(:, :), fb(:, :)
        logical, intent(out) :: ok
        real(dp), allocatable :: ctm(:, :), ftm(:, :), g(:, :), l(:, :)
        integer, allocatable :: chan(:), slipchan(:), ipiv(:)
        real(dp), allocatable :: slipsign(:)
        real(dp) :: lrow(self%na)
        integer :: n, na, j, c, cn, k, info
        n = self%n
        na = self%na
        ok = .true.
        allocate (hb(n, na), fb(self%cs%nchannel, na))
        hb = 0.0_dp
        do j = 1, n
            hb(j, j) = -self%lam(j)/self%s(j)
        end do
        hb(:, n + 1:2*n) = -self%ct
        hb(:, 2*n + 1:) = self%ft/self%se
        fb = 0.0_dp
        allocate (ctm(n, 0), ftm(n, 0), chan(0), slipchan(0), slipsign(0))
        do j = 1, self%nc
            c = self%cs%first(j)
            cn = self%cs%normal(j)
            if (cn == 0) then
                ! a plain contact: the constant limit when slipping, a constraint when stuck
                if (code(j) == 0) then
                    call constrain(self%wt(:, j), self%wt(:, j), c, 0, 0.0_dp)
                else
                    hb(:, 2*n + 1) = hb(:, 2*n + 1) - self%limit(j)*code(j)*self%wt(:, j)/self%se
                    fb(c, 2*n + 1) = -self%limit(j)*code(j)/self%se
                end if
                cycle
            end if
            if (code(j) == 2) cycle
            if (self%ckn(j) > 0.0_dp) then
                ! elastic normal: lambda = -k_n (gap + n^T x), linear in the state
                lrow = -self%ckn(j)*gap_row(self, j)
                fb(cn, :) = lrow
                call add_force(self%nt(:, j), lrow)
                if (code(j) == 0) then
                    call constrain(self%wt(:, j), self%wt(:, j), c, 0, 0.0_dp)
                else
                    fb(c, :) = -code(j)*self%cmu(j)*lrow
                    call add_force(self%wt(:, j), fb(c, :))
                end if
            else if (code(j) == 0) then
                ! rigid normal, stuck: both directions constrained
                call constrain(self%wt(:, j), self%wt(:, j), c, 0, 0.0_dp)
                call constrain(self%nt(:, j), self%nt(:, j), cn, 0, 0.0_dp)
            else
                ! rigid normal, slipping: n^T v = 0 held by lambda (n - s mu w)
                call constrain(self%nt(:, j), self%nt(:, j) - code(j)*self%cmu(j)* &
                               self%wt(:, j), cn, c, -code(j)*self%cmu(j))
            end if
        end do
        k = size(chan)
        if (k == 0) return
        ! Lambda = -(Ct^T Ft)^-1 Ct^T hb
        g = matmul(transpose(ctm), ftm)
        l = -matmul(transpose(ctm), hb)
        allocate (ipiv(k))
        call dgesv(k, na, g, k, ipiv, l, k, info)
        if (info /= 0 .or. .not. all(ieee_is_finite(l))) then
            ok = .false.
            return
        end if
        hb = hb + matmul(ftm, l)
        do k = 1, size(chan)
            fb(chan(k), :) = fb(chan(k), :) + l(k, :)
            if (slipchan(k) > 0) fb(slipchan(k), :) = fb(slipchan(k), :) + slipsign(k)*l(k, :)
        end do

    contains

        !> A constraint: direction cdir (velocity held at zero) and force direction fdir, its
        !> force on channel ch (and slip_factor times it on channel slip_ch when > 0).
        subroutine constrain(cdir, fdir, ch, slip_ch, slip_factor)
            real(dp), intent(in) :: cdir(:), fdir(:)
            integer, intent(in) :: ch, slip_ch
            real(dp), intent(in) :: slip_factor
            ctm = reshape([ctm, cdir], [n, size(ctm, 2) + 1])
            ftm = reshape([ftm, fdir], [n, size(ftm, 2) + 1])
            chan = [chan, ch]
            slipchan = [slipchan, slip_ch]
            slipsign = [slipsign, slip_factor]
        end subroutine constrain

        !> A force dir * (row . y) on the structure.
        subroutine add_force(dir, row)
            real(dp), intent(in) :: dir(:), row(:)
            integer :: q
            do q = 1, na
                hb(:, q) = hb(:, q) + dir*row(q)
            end do
        end subroutine add_force
    end subroutine law_algebra

    !> The codes of the contacts at the start state yb (balanced): a unilateral contact is
    !> open when its gap exceeds 1e-9 of its scale (or, elastic, is positive); the friction
    !> of the others slips where the slip velocity exceeds 1e-12 of its scale; the contacts
    !> at zero slip velocity (and the rigid closed ones) get the consistent modes of
    !> law_modes_at. Errors: no consistent mode.
    subroutine law_start_codes(self, yb, code, error)
        !> The dynamics.
        class(flow_modes_t), intent(inout) :: self
        !> Start state in balanced coordinates.
        real(dp), intent(in) :: yb(:)
        !> The codes.
        integer, intent(out) :: code(:)
        !> Set on failure.
        type(error_type), allocatable, intent(inout) :: error
        integer :: j, n
        integer, allocatable :: zset(:)
        real(dp) :: v, g
        n = self%n
        allocate (zset(0))
        do j = 1, self%nc
            v = dot_product(self%wt(:, j), yb(n + 1:2*n))
            code(j) = 0
            if (abs(v) > 1.0e-12_dp*self%vref(j)) code(j) = nint(sign(1.0_dp, v))
            if (self%cs%normal(j) > 0) then
                g = dot_product(gap_row(self, j), yb)
                if (g > 1.0e-9_dp*self%gref(j)) then
                    code(j) = 2
                    cycle
                end if
                ! closed (or at zero gap): its mode decided with the others
                zset = [zset, j]
            else if (code(j) == 0 .and. self%limit(j) > 0.0_dp) then
                zset = [zset, j]
            else if (code(j) == 0) then
                code(j) = 1
            end if
        end do
        call law_modes_at(self, yb, zset, code, error)
    end subroutine law_start_codes

    !> New codes for the contacts `zset` at state yb (balanced): at zero slip velocity, or
    !> (unilateral) at zero gap. A contact at zero slip velocity may stick or slip either
    !> way, one that slips keeps its direction; a unilateral one may also open. Every
    !> combination is tried, stuck and closed first; the first consistent one is kept: a
    !> stuck force within mu lambda (mu N), lambda >= 0 for a closed unilateral contact, a
    !> slip that starts from zero velocity accelerating in its direction, an open contact
    !> whose gap does not close (gap velocity, then acceleration, >= 0). Errors (stat
    !> numerical): none consistent (more than 8 contacts at once: only the first
    !> combination, stuck and closed, is tried).
    subroutine law_modes_at(self, yb, zset, code, error)
        !> The dynamics.
        class(flow_modes_t), intent(inout) :: self
        !> State in balanced coordinates.
        real(dp), intent(in) :: yb(:)
        !> The contacts to decide.
        integer, intent(in) :: zset(:)
        !> Codes; those of zset replaced.
        integer, intent(inout) :: code(:)
        !> Set on failure.
        type(error_type), allocatable, intent(inout) :: error
        integer :: nz, k, total, combo, q, j, nchoice(size(zset)), choice(4, size(zset))
        integer :: trial(size(code))
        real(dp) :: vel(size(zset))
        real(dp), allocatable :: hb(:, :), fb(:, :)
        logical :: ok, moving(size(zset))
        nz = size(zset)
        if (nz == 0) return
        do k = 1, nz
            j = zset(k)
            vel(k) = dot_product(self%wt(:, j), yb(self%n + 1:2*self%n))
            moving(k) = abs(vel(k)) > 1.0e-12_dp*self%vref(j)
            if (moving(k)) then
                nchoice(k) = 1
                choice(1, k) = nint(sign(1.0_dp, vel(k)))
            else
                nchoice(k) = 3
                choice(1:3, k) = [0, 1, -1]
            end if
            if (self%cs%normal(j) > 0) then
                nchoice(k) = nchoice(k) + 1
                choice(nchoice(k), k) = 2
            end if
        end do
        total = product(nchoice)
        if (nz > 8) total = 1
        do combo = 0, total - 1
            trial = code
            q = combo
            do k = 1, nz
                trial(zset(k)) = choice(mod(q, nchoice(k)) + 1, k)
                q = q/nchoice(k)
            end do
            call law_algebra(self, trial, hb, fb, ok)
            if (.not. ok) cycle
            if (consistent()) then
                code = trial
                return
            end if
        end do
        call fatal_error(error, "reference: no consistent contact mode at an event (contacts "// &
                         itoa(zset(1))//" ...)", stickslip_stat%numerical)

    contains

        logical function consistent()
            real(dp) :: r, lam, acc, tol, gvel, gacc
            real(dp) :: ydot(size(yb))
            integer :: kk, c, cn
            consistent = .true.
            tol = 1.0e-9_dp
            ydot = 0.0_dp
            ydot(1:self%n) = yb(self%n + 1:2*self%n)*self%s
            ydot(self%n + 1:2*self%n) = matmul(hb, yb)
            do kk = 1, nz
                j = zset(kk)
                c = self%cs%first(j)
                cn = self%cs%normal(j)
                lam = 0.0_dp
                if (cn > 0 .and. trial(j) /= 2) then
                    lam = dot_product(fb(cn, :), yb)
                    if (lam < -tol*self%fref(j)) consistent = .false.
                end if
                select case (trial(j))
                case (0)
                    r = dot_product(fb(c, :), yb)
                    if (cn > 0) then
                        if (abs(r) > self%cmu(j)*max(lam, 0.0_dp) + tol*self%fref(j)) &
                            consistent = .false.
                    else if (abs(r) > self%limit(j)*(1.0_dp + tol)) then
                        consistent = .false.
                    end if
                case (2)
                    ! open: the gap must not close
                    gvel = dot_product(self%nt(:, j), yb(self%n + 1:2*self%n))
                    if (gvel < -tol*self%gref(j)*self%omega) then
                        consistent = .false.
                    else if (gvel <= tol*self%gref(j)*self%omega) then
                        gacc = dot_product(self%nt(:, j), ydot(self%n + 1:2*self%n))
                        if (gacc < -tol*self%gref(j)*self%omega**2) consistent = .false.
                    end if
                case default
                    if (.not. moving(kk)) then
                        acc = trial(j)*dot_product(self%wt(:, j), ydot(self%n + 1:2*self%n))
                        if (acc < -tol*self%vref(j)*self%omega) consistent = .false.
                    end if
                end select
                if (.not. consistent) return
            end do
        end function consistent
    end subroutine law_modes_at

    !> A rigid contact closing with a normal velocity (an impact) at state yb (balanced):
    !> the plastic impact with Coulomb's impulse law for contact jimp and the rigid
    !> contacts already closed (code /= 2), solved as one step of zero length
    !> (stickslip_contact_step: u+ = u- + D P, D the modal Delassus matrix of their
    !> channels, n^T v+ >= 0 _|_ P_n >= 0, the tangential impulse within mu P_n). yb's
    !> velocities are replaced by the ones after the impact; `jump` (nz x nz) is the
    !> Jacobian of the jump map of the state [p; u] for the active impulses; `loss` the
    !> kinetic energy lost [J] (>= 0).
    subroutine impact_jump(self, yb, jimp, code, jump, loss)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> State in balanced coordinates; its velocities updated.
        real(dp), intent(inout) :: yb(:)
        !> The contact that closes.
        integer, intent(in) :: jimp
        !> Codes before the impact.
        integer, intent(in) :: code(:)
        !> The Jacobian of the jump of [p; u].
        real(dp), intent(out) :: jump(:, :)
        !> Kinetic energy lost.
        real(dp), intent(out) :: loss
        integer, allocatable :: involved(:)
        real(dp), allocatable :: dirs(:, :), a(:, :), q(:), p(:), ctm(:, :), ftm(:, :), &
                                 g(:, :), l(:, :)
        type(contact_law_t), allocatable :: laws(:)
        type(contact_law_t) :: one
        integer :: n, j, k, m, sweeps, info, nz
        integer, allocatable :: ipiv(:)
        real(dp) :: ke0, resid, scale, pn, pt
        type(contact_set_t) :: impacts
        n = self%n
        nz = 2*n
        allocate (involved(0))
        do j = 1, self%nc
            if (self%cs%normal(j) == 0 .or. self%ckn(j) > 0.0_dp) cycle
            if (j == jimp .or. code(j) /= 2) involved = [involved, j]
        end do
        m = size(involved)
        allocate (dirs(n, 2*m), laws(m))
        do k = 1, m
            j = involved(k)
            dirs(:, 2*k - 1) = self%wt(:, j)
            dirs(:, 2*k) = self%nt(:, j)
            one%ntangent = 1
            one%unilateral = .true.
            one%mu = self%cmu(j)
            laws(k) = one
        end do
        a = matmul(transpose(dirs), dirs)
        q = matmul(yb(n + 1:2*n), dirs)
        allocate (p(2*m))
        p = 0.0_dp
        scale = max(maxval(abs(q))/max(maxval(abs(a)), tiny(1.0_dp)), tiny(1.0_dp))
        impacts = pair_set(m)
        call impacts%step_forces(a, q, p, scale, 1.0e-14_dp, 1000, sweeps, resid)
        ke0 = 0.5_dp*dot_product(yb(n + 1:2*n), yb(n + 1:2*n))
        yb(n + 1:2*n) = yb(n + 1:2*n) + matmul(dirs, p)
        loss = ke0 - 0.5_dp*dot_product(yb(n + 1:2*n), yb(n + 1:2*n))
        ! the jump map of the active impulses: u+ = (I - Ft (Ct^T Ft)^-1 Ct^T) u-
        allocate (ctm(n, 0), ftm(n, 0))
        do k = 1, m
            pt = p(2*k - 1)
            pn = p(2*k)
            if (pn <= 0.0_dp) cycle
            if (abs(pt) < laws(k)%mu*pn*(1.0_dp - 1.0e-9_dp)) then
                ctm = reshape([ctm, dirs(:, 2*k - 1), dirs(:, 2*k)], [n, size(ctm, 2) + 2])
                ftm = reshape([ftm, dirs(:, 2*k - 1), dirs(:, 2*k)], [n, size(ftm, 2) + 2])
            else
                ctm = reshape([ctm, dirs(:, 2*k)], [n, size(ctm, 2) + 1])
                ftm = reshape([ftm, dirs(:, 2*k) + sign(laws(k)%mu, pt)*dirs(:, 2*k - 1)], &
                              [n, size(ftm, 2) + 1])
            end if
        end do
        jump = 0.0_dp
        do k = 1, nz
            jump(k, k) = 1.0_dp
        end do
        if (size(ctm, 2) == 0) return
        g = matmul(transpose(ctm), ftm)
        l = transpose(ctm)
        allocate (ipiv(size(g, 1)))
        call dgesv(size(g, 1), n, g, size(g, 1), ipiv, l, size(g, 1), info)
        if (info /= 0) return
        jump(n + 1:nz, n + 1:nz) = jump(n + 1:nz, n + 1:nz) - matmul(ftm, l)

    contains

        !> A contact set of m unilateral 1D contacts (channels [t, n] each), for the solver.
        function pair_set(m) result(cs)
            integer, intent(in) :: m
            type(contact_set_t) :: cs
            integer :: i, k
            cs%ncontact = m
            cs%nchannel = 2*m
            cs%coulomb_only = .false.
            cs%first = [(2*i - 1, i=1, m)]
            cs%width = [(2, i=1, m)]
            cs%ntangent = [(1, i=1, m)]
            cs%normal = [(2*i, i=1, m)]
            cs%contact_of = [((i, i, k=1, 1), i=1, m)]
            cs%along = [((along_tangent, along_normal, k=1, 1), i=1, m)]
            allocate (cs%elements(m))
            do i = 1, m
                allocate (cs%elements(i)%e, source=new_unilateral_element(1, laws(i)%mu, &
                          0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp))
            end do
        end function pair_set
    end subroutine impact_jump
end module stickslip_flow_laws
