!> Craig-Bampton reduction of a sparse structure (M, K, optional C) to a small dense model.
!>
!> The DOFs split into boundary DOFs b (given: every DOF a contact or a forced DOF touches)
!> and interior DOFs i (the rest). The basis is T = [I 0 0; Phi_c Phi_n Psi] (rows b, i):
!> the static constraint modes Phi_c = -K_ii^-1 K_ib (one sparse LU of K_ii, nb right-hand
!> sides) and the fixed-interface normal modes Phi_n of K_ii phi = w^2 M_ii phi (shift-invert
!> Lanczos at sigma = 0 on the sparse LU of K_ii, or LAPACK dsygv when the interior is small),
!> M_ii-orthonormal. The reduced matrices M_r = T^T M T, K_r = T^T K T, C_r = T^T C T are
!> formed from sparse products with the N x (nb + nm + nl) basis (no dense N x N matrix);
!> K_r from the basis' structure (the constraint columns of K T vanish on the interior), so
!> its dense product over the interior covers the modal and load columns only.
!> Reduced DOF j <= nb is full DOF boundary(j) (boundary DOFs ascending); reduced DOF nb + k
!> is the amplitude of fixed-interface mode k; reduced DOF nb + nm + l that of load vector l.
!>
!> Load vectors (distributed loads, argument `loads` = F, N x n_terms): the interior part F_i
!> of a load is poorly represented by the fixed-interface modes alone (their series for the
!> static response K_ii^-1 F_i converges slowly). For every column with a nonzero interior
!> part one static load-correction vector psi = K_ii^-1 F_i (the sparse LU of K_ii already
!> made for Phi_c) is M_ii-orthogonalized (twice, Gram-Schmidt) against the kept modes and
!> the load vectors before it, dropped when what is left is below load_vector_tolerance of
!> its M_ii-norm (numerically dependent), and normalized to unit modal mass. With them the
!> exact static response K^-1 F lies in the span of T, so the reduced model's static response
!> to F_r = T^T F is the full one (reduce_vectors gives T^T F). They get no modal damping
!> ratio (damping_ratio acts on the modes only); C, when given, is projected as for the rest.
!>
!> Mode-count rule (options%modes = 0): keep every fixed-interface mode with frequency below
!> cutoff_factor x the highest excitation frequency (options%highest_frequency = H omega_max),
!> cutoff_factor = 3 by default; options%max_frequency > 0 overrides the limit. Why: an
!> interior mode far above the band of the excitation responds quasi-statically, and the
!> quasi-static response of the interior to the boundary is exactly what the constraint modes
!> carry, so leaving it out costs an error of order (w / w_k)^2 (<= 1/9 of that mode's share at
!> the factor 3 and falling fast above). Damped models: a mode whose damping force at the
!> excitation frequency is comparable to its stiffness does not respond quasi-statically, so
!> (without max_frequency) mode k is also kept when w_k^2 <= cutoff_factor^2 w_h c_k, with
!> w_h = highest_frequency and c_k = phi_k^T C_ii phi_k + 2 zeta w_k its modal damping
!> coefficient (heavy mass-proportional damping then keeps more modes); the count is the last
!> mode kept by either test. The modes below the limit are found in one pass
!> (sparse_eigenpairs_below: one factorization, the count estimated from the first 20),
!> again with a higher limit while the damped test keeps the highest one found, capped at
!> max_modes (report%capped then).
!> options%modes > 0 keeps exactly that many (at most the number of interior DOFs).
!>
!> Damping: C given on the full model is projected (C_r = T^T C T; when the caller says C =
!> alpha M + beta K, argument `rayleigh`, C_r = alpha M_r + beta K_r without the third
!> projection, the same matrix to roundoff); options%damping_ratio > 0 adds modal damping 2 zeta
!> w_k on the diagonal of the fixed-interface modes (unit modal mass).
!>
!> The reduced model type, recovery and reduce_vectors live in stickslip_reduced_model, the
!> reduction error (receptance_error: the contact receptance of the reduced model against the
!> full sparse model) in stickslip_reduction_error, its cheap estimate on the interior
!> factorization (estimate_reduction_error) in stickslip_reduction_estimate; all are
!> re-exported here.
module stickslip_reduction
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa, real_text
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_transpose, &
        sparse_times_block
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_stiffness_factor, only: factorize_stiffness
    use stickslip_progress, only: progress_t
    use stickslip_arpack, only: eigen_options_t, eigen_report_t
    use stickslip_sparse_eigen, only: sparse_eigenpairs, sparse_eigenpairs_below, &
        eigen_range_report_t
    use stickslip_lapack, only: dsygv
    use stickslip_dense_products, only: mat_tmul
    use stickslip_reduced_model, only: reduced_model_t, recover_dofs, reduced_dof_of, &
        reduce_vectors
    use stickslip_reduction_error, only: receptance_error
    use stickslip_reduction_estimate, only: reduction_estimate_t, estimate_reduction_error
    implicit none
    private
    public :: reduction_options_t, reduction_report_t, reduced_model_t, craig_bampton, &
        recover_dofs, receptance_error, default_cutoff_factor, reduced_dof_of, reduce_vectors
    public :: reduction_estimate_t, estimate_reduction_error

    !> Default factor of the mode-count rule: modes below 3 H omega_max are kept.
    real(dp), parameter :: default_cutoff_factor = 3.0_dp
    !> Interiors up to this size use a dense eigensolver (LAPACK dsygv).
    integer, parameter :: dense_interior = 400
    !> A load vector is dropped when its M_ii-norm after the orthogonalization is below this
    !> fraction of its norm before (it lies in the span of the modes and earlier vectors).
    real(dp), parameter, public :: load_vector_tolerance = 1.0e-10_dp

    !> What to keep in a Craig-Bampton reduction.
    type :: reduction_options_t
        !> Number of fixed-interface modes; 0: the rule (see the module header).
        integer :: modes = 0
        !> Keep the modes below this frequency [rad/s]; 0: cutoff_factor x highest_frequency.
        real(dp) :: max_frequency = 0.0_dp
        !> Highest excitation frequency H omega_max [rad/s] (for the rule).
        real(dp) :: highest_frequency = 0.0_dp
        !> Factor of the rule.
        real(dp) :: cutoff_factor = default_cutoff_factor
        !> Modal damping ratio added to the fixed-interface modes (0: none).
        real(dp) :: damping_ratio = 0.0_dp
        !> Most fixed-interface modes the rule may take.
        integer :: max_modes = 500
    end type reduction_options_t

    !> What a reduction did (echoed in summary.nml).
    type :: reduction_report_t
        !> 'none' or 'craig-bampton'.
        character(len=16) :: method = 'none'
        !> DOFs of the full model, of the reduced model, boundary DOFs, fixed-interface modes.
        integer :: full_dof = 0
        integer :: reduced_dof = 0
        integer :: boundary_dof = 0
        integer :: modes = 0
        !> Static load-correction vectors appended to the basis (distributed loads).
        integer :: load_vectors = 0
        !> Wall time of the reduction [s].
        real(dp) :: seconds = 0.0_dp
        !> Frequency of the highest kept fixed-interface mode [rad/s] (0: none kept).
        real(dp) :: highest_mode_frequency = 0.0_dp
        !> The frequency limit the rule used [rad/s] (0: a fixed mode count).
        real(dp) :: frequency_limit = 0.0_dp
        !> The rule hit max_modes before passing the limit.
        logical :: capped = .false.
        !> Receptance error (receptance_error) at the run's frequencies; -1: not measured.
        real(dp) :: error = -1.0_dp
        !> The frequencies where `error` was measured [rad/s] (set by the caller).
        real(dp), allocatable :: error_frequencies(:)
        !> How `error` was obtained (set by the caller): 'enriched' (estimate_reduction_error,
        !> its enrichment levels agreed), 'sparse LU' (the exact measure), 'off' (not asked
        !> for), 'none' (nothing to measure: no contact or no frequency).
        character(len=16) :: error_method = 'none'
        !> Wall time of the error estimate [s] (0 when not computed in this run).
        real(dp) :: error_seconds = 0.0_dp
        !> Enrichment levels of the estimate and the change of its last level (relative to
        !> max|G|, as `error`).
        integer :: error_levels = 0
        real(dp) :: error_change = 0.0_dp
        !> A sector's reduction (set by the caller, stickslip_case): the error per nodal
        !> diameter measured with it, kept with the model by the reduction cache: the
        !> diameters, their largest relative frequency errors and lowest frequencies
        !> [rad/s], the band they were measured up to [rad/s] and the interface modes per
        !> face in effect (-1: not measured).
        integer, allocatable :: diameters(:)
        real(dp), allocatable :: diameter_errors(:), diameter_lowest(:)
        real(dp) :: diameter_band = 0.0_dp
        integer :: diameter_faces = -1
    end type reduction_report_t

