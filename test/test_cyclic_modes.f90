!> Nonlinear modes per nodal diameter on one sector of a tuned bladed disk (EPMC on the
!> sector's travelling wave, run_modes with `cyclic`), against the assembled disk: the
!> sector's cyclic modes with the contacts stuck and slipping are the disk's linear modes;
!> every backbone point of the sector, expanded to the disk (each sector its phased copy),
!> solves the disk's own nonlinear-mode equations; the family's Jacobian on the sector
!> against central differences.
module test_cyclic_modes
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, real_text, itoa
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t, assemble_disk, sector_phase, phased_copies
    use stickslip_cyclic_limits, only: cyclic_limit_modes
    use stickslip_linear_modes, only: linear_modes
    use stickslip_modes, only: modes_options_t, modes_result_t, run_modes
    use stickslip_modes_family, only: modes_family_t, new_modes_family, free_structure
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic
    use stickslip_case, only: case_t, read_case, write_case
    use fixtures, only: project_path, enter_project_root, scratch, write_lines
    use testing, only: test_counter_t, check, check_error
    use test_modes, only: jacobian_errors
    use stickslip_run_sector_modes, only: sector_backbones, sector_diameters
    use stickslip_summary, only: write_modes_summary
    use stickslip_files, only: make_directory
    use test_cli, only: summary_value
    implicit none
    private
    public :: run_cyclic_modes_tests

contains

    subroutine run_cyclic_modes_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()
        call test_limit_modes(t)
        call test_sector_backbones(t)
        call test_cyclic_jacobian(t)
        call test_modes_input(t)
        call test_mode_per_diameter(t)
        call test_static_load(t)
        call test_samples_refinement(t)
        call test_held_weight(t)
    end subroutine run_cyclic_modes_tests

    !> The remedy of a stop: the underplatform damper disk's diameter 1
    !> (examples/bladed_disk_damper_modes.nml, amplitudes 1e-3 to 0.02). With the automatic
    !> weight (6.73, the free sector's contact mobility, the light damper's) run_modes stops
    !> at the onset of slip; sector_backbones traces it again with the wave's held weight
    !> (0.027, rho_held: the damper held on one platform slips on the other as fast as that
    !> platform moves against the next) and completes it, keeping what stopped the first
    !> (first_try), a note, and both tries' CPU time. With &hbm rho given there is no retry.
    subroutine test_held_weight(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(cyclic_t) :: cyc
        type(modes_options_t) :: opts
        type(modes_result_t) :: alone, res
        type(modes_result_t), allocatable :: per(:)
        type(error_type), allocatable :: error
        logical :: noted
        call read_case(project_path("examples/bladed_disk_damper_modes.nml"), c, error)
        call check_error(t, error, "held weight: read the example", .false.)
        if (allocated(error)) return
        opts = c%modes%modes_options_t
        opts%amplitude_stop = 0.02_dp
        opts%points = 18
        ! the held weight alone (test_samples_refinement: more samples)
        opts%refinements = 0
        cyc = c%cyclic%cyc
        cyc%engine_order = 1
        call run_modes(c%model, c%hbm, opts, alone, error, cyclic=cyc)
        call check_error(t, error, "held weight: the automatic weight alone", .false.)
        if (allocated(error)) return
        call sector_backbones(c, opts, [1], res, per, error)
        call check_error(t, error, "held weight: sector_backbones", .false.)
        if (allocated(error)) return
        noted = per(1)%diagnostics%has("held_weight")
        call check(t, .not. alone%complete .and. per(1)%complete .and. res%complete .and. &
                   per(1)%rho == alone%rho_held .and. alone%rho_held < 0.01_dp*alone%rho .and. &
                   allocated(per(1)%first_try) .and. noted .and. &
                   per(1)%seconds > alone%seconds, "held weight: diameter 1 stops with the "// &
                   "automatic weight and completes traced again with the held one", &
                   "automatic rho "//real_text(alone%rho)//": "//itoa(alone%npoints)// &
                   " points; held rho "//real_text(per(1)%rho)//": "//itoa(per(1)%npoints)// &
                   " points")
        ! a weight given: no retry
        c%hbm%rho = alone%rho
        call sector_backbones(c, opts, [1], res, per, error)
        call check_error(t, error, "held weight: rho given", .false.)
        if (allocated(error)) return
        call check(t, .not. per(1)%complete .and. per(1)%rho == alone%rho .and. &
                   .not. allocated(per(1)%first_try) .and. &
                   per(1)%npoints == alone%npoints, "held weight: with &hbm rho given the "// &
                   "backbone is not traced again", itoa(per(1)%npoints)//" points")
    end subroutine test_held_weight

    !> The shrouded disk's diameter 1 (examples/bladed_disk_modes.nml, its damping ratio
    !> climbing to 0.33): at the example's 384 samples, without refinements, the backbone
    !> stops ("3 failed points in a row") with a diagnosis that gives the samples in use and
    !> suggests 4 times as many; with 1536 samples it is complete. With the default
    !> refinements run_modes continues it on 4 times the samples where it stops and
    !> completes it: its end point (modal amplitude 1) is the 1536-sample run's, every
    !> point balances its energy, and samples_end and refined_at say what was done.
    subroutine test_samples_refinement(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(cyclic_t) :: cyc
        type(hbm_options_t) :: ho
        type(modes_options_t) :: opts
        type(modes_result_t) :: coarse, fine, refined, all
        type(modes_result_t), allocatable :: per(:)
        type(error_type), allocatable :: error
        character(len=*), parameter :: dir = scratch//"/cyclic_modes_refined"
        character(len=:), allocatable :: first_try
        logical :: noted
        real(dp) :: dw, dd
        call read_case(project_path("examples/bladed_disk_modes.nml"), c, error)
        call check_error(t, error, "cyclic modes samples: read the example", .false.)
        if (allocated(error)) return
        cyc = c%cyclic%cyc
        cyc%engine_order = 1
        ho = c%hbm
        opts = c%modes%modes_options_t
        opts%refinements = 0
        call run_modes(c%model, ho, opts, coarse, error, cyclic=cyc)
        call check_error(t, error, "cyclic modes samples: 384 samples", .false.)
        if (allocated(error)) return
        ho%samples = 1536
        call run_modes(c%model, ho, opts, fine, error, cyclic=cyc)
        call check_error(t, error, "cyclic modes samples: 1536 samples", .false.)
        if (allocated(error)) return
        call check(t, .not. coarse%complete .and. &
                   index(coarse%diagnosis, "try more &hbm samples (now 384; 4 times") > 0 .and. &
                   index(coarse%diagnosis, "a smaller &hbm rho (now ") > 0 .and. &
                   index(coarse%diagnosis, ", automatic)") > 0 .and. &
                   coarse%samples == 384 .and. size(coarse%refined_at) == 0 .and. &
                   fine%complete .and. fine%npoints > coarse%npoints, &
                   "cyclic modes samples: diameter 1 stops at 384 samples, saying so, and "// &
                   "completes at 1536", itoa(coarse%npoints)//" then "//itoa(fine%npoints)// &
                   " points; "//coarse%diagnosis)
        ! the default refinements: continued on more samples where it stops
        ho = c%hbm
        opts%refinements = c%modes%refinements
        call run_modes(c%model, ho, opts, refined, error, cyclic=cyc)
        call check_error(t, error, "cyclic modes samples: refinements", .false.)
        if (allocated(error)) return
        if (.not. (refined%complete .and. refined%npoints > 0)) then
            call check(t, .false., "cyclic modes samples: refined backbone complete", &
                       refined%diagnosis)
            return
        end if
        associate (p => refined%points(refined%npoints), q => fine%points(fine%npoints))
            dw = abs(p%p%omega - q%p%omega)/q%p%omega
            dd = abs(p%damping_ratio - q%damping_ratio)
        end associate
        call check(t, refined%samples == 1536 .and. size(refined%refined_at) == 1 .and. &
                   refined%refined_at(1) >= opts%amplitude_start .and. &
                   refined%refined_at(1) <= coarse%points(coarse%npoints)%p%parameter* &
                   (1.0_dp + 1.0e-12_dp) .and. dw <= 1.0e-8_dp .and. dd <= 1.0e-8_dp .and. &
                   maxval(refined%points(1:refined%npoints)%energy_error) <= 1.0e-10_dp, &
                   "cyclic modes samples: with refinements diameter 1 completes on 1536 "// &
                   "samples, its end the 1536-sample run's", "refined at a = "// &
                   real_text(refined%refined_at(1))//", end omega "//real_text(dw)// &
                   " (relative), D "//real_text(dd)//", "//itoa(refined%npoints)//" points")
        call check(t, count(refined%points(1:refined%npoints)%p%status == 'refined') == 1, &
                   "cyclic modes samples: one point has the status 'refined'")
        ! on the sector's backbones: the held weight on 384 samples first, then the weight
        ! that got further continued on more samples; summary.nml says so
        call sector_backbones(c, c%modes%modes_options_t, [1], all, per, error)
        call check_error(t, error, "cyclic modes samples: sector_backbones", .false.)
        if (allocated(error)) return
        noted = per(1)%diagnostics%has("refined")
        call make_directory(dir, error)
        call check_error(t, error, "cyclic modes samples: the directory", .false.)
        if (allocated(error)) return
        call write_modes_summary(dir, c, all, error, per, [1])
        call check_error(t, error, "cyclic modes samples: the summary", .false.)
        if (allocated(error)) return
        first_try = ""
        if (allocated(per(1)%first_try)) first_try = per(1)%first_try
        call check(t, per(1)%complete .and. per(1)%samples > 384 .and. noted .and. &
                   index(first_try, "on 384 samples: the automatic weight") == 1 .and. &
                   summary_value(dir//"/summary.nml", "samples_end_nd1") == &
                   itoa(per(1)%samples) .and. &
                   len(summary_value(dir//"/summary.nml", "refined_at_nd1")) > 0 .and. &
                   summary_value(dir//"/summary.nml", "complete_nd1") == "T", &
                   "cyclic modes samples: the sector's diameter 1 completes on more samples, "// &
                   "noted, samples_end_nd1 and refined_at_nd1 in summary.nml", &
                   itoa(per(1)%samples)//" samples; "//first_try)
    end subroutine test_samples_refinement

    !> A static load stays in a modal analysis: the underplatform dampers of
    !> examples/bladed_disk_damper.nml, pressed on the platforms by their centrifugal load
    !> (a static force), diameter 8. The backbone's first point (dampers stuck) carries the
    !> mean normal forces of the sector's static solution under that load alone (the
    !> weighted residual on the sector with the harmonic terms removed), to 1e-8; the
    !> backbone is complete with its energy balance.
    subroutine test_static_load(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: statics
        type(cyclic_t) :: cyc
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        real(dp) :: worst, scale
        integer :: ch, i0
        call read_case(project_path("examples/bladed_disk_damper.nml"), c, error)
        call check_error(t, error, "cyclic modes static load: read the example", .false.)
        if (allocated(error)) return
        cyc = c%cyclic%cyc
        cyc%engine_order = 8
        ho = c%hbm
        ho%samples = 384
        mo%amplitude_start = 1.0e-3_dp
        mo%amplitude_stop = 1.0_dp
        mo%points = 20
        mo%error_estimate = .false.
        ! the start is checked, not how far the backbone gets (at 384 samples its end
        ! depends on roundoff: complete after the suites before it, stopped at a = 0.066
        ! when this suite runs alone), so no refinement
        mo%refinements = 0
        call run_modes(c%model, ho, mo, res, error, cyclic=cyc)
        call check_error(t, error, "cyclic modes static load: the backbone", .false.)
        if (allocated(error)) return
        ! the static solution: the static load alone (free_structure keeps it)
        statics = free_structure(c%model)
        ho%rho = res%rho
        call solve_periodic_cyclic(statics, cyc, ho, sol, error)
        call check_error(t, error, "cyclic modes static load: the static solution", .false.)
        if (allocated(error)) return
        i0 = findloc(sol%harmonic, 0, 1)
        worst = 0.0_dp
        scale = maxval(abs(sol%rcoef(i0, :)))
        do ch = 1, size(sol%rcoef, 2)
            worst = max(worst, abs(res%points(1)%p%rcoef(i0, ch) - sol%rcoef(i0, ch))/scale)
        end do
        call check(t, res%npoints >= 2 .and. res%points(1)%p%stick(1) == 1.0_dp .and. &
                   scale > 0.0_dp .and. worst < 1.0e-8_dp .and. &
                   maxval(res%points(1:res%npoints)%energy_error) < 1.0e-6_dp, &
                   "cyclic modes static load: the dampers pressed by their centrifugal "// &
                   "load, the stuck start's mean forces = the static solution's", &
                   res%diagnosis//"; difference "//real_text(worst)//" of the largest "// &
                   "mean force "// &
                   real_text(scale)//", energy error at most "// &
                   real_text(maxval(res%points(1:res%npoints)%energy_error)))
    end subroutine test_static_load

    !> &modes nodal_diameters in a case file: read and echoed on a sector (the echo reads
    !> back to the same list); refused, naming the variable, without &cyclic, on the
    !> assembled disk, out of 0 .. N/2, or repeated; method 'modes' runs on a sector.
    subroutine test_modes_input(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c, back
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/cyclic_modes_case.nml"
        character(len=*), parameter :: echo = scratch//"/cyclic_modes_echo.nml"
        character(len=100), parameter :: head(4) = [character(len=100) :: &
            "&system ndof = 4, mass = 0.25,0,0,0, 0,0.3,0,0, 0,0,0.25,0, 0,0,0,1.0,", &
            "  stiffness = 20,0,0,-20, 0,3,0,-3, 0,0,20,-20, -20,-3,-20,48 /", &
            "&friction contact_dof = 2, mu = 0.3, normal_load = 0.5 /", &
            "&run method = 'modes' /"]
        character(len=*), parameter :: cyc = "&cyclic sectors = 24, engine_order = 3, "// &
            "left_dofs = 1, right_dofs = 3, next_dof = 2"
        character(len=*), parameter :: modes = "&modes amplitude_start = 1e-3, "// &
            "amplitude_stop = 1, nodal_diameters = "
        character(len=120) :: bad(4)
        character(len=40), parameter :: named(4) = [character(len=40) :: &
            "&modes nodal_diameters: only on one", "&modes nodal_diameters: only on one", &
            "&modes nodal_diameters(2) = 13", "&modes nodal_diameters(3) = 4: given"]
        integer :: k, u, stat
        character(len=200) :: msg
        bad = [character(len=120) :: modes//"3 /", cyc//", model = 'disk' /", &
               cyc//" /", cyc//" /"]
        call write_lines(path, [character(len=120) :: head, cyc//" /", modes//"3, 4, 12 /", &
                                "&output directory = '"//scratch//"/cyclic_modes_case' /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic modes case: read", .false.)
        if (allocated(error)) return
        open (newunit=u, file=echo, status='replace', action='write')
        call write_case(u, c, stat, msg)
        close (u)
        call read_case(echo, back, error)
        call check_error(t, error, "cyclic modes case: the echo reads back", .false.)
        if (allocated(error)) return
        call check(t, c%method == 'modes' .and. allocated(back%modes%nodal_diameters), &
                   "cyclic modes case: method 'modes' on a sector, nodal_diameters echoed")
        if (allocated(back%modes%nodal_diameters)) &
            call check(t, size(back%modes%nodal_diameters) == 3 .and. &
                       all(back%modes%nodal_diameters == [3, 4, 12]), &
                       "cyclic modes case: the echo's nodal_diameters = 3, 4, 12")
        do k = 1, size(bad)
            select case (k)
            case (1)
                call write_lines(path, [character(len=120) :: head, bad(k)])
            case (2)
                call write_lines(path, [character(len=120) :: head, bad(k), modes//"3 /"])
            case (3)
                call write_lines(path, [character(len=120) :: head, bad(k), modes//"3, 13 /"])
            case (4)
                call write_lines(path, [character(len=120) :: head, bad(k), modes//"3, 4, 4 /"])
            end select
            call read_case(path, c, error)
            call check_error(t, error, "cyclic modes case: bad input "//itoa(k), .true., &
                             [named(k), "cyclic_modes_case.nml                   "])
        end do
    end subroutine test_modes_input

    !> &modes mode as a list, one per nodal diameter: read and echoed (the echo reads back
    !> to the same list); sector_backbones traces mode 1 of diameter 3 and mode 2 of
    !> diameter 7, each backbone's stuck and slipping limits those of run_modes with that
    !> one mode (and diameter 7's mode 2 is not its mode 1); refused, naming the variable,
    !> with as many values as diameters wanting, a value < 1, or without &cyclic.
    subroutine test_mode_per_diameter(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c, back
        type(error_type), allocatable :: error
        type(modes_result_t) :: res, alone(2), first
        type(modes_result_t), allocatable :: per(:)
        type(cyclic_t) :: cyc
        character(len=*), parameter :: path = scratch//"/cyclic_mode_list.nml"
        character(len=*), parameter :: echo = scratch//"/cyclic_mode_list_echo.nml"
        character(len=100), parameter :: head(4) = [character(len=100) :: &
            "&system ndof = 4, mass = 0.25,0,0,0, 0,0.3,0,0, 0,0,0.25,0, 0,0,0,1.0,", &
            "  stiffness = 20,0,0,-20, 0,3,0,-3, 0,0,20,-20, -20,-3,-20,48 /", &
            "&friction contact_dof = 2, mu = 0.3, normal_load = 0.5 /", &
            "&run method = 'modes' /"]
        character(len=*), parameter :: cy = "&cyclic sectors = 24, engine_order = 3, "// &
            "left_dofs = 1, right_dofs = 3, next_dof = 2 /"
        character(len=*), parameter :: modes = "&modes amplitude_start = 1e-3, "// &
            "amplitude_stop = 1, points = 10, error_estimate = F, "
        integer :: k, u, stat
        integer, allocatable :: diameters(:)
        character(len=200) :: msg
        real(dp) :: worst
        call write_lines(path, [character(len=160) :: head, cy, &
                                modes//"nodal_diameters = 3, 7, mode = 1, 2 /", &
                                "&output directory = '"//scratch//"/cyclic_mode_list' /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic mode list: read", .false.)
        if (allocated(error)) return
        open (newunit=u, file=echo, status='replace', action='write')
        call write_case(u, c, stat, msg)
        close (u)
        call read_case(echo, back, error)
        call check_error(t, error, "cyclic mode list: the echo reads back", .false.)
        if (allocated(error)) return
        call check(t, allocated(back%modes%diameter_modes), "cyclic mode list: echoed")
        if (allocated(back%modes%diameter_modes)) call check(t, &
            size(back%modes%diameter_modes) == 2 .and. all(back%modes%diameter_modes == [1, 2]), &
            "cyclic mode list: the echo's mode = 1, 2")
        diameters = sector_diameters(c)
        call sector_backbones(c, c%modes%modes_options_t, diameters, res, per, error)
        call check_error(t, error, "cyclic mode list: the backbones", .false.)
        if (allocated(error)) return
        cyc = c%cyclic%cyc
        do k = 1, 2
            cyc%engine_order = diameters(k)
            c%modes%mode = k
            call run_modes(c%model, c%hbm, c%modes%modes_options_t, alone(k), error, cyclic=cyc)
            if (allocated(error)) exit
        end do
        if (.not. allocated(error)) then
            c%modes%mode = 1
            call run_modes(c%model, c%hbm, c%modes%modes_options_t, first, error, cyclic=cyc)
        end if
        call check_error(t, error, "cyclic mode list: the backbones one by one", .false.)
        if (allocated(error)) return
        worst = 0.0_dp
        do k = 1, 2
            worst = max(worst, abs(per(k)%omega_stuck - alone(k)%omega_stuck)/ &
                        alone(k)%omega_stuck, abs(per(k)%omega_slipping - &
                        alone(k)%omega_slipping)/alone(k)%omega_slipping)
        end do
        call check(t, worst < 1.0e-12_dp .and. abs(per(2)%omega_stuck - first%omega_stuck) > &
                   1.0e-3_dp*first%omega_stuck, "cyclic mode list: diameter 3 traces mode 1 "// &
                   "and diameter 7 mode 2", "stuck limits "//real_text(per(1)%omega_stuck)// &
                   ", "//real_text(per(2)%omega_stuck)//" (mode 1 of diameter 7: "// &
                   real_text(first%omega_stuck)//"), difference to one by one "// &
                   real_text(worst))
        ! bad lists
        call write_lines(path, [character(len=160) :: head, cy, &
                                modes//"nodal_diameters = 3, 7, 9, mode = 1, 2 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic mode list: fewer values than diameters", .true., &
                         [character(len=60) :: "&modes mode: 2 values, but 3 nodal diameters", &
                          "cyclic_mode_list.nml"])
        call write_lines(path, [character(len=160) :: head, cy, modes//"mode = 1, 2 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic mode list: every diameter traced", .true., &
                         [character(len=60) :: "&modes mode: 2 values, but 13 nodal diameters", &
                          "every diameter 0..N/2"])
        call write_lines(path, [character(len=160) :: head, cy, &
                                modes//"nodal_diameters = 3, 7, mode = 1, 0 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic mode list: a mode 0", .true., &
                         [character(len=60) :: "&modes mode(2) = 0: must be >= 1"])
        call write_lines(path, [character(len=160) :: head, modes//"mode = 1, 2 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic mode list: without &cyclic", .true., &
                         [character(len=60) :: "&modes mode: 2 values, one per nodal "// &
                          "diameter, only on one sector"])
    end subroutine test_mode_per_diameter

    !> The example disk (examples/bladed_disk.nml: a shroud rubbing on the next blade).
    subroutine example(sector, cyc, ho, error)
        type(model_t), intent(out) :: sector
        type(cyclic_t), intent(out) :: cyc
        type(hbm_options_t), intent(out) :: ho
        type(error_type), allocatable, intent(out) :: error
        type(case_t) :: c
        call read_case(project_path("examples/bladed_disk.nml"), c, error)
        if (allocated(error)) return
        sector = c%cyclic%sector
        cyc = c%cyclic%cyc
        ho = c%hbm
    end subroutine example

    !> The sector's cyclic modes of every diameter 0..12, the shroud stuck to the next blade
    !> (a constraint D^T X = 0, D = d - e d_next) and slipping, are the assembled disk's
    !> linear modes with its 24 shrouds stuck and slipping (dense dsygv): every diameter's
    !> frequencies among the disk's, diameters 1..11 twice, and the counts add up.
    subroutine test_limit_modes(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector, disk
        type(cyclic_t) :: cyc
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        real(dp), allocatable :: ws(:), wd(:), phid(:, :), found(:)
        complex(dp), allocatable :: shapes(:, :)
        integer :: nd, k, lim, total, hits, j
        real(dp) :: worst, norm_error
        logical :: stuck
        call example(sector, cyc, ho, error)
        call check_error(t, error, "cyclic modes: read the example", .false.)
        if (allocated(error)) return
        call assemble_disk(sector, cyc, disk, error)
        call check_error(t, error, "cyclic modes: assemble the disk", .false.)
        if (allocated(error)) return
        worst = 0.0_dp
        norm_error = 0.0_dp
        do lim = 1, 2
            stuck = lim == 1
            call linear_modes(disk, stuck, wd, phid, error)
            if (allocated(error)) exit
            total = 0
            allocate (found(0))
            do nd = 0, cyc%sectors/2
                cyc%engine_order = nd
                call cyclic_limit_modes(sector, cyc, exp(cmplx(0.0_dp, &
                                        sector_phase(1, nd, cyc%sectors, 1), dp)), stuck, ws, &
                                        shapes, error)
                if (allocated(error)) exit
                do k = 1, size(ws)
                    ! each frequency's multiplicity in the disk: 1 at nd = 0, N/2, else 2
                    hits = count(abs(wd - ws(k)) <= 1.0e-9_dp*ws(k))
                    if (hits /= merge(1, 2, nd == 0 .or. nd == cyc%sectors/2)) &
                        worst = max(worst, 1.0_dp)
                    worst = max(worst, minval(abs(wd - ws(k)))/ws(k))
                    norm_error = max(norm_error, abs(real(dot_product(shapes(:, k), &
                        matmul(sector%mass, shapes(:, k))), dp) - 1.0_dp))
                    j = merge(1, 2, nd == 0 .or. nd == cyc%sectors/2)
                    total = total + j
                end do
            end do
            deallocate (found)
            if (allocated(error)) exit
            if (total /= size(wd)) worst = max(worst, 1.0_dp)
        end do
        call check_error(t, error, "cyclic modes: the limits' eigensolves", .false.)
        if (allocated(error)) return
        call check(t, worst < 1.0e-9_dp .and. norm_error < 1.0e-12_dp, &
                   "cyclic modes: the sector's stuck and slipping cyclic modes per diameter "// &
                   "= the disk's linear modes", "largest relative difference "// &
                   real_text(worst)//", mass norm "//real_text(norm_error))
    end subroutine test_limit_modes

    !> Backbones of diameters 3, 7 and 12 on the sector from the stuck to the slipping
    !> shroud: complete, each point's energy balance, the first point's frequency the stuck
    !> cyclic mode's and the last one's a slipping one (to 1 %); and every point's friction
    !> forces, copied to every sector with its phase, solve the assembled disk's
    !> nonlinear-mode equations (damping C - xi M at the point's omega, no forcing) to 1e-9
    !> of their scale (samples a multiple of N, so that the disk's quadrature is the
    !> sector's).
    subroutine test_sector_backbones(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector, disk, free
        type(cyclic_t) :: cyc
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(hb_problem_t) :: prob
        type(error_type), allocatable :: error
        integer, parameter :: diameters(3) = [3, 7, 12]
        real(dp), allocatable :: y(:), f(:), wslip(:)
        complex(dp), allocatable :: shapes(:, :)
        real(dp) :: worst_res, worst_energy, first_error, last_slip, stick_last, scale
        integer :: i, p, stat, k
        logical :: complete
        call example(sector, cyc, ho, error)
        call check_error(t, error, "cyclic backbones: read the example", .false.)
        if (allocated(error)) return
        ho%samples = 2*cyc%sectors*4
        ho%tol = 1.0e-11_dp
        mo%amplitude_start = 1.0e-3_dp
        mo%amplitude_stop = 1.0_dp
        mo%points = 40
        mo%error_estimate = .false.
        worst_res = 0.0_dp
        worst_energy = 0.0_dp
        first_error = 0.0_dp
        last_slip = 0.0_dp
        stick_last = 0.0_dp
        complete = .true.
        free = free_structure(sector)
        do i = 1, size(diameters)
            cyc%engine_order = diameters(i)
            call run_modes(sector, ho, mo, res, error, cyclic=cyc)
            if (allocated(error)) exit
            complete = complete .and. res%complete
            first_error = max(first_error, abs(res%points(1)%p%omega - res%omega_stuck)/ &
                              res%omega_stuck)
            ! the nearest slipping cyclic frequency of the diameter (the stuck mode may
            ! become the second slipping one: the shroud's slip detunes the blade)
            call cyclic_limit_modes(sector, cyc, exp(cmplx(0.0_dp, sector_phase(1, &
                                    diameters(i), cyc%sectors, 1), dp)), .false., wslip, &
                                    shapes, error)
            if (allocated(error)) exit
            last_slip = max(last_slip, minval(abs(res%points(res%npoints)%p%omega - wslip))/ &
                            res%points(res%npoints)%p%omega)
            stick_last = max(stick_last, res%points(res%npoints)%p%stick(1))
            ! the disk's equations at every point
            call assemble_disk(free, cyc, disk, error)
            if (allocated(error)) exit
            do p = 1, res%npoints
                associate (pt => res%points(p))
                    worst_energy = max(worst_energy, pt%energy_error)
                    disk%omega = pt%p%omega
                    disk%damping = 0.0_dp
                    call assemble_damping(free, cyc, pt%xi, disk)
                    call new_hb_problem(prob, disk, ho%harmonics, res%odd_only, ho%samples, &
                                        res%rho, error)
                    if (allocated(error)) exit
                    y = reshape(phased_copies(pt%p%rcoef, &
                        prob%basis%harmonic_of([(k, k=1, prob%basis%nb)]), cyc), &
                                [prob%basis%nb*prob%nc])
                    allocate (f(size(y)))
                    stat = 0
                    call prob%residual(y, f, stat)
                    ! the scale: the velocity of the point's motion (its amplitude times omega)
                    scale = pt%p%omega*maxval(abs(pt%p%amplitude))
                    worst_res = max(worst_res, norm2(f)/scale/sqrt(real(cyc%sectors, dp)))
                    deallocate (f)
                    call prob%destroy()
                end associate
            end do
            if (allocated(error)) exit
        end do
        call check_error(t, error, "cyclic backbones: diameters 3, 7, 12", .false.)
        if (allocated(error)) return
        call check(t, complete .and. worst_energy < 1.0e-6_dp, &
                   "cyclic backbones: complete, energy balance per point", &
                   "largest energy error "//real_text(worst_energy))
        call check(t, first_error < 1.0e-6_dp .and. last_slip < 0.01_dp .and. &
                   stick_last < 0.5_dp, "cyclic backbones: from the stuck cyclic mode "// &
                   "towards the slipping one", "first point "//real_text(first_error)// &
                   " from the stuck frequency, last "//real_text(last_slip)// &
                   " from a slipping one, stick share at the end "//real_text(stick_last))
        call check(t, worst_res < 1.0e-9_dp, "cyclic backbones: every point solves the "// &
                   "assembled disk's nonlinear-mode equations", "largest residual "// &
                   real_text(worst_res)//" of the point's velocity scale")
    end subroutine test_sector_backbones

    !> The disk's damping C - xi M: the sector's copied, as assemble_disk copies C.
    subroutine assemble_damping(free, cyc, xi, disk)
        type(model_t), intent(in) :: free
        type(cyclic_t), intent(in) :: cyc
        real(dp), intent(in) :: xi
        type(model_t), intent(inout) :: disk
        type(model_t) :: shifted, d2
        type(error_type), allocatable :: error
        shifted = free
        shifted%damping = free%damping - xi*free%mass
        call assemble_disk(shifted, cyc, d2, error)
        disk%damping = d2%damping
    end subroutine assemble_damping

    !> The family's Jacobian on the sector (the complex phase row, the cyclic condensation)
    !> against central differences of its residual at a stuck, a stick-slip and the last
    !> point of the diameter-3 backbone: dF/dy and dF/dlambda.
    subroutine test_cyclic_jacobian(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector, free
        type(cyclic_t) :: cyc
        type(hbm_options_t) :: ho
        type(modes_options_t) :: mo
        type(modes_result_t) :: res
        type(modes_family_t) :: fam
        type(error_type), allocatable :: error
        real(dp), allocatable :: ws(:), y(:)
        complex(dp), allocatable :: shapes(:, :)
        real(dp) :: lambda, worst, worst_l, e_y, e_l
        integer :: which(3), i, stat
        call example(sector, cyc, ho, error)
        call check_error(t, error, "cyclic modes jacobian: read the example", .false.)
        if (allocated(error)) return
        ho%samples = 192
        mo%amplitude_start = 1.0e-3_dp
        mo%amplitude_stop = 1.0_dp
        mo%points = 40
        mo%error_estimate = .false.
        cyc%engine_order = 3
        free = free_structure(sector)
        call run_modes(free, ho, mo, res, error, cyclic=cyc)
        if (.not. allocated(error)) call cyclic_limit_modes(free, cyc, exp(cmplx(0.0_dp, &
            sector_phase(1, 3, cyc%sectors, 1), dp)), .true., ws, shapes, error)
        call check_error(t, error, "cyclic modes jacobian: backbone", .false.)
        if (allocated(error)) return
        ho%rho = res%rho
        call new_modes_family(fam, free, ho, shapes(:, 1), ws(1), error, cyc)
        call check_error(t, error, "cyclic modes jacobian: the family", .false.)
        if (allocated(error)) return
        which = [1, minloc([(abs(res%points(i)%p%stick(1) - 0.5_dp), i=1, res%npoints)], 1), &
                 res%npoints]
        worst = 0.0_dp
        worst_l = 0.0_dp
        stat = 0
        do i = 1, 3
            associate (p => res%points(which(i)))
                y = [reshape(p%p%rcoef, [size(p%p%rcoef)]), p%p%omega, p%xi]
                lambda = log(p%p%parameter)
            end associate
            call jacobian_errors(fam, y, lambda, e_y, e_l, stat)
            worst = max(worst, e_y)
            worst_l = max(worst_l, e_l)
        end do
        call fam%destroy()
        call check(t, stat == 0 .and. res%complete .and. worst <= 1.0e-5_dp .and. &
                   worst_l <= 1.0e-6_dp, "cyclic modes jacobian: dF/dy and dF/dlambda "// &
                   "against central differences (stuck, stick-slip, slipping)", &
                   "dF/dy "//real_text(worst)//", dF/dlambda "//real_text(worst_l)//" "// &
                   res%diagnosis)
    end subroutine test_cyclic_jacobian
end module test_cyclic_modes
