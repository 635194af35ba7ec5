!> The exact condensation of a sparse model onto its contacts (&reduction method = 'none' for
!> models from files): the dynamics_t of stickslip_dynamics, built with sparse LU
!> factorizations (UMFPACK, stickslip_umfpack) instead of dense ones.
!>
!> Per harmonic h > 0 of the basis: one complex LU of Z_h = K - (h omega)^2 M + i h omega C
!> (the pattern of K + M + C analysed once, refactorized per harmonic; one factorization is
!> held at a time), one solve with the n_c + 1 right-hand sides [F_h, W], and from the N x
!> (n_c + 1) solution only what the weighted residual needs: V0_h and G_h (n_c sized), the
!> rows of X0_h and Y_h of the `kept` DOFs (contacts, forced and output DOFs), and two small
!> Gram matrices that make the energy balance exact without the N-row response
!> (dynamics_t%damping_gram, forcing_gram). The static term (h = 0) uses the real LU of K.
!> Memory: the factors of one Z_h plus O(N n_c) work, never N x n_c x nharm.
!>
!> Conditioning (dynamics_t%relative_conditioning, the resonance diagnostics): the smallest
!> singular values are estimated by inverse iteration (inverse_iterations steps of
!> x <- A^-1 x / ||A^-1 x||_2 from a fixed pseudo-random start; s ~ 1 / ||A^-1 x||_2), on the
!> held factorization: a few solves, no extra factorization for Z_h, one real LU each of K
!> and M per model (reusable across omega through `singular_values`). The estimate is an
!> upper bound of the 2-norm smallest singular value that converges to it geometrically
!> (ratio: the two smallest |eigenvalues| of A) for a normal A (symmetric K, M, C):
!> near a resonance, where the diagnostics matter, the gap is large and it is sharp. The
!> dense path uses LAPACK's 1-norm estimates instead; the two agree within a factor ~sqrt(N)
!> at worst, far inside the decades between the thresholds. The static rcond of K is
!> s(K) / ||K||_1.
module stickslip_sparse_dynamics
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_sparse, only: sparse_matrix_t, sparse_scaled_sum, sparse_transpose
    use stickslip_sparse_model, only: sparse_model_t, sparse_directions, sparse_load
    use stickslip_basis, only: basis_t
    use stickslip_dynamics, only: dynamics_t, check_harmonics_in_basis, singular_threshold, &
        static_singular_threshold
    use stickslip_umfpack, only: sparse_lu_t, sparse_zlu_t, ordering_metis
    use stickslip_progress, only: progress_t
    implicit none
    private
    public :: new_sparse_dynamics, sparse_contact_mobility, inverse_iterations

    !> Steps of the inverse iteration that estimates a smallest singular value.
    integer, parameter :: inverse_iterations = 6

    !> K, M, C on the union of their patterns, compressed sparse column (1-based).
    type :: z_pattern_t
        integer :: n = 0
        integer, allocatable :: colptr(:), rowind(:)
        real(dp), allocatable :: k(:), m(:), c(:)
    end type z_pattern_t

