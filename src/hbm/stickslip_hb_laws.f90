!> The projected contact equations of the weighted residual for the contact laws beyond
!> rigid 1D Coulomb friction under a constant normal load (doc/contacts.md, section 3):
!> unilateral contact with a varying normal force, 2D friction, normal and tangential
!> contact stiffness. The unknowns are the Fourier coefficients of every force channel
!> (stickslip_contact_set), the structure is condensed on the channel directions
!> (stickslip_dynamics), and each channel's kinematic quantity u (velocity units) is affine
!> in the channel forces, per harmonic:
!>     tangential: U_h = V_h + i h omega R_h / k_t,  V_h = V0_h + G_h R  (slider velocity),
!>     normal:     U_h = V_h / (i h) + omega R_h / k_n  (omega times the gap),
!>                 U_0 = omega (gap + D^T K^-1 (F_0 + D R_0) + R_0 / k_n).
!> Residual: Psi of each contact (stickslip_contact_law) at the nt samples, analysed.
!> Jacobian, exact: J = A[ju] kappa + A[jr], A[f] = P diag(f) Q from one FFT of each nonzero
!> weight function f of the laws' generalized Jacobians, kappa the kinematic receptance
!> above. Owned work arrays: one instance per problem (per thread).
module stickslip_hb_laws
    use stickslip_kinds, only: dp
    use stickslip_basis, only: basis_t
    use stickslip_dynamics, only: dynamics_t
    use stickslip_contact_set, only: contact_set_t, channel_normal
    use stickslip_contact_law, only: contact_law_t, contact_psi, contact_psi_jacobian, &
        contact_state
    implicit none
    private
    public :: hb_laws_t, new_hb_laws

    !> The contact laws of a weighted-residual problem and their work arrays.
    type :: hb_laws_t
        !> The contacts and their channels.
        type(contact_set_t) :: cs
        !> Fundamental angular frequency [rad/s].
        real(dp) :: omega = 0.0_dp
        !> Per channel: is a normal channel; its gap [m]; tangential compliance 1/k_t and
        !> normal compliance 1/k_n [m/N] (0: rigid, or not that kind of channel).
        logical, allocatable :: normal(:)
        real(dp), allocatable :: gap(:), ct(:), cn(:)
        !> The law of each contact.
        type(contact_law_t), allocatable :: law(:)
        real(dp), allocatable, private :: vc(:, :), uc(:, :), rs(:, :), us(:, :), ps(:, :), &
                                          ju(:, :, :), jr(:, :, :), a(:, :), dr(:)
        complex(dp), allocatable, private :: cw(:)
    contains
        procedure :: kinematics
        procedure :: residual => laws_residual
        procedure :: jacobian => laws_jacobian
        procedure :: samples => laws_samples
    end type hb_laws_t

