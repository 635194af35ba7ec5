!> The exact flow, the reference and the Floquet stability on a stiff reduced FE model: the
!> cantilever of examples/beam_mm (40 Euler-Bernoulli elements, 80 DOFs, C = 0.5 M + 1e-5 K)
!> reduced by Craig-Bampton to its forced and contact DOFs plus fixed-interface modes, one
!> friction contact at the tip. Its phase matrices reach |lambda| ~ 1e7 s^-1 against a
!> forcing at 50 rad/s and its M^-1 K has norm 1e12 in Craig-Bampton coordinates (the case
!> where the shooting stalled at a defect of 4e-9 and every sweep point was 'unknown').
!> Independent truth: the monodromy matrix by central finite differences of a period map
!> integrated by a 3-stage Radau IIA scheme (order 5, L-stable) written here, on the
!> model's own coordinates, the stuck contact eliminated as a DOF (not by the flow's
!> M-orthogonal projection), events located by regula falsi on the step length.
module test_stiff_flow
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_lapack, only: dgetrf, dgetrs
    use stickslip_sparse, only: sparse_matrix_t, sparse_from_dense
    use stickslip_reduction, only: reduction_options_t, reduction_report_t, reduced_model_t, &
        craig_bampton
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_reference, only: reference_options_t, reference_result_t
    use stickslip_stability, only: floquet_t, floquet_multipliers, periodic_stability
    use stickslip_flow, only: flow_t, new_flow
    use stickslip_flow_events, only: dip_samples, dip_bracket
    use testing, only: test_counter_t, check
    implicit none
    private
    public :: run_stiff_flow_tests

    !> Radau IIA, 3 stages: nodes and coefficients.
    real(dp), parameter :: s6 = sqrt(6.0_dp)
    real(dp), parameter :: rc(3) = [(4.0_dp - s6)/10.0_dp, (4.0_dp + s6)/10.0_dp, 1.0_dp]
    real(dp), parameter :: ra(3, 3) = reshape([ &
        (88.0_dp - 7.0_dp*s6)/360.0_dp, (296.0_dp + 169.0_dp*s6)/1800.0_dp, &
        (16.0_dp - s6)/36.0_dp, &
        (296.0_dp - 169.0_dp*s6)/1800.0_dp, (88.0_dp + 7.0_dp*s6)/360.0_dp, &
        (16.0_dp + s6)/36.0_dp, &
        (-2.0_dp + 3.0_dp*s6)/225.0_dp, (-2.0_dp - 3.0_dp*s6)/225.0_dp, 1.0_dp/9.0_dp], [3, 3])

    !> One contact mode of the independent integrator: z' = jm z + g(t), g = gf * cos/sin.
    type :: radau_mode_t
        !> Slip direction (+1, -1) or 0 stuck.
        integer :: s = 0
        real(dp), allocatable :: jm(:, :)
        !> Step length of the factorization, its LU and pivots.
        real(dp) :: h = -1.0_dp
        real(dp), allocatable :: lu(:, :)
        integer, allocatable :: ipiv(:)
    end type radau_mode_t

