!> The friction limits of one sector of a tuned bladed disk in a travelling wave: its cyclic
!> modes with every contact stuck or slipping (the low- and high-amplitude limits of its
!> nonlinear modes per nodal diameter), as stickslip_linear_modes gives them for a whole
!> structure.
!>
!> The sector moves as X = T q, X_right = e X_left (cyclic_basis; e = exp(-i 2 pi nd / N)
!> for the fundamental of a wave of nodal diameter nd travelling forwards). A force channel
!> measures U = D^T X with D = d - e d_next (cyclic_directions): a rigid channel in the limit
!> is the complex constraint D^T T q = 0, an elastic one the spring T^H conj(D) k D^T T
!> (channel_limit_stiffness). The Hermitian pencil on a basis of the constraints' null
!> space (LAPACK zgeqrf, zungqr) is solved by zhegv.
module stickslip_cyclic_limits
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, cyclic_basis, cyclic_directions, &
        hermitian_pencil
    use stickslip_linear_modes, only: channel_limit_stiffness, independence_tolerance, &
        rigid_tolerance
    use stickslip_lapack, only: zgeqrf, zungqr
    implicit none
    private
    public :: cyclic_limit_modes, cyclic_limit_structure

contains

    !> The undamped cyclic modes of the sector `model` at boundary phase `e` (|e| = 1) with
    !> every contact stuck (`stuck`) or slipping: natural frequencies increasing [rad/s] and
    !> the sector's complex shapes (N x m, X^H M X = 1 over the sector's DOFs, each shape's
    !> largest component real and positive). Zero frequencies (motions the contacts leave
    !> free of stiffness) are left out. Errors: those of validate_cyclic (stat input); stat
    !> numerical when the constraints leave no motion or the eigensolver fails.
    subroutine cyclic_limit_modes(model, cyc, e, stuck, omegas, shapes, error)
        !> The sector (a validated model).
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> The phase factor of the next sector.
        complex(dp), intent(in) :: e
        !> Contacts stuck (.true.) or slipping (.false.).
        logical, intent(in) :: stuck
        !> Natural frequencies [rad/s], increasing.
        real(dp), allocatable, intent(out) :: omegas(:)
        !> Mass-normalized complex shapes, N x size(omegas).
        complex(dp), allocatable, intent(out) :: shapes(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        complex(dp), allocatable :: kk(:, :), t(:, :), mr(:, :)
        real(dp), allocatable :: w(:)
        real(dp) :: scale
        integer :: m, info, j, k
        call cyclic_limit_structure(model, cyc, e, stuck, kk, t, error)
        if (allocated(error)) return
        m = size(t, 2)
        kk = matmul(conjg(transpose(t)), matmul(kk, t))
        mr = matmul(conjg(transpose(t)), matmul(cmplx(model%mass, 0.0_dp, dp), t))
        kk = 0.5_dp*(kk + conjg(transpose(kk)))
        mr = 0.5_dp*(mr + conjg(transpose(mr)))
        call hermitian_pencil(kk, mr, w, .true., info)
        if (info /= 0) then
            call fatal_error(error, "cyclic modes: the eigensolver failed (zhegv info "// &
                             itoa(info)//"): the sector's mass is not positive definite on "// &
                             "the cyclic motions the contacts allow", stickslip_stat%numerical)
            return
        end if
        scale = max(maxval(abs(w)), tiny(1.0_dp))
        omegas = sqrt(pack(w, w > rigid_tolerance*scale))
        shapes = matmul(t, kk(:, pack([(j, j=1, m)], w > rigid_tolerance*scale)))
        do j = 1, size(omegas)
            k = maxloc(abs(shapes(:, j)), 1)
            shapes(:, j) = shapes(:, j)*conjg(shapes(k, j))/abs(shapes(k, j))
        end do
    end subroutine cyclic_limit_modes

    !> The sector `model`'s structure in a friction limit at boundary phase `e`: `kk` (K plus
    !> the elastic channels' springs conj(D) k D^T, N x N) and `t` (N x m), a basis of the
    !> cyclic motions X = T q that the rigid channels' constraints D^T X = 0
    !> allow. Errors: those of validate_cyclic (stat input); stat numerical when the QR of
    !> the constraints fails or they leave no motion.
    subroutine cyclic_limit_structure(model, cyc, e, stuck, kk, t, error)
        !> The sector (a validated model).
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> The phase factor of the next sector.
        complex(dp), intent(in) :: e
        !> Contacts stuck (.true.) or slipping (.false.).
        logical, intent(in) :: stuck
        !> Stiffness with the elastic channels' springs [N/m], N x N.
        complex(dp), allocatable, intent(out) :: kk(:, :)
        !> Basis of the allowed cyclic motions, N x m.
        complex(dp), allocatable, intent(out) :: t(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(contact_set_t) :: cs
        complex(dp), allocatable :: dm(:, :), cons(:, :), q(:, :), tau(:), work(:)
        complex(dp) :: query(1)
        real(dp), allocatable :: k(:)
        integer :: n, m, c, ncons, info
        call validate_cyclic(model, cyc, error)
        if (allocated(error)) return
        n = model%ndof
        kk = cmplx(model%stiffness, 0.0_dp, dp)
        t = cyclic_basis(cyc, n, e)
        m = size(t, 2)
        allocate (cons(m, 0))
        if (model%ncontact() > 0) then
            call new_contact_set(cs, model)
            dm = cyclic_directions(model, cyc, cs, e)
            k = channel_limit_stiffness(cs, stuck)
            do c = 1, cs%nchannel
                if (k(c) > 0.0_dp) then
                    kk = kk + k(c)*matmul(conjg(dm(:, c:c)), transpose(dm(:, c:c)))
                else if (k(c) == 0.0_dp) then
                    ! the constraint D^T T q = 0: a column (T^H conj(D)) of the constraints
                    cons = reshape([cons, matmul(conjg(transpose(t)), conjg(dm(:, c)))], &
                                   [m, size(cons, 2) + 1])
                end if
            end do
        end if
        ! independent combinations of the constraints (at nd = 0 a contact against the next
        ! sector constrains nothing: D^T T = 0)
        if (size(cons, 2) > 0) call independent(cons)
        ncons = size(cons, 2)
        if (ncons == 0) return
        if (ncons >= m) then
            call fatal_error(error, "cyclic modes: the stuck contacts hold every cyclic "// &
                             "motion of the sector (no motion left)", stickslip_stat%numerical)
            return
        end if
        ! the null space of cons^H: the last m - ncons columns of the complete Q of cons
        allocate (q(m, m), tau(ncons))
        q = (0.0_dp, 0.0_dp)
        q(:, 1:ncons) = cons
        call zgeqrf(m, ncons, q, m, tau, query, -1, info)
        allocate (work(max(1, int(real(query(1), dp)), 64*m)))
        call zgeqrf(m, ncons, q, m, tau, work, size(work), info)
        if (info == 0) call zungqr(m, m, ncons, q, m, tau, work, size(work), info)
        if (info /= 0) then
            call fatal_error(error, "cyclic modes: QR of the contact constraints failed "// &
                             "(info "//itoa(info)//")", stickslip_stat%numerical)
            return
        end if
        t = matmul(t, q(:, ncons + 1:m))

    contains

        !> Keep independent combinations a V of the columns of a: V the eigenvectors of a^H a
        !> above independence_tolerance of its largest eigenvalue (none when a = 0).
        subroutine independent(a)
            complex(dp), allocatable, intent(inout) :: a(:, :)
            complex(dp), allocatable :: g(:, :), b(:, :)
            real(dp), allocatable :: w(:)
            integer :: nk, j, inf
            nk = size(a, 2)
            g = matmul(conjg(transpose(a)), a)
            allocate (b(nk, nk))
            b = (0.0_dp, 0.0_dp)
            do j = 1, nk
                b(j, j) = (1.0_dp, 0.0_dp)
            end do
            call hermitian_pencil(g, b, w, .true., inf)
            if (inf /= 0 .or. .not. (maxval(w) > 0.0_dp)) then
                deallocate (a)
                allocate (a(m, 0))
                return
            end if
            a = matmul(a, g(:, pack([(j, j=1, nk)], w > independence_tolerance*maxval(w))))
        end subroutine independent
    end subroutine cyclic_limit_structure
end module stickslip_cyclic_limits
