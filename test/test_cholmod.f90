!> stickslip_cholmod: sparse Cholesky (CHOLMOD) against dense LAPACK solves of the same SPD
!> matrices (a small one factorized simplicial, a 3D grid Laplacian large enough for the
!> supernodal factorization), one and many right-hand sides, and the failures: a matrix
!> that is not positive definite (refused; factorize_stiffness then falls back to the LU and
!> solves it), a bad pattern, a NaN, a solve without a factorization, wrong sizes.
module test_cholmod
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_lapack, only: dgesv
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_cholmod, only: sparse_cholesky_t
    use stickslip_umfpack, only: sparse_lu_t
    use stickslip_stiffness_factor, only: factorize_stiffness
    use test_umfpack, only: dense_to_csc
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_cholmod_tests

contains

    subroutine run_cholmod_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_small(t)
        call test_grid(t)
        call test_failures(t)
        call test_fallback(t)
    end subroutine run_cholmod_tests

    !> A random sparse SPD matrix of order 60 (A = B^T B + I on a sparse B): one and five
    !> right-hand sides against dgesv; release empties; a second factorize reuses the object.
    subroutine test_small(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 60, m = 5
        real(dp) :: a(n, n), b(n, m), xd(n, m), xs(n, m), x1(n)
        type(sparse_cholesky_t) :: chol
        type(error_type), allocatable :: error
        call spd_matrix(n, a)
        call random_number(b)
        call dense_solve(a, b, xd)
        call factorize(a, chol, error)
        call check(t, .not. allocated(error), "cholmod: factorizes a 60 x 60 SPD matrix")
        if (allocated(error)) return
        call check(t, chol%factorized() .and. chol%n == n .and. chol%factor_entries >= n, &
                   "cholmod: holds the factor, its order and entries")
        call chol%solve(b(:, 1), x1, error)
        call check(t, .not. allocated(error), "cholmod: one right-hand side solves")
        call check_close(t, x1, xd(:, 1), "cholmod: one right-hand side as dgesv", &
                         rtol=1.0e-10_dp, atol=1.0e-12_dp*maxval(abs(xd)))
        call chol%solve(b, xs, error)
        call check(t, .not. allocated(error), "cholmod: five right-hand sides solve")
        call check_close(t, reshape(xs, [n*m]), reshape(xd, [n*m]), &
                         "cholmod: five right-hand sides as dgesv", rtol=1.0e-10_dp, &
                         atol=1.0e-12_dp*maxval(abs(xd)))
        ! factorized again (the previous factor released), a scaled matrix
        call factorize(2.0_dp*a, chol, error)
        call chol%solve(b, xs, error)
        call check_close(t, reshape(2.0_dp*xs, [n*m]), reshape(xd, [n*m]), &
                         "cholmod: a second factorization in the same object", &
                         rtol=1.0e-10_dp, atol=1.0e-12_dp*maxval(abs(xd)))
        call chol%release()
        call check(t, .not. chol%factorized() .and. chol%n == 0, "cholmod: release empties")
        call chol%release()
    end subroutine test_small

    !> The 7-point Laplacian of a 12^3 grid plus a small diagonal shift (1728 unknowns):
    !> CHOLMOD chooses its supernodal factorization; 300 right-hand sides against dgesv
    !> (solve_many's blocks of 128: two full ones and a partial one).
    subroutine test_grid(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: g = 12, n = g**3, m = 300
        real(dp), allocatable :: a(:, :), b(:, :), xd(:, :), xs(:, :)
        type(sparse_cholesky_t) :: chol
        type(error_type), allocatable :: error
        integer :: i, j, k, p
        allocate (a(n, n), b(n, m), xd(n, m), xs(n, m))
        a = 0.0_dp
        do k = 1, g
            do j = 1, g
                do i = 1, g
                    p = i + g*(j - 1) + g*g*(k - 1)
                    a(p, p) = 6.01_dp
                    if (i > 1) call couple(p, p - 1)
                    if (j > 1) call couple(p, p - g)
                    if (k > 1) call couple(p, p - g*g)
                end do
            end do
        end do
        call random_number(b)
        call dense_solve(a, b, xd)
        call factorize(a, chol, error)
        call check(t, .not. allocated(error), "cholmod: factorizes the 12^3 grid")
        if (allocated(error)) return
        call check(t, chol%supernodal .and. chol%name() == 'supernodal Cholesky', &
                   "cholmod: the grid's factor is supernodal", chol%name())
        call chol%solve(b, xs, error)
        call check_close(t, reshape(xs, [n*m]), reshape(xd, [n*m]), &
                         "cholmod: the grid's solves as dgesv", rtol=1.0e-9_dp, &
                         atol=1.0e-11_dp*maxval(abs(xd)))
        call chol%release()
    contains
        subroutine couple(p1, p2)
            integer, intent(in) :: p1, p2
            a(p1, p2) = -1.0_dp
            a(p2, p1) = -1.0_dp
        end subroutine couple
    end subroutine test_grid

    !> Refusals: not positive definite (numerical), a bad pattern and a NaN (input), a solve
    !> without a factorization and with wrong sizes (input); nothing held after a failure.
    subroutine test_failures(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 30
        real(dp) :: a(n, n), b(n), x(n), x2(n + 1)
        type(sparse_cholesky_t) :: chol
        type(error_type), allocatable :: error
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: values(:)
        call spd_matrix(n, a)
        b = 1.0_dp
        call chol%solve(b, x, error)
        call check(t, failed(error, stickslip_stat%input, "without a factorization"), &
                   "cholmod: a solve without a factorization is refused", msg(error))
        ! indefinite: one negative eigenvalue
        a(7, 7) = -a(7, 7)
        call factorize(a, chol, error)
        call check(t, failed(error, stickslip_stat%numerical, "not positive definite"), &
                   "cholmod: an indefinite matrix is refused", msg(error))
        call check(t, .not. chol%factorized() .and. chol%n == 0, &
                   "cholmod: nothing held after a failure")
        a(7, 7) = -a(7, 7)
        call dense_to_csc(a, colptr, rowind, values)
        values(5) = ieee_value(1.0_dp, ieee_quiet_nan)
        call chol%factorize(n, colptr, rowind, values, error)
        call check(t, failed(error, stickslip_stat%input, "not finite"), &
                   "cholmod: a NaN is refused", msg(error))
        call dense_to_csc(a, colptr, rowind, values)
        colptr(1) = 2
        call chol%factorize(n, colptr, rowind, values, error)
        call check(t, failed(error, stickslip_stat%input, "colptr(1)"), &
                   "cholmod: a bad pattern is refused", msg(error))
        call factorize(a, chol, error)
        call chol%solve(b, x2, error)
        call check(t, failed(error, stickslip_stat%input, "entries"), &
                   "cholmod: a solution of the wrong size is refused", msg(error))
        call chol%release()
    end subroutine test_failures

    !> factorize_stiffness: a Cholesky for an SPD matrix, the LU for an indefinite one (which
    !> then solves as dgesv).
    subroutine test_fallback(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 40
        real(dp) :: a(n, n), b(n, 1), xd(n, 1), xs(n, 1)
        class(sparse_factor_t), allocatable :: fac
        type(error_type), allocatable :: error
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: values(:)
        call spd_matrix(n, a)
        call random_number(b)
        call dense_to_csc(a, colptr, rowind, values)
        call factorize_stiffness(n, colptr, rowind, values, fac, error)
        call check(t, .not. allocated(error) .and. same_type_as(fac, sparse_cholesky_t()), &
                   "factorize_stiffness: an SPD matrix gets a Cholesky")
        a(3, 3) = -a(3, 3)
        call dense_solve(a, b, xd)
        call dense_to_csc(a, colptr, rowind, values)
        call factorize_stiffness(n, colptr, rowind, values, fac, error)
        call check(t, .not. allocated(error) .and. same_type_as(fac, sparse_lu_t()), &
                   "factorize_stiffness: an indefinite matrix gets the LU", msg(error))
        if (allocated(error)) return
        call check(t, fac%name() == 'LU', "factorize_stiffness: the LU says so", fac%name())
        call fac%solve(b, xs, error)
        call check_close(t, xs(:, 1), xd(:, 1), "factorize_stiffness: the LU solves as dgesv", &
                         rtol=1.0e-10_dp, atol=1.0e-12_dp*maxval(abs(xd)))
        call fac%release()
    end subroutine test_fallback

    !> A random sparse SPD matrix: B^T B + I, B with about 10 % nonzeros.
    subroutine spd_matrix(n, a)
        integer, intent(in) :: n
        real(dp), intent(out) :: a(n, n)
        real(dp) :: bm(n, n), mask(n, n)
        call random_number(bm)
        call random_number(mask)
        where (mask > 0.1_dp) bm = 0.0_dp
        a = matmul(transpose(bm), bm)
        block
            integer :: i
            do i = 1, n
                a(i, i) = a(i, i) + 1.0_dp
            end do
        end block
    end subroutine spd_matrix

    subroutine factorize(a, chol, error)
        real(dp), intent(in) :: a(:, :)
        type(sparse_cholesky_t), intent(inout) :: chol
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: values(:)
        call dense_to_csc(a, colptr, rowind, values)
        call chol%factorize(size(a, 1), colptr, rowind, values, error)
    end subroutine factorize

    subroutine dense_solve(a, b, x)
        real(dp), intent(in) :: a(:, :), b(:, :)
        real(dp), intent(out) :: x(:, :)
        real(dp), allocatable :: lu(:, :)
        integer, allocatable :: ipiv(:)
        integer :: info
        lu = a
        x = b
        allocate (ipiv(size(a, 1)))
        call dgesv(size(a, 1), size(b, 2), lu, size(a, 1), ipiv, x, size(a, 1), info)
    end subroutine dense_solve

    logical function failed(error, stat, text)
        type(error_type), allocatable, intent(in) :: error
        integer, intent(in) :: stat
        character(len=*), intent(in) :: text
        failed = .false.
        if (.not. allocated(error)) return
        failed = error%stat == stat .and. index(error%message, text) > 0
    end function failed

    function msg(error) result(text)
        type(error_type), allocatable, intent(in) :: error
        character(len=:), allocatable :: text
        text = ''
        if (allocated(error)) text = error%message
    end function msg

end module test_cholmod
