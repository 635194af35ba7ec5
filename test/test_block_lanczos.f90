!> stickslip_block_lanczos and the block products. The block Lanczos on membranes of about
!> 500 DOFs (a sparse LU of K as its factorization) against LAPACK dsygv: every eigenvalue
!> below a limit found, one above, dsygv's values, M-orthonormal vectors with small
!> residuals, the exact double eigenvalues of a uniform square grid; the nev lowest; the cap
!> max_count; the count estimate stopping a run; a basis too small reported, not an error.
!> On a 3D lattice of 2744 DOFs, sparse_eigenpairs_below given a supernodal Cholesky takes
!> the block path and agrees with ARPACK's run on an LU, and so does sparse_eigenpairs' nev
!> lowest on that factor. m_orthonormalize: a block with a
!> dependent column and one inside the basis comes out M-orthonormal, M-orthogonal to the
!> basis, with the dependent directions dropped and x_projected = x_kept r. The block products
!> (CSR: sparse_times_block, across its 16-column chunks; CSC: csc_times_block) against one
!> column at a time.
module test_block_lanczos
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_umfpack, only: sparse_lu_t
    use stickslip_cholmod, only: sparse_cholesky_t
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_arpack, only: eigen_options_t, eigen_report_t
    use stickslip_sparse_eigen, only: sparse_eigenpairs_below, sparse_eigenpairs, &
        eigen_range_report_t, csc_matvec
    use stickslip_block_lanczos, only: block_lanczos_report_t, block_lowest_eigenpairs, &
        csc_times_block, m_orthonormalize
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_matvec, &
        sparse_times_block
    use test_umfpack, only: dense_to_csc
    use test_arpack, only: membrane, identity
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_block_lanczos_tests

