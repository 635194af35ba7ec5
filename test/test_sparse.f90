!> Tests of stickslip_sparse against dense arithmetic done here: assembly from unsorted
!> triplets with duplicates, product, transpose, scaled sum, symmetry defect (scale-free),
!> the size guard of the dense conversion.
module test_sparse
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_matvec, &
        sparse_to_dense, sparse_transpose, sparse_scaled_sum, sparse_symmetry_defect, &
        sparse_from_dense
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_sparse_tests

contains

    subroutine run_sparse_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_assembly(t)
        call test_arithmetic(t)
        call test_symmetry(t)
        call test_limits(t)
    end subroutine run_sparse_tests

    !> Random triplets (unsorted, with duplicates) against a dense accumulation.
    subroutine random_triplets(m, n, nt, rows, cols, vals, dense)
        integer, intent(in) :: m, n, nt
        integer, allocatable, intent(out) :: rows(:), cols(:)
        real(dp), allocatable, intent(out) :: vals(:), dense(:, :)
        real(dp) :: r(3)
        integer :: k
        allocate (rows(nt), cols(nt), vals(nt), dense(m, n))
        dense = 0.0_dp
        do k = 1, nt
            call random_number(r)
            rows(k) = 1 + int(r(1)*m)
            cols(k) = 1 + int(r(2)*n)
            vals(k) = 2.0_dp*r(3) - 1.0_dp
            dense(rows(k), cols(k)) = dense(rows(k), cols(k)) + vals(k)
        end do
    end subroutine random_triplets

    subroutine test_assembly(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        integer, allocatable :: rows(:), cols(:)
        real(dp), allocatable :: vals(:), dense(:, :), d(:, :)
        integer :: i, p
        logical :: sorted
        call random_triplets(7, 5, 60, rows, cols, vals, dense)
        call new_sparse_from_triplets(a, 7, 5, rows, cols, vals, error)
        call check_error(t, error, "sparse: triplets accepted", .false.)
        if (allocated(error)) return
        call sparse_to_dense(a, d, error)
        call check_error(t, error, "sparse: to dense", .false.)
        call check_close(t, reshape(d, [35]), reshape(dense, [35]), &
                         "sparse: duplicates summed = dense accumulation", atol=1e-15_dp)
        sorted = .true.
        do i = 1, a%nrows
            do p = a%row_start(i) + 1, a%row_start(i + 1) - 1
                sorted = sorted .and. a%col(p) > a%col(p - 1)
            end do
        end do
        call check(t, sorted .and. a%nnz() <= 35 .and. a%nnz() == count(d /= 0.0_dp .or. &
                   dense /= 0.0_dp), "sparse: columns strictly increasing, one entry each")
        call new_sparse_from_triplets(a, 3, 3, [1, 4], [1, 1], [1.0_dp, 2.0_dp], error)
        call check_error(t, error, "sparse: row index out of range rejected", .true., &
                         [character(len=20) :: "triplet 2", "(4,1)", "3 x 3"])
        call new_sparse_from_triplets(a, 3, 3, [1], [0], [1.0_dp], error)
        call check_error(t, error, "sparse: column 0 rejected", .true., [character(len=20) :: "(1,0)"])
        call new_sparse_from_triplets(a, 4, 4, [integer ::], [integer ::], [real(dp) ::], error)
        call check_error(t, error, "sparse: empty matrix accepted", .false.)
        call check(t, a%nnz() == 0 .and. all(a%row_start == 1), "sparse: empty matrix")
        call sparse_from_dense(dense, a)
        call sparse_to_dense(a, d, error)
        call check(t, all(d == dense), "sparse: from dense and back, exact")
    end subroutine test_assembly

    subroutine test_arithmetic(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: a, b, c, at
        type(error_type), allocatable :: error
        integer, allocatable :: rows(:), cols(:)
        real(dp), allocatable :: vals(:), da(:, :), db(:, :), d(:, :), y(:)
        real(dp) :: x(6)
        call random_triplets(9, 6, 30, rows, cols, vals, da)
        call new_sparse_from_triplets(a, 9, 6, rows, cols, vals, error)
        call random_triplets(9, 6, 25, rows, cols, vals, db)
        call new_sparse_from_triplets(b, 9, 6, rows, cols, vals, error)
        call random_number(x)
        call sparse_matvec(a, x, y, error)
        call check_error(t, error, "sparse: matvec", .false.)
        call check_close(t, y, matmul(da, x), "sparse: A x = dense product", atol=1e-14_dp)
        call sparse_matvec(a, x(1:5), y, error)
        call check_error(t, error, "sparse: matvec size mismatch", .true., &
                         [character(len=20) :: "5 entries", "6 columns"])
        call sparse_transpose(a, at)
        call sparse_to_dense(at, d, error)
        call check(t, all(d == transpose(da)) .and. at%nrows == 6, "sparse: transpose exact")
        call sparse_scaled_sum(0.3_dp, a, -2.5_dp, b, c, error)
        call check_error(t, error, "sparse: scaled sum", .false.)
        call sparse_to_dense(c, d, error)
        call check_close(t, reshape(d, [54]), reshape(0.3_dp*da - 2.5_dp*db, [54]), &
                         "sparse: alpha A + beta B = dense", atol=1e-15_dp)
        call sparse_scaled_sum(1.0_dp, a, 1.0_dp, at, c, error)
        call check_error(t, error, "sparse: scaled sum of unequal sizes", .true., &
                         [character(len=20) :: "9 x 6", "6 x 9"])
    end subroutine test_arithmetic

    subroutine test_symmetry(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: a
        real(dp) :: d(4, 4)
        call random_number(d)
        d = d + transpose(d)
        call sparse_from_dense(d, a)
        call check(t, sparse_symmetry_defect(a) == 0.0_dp, "sparse: symmetric matrix, defect 0")
        d(1, 3) = d(1, 3) + 1.0e-6_dp*maxval(abs(d))
        call sparse_from_dense(d, a)
        call check_close(t, sparse_symmetry_defect(a), 1.0e-6_dp, &
                         "sparse: defect relative to the largest entry", rtol=1e-6_dp)
        call sparse_from_dense(1.0e9_dp*d, a)
        call check_close(t, sparse_symmetry_defect(a), 1.0e-6_dp, &
                         "sparse: defect independent of the units", rtol=1e-6_dp)
        call sparse_from_dense(d(1:3, :), a)
        call check(t, sparse_symmetry_defect(a) == huge(1.0_dp), "sparse: non-square: huge defect")
        call sparse_from_dense(0.0_dp*d, a)
        call check(t, sparse_symmetry_defect(a) == 0.0_dp, "sparse: zero matrix is symmetric")
    end subroutine test_symmetry

    subroutine test_limits(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        real(dp), allocatable :: d(:, :)
        call new_sparse_from_triplets(a, 100000, 100000, [1], [1], [1.0_dp], error)
        call sparse_to_dense(a, d, error)
        call check_error(t, error, "sparse: dense form beyond 2**25 entries refused", .true., &
                         [character(len=20) :: "100000 x 100000", "2**25"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input .and. &
                                         .not. allocated(d), "sparse: size guard is an input error")
    end subroutine test_limits
end module test_sparse
