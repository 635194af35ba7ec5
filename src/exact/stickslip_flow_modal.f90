!> The phase propagators of the monodromy matrix in the modal form of a linear contact mode
!> (stickslip_flow's recording pass; doc/methods.md, "Floquet stability").
!>
!> A linear phase multiplies the Jacobian of the period map by exp(B tau), B the state block
!> (n_z x n_z, balanced coordinates) of the mode's dynamics and tau the phase's duration.
!> A matrix exponential per phase costs 8 to 11 matrix products on a stiff reduced FE model;
!> with the modal form B_d = V Lambda W (W = V^-1, Lambda real block diagonal: a real
!> eigenvalue a, or a pair a +- i b as the block [a b; -b a]), made once per mode and kept
!> with it (B's state block does not depend on omega), the product is W jac, a rotation and
!> scaling of each row or pair of rows, and V times that: two matrix products.
!>
!> B itself is not diagonalizable in a mode with velocity constraints (a stuck contact): the
!> constrained velocity u_c and its position form a Jordan block at 0 (x_c' = u_c, u_c' = 0).
!> The Jacobian never has a component along u_c in such a mode (the event that entered it
!> projected the velocities onto the constraints, as the start of the period does), and the
!> mode's dynamics keep the constraints, so B may be replaced by B_d = B Pi, Pi the
!> orthogonal projection of the velocities onto C_t^T u = 0: exp(B_d tau) = exp(B tau) on
!> the range of Pi, and B_d is diagonalizable (the static shapes and the constrained
!> velocities are its eigenvectors of eigenvalue 0). The form is used only when it is
!> accurate: dgeev succeeded, V is well conditioned (reciprocal condition >= min_rcond) and
!> V exp(Lambda delta) W agrees with the mode's exponential exp(B delta) (its dyadic
!> ladder's, or a matrix exponential of B when the ladder is not built) on the range of Pi
!> to check_tol; otherwise the caller keeps the matrix exponential.
!> Knows nothing of events or files; no state besides the forms it returns.
module stickslip_flow_modal
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_lapack, only: dgeev, dgetrf, dgetrs, dgecon, dgesv, dgelss
    use stickslip_dense_products, only: mat_mul
    implicit none
    private
    public :: modal_form_t, build_modal_form, modal_propagate, project_velocity_rows, &
        off_constraints, gram_solve, constraint_solve, on_constraints

    !> Largest relative component off a mode's constraints (off_constraints) of the columns
    !> the modal form propagates (a Jacobian, a phase's start state, the forcing columns).
    real(dp), parameter :: on_constraints = 1.0e-10_dp
    !> Smallest reciprocal 1-norm condition number of the eigenvector matrix accepted.
    real(dp), parameter :: min_rcond = 1.0e-8_dp
    !> Largest difference, relative to the largest entry of exp(B delta), between the modal
    !> form's propagator and the mode's exponential over one grid step.
    real(dp), parameter :: check_tol = 1.0e-11_dp
    !> Reciprocal condition number of a constraint matrix below which its constraints are
    !> taken as dependent (constraint_solve), and the singular values dropped then,
    !> relative to the largest.
    real(dp), parameter :: dependent_rcond = 1.0e-13_dp
    !> Largest residual |g x - r| of dependent constraints, relative to |r| + |g| |x|,
    !> accepted as consistent.
    real(dp), parameter :: consistency_tol = 1.0e-9_dp

    !> The modal form of one contact mode's state dynamics.
    type :: modal_form_t
        !> 0: not built; 1: usable; -1: not usable (the matrix exponential serves).
        integer :: status = 0
        !> Eigenvector matrix V (real form: a complex pair's real and imaginary parts in two
        !> columns) and W = V^-1, n_z x n_z.
        real(dp), allocatable :: v(:, :), w(:, :)
        !> Real parts a and imaginary parts b of the eigenvalues; a pair is stored in
        !> consecutive entries with b > 0 first.
        real(dp), allocatable :: re(:), im(:)
        !> The modal phase track's coefficients (stickslip_flow_track): W F (n_z x n_e, the
        !> forcing columns of the mode's dynamics), the event rows' state parts r_z^T V
        !> (n_ev x n_z), and at omega = coef_omega the particular solution P (n_z x n_e) and
        !> the rows' exosystem parts P^T rho + r_e transposed (n_ev x n_e); coef_ok when
        !> they are usable (coef_omega = huge: never, the forcing is off the constraints).
        real(dp), allocatable :: wd(:, :), rho_t(:, :), pm(:, :), q_t(:, :)
        !> 1 / lambda of each eigenvalue (0 for lambda = 0; a pair: of a + i b).
        complex(dp), allocatable :: inv_lam(:)
        !> exp(lambda delta) of each eigenvalue, delta the flow's grid step.
        complex(dp), allocatable :: edelta(:)
        real(dp) :: coef_omega = 0.0_dp
        logical :: coef_ok = .false.
    end type modal_form_t

contains

    !> The modal form of the state dynamics b (n_z x n_z, balanced coordinates; velocities in
    !> rows and columns n + 1 .. 2 n) of a mode whose velocity constraint directions are the
    !> columns of ctm (n x k, k >= 0), checked against its exponential e_delta = exp(b delta)
    !> (n_z x n_z). form%status is 1 when usable, -1 when not (no error: the matrix
    !> exponential is the fallback).
    subroutine build_modal_form(form, b, ctm, n, delta, e_delta)
        !> The form; status 1 or -1 on return.
        type(modal_form_t), intent(out) :: form
        !> State dynamics of the mode.
        real(dp), intent(in) :: b(:, :)
        !> Velocity constraint directions (modal coordinates).
        real(dp), intent(in) :: ctm(:, :)
        !> Number of DOFs (velocities are rows n + 1 .. 2 n).
        integer, intent(in) :: n
        !> The step of the check [s] and exp(b delta).
        real(dp), intent(in) :: delta, e_delta(:, :)
        real(dp), allocatable :: bd(:, :), a(:, :), work(:), wr(:), wi(:), vr(:, :), lu(:, :), &
                                 e1(:, :), d(:, :)
        real(dp) :: vl(1, 1), query(1), anorm, rcond
        integer, allocatable :: ipiv(:), iwork(:)
        integer :: nz, info, lwork, k

        form%status = -1
        nz = size(b, 1)
        if (nz == 0 .or. size(b, 2) /= nz .or. 2*n > nz) return
        bd = b
        ! B_d = B Pi: the constrained velocity columns removed
        call project_velocity_columns(ctm, n, bd)
        a = bd
        allocate (wr(nz), wi(nz), vr(nz, nz))
        call dgeev('N', 'V', nz, a, nz, wr, wi, vl, 1, vr, nz, query, -1, info)
        if (info /= 0) return
        lwork = max(4*nz, int(query(1)))
        allocate (work(lwork))
        call dgeev('N', 'V', nz, a, nz, wr, wi, vl, 1, vr, nz, work, lwork, info)
        if (info /= 0) return
        if (.not. (all(ieee_is_finite(wr)) .and. all(ieee_is_finite(wi)) .and. &
                   all(ieee_is_finite(vr)))) return
        ! W = V^-1 and the condition of V
        lu = vr
        allocate (ipiv(nz), iwork(nz))
        anorm = maxval(sum(abs(vr), 1))
        call dgetrf(nz, nz, lu, nz, ipiv, info)
        if (info /= 0) return
        deallocate (work)
        allocate (work(4*nz))
        call dgecon('1', nz, lu, nz, anorm, rcond, work, iwork, info)
        if (info /= 0 .or. .not. (rcond >= min_rcond)) return
        allocate (form%w(nz, nz))
        form%w = 0.0_dp
        do k = 1, nz
            form%w(k, k) = 1.0_dp
        end do
        call dgetrs('N', nz, nz, lu, nz, ipiv, form%w, nz, info)
        if (info /= 0 .or. .not. all(ieee_is_finite(form%w))) return
        call move_alloc(vr, form%v)
        form%re = wr
        form%im = wi
        ! the check: V exp(Lambda delta) W against exp(b delta) on the range of Pi
        form%status = 1
        allocate (e1(nz, nz))
        e1 = 0.0_dp
        do k = 1, nz
            e1(k, k) = 1.0_dp
        end do
        call modal_propagate(form, delta, e1)
        d = e1 - e_delta
        call project_velocity_columns(ctm, n, d)
        if (.not. (maxval(abs(d)) <= check_tol*max(maxval(abs(e_delta)), 1.0_dp))) then
            form%status = -1
            deallocate (form%v, form%w, form%re, form%im)
        end if
    end subroutine build_modal_form

    !> jac <- exp(b tau) jac for the mode of `form` (status 1), tau >= 0 [s]: V (exp(Lambda
    !> tau) (W jac)). Valid for columns of jac on the constraints (off_constraints small).
    subroutine modal_propagate(form, tau, jac)
        !> A usable modal form.
        type(modal_form_t), intent(in) :: form
        !> Duration [s].
        real(dp), intent(in) :: tau
        !> n_z x m, propagated in place.
        real(dp), intent(inout) :: jac(:, :)
        real(dp), allocatable :: t(:, :), r1(:)
        real(dp) :: g, c, s
        integer :: nz, j
        nz = size(form%re)
        t = mat_mul(form%w, jac)
        j = 1
        do while (j <= nz)
            if (form%im(j) > 0.0_dp .and. j < nz) then
                g = exp(form%re(j)*tau)
                c = g*cos(form%im(j)*tau)
                s = g*sin(form%im(j)*tau)
                r1 = t(j, :)
                t(j, :) = c*r1 + s*t(j + 1, :)
                t(j + 1, :) = -s*r1 + c*t(j + 1, :)
                j = j + 2
            else
                t(j, :) = exp(form%re(j)*tau)*t(j, :)
                j = j + 1
            end if
        end do
        jac = mat_mul(form%v, t)
    end subroutine modal_propagate

    !> a(n + 1:2 n, :) <- P a(n + 1:2 n, :), P = I - C (C^T C)^-1 C^T the orthogonal
    !> projection onto C^T u = 0 (C = ctm, n x k): O(k n m) for m columns. Nothing when
    !> k = 0 or C^T C is singular.
    subroutine project_velocity_rows(ctm, n, a)
        !> Constraint directions, n x k.
        real(dp), intent(in) :: ctm(:, :)
        !> Number of DOFs.
        integer, intent(in) :: n
        !> Matrix whose velocity rows are projected.
        real(dp), intent(inout) :: a(:, :)
        real(dp), allocatable :: x(:, :)
        logical :: ok
        if (size(ctm, 2) == 0 .or. size(a, 2) == 0) return
        call gram_solve(ctm, mat_mul(transpose(ctm), a(n + 1:2*n, :)), x, ok)
        if (.not. ok) return
        a(n + 1:2*n, :) = a(n + 1:2*n, :) - mat_mul(ctm, x)
    end subroutine project_velocity_rows

    !> a(:, n + 1:2 n) <- a(:, n + 1:2 n) P (P as in project_velocity_rows).
    subroutine project_velocity_columns(ctm, n, a)
        real(dp), intent(in) :: ctm(:, :)
        integer, intent(in) :: n
        real(dp), intent(inout) :: a(:, :)
        real(dp), allocatable :: x(:, :)
        logical :: ok
        if (size(ctm, 2) == 0) return
        ! a_v P = a_v - (a_v C) G^-1 C^T; G symmetric: (G^-1 C^T a_v^T)^T
        call gram_solve(ctm, mat_mul(transpose(ctm), transpose(a(:, n + 1:2*n))), x, ok)
        if (.not. ok) return
        a(:, n + 1:2*n) = a(:, n + 1:2*n) - transpose(mat_mul(ctm, x))
    end subroutine project_velocity_columns

    !> Largest |C^T u| over the columns of a, u their velocity rows, relative to the largest
    !> entry of a (0 for k = 0): how far the columns are from the constraints.
    real(dp) function off_constraints(ctm, n, a) result(r)
        !> Constraint directions, n x k.
        real(dp), intent(in) :: ctm(:, :)
        !> Number of DOFs.
        integer, intent(in) :: n
        !> The matrix.
        real(dp), intent(in) :: a(:, :)
        real(dp) :: amax
        r = 0.0_dp
        if (size(ctm, 2) == 0 .or. size(a, 2) == 0) return
        amax = maxval(abs(a))
        if (.not. (amax > 0.0_dp)) return
        r = maxval(abs(mat_mul(transpose(ctm), a(n + 1:2*n, :))))/ &
            (amax*maxval(sqrt(sum(ctm**2, 1))))
    end function off_constraints

    !> x = (C^T C)^+ r for the k columns of c (n x k) and r (k x m) (constraint_solve: the
    !> pseudo-inverse when the directions are dependent, so C x is still the orthogonal
    !> projection of the right-hand side's directions onto the span of C); ok = .false.
    !> when x is not finite.
    subroutine gram_solve(c, r, x, ok)
        !> The directions, n x k.
        real(dp), intent(in) :: c(:, :)
        !> Right-hand sides, k x m.
        real(dp), intent(in) :: r(:, :)
        !> The solutions, k x m.
        real(dp), allocatable, intent(out) :: x(:, :)
        !> The system was solved.
        logical, intent(out) :: ok
        call constraint_solve(matmul(transpose(c), c), r, x, ok)
    end subroutine gram_solve

    !> x solving g x = r, g the k x k matrix of a mode's velocity constraints (C_t^T F_t,
    !> or the Gram matrix C^T C), r k x m. Independent constraints: LU (dgesv), as always.
    !> Dependent ones (reciprocal condition below dependent_rcond: stuck contacts whose
    !> constraints close a ring, e.g. every shroud of a disk stuck, 23 of 24 independent):
    !> the minimum-norm least-squares solution (SVD, dgelss), which meets the constraints
    !> when they are consistent; the accelerations are then unique and the statically
    !> undetermined force (the ring's common one) is zero, the weighted residual's choice
    !> for the harmonics it leaves free. ok = .false. when x is not finite or dependent
    !> constraints are inconsistent (Painleve's paradox: no constraint force holds them).
    subroutine constraint_solve(g, r, x, ok)
        !> The constraint matrix, k x k (k >= 1).
        real(dp), intent(in) :: g(:, :)
        !> Right-hand sides, k x m.
        real(dp), intent(in) :: r(:, :)
        !> The solutions, k x m.
        real(dp), allocatable, intent(out) :: x(:, :)
        !> The system was solved.
        logical, intent(out) :: ok
        real(dp), allocatable :: a(:, :), b(:, :), work(:), sv(:)
        integer, allocatable :: ipiv(:), iwork(:)
        real(dp) :: anorm, rcond, query(1), resid, scale
        integer :: k, m, info, rank
        k = size(g, 1)
        m = size(r, 2)
        a = g
        x = r
        allocate (ipiv(k))
        anorm = maxval(sum(abs(g), 1))
        call dgesv(k, m, a, k, ipiv, x, k, info)
        if (info == 0 .and. all(ieee_is_finite(x))) then
            allocate (work(4*k), iwork(k))
            call dgecon('1', k, a, k, anorm, rcond, work, iwork, info)
            ok = info == 0 .and. rcond >= dependent_rcond
            if (ok) return
            deallocate (work)
        end if
        ! dependent constraints: the minimum-norm solution, if they are consistent
        a = g
        b = r
        allocate (sv(k))
        call dgelss(k, k, m, a, k, b, k, sv, dependent_rcond, rank, query, -1, info)
        ok = info == 0
        if (.not. ok) return
        allocate (work(max(1, int(query(1)))))
        call dgelss(k, k, m, a, k, b, k, sv, dependent_rcond, rank, work, size(work), info)
        ok = info == 0 .and. all(ieee_is_finite(b))
        if (.not. ok) return
        resid = maxval(abs(matmul(g, b) - r))
        scale = maxval(abs(r)) + maxval(sum(abs(g), 2))*maxval(abs(b))
        ok = resid <= consistency_tol*scale
        call move_alloc(b, x)
    end subroutine constraint_solve
end module stickslip_flow_modal
