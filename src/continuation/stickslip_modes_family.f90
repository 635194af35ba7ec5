!> The nonlinear modes of a friction-damped structure as a family in the modal amplitude:
!> the extended periodic motion concept (EPMC, Krack 2015) on the equality formulation of
!> the friction laws. The autonomous structure gets a negative modal damping term that
!> balances what the contacts (and the viscous damping) dissipate:
!>     M x'' + (C - xi M) x' + K x = W r(t),   Psi(r, v) = 0 at every contact,
!> and its periodic motions are sought at each modal amplitude a, the amplitude of the
!> fundamental harmonic in the mass norm: a^2 = c1^T M c1 + s1^T M s1 (x(t) = a phi cos(omega
!> t) + ... for a mass-normalized phi). A phase condition phi_ref^T M s1 = 0 fixes the time
!> origin (phi_ref: the linear mode the family starts from). The modal damping ratio is
!> D = xi / (2 omega).
!>
!> Unknowns y = [R; omega; xi], R the friction-force (channel) coefficients of the same
!> condensed weighted residual as a forced solve (stickslip_hb_residual: the dynamics
!> Z_h = K - (h omega)^2 M + i h omega (C - xi M) eliminated exactly, no forcing);
!> parameter lambda = ln a. Equations: the projected friction laws; v_s (Q / a^2 - 1) = 0
!> with Q = c1^T M c1 + s1^T M s1; v_s phi_ref^T M s1 / a = 0; v_s = v_ref a the velocity
!> scale of the mode (v_ref = omega_ref max |phi_ref|), so that every row is a velocity.
!> Jacobian: dF/dR the exact generalized one, the normalization rows analytic in R (x1 is
!> linear in R1: X1 = Y1 (R_cos - i R_sin)), dF/domega and dF/dxi by central differences
!> (each a new factorization of the Z_h), dF/dlambda analytic. A structure with plain
!> contacts and no static load vibrates half-wave symmetrically: its family uses the odd
!> harmonics only (the constant and even terms vanish, and the mean force of a stuck
!> contact, which nothing determines, is not an unknown). With contact laws the basis keeps
!> the constant (the mean normal force holds the preload); a tangential mean force, which
!> nothing determines while its contact sticks all period (a singular direction of dF/dR
!> that would leave the continuation's tangent undefined), gets a Tikhonov term
!> mean_weight rho R_0 in its row.
!>
!> On one sector of a tuned bladed disk (`cyclic`, its engine order the nodal diameter nd of
!> the mode) the family is the mode's travelling wave: the same equations on the sector's
!> cyclic condensation (new_cyclic_dynamics: sector s moves as sector 0 delayed by nd s / N
!> of the period), the amplitude a^2 = X1^H M X1 over the sector's DOFs (its share of the
!> disk's), and the phase condition Im(phi_ref^H M X1) = 0 with the complex cyclic mode
!> phi_ref (for a real phi_ref: phi_ref^T M s1 = 0 as above).
module stickslip_modes_family
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem, new_condensed_problem
    use stickslip_dynamics, only: dynamics_t, new_dynamics
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_cyclic, only: cyclic_t, sector_phase, cyclic_directions, cyclic_basis
    use stickslip_cyclic_dynamics, only: new_cyclic_dynamics
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_continuation, only: parametric_system_t
    implicit none
    private
    public :: modes_family_t, new_modes_family, free_structure, mean_weight

    !> The weight of the tangential mean forces' Tikhonov term (modes_family_t%mean_weight):
    !> small enough to leave a determined mean force (one with slip phases) unchanged to
    !> about this relative size, large enough to pin an undetermined one.
    real(dp), parameter :: mean_weight = 1.0e-8_dp

    !> The nonlinear-mode equations as a family in lambda = ln a.
    type, extends(parametric_system_t) :: modes_family_t
        !> The free structure (no forcing terms) with its viscous damping C.
        type(model_t) :: model
        !> Basis options in effect (rho > 0; odd harmonics for plain contacts).
        type(hbm_options_t) :: opts
        !> The projected friction equations at (omega, xi) = (current_omega, current_xi).
        type(hb_problem_t) :: prob
        real(dp) :: current_omega = -1.0_dp, current_xi = 0.0_dp
        logical :: have_current = .false.
        !> The reference shape of the phase condition (mass-normalized; complex on a sector)
        !> and M phi_ref.
        complex(dp), allocatable :: phi(:), mphi(:)
        !> The disk when the model is one sector of it (engine order: the mode's nodal
        !> diameter); unallocated: a whole structure.
        type(cyclic_t), allocatable :: cyclic
        !> Velocity scale per unit modal amplitude [1/s]: omega_ref max |phi_ref|.
        real(dp) :: vref = 1.0_dp
        !> Basis indices of cos(omega t) and sin(omega t), and the column of harmonic 1 in
        !> the dynamics' per-harmonic arrays.
        integer :: ic1 = 0, is1 = 0, ih1 = 0
        !> Friction-force unknowns nb x channels.
        integer :: n = 0
        !> Factorizations of the dynamic stiffnesses so far (one per (omega, xi) met).
        integer :: factorizations = 0
        !> Tikhonov weight of the tangential mean forces (contact laws with the constant in
        !> the basis): mean_weight rho R_0 is added to the rows of their constant terms, so
        !> that a contact stuck all period, whose mean force nothing determines, keeps
        !> R_0 = 0 and the curve a unique tangent [dimensionless].
        real(dp) :: mean_weight = 0.0_dp
        integer, allocatable :: mean_rows(:)
    contains
        procedure :: residual => modes_residual
        procedure :: jacobian => modes_jacobian
        procedure :: residual_scale => modes_scale
        procedure :: set => modes_set
        procedure :: harmonic_one => modes_harmonic_one
        procedure :: destroy => modes_destroy
    end type modes_family_t

contains

    !> `model` without its harmonic forcing terms: the free structure whose modes are sought,
    !> its static loads (force_harmonic = 0: a centrifugal load pressing a damper) kept.
    function free_structure(model) result(m)
        !> A validated model.
        type(model_t), intent(in) :: model
        type(model_t) :: m
        logical, allocatable :: static(:)
        integer :: k
        m = model
        static = model%force_harmonic == 0
        if (allocated(model%force_shape)) then
            m%force_shape = model%force_shape(:, pack([(k, k=1, size(static))], static))
        else if (allocated(model%force_dof)) then
            m%force_dof = pack(model%force_dof, static)
        end if
        m%force_harmonic = pack(model%force_harmonic, static)
        m%force_amplitude = pack(model%force_amplitude, static)
        m%force_phase = pack(model%force_phase, static)
    end function free_structure

    !> Build the family of `model` (its forcing is ignored) on the basis of `hbm` (rho > 0;
    !> odd harmonics only unless a contact needs the constant term), phase-referenced to the
    !> mass-normalized shape `phi` of frequency `omega_ref` [rad/s]; with `cyclic`, of the
    !> sector `model` of that disk (phi its complex cyclic mode). Errors: as new_hb_problem
    !> and new_cyclic_dynamics (stat numerical: a singular dynamic stiffness at omega_ref).
    subroutine new_modes_family(fam, model, hbm, phi, omega_ref, error, cyclic)
        !> The family.
        type(modes_family_t), intent(out) :: fam
        !> A validated model with contacts.
        type(model_t), intent(in) :: model
        !> Basis options (rho > 0).
        type(hbm_options_t), intent(in) :: hbm
        !> Reference shape (N), mass-normalized.
        complex(dp), intent(in) :: phi(:)
        !> Its frequency [rad/s] (> 0).
        real(dp), intent(in) :: omega_ref
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The disk of which `model` is a sector.
        type(cyclic_t), intent(in), optional :: cyclic
        type(contact_set_t) :: cs
        integer :: k, nb
        type(model_t) :: m
        type(basis_t) :: basis
        type(dynamics_t) :: dyn
        fam%model = free_structure(model)
        fam%model%omega = omega_ref
        fam%opts = hbm
        call new_contact_set(cs, fam%model)
        ! the odd harmonics unless a contact needs the constant term (a gap channel: its gap,
        ! preload and mean normal force) or the structure carries a static load
        fam%opts%odd_only = .not. cs%needs_constant() .and. fam%model%nforce() == 0
        ! built at (omega_ref, xi = 0.01 omega_ref): omega_ref may be a natural frequency of
        ! the undamped structure (the slipping limit), where Z_1 is singular without damping
        m = fam%model
        m%damping = m%damping - 0.01_dp*omega_ref*m%mass
        if (present(cyclic)) then
            fam%cyclic = cyclic
            call new_basis(basis, fam%opts%harmonics, fam%opts%odd_only, fam%opts%samples, &
                           error)
            if (allocated(error)) return
            call new_cyclic_dynamics(dyn, fam%model, cyclic, basis, error, &
                                     mass_damping=0.01_dp*omega_ref)
            call basis%destroy()
            if (allocated(error)) return
            call new_condensed_problem(fam%prob, dyn, cs, fam%opts%harmonics, &
                                       fam%opts%odd_only, fam%opts%samples, fam%opts%rho, error)
        else
            call new_hb_problem(fam%prob, m, fam%opts%harmonics, fam%opts%odd_only, &
                                fam%opts%samples, fam%opts%rho, error)
        end if
        if (allocated(error)) return
        fam%factorizations = 1
        fam%current_omega = omega_ref
        fam%current_xi = 0.01_dp*omega_ref
        fam%have_current = .true.
        fam%phi = phi
        fam%mphi = cmplx(matmul(fam%model%mass, real(phi, dp)), &
                         matmul(fam%model%mass, aimag(phi)), dp)
        fam%vref = omega_ref*maxval(abs(phi))
        nb = fam%prob%basis%nb
        fam%n = nb*fam%prob%nc
        do k = 1, nb
            if (fam%prob%basis%harmonic_of(k) == 1) then
                if (fam%ic1 == 0) then
                    fam%ic1 = k
                else
                    fam%is1 = k
                end if
            end if
        end do
        fam%ih1 = findloc(fam%prob%dyn%harm, 1, 1)
        if (fam%ic1 == 0 .or. fam%is1 == 0 .or. fam%ih1 == 0) then
            call fatal_error(error, "nonlinear modes: the basis has no fundamental harmonic", &
                             stickslip_stat%input)
            return
        end if
        ! the tangential channels' mean forces (undetermined where they stick all period)
        fam%mean_rows = fam%prob%tangential_mean_rows()
        if (present(cyclic)) fam%mean_rows = [fam%mean_rows, idle_rows(fam, cs, cyclic)]
        if (size(fam%mean_rows) > 0) fam%mean_weight = mean_weight
    end subroutine new_modes_family

    !> On a sector: the unknowns of the harmonics in which a channel against the next sector
    !> measures nothing (T_h^H conj(D_h) = 0: a contact of a DOF against its own copy on the
    !> next sector in a harmonic whose inter-sector phase is 0, e.g. harmonic 3 of diameter
    !> 8 on 24 sectors). Their forces move nothing, so nothing determines them while the
    !> contact sticks: they get the Tikhonov term of the undetermined mean forces.
    function idle_rows(fam, cs, cyc) result(rows)
        type(modes_family_t), intent(in) :: fam
        type(contact_set_t), intent(in) :: cs
        type(cyclic_t), intent(in) :: cyc
        integer, allocatable :: rows(:)
        complex(dp), allocatable :: dm(:, :), a(:, :)
        complex(dp) :: e
        integer :: ih, c, nb
        allocate (rows(0))
        nb = fam%prob%basis%nb
        do ih = 1, fam%prob%basis%nharm
            e = exp(cmplx(0.0_dp, sector_phase(fam%prob%basis%harm(ih), cyc%engine_order, &
                                               cyc%sectors, 1), dp))
            dm = cyclic_directions(fam%model, cyc, cs, e)
            a = matmul(conjg(transpose(cyclic_basis(cyc, fam%model%ndof, e))), conjg(dm))
            do c = 1, cs%nchannel
                if (maxval(abs(a(:, c))) <= 1.0e-12_dp*max(maxval(abs(dm(:, c))), &
                                                           tiny(1.0_dp))) &
                    rows = [rows, (c - 1)*nb + fam%prob%basis%icos(ih) + [0, 1]]
            end do
        end do
    end function idle_rows

    !> Move the family's dynamics to (omega, xi): Z_h with damping C - xi M, factorized
    !> anew unless already there. stat = 1 when omega is not > 0 or a Z_h is singular.
    subroutine modes_set(self, omega, xi, stat)
        !> The family.
        class(modes_family_t), intent(inout) :: self
        !> Angular frequency [rad/s] and negative modal damping [1/s].
        real(dp), intent(in) :: omega, xi
        !> Set to 1 when the family has no equations there.
        integer, intent(inout) :: stat
        type(model_t) :: m
        type(error_type), allocatable :: error
        if (self%have_current .and. omega == self%current_omega .and. xi == self%current_xi) &
            return
        if (.not. (omega > 0.0_dp .and. ieee_is_finite(omega) .and. ieee_is_finite(xi))) then
            stat = 1
            return
        end if
        m = self%model
        m%omega = omega
        if (allocated(self%cyclic)) then
            ! C - xi M: the sector's prepared modes serve (modal damping c_j - xi)
            call new_cyclic_dynamics(self%prob%dyn, m, self%cyclic, self%prob%basis, error, &
                                     mass_damping=xi)
        else
            m%damping = m%damping - xi*m%mass
            call new_dynamics(self%prob%dyn, m, self%prob%basis, error)
        end if
        self%factorizations = self%factorizations + 1
        if (allocated(error)) then
            stat = 1
            self%have_current = .false.
            return
        end if
        self%current_omega = omega
        self%current_xi = xi
        self%have_current = .true.
    end subroutine modes_set

    !> The fundamental-harmonic displacement coefficients c1, s1 (N) of the motion whose
    !> friction-force coefficients are `r` (nb x channels), at the family's current
    !> (omega, xi): X1 = Y1 (R_cos - i R_sin), c1 = Re X1, s1 = -Im X1.
    subroutine modes_harmonic_one(self, r, c1, s1)
        !> The family (set at the point's omega and xi).
        class(modes_family_t), intent(in) :: self
        !> Channel-force coefficients [N].
        real(dp), intent(in) :: r(:, :)
        !> Cosine and sine coefficients of x at omega [m].
        real(dp), intent(out) :: c1(:), s1(:)
        complex(dp) :: x1(size(c1))
        x1 = matmul(self%prob%dyn%y(:, :, self%ih1), &
                    cmplx(r(self%ic1, :), -r(self%is1, :), dp))
        c1 = real(x1, dp)
        s1 = -aimag(x1)
    end subroutine modes_harmonic_one

    !> F(y, lambda): the projected friction laws, the amplitude and the phase conditions.
    subroutine modes_residual(self, y, lambda, f, stat)
        !> The family.
        class(modes_family_t), intent(inout) :: self
        !> [R; omega; xi], and lambda = ln a.
        real(dp), intent(in) :: y(:), lambda
        !> The residual (huge when there are no equations at this omega, xi).
        real(dp), intent(out) :: f(:)
        !> Nonzero on failure.
        integer, intent(inout) :: stat
        integer :: n, nb, nc
        real(dp) :: a, c1(self%model%ndof), s1(self%model%ndof)
        n = self%n
        nb = self%prob%basis%nb
        nc = self%prob%nc
        call self%set(y(n + 1), y(n + 2), stat)
        if (stat /= 0) then
            f = huge(1.0_dp)
            return
        end if
        call self%prob%residual(y(1:n), f(1:n), stat)
        if (self%mean_weight > 0.0_dp) f(self%mean_rows) = f(self%mean_rows) + &
            self%mean_weight*self%prob%rho*y(self%mean_rows)
        call self%harmonic_one(reshape(y(1:n), [nb, nc]), c1, s1)
        a = exp(lambda)
        f(n + 1) = self%vref*(quad(c1, s1)/a - a)
        f(n + 2) = self%vref*phase(self, c1, s1)
    contains
        real(dp) function quad(c, s)
            real(dp), intent(in) :: c(:), s(:)
            quad = dot_product(c, matmul(self%model%mass, c)) + &
                   dot_product(s, matmul(self%model%mass, s))
        end function quad
    end subroutine modes_residual

    !> dF/dy (the exact generalized Jacobian in R, analytic normalization rows, central
    !> differences in omega and xi) and dF/dlambda.
    subroutine modes_jacobian(self, y, lambda, jy, jl, stat)
        !> The family.
        class(modes_family_t), intent(inout) :: self
        !> [R; omega; xi], and lambda = ln a.
        real(dp), intent(in) :: y(:), lambda
        !> dF/dy and dF/dlambda.
        real(dp), intent(out) :: jy(:, :), jl(:)
        !> Nonzero on failure.
        integer, intent(inout) :: stat
        integer :: n, nb, nc, j, k
        real(dp) :: a, h, c1(self%model%ndof), s1(self%model%ndof), mc(self%model%ndof), &
                    ms(self%model%ndof), dc(self%model%ndof), ds(self%model%ndof)
        real(dp), allocatable :: yp(:), fp(:), fm(:)
        type(dynamics_t) :: dyn_at
        n = self%n
        nb = self%prob%basis%nb
        nc = self%prob%nc
        jy = 0.0_dp
        jl = 0.0_dp
        allocate (yp(n + 2), fp(n + 2), fm(n + 2))
        call self%set(y(n + 1), y(n + 2), stat)
        if (stat /= 0) return
        call self%prob%jacobian(y(1:n), jy(1:n, 1:n), stat)
        if (stat /= 0) return
        do k = 1, size(self%mean_rows)
            j = self%mean_rows(k)
            jy(j, j) = jy(j, j) + self%mean_weight*self%prob%rho
        end do
        ! the normalization rows in R: only the fundamental's coefficients enter
        call self%harmonic_one(reshape(y(1:n), [nb, nc]), c1, s1)
        a = exp(lambda)
        mc = matmul(self%model%mass, c1)
        ms = matmul(self%model%mass, s1)
        associate (y1 => self%prob%dyn%y(:, :, self%ih1))
            do j = 1, nc
                ! d/dR_cos(j): dX1 = Y1(:, j); d/dR_sin(j): dX1 = -i Y1(:, j)
                dc = real(y1(:, j), dp)
                ds = -aimag(y1(:, j))
                jy(n + 1, (j - 1)*nb + self%ic1) = self%vref*2.0_dp*(dot_product(mc, dc) + &
                                                                   dot_product(ms, ds))/a
                jy(n + 2, (j - 1)*nb + self%ic1) = self%vref*phase(self, dc, ds)
                dc = aimag(y1(:, j))
                ds = real(y1(:, j), dp)
                jy(n + 1, (j - 1)*nb + self%is1) = self%vref*2.0_dp*(dot_product(mc, dc) + &
                                                                   dot_product(ms, ds))/a
                jy(n + 2, (j - 1)*nb + self%is1) = self%vref*phase(self, dc, ds)
            end do
        end associate
        ! f(n+1) = v_ref (Q / a - a), a = exp(lambda); the other rows do not depend on lambda
        jl(n + 1) = -self%vref*((dot_product(c1, mc) + dot_product(s1, ms))/a + a)
        ! the omega and xi columns: central differences of the whole residual; the dynamics
        ! at (omega, xi) are kept and put back afterwards (no new factorization)
        dyn_at = self%prob%dyn
        do k = 1, 2
            if (k == 1) then
                h = 1.0e-6_dp*y(n + 1)
            else
                h = 1.0e-6_dp*max(abs(y(n + 2)), 1.0e-3_dp*y(n + 1))
            end if
            yp = y
            yp(n + k) = y(n + k) + h
            call modes_residual(self, yp, lambda, fp, stat)
            yp(n + k) = y(n + k) - h
            if (stat == 0) call modes_residual(self, yp, lambda, fm, stat)
            if (stat /= 0) exit
            jy(:, n + k) = (fp - fm)/(2.0_dp*h)
        end do
        self%prob%dyn = dyn_at
        self%current_omega = y(n + 1)
        self%current_xi = y(n + 2)
        self%have_current = .true.
        if (.not. (all(ieee_is_finite(jy)) .and. all(ieee_is_finite(jl)))) stat = 1
    end subroutine modes_jacobian

    !> The phase condition's function of the fundamental X1 = c1 - i s1: -Im(phi_ref^H M X1)
    !> = Re(M phi_ref)^T s1 + Im(M phi_ref)^T c1 (linear in c1, s1).
    pure real(dp) function phase(self, c1, s1)
        !> The family.
        class(modes_family_t), intent(in) :: self
        !> Cosine and sine coefficients of x at omega [m].
        real(dp), intent(in) :: c1(:), s1(:)
        phase = dot_product(real(self%mphi, dp), s1) + dot_product(aimag(self%mphi), c1)
    end function phase

    !> The velocity scale of the mode at lambda = ln a: v_ref a [m/s].
    real(dp) function modes_scale(self, lambda) result(s)
        !> The family.
        class(modes_family_t), intent(inout) :: self
        !> lambda = ln a.
        real(dp), intent(in) :: lambda
        s = self%vref*exp(lambda)
    end function modes_scale

    !> Release the FFT plans.
    subroutine modes_destroy(self)
        !> The family.
        class(modes_family_t), intent(inout) :: self
        call self%prob%destroy()
    end subroutine modes_destroy
end module stickslip_modes_family
