!> Dense matrix products on the linked BLAS (dgemm, dgemv) instead of the intrinsic matmul
!> (which stays for small matrices):
!> the hot paths of the exact flow (the propagation of a state, the exponentials of a
!> contact mode, the monodromy), where a stiff reduced model with many contacts spends most
!> of its stability time (doc/benchmarks.md). Knows nothing of the model; no state.
module stickslip_dense_products
    use stickslip_kinds, only: dp
    use stickslip_lapack, only: dgemm, dgemv, zgemm, zgemv
    implicit none
    private
    public :: mat_mul, mat_tmul, mat_vec, cmat_mul

    !> Below this many multiply-adds (m n k; (m n)^(3/2) for a matrix-vector product) the
    !> intrinsic matmul is used: the call into BLAS costs more than it saves on the small
    !> models (measured: the seed, chain4 and damper_liftoff sweeps' stability 5-20 %
    !> slower on BLAS, their matrices 4-10 wide).
    real(dp), parameter :: small_product = 32.0_dp**3
    !> cmat_mul of at most this many columns: matrix-vector products (zgemm's packing of the
    !> other factor costs more than the product itself).
    integer, parameter :: few_columns = 4

contains

    !> c = a b (a: m x k, b: k x n) by dgemm. No error: the shapes must agree (k =
    !> size(b, 1); the caller's arrays).
    function mat_mul(a, b) result(c)
        !> Left and right factors.
        real(dp), intent(in) :: a(:, :), b(:, :)
        real(dp) :: c(size(a, 1), size(b, 2))
        call product_into('N', a, b, c)
    end function mat_mul

    !> c = a^T b (a: k x m, b: k x n) by dgemm, without forming a^T: the projections of
    !> a reduction (T^T (A T) over the long dimension k of a FE model's DOFs), where the
    !> intrinsic matmul of a transpose ran at a tenth of BLAS's speed. No error: the shapes
    !> must agree (size(a, 1) = size(b, 1); the caller's arrays).
    function mat_tmul(a, b) result(c)
        !> Left factor (transposed in the product) and right factor.
        real(dp), intent(in) :: a(:, :), b(:, :)
        real(dp) :: c(size(a, 2), size(b, 2))
        call product_into('T', a, b, c)
    end function mat_tmul

    !> c = op(a) b, op(a) = a (trans 'N') or a^T ('T'), c m x n, b k x n: dgemm, or the
    !> intrinsic matmul below small_product multiply-adds.
    subroutine product_into(trans, a, b, c)
        character(len=1), intent(in) :: trans
        real(dp), intent(in) :: a(:, :), b(:, :)
        real(dp), intent(out) :: c(:, :)
        integer :: m, n, k
        m = size(c, 1)
        n = size(c, 2)
        k = size(b, 1)
        if (m == 0 .or. n == 0) return
        if (k == 0) then
            c = 0.0_dp
            return
        end if
        if (real(m, dp)*real(n, dp)*real(k, dp) < small_product) then
            if (trans == 'T') then
                c = matmul(transpose(a), b)
            else
                c = matmul(a, b)
            end if
            return
        end if
        call dgemm(trans, 'N', m, n, k, 1.0_dp, a, size(a, 1), b, k, 0.0_dp, c, m)
    end subroutine product_into

    !> y = a x (a: m x n, x: n) by dgemv.
    function mat_vec(a, x) result(y)
        !> The matrix and the vector.
        real(dp), intent(in) :: a(:, :), x(:)
        real(dp) :: y(size(a, 1))
        integer :: m, n
        m = size(a, 1)
        n = size(a, 2)
        if (m == 0) return
        if (n == 0) then
            y = 0.0_dp
            return
        end if
        if (real(m, dp)*real(n, dp) < small_product**(2.0_dp/3.0_dp)) then
            y = matmul(a, x)
            return
        end if
        call dgemv('N', m, n, 1.0_dp, a, m, x, 1, 0.0_dp, y, 1)
    end function mat_vec

    !> The complex product A B (BLAS zgemm; Fortran's matmul for small products). No
    !> errors (the sizes must conform).
    function cmat_mul(a, b) result(c)
        !> The factors, m x k and k x n.
        complex(dp), intent(in) :: a(:, :), b(:, :)
        complex(dp) :: c(size(a, 1), size(b, 2))
        integer :: m, n, k, j
        m = size(a, 1)
        n = size(b, 2)
        k = size(a, 2)
        if (m == 0 .or. n == 0) return
        if (k == 0) then
            c = (0.0_dp, 0.0_dp)
            return
        end if
        if (real(m, dp)*real(n, dp)*real(k, dp) < small_product/4) then
            c = matmul(a, b)
            return
        end if
        if (n <= few_columns) then
            ! a few columns: one matrix-vector product each (zgemm would pack all of a)
            do j = 1, n
                call zgemv('N', m, k, (1.0_dp, 0.0_dp), a, m, b(:, j), 1, (0.0_dp, 0.0_dp), &
                           c(:, j), 1)
            end do
            return
        end if
        call zgemm('N', 'N', m, n, k, (1.0_dp, 0.0_dp), a, m, b, k, (0.0_dp, 0.0_dp), c, m)
    end function cmat_mul
end module stickslip_dense_products
