!> Explicit interfaces to the few LAPACK routines stickslip calls (system liblapack), and
!> BLAS's dgemm and dgemv (system libblas).
!> Only interfaces: no state, no wrappers that hide `info`.
module stickslip_lapack
    use stickslip_kinds, only: dp, sp
    implicit none
    private
    public :: dpotrf, dpotrs, dgetrf, dgetrs, dgecon, dlange, dgeqrf, dorgqr, zgeqrf, zungqr, &
        zgetrf, zgetrs, zgemm, zgecon, zlange, dgeev, dgesv, zgesv, dsygv, dsyev, sgetrf, sgetrs, &
        dgemm, dgemv, zgemv, zhegv, zhegvd, dgelss

    interface
        !> Cholesky factorization of a real symmetric positive definite matrix.
        subroutine dpotrf(uplo, n, a, lda, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, lda
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: info
        end subroutine dpotrf

        !> Solve with the Cholesky factor from dpotrf.
        subroutine dpotrs(uplo, n, nrhs, a, lda, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: uplo
            integer, intent(in) :: n, nrhs, lda, ldb
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dpotrs

        !> LU factorization of a general real matrix with partial pivoting.
        subroutine dgetrf(m, n, a, lda, ipiv, info)
            import :: dp
            integer, intent(in) :: m, n, lda
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*)
            integer, intent(out) :: info
        end subroutine dgetrf

        !> C <- alpha op(A) op(B) + beta C (BLAS).
        subroutine dgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
            import :: dp
            character(len=1), intent(in) :: transa, transb
            integer, intent(in) :: m, n, k, lda, ldb, ldc
            real(dp), intent(in) :: alpha, beta
            real(dp), intent(in) :: a(lda, *), b(ldb, *)
            real(dp), intent(inout) :: c(ldc, *)
        end subroutine dgemm

        !> C <- alpha op(A) op(B) + beta C, complex (BLAS).
        subroutine zgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
            import :: dp
            character(len=1), intent(in) :: transa, transb
            integer, intent(in) :: m, n, k, lda, ldb, ldc
            complex(dp), intent(in) :: alpha, beta
            complex(dp), intent(in) :: a(lda, *), b(ldb, *)
            complex(dp), intent(inout) :: c(ldc, *)
        end subroutine zgemm

        !> y <- alpha op(A) x + beta y (BLAS).
        subroutine dgemv(trans, m, n, alpha, a, lda, x, incx, beta, y, incy)
            import :: dp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: m, n, lda, incx, incy
            real(dp), intent(in) :: alpha, beta
            real(dp), intent(in) :: a(lda, *), x(*)
            real(dp), intent(inout) :: y(*)
        end subroutine dgemv

        !> Solve with the LU factors from dgetrf.
        subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb
            real(dp), intent(in) :: a(lda, *)
            integer, intent(in) :: ipiv(*)
            real(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dgetrs

        !> LU factorization of a general complex matrix with partial pivoting.
        subroutine zgetrf(m, n, a, lda, ipiv, info)
            import :: dp
            integer, intent(in) :: m, n, lda
            complex(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*)
            integer, intent(out) :: info
        end subroutine zgetrf

        !> Solve with the LU factors from zgetrf.
        subroutine zgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb
            complex(dp), intent(in) :: a(lda, *)
            integer, intent(in) :: ipiv(*)
            complex(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine zgetrs

        !> Reciprocal condition number estimate from the LU factors.
        subroutine zgecon(norm, n, a, lda, anorm, rcond, work, rwork, info)
            import :: dp
            character(len=1), intent(in) :: norm
            integer, intent(in) :: n, lda
            complex(dp), intent(in) :: a(lda, *)
            real(dp), intent(in) :: anorm
            real(dp), intent(out) :: rcond
            complex(dp), intent(out) :: work(*)
            real(dp), intent(out) :: rwork(*)
            integer, intent(out) :: info
        end subroutine zgecon

        !> Matrix norm of a complex matrix.
        function zlange(norm, m, n, a, lda, work) result(anorm)
            import :: dp
            character(len=1), intent(in) :: norm
            integer, intent(in) :: m, n, lda
            complex(dp), intent(in) :: a(lda, *)
            real(dp), intent(out) :: work(*)
            real(dp) :: anorm
        end function zlange

        !> Eigenvalues wr + i wi and optionally left / right eigenvectors of a general real
        !> matrix (a is overwritten). lwork = -1 is a workspace query (optimal size in work(1)).
        subroutine dgeev(jobvl, jobvr, n, a, lda, wr, wi, vl, ldvl, vr, ldvr, work, lwork, info)
            import :: dp
            character(len=1), intent(in) :: jobvl, jobvr
            integer, intent(in) :: n, lda, ldvl, ldvr, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(out) :: wr(*), wi(*)
            real(dp), intent(out) :: vl(ldvl, *), vr(ldvr, *)
            real(dp), intent(out) :: work(*)
            integer, intent(out) :: info
        end subroutine dgeev
        !> Solve A X = B for a general real matrix (LU with partial pivoting; a is overwritten
        !> by the factors, b by the solution).
        subroutine dgesv(n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            integer, intent(in) :: n, nrhs, lda, ldb
            real(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*)
            real(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine dgesv

        !> Minimum-norm least-squares solution of A X = B (A m x n, any rank) by the SVD:
        !> singular values below rcond times the largest are taken as zero (rank returned);
        !> s the singular values. lwork = -1 is a workspace query.
        subroutine dgelss(m, n, nrhs, a, lda, b, ldb, s, rcond, rank, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, nrhs, lda, ldb, lwork
            real(dp), intent(inout) :: a(lda, *), b(ldb, *)
            real(dp), intent(out) :: s(*), work(*)
            real(dp), intent(in) :: rcond
            integer, intent(out) :: rank, info
        end subroutine dgelss

        !> Solve A X = B for a general complex matrix (as dgesv).
        subroutine zgesv(n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: dp
            integer, intent(in) :: n, nrhs, lda, ldb
            complex(dp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*)
            complex(dp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine zgesv

        !> Symmetric eigenproblem A x = lambda x, eigenvalues w ascending; with jobz = 'V' a
        !> holds the orthonormal eigenvectors. lwork = -1 is a workspace query.
        subroutine dsyev(jobz, uplo, n, a, lda, w, work, lwork, info)
            import :: dp
            character(len=1), intent(in) :: jobz, uplo
            integer, intent(in) :: n, lda, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(out) :: w(*)
            real(dp), intent(out) :: work(*)
            integer, intent(out) :: info
        end subroutine dsyev

        !> Generalized symmetric-definite eigenproblem A x = lambda B x (itype 1), eigenvalues
        !> w ascending; with jobz = 'V' a holds the B-orthonormal eigenvectors and b its
        !> Cholesky factor. lwork = -1 is a workspace query.
        subroutine dsygv(itype, jobz, uplo, n, a, lda, b, ldb, w, work, lwork, info)
            import :: dp
            integer, intent(in) :: itype
            character(len=1), intent(in) :: jobz, uplo
            integer, intent(in) :: n, lda, ldb, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(inout) :: b(ldb, *)
            real(dp), intent(out) :: w(*)
            real(dp), intent(out) :: work(*)
            integer, intent(out) :: info
        end subroutine dsygv
        !> Generalized Hermitian-definite eigenproblem A x = lambda B x (itype = 1): w
        !> ascending; with jobz = 'V' a holds the B-orthonormal eigenvectors. lwork = -1 is
        !> a workspace query; rwork of size max(1, 3 n - 2).
        subroutine zhegv(itype, jobz, uplo, n, a, lda, b, ldb, w, work, lwork, rwork, info)
            import :: dp
            integer, intent(in) :: itype
            character(len=1), intent(in) :: jobz, uplo
            integer, intent(in) :: n, lda, ldb, lwork
            complex(dp), intent(inout) :: a(lda, *)
            complex(dp), intent(inout) :: b(ldb, *)
            real(dp), intent(out) :: w(*)
            complex(dp), intent(out) :: work(*)
            real(dp), intent(out) :: rwork(*)
            integer, intent(out) :: info
        end subroutine zhegv
        !> zhegv by divide and conquer (much faster with the eigenvectors of a large
        !> pencil): the same problem and results; workspaces work (lwork), rwork (lrwork) and
        !> iwork (liwork), their sizes returned by a query with lwork = lrwork = liwork = -1.
        subroutine zhegvd(itype, jobz, uplo, n, a, lda, b, ldb, w, work, lwork, rwork, lrwork, &
                          iwork, liwork, info)
            import :: dp
            integer, intent(in) :: itype
            character(len=1), intent(in) :: jobz, uplo
            integer, intent(in) :: n, lda, ldb, lwork, lrwork, liwork
            complex(dp), intent(inout) :: a(lda, *)
            complex(dp), intent(inout) :: b(ldb, *)
            real(dp), intent(out) :: w(*)
            complex(dp), intent(out) :: work(*)
            real(dp), intent(out) :: rwork(*)
            integer, intent(out) :: iwork(*)
            integer, intent(out) :: info
        end subroutine zhegvd
        !> LU factorization of a general single-precision matrix with partial pivoting.
        subroutine sgetrf(m, n, a, lda, ipiv, info)
            import :: sp
            integer, intent(in) :: m, n, lda
            real(sp), intent(inout) :: a(lda, *)
            integer, intent(out) :: ipiv(*)
            integer, intent(out) :: info
        end subroutine sgetrf

        !> Solve with the single-precision LU factors from sgetrf.
        subroutine sgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
            import :: sp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: n, nrhs, lda, ldb
            real(sp), intent(in) :: a(lda, *)
            integer, intent(in) :: ipiv(*)
            real(sp), intent(inout) :: b(ldb, *)
            integer, intent(out) :: info
        end subroutine sgetrs

        !> Reciprocal condition number estimate of a real matrix from its LU factors.
        subroutine dgecon(norm, n, a, lda, anorm, rcond, work, iwork, info)
            import :: dp
            character(len=1), intent(in) :: norm
            integer, intent(in) :: n, lda
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(in) :: anorm
            real(dp), intent(out) :: rcond
            real(dp), intent(out) :: work(*)
            integer, intent(out) :: iwork(*)
            integer, intent(out) :: info
        end subroutine dgecon

        !> A norm of a real matrix ('1', 'I', 'F' or 'M').
        function dlange(norm, m, n, a, lda, work) result(anorm)
            import :: dp
            character(len=1), intent(in) :: norm
            integer, intent(in) :: m, n, lda
            real(dp), intent(in) :: a(lda, *)
            real(dp), intent(inout) :: work(*)
            real(dp) :: anorm
        end function dlange

        !> Blocked QR factorization of a real matrix (Householder reflectors).
        subroutine dgeqrf(m, n, a, lda, tau, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, lda, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(out) :: tau(*)
            real(dp), intent(inout) :: work(*)
            integer, intent(out) :: info
        end subroutine dgeqrf

        !> Form the orthogonal factor Q of dgeqrf explicitly (blocked).
        subroutine dorgqr(m, n, k, a, lda, tau, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, k, lda, lwork
            real(dp), intent(inout) :: a(lda, *)
            real(dp), intent(in) :: tau(*)
            real(dp), intent(inout) :: work(*)
            integer, intent(out) :: info
        end subroutine dorgqr

        !> Blocked QR factorization of a complex matrix (Householder reflectors).
        subroutine zgeqrf(m, n, a, lda, tau, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, lda, lwork
            complex(dp), intent(inout) :: a(lda, *)
            complex(dp), intent(out) :: tau(*)
            complex(dp), intent(inout) :: work(*)
            integer, intent(out) :: info
        end subroutine zgeqrf

        !> Form the unitary factor Q of zgeqrf explicitly (blocked).
        subroutine zungqr(m, n, k, a, lda, tau, work, lwork, info)
            import :: dp
            integer, intent(in) :: m, n, k, lda, lwork
            complex(dp), intent(inout) :: a(lda, *)
            complex(dp), intent(in) :: tau(*)
            complex(dp), intent(inout) :: work(*)
            integer, intent(out) :: info
        end subroutine zungqr

        !> y <- alpha op(A) x + beta y, complex (BLAS).
        subroutine zgemv(trans, m, n, alpha, a, lda, x, incx, beta, y, incy)
            import :: dp
            character(len=1), intent(in) :: trans
            integer, intent(in) :: m, n, lda, incx, incy
            complex(dp), intent(in) :: alpha, beta, a(lda, *), x(*)
            complex(dp), intent(inout) :: y(*)
        end subroutine zgemv
    end interface
end module stickslip_lapack
