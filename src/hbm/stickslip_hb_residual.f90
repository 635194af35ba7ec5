!> The projected friction equations of the weighted-residual method and their exact
!> generalized Jacobian.
!>
!> Unknowns: the friction-force coefficients R (nb x n_c, stored contact after contact).
!> Equations: for each contact j, the Galerkin projection of Psi(r_j(t), v_j(t)) on the basis,
!> by uniform quadrature (FFT), with the contact velocities V = V0 + G R from the exact
!> condensation (stickslip_dynamics). Jacobian, with s_j(t) the stick indicator and
!> A_j = P diag(s_j) Q built from one FFT of s_j (stickslip_basis%stick_product):
!>     dF_j / dR_l = A_j G_jl + delta_jl rho (I - A_j).
module stickslip_hb_residual
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t, new_dynamics, restrict_dynamics, restrict_to_basis, &
        check_harmonics_in_basis
    use stickslip_friction, only: psi, psi_stick
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_hb_laws, only: hb_laws_t, new_hb_laws
    implicit none
    private
    public :: hb_problem_t, new_hb_problem, new_condensed_problem

    !> The projected friction equations of one model on one basis. Owns its work arrays:
    !> use one instance per thread.
    type, extends(nonlinear_system_t) :: hb_problem_t
        !> The basis (owns FFT plans: call destroy when done).
        type(basis_t) :: basis
        !> Condensed linear dynamics.
        type(dynamics_t) :: dyn
        !> Number of contacts.
        integer :: nc = 0
        !> Number of unknowns nb * n_c.
        integer :: n = 0
        !> Weight rho of Psi.
        real(dp) :: rho = 0.0_dp
        !> Friction limits mu_j N_j [N] (plain contacts; 0 for a unilateral contact).
        real(dp), allocatable :: limit(:)
        !> Every contact is plain (rigid 1D Coulomb friction under a constant normal load):
        !> the unknowns are the friction forces, one column per contact (the path of
        !> before). Otherwise `laws` holds the contact laws and the unknowns are the force
        !> channels (stickslip_hb_laws); nc is then the number of channels.
        logical :: plain = .true.
        !> The contact laws (when not plain).
        type(hb_laws_t) :: laws
        real(dp), allocatable, private :: rs(:), vs(:), ps(:), rc(:, :), vc(:, :), a(:, :)
        complex(dp), allocatable, private :: cw(:)
    contains
        procedure :: residual => hb_residual
        procedure :: jacobian => hb_jacobian
        procedure :: contact_samples
        procedure :: law_samples
        procedure :: destroy => hb_destroy
    end type hb_problem_t

