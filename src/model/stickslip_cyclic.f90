!> Cyclic symmetry of a bladed disk: N identical sectors, the right boundary of sector s being
!> the left boundary of sector s + 1 (DOF pairs of the sector model, in its own frame), forced
!> in engine order EO: sector s is forced like sector 0 delayed by EO s / N of a period.
!>
!> Conventions (doc/cyclic.md). A forcing term amplitude cos(h omega t + phase) on sector 0
!> is amplitude cos(h omega t + phase - h sigma s) on sector s, sigma = 2 pi EO / N: a wave
!> travelling forward, towards increasing s. The tuned disk answers with the same wave, x_s(t)
!> = x_0(t - s EO T / N), so at harmonic h every sector's complex amplitude is sector 0's
!> times exp(-i h sigma s), and on the boundary X_right = exp(-i h sigma) X_left: the
!> inter-sector phase of harmonic h is -h sigma, its nodal diameter the distance of h EO to
!> the nearest multiple of N (aliasing: h EO and N - h EO are the same diameter, the wave
!> travelling the other way). A contact of the sector may act against the next sector: its
!> second side on DOF `next_dof` of sector s + 1 (slip velocity v_s(dof) - v_{s+1}(next_dof)),
!> and likewise a normal against `next_normal_dof`; sector s then also receives the reaction
!> of sector s - 1's contact.
!>
!> Here: the description and its checks (cyclic_t, validate_cyclic), the full disk assembled
!> from the sector (assemble_disk: N copies, the boundaries merged, the forcing phased, every
!> contact copied; an ordinary model for every method, e.g. mistuned by hand) and the linear
!> cyclic modes of the sector per nodal diameter (cyclic_frequencies). Dense.
module stickslip_cyclic
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp, two_pi
    use stickslip_hash, only: hash_t
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, force_direction, contact_velocity_direction, &
        contact_normal_direction, contact_tangent2_direction, is_unilateral, is_planar, &
        preload_force
    use stickslip_lapack, only: zhegv, zhegvd
    use stickslip_contact_set, only: contact_set_t, channel_directions
    use stickslip_contact_element, only: along_tangent, along_normal, along_tangent2
    implicit none
    private
    public :: cyclic_t, cyclic_modes_t, validate_cyclic, nodal_diameter, disk_dof, assemble_disk, &
        conjugate_shapes, cyclic_frequencies, sector_phase, channel_displacements, next_of, &
        cyclic_basis, structure_key, disk_dof_table, channel_next_dofs, cyclic_directions, &
        cyclic_preload_force, phased_copies, hermitian_pencil, cyclic_pencil, cyclic_projection

    !> Most sectors of a disk.
    integer, parameter, public :: max_sectors = 1000

    !> The sector's cyclic modes at one nodal diameter nd (stickslip_cyclic_modal): the
    !> pencil of K and M on the motions with X_right = exp(i 2 pi nd / N) X_left, its
    !> eigenvectors M-orthonormal, the damping diagonal on them (proportional damping).
    type :: cyclic_modes_t
        !> The nodal diameter; -1 when not prepared (new_cyclic_dynamics then solves).
        integer :: nd = -1
        !> Eigenvalues lambda_j = omega_j^2 [rad^2/s^2], increasing.
        real(dp), allocatable :: lambda(:)
        !> Modal damping phi_j^H C phi_j [1/s].
        real(dp), allocatable :: damping(:)
        !> The mode shapes on all the sector's DOFs (n x m, the right boundary included),
        !> and their conjugate transpose.
        complex(dp), allocatable :: shapes(:, :), shapes_h(:, :)
    end type cyclic_modes_t

    !> A bladed disk of N identical sectors.
    type :: cyclic_t
        !> Number of sectors N (>= 2).
        integer :: sectors = 0
        !> Engine order of the forcing (>= 0).
        integer :: engine_order = 0
        !> Left and right boundary DOFs of the sector, paired: right(k) of sector s is
        !> left(k) of sector s + 1.
        integer, allocatable :: left(:), right(:)
        !> Per contact (0 or absent: none): the DOF of the next sector its tangential
        !> direction acts against, the one its normal acts against, and the one its second
        !> tangential direction acts against (2D friction against the next sector).
        integer, allocatable :: next_dof(:), next_normal_dof(:), next_tangent2_dof(:)
        !> Optional, per nodal diameter 0 .. N/2: the sector's cyclic modes
        !> (prepare_cyclic_modes), which make the condensation per harmonic a modal sum.
        !> Valid for the sector and the N they were prepared from only (modes_key).
        type(cyclic_modes_t), allocatable :: modes(:)
        !> With `modes`: the smallest singular values of the sector's K and M.
        real(dp) :: smin_k = -1.0_dp, smin_m = -1.0_dp
        !> With `modes`: structure_key of the sector and N they belong to (another
        !> sector's condensation, or this sector's in a disk of another N, ignores them).
        integer(int64) :: modes_key = 0
        !> With `modes` (when prepared): the free sector's modes (its faces free), K Phi =
        !> M Phi Lambda with Phi^H M Phi = I, whose sums give its contact mobility at any
        !> frequency (the automatic rho of solve_periodic_cyclic) without a factorization.
        real(dp), allocatable :: free_lambda(:)
        complex(dp), allocatable :: free_shapes(:, :)
    end type cyclic_t