contains

    subroutine run_block_lanczos_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_membranes(t)
        call test_lattice(t)
        call test_orthonormalize(t)
        call test_block_products(t)
    end subroutine run_block_lanczos_tests

    !> The block Lanczos on a random and a uniform membrane against dsygv.
    subroutine test_membranes(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: k(:, :), m(:, :), w(:), values(:), vectors(:, :)
        integer, allocatable :: kcol(:), krow(:), mcol(:), mrow(:)
        real(dp), allocatable :: kval(:), mval(:)
        type(sparse_lu_t) :: lu
        type(block_lanczos_report_t) :: report
        type(error_type), allocatable :: error
        real(dp) :: limit
        integer :: n, want, g, j
        character(len=24) :: name
        do g = 1, 2
            call membrane(g, k, m, w, want, limit, name)
            n = size(k, 1)
            call dense_to_csc(k, kcol, krow, kval)
            call dense_to_csc(m, mcol, mrow, mval)
            call lu%factorize(n, kcol, krow, kval, error)
            call check(t, .not. allocated(error), "block Lanczos: "//trim(name)//": K factorized")
            if (allocated(error)) return
            call block_lowest_eigenpairs(lu, n, mcol, mrow, mval, 0.0_dp, 1, limit, 500, 400, &
                                         0.0_dp, values, vectors, report, error)
            call check(t, .not. allocated(error) .and. .not. report%basis_full, &
                       "block Lanczos: "//trim(name)//": converged")
            if (allocated(error) .or. report%basis_full) return
            call check(t, count(values <= limit) == want .and. size(values) == want + 1, &
                       "block Lanczos: "//trim(name)//": every value below the limit and "// &
                       "one above", "found "//itoa(count(values <= limit))//" and "// &
                       itoa(size(values))//" in all, dsygv "//itoa(want))
            j = min(size(values), want + 1)
            call check_close(t, values(1:j), w(1:j), "block Lanczos: "//trim(name)// &
                             ": values = dsygv's", rtol=1.0e-9_dp)
            call check_close(t, reshape(matmul(transpose(vectors), matmul(m, vectors)), &
                                        [size(values)**2]), &
                             reshape(identity(size(values)), [size(values)**2]), &
                             "block Lanczos: "//trim(name)//": M-orthonormal", atol=1.0e-9_dp)
            call check_close(t, maxval(abs(matmul(k, vectors) - matmul(m, vectors)* &
                                           spread(values, 1, n))), 0.0_dp, &
                             "block Lanczos: "//trim(name)//": residuals", &
                             atol=1.0e-9_dp*maxval(values))
            call check(t, report%block_solves*8 >= report%op_applications .and. &
                       report%op_applications < 4*n/5, "block Lanczos: "//trim(name)// &
                       ": blocks of 8, a basis below n", itoa(report%op_applications)// &
                       " columns in "//itoa(report%block_solves)//" block solves")
        end do
        ! the nev lowest (no limit), the cap, the count estimate, a basis too small
        call block_lowest_eigenpairs(lu, n, mcol, mrow, mval, 0.0_dp, 12, -huge(1.0_dp), 12, &
                                     400, 0.0_dp, values, vectors, report, error)
        call check(t, .not. allocated(error) .and. size(values) == 12, &
                   "block Lanczos: the 12 lowest")
        if (.not. allocated(error) .and. size(values) == 12) &
            call check_close(t, values, w(1:12), "block Lanczos: ... = dsygv's", rtol=1.0e-9_dp)
        call block_lowest_eigenpairs(lu, n, mcol, mrow, mval, 0.0_dp, 1, limit, 10, 400, 0.0_dp, &
                                     values, vectors, report, error)
        call check(t, .not. allocated(error) .and. size(values) == 10, &
                   "block Lanczos: capped at max_count = 10")
        call block_lowest_eigenpairs(lu, n, mcol, mrow, mval, 0.0_dp, 1, 1.0e3_dp*w(n), 30, &
                                     400, 0.0_dp, values, vectors, report, error, &
                                     estimate_after=20)
        call check(t, .not. allocated(error) .and. report%capped .and. &
                   report%estimated > 30 .and. size(values) >= 20 .and. size(values) < 30, &
                   "block Lanczos: a limit far above: the count estimated after 20, the "// &
                   "run stopped", "estimated "//itoa(report%estimated)//", returned "// &
                   itoa(size(values)))
        call block_lowest_eigenpairs(lu, n, mcol, mrow, mval, 0.0_dp, 1, limit, 500, 24, 0.0_dp, &
                                     values, vectors, report, error)
        call check(t, .not. allocated(error) .and. report%basis_full .and. &
                   .not. allocated(values), "block Lanczos: a basis of 24 columns: "// &
                   "basis_full, no pairs, no error")
        call lu%release()
    end subroutine test_membranes

    !> A 14^3 lattice (springs random in [1, 2), masses in [0.5, 1.5), held at the walls):
    !> sparse_eigenpairs_below on its supernodal Cholesky (block Lanczos) against the same on
    !> an LU (ARPACK).
    subroutine test_lattice(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: s = 14
        type(sparse_matrix_t) :: k, m
        class(sparse_factor_t), allocatable :: chol, none
        real(dp), allocatable :: v1(:), x1(:, :), v2(:), x2(:, :), mx(:, :), kx(:, :)
        type(eigen_range_report_t) :: r1, r2
        type(eigen_report_t) :: erep
        type(error_type), allocatable :: error
        real(dp) :: limit
        integer :: n, j
        call lattice(s, k, m)
        n = k%nrows
        allocate (sparse_cholesky_t :: chol)
        call chol%factorize(n, k%row_start, k%col, k%val, error)
        call check(t, .not. allocated(error), "block Lanczos: lattice: Cholesky")
        if (allocated(error)) return
        call check(t, chol%solves_blocks(), "block Lanczos: lattice: CHOLMOD chose a "// &
                   "supernodal factor (cheap block solves)", chol%name())
        limit = 0.9_dp
        call sparse_eigenpairs_below(n, k%row_start, k%col, k%val, m%row_start, m%col, m%val, &
                                     limit, 300, 0.0_dp, eigen_options_t(), v1, x1, r1, error, &
                                     factorization=chol)
        call check(t, .not. allocated(error) .and. r1%block_solves > 0, &
                   "block Lanczos: lattice: the Cholesky's eigenpairs by block Lanczos")
        if (allocated(error)) return
        call sparse_eigenpairs_below(n, k%row_start, k%col, k%val, m%row_start, m%col, m%val, &
                                     limit, 300, 0.0_dp, eigen_options_t(), v2, x2, r2, error, &
                                     factorization=none)
        call check(t, .not. allocated(error) .and. r2%block_solves == 0 .and. r2%runs >= 1, &
                   "block Lanczos: lattice: ARPACK on the LU")
        if (allocated(error)) return
        call check(t, r1%below == r2%below .and. r1%below >= 10, &
                   "block Lanczos: lattice: the same count below the limit", &
                   itoa(r1%below)//" and "//itoa(r2%below))
        j = min(size(v1), size(v2))
        call check_close(t, v1(1:j), v2(1:j), "block Lanczos: lattice: the same values", &
                         rtol=1.0e-10_dp)
        allocate (mx(n, size(v1)), kx(n, size(v1)))
        call sparse_times_block(m, x1, mx)
        call sparse_times_block(k, x1, kx)
        call check_close(t, maxval(abs(kx - mx*spread(v1, 1, n))), 0.0_dp, &
                         "block Lanczos: lattice: residuals", atol=1.0e-9_dp*maxval(v1))
        call check_close(t, maxval(abs(matmul(transpose(x1), mx) - identity(size(v1)))), &
                         0.0_dp, "block Lanczos: lattice: M-orthonormal", atol=1.0e-10_dp)
        ! the nev lowest (sparse_eigenpairs, `&reduction modes`) on the same factor
        call sparse_eigenpairs(n, k%row_start, k%col, k%val, m%row_start, m%col, m%val, 12, &
                               0.0_dp, eigen_options_t(), v1, x1, erep, error, &
                               factorization=chol)
        call check(t, .not. allocated(error) .and. size(v1) == 12 .and. &
                   erep%block_solves > 0, &
                   "block Lanczos: lattice: the 12 lowest on the Cholesky, block path", &
                   itoa(erep%op_applications)//" solves, basis "//itoa(erep%ncv))
        if (.not. allocated(error) .and. size(v1) == 12) &
            call check_close(t, v1, v2(1:12), "block Lanczos: lattice: ... = ARPACK's", &
                             rtol=1.0e-10_dp)
        call chol%release()
        if (allocated(none)) call none%release()
    end subroutine test_lattice

    !> m_orthonormalize on a block of 6 against an M-orthonormal basis of 5 (n = 60, M
    !> diagonal random): column 4 = column 1 + 2 column 2, column 6 inside the basis.
    subroutine test_orthonormalize(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 60
        real(dp) :: md(n), q(n, 5), c(5, 5), g(5, 5)
        real(dp), allocatable :: x(:, :), mx(:, :), x0(:, :), r(:, :), p(:, :), mq(:, :)
        type(error_type), allocatable :: error
        integer :: kept, j
        call random_number(md)
        md = 0.5_dp + md
        call random_number(q)
        ! the basis M-orthonormal: q c^-1 with c c^T = the Cholesky of q^T M q ... by
        ! Gram-Schmidt
        do j = 1, 5
            q(:, j) = q(:, j) - matmul(q(:, 1:j - 1), matmul(transpose(q(:, 1:j - 1)), md*q(:, j)))
            q(:, j) = q(:, j)/sqrt(sum(md*q(:, j)**2))
        end do
        c = matmul(transpose(q), spread(md, 2, 5)*q)
        g = c - identity(5)
        call check(t, maxval(abs(g)) < 1.0e-12_dp, "m_orthonormalize: the test basis")
        allocate (x(n, 6))
        call random_number(x)
        x(:, 4) = x(:, 1) + 2.0_dp*x(:, 2)
        x(:, 6) = matmul(q, [1.0_dp, -2.0_dp, 0.5_dp, 3.0_dp, 1.0_dp])
        x0 = x
        mx = spread(md, 2, 6)*x
        mq = spread(md, 2, 5)*q
        call m_orthonormalize(x, mx, q, mq, 5, 1.0e-8_dp, kept, error, projection=p, r=r)
        call check(t, .not. allocated(error) .and. kept == 4, &
                   "m_orthonormalize: the dependent and the inside column dropped", &
                   "kept "//itoa(kept))
        if (allocated(error) .or. kept /= 4) return
        call check_close(t, maxval(abs(matmul(transpose(x), spread(md, 2, 4)*x) - identity(4))), &
                         0.0_dp, "m_orthonormalize: M-orthonormal", atol=1.0e-12_dp)
        call check_close(t, maxval(abs(matmul(transpose(mq), x))), 0.0_dp, &
                         "m_orthonormalize: M-orthogonal to the basis", atol=1.0e-12_dp)
        call check_close(t, maxval(abs(mx - spread(md, 2, 4)*x)), 0.0_dp, &
                         "m_orthonormalize: mx = M x", atol=1.0e-12_dp)
        call check_close(t, maxval(abs(p - matmul(transpose(mq), x0))), 0.0_dp, &
                         "m_orthonormalize: the projection coefficients", atol=1.0e-12_dp)
        ! x0 projected = x r
        call check_close(t, maxval(abs(x0 - matmul(q, matmul(transpose(mq), x0)) - &
                                       matmul(x, r))), 0.0_dp, &
                         "m_orthonormalize: x_projected = x_kept r", atol=1.0e-10_dp)
    end subroutine test_orthonormalize

    !> The block products against one column at a time: a random 70 x 50 CSR matrix with 21
    !> columns (two chunks and a part), and the CSC product of a square one.
    subroutine test_block_products(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: a
        real(dp), allocatable :: x(:, :), y(:, :), yc(:), d(:, :), xs(:, :), ys(:, :)
        integer, allocatable :: rows(:), cols(:), colptr(:), rowind(:)
        real(dp), allocatable :: vals(:), values(:), r(:)
        type(error_type), allocatable :: error
        integer :: j, nt
        nt = 600
        allocate (rows(nt), cols(nt), vals(nt), r(nt))
        call random_number(r)
        rows = 1 + int(r*70)
        call random_number(r)
        cols = 1 + int(r*50)
        call random_number(vals)
        call new_sparse_from_triplets(a, 70, 50, rows, cols, vals - 0.5_dp, error)
        call check(t, .not. allocated(error), "block products: the test matrix")
        if (allocated(error)) return
        allocate (x(50, 21), y(70, 21))
        call random_number(x)
        call sparse_times_block(a, x, y)
        do j = 1, 21
            call sparse_matvec(a, x(:, j), yc, error)
            call check_close(t, y(:, j), yc, "sparse_times_block: column "//itoa(j), &
                             rtol=1.0e-14_dp, atol=1.0e-14_dp)
        end do
        deallocate (yc)
        allocate (d(40, 40), xs(40, 5), ys(40, 5), yc(40))
        call random_number(d)
        where (d < 0.8_dp) d = 0.0_dp
        call dense_to_csc(d, colptr, rowind, values)
        call random_number(xs)
        call csc_times_block(colptr, rowind, values, xs, ys)
        do j = 1, 5
            call csc_matvec(colptr, rowind, values, xs(:, j), yc)
            call check_close(t, ys(:, j), yc, "csc_times_block: column "//itoa(j), &
                             rtol=1.0e-14_dp, atol=1.0e-14_dp)
        end do
    end subroutine test_block_products

    !> Stiffness and mass of an s^3 lattice of masses (random in [0.5, 1.5)) joined to their
    !> 6 neighbours by springs (random in [1, 2)), the outer ones also to fixed walls.
    subroutine lattice(s, k, m)
        integer, intent(in) :: s
        type(sparse_matrix_t), intent(out) :: k, m
        integer, allocatable :: rk(:), ck(:), ri(:)
        real(dp), allocatable :: vk(:), mv(:)
        type(error_type), allocatable :: error
        integer :: i, j, l, p, nt, n
        n = s**3
        allocate (rk(13*n), ck(13*n), vk(13*n), mv(n))
        call random_number(mv)
        mv = 0.5_dp + mv
        nt = 0
        do l = 1, s
            do j = 1, s
                do i = 1, s
                    p = i + (j - 1)*s + (l - 1)*s*s
                    call spring(p, merge(p + 1, 0, i < s))
                    call spring(p, merge(p + s, 0, j < s))
                    call spring(p, merge(p + s*s, 0, l < s))
                    if (i == 1) call spring(p, 0)
                    if (j == 1) call spring(p, 0)
                    if (l == 1) call spring(p, 0)
                end do
            end do
        end do
        call new_sparse_from_triplets(k, n, n, rk(1:nt), ck(1:nt), vk(1:nt), error)
        ri = [(i, i=1, n)]
        call new_sparse_from_triplets(m, n, n, ri, ri, mv, error)
    contains
        subroutine spring(a, b)
            integer, intent(in) :: a, b
            real(dp) :: ks
            call random_number(ks)
            ks = 1.0_dp + ks
            call put(a, a, ks)
            if (b > 0) then
                call put(b, b, ks)
                call put(a, b, -ks)
                call put(b, a, -ks)
            end if
        end subroutine spring
        subroutine put(a, b, value)
            integer, intent(in) :: a, b
            real(dp), intent(in) :: value
            nt = nt + 1
            rk(nt) = a
            ck(nt) = b
            vk(nt) = value
        end subroutine put
    end subroutine lattice


end module test_block_lanczos
