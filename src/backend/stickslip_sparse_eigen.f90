!> Eigenpairs of sparse K phi = lambda M phi: the shift-invert operator of stickslip_arpack
!> realized with a sparse factorization of K - sigma M (an LU, stickslip_umfpack, or one the
!> caller made, e.g. a Cholesky of K), plus the two compressed
!> sparse column helpers it needs (alpha A + beta B on the union pattern, y = A x), and
!> `sparse_eigenpairs_below`: every eigenpair below a limit in one Lanczos pass on one
!> factorization (the count estimated from a first run of 20; the next run asks only for the
!> missing ones, the found ones deflated: on the 61081-DOF interior of the Rotor 37 blade,
!> 49 modes, 189 -> 156 solves), for mode-count rules such as Craig-Bampton's. Why not
!> spectrum slicing (a new factorization of K - sigma M per slice, eigenvalues kept only
!> inside their slice): measured on a 10^4 and a 10^5-DOF plate (53
!> modes, three slices of 24) it was only about 10 % faster (2.5 against 2.8 s, 39 against
!> 44 s) with two more factorizations, and without the inertia of an LDL^T factorization
!> (UMFPACK's LU has none) a missed eigenvalue between slices cannot be ruled out; the cost
!> is in the solves with the LU (about 70 % of the time at 10^5 DOFs), which slicing does
!> not reduce.
!> Both drivers run the block Lanczos of stickslip_block_lanczos instead of ARPACK when the
!> factorization's block solves are cheap (`solves_blocks()`: CHOLMOD's supernodal
!> Cholesky), one run whose basis grows until the wanted pairs have converged (the blade's
!> 34 modes: 21 solves of 8 right-hand sides, 6-7 s, against ARPACK's 156 single solves in
!> 15.7 s); ARPACK again when that basis would exceed `block_basis` columns.
!>
!> Matrices are 1-based compressed sparse column (colptr(n+1), rowind, values) with row
!> numbers strictly ascending within each column, both triangles stored. The operator owns
!> its factorization and a copy of M: one per thread; `release()` frees the factorization.
module stickslip_sparse_eigen
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa, real_text
    use stickslip_umfpack, only: sparse_lu_t
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_arpack, only: shift_invert_operator_t, eigen_options_t, eigen_report_t, &
        smallest_eigenpairs
    use stickslip_block_lanczos, only: block_lanczos_report_t, block_lowest_eigenpairs, &
        estimated_count
    implicit none
    private
    public :: sparse_shift_invert_t, csc_combine, csc_matvec, sparse_eigenpairs, &
        sparse_eigenpairs_below, eigen_range_report_t

    !> Size of the first Lanczos run of `sparse_eigenpairs_below` (it measures the spectrum).
    integer, parameter :: first_batch = 20

    !> What `sparse_eigenpairs_below` did.
    type :: eigen_range_report_t
        !> Eigenvalues <= lambda_max found (all of them unless capped).
        integer :: below = 0
        !> max_count was reached with every value returned still <= lambda_max: there may be
        !> more below the limit than returned.
        logical :: capped = .false.
        !> With stop_above: the count below lambda_max estimated from the lowest eigenvalues
        !> (N(lambda) ~ lambda^p, no margin) when it exceeds max_count (then capped and only
        !> those lowest values are returned); 0 otherwise.
        integer :: estimated = 0
        !> Lanczos runs (ARPACK from its start) and sparse factorizations made.
        integer :: runs = 0
        integer :: factorizations = 0
        !> Applications of (K - sigma M)^-1 M over all runs, and the Lanczos restarts.
        integer :: op_applications = 0
        integer :: iterations = 0
        !> Block solves of the block Lanczos (0: ARPACK ran).
        integer :: block_solves = 0
    end type eigen_range_report_t

    !> (K - sigma M)^-1 by a sparse LU and M x by a compressed-column product.
    type, extends(shift_invert_operator_t) :: sparse_shift_invert_t
        !> The shift sigma the LU was made at.
        real(dp) :: sigma = 0.0_dp
        !> The factorization of K - sigma M (a sparse LU when made here).
        class(sparse_factor_t), allocatable :: fac
        integer, allocatable, private :: mcol(:), mrow(:)
        real(dp), allocatable, private :: mval(:)
        !> Known eigenvectors X (n x k, M-orthonormal) and M X: when allocated, every solve
        !> is followed by the M-orthogonal projection y - X (M X)^T y, so that Lanczos finds
        !> the eigenpairs of the complement (the next ones), not X again.
        real(dp), allocatable, private :: deflate(:, :), mdeflate(:, :)
    contains
        !> Factorize K - sigma M and keep M: `setup(n, kcol, krow, kval, mcol, mrow, mval,
        !> sigma, error)`.
        procedure :: setup => op_setup
        !> Take over a factorization of K - sigma M made by the caller and keep M:
        !> `adopt(lu, n, mcol, mrow, mval, sigma, error)`.
        procedure :: adopt => op_adopt
        procedure :: solve_shifted => op_solve
        procedure :: apply_mass => op_mass
        !> Free the factorization and the copy of M.
        procedure :: release => op_release
        !> Deflate known M-orthonormal eigenvectors x (n x k; k = 0: none): `deflate_with(x)`.
        procedure :: deflate_with => op_deflate_with
    end type sparse_shift_invert_t

