!> Implicit Euler on velocity level (Moreau-Jean type) for the same model as the weighted
!> residual: the time-domain comparison method.
!>
!>     x_{n+1} = x_n + h v_{n+1}
!>     M (v_{n+1} - v_n) = h ( f(t_{n+1}) - C v_{n+1} - K x_{n+1} + W r_{n+1} )
!>     Coulomb's law between r_{n+1} and the slip velocities u = W^T v_{n+1}
!>
!> With S = M + h C + h^2 K (factorized once per step size, LAPACK dgetrf):
!> v_{n+1} = v_free + h S^{-1} D r (D the channel directions of the contact elements,
!> stickslip_contact_set), and every channel's kinematic quantity at the end of the step is
!> u = q + A r, A = h D^T S^{-1} D plus the compliances / h:
!>     velocity channel: u = d^T v_{n+1} + c (r_{n+1} - r_n) / h    (a slider behind a spring),
!>     gap channel:      u = (gap + d^T x_{n+1} + c r_{n+1}) / h   (position level: impacts of
!>                       a rigid normal are plastic as h -> 0),
!> and the elements' laws Psi(r, u) = 0 give the forces (contact_set_t%step_forces: block
!> Gauss-Seidel over the elements, each by its own local solve). For Coulomb contacts only
!> the forces solve min 1/2 r^T D r + u_free^T r over the box |r_j| <= mu_j N_j (its
!> optimality conditions are Coulomb's law): closed form for one contact, projected
!> Gauss-Seidel for several (it converges when D is symmetric positive definite, i.e. for
!> symmetric C and K; stickslip_contact_solve): the kernels below, written out for speed.
!> The step is first order: errors are O(h).
!>
!> The free velocity v_free = S^{-1} (M v - h K x + h f(t)): up to opts%inverse_max_ndof
!> unknowns the matrices S^{-1} M, S^{-1} h K and S^{-1} F (F the load shapes) are formed
!> once, and a step costs one N x (2N + n_f) matrix-vector product and the cosines of the
!> forcing; above, a step forms M v - h K x + h f and solves with the LU factors of S
!> (dgetrs). No allocation and no array temporary in the step loop (written-out loops);
!> subnormal numbers are flushed to zero inside it (ieee_set_underflow_mode, restored after).
module stickslip_euler
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_support_underflow_control, &
        ieee_get_underflow_mode, ieee_set_underflow_mode
    use stickslip_kinds, only: dp, two_pi
    use stickslip_progress, only: progress_t
    use stickslip_diagnostics, only: diagnostics_t, level_untrusted
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, validate_model, force_direction, preload_force, &
        contact_normal_direction
    use stickslip_contact_set, only: contact_set_t, new_contact_set, channel_directions
    use stickslip_contact_element, only: channel_t, kinematics_gap, kinematics_velocity
    use stickslip_contact_measures, only: contact_measures_t, measure_contacts
    use stickslip_lapack, only: dgetrf, dgetrs, dgemm
    use stickslip_contact_solve, only: contact_forces
    implicit none
    private
    public :: euler_options_t, euler_result_t, integrate_euler
    public :: validate_euler_options, euler_max_steps_per_period, euler_max_total_steps

    !> Largest steps_per_period accepted by validate_euler_options (the last period is kept:
    !> steps x (2 ndof + ncontact + 1) doubles).
    integer, parameter :: euler_max_steps_per_period = 10**7
    !> Largest steps_per_period x max_periods (time steps of one run) accepted.
    integer(int64), parameter :: euler_max_total_steps = 2000000000_int64
    !> Steps whose forcing coefficients are computed together, before the steps.
    integer, parameter :: block_steps = 1024

    !> Options of the time integration.
    type :: euler_options_t
        !> Time steps per forcing period (h = T / steps_per_period).
        integer :: steps_per_period = 1000
        !> Periods integrated at most before giving up on a periodic state.
        integer :: max_periods = 2000
        !> Periodic when the states one period apart differ by less than tol times the
        !> amplitude of the response over that period (x and v separately).
        real(dp) :: tol = 1.0e-8_dp
        !> Projected Gauss-Seidel: stop when no force changes by more than contact_tol times
        !> the largest friction limit.
        real(dp) :: contact_tol = 1.0e-13_dp
        !> Projected Gauss-Seidel sweeps at most per step.
        integer :: contact_max_sweeps = 10000
        !> Iteration matrices M + h C + h^2 K of at most this order are inverted once (a step
        !> is then one matrix-vector product, no LAPACK call); larger ones are LU-factorized
        !> once and solved every step (dgetrs). Both give the same results to roundoff;
        !> 0: always the LU solve.
        integer :: inverse_max_ndof = 1024
    end type euler_options_t

    !> Result of the time integration: the report and the last period.
    type :: euler_result_t
        !> A periodic steady state was reached.
        logical :: periodic = .false.
        !> Periods integrated.
        integer :: periods = 0
        !> Periodicity defect of the last period (relative, the larger of x and v).
        real(dp) :: defect = huge(1.0_dp)
        !> Wall-clock seconds of the integration.
        real(dp) :: seconds = 0.0_dp
        !> Most projected Gauss-Seidel sweeps needed in one step (0 with one contact).
        integer :: max_sweeps = 0
        !> Empty when periodic, otherwise what happened.
        character(len=:), allocatable :: diagnosis
        !> Instants t_k = k T / steps_per_period of the last period [s].
        real(dp), allocatable :: t(:)
        !> Displacements over the last period, steps x N [m].
        real(dp), allocatable :: x(:, :)
        !> Velocities over the last period, steps x N [m/s].
        real(dp), allocatable :: v(:, :)
        !> Friction forces over the last period, steps x n_c [N] (with contact laws: the
        !> forces of every force channel, steps x n_ch, stickslip_contact_set's order).
        real(dp), allocatable :: r(:, :)
        !> The contacts and their force channels.
        type(contact_set_t) :: contacts
        !> Contact state over the last period, steps x n_c: state_open, state_stick,
        !> state_slip of stickslip_contact_law (after the step before each instant).
        integer, allocatable :: state(:, :)
        !> Normal force [N] (the constant normal load of a plain contact) and gap [m] (0 for
        !> a plain contact) over the last period, steps x n_c.
        real(dp), allocatable :: normal(:, :), gap(:, :)
        !> Kinematic quantity of every force channel over the last period (the slip or
        !> slider velocity, omega times the gap; with the force of the same step), steps x
        !> n_ch [m/s].
        real(dp), allocatable :: u(:, :)
        !> Shares of the last period each contact is open, sticks and slips, and its stick
        !> phases (stickslip_contact_measures, from the samples).
        real(dp), allocatable :: open_fraction(:), stick_fraction(:), slip_fraction(:)
        integer, allocatable :: stick_phases(:)
        !> Over the last period, by the rectangle rule on the steps [J]: work of the forcing,
        !> its gross work integral |f . v| dt, friction dissipation -integral r . D^T v dt,
        !> viscous dissipation, Coulomb's dissipation (stickslip_contact_measures). Their
        !> balance is off by implicit Euler's own numerical dissipation, O(h).
        real(dp) :: work_forcing = 0.0_dp, work_gross = 0.0_dp, diss_friction = 0.0_dp, &
                    diss_damping = 0.0_dp, diss_coulomb = 0.0_dp
        !> The force-limit ratio over the last period (stickslip_contact_measures).
        real(dp) :: max_force_ratio = 0.0_dp
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type euler_result_t

contains

    !> Check time-stepping options. Errors (stat input) name the component
    !> ("opts%steps_per_period = 1: must be >= 2") and the
    !> limit; the product steps_per_period x max_periods is formed in 64-bit integers.
    subroutine validate_euler_options(opts, error)
        !> Options to check.
        type(euler_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=200) :: buf
        if (opts%steps_per_period < 2) then
            write (buf, '(a,i0,a)') "opts%steps_per_period = ", opts%steps_per_period, &
                ": must be >= 2"
        else if (opts%steps_per_period > euler_max_steps_per_period) then
            write (buf, '(a,i0,a,i0)') "opts%steps_per_period = ", opts%steps_per_period, &
                ": must be <= ", euler_max_steps_per_period
        else if (opts%max_periods < 1) then
            write (buf, '(a,i0,a)') "opts%max_periods = ", opts%max_periods, ": must be >= 1"
        else if (int(opts%steps_per_period, int64)*opts%max_periods > euler_max_total_steps) then
            write (buf, '(a,i0,a,i0,a,i0,a)') "opts%max_periods = ", opts%max_periods, &
                ": steps_per_period x max_periods must be <= ", euler_max_total_steps, &
                " time steps (steps_per_period = ", opts%steps_per_period, ")"
        else if (.not. (opts%tol > 0.0_dp .and. opts%tol < 1.0_dp)) then
            write (buf, '(a,g0.6,a)') "opts%tol = ", opts%tol, ": must be in (0, 1)"
        else
            return
        end if
        call fatal_error(error, trim(buf), stickslip_stat%input)
    end subroutine validate_euler_options

    !> Integrate `model` from rest (or from x0, v0 at t = 0) until the response is periodic.
    !> Not reaching a periodic state within max_periods is an outcome (res%periodic = F and a
    !> diagnosis: drift, quasi-periodic or unbounded response). Errors: stat input (invalid
    !> model or options, x0 or v0 not of size ndof), stat numerical (singular iteration
    !> matrix).
    subroutine integrate_euler(model, opts, res, error, x0, v0, progress)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Integration options.
        type(euler_options_t), intent(in) :: opts
        !> The report and the last period.
        type(euler_result_t), intent(out) :: res
        !> Set on invalid input or a singular iteration matrix.
        type(error_type), allocatable, intent(out) :: error
        !> Initial displacements [m] (default 0).
        real(dp), intent(in), optional :: x0(:)
        !> Initial velocities [m/s] (default 0).
        real(dp), intent(in), optional :: v0(:)
        !> Progress of the periods (a line at most once a second when its unit is set).
        type(progress_t), intent(inout), optional :: progress
        integer :: n, nc, nf, ny, ns, info, i, j, k, period, step, first, last, nblock, nch
        logical :: inverse, ftz, gradual, fast, sliders
        real(dp), allocatable :: rstart(:), us(:, :), q(:), uprev(:), ch_gap(:), ch_c(:), &
                                 pf(:)
        logical, allocatable :: gap_channel(:)
        real(dp) :: dr, fscale
        character(len=40) :: defect_text
        real(dp) :: h, period_t, t, ampx, ampv, dx, dv, acc
        real(dp), allocatable :: s(:, :), sw(:, :), d(:, :), w(:, :), a(:, :), y(:), &
                                 ystart(:), vf(:), r(:), ufree(:), limit(:), famp(:), fph(:), &
                                 fh(:), fc(:, :), wa(:)
        integer, allocatable :: ipiv(:)
        integer(int64) :: c0, c1, rate
        character(len=300) :: buf
        integer :: c
        type(channel_t) :: ch

        call system_clock(c0, rate)
        call validate_model(model, error)
        if (allocated(error)) return
        if (opts%steps_per_period < 2) then
            call fatal_error(error, "opts%steps_per_period: must be >= 2", stickslip_stat%input)
            return
        end if
        if (opts%max_periods < 1) then
            call fatal_error(error, "opts%max_periods: must be >= 1", stickslip_stat%input)
            return
        end if
        if (.not. (opts%tol > 0.0_dp .and. opts%tol < 1.0_dp)) then
            call fatal_error(error, "opts%tol: must be in (0, 1)", stickslip_stat%input)
            return
        end if
        n = model%ndof
        if (present(x0)) then
            if (size(x0) /= n) then
                call fatal_error(error, "x0: size "//itoa(size(x0))//", must be ndof = "// &
                                 itoa(n), stickslip_stat%input)
                return
            end if
        end if
        if (present(v0)) then
            if (size(v0) /= n) then
                call fatal_error(error, "v0: size "//itoa(size(v0))//", must be ndof = "// &
                                 itoa(n), stickslip_stat%input)
                return
            end if
        end if
        nc = model%ncontact()
        nf = model%nforce()
        ! the contact elements and their force channels (nch of them); Coulomb contacts only:
        ! the written-out kernels; a preload is a constant load term
        call new_contact_set(res%contacts, model)
        nch = res%contacts%nchannel
        fast = res%contacts%coulomb_only
        pf = preload_force(model)
        if (any(pf /= 0.0_dp)) nf = nf + 1
        ny = 2*n + nf
        ns = opts%steps_per_period
        period_t = two_pi/model%omega
        h = period_t/ns
        inverse = n <= opts%inverse_max_ndof

        ! The state y = [v; x; c]: velocities, displacements and the forcing coefficients
        ! c_i = h famp_i cos(k_i omega t + phase_i) of the step. The right-hand side
        ! M v - h K x + h f(t) is A y with A = [M, -h K, F] (F: the load shapes); the free
        ! velocity S^{-1} A y is one product when A holds S^{-1} [M, -h K, F].
        allocate (s(n, n), sw(n, nch), d(nch, nch), w(n, nch), a(n, ny), y(ny), ystart(ny), &
                  vf(n), r(nch), ufree(nch), limit(nc), ipiv(n), q(nch), uprev(nch), &
                  ch_gap(nch), ch_c(nch), gap_channel(nch))
        s = model%mass + h*model%damping + h*h*model%stiffness
        call dgetrf(n, n, s, n, ipiv, info)
        if (info /= 0) then
            call fatal_error(error, "implicit Euler: the iteration matrix M + h C + h^2 K is "// &
                             "singular", stickslip_stat%numerical)
            return
        end if
        w = channel_directions(model, res%contacts)
        sw = w
        if (nch > 0) call dgetrs('N', n, nch, s, n, ipiv, sw, n, info)
        d = h*matmul(transpose(w), sw)
        do j = 1, nc
            limit(j) = res%contacts%elements(j)%e%force_scale()
        end do
        a(:, 1:n) = model%mass
        a(:, n + 1:2*n) = -h*model%stiffness
        do i = 1, model%nforce()
            a(:, 2*n + i) = force_direction(model, i)
        end do
        if (nf > model%nforce()) a(:, 2*n + nf) = pf
        ! the channels' kinematics: the compliances / h on the diagonal of the step matrix
        ! (the Delassus matrix d becomes A), gaps, which channels are gaps
        fscale = max(res%contacts%force_scale(), tiny(1.0_dp))
        sliders = .false.
        do c = 1, nch
            ch = res%contacts%channel(c)
            gap_channel(c) = ch%kinematics == kinematics_gap
            ch_gap(c) = ch%gap
            ch_c(c) = ch%compliance/h
            d(c, c) = d(c, c) + ch_c(c)
            if (ch%kinematics == kinematics_velocity .and. ch%compliance > 0.0_dp) &
                sliders = .true.
        end do
        if (inverse) then
            call dgetrs('N', n, ny, s, n, ipiv, a, n, info)
            ! S^{-1} of a chain or a beam decays away from the diagonal into subnormal
            ! numbers, whose products cost ~100 times a normal one: entries below 1e-30 of
            ! their column's largest are set to zero (a change far below roundoff)
            do j = 1, ny
                acc = 1.0e-30_dp*maxval(abs(a(:, j)))
                do k = 1, n
                    if (abs(a(k, j)) < acc) a(k, j) = 0.0_dp
                end do
            end do
        end if
        ! W^T A for one contact: its slip velocity without friction (the 2-DOF kernel)
        allocate (wa(ny))
        wa = 0.0_dp
        if (nc == 1) then
            do j = 1, ny
                do k = 1, n
                    wa(j) = wa(j) + w(k, 1)*a(k, j)
                end do
            end do
        end if
        fh = real(model%force_harmonic, dp)*model%omega
        famp = h*model%force_amplitude
        fph = model%force_phase
        if (nf > model%nforce()) then
            ! the preload: a constant term of unit amplitude
            fh = [fh, 0.0_dp]
            famp = [famp, h]
            fph = [fph, 0.0_dp]
        end if

        nblock = min(ns, block_steps)
        allocate (res%t(ns), res%x(ns, n), res%v(ns, n), res%r(ns, nch), fc(nf, nblock), &
                  us(ns, nch))
        us = 0.0_dp
        uprev = 0.0_dp
        do k = 1, ns
            res%t(k) = period_t*real(k - 1, dp)/real(ns, dp)
        end do
        y = 0.0_dp
        if (present(v0)) y(1:n) = v0
        if (present(x0)) y(n + 1:2*n) = x0
        r = 0.0_dp
        res%max_sweeps = 0

        ! No allocation, no array temporary and (up to inverse_max_ndof unknowns) no library
        ! call in the step loop: the loops below are written out for that. Subnormal numbers
        ! (below 2.2e-308) are flushed to zero in the loop where the processor allows it:
        ! from rest, the far end of a chain or a beam holds subnormal states for many steps,
        ! and their products cost ~100 normal ones (N = 256: half the time). The caller's
        ! underflow mode is restored after the loop.
        ftz = ieee_support_underflow_control(1.0_dp)
        if (ftz) then
            call ieee_get_underflow_mode(gradual)
            call ieee_set_underflow_mode(.false.)
        end if
        do period = 1, opts%max_periods
            ystart = y
            rstart = r
            do first = 1, ns, nblock
                last = min(ns, first + nblock - 1)
                ! the forcing coefficients of a block of steps first, apart from the steps: the
                ! cosines then overlap each other instead of stalling the chain of the steps
                do step = first, last
                    t = period_t*(real(period - 1, dp) + real(step, dp)/real(ns, dp))
                    do i = 1, nf
                        fc(i, step - first + 1) = famp(i)*cos(fh(i)*t + fph(i))
                    end do
                end do
                if (.not. fast) then
                    call step_block_elements(res%contacts, n, nch, nf, ns, first, last, h, &
                                             inverse, a, s, ipiv, w, sw, d, ch_gap, ch_c, &
                                             gap_channel, fscale, opts, fc, y, vf, r, q, &
                                             uprev, res%x, res%v, res%r, us, res%max_sweeps)
                else if (n == 2 .and. nc == 1 .and. nf >= 1 .and. inverse) then
                    call step_block_2(nf, ns, first, last, h, a, wa, sw, d(1, 1), limit(1), fc, y, &
                                      r(1), res%x, res%v, res%r)
                else
                    call step_block(n, nc, nf, ns, first, last, h, inverse, a, s, ipiv, w, sw, &
                                    d, limit, opts, fc, y, vf, r, ufree, res%x, res%v, res%r, &
                                    res%max_sweeps)
                end if
            end do
            res%periods = period
            ! the last stored period runs from ystart to y: compare the two ends
            ampx = maxval(abs(res%x))
            ampv = maxval(abs(res%v))
            if (.not. finite_state(y(1:2*n)) .or. ampx > 1.0e100_dp) then
                res%diagnosis = "unbounded response: the state overflowed during period "// &
                                itoa(period)
                res%defect = huge(1.0_dp)
                exit
            end if
            dx = 0.0_dp
            dv = 0.0_dp
            do k = 1, n
                dv = max(dv, abs(y(k) - ystart(k)))
                dx = max(dx, abs(y(n + k) - ystart(n + k)))
            end do
            dx = dx/max(ampx, tiny(1.0_dp))
            dv = dv/max(ampv, tiny(1.0_dp))
            if (ampx == 0.0_dp .and. ampv == 0.0_dp) then
                dx = 0.0_dp
                dv = 0.0_dp
            end if
            res%defect = max(dx, dv)
            if (sliders) then
                ! a slider behind a spring keeps its force as state
                dr = maxval(abs(r - rstart))/max(maxval(abs(res%r)), tiny(1.0_dp))
                if (maxval(abs(res%r)) == 0.0_dp) dr = 0.0_dp
                res%defect = max(res%defect, dr)
            end if
            if (res%defect <= opts%tol) then
                res%periodic = .true.
                exit
            end if
            if (present(progress)) then
                write (defect_text, '(a,es9.2e3)') "periodicity defect ", res%defect
                call progress%report(period, opts%max_periods, trim(defect_text))
            end if
        end do

        if (ftz) call ieee_set_underflow_mode(gradual)

        if (.not. res%periodic .and. .not. allocated(res%diagnosis)) then
            write (buf, '(a,i0,a,es10.2e3,a,es10.2e3,a)') "no periodic state after ", res%periods, &
                " periods: the states one period apart still differ by ", res%defect, &
                " of the amplitude (tol ", opts%tol, "); the response drifts, is "// &
                "quasi-periodic or decays too slowly (raise &euler max_periods or add damping)"
            res%diagnosis = trim(buf)
        else if (res%periodic) then
            res%diagnosis = ""
        end if
        if (.not. res%periodic) call res%diagnostics%add(level_untrusted, "not_periodic", &
                                                         res%diagnosis)
        ! the contacts' states, normal forces and gaps over the last period (each sample:
        ! after the step before it); the Coulomb kernels leave the slip velocities to here
        if (fast) us = matmul(res%v, w)
        allocate (res%state(ns, nc), res%normal(ns, nc), res%gap(ns, nc))
        associate (cs => res%contacts)
            do j = 1, nc
                associate (c0 => cs%first(j), m => cs%width(j))
                    acc = 0.0_dp
                    do k = c0, c0 + m - 1
                        acc = acc + d(k, k)/m
                    end do
                    call cs%elements(j)%e%step_states(max(acc, tiny(1.0_dp)), &
                                                      res%r(:, c0:c0 + m - 1), &
                                                      us(:, c0:c0 + m - 1), res%state(:, j))
                end associate
                if (cs%normal(j) > 0) then
                    res%normal(:, j) = res%r(:, cs%normal(j))
                    res%gap(:, j) = ch_gap(cs%normal(j)) + &
                                    matmul(res%x, contact_normal_direction(model, j))
                else
                    res%normal(:, j) = cs%elements(j)%e%normal_load()
                    res%gap(:, j) = 0.0_dp
                end if
            end do
        end associate
        call last_period_measures(res, model, us, d, period_t)
        call system_clock(c1)
        res%seconds = real(c1 - c0, dp)/real(rate, dp)
    end subroutine integrate_euler

    !> Steps first..last of a period (the kernel of integrate_euler): from the state y =
    !> [v; x; c] and the forces r, store each step's starting state in xs, vs, rs, set the
    !> forcing coefficients from fc, form the free velocity A y (solved with the LU factors
    !> of S unless A holds S^{-1} [M, -h K, F]), the friction forces and the new v and x.
    subroutine step_block(n, nc, nf, ns, first, last, h, inverse, a, s, ipiv, w, sw, d, &
                          limit, opts, fc, y, vf, r, ufree, xs, vs, rs, max_sweeps)
        !> Degrees of freedom, contacts, forcing terms, steps per period.
        integer, intent(in) :: n, nc, nf, ns
        !> First and last step of the block (1..ns).
        integer, intent(in) :: first, last
        !> Time step [s].
        real(dp), intent(in) :: h
        !> A holds S^{-1} [M, -h K, F] (else [M, -h K, F] and S its LU factors).
        logical, intent(in) :: inverse
        !> The free-velocity matrix, N x (2N + n_f).
        real(dp), intent(in) :: a(n, 2*n + nf)
        !> LU factors of S (dgetrf) and their pivots.
        real(dp), intent(in) :: s(n, n)
        !> Pivots of the LU factors.
        integer, intent(in) :: ipiv(n)
        !> Contact directions W and S^{-1} W, N x n_c.
        real(dp), intent(in) :: w(n, nc), sw(n, nc)
        !> Delassus matrix h W^T S^{-1} W.
        real(dp), intent(in) :: d(nc, nc)
        !> Friction limits mu N [N].
        real(dp), intent(in) :: limit(nc)
        !> Contact tolerances and sweeps.
        type(euler_options_t), intent(in) :: opts
        !> Forcing coefficients of the block's steps, n_f x (last - first + 1).
        real(dp), intent(in) :: fc(nf, *)
        !> State [v; x; c]: start of the block on entry, end on exit.
        real(dp), intent(inout) :: y(2*n + nf)
        !> Work: the free velocity.
        real(dp), intent(inout) :: vf(n)
        !> Friction forces: of the last step on entry, updated [N].
        real(dp), intent(inout) :: r(nc)
        !> Work: the free slip velocities.
        real(dp), intent(inout) :: ufree(nc)
        !> The samples of the period: displacements, velocities (ns x N), forces (ns x n_c).
        real(dp), intent(inout) :: xs(ns, n), vs(ns, n), rs(ns, nc)
        !> Most Gauss-Seidel sweeps of a step so far.
        integer, intent(inout) :: max_sweeps
        integer :: i, j, k, step, ny, sweeps, info
        real(dp) :: acc
        ny = 2*n + nf
        do step = first, last
            ! the state at the start of this step is sample step of the period
            do k = 1, n
                vs(step, k) = y(k)
                xs(step, k) = y(n + k)
            end do
            do j = 1, nc
                rs(step, j) = r(j)
            end do
            do i = 1, nf
                y(2*n + i) = fc(i, step - first + 1)
            end do
            ! free velocity: A y, solved with S unless A holds S^{-1} [M, -h K, F]
            call free_velocity(n, ny, a, y, inverse, s, ipiv, vf)
            ! friction forces, then v = v_free + h S^{-1} W r
            if (nc == 1) then
                acc = 0.0_dp
                do k = 1, n
                    acc = acc + w(k, 1)*vf(k)
                end do
                r(1) = max(-limit(1), min(limit(1), -acc/d(1, 1)))
                do k = 1, n
                    y(k) = vf(k) + h*(sw(k, 1)*r(1))
                end do
            else if (nc > 1) then
                do j = 1, nc
                    acc = 0.0_dp
                    do k = 1, n
                        acc = acc + w(k, j)*vf(k)
                    end do
                    ufree(j) = acc
                end do
                call contact_forces(d, ufree, limit, r, opts%contact_tol, &
                                    opts%contact_max_sweeps, sweeps)
                max_sweeps = max(max_sweeps, sweeps)
                do k = 1, n
                    acc = 0.0_dp
                    do j = 1, nc
                        acc = acc + sw(k, j)*r(j)
                    end do
                    y(k) = vf(k) + h*acc
                end do
            else
                do k = 1, n
                    y(k) = vf(k)
                end do
            end if
            do k = 1, n
                y(n + k) = y(n + k) + h*y(k)
            end do
        end do
    end subroutine step_block

    !> step_block for 2 DOF and one contact on the inverse path (the seed case's shape)
    !> with scalars, without the loop overhead that is most of a step at this size: the
    !> forcing terms of the block's steps summed first, the slip velocity formed as
    !> (W^T A) y beside the free velocity rather than after it.
    subroutine step_block_2(nf, ns, first, last, h, a, b, sw, d, limit, fc, y, r, xs, vs, rs)
        !> Forcing terms, steps per period, first and last step of the block.
        integer, intent(in) :: nf, ns, first, last
        !> Time step [s].
        real(dp), intent(in) :: h
        !> S^{-1} [M, -h K, F], 2 x (4 + n_f).
        real(dp), intent(in) :: a(2, 4 + nf)
        !> W^T A: the slip velocity W^T S^{-1} [M, -h K, F] y of the free velocity.
        real(dp), intent(in) :: b(4 + nf)
        !> S^{-1} W.
        real(dp), intent(in) :: sw(2)
        !> Delassus number h W^T S^{-1} W and friction limit mu N [N].
        real(dp), intent(in) :: d, limit
        !> Forcing coefficients of the block's steps, n_f x (last - first + 1).
        real(dp), intent(in) :: fc(nf, *)
        !> State [v; x; c]: start of the block on entry, end on exit.
        real(dp), intent(inout) :: y(4 + nf)
        !> Friction force: of the last step on entry, updated [N].
        real(dp), intent(inout) :: r
        !> The samples of the period.
        real(dp), intent(inout) :: xs(ns, 2), vs(ns, 2), rs(ns)
        real(dp) :: v1, v2, x1, x2, f1, f2, u, g(3, block_steps)
        integer :: step, i, k
        do k = 1, last - first + 1
            g(1, k) = a(1, 5)*fc(1, k)
            g(2, k) = a(2, 5)*fc(1, k)
            g(3, k) = b(5)*fc(1, k)
            do i = 2, nf
                g(1, k) = g(1, k) + a(1, 4 + i)*fc(i, k)
                g(2, k) = g(2, k) + a(2, 4 + i)*fc(i, k)
                g(3, k) = g(3, k) + b(4 + i)*fc(i, k)
            end do
        end do
        v1 = y(1)
        v2 = y(2)
        x1 = y(3)
        x2 = y(4)
        do step = first, last
            vs(step, 1) = v1
            vs(step, 2) = v2
            xs(step, 1) = x1
            xs(step, 2) = x2
            rs(step) = r
            k = step - first + 1
            f1 = a(1, 1)*v1 + a(1, 2)*v2 + a(1, 3)*x1 + a(1, 4)*x2 + g(1, k)
            f2 = a(2, 1)*v1 + a(2, 2)*v2 + a(2, 3)*x1 + a(2, 4)*x2 + g(2, k)
            u = b(1)*v1 + b(2)*v2 + b(3)*x1 + b(4)*x2 + g(3, k)
            r = max(-limit, min(limit, -u/d))
            v1 = f1 + h*(sw(1)*r)
            v2 = f2 + h*(sw(2)*r)
            x1 = x1 + h*v1
            x2 = x2 + h*v2
        end do
        y(1) = v1
        y(2) = v2
        y(3) = x1
        y(4) = x2
        y(5:) = fc(:, last - first + 1)
    end subroutine step_block_2

    !> The derived quantities of the last period (stickslip_contact_measures) and its
    !> energies by the rectangle rule on the steps: sample k holds the velocity and the
    !> forces at the end of the step before it.
    subroutine last_period_measures(res, model, us, a, period)
        type(euler_result_t), intent(inout) :: res
        type(model_t), intent(in) :: model
        real(dp), intent(in) :: us(:, :), a(:, :), period
        type(contact_measures_t) :: cm
        real(dp), allocatable :: f(:, :), pw(:), d(:, :)
        real(dp) :: h, rho
        integer :: ns, i, k
        ns = size(res%t)
        h = period/ns
        rho = 1.0_dp
        if (size(a, 1) > 0) rho = max(sum([(a(k, k), k=1, size(a, 1))])/size(a, 1), tiny(1.0_dp))
        call measure_contacts(res%contacts, rho, res%r, us, res%state, period, 1, cm)
        res%open_fraction = cm%open_fraction
        res%stick_fraction = cm%stick_fraction
        res%slip_fraction = cm%slip_fraction
        res%stick_phases = cm%stick_phases
        res%diss_coulomb = cm%diss_coulomb
        res%max_force_ratio = cm%force_ratio
        res%u = us
        ! the forcing's power at the samples (the force of the step ending there): each
        ! force's time function times its direction's velocity
        allocate (f(model%ndof, model%nforce()), pw(ns))
        do i = 1, model%nforce()
            f(:, i) = force_direction(model, i)
        end do
        d = matmul(res%v, f)
        pw = 0.0_dp
        do i = 1, model%nforce()
            do k = 1, ns
                pw(k) = pw(k) + model%force_amplitude(i)*cos(model%force_harmonic(i)* &
                        model%omega*res%t(k) + model%force_phase(i))*d(k, i)
            end do
        end do
        res%work_forcing = h*sum(pw)
        res%work_gross = h*sum(abs(pw))
        d = channel_directions(model, res%contacts)
        res%diss_friction = -h*sum(res%r*matmul(res%v, d))
        ! v_k^T C v_k summed over the samples: V C by BLAS (O(ns N^2), once per call)
        deallocate (d)
        allocate (d(ns, model%ndof))
        call dgemm('N', 'N', ns, model%ndof, model%ndof, 1.0_dp, res%v, ns, model%damping, &
                   model%ndof, 0.0_dp, d, ns)
        res%diss_damping = h*sum(res%v*d)
    end subroutine last_period_measures

    !> Steps first..last of a period with contact elements (the kernel of integrate_euler
    !> beside the Coulomb kernels): from the state y = [v; x; c] and the channel forces r,
    !> store each step's starting state in xs, vs, rs, us (the forces and kinematic
    !> quantities of the step before), set the forcing coefficients from fc, form the free
    !> velocity, the free kinematic quantities q of the channels (velocity channels: d^T v_free
    !> - c r_n / h; gap channels: d^T v_free + (gap + d^T x_n) / h), the forces of every
    !> element (contact_set_t%step_forces on u = q + A r), and the new v and x.
    subroutine step_block_elements(cs, n, nch, nf, ns, first, last, h, inverse, amat, s, ipiv, &
                                   w, sw, am, ch_gap, ch_c, gap_channel, fscale, opts, fc, y, &
                                   vf, r, q, uprev, xs, vs, rs, us, max_sweeps_used)
        !> The contact elements.
        type(contact_set_t), intent(in) :: cs
        !> Degrees of freedom, channels, forcing terms (with the preload), steps per period.
        integer, intent(in) :: n, nch, nf, ns
        !> First and last step of the block (1..ns).
        integer, intent(in) :: first, last
        !> Time step [s].
        real(dp), intent(in) :: h
        !> amat holds S^{-1} [M, -h K, F] (else [M, -h K, F] and s the LU factors of S).
        logical, intent(in) :: inverse
        !> The free-velocity matrix, N x (2N + n_f).
        real(dp), intent(in) :: amat(n, 2*n + nf)
        !> LU factors of S and their pivots.
        real(dp), intent(in) :: s(n, n)
        integer, intent(in) :: ipiv(n)
        !> Channel directions D and S^{-1} D, N x n_ch.
        real(dp), intent(in) :: w(n, nch), sw(n, nch)
        !> A = h D^T S^{-1} D + diag(compliance / h), n_ch x n_ch [m/(N s)].
        real(dp), intent(in) :: am(nch, nch)
        !> Per channel: its gap [m], compliance / h [m/(N s)], whether it is a gap channel.
        real(dp), intent(in) :: ch_gap(nch), ch_c(nch)
        logical, intent(in) :: gap_channel(nch)
        !> Force scale of the tolerances [N].
        real(dp), intent(in) :: fscale
        !> Contact tolerance and sweeps.
        type(euler_options_t), intent(in) :: opts
        !> Forcing coefficients of the block's steps, n_f x (last - first + 1).
        real(dp), intent(in) :: fc(nf, *)
        !> State [v; x; c]: start of the block on entry, end on exit.
        real(dp), intent(inout) :: y(2*n + nf)
        !> Work: the free velocity, the free kinematic quantities.
        real(dp), intent(inout) :: vf(n), q(nch)
        !> Channel forces and kinematic quantities of the last step (updated).
        real(dp), intent(inout) :: r(nch), uprev(nch)
        !> The samples of the period: displacements, velocities (ns x N), channel forces and
        !> kinematic quantities (ns x n_ch).
        real(dp), intent(inout) :: xs(ns, n), vs(ns, n), rs(ns, nch), us(ns, nch)
        !> Most sweeps of a step so far.
        integer, intent(inout) :: max_sweeps_used
        integer :: i, j, k, step, ny, sweeps
        real(dp) :: acc
        ny = 2*n + nf
        do step = first, last
            do k = 1, n
                vs(step, k) = y(k)
                xs(step, k) = y(n + k)
            end do
            rs(step, :) = r
            us(step, :) = uprev
            do i = 1, nf
                y(2*n + i) = fc(i, step - first + 1)
            end do
            call free_velocity(n, ny, amat, y, inverse, s, ipiv, vf)
            do j = 1, nch
                acc = 0.0_dp
                do k = 1, n
                    acc = acc + w(k, j)*vf(k)
                end do
                q(j) = acc
                if (gap_channel(j)) then
                    acc = ch_gap(j)
                    do k = 1, n
                        acc = acc + w(k, j)*y(n + k)
                    end do
                    q(j) = q(j) + acc/h
                else
                    q(j) = q(j) - ch_c(j)*r(j)
                end if
            end do
            call cs%step_forces(am, q, r, max(fscale, maxval(abs(r))), opts%contact_tol, &
                                opts%contact_max_sweeps, sweeps)
            max_sweeps_used = max(max_sweeps_used, sweeps)
            do k = 1, n
                acc = 0.0_dp
                do j = 1, nch
                    acc = acc + sw(k, j)*r(j)
                end do
                y(k) = vf(k) + h*acc
            end do
            do k = 1, n
                y(n + k) = y(n + k) + h*y(k)
            end do
            do j = 1, nch
                acc = q(j)
                do k = 1, nch
                    acc = acc + am(j, k)*r(k)
                end do
                uprev(j) = acc
            end do
        end do
    end subroutine step_block_elements

    !> The free velocity of a step, vf = S^-1 A y: the written-out product A y (no array
    !> temporary), then solved with the LU factors of S unless A already holds S^-1 [M,
    !> -h K, F] (`inverse`). Shared by the Coulomb and the elements' step kernels.
    subroutine free_velocity(n, ny, a, y, inverse, s, ipiv, vf)
        !> DOFs and the size of y.
        integer, intent(in) :: n, ny
        !> [M, -h K, F] or S^-1 times it, n x ny.
        real(dp), intent(in) :: a(n, ny)
        !> [v; x; forcing terms].
        real(dp), intent(in) :: y(ny)
        !> a holds S^-1 [M, -h K, F].
        logical, intent(in) :: inverse
        !> LU factors of S and their pivots (used when not inverse).
        real(dp), intent(in) :: s(n, n)
        integer, intent(in) :: ipiv(n)
        !> The free velocity [m/s].
        real(dp), intent(out) :: vf(n)
        integer :: j, k, info
        do k = 1, n
            vf(k) = a(k, 1)*y(1)
        end do
        do j = 2, ny
            do k = 1, n
                vf(k) = vf(k) + a(k, j)*y(j)
            end do
        end do
        if (.not. inverse) call dgetrs('N', n, 1, s, n, ipiv, vf, n, info)
    end subroutine free_velocity

    !> True when every entry of `z` is finite.
    pure logical function finite_state(z) result(ok)
        !> The state.
        real(dp), intent(in) :: z(:)
        integer :: k
        ok = .true.
        do k = 1, size(z)
            ok = ok .and. ieee_is_finite(z(k))
        end do
    end function finite_state
end module stickslip_euler
