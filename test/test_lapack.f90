!> stickslip_lapack: the interface blocks agree with the system LAPACK (argument order,
!> kinds, intents) on problems with known answers: real and complex LU solves, a Cholesky
!> solve, a singular and a non-SPD matrix reported by info, a condition-number estimate and
!> a matrix norm of a diagonal matrix, and the eigenvalues of a rotation-plus-scaling matrix;
!> the dense products on BLAS against the intrinsic matmul.
module test_lapack
    use stickslip_kinds, only: dp
    use stickslip_lapack, only: dpotrf, dpotrs, dgetrf, dgetrs, zgetrf, zgetrs, zgecon, &
        zlange, dgeev
    use testing, only: test_counter_t, check, check_close
    use stickslip_small_dense, only: small_zgetrf, small_zgetrs, small_zrcond
    use stickslip_dense_products, only: mat_mul, mat_tmul
    implicit none
    private
    public :: run_lapack_tests

contains

    subroutine run_lapack_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_real(t)
        call test_complex(t)
        call test_eigen(t)
        call test_small_dense(t)
        call test_products(t)
    end subroutine run_lapack_tests

    !> mat_mul and mat_tmul (stickslip_dense_products: dgemm above 32^3 multiply-adds, the
    !> intrinsic matmul below) against matmul on random factors of both sizes, a^T b with a
    !> k x m (k the long dimension, as a reduction's projections), relative 1e-13.
    subroutine test_products(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: a(:, :), b(:, :)
        integer, parameter :: rows(2) = [5, 300], cols(2) = [3, 70]
        real(dp) :: worst_n, worst_t
        integer :: i
        worst_n = 0.0_dp
        worst_t = 0.0_dp
        do i = 1, 2
            allocate (a(rows(i), cols(i)), b(rows(i), cols(i) + 1))
            call random_number(a)
            call random_number(b)
            worst_t = max(worst_t, maxval(abs(mat_tmul(a, b) - matmul(transpose(a), b)))/ &
                          maxval(abs(matmul(transpose(a), b))))
            worst_n = max(worst_n, maxval(abs(mat_mul(transpose(a), b) - &
                                              matmul(transpose(a), b)))/ &
                          maxval(abs(matmul(transpose(a), b))))
            deallocate (a, b)
        end do
        call check(t, worst_t < 1.0e-13_dp, "mat_tmul = matmul(transpose(a), b), small and large")
        call check(t, worst_n < 1.0e-13_dp, "mat_mul = matmul, small and large")
    end subroutine test_products

    !> The plain-Fortran LU of small complex matrices against LAPACK: the same solutions
    !> (n = 1..16, nonsymmetric, 3 right-hand sides, relative 1e-12), the condition number
    !> against ||A||_1 ||A^-1||_1 from the explicit inverse, and a singular matrix's zero
    !> pivot reported as zgetrf reports it.
    subroutine test_small_dense(t)
        type(test_counter_t), intent(inout) :: t
        complex(dp), allocatable :: a(:, :), f(:, :), b(:, :), x(:, :), y(:, :), inv(:, :)
        real(dp), allocatable :: re(:, :), im(:, :)
        integer, allocatable :: ipiv(:), jpiv(:)
        integer :: n, info, k
        real(dp) :: worst, worst_rcond, rcond, exact
        worst = 0.0_dp
        worst_rcond = 0.0_dp
        do n = 1, 16
            allocate (re(n, n), im(n, n), b(n, 3), ipiv(n), jpiv(n))
            call random_number(re)
            call random_number(im)
            a = cmplx(re - 0.5_dp, im - 0.5_dp, dp)
            do k = 1, n
                a(k, k) = a(k, k) + 0.3_dp
            end do
            call random_number(re(:, 1:min(3, n)))
            b = (1.0_dp, 0.5_dp)
            b(:, 1) = cmplx(re(:, 1), 0.0_dp, dp)
            f = a
            call small_zgetrf(n, f, ipiv, info)
            x = b
            call small_zgetrs(n, 3, f, ipiv, x)
            inv = a
            call zgetrf(n, n, inv, n, jpiv, info)
            y = b
            call zgetrs('N', n, 3, inv, n, jpiv, y, n, info)
            worst = max(worst, maxval(abs(x - y))/maxval(abs(y)))
            ! the exact condition: the inverse column by column from LAPACK's factors
            deallocate (y)
            allocate (y(n, n))
            y = (0.0_dp, 0.0_dp)
            do k = 1, n
                y(k, k) = (1.0_dp, 0.0_dp)
            end do
            call zgetrs('N', n, n, inv, n, jpiv, y, n, info)
            exact = 1.0_dp/(maxval(sum(abs(a), dim=1))*maxval(sum(abs(y), dim=1)))
            rcond = small_zrcond(n, f, ipiv, maxval(sum(abs(a), dim=1)))
            worst_rcond = max(worst_rcond, abs(rcond - exact)/exact)
            deallocate (re, im, b, ipiv, jpiv, y)
        end do
        call check(t, worst < 1.0e-12_dp, "small dense: solutions = LAPACK's (n = 1..16)")
        call check(t, worst_rcond < 1.0e-12_dp, "small dense: exact 1-norm condition")
        ! a singular matrix: the second column a multiple of the first
        a = reshape([(1.0_dp, 0.0_dp), (2.0_dp, 0.0_dp), (2.0_dp, 0.0_dp), (4.0_dp, 0.0_dp)], &
                    [2, 2])
        allocate (ipiv(2))
        call small_zgetrf(2, a, ipiv, info)
        call check(t, info == 2, "small dense: a zero pivot is reported (info = 2)")
    end subroutine test_small_dense

    subroutine test_real(t)
        type(test_counter_t), intent(inout) :: t
        real(dp) :: a(3, 3), lu(3, 3), b(3, 2), x(3, 2), s(3, 3)
        integer :: ipiv(3), info
        ! A x = b with x chosen; a pivot is needed (a(1,1) = 0)
        a = reshape([0.0_dp, 2.0_dp, 1.0_dp, 1.0_dp, 1.0_dp, -1.0_dp, 3.0_dp, 0.0_dp, 4.0_dp], &
                    [3, 3])
        x = reshape([1.0_dp, -2.0_dp, 0.5_dp, 3.0_dp, 0.0_dp, -1.0_dp], [3, 2])
        b = matmul(a, x)
        lu = a
        call dgetrf(3, 3, lu, 3, ipiv, info)
        call check(t, info == 0, "lapack: dgetrf info 0")
        call dgetrs('N', 3, 2, lu, 3, ipiv, b, 3, info)
        call check_close(t, reshape(b, [6]), reshape(x, [6]), "lapack: dgetrs solves A x = b", &
                         rtol=0.0_dp, atol=1.0e-14_dp)
        b = matmul(transpose(a), x)
        call dgetrs('T', 3, 2, lu, 3, ipiv, b, 3, info)
        call check_close(t, reshape(b, [6]), reshape(x, [6]), "lapack: dgetrs solves A^T x = b", &
                         rtol=0.0_dp, atol=1.0e-14_dp)
        ! singular (two equal columns; the elimination is exact): info > 0
        lu = reshape([1.0_dp, 2.0_dp, 4.0_dp, 1.0_dp, 2.0_dp, 4.0_dp, 0.0_dp, 1.0_dp, 1.0_dp], [3, 3])
        call dgetrf(3, 3, lu, 3, ipiv, info)
        call check(t, info > 0, "lapack: dgetrf reports a singular matrix")
        ! Cholesky of the SPD matrix S = A^T A + I
        s = matmul(transpose(a), a)
        s(1, 1) = s(1, 1) + 1.0_dp
        s(2, 2) = s(2, 2) + 1.0_dp
        s(3, 3) = s(3, 3) + 1.0_dp
        b = matmul(s, x)
        lu = s
        call dpotrf('U', 3, lu, 3, info)
        call check(t, info == 0, "lapack: dpotrf info 0 on an SPD matrix")
        call dpotrs('U', 3, 2, lu, 3, b, 3, info)
        call check_close(t, reshape(b, [6]), reshape(x, [6]), "lapack: dpotrs solves S x = b", &
                         rtol=0.0_dp, atol=1.0e-13_dp)
        lu = a
        call dpotrf('U', 3, lu, 3, info)
        call check(t, info > 0, "lapack: dpotrf reports a matrix that is not SPD")
    end subroutine test_real

    subroutine test_complex(t)
        type(test_counter_t), intent(inout) :: t
        complex(dp) :: z(2, 2), lu(2, 2), b(2, 1), x(2, 1), work(4)
        real(dp) :: rwork(4), anorm, rcond
        integer :: ipiv(2), info
        z = reshape([(1.0_dp, 2.0_dp), (0.0_dp, -1.0_dp), (3.0_dp, 0.0_dp), (2.0_dp, 2.0_dp)], &
                    [2, 2])
        x = reshape([(1.0_dp, -1.0_dp), (0.5_dp, 2.0_dp)], [2, 1])
        b = matmul(z, x)
        lu = z
        call zgetrf(2, 2, lu, 2, ipiv, info)
        call check(t, info == 0, "lapack: zgetrf info 0")
        call zgetrs('N', 2, 1, lu, 2, ipiv, b, 2, info)
        call check_close(t, [real(b(:, 1)), aimag(b(:, 1))], [real(x(:, 1)), aimag(x(:, 1))], &
                         "lapack: zgetrs solves Z x = b", rtol=0.0_dp, atol=1.0e-14_dp)
        ! diagonal diag(4i, 0.5): 1-norm 4, reciprocal condition number 0.5 / 4
        z = (0.0_dp, 0.0_dp)
        z(1, 1) = (0.0_dp, 4.0_dp)
        z(2, 2) = (0.5_dp, 0.0_dp)
        anorm = zlange('1', 2, 2, z, 2, rwork)
        call check_close(t, anorm, 4.0_dp, "lapack: zlange 1-norm of a diagonal matrix")
        lu = z
        call zgetrf(2, 2, lu, 2, ipiv, info)
        call zgecon('1', 2, lu, 2, anorm, rcond, work, rwork, info)
        call check(t, info == 0, "lapack: zgecon info 0")
        call check_close(t, rcond, 0.125_dp, "lapack: zgecon rcond of a diagonal matrix", &
                         rtol=1.0e-14_dp)
    end subroutine test_complex

    !> [a -b; b a] has eigenvalues a +- i b; with a workspace query first.
    subroutine test_eigen(t)
        type(test_counter_t), intent(inout) :: t
        real(dp) :: a(2, 2), wr(2), wi(2), vl(1, 1), vr(2, 2), query(1)
        real(dp), allocatable :: work(:)
        integer :: info
        a = reshape([-0.3_dp, 2.0_dp, -2.0_dp, -0.3_dp], [2, 2])
        call dgeev('N', 'V', 2, a, 2, wr, wi, vl, 1, vr, 2, query, -1, info)
        call check(t, info == 0 .and. query(1) >= 1.0_dp, "lapack: dgeev workspace query")
        allocate (work(int(query(1))))
        a = reshape([-0.3_dp, 2.0_dp, -2.0_dp, -0.3_dp], [2, 2])
        call dgeev('N', 'V', 2, a, 2, wr, wi, vl, 1, vr, 2, work, size(work), info)
        call check(t, info == 0, "lapack: dgeev info 0")
        call check_close(t, wr, [-0.3_dp, -0.3_dp], "lapack: dgeev real parts", rtol=1.0e-14_dp)
        call check_close(t, [maxval(wi), minval(wi)], [2.0_dp, -2.0_dp], &
                         "lapack: dgeev imaginary parts", rtol=1.0e-14_dp)
    end subroutine test_eigen
end module test_lapack
