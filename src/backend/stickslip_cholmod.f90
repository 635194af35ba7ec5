!> The only module that talks to CHOLMOD (SuiteSparse, system libcholmod): the sparse
!> Cholesky factorization A = L L^T of a real symmetric positive definite matrix
!> (`sparse_cholesky_t`), factorized once and solved many times, for example the interior
!> stiffness K_ii of a Craig-Bampton reduction.
!>
!> Why beside UMFPACK's LU: for the SPD stiffness of a 3D solid FE model CHOLMOD's
!> supernodal factorization (dense BLAS blocks, half the entries of an LU) is several times
!> faster, and so are its solves, more so with many right-hand sides at once (one pass over
!> L for the whole block). Rotor 37 blade, 61,098 DOFs: factorization 1.9 s instead of 5.2 s
!> (UMFPACK, METIS), one solve 0.06 s instead of 0.14 s, 17 right-hand sides 0.21 s instead
!> of 2.4 s (doc/benchmarks.md).
!>
!> Binding by hand: the `cholmod_sparse`, `cholmod_dense` and `cholmod_factor` structs are
!> mirrored by `bind(C)` types (their layouts are public and have not changed since CHOLMOD
!> 1.0); the large `cholmod_common` is kept as an opaque buffer that `cholmod_start` fills
!> with its defaults. Two of its settings are changed: `print` = 0 (CHOLMOD must not write
!> to stdout) and `final_ll` = TRUE (a simplicial factorization is L L^T too, so that a
!> matrix that is not positive definite is refused rather than factorized as L D L^T
!> without pivoting). Their offsets are those of CHOLMOD 3 to 5; they are used only after
!> the defaults found at the known offsets of the struct's first fields match CHOLMOD's
!> (dbound, grow0, grow1, grow2, maxrank, supernodal_switch, supernodal, final_asis,
!> final_super, final_ll, print). Otherwise `factorize` returns an error (stat numerical)
!> and callers fall back to the LU. The 32-bit index interface (`cholmod_*`, CHOLMOD_INT)
!> is used: orders and entry counts of the models this program reduces fit.
!>
!> Input convention: 1-based compressed sparse column; only the upper triangle (row <=
!> column) is read, so full storage of a symmetric matrix or its upper half both work.
!>
!> Memory: each object owns a CHOLMOD common and factor (C heap). Call `release()` when done;
!> never copy a factorized object by assignment (hand it over with `move_alloc` on
!> `class(sparse_factor_t), allocatable`). No module state: different objects may be used
!> from different threads at once; one object is not for concurrent use.
module stickslip_cholmod
    use, intrinsic :: iso_c_binding, only: c_int, c_int64_t, c_size_t, c_double, c_ptr, &
        c_null_ptr, c_associated, c_loc, c_f_pointer
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_sparse_factor, only: sparse_factor_t, check_pattern
    implicit none
    private
    public :: sparse_cholesky_t

    !> CHOLMOD constants (cholmod_core.h, cholmod_cholesky.h).
    integer(c_int), parameter :: cholmod_int = 0, cholmod_double = 0, cholmod_real = 1, &
                                 cholmod_sys_a = 0
    !> Size of the buffer given to cholmod_start, in 8-byte words (CHOLMOD 3's common is 2664
    !> bytes; the buffer leaves room for later versions).
    integer, parameter :: common_words = 4096
    !> Right-hand sides per call of cholmod_solve in chol_solve_many.
    integer, parameter :: solve_chunk = 128

    !> cholmod_sparse.
    type, bind(C) :: c_sparse
        integer(c_size_t) :: nrow, ncol, nzmax
        type(c_ptr) :: p, i, nz, x, z
        integer(c_int) :: stype, itype, xtype, dtype, sorted, packed
    end type c_sparse

    !> cholmod_dense.
    type, bind(C) :: c_dense
        integer(c_size_t) :: nrow, ncol, nzmax, d
        type(c_ptr) :: x, z
        integer(c_int) :: xtype, dtype
    end type c_dense

    !> cholmod_factor.
    type, bind(C) :: c_factor
        integer(c_size_t) :: n, minor
        type(c_ptr) :: perm, colcount, iperm
        integer(c_size_t) :: nzmax
        type(c_ptr) :: p, i, x, z, nz, next, prev
        integer(c_size_t) :: nsuper, ssize, xsize, maxcsize, maxesize
        type(c_ptr) :: super, pi, px, s
        integer(c_int) :: ordering, is_ll, is_super, is_monotonic, itype, xtype, dtype, usegpu
    end type c_factor

    !> Sparse Cholesky factorization A = L L^T of a real SPD matrix (CHOLMOD, supernodal or
    !> simplicial as CHOLMOD chooses, its choice of fill-reducing ordering: AMD, and METIS
    !> when AMD's fill is high, the better one kept).
    type, extends(sparse_factor_t) :: sparse_cholesky_t
        !> Supernodal (.true.) or simplicial factor.
        logical :: supernodal = .false.
        integer(c_int64_t), pointer, private :: common(:) => null()
        type(c_ptr), private :: factor = c_null_ptr
    contains
        !> Analyse and factorize: `factorize(n, colptr, rowind, values, error)`.
        procedure :: factorize => chol_factorize
        !> Solve A x = b (`solve(b, x, error)`, b(:) or b(:, :): one pass for the block).
        procedure :: solve_one => chol_solve_one
        procedure :: solve_many => chol_solve_many
        !> Free the factor and CHOLMOD's workspace (safe to call twice).
        procedure :: release => chol_release
        !> Whether a factorization is held.
        procedure :: factorized => chol_factorized
        !> 'Cholesky'.
        procedure :: name => chol_name
        !> .true.: a supernodal solve passes over L once for the whole block.
        procedure :: solves_blocks => chol_solves_blocks
    end type sparse_cholesky_t

    interface
        !> int cholmod_start(cholmod_common *Common)
        integer(c_int) function cholmod_start(common) bind(C, name="cholmod_start")
            import :: c_int, c_ptr
            type(c_ptr), value :: common
        end function cholmod_start
        !> int cholmod_finish(cholmod_common *Common)
        integer(c_int) function cholmod_finish(common) bind(C, name="cholmod_finish")
            import :: c_int, c_ptr
            type(c_ptr), value :: common
        end function cholmod_finish
        !> cholmod_factor *cholmod_analyze(cholmod_sparse *A, cholmod_common *Common)
        type(c_ptr) function cholmod_analyze(a, common) bind(C, name="cholmod_analyze")
            import :: c_ptr
            type(c_ptr), value :: a, common
        end function cholmod_analyze
        !> int cholmod_factorize(cholmod_sparse *A, cholmod_factor *L, cholmod_common *Common)
        integer(c_int) function cholmod_factorize(a, l, common) bind(C, name="cholmod_factorize")
            import :: c_int, c_ptr
            type(c_ptr), value :: a, l, common
        end function cholmod_factorize
        !> cholmod_dense *cholmod_solve(int sys, cholmod_factor *L, cholmod_dense *B,
        !> cholmod_common *Common)
        type(c_ptr) function cholmod_solve(sys, l, b, common) bind(C, name="cholmod_solve")
            import :: c_int, c_ptr
            integer(c_int), value :: sys
            type(c_ptr), value :: l, b, common
        end function cholmod_solve
        !> int cholmod_free_factor(cholmod_factor **L, cholmod_common *Common)
        integer(c_int) function cholmod_free_factor(l, common) bind(C, name="cholmod_free_factor")
            import :: c_int, c_ptr
            type(c_ptr) :: l
            type(c_ptr), value :: common
        end function cholmod_free_factor
        !> int cholmod_free_dense(cholmod_dense **X, cholmod_common *Common)
        integer(c_int) function cholmod_free_dense(x, common) bind(C, name="cholmod_free_dense")
            import :: c_int, c_ptr
            type(c_ptr) :: x
            type(c_ptr), value :: common
        end function cholmod_free_dense
    end interface

contains

    !> Analyse and factorize the SPD n x n matrix A given in 1-based compressed sparse column
    !> form (its upper triangle is read). Errors: a bad pattern or a non-finite value
    !> (input); CHOLMOD not usable as bound here, out of memory, or A not positive definite
    !> (numerical: the message names the column where the factorization stopped). On error
    !> nothing is held.
    subroutine chol_factorize(self, n, colptr, rowind, values, error)
        !> The factorization (any previous one is released first).
        class(sparse_cholesky_t), intent(inout) :: self
        !> Order of A.
        integer, intent(in) :: n
        !> Column pointers, size n + 1, colptr(1) = 1.
        integer, intent(in) :: colptr(:)
        !> Row numbers (1..n, strictly ascending within each column).
        integer, intent(in) :: rowind(:)
        !> Values A(rowind(k), j) for k in colptr(j)..colptr(j+1)-1.
        real(dp), intent(in) :: values(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        integer(c_int), allocatable, target :: ap(:), ai(:)
        real(c_double), allocatable, target :: ax(:)
        type(c_sparse), target :: a
        type(c_factor), pointer :: f
        integer :: j, k, nup
        integer(c_int) :: ok

        call self%release()
        call check_pattern("sparse Cholesky", n, colptr, rowind, size(values), error)
        if (allocated(error)) return
        if (.not. all(ieee_is_finite(values))) then
            call fatal_error(error, "sparse Cholesky: a value is not finite", stickslip_stat%input)
            return
        end if
        ! the upper triangle, 0-based
        nup = 0
        do j = 1, n
            nup = nup + count(rowind(colptr(j):colptr(j + 1) - 1) <= j)
        end do
        allocate (ap(n + 1), ai(nup), ax(nup))
        nup = 0
        ap(1) = 0
        do j = 1, n
            do k = colptr(j), colptr(j + 1) - 1
                if (rowind(k) > j) exit
                nup = nup + 1
                ai(nup) = int(rowind(k) - 1, c_int)
                ax(nup) = values(k)
            end do
            ap(j + 1) = int(nup, c_int)
        end do

        allocate (self%common(common_words))
        self%common = 0_c_int64_t
        ok = cholmod_start(c_loc(self%common))
        if (ok == 0 .or. .not. set_common(self%common)) then
            call fatal_error(error, "sparse Cholesky: the CHOLMOD library does not have the "// &
                             "layout this program was written for", stickslip_stat%numerical)
            call self%release()
            return
        end if
        a = c_sparse(nrow=int(n, c_size_t), ncol=int(n, c_size_t), nzmax=int(nup, c_size_t), &
                     p=c_loc(ap), i=c_loc(ai), nz=c_null_ptr, x=c_loc(ax), z=c_null_ptr, &
                     stype=1_c_int, itype=cholmod_int, xtype=cholmod_real, &
                     dtype=cholmod_double, sorted=1_c_int, packed=1_c_int)
        self%factor = cholmod_analyze(c_loc(a), c_loc(self%common))
        if (.not. c_associated(self%factor)) then
            call fatal_error(error, "sparse Cholesky: the analysis failed (out of memory?)", &
                             stickslip_stat%numerical)
            call self%release()
            return
        end if
        ok = cholmod_factorize(c_loc(a), self%factor, c_loc(self%common))
        call c_f_pointer(self%factor, f)
        if (ok == 0 .or. f%minor < int(n, c_size_t)) then
            if (ok /= 0) then
                call fatal_error(error, "sparse Cholesky: the matrix is not positive "// &
                                 "definite (the factorization stopped at column "// &
                                 itoa(int(f%minor) + 1)//" of the ordered matrix)", &
                                 stickslip_stat%numerical)
            else
                call fatal_error(error, "sparse Cholesky: the factorization failed (out of "// &
                                 "memory?)", stickslip_stat%numerical)
            end if
            call self%release()
            return
        end if
        self%n = n
        self%supernodal = f%is_super /= 0
        if (self%supernodal) then
            self%factor_entries = real(f%xsize, dp)
        else
            self%factor_entries = real(f%nzmax, dp)
        end if
    end subroutine chol_factorize

    !> Check the defaults cholmod_start wrote at the offsets this module knows, then set print
    !> = 0 and final_ll = TRUE there. .false. (nothing changed) when a default differs.
    logical function set_common(common) result(ok)
        integer(c_int64_t), intent(inout) :: common(:)
        integer(c_int) :: pair(2)
        real(dp), parameter :: tol = 1.0e-12_dp
        ok = .false.
        ! dbound 0, grow0 1.2, grow1 1.2 (doubles at bytes 0, 8, 16), grow2 5, maxrank 8
        ! (size_t at 24, 32), supernodal_switch 40 (double at 40)
        if (abs(transfer(common(1), 1.0_dp)) > tol) return
        if (abs(transfer(common(2), 1.0_dp) - 1.2_dp) > tol) return
        if (abs(transfer(common(3), 1.0_dp) - 1.2_dp) > tol) return
        if (common(4) /= 5_c_int64_t .or. common(5) /= 8_c_int64_t) return
        if (abs(transfer(common(6), 1.0_dp) - 40.0_dp) > tol) return
        ! supernodal = CHOLMOD_AUTO (1), final_asis = TRUE (ints at 48, 52)
        pair = transfer(common(7), pair)
        if (pair(1) /= 1 .or. pair(2) /= 1) return
        ! final_super = TRUE, final_ll = FALSE (ints at 56, 60)
        pair = transfer(common(8), pair)
        if (pair(1) /= 1 .or. pair(2) /= 0) return
        pair(2) = 1
        common(8) = transfer(pair, common(8))
        ! print = 3 (int at 144)
        pair = transfer(common(19), pair)
        if (pair(1) /= 3) return
        pair(1) = 0
        common(19) = transfer(pair, common(19))
        ok = .true.
    end function set_common

    !> Solve A x = b with the held factor. Errors: nothing factorized or wrong sizes (input),
    !> CHOLMOD failure (numerical).
    subroutine chol_solve_one(self, b, x, error)
        !> The factorization.
        class(sparse_cholesky_t), intent(inout) :: self
        !> Right-hand side, size n.
        real(dp), intent(in) :: b(:)
        !> Solution, size n.
        real(dp), intent(out) :: x(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: xx(:, :)
        if (size(x) /= size(b)) then
            call fatal_error(error, "sparse Cholesky: b has "//itoa(size(b))//" entries, x " &
                             //itoa(size(x)), stickslip_stat%input)
            return
        end if
        allocate (xx(size(b), 1))
        call self%solve_many(reshape(b, [size(b), 1]), xx, error)
        if (.not. allocated(error)) x = xx(:, 1)
    end subroutine chol_solve_one

    !> Solve A X = B for the columns of B (n x nrhs), solve_chunk columns a pass over the
    !> factor.
    subroutine chol_solve_many(self, b, x, error)
        !> The factorization.
        class(sparse_cholesky_t), intent(inout) :: self
        !> Right-hand sides, n x nrhs.
        real(dp), intent(in) :: b(:, :)
        !> Solutions, n x nrhs.
        real(dp), intent(out) :: x(:, :)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(c_double), allocatable, target :: bb(:, :)
        type(c_dense), target :: bd
        type(c_dense), pointer :: xd
        real(c_double), pointer :: xv(:, :)
        type(c_ptr) :: xp
        integer(c_int) :: ok
        if (.not. c_associated(self%factor)) then
            call fatal_error(error, "sparse Cholesky: solve called without a factorization", &
                             stickslip_stat%input)
            return
        end if
        if (size(b, 1) /= self%n .or. size(x, 1) /= self%n .or. size(b, 2) /= size(x, 2)) then
            call fatal_error(error, "sparse Cholesky: b is "//itoa(size(b, 1))//" x "// &
                             itoa(size(b, 2))//", x "//itoa(size(x, 1))//" x "// &
                             itoa(size(x, 2))//": must be n x nrhs, n = "//itoa(self%n), &
                             stickslip_stat%input)
            return
        end if
        if (size(b, 2) == 0) return
        block
            integer :: c0, nc
            ! in blocks of solve_chunk columns: CHOLMOD's supernodal solve of 1083
            ! right-hand sides at once took 12.5 s on a 33k-DOF sector, 4-5 s in blocks
            ! of 32 to 256 (a smaller working set per supernode, presumably)
            do c0 = 1, size(b, 2), solve_chunk
                nc = min(solve_chunk, size(b, 2) - c0 + 1)
                bb = b(:, c0:c0 + nc - 1)
                bd = c_dense(nrow=int(self%n, c_size_t), ncol=int(nc, c_size_t), &
                             nzmax=int(size(bb), c_size_t), d=int(self%n, c_size_t), &
                             x=c_loc(bb), z=c_null_ptr, xtype=cholmod_real, &
                             dtype=cholmod_double)
                xp = cholmod_solve(cholmod_sys_a, self%factor, c_loc(bd), c_loc(self%common))
                if (.not. c_associated(xp)) then
                    call fatal_error(error, "sparse Cholesky: the solve failed (out of "// &
                                     "memory?)", stickslip_stat%numerical)
                    return
                end if
                call c_f_pointer(xp, xd)
                call c_f_pointer(xd%x, xv, [int(xd%d), int(xd%ncol)])
                x(:, c0:c0 + nc - 1) = xv(1:self%n, :)
                ok = cholmod_free_dense(xp, c_loc(self%common))
            end do
        end block
    end subroutine chol_solve_many

    !> Free the factor and CHOLMOD's workspace.
    subroutine chol_release(self)
        !> The factorization.
        class(sparse_cholesky_t), intent(inout) :: self
        integer(c_int) :: ok
        if (associated(self%common)) then
            if (c_associated(self%factor)) ok = cholmod_free_factor(self%factor, &
                                                                    c_loc(self%common))
            ok = cholmod_finish(c_loc(self%common))
            deallocate (self%common)
        end if
        self%factor = c_null_ptr
        self%n = 0
        self%factor_entries = 0.0_dp
        self%supernodal = .false.
    end subroutine chol_release

    !> Whether a factor is held.
    logical function chol_factorized(self)
        !> The factorization.
        class(sparse_cholesky_t), intent(in) :: self
        chol_factorized = c_associated(self%factor)
    end function chol_factorized

    !> 'Cholesky', for reports (supernodal or simplicial).
    function chol_name(self) result(text)
        !> The factorization.
        class(sparse_cholesky_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = merge('supernodal Cholesky', 'Cholesky           ', self%supernodal)
        text = trim(text)
    end function chol_name

    !> Whether block solves are cheap: a supernodal factor is read once per block (dense
    !> BLAS on its supernodes; 17 right-hand sides cost about 3.5 single solves on the
    !> Rotor 37 blade's K_ii), a simplicial one column by column.
    logical function chol_solves_blocks(self) result(cheap)
        !> The factorization.
        class(sparse_cholesky_t), intent(in) :: self
        cheap = self%supernodal .and. c_associated(self%factor)
    end function chol_solves_blocks

end module stickslip_cholmod