contains

    !> Condense `smodel` exactly on `basis` (see the module header), keeping the rows of
    !> X0_h, Y_h of the DOFs `kept` (each in 1..N, in the order given; dynamics_t%kept).
    !> The result is a dynamics_t as new_dynamics builds it, except that x0, y, x0_static,
    !> y_static hold only the kept rows and damping_gram, forcing_gram are set.
    !> Errors: stat input (a forcing harmonic not in the basis, a kept DOF out of range, a
    !> bad pattern); stat numerical ("the stiffness matrix K is singular ..." when the basis
    !> has the constant, "undamped resonance at harmonic h ...", M singular, an UMFPACK
    !> failure such as out of memory). `singular_values` = [smin_k, smin_m] of an earlier
    !> call for the same M and K skips their two factorizations; `analysis`, the symbolic
    !> analysis (fill-reducing ordering) of Z_h an earlier call left, skips it: a sweep
    !> analyses the pattern once and factorizes per harmonic and frequency. The
    !> factorizations are ordered by METIS nested dissection (less fill on FE meshes than
    !> AMD: 6.3e7 against 8.9e7 entries in the factors of the Rotor 37 blade's K_ii).
    !> `progress`, when its unit is on, gets a line per harmonic ('stickslip: exact
    !> condensation h/n harmonics, h = ..., s').
    subroutine new_sparse_dynamics(self, smodel, basis, kept, error, singular_values, &
                                   with_omega_derivative, analysis, progress)
        !> The condensed dynamics.
        type(dynamics_t), intent(out) :: self
        !> A validated sparse model.
        type(sparse_model_t), intent(in) :: smodel
        !> The harmonic basis.
        type(basis_t), intent(in) :: basis
        !> The DOFs whose response rows are kept.
        integer, intent(in) :: kept(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> [smin_k, smin_m] from a dynamics of the same M and K.
        real(dp), intent(in), optional :: singular_values(2)
        !> Also dv0 and dg, the omega derivatives of V0_h and G_h (as new_dynamics; n_c + 1
        !> more solves per harmonic), for a continuation in omega.
        logical, intent(in), optional :: with_omega_derivative
        !> The analysis of Z_h's pattern from an earlier call for the same model (any omega),
        !> reused and updated (empty or of another order: analysed here and kept).
        type(sparse_zlu_t), intent(inout), optional, target :: analysis
        !> Progress of the harmonics (the host's unit; label and items set here).
        type(progress_t), intent(in), optional :: progress
        type(progress_t) :: hprog
        logical :: reuse
        type(z_pattern_t) :: pat
        type(sparse_lu_t) :: klu
        type(sparse_zlu_t), target :: own
        !> The factorization worked on: the caller's analysis, or this call's own.
        type(sparse_zlu_t), pointer :: zlu
        real(dp), allocatable :: w(:, :), rrhs(:, :), rsol(:, :)
        complex(dp), allocatable :: rhs(:, :), xs(:, :), cx(:, :), z(:), dx(:, :), mx(:, :)
        logical :: deriv
        complex(dp) :: ihw
        real(dp) :: knorm, smin_k, smin_m, smin_z, zscale, rel, rcond, homega
        integer :: n, nc, nk, ih, h, j
        logical :: k_factorized
        character(len=512) :: buf

        n = smodel%model%ndof
        ! the force channels (the contacts of a plain model)
        w = sparse_directions(smodel)
        nc = size(w, 2)
        nk = size(kept)
        if (smodel%model%nforce() > 0) then
            call check_harmonics_in_basis(smodel%model%force_harmonic, basis, error)
            if (allocated(error)) return
        end if
        if (any(kept < 1 .or. kept > n)) then
            call fatal_error(error, "new_sparse_dynamics: a kept DOF is outside 1.."// &
                             itoa(n), stickslip_stat%input)
            return
        end if
        self%ndof = n
        self%ncontact = nc
        self%omega = smodel%model%omega
        self%kept = kept
        self%harm = basis%harm(1:basis%nharm)
        allocate (self%rel(basis%nharm))
        allocate (self%x0(nk, basis%nharm), self%y(nk, nc, basis%nharm))
        allocate (self%v0(nc, basis%nharm), self%g(nc, nc, basis%nharm))
        allocate (self%damping_gram(nc + 1, nc + 1, basis%nharm), &
                  self%forcing_gram(nc + 1, basis%nharm))
        deriv = .false.
        if (present(with_omega_derivative)) deriv = with_omega_derivative
        if (deriv) allocate (self%dv0(nc, basis%nharm), self%dg(nc, nc, basis%nharm))

        call build_pattern(smodel, pat, error)
        if (allocated(error)) return

        ! the smallest singular values of K and M (0 when singular)
        k_factorized = .false.
        if (present(singular_values)) then
            smin_k = singular_values(1)
            smin_m = singular_values(2)
        else
            klu%ordering = ordering_metis
            call smallest_singular_real(pat, pat%k, smin_k, klu)
            k_factorized = klu%factorized()
            block
                type(sparse_lu_t) :: mlu
                mlu%ordering = ordering_metis
                call smallest_singular_real(pat, pat%m, smin_m, mlu)
                call mlu%release()
            end block
        end if
        self%smin_k = smin_k
        self%smin_m = smin_m
        self%relative_conditioning = 1.0_dp

        if (basis%has_zero) then
            if (.not. k_factorized) then
                call klu%factorize(n, pat%colptr, pat%rowind, pat%k, error)
                if (allocated(error)) then
                    if (error%stat /= stickslip_stat%numerical) return
                    deallocate (error)
                end if
            end if
            knorm = column_norm(pat, pat%k)
            rcond = 0.0_dp
            if (klu%factorized() .and. knorm > 0.0_dp) rcond = smin_k/knorm
            if (.not. (rcond >= static_singular_threshold)) then
                call klu%release()
                write (buf, '(a,es10.2e3,a)') "the stiffness matrix K is singular (rcond = ", &
                    rcond, "): the static (zeroth-harmonic) response is undetermined; "// &
                    "restrain the rigid-body motion or set &hbm odd_only = .true."
                call fatal_error(error, trim(buf), stickslip_stat%numerical)
                return
            end if
            allocate (rrhs(n, nc + 1), rsol(n, nc + 1))
            rrhs(:, 1) = real(sparse_load(smodel, 0), dp)
            rrhs(:, 2:) = w
            call klu%solve(rrhs, rsol, error)
            if (allocated(error)) return
            self%x0_static = rsol(kept, 1)
            self%y_static = rsol(kept, 2:)
            self%g_static = matmul(transpose(w), rsol(:, 2:))
            self%u_static = matmul(rsol(:, 1), w)
            deallocate (rrhs, rsol)
        end if
        call klu%release()

        allocate (rhs(n, nc + 1), xs(n, nc + 1), z(size(pat%k)))
        reuse = .false.
        zlu => own
        if (present(analysis)) then
            zlu => analysis
            reuse = analysis%analysed() .and. analysis%n == n
        end if
        zlu%ordering = ordering_metis
        if (present(progress)) hprog = progress%stage('exact condensation', 'harmonics')
        do ih = 1, basis%nharm
            h = basis%harm(ih)
            homega = h*smodel%model%omega
            z = cmplx(pat%k - homega**2*pat%m, homega*pat%c, dp)
            if (ih == 1 .and. .not. reuse) then
                call zlu%factorize(n, pat%colptr, pat%rowind, z, error)
            else
                call zlu%refactorize(z, error)
            end if
            smin_z = 0.0_dp
            if (allocated(error)) then
                ! an exactly singular Z_h is the resonance reported below
                if (error%stat /= stickslip_stat%numerical .or. &
                    index(error%message, "singular") == 0) then
                    call zlu%release()
                    return
                end if
                deallocate (error)
            else
                ! the estimate needs no iterative refinement of its solves
                j = zlu%refinement_steps
                zlu%refinement_steps = 0
                smin_z = smallest_singular_complex(zlu, n)
                zlu%refinement_steps = j
            end if
            zscale = smin_k + homega**2*smin_m
            rel = 0.0_dp
            if (zscale > 0.0_dp) rel = smin_z/zscale
            self%rel(ih) = rel
            if (rel < self%relative_conditioning) then
                self%relative_conditioning = rel
                self%worst_harmonic = h
            end if
            if (.not. (rel >= singular_threshold)) then
                call zlu%release()
                write (buf, '(a,i0,a,g0.6,a,es10.2e3,a)') "undamped resonance at harmonic h = ", &
                    h, " (h omega = ", homega, " rad/s): the dynamic stiffness "// &
                    "K - (h omega)^2 M + i h omega C is singular (relative conditioning ", &
                    rel, "): the weighted residual cannot condense the structure there (the "// &
                    "friction may still hold it: implicit Euler and the exact reference "// &
                    "integrate in time). Add damping or move omega"
                call fatal_error(error, trim(buf), stickslip_stat%numerical)
                return
            end if
            rhs(:, 1) = sparse_load(smodel, h)
            rhs(:, 2:) = cmplx(w, 0.0_dp, dp)
            call zlu%solve(rhs, xs, error)
            if (allocated(error)) then
                call zlu%release()
                return
            end if
            ihw = cmplx(0.0_dp, homega, dp)
            do j = 1, nc
                self%v0(j, ih) = ihw*sum(w(:, j)*xs(:, 1))
                self%g(j, :, ih) = ihw*matmul(w(:, j), xs(:, 2:))
            end do
            self%x0(:, ih) = xs(kept, 1)
            self%y(:, :, ih) = xs(kept, 2:)
            call damping_times(smodel%damping, xs, cx)
            self%damping_gram(:, :, ih) = matmul(conjg(transpose(xs)), cx)
            self%forcing_gram(:, ih) = matmul(conjg(rhs(:, 1)), xs)
            if (deriv) then
                ! Z^-1 (dZ/domega) X, dZ/domega = -2 h^2 omega M + i h C (as new_dynamics)
                call damping_times(smodel%mass, xs, mx)
                if (.not. allocated(dx)) allocate (dx(n, nc + 1))
                call zlu%solve(-2.0_dp*h*h*smodel%model%omega*mx + &
                               cmplx(0.0_dp, real(h, dp), dp)*cx, dx, error)
                if (allocated(error)) then
                    call zlu%release()
                    return
                end if
                do j = 1, nc
                    self%dv0(j, ih) = cmplx(0.0_dp, real(h, dp), dp)*sum(w(:, j)*xs(:, 1)) &
                                      - ihw*sum(w(:, j)*dx(:, 1))
                    self%dg(j, :, ih) = cmplx(0.0_dp, real(h, dp), dp)* &
                                        matmul(w(:, j), xs(:, 2:)) - ihw*matmul(w(:, j), dx(:, 2:))
                end do
            end if
            if (present(progress)) then
                write (buf, '(a,i0,a,g0.6,a)') "h = ", h, " (h omega = ", homega, " rad/s)"
                call hprog%report(ih, basis%nharm, trim(buf))
            end if
        end do
        if (present(analysis)) then
            ! the factors go, the ordering stays for the next frequency
            call zlu%release_numeric()
        else
            call zlu%release()
        end if
    end subroutine new_sparse_dynamics

    !> The resonance-free mobility of every contact, Omega w_j^T (K + Omega^2 M)^{-1} w_j
    !> [m/(N s)] at Omega = h_f omega (h_f: the harmonic of the largest forcing term, 1 when
    !> the forcing is static), with the mass-line fallback w_j^T M^{-1} w_j / Omega; the
    !> sparse twin of stickslip_rho's contact_mobility (one real LU of K + Omega^2 M).
    !> Errors: stat numerical when M cannot be factorized either.
    subroutine sparse_contact_mobility(smodel, mob, error)
        !> A validated sparse model.
        type(sparse_model_t), intent(in) :: smodel
        !> Mobility of each contact (of each force channel with contact laws) [m/(N s)].
        real(dp), allocatable, intent(out) :: mob(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(z_pattern_t) :: pat
        type(sparse_lu_t) :: lu
        real(dp), allocatable :: w(:, :), y(:, :)
        real(dp) :: big, big_omega
        integer :: i, j, hf, nc
        ! the force channels (the contacts of a plain model)
        w = sparse_directions(smodel)
        nc = size(w, 2)
        allocate (mob(nc))
        if (nc == 0) return
        hf = 1
        big = 0.0_dp
        associate (m => smodel%model)
            do i = 1, m%nforce()
                if (m%force_harmonic(i) > 0 .and. abs(m%force_amplitude(i)) > big) then
                    big = abs(m%force_amplitude(i))
                    hf = m%force_harmonic(i)
                end if
            end do
            big_omega = hf*m%omega
        end associate
        call build_pattern(smodel, pat, error)
        if (allocated(error)) return
        allocate (y(size(w, 1), nc))
        mob = -1.0_dp
        call lu%factorize(pat%n, pat%colptr, pat%rowind, pat%k + big_omega**2*pat%m, error)
        if (.not. allocated(error)) call lu%solve(w, y, error)
        if (.not. allocated(error)) then
            do j = 1, nc
                mob(j) = big_omega*dot_product(w(:, j), y(:, j))
            end do
        end if
        if (allocated(error)) deallocate (error)
        call lu%release()
        if (all(mob > 0.0_dp .and. mob <= huge(1.0_dp))) return
        call lu%factorize(pat%n, pat%colptr, pat%rowind, pat%m, error)
        if (allocated(error)) return
        call lu%solve(w, y, error)
        call lu%release()
        if (allocated(error)) return
        do j = 1, nc
            if (mob(j) > 0.0_dp .and. mob(j) <= huge(1.0_dp)) cycle
            mob(j) = dot_product(w(:, j), y(:, j))/big_omega
        end do
    end subroutine sparse_contact_mobility

    !> K, M, C on the union of their patterns in compressed sparse column form (the CSR
    !> of each transposed; explicit zeros where a matrix has no entry).
    subroutine build_pattern(smodel, pat, error)
        type(sparse_model_t), intent(in) :: smodel
        type(z_pattern_t), intent(out) :: pat
        type(error_type), allocatable, intent(out) :: error
        type(sparse_matrix_t) :: u, u1
        call sparse_scaled_sum(1.0_dp, smodel%stiffness, 1.0_dp, smodel%mass, u1, error)
        if (allocated(error)) return
        if (smodel%damping%nnz() > 0) then
            call sparse_scaled_sum(1.0_dp, u1, 1.0_dp, smodel%damping, u, error)
            if (allocated(error)) return
        else
            u = u1
        end if
        pat%n = smodel%model%ndof
        call on_pattern(smodel%stiffness, pat%k, .true.)
        if (allocated(error)) return
        call on_pattern(smodel%mass, pat%m, .false.)
        if (allocated(error)) return
        if (smodel%damping%nnz() > 0) then
            call on_pattern(smodel%damping, pat%c, .false.)
        else
            allocate (pat%c(size(pat%k)))
            pat%c = 0.0_dp
        end if

    contains

        subroutine on_pattern(a, values, keep_pattern)
            type(sparse_matrix_t), intent(in) :: a
            real(dp), allocatable, intent(out) :: values(:)
            logical, intent(in) :: keep_pattern
            type(sparse_matrix_t) :: s, t
            call sparse_scaled_sum(1.0_dp, a, 0.0_dp, u, s, error)
            if (allocated(error)) return
            call sparse_transpose(s, t)
            call move_alloc(t%val, values)
            if (keep_pattern) then
                call move_alloc(t%row_start, pat%colptr)
                call move_alloc(t%col, pat%rowind)
            end if
        end subroutine on_pattern
    end subroutine build_pattern

    !> max_j sum_i |a_ij| of values on the pattern.
    pure real(dp) function column_norm(pat, values) result(s)
        type(z_pattern_t), intent(in) :: pat
        real(dp), intent(in) :: values(:)
        integer :: j
        s = 0.0_dp
        do j = 1, pat%n
            s = max(s, sum(abs(values(pat%colptr(j):pat%colptr(j + 1) - 1))))
        end do
    end function column_norm

    !> The fixed pseudo-random start of the inverse iterations (entries in [-0.5, 0.5)).
    pure function start_vector(n) result(x)
        integer, intent(in) :: n
        real(dp) :: x(n)
        integer :: i
        do i = 1, n
            x(i) = modulo(real(i, dp)*0.6180339887498949_dp + 0.1_dp, 1.0_dp) - 0.5_dp
        end do
        x = x/norm2(x)
    end function start_vector

    !> Factorize the real matrix `values` (on the pattern) into `lu` and estimate its
    !> smallest singular value by inverse iteration (0 when singular; `lu` is then not
    !> factorized). The caller releases `lu`.
    subroutine smallest_singular_real(pat, values, smin, lu)
        type(z_pattern_t), intent(in) :: pat
        real(dp), intent(in) :: values(:)
        real(dp), intent(out) :: smin
        type(sparse_lu_t), intent(inout) :: lu
        type(error_type), allocatable :: error
        real(dp) :: x(pat%n), y(pat%n)
        integer :: it
        smin = 0.0_dp
        call lu%factorize(pat%n, pat%colptr, pat%rowind, values, error)
        if (allocated(error)) then
            call lu%release()
            return
        end if
        x = start_vector(pat%n)
        do it = 1, inverse_iterations
            call lu%solve(x, y, error)
            if (allocated(error)) exit
            if (.not. (norm2(y) > 0.0_dp) .or. norm2(y) > huge(1.0_dp)) exit
            smin = 1.0_dp/norm2(y)
            x = y*smin
        end do
        if (allocated(error)) smin = 0.0_dp
    end subroutine smallest_singular_real

    !> Smallest singular value of the factorized complex matrix by inverse iteration.
    function smallest_singular_complex(lu, n) result(smin)
        type(sparse_zlu_t), intent(inout) :: lu
        integer, intent(in) :: n
        real(dp) :: smin
        complex(dp) :: x(n), y(n)
        type(error_type), allocatable :: error
        integer :: it
        smin = 0.0_dp
        x = cmplx(start_vector(n), 0.0_dp, dp)
        do it = 1, inverse_iterations
            call lu%solve(x, y, error)
            if (allocated(error)) then
                smin = 0.0_dp
                return
            end if
            if (.not. (norm2c(y) > 0.0_dp) .or. norm2c(y) > huge(1.0_dp)) return
            smin = 1.0_dp/norm2c(y)
            x = y*smin
        end do
    end function smallest_singular_complex

    pure real(dp) function norm2c(x)
        complex(dp), intent(in) :: x(:)
        norm2c = sqrt(norm2(real(x, dp))**2 + norm2(aimag(x))**2)
    end function norm2c

    !> cx = C x for the columns of x (C in CSR, e.g. the damping or the mass; empty C gives 0).
    subroutine damping_times(c, x, cx)
        type(sparse_matrix_t), intent(in) :: c
        complex(dp), intent(in) :: x(:, :)
        complex(dp), allocatable, intent(inout) :: cx(:, :)
        integer :: i, p
        if (.not. allocated(cx)) allocate (cx(size(x, 1), size(x, 2)))
        cx = (0.0_dp, 0.0_dp)
        if (c%nnz() == 0) return
        do i = 1, c%nrows
            do p = c%row_start(i), c%row_start(i + 1) - 1
                cx(i, :) = cx(i, :) + c%val(p)*x(c%col(p), :)
            end do
        end do
    end subroutine damping_times
end module stickslip_sparse_dynamics
