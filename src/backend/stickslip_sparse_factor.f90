!> The interface of a sparse factorization of a real square matrix, made once and solved
!> many times: the sparse LU (`sparse_lu_t`, UMFPACK) and the sparse Cholesky
!> (`sparse_cholesky_t`, CHOLMOD) extend it. Code that only solves with a factorization
!> (the shift-invert Lanczos operator, the Craig-Bampton constraint modes and its error
!> estimate) holds a `class(sparse_factor_t)` and works with either; a factorization is
!> handed from one owner to the next with `move_alloc` on `class(sparse_factor_t),
!> allocatable` objects (never by assignment: both copies would own the same C handles).
module stickslip_sparse_factor
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    implicit none
    private
    public :: sparse_factor_t, check_pattern

    !> A sparse factorization of a real n x n matrix.
    type, abstract :: sparse_factor_t
        !> Order of the matrix (0: nothing factorized).
        integer :: n = 0
        !> Entries of the factors of the last factorization (L and U, or L).
        real(dp) :: factor_entries = 0.0_dp
    contains
        !> Analyse and factorize A given in 1-based compressed sparse column form:
        !> `factorize(n, colptr, rowind, values, error)`.
        procedure(factorize_interface), deferred :: factorize
        !> Solve A x = b for one right-hand side.
        procedure(solve_one_interface), deferred :: solve_one
        !> Solve A X = B for the columns of B (n x nrhs).
        procedure(solve_many_interface), deferred :: solve_many
        !> Solve A x = b for one (`b(:)`) or several (`b(:, :)`) right-hand sides.
        generic :: solve => solve_one, solve_many
        !> Free the factorization (safe to call twice).
        procedure(release_interface), deferred :: release
        !> Whether a factorization is held.
        procedure(factorized_interface), deferred :: factorized
        !> What the factorization is, for reports ('LU', 'Cholesky').
        procedure(name_interface), deferred :: name
        !> Whether a solve with many right-hand sides costs much less than that many solves
        !> (one pass over the factors for the block): .false. unless a kind says so.
        procedure :: solves_blocks => factor_solves_blocks
    end type sparse_factor_t

    abstract interface
        subroutine factorize_interface(self, n, colptr, rowind, values, error)
            import :: sparse_factor_t, dp, error_type
            class(sparse_factor_t), intent(inout) :: self
            integer, intent(in) :: n
            integer, intent(in) :: colptr(:), rowind(:)
            real(dp), intent(in) :: values(:)
            type(error_type), allocatable, intent(out) :: error
        end subroutine factorize_interface

        subroutine solve_one_interface(self, b, x, error)
            import :: sparse_factor_t, dp, error_type
            class(sparse_factor_t), intent(inout) :: self
            real(dp), intent(in) :: b(:)
            real(dp), intent(out) :: x(:)
            type(error_type), allocatable, intent(out) :: error
        end subroutine solve_one_interface

        subroutine solve_many_interface(self, b, x, error)
            import :: sparse_factor_t, dp, error_type
            class(sparse_factor_t), intent(inout) :: self
            real(dp), intent(in) :: b(:, :)
            real(dp), intent(out) :: x(:, :)
            type(error_type), allocatable, intent(out) :: error
        end subroutine solve_many_interface

        subroutine release_interface(self)
            import :: sparse_factor_t
            class(sparse_factor_t), intent(inout) :: self
        end subroutine release_interface

        logical function factorized_interface(self)
            import :: sparse_factor_t
            class(sparse_factor_t), intent(in) :: self
        end function factorized_interface

        function name_interface(self) result(text)
            import :: sparse_factor_t
            class(sparse_factor_t), intent(in) :: self
            character(len=:), allocatable :: text
        end function name_interface
    end interface

contains

    !> .false.: by default a block solve is taken to cost one solve per column.
    logical function factor_solves_blocks(self) result(cheap)
        !> The factorization.
        class(sparse_factor_t), intent(in) :: self
        cheap = .false.
    end function factor_solves_blocks

    !> Check a 1-based compressed sparse column pattern of an n x n matrix with nvalues values
    !> (errors, input, name `who`: n < 1, pointers that do not start at 1, decrease or disagree
    !> with the sizes, a row outside 1..n, rows not strictly ascending in a column).
    subroutine check_pattern(who, n, colptr, rowind, nvalues, error)
        character(len=*), intent(in) :: who
        integer, intent(in) :: n
        integer, intent(in) :: colptr(:), rowind(:)
        integer, intent(in) :: nvalues
        type(error_type), allocatable, intent(out) :: error
        integer :: j, k
        if (n < 1) then
            call fatal_error(error, who//": n = "//itoa(n)//": must be >= 1", stickslip_stat%input)
            return
        end if
        if (size(colptr) /= n + 1) then
            call fatal_error(error, who//": size(colptr) = "//itoa(size(colptr))//": must be n + 1 = " &
                             //itoa(n + 1), stickslip_stat%input)
            return
        end if
        if (colptr(1) /= 1) then
            call fatal_error(error, who//": colptr(1) = "//itoa(colptr(1))//": must be 1 (1-based " &
                             //"compressed sparse column)", stickslip_stat%input)
            return
        end if
        do j = 1, n
            if (colptr(j + 1) < colptr(j)) then
                call fatal_error(error, who//": colptr("//itoa(j + 1)//") < colptr("//itoa(j) &
                                 //"): column pointers must not decrease", stickslip_stat%input)
                return
            end if
        end do
        if (colptr(n + 1) - 1 /= size(rowind) .or. size(rowind) /= nvalues) then
            call fatal_error(error, who//": colptr(n+1) - 1 = "//itoa(colptr(n + 1) - 1) &
                             //", size(rowind) = "//itoa(size(rowind))//", size(values) = " &
                             //itoa(nvalues)//": must agree", stickslip_stat%input)
            return
        end if
        do j = 1, n
            do k = colptr(j), colptr(j + 1) - 1
                if (rowind(k) < 1 .or. rowind(k) > n) then
                    call fatal_error(error, who//": rowind("//itoa(k)//") = "//itoa(rowind(k)) &
                                     //" in column "//itoa(j)//": must be in 1.."//itoa(n), &
                                     stickslip_stat%input)
                    return
                end if
                if (k > colptr(j)) then
                    if (rowind(k) <= rowind(k - 1)) then
                        call fatal_error(error, who//": column "//itoa(j)//": row numbers must be " &
                                         //"strictly ascending (rowind("//itoa(k)//") = " &
                                         //itoa(rowind(k))//" after "//itoa(rowind(k - 1))//")", &
                                         stickslip_stat%input)
                        return
                    end if
                end if
            end do
        end do
    end subroutine check_pattern

end module stickslip_sparse_factor