contains

    !> C = alpha A + beta B for n-column compressed sparse column matrices, on the union of
    !> the patterns (an entry present in either is kept, even if the sum is zero, so that
    !> the pattern does not depend on alpha and beta). Row numbers ascending in, ascending out.
    pure subroutine csc_combine(n, acol, arow, aval, alpha, bcol, brow, bval, beta, ccol, &
                                crow, cval)
        !> Number of columns.
        integer, intent(in) :: n
        !> A: column pointers, row numbers, values.
        integer, intent(in) :: acol(:), arow(:)
        real(dp), intent(in) :: aval(:)
        !> Factor of A.
        real(dp), intent(in) :: alpha
        !> B: column pointers, row numbers, values.
        integer, intent(in) :: bcol(:), brow(:)
        real(dp), intent(in) :: bval(:)
        !> Factor of B.
        real(dp), intent(in) :: beta
        !> C: column pointers (n + 1), row numbers, values.
        integer, allocatable, intent(out) :: ccol(:), crow(:)
        real(dp), allocatable, intent(out) :: cval(:)
        integer :: j, ia, ib, k, pass, row
        real(dp) :: value
        allocate (ccol(n + 1))
        do pass = 1, 2
            k = 0
            ccol(1) = 1
            do j = 1, n
                ia = acol(j)
                ib = bcol(j)
                do while (ia < acol(j + 1) .or. ib < bcol(j + 1))
                    k = k + 1
                    if (ib >= bcol(j + 1)) then
                        row = arow(ia)
                        value = alpha*aval(ia)
                        ia = ia + 1
                    else if (ia >= acol(j + 1)) then
                        row = brow(ib)
                        value = beta*bval(ib)
                        ib = ib + 1
                    else if (arow(ia) < brow(ib)) then
                        row = arow(ia)
                        value = alpha*aval(ia)
                        ia = ia + 1
                    else if (brow(ib) < arow(ia)) then
                        row = brow(ib)
                        value = beta*bval(ib)
                        ib = ib + 1
                    else
                        row = arow(ia)
                        value = alpha*aval(ia) + beta*bval(ib)
                        ia = ia + 1
                        ib = ib + 1
                    end if
                    if (pass == 2) then
                        crow(k) = row
                        cval(k) = value
                    end if
                end do
                ccol(j + 1) = k + 1
            end do
            if (pass == 1) allocate (crow(k), cval(k))
        end do
    end subroutine csc_combine

    !> y = A x for A in compressed sparse column form (size(colptr) - 1 columns).
    pure subroutine csc_matvec(colptr, rowind, values, x, y)
        !> Column pointers.
        integer, intent(in) :: colptr(:)
        !> Row numbers.
        integer, intent(in) :: rowind(:)
        !> Values.
        real(dp), intent(in) :: values(:)
        !> The vector, one entry per column.
        real(dp), intent(in) :: x(:)
        !> The product, one entry per row.
        real(dp), intent(out) :: y(:)
        integer :: j, k
        y = 0.0_dp
        do j = 1, size(colptr) - 1
            do k = colptr(j), colptr(j + 1) - 1
                y(rowind(k)) = y(rowind(k)) + values(k)*x(j)
            end do
        end do
    end subroutine csc_matvec

    !> Factorize K - sigma M (sparse LU) and keep a copy of M. Errors: bad patterns (input),
    !> K - sigma M singular (numerical: sigma is an eigenvalue, or K has a rigid-body mode
    !> and sigma = 0; shift sigma below the spectrum).
    subroutine op_setup(self, n, kcol, krow, kval, mcol, mrow, mval, sigma, error)
        !> The operator.
        class(sparse_shift_invert_t), intent(inout) :: self
        !> Order of K and M.
        integer, intent(in) :: n
        !> K: column pointers, row numbers, values.
        integer, intent(in) :: kcol(:), krow(:)
        real(dp), intent(in) :: kval(:)
        !> M: column pointers, row numbers, values.
        integer, intent(in) :: mcol(:), mrow(:)
        real(dp), intent(in) :: mval(:)
        !> The shift [units of lambda].
        real(dp), intent(in) :: sigma
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: scol(:), srow(:)
        real(dp), allocatable :: sval(:)
        call self%release()
        if (size(kcol) /= n + 1) then
            call fatal_error(error, "sparse eigenproblem: K and M need n + 1 = "//itoa(n + 1) &
                             //" column pointers", stickslip_stat%input)
            return
        end if
        if (kcol(n + 1) - 1 /= size(krow) .or. size(krow) /= size(kval) .or. kcol(1) /= 1) then
            call fatal_error(error, "sparse eigenproblem: K: colptr, rowind and values " &
                             //"disagree", stickslip_stat%input)
            return
        end if
        call check_mass(n, mcol, mrow, mval, error)
        if (allocated(error)) return
        call csc_combine(n, kcol, krow, kval, 1.0_dp, mcol, mrow, mval, -sigma, scol, srow, sval)
        ! Lanczos needs no iterative refinement of its solves (2.5x their cost)
        if (.not. allocated(self%fac)) allocate (sparse_lu_t :: self%fac)
        select type (f => self%fac)
        type is (sparse_lu_t)
            f%refinement_steps = 0
        end select
        call self%fac%factorize(n, scol, srow, sval, error)
        if (allocated(error)) then
            error%message = "K - sigma M, sigma = "//real_text(sigma, '(es12.5)')//": "//error%message
            return
        end if
        call keep_mass(self, mcol, mrow, mval, sigma)
    end subroutine op_setup

    !> Errors (input) of M's compressed sparse column arrays for order n: not n + 1 column
    !> pointers, pointers, row numbers and values that disagree, a row outside 1..n.
    subroutine check_mass(n, mcol, mrow, mval, error)
        integer, intent(in) :: n, mcol(:), mrow(:)
        real(dp), intent(in) :: mval(:)
        type(error_type), allocatable, intent(out) :: error
        if (size(mcol) /= n + 1) then
            call fatal_error(error, "sparse eigenproblem: K and M need n + 1 = "//itoa(n + 1) &
                             //" column pointers", stickslip_stat%input)
        else if (mcol(n + 1) - 1 /= size(mrow) .or. size(mrow) /= size(mval) .or. &
                 mcol(1) /= 1) then
            call fatal_error(error, "sparse eigenproblem: M: colptr, rowind and values "// &
                             "disagree", stickslip_stat%input)
        else if (any(mrow < 1) .or. any(mrow > n)) then
            call fatal_error(error, "sparse eigenproblem: M has a row number outside 1.." &
                             //itoa(n), stickslip_stat%input)
        end if
    end subroutine check_mass

    !> The shift and a copy of M, once the operator holds its factorization.
    subroutine keep_mass(self, mcol, mrow, mval, sigma)
        class(sparse_shift_invert_t), intent(inout) :: self
        integer, intent(in) :: mcol(:), mrow(:)
        real(dp), intent(in) :: mval(:)
        real(dp), intent(in) :: sigma
        self%sigma = sigma
        self%mcol = mcol
        self%mrow = mrow
        self%mval = mval
    end subroutine keep_mass

    !> Take over `lu`, a factorization of K - sigma M of order n made by the caller (it is
    !> left unallocated: give it back with `move_alloc(self%fac, lu)`), and keep a copy of
    !> M. Errors (input): `lu` holds no factorization of order n, M's arrays disagree.
    subroutine op_adopt(self, lu, n, mcol, mrow, mval, sigma, error)
        !> The operator.
        class(sparse_shift_invert_t), intent(inout) :: self
        !> The factorization of K - sigma M (moved into the operator).
        class(sparse_factor_t), allocatable, intent(inout) :: lu
        !> Order of K and M.
        integer, intent(in) :: n
        !> M: column pointers, row numbers, values.
        integer, intent(in) :: mcol(:), mrow(:)
        real(dp), intent(in) :: mval(:)
        !> The shift the factorization was made at [units of lambda].
        real(dp), intent(in) :: sigma
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        call self%release()
        if (.not. allocated(lu)) then
            call fatal_error(error, "sparse eigenproblem: no factorization given", &
                             stickslip_stat%input)
            return
        end if
        if (.not. lu%factorized() .or. lu%n /= n) then
            call fatal_error(error, "sparse eigenproblem: the factorization given is not "// &
                             "one of order "//itoa(n), stickslip_stat%input)
            return
        end if
        call check_mass(n, mcol, mrow, mval, error)
        if (allocated(error)) return
        if (allocated(self%fac)) deallocate (self%fac)
        call move_alloc(lu, self%fac)
        call keep_mass(self, mcol, mrow, mval, sigma)
    end subroutine op_adopt

    !> y = (K - sigma M)^-1 x.
    subroutine op_solve(self, x, y, stat)
        !> The operator.
        class(sparse_shift_invert_t), intent(inout) :: self
        !> Input vector.
        real(dp), intent(in) :: x(:)
        !> Result.
        real(dp), intent(out) :: y(:)
        !> Set to 1 if the solve fails.
        integer, intent(inout) :: stat
        type(error_type), allocatable :: error
        call self%fac%solve(x, y, error)
        if (allocated(error)) stat = 1
        if (allocated(self%deflate)) then
            if (size(self%deflate, 2) > 0) y = y - matmul(self%deflate, matmul(y, self%mdeflate))
        end if
    end subroutine op_solve

    !> From now on, project the known M-orthonormal eigenvectors x (n x k) out of every
    !> solve (k = 0: no deflation).
    subroutine op_deflate_with(self, x)
        !> The operator.
        class(sparse_shift_invert_t), intent(inout) :: self
        !> The known eigenvectors, n x k.
        real(dp), intent(in) :: x(:, :)
        integer :: j
        self%deflate = x
        if (allocated(self%mdeflate)) deallocate (self%mdeflate)
        allocate (self%mdeflate(size(x, 1), size(x, 2)))
        do j = 1, size(x, 2)
            call csc_matvec(self%mcol, self%mrow, self%mval, x(:, j), self%mdeflate(:, j))
        end do
    end subroutine op_deflate_with

    !> y = M x.
    subroutine op_mass(self, x, y, stat)
        !> The operator.
        class(sparse_shift_invert_t), intent(inout) :: self
        !> Input vector.
        real(dp), intent(in) :: x(:)
        !> Result.
        real(dp), intent(out) :: y(:)
        !> Unchanged (the product cannot fail).
        integer, intent(inout) :: stat
        call csc_matvec(self%mcol, self%mrow, self%mval, x, y)
    end subroutine op_mass

    !> Free the factorization and the copy of M.
    subroutine op_release(self)
        !> The operator.
        class(sparse_shift_invert_t), intent(inout) :: self
        if (allocated(self%fac)) call self%fac%release()
        if (allocated(self%mcol)) deallocate (self%mcol)
        if (allocated(self%mrow)) deallocate (self%mrow)
        if (allocated(self%mval)) deallocate (self%mval)
        if (allocated(self%deflate)) deallocate (self%deflate)
        if (allocated(self%mdeflate)) deallocate (self%mdeflate)
    end subroutine op_release

    !> The nev eigenpairs of sparse K phi = lambda M phi nearest sigma (the nev smallest when
    !> sigma lies below the spectrum), ascending, M-orthonormal: K - sigma M factorized once
    !> with UMFPACK, then shift-invert Lanczos (ARPACK). Errors as `op%setup` and
    !> `smallest_eigenpairs`; not for concurrent use without OpenMP (ARPACK).
    !> With `factorization` as for `sparse_eigenpairs_below`: a given LU of K - sigma M is
    !> used (and kept by the caller), an empty one receives the LU made here.
    subroutine sparse_eigenpairs(n, kcol, krow, kval, mcol, mrow, mval, nev, sigma, opts, &
                                 values, vectors, report, error, factorization)
        !> Order of K and M.
        integer, intent(in) :: n
        !> K: column pointers, row numbers, values (1-based, both triangles).
        integer, intent(in) :: kcol(:), krow(:)
        real(dp), intent(in) :: kval(:)
        !> M: column pointers, row numbers, values (1-based, both triangles).
        integer, intent(in) :: mcol(:), mrow(:)
        real(dp), intent(in) :: mval(:)
        !> Number of eigenpairs, 1 <= nev < n.
        integer, intent(in) :: nev
        !> The shift [units of lambda]; 0 for a structure fixed against rigid-body motion.
        real(dp), intent(in) :: sigma
        !> Lanczos options (`eigen_options_t()`: ARPACK's defaults).
        type(eigen_options_t), intent(in) :: opts
        !> Eigenvalues, ascending.
        real(dp), allocatable, intent(out) :: values(:)
        !> Eigenvectors (n x nev), M-orthonormal.
        real(dp), allocatable, intent(out) :: vectors(:, :)
        !> Counts of the Lanczos run.
        type(eigen_report_t), intent(out) :: report
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        !> A factorization of K - sigma M to use (kept by the caller), or an unallocated or
        !> empty one to receive the factorization made here.
        class(sparse_factor_t), allocatable, intent(inout), optional :: factorization
        type(sparse_shift_invert_t) :: op
        type(block_lanczos_report_t) :: brep
        integer :: made
        call shift_invert_operator(op, n, kcol, krow, kval, mcol, mrow, mval, sigma, &
                                   made, error, factorization)
        if (allocated(error)) return
        brep%basis_full = .true.
        if (op%fac%solves_blocks() .and. nev >= 1 .and. nev < n) then
            call block_lowest_eigenpairs(op%fac, n, mcol, mrow, mval, sigma, nev, &
                                         -huge(1.0_dp), nev, block_basis(n, nev), opts%tol, &
                                         values, vectors, brep, error)
            report%op_applications = brep%op_applications
            report%converged = brep%converged
            report%ncv = brep%basis
            report%block_solves = brep%block_solves
        end if
        if (brep%basis_full .and. .not. allocated(error)) then
            call smallest_eigenpairs(op, n, nev, sigma, opts, values, vectors, report, error)
            report%block_solves = 0
        end if
        if (present(factorization)) call move_alloc(op%fac, factorization)
        call op%release()
    end subroutine sparse_eigenpairs

    !> Every eigenpair of sparse K phi = lambda M phi with lambda <= lambda_max, ascending and
    !> M-orthonormal, for a spectrum above the shift sigma (sigma = 0 for a structure held
    !> against rigid-body motion): the m lowest, m > the count below lambda_max (at least
    !> one eigenvalue above the limit is returned, when n allows, so the caller sees where
    !> the spectrum goes on), m <= max_count (report%capped when the limit was not passed
    !> within max_count). K - sigma M is factorized once; a first Lanczos run of 20 pairs
    !> measures the spectrum, and when the limit lies above it the count below lambda_max is
    !> estimated from the growth of the eigenvalue count N(lambda) ~ lambda^p seen in that
    !> run (Weyl's law: p = d/2 for a d-dimensional continuum, 1/4 for beam bending; p is
    !> fitted, not assumed), and one run asks for that many with a margin (repeated with a
    !> new estimate if it fell short). Errors as `sparse_eigenpairs`; max_count < 1 (input).
    !> With `factorization` (a factorization of K - sigma M, e.g. the Cholesky of K_ii a
    !> Craig-Bampton reduction made for its constraint modes) no factorization is made, and
    !> the caller keeps it on return; given unallocated or empty, the one made here (an LU,
    !> or the empty object's kind with its options) is returned in it.
    subroutine sparse_eigenpairs_below(n, kcol, krow, kval, mcol, mrow, mval, lambda_max, &
                                       max_count, sigma, opts, values, vectors, report, error, &
                                       stop_above, factorization)
        !> Order of K and M (>= 2).
        integer, intent(in) :: n
        !> K: column pointers, row numbers, values (1-based, both triangles).
        integer, intent(in) :: kcol(:), krow(:)
        real(dp), intent(in) :: kval(:)
        !> M: column pointers, row numbers, values (1-based, both triangles).
        integer, intent(in) :: mcol(:), mrow(:)
        real(dp), intent(in) :: mval(:)
        !> The limit [units of lambda, e.g. rad^2/s^2 for lambda = w^2].
        real(dp), intent(in) :: lambda_max
        !> Most eigenpairs returned (>= 1).
        integer, intent(in) :: max_count
        !> A shift below the spectrum [units of lambda].
        real(dp), intent(in) :: sigma
        !> Lanczos options (ncv is ignored: every run sizes its own basis).
        type(eigen_options_t), intent(in) :: opts
        !> Eigenvalues, ascending.
        real(dp), allocatable, intent(out) :: values(:)
        !> Eigenvectors (n x size(values)), M-orthonormal.
        real(dp), allocatable, intent(out) :: vectors(:, :)
        !> Counts.
        type(eigen_range_report_t), intent(out) :: report
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        !> Stop after the first run when the count below lambda_max is estimated above
        !> max_count (report%estimated, report%capped), instead of computing max_count
        !> eigenpairs that cannot all be kept anyway.
        logical, intent(in), optional :: stop_above
        !> A factorization of K - sigma M to use (kept by the caller), or an unallocated or
        !> empty one to receive the factorization made here.
        class(sparse_factor_t), allocatable, intent(inout), optional :: factorization
        type(sparse_shift_invert_t) :: op
        type(eigen_report_t) :: rep
        type(eigen_options_t) :: o
        type(block_lanczos_report_t) :: brep
        integer :: nev, cap
        if (max_count < 1 .or. .not. (lambda_max == lambda_max)) then
            call fatal_error(error, "eigenpairs below a limit: max_count = "//itoa(max_count) &
                             //" must be >= 1 and lambda_max a number", stickslip_stat%input)
            return
        end if
        call shift_invert_operator(op, n, kcol, krow, kval, mcol, mrow, mval, sigma, &
                                   report%factorizations, error, factorization)
        if (allocated(error)) return
        cap = min(max_count, n - 1)
        if (op%fac%solves_blocks()) then
            ! block Lanczos on a factorization with cheap block solves; ARPACK when its basis
            ! would not fit
            call block_lowest_eigenpairs(op%fac, n, mcol, mrow, mval, sigma, 1, lambda_max, &
                                         cap, block_basis(n, cap), opts%tol, values, vectors, &
                                         brep, error, estimate_after=merge(first_batch, 0, &
                                                                           estimating()))
            report%op_applications = brep%op_applications
            report%block_solves = brep%block_solves
            if (allocated(error) .or. .not. brep%basis_full) then
                report%runs = 1
                call give_back()
                if (allocated(error)) return
                report%below = count(values <= lambda_max)
                report%estimated = brep%estimated
                report%capped = brep%capped .or. &
                                (values(size(values)) <= lambda_max .and. size(values) < n)
                return
            end if
        end if
        nev = min(first_batch, cap)
        o = opts
        o%ncv = 0
        do
            if (.not. allocated(values)) then
                call smallest_eigenpairs(op, n, nev, sigma, o, values, vectors, rep, error)
            else
                call more_eigenpairs()
            end if
            report%runs = report%runs + 1
            report%op_applications = report%op_applications + rep%op_applications
            report%iterations = report%iterations + rep%iterations
            if (allocated(error)) exit
            if (values(nev) > lambda_max .or. nev >= cap) exit
            if (present(stop_above)) then
                if (stop_above .and. report%runs == 1 .and. nev >= 2) then
                    ! the estimate without its margin: (count - 8) / 1.15
                    report%estimated = int((estimated_count(values, lambda_max) - 8)/1.15_dp)
                    if (report%estimated > max_count) then
                        report%capped = .true.
                        call give_back()
                        report%below = count(values <= lambda_max)
                        return
                    end if
                    report%estimated = 0
                end if
            end if
            nev = max(nev + 10, min(cap, estimated_count(values, lambda_max)))
            nev = min(nev, cap)
        end do
        call give_back()
        if (allocated(error)) return
        report%below = count(values <= lambda_max)
        report%capped = values(size(values)) <= lambda_max .and. size(values) < n
    contains
        !> nev eigenpairs in all, from the ones found (values, vectors): the run asks only for
        !> the missing ones, with the found ones deflated (their M-orthogonal complement),
        !> unless that complement is too small for the Lanczos basis (then all afresh).
        subroutine more_eigenpairs()
            real(dp), allocatable :: v2(:), x2(:, :), vall(:), xall(:, :)
            integer, allocatable :: perm(:)
            integer :: found, want, ncv, i, j
            found = size(values)
            want = nev - found
            ncv = min(n, max(2*want + 1, want + 20))
            if (want < 1 .or. ncv > n - found) then
                call op%deflate_with(vectors(:, 1:0))
                call smallest_eigenpairs(op, n, nev, sigma, o, values, vectors, rep, error)
                return
            end if
            call op%deflate_with(vectors)
            call smallest_eigenpairs(op, n, want, sigma, o, v2, x2, rep, error)
            call op%deflate_with(vectors(:, 1:0))
            if (allocated(error)) return
            ! merge, ascending (the new ones lie above the found ones, up to roundoff)
            vall = [values, v2]
            allocate (xall(n, nev), perm(nev))
            perm = [(i, i=1, nev)]
            do i = 2, nev
                j = i - 1
                do while (j >= 1)
                    if (vall(perm(j)) <= vall(perm(j + 1))) exit
                    perm([j, j + 1]) = perm([j + 1, j])
                    j = j - 1
                end do
            end do
            do i = 1, nev
                if (perm(i) <= found) then
                    xall(:, i) = vectors(:, perm(i))
                else
                    xall(:, i) = x2(:, perm(i) - found)
                end if
            end do
            values = vall(perm)
            call move_alloc(xall, vectors)
        end subroutine more_eigenpairs

        !> Whether stop_above asks for the count estimate.
        logical function estimating()
            estimating = .false.
            if (present(stop_above)) estimating = stop_above
        end function estimating

        !> The factorization back to the caller (when one was given), the operator freed.
        subroutine give_back()
            if (present(factorization)) call move_alloc(op%fac, factorization)
            call op%release()
        end subroutine give_back
    end subroutine sparse_eigenpairs_below

    !> The shift-invert operator (K - sigma M)^-1 M of the two Lanczos drivers: adopting a
    !> given factorization (used as it is), or factorizing here (into the empty
    !> `factorization` object when one is given: its kind and options; a sparse LU without
    !> iterative refinement otherwise). `made` returns 1 when a factorization was made here
    !> (else 0). Errors as op%setup and op%adopt.
    subroutine shift_invert_operator(op, n, kcol, krow, kval, mcol, mrow, mval, sigma, &
                                     made, error, factorization)
        !> The operator set up.
        type(sparse_shift_invert_t), intent(inout) :: op
        !> Order, K and M (CSC, 1-based, both triangles), the shift.
        integer, intent(in) :: n, kcol(:), krow(:), mcol(:), mrow(:)
        real(dp), intent(in) :: kval(:), mval(:), sigma
        !> Factorizations made here.
        integer, intent(out) :: made
        !> Error (last but one).
        type(error_type), allocatable, intent(out) :: error
        !> A factorization to adopt, or an empty one to factorize into.
        class(sparse_factor_t), allocatable, intent(inout), optional :: factorization
        made = 1
        if (present(factorization)) then
            if (allocated(factorization)) then
                if (factorization%factorized()) then
                    call op%adopt(factorization, n, mcol, mrow, mval, sigma, error)
                    made = 0
                    return
                end if
                call move_alloc(factorization, op%fac)
            end if
        end if
        call op%setup(n, kcol, krow, kval, mcol, mrow, mval, sigma, error)
    end subroutine shift_invert_operator

    !> The most basis columns a block Lanczos run for `count` eigenpairs of order n may use:
    !> ten times the count and 100 (the blade's 37 pairs took 176 columns, the 18 lowest of
    !> the 14^3 test lattice's clustered spectrum 216), within 32 million reals per basis (V
    !> and M V: 512 MB together), at least 64; at most n.
    pure integer function block_basis(n, count) result(cols)
        !> Order and number of eigenpairs wanted.
        integer, intent(in) :: n, count
        cols = min(n, 10*count + 100, max(64, 32000000/max(n, 1)))
    end function block_basis

end module stickslip_sparse_eigen
