!> Tests of the automatic rho (closed forms, invariance under a change of units, the
!> relative-contact identity, cold starts where a fixed rho stalls) and of the robustness
!> study (rows, errors against the reference, warm starts, robustness.csv).
module test_robustness
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_positive_inf, &
        ieee_is_nan
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options
    use stickslip_euler, only: euler_options_t
    use stickslip_reference_start, only: reference_start_options_t
    use stickslip_rho, only: automatic_rho, contact_mobility, rho_fraction
    use stickslip_robustness, only: robustness_options_t, robustness_row_t, run_robustness, &
        validate_robustness_options, default_robustness_options, robustness_samples
    use stickslip_files, only: make_directory
    use stickslip_csv, only: write_robustness_csv
    use fixtures, only: seed_model, chain_model, one_dof_model, enter_project_root
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_robustness_tests

    character(len=*), parameter :: scratch = "build/test-scratch/robustness"

contains

    subroutine run_robustness_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()  ! its scratch path is relative to the root
        call test_rho_closed_forms(t)
        call test_rho_options(t)
        call test_rho_units(t)
        call test_rho_cold_starts(t)
        call test_robustness_options(t)
        call test_robustness_grid(t)
    end subroutine run_robustness_tests

    !> The mobility against hand computations: seed case, a single DOF, the mirrored pair,
    !> the forcing harmonic of largest amplitude, the mass-line fallback.
    subroutine test_rho_closed_forms(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m, one
        real(dp) :: w, mob(2)
        m = seed_model()
        ! Omega w^T (K + Omega^2 M)^{-1} w with w = e2: Omega (2 + Omega^2) / det
        w = 4.5_dp
        mob(1:1) = contact_mobility(m)
        call check_close(t, mob(1), w*(2.0_dp + w**2)/((2.0_dp + w**2)*(1.0_dp + w**2) - &
                         1.0_dp), "rho: seed mobility closed form", rtol=1.0e-13_dp)
        call check_close(t, mob(1), 0.2122_dp, "rho: seed mobility ~ 0.2", rtol=1.0e-3_dp)
        call check_close(t, automatic_rho(m), rho_fraction*mob(1), "rho: fraction of mobility", &
                         rtol=1.0e-14_dp)
        ! one DOF: Omega / (k + Omega^2 m), finite at the resonance Omega^2 = k / m
        one = one_dof_model(mass=2.0_dp, stiffness=8.0_dp, damping=0.0_dp, omega=2.0_dp, &
                            force=1.0_dp, mu=0.3_dp, normal_load=1.0_dp)
        call check_close(t, automatic_rho(one), rho_fraction*2.0_dp/(8.0_dp + 4.0_dp*2.0_dp), &
                         "rho: one DOF at resonance 1/(2 sqrt(k m))", rtol=1.0e-14_dp)
        ! the largest forcing term sets the frequency: harmonic 3 dominates
        one%force_harmonic = [0, 3, 1]
        one%force_dof = [1, 1, 1]
        one%force_amplitude = [100.0_dp, -5.0_dp, 1.0_dp]
        one%force_phase = [0.0_dp, 0.0_dp, 0.0_dp]
        call check_close(t, automatic_rho(one), rho_fraction*6.0_dp/(8.0_dp + 36.0_dp*2.0_dp), &
                         "rho: dominant forcing harmonic", rtol=1.0e-14_dp)
        ! indefinite K with K + Omega^2 M singular: the mass line 1 / (Omega m)
        one%force_harmonic = [1]
        one%force_dof = [1]
        one%force_amplitude = [1.0_dp]
        one%force_phase = [0.0_dp]
        one%stiffness = reshape([-8.0_dp], [1, 1])
        call check_close(t, automatic_rho(one), rho_fraction/(2.0_dp*2.0_dp), &
                         "rho: mass line when K + Omega^2 M is singular", rtol=1.0e-14_dp)
        ! two contacts: the geometric mean of the mobilities
        m = chain_model()
        mob = contact_mobility(m)
        call check(t, all(mob > 0.0_dp), "rho: chain mobilities > 0")
        call check_close(t, automatic_rho(m), rho_fraction*sqrt(mob(1)*mob(2)), &
                         "rho: geometric mean", &
                         rtol=1.0e-14_dp)
        m%mu(2) = 0.0_dp
        call check_close(t, automatic_rho(m), rho_fraction*mob(1), &
                         "rho: contacts without a limit ignored", &
                         rtol=1.0e-14_dp)
        ! no contact: rho is unused and 1
        m = seed_model()
        deallocate (m%contact_dof, m%contact_dof2, m%mu, m%normal_load)
        allocate (m%contact_dof(0), m%contact_dof2(0), m%mu(0), m%normal_load(0))
        call check_close(t, automatic_rho(m), 1.0_dp, "rho: no contact")
    end subroutine test_rho_closed_forms

    !> rho = 0 is the automatic choice, reported in sol%rho; negative, NaN, Inf rejected.
    subroutine test_rho_options(t)
        type(test_counter_t), intent(inout) :: t
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        type(error_type), allocatable :: error
        type(model_t) :: m
        call check_close(t, o%rho, 0.0_dp, "rho: default is automatic (0)")
        call validate_options(o, error)
        call check_error(t, error, "rho = 0 accepted", .false.)
        o%rho = -0.1_dp
        call validate_options(o, error)
        call check_error(t, error, "rho < 0 rejected", .true., &
                         [character(len=20) :: "opts%rho", ">= 0", "automatic"])
        o%rho = ieee_value(1.0_dp, ieee_quiet_nan)
        call validate_options(o, error)
        call check_error(t, error, "rho NaN rejected", .true., [character(len=20) :: "opts%rho"])
        o%rho = ieee_value(1.0_dp, ieee_positive_inf)
        call validate_options(o, error)
        call check_error(t, error, "rho Inf rejected", .true., [character(len=20) :: "opts%rho"])
        m = seed_model()
        o = hbm_options_t()
        o%harmonics = 10
        o%samples = 128
        call solve_periodic(m, o, s, error)
        call check_error(t, error, "rho auto: solve", .false.)
        if (allocated(error)) return
        call check(t, s%converged, "rho auto: converged")
        call check_close(t, s%rho, automatic_rho(m), "rho auto: sol%rho is the automatic rho")
        o%rho = 0.3_dp
        call solve_periodic(m, o, s, error)
        call check_error(t, error, "rho fixed: solve", .false.)
        call check_close(t, s%rho, 0.3_dp, "rho fixed: sol%rho = opts%rho")
    end subroutine test_rho_options

    !> A change of units (M, C, K, forces and normal loads times 1000: forces in mN) leaves
    !> the iterations of the automatic rho unchanged (same evaluations, same x, forces times
    !> 1000), while a fixed rho = 0.2 m/(N s) becomes, in the new units, 1000 times too large
    !> and stalls from a cold start.
    subroutine test_rho_units(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m, ms
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s, ss
        type(error_type), allocatable :: error
        real(dp), parameter :: c = 1000.0_dp
        m = seed_model()
        ms = m
        ms%mass = c*m%mass
        ms%stiffness = c*m%stiffness
        ms%damping = c*m%damping
        ms%force_amplitude = c*m%force_amplitude
        ms%normal_load = c*m%normal_load
        call check_close(t, automatic_rho(ms), automatic_rho(m)/c, "rho units: rho / 1000", &
                         rtol=1.0e-13_dp)
        o%harmonics = 30
        o%samples = 256
        o%start = 'direct'
        o%want_samples = .false.
        call solve_periodic(m, o, s, error)
        call check_error(t, error, "rho units: solve", .false.)
        call solve_periodic(ms, o, ss, error)
        call check_error(t, error, "rho units: scaled solve", .false.)
        if (allocated(error)) return
        call check(t, s%converged .and. ss%converged, "rho units: both converge")
        call check(t, s%nfev == ss%nfev, "rho units: same evaluations")
        call check_close(t, ss%xcoef(:, 2), s%xcoef(:, 2), "rho units: same x2", atol=1.0e-10_dp)
        call check_close(t, ss%rcoef(:, 1)/c, s%rcoef(:, 1), "rho units: forces times 1000", &
                         atol=1.0e-10_dp)
        o%rho = 0.2_dp
        call solve_periodic(ms, o, ss, error)
        call check_error(t, error, "rho units: fixed rho, scaled", .false.)
        call check(t, .not. ss%converged, "rho units: fixed rho = 0.2 stalls in mN")
    end subroutine test_rho_units

    !> The seed case from a cold start (no ladder): the automatic rho converges at H = 30 and
    !> 100 where rho = 5 does not, or only after more than 3x its evaluations (DESIGN
    !> section 3).
    subroutine test_rho_cold_starts(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        type(error_type), allocatable :: error
        integer, parameter :: hs(2) = [30, 100]
        integer :: i, nfev_auto
        character(len=40) :: tag
        m = seed_model()
        do i = 1, size(hs)
            write (tag, '(a,i0)') "cold start H = ", hs(i)
            o = hbm_options_t()
            o%harmonics = hs(i)
            o%samples = 512
            o%start = 'direct'
            o%want_samples = .false.
            call solve_periodic(m, o, s, error)
            call check(t, .not. allocated(error) .and. s%converged, trim(tag)//": auto rho converges")
            if (.not. allocated(error)) call check(t, s%stick_phases(1) == 2, &
                                                   trim(tag)//": auto rho, two stick phases")
            nfev_auto = s%nfev
            o%rho = 5.0_dp
            call solve_periodic(m, o, s, error)
            ! whether hybrj's restarts finally get through depends on roundoff (at H = 26..34
            ! and 256..1024 samples it converges at some, stalls at the others)
            call check(t, .not. allocated(error) .and. (.not. s%converged .or. &
                       s%nfev > 3*nfev_auto), trim(tag)//": rho = 5 stalls or needs more "// &
                       "than 3x the evaluations of the automatic rho")
        end do
    end subroutine test_rho_cold_starts

    subroutine test_robustness_options(t)
        type(test_counter_t), intent(inout) :: t
        type(robustness_options_t) :: r
        type(error_type), allocatable :: error
        r = default_robustness_options()
        call validate_robustness_options(r, error)
        call check_error(t, error, "robustness: defaults valid", .false.)
        call check(t, size(r%omegas) == 12 .and. any(r%rhos == 0.0_dp), &
                   "robustness: default grid holds the automatic rho")
        r%rhos = [0.2_dp, -1.0_dp]
        call validate_robustness_options(r, error)
        call check_error(t, error, "robustness: negative rho rejected", .true., &
                         [character(len=20) :: "opts%rhos"])
        r = default_robustness_options()
        r%samples = [16]
        call validate_robustness_options(r, error)
        call check_error(t, error, "robustness: too few samples rejected", .true., &
                         [character(len=20) :: "samples = 16", "harmonics = 10"])
        r = default_robustness_options()
        deallocate (r%mus)
        call validate_robustness_options(r, error)
        call check_error(t, error, "robustness: missing list rejected", .true., &
                         [character(len=20) :: "must be set"])
        call check(t, robustness_samples(0, 100, 256) == 512 .and. &
                   robustness_samples(0, 10, 256) == 256 .and. &
                   robustness_samples(300, 100, 256) == 300, "robustness: samples rule")
    end subroutine test_robustness_options

    !> A tiny grid: 2 omegas x 2 mus, H = 30, rho = 5 and automatic, bare cold starts and
    !> warm starts, implicit Euler with 400 steps per period.
    subroutine test_robustness_grid(t)
        type(test_counter_t), intent(inout) :: t
        type(robustness_options_t) :: r
        type(robustness_row_t), allocatable :: rows(:)
        type(error_type), allocatable :: error
        type(hbm_options_t) :: ho
        type(euler_options_t) :: eo
        type(reference_start_options_t) :: ro
        integer :: k, u, nline, stat
        character(len=400) :: line
        logical :: ok
        r%omegas = [4.5_dp, 4.0_dp]
        r%mus = [0.45_dp, 1.0_dp]
        r%harmonics = [30]
        r%rhos = [5.0_dp, 0.0_dp]
        r%samples = [128]
        r%steps_per_period = [400]
        ho%start = 'direct'
        eo%max_periods = 200
        call run_robustness(seed_model(), ho, eo, ro, r, rows, error)
        call check_error(t, error, "robustness grid: runs", .false.)
        if (allocated(error)) return
        ! per mu: 2 Euler rows, then 2 rho x 2 omegas x (cold, warm)
        call check(t, size(rows) == 2*(2 + 2*2*2), "robustness grid: row count")
        if (size(rows) /= 20) return
        call check(t, count(rows%method == 'euler') == 4 .and. &
                   count(rows%method == 'hbm-cold') == 8 .and. &
                   count(rows%method == 'hbm-warm') == 8, "robustness grid: methods")
        call check(t, all(rows(1:10)%mu == 0.45_dp) .and. all(rows(11:20)%mu == 1.0_dp) .and. &
                   all(rows(3:6)%rho == 5.0_dp) .and. all(rows(7:10)%rho_auto) .and. &
                   all(rows([3, 4, 7, 8])%omega == 4.5_dp) .and. &
                   all(rows([5, 6, 9, 10])%omega == 4.0_dp), "robustness grid: row order")
        ok = .true.
        do k = 1, size(rows)
            if (rows(k)%method == 'euler') then
                ok = ok .and. ieee_is_nan(rows(k)%rho) .and. rows(k)%harmonics == 0 .and. &
                     rows(k)%samples == 400
            else if (rows(k)%rho_auto) then
                ok = ok .and. rows(k)%rho > 0.09_dp .and. rows(k)%rho < 0.13_dp .and. &
                     rows(k)%samples == 128 .and. rows(k)%harmonics == 30
            else
                ok = ok .and. rows(k)%rho == 5.0_dp
            end if
        end do
        call check(t, ok, "robustness grid: rho recorded (effective, NaN for Euler)")
        ! the automatic rho converges everywhere, close to the reference
        ok = .true.
        do k = 1, size(rows)
            if (.not. rows(k)%rho_auto) cycle
            ok = ok .and. rows(k)%converged .and. rows(k)%success .and. &
                 rows(k)%err_amplitude < 5.0e-2_dp .and. rows(k)%iterations > 0 .and. &
                 index(rows(k)%diagnosis, "not converged") == 0
        end do
        call check(t, ok, "robustness grid: automatic rho converges, error < 5e-2")
        ! rho = 5 from a cold start stalls where mu N can be overcome (mu = 0.45), ...
        call check(t, .not. any(rows(3:6)%converged .or. rows(3:6)%success) .and. &
                   index(rows(3)%diagnosis, "not converged") == 1, &
                   "robustness grid: rho = 5 stalls at mu = 0.45")
        ! ... and converges at once where the contact sticks all the time (mu = 1)
        call check(t, all(rows(13:16)%converged .and. rows(13:16)%iterations <= 5), &
                   "robustness grid: rho = 5 at a stuck contact")
        ok = .true.
        do k = 1, size(rows)
            if (rows(k)%converged) ok = ok .and. rows(k)%err_amplitude < 5.0e-2_dp
            if (.not. rows(k)%converged) ok = ok .and. .not. rows(k)%success
        end do
        call check(t, ok, "robustness grid: every converged run close to the reference")
        ! implicit Euler: periodic at (4, 0.45) with a first-order error; the undamped stuck
        ! system (mu = 1) keeps its free vibration and never becomes periodic
        call check(t, rows(2)%converged .and. rows(2)%iterations > 1 .and. &
                   rows(2)%err_amplitude > 1.0e-3_dp .and. rows(2)%err_amplitude < 0.1_dp, &
                   "robustness grid: Euler periodic, first-order error")
        call check(t, .not. any(rows(11:12)%converged) .and. all(rows(11:12)%iterations == 200) &
                   .and. index(rows(11)%diagnosis, "not periodic") == 1, &
                   "robustness grid: Euler not periodic at a stuck undamped contact")
        ! warm starts: the first one is a cold start and says so; the second converges
        call check(t, index(rows(8)%diagnosis, "cold start") > 0 .and. &
                   rows(8)%iterations == rows(7)%iterations, &
                   "robustness grid: first warm row is a cold start")
        call check(t, rows(10)%converged .and. len(rows(10)%diagnosis) == 0, &
                   "robustness grid: warm start converges")

        call make_directory(scratch, error)
        call check_error(t, error, "robustness csv: directory", .false.)
        if (allocated(error)) return
        call write_robustness_csv(scratch, rows, error)
        call check_error(t, error, "robustness csv: written", .false.)
        if (allocated(error)) return
        open (newunit=u, file=scratch//"/robustness.csv", status='old', action='read', &
              iostat=stat)
        call check(t, stat == 0, "robustness csv: exists")
        if (stat /= 0) return
        read (u, '(a)') line
        call check(t, trim(line) == "method,omega,mu,harmonics,rho,rho_auto,samples,"// &
                   "converged,success,iterations,cpu_seconds,err_amplitude,diagnosis", &
                   "robustness csv: header")
        nline = 0
        ok = .true.
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            nline = nline + 1
            ok = ok .and. line(len_trim(line):len_trim(line)) == '"'
        end do
        close (u)
        call check(t, nline == size(rows), "robustness csv: one line per row")
        call check(t, ok, "robustness csv: quoted diagnosis last")
        inquire (file=scratch//"/robustness.csv.tmp", exist=ok)
        call check(t, .not. ok, "robustness csv: no temporary left")
    end subroutine test_robustness_grid
end module test_robustness