contains

    !> The laws of contact set `cs` at angular frequency `omega` [rad/s] on a basis of nb
    !> functions and nt samples. No error can occur.
    subroutine new_hb_laws(self, cs, omega, nb, nt)
        !> The laws.
        type(hb_laws_t), intent(out) :: self
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> Fundamental angular frequency [rad/s].
        real(dp), intent(in) :: omega
        !> Basis functions and samples per period.
        integer, intent(in) :: nb, nt
        integer :: j, c, nch
        self%cs = cs
        self%omega = omega
        nch = cs%nchannel
        allocate (self%normal(nch), self%gap(nch), self%ct(nch), self%cn(nch), &
                  self%law(cs%ncontact))
        self%normal = cs%kind == channel_normal
        self%gap = 0.0_dp
        self%ct = 0.0_dp
        self%cn = 0.0_dp
        do j = 1, cs%ncontact
            self%law(j) = cs%law(j)
            do c = cs%first(j), cs%first(j) + cs%width(j) - 1
                if (self%normal(c)) then
                    self%gap(c) = cs%gap(j)
                    if (cs%kn(j) > 0.0_dp) self%cn(c) = 1.0_dp/cs%kn(j)
                else if (cs%kt(j) > 0.0_dp) then
                    self%ct(c) = 1.0_dp/cs%kt(j)
                end if
            end do
        end do
        allocate (self%vc(nb, nch), self%uc(nb, nch), self%rs(nt, 3), self%us(nt, 3), &
                  self%ps(nt, 3), self%ju(3, 3, nt), self%jr(3, 3, nt), self%a(nb, nb), &
                  self%dr(nb), self%cw(nt/2 + 1))
    end subroutine new_hb_laws

    !> The kinematic coefficients U (nb x n_ch) of the channel forces R (nb x n_ch) [m/s]:
    !> slider velocities of the tangential channels, omega times the gap (plus the normal
    !> compliance) of the normal ones.
    subroutine kinematics(self, basis, dyn, rc, uc)
        !> The laws.
        class(hb_laws_t), intent(inout) :: self
        !> The basis.
        type(basis_t), intent(in) :: basis
        !> The condensed dynamics on the channels.
        type(dynamics_t), intent(in) :: dyn
        !> Channel force coefficients, nb x n_ch [N].
        real(dp), intent(in) :: rc(:, :)
        !> Kinematic coefficients, nb x n_ch [m/s].
        real(dp), intent(out) :: uc(:, :)
        integer :: c, ih, k, i0
        real(dp) :: h
        call dyn%contact_velocity(basis, rc, self%vc)
        i0 = basis%i0
        do c = 1, size(rc, 2)
            if (.not. self%normal(c)) then
                uc(:, c) = self%vc(:, c)
                if (self%ct(c) > 0.0_dp) then
                    call basis%derivative(rc(:, c), self%omega, self%dr)
                    uc(:, c) = uc(:, c) + self%ct(c)*self%dr
                end if
            else
                ! omega times the displacement: the velocity integrated per harmonic
                do ih = 1, basis%nharm
                    k = basis%icos(ih)
                    h = real(basis%harm(ih), dp)
                    uc(k, c) = -self%vc(k + 1, c)/h
                    uc(k + 1, c) = self%vc(k, c)/h
                end do
                if (basis%has_zero) uc(i0, c) = self%omega*(self%gap(c) + dyn%u_static(c) + &
                                                            dot_product(dyn%g_static(c, :), rc(i0, :)))
                uc(:, c) = uc(:, c) + self%omega*self%cn(c)*rc(:, c)
            end if
        end do
    end subroutine kinematics

    !> F(R): the projections of Psi of every contact [m/s], f of length nb n_ch.
    subroutine laws_residual(self, basis, dyn, rho, x, f)
        !> The laws.
        class(hb_laws_t), intent(inout) :: self
        !> The basis.
        type(basis_t), intent(inout) :: basis
        !> The condensed dynamics on the channels.
        type(dynamics_t), intent(in) :: dyn
        !> Weight of the equalities [m/(N s)].
        real(dp), intent(in) :: rho
        !> Channel force coefficients, channel after channel [N].
        real(dp), intent(in) :: x(:)
        !> Projected residuals.
        real(dp), intent(out) :: f(:)
        integer :: j, c, m, k, nb, nt, c0
        nb = basis%nb
        nt = basis%nt
        call self%kinematics(basis, dyn, reshape(x, [nb, self%cs%nchannel]), self%uc)
        do j = 1, self%cs%ncontact
            c0 = self%cs%first(j) - 1
            m = self%cs%width(j)
            do c = 1, m
                call basis%synthesize(x((c0 + c - 1)*nb + 1:(c0 + c)*nb), self%rs(:, c), self%cw)
                call basis%synthesize(self%uc(:, c0 + c), self%us(:, c), self%cw)
            end do
            do k = 1, nt
                call contact_psi(self%law(j), rho, self%rs(k, 1:m), self%us(k, 1:m), &
                                 self%ps(k, 1:m))
            end do
            do c = 1, m
                call basis%analyse(self%ps(:, c), f((c0 + c - 1)*nb + 1:(c0 + c)*nb), self%cw)
            end do
        end do
    end subroutine laws_residual

    !> dF/dR, an element of the generalized Jacobian, (nb n_ch) x (nb n_ch); exact.
    subroutine laws_jacobian(self, basis, dyn, rho, x, jac)
        !> The laws.
        class(hb_laws_t), intent(inout) :: self
        !> The basis.
        type(basis_t), intent(inout) :: basis
        !> The condensed dynamics on the channels.
        type(dynamics_t), intent(in) :: dyn
        !> Weight of the equalities [m/(N s)].
        real(dp), intent(in) :: rho
        !> Channel force coefficients [N].
        real(dp), intent(in) :: x(:)
        !> The Jacobian.
        real(dp), intent(out) :: jac(:, :)
        integer :: j, a, b, c, m, k, nb, nt, c0, ra, cb, ih, kk, col, nch, i0
        real(dp) :: w(basis%nt)
        complex(dp) :: kap
        nb = basis%nb
        nt = basis%nt
        nch = self%cs%nchannel
        i0 = basis%i0
        call self%kinematics(basis, dyn, reshape(x, [nb, nch]), self%uc)
        jac = 0.0_dp
        do j = 1, self%cs%ncontact
            c0 = self%cs%first(j) - 1
            m = self%cs%width(j)
            do c = 1, m
                call basis%synthesize(x((c0 + c - 1)*nb + 1:(c0 + c)*nb), self%rs(:, c), self%cw)
                call basis%synthesize(self%uc(:, c0 + c), self%us(:, c), self%cw)
            end do
            do k = 1, nt
                call contact_psi_jacobian(self%law(j), rho, self%rs(k, 1:m), self%us(k, 1:m), &
                                          self%ps(k, 1:m), self%jr(1:m, 1:m, k), &
                                          self%ju(1:m, 1:m, k))
            end do
            do a = 1, m
                ra = (c0 + a - 1)*nb
                do b = 1, m
                    ! d Psi_a / d u_b, through the kinematic receptance of channel b
                    w = self%ju(a, b, :)
                    if (any(w /= 0.0_dp)) then
                        call product_matrix()
                        cb = c0 + b
                        do c = 1, nch
                            col = (c - 1)*nb
                            do ih = 1, basis%nharm
                                kk = basis%icos(ih)
                                kap = receptance(cb, c, ih)
                                jac(ra + 1:ra + nb, col + kk) = jac(ra + 1:ra + nb, col + kk) + &
                                    real(kap, dp)*self%a(:, kk) - aimag(kap)*self%a(:, kk + 1)
                                jac(ra + 1:ra + nb, col + kk + 1) = &
                                    jac(ra + 1:ra + nb, col + kk + 1) + &
                                    aimag(kap)*self%a(:, kk) + real(kap, dp)*self%a(:, kk + 1)
                            end do
                            if (basis%has_zero .and. self%normal(cb)) then
                                kap = self%omega*dyn%g_static(cb, c)
                                if (c == cb) kap = kap + self%omega*self%cn(cb)
                                jac(ra + 1:ra + nb, col + i0) = jac(ra + 1:ra + nb, col + i0) + &
                                    real(kap, dp)*self%a(:, i0)
                            end if
                        end do
                    end if
                    ! d Psi_a / d r_b directly
                    w = self%jr(a, b, :)
                    if (any(w /= 0.0_dp)) then
                        call product_matrix()
                        col = (c0 + b - 1)*nb
                        jac(ra + 1:ra + nb, col + 1:col + nb) = &
                            jac(ra + 1:ra + nb, col + 1:col + nb) + self%a
                    end if
                end do
            end do
        end do

    contains

        !> self%a = P diag(w) Q, from one FFT of the weight function w (the host's; the
        !> transform may overwrite it).
        subroutine product_matrix()
            call basis%fft%forward(w, self%cw)
            self%cw = self%cw/real(nt, dp)
            call basis%stick_product(self%cw, self%a)
        end subroutine product_matrix

        !> Kinematic receptance of channel b to the force of channel c at harmonic ih.
        complex(dp) function receptance(b, c, ih) result(kap)
            integer, intent(in) :: b, c, ih
            real(dp) :: hw
            hw = basis%harm(ih)*self%omega
            if (self%normal(b)) then
                kap = dyn%g(b, c, ih)/cmplx(0.0_dp, real(basis%harm(ih), dp), dp)
                if (b == c) kap = kap + self%omega*self%cn(b)
            else
                kap = dyn%g(b, c, ih)
                if (b == c) kap = kap + cmplx(0.0_dp, hw*self%ct(b), dp)
            end if
        end function receptance
    end subroutine laws_jacobian

    !> Samples of every channel's force r and kinematic quantity u (nt x n_ch) and of every
    !> contact's state (nt x n_c: state_open, state_stick, state_slip) for unknowns x.
    subroutine laws_samples(self, basis, dyn, rho, x, r, u, state)
        !> The laws.
        class(hb_laws_t), intent(inout) :: self
        !> The basis.
        type(basis_t), intent(inout) :: basis
        !> The condensed dynamics on the channels.
        type(dynamics_t), intent(in) :: dyn
        !> Weight of the equalities [m/(N s)].
        real(dp), intent(in) :: rho
        !> Channel force coefficients [N].
        real(dp), intent(in) :: x(:)
        !> Channel forces [N] and kinematic quantities [m/s] at the samples.
        real(dp), intent(out) :: r(:, :), u(:, :)
        !> Contact states at the samples.
        integer, intent(out) :: state(:, :)
        integer :: j, c, k, nb, m, c0
        nb = basis%nb
        call self%kinematics(basis, dyn, reshape(x, [nb, self%cs%nchannel]), self%uc)
        do c = 1, self%cs%nchannel
            call basis%synthesize(x((c - 1)*nb + 1:c*nb), r(:, c), self%cw)
            call basis%synthesize(self%uc(:, c), u(:, c), self%cw)
        end do
        do j = 1, self%cs%ncontact
            c0 = self%cs%first(j)
            m = self%cs%width(j)
            do k = 1, basis%nt
                state(k, j) = contact_state(self%law(j), rho, r(k, c0:c0 + m - 1), &
                                            u(k, c0:c0 + m - 1))
            end do
        end do
    end subroutine laws_samples
end module stickslip_hb_laws