contains

    !> Build the problem for `model` on the basis of highest harmonic `harmonics` (all or odd
    !> only) with `samples` quadrature points and weight `rho` > 0. Errors: stat input for
    !> bad sizes or rho, a forcing harmonic outside the basis; stat numerical for a singular
    !> dynamic stiffness (see new_dynamics).
    !> With `dyn` (the condensed dynamics of this model at its omega on this basis or on a
    !> larger one, e.g. kept by a continuation at the same omega, or the full basis of a
    !> harmonic ladder), nothing is factorized: the dynamics are copied or restricted
    !> (restrict_dynamics; stat input when its sizes, omega or harmonics do not fit).
    subroutine new_hb_problem(self, model, harmonics, odd_only, samples, rho, error, dyn)
        !> The problem.
        type(hb_problem_t), intent(out) :: self
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Highest harmonic H.
        integer, intent(in) :: harmonics
        !> Odd harmonics only.
        logical, intent(in) :: odd_only
        !> Quadrature samples per period.
        integer, intent(in) :: samples
        !> Weight rho > 0 [m/(N s)].
        real(dp), intent(in) :: rho
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Dynamics already built for `model` on this basis (not refactorized).
        type(dynamics_t), intent(in), optional :: dyn
        integer :: nb, nc, nt
        character(len=100) :: buf

        if (.not. (rho > 0.0_dp) .or. rho > huge(rho)) then
            write (buf, '(a,g0.6,a)') "rho = ", rho, ": must be finite and > 0"
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        call new_basis(self%basis, harmonics, odd_only, samples, error)
        if (allocated(error)) return
        if (present(dyn)) then
            if (dyn%ndof /= model%ndof .or. dyn%ncontact /= channel_count(model) .or. &
                .not. allocated(dyn%v0) .or. .not. (dyn%omega == model%omega)) then
                call fatal_error(error, "new_hb_problem: dyn was not built for this model "// &
                                 "(sizes or omega differ)", stickslip_stat%input)
            else if (same_harmonics(dyn, self%basis)) then
                self%dyn = dyn
            else
                call restrict_dynamics(dyn, model, self%basis, self%dyn, error)
            end if
        else
            call new_dynamics(self%dyn, model, self%basis, error)
        end if
        if (allocated(error)) then
            call self%basis%destroy()
            return
        end if
        nb = self%basis%nb
        nc = model%ncontact()
        nt = samples
        self%nc = nc
        self%n = nb*nc
        self%rho = rho
        self%limit = model%mu*model%normal_load
        allocate (self%rs(nt), self%vs(nt), self%ps(nt), self%cw(nt/2 + 1))
        allocate (self%rc(nb, nc), self%vc(nb, nc), self%a(nb, nb))
        block
            type(contact_set_t) :: cs
            call new_contact_set(cs, model)
            if (.not. cs%plain) call set_laws(self, cs, model%omega, error)
        end block
    end subroutine new_hb_problem

    !> Take the contact laws of `cs` (not plain) at omega [rad/s]: the unknowns become the
    !> force channels. Error (stat input): a unilateral contact on a basis without the
    !> constant term (its gap, preload and mean normal force need it).
    subroutine set_laws(self, cs, omega, error)
        type(hb_problem_t), intent(inout) :: self
        type(contact_set_t), intent(in) :: cs
        real(dp), intent(in) :: omega
        type(error_type), allocatable, intent(out) :: error
        integer :: j, nb, nt
        if (.not. self%basis%has_zero .and. any(cs%normal > 0)) then
            j = findloc(cs%normal > 0, .true., 1)
            call fatal_error(error, "opts%odd_only = .true.: contact "//itoa(j)//" is "// &
                             "unilateral, and its gap, preload and mean normal force need "// &
                             "the constant term of the basis; set odd_only = .false.", &
                             stickslip_stat%input)
            call self%basis%destroy()
            return
        end if
        nb = self%basis%nb
        nt = self%basis%nt
        self%plain = .false.
        self%nc = cs%nchannel
        self%n = nb*cs%nchannel
        self%limit = cs%constant_limit([(j, j=1, cs%ncontact)])
        call new_hb_laws(self%laws, cs, omega, nb, nt)
        if (allocated(self%rc)) deallocate (self%rc, self%vc)
        allocate (self%rc(nb, cs%nchannel), self%vc(nb, cs%nchannel))
    end subroutine set_laws

    !> The problem on condensed dynamics already built, without a model (the exact sparse
    !> condensation, the rungs of a harmonic ladder): `dyn` on this basis or on a larger one
    !> (restricted, restrict_to_basis), friction limits `limit` = mu_j N_j. With
    !> `force_harmonic`, those harmonics must be in the basis (as new_hb_problem checks the
    !> model's). Errors: stat input (rho, sizes, a harmonic missing from `dyn` or from the
    !> basis).
    subroutine new_condensed_problem(self, dyn, limit, harmonics, odd_only, samples, rho, &
                                     error, force_harmonic, contacts)
        !> The problem.
        type(hb_problem_t), intent(out) :: self
        !> Condensed dynamics on this basis or a larger one.
        type(dynamics_t), intent(in) :: dyn
        !> Friction limits mu_j N_j, one per contact of `dyn` [N].
        real(dp), intent(in) :: limit(:)
        !> Highest harmonic H.
        integer, intent(in) :: harmonics
        !> Odd harmonics only.
        logical, intent(in) :: odd_only
        !> Quadrature samples per period.
        integer, intent(in) :: samples
        !> Weight rho > 0 [m/(N s)].
        real(dp), intent(in) :: rho
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Harmonics of the forcing terms.
        integer, intent(in), optional :: force_harmonic(:)
        !> The contacts, when they have contact laws (then `dyn` is condensed on their
        !> channels and `limit` holds one value per contact).
        type(contact_set_t), intent(in), optional :: contacts
        integer :: nb, nc, nt
        logical :: laws
        character(len=100) :: buf
        laws = .false.
        if (present(contacts)) laws = .not. contacts%plain
        if (.not. (rho > 0.0_dp) .or. rho > huge(rho)) then
            write (buf, '(a,g0.6,a)') "rho = ", rho, ": must be finite and > 0"
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        call new_basis(self%basis, harmonics, odd_only, samples, error)
        if (allocated(error)) return
        if (present(force_harmonic)) then
            call check_harmonics_in_basis(force_harmonic, self%basis, error)
        end if
        if (.not. allocated(error)) then
            if ((.not. laws .and. size(limit) /= dyn%ncontact) .or. .not. allocated(dyn%v0)) then
                call fatal_error(error, "new_condensed_problem: limit and dyn disagree on "// &
                                 "the contacts, or dyn was not built", stickslip_stat%input)
            else if (same_harmonics(dyn, self%basis)) then
                self%dyn = dyn
            else
                call restrict_to_basis(dyn, self%basis, self%dyn, error)
            end if
        end if
        if (allocated(error)) then
            call self%basis%destroy()
            return
        end if
        nb = self%basis%nb
        nc = dyn%ncontact
        nt = samples
        self%nc = nc
        self%n = nb*nc
        self%rho = rho
        self%limit = limit
        allocate (self%rs(nt), self%vs(nt), self%ps(nt), self%cw(nt/2 + 1))
        allocate (self%rc(nb, nc), self%vc(nb, nc), self%a(nb, nb))
        if (laws) call set_laws(self, contacts, dyn%omega, error)
    end subroutine new_condensed_problem

    !> Number of force channels of a model (its contacts when plain).
    integer function channel_count(model)
        type(model_t), intent(in) :: model
        type(contact_set_t) :: cs
        call new_contact_set(cs, model)
        channel_count = cs%nchannel
    end function channel_count

    !> Whether `dyn` holds exactly the harmonics (and constant) of `basis`.
    pure logical function same_harmonics(dyn, basis)
        type(dynamics_t), intent(in) :: dyn
        type(basis_t), intent(in) :: basis
        same_harmonics = .false.
        if (.not. allocated(dyn%harm)) return
        if (size(dyn%harm) /= basis%nharm) return
        if (basis%has_zero .neqv. allocated(dyn%x0_static)) return
        same_harmonics = all(dyn%harm == basis%harm(1:basis%nharm))
    end function same_harmonics

    !> F(R): projections of Psi(r_j, v_j) for every contact [m/s]. stat is left unchanged
    !> unless a NaN appears (stat = 1).
    subroutine hb_residual(self, x, f, stat)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Friction force coefficients, contact after contact (length nb * n_c) [N].
        real(dp), intent(in) :: x(:)
        !> Projected residuals (length nb * n_c).
        real(dp), intent(out) :: f(:)
        !> Callback status.
        integer, intent(inout) :: stat
        integer :: j, nb
        if (.not. self%plain) then
            call self%laws%residual(self%basis, self%dyn, self%rho, x, f)
            if (.not. all(ieee_is_finite(f))) stat = 1
            return
        end if
        nb = self%basis%nb
        self%rc = reshape(x, [nb, self%nc])
        call self%dyn%contact_velocity(self%basis, self%rc, self%vc)
        do j = 1, self%nc
            call self%basis%synthesize(self%rc(:, j), self%rs, self%cw)
            call self%basis%synthesize(self%vc(:, j), self%vs, self%cw)
            self%ps = psi(self%rs, self%vs, self%limit(j), self%rho)
            call self%basis%analyse(self%ps, f((j - 1)*nb + 1:j*nb), self%cw)
        end do
        if (.not. all(ieee_is_finite(f))) stat = 1
    end subroutine hb_residual

    !> dF/dR, an element of the generalized (Clarke) Jacobian; exact, no finite differences.
    subroutine hb_jacobian(self, x, jac, stat)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Friction force coefficients (length nb * n_c) [N].
        real(dp), intent(in) :: x(:)
        !> Jacobian, (nb n_c) x (nb n_c).
        real(dp), intent(out) :: jac(:, :)
        !> Callback status.
        integer, intent(inout) :: stat
        integer :: j, l, nb, ih, k, rj, cl, i
        real(dp) :: gr, gi
        if (.not. self%plain) then
            call self%laws%jacobian(self%basis, self%dyn, self%rho, x, jac)
            if (.not. all(ieee_is_finite(jac))) stat = 1
            return
        end if
        nb = self%basis%nb
        self%rc = reshape(x, [nb, self%nc])
        call self%dyn%contact_velocity(self%basis, self%rc, self%vc)
        jac = 0.0_dp
        do j = 1, self%nc
            call self%basis%synthesize(self%rc(:, j), self%rs, self%cw)
            call self%basis%synthesize(self%vc(:, j), self%vs, self%cw)
            self%ps = psi_stick(self%rs, self%vs, self%limit(j), self%rho)
            call self%basis%fft%forward(self%ps, self%cw)
            self%cw = self%cw/real(self%basis%nt, dp)
            call self%basis%stick_product(self%cw, self%a)
            rj = (j - 1)*nb
            do l = 1, self%nc
                cl = (l - 1)*nb
                do ih = 1, self%basis%nharm
                    k = self%basis%icos(ih)
                    gr = real(self%dyn%g(j, l, ih), dp)
                    gi = aimag(self%dyn%g(j, l, ih))
                    jac(rj + 1:rj + nb, cl + k) = gr*self%a(:, k) - gi*self%a(:, k + 1)
                    jac(rj + 1:rj + nb, cl + k + 1) = gi*self%a(:, k) + gr*self%a(:, k + 1)
                end do
            end do
            do i = 1, nb
                jac(rj + 1:rj + nb, rj + i) = jac(rj + 1:rj + nb, rj + i) - self%rho*self%a(:, i)
                jac(rj + i, rj + i) = jac(rj + i, rj + i) + self%rho
            end do
        end do
        if (.not. all(ieee_is_finite(jac))) stat = 1
    end subroutine hb_jacobian

    !> Samples of the friction force r_j, slip velocity v_j and stick indicator s_j of every
    !> contact at the nt quadrature instants, for unknowns x.
    subroutine contact_samples(self, x, r, v, s)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Friction force coefficients (length nb * n_c) [N].
        real(dp), intent(in) :: x(:)
        !> Friction forces, nt x n_c [N].
        real(dp), intent(out) :: r(:, :)
        !> Slip velocities, nt x n_c [m/s].
        real(dp), intent(out) :: v(:, :)
        !> Stick indicators, nt x n_c.
        real(dp), intent(out) :: s(:, :)
        integer :: j, nb
        nb = self%basis%nb
        self%rc = reshape(x, [nb, self%nc])
        call self%dyn%contact_velocity(self%basis, self%rc, self%vc)
        do j = 1, self%nc
            call self%basis%synthesize(self%rc(:, j), r(:, j), self%cw)
            call self%basis%synthesize(self%vc(:, j), v(:, j), self%cw)
            s(:, j) = psi_stick(r(:, j), v(:, j), self%limit(j), self%rho)
        end do
    end subroutine contact_samples

    !> Samples of every force channel's force r and kinematic quantity u (nt x n_ch; the
    !> friction force and slip velocity of a plain contact) and of every contact's state
    !> (nt x n_c: state_open, state_stick, state_slip of stickslip_contact_law).
    subroutine law_samples(self, x, r, u, state)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Force coefficients of the channels [N].
        real(dp), intent(in) :: x(:)
        !> Channel forces [N] and kinematic quantities [m/s], nt x n_ch.
        real(dp), intent(out) :: r(:, :), u(:, :)
        !> Contact states, nt x n_c.
        integer, intent(out) :: state(:, :)
        real(dp), allocatable :: s(:, :)
        if (.not. self%plain) then
            call self%laws%samples(self%basis, self%dyn, self%rho, x, r, u, state)
            return
        end if
        allocate (s(size(r, 1), self%nc))
        call self%contact_samples(x, r, u, s)
        ! a plain contact is never open: stick or slip
        state = merge(1, 2, s > 0.5_dp)
    end subroutine law_samples

    !> Release the FFT plans of the problem's basis.
    subroutine hb_destroy(self)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        call self%basis%destroy()
    end subroutine hb_destroy
end module stickslip_hb_residual
