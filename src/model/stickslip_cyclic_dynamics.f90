!> The condensation of one sector of a tuned bladed disk in its travelling wave
!> (stickslip_cyclic): the same dynamics_t as new_dynamics gives a whole structure, so that
!> the weighted residual solves the disk on one sector.
!>
!> At harmonic h the sector's motions are X = T_h q: its DOFs off the right boundary free,
!> the right boundary the left one times e_h = exp(-i h 2 pi EO / N) (the next sector is
!> this one delayed by EO / N of the period). The boundary forces of the neighbours drop out
!> of the projection T_h^H Z_h T_h (they are equal and opposite with that phase). A channel
!> against the next sector measures U = D^T X with D = d - e_h d_next (d on the sector, d_next
!> the unit vector of the next sector's DOF) and is pushed by conj(D) R: +d R on this
!> sector, and -d_next R from the previous sector's contact, which is this one's advanced by
!> EO / N (exp(+i h 2 pi EO / N) R). So X0_h = T (T^H Z T)^-1 T^H F_h, Y_h = T (T^H Z T)^-1
!> T^H conj(D), V0_h = i h omega D^T X0_h, G_h = i h omega D^T Y_h; the static term (h = 0)
!> with e = 1. The Gram matrices of the sector's damping and forcing over its DOFs are set
!> (damping_gram, forcing_gram): the energies per period are the sector's share of the
!> disk's. With the sector's cyclic modes prepared (cyc%modes, stickslip_cyclic_modal:
!> proportional damping) (T^H Z T)^-1 is their modal sum, exact, O(n m) per harmonic;
!> otherwise a dense LU of the projected pencil per harmonic (LAPACK), O(n^2 m).
module stickslip_cyclic_dynamics
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t, force_direction
    use stickslip_basis, only: basis_t
    use stickslip_dynamics, only: dynamics_t, check_harmonics_in_basis, singular_threshold, &
        static_singular_threshold, smallest_singular, note_conditioning
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, sector_phase, cyclic_basis, &
        nodal_diameter, structure_key, cyclic_directions, cyclic_preload_force, conjugate_shapes
    use stickslip_lapack, only: zgetrf, zgetrs, zgecon, zlange
    use stickslip_dense_products, only: cmat_mul
    implicit none
    private
    public :: new_cyclic_dynamics, cyclic_projections_t

    !> What new_cyclic_dynamics can keep from one omega to the next on a sector with
    !> prepared modes: per harmonic of the basis, the projections G^H [F_h, conj(D_h)] of
    !> the forcing and of the channels' measuring directions on the diameter's mode shapes
    !> G (m x (n_c + 1)), and the F_h and D_h they were made from. They do not depend on
    !> omega, so with them a build of the channels' dynamics costs O(m n_c^2) per harmonic
    !> instead of O(n m n_c). A cache of one caller for one sector (a family's; its M, K and
    !> C never change along it): the sector's fingerprint is checked when it is made, its
    !> forcing and directions at every use.
    type :: cyclic_projections_t
        !> The prepared modes' fingerprint (cyclic_t%modes_key) the entries belong to.
        integer(int64) :: modes_key = 0
        !> Per harmonic index 0 .. nharm of the basis: made.
        logical, allocatable :: made(:)
        !> The harmonics h > 0 of the basis (dynamics_t%harm).
        integer, allocatable :: harm(:)
        !> F_h, N x (0:nharm).
        complex(dp), allocatable :: f(:, :)
        !> D_h, N x n_c x (0:nharm).
        complex(dp), allocatable :: d(:, :, :)
        !> G^H [F_h, conj(D_h)], m x (n_c + 1) x (0:nharm).
        complex(dp), allocatable :: a(:, :, :)
    end type cyclic_projections_t

contains

    !> The condensed dynamics of the sector `model` of the disk `cyc` on `basis` (see the
    !> module). With `with_omega_derivative`, dv0 and dg too (continuation in omega). With
    !> `mass_damping` xi [1/s], the damping is C - xi M (a nonlinear mode's negative modal
    !> damping): the prepared modes still serve, each modal damping c_j - xi. With
    !> `channels_only`, the N-row responses (x0, y, x0_static, y_static) are not kept (left
    !> unallocated): what the friction equations need, without what recovers the
    !> displacements, at O(m n_c^2) per harmonic on prepared modes with `projections`.
    !> Errors: those of validate_cyclic and check_harmonics_in_basis (stat input); stat
    !> numerical when the projected dynamic stiffness is singular (an undamped cyclic mode at
    !> h omega) or K on the cyclic motions is (h = 0).
    subroutine new_cyclic_dynamics(self, model, cyc, basis, error, with_omega_derivative, &
                                   mass_damping, channels_only, projections)
        !> The condensed dynamics (rows: the sector's DOFs).
        type(dynamics_t), intent(out) :: self
        !> The sector (a validated model).
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> The harmonic basis.
        type(basis_t), intent(in) :: basis
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Also dv0 and dg (default .false.).
        logical, intent(in), optional :: with_omega_derivative
        !> Mass-proportional damping removed, xi [1/s] (default 0).
        real(dp), intent(in), optional :: mass_damping
        !> Keep the channels' dynamics only (default .false.).
        logical, intent(in), optional :: channels_only
        !> The projections kept from an earlier call for this sector (made or updated here).
        type(cyclic_projections_t), intent(inout), optional :: projections
        type(contact_set_t) :: cs
        real(dp), allocatable :: damping(:, :)
        real(dp) :: xi
        real(dp), allocatable :: rwork(:)
        complex(dp), allocatable :: t(:, :), rhs(:, :), x(:, :), dm(:, :), f(:), work(:), &
                                    dx(:, :), cx(:, :), cv(:, :), dcv(:, :)
        integer, allocatable :: ipiv(:)
        integer :: n, m, nc, ih, h, k, info
        real(dp) :: anorm, rcond, zscale, rel, smin_k, smin_m
        complex(dp) :: e, ihw
        logical :: deriv, modal, modal_gram, conj_shapes, keep_x, cached

        call validate_cyclic(model, cyc, error)
        if (allocated(error)) return
        call check_harmonics_in_basis(model%force_harmonic, basis, error)
        if (allocated(error)) return
        deriv = .false.
        if (present(with_omega_derivative)) deriv = with_omega_derivative
        keep_x = .true.
        if (present(channels_only)) keep_x = .not. channels_only
        xi = 0.0_dp
        if (present(mass_damping)) xi = mass_damping
        n = model%ndof
        m = n - size(cyc%right)
        call new_contact_set(cs, model)
        nc = cs%nchannel
        self%ndof = n
        self%ncontact = nc
        self%omega = model%omega
        self%harm = basis%harm(1:basis%nharm)
        allocate (self%rel(basis%nharm), self%v0(nc, basis%nharm), self%g(nc, nc, basis%nharm), &
                  self%damping_gram(nc + 1, nc + 1, basis%nharm), &
                  self%forcing_gram(nc + 1, basis%nharm))
        if (keep_x) allocate (self%x0(n, basis%nharm), self%y(n, nc, basis%nharm))
        if (deriv) allocate (self%dv0(nc, basis%nharm), self%dg(nc, nc, basis%nharm))
        allocate (ipiv(m), work(2*m), rwork(2*m), dm(n, nc), f(n), rhs(n, nc + 1))
        ! the smallest singular values of K and M of the sector (the scale of the distance
        ! to a resonance, as new_dynamics); prepared with the modes. A cache made for these
        ! modes stands for the fingerprint's check (see cyclic_projections_t).
        modal = .false.
        cached = .false.
        if (allocated(cyc%modes) .and. present(projections)) then
            cached = allocated(projections%made) .and. projections%modes_key == cyc%modes_key
            if (cached) cached = size(projections%made) == basis%nharm + 1 .and. &
                                 size(projections%f, 1) == n .and. size(projections%d, 2) == nc
            if (cached) cached = size(projections%harm) == size(self%harm)
            if (cached) cached = all(projections%harm == self%harm)
        end if
        if (cached) then
            modal = .true.
        else if (allocated(cyc%modes)) then
            modal = cyc%modes_key == structure_key(model, cyc%sectors)
            if (modal .and. present(projections)) call reset_projections()
        end if
        if (modal) then
            smin_k = cyc%smin_k
            smin_m = cyc%smin_m
        else
            smin_k = smallest_singular(model%stiffness, maxval(sum(abs(model%stiffness), 1)))
            smin_m = smallest_singular(model%mass, maxval(sum(abs(model%mass), 1)))
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
            e = exp(cmplx(0.0_dp, sector_phase(h, cyc%engine_order, cyc%sectors, 1), dp))
            ! the measuring directions D = d - e d_next
            dm = cyclic_directions(model, cyc, cs, e)
            ! the forcing of harmonic h on the sector
            f = (0.0_dp, 0.0_dp)
            do k = 1, model%nforce()
                if (model%force_harmonic(k) == h) f = f + model%force_amplitude(k)* &
                    exp(cmplx(0.0_dp, model%force_phase(k), dp))*force_direction(model, k)
            end do
            if (h == 0) then
                ! the preloads, along the normals' D: a contact against the next sector
                ! presses its next DOF back (its reaction from the previous sector's contact
                ! cancels the pair on a tuned disk)
                f = f + cyclic_preload_force(model, cyc)
            end if
            rhs(:, 1) = f
            rhs(:, 2:) = conj_dm(dm)
            modal_gram = .false.
            if (modal_harmonic(h, conj_shapes)) then
                call modal_solve(h, conj_shapes)
            else
                call direct_solve(h)
                if (.not. allocated(error)) then
                    ! the channels' values D^T [X0, Y] (and their omega derivative)
                    cv = matmul(transpose(dm), x)
                    if (deriv .and. h > 0) dcv = matmul(transpose(dm), dx)
                end if
            end if
            if (allocated(error)) return
            if (h == 0) then
                if (keep_x) then
                    self%x0_static = real(x(:, 1), dp)
                    self%y_static = real(x(:, 2:), dp)
                end if
                self%g_static = real(cv(:, 2:), dp)
                self%u_static = real(cv(:, 1), dp)
                cycle
            end if
            if (keep_x) then
                self%x0(:, ih) = x(:, 1)
                self%y(:, :, ih) = x(:, 2:)
            end if
            ihw = cmplx(0.0_dp, h*model%omega, dp)
            self%v0(:, ih) = ihw*cv(:, 1)
            self%g(:, :, ih) = ihw*cv(:, 2:)
            if (.not. modal_gram) then
                cx = cmplx(matmul(damping, real(x, dp)), matmul(damping, aimag(x)), dp)
                self%damping_gram(:, :, ih) = matmul(conjg(transpose(x)), cx)
                self%forcing_gram(:, ih) = matmul(conjg(f), x)
            end if
            if (deriv) then
                ! dx = T Zc^-1 T^H (dZ/domega) X: d X / d omega = -dx
                self%dv0(:, ih) = cmplx(0.0_dp, real(h, dp), dp)*cv(:, 1) - ihw*dcv(:, 1)
                self%dg(:, :, ih) = cmplx(0.0_dp, real(h, dp), dp)*cv(:, 2:) - ihw*dcv(:, 2:)
            end if
        end do

    contains

        !> conj(D), a copy.
        pure function conj_dm(a) result(b)
            complex(dp), intent(in) :: a(:, :)
            complex(dp) :: b(size(a, 1), size(a, 2))
            b = conjg(a)
        end function conj_dm

        !> An empty cache for these modes and this basis.
        subroutine reset_projections()
            projections%modes_key = cyc%modes_key
            projections%harm = self%harm
            if (allocated(projections%made)) deallocate (projections%made, projections%f, &
                                                         projections%d, projections%a)
            allocate (projections%made(0:basis%nharm), projections%f(n, 0:basis%nharm), &
                      projections%d(n, nc, 0:basis%nharm), &
                      projections%a(m, nc + 1, 0:basis%nharm))
            projections%made = .false.
        end subroutine reset_projections

        !> Whether harmonic h has prepared modes; then its T Phi are the prepared shapes S,
        !> or with `conj_shapes` their conjugates (a phase p <= N/2, see
        !> stickslip_cyclic_modal).
        logical function modal_harmonic(h, conj_shapes)
            integer, intent(in) :: h
            logical, intent(out) :: conj_shapes
            integer :: nd
            modal_harmonic = .false.
            conj_shapes = .false.
            if (.not. modal) return
            nd = nodal_diameter(h, cyc%engine_order, cyc%sectors)
            if (cyc%modes(nd)%nd /= nd) return
            if (size(cyc%modes(nd)%shapes, 1) /= n) return
            conj_shapes = conjugate_shapes(h, cyc%engine_order, cyc%sectors)
            modal_harmonic = .true.
        end function modal_harmonic

        !> The projections a = G^H rhs of this harmonic, G = S or conj(S) (G^H b = conj(S^H
        !> conj(b))): from the cache when it holds them for this F_h and D_h.
        function projected(conj_shapes, nd) result(a)
            integer, intent(in) :: nd
            logical, intent(in) :: conj_shapes
            complex(dp), allocatable :: a(:, :)
            if (present(projections)) then
                if (projections%made(ih)) then
                    if (all(projections%f(:, ih) == f) .and. &
                        all(projections%d(:, :, ih) == dm)) then
                        a = projections%a(:, :, ih)
                        return
                    end if
                end if
            end if
            if (conj_shapes) then
                a = conjg(cmat_mul(cyc%modes(nd)%shapes_h, conjg(rhs)))
            else
                a = cmat_mul(cyc%modes(nd)%shapes_h, rhs)
            end if
            if (present(projections)) then
                projections%f(:, ih) = f
                projections%d(:, :, ih) = dm
                projections%a(:, :, ih) = a
                projections%made(ih) = .true.
            end if
        end function projected

        !> The channels' values cv = D^T x at harmonic h by the modal sum x = G diag(1 / D)
        !> G^H rhs, D_j = lambda_j - (h w)^2 + i h w c_j, with a = G^H rhs (projected),
        !> q = diag(1 / D) a: with x kept, x = G q (G a = conj(S conj(a)) for the conjugate
        !> shapes) and cv = D^T x; without, cv = a(:, 2:)^H q (D^T G = a(:, 2:)^H). The
        !> conditioning min |D_j| / (lambda_1 + (h w)^2); the Gram matrices x^H C x = q^H
        !> diag(c) q and F^H x (= a(:, 1)^H q); with the derivative dcv, the same with q
        !> (-2 h^2 w + i h c_j) / D_j.
        subroutine modal_solve(h, conj_shapes)
            integer, intent(in) :: h
            logical, intent(in) :: conj_shapes
            complex(dp), allocatable :: dd(:), a(:, :), gr(:, :), gq(:, :), ah(:, :)
            real(dp) :: hw
            integer :: nd, jj
            nd = nodal_diameter(h, cyc%engine_order, cyc%sectors)
            hw = h*model%omega
            associate (md => cyc%modes(nd))
                dd = cmplx(md%lambda - hw**2, hw*(md%damping - xi), dp)
                if (h == 0) then
                    rel = minval(abs(md%lambda))/max(maxval(abs(md%lambda)), tiny(1.0_dp))
                else
                    rel = minval(abs(dd))/max(md%lambda(1) + hw**2, tiny(1.0_dp))
                end if
            end associate
            if (.not. check_conditioning(h, rel)) return
            a = projected(conj_shapes, nd)
            gr = a
            do jj = 1, size(dd)
                gr(jj, :) = gr(jj, :)/dd(jj)
            end do
            ! with x kept, the channels from it (D^T x, as a whole structure's); else by
            ! D^T G = a(:, 2:)^H, equal up to roundoff
            if (keep_x) then
                x = shapes_times(gr, nd, conj_shapes)
                cv = matmul(transpose(dm), x)
            else
                ah = conjg(transpose(a(:, 2:)))
                cv = matmul(ah, gr)
            end if
            if (h > 0) then
                modal_gram = .true.
                gq = gr
                associate (md => cyc%modes(nd))
                    do jj = 1, size(dd)
                        gq(jj, :) = (md%damping(jj) - xi)*gr(jj, :)
                    end do
                end associate
                self%damping_gram(:, :, ih) = matmul(conjg(transpose(gr)), gq)
                if (keep_x) then
                    self%forcing_gram(:, ih) = matmul(conjg(f), x)
                else
                    self%forcing_gram(:, ih) = matmul(conjg(a(:, 1)), gr)
                end if
            end if
            if (deriv .and. h > 0) then
                associate (md => cyc%modes(nd))
                    do jj = 1, size(dd)
                        gr(jj, :) = gr(jj, :)*cmplx(-2.0_dp*h*h*model%omega, &
                                                    h*(md%damping(jj) - xi), dp)/dd(jj)
                    end do
                end associate
                if (keep_x) then
                    dcv = matmul(transpose(dm), shapes_times(gr, nd, conj_shapes))
                else
                    dcv = matmul(ah, gr)
                end if
            end if
        end subroutine modal_solve

        !> S a, or conj(S conj(a)) with `conj_shapes`, S the prepared shapes of the
        !> diameter nd.
        function shapes_times(a, nd, conj_shapes) result(b)
            complex(dp), intent(in) :: a(:, :)
            integer, intent(in) :: nd
            logical, intent(in) :: conj_shapes
            complex(dp), allocatable :: b(:, :)
            if (conj_shapes) then
                b = conjg(cmat_mul(cyc%modes(nd)%shapes, conjg(a)))
            else
                b = cmat_mul(cyc%modes(nd)%shapes, a)
            end if
        end function shapes_times

        !> x (and dx) at harmonic h by LAPACK's LU of the projected pencil T^H Z T.
        subroutine direct_solve(h)
            integer, intent(in) :: h
            complex(dp), allocatable :: z(:, :), zc(:, :), r(:, :)
            ! C - xi M, once (the modal path never needs it)
            if (.not. allocated(damping)) then
                damping = model%damping
                if (xi /= 0.0_dp) damping = damping - xi*model%mass
            end if
            ! the cyclic motions: the right boundary is the left one times e
            t = cyclic_basis(cyc, n, e)
            z = cmplx(model%stiffness - (h*model%omega)**2*model%mass, &
                      h*model%omega*damping, dp)
            zc = matmul(conjg(transpose(t)), matmul(z, t))
            anorm = zlange('1', m, m, zc, m, rwork)
            call zgetrf(m, m, zc, m, ipiv, info)
            rcond = 0.0_dp
            if (info == 0) call zgecon('1', m, zc, m, anorm, rcond, work, rwork, info)
            rel = rcond
            if (h > 0) then
                zscale = smin_k + (h*model%omega)**2*smin_m
                rel = 0.0_dp
                if (zscale > 0.0_dp) rel = rcond*anorm/zscale
            end if
            if (.not. check_conditioning(h, rel)) return
            r = matmul(conjg(transpose(t)), rhs)
            call zgetrs('N', m, nc + 1, zc, m, ipiv, r, m, info)
            x = matmul(t, r)
            if (deriv .and. h > 0) then
                r = matmul(conjg(transpose(t)), matmul(cmplx(-2.0_dp*h*h*model%omega* &
                                                             model%mass, h*damping, &
                                                             dp), x))
                call zgetrs('N', m, nc + 1, zc, m, ipiv, r, m, info)
                dx = matmul(t, r)
            end if
        end subroutine direct_solve

        !> Record the conditioning `rel` of harmonic h; false (and the error set) when the
        !> projected dynamic stiffness is singular.
        logical function check_conditioning(h, rel)
            integer, intent(in) :: h
            real(dp), intent(in) :: rel
            character(len=300) :: buf
            check_conditioning = .true.
            if (h > 0) call note_conditioning(self, ih, h, rel)
            if ((h == 0 .and. .not. (rel >= static_singular_threshold)) .or. &
                (h > 0 .and. .not. (rel >= singular_threshold))) then
                if (h == 0) then
                    buf = "the sector's stiffness on its cyclic motions is singular (a free "// &
                          "disk): the static response is undetermined; restrain it or set "// &
                          "&hbm odd_only = .true."
                else
                    write (buf, '(a,i0,a,g0.6,a)') "undamped cyclic resonance at harmonic h = ", &
                        h, " (h omega = ", h*model%omega, " rad/s): the sector's dynamic "// &
                        "stiffness on its travelling-wave motions is singular. Add damping "// &
                        "or move omega"
                end if
                call fatal_error(error, trim(buf), stickslip_stat%numerical)
                check_conditioning = .false.
            end if
        end function check_conditioning
    end subroutine new_cyclic_dynamics
end module stickslip_cyclic_dynamics
