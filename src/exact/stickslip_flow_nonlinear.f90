!> The nonlinear phases of the exact flow (a 2D slip: the friction force -g u/|u| of planar
!> friction, the slider rate of a 2D Jenkins element turn with the state): y' = B y + G q(y),
!> B the mode's linear dynamics (stiff: the modes of a reduced FE model), G the columns of
!> its nonlinear inputs q (smooth while the slip lasts), integrated by exponential
!> collocation: over a step [0, h] the input is the polynomial through its values at the s
!> = 3 Gauss nodes c_i h, q(sigma) = sum_k b_k sigma^k / k!, and the state is the exact
!> solution of the linear dynamics driven by it,
!>     y(sigma) = [exp(sigma A) (y0, b)]_y,   A = [[B, G, 0, 0], [0, 0, I, 0], [0, 0, 0, I],
!>                                                [0, 0, 0, 0]]
!> (the augmented dynamics of the polynomial's Taylor coefficients), the node values solved
!> by Newton's method on q_i = q(y(c_i h)) (collocation; the stiff part exact, A-stable).
!> Order 2s = 6 at the step's end. The step's error estimate is by step doubling (the
!> same interval in two half steps: 64/63 of the difference, relative to the state's size);
!> steps are delta 2^-k (the exponentials of each level cached), refined until the estimate
!> meets the tolerance (&reference ode_tol) and coarsened when it is 128 times below. The step's
!> Jacobian dy(h)/dy0 differentiates the collocation solution (the implicit function
!> theorem on its Newton system): the monodromy of a period with nonlinear phases is exact
!> for the discrete solution. Dense output between the nodes: y(sigma) above, by the dyadic
!> ladder of A (matrix-vector products).
module stickslip_flow_nonlinear
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_expm, only: expm
    use stickslip_lapack, only: dgesv
    use stickslip_flow_modes, only: mode_t, flow_modes_t, ladder_of, propagate_matrix
    use stickslip_flow_algebra, only: eval_inputs
    implicit none
    private
    public :: nodes, node, gauss_weight, max_level, nl_step_t, nl_prepare, nl_step, &
        nl_checked_step, nl_state_at, nl_exponentials, nl_dense, nl_dense_jacobian, nl_input_at

    !> Collocation nodes per step (Gauss-Legendre on [0, 1]) and their quadrature weights.
    integer, parameter :: nodes = 3
    real(dp), parameter :: node(nodes) = [0.5_dp - sqrt(15.0_dp)/10.0_dp, 0.5_dp, &
                                          0.5_dp + sqrt(15.0_dp)/10.0_dp]
    real(dp), parameter :: gauss_weight(nodes) = [5.0_dp/18.0_dp, 8.0_dp/18.0_dp, &
                                                  5.0_dp/18.0_dp]
    !> Finest step level: delta 2^-max_level.
    integer, parameter :: max_level = 24

    !> One collocation step: its length h [s], start y0 and end y1 (balanced), the input
    !> values at the nodes q (m x s) and the Taylor coefficients b (m s) of their polynomial,
    !> the states at the nodes, the error estimate (relative), the Jacobians dq/dy0 (m s x
    !> nz) and dy1/dy0 (na x nz) when asked, whether Newton's method converged.
    type :: nl_step_t
        real(dp) :: h = 0.0_dp, err = 0.0_dp
        real(dp), allocatable :: y0(:), y1(:), q(:, :), b(:), ynode(:, :), dqdy(:, :), &
                                 jac(:, :)
        logical :: ok = .false.
    end type nl_step_t

contains

    !> The augmented dynamics of a nonlinear mode md and its dyadic ladder (dense output),
    !> built on first use. Error (stat numerical): a non-finite exponential.
    subroutine nl_prepare(self, md, error)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The nonlinear mode.
        type(mode_t), intent(inout) :: md
        !> Set on failure.
        type(error_type), allocatable, intent(inout) :: error
        integer :: na, m, k, i, naug
        if (allocated(md%aug)) return
        na = self%na
        m = md%m
        naug = na + m*nodes
        allocate (md%aug(naug, naug))
        md%aug = 0.0_dp
        md%aug(1:na, 1:na) = md%b
        md%aug(1:na, na + 1:na + m) = md%gin
        do k = 0, nodes - 2
            do i = 1, m
                md%aug(na + k*m + i, na + (k + 1)*m + i) = 1.0_dp
            end do
        end do
        call ladder_of(md%aug, self%delta, md%aug_ladder, md%aug_nl, error)
        allocate (md%level(0:max_level + 1))
    end subroutine nl_prepare

    !> The exponentials of the augmented dynamics at the nodes and the end of a step of
    !> length h: e(:, :, i) = exp(c_i h A), e(:, :, s + 1) = exp(h A).
    subroutine exponentials(md, h, e)
        type(mode_t), intent(in) :: md
        real(dp), intent(in) :: h
        real(dp), intent(out) :: e(:, :, :)
        integer :: i, stat
        do i = 1, nodes
            call expm(md%aug*(node(i)*h), e(:, :, i), stat)
        end do
        call expm(md%aug*h, e(:, :, nodes + 1), stat)
    end subroutine exponentials

    !> T = V^-1, V(i, k) = (c_i h)^(k-1) / (k-1)!: the Taylor coefficients b = T q of the
    !> polynomial through the node values.
    function taylor_matrix(h) result(t)
        real(dp), intent(in) :: h
        real(dp) :: t(nodes, nodes)
        real(dp) :: v(nodes, nodes), f
        integer :: i, k, ipiv(nodes), info
        do i = 1, nodes
            f = 1.0_dp
            do k = 1, nodes
                if (k > 1) f = f*node(i)*h/real(k - 1, dp)
                v(i, k) = f
            end do
        end do
        t = 0.0_dp
        do i = 1, nodes
            t(i, i) = 1.0_dp
        end do
        call dgesv(nodes, nodes, v, nodes, ipiv, t, nodes, info)
    end function taylor_matrix

    !> One collocation step of mode md from the balanced state y0: of length delta 2^-level
    !> (the exponentials cached in md%level), or of the length h_given. Newton's method on
    !> the node values (at most 30 iterations, |F| <= 1e-13 of the inputs' size, or below
    !> 1e-7 when it no longer halves: the roundoff of a stiff input, the slip direction
    !> near rest); with want_jac the Jacobians (columns: the nz state entries). `code` the
    !> mode's codes, `dirs` the elements' slip memories.
    subroutine nl_step(self, md, code, dirs, y0, level, want_jac, st, h_given)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The nonlinear mode (level exponentials built on first use).
        type(mode_t), intent(inout) :: md
        !> The codes of every slot.
        integer, intent(in) :: code(:)
        !> The elements' slip memories (3 x n_c).
        real(dp), intent(in) :: dirs(:, :)
        !> Start (balanced).
        real(dp), intent(in) :: y0(:)
        !> Step level (used without h_given).
        integer, intent(in) :: level
        !> Compute the Jacobians.
        logical, intent(in) :: want_jac
        !> The step.
        type(nl_step_t), intent(out) :: st
        !> A step of this length instead [s].
        real(dp), intent(in), optional :: h_given
        real(dp), allocatable :: e(:, :, :)
        integer :: naug
        naug = self%na + md%m*nodes
        if (present(h_given)) then
            allocate (e(naug, naug, nodes + 1))
            call exponentials(md, h_given, e)
            call collocate(self, md, code, dirs, y0, h_given, e, want_jac, st)
        else
            if (.not. allocated(md%level(level)%e)) then
                allocate (md%level(level)%e(naug, naug, nodes + 1))
                call exponentials(md, self%delta*0.5_dp**level, md%level(level)%e)
            end if
            call collocate(self, md, code, dirs, y0, self%delta*0.5_dp**level, &
                           md%level(level)%e, want_jac, st)
        end if
    end subroutine nl_step

    !> A collocation step of length h of mode md from y0 (balanced), the exponentials of
    !> its augmented dynamics at the nodes and the end given (e): nl_step's work.
    subroutine collocate(self, md, code, dirs, y0, h, e, want_jac, st)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The nonlinear mode.
        type(mode_t), intent(in) :: md
        !> The codes of every slot.
        integer, intent(in) :: code(:)
        !> The elements' slip memories (3 x n_c).
        real(dp), intent(in) :: dirs(:, :)
        !> Start (balanced) and step length [s].
        real(dp), intent(in) :: y0(:), h
        !> exp(c_i h A) (i = 1..s) and exp(h A).
        real(dp), intent(in) :: e(:, :, :)
        !> Compute the Jacobians.
        logical, intent(in) :: want_jac
        !> The step.
        type(nl_step_t), intent(out) :: st
        real(dp), allocatable :: tk(:, :), jmat(:, :), f(:), dq(:, :, :), rhs(:, :), qy(:), &
                                 dqy(:, :)
        real(dp) :: t(nodes, nodes), fn, fn_old, qscale
        integer :: na, nz, m, ms, i, it, k, a, info
        integer, allocatable :: ipiv(:)
        na = self%na
        nz = self%nz
        m = md%m
        ms = m*nodes
        st%h = h
        t = taylor_matrix(st%h)
        ! the Taylor coefficients of the node values: b = (T x I_m) Q
        allocate (tk(ms, ms))
        tk = 0.0_dp
        do k = 1, nodes
            do i = 1, nodes
                do a = 1, m
                    tk((k - 1)*m + a, (i - 1)*m + a) = t(k, i)
                end do
            end do
        end do
        allocate (st%q(m, nodes), st%ynode(na, nodes), qy(m), dqy(m, na), dq(m, na, nodes), &
                  f(ms), jmat(ms, ms), ipiv(ms))
        st%y0 = y0
        call eval_inputs(self, code, md%in_elem, y0, dirs, md%fbal, md%fin, qy, dqy, md%b, &
                         md%gin)
        do i = 1, nodes
            st%q(:, i) = qy
        end do
        qscale = max(maxval(abs(qy)), tiny(1.0_dp))
        st%ok = .false.
        fn_old = huge(1.0_dp)
        do it = 1, 30
            st%b = matmul(tk, reshape(st%q, [ms]))
            do i = 1, nodes
                st%ynode(:, i) = matmul(e(1:na, 1:na, i), y0) + matmul(e(1:na, na + 1:, i), st%b)
                call eval_inputs(self, code, md%in_elem, st%ynode(:, i), dirs, md%fbal, md%fin, &
                                 qy, dq(:, :, i), md%b, md%gin)
                f((i - 1)*m + 1:i*m) = st%q(:, i) - qy
            end do
            fn = maxval(abs(f))
            if (.not. (fn <= huge(1.0_dp))) exit
            ! converged; or stalled at the roundoff of a stiff input (a slip near rest)
            if (fn <= 1.0e-13_dp*qscale .or. &
                (fn <= 1.0e-7_dp*qscale .and. fn >= 0.5_dp*fn_old)) then
                st%ok = .true.
                exit
            end if
            fn_old = fn
            call newton_matrix()
            call dgesv(ms, 1, jmat, ms, ipiv, f, ms, info)
            if (info /= 0) exit
            st%q = st%q - reshape(f, [m, nodes])
        end do
        st%b = matmul(tk, reshape(st%q, [ms]))
        st%y1 = matmul(e(1:na, 1:na, nodes + 1), y0) + matmul(e(1:na, na + 1:, nodes + 1), st%b)
        if (.not. all(ieee_is_finite(st%y1))) st%ok = .false.
        if (.not. (st%ok .and. want_jac)) return
        ! dQ/dy0 = J^-1 [dq_i exp(c_i h B)], dy1/dy0 = exp(h B) + P_end T dQ/dy0 (nz columns)
        call newton_matrix()
        allocate (rhs(ms, nz))
        do i = 1, nodes
            rhs((i - 1)*m + 1:i*m, :) = matmul(dq(:, :, i), e(1:na, 1:nz, i))
        end do
        call dgesv(ms, nz, jmat, ms, ipiv, rhs, ms, info)
        st%dqdy = rhs
        st%jac = e(1:na, 1:nz, nodes + 1) + matmul(matmul(e(1:na, na + 1:, nodes + 1), tk), rhs)

    contains

        !> The Newton matrix I - blockdiag(dq_i) [P_i T] at the current node states.
        subroutine newton_matrix()
            integer :: ii
            jmat = 0.0_dp
            do ii = 1, ms
                jmat(ii, ii) = 1.0_dp
            end do
            do ii = 1, nodes
                jmat((ii - 1)*m + 1:ii*m, :) = jmat((ii - 1)*m + 1:ii*m, :) - &
                    matmul(dq(:, :, ii), matmul(e(1:na, na + 1:, ii), tk))
            end do
        end subroutine newton_matrix
    end subroutine collocate

    !> One collocation step (nl_step) with its error estimate by step doubling: the same
    !> interval in two steps of half the length; the error of the one step is 64/63 of the
    !> difference of their ends (order 6), relative to the state's size (st%err). The step
    !> kept is the one step (its nodes, dense output and Jacobians).
    subroutine nl_checked_step(self, md, code, dirs, y0, level, want_jac, st, h_given)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The nonlinear mode (level exponentials built on first use).
        type(mode_t), intent(inout) :: md
        !> The codes of every slot.
        integer, intent(in) :: code(:)
        !> The elements' slip memories (3 x n_c).
        real(dp), intent(in) :: dirs(:, :)
        !> Start (balanced).
        real(dp), intent(in) :: y0(:)
        !> Step level (used without h_given).
        integer, intent(in) :: level
        !> Compute the Jacobians of the step.
        logical, intent(in) :: want_jac
        !> The step.
        type(nl_step_t), intent(out) :: st
        !> A step of this length instead [s].
        real(dp), intent(in), optional :: h_given
        type(nl_step_t) :: half1, half2
        integer :: nz
        nz = self%nz
        if (present(h_given)) then
            call nl_step(self, md, code, dirs, y0, level, want_jac, st, h_given)
            if (.not. st%ok) return
            call nl_step(self, md, code, dirs, y0, level, .false., half1, 0.5_dp*h_given)
            if (half1%ok) call nl_step(self, md, code, dirs, half1%y1, level, .false., half2, &
                                       0.5_dp*h_given)
        else
            call nl_step(self, md, code, dirs, y0, level, want_jac, st)
            if (.not. st%ok) return
            call nl_step(self, md, code, dirs, y0, level + 1, .false., half1)
            if (half1%ok) call nl_step(self, md, code, dirs, half1%y1, level + 1, .false., half2)
        end if
        if (.not. (half1%ok .and. half2%ok)) then
            st%ok = .false.
            return
        end if
        st%err = 64.0_dp/63.0_dp*norm2(st%y1(1:nz) - half2%y1(1:nz))/ &
                 max(norm2(st%y1(1:nz)), tiny(1.0_dp))
    end subroutine nl_checked_step

    !> The state at sigma [s] after y0 (balanced) in the nonlinear mode md, as the end of a
    !> collocation step of that length (of the step's order, where the dense output inside
    !> a step is of a lower one); ok = .false. when its Newton iteration fails. `e`: the
    !> exponentials of that step length (nl_exponentials), when the caller keeps them.
    subroutine nl_state_at(self, md, code, dirs, y0, sigma, y, ok, e)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The nonlinear mode.
        type(mode_t), intent(in) :: md
        !> The codes of every slot.
        integer, intent(in) :: code(:)
        !> The elements' slip memories (3 x n_c).
        real(dp), intent(in) :: dirs(:, :)
        !> Start (balanced) and time after it [s].
        real(dp), intent(in) :: y0(:), sigma
        !> The state (balanced).
        real(dp), intent(out) :: y(:)
        !> The step converged.
        logical, intent(out) :: ok
        !> Exponentials of the step length sigma.
        real(dp), intent(in), optional :: e(:, :, :)
        real(dp), allocatable :: ew(:, :, :)
        type(nl_step_t) :: st
        y = y0
        ok = .true.
        if (.not. (sigma > 0.0_dp)) return
        if (present(e)) then
            call collocate(self, md, code, dirs, y0, sigma, e, .false., st)
        else
            call nl_exponentials(md, sigma, ew)
            call collocate(self, md, code, dirs, y0, sigma, ew, .false., st)
        end if
        ok = st%ok
        if (ok) y = st%y1
    end subroutine nl_state_at

    !> The exponentials of a collocation step of length h [s] of the nonlinear mode md
    !> (its augmented dynamics at the nodes and the end).
    subroutine nl_exponentials(md, h, e)
        !> The nonlinear mode (nl_prepare'd).
        type(mode_t), intent(in) :: md
        !> Step length [s].
        real(dp), intent(in) :: h
        !> exp(c_i h A), i = 1..s, and exp(h A).
        real(dp), allocatable, intent(out) :: e(:, :, :)
        allocate (e(size(md%aug, 1), size(md%aug, 1), nodes + 1))
        call exponentials(md, h, e)
    end subroutine nl_exponentials

    !> The dense output of step st at sigma in [0, h] (balanced): the exact solution driven
    !> by the step's input polynomial (the augmented dynamics' ladder).
    function nl_dense(self, md, st, sigma) result(y)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The nonlinear mode.
        type(mode_t), intent(in) :: md
        !> The step.
        type(nl_step_t), intent(in) :: st
        !> Time into the step [s].
        real(dp), intent(in) :: sigma
        real(dp) :: y(self%na)
        real(dp) :: z(size(md%aug, 1)), z1(size(md%aug, 1))
        z(1:self%na) = st%y0
        z(self%na + 1:) = st%b
        call propagate_matrix(md%aug, md%aug_ladder, md%aug_nl, self%delta, sigma, z, z1)
        y = z1(1:self%na)
    end function nl_dense

    !> The Jacobian of the dense output at sigma with respect to the step's start (nz state
    !> columns): exp(sigma B) + P(sigma) T dQ/dy0 (one exponential of the augmented
    !> dynamics; st with its Jacobians).
    function nl_dense_jacobian(self, md, st, sigma) result(jac)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The nonlinear mode.
        type(mode_t), intent(in) :: md
        !> The step (computed with want_jac).
        type(nl_step_t), intent(in) :: st
        !> Time into the step [s].
        real(dp), intent(in) :: sigma
        real(dp) :: jac(self%na, self%nz)
        real(dp) :: e(size(md%aug, 1), size(md%aug, 1)), t(nodes, nodes)
        real(dp), allocatable :: tk(:, :)
        integer :: na, m, ms, i, k, a, stat
        na = self%na
        m = md%m
        ms = m*nodes
        call expm(md%aug*sigma, e, stat)
        t = taylor_matrix(st%h)
        allocate (tk(ms, ms))
        tk = 0.0_dp
        do k = 1, nodes
            do i = 1, nodes
                do a = 1, m
                    tk((k - 1)*m + a, (i - 1)*m + a) = t(k, i)
                end do
            end do
        end do
        jac = e(1:na, 1:self%nz) + matmul(matmul(e(1:na, na + 1:), tk), st%dqdy)
    end function nl_dense_jacobian

    !> The input polynomial of step st at sigma [s] into the step (m values).
    pure function nl_input_at(md, st, sigma) result(q)
        !> The nonlinear mode.
        type(mode_t), intent(in) :: md
        !> The step.
        type(nl_step_t), intent(in) :: st
        !> Time into the step [s].
        real(dp), intent(in) :: sigma
        real(dp) :: q(md%m)
        real(dp) :: f
        integer :: k
        q = 0.0_dp
        f = 1.0_dp
        do k = 0, nodes - 1
            if (k > 0) f = f*sigma/real(k, dp)
            q = q + f*st%b(k*md%m + 1:(k + 1)*md%m)
        end do
    end function nl_input_at
end module stickslip_flow_nonlinear