contains

    !> Craig-Bampton reduction of (M, K, C) with the boundary DOFs `boundary_dofs` (any
    !> order, duplicates ignored); with `loads`, one static load-correction vector per load
    !> column with a nonzero interior part (see the module header). Errors (input): sizes that
    !> disagree, a DOF out of range, no boundary or no interior DOF, options out of range, a
    !> non-finite load; (numerical): K_ii singular (the interior moves as a rigid body when
    !> the boundary is fixed), the eigensolver failing.
    !> K_ii is factorized once (CHOLMOD's Cholesky; UMFPACK's LU if K_ii is not positive
    !> definite), for the constraint modes and the load vectors (block solves) and the
    !> shift-invert Lanczos of the fixed-interface modes alike; with
    !> `interior_lu` the factorization is handed to the caller on return (for the error
    !> estimate, stickslip_reduction_estimate), released otherwise. With `progress`, the
    !> phases that took a second or more are reported (progress_t%phase). With `rayleigh`
    !> = [alpha, beta] the caller says that cmat is alpha M + beta K (Rayleigh damping):
    !> C_r is then formed from M_r and K_r.
    subroutine craig_bampton(kmat, mmat, boundary_dofs, options, reduced, report, error, cmat, &
                             loads, interior_lu, progress, rayleigh)
        !> Stiffness K, N x N (full storage).
        type(sparse_matrix_t), intent(in) :: kmat
        !> Mass M, N x N.
        type(sparse_matrix_t), intent(in) :: mmat
        !> Boundary DOFs (1..N).
        integer, intent(in) :: boundary_dofs(:)
        !> Mode count or frequency limit, damping ratio.
        type(reduction_options_t), intent(in) :: options
        !> The reduced model.
        type(reduced_model_t), intent(out) :: reduced
        !> Sizes, time, modes.
        type(reduction_report_t), intent(out) :: report
        !> Error (last non-optional).
        type(error_type), allocatable, intent(out) :: error
        !> Damping C, N x N (optional: projected).
        type(sparse_matrix_t), intent(in), optional :: cmat
        !> Distributed loads F, N x n_terms (optional: load vectors for their interior parts).
        real(dp), intent(in), optional :: loads(:, :)
        !> On return the sparse LU of K_ii (interior numbering, ascending full DOFs), when
        !> the reduction succeeded and the interior was factorized sparse; the caller
        !> releases it.
        class(sparse_factor_t), allocatable, intent(inout), optional :: interior_lu
        !> Where the phases are reported (optional).
        type(progress_t), intent(inout), optional :: progress
        !> [alpha, beta] [1/s, s]: cmat is alpha M + beta K (optional; only with cmat).
        real(dp), intent(in), optional :: rayleigh(2)
        integer, allocatable :: loc(:)
        integer :: n, nb, ni, j, p, r, q, nm, nr, nl
        real(dp), allocatable :: psi(:, :)
        integer(int64) :: t0, t1, rate, tphase
        type(sparse_matrix_t) :: kii, mii, kiit, miit, cii
        class(sparse_factor_t), allocatable :: lu
        real(dp), allocatable :: rhs(:, :), lam(:), vec(:, :), t(:, :), at(:, :)
        real(dp) :: limit, lmax
        type(eigen_options_t) :: eopts
        type(eigen_report_t) :: erep
        type(eigen_range_report_t) :: rrep

        call system_clock(t0, rate)
        tphase = t0
        n = kmat%nrows
        if (kmat%ncols /= n .or. mmat%nrows /= n .or. mmat%ncols /= n) then
            call fatal_error(error, "craig_bampton: K and M must be square of equal size", &
                             stickslip_stat%input)
            return
        end if
        if (present(cmat)) then
            if (cmat%nrows /= n .or. cmat%ncols /= n) then
                call fatal_error(error, "craig_bampton: C must be "//itoa(n)//" x "//itoa(n), &
                                 stickslip_stat%input)
                return
            end if
        end if
        if (present(rayleigh)) then
            if (.not. (present(cmat) .and. all(ieee_is_finite(rayleigh)))) then
                call fatal_error(error, "craig_bampton: rayleigh needs cmat and finite "// &
                                 "factors", stickslip_stat%input)
                return
            end if
        end if
        if (present(loads)) then
            if (size(loads, 1) /= n) then
                call fatal_error(error, "craig_bampton: loads has "//itoa(size(loads, 1))// &
                                 " rows, must be "//itoa(n), stickslip_stat%input)
                return
            end if
            if (.not. all(ieee_is_finite(loads))) then
                call fatal_error(error, "craig_bampton: loads: not all finite", &
                                 stickslip_stat%input)
                return
            end if
        end if
        if (options%modes > options%max_modes) then
            call fatal_error(error, "craig_bampton: options%modes = "//itoa(options%modes)// &
                             ": must be <= "//itoa(options%max_modes)//" (options%max_modes: "// &
                             "the most fixed-interface modes of a reduction; the reduced "// &
                             "model is dense)", stickslip_stat%input)
            return
        end if
        if (options%modes < 0 .or. .not. (options%max_frequency >= 0.0_dp) .or. &
            .not. (options%damping_ratio >= 0.0_dp) .or. &
            .not. (options%cutoff_factor > 0.0_dp)) then
            call fatal_error(error, "craig_bampton: modes, max_frequency, damping_ratio must "// &
                             "be >= 0", stickslip_stat%input)
            return
        end if
        allocate (loc(n))
        loc = 0
        do j = 1, size(boundary_dofs)
            if (boundary_dofs(j) < 1 .or. boundary_dofs(j) > n) then
                call fatal_error(error, "craig_bampton: boundary DOF "//itoa(boundary_dofs(j)) &
                                 //" out of range 1.."//itoa(n), stickslip_stat%input)
                return
            end if
            loc(boundary_dofs(j)) = -1
        end do
        nb = count(loc < 0)
        ni = n - nb
        if (nb == 0 .or. ni == 0) then
            call fatal_error(error, "craig_bampton: "//itoa(nb)//" boundary and "//itoa(ni)// &
                             " interior DOFs: both must be nonzero", stickslip_stat%input)
            return
        end if
        reduced%n = n
        reduced%nb = nb
        allocate (reduced%boundary(nb), reduced%interior(ni))
        q = 0
        p = 0
        do j = 1, n
            if (loc(j) < 0) then
                q = q + 1
                reduced%boundary(q) = j
                loc(j) = -q
            else
                p = p + 1
                reduced%interior(p) = j
                loc(j) = p
            end if
        end do

        ! K_ii, M_ii (their transposes in CSR = the matrices in CSC) and K_ib
        call submatrix(kmat, kii)
        call submatrix(mmat, mii)
        if (allocated(error)) return
        if (present(cmat)) then
            call submatrix(cmat, cii)
            if (allocated(error)) return
        end if
        call sparse_transpose(kii, kiit)
        call sparse_transpose(mii, miit)
        allocate (rhs(ni, nb))
        rhs = 0.0_dp
        do r = 1, n
            if (loc(r) <= 0) cycle
            do p = kmat%row_start(r), kmat%row_start(r + 1) - 1
                if (loc(kmat%col(p)) < 0) rhs(loc(r), -loc(kmat%col(p))) = &
                    rhs(loc(r), -loc(kmat%col(p))) - kmat%val(p)
            end do
        end do
        call factorize_stiffness(ni, kiit%row_start, kiit%col, kiit%val, lu, error)
        if (allocated(error)) then
            error%message = "craig_bampton: the interior stiffness K_ii ("//itoa(ni)// &
                            " DOFs) cannot be factorized (is the interior held by the "// &
                            "boundary DOFs?): "//error%message
            return
        end if
        call phase("K_ii factorized ("//itoa(ni)//" interior DOFs, "// &
                   lu%name()//", "//real_text(lu%factor_entries, '(es9.2)')//" entries)")
        allocate (reduced%constraint(ni, nb))
        call lu%solve(rhs, reduced%constraint, error)
        if (.not. allocated(error) .and. present(loads)) call interior_load_solutions(psi)
        if (allocated(error)) then
            call lu%release()
            return
        end if
        call phase(itoa(nb)//" constraint modes")

        ! fixed-interface modes
        limit = 0.0_dp
        if (options%modes == 0) then
            limit = options%max_frequency
            if (limit == 0.0_dp) limit = options%cutoff_factor*options%highest_frequency
        end if
        report%frequency_limit = limit
        if (options%modes > 0) then
            nm = min(options%modes, ni)
            ! one more when the interior allows: the first mode left out (for the error
            ! estimate's convergence bound)
            call eigen(min(nm + 1, ni), lam, vec)
            if (allocated(error)) then
                call lu%release()
                return
            end if
        else if (limit > 0.0_dp) then
            if (ni <= dense_interior) then
                call eigen(ni, lam, vec)
                if (allocated(error)) then
                    call lu%release()
                    return
                end if
                nm = last_kept(lam, vec)
                if (nm > options%max_modes) then
                    if (options%max_frequency > 0.0_dp) then
                        call too_many_below(nm)
                        call lu%release()
                        return
                    end if
                    nm = options%max_modes
                    report%capped = .true.
                end if
            else
                ! every mode below the limit in one Lanczos pass (stickslip_sparse_eigen
                ! estimates the count), more only while the damped test keeps the highest
                lmax = min(limit, sqrt(0.1_dp*huge(1.0_dp)))**2
                do
                    call sparse_eigenpairs_below(ni, kiit%row_start, kiit%col, kiit%val, &
                                                 miit%row_start, miit%col, miit%val, lmax, &
                                                 options%max_modes, 0.0_dp, eopts, lam, vec, &
                                                 rrep, error, &
                                                 stop_above=options%max_frequency > 0.0_dp, &
                                                 factorization=lu)
                    if (allocated(error)) then
                        error%message = "craig_bampton: fixed-interface modes: "//error%message
                        call lu%release()
                        return
                    end if
                    if (rrep%estimated > 0) then
                        call too_many_below(rrep%estimated)
                        call lu%release()
                        return
                    end if
                    nm = last_kept(lam, vec)
                    if (nm < size(lam)) exit
                    if (size(lam) >= min(ni - 1, options%max_modes)) then
                        report%capped = .true.
                        exit
                    end if
                    lmax = 4.0_dp*lam(size(lam))
                end do
            end if
        else
            nm = 0
        end if
        if (nm > 0 .and. rrep%block_solves + erep%block_solves > 0) then
            call phase(itoa(nm)//" fixed-interface modes (highest "// &
                       real_text(sqrt(max(lam(nm), 0.0_dp)), '(es10.3)')//" rad/s; "// &
                       "block Lanczos, "//itoa(rrep%block_solves + erep%block_solves)// &
                       " block solves of "// &
                       itoa(rrep%op_applications + erep%op_applications)//" vectors)")
        else if (nm > 0) then
            call phase(itoa(nm)//" fixed-interface modes (highest "// &
                       real_text(sqrt(max(lam(nm), 0.0_dp)), '(es10.3)')//" rad/s; "// &
                       itoa(rrep%runs + merge(1, 0, erep%op_applications > 0))// &
                       " Lanczos runs, "// &
                       itoa(rrep%op_applications + erep%op_applications)//" solves)")
        end if
        reduced%nm = nm
        reduced%modal_damping_ratio = options%damping_ratio
        if (allocated(lam)) then
            if (size(lam) > nm) reduced%next_frequency = sqrt(max(lam(nm + 1), 0.0_dp))
        end if
        allocate (reduced%modes(ni, nm), reduced%frequencies(nm))
        if (nm > 0) then
            reduced%modes = vec(:, 1:nm)
            reduced%frequencies = sqrt(max(lam(1:nm), 0.0_dp))
        end if
        if (.not. allocated(psi)) allocate (psi(ni, 0))
        call orthonormal_loads(psi, reduced%loads)
        nl = size(reduced%loads, 2)
        reduced%nl = nl
        nr = nb + nm + nl
        reduced%nr = nr

        ! T (N x nr) and the projections
        allocate (t(n, nr))
        t = 0.0_dp
        do j = 1, nb
            t(reduced%boundary(j), j) = 1.0_dp
        end do
        do p = 1, ni
            t(reduced%interior(p), 1:nb) = reduced%constraint(p, :)
            if (nm > 0) t(reduced%interior(p), nb + 1:nb + nm) = reduced%modes(p, :)
            if (nl > 0) t(reduced%interior(p), nb + nm + 1:nr) = reduced%loads(p, :)
        end do
        call project(mmat, reduced%mass)
        call project_stiffness(reduced%stiffness)
        if (present(cmat) .and. present(rayleigh)) then
            reduced%damping = rayleigh(1)*reduced%mass + rayleigh(2)*reduced%stiffness
        else if (present(cmat)) then
            call project(cmat, reduced%damping)
        else
            allocate (reduced%damping(nr, nr))
            reduced%damping = 0.0_dp
        end if
        do j = 1, nm
            reduced%damping(nb + j, nb + j) = reduced%damping(nb + j, nb + j) + &
                2.0_dp*options%damping_ratio*reduced%frequencies(j)
        end do

        call phase("reduced matrices ("//itoa(nr)//" DOFs)")
        if (present(interior_lu)) then
            if (allocated(interior_lu)) call interior_lu%release()
            call move_alloc(lu, interior_lu)
        else
            call lu%release()
        end if
        call system_clock(t1)
        report%method = 'craig-bampton'
        report%full_dof = n
        report%reduced_dof = nr
        report%boundary_dof = nb
        report%modes = nm
        report%load_vectors = nl
        report%seconds = real(t1 - t0, dp)/real(max(rate, 1_int64), dp)
        if (nm > 0) report%highest_mode_frequency = reduced%frequencies(nm)

    contains

        !> K_ii^-1 F_i for every column of `loads` with a nonzero interior part (on the LU of
        !> K_ii), ni x (those columns).
        subroutine interior_load_solutions(psi)
            real(dp), allocatable, intent(out) :: psi(:, :)
            real(dp), allocatable :: fi(:, :)
            integer :: c, m
            allocate (fi(ni, size(loads, 2)))
            m = 0
            do c = 1, size(loads, 2)
                if (all(loads(reduced%interior, c) == 0.0_dp)) cycle
                m = m + 1
                fi(:, m) = loads(reduced%interior, c)
            end do
            allocate (psi(ni, m))
            if (m == 0) return
            call lu%solve(fi(:, 1:m), psi, error)
            if (allocated(error)) error%message = "craig_bampton: load vectors: "// &
                error%message
        end subroutine interior_load_solutions

        !> The load vectors: each column of `raw` M_ii-orthogonalized (classical Gram-Schmidt,
        !> twice) against the kept modes and the vectors kept before it, dropped below
        !> load_vector_tolerance, normalized to unit modal mass.
        subroutine orthonormal_loads(raw, kept)
            real(dp), intent(in) :: raw(:, :)
            real(dp), allocatable, intent(out) :: kept(:, :)
            real(dp), allocatable :: v(:, :), mv(:, :)
            real(dp) :: norm0, norm1
            integer :: c, pass, m
            allocate (kept(ni, size(raw, 2)), v(ni, 1), mv(ni, 1))
            m = 0
            do c = 1, size(raw, 2)
                v(:, 1) = raw(:, c)
                call sparse_times_block(mii, v, mv)
                norm0 = sqrt(max(dot_product(v(:, 1), mv(:, 1)), 0.0_dp))
                if (.not. (norm0 > 0.0_dp)) cycle
                do pass = 1, 2
                    if (nm + m == 0) exit
                    ! v -= B B^T M v with B = [modes, kept(:, 1:m)] (M_ii-orthonormal columns)
                    if (nm > 0) v(:, 1) = v(:, 1) - matmul(reduced%modes, &
                                                           matmul(mv(:, 1), reduced%modes))
                    if (m > 0) v(:, 1) = v(:, 1) - matmul(kept(:, 1:m), &
                                                          matmul(mv(:, 1), kept(:, 1:m)))
                    call sparse_times_block(mii, v, mv)
                end do
                norm1 = sqrt(max(dot_product(v(:, 1), mv(:, 1)), 0.0_dp))
                if (.not. (norm1 > load_vector_tolerance*norm0)) cycle
                m = m + 1
                kept(:, m) = v(:, 1)/norm1
            end do
            kept = kept(:, 1:m)
        end subroutine orthonormal_loads

        !> The last mode the rule keeps (0: none): w_k <= limit, or (damped, no max_frequency)
        !> w_k^2 <= cutoff_factor^2 highest_frequency c_k.
        integer function last_kept(lam, vec) result(last)
            real(dp), intent(in) :: lam(:), vec(:, :)
            real(dp), allocatable :: cphi(:, :)
            real(dp) :: ck, wh
            integer :: kk
            logical :: damped
            wh = options%highest_frequency
            damped = options%max_frequency == 0.0_dp .and. wh > 0.0_dp .and. &
                     (present(cmat) .or. options%damping_ratio > 0.0_dp)
            if (damped .and. present(cmat)) then
                allocate (cphi(ni, size(lam)))
                call sparse_times_block(cii, vec, cphi)
            end if
            last = 0
            do kk = 1, size(lam)
                if (lam(kk) <= limit**2) then
                    last = kk
                else if (damped) then
                    ck = 2.0_dp*options%damping_ratio*sqrt(max(lam(kk), 0.0_dp))
                    if (present(cmat)) ck = ck + dot_product(vec(:, kk), cphi(:, kk))
                    if (lam(kk) <= options%cutoff_factor**2*wh*ck) last = kk
                end if
            end do
        end function last_kept

        !> The interior-interior block of a.
        subroutine submatrix(a, s)
            type(sparse_matrix_t), intent(in) :: a
            type(sparse_matrix_t), intent(out) :: s
            integer, allocatable :: ri(:), ci(:)
            real(dp), allocatable :: vi(:)
            integer :: row, k, m
            m = 0
            do row = 1, n
                if (loc(row) <= 0) cycle
                do k = a%row_start(row), a%row_start(row + 1) - 1
                    if (loc(a%col(k)) > 0) m = m + 1
                end do
            end do
            allocate (ri(m), ci(m), vi(m))
            m = 0
            do row = 1, n
                if (loc(row) <= 0) cycle
                do k = a%row_start(row), a%row_start(row + 1) - 1
                    if (loc(a%col(k)) > 0) then
                        m = m + 1
                        ri(m) = loc(row)
                        ci(m) = loc(a%col(k))
                        vi(m) = a%val(k)
                    end if
                end do
            end do
            call new_sparse_from_triplets(s, ni, ni, ri, ci, vi, error)
        end subroutine submatrix

        !> The boundary rows of a (nb x n, in the order of reduced%boundary).
        subroutine boundary_rows(a, s)
            type(sparse_matrix_t), intent(in) :: a
            type(sparse_matrix_t), intent(out) :: s
            integer, allocatable :: ri(:), ci(:)
            real(dp), allocatable :: vi(:)
            integer :: jb, k, m, row
            m = 0
            do jb = 1, nb
                row = reduced%boundary(jb)
                m = m + a%row_start(row + 1) - a%row_start(row)
            end do
            allocate (ri(m), ci(m), vi(m))
            m = 0
            do jb = 1, nb
                row = reduced%boundary(jb)
                do k = a%row_start(row), a%row_start(row + 1) - 1
                    m = m + 1
                    ri(m) = jb
                    ci(m) = a%col(k)
                    vi(m) = a%val(k)
                end do
            end do
            call new_sparse_from_triplets(s, nb, n, ri, ci, vi, error)
        end subroutine boundary_rows

        !> A phase is done: report it (progress) with its wall time since the last one.
        subroutine phase(text)
            character(len=*), intent(in) :: text
            integer(int64) :: now
            call system_clock(now)
            if (present(progress)) call progress%phase("reduction: "//text, &
                real(now - tphase, dp)/real(max(rate, 1_int64), dp))
            tphase = now
        end subroutine phase

        !> The nev lowest fixed-interface eigenpairs (lam ascending, vec M_ii-orthonormal).
        subroutine eigen(nev, lam, vec)
            integer, intent(in) :: nev
            real(dp), allocatable, intent(out) :: lam(:), vec(:, :)
            real(dp), allocatable :: a(:, :), b(:, :), w(:), work(:)
            real(dp) :: wq(1)
            integer :: info, row, k
            if (ni <= dense_interior .or. nev >= ni - 1) then
                allocate (a(ni, ni), b(ni, ni), w(ni))
                a = 0.0_dp
                b = 0.0_dp
                do row = 1, ni
                    do k = kii%row_start(row), kii%row_start(row + 1) - 1
                        a(row, kii%col(k)) = kii%val(k)
                    end do
                    do k = mii%row_start(row), mii%row_start(row + 1) - 1
                        b(row, mii%col(k)) = mii%val(k)
                    end do
                end do
                call dsygv(1, 'V', 'U', ni, a, ni, b, ni, w, wq, -1, info)
                allocate (work(max(1, int(wq(1)))))
                call dsygv(1, 'V', 'U', ni, a, ni, b, ni, w, work, size(work), info)
                if (info /= 0) then
                    call fatal_error(error, "craig_bampton: dense fixed-interface "// &
                                     "eigenproblem failed (dsygv info "//itoa(info)//"; "// &
                                     "is M_ii positive definite?)", stickslip_stat%numerical)
                    return
                end if
                lam = w(1:nev)
                vec = a(:, 1:nev)
            else
                call sparse_eigenpairs(ni, kiit%row_start, kiit%col, kiit%val, &
                                       miit%row_start, miit%col, miit%val, nev, 0.0_dp, &
                                       eopts, lam, vec, erep, error, factorization=lu)
                if (allocated(error)) error%message = "craig_bampton: fixed-interface "// &
                    "modes: "//error%message
            end if
        end subroutine eigen

        !> T^T A T (nr x nr) by sparse products with the columns of T.
        subroutine project(a, r)
            type(sparse_matrix_t), intent(in) :: a
            real(dp), allocatable, intent(out) :: r(:, :)
            allocate (at(n, nr))
            call sparse_times_block(a, t, at)
            r = mat_tmul(t, at)
            r = 0.5_dp*(r + transpose(r))
            deallocate (at)
        end subroutine project

        !> T^T K T (nr x nr) from the basis' structure: the constraint columns of K T vanish on
        !> the interior (K_ii Phi_c + K_ib = 0, to the solve's roundoff), so their part is
        !> the boundary rows of K T (K_bb + K_bi Phi_c, the Schur complement, and K_bi Phi_n,
        !> K_bi Psi), and the dense product over the interior is formed for the modal and
        !> load columns only (nr x (nm + nl) instead of nr x nr).
        subroutine project_stiffness(r)
            real(dp), allocatable, intent(out) :: r(:, :)
            real(dp), allocatable :: kt(:, :), kti(:, :)
            type(sparse_matrix_t) :: kb
            allocate (r(nr, nr), kt(nb, nr))
            r = 0.0_dp
            ! the boundary rows of K T: K's boundary rows (nb x n) times T
            call boundary_rows(kmat, kb)
            if (allocated(error)) return
            call sparse_times_block(kb, t, kt)
            r(1:nb, :) = kt
            deallocate (kt)
            if (nr > nb) then
                allocate (kt(n, nr - nb))
                call sparse_times_block(kmat, t(:, nb + 1:nr), kt)
                kti = kt(reduced%interior, :)
                deallocate (kt)
                r(1:nb, nb + 1:) = r(1:nb, nb + 1:) + mat_tmul(reduced%constraint, kti)
                if (nm > 0) r(nb + 1:nb + nm, nb + 1:) = r(nb + 1:nb + nm, nb + 1:) + &
                                                         mat_tmul(reduced%modes, kti)
                if (nl > 0) r(nb + nm + 1:, nb + 1:) = r(nb + nm + 1:, nb + 1:) + &
                                                       mat_tmul(reduced%loads, kti)
            end if
            r = 0.5_dp*(r + transpose(r))
        end subroutine project_stiffness

        !> Error: an explicit max_frequency with more modes below it than max_modes.
        subroutine too_many_below(count)
            integer, intent(in) :: count
            call fatal_error(error, "craig_bampton: options%max_frequency = "// &
                             real_text(options%max_frequency, '(es10.3e3)')//" rad/s: about "// &
                             itoa(min(count, ni))//" fixed-interface modes lie below "// &
                             "it (estimated "// &
                             "from the lowest ones), more than options%max_modes = "// &
                             itoa(options%max_modes)//" a reduction keeps: lower it, or "// &
                             "give the number of modes", stickslip_stat%input)
        end subroutine too_many_below
    end subroutine craig_bampton

end module stickslip_reduction
