!> The undamped linear modes of a model's structure in its two friction limits: every
!> contact stuck (the low-amplitude limit of its nonlinear modes) or every contact slipping
!> freely (the high-amplitude limit). Stuck: a rigid force channel (a tangential direction
!> without tangential_stiffness, a closed unilateral normal without normal_stiffness) is a
!> constraint d^T x = 0, an elastic one a spring k d d^T (k = 1 / its compliance; the
!> sliders of a microslip element in parallel). Slipping: the tangential channels carry
!> nothing (a Jenkins element's slider slips), a closed unilateral normal stays a
!> constraint or a spring. A unilateral contact counts as closed when it is
!> pressed (preload > 0) or its gap is closed (gap <= 0). The constraints are eliminated
!> with an orthonormal basis of their null space (LAPACK QR), the reduced pencil solved by
!> LAPACK dsygv. Dense: for the models the weighted residual solves densely (reduced FE
!> models included).
module stickslip_linear_modes
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_contact_set, only: contact_set_t, new_contact_set, channel_directions
    use stickslip_contact_element, only: channel_t, kinematics_gap
    use stickslip_lapack, only: dsygv, dsyev, dgeqrf, dorgqr
    implicit none
    private
    public :: linear_modes, limit_structure, channel_limit_stiffness, independence_tolerance, &
        rigid_tolerance

    !> Eigenvalues of a constraint set's Gram matrix below this share of the largest are
    !> dependent combinations (singular values below 1e-6 of the largest).
    real(dp), parameter :: independence_tolerance = 1.0e-12_dp
    !> Eigenvalues (omega^2) below this share of the largest are rigid-body motions (their
    !> roundoff, about 1e-16 of the largest): a reduced FE model's pencil spans ten decades
    !> or more, so its lowest genuine modes sit at 1e-11 of the largest.
    real(dp), parameter :: rigid_tolerance = 1.0e-13_dp

contains

    !> The undamped modes of `model` with every contact stuck (`stuck` = .true.) or slipping
    !> (.false.), natural frequencies increasing: omegas [rad/s] and mass-normalized shapes
    !> (N x m, phi^T M phi = I; each shape's largest component positive). Modes of zero
    !> frequency (rigid-body motions of the slipping structure) are left out. Errors (stat
    !> numerical): the constraints leave no motion, the eigensolver fails (M not positive
    !> definite on the free motions).
    subroutine linear_modes(model, stuck, omegas, shapes, error)
        !> A validated model (dense M and K).
        type(model_t), intent(in) :: model
        !> Contacts stuck (.true.) or slipping (.false.).
        logical, intent(in) :: stuck
        !> Natural frequencies [rad/s], increasing.
        real(dp), allocatable, intent(out) :: omegas(:)
        !> Mass-normalized mode shapes, N x size(omegas).
        real(dp), allocatable, intent(out) :: shapes(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: kk(:, :), t(:, :), work(:), kr(:, :), mr(:, :), w(:)
        real(dp) :: wq(1), scale
        integer :: nfree, info, lwork, m, j
        call limit_structure(model, stuck, kk, t, error)
        if (allocated(error)) return
        nfree = size(t, 2)
        kr = matmul(transpose(t), matmul(kk, t))
        mr = matmul(transpose(t), matmul(model%mass, t))
        kr = 0.5_dp*(kr + transpose(kr))
        mr = 0.5_dp*(mr + transpose(mr))
        allocate (w(nfree))
        call dsygv(1, 'V', 'U', nfree, kr, nfree, mr, nfree, w, wq, -1, info)
        lwork = max(1, int(wq(1)), 3*nfree)
        allocate (work(lwork))
        call dsygv(1, 'V', 'U', nfree, kr, nfree, mr, nfree, w, work, lwork, info)
        if (info /= 0) then
            call fatal_error(error, "linear modes: the eigensolver failed (dsygv info "// &
                             itoa(info)//"): the mass matrix is not positive definite on "// &
                             "the motions the contacts allow", stickslip_stat%numerical)
            return
        end if
        ! drop the zero-frequency (rigid-body) modes of a structure held only by friction
        scale = max(maxval(abs(w)), tiny(1.0_dp))
        m = count(w > rigid_tolerance*scale)
        omegas = sqrt(pack(w, w > rigid_tolerance*scale))
        shapes = matmul(t, kr(:, pack([(j, j=1, nfree)], w > rigid_tolerance*scale)))
        do j = 1, m
            if (shapes(maxloc(abs(shapes(:, j)), 1), j) < 0.0_dp) shapes(:, j) = -shapes(:, j)
        end do
    end subroutine linear_modes

    !> The structure of `model` in a friction limit, every contact stuck (`stuck` = .true.)
    !> or slipping (.false.): its stiffness `kk` (K plus the springs k d d^T of the elastic
    !> channels) and an orthonormal basis `t` (N x nfree) of the motions the rigid channels'
    !> constraints d^T x = 0 allow (the identity without constraints). Errors (stat
    !> numerical): the QR of the constraints fails, the constraints leave no motion.
    subroutine limit_structure(model, stuck, kk, t, error)
        !> A validated model (dense M and K).
        type(model_t), intent(in) :: model
        !> Contacts stuck (.true.) or slipping (.false.).
        logical, intent(in) :: stuck
        !> Stiffness with the elastic channels' springs [N/m], N x N.
        real(dp), allocatable, intent(out) :: kk(:, :)
        !> Orthonormal basis of the allowed motions, N x nfree.
        real(dp), allocatable, intent(out) :: t(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(contact_set_t) :: cs
        real(dp), allocatable :: d(:, :), cons(:, :), q(:, :), tau(:), work(:), k(:)
        real(dp) :: wq(1)
        integer :: n, c, j, ncons, nfree, info, lwork
        n = model%ndof
        kk = model%stiffness
        allocate (cons(n, 0))
        if (model%ncontact() > 0) then
            call new_contact_set(cs, model)
            d = channel_directions(model, cs)
            k = channel_limit_stiffness(cs, stuck)
            do c = 1, cs%nchannel
                if (k(c) > 0.0_dp) then
                    kk = kk + k(c)*spread(d(:, c), 2, n)*spread(d(:, c), 1, n)
                else if (k(c) == 0.0_dp) then
                    cons = reshape([cons, d(:, c)], [n, size(cons, 2) + 1])
                end if
            end do
        end if
        ! independent combinations of the constraints (channels that close a ring, e.g.
        ! contacts between the neighbours all round a disk, are dependent)
        if (size(cons, 2) > 0) cons = independent_columns(cons)
        ncons = size(cons, 2)
        ! an orthonormal basis t of the motions the constraints allow: the last columns of
        ! the complete Q of cons = Q R (rank = ncons after the selection)
        if (ncons > 0) then
            allocate (q(n, n), tau(min(n, ncons)))
            q = 0.0_dp
            q(:, 1:ncons) = cons
            call dgeqrf(n, ncons, q, n, tau, wq, -1, info)
            lwork = max(1, int(wq(1)), n*64)
            allocate (work(lwork))
            call dgeqrf(n, ncons, q, n, tau, work, lwork, info)
            if (info == 0) call dorgqr(n, n, min(n, ncons), q, n, tau, work, lwork, info)
            if (info /= 0) then
                call fatal_error(error, "linear modes: QR of the contact constraints failed "// &
                                 "(info "//itoa(info)//")", stickslip_stat%numerical)
                return
            end if
            nfree = n - ncons
            t = q(:, ncons + 1:n)
        else
            nfree = n
            allocate (t(n, n))
            t = 0.0_dp
            do j = 1, n
                t(j, j) = 1.0_dp
            end do
        end if
        if (nfree < 1) then
            call fatal_error(error, "linear modes: the stuck contacts hold every degree of "// &
                             "freedom (no motion left)", stickslip_stat%numerical)
            return
        end if
    end subroutine limit_structure

    !> What each force channel of `cs` is in a friction limit (every contact stuck when
    !> `stuck`, else slipping): its stiffness k > 0 (an elastic channel: 1 / its compliance),
    !> 0 (a rigid one: a constraint d^T x = 0) or -1 (it carries nothing: a slipping
    !> tangential channel, an open unilateral normal). A unilateral normal counts as closed
    !> when pressed (preload > 0) or without a gap (gap <= 0). No errors.
    function channel_limit_stiffness(cs, stuck) result(k)
        !> The contacts.
        type(contact_set_t), intent(in) :: cs
        !> Contacts stuck (.true.) or slipping (.false.).
        logical, intent(in) :: stuck
        real(dp) :: k(cs%nchannel)
        type(channel_t) :: ch
        integer :: c, j
        do c = 1, cs%nchannel
            j = cs%contact_of(c)
            ch = cs%channel(c)
            k(c) = -1.0_dp
            if (ch%kinematics == kinematics_gap) then
                if (.not. (cs%elements(j)%e%preload() > 0.0_dp .or. ch%gap <= 0.0_dp)) cycle
            else if (.not. stuck) then
                cycle
            end if
            k(c) = 0.0_dp
            if (ch%compliance > 0.0_dp) k(c) = 1.0_dp/ch%compliance
        end do
    end function channel_limit_stiffness

    !> Independent combinations spanning the columns of `a` (N x k): a V, V the eigenvectors of
    !> a^T a whose eigenvalues exceed independence_tolerance of the largest (none when a = 0
    !> or the eigensolver fails on a non-finite a). No errors.
    function independent_columns(a) result(b)
        real(dp), intent(in) :: a(:, :)
        real(dp), allocatable :: b(:, :)
        real(dp), allocatable :: g(:, :), w(:), work(:)
        real(dp) :: wq(1)
        integer :: k, info, j
        k = size(a, 2)
        g = matmul(transpose(a), a)
        allocate (w(k))
        call dsyev('V', 'U', k, g, k, w, wq, -1, info)
        allocate (work(max(1, int(wq(1)), 3*k)))
        call dsyev('V', 'U', k, g, k, w, work, size(work), info)
        if (info /= 0 .or. .not. (maxval(w) > 0.0_dp)) then
            allocate (b(size(a, 1), 0))
            return
        end if
        b = matmul(a, g(:, pack([(j, j=1, k)], w > independence_tolerance*maxval(w))))
    end function independent_columns
end module stickslip_linear_modes
