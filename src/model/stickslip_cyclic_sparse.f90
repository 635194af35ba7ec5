!> Cyclic symmetry of a sector given as sparse matrices (an FE sector from Matrix Market
!> files): its natural frequencies per nodal diameter, the full disk's matrices, and the
!> error of its Craig-Bampton reduction per nodal diameter.
!>
!> At nodal diameter nd the sector's motions are X = T q, X_right = e X_left, e = exp(i 2 pi
!> nd / N) (stickslip_cyclic). The projected pencil K_c = T^H K T, M_c = T^H M T is
!> Hermitian; written in real arithmetic, H = A + i B acting on (Re q, Im q) is the real
!> symmetric [A -B; B A] of order 2 m, whose eigenvalues are K_c's, each twice (q and i q).
!> The sparse shift-invert block Lanczos on its Cholesky factor (CHOLMOD) solves it; the
!> block handles the double eigenvalues. At nd = 0 and N/2 (e = +-1) B vanishes and the
!> pencil is the real A of order m, solved as it is. The full disk is N copies of the sector
!> with the boundaries merged (disk_dof), each nodal diameter 1 .. N/2 - 1 a double
!> eigenvalue there.
module stickslip_cyclic_sparse
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets
    use stickslip_arpack, only: eigen_options_t, eigen_report_t
    use stickslip_sparse_eigen, only: sparse_eigenpairs
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_stiffness_factor, only: factorize_stiffness
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t, disk_dof_table, cyclic_frequencies
    implicit none
    private
    public :: cyclic_sparse_frequencies, sparse_disk, diameter_frequency_errors

