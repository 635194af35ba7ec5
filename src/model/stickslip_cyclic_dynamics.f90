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
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t, force_direction
    use stickslip_basis, only: basis_t
    use stickslip_dynamics, only: dynamics_t, check_harmonics_in_basis, singular_threshold, &
        static_singular_threshold, smallest_singular, note_conditioning
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, sector_phase, cyclic_basis, &
        nodal_diameter, structure_key, cyclic_directions, cyclic_preload_force
    use stickslip_lapack, only: zgetrf, zgetrs, zgecon, zlange
    use stickslip_dense_products, only: cmat_mul
    implicit none
    private
    public :: new_cyclic_dynamics

contains

    !> The condensed dynamics of the sector `model` of the disk `cyc` on `basis` (see the
    !> module). With `with_omega_derivative`, dv0 and dg too (continuation in omega). With
    !> `mass_damping` xi [1/s], the damping is C - xi M (a nonlinear mode's negative modal
    !> damping): the prepared modes still serve, each modal damping c_j - xi.
    !> Errors: those of validate_cyclic and check_harmonics_in_basis (stat input); stat
    !> numerical when the projected dynamic stiffness is singular (an undamped cyclic mode at
    !> h omega) or K on the cyclic motions is (h = 0).
    subroutine new_cyclic_dynamics(self, model, cyc, basis, error, with_omega_derivative, &
                                   mass_damping)
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
        type(contact_set_t) :: cs
        real(dp), allocatable :: damping(:, :)
        real(dp) :: xi
        real(dp), allocatable :: rwork(:)
        complex(dp), allocatable :: t(:, :), rhs(:, :), x(:, :), dm(:, :), f(:), work(:), &
                                    dx(:, :), cx(:, :)
        integer, allocatable :: ipiv(:)
        integer :: n, m, nc, ih, h, j, c, k, info
        real(dp) :: anorm, rcond, zscale, rel, smin_k, smin_m
        complex(dp) :: e, ihw
        logical :: deriv, modal, modal_gram, conj_shapes

        call validate_cyclic(model, cyc, error)
        if (allocated(error)) return
        call check_harmonics_in_basis(model%force_harmonic, basis, error)
        if (allocated(error)) return
        deriv = .false.
        if (present(with_omega_derivative)) deriv = with_omega_derivative
        xi = 0.0_dp
        if (present(mass_damping)) xi = mass_damping
        damping = model%damping
        if (xi /= 0.0_dp) damping = damping - xi*model%mass
        n = model%ndof
        m = n - size(cyc%right)
        call new_contact_set(cs, model)
        nc = cs%nchannel
        self%ndof = n
        self%ncontact = nc
        self%omega = model%omega
        self%harm = basis%harm(1:basis%nharm)
        allocate (self%rel(basis%nharm), self%x0(n, basis%nharm), self%y(n, nc, basis%nharm), &
                  self%v0(nc, basis%nharm), self%g(nc, nc, basis%nharm), &
                  self%damping_gram(nc + 1, nc + 1, basis%nharm), &
                  self%forcing_gram(nc + 1, basis%nharm))
        if (deriv) allocate (self%dv0(nc, basis%nharm), self%dg(nc, nc, basis%nharm))
        allocate (ipiv(m), work(2*m), rwork(2*m), dm(n, nc), f(n), rhs(n, nc + 1))
        ! the smallest singular values of K and M of the sector (the scale of the distance
        ! to a resonance, as new_dynamics); prepared with the modes
        modal = .false.
        if (allocated(cyc%modes)) modal = cyc%modes_key == structure_key(model)
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
            end if
            if (allocated(error)) return
            if (h == 0) then
                self%x0_static = real(x(:, 1), dp)
                self%y_static = real(x(:, 2:), dp)
                self%g_static = matmul(transpose(real(dm, dp)), self%y_static)
                self%u_static = matmul(self%x0_static, real(dm, dp))
                cycle
            end if
            self%x0(:, ih) = x(:, 1)
            self%y(:, :, ih) = x(:, 2:)
            ihw = cmplx(0.0_dp, h*model%omega, dp)
            self%v0(:, ih) = ihw*matmul(transpose(dm), x(:, 1))
            self%g(:, :, ih) = ihw*matmul(transpose(dm), x(:, 2:))
            if (.not. modal_gram) then
                cx = cmplx(matmul(damping, real(x, dp)), matmul(damping, aimag(x)), dp)
                self%damping_gram(:, :, ih) = matmul(conjg(transpose(x)), cx)
            end if
            self%forcing_gram(:, ih) = matmul(conjg(f), x)
            if (deriv) then
                ! dx = T Zc^-1 T^H (dZ/domega) X: d X / d omega = -dx
                self%dv0(:, ih) = cmplx(0.0_dp, real(h, dp), dp)* &
                                  matmul(transpose(dm), x(:, 1)) - &
                                  ihw*matmul(transpose(dm), dx(:, 1))
                self%dg(:, :, ih) = cmplx(0.0_dp, real(h, dp), dp)* &
                                    matmul(transpose(dm), x(:, 2:)) - &
                                    ihw*matmul(transpose(dm), dx(:, 2:))
            end if
        end do

    contains

        !> conj(D), a copy.
        pure function conj_dm(a) result(b)
            complex(dp), intent(in) :: a(:, :)
            complex(dp) :: b(size(a, 1), size(a, 2))
            b = conjg(a)
        end function conj_dm

        !> Whether harmonic h has prepared modes; then its T Phi are the prepared shapes S,
        !> or with `conj_shapes` their conjugates (a phase p <= N/2, see
        !> stickslip_cyclic_modal).
        logical function modal_harmonic(h, conj_shapes)
            integer, intent(in) :: h
            logical, intent(out) :: conj_shapes
            integer :: p, nd
            modal_harmonic = .false.
            conj_shapes = .false.
            if (.not. modal) return
            p = modulo(h*cyc%engine_order, cyc%sectors)
            nd = nodal_diameter(h, cyc%engine_order, cyc%sectors)
            if (cyc%modes(nd)%nd /= nd) return
            if (size(cyc%modes(nd)%shapes, 1) /= n) return
            conj_shapes = p == nd
            modal_harmonic = .true.
        end function modal_harmonic

        !> x (and dx) at harmonic h as the modal sum G diag(1 / D) G^H rhs, D_j = lambda_j
        !> - (h w)^2 + i h w c_j, G = S or conj(S) (G^H b = conj(S^H conj(b)), G a =
        !> conj(S conj(a))); the conditioning min |D_j| / (lambda_1 + (h w)^2); the damping
        !> Gram matrix x^H C x = q^H diag(c) q, q = D^-1 G^H rhs.
        subroutine modal_solve(h, conj_shapes)
            integer, intent(in) :: h
            logical, intent(in) :: conj_shapes
            complex(dp), allocatable :: dd(:), gr(:, :), gq(:, :)
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
            associate (md => cyc%modes(nd))
                if (conj_shapes) then
                    gr = conjg(cmat_mul(md%shapes_h, conjg(rhs)))
                else
                    gr = cmat_mul(md%shapes_h, rhs)
                end if
                do jj = 1, size(dd)
                    gr(jj, :) = gr(jj, :)/dd(jj)
                end do
                x = shapes_times(gr, nd, conj_shapes)
                if (h > 0) then
                    modal_gram = .true.
                    gq = gr
                    do jj = 1, size(dd)
                        gq(jj, :) = (md%damping(jj) - xi)*gr(jj, :)
                    end do
                    self%damping_gram(:, :, ih) = matmul(conjg(transpose(gr)), gq)
                end if
                if (deriv .and. h > 0) then
                    do jj = 1, size(dd)
                        gr(jj, :) = gr(jj, :)*cmplx(-2.0_dp*h*h*model%omega, &
                                                    h*(md%damping(jj) - xi), dp)/dd(jj)
                    end do
                    dx = shapes_times(gr, nd, conj_shapes)
                end if
            end associate
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
