!> stickslip_arpack: shift-invert Lanczos (ARPACK) with the operator applied through a sparse
!> LU (UMFPACK). A fixed-fixed spring-mass chain of N = 500 equal masses m and springs k has
!> lambda_j = 2 k / m (1 - cos(j pi / (N + 1))): the nev smallest, their M-orthonormal
!> vectors and residuals ||K phi - lambda M phi||. A chain with random springs and a
!> consistent (tridiagonal) mass matrix against LAPACK dsygv, at shift 0 and at a shift
!> inside the spectrum. Failures: nev >= n, an operator that stops. Four chains solved from
!> four OpenMP threads at once (OpenMP build; serially otherwise) give their closed forms.
!> stickslip_sparse_eigen: alpha A + beta B on the union pattern against the dense sum; a
!> chain of N = 1000 with a consistent (tridiagonal) mass matrix in compressed columns against
!> lambda_j = k (2 - 2 cos t_j) / (m + me/6 (4 + 2 cos t_j)), t_j = j pi/(N+1); a free-free
!> chain: sigma = 0 reported singular, sigma < 0 finds the rigid mode lambda = 0 and
!> lambda_j = 2k/m (1 - cos(j pi/N)).
module test_arpack
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat, itoa
    use stickslip_lapack, only: dsygv
    use stickslip_umfpack, only: sparse_lu_t
    use stickslip_arpack, only: shift_invert_operator_t, eigen_options_t, eigen_report_t, &
        smallest_eigenpairs
    use stickslip_sparse_eigen, only: csc_combine, csc_matvec_lib => csc_matvec, &
        sparse_eigenpairs, sparse_eigenpairs_below, eigen_range_report_t
    use test_umfpack, only: dense_to_csc
    use testing, only: test_counter_t, check, check_close
    implicit none
    private
    public :: run_arpack_tests, membrane, identity

    real(dp), parameter :: pi = acos(-1.0_dp)

    !> (K - sigma M)^-1 by a sparse LU, M x by a compressed-column product.
    type, extends(shift_invert_operator_t) :: sparse_op_t
        type(sparse_lu_t) :: lu
        integer, allocatable :: mcol(:), mrow(:)
        real(dp), allocatable :: mval(:)
        !> Stop after this many mass products (0: never), to test the callback stop.
        integer :: stop_after = 0
        integer :: products = 0
    contains
        procedure :: solve_shifted => op_solve
        procedure :: apply_mass => op_mass
    end type sparse_op_t

