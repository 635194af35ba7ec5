!> The Craig-Bampton reduced model (reduced_model_t: the reduced matrices and the basis) and
!> what works on it alone: the reduced DOF of a boundary DOF (reduced_dof_of), full-model
!> DOFs from reduced coordinates (recover_dofs, x = T q) and T^T A for full-model vectors
!> (reduce_vectors). Built by craig_bampton (stickslip_reduction, whose header describes the
!> basis, the mode-count rule and the load vectors); every name here is re-exported there.
!>
!> The basis is T = [I 0 0; Phi_c Phi_n Psi] (rows b, i): constraint modes Phi_c,
!> fixed-interface modes Phi_n, load vectors Psi. Reduced DOF j <= nb is full DOF boundary(j)
!> (boundary DOFs ascending); reduced DOF nb + k is the amplitude of fixed-interface mode k;
!> reduced DOF nb + nm + l that of load vector l.
module stickslip_reduced_model
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    implicit none
    private
    public :: reduced_model_t, recover_dofs, reduced_dof_of, reduce_vectors

    !> A Craig-Bampton reduced model and its basis.
    type :: reduced_model_t
        !> Full DOFs, boundary DOFs, fixed-interface modes, load vectors, reduced DOFs
        !> (nb + nm + nl).
        integer :: n = 0
        integer :: nb = 0
        integer :: nm = 0
        integer :: nl = 0
        integer :: nr = 0
        !> Full DOF of boundary DOF j (ascending), size nb.
        integer, allocatable :: boundary(:)
        !> Full DOF of interior DOF p (ascending), size n - nb.
        integer, allocatable :: interior(:)
        !> Reduced mass, stiffness and damping, nr x nr (damping zero when none).
        real(dp), allocatable :: mass(:, :), stiffness(:, :), damping(:, :)
        !> Static constraint modes Phi_c, (n - nb) x nb.
        real(dp), allocatable :: constraint(:, :)
        !> Fixed-interface modes Phi_n, (n - nb) x nm, M_ii-orthonormal.
        real(dp), allocatable :: modes(:, :)
        !> Their frequencies [rad/s], ascending.
        real(dp), allocatable :: frequencies(:)
        !> Static load-correction vectors Psi, (n - nb) x nl, M_ii-orthonormal and
        !> M_ii-orthogonal to the modes (see the header of stickslip_reduction).
        real(dp), allocatable :: loads(:, :)
        !> The modal damping ratio zeta added to the modes (2 zeta w_k on the diagonal of
        !> `damping`; not in T^T C T).
        real(dp) :: modal_damping_ratio = 0.0_dp
        !> Frequency of the first fixed-interface mode left out [rad/s] (0: not known; every
        !> mode kept, or the eigensolve stopped at the modes kept).
        real(dp) :: next_frequency = 0.0_dp
    end type reduced_model_t

    !> Full-model DOFs from reduced coordinates, real (recover_real) or complex
    !> (recover_complex: harmonic coefficients).

    interface recover_dofs
        module procedure recover_real, recover_complex
    end interface recover_dofs