contains

    !> Check `cyc` against the sector `model`. Errors (stat input) name the component:
    !> cyc%sectors < 2, cyc%engine_order < 0, left and right of other sizes, a DOF out of
    !> range, repeated, or on both boundaries, a contact's next DOF out of range or given to
    !> a contact that has no such direction.
    subroutine validate_cyclic(model, cyc, error)
        !> The sector.
        type(model_t), intent(in) :: model
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=300) :: buf
        integer :: k, n
        buf = ''
        n = model%ndof
        if (cyc%sectors < 2 .or. cyc%sectors > max_sectors) then
            write (buf, '(a,i0,a,i0)') "cyc%sectors = ", cyc%sectors, ": must be 2 to ", &
                max_sectors
        else if (cyc%engine_order < 0) then
            write (buf, '(a,i0,a)') "cyc%engine_order = ", cyc%engine_order, ": must be >= 0"
        else if (.not. (allocated(cyc%left) .and. allocated(cyc%right))) then
            buf = "cyc%left, cyc%right: missing (the boundary DOF pairs)"
        else if (size(cyc%left) /= size(cyc%right)) then
            write (buf, '(a,i0,a,i0,a)') "cyc%left, cyc%right: ", size(cyc%left), " and ", &
                size(cyc%right), " DOFs: the boundaries must pair one to one"
        else if (size(cyc%left) == 0) then
            buf = "cyc%left, cyc%right: no DOF pair (the sectors would not be joined)"
        end if
        if (len_trim(buf) == 0) then
            do k = 1, size(cyc%left)
                if (cyc%left(k) < 1 .or. cyc%left(k) > n) then
                    write (buf, '(a,i0,a,i0,a,i0,a)') "cyc%left(", k, ") = ", cyc%left(k), &
                        ": not a DOF of the sector (1 to ", n, ")"
                else if (cyc%right(k) < 1 .or. cyc%right(k) > n) then
                    write (buf, '(a,i0,a,i0,a,i0,a)') "cyc%right(", k, ") = ", cyc%right(k), &
                        ": not a DOF of the sector (1 to ", n, ")"
                else if (any(cyc%left(1:k - 1) == cyc%left(k))) then
                    write (buf, '(a,i0,a,i0,a)') "cyc%left(", k, ") = ", cyc%left(k), &
                        ": repeated"
                else if (any(cyc%right(1:k - 1) == cyc%right(k))) then
                    write (buf, '(a,i0,a,i0,a)') "cyc%right(", k, ") = ", cyc%right(k), &
                        ": repeated"
                else if (any(cyc%left == cyc%right(k))) then
                    write (buf, '(a,i0,a,i0,a)') "cyc%right(", k, ") = ", cyc%right(k), &
                        ": also a left boundary DOF"
                end if
                if (len_trim(buf) > 0) exit
            end do
        end if
        if (len_trim(buf) == 0) call check_next(cyc%next_dof, "next_dof", along_tangent)
        if (len_trim(buf) == 0) call check_next(cyc%next_normal_dof, "next_normal_dof", &
                                                along_normal)
        if (len_trim(buf) == 0) call check_next(cyc%next_tangent2_dof, "next_tangent2_dof", &
                                                along_tangent2)
        ! a 2D contact against the next sector: both tangents against it, or neither
        if (len_trim(buf) == 0) then
            do k = 1, model%ncontact()
                if (.not. is_planar(model, k)) cycle
                if ((next_of(cyc%next_dof, k) > 0) .eqv. &
                    (next_of(cyc%next_tangent2_dof, k) > 0)) cycle
                if (next_of(cyc%next_dof, k) > 0) then
                    write (buf, '(a,i0,a)') "cyc%next_tangent2_dof(", k, "): missing (a 2D "// &
                        "contact against the next sector, next_dof, needs the next sector's "// &
                        "DOF of its second tangent too)"
                else
                    write (buf, '(a,i0,a)') "cyc%next_tangent2_dof(", k, "): given without "// &
                        "next_dof (a 2D contact rubs on the next sector in both tangents)"
                end if
                exit
            end do
        end if
        if (len_trim(buf) > 0) call fatal_error(error, trim(buf), stickslip_stat%input)

    contains

        subroutine check_next(next, name, along)
            integer, allocatable, intent(in) :: next(:)
            character(len=*), intent(in) :: name
            integer, intent(in) :: along
            integer :: j
            if (.not. allocated(next)) return
            if (size(next) > model%ncontact()) then
                write (buf, '(a,i0,a,i0,a)') "cyc%"//name//": ", size(next), &
                    " values for ", model%ncontact(), " contacts"
                return
            end if
            do j = 1, size(next)
                if (next(j) == 0) cycle
                if (next(j) < 1 .or. next(j) > n) then
                    write (buf, '(a,i0,a,i0,a,i0,a)') "cyc%"//name//"(", j, ") = ", next(j), &
                        ": not a DOF of the next sector (1 to ", n, ")"
                else if (any(cyc%right == next(j))) then
                    write (buf, '(a,i0,a,i0,a)') "cyc%"//name//"(", j, ") = ", next(j), &
                        ": a right boundary DOF (it belongs to the sector after the next: "// &
                        "name that sector's left DOF instead)"
                else if (along == along_normal .and. .not. is_unilateral(model, j)) then
                    write (buf, '(a,i0,a)') "cyc%"//name//"(", j, &
                        "): the contact has no normal direction (normal_dof)"
                else if (along == along_tangent2 .and. .not. is_planar(model, j)) then
                    write (buf, '(a,i0,a)') "cyc%"//name//"(", j, &
                        "): the contact has no second tangent (tangent2_dof: 2D friction)"
                end if
                if (len_trim(buf) > 0) return
            end do
        end subroutine check_next
    end subroutine validate_cyclic

    !> A fingerprint of the sector's structure (ndof, M, K, C) and of the number of sectors
    !> N, what its cyclic modes depend on: a hash of N, of the sums of |A| and of the
    !> quadratic forms v^T A v with v_i = i / n for each matrix (O(n^2), cheap beside a
    !> condensation; another sector or another N gives another key but for a coincidence
    !> of all six). No errors.
    pure integer(int64) function structure_key(model, sectors) result(key)
        !> The sector.
        type(model_t), intent(in) :: model
        !> The number of sectors N of the disk.
        integer, intent(in) :: sectors
        type(hash_t) :: hk
        real(dp), allocatable :: v(:)
        integer :: i
        v = [(real(i, dp)/real(max(model%ndof, 1), dp), i=1, model%ndof)]
        call hk%add(model%ndof)
        call hk%add(sectors)
        call hk%add([sum(abs(model%mass)), dot_product(v, matmul(model%mass, v)), &
                     sum(abs(model%stiffness)), dot_product(v, matmul(model%stiffness, v))])
        call hk%add(allocated(model%damping))
        if (allocated(model%damping)) call hk%add([sum(abs(model%damping)), &
                                                  dot_product(v, matmul(model%damping, v))])
        key = hk%value()
    end function structure_key

    !> Entry j of a per-contact list of next-sector DOFs (cyclic_t%next_dof,
    !> next_normal_dof): 0 when the list is absent or shorter.
    pure integer function next_of(list, j)
        !> The list.
        integer, allocatable, intent(in) :: list(:)
        !> The contact.
        integer, intent(in) :: j
        next_of = 0
        if (.not. allocated(list)) return
        if (j <= size(list)) next_of = list(j)
    end function next_of

    !> Each force channel's DOF on the next sector (0: none): the `next_dof` of a tangential
    !> channel's contact, the `next_normal_dof` of a normal one. No errors.
    function channel_next_dofs(cyc, contacts) result(next)
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> The sector's contacts.
        type(contact_set_t), intent(in) :: contacts
        integer :: next(contacts%nchannel)
        integer :: c, j
        next = 0
        do c = 1, contacts%nchannel
            j = contacts%contact_of(c)
            if (contacts%along(c) == along_tangent) next(c) = next_of(cyc%next_dof, j)
            if (contacts%along(c) == along_normal) next(c) = next_of(cyc%next_normal_dof, j)
            if (contacts%along(c) == along_tangent2) &
                next(c) = next_of(cyc%next_tangent2_dof, j)
        end do
    end function channel_next_dofs

    !> The measuring directions of the sector's force channels at boundary phase e (the
    !> next sector's motion is this one's times e): D = d - e d_next, N x channels; a channel
    !> measures U = D^T X and pushes the sector with conj(D) R. No errors.
    function cyclic_directions(model, cyc, contacts, e) result(dm)
        !> The sector.
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> The sector's contacts.
        type(contact_set_t), intent(in) :: contacts
        !> The phase factor of the next sector.
        complex(dp), intent(in) :: e
        complex(dp), allocatable :: dm(:, :)
        integer :: next(contacts%nchannel), c
        dm = cmplx(channel_directions(model, contacts), 0.0_dp, dp)
        next = channel_next_dofs(cyc, contacts)
        do c = 1, contacts%nchannel
            if (next(c) > 0) dm(next(c), c) = dm(next(c), c) - e
        end do
    end function cyclic_directions

    !> The static load of the preloads on the sector [N]: each pressed contact's preload
    !> along its normal (preload_force), and for a contact against the next sector
    !> (next_normal_dof) its next DOF pressed back, the reaction of the previous sector's
    !> contact on a tuned disk (the pair acts along D = d - d_next). No errors.
    function cyclic_preload_force(model, cyc) result(f)
        !> The sector.
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        real(dp) :: f(model%ndof)
        integer :: k, b
        f = preload_force(model)
        if (.not. allocated(model%preload)) return
        do k = 1, size(model%preload)
            b = next_of(cyc%next_normal_dof, k)
            if (b > 0) f(b) = f(b) + model%preload(k)
        end do
    end function cyclic_preload_force

    !> The sector's cyclic motions for the boundary phase e, n x (n - boundary pairs): the
    !> DOFs off the right boundary free (an identity column each, in their order), the right
    !> boundary the paired left DOF times e (X_right = e X_left). No errors.
    pure function cyclic_basis(cyc, n, e) result(t)
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> DOFs of the sector.
        integer, intent(in) :: n
        !> The phase factor of the right boundary.
        complex(dp), intent(in) :: e
        complex(dp) :: t(n, n - size(cyc%right))
        integer :: j, k, col
        t = (0.0_dp, 0.0_dp)
        col = 0
        do j = 1, n
            if (any(cyc%right == j)) cycle
            col = col + 1
            t(j, col) = (1.0_dp, 0.0_dp)
            do k = 1, size(cyc%left)
                if (cyc%left(k) == j) t(cyc%right(k), col) = e
            end do
        end do
    end function cyclic_basis

    !> The nodal diameter of harmonic h under engine order eo on n sectors: h eo modulo n,
    !> folded to 0..n/2 (h eo and n - h eo are the same diameter, travelling the other way).
    pure integer function nodal_diameter(h, eo, n) result(nd)
        !> Harmonic, engine order, sectors.
        integer, intent(in) :: h, eo, n
        nd = modulo(h*eo, n)
        if (nd > n/2) nd = n - nd
    end function nodal_diameter

    !> Whether harmonic h under engine order eo on n sectors uses the conjugates of its
    !> diameter's prepared shapes (cyclic_modes_t): its inter-sector phase exp(-i 2 pi p /
    !> N), p = h eo modulo n, is the conjugate of the diameter's basis when p <= n/2
    !> (stickslip_cyclic_modal).
    pure logical function conjugate_shapes(h, eo, n)
        !> Harmonic, engine order, sectors.
        integer, intent(in) :: h, eo, n
        conjugate_shapes = modulo(h*eo, n) == nodal_diameter(h, eo, n)
    end function conjugate_shapes

    !> The phase of harmonic h of sector s relative to sector 0 in a travelling wave of
    !> engine order eo on n sectors: -h 2 pi eo s / n [rad] (X_s = X_0 exp(i phase)).
    pure real(dp) function sector_phase(h, eo, n, s) result(phase)
        !> Harmonic, engine order, sectors, sector (0-based).
        integer, intent(in) :: h, eo, n, s
        phase = -two_pi*real(modulo(h*eo*s, n), dp)/real(n, dp)
    end function sector_phase

    !> The DOF of the full disk that DOF j of sector s (0-based) is: the sector's DOFs other
    !> than its right boundary, sector after sector, in their order; a right boundary DOF
    !> is the paired left DOF of sector s + 1 (modulo N).
    pure integer function disk_dof(cyc, n, j, s) result(g)
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> DOFs of the sector, the DOF and the sector.
        integer, intent(in) :: n, j, s
        integer :: k, kept, t, jj
        ! a right boundary DOF is its left partner one sector on (never itself on the
        ! right: validate_cyclic refuses a two-sided DOF)
        t = modulo(s, cyc%sectors)
        jj = j
        do k = 1, size(cyc%right)
            if (cyc%right(k) == j) then
                jj = cyc%left(k)
                t = modulo(t + 1, cyc%sectors)
                exit
            end if
        end do
        kept = n - size(cyc%right)
        g = t*kept + jj - count(cyc%right < jj)
    end function disk_dof

    !> disk_dof for every DOF of every sector: g(j, s), n x (0 .. N - 1) (assign it to an
    !> array allocated with those bounds: an expression's lower bounds are 1).
    pure function disk_dof_table(cyc, n) result(g)
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> DOFs of the sector.
        integer, intent(in) :: n
        integer :: g(n, 0:cyc%sectors - 1)
        integer :: j, s
        do s = 0, cyc%sectors - 1
            do j = 1, n
                g(j, s) = disk_dof(cyc, n, j, s)
            end do
        end do
    end function disk_dof_table

    !> The full disk of `sector`: N copies with their boundaries merged (M, K and C
    !> assembled), every forcing term on every sector with its travelling-wave phase (a load
    !> shape each), every contact on every sector (its directions scattered; one against
    !> the next sector reaching into it), in sector order: contact j of sector s is contact
    !> s n_c + j. Contact laws are copied. Errors: those of validate_cyclic.
    subroutine assemble_disk(sector, cyc, disk, error)
        !> The sector (a validated model).
        type(model_t), intent(in) :: sector
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> The disk.
        type(model_t), intent(out) :: disk
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: n, nd, ns, s, i, j, nc, nf, c
        integer, allocatable :: g(:, :)
        logical :: unilateral, planar
        call validate_cyclic(sector, cyc, error)
        if (allocated(error)) return
        n = sector%ndof
        ns = cyc%sectors
        nd = ns*(n - size(cyc%right))
        allocate (g(n, 0:ns - 1))
        g = disk_dof_table(cyc, n)
        disk%ndof = nd
        disk%omega = sector%omega
        allocate (disk%mass(nd, nd), disk%stiffness(nd, nd), disk%damping(nd, nd))
        disk%mass = 0.0_dp
        disk%stiffness = 0.0_dp
        disk%damping = 0.0_dp
        do s = 0, ns - 1
            do j = 1, n
                do i = 1, n
                    disk%mass(g(i, s), g(j, s)) = disk%mass(g(i, s), g(j, s)) + sector%mass(i, j)
                    disk%stiffness(g(i, s), g(j, s)) = disk%stiffness(g(i, s), g(j, s)) + &
                                                       sector%stiffness(i, j)
                    disk%damping(g(i, s), g(j, s)) = disk%damping(g(i, s), g(j, s)) + &
                                                     sector%damping(i, j)
                end do
            end do
        end do
        ! the forcing: each term on each sector, phased
        nf = sector%nforce()
        allocate (disk%force_shape(nd, nf*ns), disk%force_harmonic(nf*ns), &
                  disk%force_amplitude(nf*ns), disk%force_phase(nf*ns), disk%force_dof(0))
        disk%force_shape = 0.0_dp
        do s = 0, ns - 1
            do i = 1, nf
                c = s*nf + i
                disk%force_shape(:, c) = scatter(force_direction(sector, i), s)
                disk%force_harmonic(c) = sector%force_harmonic(i)
                disk%force_amplitude(c) = sector%force_amplitude(i)
                disk%force_phase(c) = sector%force_phase(i) + &
                                      sector_phase(sector%force_harmonic(i), cyc%engine_order, &
                                                   ns, s)
            end do
        end do
        ! the contacts: directions scattered, scalars copied, laws copied
        nc = sector%ncontact()
        unilateral = .false.
        planar = .false.
        do j = 1, nc
            unilateral = unilateral .or. is_unilateral(sector, j)
            planar = planar .or. is_planar(sector, j)
        end do
        allocate (disk%contact_direction(nd, nc*ns), disk%contact_dof(0), disk%contact_dof2(0))
        if (unilateral) allocate (disk%normal_direction(nd, nc*ns))
        if (planar) allocate (disk%tangent2_direction(nd, nc*ns))
        disk%mu = [(sector%mu, s=1, ns)]
        disk%normal_load = [(sector%normal_load, s=1, ns)]
        call copy_scalars(sector%gap, disk%gap)
        call copy_scalars(sector%preload, disk%preload)
        call copy_scalars(sector%normal_stiffness, disk%normal_stiffness)
        call copy_scalars(sector%tangential_stiffness, disk%tangential_stiffness)
        if (allocated(sector%laws)) then
            if (size(sector%laws) > 0) allocate (disk%laws(nc*ns))
        end if
        do s = 0, ns - 1
            do j = 1, nc
                c = s*nc + j
                ! the second side on the next sector: slip velocity v_s(dof) - v_{s+1}(b)
                disk%contact_direction(:, c) = &
                    against_next(contact_velocity_direction(sector, j), cyc%next_dof, j, s)
                if (unilateral) disk%normal_direction(:, c) = &
                    against_next(contact_normal_direction(sector, j), cyc%next_normal_dof, j, s)
                if (planar) disk%tangent2_direction(:, c) = &
                    against_next(contact_tangent2_direction(sector, j), cyc%next_tangent2_dof, &
                                 j, s)
                if (allocated(disk%laws)) then
                    if (allocated(sector%laws(j)%e)) &
                        allocate (disk%laws(c)%e, source=sector%laws(j)%e)
                end if
            end do
        end do

    contains

        !> A vector of the sector's DOFs on sector s of the disk.
        function scatter(v, s) result(w)
            real(dp), intent(in) :: v(:)
            integer, intent(in) :: s
            real(dp) :: w(nd)
            integer :: k
            w = 0.0_dp
            do k = 1, n
                w(g(k, s)) = w(g(k, s)) + v(k)
            end do
        end function scatter

        !> Direction v of contact j on sector s, minus the unit vector of its next-sector
        !> DOF (entry j of `next`, 0 or absent: none) on sector s + 1.
        function against_next(v, next, j, s) result(w)
            real(dp), intent(in) :: v(:)
            integer, allocatable, intent(in) :: next(:)
            integer, intent(in) :: j, s
            real(dp) :: w(nd)
            w = scatter(v, s)
            if (next_of(next, j) > 0) w(g(next_of(next, j), modulo(s + 1, ns))) = &
                w(g(next_of(next, j), modulo(s + 1, ns))) - 1.0_dp
        end function against_next

        subroutine copy_scalars(a, b)
            real(dp), allocatable, intent(in) :: a(:)
            real(dp), allocatable, intent(out) :: b(:)
            integer :: k
            if (allocated(a)) b = [(a, k=1, ns)]
        end subroutine copy_scalars
    end subroutine assemble_disk

    !> The whole disk's coefficients of a travelling wave from sector 0's `coef` (nb x m, rows
    !> of harmonics `harmonic`: cos then sin): nb x (m N), sector s's m columns after sector
    !> s - 1's, each harmonic h times exp(-i h 2 pi EO s / N) (X = a - i b). No errors.
    pure function phased_copies(coef, harmonic, cyc) result(all)
        !> Sector 0's coefficients.
        real(dp), intent(in) :: coef(:, :)
        !> Harmonic of each row.
        integer, intent(in) :: harmonic(:)
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        real(dp) :: all(size(coef, 1), size(coef, 2)*cyc%sectors)
        complex(dp) :: z
        integer :: nb, m, s, c, k
        nb = size(coef, 1)
        m = size(coef, 2)
        do s = 0, cyc%sectors - 1
            do c = 1, m
                k = 1
                do while (k <= nb)
                    if (harmonic(k) == 0) then
                        all(k, s*m + c) = coef(k, c)
                        k = k + 1
                        cycle
                    end if
                    z = cmplx(coef(k, c), -coef(k + 1, c), dp)* &
                        exp(cmplx(0.0_dp, sector_phase(harmonic(k), cyc%engine_order, &
                                                       cyc%sectors, s), dp))
                    all(k, s*m + c) = real(z, dp)
                    all(k + 1, s*m + c) = -aimag(z)
                    k = k + 2
                end do
            end do
        end do
    end function phased_copies

    !> The Fourier coefficients of the displacement along each force channel of the sector
    !> `model` (nb x channels [m]) from its DOFs' coefficients `xcoef` (nb x N, rows of
    !> harmonics `harmonic`: cos then sin): d^T x, and for a channel against the next sector
    !> d^T x - x_next(b), the next sector's motion being this one's delayed by EO / N of the
    !> period (harmonic h: times exp(-i h 2 pi EO / N)). No errors.
    function channel_displacements(model, cyc, contacts, harmonic, xcoef) result(u)
        !> The sector.
        type(model_t), intent(in) :: model
        !> The disk.
        type(cyclic_t), intent(in) :: cyc
        !> The sector's contacts.
        type(contact_set_t), intent(in) :: contacts
        !> Harmonic of each row.
        integer, intent(in) :: harmonic(:)
        !> Coefficients of the DOFs.
        real(dp), intent(in) :: xcoef(:, :)
        real(dp), allocatable :: u(:, :)
        real(dp), allocatable :: d(:, :)
        integer :: c, k, b, h, next(contacts%nchannel)
        complex(dp) :: e, x
        d = channel_directions(model, contacts)
        u = matmul(xcoef, d)
        next = channel_next_dofs(cyc, contacts)
        do c = 1, contacts%nchannel
            b = next(c)
            if (b == 0) cycle
            k = 1
            do while (k <= size(harmonic))
                h = harmonic(k)
                if (h == 0) then
                    u(k, c) = u(k, c) - xcoef(k, b)
                    k = k + 1
                    cycle
                end if
                ! rows k, k + 1: a cos + b sin = Re((a - i b) exp(i h omega t))
                e = exp(cmplx(0.0_dp, sector_phase(h, cyc%engine_order, cyc%sectors, 1), dp))
                x = e*cmplx(xcoef(k, b), -xcoef(k + 1, b), dp)
                u(k, c) = u(k, c) - real(x, dp)
                u(k + 1, c) = u(k + 1, c) + aimag(x)
                k = k + 2
            end do
        end do
    end function channel_displacements

    !> The sector's stiffness and mass on the cyclic motions of nodal diameter nd: t =
    !> cyclic_basis(cyc, n, exp(i 2 pi nd / N)) (n x m), kc = t^H K t and mc = t^H M t (m x m,
    !> Hermitian). No errors.
    pure subroutine cyclic_pencil(sector, cyc, nd, t, kc, mc)
        !> The sector.
        type(model_t), intent(in) :: sector
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> The nodal diameter.
        integer, intent(in) :: nd
        !> The cyclic motions and the projected stiffness and mass.
        complex(dp), allocatable, intent(out) :: t(:, :), kc(:, :), mc(:, :)
        complex(dp) :: e
        e = exp(cmplx(0.0_dp, two_pi*real(nd, dp)/real(cyc%sectors, dp), dp))
        t = cyclic_basis(cyc, sector%ndof, e)
        kc = cyclic_projection(sector%stiffness, cyc, e)
        mc = cyclic_projection(sector%mass, cyc, e)
    end subroutine cyclic_pencil

    !> t^H A t for t = cyclic_basis(cyc, n, e) (A real, n x n; the result m x m, m = n -
    !> the right boundary DOFs), from A's columns and rows: column j of t is 1 on its DOF
    !> and e on that DOF's right partner when it is a left boundary DOF, so the product
    !> costs n m operations instead of a dense product's n^2 m (a reduced FE sector of a
    !> thousand DOFs, projected on every nodal diameter). No errors.
    pure function cyclic_projection(a, cyc, e) result(r)
        !> The sector's matrix.
        real(dp), intent(in) :: a(:, :)
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> The phase factor of the right boundary.
        complex(dp), intent(in) :: e
        complex(dp), allocatable :: r(:, :)
        complex(dp), allocatable :: at(:, :)
        integer, allocatable :: dof(:), partner(:)
        integer :: n, m, j, k
        n = size(a, 1)
        m = n - size(cyc%right)
        allocate (dof(m), partner(m), at(n, m), r(m, m))
        partner = 0
        j = 0
        do k = 1, n
            if (any(cyc%right == k)) cycle
            j = j + 1
            dof(j) = k
        end do
        do k = 1, size(cyc%left)
            j = findloc(dof, cyc%left(k), 1)
            partner(j) = cyc%right(k)
        end do
        ! A t, column by column; then t^H (A t), row by row
        do j = 1, m
            at(:, j) = cmplx(a(:, dof(j)), 0.0_dp, dp)
            if (partner(j) > 0) at(:, j) = at(:, j) + e*a(:, partner(j))
        end do
        do j = 1, m
            r(j, :) = at(dof(j), :)
            if (partner(j) > 0) r(j, :) = r(j, :) + conjg(e)*at(partner(j), :)
        end do
    end function cyclic_projection

    !> The Hermitian-definite pencil A v = lambda B v (LAPACK zhegv with its workspace query;
    !> zhegvd, divide and conquer, when the eigenvectors are wanted):
    !> `w` the eigenvalues, increasing; with `vectors` A holds the B-orthonormal eigenvectors
    !> on return (B is overwritten either way). info: zhegv's (nonzero: B not positive
    !> definite, or no convergence).
    subroutine hermitian_pencil(a, b, w, vectors, info)
        !> A, n x n; the eigenvectors with `vectors`.
        complex(dp), intent(inout) :: a(:, :)
        !> B, n x n, positive definite.
        complex(dp), intent(inout) :: b(:, :)
        !> The eigenvalues.
        real(dp), allocatable, intent(out) :: w(:)
        !> Compute the eigenvectors.
        logical, intent(in) :: vectors
        !> zhegv's info.
        integer, intent(out) :: info
        complex(dp), allocatable :: work(:)
        complex(dp) :: query(1)
        real(dp), allocatable :: rwork(:)
        real(dp) :: rquery(1)
        integer, allocatable :: iwork(:)
        integer :: n, iquery(1)
        n = size(a, 1)
        allocate (w(n))
        if (vectors) then
            ! divide and conquer: the eigenvectors of a reduced FE sector's pencil (a
            ! thousand DOFs) in a fraction of the QR iteration's time
            call zhegvd(1, 'V', 'U', n, a, n, b, n, w, query, -1, rquery, -1, iquery, -1, info)
            if (info /= 0) return
            allocate (work(max(1, int(real(query(1), dp)))), &
                      rwork(max(1, int(rquery(1)))), iwork(max(1, iquery(1))))
            call zhegvd(1, 'V', 'U', n, a, n, b, n, w, work, size(work), rwork, size(rwork), &
                        iwork, size(iwork), info)
        else
            allocate (rwork(max(1, 3*n - 2)))
            call zhegv(1, 'N', 'U', n, a, n, b, n, w, query, -1, rwork, info)
            allocate (work(max(1, int(real(query(1), dp)), 2*n)))
            call zhegv(1, 'N', 'U', n, a, n, b, n, w, work, size(work), rwork, info)
        end if
    end subroutine hermitian_pencil

    !> The undamped natural frequencies [rad/s], increasing, of the sector's structure (M and
    !> K, its contacts carrying nothing) in the cyclic modes of nodal diameter `nd`: sector
    !> s moves as sector 0 times exp(i 2 pi nd s / N), so X_right = exp(i 2 pi nd / N)
    !> X_left, and the sector's pencil is projected on those motions (Hermitian, LAPACK
    !> zhegv). Each frequency of 0 < nd < N/2 is a double one of the disk (the waves
    !> travelling either way). Errors: those of validate_cyclic; nd outside 0..N/2 (stat
    !> input); the eigensolver failing (stat numerical).
    subroutine cyclic_frequencies(sector, cyc, nd, omegas, error)
        !> The sector (a validated model).
        type(model_t), intent(in) :: sector
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> The nodal diameter.
        integer, intent(in) :: nd
        !> The natural frequencies [rad/s].
        real(dp), allocatable, intent(out) :: omegas(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        complex(dp), allocatable :: t(:, :), kc(:, :), mc(:, :)
        real(dp), allocatable :: w(:)
        integer :: info
        call validate_cyclic(sector, cyc, error)
        if (allocated(error)) return
        if (nd < 0 .or. nd > cyc%sectors/2) then
            call fatal_error(error, "nodal diameter "//itoa(nd)//": must be 0 to "// &
                             itoa(cyc%sectors/2), stickslip_stat%input)
            return
        end if
        call cyclic_pencil(sector, cyc, nd, t, kc, mc)
        call hermitian_pencil(kc, mc, w, .false., info)
        if (info /= 0) then
            call fatal_error(error, "cyclic modes: the eigensolver failed (zhegv info "// &
                             itoa(info)//"): the sector's mass is not positive definite on "// &
                             "the cyclic motions", stickslip_stat%numerical)
            return
        end if
        omegas = sqrt(max(w, 0.0_dp))
    end subroutine cyclic_frequencies
end module stickslip_cyclic
