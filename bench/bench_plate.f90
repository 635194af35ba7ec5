!> The cantilever steel plate of the benchmarks (bench_reduction, bench_solver): a plate of
!> fixed physical size (0.4 m x 0.1 m x 10 mm steel, plane stress, bilinear Q4 elements,
!> 2 DOFs per node, consistent mass, clamped at x = 0) meshed with nx x ny elements, assembled
!> in-process from triplets into sparse_matrix_t; its first natural frequency; the contact
!> and forced DOFs of a case (friction contacts against the ground on the transverse (y) DOFs
!> of the upper edge, the first at the tip, the others spread over the outer half; a harmonic
!> transverse force at the lower tip corner); and the dense model_t of a Craig-Bampton
!> reduction of it (the force, friction coefficient and normal loads of bench_reduction).
!>
!> Mesh numbering: nodes (i, j), i = 0..nx along x, j = 0..ny along y, the nodes i = 0
!> clamped; free node p = (i - 1)(ny + 1) + j + 1 has DOFs 2p - 1 (x) and 2p (y), so the
!> model has N = 2 nx (ny + 1) DOFs. The mesh size is passed explicitly: no module state.
!>
!> The module is named with the package prefix because fpm 0.12 enforces the manifest's
!> module-naming = "stickslip" on the modules of examples (not on those of tests).
module stickslip_bench_plate
    use stickslip, only: dp, error_type, model_t, sparse_matrix_t, new_sparse_from_triplets, &
        reduced_model_t, reduced_dof_of, reduction_options_t, reduction_report_t, craig_bampton
    use stickslip_arpack, only: eigen_options_t, eigen_report_t
    use stickslip_sparse_eigen, only: sparse_eigenpairs
    implicit none
    private
    public :: plate, plate_node, element, first_frequency, plate_damping, case_dofs, &
              plate_model, reduced_plate, reduced_plate_unilateral

    !> Plate length along x [m].
    real(dp), parameter, public :: plate_l = 0.4_dp
    !> Plate height along y [m].
    real(dp), parameter, public :: plate_h = 0.1_dp
    !> Plate thickness [m].
    real(dp), parameter, public :: thick = 0.01_dp
    !> Young's modulus [Pa].
    real(dp), parameter, public :: young = 210.0e9_dp
    !> Poisson ratio [-].
    real(dp), parameter, public :: poisson = 0.3_dp
    !> Density [kg/m^3].
    real(dp), parameter, public :: density = 7800.0_dp
    !> Amplitude of the harmonic force at the lower tip corner [N].
    real(dp), parameter, public :: force = 100.0_dp
    !> Friction coefficient of every contact [-].
    real(dp), parameter, public :: mu = 0.3_dp
    !> Total friction limit (sum of mu N over the contacts) / force amplitude [-].
    real(dp), parameter, public :: friction_share = 0.3_dp
    !> Modal damping ratio at the first resonance of the mass-proportional damping [-].
    real(dp), parameter, public :: damping_ratio = 0.01_dp

