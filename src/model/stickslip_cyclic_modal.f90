!> The sector's cyclic modes per nodal diameter, prepared once so that the condensation of
!> a large (reduced FE) sector per harmonic and per omega is a modal sum instead of a dense
!> factorization (stickslip_cyclic_dynamics).
!>
!> At nodal diameter nd the sector's motions are X = T q with X_right = e X_left, e = exp(i 2
!> pi nd / N) (cyclic_basis). K_c = T^H K T and M_c = T^H M T are Hermitian, M_c positive
!> definite: K_c Phi = M_c Phi Lambda with Phi^H M_c Phi = I (LAPACK zhegv). When the damping
!> is proportional (Phi^H C_c Phi diagonal: Rayleigh damping, also after a Craig-Bampton
!> reduction, which projects C = a M + b K to a M_r + b K_r), Z_c(w) = K_c - w^2 M_c + i w C_c
!> has the inverse Phi diag(1 / (lambda_j - w^2 + i w c_j)) Phi^H, exactly. The harmonics
!> whose inter-sector phase is exp(-i 2 pi p / N) use nd = p (p <= N/2: the conjugate basis,
!> so the conjugate shapes) or nd = N - p; only the diameters the harmonics 0..hmax reach
!> are prepared.
module stickslip_cyclic_modal
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, cyclic_pencil, nodal_diameter, &
        structure_key, hermitian_pencil, cyclic_projection
    use stickslip_dynamics, only: smallest_singular
    implicit none
    private
    public :: prepare_cyclic_modes, modal_tolerance

    !> Largest off-diagonal entry of Phi^H C_c Phi, relative to the largest diagonal one,
    !> for the damping to count as proportional (Rayleigh damping: roundoff, 1e-14).
    real(dp), parameter :: modal_tolerance = 1.0e-9_dp

contains

    !> Prepare cyc%modes for the sector `model`: the cyclic modes of every nodal diameter that
    !> the harmonics 0..hmax of engine order cyc%engine_order reach, and cyc%smin_k,
    !> cyc%smin_m. Not prepared (cyc%modes left unallocated, `prepared` false) when the
    !> damping is not proportional on some diameter or M_c is not positive definite: the
    !> condensation then factorizes per harmonic, as before; that is no error. Errors: those
    !> of validate_cyclic (stat input).
    subroutine prepare_cyclic_modes(model, cyc, hmax, error, prepared)
        !> The sector (a validated model).
        type(model_t), intent(in) :: model
        !> The symmetry; on return with its modes.
        type(cyclic_t), intent(inout) :: cyc
        !> Highest harmonic of the runs.
        integer, intent(in) :: hmax
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The modes were prepared.
        logical, intent(out), optional :: prepared
        complex(dp), allocatable :: t(:, :), kc(:, :), mc(:, :), cc(:, :)
        real(dp), allocatable :: w(:)
        logical, allocatable :: wanted(:)
        real(dp) :: offdiag, diag
        integer :: n, m, nd, h, info, j
        logical :: ok

        if (present(prepared)) prepared = .false.
        if (allocated(cyc%modes)) deallocate (cyc%modes)
        if (allocated(cyc%free_lambda)) deallocate (cyc%free_lambda, cyc%free_shapes)
        call validate_cyclic(model, cyc, error)
        if (allocated(error)) return
        if (hmax < 0) then
            call fatal_error(error, "prepare_cyclic_modes: hmax < 0", stickslip_stat%input)
            return
        end if
        n = model%ndof
        m = n - size(cyc%right)
        allocate (wanted(0:cyc%sectors/2))
        wanted = .false.
        do h = 0, hmax
            wanted(nodal_diameter(h, cyc%engine_order, cyc%sectors)) = .true.
        end do
        allocate (cyc%modes(0:cyc%sectors/2))
        ok = .true.
        do nd = 0, cyc%sectors/2
            if (.not. wanted(nd)) cycle
            call cyclic_pencil(model, cyc, nd, t, kc, mc)
            cc = cyclic_projection(model%damping, cyc, exp(cmplx(0.0_dp, two_pi*real(nd, dp)/ &
                                                                real(cyc%sectors, dp), dp)))
            call hermitian_pencil(kc, mc, w, .true., info)
            if (info /= 0) then
                ok = .false.
                exit
            end if
            ! kc now holds Phi (M_c-orthonormal): the damping on the modes
            cc = matmul(conjg(transpose(kc)), matmul(cc, kc))
            allocate (cyc%modes(nd)%damping(m))
            diag = 0.0_dp
            offdiag = 0.0_dp
            do j = 1, m
                cyc%modes(nd)%damping(j) = real(cc(j, j), dp)
                diag = max(diag, abs(cc(j, j)))
                cc(j, j) = (0.0_dp, 0.0_dp)
                offdiag = max(offdiag, maxval(abs(cc(:, j))))
            end do
            if (offdiag > modal_tolerance*diag) then
                ok = .false.
                exit
            end if
            cyc%modes(nd)%nd = nd
            cyc%modes(nd)%lambda = w
            cyc%modes(nd)%shapes = matmul(t, kc)
            cyc%modes(nd)%shapes_h = conjg(transpose(cyc%modes(nd)%shapes))
        end do
        if (.not. ok) then
            deallocate (cyc%modes)
            return
        end if
        ! the free sector's modes (for its contact mobility; none when zhegv fails)
        kc = cmplx(model%stiffness, 0.0_dp, dp)
        mc = cmplx(model%mass, 0.0_dp, dp)
        call hermitian_pencil(kc, mc, w, .true., info)
        if (info == 0) then
            cyc%free_lambda = w
            cyc%free_shapes = kc
        end if
        cyc%smin_k = smallest_singular(model%stiffness, maxval(sum(abs(model%stiffness), 1)))
        cyc%smin_m = smallest_singular(model%mass, maxval(sum(abs(model%mass), 1)))
        cyc%modes_key = structure_key(model, cyc%sectors)
        if (present(prepared)) prepared = .true.
    end subroutine prepare_cyclic_modes
end module stickslip_cyclic_modal