contains

    subroutine run_stiff_flow_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_verdicts(t)
        call test_monodromy_fd(t)
        call test_track_vs_ladder(t)
        call test_fresh_dips(t)
    end subroutine run_stiff_flow_tests

    !> The samples of a row that starts its phase at zero and flat, and the dip they find: a
    !> hump then a dip below zero within the step (what a stiff blade's slip velocity did
    !> after a grazing stick -> slip, 2 us into a 3 us step, unseen by the slopes at the
    !> step's ends), the start's roundoff that is no dip, a row below zero from the start, a
    !> row that stays positive.
    subroutine test_fresh_dips(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), parameter :: h = 3.0e-6_dp, t1 = 2.0e-7_dp, zero = 1.0e-8_dp
        real(dp) :: ts(41), gs(41), lo, glo, hi, ghi
        logical :: dips
        integer :: k
        ts = dip_samples(h)
        call check(t, all(ts(2:) > ts(:40)) .and. ts(1) > 0.0_dp .and. ts(1) <= 1.0e-8_dp*h &
                   .and. ts(41) < h, "fresh dips: 41 ascending samples in (0, h), the first "// &
                   "below 1e-8 h")
        ! a hump, then below zero from t1 on (and positive again by the step's end)
        gs = [(ts(k)*(t1 - ts(k))*(h - ts(k))*1.0e12_dp, k=1, 41)]
        call dip_bracket(ts, gs, -1.0e-14_dp, zero, dips, lo, glo, hi, ghi)
        call check(t, dips .and. lo < t1 .and. hi > t1 .and. glo > 0.0_dp .and. ghi < 0.0_dp, &
                   "fresh dips: a hump then a dip is bracketed around its zero")
        ! roundoff about zero, then positive: no dip
        gs = [(merge(-5.0e-9_dp, ts(k)*1.0e3_dp, ts(k) < 1.0e-9_dp), k=1, 41)]
        call dip_bracket(ts, gs, -1.0e-14_dp, zero, dips, lo, glo, hi, ghi)
        call check(t, .not. dips, "fresh dips: the start's roundoff about zero is no dip")
        ! below zero from the start
        gs = -ts*1.0e3_dp
        call dip_bracket(ts, gs, 0.0_dp, zero, dips, lo, glo, hi, ghi)
        call check(t, dips .and. lo == 0.0_dp .and. glo <= 0.0_dp .and. hi <= 1.0e-5_dp*h, &
                   "fresh dips: a row below zero from the start dips at once")
        gs = ts*1.0e3_dp
        call dip_bracket(ts, gs, 0.0_dp, zero, dips, lo, glo, hi, ghi)
        call check(t, .not. dips, "fresh dips: a row that rises has no dip")
    end subroutine test_fresh_dips

    !> The period map and its monodromy on the 30-DOF reduced beam (n_z = 60: its linear
    !> phases tracked in modal coordinates, stickslip_flow_track) against the same flow
    !> stepped on the dyadic ladder (use_track = .false.), from the exact orbit's start and
    !> from a perturbed state (other event times), at two frequencies of one flow (a
    !> retune: the track's coefficients and the ladder's exosystem columns follow omega).
    subroutine test_track_vs_ladder(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_solution_t) :: sol
        type(floquet_t) :: fl
        type(reference_options_t) :: ro
        type(reference_result_t) :: ref
        type(flow_t) :: ftrack, fladder
        type(error_type), allocatable :: error
        real(dp), allocatable :: z0(:), za(:), zb(:), ma(:, :), mb(:, :), vref(:)
        real(dp) :: dz, dm, omega
        integer :: n, k, i, ntracked
        logical :: ok, retuned
        character(len=200) :: buf
        m = reduced_beam(28, 50.0_dp)
        n = m%ndof
        call hbm_point(m, sol)
        call periodic_stability(m, sol, ro, fl, error, ref=ref)
        if (allocated(error)) then
            call check(t, .false., "track: the reference on the 30-DOF beam", error%message)
            return
        end if
        if (.not. ref%converged) then
            call check(t, .false., "track: the reference converges on the 30-DOF beam", &
                       ref%diagnosis)
            return
        end if
        vref = [maxval(abs(ref%v(:, 2)))]
        call new_flow(ftrack, m, ro%bracket_steps, vref, error)
        if (.not. allocated(error)) call new_flow(fladder, m, ro%bracket_steps, vref, error)
        if (allocated(error)) then
            call check(t, .false., "track: new_flow", error%message)
            return
        end if
        fladder%use_track = .false.
        allocate (za(2*n), zb(2*n), ma(2*n, 2*n), mb(2*n, 2*n))
        ok = .true.
        buf = ''
        do k = 1, 4
            omega = merge(50.0_dp, 50.3_dp, k <= 2)
            if (k == 3) then
                call ftrack%retune(omega, retuned)
                call fladder%retune(omega, ok)
                ok = ok .and. retuned
            end if
            z0 = ref%orbit%phase_y(1:2*n, 1)
            if (mod(k, 2) == 0) z0 = z0*(1.0_dp + 0.02_dp*[(sin(1.7_dp*i), i=1, 2*n)])
            call ftrack%period_map(ref%t_section, z0, za, error, mono=ma)
            if (.not. allocated(error)) call fladder%period_map(ref%t_section, z0, zb, error, &
                                                                mono=mb)
            if (allocated(error)) then
                ok = .false.
                buf = error%message
                exit
            end if
            dz = maxval(abs(za - zb))/maxval(abs(zb))
            dm = maxval(abs(ma - mb))/maxval(abs(mb))
            write (buf, '(a,i0,a,2es10.2)') "case ", k, ": relative differences z, monodromy ", &
                dz, dm
            if (.not. (dz < 1.0e-10_dp .and. dm < 1.0e-8_dp)) then
                ok = .false.
                exit
            end if
        end do
        ntracked = count([(ftrack%modes(i)%modal%coef_ok, i=1, ftrack%nmodes)])
        call check(t, ok, "track: the tracked period map and monodromy = the ladder's", &
                   trim(buf))
        call check(t, ntracked > 0, "track: the 30-DOF beam's phases are tracked")
    end subroutine test_track_vs_ladder

    !> The beam reduced to DOFs 77 (forced, 5 N at omega) and 79 (friction, mu N = 2 N)
    !> plus nm fixed-interface modes: reduced DOF 1 is 77, DOF 2 is 79.
    function reduced_beam(nm, omega) result(m)
        integer, intent(in) :: nm
        real(dp), intent(in) :: omega
        type(model_t) :: m
        integer, parameter :: ne = 40
        real(dp), allocatable :: k(:, :), mm(:, :)
        real(dp) :: le, ke(4, 4), me(4, 4)
        integer :: e, a, b, dofs(4)
        type(sparse_matrix_t) :: ks, ms, cs
        type(reduced_model_t) :: red
        type(reduction_report_t) :: rep
        type(error_type), allocatable :: error
        le = 1.0_dp/ne
        ke = reshape([12.0_dp, 6*le, -12.0_dp, 6*le, 6*le, 4*le**2, -6*le, 2*le**2, &
                      -12.0_dp, -6*le, 12.0_dp, -6*le, 6*le, 2*le**2, -6*le, 4*le**2], &
                     [4, 4])*700.0_dp/le**3
        me = reshape([156.0_dp, 22*le, 54.0_dp, -13*le, 22*le, 4*le**2, 13*le, -3*le**2, &
                      54.0_dp, 13*le, 156.0_dp, -22*le, -13*le, -3*le**2, -22*le, 4*le**2], &
                     [4, 4])*3.12_dp*le/420.0_dp
        allocate (k(2*ne, 2*ne), mm(2*ne, 2*ne))
        k = 0.0_dp
        mm = 0.0_dp
        do e = 1, ne
            dofs = [2*e - 3, 2*e - 2, 2*e - 1, 2*e]
            do a = 1, 4
                do b = 1, 4
                    if (dofs(a) < 1 .or. dofs(b) < 1) cycle
                    k(dofs(a), dofs(b)) = k(dofs(a), dofs(b)) + ke(a, b)
                    mm(dofs(a), dofs(b)) = mm(dofs(a), dofs(b)) + me(a, b)
                end do
            end do
        end do
        call sparse_from_dense(k, ks)
        call sparse_from_dense(mm, ms)
        call sparse_from_dense(0.5_dp*mm + 1.0e-5_dp*k, cs)
        call craig_bampton(ks, ms, [77, 79], reduction_options_t(modes=nm), red, rep, error, &
                           cmat=cs)
        if (allocated(error)) error stop "test_stiff_flow: the reduction failed"
        m%ndof = red%nr
        m%mass = red%mass
        m%stiffness = red%stiffness
        m%damping = red%damping
        m%omega = omega
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [5.0_dp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [2]
        m%contact_dof2 = [0]
        m%mu = [0.5_dp]
        m%normal_load = [4.0_dp]
    end function reduced_beam

    !> The weighted-residual solution (H = 15, odd harmonics, 128 samples).
    subroutine hbm_point(m, sol)
        type(model_t), intent(in) :: m
        type(hbm_solution_t), intent(out) :: sol
        type(hbm_options_t) :: o
        type(error_type), allocatable :: error
        o%harmonics = 15
        o%odd_only = .true.
        o%samples = 128
        call solve_periodic(m, o, sol, error)
        if (allocated(error)) error stop "test_stiff_flow: solve_periodic failed"
    end subroutine hbm_point

    !> A verdict (not 'unknown') at points across the first resonance of the 30-DOF reduced
    !> beam with the default &reference options, the exact orbit periodic to the default
    !> tolerance.
    subroutine test_verdicts(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_solution_t) :: sol
        type(floquet_t) :: fl
        type(reference_options_t) :: ro
        type(error_type), allocatable :: error
        real(dp), parameter :: omegas(4) = [45.0_dp, 50.0_dp, 53.0_dp, 60.0_dp]
        integer :: k
        logical :: all_known, all_stable
        character(len=200) :: buf
        all_known = .true.
        all_stable = .true.
        buf = ''
        do k = 1, size(omegas)
            m = reduced_beam(28, omegas(k))
            call hbm_point(m, sol)
            call periodic_stability(m, sol, ro, fl, error)
            if (allocated(error)) then
                all_known = .false.
                buf = error%message
                exit
            end if
            if (fl%verdict == 'unknown') then
                all_known = .false.
                write (buf, '(a,f6.1,a)') "omega ", omegas(k), ": "//fl%diagnosis(1:100)
            end if
            ! C = 0.5 M + 1e-5 K damps every mode and the contact slips: asymptotically stable
            all_stable = all_stable .and. fl%verdict == 'stable' .and. fl%max_modulus < 0.99_dp
        end do
        call check(t, m%ndof == 30, "stiff: the reduced beam has 30 DOFs")
        call check(t, all_known, "stiff: a verdict at every point of the reduced beam", trim(buf))
        call check(t, all_stable, "stiff: the damped beam with a slipping damper is stable")
    end subroutine test_verdicts

    !> The monodromy matrix of the reference on the reduced beam (12 DOFs) against central
    !> differences of the Radau IIA period map, and the multipliers of both.
    subroutine test_monodromy_fd(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_solution_t) :: sol
        type(floquet_t) :: fl, flfd
        type(reference_options_t) :: ro
        type(reference_result_t) :: ref
        type(error_type), allocatable :: error
        real(dp), allocatable :: z0(:), z1(:), zp(:), zm(:), zn(:), fd(:, :), ex(:, :), sc(:)
        real(dp) :: ax, av, eps, dmono(2), dper, dmult
        integer :: n, i, k, nmatch, ist
        character(len=200) :: buf
        m = reduced_beam(10, 50.0_dp)
        n = m%ndof
        call hbm_point(m, sol)
        call periodic_stability(m, sol, ro, fl, error, ref=ref)
        call check(t, .not. allocated(error) .and. ref%converged, &
                   "stiff: the reference converges on the 12-DOF reduced beam")
        if (allocated(error) .or. .not. ref%converged) return
        z0 = ref%orbit%phase_y(1:2*n, 1)
        ax = maxval(abs(ref%x))
        av = maxval(abs(ref%v))
        sc = [(ax, i=1, n), (av, i=1, n)]
        allocate (z1(2*n), zp(2*n), zm(2*n), zn(2*n), fd(2*n, 2*n))
        ! the exact orbit is periodic for the independent integrator too
        call radau_period(m, ref%t_section, z0, 4000, z1)
        dper = maxval(abs(z1 - z0)/sc)
        write (buf, '(a,es10.2)') "relative periodicity defect ", dper
        call check(t, dper < 1.0e-8_dp, "stiff: the exact orbit is a periodic orbit of the "// &
                   "Radau IIA integration", trim(buf))
        ! central differences, steps eps of the amplitudes, with 2000 and 4000 steps per
        ! period: the difference to the exact monodromy falls like the integrator's error
        ! (order 5: 1.1e-5, then 3.4e-7 measured; the differencing error is below 1e-8)
        ex = ref%monodromy
        do i = 1, 2*n
            ex(i, :) = ex(i, :)*sc/sc(i)
        end do
        eps = 1.0e-6_dp
        do ist = 1, 2
            do k = 1, 2*n
                zp = z0
                zm = z0
                zp(k) = zp(k) + eps*sc(k)
                zm(k) = zm(k) - eps*sc(k)
                call radau_period(m, ref%t_section, zp, 2000*ist, z1)
                call radau_period(m, ref%t_section, zm, 2000*ist, zn)
                fd(:, k) = (z1 - zn)/(2.0_dp*eps*sc(k))
            end do
            ! compare in the scaled state (x / ax, v / av)
            do i = 1, 2*n
                fd(i, :) = fd(i, :)*sc/sc(i)
            end do
            dmono(ist) = maxval(abs(ex - fd))/maxval(abs(ex))
        end do
        write (buf, '(a,2es10.2,a,es10.2)') "max |M - M_fd| / max |M| = ", dmono, &
            " (2000, 4000 steps), max |M| = ", maxval(abs(ex))
        call check(t, dmono(2) < 2.0e-6_dp .and. dmono(1) > 8.0_dp*dmono(2), &
                   "stiff: monodromy = finite differences of an independent Radau IIA "// &
                   "integration, converging with its step", trim(buf))
        ! every multiplier of the finite-difference matrix above 1e-3 has an exact partner
        call floquet_multipliers(fd, flfd, error)
        if (allocated(error)) return
        nmatch = 0
        dmult = 0.0_dp
        do k = 1, size(flfd%multipliers)
            if (abs(flfd%multipliers(k)) < 1.0e-3_dp) exit
            nmatch = nmatch + 1
            dmult = max(dmult, minval(abs(fl%multipliers - flfd%multipliers(k))))
        end do
        write (buf, '(a,i0,a,es10.2,a,f9.6,a,f9.6)') "multipliers compared ", nmatch, &
            ", largest difference ", dmult, ", rho exact ", fl%max_modulus, ", fd ", &
            flfd%max_modulus
        call check(t, nmatch >= 2 .and. dmult < 1.0e-5_dp .and. &
                   abs(fl%max_modulus - flfd%max_modulus) < 1.0e-5_dp, &
                   "stiff: Floquet multipliers = those of the finite-difference monodromy", &
                   trim(buf))
    end subroutine test_monodromy_fd

    !> One period from state z0 = [x; v] at t0 by Radau IIA with nsteps steps per period
    !> (shortened at events), for a model with one grounded contact (contact_dof(1)).
    !> Slip: M a = f - C v - K x - mu N s e_c. Stick: v_c = 0, a_c = 0, the other rows of
    !> M a = f - C v - K x; the stuck force r = (M a + C v + K x - f)_c; the contact slips
    !> when |r| reaches mu N (s = -sign r) and sticks when v_c reaches 0 with |r| < mu N.
    subroutine radau_period(m, t0, z0, nsteps, z1)
        type(model_t), intent(in) :: m
        real(dp), intent(in) :: t0, z0(:)
        integer, intent(in) :: nsteps
        real(dp), intent(out) :: z1(:)
        type(radau_mode_t) :: modes(-1:1)
        real(dp) :: t, tend, h, hstd, lo, hi, glo, ghi, hm, gm, limit
        real(dp), allocatable :: z(:), zn(:), ztry(:)
        integer :: n, c, s, iter, side
        n = m%ndof
        c = m%contact_dof(1)
        limit = m%mu(1)*m%normal_load(1)
        do s = -1, 1
            call build_mode(m, s, modes(s))
        end do
        hstd = two_pi/m%omega/nsteps
        t = t0
        tend = t0 + two_pi/m%omega
        z = z0
        s = nint(sign(1.0_dp, z(n + c)))
        allocate (zn(2*n), ztry(2*n))
        do while (t < tend - 1.0e-12_dp*hstd)
            h = min(hstd, tend - t)
            call radau_step(m, modes(s), t, z, h, zn)
            if (event_g(zn, t + h) > 0.0_dp) then
                t = t + h
                z = zn
                cycle
            end if
            ! locate the event on the step length (Illinois regula falsi)
            lo = 0.0_dp
            glo = event_g(z, t)
            hi = h
            ghi = event_g(zn, t + h)
            side = 0
            do iter = 1, 100
                if (hi - lo <= 1.0e-14_dp*hstd) exit
                hm = (lo*ghi - hi*glo)/(ghi - glo)
                if (.not. (hm > lo .and. hm < hi)) hm = 0.5_dp*(lo + hi)
                call radau_step(m, modes(s), t, z, hm, ztry)
                gm = event_g(ztry, t + hm)
                if (gm > 0.0_dp) then
                    lo = hm
                    glo = gm
                    if (side == -1) ghi = 0.5_dp*ghi
                    side = -1
                else
                    hi = hm
                    ghi = gm
                    zn = ztry
                    if (side == 1) glo = 0.5_dp*glo
                    side = 1
                end if
            end do
            t = t + hi
            z = zn
            if (s /= 0) then
                ! slip velocity zero: stick if the stuck force holds, else reverse
                z(n + c) = 0.0_dp
                if (abs(stuck_force(z, t)) < limit) then
                    s = 0
                else
                    s = -s
                end if
            else
                s = -nint(sign(1.0_dp, stuck_force(z, t)))
            end if
        end do
        z1 = z

    contains

        !> The event function of the current mode: s v_c in slip, mu N - |r| in stick.
        real(dp) function event_g(zz, tt)
            real(dp), intent(in) :: zz(:), tt
            if (s /= 0) then
                event_g = s*zz(n + c)
            else
                event_g = limit - abs(stuck_force(zz, tt))
            end if
        end function event_g

        !> The force the stuck contact carries, r = (M a + C v + K x - f)_c, a the stuck
        !> acceleration (modes(0)).
        real(dp) function stuck_force(zz, tt)
            real(dp), intent(in) :: zz(:), tt
            real(dp) :: acc(n)
            acc = matmul(modes(0)%jm(n + 1:2*n, :), zz) + gvec(m, 0, tt, n)
            stuck_force = dot_product(m%mass(c, :), acc) + &
                          dot_product(m%damping(c, :), zz(n + 1:)) + &
                          dot_product(m%stiffness(c, :), zz(1:n)) - forcing(m, tt, c)
        end function stuck_force
    end subroutine radau_period

    !> The first-order matrix of a mode: slip (s = +-1) z' = [v; M^-1 (-K x - C v)] + g;
    !> stick (s = 0): the contact DOF c eliminated (v_c' = 0, the other accelerations from
    !> the rows o of M with a_c = 0).
    subroutine build_mode(m, s, md)
        type(model_t), intent(in) :: m
        integer, intent(in) :: s
        type(radau_mode_t), intent(out) :: md
        integer :: n, c, i, info
        integer, allocatable :: o(:), ipiv(:)
        real(dp), allocatable :: moo(:, :), rhs(:, :)
        n = m%ndof
        c = m%contact_dof(1)
        md%s = s
        allocate (md%jm(2*n, 2*n))
        md%jm = 0.0_dp
        do i = 1, n
            md%jm(i, n + i) = 1.0_dp
        end do
        if (s /= 0) then
            o = [(i, i=1, n)]
        else
            o = pack([(i, i=1, n)], [(i, i=1, n)] /= c)
        end if
        moo = m%mass(o, o)
        allocate (rhs(size(o), 2*n), ipiv(size(o)))
        rhs(:, 1:n) = -m%stiffness(o, :)
        rhs(:, n + 1:) = -m%damping(o, :)
        call dgetrf(size(o), size(o), moo, size(o), ipiv, info)
        call dgetrs('N', size(o), 2*n, moo, size(o), ipiv, rhs, size(o), info)
        md%jm(n + o, :) = rhs
        if (s == 0) md%jm(c, :) = 0.0_dp
    end subroutine build_mode

    !> The inhomogeneous term of mode s at time tt: [0; M^-1 (f(t) - mu N s e_c)] (slip) or
    !> its stuck version (rows o of M, a_c = 0), returned as the acceleration part (n).
    function gvec(m, s, tt, n) result(g)
        type(model_t), intent(in) :: m
        integer, intent(in) :: s, n
        real(dp), intent(in) :: tt
        real(dp) :: g(n)
        integer :: c, i, info, no
        integer, allocatable :: o(:), ipiv(:)
        real(dp), allocatable :: moo(:, :), rhs(:, :)
        c = m%contact_dof(1)
        if (s /= 0) then
            o = [(i, i=1, n)]
        else
            o = pack([(i, i=1, n)], [(i, i=1, n)] /= c)
        end if
        no = size(o)
        allocate (rhs(no, 1), ipiv(no))
        do i = 1, no
            rhs(i, 1) = forcing(m, tt, o(i))
            if (o(i) == c) rhs(i, 1) = rhs(i, 1) - m%mu(1)*m%normal_load(1)*s
        end do
        moo = m%mass(o, o)
        call dgetrf(no, no, moo, no, ipiv, info)
        call dgetrs('N', no, 1, moo, no, ipiv, rhs, no, info)
        g = 0.0_dp
        g(o) = rhs(:, 1)
    end function gvec

    !> The external force on DOF i at time tt [N].
    real(dp) function forcing(m, tt, i) result(f)
        type(model_t), intent(in) :: m
        real(dp), intent(in) :: tt
        integer, intent(in) :: i
        integer :: k
        f = 0.0_dp
        do k = 1, size(m%force_dof)
            if (m%force_dof(k) == i) f = f + m%force_amplitude(k)* &
                cos(m%force_harmonic(k)*m%omega*tt + m%force_phase(k))
        end do
    end function forcing

    !> One Radau IIA step of length h from (tt, z): the stages Y solve
    !> (I - h A (x) J) Y = 1 (x) z + h (A (x) I) G, G_j = [0; g(tt + c_j h)]; z1 = Y_3.
    subroutine radau_step(m, md, tt, z, h, z1)
        type(model_t), intent(in) :: m
        type(radau_mode_t), intent(inout) :: md
        real(dp), intent(in) :: tt, z(:), h
        real(dp), intent(out) :: z1(:)
        integer :: nz, i, j, info, n
        real(dp), allocatable :: rhs(:, :), gst(:, :)
        nz = size(z)
        n = nz/2
        if (md%h /= h) then
            if (.not. allocated(md%lu)) allocate (md%lu(3*nz, 3*nz), md%ipiv(3*nz))
            md%lu = 0.0_dp
            do i = 1, 3
                do j = 1, 3
                    md%lu((i - 1)*nz + 1:i*nz, (j - 1)*nz + 1:j*nz) = -h*ra(i, j)*md%jm
                end do
            end do
            do i = 1, 3*nz
                md%lu(i, i) = md%lu(i, i) + 1.0_dp
            end do
            call dgetrf(3*nz, 3*nz, md%lu, 3*nz, md%ipiv, info)
            md%h = h
        end if
        allocate (gst(nz, 3), rhs(3*nz, 1))
        gst = 0.0_dp
        do j = 1, 3
            gst(n + 1:, j) = gvec(m, md%s, tt + rc(j)*h, n)
        end do
        do i = 1, 3
            rhs((i - 1)*nz + 1:i*nz, 1) = z + h*matmul(gst, ra(i, :))
        end do
        call dgetrs('N', 3*nz, 1, md%lu, 3*nz, md%ipiv, rhs, 3*nz, info)
        z1 = rhs(2*nz + 1:3*nz, 1)
    end subroutine radau_step
end module test_stiff_flow
