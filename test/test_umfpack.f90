!> stickslip_umfpack: sparse LU (UMFPACK) against dense LAPACK solves of the same matrices:
!> a random sparse nonsymmetric real matrix with several right-hand sides, a refactorization
!> on the same pattern, a random sparse complex Z = K - w^2 M + i w C, and the failures: a
!> singular real matrix, an undamped resonance (complex singular), bad patterns, a NaN, a
!> solve without a factorization; the orderings, refinement off, and move_to.
module test_umfpack
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_lapack, only: dgesv, zgesv
    use stickslip_umfpack, only: sparse_lu_t, sparse_zlu_t, ordering_amd, ordering_cholmod, &
        ordering_metis
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_umfpack_tests, dense_to_csc

contains

    subroutine run_umfpack_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_real(t)
        call test_complex(t)
        call test_failures(t)
        call test_options(t)
    end subroutine run_umfpack_tests

    !> The orderings (AMD, CHOLMOD's choice, METIS) and refinement off solve as dgesv does;
    !> move_to hands a factorization over (the source empty, the target solving).
    subroutine test_options(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 80
        real(dp) :: a(n, n), lu(n, n), b(n), xd(n), xs(n)
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: values(:)
        integer :: ipiv(n), info, k
        integer, parameter :: orderings(3) = [ordering_amd, ordering_cholmod, ordering_metis]
        type(sparse_lu_t) :: slu, other
        type(error_type), allocatable :: error
        call random_sparse(n, 0.08_dp, 0.5_dp, a)
        call random_number(b)
        call dense_to_csc(a, colptr, rowind, values)
        lu = a
        xd = b
        call dgesv(n, 1, lu, n, ipiv, xd, n, info)
        do k = 1, 3
            slu%ordering = orderings(k)
            slu%refinement_steps = mod(k, 2)*2
            call slu%factorize(n, colptr, rowind, values, error)
            call check(t, .not. allocated(error) .and. slu%factor_entries >= n, &
                       "umfpack options: factorizes with ordering "//achar(48 + k))
            if (allocated(error)) return
            call slu%solve(b, xs, error)
            call check_close(t, xs, xd, "umfpack options: ordering "//achar(48 + k)// &
                             " solves as dgesv", rtol=1.0e-10_dp, atol=1.0e-10_dp*maxval(abs(xd)))
        end do
        call slu%move_to(other)
        call check(t, .not. slu%factorized() .and. slu%n == 0 .and. other%factorized() .and. &
                   other%n == n, "umfpack options: move_to hands the factorization over")
        call other%solve(b, xs, error)
        call check_close(t, xs, xd, "umfpack options: the moved factorization solves", &
                         rtol=1.0e-10_dp, atol=1.0e-10_dp*maxval(abs(xd)))
        call slu%release()
        call other%release()
    end subroutine test_options

    !> The nonzeros of a dense real matrix in 1-based compressed sparse column form.
    subroutine dense_to_csc(a, colptr, rowind, values)
        real(dp), intent(in) :: a(:, :)
        integer, allocatable, intent(out) :: colptr(:), rowind(:)
        real(dp), allocatable, intent(out) :: values(:)
        integer :: i, j, k, nnz
        nnz = count(a /= 0.0_dp)
        allocate (colptr(size(a, 2) + 1), rowind(nnz), values(nnz))
        k = 0
        colptr(1) = 1
        do j = 1, size(a, 2)
            do i = 1, size(a, 1)
                if (a(i, j) /= 0.0_dp) then
                    k = k + 1
                    rowind(k) = i
                    values(k) = a(i, j)
                end if
            end do
            colptr(j + 1) = k + 1
        end do
    end subroutine dense_to_csc

    !> The entries of a dense complex matrix on a given pattern.
    subroutine gather_complex(z, colptr, rowind, values)
        complex(dp), intent(in) :: z(:, :)
        integer, intent(in) :: colptr(:), rowind(:)
        complex(dp), allocatable, intent(out) :: values(:)
        integer :: j, k
        allocate (values(size(rowind)))
        do j = 1, size(colptr) - 1
            do k = colptr(j), colptr(j + 1) - 1
                values(k) = z(rowind(k), j)
            end do
        end do
    end subroutine gather_complex

    !> A random sparse n x n matrix (about `density` of the off-diagonal entries nonzero,
    !> values in [-1, 1]) plus `shift` on the diagonal.
    subroutine random_sparse(n, density, shift, a)
        integer, intent(in) :: n
        real(dp), intent(in) :: density, shift
        real(dp), intent(out) :: a(n, n)
        real(dp) :: keep(n, n)
        integer :: i
        call random_number(a)
        call random_number(keep)
        a = 2.0_dp*a - 1.0_dp
        where (keep > density) a = 0.0_dp
        do i = 1, n
            a(i, i) = a(i, i) + shift
        end do
    end subroutine random_sparse

    subroutine test_real(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 60, nrhs = 3
        real(dp) :: a(n, n), lu(n, n), b(n, nrhs), xd(n, nrhs), xs(n, nrhs), x1(n)
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: values(:)
        integer :: ipiv(n), info
        type(sparse_lu_t) :: slu
        type(error_type), allocatable :: error
        ! nonsymmetric, not diagonally dominant (shift 0.5 against ~6 entries of size <= 1)
        call random_sparse(n, 0.1_dp, 0.5_dp, a)
        call random_number(b)
        call dense_to_csc(a, colptr, rowind, values)
        call check(t, size(values) < n*n/5, "umfpack: the test matrix is sparse")
        lu = a
        xd = b
        call dgesv(n, nrhs, lu, n, ipiv, xd, n, info)
        call check(t, info == 0, "umfpack: dense reference dgesv info 0")
        call slu%factorize(n, colptr, rowind, values, error)
        call check(t, .not. allocated(error), "umfpack: real factorize succeeds")
        if (allocated(error)) return
        call check(t, slu%factorized() .and. slu%rcond > 0.0_dp .and. slu%rcond <= 1.0_dp, &
                   "umfpack: factorized, rcond in (0, 1]")
        call slu%solve(b, xs, error)
        call check(t, .not. allocated(error), "umfpack: real solve with 3 right-hand sides")
        call check_close(t, reshape(xs, [n*nrhs]), reshape(xd, [n*nrhs]), &
                         "umfpack: real sparse LU = dgesv (3 right-hand sides)", &
                         rtol=1.0e-10_dp, atol=1.0e-10_dp*maxval(abs(xd)))
        call slu%solve(b(:, 2), x1, error)
        call check_close(t, x1, xd(:, 2), "umfpack: real solve with one right-hand side", &
                         rtol=1.0e-10_dp, atol=1.0e-10_dp*maxval(abs(xd)))
        call check_close(t, maxval(abs(matmul(a, xs) - b)), 0.0_dp, &
                         "umfpack: real residual ||A x - b||_max", atol=1.0e-12_dp)
        ! new values on the same pattern: 2 A x = b gives x / 2
        call slu%refactorize(2.0_dp*values, error)
        call check(t, .not. allocated(error), "umfpack: refactorize succeeds")
        call slu%solve(b, xs, error)
        call check_close(t, reshape(xs, [n*nrhs]), 0.5_dp*reshape(xd, [n*nrhs]), &
                         "umfpack: refactorized 2 A solves to x / 2", &
                         rtol=1.0e-10_dp, atol=1.0e-10_dp*maxval(abs(xd)))
        call slu%release()
        call check(t, .not. slu%factorized() .and. slu%n == 0, "umfpack: release empties")
        call slu%release()
    end subroutine test_real

    subroutine test_complex(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 50, nrhs = 2
        real(dp), parameter :: w = 1.7_dp
        real(dp) :: k(n, n), m(n, n), c(n, n), br(n, nrhs), bi(n, nrhs), pattern(n, n)
        complex(dp) :: z(n, n), lu(n, n), b(n, nrhs), xd(n, nrhs), xs(n, nrhs)
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: dummy(:)
        complex(dp), allocatable :: values(:)
        integer :: ipiv(n), info
        type(sparse_zlu_t) :: zlu
        type(error_type), allocatable :: error
        call random_sparse(n, 0.08_dp, 3.0_dp, k)
        call random_sparse(n, 0.05_dp, 1.0_dp, m)
        call random_sparse(n, 0.05_dp, 0.1_dp, c)
        z = cmplx(k - w**2*m, w*c, dp)
        pattern = abs(k) + abs(m) + abs(c)
        call dense_to_csc(pattern, colptr, rowind, dummy)
        call gather_complex(z, colptr, rowind, values)
        call random_number(br)
        call random_number(bi)
        b = cmplx(br, bi, dp)
        lu = z
        xd = b
        call zgesv(n, nrhs, lu, n, ipiv, xd, n, info)
        call check(t, info == 0, "umfpack: dense reference zgesv info 0")
        call zlu%factorize(n, colptr, rowind, values, error)
        call check(t, .not. allocated(error), "umfpack: complex factorize succeeds")
        if (allocated(error)) return
        call zlu%solve(b, xs, error)
        call check(t, .not. allocated(error), "umfpack: complex solve succeeds")
        call check_close(t, [real(reshape(xs, [n*nrhs]), dp), aimag(reshape(xs, [n*nrhs]))], &
                         [real(reshape(xd, [n*nrhs]), dp), aimag(reshape(xd, [n*nrhs]))], &
                         "umfpack: complex sparse LU of K - w^2 M + i w C = zgesv", &
                         rtol=1.0e-10_dp, atol=1.0e-10_dp*maxval(abs(xd)))
        ! the same pattern at another frequency
        z = cmplx(k - 0.3_dp**2*m, 0.3_dp*c, dp)
        call gather_complex(z, colptr, rowind, values)
        call zlu%refactorize(values, error)
        call check(t, .not. allocated(error), "umfpack: complex refactorize succeeds")
        call zlu%solve(b(:, 1), xs(:, 1), error)
        call check_close(t, maxval(abs(matmul(z, xs(:, 1)) - b(:, 1))), 0.0_dp, &
                         "umfpack: complex residual after refactorize", atol=1.0e-12_dp)
        call zlu%release()
    end subroutine test_complex

    subroutine test_failures(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_lu_t) :: slu
        type(sparse_zlu_t) :: zlu
        type(error_type), allocatable :: error
        real(dp) :: x(3), a(3, 3)
        complex(dp) :: zx(2)
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: values(:)
        real(dp) :: nan
        ! numerically singular: column 3 = column 1 + column 2
        a = reshape([1.0_dp, 2.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 3.0_dp, 1.0_dp, 3.0_dp, 3.0_dp], [3, 3])
        call dense_to_csc(a, colptr, rowind, values)
        call slu%factorize(3, colptr, rowind, values, error)
        call check(t, allocated(error), "umfpack: a singular matrix is reported")
        if (allocated(error)) then
            call check(t, error%stat == stickslip_stat%numerical .and. &
                       index(error%message, "singular") > 0, "umfpack: singular is numerical, " &
                       //"says singular", error%message)
        end if
        call check(t, .not. slu%factorized(), "umfpack: nothing held after a failed factorize")
        call slu%solve([1.0_dp, 1.0_dp, 1.0_dp], x, error)
        call check(t, allocated(error), "umfpack: solve without a factorization is an error")
        ! structurally singular: an empty column
        call slu%factorize(2, [1, 2, 2], [1], [1.0_dp], error)
        call check(t, allocated(error), "umfpack: an empty column is reported singular")
        ! undamped resonance: Z = K - w^2 M with K = diag(1, 4), M = I, w = 1
        call zlu%factorize(2, [1, 2, 3], [1, 2], [(0.0_dp, 0.0_dp), (3.0_dp, 0.0_dp)], error)
        call check(t, allocated(error), "umfpack: a complex singular matrix is reported")
        if (allocated(error)) then
            call check(t, index(error%message, "singular") > 0, &
                       "umfpack: complex singular message", error%message)
        end if
        call zlu%solve([(1.0_dp, 0.0_dp), (1.0_dp, 0.0_dp)], zx, error)
        call check(t, allocated(error), "umfpack: complex solve without a factorization")
        ! bad patterns
        call slu%factorize(2, [1, 2, 3], [1, 3], [1.0_dp, 1.0_dp], error)
        call check(t, allocated(error), "umfpack: a row number out of range is reported")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input .and. &
                                         index(error%message, "rowind(2) = 3") > 0, &
                                         "umfpack: out of range names rowind(2)", error%message)
        call slu%factorize(2, [1, 3, 4], [2, 1, 2], [1.0_dp, 1.0_dp, 1.0_dp], error)
        call check(t, allocated(error), "umfpack: unsorted rows in a column are reported")
        call slu%factorize(2, [1, 2, 3], [1, 2], [1.0_dp], error)
        call check(t, allocated(error), "umfpack: too few values is reported")
        nan = ieee_value(nan, ieee_quiet_nan)
        call slu%factorize(2, [1, 2, 3], [1, 2], [1.0_dp, nan], error)
        call check(t, allocated(error), "umfpack: a NaN value is reported")
        if (allocated(error)) call check(t, index(error%message, "values(2)") > 0, &
                                         "umfpack: the NaN message names values(2)", error%message)
        call slu%release()
        call zlu%release()
    end subroutine test_failures
end module test_umfpack