contains

    !> The reduced DOF of full DOF `dof`: its position among the boundary DOFs, 0 if `dof`
    !> is not a boundary DOF (dof = 0, the ground, gives 0).
    pure integer function reduced_dof_of(reduced, dof) result(j)
        !> The reduced model.
        type(reduced_model_t), intent(in) :: reduced
        !> A full-model DOF.
        integer, intent(in) :: dof
        integer :: k
        j = 0
        do k = 1, reduced%nb
            if (reduced%boundary(k) == dof) then
                j = k
                return
            end if
        end do
    end function reduced_dof_of

    !> Recover full-model DOFs from reduced coordinates: x(k) = T(dofs(k), :) q.
    !> Errors (input): wrong size of q or x, a DOF out of range.
    subroutine recover_real(reduced, dofs, q, x, error)
        !> The reduced model.
        type(reduced_model_t), intent(in) :: reduced
        !> Full-model DOFs wanted (1..n).
        integer, intent(in) :: dofs(:)
        !> Reduced coordinates, size nr.
        real(dp), intent(in) :: q(:)
        !> Full-model values, size(dofs).
        real(dp), intent(out) :: x(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        integer :: k, j, p
        call check_recover(reduced, dofs, size(q), size(x), error)
        if (allocated(error)) return
        do k = 1, size(dofs)
            j = reduced_dof_of(reduced, dofs(k))
            if (j > 0) then
                x(k) = q(j)
            else
                p = interior_position(reduced, dofs(k))
                x(k) = dot_product(reduced%constraint(p, :), q(1:reduced%nb))
                if (reduced%nm > 0) x(k) = x(k) + dot_product(reduced%modes(p, :), &
                                                              q(reduced%nb + 1:reduced%nb + reduced%nm))
                if (reduced%nl > 0) x(k) = x(k) + dot_product(reduced%loads(p, :), &
                                                              q(reduced%nb + reduced%nm + 1:reduced%nr))
            end if
        end do
    end subroutine recover_real

    !> Recover complex full-model DOFs (harmonic coefficients): x(k) = T(dofs(k), :) q.
    subroutine recover_complex(reduced, dofs, q, x, error)
        !> The reduced model.
        type(reduced_model_t), intent(in) :: reduced
        !> Full-model DOFs wanted (1..n).
        integer, intent(in) :: dofs(:)
        !> Reduced coordinates, size nr.
        complex(dp), intent(in) :: q(:)
        !> Full-model values, size(dofs).
        complex(dp), intent(out) :: x(:)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        integer :: k, j, p
        call check_recover(reduced, dofs, size(q), size(x), error)
        if (allocated(error)) return
        do k = 1, size(dofs)
            j = reduced_dof_of(reduced, dofs(k))
            if (j > 0) then
                x(k) = q(j)
            else
                p = interior_position(reduced, dofs(k))
                x(k) = sum(reduced%constraint(p, :)*q(1:reduced%nb))
                if (reduced%nm > 0) x(k) = x(k) + sum(reduced%modes(p, :)* &
                                                      q(reduced%nb + 1:reduced%nb + reduced%nm))
                if (reduced%nl > 0) x(k) = x(k) + sum(reduced%loads(p, :)* &
                                                      q(reduced%nb + reduced%nm + 1:reduced%nr))
            end if
        end do
    end subroutine recover_complex

    !> Errors (input) of recover_dofs: size(q) /= nr, size(x) /= size(dofs), a DOF out of range.
    subroutine check_recover(reduced, dofs, nq, nx, error)
        type(reduced_model_t), intent(in) :: reduced
        integer, intent(in) :: dofs(:), nq, nx
        type(error_type), allocatable, intent(out) :: error
        if (nq /= reduced%nr .or. nx /= size(dofs)) then
            call fatal_error(error, "recover_dofs: size(q) = "//itoa(nq)//" (must be "// &
                             itoa(reduced%nr)//"), size(x) = "//itoa(nx)//" (must be "// &
                             itoa(size(dofs))//")", stickslip_stat%input)
            return
        end if
        if (size(dofs) > 0) then
            if (minval(dofs) < 1 .or. maxval(dofs) > reduced%n) call fatal_error(error, &
                "recover_dofs: a DOF out of range 1.."//itoa(reduced%n), stickslip_stat%input)
        end if
    end subroutine check_recover

    !> T^T A for a dense N x m block A (loads, contact directions): rows 1..nb are
    !> A_b + Phi_c^T A_i, then Phi_n^T A_i and Psi^T A_i (nr x m). For A zero on the interior
    !> (contact directions on boundary DOFs) it is A_b exactly, padded with zeros.
    !> Errors (input): A without N rows.
    subroutine reduce_vectors(reduced, a, ar, error)
        !> The reduced model.
        type(reduced_model_t), intent(in) :: reduced
        !> Full-model vectors, N x m.
        real(dp), intent(in) :: a(:, :)
        !> Reduced vectors, nr x m.
        real(dp), allocatable, intent(out) :: ar(:, :)
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: ai(:, :)
        integer :: nb, nm
        if (size(a, 1) /= reduced%n) then
            call fatal_error(error, "reduce_vectors: "//itoa(size(a, 1))//" rows, must be "// &
                             itoa(reduced%n), stickslip_stat%input)
            return
        end if
        nb = reduced%nb
        nm = reduced%nm
        allocate (ar(reduced%nr, size(a, 2)))
        ar(1:nb, :) = a(reduced%boundary, :)
        ar(nb + 1:, :) = 0.0_dp
        ai = a(reduced%interior, :)
        if (all(ai == 0.0_dp)) return
        ar(1:nb, :) = ar(1:nb, :) + matmul(transpose(reduced%constraint), ai)
        if (nm > 0) ar(nb + 1:nb + nm, :) = matmul(transpose(reduced%modes), ai)
        if (reduced%nl > 0) ar(nb + nm + 1:, :) = matmul(transpose(reduced%loads), ai)
    end subroutine reduce_vectors

    !> Position of full DOF `dof` among the interior DOFs (binary search; 0: not interior).
    pure integer function interior_position(reduced, dof) result(p)
        type(reduced_model_t), intent(in) :: reduced
        integer, intent(in) :: dof
        integer :: lo, hi, mid
        p = 0
        lo = 1
        hi = size(reduced%interior)
        do while (lo <= hi)
            mid = (lo + hi)/2
            if (reduced%interior(mid) == dof) then
                p = mid
                return
            else if (reduced%interior(mid) < dof) then
                lo = mid + 1
            else
                hi = mid - 1
            end if
        end do
    end function interior_position
end module stickslip_reduced_model
