!> Linear dynamics per harmonic and the exact condensation onto the contact coordinates.
!>
!> For each harmonic h > 0 of the basis, with complex amplitudes X = a - i b
!> (x(t) = Re(X exp(i h omega t)) = a cos + b sin) and Z_h = K - (h omega)^2 M + i h omega C:
!>     X_h = Z_h^{-1} (F_h + W R_h) = X0_h + Y_h R_h,
!>     V_h (contacts) = i h omega W^T X_h = V0_h + G_h R_h.
!> For h = 0: X_0 = K^{-1} (F_0 + W R_0) and the contact velocity is zero.
!> The factorizations are done once (LAPACK zgetrf); afterwards only O(n_c^2) work per
!> harmonic is left for the nonlinear solve. Only the data: no FFT, no friction law.
!> With contact laws (doc/contacts.md) the "contacts" of the condensation are the force
!> channels of stickslip_contact_set (W is the channel direction matrix D, ncontact the number
!> of channels), the static load includes the preload, and the static channel receptance
!> D^T K^-1 D and D^T K^-1 F_0 are kept for the normal channels. A plain model builds exactly
!> what it built before.
module stickslip_dynamics
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t, force_direction, preload_force
    use stickslip_contact_set, only: contact_set_t, new_contact_set, channel_directions
    use stickslip_basis, only: basis_t
    use stickslip_lapack, only: zgetrf, zgetrs, zgecon, zlange
    use stickslip_small_dense, only: small_zgetrf, small_zgetrs, small_zrcond, small_dense_max
    implicit none
    private
    public :: dynamics_t, new_dynamics, restrict_dynamics, check_harmonics_in_basis, &
        smallest_singular, note_conditioning, &
        restrict_to_basis

    !> Condensed linear dynamics on a basis.
    type :: dynamics_t
        !> Degrees of freedom N.
        integer :: ndof = 0
        !> Contacts n_c.
        integer :: ncontact = 0
        !> Fundamental angular frequency [rad/s].
        real(dp) :: omega = 0.0_dp
        !> X0_h = Z_h^{-1} F_h, N x nharm (complex amplitudes) [m].
        complex(dp), allocatable :: x0(:, :)
        !> Y_h = Z_h^{-1} W, N x n_c x nharm [m/N].
        complex(dp), allocatable :: y(:, :, :)
        !> V0_h = i h omega W^T X0_h, n_c x nharm [m/s].
        complex(dp), allocatable :: v0(:, :)
        !> G_h = i h omega W^T Y_h, n_c x n_c x nharm [m/(N s)].
        complex(dp), allocatable :: g(:, :, :)
        !> Static response K^{-1} F_0 (when the basis has the constant) [m].
        real(dp), allocatable :: x0_static(:)
        !> Static flexibility K^{-1} W, N x n_c (when the basis has the constant) [m/N].
        real(dp), allocatable :: y_static(:, :)
        !> Static channel receptance D^T K^-1 D, n_c x n_c [m/N], and static channel
        !> displacements D^T K^-1 F_0, n_c [m] (F_0 with the preload), when the basis has
        !> the constant (the normal channels of unilateral contacts read them).
        real(dp), allocatable :: g_static(:, :), u_static(:)
        !> d V0_h / d omega, n_c x nharm (only when built with_omega_derivative) [m].
        complex(dp), allocatable :: dv0(:, :)
        !> d G_h / d omega, n_c x n_c x nharm (only when built with_omega_derivative)
        !> [m/N].
        complex(dp), allocatable :: dg(:, :, :)
        !> Smallest relative conditioning over the harmonics h > 0 of the basis: the smallest
        !> singular value of Z_h over that of the same terms without cancellation,
        !> s(Z_h) / (s(K) + (h omega)^2 s(M)), each s = 1 / ||A^-1||_1 (LAPACK estimates).
        !> About the relative distance of (h omega)^2 to the nearest natural frequency squared
        !> of the undamped structure: dimensionless, blind to the mesh's own conditioning (a
        !> fine FE mesh with cond(K) = 1e13 is far from 0 when h omega is between its modes),
        !> and, unlike rcond, it sees the resonance of a 1 x 1 Z_h (whose rcond is always 1).
        !> Below singular_threshold new_dynamics fails. 1 when the basis has no h > 0.
        real(dp) :: relative_conditioning = huge(1.0_dp)
        !> Harmonic where relative_conditioning is reached (-1 before new_dynamics).
        integer :: worst_harmonic = -1
        !> The smallest singular values of K and M (1-norm estimates, 0 when singular; -1
        !> before new_dynamics): they do not depend on omega, so a caller building the
        !> dynamics at another omega of the same model passes them back (`singular_values`)
        !> instead of factorizing K and M again.
        real(dp) :: smin_k = -1.0_dp, smin_m = -1.0_dp
        !> The harmonics h > 0 of the columns of x0, y, v0, g (those of the basis).
        integer, allocatable :: harm(:)
        !> Relative conditioning of Z_h per harmonic of `harm` (see relative_conditioning).
        real(dp), allocatable :: rel(:)
        !> The DOFs of the rows of x0, y, x0_static, y_static when not all N are kept (the
        !> exact sparse condensation, stickslip_sparse_dynamics); unallocated: rows 1..N.
        integer, allocatable :: kept(:)
        !> Sparse condensation only: P_h = [X0_h, Y_h]^H C [X0_h, Y_h] over ALL N DOFs,
        !> (n_c + 1) x (n_c + 1) x nharm, so that the viscous dissipation of the response
        !> X_h = X0_h + Y_h R_h is exact without the N-row X_h: X_h^H C X_h = [1; R_h]^H P_h
        !> [1; R_h] [m^2 N s/m].
        complex(dp), allocatable :: damping_gram(:, :, :)
        !> Sparse condensation only: q_h = F_h^H [X0_h, Y_h] over all N DOFs, (n_c + 1) x
        !> nharm: the forcing work per period is sum_h (T/2) h omega Re(i q_h [1; R_h]) [N m].
        complex(dp), allocatable :: forcing_gram(:, :)
    contains
        procedure :: contact_velocity
        procedure :: contact_velocity_derivative
        procedure :: displacement
    end type dynamics_t

    !> Z_h (h > 0) is called singular when its relative conditioning (see
    !> relative_conditioning in dynamics_t) is below this: h omega is a natural frequency to
    !> roundoff. K itself (h = 0) is called singular when its rcond is below
    !> static_singular_threshold (a few roundoffs: a healthy fine mesh with cond 1e13 passes).
    real(dp), parameter, public :: singular_threshold = 1.0e-13_dp
    !> rcond of K below which the static (zeroth-harmonic) problem is singular.
    real(dp), parameter, public :: static_singular_threshold = 1.0e-15_dp
    !> Z_h is called nearly singular (a resonance of the undamped structure within about
    !> this relative distance) below this: the response then hangs on the last digits of
    !> omega, M and K (stickslip_hbm reports it as untrusted, key 'near_resonance').
    real(dp), parameter, public :: near_singular_threshold = 1.0e-6_dp

