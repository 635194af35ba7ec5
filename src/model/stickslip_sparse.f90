!> Sparse real matrices in compressed sparse row (CSR) form with FULL storage: a symmetric
!> matrix holds both triangles (a file that gives one triangle is expanded by its reader), so
!> every operation is the plain one and no operation needs to know about symmetry. Within a
!> row the column indices are strictly increasing (sorted, duplicates summed); explicit zeros
!> may be stored. Plain data and arithmetic: it knows nothing of files nor of solvers.
module stickslip_sparse
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    implicit none
    private
    public :: sparse_matrix_t, new_sparse_from_triplets, sparse_matvec, sparse_to_dense, &
        sparse_transpose, sparse_scaled_sum, sparse_symmetry_defect, sparse_max_abs, &
        sparse_from_dense, max_dense_entries, sparse_times_block

    !> Columns of a block that sparse_times_block multiplies in one pass over the matrix.
    integer, parameter :: block_chunk = 16

    !> Most entries (rows x columns) sparse_to_dense creates: 2**25 doubles = 256 MiB.
    integer(int64), parameter :: max_dense_entries = 2_int64**25

    !> A real nrows x ncols matrix in CSR form, full storage (both triangles of a symmetric
    !> matrix), column indices strictly increasing within each row.
    type :: sparse_matrix_t
        !> Number of rows.
        integer :: nrows = 0
        !> Number of columns.
        integer :: ncols = 0
        !> Row i holds entries row_start(i) .. row_start(i+1)-1 (size nrows + 1).
        integer, allocatable :: row_start(:)
        !> Column index of each stored entry (1-based).
        integer, allocatable :: col(:)
        !> Value of each stored entry.
        real(dp), allocatable :: val(:)
    contains
        !> Number of stored entries.
        procedure :: nnz => sparse_nnz
    end type sparse_matrix_t