contains

    subroutine run_arpack_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_uniform_chain(t)
        call test_against_dsygv(t)
        call test_failures(t)
        call test_threads(t)
        call test_combine(t)
        call test_sparse_chain(t)
        call test_free_chain(t)
        call test_below_limit(t)
    end subroutine run_arpack_tests

    !> Stiffness and mass of a nx x ny grid of masses joined to their 4 neighbours by springs,
    !> the outer ones also to fixed walls (a membrane): springs random in [1, 2) and masses
    !> random in [0.5, 1.5) (`uniform`: all 1, so that the spectrum of a square grid has
    !> exact double eigenvalues).
    subroutine grid(nx, ny, uniform, k, m)
        integer, intent(in) :: nx, ny
        logical, intent(in) :: uniform
        real(dp), allocatable, intent(out) :: k(:, :), m(:, :)
        integer :: i, j, p
        real(dp) :: s
        allocate (k(nx*ny, nx*ny), m(nx*ny, nx*ny))
        k = 0.0_dp
        m = 0.0_dp
        do j = 1, ny
            do i = 1, nx
                p = i + (j - 1)*nx
                m(p, p) = 1.0_dp
                if (.not. uniform) then
                    call random_number(s)
                    m(p, p) = 0.5_dp + s
                end if
                ! the springs to the right and up (to a wall at the edge), and from the walls
                ! on the left and at the bottom
                call spring(p, merge(p + 1, 0, i < nx))
                call spring(p, merge(p + nx, 0, j < ny))
                if (i == 1) call spring(p, 0)
                if (j == 1) call spring(p, 0)
            end do
        end do
    contains
        subroutine spring(a, b)
            integer, intent(in) :: a, b
            real(dp) :: ks
            ks = 1.0_dp
            if (.not. uniform) then
                call random_number(ks)
                ks = 1.0_dp + ks
            end if
            k(a, a) = k(a, a) + ks
            if (b > 0) then
                k(b, b) = k(b, b) + ks
                k(a, b) = k(a, b) - ks
                k(b, a) = k(b, a) - ks
            end if
        end subroutine spring
    end subroutine grid

    !> Test membrane g (1: a random 24 x 20 grid, 2: a uniform 22 x 22 grid with exact double
    !> eigenvalues): K, M, all eigenvalues w (dsygv), the count `want` of those below `limit`,
    !> a limit in a gap of the spectrum near the 45th (60th) (double eigenvalues never
    !> split), and the case's name.
    subroutine membrane(g, k, m, w, want, limit, name)
        integer, intent(in) :: g
        real(dp), allocatable, intent(out) :: k(:, :), m(:, :), w(:)
        integer, intent(out) :: want
        real(dp), intent(out) :: limit
        character(len=*), intent(out) :: name
        if (g == 1) then
            call grid(24, 20, .false., k, m)
            want = 45
            name = "random 24 x 20 grid"
        else
            call grid(22, 22, .true., k, m)
            name = "uniform 22 x 22 grid"
            want = 60
        end if
        call all_pairs(k, m, w)
        do while (w(want + 1) - w(want) < 1.0e-6_dp*w(want))
            want = want + 1
        end do
        limit = 0.5_dp*(w(want) + w(want + 1))
    end subroutine membrane

    !> sparse_eigenpairs_below against LAPACK dsygv (all eigenpairs) on membranes of about
    !> 500 DOFs: every eigenvalue below the limit found (the count estimated from the first
    !> 20, a second run), equal to dsygv's, one more above it, M-orthonormal vectors with
    !> small residuals; exact double eigenvalues of a square uniform grid all found; the cap
    !> max_count; a limit below the spectrum; max_count = 0 rejected.
    subroutine test_below_limit(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: k(:, :), m(:, :), w(:), values(:), vectors(:, :)
        integer, allocatable :: kcol(:), krow(:), mcol(:), mrow(:)
        real(dp), allocatable :: kval(:), mval(:)
        type(eigen_range_report_t) :: report
        type(error_type), allocatable :: error
        real(dp) :: limit
        integer :: n, want, g, j
        character(len=24) :: name
        do g = 1, 2
            call membrane(g, k, m, w, want, limit, name)
            n = size(k, 1)
            call dense_to_csc(k, kcol, krow, kval)
            call dense_to_csc(m, mcol, mrow, mval)
            call sparse_eigenpairs_below(n, kcol, krow, kval, mcol, mrow, mval, limit, 500, &
                                         0.0_dp, eigen_options_t(), values, vectors, report, &
                                         error)
            call check(t, .not. allocated(error), "eigenpairs below: "//trim(name))
            if (allocated(error)) return
            call check(t, report%below == want .and. count(values <= limit) == want, &
                       "eigenpairs below: "//trim(name)//": none missed", &
                       "found "//itoa(report%below)//", dsygv "//itoa(want))
            call check(t, size(values) > want .and. .not. report%capped, &
                       "eigenpairs below: "//trim(name)//": one above the limit returned")
            call check(t, report%runs == 2 .and. report%factorizations == 1, &
                       "eigenpairs below: "//trim(name)//": the count estimated, two runs "// &
                       "on one factorization")
            j = min(size(values), want + 1)
            call check_close(t, values(1:j), w(1:j), "eigenpairs below: "//trim(name)// &
                             ": values = dsygv's", rtol=1.0e-9_dp)
            call check_close(t, reshape(matmul(transpose(vectors), matmul(m, vectors)), &
                                        [size(values)**2]), &
                             reshape(identity(size(values)), [size(values)**2]), &
                             "eigenpairs below: "//trim(name)//": M-orthonormal", &
                             atol=1.0e-9_dp)
            call check_close(t, maxval(abs(matmul(k, vectors) - matmul(m, vectors)* &
                                           spread(values, 1, n))), 0.0_dp, &
                             "eigenpairs below: "//trim(name)//": residuals", &
                             atol=1.0e-9_dp*maxval(values))
        end do
        ! the cap, and a limit below the spectrum (the last grid)
        call sparse_eigenpairs_below(n, kcol, krow, kval, mcol, mrow, mval, limit, 10, 0.0_dp, &
                                     eigen_options_t(), values, vectors, report, error)
        call check(t, .not. allocated(error), "eigenpairs below: max_count = 10")
        if (allocated(error)) return
        call check(t, size(values) == 10 .and. report%capped .and. report%below == 10, &
                   "eigenpairs below: capped at max_count")
        call check_close(t, values, w(1:10), "eigenpairs below: capped: the 10 lowest", &
                         rtol=1.0e-9_dp)
        call sparse_eigenpairs_below(n, kcol, krow, kval, mcol, mrow, mval, 0.5_dp*w(1), 500, &
                                     0.0_dp, eigen_options_t(), values, vectors, report, error)
        call check(t, .not. allocated(error), "eigenpairs below: limit below the spectrum")
        if (allocated(error)) return
        call check(t, report%below == 0 .and. size(values) >= 1 .and. .not. report%capped &
                   .and. report%runs == 1, "eigenpairs below: none below, the lowest returned")
        call check_close(t, values(1), w(1), "eigenpairs below: ... and it is dsygv's first", &
                         rtol=1.0e-9_dp)
        call sparse_eigenpairs_below(n, kcol, krow, kval, mcol, mrow, mval, limit, 0, 0.0_dp, &
                                     eigen_options_t(), values, vectors, report, error)
        call check(t, allocated(error), "eigenpairs below: max_count = 0 rejected")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "eigenpairs below: ... as an input error")
    end subroutine test_below_limit

    !> All eigenvalues of K phi = lambda M phi by LAPACK dsygv, ascending.
    subroutine all_pairs(k, m, w)
        real(dp), intent(in) :: k(:, :), m(:, :)
        real(dp), allocatable, intent(out) :: w(:)
        real(dp), allocatable :: a(:, :), b(:, :), work(:)
        real(dp) :: wq(1)
        integer :: n, info
        n = size(k, 1)
        a = k
        b = m
        allocate (w(n))
        call dsygv(1, 'N', 'U', n, a, n, b, n, w, wq, -1, info)
        allocate (work(int(wq(1))))
        call dsygv(1, 'N', 'U', n, a, n, b, n, w, work, size(work), info)
        if (info /= 0) w = -1.0_dp
    end subroutine all_pairs

    pure function identity(n) result(e)
        integer, intent(in) :: n
        real(dp) :: e(n, n)
        integer :: i
        e = 0.0_dp
        do i = 1, n
            e(i, i) = 1.0_dp
        end do
    end function identity

    subroutine test_combine(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 30
        real(dp) :: a(n, n), b(n, n), keep(n, n), c(n, n), x(n), y(n)
        integer, allocatable :: acol(:), arow(:), bcol(:), brow(:), ccol(:), crow(:)
        real(dp), allocatable :: aval(:), bval(:), cval(:)
        integer :: j, k
        call random_number(a)
        call random_number(keep)
        where (keep > 0.2_dp) a = 0.0_dp
        call random_number(b)
        call random_number(keep)
        where (keep > 0.2_dp) b = 0.0_dp
        call dense_to_csc(a, acol, arow, aval)
        call dense_to_csc(b, bcol, brow, bval)
        call csc_combine(n, acol, arow, aval, 2.0_dp, bcol, brow, bval, -3.0_dp, ccol, crow, cval)
        c = 0.0_dp
        do j = 1, n
            do k = ccol(j), ccol(j + 1) - 1
                c(crow(k), j) = cval(k)
            end do
        end do
        call check_close(t, reshape(c, [n*n]), reshape(2.0_dp*a - 3.0_dp*b, [n*n]), &
                         "sparse_eigen: csc_combine = 2 A - 3 B", atol=1.0e-15_dp)
        call check(t, size(crow) == count(a /= 0.0_dp .or. b /= 0.0_dp) .and. &
                   all([(all(crow(ccol(j) + 1:ccol(j + 1) - 1) > crow(ccol(j):ccol(j + 1) - 2)), &
                         j=1, n)]), "sparse_eigen: union pattern, rows ascending")
        call random_number(x)
        call csc_matvec_lib(ccol, crow, cval, x, y)
        call check_close(t, y, matmul(c, x), "sparse_eigen: csc_matvec = dense product", &
                         rtol=1.0e-13_dp, atol=1.0e-13_dp)
    end subroutine test_combine

    !> A uniform chain in compressed sparse columns: n masses (lumped m plus consistent
    !> element masses me), n + 1 springs k when fixed at both ends, n - 1 when free.
    subroutine csc_chain(n, fixed, stiff, m, me, kcol, krow, kval, mcol, mrow, mval)
        integer, intent(in) :: n
        logical, intent(in) :: fixed
        real(dp), intent(in) :: stiff, m, me
        integer, allocatable, intent(out) :: kcol(:), krow(:), mcol(:), mrow(:)
        real(dp), allocatable, intent(out) :: kval(:), mval(:)
        integer :: j, k
        real(dp) :: kd, md
        allocate (kcol(n + 1), krow(3*n - 2), kval(3*n - 2))
        k = 0
        kcol(1) = 1
        do j = 1, n
            kd = 2.0_dp*stiff
            md = m + 2.0_dp*me/3.0_dp
            if (.not. fixed .and. (j == 1 .or. j == n)) then
                kd = stiff
                md = m + me/3.0_dp
            end if
            if (j > 1) call put(j - 1, -stiff)
            call put(j, kd)
            if (j < n) call put(j + 1, -stiff)
            kcol(j + 1) = k + 1
        end do
        mcol = kcol
        mrow = krow
        allocate (mval(size(kval)))
        do j = 1, n
            do k = kcol(j), kcol(j + 1) - 1
                if (krow(k) == j) then
                    mval(k) = m + 2.0_dp*me/3.0_dp
                    if (.not. fixed .and. (j == 1 .or. j == n)) mval(k) = m + me/3.0_dp
                else
                    mval(k) = me/6.0_dp
                end if
            end do
        end do
    contains
        subroutine put(row, value)
            integer, intent(in) :: row
            real(dp), intent(in) :: value
            k = k + 1
            krow(k) = row
            kval(k) = value
        end subroutine put
    end subroutine csc_chain

    subroutine test_sparse_chain(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 1000, nev = 8
        real(dp), parameter :: stiff = 5.0_dp, m = 0.7_dp, me = 0.4_dp
        integer, allocatable :: kcol(:), krow(:), mcol(:), mrow(:)
        real(dp), allocatable :: kval(:), mval(:), values(:), vectors(:, :)
        real(dp) :: exact(nev), th, kp(n), mp(n), res, orth
        type(eigen_report_t) :: report
        type(error_type), allocatable :: error
        integer :: i, j
        call csc_chain(n, .true., stiff, m, me, kcol, krow, kval, mcol, mrow, mval)
        call sparse_eigenpairs(n, kcol, krow, kval, mcol, mrow, mval, nev, 0.0_dp, &
                               eigen_options_t(), values, vectors, report, error)
        call check(t, .not. allocated(error), "sparse_eigen: chain N = 1000, consistent mass")
        if (allocated(error)) then
            call check(t, .false., "sparse_eigen: chain error", error%message)
            return
        end if
        do j = 1, nev
            th = j*pi/(n + 1)
            exact(j) = stiff*(2.0_dp - 2.0_dp*cos(th))/(m + me/6.0_dp*(4.0_dp + 2.0_dp*cos(th)))
        end do
        call check_close(t, values, exact, "sparse_eigen: consistent-mass chain closed form", &
                         rtol=1.0e-10_dp)
        res = 0.0_dp
        orth = 0.0_dp
        do j = 1, nev
            call csc_matvec_lib(kcol, krow, kval, vectors(:, j), kp)
            call csc_matvec_lib(mcol, mrow, mval, vectors(:, j), mp)
            res = max(res, norm2(kp - values(j)*mp)/(4.0_dp*stiff*norm2(vectors(:, j))))
            do i = 1, nev
                call csc_matvec_lib(mcol, mrow, mval, vectors(:, i), mp)
                orth = max(orth, abs(dot_product(vectors(:, j), mp) - merge(1.0_dp, 0.0_dp, i == j)))
            end do
        end do
        call check_close(t, res, 0.0_dp, "sparse_eigen: residuals", atol=1.0e-10_dp)
        call check_close(t, orth, 0.0_dp, "sparse_eigen: M-orthonormal", atol=1.0e-10_dp)
    end subroutine test_sparse_chain

    subroutine test_free_chain(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 200, nev = 4
        real(dp), parameter :: stiff = 2.0_dp, m = 1.5_dp
        integer, allocatable :: kcol(:), krow(:), mcol(:), mrow(:)
        real(dp), allocatable :: kval(:), mval(:), values(:), vectors(:, :)
        type(eigen_report_t) :: report
        type(error_type), allocatable :: error
        integer :: j
        call csc_chain(n, .false., stiff, m, 0.0_dp, kcol, krow, kval, mcol, mrow, mval)
        call sparse_eigenpairs(n, kcol, krow, kval, mcol, mrow, mval, nev, 0.0_dp, &
                               eigen_options_t(), values, vectors, report, error)
        call check(t, allocated(error), "sparse_eigen: free chain at sigma = 0 is reported")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%numerical .and. &
                                         index(error%message, "singular") > 0 .and. &
                                         index(error%message, "sigma") > 0, &
                                         "sparse_eigen: ... as singular K - sigma M", error%message)
        call sparse_eigenpairs(n, kcol, krow, kval, mcol, mrow, mval, nev, -0.01_dp, &
                               eigen_options_t(), values, vectors, report, error)
        call check(t, .not. allocated(error), "sparse_eigen: free chain at sigma < 0")
        if (allocated(error)) return
        call check_close(t, values(1), 0.0_dp, "sparse_eigen: the rigid mode lambda = 0", &
                         atol=1.0e-12_dp)
        call check_close(t, values(2:), [(2.0_dp*stiff/m*(1.0_dp - cos(j*pi/n)), j=1, nev - 1)], &
                         "sparse_eigen: free chain lambda_j = 2k/m (1 - cos(j pi/N))", &
                         rtol=1.0e-10_dp)
        call check_close(t, maxval(vectors(:, 1)) - minval(vectors(:, 1)), 0.0_dp, &
                         "sparse_eigen: the rigid mode is a translation", atol=1.0e-10_dp)
    end subroutine test_free_chain

    !> Four uniform chains (stiffness 1..4) solved at once: each must give its closed form
    !> (the ARPACK calls are serialized inside smallest_eigenpairs).
    subroutine test_threads(t)
        type(test_counter_t), intent(inout) :: t
        real(dp) :: worst(4)
        integer :: i
        worst = huge(1.0_dp)
        !$omp parallel do num_threads(4) schedule(static, 1)
        do i = 1, 4
            call one_chain(real(i, dp), worst(i))
        end do
        !$omp end parallel do
        call check_close(t, maxval(worst), 0.0_dp, "arpack: four chains at once (OpenMP " &
                         //"build: four threads) give lambda_j to 1e-10", atol=1.0e-10_dp)
    end subroutine test_threads

    !> Largest relative error of the 4 smallest eigenvalues of a uniform chain of 120 unit
    !> masses with springs `stiff` (huge on failure).
    subroutine one_chain(stiff, worst)
        real(dp), intent(in) :: stiff
        real(dp), intent(out) :: worst
        integer, parameter :: n = 120, nev = 4
        real(dp), allocatable :: k(:, :), m(:, :), values(:), vectors(:, :)
        real(dp) :: exact(nev)
        type(sparse_op_t) :: op
        type(eigen_report_t) :: report
        type(error_type), allocatable :: error
        integer :: j
        worst = huge(1.0_dp)
        allocate (k(n, n), m(n, n))
        call chain(n, [(stiff, j=1, n + 1)], [(1.0_dp, j=1, n)], [(0.0_dp, j=1, n + 1)], k, m)
        call new_op(k, m, 0.0_dp, op, error)
        if (allocated(error)) return
        call smallest_eigenpairs(op, n, nev, 0.0_dp, eigen_options_t(), values, vectors, &
                                 report, error)
        call op%lu%release()
        if (allocated(error)) return
        exact = [(2.0_dp*stiff*(1.0_dp - cos(j*pi/(n + 1))), j=1, nev)]
        worst = maxval(abs(values - exact)/exact)
    end subroutine one_chain

    subroutine op_solve(self, x, y, stat)
        class(sparse_op_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: y(:)
        integer, intent(inout) :: stat
        type(error_type), allocatable :: error
        call self%lu%solve(x, y, error)
        if (allocated(error)) stat = 1
    end subroutine op_solve

    subroutine op_mass(self, x, y, stat)
        class(sparse_op_t), intent(inout) :: self
        real(dp), intent(in) :: x(:)
        real(dp), intent(out) :: y(:)
        integer, intent(inout) :: stat
        call csc_matvec(self%mcol, self%mrow, self%mval, x, y)
        self%products = self%products + 1
        if (self%stop_after > 0 .and. self%products >= self%stop_after) stat = 7
    end subroutine op_mass

    !> y = A x for A in 1-based compressed sparse column form.
    subroutine csc_matvec(colptr, rowind, values, x, y)
        integer, intent(in) :: colptr(:), rowind(:)
        real(dp), intent(in) :: values(:), x(:)
        real(dp), intent(out) :: y(:)
        integer :: j, k
        y = 0.0_dp
        do j = 1, size(colptr) - 1
            do k = colptr(j), colptr(j + 1) - 1
                y(rowind(k)) = y(rowind(k)) + values(k)*x(j)
            end do
        end do
    end subroutine csc_matvec

    !> Stiffness and consistent mass of a fixed-fixed chain of n masses and n + 1 springs:
    !> springs(e) joins mass e - 1 and e (mass 0 and n + 1 are the walls); lumped(i) on the
    !> diagonal of M plus consistent element masses me(e) (me/6 [2 1; 1 2]).
    subroutine chain(n, springs, lumped, me, k, m)
        integer, intent(in) :: n
        real(dp), intent(in) :: springs(n + 1), lumped(n), me(n + 1)
        real(dp), intent(out) :: k(n, n), m(n, n)
        integer :: e, i, j
        k = 0.0_dp
        m = 0.0_dp
        do i = 1, n
            m(i, i) = lumped(i)
        end do
        do e = 1, n + 1
            i = e - 1
            j = e
            if (i >= 1) then
                k(i, i) = k(i, i) + springs(e)
                m(i, i) = m(i, i) + me(e)/3.0_dp
            end if
            if (j <= n) then
                k(j, j) = k(j, j) + springs(e)
                m(j, j) = m(j, j) + me(e)/3.0_dp
            end if
            if (i >= 1 .and. j <= n) then
                k(i, j) = k(i, j) - springs(e)
                k(j, i) = k(j, i) - springs(e)
                m(i, j) = m(i, j) + me(e)/6.0_dp
                m(j, i) = m(j, i) + me(e)/6.0_dp
            end if
        end do
    end subroutine chain

    !> Build the operator for K - sigma M.
    subroutine new_op(k, m, sigma, op, error)
        real(dp), intent(in) :: k(:, :), m(:, :), sigma
        type(sparse_op_t), intent(out) :: op
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: values(:)
        call dense_to_csc(k - sigma*m, colptr, rowind, values)
        call op%lu%factorize(size(k, 1), colptr, rowind, values, error)
        if (allocated(error)) return
        call dense_to_csc(m, op%mcol, op%mrow, op%mval)
    end subroutine new_op

    subroutine test_uniform_chain(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 500, nev = 6
        real(dp), parameter :: mass = 2.0_dp, stiff = 3.0_dp
        real(dp), allocatable :: k(:, :), m(:, :), values(:), vectors(:, :), gram(:, :)
        real(dp) :: exact(nev), res, ek(n), em(n)
        type(sparse_op_t) :: op
        type(eigen_report_t) :: report
        type(error_type), allocatable :: error
        integer :: j
        allocate (k(n, n), m(n, n))
        call chain(n, [(stiff, j=1, n + 1)], [(mass, j=1, n)], [(0.0_dp, j=1, n + 1)], k, m)
        call new_op(k, m, 0.0_dp, op, error)
        call check(t, .not. allocated(error), "arpack: factorize the chain's K")
        if (allocated(error)) return
        call smallest_eigenpairs(op, n, nev, 0.0_dp, eigen_options_t(), values, vectors, &
                                 report, error)
        call check(t, .not. allocated(error), "arpack: chain N = 500 eigensolve succeeds")
        if (allocated(error)) then
            call check(t, .false., "arpack: chain error", error%message)
            return
        end if
        exact = [(2.0_dp*stiff/mass*(1.0_dp - cos(j*pi/(n + 1))), j=1, nev)]
        call check_close(t, values, exact, "arpack: chain lambda_j = 2k/m (1 - cos(j pi/(N+1)))", &
                         rtol=1.0e-10_dp)
        call check(t, report%converged >= nev, "arpack: report counts nev converged")
        gram = matmul(transpose(vectors), matmul(m, vectors))
        do j = 1, nev
            gram(j, j) = gram(j, j) - 1.0_dp
        end do
        call check_close(t, maxval(abs(gram)), 0.0_dp, "arpack: chain vectors M-orthonormal", &
                         atol=1.0e-10_dp)
        res = 0.0_dp
        do j = 1, nev
            call csc_matvec_dense(k, vectors(:, j), ek)
            call csc_matvec_dense(m, vectors(:, j), em)
            res = max(res, norm2(ek - values(j)*em)/(4.0_dp*stiff*norm2(vectors(:, j))))
        end do
        call check_close(t, res, 0.0_dp, "arpack: chain residual ||K phi - lambda M phi|| / " &
                         //"(||K|| ||phi||)", atol=1.0e-10_dp)
        call op%lu%release()
    end subroutine test_uniform_chain

    !> y = A x (dense; the reference products).
    subroutine csc_matvec_dense(a, x, y)
        real(dp), intent(in) :: a(:, :), x(:)
        real(dp), intent(out) :: y(:)
        y = matmul(a, x)
    end subroutine csc_matvec_dense

    subroutine test_against_dsygv(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 40, nev = 5
        real(dp) :: k(n, n), m(n, n), a(n, n), b(n, n), w(n), springs(n + 1), lumped(n), &
                    me(n + 1), work(20*n), sigma, dist(n), overlap
        real(dp), allocatable :: values(:), vectors(:, :)
        type(sparse_op_t) :: op
        type(eigen_report_t) :: report
        type(error_type), allocatable :: error
        integer :: info, j, idx(nev), i
        logical :: used(n)
        call random_number(springs)
        call random_number(lumped)
        call random_number(me)
        springs = 1.0_dp + springs
        lumped = 0.5_dp + lumped
        me = 0.2_dp*me
        call chain(n, springs, lumped, me, k, m)
        a = k
        b = m
        call dsygv(1, 'V', 'U', n, a, n, b, n, w, work, size(work), info)
        call check(t, info == 0, "arpack: reference dsygv info 0")
        ! shift 0: the nev smallest
        call new_op(k, m, 0.0_dp, op, error)
        call smallest_eigenpairs(op, n, nev, 0.0_dp, eigen_options_t(), values, vectors, &
                                 report, error)
        call check(t, .not. allocated(error), "arpack: random chain eigensolve succeeds")
        if (allocated(error)) return
        call check_close(t, values, w(1:nev), "arpack: nev smallest = dsygv", rtol=1.0e-10_dp)
        overlap = 0.0_dp
        do j = 1, nev
            overlap = max(overlap, abs(1.0_dp - abs(dot_product(vectors(:, j), &
                                                                  matmul(m, a(:, j))))))
        end do
        call check_close(t, overlap, 0.0_dp, "arpack: vectors = dsygv's up to sign " &
                         //"(|phi^T M psi| = 1)", atol=1.0e-8_dp)
        call op%lu%release()
        ! a shift inside the spectrum: the nev eigenvalues nearest sigma
        sigma = 0.5_dp*(w(10) + w(11)) + 0.1_dp*(w(11) - w(10))
        call new_op(k, m, sigma, op, error)
        call check(t, .not. allocated(error), "arpack: factorize K - sigma M (indefinite)")
        if (allocated(error)) return
        call smallest_eigenpairs(op, n, nev, sigma, eigen_options_t(tol=1.0e-13_dp), values, &
                                 vectors, report, error)
        call check(t, .not. allocated(error), "arpack: shifted eigensolve succeeds")
        if (allocated(error)) return
        dist = abs(w - sigma)
        used = .false.
        do j = 1, nev
            idx(j) = minloc(dist, 1, mask=.not. used)
            used(idx(j)) = .true.
        end do
        ! sort the nearest ones ascending
        do j = 2, nev
            do i = j, 2, -1
                if (w(idx(i - 1)) <= w(idx(i))) exit
                idx([i - 1, i]) = idx([i, i - 1])
            end do
        end do
        call check_close(t, values, w(idx), "arpack: the nev nearest sigma = dsygv's", &
                         rtol=1.0e-10_dp)
        call op%lu%release()
    end subroutine test_against_dsygv

    subroutine test_failures(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 30
        real(dp) :: k(n, n), m(n, n)
        real(dp), allocatable :: values(:), vectors(:, :)
        type(sparse_op_t) :: op
        type(eigen_report_t) :: report
        type(error_type), allocatable :: error
        integer :: j
        call chain(n, [(1.0_dp, j=1, n + 1)], [(1.0_dp, j=1, n)], [(0.0_dp, j=1, n + 1)], k, m)
        call new_op(k, m, 0.0_dp, op, error)
        call smallest_eigenpairs(op, n, n, 0.0_dp, eigen_options_t(), values, vectors, &
                                 report, error)
        call check(t, allocated(error), "arpack: nev = n is reported")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input .and. &
                                         index(error%message, "nev = 30") > 0, &
                                         "arpack: nev = n is input, named", error%message)
        call smallest_eigenpairs(op, n, 3, 0.0_dp, eigen_options_t(ncv=3), values, vectors, &
                                 report, error)
        call check(t, allocated(error), "arpack: ncv = nev is reported")
        op%stop_after = 3
        call smallest_eigenpairs(op, n, 3, 0.0_dp, eigen_options_t(), values, vectors, &
                                 report, error)
        call check(t, allocated(error), "arpack: an operator that stops is reported")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%callback, &
                                         "arpack: operator stop is a callback error", &
                                         error%message)
        ! a run after an aborted one starts afresh
        op%stop_after = 0
        call smallest_eigenpairs(op, n, 3, 0.0_dp, eigen_options_t(), values, vectors, &
                                 report, error)
        call check(t, .not. allocated(error), "arpack: a solve after an aborted one succeeds")
        if (.not. allocated(error)) call check_close(t, values, &
            [(2.0_dp*(1.0_dp - cos(j*pi/(n + 1))), j=1, 3)], &
            "arpack: ... and is right", rtol=1.0e-10_dp)
        call op%lu%release()
    end subroutine test_failures
end module test_arpack