contains

    !> Stiffness and consistent mass of the clamped plate meshed with nx x ny Q4 elements,
    !> N = 2 nx (ny + 1) DOFs (numbering: see the module). `error` is allocated when the
    !> assembly fails.
    subroutine plate(nx, ny, k, m, error)
        !> Elements along x (the length) and along y (the height) [-].
        integer, intent(in) :: nx, ny
        !> Stiffness matrix [N/m], N x N, symmetric (both triangles stored).
        type(sparse_matrix_t), intent(out) :: k
        !> Mass matrix [kg], N x N, the same pattern as `k`.
        type(sparse_matrix_t), intent(out) :: m
        !> Allocated on failure (the message names the matrix).
        type(error_type), allocatable, intent(out) :: error
        real(dp) :: ke(8, 8), me(8, 8)
        integer, allocatable :: ri(:), ci(:)
        real(dp), allocatable :: kv(:), mv(:)
        integer :: i, j, a, b, t, n, dofs(8), nodes(4), q
        call element(plate_l/nx, plate_h/ny, ke, me)
        n = 2*nx*(ny + 1)
        allocate (ri(64*nx*ny), ci(64*nx*ny), kv(64*nx*ny), mv(64*nx*ny))
        t = 0
        do i = 1, nx
            do j = 1, ny
                ! counter-clockwise: (i-1, j-1), (i, j-1), (i, j), (i-1, j)
                nodes = [plate_node(ny, i - 1, j - 1), plate_node(ny, i, j - 1), &
                         plate_node(ny, i, j), plate_node(ny, i - 1, j)]
                do q = 1, 4
                    dofs(2*q - 1) = merge(2*nodes(q) - 1, 0, nodes(q) > 0)
                    dofs(2*q) = merge(2*nodes(q), 0, nodes(q) > 0)
                end do
                do b = 1, 8
                    if (dofs(b) == 0) cycle
                    do a = 1, 8
                        if (dofs(a) == 0) cycle
                        t = t + 1
                        ri(t) = dofs(a)
                        ci(t) = dofs(b)
                        kv(t) = ke(a, b)
                        mv(t) = me(a, b)
                    end do
                end do
            end do
        end do
        call new_sparse_from_triplets(k, n, n, ri(1:t), ci(1:t), kv(1:t), error)
        if (allocated(error)) then
            error%message = "plate stiffness: "//error%message
            return
        end if
        call new_sparse_from_triplets(m, n, n, ri(1:t), ci(1:t), mv(1:t), error)
        if (allocated(error)) error%message = "plate mass: "//error%message
    end subroutine plate

    !> The free-node number of mesh node (ii, jj), 0 for a clamped node (ii = 0).
    pure integer function plate_node(ny, ii, jj) result(node)
        !> Elements along y (the height) [-].
        integer, intent(in) :: ny
        !> Node column (0..nx, along x) and row (0..ny, along y) [-].
        integer, intent(in) :: ii, jj
        node = 0
        if (ii > 0) node = (ii - 1)*(ny + 1) + jj + 1
    end function plate_node

    !> Stiffness and consistent mass of a rectangular a x b Q4 plane-stress element of the
    !> plate's thickness and material (2 x 2 Gauss points, exact for both), DOFs
    !> (x1, y1, .., x4, y4), nodes counter-clockwise from the lower left corner.
    pure subroutine element(a, b, ke, me)
        !> Element length along x and height along y [m].
        real(dp), intent(in) :: a, b
        !> Element stiffness matrix [N/m].
        real(dp), intent(out) :: ke(8, 8)
        !> Element consistent mass matrix [kg].
        real(dp), intent(out) :: me(8, 8)
        real(dp), parameter :: xi_n(4) = [-1.0_dp, 1.0_dp, 1.0_dp, -1.0_dp], &
                               eta_n(4) = [-1.0_dp, -1.0_dp, 1.0_dp, 1.0_dp]
        real(dp) :: d(3, 3), bm(3, 8), nm(2, 8), g(2), xi, eta, shape(4), dx(4), dy(4), w
        integer :: p, q, i
        g = [-1.0_dp, 1.0_dp]/sqrt(3.0_dp)
        d = reshape([1.0_dp, poisson, 0.0_dp, poisson, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, &
                     0.5_dp*(1.0_dp - poisson)], [3, 3])*young/(1.0_dp - poisson**2)
        ke = 0.0_dp
        me = 0.0_dp
        w = 0.25_dp*a*b*thick
        do p = 1, 2
            do q = 1, 2
                xi = g(p)
                eta = g(q)
                do i = 1, 4
                    shape(i) = 0.25_dp*(1.0_dp + xi*xi_n(i))*(1.0_dp + eta*eta_n(i))
                    dx(i) = 0.25_dp*xi_n(i)*(1.0_dp + eta*eta_n(i))*2.0_dp/a
                    dy(i) = 0.25_dp*eta_n(i)*(1.0_dp + xi*xi_n(i))*2.0_dp/b
                end do
                bm = 0.0_dp
                nm = 0.0_dp
                do i = 1, 4
                    bm(1, 2*i - 1) = dx(i)
                    bm(2, 2*i) = dy(i)
                    bm(3, 2*i - 1) = dy(i)
                    bm(3, 2*i) = dx(i)
                    nm(1, 2*i - 1) = shape(i)
                    nm(2, 2*i) = shape(i)
                end do
                ke = ke + w*matmul(transpose(bm), matmul(d, bm))
                me = me + w*density*matmul(transpose(nm), nm)
            end do
        end do
    end subroutine element

    !> The first natural frequency of the clamped plate (ARPACK, shift-invert at 0).
    subroutine first_frequency(k, m, w, error)
        !> Stiffness [N/m] and mass [kg] of `plate` (symmetric: the CSR arrays are also the
        !> compressed columns).
        type(sparse_matrix_t), intent(in) :: k, m
        !> First natural frequency w1 [rad/s].
        real(dp), intent(out) :: w
        !> Allocated on failure.
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: values(:), vectors(:, :)
        type(eigen_report_t) :: rep
        w = 0.0_dp
        call sparse_eigenpairs(k%nrows, k%row_start, k%col, k%val, m%row_start, m%col, &
                               m%val, 1, 0.0_dp, eigen_options_t(), values, vectors, rep, error)
        if (allocated(error)) return
        w = sqrt(values(1))
    end subroutine first_frequency

    !> The mass-proportional damping of the plate: C = 2 damping_ratio w1 M (damping_ratio
    !> of critical at w1).
    function plate_damping(m, w1) result(c)
        !> Mass matrix [kg].
        type(sparse_matrix_t), intent(in) :: m
        !> First natural frequency [rad/s].
        real(dp), intent(in) :: w1
        !> Damping matrix [N s/m], the pattern of `m`.
        type(sparse_matrix_t) :: c
        c = m
        c%val = 2.0_dp*damping_ratio*w1*m%val
    end function plate_damping

    !> The DOFs of a case with `nc` contacts, in full DOF numbers: the contacts on the y DOFs
    !> of the upper edge (the first at the tip, the others spread evenly over the outer half
    !> of the length), the force on the y DOF of the lower tip corner.
    subroutine case_dofs(nx, ny, nc, contact, forced)
        !> Elements along x (the length) and along y (the height) [-].
        integer, intent(in) :: nx, ny
        !> Number of contacts [-].
        integer, intent(in) :: nc
        !> The contact DOFs (y DOFs of upper-edge nodes) [-], size nc.
        integer, allocatable, intent(out) :: contact(:)
        !> The forced DOF (y DOF of the lower tip corner) [-].
        integer, intent(out) :: forced
        integer :: c, i
        allocate (contact(nc))
        do c = 1, nc
            i = nx
            if (nc > 1) i = nint(nx*(1.0_dp - 0.5_dp*real(c - 1, dp)/real(nc - 1, dp)))
            contact(c) = 2*((i - 1)*(ny + 1) + ny + 1)
        end do
        forced = 2*((nx - 1)*(ny + 1) + 1)
    end subroutine case_dofs

    !> The dense model of a reduced plate case: the reduced matrices of `rm`, the force
    !> `force` cos(omega t) on the forced DOF, a ground contact on every contact DOF with
    !> friction coefficient `mu` and equal normal loads whose friction limits add up to
    !> friction_share x force.
    function plate_model(rm, contact, forced, omega) result(model)
        !> The Craig-Bampton reduction of the plate with [contact, forced] as boundary DOFs.
        type(reduced_model_t), intent(in) :: rm
        !> The contact DOFs and the forced DOF in full DOF numbers (from case_dofs) [-].
        integer, intent(in) :: contact(:), forced
        !> Excitation frequency [rad/s].
        real(dp), intent(in) :: omega
        !> The reduced model (mass [kg], stiffness [N/m], damping [N s/m], force [N],
        !> normal loads [N]).
        type(model_t) :: model
        integer :: k, nc
        nc = size(contact)
        model%ndof = rm%nr
        model%mass = rm%mass
        model%stiffness = rm%stiffness
        model%damping = rm%damping
        model%omega = omega
        model%force_dof = [reduced_dof_of(rm, forced)]
        model%force_harmonic = [1]
        model%force_amplitude = [force]
        model%force_phase = [0.0_dp]
        model%contact_dof = [(reduced_dof_of(rm, contact(k)), k=1, nc)]
        model%contact_dof2 = [(0, k=1, nc)]
        model%mu = [(mu, k=1, nc)]
        model%normal_load = [(friction_share*force/(mu*nc), k=1, nc)]
    end function plate_model

    !> The whole chain for a solver benchmark: assemble the nx x ny plate, its first
    !> frequency w1 and damping, the Craig-Bampton reduction with `nc` contacts and the
    !> mode-count rule of bench_reduction for `harmonics` harmonics (highest_frequency =
    !> harmonics x 1.1 w1), and the reduced model at omega = omega_ratio x w1.
    subroutine reduced_plate(nx, ny, nc, harmonics, omega_ratio, model, w1, n, error)
        !> Elements along x (the length) and along y (the height) [-].
        integer, intent(in) :: nx, ny
        !> Number of contacts [-].
        integer, intent(in) :: nc
        !> Harmonics the reduction is meant for (sets its highest frequency) [-].
        integer, intent(in) :: harmonics
        !> Excitation frequency / w1 [-].
        real(dp), intent(in) :: omega_ratio
        !> The reduced model (see plate_model).
        type(model_t), intent(out) :: model
        !> First natural frequency of the full plate [rad/s].
        real(dp), intent(out) :: w1
        !> DOFs of the full plate model [-].
        integer, intent(out) :: n
        !> Allocated on failure.
        type(error_type), allocatable, intent(out) :: error
        type(sparse_matrix_t) :: k, m, c
        type(reduction_options_t) :: opts
        type(reduction_report_t) :: rep
        type(reduced_model_t) :: rm
        integer, allocatable :: contact(:)
        integer :: forced
        w1 = 0.0_dp
        n = 2*nx*(ny + 1)
        call plate(nx, ny, k, m, error)
        if (allocated(error)) return
        call first_frequency(k, m, w1, error)
        if (allocated(error)) return
        c = plate_damping(m, w1)
        call case_dofs(nx, ny, nc, contact, forced)
        opts = reduction_options_t(highest_frequency=harmonics*1.1_dp*w1)
        call craig_bampton(k, m, [contact, forced], opts, rm, rep, error, cmat=c)
        if (allocated(error)) return
        model = plate_model(rm, contact, forced, omega_ratio*w1)
    end subroutine reduced_plate
    !> The reduced plate with `nc` unilateral contacts (doc/contacts.md) on the upper-edge
    !> nodes of case_dofs: each presses on an obstacle above its node (normal direction -e_y,
    !> gap 0, elastic normal stiffness `kn`, preload `preload`) and rubs along x (friction
    !> coefficient mu on the node's x DOF); with `constant_load`, the same contacts as plain
    !> friction under the constant normal load `preload` (the contact that never opens). The
    !> force of plate_model on the lower tip corner. Boundary DOFs: the contacts' x and y
    !> DOFs and the forced DOF.
    subroutine reduced_plate_unilateral(nx, ny, nc, harmonics, omega_ratio, kn, preload, &
                                        constant_load, model, w1, n, error)
        !> Elements along x (the length) and along y (the height) [-].
        integer, intent(in) :: nx, ny
        !> Number of contacts [-].
        integer, intent(in) :: nc
        !> Harmonics the reduction is meant for (sets its highest frequency) [-].
        integer, intent(in) :: harmonics
        !> Excitation frequency / w1 [-].
        real(dp), intent(in) :: omega_ratio
        !> Normal contact stiffness [N/m] (0: rigid) and preload [N] of every contact.
        real(dp), intent(in) :: kn, preload
        !> Plain friction under the constant normal load `preload` instead.
        logical, intent(in) :: constant_load
        !> The reduced model.
        type(model_t), intent(out) :: model
        !> First natural frequency of the full plate [rad/s].
        real(dp), intent(out) :: w1
        !> DOFs of the full plate model [-].
        integer, intent(out) :: n
        !> Allocated on failure.
        type(error_type), allocatable, intent(out) :: error
        type(sparse_matrix_t) :: k, m, c
        type(reduction_options_t) :: opts
        type(reduction_report_t) :: rep
        type(reduced_model_t) :: rm
        integer, allocatable :: ydof(:), xdof(:)
        integer :: forced, j
        w1 = 0.0_dp
        n = 2*nx*(ny + 1)
        call plate(nx, ny, k, m, error)
        if (allocated(error)) return
        call first_frequency(k, m, w1, error)
        if (allocated(error)) return
        c = plate_damping(m, w1)
        call case_dofs(nx, ny, nc, ydof, forced)
        xdof = ydof - 1
        opts = reduction_options_t(highest_frequency=harmonics*1.1_dp*w1)
        call craig_bampton(k, m, [xdof, ydof, forced], opts, rm, rep, error, cmat=c)
        if (allocated(error)) return
        model = plate_model(rm, xdof, forced, omega_ratio*w1)
        if (constant_load) then
            model%normal_load = [(preload, j=1, nc)]
            return
        end if
        model%normal_load = [(0.0_dp, j=1, nc)]
        allocate (model%normal_direction(model%ndof, nc))
        model%normal_direction = 0.0_dp
        do j = 1, nc
            model%normal_direction(reduced_dof_of(rm, ydof(j)), j) = -1.0_dp
        end do
        model%preload = [(preload, j=1, nc)]
        model%normal_stiffness = [(kn, j=1, nc)]
    end subroutine reduced_plate_unilateral
end module stickslip_bench_plate
