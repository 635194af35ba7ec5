!> The sweep with contact laws against independent truth: a unilateral contact that never
!> opens sweeps the curve of the constant-load case (its points against separate solves
!> of that case); the points of a sweep in omega and in the preload over a contact that
!> lifts off are the separate solves at their parameters, each warm-started from the
!> previous (amplitudes, open shares, largest normal forces); the family's parameter derivative
!> (central differences with the laws) against a difference quotient of wider step; a
!> stability verdict of the exact reference at points; a planar contact swept with its
!> stability.
module test_contact_sweep
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, real_text, itoa
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_reference, only: reference_options_t
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep
    use stickslip_sweep_result, only: frc_point_t
    use stickslip_sweep_options, only: set_sweep_parameter, continuation_options_of
    use stickslip_continuation, only: continuation_options_t, validate_continuation_options
    use stickslip_friction_family, only: friction_family_t, new_friction_family
    use fixtures, only: damped_seed, unilateral_seed, liftoff_model, planar_model
    use stickslip_diagnostics, only: level_untrusted
    use testing, only: test_counter_t, check, check_error
    implicit none
    private
    public :: run_contact_sweep_tests

contains

    subroutine run_contact_sweep_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_never_opens(t)
        call test_points_are_solves(t, 'omega', 1.5_dp, 1.3_dp)
        call test_points_are_solves(t, 'preload', 0.5_dp, 2.0_dp)
        call test_parameter_derivative(t)
        call test_planar_stability(t)
        call test_designer_fold(t)
        call test_designer_stuck(t)
        call test_preload_vibration(t)
        call test_vibration_of_coefficients(t)
        call test_designer_crawl(t)
        call test_automatic_step(t)
    end subroutine run_contact_sweep_tests

    !> The automatic first step (|stop - start| / 100) stays within the min_step and max_step
    !> a case gives: `&sweep max_step = 0.01` alone on a range of 2.2 was refused ("need
    !> min_step <= step <= max_step (... <= 0.022 <= 0.01)"), the remedy the sweep's own
    !> failure message gives.
    subroutine test_automatic_step(t)
        type(test_counter_t), intent(inout) :: t
        type(sweep_options_t) :: so
        type(continuation_options_t) :: co
        type(error_type), allocatable :: error
        so%parameter = 'omega'
        so%start = 3.0_dp
        so%stop = 0.8_dp
        so%max_step = 0.01_dp
        co = continuation_options_of(so)
        call validate_continuation_options(co, error)
        call check(t, .not. allocated(error) .and. co%step == 0.01_dp .and. &
                   co%max_step == 0.01_dp, "contact_sweep: max_step alone bounds the "// &
                   "automatic step", real_text(co%step))
        so%max_step = 0.0_dp
        so%min_step = 0.05_dp
        co = continuation_options_of(so)
        call validate_continuation_options(co, error)
        call check(t, .not. allocated(error) .and. co%step == 0.05_dp, "contact_sweep: "// &
                   "min_step alone bounds the automatic step", real_text(co%step))
    end subroutine test_automatic_step

    !> The designer's 3-DOF case (examples/designer_damper.nml, issue 24): DOF 1 the blade,
    !> DOFs 2 and 3 the platform's tangential and normal motion, an elastic unilateral
    !> damper contact (k_n = 20) under `preload`, forced by `force` at DOF 1.
    function designer(preload, force) result(m)
        real(dp), intent(in) :: preload, force
        type(model_t) :: m
        m%ndof = 3
        m%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.3_dp, 0.0_dp, 0.0_dp, 0.0_dp, &
                          0.3_dp], [3, 3])
        m%stiffness = reshape([1.0_dp, -0.5_dp, 0.0_dp, -0.5_dp, 1.5_dp, 0.4_dp, 0.0_dp, &
                               0.4_dp, 2.0_dp], [3, 3])
        m%damping = 0.03_dp*m%mass + 0.01_dp*m%stiffness
        m%omega = 1.2_dp
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [force]
        m%force_phase = [0.0_dp]
        m%contact_dof = [2]
        m%contact_dof2 = [0]
        m%mu = [0.5_dp]
        m%normal_load = [0.0_dp]
        allocate (m%normal_direction(3, 1))
        m%normal_direction = reshape([0.0_dp, 0.0_dp, 1.0_dp], [3, 1])
        m%preload = [preload]
        m%normal_stiffness = [20.0_dp]
        m%tangential_stiffness = [0.0_dp]
    end function designer

    !> Down through the designer damper's folds near its lift-off resonance (0.93 -> 0.86):
    !> at 0.9058 the curve turns back onto an unstable branch whose blade amplitude agrees
    !> with the stable one's to 1e-3 (the normal motion differs by 2 %). The retrace test took
    !> it for a retrace, jumped back and failed 3 points in a row there; now the sweep
    !> completes through both folds, without an untrusted point. (Stability and truncation
    !> off for speed: doc/convergence.md draws the whole curve with them, at H = 45.)
    subroutine test_designer_fold(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(error_type), allocatable :: error
        integer :: k, n
        ho%harmonics = 30
        so%parameter = 'omega'
        so%start = 0.93_dp
        so%stop = 0.86_dp
        so%step = 0.022_dp
        so%min_step = 2.2e-5_dp
        so%max_step = 0.088_dp
        so%stability = .false.
        so%truncation = .false.
        call run_sweep(designer(0.7_dp, 0.3_dp), ho, ro, so, res, error)
        call check_error(t, error, "contact_sweep: designer fold: swept", .false.)
        if (allocated(error)) return
        n = res%npoints
        call check(t, res%complete .and. res%folds >= 2, "contact_sweep: designer: "// &
                   "complete through the folds near the lift-off resonance ("// &
                   itoa(res%folds)//" folds)", res%diagnosis)
        call check(t, all([(res%points(k)%check_level < level_untrusted, k=1, n)]), &
                   "contact_sweep: designer: no untrusted point through the folds")
    end subroutine test_designer_fold

    !> The designer damper with preload 2 and forcing 0.3 sticks all period from 0.8 to about
    !> 0.88 rad/s: the mean tangential force is undetermined there, and the continuation
    !> walked along that family and turned back ("left the range at its start", exit 2).
    !> With the mean pinned to the one the branch arrived with, the sweep runs 0.8 -> 1.2
    !> with omega increasing at every point; every stuck-all-period point has its stability
    !> known (the exact orbit compared up to the static offset: before, 'unknown').
    subroutine test_designer_stuck(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(error_type), allocatable :: error
        integer :: k, n, stuck
        ho%harmonics = 15
        ho%samples = 256
        so%parameter = 'omega'
        so%start = 0.8_dp
        so%stop = 1.2_dp
        so%stability = .true.
        call run_sweep(designer(2.0_dp, 0.3_dp), ho, ro, so, res, error)
        call check_error(t, error, "contact_sweep: designer stuck: swept", .false.)
        if (allocated(error)) return
        n = res%npoints
        stuck = count([(res%points(k)%stick(1) == 1.0_dp, k=1, n)])
        call check(t, res%complete .and. stuck >= 2 .and. &
                   all([(res%points(k + 1)%parameter > res%points(k)%parameter, k=1, n - 1)]), &
                   "contact_sweep: designer: stuck all period at the start, omega "// &
                   "increasing at every point ("//itoa(stuck)//" stuck points)", res%diagnosis)
        call check(t, all([(res%points(k)%stable /= -1, k=1, n)]) .and. &
                   all([(res%points(k)%check_level < level_untrusted, k=1, n)]), &
                   "contact_sweep: designer: every point's stability known, none untrusted "// &
                   "(the Signorini check of a closed, stuck contact)")
    end subroutine test_designer_stuck

    !> A preloaded damper that sticks: the designer damper at 0.85 rad/s (stuck all period at
    !> preload 2, above) swept in the preload 2 -> 4. Its vibration is the stuck linear
    !> response, whatever the preload: half the peak-to-peak and the first harmonic of every
    !> DOF stay put (to 1e-8), while max_t |x| of the normal DOF, which holds the preload's
    !> static offset, rises with it (by more than 20 %).
    subroutine test_preload_vibration(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(model_t) :: m
        type(error_type), allocatable :: error
        real(dp), allocatable :: vib(:, :), h1(:, :), half(:), first(:)
        real(dp) :: spread_vib, spread_h1, rise
        integer :: k, n
        ho%harmonics = 15
        ho%samples = 256
        so%parameter = 'preload'
        so%start = 2.0_dp
        so%stop = 4.0_dp
        m = designer(2.0_dp, 0.3_dp)
        m%omega = 0.85_dp
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "contact_sweep: preloaded damper: swept", .false.)
        if (allocated(error)) return
        n = res%npoints
        allocate (vib(3, n), h1(3, n))
        do k = 1, n
            call res%points(k)%vibration(half, first)
            vib(:, k) = half
            h1(:, k) = first
        end do
        spread_vib = maxval([(maxval(abs(vib(:, k) - vib(:, 1)))/maxval(abs(vib(:, 1))), &
                              k=1, n)])
        spread_h1 = maxval([(maxval(abs(h1(:, k) - h1(:, 1)))/maxval(abs(h1(:, 1))), k=1, n)])
        rise = res%points(n)%amplitude(3)/res%points(1)%amplitude(3) - 1.0_dp
        call check(t, res%complete .and. n >= 5 .and. &
                   all([(res%points(k)%stick(1) == 1.0_dp, k=1, n)]), &
                   "contact_sweep: preloaded damper: stuck all period from preload 2 to 4 ("// &
                   itoa(n)//" points)", res%diagnosis)
        call check(t, spread_vib <= 1.0e-8_dp .and. spread_h1 <= 1.0e-8_dp .and. &
                   rise > 0.2_dp, "contact_sweep: preloaded damper: the vibration amplitudes "// &
                   "flat where it sticks, max |x| of the normal DOF rising with the preload", &
                   "half peak-to-peak spread "//real_text(spread_vib)//", first harmonic "// &
                   real_text(spread_h1)//", max |x_3| rise "//real_text(rise))
    end subroutine test_preload_vibration

    !> frc_point_t%vibration against series known in closed form: x = 5 + cos t (half the
    !> peak-to-peak 1, first harmonic 1, max |x| 6), x = 0.6 cos t + 0.8 sin t (1 and 1), x =
    !> sin 3t (1 and 0), and NaN for a point without coefficients (an old checkpoint's).
    subroutine test_vibration_of_coefficients(t)
        type(test_counter_t), intent(inout) :: t
        type(frc_point_t) :: p
        real(dp), allocatable :: half(:), first(:)
        p%amplitude = [6.0_dp, 1.0_dp, 1.0_dp]
        p%harmonic = [0, 1, 1, 3, 3]
        p%xcoef = reshape([5.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, &
                           0.0_dp, 0.6_dp, 0.8_dp, 0.0_dp, 0.0_dp, &
                           0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [5, 3])
        call p%vibration(half, first)
        call check(t, all(abs(half - [1.0_dp, 1.0_dp, 1.0_dp]) <= 2.0e-3_dp) .and. &
                   all(abs(first - [1.0_dp, 1.0_dp, 0.0_dp]) <= 1.0e-14_dp), &
                   "contact_sweep: vibration amplitudes of known series (half the "// &
                   "peak-to-peak on 128 samples, the first harmonic exact)")
        deallocate (p%xcoef)
        call p%vibration(half, first)
        call check(t, all(half /= half) .and. all(first /= first), &
                   "contact_sweep: vibration amplitudes NaN without coefficients")
    end subroutine test_vibration_of_coefficients

    !> The harsh designer case (preload 0.3, forcing 1.5: the damper open 77 % of the period at
    !> resonance, normal forces 50 times the preload) swept 3 -> 0.8 rad/s at H = 10: the
    !> forces grow tenfold at the peak and the steps with them (relative steps); before, the
    !> sweep crawled (omega moving 4e-5 per point) and stopped at max_points = 2000. Without
    !> stability (the peak is unstable and partly quasi-periodic: not what is tested here).
    subroutine test_designer_crawl(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(error_type), allocatable :: error
        ho%harmonics = 10
        ho%samples = 256
        so%parameter = 'omega'
        so%start = 3.0_dp
        so%stop = 0.8_dp
        so%stability = .false.
        so%truncation = .false.
        so%max_points = 800
        call run_sweep(designer(0.3_dp, 1.5_dp), ho, ro, so, res, error)
        call check_error(t, error, "contact_sweep: designer crawl: swept", .false.)
        if (allocated(error)) return
        call check(t, res%complete, "contact_sweep: designer: through the lift-off "// &
                   "resonance in "//itoa(res%npoints)//" points (at most 800)", res%diagnosis)
    end subroutine test_designer_crawl

    !> The damped seed with its contact made unilateral (rigid, never opening, preload 1 on
    !> its own normal DOF) sweeps in omega the curve of the constant-load seed: the same
    !> number of points, the amplitudes of DOFs 1, 2 to the solver tolerance.
    subroutine test_never_opens(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: plain, uni, mk
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: ru
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: worst
        integer :: k, i
        plain = damped_seed()
        uni = unilateral_seed(0.0_dp)
        uni%damping(1:2, 1:2) = plain%damping
        ho%harmonics = 10
        ho%samples = 128
        ho%rho = 0.2_dp
        so%parameter = 'omega'
        so%start = 2.0_dp
        so%stop = 3.0_dp
        so%step = 0.05_dp
        so%max_step = 0.1_dp
        so%stability = .false.
        call run_sweep(uni, ho, ro, so, ru, error)
        call check_error(t, error, "contact_sweep: never opens: swept", .false.)
        if (allocated(error)) return
        call check(t, ru%complete .and. ru%npoints > 5, "contact_sweep: never opens: "// &
                   "complete", ru%diagnosis)
        ! each point against the constant-load seed solved at its omega
        worst = 0.0_dp
        ho%want_samples = .true.
        do k = 1, ru%npoints
            mk = plain
            mk%omega = ru%points(k)%parameter
            call solve_periodic(mk, ho, sol, error)
            if (allocated(error)) return
            worst = max(worst, maxval(abs(ru%points(k)%amplitude(1:2) - &
                                          [(maxval(abs(sol%x(:, i))), i=1, 2)])/ &
                                      ru%points(k)%amplitude(1:2)))
        end do
        call check(t, worst <= 1.0e-7_dp .and. all([(ru%points(k)%open(1) == 0.0_dp, &
                   k=1, ru%npoints)]), "contact_sweep: a contact that never opens sweeps "// &
                   "the constant-load curve", "worst difference "//real_text(worst))
    end subroutine test_never_opens

    !> A sweep of the elastic lift-off in `parameter` from p0 to p1: complete, and every
    !> third point is the separate solve at its parameter (amplitudes, open share, largest
    !> normal force), the forcing work = the dissipation.
    subroutine test_points_are_solves(t, parameter, p0, p1)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: parameter
        real(dp), intent(in) :: p0, p1
        type(model_t) :: m, mk
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(hbm_solution_t) :: sol, last
        type(error_type), allocatable :: error
        real(dp), parameter :: pi = acos(-1.0_dp)
        real(dp) :: worst, balance, coefs, work, worst_work
        integer :: k, i, c, missed
        coefs = 0.0_dp
        worst_work = 0.0_dp
        m = liftoff_model(10.0_dp, 0.0_dp)
        ho%harmonics = 15
        ho%samples = 256
        so%parameter = parameter
        so%start = p0
        so%stop = p1
        so%stability = .false.
        call run_sweep(m, ho, ro, so, res, error)
        call check_error(t, error, "contact_sweep: "//parameter//": swept", .false.)
        if (allocated(error)) return
        call check(t, res%complete .and. res%npoints > 5, "contact_sweep: "//parameter// &
                   ": complete", res%diagnosis)
        ! separate solves, each started from the previous one's forces (several periodic
        ! solutions coexist at some parameters), with the sweep's rho (the automatic one
        ! at its start: the projected equations depend on rho at finite H); a warm start
        ! that does not converge (the single solve is less robust than the continuation
        ! near contact transitions) is counted, the next one starts from the last that did
        worst = 0.0_dp
        balance = 0.0_dp
        missed = 0
        ho%want_samples = .true.
        do k = 1, res%npoints
            mk = m
            call set_sweep_parameter(mk, parameter, res%points(k)%parameter, m%force_amplitude)
            if (k == 1) then
                call solve_periodic(mk, ho, sol, error)
                ho%rho = sol%rho
            else
                call solve_periodic(mk, ho, sol, error, r_start=last%rcoef)
            end if
            if (allocated(error)) exit
            if (.not. sol%converged) then
                missed = missed + 1
                cycle
            end if
            last = sol
            worst = max(worst, maxval(abs([(maxval(abs(sol%x(:, i))), i=1, 2)] - &
                                          res%points(k)%amplitude)/res%points(k)%amplitude), &
                        abs(sol%open_fraction(1) - res%points(k)%open(1)), &
                        abs(maxval(sol%normal(:, 1)) - res%points(k)%normal_max(1))/ &
                        res%points(k)%normal_max(1))
            balance = max(balance, abs(sol%work_forcing - res%points(k)%dissipation)/ &
                          sol%work_forcing)
            ! the point's Fourier coefficients (frc_harmonics.csv): the solve's, the
            ! displacements along the channels (tangent DOF 1, normal DOF 2), and the work
            ! of the contact forces integrated exactly from them is the point's
            ! diss_friction (every channel: the normal force's work is the truncation's)
            associate (p => res%points(k))
                coefs = max(coefs, maxval(abs(p%xcoef - sol%xcoef))/maxval(abs(sol%xcoef)), &
                            maxval(abs(p%ucoef(:, 1) - p%xcoef(:, 1))), &
                            maxval(abs(p%ucoef(:, 2) - p%xcoef(:, 2))))
                work = 0.0_dp
                do c = 1, size(p%rcoef, 2)
                    do i = 2, size(p%harmonic), 2
                        work = work - pi*p%harmonic(i)*(p%rcoef(i, c)*p%ucoef(i + 1, c) - &
                                                        p%rcoef(i + 1, c)*p%ucoef(i, c))
                    end do
                end do
                worst_work = max(worst_work, abs(work - p%diss_friction)/p%dissipation)
            end associate
        end do
        call check(t, coefs <= 1.0e-5_dp .and. worst_work <= 1.0e-9_dp, "contact_sweep: "// &
                   parameter//": the points' coefficients are the solves', the friction "// &
                   "work from them is diss_friction", "coefficients "//real_text(coefs)// &
                   ", work "//real_text(worst_work))
        call check_error(t, error, "contact_sweep: "//parameter//": point solves", .false.)
        call check(t, worst <= 1.0e-5_dp .and. balance <= 1.0e-6_dp .and. &
                   missed <= res%npoints/5, "contact_sweep: "// &
                   parameter//": the points are the separate solves (amplitudes, open "// &
                   "share, normal force, energy)", "worst "//real_text(worst)//", balance "// &
                   real_text(balance)//", warm starts not converged "//itoa(missed))
    end subroutine test_points_are_solves

    !> dF/dlambda of the family (central differences with step 1e-6) against the quotient
    !> of step 1e-4 around a lift-off solution, in omega and in the preload: the two agree to
    !> the quotients' truncation.
    subroutine test_parameter_derivative(t)
        type(test_counter_t), intent(inout) :: t
        character(len=8), parameter :: names(2) = [character(len=8) :: 'omega', 'preload']
        real(dp), parameter :: values(2) = [1.5_dp, 1.0_dp]
        type(friction_family_t) :: fam
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp), allocatable :: y(:), jy(:, :), jl(:), fp(:), fm(:)
        real(dp) :: h
        integer :: k, stat
        ho%harmonics = 10
        ho%samples = 128
        call solve_periodic(liftoff_model(10.0_dp, 0.0_dp), ho, sol, error)
        if (allocated(error)) return
        y = reshape(sol%rcoef, [size(sol%rcoef)])
        do k = 1, 2
            call new_friction_family(fam, liftoff_model(10.0_dp, 0.0_dp), ho, trim(names(k)), &
                                     values(k), sol%rho, error)
            call check_error(t, error, "contact_sweep: family in "//trim(names(k)), .false.)
            if (allocated(error)) return
            allocate (jy(size(y), size(y)), jl(size(y)), fp(size(y)), fm(size(y)))
            stat = 0
            call fam%jacobian(y, values(k), jy, jl, stat)
            h = 1.0e-4_dp*values(k)
            call fam%residual(y, values(k) + h, fp, stat)
            call fam%residual(y, values(k) - h, fm, stat)
            call check(t, stat == 0 .and. norm2(jl - (fp - fm)/(2.0_dp*h)) <= &
                       1.0e-4_dp*norm2(jl) .and. norm2(jl) > 0.0_dp, "contact_sweep: "// &
                       "dF/d"//trim(names(k))//" with the laws = the difference quotient")
            call fam%destroy()
            deallocate (jy, jl, fp, fm)
        end do
    end subroutine test_parameter_derivative

    !> A sweep over a planar contact with stability = .true.: complete, a largest Floquet
    !> multiplier at every point from the exact reference (checked against the period
    !> map's differences in test_reference_2d), the full slip stable.
    subroutine test_planar_stability(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(error_type), allocatable :: error
        ho%harmonics = 5
        ho%samples = 64
        so%parameter = 'omega'
        so%start = 1.7_dp
        so%stop = 1.9_dp
        so%step = 0.05_dp
        so%max_step = 0.05_dp
        so%stability = .true.
        call run_sweep(planar_model(1.0_dp, 0.5_dp, 0.0_dp), ho, ro, so, res, error)
        call check_error(t, error, "contact_sweep: planar contact with stability", .false.)
        if (allocated(error)) return
        call check(t, res%complete .and. all(res%points(1:res%npoints)%stable == 1) .and. &
                   all(res%points(1:res%npoints)%floquet_max < 1.0_dp), "contact_sweep: "// &
                   "a planar contact sweeps with stability, every point stable")
    end subroutine test_planar_stability
end module test_contact_sweep
