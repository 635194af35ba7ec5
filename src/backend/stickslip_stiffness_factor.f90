!> The factorization of a symmetric stiffness matrix for many solves (the interior
!> stiffness K_ii of a Craig-Bampton reduction and its error estimate): the sparse Cholesky
!> when the matrix is positive definite, the sparse LU otherwise.
module stickslip_stiffness_factor
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_cholmod, only: sparse_cholesky_t
    use stickslip_umfpack, only: sparse_lu_t, ordering_cholmod
    implicit none
    private
    public :: factorize_stiffness

contains

    !> Factorize the symmetric n x n matrix A (1-based compressed sparse column, both
    !> triangles) into `fac`: CHOLMOD's Cholesky, or, when that fails (A not positive
    !> definite, CHOLMOD unusable), UMFPACK's LU (CHOLMOD's choice of ordering, solves
    !> without iterative refinement). Errors: those of the LU (input: a bad pattern or value;
    !> numerical: A singular); on error `fac` holds nothing.
    subroutine factorize_stiffness(n, colptr, rowind, values, fac, error)
        !> Order of A.
        integer, intent(in) :: n
        !> Column pointers (n + 1), row numbers (ascending in each column), values.
        integer, intent(in) :: colptr(:), rowind(:)
        real(dp), intent(in) :: values(:)
        !> The factorization made (any previous one is released).
        class(sparse_factor_t), allocatable, intent(inout) :: fac
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        type(sparse_lu_t), allocatable :: lu
        if (allocated(fac)) then
            call fac%release()
            deallocate (fac)
        end if
        allocate (sparse_cholesky_t :: fac)
        call fac%factorize(n, colptr, rowind, values, error)
        if (.not. allocated(error)) return
        deallocate (error)
        deallocate (fac)
        allocate (lu)
        lu%ordering = ordering_cholmod
        lu%refinement_steps = 0
        call lu%factorize(n, colptr, rowind, values, error)
        call move_alloc(lu, fac)
    end subroutine factorize_stiffness

end module stickslip_stiffness_factor
