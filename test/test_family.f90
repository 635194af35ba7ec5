!> Families of forced-response curves against independent truth: the golden-section search
!> on a known maximum; the linear limits' peaks against the closed-form peak of a damped
!> oscillator (stuck limit) and a brute-force scan of the undamped-contact structure's
!> receptance (slipping limit); a friction damper's family over 9 normal loads against
!> separate sweeps at three of the loads (the same peaks), with its optimum between the
!> stuck and slipping limits and its ends on them; the family's checkpoints (a run killed
!> in one curve resumes to the same family); the files of the command line (frc.csv's
!> curve and family_value columns, family.csv, family.gp) and bad &sweep family input.
module test_family
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, real_text, itoa
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_case, only: case_t, read_case
    use stickslip_golden, only: golden_search_t
    use stickslip_linear_response, only: limit_peak_t, linear_limit_peaks
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep
    use stickslip_sweep_options, only: set_sweep_parameter
    use stickslip_sweep_family, only: family_options_t, family_result_t, run_family, &
        curve_peaks, family_peak_t, observer_slot_t
    use stickslip_checkpoint, only: checkpoint_writer_t, case_fingerprint, &
        family_checkpoint_name
    use stickslip_files, only: make_directory
    use stickslip_driver, only: run_sweep_case
    use fixtures, only: scratch, write_lines, enter_project_root, project_path
    use test_cli, only: cli, summary_value, count_lines, csv_rows
    use testing, only: test_counter_t, check, check_error
    use test_sweep_files, only: killed_writer_t
    implicit none
    private
    public :: run_family_tests

    !> The friction damper: DOF 1 the blade (forced), DOF 2 the platform with a Coulomb
    !> contact (normal load swept by the family), DOF 3 coupled to it.
    character(len=*), parameter :: damper(7) = [character(len=100) :: &
        "&system ndof = 3, mass = 1,0,0, 0,0.3,0, 0,0,0.3,", &
        "  stiffness = 1.0,-0.5,0, -0.5,1.5,0.4, 0,0.4,2.0,", &
        "  rayleigh_alpha = 0.03, rayleigh_beta = 0.01 /", &
        "&forcing omega = 1.2, force_dof = 1, force_amplitude = 0.3 /", &
        "&friction contact_dof = 2, mu = 0.5, normal_load = 0.7 /", &
        "&hbm harmonics = 15 /", &
        "&run method = 'sweep' /"]
    character(len=*), parameter :: family_sweep = "&sweep start = 0.6, stop = 1.3, "// &
        "stability = .false., truncation = .false., family_parameter = 'normal_load', "// &
        "family_values = 0.03, 0.1, 0.3, 0.6, 1.0, 1.5, 2.5, 5, 10 /"

