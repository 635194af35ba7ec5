!> The lowest eigenpairs of sparse K phi = lambda M phi by block shift-invert Lanczos on a
!> factorization of K - sigma M whose block solves are cheap (CHOLMOD's supernodal Cholesky
!> reads its factor once for a whole block of right-hand sides).
!>
!> Why beside ARPACK's single-vector Lanczos (stickslip_arpack): on a large FE interior the
!> time is in the solves and the mass products, one vector at a time there. On the Rotor 37
!> blade's 61,081 interior DOFs one solve costs 0.06-0.1 s and 17 at once 0.21 s; the 34
!> fixed-interface modes of its Craig-Bampton reduction took ARPACK 156 solves in two runs
!> (15.7 s), the block method 21 solves of 8 columns (6-7 s; doc/benchmarks.md, "Rotor 37 ... fifth
!> part"). Also, it keeps no state outside its arguments (ARPACK's SAVEd variables make that
!> one serialize concurrent calls).
!>
!> The method: a block Krylov basis V of Op = (K - sigma M)^-1 M, M-orthonormal, every new
!> block W = Op V_last orthogonalized against the whole basis twice (classical Gram-Schmidt
!> by dgemm, M W carried along) and then within itself (SVQB; `m_orthonormalize`), fresh
!> pseudo-random directions when the basis became invariant. The projected matrix T is
!> block tridiagonal, as in exact arithmetic: its diagonal blocks from the first
!> Gram-Schmidt pass (symmetrized), its off-diagonal blocks R from the normalization (W =
!> V_new R). (The full V^T M Op V was tried first: the solves' roundoff makes it unsymmetric
!> at 1e-8 on the blade and couples each converged vector to every new block, so the
!> residuals stalled there.) The residual of a Ritz vector V s, Op V s - theta V s = W s_b
!> (s_b the last block's rows of s), has the M-norm sqrt(s_b^T G s_b), G = W^T M W: no extra
!> product. A pair is converged when that is <= tol theta. lambda = sigma + 1 / theta;
!> pairs with theta <= 0 (lambda below sigma) are not returned. The basis grows until the
!> wanted pairs, the lowest ones, have all converged; no restarts (the basis is capped by
!> the caller, who falls back to ARPACK beyond it).
!>
!> Matrices are 1-based compressed sparse column, both triangles stored. No state.
module stickslip_block_lanczos
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_lapack, only: dgemm, dsyev
    implicit none
    private
    public :: block_lanczos_report_t, block_lowest_eigenpairs, csc_times_block, estimated_count, &
        m_orthonormalize

    !> Columns of a block (fewer when n is smaller).
    integer, parameter :: default_block = 8
    !> A Ritz pair is converged when its residual's M-norm is <= this times theta (unless
    !> the caller gives a tolerance).
    real(dp), parameter :: default_tolerance = 1.0e-12_dp
    !> A new direction is kept when its M-norm after the orthogonalization exceeds this
    !> fraction of its M-norm before (dropped: it lies in the basis).
    real(dp), parameter :: rank_tolerance = 1.0e-12_dp
    !> The low 32 bits.
    integer(int64), parameter :: mask32 = 4294967295_int64

    !> What a block Lanczos run did.
    type :: block_lanczos_report_t
        !> Pairs returned (converged).
        integer :: converged = 0
        !> Block solves, and the columns they solved (applications of Op).
        integer :: block_solves = 0
        integer :: op_applications = 0
        !> Basis size at the end.
        integer :: basis = 0
        !> The basis reached max_basis before the wanted pairs converged (nothing returned).
        logical :: basis_full = .false.
        !> With estimate_after: the count below lambda_max estimated above max_count (the
        !> pairs converged so far are returned), and that estimate.
        logical :: capped = .false.
        integer :: estimated = 0
    end type block_lanczos_report_t