contains

    !> Number of stored entries of the matrix.
    pure integer function sparse_nnz(self)
        !> The matrix.
        class(sparse_matrix_t), intent(in) :: self
        sparse_nnz = 0
        if (allocated(self%val)) sparse_nnz = size(self%val)
    end function sparse_nnz

    !> Build `a` (nrows x ncols) from triplets (rows(k), cols(k), vals(k)): entries sorted by
    !> row then column, duplicates summed. Errors (stat input): negative sizes, arrays of
    !> unequal length, an index out of range (named with its position k).
    subroutine new_sparse_from_triplets(a, nrows, ncols, rows, cols, vals, error)
        !> The matrix built.
        type(sparse_matrix_t), intent(out) :: a
        !> Number of rows and columns (>= 0).
        integer, intent(in) :: nrows, ncols
        !> Row and column index (1-based) of each triplet.
        integer, intent(in) :: rows(:), cols(:)
        !> Value of each triplet.
        real(dp), intent(in) :: vals(:)
        !> Set on bad sizes or indices.
        type(error_type), allocatable, intent(out) :: error
        integer :: k, i, p, q, nt, count
        integer, allocatable :: start(:), fill(:), c(:)
        real(dp), allocatable :: v(:)
        integer :: jtmp
        real(dp) :: vtmp

        if (nrows < 0 .or. ncols < 0) then
            call fatal_error(error, "sparse matrix: negative size "//itoa(nrows)//" x "// &
                             itoa(ncols), stickslip_stat%input)
            return
        end if
        nt = size(rows)
        if (size(cols) /= nt .or. size(vals) /= nt) then
            call fatal_error(error, "sparse matrix: rows, cols and vals must have the same "// &
                             "length", stickslip_stat%input)
            return
        end if
        do k = 1, nt
            if (rows(k) < 1 .or. rows(k) > nrows .or. cols(k) < 1 .or. cols(k) > ncols) then
                call fatal_error(error, "sparse matrix: triplet "//itoa(k)//" at ("// &
                                 itoa(rows(k))//","//itoa(cols(k))//") outside "// &
                                 itoa(nrows)//" x "//itoa(ncols), stickslip_stat%input)
                return
            end if
        end do
        ! counting sort by row
        allocate (start(nrows + 1), fill(nrows), c(nt), v(nt))
        start = 0
        do k = 1, nt
            start(rows(k) + 1) = start(rows(k) + 1) + 1
        end do
        start(1) = 1
        do i = 1, nrows
            start(i + 1) = start(i + 1) + start(i)
        end do
        fill = start(1:nrows)
        do k = 1, nt
            i = rows(k)
            c(fill(i)) = cols(k)
            v(fill(i)) = vals(k)
            fill(i) = fill(i) + 1
        end do
        ! sort each row by column (insertion sort: FE rows are short), then sum duplicates
        a%nrows = nrows
        a%ncols = ncols
        allocate (a%row_start(nrows + 1), a%col(nt), a%val(nt))
        count = 0
        a%row_start(1) = 1
        do i = 1, nrows
            do p = start(i) + 1, start(i + 1) - 1
                jtmp = c(p)
                vtmp = v(p)
                q = p - 1
                do while (q >= start(i))
                    if (c(q) <= jtmp) exit
                    c(q + 1) = c(q)
                    v(q + 1) = v(q)
                    q = q - 1
                end do
                c(q + 1) = jtmp
                v(q + 1) = vtmp
            end do
            do p = start(i), start(i + 1) - 1
                if (count >= a%row_start(i)) then
                    if (a%col(count) == c(p)) then
                        a%val(count) = a%val(count) + v(p)
                        cycle
                    end if
                end if
                count = count + 1
                a%col(count) = c(p)
                a%val(count) = v(p)
            end do
            a%row_start(i + 1) = count + 1
        end do
        if (count < nt) then
            a%col = a%col(1:count)
            a%val = a%val(1:count)
        end if
    end subroutine new_sparse_from_triplets

    !> The sparse form of a dense matrix (its nonzero entries).
    subroutine sparse_from_dense(d, a)
        !> The dense matrix.
        real(dp), intent(in) :: d(:, :)
        !> The same matrix, sparse.
        type(sparse_matrix_t), intent(out) :: a
        integer :: i, j, k
        a%nrows = size(d, 1)
        a%ncols = size(d, 2)
        allocate (a%row_start(a%nrows + 1), a%col(count(d /= 0.0_dp)), &
                  a%val(count(d /= 0.0_dp)))
        k = 0
        a%row_start(1) = 1
        do i = 1, a%nrows
            do j = 1, a%ncols
                if (d(i, j) == 0.0_dp) cycle
                k = k + 1
                a%col(k) = j
                a%val(k) = d(i, j)
            end do
            a%row_start(i + 1) = k + 1
        end do
    end subroutine sparse_from_dense

    !> Y = A X for a block X (ncols x k; Y: nrows x k): one pass over A for up to 16 columns
    !> (X transposed so that each entry of A reads a contiguous row of it), the rows shared
    !> among the OpenMP threads when the product is large. On the Rotor 37 blade's mass
    !> matrix (7 million entries) 34 columns cost about what 5 single products did. No
    !> error: the shapes are the caller's (size(x, 1) = ncols, size(y) = [nrows, k]).
    subroutine sparse_times_block(a, x, y)
        !> The matrix.
        type(sparse_matrix_t), intent(in) :: a
        !> The block, ncols x k.
        real(dp), intent(in) :: x(:, :)
        !> The product, nrows x k.
        real(dp), intent(out) :: y(:, :)
        real(dp), allocatable :: xt(:, :)
        real(dp) :: acc(block_chunk)
        integer :: c0, nc, i, p
        logical :: large
        large = real(a%nnz(), dp)*real(size(x, 2), dp) > 4.0e6_dp
        do c0 = 1, size(x, 2), block_chunk
            nc = min(block_chunk, size(x, 2) - c0 + 1)
            xt = transpose(x(:, c0:c0 + nc - 1))
            !$omp parallel do schedule(static) private(i, p, acc) if (large)
            do i = 1, a%nrows
                acc(1:nc) = 0.0_dp
                do p = a%row_start(i), a%row_start(i + 1) - 1
                    acc(1:nc) = acc(1:nc) + a%val(p)*xt(1:nc, a%col(p))
                end do
                y(i, c0:c0 + nc - 1) = acc(1:nc)
            end do
            !$omp end parallel do
        end do
    end subroutine sparse_times_block

    !> y = A x. Errors (stat input) when size(x) /= ncols.
    subroutine sparse_matvec(a, x, y, error)
        !> The matrix.
        type(sparse_matrix_t), intent(in) :: a
        !> The vector (ncols).
        real(dp), intent(in) :: x(:)
        !> The product (nrows).
        real(dp), allocatable, intent(out) :: y(:)
        !> Set on a size mismatch.
        type(error_type), allocatable, intent(out) :: error
        integer :: i, p
        if (size(x) /= a%ncols) then
            call fatal_error(error, "sparse_matvec: x has "//itoa(size(x))// &
                             " entries, the matrix "//itoa(a%ncols)//" columns", &
                             stickslip_stat%input)
            return
        end if
        allocate (y(a%nrows))
        do i = 1, a%nrows
            y(i) = 0.0_dp
            do p = a%row_start(i), a%row_start(i + 1) - 1
                y(i) = y(i) + a%val(p)*x(a%col(p))
            end do
        end do
    end subroutine sparse_matvec

    !> The dense form of `a`. Errors (stat input) when nrows x ncols > max_dense_entries
    !> (2**25 doubles, 256 MiB): the message gives the size, never an allocation failure.
    subroutine sparse_to_dense(a, d, error)
        !> The matrix.
        type(sparse_matrix_t), intent(in) :: a
        !> Its dense form (nrows x ncols).
        real(dp), allocatable, intent(out) :: d(:, :)
        !> Set when the dense form would be too large.
        type(error_type), allocatable, intent(out) :: error
        integer :: i, p
        if (int(a%nrows, int64)*int(a%ncols, int64) > max_dense_entries) then
            call fatal_error(error, "sparse_to_dense: "//itoa(a%nrows)//" x "//itoa(a%ncols)// &
                             " dense matrix is larger than 2**25 entries (256 MiB)", &
                             stickslip_stat%input)
            return
        end if
        allocate (d(a%nrows, a%ncols))
        d = 0.0_dp
        do i = 1, a%nrows
            do p = a%row_start(i), a%row_start(i + 1) - 1
                d(i, a%col(p)) = d(i, a%col(p)) + a%val(p)
            end do
        end do
    end subroutine sparse_to_dense

    !> The transpose of `a`.
    subroutine sparse_transpose(a, b)
        !> The matrix.
        type(sparse_matrix_t), intent(in) :: a
        !> Its transpose (ncols x nrows, columns sorted within rows).
        type(sparse_matrix_t), intent(out) :: b
        integer :: i, p, j
        integer, allocatable :: fill(:)
        b%nrows = a%ncols
        b%ncols = a%nrows
        allocate (b%row_start(b%nrows + 1), b%col(a%nnz()), b%val(a%nnz()), fill(b%nrows))
        b%row_start = 0
        do p = 1, a%nnz()
            b%row_start(a%col(p) + 1) = b%row_start(a%col(p) + 1) + 1
        end do
        b%row_start(1) = 1
        do j = 1, b%nrows
            b%row_start(j + 1) = b%row_start(j + 1) + b%row_start(j)
        end do
        fill = b%row_start(1:b%nrows)
        ! rows of a in increasing order give increasing columns of b
        do i = 1, a%nrows
            do p = a%row_start(i), a%row_start(i + 1) - 1
                j = a%col(p)
                b%col(fill(j)) = i
                b%val(fill(j)) = a%val(p)
                fill(j) = fill(j) + 1
            end do
        end do
    end subroutine sparse_transpose

    !> c = alpha a + beta b (e.g. Rayleigh damping alpha M + beta K). The pattern of c is the
    !> union of the patterns. Errors (stat input) when the sizes differ.
    subroutine sparse_scaled_sum(alpha, a, beta, b, c, error)
        !> Factor of a.
        real(dp), intent(in) :: alpha
        !> First matrix.
        type(sparse_matrix_t), intent(in) :: a
        !> Factor of b.
        real(dp), intent(in) :: beta
        !> Second matrix (same size as a).
        type(sparse_matrix_t), intent(in) :: b
        !> The sum.
        type(sparse_matrix_t), intent(out) :: c
        !> Set on a size mismatch.
        type(error_type), allocatable, intent(out) :: error
        integer :: i, p, q, pe, qe, k
        if (a%nrows /= b%nrows .or. a%ncols /= b%ncols) then
            call fatal_error(error, "sparse_scaled_sum: sizes differ: "//itoa(a%nrows)//" x "// &
                             itoa(a%ncols)//" and "//itoa(b%nrows)//" x "//itoa(b%ncols), &
                             stickslip_stat%input)
            return
        end if
        c%nrows = a%nrows
        c%ncols = a%ncols
        allocate (c%row_start(c%nrows + 1), c%col(a%nnz() + b%nnz()), c%val(a%nnz() + b%nnz()))
        k = 0
        c%row_start(1) = 1
        do i = 1, a%nrows
            p = a%row_start(i)
            pe = a%row_start(i + 1) - 1
            q = b%row_start(i)
            qe = b%row_start(i + 1) - 1
            do while (p <= pe .or. q <= qe)
                k = k + 1
                if (q > qe) then
                    c%col(k) = a%col(p)
                    c%val(k) = alpha*a%val(p)
                    p = p + 1
                else if (p > pe) then
                    c%col(k) = b%col(q)
                    c%val(k) = beta*b%val(q)
                    q = q + 1
                else if (a%col(p) < b%col(q)) then
                    c%col(k) = a%col(p)
                    c%val(k) = alpha*a%val(p)
                    p = p + 1
                else if (b%col(q) < a%col(p)) then
                    c%col(k) = b%col(q)
                    c%val(k) = beta*b%val(q)
                    q = q + 1
                else
                    c%col(k) = a%col(p)
                    c%val(k) = alpha*a%val(p) + beta*b%val(q)
                    p = p + 1
                    q = q + 1
                end if
            end do
            c%row_start(i + 1) = k + 1
        end do
        c%col = c%col(1:k)
        c%val = c%val(1:k)
    end subroutine sparse_scaled_sum

    !> Largest |a_ij| (0 for an empty matrix).
    pure real(dp) function sparse_max_abs(a) result(s)
        !> The matrix.
        type(sparse_matrix_t), intent(in) :: a
        s = 0.0_dp
        if (a%nnz() > 0) s = maxval(abs(a%val))
    end function sparse_max_abs

    !> The symmetry defect of `a` relative to its scale: max |a_ij - a_ji| / max |a_ij|
    !> (0 for a zero matrix; huge(1.0_dp) for a non-square one). A matrix is symmetric to
    !> roundoff when the defect is below ~1e-12. Non-finite entries give a non-finite defect.
    real(dp) function sparse_symmetry_defect(a) result(defect)
        !> The matrix.
        type(sparse_matrix_t), intent(in) :: a
        type(sparse_matrix_t) :: t, d
        type(error_type), allocatable :: error
        real(dp) :: scale
        defect = huge(1.0_dp)
        if (a%nrows /= a%ncols) return
        scale = sparse_max_abs(a)
        defect = 0.0_dp
        if (scale == 0.0_dp) return
        if (.not. ieee_is_finite(scale)) then
            defect = scale
            return
        end if
        call sparse_transpose(a, t)
        call sparse_scaled_sum(1.0_dp, a, -1.0_dp, t, d, error)
        defect = sparse_max_abs(d)/scale
    end function sparse_symmetry_defect
end module stickslip_sparse
