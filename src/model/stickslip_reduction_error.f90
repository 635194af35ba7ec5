!> The reduction error of a Craig-Bampton model (receptance_error): the contact receptance
!> G = W^T Z^-1 W with Z = K - w^2 M + i w C and W the contact directions (e_dof1 - e_dof2, or
!> any W nonzero on boundary DOFs only), of the reduced model against the full sparse model
!> (complex sparse LU, UMFPACK) at given frequencies:
!> max over the frequencies of max|G_r - G| / max|G|.
!> Re-exported by stickslip_reduction.
module stickslip_reduction_error
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa, real_text
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets
    use stickslip_umfpack, only: sparse_zlu_t, ordering_cholmod
    use stickslip_lapack, only: zgesv
    use stickslip_reduced_model, only: reduced_model_t, reduced_dof_of
    implicit none
    private
    public :: receptance_error

    !> The contact receptance error of a reduction (see receptance_error_directions), for
    !> contacts given by DOF pairs or by directions W.
    interface receptance_error
        module procedure receptance_error_dofs, receptance_error_directions
    end interface receptance_error

contains

    !> Reduction error for contacts given by DOFs: receptance_error with W column j
    !> e_dof1(j) - e_dof2(j) (dof2 = 0 the ground). Errors (input): a contact DOF that is not
    !> a boundary DOF, sizes; (numerical): Z singular at a frequency (named).
    subroutine receptance_error_dofs(kmat, mmat, reduced, dof1, dof2, frequencies, max_error, &
                                     error, cmat, frequency_errors)
        !> Full stiffness K.
        type(sparse_matrix_t), intent(in) :: kmat
        !> Full mass M.
        type(sparse_matrix_t), intent(in) :: mmat
        !> The reduced model of (K, M, C).
        type(reduced_model_t), intent(in) :: reduced
        !> Contact DOFs (1..n) and their second DOFs (0: ground), one per contact.
        integer, intent(in) :: dof1(:), dof2(:)
        !> Frequencies w [rad/s].
        real(dp), intent(in) :: frequencies(:)
        !> The error measure (0 when there are no contacts or frequencies).
        real(dp), intent(out) :: max_error
        !> Error (last non-optional).
        type(error_type), allocatable, intent(out) :: error
        !> Full damping C (optional).
        type(sparse_matrix_t), intent(in), optional :: cmat
        !> The error at each frequency (optional, size(frequencies)).
        real(dp), intent(out), optional :: frequency_errors(:)
        real(dp), allocatable :: w(:, :)
        integer :: k, nc
        max_error = 0.0_dp
        nc = size(dof1)
        if (size(dof2) /= nc) then
            call fatal_error(error, "receptance_error: dof1 and dof2 differ in size", &
                             stickslip_stat%input)
            return
        end if
        do k = 1, nc
            if (reduced_dof_of(reduced, dof1(k)) == 0 .or. (dof2(k) /= 0 .and. &
                                                              reduced_dof_of(reduced, dof2(k)) == 0)) then
                call fatal_error(error, "receptance_error: contact "//itoa(k)//" (DOFs "// &
                                 itoa(dof1(k))//", "//itoa(dof2(k))//") is not on the "// &
                                 "boundary", stickslip_stat%input)
                return
            end if
        end do
        allocate (w(reduced%n, nc))
        w = 0.0_dp
        do k = 1, nc
            w(dof1(k), k) = 1.0_dp
            if (dof2(k) > 0) w(dof2(k), k) = w(dof2(k), k) - 1.0_dp
        end do
        call receptance_error_directions(kmat, mmat, reduced, w, frequencies, max_error, error, &
                                         cmat, frequency_errors)
    end subroutine receptance_error_dofs

    !> Reduction error: max over `frequencies` of max|G_r - G| / max|G|, G = W^T Z^-1 W the
    !> receptance of the contact directions W (N x n_c, nonzero on boundary DOFs only) of
    !> the full sparse model (complex sparse LU of Z = K - w^2 M + i w C per frequency) and
    !> G_r = W_r^T Z_r^-1 W_r that of the reduced model, W_r = T^T W (the boundary rows of
    !> W). Errors (input): W with a nonzero interior entry or the wrong number of rows;
    !> (numerical): Z singular at a frequency (named).
    !> The full model's LU uses CHOLMOD's choice of ordering (METIS on 3D meshes: half the
    !> fill of AMD), analysed once for all frequencies.
    subroutine receptance_error_directions(kmat, mmat, reduced, directions, frequencies, &
                                           max_error, error, cmat, frequency_errors)
        !> Full stiffness K.
        type(sparse_matrix_t), intent(in) :: kmat
        !> Full mass M.
        type(sparse_matrix_t), intent(in) :: mmat
        !> The reduced model of (K, M, C).
        type(reduced_model_t), intent(in) :: reduced
        !> Contact directions W, N x n_c.
        real(dp), intent(in) :: directions(:, :)
        !> Frequencies w [rad/s].
        real(dp), intent(in) :: frequencies(:)
        !> The error measure (0 when there are no contacts or frequencies).
        real(dp), intent(out) :: max_error
        !> Error (last non-optional).
        type(error_type), allocatable, intent(out) :: error
        !> Full damping C (optional).
        type(sparse_matrix_t), intent(in), optional :: cmat
        !> The error at each frequency (optional, size(frequencies)).
        real(dp), intent(out), optional :: frequency_errors(:)
        integer :: n, nc, nr, k, f, row, m, info, pk, pm, pc
        type(sparse_matrix_t) :: pattern
        integer, allocatable :: ri(:), ci(:), posk(:), posm(:), posc(:), ipiv(:)
        real(dp), allocatable :: ones(:)
        complex(dp), allocatable :: zval(:), b(:, :), x(:, :), zr(:, :), br(:, :), g(:, :), &
                                    gr(:, :)
        type(sparse_zlu_t) :: zlu
        real(dp) :: w

        max_error = 0.0_dp
        if (present(frequency_errors)) frequency_errors = 0.0_dp
        n = reduced%n
        nr = reduced%nr
        nc = size(directions, 2)
        if (size(directions, 1) /= n) then
            call fatal_error(error, "receptance_error: directions has "// &
                             itoa(size(directions, 1))//" rows, must be "//itoa(n), &
                             stickslip_stat%input)
            return
        end if
        if (nc == 0 .or. size(frequencies) == 0) return
        do k = 1, nc
            if (any(directions(reduced%interior, k) /= 0.0_dp)) then
                call fatal_error(error, "receptance_error: contact "//itoa(k)//" has a "// &
                                 "direction on interior DOF "// &
                                 itoa(reduced%interior(findloc(directions(reduced%interior, k) &
                                                               /= 0.0_dp, .true., 1)))// &
                                 " (not on the boundary)", stickslip_stat%input)
                return
            end if
        end do
        ! pattern of Z^T in CSR (= Z in CSC): triplets (col, row) of K, M, C
        m = kmat%nnz() + mmat%nnz()
        if (present(cmat)) m = m + cmat%nnz()
        allocate (ri(m), ci(m), ones(m))
        m = 0
        call add_pattern(kmat)
        call add_pattern(mmat)
        if (present(cmat)) call add_pattern(cmat)
        ones = 1.0_dp
        call new_sparse_from_triplets(pattern, n, n, ri, ci, ones, error)
        if (allocated(error)) return
        call positions(kmat, posk)
        call positions(mmat, posm)
        if (present(cmat)) call positions(cmat, posc)

        allocate (b(n, nc), x(n, nc), br(nr, nc), zr(nr, nr), ipiv(nr), zval(pattern%nnz()))
        b = cmplx(directions, 0.0_dp, dp)
        br = (0.0_dp, 0.0_dp)
        br(1:reduced%nb, :) = b(reduced%boundary, :)
        do f = 1, size(frequencies)
            w = frequencies(f)
            zval = (0.0_dp, 0.0_dp)
            do pk = 1, size(posk)
                zval(posk(pk)) = zval(posk(pk)) + kmat%val(pk)
            end do
            do pm = 1, size(posm)
                zval(posm(pm)) = zval(posm(pm)) - w**2*mmat%val(pm)
            end do
            if (present(cmat)) then
                do pc = 1, size(posc)
                    zval(posc(pc)) = zval(posc(pc)) + cmplx(0.0_dp, w*cmat%val(pc), dp)
                end do
            end if
            if (f == 1) then
                zlu%ordering = ordering_cholmod
                call zlu%factorize(n, pattern%row_start, pattern%col, zval, error)
            else
                call zlu%refactorize(zval, error)
            end if
            if (allocated(error)) then
                error%message = "receptance_error: full model at w = "//real_text(w, '(es12.5)')//" rad/s: "// &
                                error%message
                call zlu%release()
                return
            end if
            call zlu%solve(b, x, error)
            if (allocated(error)) then
                call zlu%release()
                return
            end if
            g = matmul(transpose(b), x)
            zr = cmplx(reduced%stiffness - w**2*reduced%mass, w*reduced%damping, dp)
            gr = br
            call zgesv(nr, nc, zr, nr, ipiv, gr, nr, info)
            if (info /= 0) then
                call fatal_error(error, "receptance_error: reduced model singular at w = "// &
                                 real_text(w, '(es12.5)')//" rad/s", stickslip_stat%numerical)
                call zlu%release()
                return
            end if
            gr = matmul(transpose(br), gr)
            if (maxval(abs(g)) > 0.0_dp) then
                max_error = max(max_error, maxval(abs(gr - g))/maxval(abs(g)))
                if (present(frequency_errors)) frequency_errors(f) = &
                    maxval(abs(gr - g))/maxval(abs(g))
            end if
        end do
        call zlu%release()

    contains

        subroutine add_pattern(a)
            type(sparse_matrix_t), intent(in) :: a
            integer :: kk
            do row = 1, n
                do kk = a%row_start(row), a%row_start(row + 1) - 1
                    m = m + 1
                    ri(m) = a%col(kk)
                    ci(m) = row
                end do
            end do
        end subroutine add_pattern

        !> Position in `pattern` (CSR of Z^T) of each entry of a.
        subroutine positions(a, pos)
            type(sparse_matrix_t), intent(in) :: a
            integer, allocatable, intent(out) :: pos(:)
            integer :: kk, lo, hi, mid, c
            allocate (pos(a%nnz()))
            do row = 1, n
                do kk = a%row_start(row), a%row_start(row + 1) - 1
                    c = a%col(kk)
                    lo = pattern%row_start(c)
                    hi = pattern%row_start(c + 1) - 1
                    do while (lo < hi)
                        mid = (lo + hi)/2
                        if (pattern%col(mid) < row) then
                            lo = mid + 1
                        else
                            hi = mid
                        end if
                    end do
                    pos(kk) = lo
                end do
            end do
        end subroutine positions
    end subroutine receptance_error_directions
end module stickslip_reduction_error
