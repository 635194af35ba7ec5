!> Benchmark of the implicit Euler stepper (a program that prints figures, not a test).
!> Run from the project root: fpm run --example bench_euler --profile release [-- repeats
!> [seed]] (seed: parts 1 and 2 only)
!> 1. Seed case (examples/seed.nml), 1000 steps per period, 400 periods: nanoseconds per step
!>    of the library stepper (integrate_euler), of the step loop it replaced (frozen below as
!>    legacy_euler) and of a hand-written 2x2 loop of the same scheme (hand_2x2), medians
!>    over the repeats, measured side by side, with the ratios and the end-state differences.
!> 2. The run of bench/euler_vs_python.sh inside the library: seed, 1000 steps per period,
!>    from rest until periodic (tol 1e-8).
!> 3. Dense N = 256 and N = 1024 chains (10 contacts): steps/s of the replaced loop, the LU
!>    path (inverse_max_ndof = 0) and the inverse path, and the set-up time of each.
!> 4. The figures of earlier sessions: the seed at h = 1e-4 s (about 2 million steps) and a
!>    100-DOF chain with 10 contacts.
program bench_euler
    use, intrinsic :: iso_fortran_env, only: output_unit, int64
    use stickslip_kinds, only: dp, two_pi
    use stickslip_sorting, only: sort_ascending
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t, contact_velocity_direction, force_direction
    use stickslip_lapack, only: dgetrf, dgetrs
    use stickslip_contact_solve, only: contact_forces
    use stickslip_case, only: case_t, read_case
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_blas_threads, only: limit_blas_threads
    implicit none
    type(case_t) :: c, cx
    integer :: icase
    character(len=*), parameter :: examples(2) = [character(len=24) :: &
                                                  "examples/many_sticks.nml", "examples/chain4.nml"]
    type(model_t) :: m
    type(euler_options_t) :: o
    type(euler_result_t) :: res, old, hand
    type(error_type), allocatable :: error
    integer :: i, steps, repeats, nargs, sizes(2), isize
    real(dp), allocatable :: tlib(:), told(:), thand(:)
    real(dp) :: dlib, dold, dhand, t0, t1
    character(len=32) :: arg
    logical :: seed_only

    call limit_blas_threads()
    repeats = 5
    nargs = command_argument_count()
    if (nargs >= 1) then
        call get_command_argument(1, arg)
        read (arg, *) repeats
    end if
    seed_only = .false.
    if (nargs >= 2) then
        call get_command_argument(2, arg)
        seed_only = arg == 'seed'
    end if
    call read_case("examples/seed.nml", c, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if

    ! 1. per step, seed, 1000 steps per period, 400 periods (no early exit: tol tiny)
    o%steps_per_period = 1000
    o%max_periods = 400
    o%tol = 1.0e-300_dp
    allocate (tlib(repeats), told(repeats), thand(repeats))
    ! CPU time (the machine is shared: wall time counts other processes' turns)
    do i = 1, repeats
        call cpu_time(t0)
        call integrate_euler(c%model, o, res, error)
        call cpu_time(t1)
        tlib(i) = t1 - t0
        call legacy_euler(c%model, o, old)
        call cpu_time(t0)
        told(i) = t0 - t1
        call hand_2x2(c%model, o, hand)
        call cpu_time(t1)
        thand(i) = t1 - t0
        call integrate_euler(c%model, o, res, error)
        call cpu_time(t0)
        tlib(i) = min(tlib(i), t0 - t1)
    end do
    steps = o%steps_per_period*o%max_periods
    dlib = median(tlib)/steps*1.0e9_dp
    dold = median(told)/steps*1.0e9_dp
    dhand = median(thand)/steps*1.0e9_dp
    write (output_unit, '(a,i0,a,i0,a)') "seed, 1000 steps per period, ", steps, &
        " steps, median of ", repeats, " (release build):"
    write (output_unit, '(a,f8.1,a)') "  library stepper (integrate_euler): ", dlib, " ns/step"
    write (output_unit, '(a,f8.1,a,f6.2,a)') "  replaced step loop (legacy):       ", dold, &
        " ns/step  (", dold/dlib, "x the library's time)"
    write (output_unit, '(a,f8.1,a,f6.2,a)') "  hand-written 2x2 loop:             ", dhand, &
        " ns/step  (library / hand = ", dlib/dhand, ")"
    write (output_unit, '(a,es9.2,a,es9.2)') "  last period, max |x - x_hand| / max |x|: ", &
        maxval(abs(res%x - hand%x))/maxval(abs(hand%x)), ", against the replaced loop: ", &
        maxval(abs(res%x - old%x))/maxval(abs(old%x))

    ! per step on the other examples (the general kernel): library against the replaced loop
    do icase = 1, 2
        call read_case(trim(examples(icase)), cx, error)
        if (allocated(error)) then
            write (output_unit, '(a)') "error: "//error%message
            stop 1
        end if
        o%max_periods = 100
        do i = 1, repeats
            call cpu_time(t0)
            call integrate_euler(cx%model, o, res, error)
            call cpu_time(t1)
            tlib(i) = t1 - t0
            call legacy_euler(cx%model, o, old)
            call cpu_time(t0)
            told(i) = t0 - t1
        end do
        steps = o%steps_per_period*o%max_periods
        write (output_unit, '(a,a,i0,a,i0,a,i0,a,f0.1,a,f0.1,a,f0.2,a,es9.2)') &
            trim(examples(icase)), " (", cx%model%ndof, " DOF, ", cx%model%ncontact(), &
            " contacts, ", cx%model%nforce(), " forces): library ", median(tlib)/steps*1e9_dp, &
            " ns/step, replaced loop ", median(told)/steps*1e9_dp, " ns/step (", &
            median(told)/median(tlib), "x); last period max |x - x_old| / max |x|: ", &
            maxval(abs(res%x - old%x))/maxval(abs(old%x))
    end do

    ! 2. the run of bench/euler_vs_python.sh: from rest until periodic
    o%tol = 1.0e-8_dp
    o%max_periods = 2000
    do i = 1, repeats
        call cpu_time(t0)
        call integrate_euler(c%model, o, res, error)
        call cpu_time(t1)
        tlib(i) = t1 - t0
        call legacy_euler(c%model, o, old)
        call cpu_time(t0)
        told(i) = t0 - t1
    end do
    write (output_unit, '(a,i0,a,f0.2,a,f0.2,a)') "seed from rest until periodic (", &
        res%periods, " periods of 1000 steps): ", median(tlib)*1e3_dp, " ms (replaced loop ", &
        median(told)*1e3_dp, " ms)"

    if (seed_only) stop
    ! 3. dense chains
    sizes = [256, 1024]
    do isize = 1, 2
        call dense_chain(sizes(isize))
    end do

    ! 4. figures of earlier sessions
    o = euler_options_t()
    o%steps_per_period = nint(two_pi/c%model%omega/1.0e-4_dp)
    o%max_periods = 2000000/o%steps_per_period
    o%tol = 1.0e-15_dp
    call integrate_euler(c%model, o, res, error)
    steps = o%steps_per_period*res%periods
    write (output_unit, '(a,i0,a,i0,a,f0.3,a,es9.2,a)') "seed, h = 1e-4 s: ", steps, &
        " steps (", res%periods, " periods) in ", res%seconds, " s = ", &
        steps/res%seconds, " steps/s"
    m = chain(100)
    o = euler_options_t()
    o%steps_per_period = 1000
    o%max_periods = 50
    o%tol = 1.0e-15_dp
    call integrate_euler(m, o, res, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    steps = o%steps_per_period*res%periods
    write (output_unit, '(a,i0,a,f0.3,a,es9.2,a,i0)') "100-DOF chain, 10 contacts: ", steps, &
        " steps in ", res%seconds, " s = ", steps/res%seconds, &
        " steps/s; most Gauss-Seidel sweeps in a step: ", res%max_sweeps

contains

    !> Steps/s of the three paths on an n-DOF dense chain: runs of 1 and 3 periods of 100
    !> steps; per step = the difference / 200 steps, set-up = the 1-period run less its steps.
    subroutine dense_chain(n)
        integer, intent(in) :: n
        type(model_t) :: mc
        type(euler_options_t) :: oc
        real(dp) :: t1(3), t3(3), per, setup, ta, tb
        integer :: path, k
        character(len=*), parameter :: names(3) = [character(len=24) :: "replaced loop", &
                                                   "LU path (dgetrs)", "inverse path"]
        mc = chain(n)
        oc%steps_per_period = 100
        oc%tol = 1.0e-300_dp
        do path = 1, 3
            oc%inverse_max_ndof = merge(0, huge(1), path == 2)
            do k = 1, 3
                oc%max_periods = merge(1, 3, k == 1)
                call cpu_time(ta)
                if (path == 1) then
                    call legacy_euler(mc, oc, res)
                else
                    call integrate_euler(mc, oc, res, error)
                end if
                call cpu_time(tb)
                t1(k) = tb - ta
            end do
            ! t1(1): 1 period; t1(2), t1(3): 3 periods
            t3(path) = min(t1(2), t1(3))
            per = (t3(path) - t1(1))/(2*oc%steps_per_period)
            setup = max(t1(1) - per*oc%steps_per_period, 0.0_dp)
            write (output_unit, '(a,i0,a,a,a,es9.2,a,f0.3,a)') "dense chain N = ", n, &
                ", 10 contacts, ", names(path), ": ", 1.0_dp/per, " steps/s, set-up ", &
                setup, " s"
        end do
    end subroutine dense_chain

    !> n-DOF chain stored dense, 10 grounded contacts on every (n/10)-th DOF, light damping.
    function chain(n) result(mc)
        integer, intent(in) :: n
        type(model_t) :: mc
        integer :: k
        mc%ndof = n
        allocate (mc%mass(n, n), mc%stiffness(n, n))
        mc%mass = 0.0_dp
        mc%stiffness = 0.0_dp
        do k = 1, n
            mc%mass(k, k) = 1.0_dp
            mc%stiffness(k, k) = 2.0_dp
            if (k < n) then
                mc%stiffness(k, k + 1) = -1.0_dp
                mc%stiffness(k + 1, k) = -1.0_dp
            end if
        end do
        mc%damping = 0.01_dp*mc%stiffness
        mc%omega = 0.8_dp
        mc%force_dof = [1]
        mc%force_harmonic = [1]
        mc%force_amplitude = [5.0_dp]
        mc%force_phase = [0.0_dp]
        mc%contact_dof = [((n/10)*k, k=1, 10)]
        mc%contact_dof2 = [(0, k=1, 10)]
        mc%mu = [(0.3_dp, k=1, 10)]
        mc%normal_load = [(1.0_dp, k=1, 10)]
    end function chain

    real(dp) function median(a)
        real(dp), intent(in) :: a(:)
        real(dp) :: b(size(a))
        b = a
        call sort_ascending(b)
        median = b((size(b) + 1)/2)
    end function median

    !> The same scheme written by hand for 2 DOF and one contact on DOF 2 against the ground,
    !> forcing on DOF 1 (the seed case): S inverted by the 2x2 formula, scalars only; stores
    !> the last period and tests periodicity like integrate_euler.
    subroutine hand_2x2(model, opts, res)
        type(model_t), intent(in) :: model
        type(euler_options_t), intent(in) :: opts
        type(euler_result_t), intent(out) :: res
        real(dp) :: h, pt, s(2, 2), si(2, 2), det, p(2, 4), g(2), sw(2), d, lim, t, cf, &
                    v1, v2, x1, x2, f1, f2, r, om, amp, ph, xs1, xs2, vs1, vs2, ampx, ampv, dx, dv
        real(dp), allocatable :: cfs(:)
        integer :: ns, period, step
        integer(int64) :: c0, c1, rate
        call system_clock(c0, rate)
        ns = opts%steps_per_period
        pt = two_pi/model%omega
        h = pt/ns
        s = model%mass + h*model%damping + h*h*model%stiffness
        det = s(1, 1)*s(2, 2) - s(1, 2)*s(2, 1)
        si = reshape([s(2, 2), -s(2, 1), -s(1, 2), s(1, 1)], [2, 2])/det
        p(:, 1:2) = matmul(si, model%mass)
        p(:, 3:4) = matmul(si, -h*model%stiffness)
        g = si(:, 1)
        sw = si(:, 2)
        d = h*sw(2)
        lim = model%mu(1)*model%normal_load(1)
        om = model%force_harmonic(1)*model%omega
        amp = h*model%force_amplitude(1)
        ph = model%force_phase(1)
        allocate (res%t(ns), res%x(ns, 2), res%v(ns, 2), res%r(ns, 1), cfs(ns))
        v1 = 0.0_dp
        v2 = 0.0_dp
        x1 = 0.0_dp
        x2 = 0.0_dp
        r = 0.0_dp
        do period = 1, opts%max_periods
            xs1 = x1
            xs2 = x2
            vs1 = v1
            vs2 = v2
            do step = 1, ns
                t = pt*(real(period - 1, dp) + real(step, dp)/real(ns, dp))
                cfs(step) = amp*cos(om*t + ph)
            end do
            do step = 1, ns
                res%x(step, 1) = x1
                res%x(step, 2) = x2
                res%v(step, 1) = v1
                res%v(step, 2) = v2
                res%r(step, 1) = r
                cf = cfs(step)
                f1 = p(1, 1)*v1 + p(1, 2)*v2 + p(1, 3)*x1 + p(1, 4)*x2 + g(1)*cf
                f2 = p(2, 1)*v1 + p(2, 2)*v2 + p(2, 3)*x1 + p(2, 4)*x2 + g(2)*cf
                r = max(-lim, min(lim, -f2/d))
                v1 = f1 + h*(sw(1)*r)
                v2 = f2 + h*(sw(2)*r)
                x1 = x1 + h*v1
                x2 = x2 + h*v2
            end do
            res%periods = period
            ampx = maxval(abs(res%x))
            ampv = maxval(abs(res%v))
            dx = max(abs(x1 - xs1), abs(x2 - xs2))/max(ampx, tiny(1.0_dp))
            dv = max(abs(v1 - vs1), abs(v2 - vs2))/max(ampv, tiny(1.0_dp))
            res%defect = max(dx, dv)
            if (res%defect <= opts%tol) then
                res%periodic = .true.
                exit
            end if
        end do
        call system_clock(c1)
        res%seconds = real(c1 - c0, dp)/real(rate, dp)
    end subroutine hand_2x2

    !> The step loop before issue 12 (commit 502f373), frozen: per step b = M v - h K x + h f
    !> by matmul, a dgetrs with the LU factors of S, the friction forces, v and x.
    subroutine legacy_euler(model, opts, res)
        type(model_t), intent(in) :: model
        type(euler_options_t), intent(in) :: opts
        type(euler_result_t), intent(out) :: res
        integer :: n, nc, ns, info, j, period, step, sweeps, k
        real(dp) :: h, period_t, tt, ampx, ampv, dx, dv
        real(dp), allocatable :: s(:, :), sw(:, :), d(:, :), w(:, :), b(:), wk(:), x(:), v(:), &
                                 xstart(:), vstart(:), r(:), ufree(:), limit(:), famp(:), fph(:), &
                                 fshape(:, :)
        integer, allocatable :: ipiv(:), fh(:)
        integer(int64) :: c0, c1, rate
        call system_clock(c0, rate)
        n = model%ndof
        nc = model%ncontact()
        ns = opts%steps_per_period
        period_t = two_pi/model%omega
        h = period_t/ns
        allocate (s(n, n), sw(n, nc), d(nc, nc), w(n, nc), b(n), wk(n), x(n), v(n), xstart(n), &
                  vstart(n), r(nc), ufree(nc), limit(nc), ipiv(n))
        s = model%mass + h*model%damping + h*h*model%stiffness
        call dgetrf(n, n, s, n, ipiv, info)
        do j = 1, nc
            w(:, j) = contact_velocity_direction(model, j)
        end do
        sw = w
        if (nc > 0) call dgetrs('N', n, nc, s, n, ipiv, sw, n, info)
        d = h*matmul(transpose(w), sw)
        limit = model%mu*model%normal_load
        allocate (fshape(n, model%nforce()))
        do k = 1, model%nforce()
            fshape(:, k) = force_direction(model, k)
        end do
        fh = model%force_harmonic
        famp = model%force_amplitude
        fph = model%force_phase
        allocate (res%t(ns), res%x(ns, n), res%v(ns, n), res%r(ns, nc))
        x = 0.0_dp
        v = 0.0_dp
        r = 0.0_dp
        res%max_sweeps = 0
        do period = 1, opts%max_periods
            xstart = x
            vstart = v
            do step = 1, ns
                res%x(step, :) = x
                res%v(step, :) = v
                res%r(step, :) = r
                tt = period_t*(real(period - 1, dp) + real(step, dp)/real(ns, dp))
                b = matmul(model%mass, v)
                wk = matmul(model%stiffness, x)
                b = b - h*wk
                do k = 1, size(fh)
                    b = b + (h*famp(k)*cos(fh(k)*model%omega*tt + fph(k)))*fshape(:, k)
                end do
                call dgetrs('N', n, 1, s, n, ipiv, b, n, info)
                v = b
                if (nc > 0) then
                    ufree = matmul(v, w)
                    call contact_forces(d, ufree, limit, r, opts%contact_tol, &
                                        opts%contact_max_sweeps, sweeps)
                    res%max_sweeps = max(res%max_sweeps, sweeps)
                    wk = matmul(sw, r)
                    v = v + h*wk
                end if
                x = x + h*v
            end do
            res%periods = period
            ampx = maxval(abs(res%x))
            ampv = maxval(abs(res%v))
            dx = maxval(abs(x - xstart))/max(ampx, tiny(1.0_dp))
            dv = maxval(abs(v - vstart))/max(ampv, tiny(1.0_dp))
            res%defect = max(dx, dv)
            if (res%defect <= opts%tol) then
                res%periodic = .true.
                exit
            end if
        end do
        call system_clock(c1)
        res%seconds = real(c1 - c0, dp)/real(rate, dp)
    end subroutine legacy_euler
end program bench_euler
