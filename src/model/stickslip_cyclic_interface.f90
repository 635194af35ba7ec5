!> Interface reduction of a reduced sector's cyclic faces (&reduction interface_modes).
!>
!> A Craig-Bampton sector keeps every DOF of its two cyclic faces, so its size grows with the
!> faces' mesh, not with what moves. Here each face is described by p interface modes, one
!> basis Psi (n_f x p) for both: x_left = Psi eta_left, x_right = Psi eta_right. Sector s's
!> right face is sector s + 1's left face, each in its own frame, so with the same Psi on
!> both the cyclic constraint stays exact in the new coordinates (eta_right of sector s =
!> eta_left of sector s + 1): the condensation per harmonic, the assembled disk and the
!> contacts against the next sector work on the pairs (eta_left(i), eta_right(i)) as on DOF
!> pairs. What is lost is the face motion outside the span of Psi.
!>
!> Psi: the p dominant shapes of the faces' motion in the sector's cyclic modes. For every
!> nodal diameter d = 0..N/2 the reduced sector's cyclic modes (X_right = e X_left, e = exp(i
!> 2 pi d / N); zhegv, M-orthonormal) up to the frequency `band` (the run's highest harmonic
!> frequency) give their left-face motion phi_L; C = sum Re(phi_L phi_L^H) / lambda_j (a
!> mode's static share: lambda_j = omega_j^2, floored at (band / 1000)^2) is the faces'
!> motion correlation, and Psi its p eigenvectors of largest eigenvalue (LAPACK dsyev,
!> orthonormal). A mode whose face motion lies in span(Psi) is then in the reduced basis
!> and kept exactly (Rayleigh-Ritz); `share_left_out` (the eigenvalues left out over their
!> sum) says how much is not, and the error per nodal diameter against the full FE sector
!> (stickslip_cyclic_sparse) measures what it costs. Because the snapshots cover every
!> diameter, the same faces serve the travelling wave of any engine order, the nonlinear
!> modes per diameter and the assembled disk.
!>
!> Face pairs that a DOF index of the model or the symmetry names (a contact or forced DOF,
!> a next-sector DOF, a DOF the caller keeps, e.g. an output) stay physical DOFs, both
!> sides. The new DOFs: the old ones that stay, in their order, then eta_left(1..p), then
!> eta_right(1..p). The model's matrices become T^T A T and its directions and load shapes
!> T^T W, with T (n x n2) the transformation x = T x2 (`face_reduction_t%basis`).
module stickslip_cyclic_interface
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_lapack, only: dsyev
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t, cyclic_pencil, hermitian_pencil
    implicit none
    private
    public :: face_reduction_t, reduce_cyclic_faces

    !> What an interface reduction did, and its transformation.
    type :: face_reduction_t
        !> DOFs of each face reduced (pairs not named by a DOF index), interface modes kept.
        integer :: face_dofs = 0
        integer :: modes = 0
        !> Cyclic modes (all nodal diameters) below the band whose face motion was taken.
        integer :: modes_in_band = 0
        !> Share of that motion (weighted, see the module header) outside the interface
        !> modes kept: the sum of the left-out eigenvalues over the sum of all.
        real(dp) :: share_left_out = 0.0_dp
        !> x_old = basis x_new, old DOFs x new DOFs.
        real(dp), allocatable :: basis(:, :)
        !> The new number of each old DOF (0: a face DOF reduced away).
        integer, allocatable :: new_of_old(:)
    end type face_reduction_t

contains

    !> Replace the faces of the sector `model` (symmetry `cyc`, in its numbers) by `modes`
    !> interface modes each (see the module header); `model` and `cyc` are renumbered, the
    !> cyclic modes of `cyc` dropped (they belong to the old sector). `keep`: more DOFs that
    !> must stay physical (any order; 0 ignored). Errors (stat input): modes < 1, band <= 0 or
    !> no cyclic mode below it, no face pair left to reduce, modes >= the face DOFs to reduce;
    !> (stat numerical): a diameter's pencil not definite (zhegv) or dsyev failing. On error
    !> `model` and `cyc` are unchanged.
    subroutine reduce_cyclic_faces(model, cyc, modes, keep, band, red, error)
        !> The sector (dense, e.g. Craig-Bampton reduced); reduced on return.
        type(model_t), intent(inout) :: model
        !> Its symmetry; in the new numbers on return.
        type(cyclic_t), intent(inout) :: cyc
        !> Interface modes per face (p >= 1).
        integer, intent(in) :: modes
        !> DOFs of `model` that stay physical.
        integer, intent(in) :: keep(:)
        !> The cyclic modes up to this frequency shape the interface modes [rad/s] (> 0).
        real(dp), intent(in) :: band
        !> What was done and the transformation.
        type(face_reduction_t), intent(out) :: red
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        logical, allocatable :: named(:), reduce(:)
        integer, allocatable :: lf(:), rf(:), stay(:)
        real(dp), allocatable :: kf(:, :), w(:), work(:)
        real(dp) :: query(1)
        integer :: n, nf, n2, ns, k, info, count_in_band

        n = model%ndof
        if (modes < 1) then
            call fatal_error(error, "must be >= 1", stickslip_stat%input)
            return
        end if
        allocate (named(n))
        named = .false.
        call mark(model%contact_dof)
        call mark(model%contact_dof2)
        call mark(model%force_dof)
        call mark(cyc%next_dof)
        call mark(cyc%next_normal_dof)
        call mark(cyc%next_tangent2_dof)
        call mark(keep)
        reduce = .not. (named(cyc%left) .or. named(cyc%right))
        lf = pack(cyc%left, reduce)
        rf = pack(cyc%right, reduce)
        nf = size(lf)
        if (nf == 0) then
            call fatal_error(error, "every DOF pair of the faces is a "// &
                             "contact, forced, next-sector or output DOF: nothing to reduce", &
                             stickslip_stat%input)
            return
        end if
        if (modes >= nf) then
            call fatal_error(error, "must be less "// &
                             "than the "//itoa(nf)//" DOFs of each face that are reduced "// &
                             "(the face pairs no contact, force, next-sector or output DOF "// &
                             "names)", stickslip_stat%input)
            return
        end if

        ! the faces' motion in the cyclic modes of every nodal diameter up to `band`
        if (.not. (band > 0.0_dp)) then
            call fatal_error(error, "no frequency band to take the faces' motion from (the "// &
                             "run's highest harmonic frequency is 0)", stickslip_stat%input)
            return
        end if
        call face_correlation(kf, error)
        if (allocated(error)) return
        if (count_in_band == 0) then
            call fatal_error(error, "the sector has no cyclic mode below the run's highest "// &
                             "harmonic frequency: nothing shapes the interface modes", &
                             stickslip_stat%input)
            return
        end if
        allocate (w(nf))
        call dsyev('V', 'U', nf, kf, nf, w, query, -1, info)
        allocate (work(max(1, int(query(1)))))
        call dsyev('V', 'U', nf, kf, nf, w, work, size(work), info)
        if (info /= 0) then
            call fatal_error(error, "the faces' motion in the cyclic modes: LAPACK dsyev "// &
                             "info = "//itoa(info), stickslip_stat%numerical)
            return
        end if
        ! dsyev's order is increasing: the shapes that carry most, first
        kf = kf(:, nf:1:-1)
        w = w(nf:1:-1)

        ! the transformation: the DOFs that stay, then eta_left, then eta_right
        allocate (red%new_of_old(n))
        red%new_of_old = 1
        red%new_of_old(lf) = 0
        red%new_of_old(rf) = 0
        stay = pack([(k, k=1, n)], red%new_of_old == 1)
        ns = size(stay)
        n2 = ns + 2*modes
        red%new_of_old = 0
        red%new_of_old(stay) = [(k, k=1, ns)]
        allocate (red%basis(n, n2))
        red%basis = 0.0_dp
        do k = 1, ns
            red%basis(stay(k), k) = 1.0_dp
        end do
        red%basis(lf, ns + 1:ns + modes) = kf(:, 1:modes)
        red%basis(rf, ns + modes + 1:n2) = kf(:, 1:modes)
        red%face_dofs = nf
        red%modes = modes
        red%modes_in_band = count_in_band
        red%share_left_out = sum(max(w(modes + 1:), 0.0_dp))/max(sum(max(w, 0.0_dp)), &
                                                                tiny(1.0_dp))

        ! the model and the symmetry in the new coordinates
        call project(model%mass)
        call project(model%stiffness)
        if (allocated(model%damping)) call project(model%damping)
        call transform(model%contact_direction)
        call transform(model%force_shape)
        call transform(model%normal_direction)
        call transform(model%tangent2_direction)
        call renumber(model%contact_dof)
        call renumber(model%contact_dof2)
        call renumber(model%force_dof)
        call renumber(cyc%next_dof)
        call renumber(cyc%next_normal_dof)
        call renumber(cyc%next_tangent2_dof)
        cyc%left = [red%new_of_old(pack(cyc%left, .not. reduce)), (ns + k, k=1, modes)]
        cyc%right = [red%new_of_old(pack(cyc%right, .not. reduce)), &
                     (ns + modes + k, k=1, modes)]
        if (allocated(cyc%modes)) deallocate (cyc%modes)
        if (allocated(cyc%free_lambda)) deallocate (cyc%free_lambda)
        if (allocated(cyc%free_shapes)) deallocate (cyc%free_shapes)
        cyc%modes_key = 0
        model%ndof = n2

    contains

        !> C = sum over the cyclic modes phi_j of every nodal diameter 0..N/2 with omega_j
        !> <= band of Re(phi_L phi_L^H) / max(lambda_j, lambda_floor) (phi_L: the mode's
        !> motion of the left face DOFs reduced, M-orthonormal modes), lambda_floor = (band /
        !> 1000)^2. Errors (stat numerical): the pencil of a diameter not definite.
        subroutine face_correlation(c, error)
            real(dp), allocatable, intent(out) :: c(:, :)
            type(error_type), allocatable, intent(out) :: error
            complex(dp), allocatable :: t(:, :), kc(:, :), mc(:, :), phi(:)
            real(dp), allocatable :: lam(:)
            integer :: nd, j, status
            allocate (c(nf, nf))
            c = 0.0_dp
            count_in_band = 0
            do nd = 0, cyc%sectors/2
                call cyclic_pencil(model, cyc, nd, t, kc, mc)
                call hermitian_pencil(kc, mc, lam, .true., status)
                if (status /= 0) then
                    call fatal_error(error, "the sector's cyclic modes at nodal diameter "// &
                                     itoa(nd)//": LAPACK zhegv info = "//itoa(status), &
                                     stickslip_stat%numerical)
                    return
                end if
                do j = 1, size(lam)
                    if (lam(j) > band**2) exit
                    phi = matmul(t(lf, :), kc(:, j))
                    c = c + real(spread(phi, 2, nf)*spread(conjg(phi), 1, nf), dp)/ &
                        max(lam(j), (band/1000.0_dp)**2)
                    count_in_band = count_in_band + 1
                end do
            end do
        end subroutine face_correlation

        !> Mark the DOFs 1..n of `dofs` (others, e.g. 0, ignored) as named.
        subroutine mark(dofs)
            integer, intent(in), optional :: dofs(:)
            integer :: j
            if (.not. present(dofs)) return
            do j = 1, size(dofs)
                if (dofs(j) >= 1 .and. dofs(j) <= n) named(dofs(j)) = .true.
            end do
        end subroutine mark

        !> A = T^T A T, symmetric to the last bit (the roundoff of the products made even).
        subroutine project(a)
            real(dp), allocatable, intent(inout) :: a(:, :)
            a = matmul(transpose(red%basis), matmul(a, red%basis))
            a = 0.5_dp*(a + transpose(a))
        end subroutine project

        !> W = T^T W (unallocated: left so).
        subroutine transform(a)
            real(dp), allocatable, intent(inout) :: a(:, :)
            if (.not. allocated(a)) return
            if (size(a, 1) /= n) return
            a = matmul(transpose(red%basis), a)
        end subroutine transform

        !> DOF numbers into the new ones (0 stays 0).
        subroutine renumber(dofs)
            integer, allocatable, intent(inout) :: dofs(:)
            integer :: j
            if (.not. allocated(dofs)) return
            do j = 1, size(dofs)
                if (dofs(j) >= 1 .and. dofs(j) <= n) dofs(j) = red%new_of_old(dofs(j))
            end do
        end subroutine renumber
    end subroutine reduce_cyclic_faces
end module stickslip_cyclic_interface