contains

    subroutine run_family_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()
        call test_golden(t)
        call test_linear_limits(t)
        call test_family_against_sweeps(t)
        call test_family_resume(t)
        call test_family_cli(t)
        call test_family_input(t)
        call test_family_laws(t)
        call test_family_reduced(t)
    end subroutine run_family_tests

    !> The search finds the maximum of 1 - (x - 0.3)^2 on [0, 1] to its width, and a
    !> maximum at an end of the interval.
    subroutine test_golden(t)
        type(test_counter_t), intent(inout) :: t
        type(golden_search_t) :: s
        real(dp) :: x, best, best_x
        best = -huge(1.0_dp)
        best_x = 0.0_dp
        call s%begin(1.0_dp, 0.0_dp, 1.0e-8_dp)
        do while (.not. s%done())
            x = s%next()
            call s%tell(1.0_dp - (x - 0.3_dp)**2)
            if (1.0_dp - (x - 0.3_dp)**2 > best) then
                best = 1.0_dp - (x - 0.3_dp)**2
                best_x = x
            end if
        end do
        call check(t, abs(best_x - 0.3_dp) < 1.0e-8_dp .and. s%nfev < 45, &
                   "golden: the maximum of 1 - (x - 0.3)^2 in 0..1", &
                   real_text(best_x)//" after "//itoa(s%nfev))
        best = -huge(1.0_dp)
        call s%begin(0.0_dp, 1.0_dp, 1.0e-6_dp)
        do while (.not. s%done())
            x = s%next()
            call s%tell(x)
            best = max(best, x)
        end do
        call check(t, best > 1.0_dp - 2.0e-6_dp, "golden: a maximum at the end of the interval", &
                   real_text(best))
    end subroutine test_golden

    !> The stuck limit of a 2-DOF model whose contact holds DOF 2 is the damped oscillator of
    !> DOF 1 (m = 1, k = 1 + 1.5 ... here k11 = 2, c = 0.1): its receptance peak F / (c
    !> omega_d') at omega = sqrt(k/m - c^2/(2 m^2)) in closed form; the slipping limit (the
    !> contact carries nothing) against the largest |Z(omega)^-1 F| over 200001 omegas.
    subroutine test_linear_limits(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: m
        type(limit_peak_t), allocatable :: stuck(:), slipping(:)
        type(error_type), allocatable :: error
        real(dp) :: k, c, f, wpk, apk, w, best, best_w
        complex(dp) :: z(2, 2), det, x1
        integer :: j
        k = 2.0_dp
        c = 0.1_dp
        f = 0.7_dp
        m%ndof = 2
        m%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.5_dp], [2, 2])
        m%stiffness = reshape([k, -1.0_dp, -1.0_dp, 1.5_dp], [2, 2])
        m%damping = reshape([c, 0.0_dp, 0.0_dp, 0.05_dp], [2, 2])
        m%omega = 1.0_dp
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [f]
        m%force_phase = [0.0_dp]
        m%contact_dof = [2]
        m%contact_dof2 = [0]
        m%mu = [0.3_dp]
        m%normal_load = [1.0_dp]
        call linear_limit_peaks(m, .true., 0.5_dp, 2.5_dp, 'half_peak_to_peak', stuck, error)
        call check_error(t, error, "linear limits: stuck", .false.)
        if (allocated(error)) return
        ! |X| = f / sqrt((k - w^2)^2 + (c w)^2), largest at w^2 = k - c^2 / 2
        wpk = sqrt(k - 0.5_dp*c**2)
        apk = f/sqrt((k - wpk**2)**2 + (c*wpk)**2)
        call check(t, abs(stuck(1)%amplitude - apk) < 1.0e-9_dp*apk .and. &
                   abs(stuck(1)%omega - wpk) < 1.0e-4_dp .and. stuck(2)%amplitude == 0.0_dp, &
                   "linear limits: stuck peak = the damped oscillator's closed form", &
                   real_text(stuck(1)%amplitude)//" vs "//real_text(apk)//" at "// &
                   real_text(stuck(1)%omega)//" vs "//real_text(wpk))
        call linear_limit_peaks(m, .false., 0.5_dp, 2.5_dp, 'first_harmonic', slipping, error)
        call check_error(t, error, "linear limits: slipping", .false.)
        if (allocated(error)) return
        best = 0.0_dp
        best_w = 0.0_dp
        do j = 0, 200000
            w = 0.5_dp + 2.0_dp*real(j, dp)/200000.0_dp
            z = cmplx(m%stiffness - w**2*m%mass, w*m%damping, dp)
            det = z(1, 1)*z(2, 2) - z(1, 2)*z(2, 1)
            x1 = z(2, 2)*f/det
            if (abs(x1) > best) then
                best = abs(x1)
                best_w = w
            end if
        end do
        call check(t, slipping(1)%amplitude >= best*(1.0_dp - 1.0e-9_dp) .and. &
                   slipping(1)%amplitude <= best*(1.0_dp + 1.0e-6_dp) .and. &
                   abs(slipping(1)%omega - best_w) < 2.0e-4_dp, &
                   "linear limits: slipping peak = the scanned receptance's", &
                   real_text(slipping(1)%amplitude)//" vs "//real_text(best))
        ! without damping the peak is unbounded: NaN, not a number from roundoff
        m%damping = 0.0_dp
        call linear_limit_peaks(m, .false., 0.5_dp, 2.5_dp, 'first_harmonic', slipping, error)
        call check(t, .not. allocated(error) .and. &
                   slipping(1)%amplitude /= slipping(1)%amplitude, &
                   "linear limits: undamped, no finite peak (NaN)")
    end subroutine test_linear_limits

    !> The family of the friction damper over 9 normal loads: complete; its peaks against
    !> separate sweeps at three loads (each traced from a cold start, its peak refined the
    !> same way; one with a smaller largest step, on other points) to 1e-7; the optimum
    !> strictly inside the loads, below both linear limits; the smallest load's peak within
    !> 3 % of the slipping limit's, the largest's within 0.5 % of the stuck limit's; every
    !> peak refined.
    subroutine test_family_against_sweeps(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(family_result_t) :: fam
        type(sweep_result_t) :: single
        type(family_peak_t), allocatable :: peaks(:)
        type(model_t) :: m
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/family_peaks.nml"
        integer :: j, k, n, best
        integer, parameter :: picks(3) = [2, 5, 8]
        real(dp) :: worst, p(9)
        logical :: refined, other_path
        type(sweep_options_t) :: so
        call write_lines(path, [character(len=300) :: damper, family_sweep, &
                                "&output directory = '"//scratch//"/family_peaks' /"])
        call read_case(path, c, error)
        call check_error(t, error, "family: read case", .false.)
        if (allocated(error)) return
        call run_family(c%model, c%hbm, c%reference%reference_options_t, &
                        c%sweep%sweep_options_t, c%sweep%family, fam, error)
        call check_error(t, error, "family: run", .false.)
        if (allocated(error)) return
        n = size(fam%values)
        call check(t, fam%complete .and. n == 9 .and. all([(fam%curves(k)%npoints > 10, &
                   k=1, n)]), "family: 9 complete curves")
        worst = 0.0_dp
        do j = 1, size(picks)
            k = picks(j)
            m = c%model
            call set_sweep_parameter(m, 'normal_load', fam%values(k), m%force_amplitude)
            ! the second on another path (a smaller largest step): the refined peak is the
            ! answer's, not the path's
            so = c%sweep%sweep_options_t
            if (j == 2) so%max_step = 0.011_dp
            call run_sweep(m, c%hbm, c%reference%reference_options_t, so, single, error)
            call check_error(t, error, "family: separate sweep "//itoa(k), .false.)
            if (allocated(error)) return
            ho = c%hbm
            ho%rho = single%rho
            call curve_peaks(m, ho, so, 'half_peak_to_peak', single, peaks, error)
            call check_error(t, error, "family: separate sweep's peaks "//itoa(k), .false.)
            if (allocated(error)) return
            worst = max(worst, abs(peaks(1)%amplitude - fam%peaks(1, k)%amplitude)/ &
                        peaks(1)%amplitude)
            if (j == 2) other_path = single%npoints /= fam%curves(k)%npoints
        end do
        call check(t, worst < 1.0e-7_dp .and. other_path, &
                   "family: peaks = separate sweeps' at three loads (one on another path)", &
                   "largest relative difference "//real_text(worst))
        p = fam%peaks(1, :)%amplitude
        best = minloc(p, 1)
        call check(t, best > 1 .and. best < n .and. p(best) < 0.5_dp*fam%stuck(1, 1)%amplitude &
                   .and. p(best) < 0.5_dp*fam%slipping(1, 1)%amplitude, &
                   "family: the optimum lies inside the loads, below both linear limits", &
                   "best at curve "//itoa(best)//": "//real_text(p(best)))
        call check(t, abs(p(1) - fam%slipping(1, 1)%amplitude) < &
                   0.03_dp*fam%slipping(1, 1)%amplitude .and. &
                   abs(p(n) - fam%stuck(1, n)%amplitude) < 0.005_dp*fam%stuck(1, n)%amplitude, &
                   "family: the ends approach the slipping and stuck limits", &
                   real_text(p(1))//" vs "//real_text(fam%slipping(1, 1)%amplitude)//"; "// &
                   real_text(p(n))//" vs "//real_text(fam%stuck(1, n)%amplitude))
        refined = all(fam%peaks(1, :)%refined) .and. all(fam%peaks(1, :)%interior)
        call check(t, refined, "family: every peak interior and refined by single solves")
    end subroutine test_family_against_sweeps

    !> A family run killed in its third curve after 4 points leaves the curves'
    !> checkpoints; the case run again goes on from them (the finished curves are not
    !> traced again, the third from its 4 points) and gives the uninterrupted family.
    subroutine test_family_resume(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/family_resume"
        type(case_t) :: c
        type(family_result_t) :: whole, cut, resumed
        type(sweep_result_t) :: all_points
        type(observer_slot_t), allocatable :: slots(:)
        type(killed_writer_t) :: killer
        type(error_type), allocatable :: error
        logical :: same, exists
        integer :: k, j
        call write_lines(dir//".nml", [character(len=300) :: damper, &
            "&sweep start = 0.6, stop = 1.3, stability = .false., truncation = .false., "// &
            "family_parameter = 'mu', family_values = 0.2, 0.5, 1.0 /", &
            "&output directory = '"//dir//"' /"])
        call read_case(dir//".nml", c, error)
        call check_error(t, error, "family resume: read case", .false.)
        if (allocated(error)) return
        call make_directory(dir, error)
        call run_family(c%model, c%hbm, c%reference%reference_options_t, &
                        c%sweep%sweep_options_t, c%sweep%family, whole, error)
        call check_error(t, error, "family resume: uninterrupted run", .false.)
        if (allocated(error)) return
        allocate (slots(3))
        do k = 1, 3
            killer%directory = dir
            killer%fingerprint = case_fingerprint(c, error)
            killer%name = family_checkpoint_name(k)
            killer%interval = 0.0_dp
            killer%stop_after = merge(4, huge(1), k == 3)
            allocate (slots(k)%observer, source=killer)
        end do
        call run_family(c%model, c%hbm, c%reference%reference_options_t, &
                        c%sweep%sweep_options_t, c%sweep%family, cut, error, observers=slots)
        call check_error(t, error, "family resume: the killed run stops", .true.)
        inquire (file=dir//"/"//family_checkpoint_name(3), exist=exists)
        call check(t, exists, "family resume: the third curve's checkpoint survives")
        call run_sweep_case(c, all_points, error, family=resumed)
        call check_error(t, error, "family resume: resumed run", .false.)
        if (allocated(error)) return
        call check(t, resumed%curves(3)%resumed_points == 4 .and. &
                   resumed%curves(1)%resumed_points == whole%curves(1)%npoints, &
                   "family resume: the finished curves and 4 points of the third come "// &
                   "from the checkpoints", itoa(resumed%curves(3)%resumed_points)//", "// &
                   itoa(resumed%curves(1)%resumed_points))
        same = .true.
        do k = 1, 3
            same = same .and. resumed%curves(k)%npoints == whole%curves(k)%npoints
            if (.not. same) exit
            do j = 1, whole%curves(k)%npoints
                same = same .and. abs(resumed%curves(k)%points(j)%parameter - &
                                      whole%curves(k)%points(j)%parameter) <= 1.0e-12_dp
            end do
            same = same .and. abs(resumed%peaks(1, k)%amplitude - whole%peaks(1, k)%amplitude) &
                   <= 1.0e-10_dp*whole%peaks(1, k)%amplitude
        end do
        call check(t, same, "family resume: the same family as an uninterrupted run")
        inquire (file=dir//"/"//family_checkpoint_name(3), exist=exists)
        call check(t, .not. exists, "family resume: the checkpoints removed once written")
    end subroutine test_family_resume

    !> The command line on a family case: exit 0, frc.csv with the columns curve and
    !> family_value before trusted,check and one row per point, family.csv with one row per
    !> curve and its header, family.gp drawing both pictures, summary.nml with the curves.
    subroutine test_family_cli(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/family_cli"
        integer :: code, u, points
        character(len=:), allocatable :: out, err
        character(len=4000) :: header
        character(len=20000) :: script
        integer :: stat
        call write_lines(dir//".nml", [character(len=300) :: damper, &
            "&sweep start = 0.6, stop = 1.3, stability = .false., truncation = .false., "// &
            "plot = .false., "// &
            "family_parameter = 'mu', family_values = 0.1, 0.5 /", &
            "&output directory = '"//dir//"', dofs = 1, 2 /"])
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 0, "family cli: exit 0", err)
        if (code /= 0) return
        open (newunit=u, file=dir//"/frc.csv", status='old', action='read', iostat=stat)
        header = ''
        if (stat == 0) read (u, '(a)', iostat=stat) header
        if (stat == 0) close (u)
        call check(t, index(header, ",vib_1,vib_2,h1_1,h1_2,curve,family_value,trusted,check") &
                   > 0, "family cli: frc.csv ends with curve,family_value,trusted,check", &
                   trim(header))
        points = summary_integer(dir//"/summary.nml", "points")
        call check(t, csv_rows(dir//"/frc.csv") == points .and. points > 20 .and. &
                   csv_rows(dir//"/family.csv") == 2 .and. &
                   summary_integer(dir//"/summary.nml", "curves") == 2, &
                   "family cli: frc.csv a row per point, family.csv a row per curve")
        open (newunit=u, file=dir//"/family.csv", status='old', action='read', iostat=stat)
        header = ''
        if (stat == 0) read (u, '(a)', iostat=stat) header
        if (stat == 0) close (u)
        block
            character(len=4000) :: row, first
            open (newunit=u, file=dir//"/family.csv", status='old', action='read', iostat=stat)
            row = ''
            if (stat == 0) read (u, '(a)', iostat=stat) row
            if (stat == 0) read (u, '(a)', iostat=stat) row
            if (stat == 0) close (u)
            call check(t, count_char(row, ',') == 19 .and. count_char(header, ',') == 19, &
                       "family cli: family.csv's rows have the header's 20 fields", trim(row))
            open (newunit=u, file=dir//"/frc.csv", status='old', action='read', iostat=stat)
            first = ''
            row = ''
            if (stat == 0) read (u, '(a)', iostat=stat) first
            if (stat == 0) read (u, '(a)', iostat=stat) row
            if (stat == 0) close (u)
            call check(t, count_char(row, ',') == count_char(first, ',') .and. &
                       count_char(row, ',') > 20, &
                       "family cli: frc.csv's rows have the header's fields", trim(row))
        end block
        call check(t, trim(header) == "curve,family_value,points,complete,peak_1,peak_2,"// &
                   "peak_omega_1,peak_omega_2,peak_frequency_1,peak_frequency_2,"// &
                   "peak_dissipation_1,peak_dissipation_2,refined_1,refined_2,"// &
                   "stuck_peak_1,stuck_peak_2,slipping_peak_1,slipping_peak_2,trusted,check", &
                   "family cli: family.csv's header", trim(header))
        open (newunit=u, file=dir//"/family.gp", status='old', action='read', &
              access='stream', form='unformatted', iostat=stat)
        script = ''
        if (stat == 0) read (u, iostat=stat) script
        close (u)
        call check(t, index(script, "set output 'frc_family.png'.suffix") > 0 .and. &
                   index(script, "set output 'family.png'.suffix") > 0 .and. &
                   index(script, "friction coefficient mu") > 0, &
                   "family cli: family.gp draws frc_family.png and family.png")
    end subroutine test_family_cli

    !> A family in the preload of a damper that lifts off (a contact law): each curve's
    !> first point is a periodic solution of the model at that preload and the start's omega
    !> (a single solve started from its forces stays there, amplitudes to 1e-8), whichever
    !> neighbour it was started from, and the first curve's (started cold) is the cold
    !> single solve's. The case has two periodic solutions at preload 2 (max |r| 2.12 and
    !> 5.46, both converged and trusted): on an AMD EPYC VM the second curve, started from
    !> the first's stuck solution, reaches the other one than the cold solve, so a cold
    !> solve is no yardstick for the curves started from a neighbour.
    subroutine test_family_laws(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(family_result_t) :: fam
        type(model_t) :: m
        type(hbm_solution_t) :: sol
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/family_laws.nml"
        real(dp) :: worst, a, cold
        integer :: k
        call write_lines(path, [character(len=300) :: &
            "&system ndof = 2, mass = 1,0,0,1, stiffness = 1.3,-0.3,-0.3,1.8,", &
            "  rayleigh_alpha = 0.02, rayleigh_beta = 0.002 /", &
            "&forcing omega = 1.5, force_dof = 1, 2, force_amplitude = 1.0, 2.0, "// &
            "force_phase = 0.0, 0.4 /", &
            "&friction contact_dof = 1, mu = 0.5, normal_dof = 2, preload = 1.0, "// &
            "normal_stiffness = 10.0 /", &
            "&hbm harmonics = 20 /", &
            "&run method = 'sweep' /", &
            "&sweep start = 0.8, stop = 1.1, stability = .false., truncation = .false., "// &
            "family_parameter = 'preload', family_values = 4, 2, 1 /", &
            "&output directory = '"//scratch//"/family_laws' /"])
        call read_case(path, c, error)
        call check_error(t, error, "family laws: read case", .false.)
        if (allocated(error)) return
        call run_family(c%model, c%hbm, c%reference%reference_options_t, &
                        c%sweep%sweep_options_t, c%sweep%family, fam, error)
        call check_error(t, error, "family laws: run", .false.)
        if (allocated(error)) return
        worst = huge(1.0_dp)
        cold = huge(1.0_dp)
        if (all([(fam%curves(k)%npoints > 0, k=1, 3)])) then
            worst = 0.0_dp
            do k = 1, 3
                m = c%model
                call set_sweep_parameter(m, 'preload', fam%values(k), m%force_amplitude)
                call set_sweep_parameter(m, 'omega', 0.8_dp, m%force_amplitude)
                ho = c%hbm
                ho%want_samples = .true.
                associate (p => fam%curves(k)%points(1))
                    call solve_periodic(m, ho, sol, error, r_start=p%rcoef)
                    if (allocated(error)) exit
                    a = maxval(abs(sol%x(:, 1)))
                    worst = max(worst, abs(p%amplitude(1) - a)/a)
                    if (k == 1) then
                        call solve_periodic(m, ho, sol, error)
                        if (allocated(error)) exit
                        a = maxval(abs(sol%x(:, 1)))
                        cold = abs(p%amplitude(1) - a)/a
                    end if
                end associate
            end do
        end if
        call check(t, .not. allocated(error) .and. worst < 1.0e-8_dp .and. cold < 1.0e-8_dp, &
                   "family laws: each curve's first point is a solution at its preload, "// &
                   "the first curve's the cold single solve", &
                   "largest relative difference "//real_text(worst)//", cold "// &
                   real_text(cold))
    end subroutine test_family_laws

    !> A family on the reduced CalculiX strip (2412 DOFs, Craig-Bampton): both curves complete,
    !> family.csv's peaks named by the full-model DOFs of &output dofs, each peak interior.
    subroutine test_family_reduced(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/family_fe"
        integer :: code, u, stat
        character(len=:), allocatable :: out, err
        character(len=4000) :: header, row1, row2
        ! fixed-length lines first: a constructor of deferred-length results overruns
        ! (gfortran 12)
        character(len=300) :: mass_line, stiffness_line
        mass_line = "&system mass_file = '"//project_path("examples/calculix_beam/mass.mtx")//"',"
        stiffness_line = "  stiffness_file = '"// &
                         project_path("examples/calculix_beam/stiffness.mtx")//"',"
        call write_lines(dir//".nml", [character(len=300) :: mass_line, stiffness_line, &
            "  rayleigh_alpha = 2.0 /", &
            "&forcing omega = 534.7, force_dof = 2244, force_amplitude = 0.2 /", &
            "&friction contact_dof = 2409, mu = 0.5, normal_load = 0.24 /", &
            "&hbm harmonics = 7, odd_only = T, samples = 128 /", &
            "&run method = 'sweep' /", &
            "&sweep start = 500.0, stop = 570.0, max_step = 5.0, stability = F, truncation = F,", &
            "  plot = F, family_parameter = 'normal_load', family_values = 0.12, 0.24 /", &
            "&output directory = '"//dir//"', dofs = 2409, 2244 /"])
        call cli([character(len=200) :: dir//".nml"], code, out, err)
        call check(t, code == 0, "family fe: exit 0", err)
        if (code /= 0) return
        open (newunit=u, file=dir//"/family.csv", status='old', action='read', iostat=stat)
        header = ''
        row1 = ''
        row2 = ''
        if (stat == 0) read (u, '(a)', iostat=stat) header
        if (stat == 0) read (u, '(a)', iostat=stat) row1
        if (stat == 0) read (u, '(a)', iostat=stat) row2
        if (stat == 0) close (u)
        call check(t, index(header, "points,complete,peak_2409,peak_2244,") > 0 .and. &
                   index(row1, ",1,1,") > 0 .and. index(row2, ",1,1,") > 0, &
                   "family fe: full-model DOFs named, both curves complete, peaks refined", &
                   trim(header)//new_line('a')//trim(row1)//new_line('a')//trim(row2))
    end subroutine test_family_reduced

    !> Bad family input: one line naming &sweep and the variable, exit 1.
    subroutine test_family_input(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/family_bad"
        character(len=120), parameter :: bad(6) = [character(len=120) :: &
            "family_values = 0.1, 0.2 /", &
            "family_parameter = 'mu' /", &
            "family_parameter = 'omega', family_values = 1, 2 /", &
            "family_parameter = 'mu', family_values = 0.1, 0.2, 0.1 /", &
            "family_parameter = 'normal_load', family_values = 0.5, -1 /", &
            "family_parameter = 'force_amplitude', family_values = 0, 1 /"]
        character(len=40), parameter :: named(6) = [character(len=40) :: &
            "&sweep family_parameter", "&sweep family_values", "&sweep family_parameter", &
            "&sweep family_values(3)", "&sweep family_values", "&sweep family_values"]
        integer :: k, code
        character(len=:), allocatable :: out, err
        do k = 1, size(bad)
            call write_lines(dir//".nml", [character(len=300) :: damper, &
                "&sweep start = 0.6, stop = 1.3, "//trim(bad(k)), &
                "&output directory = '"//dir//"' /"])
            call cli([character(len=200) :: dir//".nml"], code, out, err)
            call check(t, code == 1 .and. index(err, trim(named(k))) > 0 .and. &
                       index(err, "family_bad.nml") > 0 .and. count_lines(err) == 1, &
                       "family input: "//trim(bad(k))//" named", err)
        end do
    end subroutine test_family_input

    !> How many times `c` occurs in `s` (trailing blanks ignored).
    pure integer function count_char(s, c)
        character(len=*), intent(in) :: s
        character, intent(in) :: c
        integer :: i
        count_char = 0
        do i = 1, len_trim(s)
            if (s(i:i) == c) count_char = count_char + 1
        end do
    end function count_char

    !> An integer value of summary.nml (-1 when absent or unreadable).
    integer function summary_integer(path, key)
        character(len=*), intent(in) :: path, key
        character(len=:), allocatable :: v
        integer :: stat
        v = summary_value(path, key)
        summary_integer = -1
        if (len(v) > 0) read (v, *, iostat=stat) summary_integer
    end function summary_integer

end module test_family