contains

    !> The `count` lowest natural frequencies [rad/s] of the sector (sparse K and M, n x n,
    !> fixed against rigid-body motion) in the cyclic modes of nodal diameter nd (0..N/2).
    !> Errors: nd out of range, count < 1 or >= the cyclic motions (stat input); the
    !> eigensolver's (stat numerical).
    subroutine cyclic_sparse_frequencies(kmat, mmat, cyc, nd, count, omegas, error)
        !> Stiffness and mass of the sector (full storage).
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        !> The symmetry (its DOFs those of kmat).
        type(cyclic_t), intent(in) :: cyc
        !> Nodal diameter and number of frequencies.
        integer, intent(in) :: nd, count
        !> The frequencies, increasing [rad/s].
        real(dp), allocatable, intent(out) :: omegas(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(sparse_matrix_t) :: kr, mr
        type(eigen_report_t) :: report
        class(sparse_factor_t), allocatable :: fac
        real(dp), allocatable :: values(:), vectors(:, :)
        integer :: n, m, order
        logical :: real_phase
        complex(dp) :: e
        n = kmat%nrows
        m = n - size(cyc%right)
        if (nd < 0 .or. nd > cyc%sectors/2) then
            call fatal_error(error, "nodal diameter "//itoa(nd)//": must be 0 to "// &
                             itoa(cyc%sectors/2), stickslip_stat%input)
            return
        end if
        if (count < 1 .or. 2*count >= 2*m) then
            call fatal_error(error, "cyclic frequencies: count = "//itoa(count)// &
                             ": must be 1 to "//itoa(m - 1), stickslip_stat%input)
            return
        end if
        e = exp(cmplx(0.0_dp, two_pi*real(nd, dp)/real(cyc%sectors, dp), dp))
        ! e = +-1: the pencil is real (B = 0), of order m, each eigenvalue once
        real_phase = nd == 0 .or. 2*nd == cyc%sectors
        if (real_phase) e = cmplx(merge(1.0_dp, -1.0_dp, nd == 0), 0.0_dp, dp)
        order = merge(m, 2*m, real_phase)
        call realified(kmat, kr, error)
        if (allocated(error)) return
        call realified(mmat, mr, error)
        if (allocated(error)) return
        ! full storage, symmetric: the CSR arrays are the CSC ones. The real form of a
        ! positive definite K_c is: its Cholesky factor (supernodal on a FE sector) lets the
        ! block Lanczos read it once per block of solves (an LU where it is not)
        call factorize_stiffness(order, kr%row_start, kr%col, kr%val, fac, error)
        if (.not. allocated(error)) then
            call sparse_eigenpairs(order, kr%row_start, kr%col, kr%val, mr%row_start, mr%col, &
                                   mr%val, merge(count, 2*count, real_phase), 0.0_dp, &
                                   eigen_options_t(), values, vectors, report, error, &
                                   factorization=fac)
        end if
        if (allocated(fac)) call fac%release()
        if (allocated(error)) then
            error%message = "cyclic frequencies, nodal diameter "//itoa(nd)//": "// &
                            error%message
            return
        end if
        ! every eigenvalue twice: take one of each pair
        if (real_phase) then
            omegas = sqrt(max(values(1:count), 0.0_dp))
        else
            omegas = sqrt(max(values(1:2*count:2), 0.0_dp))
        end if

    contains

        !> The real form [A -B; B A] of T^H A T (A real, full storage).
        subroutine realified(a, r, error)
            type(sparse_matrix_t), intent(in) :: a
            type(sparse_matrix_t), intent(out) :: r
            type(error_type), allocatable, intent(out) :: error
            integer, allocatable :: col(:), rows(:), cols(:)
            complex(dp), allocatable :: f(:)
            real(dp), allocatable :: vals(:)
            complex(dp) :: c
            integer :: i, j, k, p, q, nt
            ! each DOF's cyclic coordinate and factor: X_j = f_j q_col(j)
            allocate (col(n), f(n))
            q = 0
            do j = 1, n
                if (any(cyc%right == j)) cycle
                q = q + 1
                col(j) = q
                f(j) = (1.0_dp, 0.0_dp)
            end do
            do k = 1, size(cyc%right)
                col(cyc%right(k)) = col(cyc%left(k))
                f(cyc%right(k)) = e
            end do
            nt = merge(1, 4, real_phase)*a%nnz()
            allocate (rows(nt), cols(nt), vals(nt))
            p = 0
            do i = 1, n
                do k = a%row_start(i), a%row_start(i + 1) - 1
                    j = a%col(k)
                    c = conjg(f(i))*a%val(k)*f(j)
                    if (real_phase) then
                        rows(p + 1) = col(i)
                        cols(p + 1) = col(j)
                        vals(p + 1) = real(c, dp)
                        p = p + 1
                    else
                        rows(p + 1:p + 4) = [col(i), col(i), col(i) + m, col(i) + m]
                        cols(p + 1:p + 4) = [col(j), col(j) + m, col(j), col(j) + m]
                        vals(p + 1:p + 4) = [real(c, dp), -aimag(c), aimag(c), real(c, dp)]
                        p = p + 4
                    end if
                end do
            end do
            call new_sparse_from_triplets(r, order, order, rows, cols, vals, error)
        end subroutine realified
    end subroutine cyclic_sparse_frequencies

    !> The full disk's matrix of the sector's `a` (n x n, full storage): N copies with the
    !> boundaries merged, DOF j of sector s at disk_dof(cyc, n, j, s). Errors: those of
    !> new_sparse_from_triplets.
    subroutine sparse_disk(a, cyc, disk, error)
        !> The sector's matrix.
        type(sparse_matrix_t), intent(in) :: a
        !> The symmetry.
        type(cyclic_t), intent(in) :: cyc
        !> The disk's matrix, N (n - boundary pairs) square.
        type(sparse_matrix_t), intent(out) :: disk
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: rows(:), cols(:), g(:, :)
        integer :: n, nt, s, i, k, p
        n = a%nrows
        nt = cyc%sectors*a%nnz()
        allocate (rows(nt), cols(nt), g(n, 0:cyc%sectors - 1))
        g = disk_dof_table(cyc, n)
        p = 0
        do s = 0, cyc%sectors - 1
            do i = 1, n
                do k = a%row_start(i), a%row_start(i + 1) - 1
                    p = p + 1
                    rows(p) = g(i, s)
                    cols(p) = g(a%col(k), s)
                end do
            end do
        end do
        call new_sparse_from_triplets(disk, cyc%sectors*(n - size(cyc%right)), &
                                      cyc%sectors*(n - size(cyc%right)), rows, cols, &
                                      [(a%val, s=1, cyc%sectors)], error)
    end subroutine sparse_disk

    !> The error of a reduced sector per nodal diameter: for each nd of `nds`, the largest
    !> relative difference of its natural frequencies (cyclic_frequencies, dense) from the
    !> full sparse sector's (cyclic_sparse_frequencies), over its frequencies up to `band`
    !> [rad/s] and at least the lowest (at most max_compared). errors(k) belongs to nds(k);
    !> `lowest(k)` is the full sector's lowest frequency there. Errors: those of both.
    subroutine diameter_frequency_errors(kmat, mmat, cyc_full, reduced, cyc_reduced, nds, &
                                         band, errors, lowest, error)
        !> The full sector's stiffness and mass.
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        !> Its symmetry (full numbers).
        type(cyclic_t), intent(in) :: cyc_full
        !> The reduced sector (dense).
        type(model_t), intent(in) :: reduced
        !> Its symmetry (reduced numbers).
        type(cyclic_t), intent(in) :: cyc_reduced
        !> The nodal diameters.
        integer, intent(in) :: nds(:)
        !> The highest frequency compared [rad/s].
        real(dp), intent(in) :: band
        !> Largest relative frequency error per diameter, and the lowest frequency [rad/s].
        real(dp), allocatable, intent(out) :: errors(:), lowest(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer, parameter :: max_compared = 40
        real(dp), allocatable :: wr(:), wf(:)
        integer :: k, ncount
        allocate (errors(size(nds)), lowest(size(nds)))
        do k = 1, size(nds)
            call cyclic_frequencies(reduced, cyc_reduced, nds(k), wr, error)
            if (allocated(error)) return
            ncount = min(max(1, count(wr <= band)), max_compared, size(wr) - 1, &
                         kmat%nrows - size(cyc_full%right) - 1)
            call cyclic_sparse_frequencies(kmat, mmat, cyc_full, nds(k), ncount, wf, error)
            if (allocated(error)) return
            errors(k) = maxval(abs(wr(1:ncount) - wf)/wf)
            lowest(k) = wf(1)
        end do
    end subroutine diameter_frequency_errors
end module stickslip_cyclic_sparse
