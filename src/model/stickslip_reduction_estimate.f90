!> The reduction error of a Craig-Bampton model, estimated without factorizing the full
!> dynamic stiffness: the same measure as receptance_error (max over the frequencies of
!> max|G_r - G| / max|G|, G = W^T Z^-1 W the contact receptance of the full model, G_r that
!> of the reduced one, Z = K - w^2 M + i w C), with the full model's G replaced by that of
!> an enriched Galerkin model whose error is checked to be small against the one measured.
!>
!> The enrichment (a block Krylov sequence on the factorization of K_ii the reduction made,
!> the "residual flexibility" of the modes left out): with the boundary fixed, the interior
!> response the basis T lacks is that of the modes above the kept ones to the inertia
!> (and damping) loads of the constraint modes and the load vectors. Level 1 adds
!> V_1 = K_ii^-1 [M T]_i (and K_ii^-1 [C T]_i for a damping matrix that is not
!> alpha M + beta K), level l the images K_ii^-1 M_ii V_(l-1) (and with C), each
!> M_ii-orthogonalized against the kept modes, the load vectors and the levels before
!> (modal columns give nothing new: K_ii^-1 M_ii Phi_n = Phi_n Lambda^-1). The Galerkin
!> model on [T, V_1 .. V_l] is computed for every frequency (dense, small), its receptance
!> G_l. The error of G_l falls like (w / w_(nm+1))^(2 l + 2) while that of G_r is of order
!> (w / w_(nm+1))^2, so e_l = max|G_r - G_l| / max|G_l| converges to the true error; the
!> estimate is accepted at the first level l >= 2 where |e_l - e_(l-1)| <= 0.1 e_l + 1e-9
!> at every frequency. With e_l = E (1 - q^l) that says q <= 0.11 at l = 2 (the error
!> left, E q^l, within 1.2 % of the estimate) and q <= 0.43 at l = 4 (within 4 %); with the
!> mode-count rule q is about (5 omega / (3 H omega))^2 <= 0.11. When an error frequency
!> reaches half the first mode left out (q >= 1/4: modes = 2 asked with a high forcing
!> frequency), or the levels do not agree within max_levels, the exact measure runs
!> instead (receptance_error: a complex sparse LU of the full model per frequency).
!> Response-seeded first level: with many boundary DOFs (a sector's cyclic faces) and few
!> contact directions and frequencies, the first level is seeded with the loads of the
!> boundary motions the contact loads actually make instead of every constraint mode: V_1 =
!> K_ii^-1 [M T]_i Q (and [C T]_i Q), Q the real and imaginary parts of the reduced model's
!> responses q_r = Z_r^-1 T^T W at every frequency (2 n_c n_f columns), used when that is
!> fewer columns than nb + nl. The span then lacks only the interior's dynamic response to
!> the boundary motion's own error (of the order of the reduction's error d in the
!> response), so the enriched response is off by about d q and, the receptance of a
!> Galerkin model being off by the square of its response's error (G - G_S = e^T Z e), the
!> estimate by about q^2 of itself (q <= 0.11: 1.2 %), as with the full seeds at level 2;
!> tested against the exact measure on the CalculiX sector with its faces
!> (test_reduction_estimate) and on its refinements of 10^4 DOFs and more (doc/cyclic.md).
!> Cost: (nb + nl) real solves per level (2 n_c n_f response-seeded) with the held
!> factorization and sparse products, whatever the number of frequencies (Rotor 37 blade,
!> 61098 DOFs, 17 boundary DOFs, 3 frequencies: about 4 s per level, two levels), against
!> one complex sparse LU of the full model per frequency (about 25-35 s each there); a
!> 33414-DOF sector with 1083 boundary DOFs: 1.6 s response-seeded, 62 s with every
!> constraint mode.
!>
!> Knows nothing of case files; the caller (stickslip_case_reduction) decides when to run it.
module stickslip_reduction_estimate
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa, real_text
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_transpose, &
        sparse_times_block
    use stickslip_block_lanczos, only: m_orthonormalize
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_stiffness_factor, only: factorize_stiffness
    use stickslip_lapack, only: zgesv
    use stickslip_dense_products, only: mat_mul, mat_tmul
    use stickslip_reduced_model, only: reduced_model_t
    use stickslip_reduction_error, only: receptance_error
    use stickslip_progress, only: progress_t
    implicit none
    private
    public :: reduction_estimate_t, estimate_reduction_error, estimate_max_levels

    !> Most enrichment levels before the exact measure takes over.
    integer, parameter :: estimate_max_levels = 4
    !> Two levels agree when |e_l - e_(l-1)| <= agreement e_l + floor (relative to max|G|).
    real(dp), parameter :: agreement = 0.1_dp, agreement_floor = 1.0e-9_dp
    !> The exact measure runs at once when an error frequency exceeds this fraction of the
    !> first mode left out (or of the highest kept when that is not known).
    real(dp), parameter :: frequency_fraction = 0.5_dp
    !> An enrichment vector is dropped when less than this fraction of its M_ii-norm is left
    !> after the orthogonalization (it lies in the span of the others).
    real(dp), parameter :: drop_tolerance = 1.0e-8_dp

    !> What an error estimate found and how.
    type :: reduction_estimate_t
        !> max over the frequencies of max|G_r - G| / max|G| (-1: not estimated).
        real(dp) :: error = -1.0_dp
        !> The same per frequency.
        real(dp), allocatable :: frequency_errors(:)
        !> 'enriched' (the enriched Galerkin model, levels agreed), 'sparse LU' (the exact
        !> measure, receptance_error), 'none' (no contact direction or frequency).
        character(len=16) :: method = 'none'
        !> Enrichment levels computed, and the vectors they added.
        integer :: levels = 0
        integer :: vectors = 0
        !> The first level was seeded by the reduced model's responses to the contact
        !> directions, not by every column of the basis (fewer vectors; module header).
        logical :: response_seeded = .false.
        !> |e_l - e_(l-1)| of the last two levels (the estimate's own uncertainty, relative
        !> to max|G| as the error), at the worst frequency.
        real(dp) :: change = 0.0_dp
        !> Why the exact measure ran ('' when it did not).
        character(len=:), allocatable :: fallback
        !> Wall time [s].
        real(dp) :: seconds = 0.0_dp
    end type reduction_estimate_t

