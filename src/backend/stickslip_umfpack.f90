!> The only module that talks to UMFPACK (SuiteSparse, system libumfpack): sparse LU
!> factorizations of real (`sparse_lu_t`) and complex (`sparse_zlu_t`) square matrices in
!> compressed sparse column form, factorized once and solved many times.
!>
!> Why UMFPACK and not MUMPS: UMFPACK's C API is a handful of functions with plain arrays
!> and an opaque handle, which binds by hand with `bind(C)` and no vendored header; MUMPS's
!> interface is one large control structure (`DMUMPS_STRUC_C`, hundreds of fields whose
!> layout changes between versions) that is fragile to mirror by hand, and its sequential
!> Debian build brings MPI stubs along. UMFPACK handles real and complex unsymmetric matrices
!> (Z_h = K - w^2 M + i w C is complex symmetric, not Hermitian) with a fill-reducing
!> ordering (AMD/COLAMD) and iterative refinement. The `umfpack_dl_*` / `umfpack_zl_*`
!> (64-bit index, `SuiteSparse_long` = C `long` on Linux) variants are used throughout; the
!> complex matrix and vectors are passed in UMFPACK's "packed complex" form (Az = NULL:
!> real and imaginary parts interleaved, which is exactly Fortran's `complex(c_double)`).
!>
!> Input convention (Fortran's): 1-based compressed sparse column. colptr(1) = 1,
!> colptr(j+1) - colptr(j) entries in column j, with their row numbers rowind(k) in 1..n
!> strictly ascending within a column (UMFPACK's requirement; no duplicates) and values(k).
!> The arrays are copied (0-based, 64-bit) into the factorization object, which needs the
!> matrix for the iterative refinement of each solve.
!>
!> Options (components set before `factorize`): `ordering` (ordering_amd, UMFPACK's default
!> and ours; ordering_cholmod: AMD, then METIS nested dissection when AMD's fill is high,
!> the better one kept; for the 3D solid meshes of FE models it halves the fill and the
!> factorization time: Rotor 37 blade interior, 61081 DOFs, 8.9 -> 5.2 s, 720 -> 510 MB of
!> factors) and `refinement_steps` (UMFPACK's iterative refinement, at most this many steps
!> per solve, default 2 as UMFPACK's; read at every solve). With refinement on, UMFPACK
!> computes the residual and the backward error of every solution even when no step is
!> taken: a solve with a well-conditioned SPD matrix (a shift-invert Lanczos step) costs 2.5x
!> one without (0.43 against 0.17 s on the blade), for the same bits when no step is taken.
!>
!> Memory: each object owns an UMFPACK Symbolic and Numeric object (C heap). Call
!> `release()` when done (a new `factorize` releases the previous one); do not copy a
!> factorized object by assignment (both copies would own the same handles): hand it over
!> with `move_to`. No module state: different objects may be used from different threads at
!> once; one object is not for concurrent use.
module stickslip_umfpack
    use, intrinsic :: iso_c_binding, only: c_long, c_double, c_double_complex, c_ptr, &
        c_null_ptr, c_associated
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_sparse_factor, only: sparse_factor_t, check_pattern
    implicit none
    private
    public :: sparse_lu_t, sparse_zlu_t, umfpack_status_text
    public :: ordering_amd, ordering_cholmod, ordering_metis

    !> Sizes of UMFPACK's Control and Info arrays (umfpack.h).
    integer, parameter :: n_control = 20, n_info = 90
    !> Info index (0-based in C) of the reciprocal condition number estimate.
    integer, parameter :: info_rcond = 67
    !> Control indices (0-based in C): the ordering, the iterative refinement steps.
    integer, parameter :: control_ordering = 10, control_irstep = 7
    !> Info indices (0-based in C): entries of L and U.
    integer, parameter :: info_lnz = 43, info_unz = 44
    !> Fill-reducing orderings (UMFPACK_ORDERING_*): AMD (UMFPACK's default), CHOLMOD's
    !> choice (AMD, then METIS when the fill is high; the better kept), METIS.
    integer, parameter :: ordering_amd = 1, ordering_cholmod = 0, ordering_metis = 3
    !> System to solve: A x = b.
    integer(c_long), parameter :: umfpack_a = 0_c_long
    !> Status codes (umfpack.h).
    integer(c_long), parameter :: umfpack_ok = 0_c_long, &
                                  warning_singular = 1_c_long

    !> Sparse LU factorization of a real square matrix (UMFPACK, umfpack_dl_*); n and
    !> factor_entries (entries of L and U) come from sparse_factor_t.
    type, extends(sparse_factor_t) :: sparse_lu_t
        !> UMFPACK's estimate of the reciprocal condition number, min|U_ii| / max|U_ii| of the
        !> scaled factors (a cheap, rough indicator; relative to the matrix's own scale).
        real(dp) :: rcond = 0.0_dp
        !> Fill-reducing ordering of the next `factorize` (ordering_amd, ordering_cholmod,
        !> ordering_metis).
        integer :: ordering = ordering_amd
        !> Most iterative refinement steps of a solve (0: none; UMFPACK's default 2).
        integer :: refinement_steps = 2
        integer(c_long), allocatable, private :: ap(:), ai(:)
        real(c_double), allocatable, private :: ax(:)
        real(c_double), private :: control(n_control) = 0.0_c_double
        type(c_ptr), private :: symbolic = c_null_ptr
        type(c_ptr), private :: numeric = c_null_ptr
    contains
        !> Analyse and factorize a matrix: `factorize(n, colptr, rowind, values, error)`.
        procedure :: factorize => lu_factorize
        !> Factorize new values on the pattern of the last `factorize` (the ordering and
        !> symbolic analysis are reused): `refactorize(values, error)`.
        procedure :: refactorize => lu_refactorize
        !> Solve A x = b (`solve(b, x, error)`, b(:) or b(:, :)).
        procedure :: solve_one => lu_solve_one
        procedure :: solve_many => lu_solve_many
        !> Free the UMFPACK objects and the stored matrix (safe to call twice).
        procedure :: release => lu_release
        !> Whether a factorization is held.
        procedure :: factorized => lu_factorized
        !> 'LU'.
        procedure :: name => lu_name
        !> Hand the factorization and options over to another object (`move_to(other)`),
        !> leaving this one empty.
        procedure :: move_to => lu_move_to
    end type sparse_lu_t

    !> Sparse LU factorization of a complex square matrix (UMFPACK, umfpack_zl_*), for example
    !> the dynamic stiffness Z_h = K - w^2 M + i w C.
    type :: sparse_zlu_t
        !> Order of the matrix (0: nothing factorized).
        integer :: n = 0
        !> UMFPACK's estimate of the reciprocal condition number (see sparse_lu_t).
        real(dp) :: rcond = 0.0_dp
        !> Fill-reducing ordering of the next `factorize` (see sparse_lu_t).
        integer :: ordering = ordering_amd
        !> Most iterative refinement steps of a solve (see sparse_lu_t).
        integer :: refinement_steps = 2
        !> Entries of the factors L and U of the last factorization.
        real(dp) :: factor_entries = 0.0_dp
        integer(c_long), allocatable, private :: ap(:), ai(:)
        complex(c_double_complex), allocatable, private :: ax(:)
        real(c_double), private :: control(n_control) = 0.0_c_double
        type(c_ptr), private :: symbolic = c_null_ptr
        type(c_ptr), private :: numeric = c_null_ptr
    contains
        !> Analyse and factorize a matrix: `factorize(n, colptr, rowind, values, error)`.
        procedure :: factorize => zlu_factorize
        !> Factorize new values on the pattern of the last `factorize`.
        procedure :: refactorize => zlu_refactorize
        procedure, private :: zlu_solve_one, zlu_solve_many
        !> Solve A x = b for one (`b(:)`) or several (`b(:, :)`) right-hand sides.
        generic :: solve => zlu_solve_one, zlu_solve_many
        !> Free the UMFPACK objects and the stored matrix (safe to call twice).
        procedure :: release => zlu_release
        !> Whether a factorization is held.
        procedure :: factorized => zlu_factorized
        !> Whether a symbolic analysis (the ordering of a pattern) is held.
        procedure :: analysed => zlu_analysed
        !> Free the numeric factorization only; the analysis stays for `refactorize`.
        procedure :: release_numeric => zlu_release_numeric
    end type sparse_zlu_t

    interface
        !> void umfpack_dl_defaults(double Control[UMFPACK_CONTROL])
        subroutine umfpack_dl_defaults(control) bind(C, name="umfpack_dl_defaults")
            import :: c_double
            real(c_double), intent(out) :: control(*)
        end subroutine umfpack_dl_defaults

        !> SuiteSparse_long umfpack_dl_symbolic(n_row, n_col, Ap, Ai, Ax, &Symbolic, Control, Info)
        function umfpack_dl_symbolic(n_row, n_col, ap, ai, ax, symbolic, control, info) &
            result(status) bind(C, name="umfpack_dl_symbolic")
            import :: c_long, c_double, c_ptr
            integer(c_long), value :: n_row, n_col
            integer(c_long), intent(in) :: ap(*), ai(*)
            real(c_double), intent(in) :: ax(*)
            type(c_ptr), intent(out) :: symbolic
            real(c_double), intent(in) :: control(*)
            real(c_double), intent(out) :: info(*)
            integer(c_long) :: status
        end function umfpack_dl_symbolic

        !> SuiteSparse_long umfpack_dl_numeric(Ap, Ai, Ax, Symbolic, &Numeric, Control, Info)
        function umfpack_dl_numeric(ap, ai, ax, symbolic, numeric, control, info) &
            result(status) bind(C, name="umfpack_dl_numeric")
            import :: c_long, c_double, c_ptr
            integer(c_long), intent(in) :: ap(*), ai(*)
            real(c_double), intent(in) :: ax(*)
            type(c_ptr), value :: symbolic
            type(c_ptr), intent(out) :: numeric
            real(c_double), intent(in) :: control(*)
            real(c_double), intent(out) :: info(*)
            integer(c_long) :: status
        end function umfpack_dl_numeric

        !> SuiteSparse_long umfpack_dl_solve(sys, Ap, Ai, Ax, X, B, Numeric, Control, Info)
        function umfpack_dl_solve(sys, ap, ai, ax, x, b, numeric, control, info) &
            result(status) bind(C, name="umfpack_dl_solve")
            import :: c_long, c_double, c_ptr
            integer(c_long), value :: sys
            integer(c_long), intent(in) :: ap(*), ai(*)
            real(c_double), intent(in) :: ax(*)
            real(c_double), intent(out) :: x(*)
            real(c_double), intent(in) :: b(*)
            type(c_ptr), value :: numeric
            real(c_double), intent(in) :: control(*)
            real(c_double), intent(out) :: info(*)
            integer(c_long) :: status
        end function umfpack_dl_solve

        !> void umfpack_dl_free_symbolic(void **Symbolic)
        subroutine umfpack_dl_free_symbolic(symbolic) bind(C, name="umfpack_dl_free_symbolic")
            import :: c_ptr
            type(c_ptr), intent(inout) :: symbolic
        end subroutine umfpack_dl_free_symbolic

        !> void umfpack_dl_free_numeric(void **Numeric)
        subroutine umfpack_dl_free_numeric(numeric) bind(C, name="umfpack_dl_free_numeric")
            import :: c_ptr
            type(c_ptr), intent(inout) :: numeric
        end subroutine umfpack_dl_free_numeric

        !> void umfpack_zl_defaults(double Control[UMFPACK_CONTROL])
        subroutine umfpack_zl_defaults(control) bind(C, name="umfpack_zl_defaults")
            import :: c_double
            real(c_double), intent(out) :: control(*)
        end subroutine umfpack_zl_defaults

        !> umfpack_zl_symbolic(n_row, n_col, Ap, Ai, Ax, Az, &Symbolic, Control, Info), packed
        !> complex: Ax holds (re, im) pairs and Az = NULL.
        function umfpack_zl_symbolic(n_row, n_col, ap, ai, ax, az, symbolic, control, info) &
            result(status) bind(C, name="umfpack_zl_symbolic")
            import :: c_long, c_double, c_double_complex, c_ptr
            integer(c_long), value :: n_row, n_col
            integer(c_long), intent(in) :: ap(*), ai(*)
            complex(c_double_complex), intent(in) :: ax(*)
            type(c_ptr), value :: az
            type(c_ptr), intent(out) :: symbolic
            real(c_double), intent(in) :: control(*)
            real(c_double), intent(out) :: info(*)
            integer(c_long) :: status
        end function umfpack_zl_symbolic

        !> umfpack_zl_numeric(Ap, Ai, Ax, Az, Symbolic, &Numeric, Control, Info), packed complex.
        function umfpack_zl_numeric(ap, ai, ax, az, symbolic, numeric, control, info) &
            result(status) bind(C, name="umfpack_zl_numeric")
            import :: c_long, c_double, c_double_complex, c_ptr
            integer(c_long), intent(in) :: ap(*), ai(*)
            complex(c_double_complex), intent(in) :: ax(*)
            type(c_ptr), value :: az
            type(c_ptr), value :: symbolic
            type(c_ptr), intent(out) :: numeric
            real(c_double), intent(in) :: control(*)
            real(c_double), intent(out) :: info(*)
            integer(c_long) :: status
        end function umfpack_zl_numeric

        !> umfpack_zl_solve(sys, Ap, Ai, Ax, Az, Xx, Xz, Bx, Bz, Numeric, Control, Info),
        !> packed complex (Az = Xz = Bz = NULL).
        function umfpack_zl_solve(sys, ap, ai, ax, az, xx, xz, bx, bz, numeric, control, info) &
            result(status) bind(C, name="umfpack_zl_solve")
            import :: c_long, c_double, c_double_complex, c_ptr
            integer(c_long), value :: sys
            integer(c_long), intent(in) :: ap(*), ai(*)
            complex(c_double_complex), intent(in) :: ax(*)
            type(c_ptr), value :: az
            complex(c_double_complex), intent(out) :: xx(*)
            type(c_ptr), value :: xz
            complex(c_double_complex), intent(in) :: bx(*)
            type(c_ptr), value :: bz
            type(c_ptr), value :: numeric
            real(c_double), intent(in) :: control(*)
            real(c_double), intent(out) :: info(*)
            integer(c_long) :: status
        end function umfpack_zl_solve

        !> void umfpack_zl_free_symbolic(void **Symbolic)
        subroutine umfpack_zl_free_symbolic(symbolic) bind(C, name="umfpack_zl_free_symbolic")
            import :: c_ptr
            type(c_ptr), intent(inout) :: symbolic
        end subroutine umfpack_zl_free_symbolic

        !> void umfpack_zl_free_numeric(void **Numeric)
        subroutine umfpack_zl_free_numeric(numeric) bind(C, name="umfpack_zl_free_numeric")
            import :: c_ptr
            type(c_ptr), intent(inout) :: numeric
        end subroutine umfpack_zl_free_numeric
    end interface

contains

    !> A person's reading of an UMFPACK status code (umfpack.h), for error messages.
    pure function umfpack_status_text(status) result(text)
        !> UMFPACK status (Info[UMFPACK_STATUS] or a function's return value).
        integer, intent(in) :: status
        character(len=:), allocatable :: text
        select case (status)
        case (0)
            text = "ok"
        case (1)
            text = "the matrix is singular (a zero pivot in U)"
        case (2)
            text = "the determinant underflows"
        case (3)
            text = "the determinant overflows"
        case (-1)
            text = "out of memory"
        case (-3)
            text = "invalid Numeric object"
        case (-4)
            text = "invalid Symbolic object"
        case (-5)
            text = "a required argument is missing"
        case (-6)
            text = "the order n must be > 0"
        case (-8)
            text = "invalid matrix (column pointers or row indices out of order, out of range " &
                   //"or duplicated)"
        case (-11)
            text = "the pattern differs from the one analysed"
        case (-13)
            text = "invalid system to solve"
        case (-15)
            text = "invalid permutation"
        case (-17)
            text = "file I/O error"
        case (-18)
            text = "the fill-reducing ordering failed"
        case (-911)
            text = "internal error in UMFPACK"
        case default
            text = "unknown UMFPACK status"
        end select
        text = text//" (UMFPACK status "//itoa(status)//")"
    end function umfpack_status_text

    !> The first non-finite entry of a value array (0 if none).
    pure integer function first_nonfinite(re, im) result(k)
        real(dp), intent(in) :: re(:), im(:)
        do k = 1, size(re)
            if (.not. (ieee_is_finite(re(k)) .and. ieee_is_finite(im(k)))) return
        end do
        k = 0
    end function first_nonfinite

    ! ---------------------------------------------------------------- real

    !> Analyse and factorize the real n x n matrix A given in 1-based compressed sparse column
    !> form. Errors: a bad pattern or a non-finite value (input), a singular matrix or UMFPACK
    !> failure (numerical; the message gives UMFPACK's status). On error nothing is held.
    subroutine lu_factorize(self, n, colptr, rowind, values, error)
        !> The factorization (any previous one is released first).
        class(sparse_lu_t), intent(inout) :: self
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
        real(c_double) :: info(n_info)
        integer(c_long) :: status
        call self%release()
        call check_pattern("sparse LU", n, colptr, rowind, size(values), error)
        if (allocated(error)) return
        self%ap = int(colptr, c_long) - 1_c_long
        self%ai = int(rowind, c_long) - 1_c_long
        call umfpack_dl_defaults(self%control)
        self%control(control_ordering + 1) = real(self%ordering, c_double)
        status = umfpack_dl_symbolic(int(n, c_long), int(n, c_long), self%ap, self%ai, values, &
                                     self%symbolic, self%control, info)
        if (status /= umfpack_ok) then
            call fatal_error(error, "sparse LU: symbolic analysis failed: " &
                             //umfpack_status_text(int(status)), status_category(status))
            call self%release()
            return
        end if
        self%n = n
        call self%refactorize(values, error)
        if (allocated(error)) call self%release()
    end subroutine lu_factorize

    !> Factorize new values on the pattern given to the last `factorize` (same colptr and
    !> rowind; the fill-reducing ordering is reused). Errors: nothing analysed, wrong size,
    !> non-finite values (input); singular or UMFPACK failure (numerical: then no numeric
    !> factorization is held, the analysis is kept).
    subroutine lu_refactorize(self, values, error)
        !> The factorization.
        class(sparse_lu_t), intent(inout) :: self
        !> New values, in the order of the pattern's entries.
        real(dp), intent(in) :: values(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(c_double) :: info(n_info)
        integer(c_long) :: status
        integer :: k
        if (.not. c_associated(self%symbolic)) then
            call fatal_error(error, "sparse LU: refactorize called before factorize", &
                             stickslip_stat%input)
            return
        end if
        if (size(values) /= size(self%ai)) then
            call fatal_error(error, "sparse LU: size(values) = "//itoa(size(values)) &
                             //": must be the pattern's "//itoa(size(self%ai))//" entries", &
                             stickslip_stat%input)
            return
        end if
        k = first_nonfinite(values, values)
        if (k > 0) then
            call fatal_error(error, "sparse LU: values("//itoa(k)//") is not finite", &
                             stickslip_stat%input)
            return
        end if
        if (c_associated(self%numeric)) call umfpack_dl_free_numeric(self%numeric)
        self%numeric = c_null_ptr
        self%ax = values
        status = umfpack_dl_numeric(self%ap, self%ai, self%ax, self%symbolic, self%numeric, &
                                    self%control, info)
        self%rcond = info(info_rcond + 1)
        self%factor_entries = info(info_lnz + 1) + info(info_unz + 1)
        if (status /= umfpack_ok) then
            if (c_associated(self%numeric)) call umfpack_dl_free_numeric(self%numeric)
            self%numeric = c_null_ptr
            call fatal_error(error, "sparse LU of an order-"//itoa(self%n)//" matrix: " &
                             //umfpack_status_text(int(status)), status_category(status))
        end if
    end subroutine lu_refactorize

    !> Solve A x = b with the held factorization (with UMFPACK's iterative refinement).
    !> Errors: nothing factorized or wrong sizes (input), UMFPACK failure (numerical).
    subroutine lu_solve_one(self, b, x, error)
        !> The factorization.
        class(sparse_lu_t), intent(inout) :: self
        !> Right-hand side, size n.
        real(dp), intent(in) :: b(:)
        !> Solution, size n.
        real(dp), intent(out) :: x(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(c_double) :: info(n_info)
        integer(c_long) :: status
        if (.not. c_associated(self%numeric)) then
            call fatal_error(error, "sparse LU: solve called without a factorization", &
                             stickslip_stat%input)
            return
        end if
        if (size(b) /= self%n .or. size(x) /= self%n) then
            call fatal_error(error, "sparse LU: size(b) = "//itoa(size(b))//", size(x) = " &
                             //itoa(size(x))//": must be n = "//itoa(self%n), stickslip_stat%input)
            return
        end if
        self%control(control_irstep + 1) = real(max(self%refinement_steps, 0), c_double)
        status = umfpack_dl_solve(umfpack_a, self%ap, self%ai, self%ax, x, b, self%numeric, &
                                  self%control, info)
        if (status /= umfpack_ok) then
            call fatal_error(error, "sparse LU solve: "//umfpack_status_text(int(status)), &
                             status_category(status))
        end if
    end subroutine lu_solve_one

    !> Solve A X = B column by column (B and X are n x nrhs).
    subroutine lu_solve_many(self, b, x, error)
        !> The factorization.
        class(sparse_lu_t), intent(inout) :: self
        !> Right-hand sides, n x nrhs.
        real(dp), intent(in) :: b(:, :)
        !> Solutions, n x nrhs.
        real(dp), intent(out) :: x(:, :)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        integer :: j
        if (size(b, 2) /= size(x, 2)) then
            call fatal_error(error, "sparse LU: b has "//itoa(size(b, 2))//" columns, x " &
                             //itoa(size(x, 2)), stickslip_stat%input)
            return
        end if
        do j = 1, size(b, 2)
            call self%solve_one(b(:, j), x(:, j), error)
            if (allocated(error)) return
        end do
    end subroutine lu_solve_many

    !> Free the UMFPACK objects and the stored matrix.
    subroutine lu_release(self)
        !> The factorization.
        class(sparse_lu_t), intent(inout) :: self
        if (c_associated(self%numeric)) call umfpack_dl_free_numeric(self%numeric)
        if (c_associated(self%symbolic)) call umfpack_dl_free_symbolic(self%symbolic)
        self%numeric = c_null_ptr
        self%symbolic = c_null_ptr
        if (allocated(self%ap)) deallocate (self%ap)
        if (allocated(self%ai)) deallocate (self%ai)
        if (allocated(self%ax)) deallocate (self%ax)
        self%n = 0
        self%rcond = 0.0_dp
    end subroutine lu_release

    !> Whether a numeric factorization is held.
    logical function lu_factorized(self)
        !> The factorization.
        class(sparse_lu_t), intent(in) :: self
        lu_factorized = c_associated(self%numeric)
    end function lu_factorized

    !> 'LU', for reports.
    function lu_name(self) result(text)
        !> The factorization.
        class(sparse_lu_t), intent(in) :: self
        character(len=:), allocatable :: text
        text = 'LU'
    end function lu_name

    !> Hand the factorization (UMFPACK handles, the stored matrix) and the options over to
    !> `other` (whose own factorization is released first); `self` is left empty, with its
    !> options kept.
    subroutine lu_move_to(self, other)
        !> The factorization given away.
        class(sparse_lu_t), intent(inout) :: self
        !> The object that takes it.
        class(sparse_lu_t), intent(inout) :: other
        call other%release()
        other%n = self%n
        other%rcond = self%rcond
        other%ordering = self%ordering
        other%refinement_steps = self%refinement_steps
        other%factor_entries = self%factor_entries
        other%control = self%control
        other%symbolic = self%symbolic
        other%numeric = self%numeric
        if (allocated(self%ap)) call move_alloc(self%ap, other%ap)
        if (allocated(self%ai)) call move_alloc(self%ai, other%ai)
        if (allocated(self%ax)) call move_alloc(self%ax, other%ax)
        self%symbolic = c_null_ptr
        self%numeric = c_null_ptr
        self%n = 0
        self%rcond = 0.0_dp
        self%factor_entries = 0.0_dp
    end subroutine lu_move_to

    ! ------------------------------------------------------------- complex

    !> Analyse and factorize the complex n x n matrix A in 1-based compressed sparse column
    !> form (see sparse_lu_t%factorize; same errors).
    subroutine zlu_factorize(self, n, colptr, rowind, values, error)
        !> The factorization (any previous one is released first).
        class(sparse_zlu_t), intent(inout) :: self
        !> Order of A.
        integer, intent(in) :: n
        !> Column pointers, size n + 1, colptr(1) = 1.
        integer, intent(in) :: colptr(:)
        !> Row numbers (1..n, strictly ascending within each column).
        integer, intent(in) :: rowind(:)
        !> Values A(rowind(k), j) for k in colptr(j)..colptr(j+1)-1.
        complex(dp), intent(in) :: values(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(c_double) :: info(n_info)
        integer(c_long) :: status
        call self%release()
        call check_pattern("sparse complex LU", n, colptr, rowind, size(values), error)
        if (allocated(error)) return
        self%ap = int(colptr, c_long) - 1_c_long
        self%ai = int(rowind, c_long) - 1_c_long
        call umfpack_zl_defaults(self%control)
        self%control(control_ordering + 1) = real(self%ordering, c_double)
        status = umfpack_zl_symbolic(int(n, c_long), int(n, c_long), self%ap, self%ai, values, &
                                     c_null_ptr, self%symbolic, self%control, info)
        if (status /= umfpack_ok) then
            call fatal_error(error, "sparse complex LU: symbolic analysis failed: " &
                             //umfpack_status_text(int(status)), status_category(status))
            call self%release()
            return
        end if
        self%n = n
        call self%refactorize(values, error)
        if (allocated(error)) call self%release()
    end subroutine zlu_factorize

    !> Factorize new complex values on the pattern of the last `factorize` (for Z_h at a new
    !> frequency: the pattern of K, M, C merged once, the ordering reused).
    subroutine zlu_refactorize(self, values, error)
        !> The factorization.
        class(sparse_zlu_t), intent(inout) :: self
        !> New values, in the order of the pattern's entries.
        complex(dp), intent(in) :: values(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(c_double) :: info(n_info)
        integer(c_long) :: status
        integer :: k
        if (.not. c_associated(self%symbolic)) then
            call fatal_error(error, "sparse complex LU: refactorize called before factorize", &
                             stickslip_stat%input)
            return
        end if
        if (size(values) /= size(self%ai)) then
            call fatal_error(error, "sparse complex LU: size(values) = "//itoa(size(values)) &
                             //": must be the pattern's "//itoa(size(self%ai))//" entries", &
                             stickslip_stat%input)
            return
        end if
        k = first_nonfinite(real(values, dp), aimag(values))
        if (k > 0) then
            call fatal_error(error, "sparse complex LU: values("//itoa(k)//") is not finite", &
                             stickslip_stat%input)
            return
        end if
        if (c_associated(self%numeric)) call umfpack_zl_free_numeric(self%numeric)
        self%numeric = c_null_ptr
        self%ax = values
        status = umfpack_zl_numeric(self%ap, self%ai, self%ax, c_null_ptr, self%symbolic, &
                                    self%numeric, self%control, info)
        self%rcond = info(info_rcond + 1)
        self%factor_entries = info(info_lnz + 1) + info(info_unz + 1)
        if (status /= umfpack_ok) then
            if (c_associated(self%numeric)) call umfpack_zl_free_numeric(self%numeric)
            self%numeric = c_null_ptr
            call fatal_error(error, "sparse complex LU of an order-"//itoa(self%n)//" matrix: " &
                             //umfpack_status_text(int(status)), status_category(status))
        end if
    end subroutine zlu_refactorize

    !> Solve A x = b (complex) with the held factorization.
    subroutine zlu_solve_one(self, b, x, error)
        !> The factorization.
        class(sparse_zlu_t), intent(inout) :: self
        !> Right-hand side, size n.
        complex(dp), intent(in) :: b(:)
        !> Solution, size n.
        complex(dp), intent(out) :: x(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(c_double) :: info(n_info)
        integer(c_long) :: status
        if (.not. c_associated(self%numeric)) then
            call fatal_error(error, "sparse complex LU: solve called without a factorization", &
                             stickslip_stat%input)
            return
        end if
        if (size(b) /= self%n .or. size(x) /= self%n) then
            call fatal_error(error, "sparse complex LU: size(b) = "//itoa(size(b)) &
                             //", size(x) = "//itoa(size(x))//": must be n = "//itoa(self%n), &
                             stickslip_stat%input)
            return
        end if
        self%control(control_irstep + 1) = real(max(self%refinement_steps, 0), c_double)
        status = umfpack_zl_solve(umfpack_a, self%ap, self%ai, self%ax, c_null_ptr, x, &
                                  c_null_ptr, b, c_null_ptr, self%numeric, self%control, info)
        if (status /= umfpack_ok) then
            call fatal_error(error, "sparse complex LU solve: " &
                             //umfpack_status_text(int(status)), status_category(status))
        end if
    end subroutine zlu_solve_one

    !> Solve A X = B (complex) column by column (B and X are n x nrhs).
    subroutine zlu_solve_many(self, b, x, error)
        !> The factorization.
        class(sparse_zlu_t), intent(inout) :: self
        !> Right-hand sides, n x nrhs.
        complex(dp), intent(in) :: b(:, :)
        !> Solutions, n x nrhs.
        complex(dp), intent(out) :: x(:, :)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        integer :: j
        if (size(b, 2) /= size(x, 2)) then
            call fatal_error(error, "sparse complex LU: b has "//itoa(size(b, 2)) &
                             //" columns, x "//itoa(size(x, 2)), stickslip_stat%input)
            return
        end if
        do j = 1, size(b, 2)
            call self%zlu_solve_one(b(:, j), x(:, j), error)
            if (allocated(error)) return
        end do
    end subroutine zlu_solve_many

    !> Free the UMFPACK objects and the stored matrix.
    subroutine zlu_release(self)
        !> The factorization.
        class(sparse_zlu_t), intent(inout) :: self
        if (c_associated(self%numeric)) call umfpack_zl_free_numeric(self%numeric)
        if (c_associated(self%symbolic)) call umfpack_zl_free_symbolic(self%symbolic)
        self%numeric = c_null_ptr
        self%symbolic = c_null_ptr
        if (allocated(self%ap)) deallocate (self%ap)
        if (allocated(self%ai)) deallocate (self%ai)
        if (allocated(self%ax)) deallocate (self%ax)
        self%n = 0
        self%rcond = 0.0_dp
    end subroutine zlu_release

    !> Whether a symbolic analysis is held (`refactorize` can follow).
    logical function zlu_analysed(self)
        !> The factorization.
        class(sparse_zlu_t), intent(in) :: self
        zlu_analysed = c_associated(self%symbolic)
    end function zlu_analysed

    !> Free the numeric factorization (the factors' memory), keeping the symbolic analysis.
    subroutine zlu_release_numeric(self)
        !> The factorization.
        class(sparse_zlu_t), intent(inout) :: self
        if (c_associated(self%numeric)) call umfpack_zl_free_numeric(self%numeric)
        self%numeric = c_null_ptr
        self%rcond = 0.0_dp
    end subroutine zlu_release_numeric

    !> Whether a numeric factorization is held.
    logical function zlu_factorized(self)
        !> The factorization.
        class(sparse_zlu_t), intent(in) :: self
        zlu_factorized = c_associated(self%numeric)
    end function zlu_factorized

    !> Error category of an UMFPACK status: a bad matrix is input, a bug is internal, the
    !> rest (singular, out of memory) numerical.
    pure integer function status_category(status) result(stat)
        integer(c_long), intent(in) :: status
        select case (int(status))
        case (-8, -6)
            stat = stickslip_stat%input
        case (-911, -3, -4, -5, -13, -15)
            stat = stickslip_stat%internal
        case default
            stat = stickslip_stat%numerical
        end select
    end function status_category
end module stickslip_umfpack
