!> The projected contact equations of the weighted-residual method and their exact
!> generalized Jacobian, for every contact element (stickslip_contact_element).
!>
!> Unknowns: the Fourier coefficients of every force channel (nb x n_ch, stored channel after
!> channel; for Coulomb contacts the friction forces, one channel per contact). The structure
!> is condensed on the channel directions (stickslip_dynamics: V = V0 + G R), and each
!> channel's kinematic quantity u is affine in the channel forces, per harmonic
!> (channel_t%kinematics):
!>     velocity: U_h = V_h + i h omega c R_h          (c the channel's compliance),
!>     gap:      U_h = V_h / (i h) + omega c R_h,
!>               U_0 = omega (gap + D^T K^-1 (F_0 + D R_0) + c R_0).
!> Residual: each element's Psi at the nt samples of its channels' r and u, analysed
!> (uniform quadrature, FFT). Jacobian: each element's rows, J = A[ju] kappa + A[jr] with
!> A[f] = P diag(f) Q from one FFT of each nonzero weight function f of its generalized
!> Jacobians and kappa the receptance above (contact_element_t%hb_jacobian; a Coulomb contact
!> uses its own batched form, A G + rho (I - A) from one FFT of the stick indicator).
module stickslip_hb_residual
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t, new_dynamics, restrict_dynamics, restrict_to_basis, &
        check_harmonics_in_basis
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_contact_element, only: hb_work_t, channel_t, kinematics_gap, &
        kinematics_velocity, along_normal
    implicit none
    private
    public :: hb_problem_t, new_hb_problem, new_condensed_problem

    !> The projected contact equations of one model on one basis. Owns its work arrays: use
    !> one instance per thread.
    type, extends(nonlinear_system_t) :: hb_problem_t
        !> The basis (owns FFT plans: call destroy when done).
        type(basis_t) :: basis
        !> Condensed linear dynamics on the channels (its omega is the problem's).
        type(dynamics_t) :: dyn
        !> The contact elements and their channels.
        type(contact_set_t) :: contacts
        !> Number of force channels n_ch (the contacts of a Coulomb-only set).
        integer :: nc = 0
        !> Number of unknowns nb * n_ch.
        integer :: n = 0
        !> Weight rho of Psi [m/(N s)].
        real(dp) :: rho = 0.0_dp
        real(dp), allocatable, private :: rs(:, :), us(:, :), ps(:, :), rc(:, :), uc(:, :), &
                                          vc(:, :), dr(:), kap0(:, :)
        complex(dp), allocatable, private :: cw(:), kap(:, :, :)
        type(hb_work_t), private :: work
    contains
        procedure :: residual => hb_residual
        procedure :: jacobian => hb_jacobian
        procedure :: kinematics
        procedure :: law_samples
        procedure :: tangential_mean_rows
        procedure :: destroy => hb_destroy
    end type hb_problem_t

contains

    !> Build the problem for `model` on the basis of highest harmonic `harmonics` (all or odd
    !> only) with `samples` quadrature points and weight `rho` > 0. Errors: stat input for
    !> bad sizes or rho, a forcing harmonic outside the basis, odd harmonics only with a
    !> contact whose law needs the constant term (a gap channel); stat numerical for a
    !> singular dynamic stiffness (see new_dynamics).
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
        type(contact_set_t) :: cs

        call check_rho(rho, error)
        if (allocated(error)) return
        call new_contact_set(cs, model)
        call new_basis(self%basis, harmonics, odd_only, samples, error)
        if (allocated(error)) return
        if (present(dyn)) then
            if (dyn%ndof /= model%ndof .or. dyn%ncontact /= cs%nchannel .or. &
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
        call set_contacts(self, cs, rho, error)
    end subroutine new_hb_problem

    !> The problem on condensed dynamics already built, without a model (the exact sparse
    !> condensation, the rungs of a harmonic ladder): `dyn` (condensed on the channels of
    !> `contacts`) on this basis or on a larger one (restricted, restrict_to_basis). With
    !> `force_harmonic`, those harmonics must be in the basis (as new_hb_problem checks the
    !> model's). Errors: stat input (rho, sizes, a harmonic missing from `dyn` or from the
    !> basis, odd harmonics only with a gap channel).
    subroutine new_condensed_problem(self, dyn, contacts, harmonics, odd_only, samples, rho, &
                                     error, force_harmonic)
        !> The problem.
        type(hb_problem_t), intent(out) :: self
        !> Condensed dynamics on this basis or a larger one.
        type(dynamics_t), intent(in) :: dyn
        !> The contacts (dyn is condensed on their channels).
        type(contact_set_t), intent(in) :: contacts
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
        call check_rho(rho, error)
        if (allocated(error)) return
        call new_basis(self%basis, harmonics, odd_only, samples, error)
        if (allocated(error)) return
        if (present(force_harmonic)) then
            call check_harmonics_in_basis(force_harmonic, self%basis, error)
        end if
        if (.not. allocated(error)) then
            if (contacts%nchannel /= dyn%ncontact .or. .not. allocated(dyn%v0)) then
                call fatal_error(error, "new_condensed_problem: the contacts' channels and "// &
                                 "dyn disagree, or dyn was not built", stickslip_stat%input)
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
        call set_contacts(self, contacts, rho, error)
    end subroutine new_condensed_problem

    !> rho finite and > 0 (stat input).
    subroutine check_rho(rho, error)
        real(dp), intent(in) :: rho
        type(error_type), allocatable, intent(out) :: error
        character(len=100) :: buf
        if (.not. (rho > 0.0_dp) .or. rho > huge(rho)) then
            write (buf, '(a,g0.6,a)') "rho = ", rho, ": must be finite and > 0"
            call fatal_error(error, trim(buf), stickslip_stat%input)
        end if
    end subroutine check_rho

    !> Take the contacts (the unknowns are their channels) and allocate the work arrays.
    !> Error (stat input): a gap channel on a basis without the constant term (its gap,
    !> preload and mean normal force need it).
    subroutine set_contacts(self, cs, rho, error)
        type(hb_problem_t), intent(inout) :: self
        type(contact_set_t), intent(in) :: cs
        real(dp), intent(in) :: rho
        type(error_type), allocatable, intent(out) :: error
        integer :: c, nb, nt, nch, mw
        type(channel_t) :: ch
        nch = cs%nchannel
        if (.not. self%basis%has_zero) then
            do c = 1, nch
                ch = cs%channel(c)
                if (ch%kinematics == kinematics_gap) then
                    call fatal_error(error, "opts%odd_only = .true.: contact "// &
                                     itoa(cs%contact_of(c))//" is unilateral, and its gap, "// &
                                     "preload and mean normal force need the constant term "// &
                                     "of the basis; set odd_only = .false.", &
                                     stickslip_stat%input)
                    call self%basis%destroy()
                    return
                end if
            end do
        end if
        self%contacts = cs
        nb = self%basis%nb
        nt = self%basis%nt
        self%nc = nch
        self%n = nb*nch
        self%rho = rho
        mw = 1
        if (cs%ncontact > 0) mw = maxval(cs%width)
        allocate (self%rs(nt, mw), self%us(nt, mw), self%ps(nt, mw), self%rc(nb, nch), &
                  self%uc(nb, nch), self%vc(nb, nch), self%dr(nb), self%cw(nt/2 + 1), &
                  self%kap(mw, nch, self%basis%nharm), self%kap0(mw, nch))
        allocate (self%work%a(nb, nb), self%work%w(nt), self%work%cw(nt/2 + 1))
    end subroutine set_contacts

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

    !> The kinematic coefficients U (nb x n_ch) of the channel forces R (nb x n_ch) [m/s]:
    !> (slider) velocities of the velocity channels, omega times the gap (with the normal
    !> compliance) of the gap channels.
    subroutine kinematics(self, rc, uc)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Channel force coefficients, nb x n_ch [N].
        real(dp), intent(in) :: rc(:, :)
        !> Kinematic coefficients, nb x n_ch [m/s].
        real(dp), intent(out) :: uc(:, :)
        integer :: c, ih, k, i0
        real(dp) :: h, omega
        type(channel_t) :: ch
        call self%dyn%contact_velocity(self%basis, rc, self%vc)
        i0 = self%basis%i0
        omega = self%dyn%omega
        do c = 1, size(rc, 2)
            ch = self%contacts%channel(c)
            if (ch%kinematics == kinematics_velocity) then
                uc(:, c) = self%vc(:, c)
                if (ch%compliance > 0.0_dp) then
                    call self%basis%derivative(rc(:, c), omega, self%dr)
                    uc(:, c) = uc(:, c) + ch%compliance*self%dr
                end if
            else
                ! omega times the displacement: the velocity integrated per harmonic
                do ih = 1, self%basis%nharm
                    k = self%basis%icos(ih)
                    h = real(self%basis%harm(ih), dp)
                    uc(k, c) = -self%vc(k + 1, c)/h
                    uc(k + 1, c) = self%vc(k, c)/h
                end do
                if (self%basis%has_zero) uc(i0, c) = omega*(ch%gap + self%dyn%u_static(c) + &
                                                            dot_product(self%dyn%g_static(c, :), &
                                                                        rc(i0, :)))
                uc(:, c) = uc(:, c) + omega*ch%compliance*rc(:, c)
            end if
        end do
    end subroutine kinematics

    !> F(R): projections of every element's Psi [m/s]. stat is left unchanged unless a NaN
    !> appears (stat = 1).
    subroutine hb_residual(self, x, f, stat)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Channel force coefficients, channel after channel (length nb * n_ch) [N].
        real(dp), intent(in) :: x(:)
        !> Projected residuals (length nb * n_ch).
        real(dp), intent(out) :: f(:)
        !> Callback status.
        integer, intent(inout) :: stat
        integer :: j, c, m, nb, c0
        nb = self%basis%nb
        self%rc = reshape(x, [nb, self%nc])
        call self%kinematics(self%rc, self%uc)
        do j = 1, self%contacts%ncontact
            c0 = self%contacts%first(j) - 1
            m = self%contacts%width(j)
            call sample_channels(self, c0, m)
            call self%contacts%elements(j)%e%psi(self%rho, self%rs(:, 1:m), self%us(:, 1:m), &
                                                 self%ps(:, 1:m))
            do c = 1, m
                call self%basis%analyse(self%ps(:, c), f((c0 + c - 1)*nb + 1:(c0 + c)*nb), &
                                        self%cw)
            end do
        end do
        if (.not. all(ieee_is_finite(f))) stat = 1
    end subroutine hb_residual

    !> The samples of channels c0+1..c0+m: forces into rs, kinematic quantities into us.
    subroutine sample_channels(self, c0, m)
        type(hb_problem_t), intent(inout) :: self
        integer, intent(in) :: c0, m
        integer :: c
        do c = 1, m
            call self%basis%synthesize(self%rc(:, c0 + c), self%rs(:, c), self%cw)
            call self%basis%synthesize(self%uc(:, c0 + c), self%us(:, c), self%cw)
        end do
    end subroutine sample_channels

    !> dF/dR, an element of the generalized (Clarke) Jacobian; exact, no finite differences.
    subroutine hb_jacobian(self, x, jac, stat)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Channel force coefficients (length nb * n_ch) [N].
        real(dp), intent(in) :: x(:)
        !> Jacobian, (nb n_ch) x (nb n_ch).
        real(dp), intent(out) :: jac(:, :)
        !> Callback status.
        integer, intent(inout) :: stat
        integer :: j, m, nb, c0, b, c, ih
        real(dp) :: omega, hw
        type(channel_t) :: ch
        nb = self%basis%nb
        omega = self%dyn%omega
        self%rc = reshape(x, [nb, self%nc])
        call self%kinematics(self%rc, self%uc)
        jac = 0.0_dp
        do j = 1, self%contacts%ncontact
            c0 = self%contacts%first(j) - 1
            m = self%contacts%width(j)
            call sample_channels(self, c0, m)
            ! the receptance of the element's kinematic quantities to every channel force
            do b = 1, m
                ch = self%contacts%channel(c0 + b)
                do ih = 1, self%basis%nharm
                    hw = self%basis%harm(ih)*omega
                    if (ch%kinematics == kinematics_gap) then
                        self%kap(b, :, ih) = self%dyn%g(c0 + b, :, ih)/ &
                                             cmplx(0.0_dp, real(self%basis%harm(ih), dp), dp)
                        self%kap(b, c0 + b, ih) = self%kap(b, c0 + b, ih) + omega*ch%compliance
                    else
                        self%kap(b, :, ih) = self%dyn%g(c0 + b, :, ih)
                        if (ch%compliance > 0.0_dp) self%kap(b, c0 + b, ih) = &
                            self%kap(b, c0 + b, ih) + cmplx(0.0_dp, hw*ch%compliance, dp)
                    end if
                end do
                self%kap0(b, :) = 0.0_dp
                if (self%basis%has_zero .and. ch%kinematics == kinematics_gap) then
                    do c = 1, self%nc
                        self%kap0(b, c) = omega*self%dyn%g_static(c0 + b, c)
                    end do
                    self%kap0(b, c0 + b) = self%kap0(b, c0 + b) + omega*ch%compliance
                end if
            end do
            call self%contacts%elements(j)%e%hb_jacobian(self%basis, self%rho, &
                                                         self%rs(:, 1:m), self%us(:, 1:m), &
                                                         self%kap(1:m, :, :), &
                                                         self%kap0(1:m, :), c0 + 1, &
                                                         jac(c0*nb + 1:(c0 + m)*nb, :), &
                                                         self%work)
        end do
        if (.not. all(ieee_is_finite(jac))) stat = 1
    end subroutine hb_jacobian

    !> Samples of every force channel's force r and kinematic quantity u (nt x n_ch; the
    !> friction force and slip velocity of a Coulomb contact) and of every contact's state
    !> (nt x n_c: state_open, state_stick, state_slip), for unknowns x.
    subroutine law_samples(self, x, r, u, state)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        !> Force coefficients of the channels [N].
        real(dp), intent(in) :: x(:)
        !> Channel forces [N] and kinematic quantities [m/s], nt x n_ch.
        real(dp), intent(out) :: r(:, :), u(:, :)
        !> Contact states, nt x n_c.
        integer, intent(out) :: state(:, :)
        integer :: j, c, nb, c0, m
        nb = self%basis%nb
        self%rc = reshape(x, [nb, self%nc])
        call self%kinematics(self%rc, self%uc)
        do c = 1, self%nc
            call self%basis%synthesize(self%rc(:, c), r(:, c), self%cw)
            call self%basis%synthesize(self%uc(:, c), u(:, c), self%cw)
        end do
        do j = 1, self%contacts%ncontact
            c0 = self%contacts%first(j)
            m = self%contacts%width(j)
            call self%contacts%elements(j)%e%states(self%rho, r(:, c0:c0 + m - 1), &
                                                    u(:, c0:c0 + m - 1), state(:, j))
        end do
    end subroutine law_samples

    !> The rows (and columns) of the tangential channels' mean forces among the unknowns
    !> (channel c's constant term, (c - 1) nb + i0); none when the basis has no constant.
    !> A contact stuck all period leaves these free: the families pin them.
    function tangential_mean_rows(self) result(rows)
        !> The problem.
        class(hb_problem_t), intent(in) :: self
        integer, allocatable :: rows(:)
        integer :: c
        allocate (rows(0))
        if (self%basis%i0 <= 0) return
        rows = pack([((c - 1)*self%basis%nb + self%basis%i0, c=1, self%nc)], &
                    self%contacts%along(1:self%nc) /= along_normal)
    end function tangential_mean_rows

    !> Release the FFT plans of the problem's basis.
    subroutine hb_destroy(self)
        !> The problem.
        class(hb_problem_t), intent(inout) :: self
        call self%basis%destroy()
    end subroutine hb_destroy
end module stickslip_hb_residual