contains

    !> Estimate the reduction error of `reduced` (a Craig-Bampton model of K, M, C with its
    !> basis) for the contact directions W (N x n_c, nonzero on boundary DOFs only) at
    !> `frequencies` (see the module header). `interior_lu`, when given factorized, is the
    !> factorization of K_ii in the reduction's interior numbering (craig_bampton's
    !> interior_lu); otherwise K_ii is factorized here. `proportional` (default .false.):
    !> C = alpha M + beta K, so no damping vectors are needed; `rayleigh` = [alpha, beta]
    !> says the same with the factors, and the enriched C is then alpha M + beta K of the
    !> enriched M and K (no sparse products with C). Errors (input): W with the
    !> wrong number of rows or an interior entry, a model without its basis; (numerical):
    !> K_ii singular, the exact measure failing.
    subroutine estimate_reduction_error(kmat, mmat, reduced, directions, frequencies, &
                                        estimate, error, cmat, proportional, interior_lu, &
                                        progress, rayleigh)
        !> Full stiffness K, N x N.
        type(sparse_matrix_t), intent(in) :: kmat
        !> Full mass M.
        type(sparse_matrix_t), intent(in) :: mmat
        !> The reduced model with its basis.
        type(reduced_model_t), intent(in) :: reduced
        !> Contact directions W, N x n_c.
        real(dp), intent(in) :: directions(:, :)
        !> Frequencies w [rad/s].
        real(dp), intent(in) :: frequencies(:)
        !> The estimate.
        type(reduction_estimate_t), intent(out) :: estimate
        !> Error (last non-optional).
        type(error_type), allocatable, intent(out) :: error
        !> Full damping C (optional).
        type(sparse_matrix_t), intent(in), optional :: cmat
        !> C is alpha M + beta K (no damping vectors needed).
        logical, intent(in), optional :: proportional
        !> The factorization of K_ii (used when factorized; left as given).
        class(sparse_factor_t), allocatable, intent(inout), optional :: interior_lu
        !> Where the phases are reported (optional).
        type(progress_t), intent(inout), optional :: progress
        !> [alpha, beta] [1/s, s]: cmat is alpha M + beta K (optional; only with cmat).
        real(dp), intent(in), optional :: rayleigh(2)
        class(sparse_factor_t), allocatable :: own_lu
        integer(int64) :: t0, t1, rate
        integer :: n, nb, ni, nr, nc, nf, level, f, k, nv, nlev, nold
        integer, allocatable :: loc(:)
        logical :: damped, with_c, accepted
        real(dp), allocatable :: wb(:, :), v(:, :), newv(:, :), mv(:, :), cv(:, :)
        real(dp), allocatable :: kred(:, :), mred(:, :), cred(:, :), kz(:, :), mz(:, :), &
                                 cz(:, :), ma(:, :), ca(:, :), ef(:, :), base(:, :), &
                                 seeds(:, :), mbase(:, :), q(:, :), tq(:, :)
        complex(dp), allocatable :: gr(:, :), g(:, :), qf(:, :)
        real(dp) :: gmax, last_change, exact

        call system_clock(t0, rate)
        n = reduced%n
        nb = reduced%nb
        nr = reduced%nr
        ni = n - nb
        nc = size(directions, 2)
        nf = size(frequencies)
        if (.not. allocated(reduced%constraint) .or. .not. allocated(reduced%interior)) then
            call fatal_error(error, "reduction error estimate: the reduced model has no "// &
                             "basis", stickslip_stat%input)
            return
        end if
        if (size(directions, 1) /= n .or. kmat%nrows /= n .or. mmat%nrows /= n) then
            call fatal_error(error, "reduction error estimate: directions has "// &
                             itoa(size(directions, 1))//" rows and K "//itoa(kmat%nrows)// &
                             ", must be "//itoa(n), stickslip_stat%input)
            return
        end if
        do k = 1, nc
            if (any(directions(reduced%interior, k) /= 0.0_dp)) then
                call fatal_error(error, "reduction error estimate: contact "//itoa(k)// &
                                 " has a direction on interior DOF "// &
                                 itoa(reduced%interior(findloc(directions(reduced%interior, k) &
                                                               /= 0.0_dp, .true., 1)))// &
                                 " (not on the boundary)", stickslip_stat%input)
                return
            end if
        end do
        if (present(rayleigh)) then
            if (.not. (present(cmat) .and. all(ieee_is_finite(rayleigh)))) then
                call fatal_error(error, "reduction error estimate: rayleigh needs cmat and "// &
                                 "finite factors", stickslip_stat%input)
                return
            end if
        end if
        allocate (estimate%frequency_errors(nf))
        estimate%frequency_errors = 0.0_dp
        if (nc == 0 .or. nf == 0) then
            call finish()
            return
        end if
        estimate%error = 0.0_dp
        damped = present(cmat)
        with_c = damped
        if (present(proportional)) with_c = damped .and. .not. proportional
        if (present(rayleigh)) with_c = .false.
        allocate (loc(n))
        loc = 0
        loc(reduced%interior) = [(k, k=1, ni)]
        wb = directions(reduced%boundary, :)
        if (near_left_out()) then
            call exact_measure("an error frequency ("//real_text(maxval(frequencies), &
                               '(es10.3)')//" rad/s) reaches half the first mode left out")
            return
        end if

        ! the interior factorization: the reduction's, or one made here
        if (present(interior_lu)) then
            if (.not. given_factor()) then
                call factorize_interior(own_lu)
                if (allocated(error)) return
            end if
        else
            call factorize_interior(own_lu)
            if (allocated(error)) return
        end if

        ! the Galerkin matrices of T (without the added modal damping)
        kred = reduced%stiffness
        mred = reduced%mass
        cred = reduced%damping
        do k = 1, reduced%nm
            cred(nb + k, nb + k) = cred(nb + k, nb + k) - &
                                   2.0_dp*reduced%modal_damping_ratio*reduced%frequencies(k)
        end do
        ! the reduced model's own receptance per frequency and its responses q_r = Z_r^-1
        ! T^T W (real and imaginary parts, the columns of q)
        allocate (gr(nc, nc*nf), q(nr, 2*nc*nf), qf(nr, nc))
        do f = 1, nf
            call receptance(reduced%stiffness, reduced%mass, reduced%damping, nr, &
                            frequencies(f), gr(:, (f - 1)*nc + 1:f*nc), qf)
            if (allocated(error)) return
            q(:, (f - 1)*2*nc + 1:(f - 1)*2*nc + nc) = real(qf, dp)
            q(:, (f - 1)*2*nc + nc + 1:f*2*nc) = aimag(qf)
        end do
        ! the first level's seeds: the interior inertia (and damping) loads of the basis,
        ! [M T]_i (and [C T]_i); mass: the constraint-mode and load-vector columns only
        ! (K_ii^-1 M_ii Phi_n = Phi_n Lambda^-1 is in the span), damping: every column. Or,
        ! when that is fewer columns, the same loads of the reduced model's responses only,
        ! [M T]_i q (and [C T]_i q): the boundary motions the contact loads make
        ! (`response_seeded`, see the module header)
        estimate%response_seeded = size(q, 2)*merge(2, 1, with_c) < &
                                   nb + reduced%nl + merge(nr, 0, with_c)
        if (estimate%response_seeded) then
            ! [A T]_i q = [A (T q)]_i: one sparse product with the n x 2 n_c n_f block T q
            tq = basis_times(q)
            call interior_products(mmat, tq, seeds, full_length=.true.)
            if (with_c) then
                call interior_products(cmat, tq, ca, full_length=.true.)
                seeds = reshape([seeds, ca], [ni, 2*size(q, 2)])
            end if
        else
            call basis_images(mmat, ma)
            ma = reshape([ma(:, 1:nb), ma(:, nb + reduced%nm + 1:nr)], [ni, nb + reduced%nl])
            if (with_c) then
                call basis_images(cmat, ca)
                seeds = reshape([ma, ca], [ni, size(ma, 2) + nr])
            else
                seeds = ma
            end if
        end if
        ! base: the interior parts of the modes and load vectors (M_ii-orthonormal), then the
        ! enrichment vectors as they are kept
        allocate (base(ni, 0))
        if (reduced%nm > 0) base = reshape([base, reduced%modes], [ni, size(base, 2) + reduced%nm])
        if (reduced%nl > 0) base = reshape([base, reduced%loads], [ni, size(base, 2) + reduced%nl])
        call interior_products(mmat, base, mbase)
        allocate (v(ni, 0), ef(nf, estimate_max_levels))
        nv = 0
        ef = 0.0_dp
        accepted = .false.
        nlev = 0
        last_change = 0.0_dp
        kz = kred
        mz = mred
        if (damped) cz = cred
        do level = 1, estimate_max_levels
            call interior_solves(seeds, newv)
            if (allocated(error)) return
            call orthonormalize(newv, mv)
            if (allocated(error)) return
            nlev = level
            estimate%levels = level
            if (size(newv, 2) > 0) then
                v = reshape([v, newv], [ni, size(v, 2) + size(newv, 2)])
                base = reshape([base, newv], [ni, size(base, 2) + size(newv, 2)])
                mbase = reshape([mbase, mv], [ni, size(mbase, 2) + size(mv, 2)])
            end if
            nold = nv
            nv = size(v, 2)
            estimate%vectors = nv
            ! the enriched Galerkin matrices [T V]^T A [T V], the last level's extended
            call enriched(kmat, kz)
            call enriched(mmat, mz)
            if (damped .and. present(rayleigh)) then
                cz = rayleigh(1)*mz + rayleigh(2)*kz
            else if (damped) then
                call enriched(cmat, cz)
            else
                if (allocated(cz)) deallocate (cz)
                allocate (cz(nr + nv, nr + nv))
                cz = 0.0_dp
            end if
            if (.not. allocated(g)) allocate (g(nc, nc))
            do f = 1, nf
                call receptance(kz, mz, cz, nr + nv, frequencies(f), g)
                if (allocated(error)) return
                gmax = maxval(abs(g))
                if (gmax > 0.0_dp) ef(f, level) = maxval(abs(gr(:, (f - 1)*nc + 1:f*nc) - g))/gmax
            end do
            call report_level()
            if (size(newv, 2) == 0) then
                ! nothing new: the basis holds the exact interior response (every mode)
                accepted = .true.
                exit
            end if
            if (level >= 2) then
                last_change = maxval(abs(ef(:, level) - ef(:, level - 1)))
                if (all(abs(ef(:, level) - ef(:, level - 1)) <= agreement*ef(:, level) + &
                        agreement_floor)) then
                    accepted = .true.
                    exit
                end if
            end if
            ! the next level's seeds: M_ii (and C_ii) times the new vectors (M_ii: from the
            ! orthonormalization)
            if (with_c) then
                call interior_products(cmat, newv, cv)
                seeds = reshape([mv, cv], [ni, 2*size(newv, 2)])
            else
                seeds = mv
            end if
        end do
        estimate%change = last_change
        if (accepted .and. all(ieee_is_finite(ef(:, nlev)))) then
            estimate%method = 'enriched'
            estimate%frequency_errors = ef(:, nlev)
            estimate%error = maxval(ef(:, nlev))
            call release_own()
            call finish()
        else
            call exact_measure("the enrichment levels did not agree within "// &
                               itoa(estimate_max_levels)//" levels")
        end if

    contains

        !> Whether an error frequency reaches frequency_fraction of the first mode left out
        !> (of the highest kept when that is not known; always when neither is).
        logical function near_left_out() result(near)
            real(dp) :: next
            next = reduced%next_frequency
            if (.not. (next > 0.0_dp) .and. reduced%nm > 0) next = reduced%frequencies(reduced%nm)
            if (.not. (next > 0.0_dp)) then
                ! no mode computed (modes = 0 without a rule): the levels decide
                near = .false.
                return
            end if
            near = maxval(frequencies) >= frequency_fraction*next
        end function near_left_out

        !> The exact measure (receptance_error: one complex sparse LU of the full model per
        !> frequency) as the estimate, with why.
        subroutine exact_measure(why)
            character(len=*), intent(in) :: why
            call release_own()
            estimate%fallback = why
            estimate%method = 'sparse LU'
            if (damped) then
                call receptance_error(kmat, mmat, reduced, directions, frequencies, exact, &
                                      error, cmat=cmat, frequency_errors=estimate%frequency_errors)
            else
                call receptance_error(kmat, mmat, reduced, directions, frequencies, exact, &
                                      error, frequency_errors=estimate%frequency_errors)
            end if
            if (allocated(error)) return
            estimate%error = exact
            call finish()
            if (present(progress)) call progress%phase("reduction: error estimate by the "// &
                "exact measure ("//why//"; a complex sparse LU at "//itoa(nf)// &
                " frequencies): "//real_text(exact, '(es9.2)'), estimate%seconds)
        end subroutine exact_measure

        !> The wall time into the estimate.
        subroutine finish()
            call system_clock(t1)
            estimate%seconds = real(t1 - t0, dp)/real(max(rate, 1_int64), dp)
        end subroutine finish

        subroutine release_own()
            if (allocated(own_lu)) call own_lu%release()
        end subroutine release_own

        !> Whether the caller gave a factorization of K_ii.
        logical function given_factor()
            given_factor = .false.
            if (.not. present(interior_lu)) return
            if (.not. allocated(interior_lu)) return
            given_factor = interior_lu%factorized() .and. interior_lu%n == ni
        end function given_factor

        !> One progress line per level.
        subroutine report_level()
            if (.not. present(progress)) return
            call system_clock(t1)
            call progress%phase("reduction: error estimate, level "//itoa(level)//" ("// &
                                itoa(nv)//" vectors): "// &
                                real_text(maxval(ef(:, level)), '(es9.2)'), &
                                real(t1 - t0, dp)/real(max(rate, 1_int64), dp))
        end subroutine report_level

        !> Factorize K_ii here (Cholesky, or LU when it is not positive definite).
        subroutine factorize_interior(lu)
            class(sparse_factor_t), allocatable, intent(inout) :: lu
            type(sparse_matrix_t) :: kii, kiit
            call interior_block(kmat, kii)
            if (allocated(error)) return
            call sparse_transpose(kii, kiit)
            call factorize_stiffness(ni, kiit%row_start, kiit%col, kiit%val, lu, error)
            if (allocated(error)) error%message = "reduction error estimate: K_ii: "// &
                error%message
        end subroutine factorize_interior

        !> The interior-interior block of a (CSR).
        subroutine interior_block(a, s)
            type(sparse_matrix_t), intent(in) :: a
            type(sparse_matrix_t), intent(out) :: s
            integer, allocatable :: ri(:), ci(:)
            real(dp), allocatable :: vi(:)
            integer :: row, kk, m
            allocate (ri(a%nnz()), ci(a%nnz()), vi(a%nnz()))
            m = 0
            do row = 1, n
                if (loc(row) == 0) cycle
                do kk = a%row_start(row), a%row_start(row + 1) - 1
                    if (loc(a%col(kk)) == 0) cycle
                    m = m + 1
                    ri(m) = loc(row)
                    ci(m) = loc(a%col(kk))
                    vi(m) = a%val(kk)
                end do
            end do
            call new_sparse_from_triplets(s, ni, ni, ri(1:m), ci(1:m), vi(1:m), error)
        end subroutine interior_block

        !> K_ii^-1 b for every column of b (ni x m), on the held factorization.
        subroutine interior_solves(b, x)
            real(dp), intent(in) :: b(:, :)
            real(dp), allocatable, intent(out) :: x(:, :)
            allocate (x(ni, size(b, 2)))
            if (size(b, 2) == 0) return
            if (allocated(own_lu)) then
                call own_lu%solve(b, x, error)
            else
                call interior_lu%solve(b, x, error)
            end if
            if (allocated(error)) error%message = "reduction error estimate: "//error%message
        end subroutine interior_solves

        !> [A T]_i: the interior rows of A times the basis T (ni x nr), T = [I 0 0; Phi_c
        !> Phi_n Psi]; modal columns of a mass-like A are kept (their images are in the
        !> span, dropped by the orthogonalization).
        subroutine basis_images(a, at)
            type(sparse_matrix_t), intent(in) :: a
            real(dp), allocatable, intent(out) :: at(:, :)
            real(dp), allocatable :: t(:, :), full(:, :)
            integer :: c
            ! only the constraint-mode and load-vector columns bring new directions for a
            ! mass-like matrix: K_ii^-1 M_ii Phi_n = Phi_n Lambda^-1 (M); for C all columns
            allocate (t(n, nr), full(n, nr))
            t = 0.0_dp
            do c = 1, nb
                t(reduced%boundary(c), c) = 1.0_dp
            end do
            t(reduced%interior, 1:nb) = reduced%constraint
            if (reduced%nm > 0) t(reduced%interior, nb + 1:nb + reduced%nm) = reduced%modes
            if (reduced%nl > 0) t(reduced%interior, nb + reduced%nm + 1:nr) = reduced%loads
            call sparse_times_block(a, t, full)
            at = full(reduced%interior, :)
        end subroutine basis_images

        !> A_ii x for interior vectors x (ni x m); with `full_length` x holds every DOF (n x
        !> m) and y is the interior rows of A x.
        subroutine interior_products(a, x, y, full_length)
            type(sparse_matrix_t), intent(in) :: a
            real(dp), intent(in) :: x(:, :)
            real(dp), allocatable, intent(out) :: y(:, :)
            logical, intent(in), optional :: full_length
            real(dp), allocatable :: xf(:, :), yf(:, :)
            allocate (yf(n, size(x, 2)))
            if (present(full_length)) then
                if (full_length) then
                    call sparse_times_block(a, x, yf)
                    y = yf(reduced%interior, :)
                    return
                end if
            end if
            allocate (xf(n, size(x, 2)))
            xf = 0.0_dp
            xf(reduced%interior, :) = x
            call sparse_times_block(a, xf, yf)
            y = yf(reduced%interior, :)
        end subroutine interior_products

        !> T x for reduced coordinates x (nr x m): every DOF, n x m.
        function basis_times(x) result(y)
            real(dp), intent(in) :: x(:, :)
            real(dp), allocatable :: y(:, :)
            real(dp), allocatable :: part(:, :)
            integer :: nm, nl
            nm = reduced%nm
            nl = reduced%nl
            allocate (y(n, size(x, 2)))
            ! (each block of rows copied: contiguous for dgemm)
            part = x(1:nb, :)
            y(reduced%boundary, :) = part
            y(reduced%interior, :) = mat_mul(reduced%constraint, part)
            if (nm > 0) then
                part = x(nb + 1:nb + nm, :)
                y(reduced%interior, :) = y(reduced%interior, :) + mat_mul(reduced%modes, part)
            end if
            if (nl > 0) then
                part = x(nb + nm + 1:nr, :)
                y(reduced%interior, :) = y(reduced%interior, :) + mat_mul(reduced%loads, part)
            end if
        end function basis_times

        !> The columns of x M_ii-orthogonalized (classical Gram-Schmidt, twice) against
        !> `base` (M_ii-orthonormal, M_ii base in mbase) and M_ii-orthonormalized among
        !> themselves (m_orthonormalize: directions below drop_tolerance of their norm
        !> dropped); x is replaced by the vectors kept, mx returns M_ii times them.
        subroutine orthonormalize(x, mx)
            real(dp), allocatable, intent(inout) :: x(:, :)
            real(dp), allocatable, intent(out) :: mx(:, :)
            integer :: kept
            call interior_products(mmat, x, mx)
            call m_orthonormalize(x, mx, base, mbase, size(base, 2), drop_tolerance, kept, &
                                  error)
        end subroutine orthonormalize

        !> [T V]^T A [T V], (nr + nv)^2, from the last level's (r on entry, (nr + nold)^2:
        !> T^T A T at the first) and the enrichment vectors v (interior only), of which the
        !> columns after nold are new: only their products are formed, T^T A V_new = [ (A
        !> V_new)_b + Phi_c^T (A V_new)_i ; Phi_n^T (A V_new)_i ; Psi^T (A V_new)_i ] and
        !> V^T A V_new = V^T (A V_new)_i, with their transposes (A symmetric).
        subroutine enriched(a, r)
            type(sparse_matrix_t), intent(in) :: a
            real(dp), allocatable, intent(inout) :: r(:, :)
            real(dp), allocatable :: av(:, :), tav(:, :), vf(:, :), avi(:, :), old(:, :), &
                                     vav(:, :)
            integer :: nnew, lo
            nnew = nv - nold
            if (nnew == 0) return
            lo = nr + nold + 1
            call move_alloc(r, old)
            allocate (r(nr + nv, nr + nv), av(n, nnew), tav(nr, nnew))
            r(1:nr + nold, 1:nr + nold) = old
            deallocate (old)
            allocate (vf(n, nnew))
            vf = 0.0_dp
            vf(reduced%interior, :) = v(:, nold + 1:nv)
            call sparse_times_block(a, vf, av)
            deallocate (vf)
            avi = av(reduced%interior, :)
            tav(1:nb, :) = av(reduced%boundary, :) + mat_tmul(reduced%constraint, avi)
            if (reduced%nm > 0) tav(nb + 1:nb + reduced%nm, :) = mat_tmul(reduced%modes, avi)
            if (reduced%nl > 0) tav(nb + reduced%nm + 1:nr, :) = mat_tmul(reduced%loads, avi)
            r(1:nr, lo:) = tav
            r(lo:, 1:nr) = transpose(tav)
            vav = mat_tmul(v, avi)
            r(nr + 1:, lo:) = vav
            r(lo:, nr + 1:) = transpose(vav)
            r(lo:, lo:) = 0.5_dp*(vav(nold + 1:, :) + transpose(vav(nold + 1:, :)))
        end subroutine enriched

        !> The receptance W_b^T Z^-1 W_b (n_c x n_c) of the dense model (k, m, c) of order
        !> `order` whose first nb coordinates are the boundary DOFs, at frequency w.
        subroutine receptance(k, m, c, order, w, gout, sol)
            real(dp), intent(in) :: k(:, :), m(:, :), c(:, :)
            integer, intent(in) :: order
            real(dp), intent(in) :: w
            complex(dp), intent(out) :: gout(:, :)
            !> Z^-1 [W_b; 0] (order x n_c), optional.
            complex(dp), intent(out), optional :: sol(:, :)
            complex(dp), allocatable :: z(:, :), b(:, :)
            integer, allocatable :: ipiv(:)
            integer :: info
            allocate (z(order, order), b(order, nc), ipiv(order))
            z = cmplx(k - w**2*m, w*c, dp)
            b = (0.0_dp, 0.0_dp)
            b(1:nb, :) = cmplx(wb, 0.0_dp, dp)
            call zgesv(order, nc, z, order, ipiv, b, order, info)
            if (info /= 0) then
                call fatal_error(error, "reduction error estimate: a reduced model is "// &
                                 "singular at w = "//real_text(w, '(es12.5)')//" rad/s", &
                                 stickslip_stat%numerical)
                return
            end if
            gout = matmul(transpose(cmplx(wb, 0.0_dp, dp)), b(1:nb, :))
            if (present(sol)) sol = b
        end subroutine receptance
    end subroutine estimate_reduction_error
end module stickslip_reduction_estimate