contains

    !> Factorize the dynamic stiffness at every harmonic of `basis` and condense onto the
    !> contacts. Errors: stat input if a forcing term's harmonic is not in the basis;
    !> stat numerical if Z_h is singular (a natural frequency of the undamped structure at
    !> h omega: "undamped resonance at harmonic h ..."; relative test, see
    !> singular_threshold) or K is singular while the basis holds the constant.
    !> With `with_omega_derivative`, also d V0_h / d omega and d G_h / d omega (for the
    !> continuation in omega): with X = Z_h^{-1} [F_h, W] and dZ_h/domega = -2 h^2 omega M
    !> + i h C, d(i h omega W^T X)/domega = i h W^T X - i h omega W^T Z_h^{-1} (dZ_h/domega) X.
    !> `singular_values` = [smin_k, smin_m] of a dynamics of the same model (another omega)
    !> skips the two factorizations of K and M that estimate them.
    subroutine new_dynamics(self, model, basis, error, with_omega_derivative, singular_values)
        !> The condensed dynamics.
        type(dynamics_t), intent(out) :: self
        !> A validated model.
        type(model_t), intent(in) :: model
        !> The harmonic basis.
        type(basis_t), intent(in) :: basis
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Also compute dv0 and dg (default .false.).
        logical, intent(in), optional :: with_omega_derivative
        !> [smin_k, smin_m] from a dynamics of the same M and K (see dynamics_t).
        real(dp), intent(in), optional :: singular_values(2)
        integer :: n, nc, ih, h, j, i, info
        complex(dp), allocatable :: z(:, :), rhs(:, :), work(:), drhs(:, :)
        logical :: deriv
        real(dp), allocatable :: rwork(:), d(:, :)
        integer, allocatable :: ipiv(:)
        real(dp) :: anorm, rcond, w(model%ndof), knorm, mnorm, zscale, rel, smin_k, smin_m
        complex(dp) :: ihw
        character(len=512) :: buf
        type(contact_set_t) :: cs
        logical :: small

        n = model%ndof
        small = n <= small_dense_max
        ! the force channels (the contacts of a plain model) and their directions
        call new_contact_set(cs, model)
        nc = cs%nchannel
        d = channel_directions(model, cs)
        self%ndof = n
        self%ncontact = nc
        self%omega = model%omega

        call check_forcing_in_basis(model, basis, error)
        if (allocated(error)) return
        self%harm = basis%harm(1:basis%nharm)
        allocate (self%rel(basis%nharm))

        allocate (self%x0(n, basis%nharm), self%y(n, nc, basis%nharm))
        allocate (self%v0(nc, basis%nharm), self%g(nc, nc, basis%nharm))
        allocate (z(n, n), rhs(n, nc + 1), ipiv(n), work(2*n), rwork(2*n))
        deriv = .false.
        if (present(with_omega_derivative)) deriv = with_omega_derivative
        if (deriv) allocate (self%dv0(nc, basis%nharm), self%dg(nc, nc, basis%nharm), &
                             drhs(n, nc + 1))

        knorm = maxval(sum(abs(model%stiffness), dim=1))
        mnorm = maxval(sum(abs(model%mass), dim=1))
        ! the smallest singular values of K and M (1-norm estimates; 0 when singular)
        if (present(singular_values)) then
            smin_k = singular_values(1)
            smin_m = singular_values(2)
        else
            smin_k = smallest_singular(model%stiffness, knorm)
            smin_m = smallest_singular(model%mass, mnorm)
        end if
        self%smin_k = smin_k
        self%smin_m = smin_m
        self%relative_conditioning = 1.0_dp
        do ih = 0, basis%nharm
            if (ih == 0) then
                if (.not. basis%has_zero) cycle
                h = 0
            else
                h = basis%harm(ih)
            end if
            z = cmplx(model%stiffness - (h*model%omega)**2*model%mass, &
                      h*model%omega*model%damping, dp)
            anorm = zlange('1', n, n, z, n, rwork)
            ! a small model in plain Fortran (stickslip_small_dense: OpenBLAS's calls on
            ! tiny matrices serialize the threads of a family)
            if (small) then
                call small_zgetrf(n, z, ipiv, info)
            else
                call zgetrf(n, n, z, n, ipiv, info)
            end if
            if (info < 0) then
                call fatal_error(error, "zgetrf: illegal argument", stickslip_stat%lapack)
                return
            end if
            rcond = 0.0_dp
            if (info == 0) then
                if (small) then
                    rcond = small_zrcond(n, z, ipiv, anorm)
                else
                    call zgecon('1', n, z, n, anorm, rcond, work, rwork, info)
                end if
            end if
            ! h > 0: the smallest singular value of Z_h relative to that of K + (h omega)^2 M
            ! (no cancellation): the distance to a resonance, not the mesh's conditioning
            rel = 1.0_dp
            if (h > 0) then
                zscale = smin_k + (h*model%omega)**2*smin_m
                rel = 0.0_dp
                if (zscale > 0.0_dp) rel = rcond*anorm/zscale
                call note_conditioning(self, ih, h, rel)
            end if
            if ((h == 0 .and. .not. (rcond >= static_singular_threshold)) .or. &
                (h > 0 .and. .not. (rel >= singular_threshold))) then
                if (h == 0) then
                    write (buf, '(a,es10.2e3,a)') "the stiffness matrix K is singular (rcond = ", &
                        rcond, "): the static (zeroth-harmonic) response is undetermined; "// &
                        "restrain the rigid-body motion or set &hbm odd_only = .true."
                else
                    write (buf, '(a,i0,a,g0.6,a,es10.2e3,a)') "undamped resonance at harmonic h = ", &
                        h, " (h omega = ", h*model%omega, " rad/s): the dynamic stiffness "// &
                        "K - (h omega)^2 M + i h omega C is singular (relative conditioning ", &
                        rel, "): the weighted residual cannot condense the structure there (the "// &
                        "friction may still hold it: implicit Euler and the exact reference "// &
                        "integrate in time). Add damping or move omega"
                end if
                call fatal_error(error, trim(buf), stickslip_stat%numerical)
                return
            end if
            rhs = (0.0_dp, 0.0_dp)
            do i = 1, model%nforce()
                if (model%force_harmonic(i) == h) then
                    ! F_h += amplitude exp(i phase) f_i (a unit f_i adds to its DOF exactly)
                    rhs(:, 1) = rhs(:, 1) + model%force_amplitude(i)* &
                                exp(cmplx(0.0_dp, model%force_phase(i), dp))*force_direction(model, i)
                end if
            end do
            ! the static preload of unilateral contacts (a zero vector without)
            if (h == 0) rhs(:, 1) = rhs(:, 1) + preload_force(model)
            do j = 1, nc
                rhs(:, j + 1) = d(:, j)
            end do
            if (small) then
                call small_zgetrs(n, nc + 1, z, ipiv, rhs)
            else
                call zgetrs('N', n, nc + 1, z, n, ipiv, rhs, n, info)
            end if
            if (h == 0) then
                self%x0_static = real(rhs(:, 1), dp)
                self%y_static = real(rhs(:, 2:), dp)
                self%g_static = matmul(transpose(d), self%y_static)
                self%u_static = matmul(self%x0_static, d)
                cycle
            end if
            self%x0(:, ih) = rhs(:, 1)
            self%y(:, :, ih) = rhs(:, 2:)
            ihw = cmplx(0.0_dp, h*model%omega, dp)
            do j = 1, nc
                w = d(:, j)
                self%v0(j, ih) = ihw*sum(w*rhs(:, 1))
                do i = 1, nc
                    self%g(j, i, ih) = ihw*sum(w*rhs(:, i + 1))
                end do
            end do
            if (deriv) then
                ! Z^{-1} (dZ/domega) Z^{-1} [F, W]
                drhs = matmul(cmplx(-2.0_dp*h*h*model%omega*model%mass, h*model%damping, dp), &
                              rhs)
                if (small) then
                    call small_zgetrs(n, nc + 1, z, ipiv, drhs)
                else
                    call zgetrs('N', n, nc + 1, z, n, ipiv, drhs, n, info)
                end if
                do j = 1, nc
                    w = d(:, j)
                    self%dv0(j, ih) = cmplx(0.0_dp, real(h, dp), dp)*sum(w*rhs(:, 1)) &
                                      - ihw*sum(w*drhs(:, 1))
                    do i = 1, nc
                        self%dg(j, i, ih) = cmplx(0.0_dp, real(h, dp), dp)*sum(w*rhs(:, i + 1)) &
                                            - ihw*sum(w*drhs(:, i + 1))
                    end do
                end do
            end if
        end do
    end subroutine new_dynamics

    !> The dynamics of the same model at the same omega on `basis`, a subset of the
    !> harmonics of `self` (a lower rung of a harmonic ladder, the coarse set of a
    !> truncation estimate): the columns of those harmonics, copied, with no new
    !> factorization; equal to new_dynamics on `basis` (relative_conditioning and
    !> worst_harmonic over the subset). Errors: stat input when a harmonic of `basis` (or
    !> its constant) is not in `self`, or a forcing harmonic is not in `basis`.
    subroutine restrict_dynamics(self, model, basis, sub, error)
        !> Dynamics on a larger basis.
        class(dynamics_t), intent(in) :: self
        !> The model they were built for.
        type(model_t), intent(in) :: model
        !> The smaller basis.
        type(basis_t), intent(in) :: basis
        !> The dynamics on `basis`.
        type(dynamics_t), intent(out) :: sub
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        call check_forcing_in_basis(model, basis, error)
        if (allocated(error)) return
        call restrict_to_basis(self, basis, sub, error)
    end subroutine restrict_dynamics

    !> restrict_dynamics without the model: the forcing harmonics are the caller's to check
    !> (check_harmonics_in_basis). Errors: stat input when a harmonic of `basis` (or its
    !> constant) is not in `self`.
    subroutine restrict_to_basis(self, basis, sub, error)
        !> Dynamics on a larger basis.
        class(dynamics_t), intent(in) :: self
        !> The smaller basis.
        type(basis_t), intent(in) :: basis
        !> The dynamics on `basis`.
        type(dynamics_t), intent(out) :: sub
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: ih, k, nh
        integer :: pick(basis%nharm)
        if (.not. allocated(self%harm)) then
            call fatal_error(error, "restrict_dynamics: the dynamics were not built", &
                             stickslip_stat%input)
            return
        end if
        nh = basis%nharm
        do ih = 1, nh
            pick(ih) = findloc(self%harm, basis%harm(ih), 1)
        end do
        if (any(pick == 0) .or. (basis%has_zero .and. .not. allocated(self%x0_static))) then
            call fatal_error(error, "restrict_dynamics: the basis holds a harmonic the "// &
                             "dynamics were not built for", stickslip_stat%input)
            return
        end if
        sub%ndof = self%ndof
        sub%ncontact = self%ncontact
        sub%omega = self%omega
        sub%smin_k = self%smin_k
        sub%smin_m = self%smin_m
        sub%harm = self%harm(pick)
        sub%rel = self%rel(pick)
        if (allocated(self%kept)) sub%kept = self%kept
        if (allocated(self%damping_gram)) sub%damping_gram = self%damping_gram(:, :, pick)
        if (allocated(self%forcing_gram)) sub%forcing_gram = self%forcing_gram(:, pick)
        sub%x0 = self%x0(:, pick)
        sub%y = self%y(:, :, pick)
        sub%v0 = self%v0(:, pick)
        sub%g = self%g(:, :, pick)
        if (allocated(self%dv0)) sub%dv0 = self%dv0(:, pick)
        if (allocated(self%dg)) sub%dg = self%dg(:, :, pick)
        if (basis%has_zero) then
            sub%x0_static = self%x0_static
            sub%y_static = self%y_static
            if (allocated(self%g_static)) sub%g_static = self%g_static
            if (allocated(self%u_static)) sub%u_static = self%u_static
        end if
        ! as new_dynamics: the first harmonic where the smallest value is reached
        sub%relative_conditioning = 1.0_dp
        do k = 1, nh
            if (sub%rel(k) < sub%relative_conditioning) then
                sub%relative_conditioning = sub%rel(k)
                sub%worst_harmonic = sub%harm(k)
            end if
        end do
    end subroutine restrict_to_basis

    !> Error (stat input) when a forcing term's harmonic is not in `basis`.
    subroutine check_forcing_in_basis(model, basis, error)
        type(model_t), intent(in) :: model
        type(basis_t), intent(in) :: basis
        type(error_type), allocatable, intent(out) :: error
        if (model%nforce() == 0) return
        call check_harmonics_in_basis(model%force_harmonic, basis, error)
    end subroutine check_forcing_in_basis

    !> Error (stat input, "model%force_harmonic(i) = h: not in the harmonic basis ...")
    !> when one of the forcing harmonics `force_harmonic` is not in `basis`.
    subroutine check_harmonics_in_basis(force_harmonic, basis, error)
        !> Harmonic of each forcing term.
        integer, intent(in) :: force_harmonic(:)
        !> The basis.
        type(basis_t), intent(in) :: basis
        !> Set when a harmonic is missing.
        type(error_type), allocatable, intent(out) :: error
        integer :: i, h
        logical :: placed
        character(len=200) :: buf
        do i = 1, size(force_harmonic)
            h = force_harmonic(i)
            if (h == 0) then
                placed = basis%has_zero
            else
                placed = any(basis%harm == h)
            end if
            if (.not. placed) then
                write (buf, '(a,i0,a,i0,a)') "model%force_harmonic(", i, ") = ", h, &
                    ": not in the harmonic basis (check basis%harmonics and basis%odd_only)"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
        end do
    end subroutine check_harmonics_in_basis

    !> Contact slip-velocity coefficients V = V0 + G R (nb x n_c) for friction-force
    !> coefficients R (nb x n_c), in the real coefficient layout of `basis`.
    pure subroutine contact_velocity(self, basis, rcoef, vcoef)
        !> The condensed dynamics.
        class(dynamics_t), intent(in) :: self
        !> The basis.
        type(basis_t), intent(in) :: basis
        !> Friction force coefficients, nb x n_c [N].
        real(dp), intent(in) :: rcoef(:, :)
        !> Contact velocity coefficients, nb x n_c [m/s].
        real(dp), intent(out) :: vcoef(:, :)
        call affine_contact(self%ncontact, basis, self%v0, self%g, rcoef, vcoef)
    end subroutine contact_velocity

    !> d V / d omega = dV0/domega + dG/domega R (nb x n_c) [m] for friction-force
    !> coefficients R held fixed; needs a dynamics built with_omega_derivative.
    pure subroutine contact_velocity_derivative(self, basis, rcoef, dvcoef)
        !> The condensed dynamics.
        class(dynamics_t), intent(in) :: self
        !> The basis.
        type(basis_t), intent(in) :: basis
        !> Friction force coefficients, nb x n_c [N].
        real(dp), intent(in) :: rcoef(:, :)
        !> Derivative of the contact velocity coefficients, nb x n_c [m].
        real(dp), intent(out) :: dvcoef(:, :)
        call affine_contact(self%ncontact, basis, self%dv0, self%dg, rcoef, dvcoef)
    end subroutine contact_velocity_derivative

    !> u_h = a_h + b_h R_h per harmonic (zero constant term), in real coefficient layout.
    pure subroutine affine_contact(nc, basis, a, b, rcoef, ucoef)
        integer, intent(in) :: nc
        type(basis_t), intent(in) :: basis
        complex(dp), intent(in) :: a(:, :), b(:, :, :)
        real(dp), intent(in) :: rcoef(:, :)
        real(dp), intent(out) :: ucoef(:, :)
        integer :: ih, k, j
        complex(dp) :: v(nc), r(nc)
        if (basis%has_zero) ucoef(basis%i0, :) = 0.0_dp
        do ih = 1, basis%nharm
            k = basis%icos(ih)
            r = cmplx(rcoef(k, :), -rcoef(k + 1, :), dp)
            v = a(:, ih)
            do j = 1, nc
                v = v + b(:, j, ih)*r(j)
            end do
            ucoef(k, :) = real(v, dp)
            ucoef(k + 1, :) = -aimag(v)
        end do
    end subroutine affine_contact

    !> Displacement coefficients of every DOF, X = X0 + Y R (nb x N), for friction-force
    !> coefficients R (nb x n_c); nb x size(kept) for the kept DOFs of a sparse condensation.
    pure subroutine displacement(self, basis, rcoef, xcoef)
        !> The condensed dynamics.
        class(dynamics_t), intent(in) :: self
        !> The basis.
        type(basis_t), intent(in) :: basis
        !> Friction force coefficients, nb x n_c [N].
        real(dp), intent(in) :: rcoef(:, :)
        !> Displacement coefficients, nb x N (nb x size(kept) when kept) [m].
        real(dp), intent(out) :: xcoef(:, :)
        integer :: ih, k, j
        complex(dp) :: x(size(self%x0, 1)), r(self%ncontact)
        if (basis%has_zero) then
            xcoef(basis%i0, :) = self%x0_static
            do j = 1, self%ncontact
                xcoef(basis%i0, :) = xcoef(basis%i0, :) + self%y_static(:, j)*rcoef(basis%i0, j)
            end do
        end if
        do ih = 1, basis%nharm
            k = basis%icos(ih)
            r = cmplx(rcoef(k, :), -rcoef(k + 1, :), dp)
            x = self%x0(:, ih)
            do j = 1, self%ncontact
                x = x + self%y(:, j, ih)*r(j)
            end do
            xcoef(k, :) = real(x, dp)
            xcoef(k + 1, :) = -aimag(x)
        end do
    end subroutine displacement

    !> Record the relative conditioning `rel` of harmonic h > 0 (entry ih of the basis):
    !> self%rel(ih), and the worst so far (relative_conditioning, worst_harmonic).
    pure subroutine note_conditioning(self, ih, h, rel)
        !> The dynamics being built.
        type(dynamics_t), intent(inout) :: self
        !> Entry of the basis and its harmonic.
        integer, intent(in) :: ih, h
        !> The relative conditioning of Z_h.
        real(dp), intent(in) :: rel
        self%rel(ih) = rel
        if (rel < self%relative_conditioning) then
            self%relative_conditioning = rel
            self%worst_harmonic = h
        end if
    end subroutine note_conditioning

    !> 1 / ||A^-1||_1 of a real square matrix (LAPACK's estimate, through the complex
    !> routines used for Z_h), `anorm` = ||A||_1; 0 when A is singular.
    function smallest_singular(a, anorm) result(smin)
        !> The matrix.
        real(dp), intent(in) :: a(:, :)
        !> Its 1-norm.
        real(dp), intent(in) :: anorm
        real(dp) :: smin
        complex(dp), allocatable :: z(:, :), work(:)
        real(dp), allocatable :: rwork(:)
        real(dp) :: rcond
        integer, allocatable :: ipiv(:)
        integer :: info, n
        n = size(a, 1)
        smin = 0.0_dp
        if (n == 0) return
        allocate (z(n, n), work(2*n), rwork(2*n), ipiv(n))
        z = cmplx(a, 0.0_dp, dp)
        call zgetrf(n, n, z, n, ipiv, info)
        if (info /= 0) return
        call zgecon('1', n, z, n, anorm, rcond, work, rwork, info)
        if (info /= 0) return
        smin = rcond*anorm
    end function smallest_singular
end module stickslip_dynamics