contains

    !> The lowest eigenpairs lambda > sigma of K phi = lambda M phi, ascending, M-orthonormal,
    !> given `fac`, a factorization of K - sigma M (used, not changed): the smallest count m
    !> with m >= nev and (values(m) > lambda_max or m = max_count), all converged. With
    !> `estimate_after` = e > 0: once e pairs have converged, the count below lambda_max is
    !> estimated from them (`estimated_count` without its margin) and, when above max_count,
    !> those pairs are returned (report%capped, report%estimated). Errors: bad sizes (input), a
    !> failed solve or dsyev (numerical). The basis reaching max_basis columns first is no
    !> error: report%basis_full, no pairs.
    subroutine block_lowest_eigenpairs(fac, n, mcol, mrow, mval, sigma, nev, lambda_max, &
                                       max_count, max_basis, tolerance, values, vectors, &
                                       report, error, estimate_after)
        !> The factorization of K - sigma M.
        class(sparse_factor_t), intent(inout) :: fac
        !> Order of K and M.
        integer, intent(in) :: n
        !> M: column pointers, row numbers, values.
        integer, intent(in) :: mcol(:), mrow(:)
        real(dp), intent(in) :: mval(:)
        !> The shift [units of lambda].
        real(dp), intent(in) :: sigma
        !> Fewest pairs returned (>= 1).
        integer, intent(in) :: nev
        !> Pairs up to the first above this are returned [units of lambda].
        real(dp), intent(in) :: lambda_max
        !> Most pairs returned (>= nev).
        integer, intent(in) :: max_count
        !> Most basis columns (memory: 2 n max_basis reals).
        integer, intent(in) :: max_basis
        !> Residual tolerance relative to theta (0: default_tolerance).
        real(dp), intent(in) :: tolerance
        !> Eigenvalues, ascending.
        real(dp), allocatable, intent(out) :: values(:)
        !> Eigenvectors (n x size(values)), M-orthonormal.
        real(dp), allocatable, intent(out) :: vectors(:, :)
        !> Counts.
        type(block_lanczos_report_t), intent(out) :: report
        !> Error (last but one).
        type(error_type), allocatable, intent(out) :: error
        !> Estimate the count below lambda_max once this many pairs have converged (<= 0 or
        !> absent: never).
        integer, intent(in), optional :: estimate_after
        real(dp), allocatable :: v(:, :), mv(:, :), t(:, :), w(:, :), mw(:, :), c(:, :)
        real(dp), allocatable :: a(:, :), theta(:), lam(:), res(:), rcoef(:, :), g(:, :)
        integer, allocatable :: order(:)
        real(dp) :: tol
        integer :: bs, m, j0, jp, nb, cap, k, i, nconv, want, npos, kept
        logical :: estimated

        if (n < 2 .or. nev < 1 .or. max_count < nev .or. max_basis < 2 .or. &
            size(mcol) /= n + 1) then
            call fatal_error(error, "block Lanczos: n = "//itoa(n)//", nev = "//itoa(nev)// &
                             ", max_count = "//itoa(max_count)//", max_basis = "// &
                             itoa(max_basis)//": need n >= 2, 1 <= nev <= max_count, "// &
                             "max_basis >= 2 and n + 1 column pointers of M", &
                             stickslip_stat%input)
            return
        end if
        if (fac%n /= n) then
            call fatal_error(error, "block Lanczos: the factorization is of order "// &
                             itoa(fac%n)//", not "//itoa(n), stickslip_stat%input)
            return
        end if
        tol = tolerance
        if (.not. (tol > 0.0_dp)) tol = default_tolerance
        cap = min(n, max_basis)
        bs = min(default_block, cap)
        estimated = .true.
        if (present(estimate_after)) estimated = estimate_after <= 0
        allocate (v(n, min(cap, 8*bs)), mv(n, min(cap, 8*bs)), t(cap, cap))
        t = 0.0_dp
        m = 0
        jp = 0
        ! the first block: pseudo-random (reproducible), M-orthonormalized
        call fresh_block(bs)
        if (allocated(error)) return
        call append()
        do
            j0 = m - nb + 1
            ! W = Op V_last and M W; the Rayleigh quotient's diagonal block from the first
            ! Gram-Schmidt pass, the coupling to the block before from its normalization
            allocate (w(n, nb), mw(n, nb))
            call fac%solve(mv(:, j0:m), w, error)
            if (allocated(error)) then
                error%message = "block Lanczos: "//error%message
                return
            end if
            report%block_solves = report%block_solves + 1
            report%op_applications = report%op_applications + nb
            call csc_times_block(mcol, mrow, mval, w, mw)
            call m_orthonormalize(w, mw, v, mv, m, rank_tolerance, kept, error, &
                                  projection=c, r=rcoef, gram_projected=g)
            if (allocated(error)) return
            t(j0:m, j0:m) = 0.5_dp*(c(j0:m, :) + transpose(c(j0:m, :)))
            ! Ritz pairs of T and their residuals ||W s_b||_M (W: the projected block, Gram g)
            call ritz(m, a, theta)
            if (allocated(error)) return
            npos = count(theta > 0.0_dp)
            ! descending theta = ascending lambda (theta > 0 only)
            order = [(i, i=m, m - npos + 1, -1)]
            allocate (lam(npos), res(npos))
            do i = 1, npos
                k = order(i)
                lam(i) = sigma + 1.0_dp/theta(k)
                res(i) = sqrt(max(dot_product(a(j0:m, k), matmul(g, a(j0:m, k))), 0.0_dp))
            end do
            nconv = 0
            do i = 1, npos
                if (res(i) > tol*theta(order(i))) exit
                nconv = i
            end do
            want = 0
            do i = nev, min(nconv, max_count)
                if (lam(i) > lambda_max .or. i == max_count) then
                    want = i
                    exit
                end if
            end do
            if (want == 0 .and. nconv == npos .and. m == n .and. npos >= nev) &
                want = min(npos, max_count)
            if (want == 0 .and. .not. estimated) then
                if (nconv >= estimate_after .and. nconv >= 2) then
                    estimated = .true.
                    report%estimated = int((estimated_count(lam(1:nconv), lambda_max) - 8)/ &
                                           1.15_dp)
                    if (report%estimated > max_count) then
                        report%capped = .true.
                        want = nconv
                    else
                        report%estimated = 0
                    end if
                end if
            end if
            if (want > 0) then
                values = lam(1:want)
                allocate (vectors(n, want))
                call dgemm('N', 'N', n, want, m, 1.0_dp, v, n, a(:, order(1:want)), m, 0.0_dp, &
                           vectors, n)
                report%converged = want
                report%basis = m
                return
            end if
            if (m >= cap) then
                report%basis_full = .true.
                report%basis = m
                return
            end if
            deallocate (lam, res)
            ! the next block: the kept directions of W, coupled to V_last by R; fresh
            ! directions (uncoupled) when the basis became invariant
            jp = j0
            if (kept == 0) then
                deallocate (w, mw)
                call fresh_block(min(bs, cap - m))
                if (allocated(error)) return
                jp = 0
            end if
            if (m + size(w, 2) > cap) then
                w = w(:, 1:cap - m)
                mw = mw(:, 1:cap - m)
            end if
            call append()
        end do

    contains

        !> w: cols pseudo-random columns (reproducible: a hash of the position),
        !> M-orthogonalized against the basis and among themselves; mw = M w. Error: none
        !> left (M not positive definite?).
        subroutine fresh_block(cols)
            integer, intent(in) :: cols
            integer :: r, col, got
            allocate (w(n, cols), mw(n, cols))
            do col = 1, cols
                do r = 1, n
                    w(r, col) = hashed_uniform(r, col + m)
                end do
            end do
            call csc_times_block(mcol, mrow, mval, w, mw)
            call m_orthonormalize(w, mw, v, mv, m, rank_tolerance, got, error)
            if (allocated(error)) return
            if (got == 0) call fatal_error(error, "block Lanczos: no new direction "// &
                                           "M-orthogonal to a basis of "//itoa(m)// &
                                           " (is M positive definite?)", &
                                           stickslip_stat%numerical)
        end subroutine fresh_block

        !> The columns w (and mw = M w) appended to the basis (grown by doubling), with their
        !> coupling R to the block before in T (when jp > 0).
        subroutine append()
            real(dp), allocatable :: tmp(:, :)
            integer :: cols, room
            cols = size(w, 2)
            if (m + cols > size(v, 2)) then
                room = min(cap, max(2*size(v, 2), m + cols))
                allocate (tmp(n, room))
                tmp(:, 1:m) = v(:, 1:m)
                call move_alloc(tmp, v)
                allocate (tmp(n, room))
                tmp(:, 1:m) = mv(:, 1:m)
                call move_alloc(tmp, mv)
            end if
            v(:, m + 1:m + cols) = w
            mv(:, m + 1:m + cols) = mw
            if (jp > 0) then
                t(m + 1:m + cols, jp:m) = rcoef(1:cols, :)
                t(jp:m, m + 1:m + cols) = transpose(rcoef(1:cols, :))
            end if
            m = m + cols
            nb = cols
            deallocate (w, mw)
        end subroutine append

        !> The eigenpairs of T(1:mm, 1:mm): vectors in aa, values ascending in th.
        subroutine ritz(mm, aa, th)
            integer, intent(in) :: mm
            real(dp), allocatable, intent(out) :: aa(:, :), th(:)
            aa = t(1:mm, 1:mm)
            call symmetric_eigen(aa, th, error)
        end subroutine ritz
    end subroutine block_lowest_eigenpairs

    !> The columns of x (n x k, mx = M x given) M-orthogonalized against the first m columns
    !> of an M-orthonormal basis v (mv = M v) by classical Gram-Schmidt twice (dgemm; mx is
    !> updated alike, so no product with M is needed), then M-orthonormalized among
    !> themselves (SVQB: the eigenvectors of their Gram matrix, scaled by each column's
    !> M-norm before the projection), and once more against the basis when that left them
    !> less M-orthogonal to it than 1e-10. A direction is dropped when its M-norm left is <=
    !> drop times that of the columns before the projection, or below what the Gram matrix
    !> resolves (1e-7 of the block's largest direction: its eigenvalues carry roundoff of
    !> order eps times the largest). x and mx are replaced by the kept columns, `kept` of
    !> them (0: x lay in the basis). Optional: `projection`, the first pass's coefficients
    !> mv^T x (m x k); `r` (kept x k), the kept columns' coefficients of the projected x
    !> (x_projected = x_kept r but for the dropped directions); `gram_projected`, the Gram
    !> matrix x_projected^T M x_projected (k x k). Errors: dsyev failed (numerical).
    subroutine m_orthonormalize(x, mx, v, mv, m, drop, kept, error, projection, r, &
                                gram_projected)
        !> The columns, n x k; on return the kept ones, n x kept.
        real(dp), allocatable, intent(inout) :: x(:, :)
        !> M x, updated alike.
        real(dp), allocatable, intent(inout) :: mx(:, :)
        !> The basis (its first m columns are used) and M times it.
        real(dp), intent(in) :: v(:, :), mv(:, :)
        !> Columns of the basis.
        integer, intent(in) :: m
        !> Relative M-norm below which a direction is dropped.
        real(dp), intent(in) :: drop
        !> Columns kept.
        integer, intent(out) :: kept
        !> Error (dsyev).
        type(error_type), allocatable, intent(out) :: error
        !> The first pass's coefficients mv^T x, m x k.
        real(dp), allocatable, intent(out), optional :: projection(:, :)
        !> The kept columns' coefficients of the projected x, kept x k.
        real(dp), allocatable, intent(out), optional :: r(:, :)
        !> The Gram matrix of the projected x, k x k.
        real(dp), allocatable, intent(out), optional :: gram_projected(:, :)
        real(dp), allocatable :: cf(:, :), g(:, :), y(:, :), d(:), rr(:, :)
        integer :: n, k, q, pass
        n = size(x, 1)
        k = size(x, 2)
        allocate (d(k))
        do q = 1, k
            d(q) = sqrt(max(dot_product(x(:, q), mx(:, q)), 0.0_dp))
        end do
        do pass = 1, 2
            call project_out(cf)
            if (pass == 1 .and. present(projection)) projection = cf
        end do
        g = gram(x, mx)
        if (present(gram_projected)) gram_projected = g
        call svqb(g, d, drop, y, error)
        if (allocated(error)) return
        kept = size(y, 2)
        rr = matmul(transpose(y), g)
        x = matmul_n(x, y)
        mx = matmul_n(mx, y)
        if (kept > 0 .and. m > 0) then
            ! once more when the normalization lost orthogonality to the basis
            call project_out(cf)
            if (maxval(abs(cf)) > 1.0e-10_dp) then
                g = gram(x, mx)
                d = 1.0_dp
                call svqb(g, d(1:kept), 0.0_dp, y, error)
                if (allocated(error)) return
                kept = size(y, 2)
                rr = matmul(matmul(transpose(y), g), rr)
                x = matmul_n(x, y)
                mx = matmul_n(mx, y)
            end if
        end if
        if (present(r)) call move_alloc(rr, r)
    contains
        !> x -= v (mv^T x), mx -= mv (mv^T x); the coefficients in c.
        subroutine project_out(c)
            real(dp), allocatable, intent(out) :: c(:, :)
            integer :: cols
            cols = size(x, 2)
            allocate (c(m, cols))
            if (m == 0 .or. cols == 0) return
            call dgemm('T', 'N', m, cols, n, 1.0_dp, mv, size(mv, 1), x, n, 0.0_dp, c, m)
            call dgemm('N', 'N', n, cols, m, -1.0_dp, v, size(v, 1), c, m, 1.0_dp, x, n)
            call dgemm('N', 'N', n, cols, m, -1.0_dp, mv, size(mv, 1), c, m, 1.0_dp, mx, n)
        end subroutine project_out
    end subroutine m_orthonormalize

    !> SVQB: given the Gram matrix g (k x k) of k columns and their reference norms nrm, the
    !> coefficients y (k x kept) of M-orthonormal combinations of them: the eigenvectors of
    !> D g D (D = diag(1 / nrm)) with eigenvalue mu > drop^2 and > 1e-14 times the largest,
    !> scaled by D / sqrt(mu), largest first. A column of reference norm 0 is left out.
    !> Errors: dsyev failed (numerical).
    subroutine svqb(g, nrm, drop, y, error)
        !> Gram matrix.
        real(dp), intent(in) :: g(:, :)
        !> Reference norms of the columns.
        real(dp), intent(in) :: nrm(:)
        !> Relative norm below which a direction is dropped.
        real(dp), intent(in) :: drop
        !> The coefficients, k x kept.
        real(dp), allocatable, intent(out) :: y(:, :)
        !> Error.
        type(error_type), allocatable, intent(inout) :: error
        real(dp), allocatable :: u(:, :), mu(:), dd(:)
        integer :: k, q, kept
        k = size(g, 1)
        allocate (dd(k))
        dd = 0.0_dp
        where (nrm > 0.0_dp) dd = 1.0_dp/nrm
        u = g
        do q = 1, k
            u(:, q) = dd*u(:, q)*dd(q)
        end do
        call symmetric_eigen(u, mu, error)
        if (allocated(error)) return
        kept = 0
        do q = k, 1, -1
            if (.not. (mu(q) > drop**2 .and. mu(q) > 1.0e-14_dp*mu(k))) exit
            kept = kept + 1
        end do
        allocate (y(k, kept))
        do q = 1, kept
            y(:, q) = dd*u(:, k - q + 1)/sqrt(mu(k - q + 1))
        end do
    end subroutine svqb

    !> The eigenvectors (in a) and eigenvalues (ascending, in w) of a symmetric matrix a by
    !> dsyev. Error: dsyev failed (numerical).
    subroutine symmetric_eigen(a, w, error)
        !> The matrix; on return its orthonormal eigenvectors.
        real(dp), intent(inout) :: a(:, :)
        !> The eigenvalues, ascending.
        real(dp), allocatable, intent(out) :: w(:)
        !> Error.
        type(error_type), allocatable, intent(inout) :: error
        real(dp), allocatable :: work(:)
        real(dp) :: wq(1)
        integer :: info, nn
        nn = size(a, 1)
        allocate (w(nn))
        if (nn == 0) return
        call dsyev('V', 'U', nn, a, nn, w, wq, -1, info)
        allocate (work(max(1, int(wq(1)))))
        call dsyev('V', 'U', nn, a, nn, w, work, size(work), info)
        if (info /= 0) call fatal_error(error, "block Lanczos: dsyev failed (info "// &
                                        itoa(info)//")", stickslip_stat%numerical)
    end subroutine symmetric_eigen

    !> x^T y for n x k blocks (k x k).
    function gram(x, y) result(g)
        real(dp), intent(in) :: x(:, :), y(:, :)
        real(dp) :: g(size(x, 2), size(y, 2))
        call dgemm('T', 'N', size(x, 2), size(y, 2), size(x, 1), 1.0_dp, x, size(x, 1), y, &
                   size(y, 1), 0.0_dp, g, size(x, 2))
    end function gram

    !> x y by dgemm (x: n x k, y: k x j).
    function matmul_n(x, y) result(z)
        real(dp), intent(in) :: x(:, :), y(:, :)
        real(dp) :: z(size(x, 1), size(y, 2))
        if (size(y, 2) == 0 .or. size(x, 1) == 0) return
        call dgemm('N', 'N', size(x, 1), size(y, 2), size(x, 2), 1.0_dp, x, size(x, 1), y, &
                   size(y, 1), 0.0_dp, z, size(x, 1))
    end function matmul_n

    !> A number in [-1/2, 1/2) from two integers (i, j >= 0): a 32-bit integer hash of i
    !> combined with j, hashed again (multiplications kept below 2^63 in 64-bit integers);
    !> reproducible, and columns j of it are far from linearly dependent.
    pure real(dp) function hashed_uniform(i, j) result(u)
        integer, intent(in) :: i, j
        u = real(mix32(ieor(mix32(int(i, int64)), iand(int(j, int64)*40503_int64, mask32))), dp) &
            /4294967296.0_dp - 0.5_dp
    end function hashed_uniform

    !> A 32-bit integer hash (xor-shift-multiply rounds) of the low 32 bits of x.
    pure integer(int64) function mix32(x) result(z)
        integer(int64), intent(in) :: x
        z = iand(x, mask32)
        z = ieor(z, ishft(z, -16))
        z = iand(z*2146121005_int64, mask32)
        z = ieor(z, ishft(z, -15))
        z = iand(z*739982445_int64, mask32)
        z = ieor(z, ishft(z, -16))
    end function mix32

    !> y = A x for A in compressed sparse column form and a block x (size(colptr) - 1 rows of
    !> x, size(y, 1) rows of A): one pass over A for the whole block, the block transposed so
    !> that each entry of A updates a contiguous row.
    subroutine csc_times_block(colptr, rowind, values, x, y)
        !> Column pointers.
        integer, intent(in) :: colptr(:)
        !> Row numbers.
        integer, intent(in) :: rowind(:)
        !> Values.
        real(dp), intent(in) :: values(:)
        !> The block, one row per column of A.
        real(dp), intent(in) :: x(:, :)
        !> The product, one row per row of A.
        real(dp), intent(out) :: y(:, :)
        real(dp), allocatable :: xt(:, :), yt(:, :)
        integer :: j, k
        allocate (xt(size(x, 2), size(x, 1)), yt(size(x, 2), size(y, 1)))
        xt = transpose(x)
        yt = 0.0_dp
        do j = 1, size(colptr) - 1
            do k = colptr(j), colptr(j + 1) - 1
                yt(:, rowind(k)) = yt(:, rowind(k)) + values(k)*xt(:, j)
            end do
        end do
        y = transpose(yt)
    end subroutine csc_times_block

    !> How many eigenvalues to ask for to pass `limit`, from the lowest ones `values`
    !> (ascending, size >= 2): N(lambda) ~ c lambda^p fitted through the counts at the middle
    !> and the end of `values`, p clamped to [1/4, 2], plus a margin of 15 % and 8.
    pure integer function estimated_count(values, limit) result(nev)
        !> The lowest eigenvalues, ascending.
        real(dp), intent(in) :: values(:)
        !> The limit [units of the values].
        real(dp), intent(in) :: limit
        integer :: m, k
        real(dp) :: p, lo, hi
        m = size(values)
        k = max(1, m/2)
        lo = max(values(k), tiny(1.0_dp))
        hi = values(m)
        p = 1.0_dp
        if (hi > lo*(1.0_dp + 1.0e-6_dp) .and. k < m) &
            p = log(real(m, dp)/real(k, dp))/log(hi/lo)
        p = min(max(p, 0.25_dp), 2.0_dp)
        ! a limit far above the spectrum seen (1e300) must not overflow the count
        nev = int(min(1.15_dp*m*exp(min(p*log(max(limit, hi)/hi), 40.0_dp)) + 9.0_dp, 1.0e9_dp))
    end function estimated_count

end module stickslip_block_lanczos
