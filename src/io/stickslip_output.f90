!> Result files: hbm.csv, euler.csv and reference.csv (one period of samples),
!> coefficients.csv (Fourier coefficients of x and r), events.csv (the reference's events),
!> study.csv (the work-precision study) and summary.nml (convergence reports, diagnostics,
!> energy balance, differences between methods and the effective case). Every file is written under a temporary name in the output directory and renamed
!> when complete, so a reader never sees a partial file. Knows nothing of how results are
!> computed.
module stickslip_output
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_solution, only: hbm_solution_t
    use stickslip_euler, only: euler_result_t
    use stickslip_case, only: case_t, write_case, put, rtoa, ltoa, rlist, ilist, llist
    use stickslip_reference, only: reference_result_t
    use stickslip_flow, only: event_name
    use stickslip_compare, only: comparison_t, quantity_names
    use stickslip_side_by_side, only: side_by_side_t
    use stickslip_study, only: study_result_t
    use stickslip_sweep, only: sweep_result_t, sweep_options_t
    use stickslip_checks, only: hbm_checks_t
    use stickslip_robustness, only: robustness_row_t, robustness_options_t
    implicit none
    private
    public :: make_directory, write_hbm_csv, write_samples_csv, write_coefficients_csv, &
              write_summary, write_euler_summary, energy_balance_error
    public :: write_events_csv, write_reference_summary, write_side_by_side_summary
    public :: write_study_csv, write_study_summary, reference_balance_error
    public :: open_temporary, close_and_rename, real_fmt
    public :: write_frc_csv, write_sweep_summary, write_frc_plot_script
    public :: write_robustness_csv, write_robustness_summary, write_robustness_plot_script

    interface
        function c_mkdir(path, mode) bind(c, name='mkdir') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: mode
            integer(c_int) :: stat
        end function c_mkdir

        function c_rename(old, new) bind(c, name='rename') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: old(*), new(*)
            integer(c_int) :: stat
        end function c_rename
    end interface

    character(len=*), parameter :: real_fmt = 'es25.17e3'

contains

    !> Create directory `path` and its missing parents (like mkdir -p). Error (stat io) when
    !> a component cannot be created.
    subroutine make_directory(path, error)
        !> Directory path.
        character(len=*), intent(in) :: path
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: k, stat
        logical :: exists
        do k = 1, len(path)
            if (k < len(path) .and. path(k:k) /= '/') cycle
            if (k == 1 .and. path(1:1) == '/') cycle
            if (path(k:k) == '/') then
                if (is_directory(path(1:k - 1))) cycle
                stat = c_mkdir(path(1:k - 1)//c_null_char, int(o'755', c_int))
            else
                if (is_directory(path)) cycle
                stat = c_mkdir(path//c_null_char, int(o'755', c_int))
            end if
        end do
        exists = is_directory(path)
        if (.not. exists) call fatal_error(error, path//": cannot create the output directory", &
                                           stickslip_stat%io)
    end subroutine make_directory

    logical function is_directory(path)
        character(len=*), intent(in) :: path
        inquire (file=path//'/.', exist=is_directory)
    end function is_directory

    !> Open `dir/name.tmp` for writing; finish with close_and_rename. Error: stat io.
    subroutine open_temporary(dir, name, unit, error)
        character(len=*), intent(in) :: dir, name
        integer, intent(out) :: unit
        type(error_type), allocatable, intent(out) :: error
        integer :: stat
        character(len=512) :: msg
        open (newunit=unit, file=dir//'/'//name//'.tmp', status='replace', action='write', &
              iostat=stat, iomsg=msg)
        if (stat /= 0) call fatal_error(error, dir//'/'//name//".tmp: cannot open for writing: "// &
                                        trim(msg), stickslip_stat%io)
    end subroutine open_temporary

    !> Close `unit` (opened by open_temporary) and rename `dir/name.tmp` to `dir/name`; when
    !> stat_write /= 0 (a write failed) delete the temporary instead. Error: stat io.
    subroutine close_and_rename(dir, name, unit, stat_write, msg_write, error)
        character(len=*), intent(in) :: dir, name
        integer, intent(in) :: unit, stat_write
        character(len=*), intent(in) :: msg_write
        type(error_type), allocatable, intent(out) :: error
        integer :: stat
        character(len=512) :: msg
        if (stat_write /= 0) then
            close (unit, status='delete', iostat=stat)
            call fatal_error(error, dir//'/'//name//": write failed: "//trim(msg_write), &
                             stickslip_stat%io)
            return
        end if
        close (unit, iostat=stat, iomsg=msg)
        if (stat /= 0) then
            call fatal_error(error, dir//'/'//name//": close failed: "//trim(msg), stickslip_stat%io)
            return
        end if
        if (c_rename(dir//'/'//name//'.tmp'//c_null_char, dir//'/'//name//c_null_char) /= 0) &
            call fatal_error(error, dir//'/'//name//": cannot rename the temporary file", &
                             stickslip_stat%io)
    end subroutine close_and_rename

    !> Write `dir`/hbm.csv: header t,x1..xN,v1..vN,r1..rC and one row per sample
    !> t_k = k T / nt, full double precision. Needs the solution's samples. Error: stat io.
    subroutine write_hbm_csv(dir, sol, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> A solution with samples.
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        call write_samples_csv(dir, "hbm.csv", sol%t, sol%x, sol%v, sol%r, error)
    end subroutine write_hbm_csv

    !> Write `dir`/`name`: header t,x1..xN,v1..vN,r1..rC and one row per instant, full
    !> double precision (the format of hbm.csv, also used for euler.csv). Error: stat io.
    subroutine write_samples_csv(dir, name, t, x, v, r, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> File name.
        character(len=*), intent(in) :: name
        !> Instants [s].
        real(dp), intent(in) :: t(:)
        !> Displacements, instants x N [m].
        real(dp), intent(in) :: x(:, :)
        !> Velocities, instants x N [m/s].
        real(dp), intent(in) :: v(:, :)
        !> Friction forces, instants x n_c [N].
        real(dp), intent(in) :: r(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, k, i, n, nc, stat
        character(len=512) :: msg
        character(len=:), allocatable :: header
        character(len=80) :: fmt

        n = size(x, 2)
        nc = size(r, 2)
        header = "t"
        do i = 1, n
            header = header//",x"//itoa(i)
        end do
        do i = 1, n
            header = header//",v"//itoa(i)
        end do
        do i = 1, nc
            header = header//",r"//itoa(i)
        end do
        write (fmt, '(a,i0,a)') '(', 1 + 2*n + nc, '(' // real_fmt // ',:,","))'
        call open_temporary(dir, name, u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, size(t)
            if (stat /= 0) exit
            write (u, fmt, iostat=stat, iomsg=msg) t(k), x(k, :), v(k, :), r(k, :)
        end do
        call close_and_rename(dir, name, u, stat, msg, error)
    end subroutine write_samples_csv

    !> Write `dir`/coefficients.csv: header harmonic,kind,x1..xN,r1..rC and one row per basis
    !> function, kind c0 (constant), cos or sin; u(t) = c0 + sum a cos(h omega t) + b sin(...).
    subroutine write_coefficients_csv(dir, sol, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The solution.
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, k, i, n, nc, stat
        character(len=512) :: msg
        character(len=:), allocatable :: header, kind
        character(len=80) :: fmt

        n = size(sol%xcoef, 2)
        nc = size(sol%rcoef, 2)
        header = "harmonic,kind"
        do i = 1, n
            header = header//",x"//itoa(i)
        end do
        do i = 1, nc
            header = header//",r"//itoa(i)
        end do
        write (fmt, '(a,i0,a)') '(i0,",",a,",",', n + nc, '(' // real_fmt // ',:,","))'
        call open_temporary(dir, "coefficients.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, sol%nb
            if (stat /= 0) exit
            if (sol%harmonic(k) == 0) then
                kind = "c0"
            else if (k > 1 .and. sol%harmonic(max(k - 1, 1)) == sol%harmonic(k)) then
                kind = "sin"
            else
                kind = "cos"
            end if
            write (u, fmt, iostat=stat, iomsg=msg) sol%harmonic(k), kind, sol%xcoef(k, :), &
                sol%rcoef(k, :)
        end do
        call close_and_rename(dir, "coefficients.csv", u, stat, msg, error)
    end subroutine write_coefficients_csv

    !> Relative energy balance error over one period: |work_forcing - diss_friction -
    !> diss_damping| / max(|work_forcing|, 1e-6 work_gross): relative to the net work, or to
    !> the gross work integral |f . v| dt when the net work is ~0 (a contact stuck all
    !> period, undamped: nothing dissipates, and the balance is 0 = 0 to roundoff).
    pure real(dp) function energy_balance_error(sol) result(e)
        !> The solution.
        type(hbm_solution_t), intent(in) :: sol
        e = abs(sol%work_forcing - sol%diss_friction - sol%diss_damping)/ &
            max(abs(sol%work_forcing), 1.0e-6_dp*sol%work_gross, tiny(1.0_dp))
    end function energy_balance_error

    !> Write `dir`/summary.nml: a namelist group &summary (one `key = value` per line) with
    !> the convergence report and diagnostics, followed by the effective case as namelist
    !> groups (read_case reads the file back as a case).
    subroutine write_summary(dir, case, sol, error, checks)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case solved.
        type(case_t), intent(in) :: case
        !> The solution (converged or not).
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Truncation estimate, stability and periodicity defect of the solution.
        type(hbm_checks_t), intent(in), optional :: checks
        integer :: u, stat
        character(len=512) :: msg

        call begin_summary(dir, "hbm", u, stat, msg, error)
        if (allocated(error)) return
        call put_hbm_keys(u, sol, stat, msg)
        if (present(checks)) call put_check_keys(u, checks, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_summary

    !> The keys of the checks of a solution (README, "summary.nml").
    subroutine put_check_keys(u, checks, stat, msg)
        integer, intent(in) :: u
        type(hbm_checks_t), intent(in) :: checks
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        associate (e => checks%truncation)
            if (e%available) then
                call put(u, "  truncation_estimate = "//rtoa(e%estimate), stat, msg)
                call put(u, "  truncation_psi_rms = "//rtoa(e%psi_rms), stat, msg)
                call put(u, "  truncation_coarse_harmonics = "//itoa(e%coarse_harmonics), &
                         stat, msg)
                if (allocated(e%displacement_change_rel)) call put(u, &
                    "  truncation_displacement_change = "//rlist(e%displacement_change_rel), &
                    stat, msg)
                call put(u, "  truncation_dissipation_change = "// &
                         rtoa(e%dissipation_change_rel), stat, msg)
            end if
            if (e%tolerance > 0.0_dp) then
                call put(u, "  harmonics_tol_met = "//ltoa(e%met), stat, msg)
                if (allocated(e%history_harmonics)) then
                    call put(u, "  harmonics_tried = "//ilist(e%history_harmonics), stat, msg)
                    call put(u, "  estimates_tried = "//rlist(e%history_estimate), stat, msg)
                end if
            end if
        end associate
        if (checks%stability) then
            associate (f => checks%floquet)
                call put(u, "  stability = '"//f%verdict//"'", stat, msg)
                call put(u, "  stable = "//ltoa(f%stable), stat, msg)
                if (f%verdict /= 'unknown') then
                    call put(u, "  floquet_max = "//rtoa(f%max_modulus), stat, msg)
                    call put(u, "  floquet_multipliers_re = "//rlist(real(f%multipliers, dp)), &
                             stat, msg)
                    call put(u, "  floquet_multipliers_im = "//rlist(aimag(f%multipliers)), &
                             stat, msg)
                end if
                if (allocated(f%diagnosis)) call put(u, "  stability_diagnosis = '"// &
                                                     quote(f%diagnosis)//"'", stat, msg)
            end associate
        end if
        if (allocated(checks%defect)) then
            if (size(checks%defect) > 0) then
                call put(u, "  periodicity_defect = "//rlist(checks%defect), stat, msg)
            end if
        end if
        if (allocated(checks%notes)) call put(u, "  notes = '"//quote(checks%notes)//"'", &
                                              stat, msg)
    end subroutine put_check_keys

    !> Write `dir`/summary.nml for a time integration: a group &summary (method = 'euler',
    !> periodic, periods, defect, seconds, max_sweeps, diagnosis), then the effective case.
    subroutine write_euler_summary(dir, case, res, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case integrated.
        type(case_t), intent(in) :: case
        !> The integration result.
        type(euler_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat
        character(len=512) :: msg
        call begin_summary(dir, "euler", u, stat, msg, error)
        if (allocated(error)) return
        call put_euler_keys(u, case, res, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_euler_summary

    !> The keys of a weighted-residual solution (README, "summary.nml").
    subroutine put_hbm_keys(u, sol, stat, msg)
        integer, intent(in) :: u
        type(hbm_solution_t), intent(in) :: sol
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        integer :: nc
        nc = 0
        if (allocated(sol%stick_fraction)) nc = size(sol%stick_fraction)
        call put(u, "  converged = "//ltoa(sol%converged), stat, msg)
        call put(u, "  info = "//itoa(sol%info), stat, msg)
        call put(u, "  nfev = "//itoa(sol%nfev), stat, msg)
        call put(u, "  njev = "//itoa(sol%njev), stat, msg)
        call put(u, "  hybrj_calls = "//itoa(sol%hybrj_calls), stat, msg)
        call put(u, "  fnorm = "//rtoa(sol%fnorm), stat, msg)
        call put(u, "  fscale = "//rtoa(sol%fscale), stat, msg)
        call put(u, "  solve_seconds = "//rtoa(sol%seconds), stat, msg)
        call put(u, "  harmonics = "//itoa(sol%harmonics), stat, msg)
        call put(u, "  odd_only = "//ltoa(sol%odd_only), stat, msg)
        call put(u, "  samples = "//itoa(sol%samples), stat, msg)
        call put(u, "  rho = "//rtoa(sol%rho), stat, msg)
        call put(u, "  ncontact = "//itoa(nc), stat, msg)
        if (nc > 0) then
            call put(u, "  stick_fraction = "//rlist(sol%stick_fraction), stat, msg)
            call put(u, "  stick_phases = "//ilist(sol%stick_phases), stat, msg)
            call put(u, "  offset_undetermined = "//llist(sol%offset_undetermined), stat, msg)
        end if
        call put(u, "  work_forcing = "//rtoa(sol%work_forcing), stat, msg)
        call put(u, "  work_gross = "//rtoa(sol%work_gross), stat, msg)
        call put(u, "  diss_friction = "//rtoa(sol%diss_friction), stat, msg)
        call put(u, "  diss_damping = "//rtoa(sol%diss_damping), stat, msg)
        call put(u, "  diss_coulomb = "//rtoa(sol%diss_coulomb), stat, msg)
        call put(u, "  energy_balance_error = "//rtoa(energy_balance_error(sol)), stat, msg)
        call put(u, "  diagnosis = '"//quote(sol%diagnosis)//"'", stat, msg)
    end subroutine put_hbm_keys

    !> The keys of an implicit Euler integration.
    subroutine put_euler_keys(u, case, res, stat, msg)
        integer, intent(in) :: u
        type(case_t), intent(in) :: case
        type(euler_result_t), intent(in) :: res
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        call put(u, "  periodic = "//ltoa(res%periodic), stat, msg)
        call put(u, "  periods = "//itoa(res%periods), stat, msg)
        call put(u, "  defect = "//rtoa(res%defect), stat, msg)
        call put(u, "  euler_seconds = "//rtoa(res%seconds), stat, msg)
        call put(u, "  steps_per_period = "//itoa(case%euler%steps_per_period), stat, msg)
        call put(u, "  max_sweeps = "//itoa(res%max_sweeps), stat, msg)
        call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
    end subroutine put_euler_keys

    !> Relative energy balance error of the reference over one period:
    !> |work_forcing - diss_friction - diss_damping| / max(|work_forcing|, tiny).
    pure real(dp) function reference_balance_error(ref) result(e)
        !> A reference solution.
        type(reference_result_t), intent(in) :: ref
        e = abs(ref%work_forcing - ref%diss_friction - ref%diss_damping)/ &
            max(abs(ref%work_forcing), 1.0e-6_dp*ref%work_gross, tiny(1.0_dp))
    end function reference_balance_error

    !> The keys of a reference solution.
    subroutine put_reference_keys(u, ref, stat, msg)
        integer, intent(in) :: u
        type(reference_result_t), intent(in) :: ref
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        integer :: nc
        nc = 0
        if (allocated(ref%stick_fraction)) nc = size(ref%stick_fraction)
        call put(u, "  converged = "//ltoa(ref%converged), stat, msg)
        call put(u, "  defect = "//rtoa(ref%defect), stat, msg)
        call put(u, "  nfev = "//itoa(ref%nfev), stat, msg)
        call put(u, "  njev = "//itoa(ref%njev), stat, msg)
        call put(u, "  start = '"//ref%start//"'", stat, msg)
        call put(u, "  shooting_seconds = "//rtoa(ref%seconds), stat, msg)
        call put(u, "  start_seconds = "//rtoa(ref%start_seconds), stat, msg)
        call put(u, "  t_section = "//rtoa(ref%t_section), stat, msg)
        call put(u, "  ncontact = "//itoa(nc), stat, msg)
        if (nc > 0) then
            call put(u, "  stick_fraction = "//rlist(ref%stick_fraction), stat, msg)
            call put(u, "  stick_phases = "//ilist(ref%stick_phases), stat, msg)
        end if
        call put(u, "  nevent = "//itoa(ref%nevent), stat, msg)
        call put(u, "  work_forcing = "//rtoa(ref%work_forcing), stat, msg)
        call put(u, "  diss_friction = "//rtoa(ref%diss_friction), stat, msg)
        call put(u, "  diss_damping = "//rtoa(ref%diss_damping), stat, msg)
        call put(u, "  energy_balance_error = "//rtoa(reference_balance_error(ref)), stat, msg)
        call put(u, "  diagnosis = '"//quote(ref%diagnosis)//"'", stat, msg)
    end subroutine put_reference_keys

    !> Write `dir`/summary.nml for the reference: a group &summary (method = 'reference',
    !> converged, defect, nfev, njev, start, shooting_seconds, start_seconds, t_section,
    !> ncontact, stick_fraction, stick_phases, nevent, energies, diagnosis), then the case.
    subroutine write_reference_summary(dir, case, ref, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case solved.
        type(case_t), intent(in) :: case
        !> The reference (converged or not).
        type(reference_result_t), intent(in) :: ref
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat
        character(len=512) :: msg
        call begin_summary(dir, "reference", u, stat, msg, error)
        if (allocated(error)) return
        call put_reference_keys(u, ref, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_reference_summary

    !> Write `dir`/events.csv: header t,contact,kind,direction,force,velocity and one row per
    !> event of the reference in one period, sorted by time in [0, T): kind is stick, slip,
    !> reversal or graze, direction the slip direction after the event (0 stuck, +1, -1),
    !> force [N] and slip velocity [m/s] at the event. Error: stat io.
    subroutine write_events_csv(dir, ref, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> A reference solution.
        type(reference_result_t), intent(in) :: ref
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, k, stat
        character(len=512) :: msg
        character(len=*), parameter :: fmt = '(' // real_fmt // ',",",i0,",",a,",",i0,",",' // &
                                              real_fmt // ',",",' // real_fmt // ')'
        call open_temporary(dir, "events.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) "t,contact,kind,direction,force,velocity"
        do k = 1, ref%nevent
            if (stat /= 0) exit
            write (u, fmt, iostat=stat, iomsg=msg) ref%event_t(k), ref%event_contact(k), &
                event_name(ref%event_kind(k)), ref%event_direction(k), ref%event_force(k), &
                ref%event_velocity(k)
        end do
        call close_and_rename(dir, "events.csv", u, stat, msg, error)
    end subroutine write_events_csv

    !> The keys of the differences: for each comparison `<method>_vs_<against>_max` and
    !> `_rms`, one value per quantity in the order of `quantities`.
    subroutine put_comparison_keys(u, cmp, stat, msg)
        integer, intent(in) :: u
        type(comparison_t), intent(in) :: cmp
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        call put(u, "  "//cmp%method//"_vs_"//cmp%against//"_max = "//rlist(cmp%max_error), &
                 stat, msg)
        call put(u, "  "//cmp%method//"_vs_"//cmp%against//"_rms = "//rlist(cmp%rms_error), &
                 stat, msg)
    end subroutine put_comparison_keys

    !> Write `dir`/summary.nml for the three methods side by side: a group &summary
    !> (method = 'all', the CPU seconds of each method, the common grid, the quantity names
    !> and the relative max and RMS differences per quantity), then the groups
    !> &summary_hbm, &summary_euler and &summary_reference with each method's own keys,
    !> then the effective case.
    subroutine write_side_by_side_summary(dir, case, res, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case solved.
        type(case_t), intent(in) :: case
        !> The three solutions.
        type(side_by_side_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, k
        character(len=512) :: msg
        character(len=12), allocatable :: names(:)
        character(len=:), allocatable :: line
        call begin_summary(dir, "all", u, stat, msg, error)
        if (allocated(error)) return
        call put(u, "  hbm_cpu_seconds = "//rtoa(res%hbm_seconds), stat, msg)
        call put(u, "  euler_cpu_seconds = "//rtoa(res%euler_seconds), stat, msg)
        call put(u, "  reference_cpu_seconds = "//rtoa(res%reference_seconds), stat, msg)
        call put(u, "  grid = "//itoa(res%grid), stat, msg)
        names = quantity_names(case%model%ndof, case%model%ncontact())
        line = "  quantities = "
        do k = 1, size(names)
            line = line//"'"//trim(names(k))//"'"
            if (k < size(names)) line = line//", "
        end do
        call put(u, line, stat, msg)
        do k = 1, size(res%comparisons)
            call put_comparison_keys(u, res%comparisons(k), stat, msg)
        end do
        call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_hbm", stat, msg)
        call put_hbm_keys(u, res%hbm, stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_euler", stat, msg)
        call put_euler_keys(u, case, res%euler, stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_reference", stat, msg)
        call put_reference_keys(u, res%reference, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_side_by_side_summary

    !> Write `dir`/study.csv: header method,parameter,samples,converged,cpu_seconds,repeats,
    !> iterations,err_x,err_v,err_r,rms_x,rms_v,rms_r, then err_<q> for every quantity q
    !> (x1..xN, v1..vN, r1..); one row per run. err_* are max errors relative to the
    !> reference amplitude of each quantity (err_x: the worst DOF), rms_* the RMS ones;
    !> NaN when the run produced no solution. Error: stat io.
    subroutine write_study_csv(dir, study, n, nc, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The study.
        type(study_result_t), intent(in) :: study
        !> Degrees of freedom and contacts of the model.
        integer, intent(in) :: n, nc
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, k, i, stat
        character(len=512) :: msg
        character(len=12), allocatable :: names(:)
        character(len=:), allocatable :: header
        character(len=80) :: fmt
        real(dp), allocatable :: e(:)
        real(dp) :: nan
        nan = ieee_value(1.0_dp, ieee_quiet_nan)
        names = quantity_names(n, nc)
        header = "method,parameter,samples,converged,cpu_seconds,repeats,iterations," // &
                 "err_x,err_v,err_r,rms_x,rms_v,rms_r"
        do i = 1, size(names)
            header = header//",err_"//trim(names(i))
        end do
        write (fmt, '(a,i0,a)') '(a,",",i0,",",i0,",",a,",",' // real_fmt // &
            ',",",i0,",",i0,",",', 6 + size(names), '(' // real_fmt // ',:,","))'
        call open_temporary(dir, "study.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, size(study%rows)
            if (stat /= 0) exit
            associate (row => study%rows(k))
                if (allocated(row%cmp%max_error)) then
                    e = [row%cmp%worst('x'), row%cmp%worst('v'), row%cmp%worst('r'), &
                         row%cmp%worst('x', .true.), row%cmp%worst('v', .true.), &
                         row%cmp%worst('r', .true.), row%cmp%max_error]
                else
                    e = [(nan, i=1, 6 + size(names))]
                end if
                write (u, fmt, iostat=stat, iomsg=msg) trim(row%method), row%parameter, &
                    row%samples, ltoa(row%converged), row%cpu_seconds, row%repeats, &
                    row%iterations, e
            end associate
        end do
        call close_and_rename(dir, "study.csv", u, stat, msg, error)
    end subroutine write_study_csv

    !> Write `dir`/summary.nml for a study: a group &summary (method = 'study', rows,
    !> skipped, reference_cpu_seconds), the group &summary_reference, then the case.
    subroutine write_study_summary(dir, case, study, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case studied.
        type(case_t), intent(in) :: case
        !> The study.
        type(study_result_t), intent(in) :: study
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, nrow
        character(len=512) :: msg
        nrow = 0
        if (allocated(study%rows)) nrow = size(study%rows)
        call begin_summary(dir, "study", u, stat, msg, error)
        if (allocated(error)) return
        call put(u, "  rows = "//itoa(nrow), stat, msg)
        call put(u, "  skipped = "//itoa(study%skipped), stat, msg)
        call put(u, "  reference_cpu_seconds = "//rtoa(study%reference_seconds), stat, msg)
        call put(u, "/", stat, msg)
        call put(u, "&summary_reference", stat, msg)
        call put_reference_keys(u, study%reference, stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_study_summary

    !> Write `dir`/frc.csv, one row per point of the forced-response curve: parameter,
    !> amp_1..amp_N (max_t |x_k| [m]), dissipation (energy dissipated per period, friction +
    !> viscous [J]), rmax_1..rmax_C (max_t |r_j| [N]), stick_1..stick_C (stick fraction),
    !> harmonics, residual (||F|| / fscale), status, floquet_max (largest Floquet
    !> multiplier modulus, NaN when not computed), stable (1 stable, 0 unstable, -1 unknown),
    !> truncation (relative harmonic truncation error estimate, NaN when not computed), then
    !> arclength, diss_friction, diss_damping [J], nfev. Error: stat io.
    subroutine write_frc_csv(dir, res, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The curve.
        type(sweep_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, k, i, stat, n, nc
        character(len=512) :: msg
        character(len=:), allocatable :: header
        character(len=160) :: fmt
        stat = 0
        msg = ''
        n = 0
        nc = 0
        if (res%npoints > 0) then
            n = size(res%points(1)%amplitude)
            nc = size(res%points(1)%rmax)
        end if
        header = "parameter"
        do i = 1, n
            header = header//",amp_"//itoa(i)
        end do
        header = header//",dissipation"
        do i = 1, nc
            header = header//",rmax_"//itoa(i)
        end do
        do i = 1, nc
            header = header//",stick_"//itoa(i)
        end do
        header = header//",harmonics,residual,status,floquet_max,stable,truncation,"// &
                 "arclength,diss_friction,diss_damping,nfev"
        write (fmt, '(a,i0,a)') '(', 2 + n + 2*nc, '(' // real_fmt // ',","),i0,",",' // &
            real_fmt // ',",",a,",",' // real_fmt // ',",",i0,",",4(' // real_fmt // &
            ',","),i0)'
        call open_temporary(dir, "frc.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, res%npoints
            if (stat /= 0) exit
            associate (p => res%points(k))
                write (u, fmt, iostat=stat, iomsg=msg) p%parameter, p%amplitude, p%dissipation, &
                    p%rmax, p%stick, p%harmonics, p%residual, trim(p%status), p%floquet_max, &
                    p%stable, p%truncation, p%arclength, p%diss_friction, p%diss_damping, p%nfev
            end associate
        end do
        call close_and_rename(dir, "frc.csv", u, stat, msg, error)
    end subroutine write_frc_csv

    !> Write `dir`/summary.nml for a sweep: &summary (method = 'sweep', complete, points,
    !> the parameter's range covered, folds, unstable points, CPU seconds, diagnosis), then
    !> the effective case. Error: stat io.
    subroutine write_sweep_summary(dir, case, res, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case.
        type(case_t), intent(in) :: case
        !> The curve.
        type(sweep_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat
        character(len=512) :: msg
        call begin_summary(dir, "sweep", u, stat, msg, error)
        if (allocated(error)) return
        call put(u, "  complete = "//ltoa(res%complete), stat, msg)
        call put(u, "  points = "//itoa(res%npoints), stat, msg)
        call put(u, "  resumed_points = "//itoa(res%resumed_points), stat, msg)
        if (res%npoints > 0) then
            call put(u, "  parameter_first = "//rtoa(res%points(1)%parameter), stat, msg)
            call put(u, "  parameter_last = "//rtoa(res%points(res%npoints)%parameter), &
                     stat, msg)
            call put(u, "  parameter_min = "//rtoa(minval(res%points(1:res%npoints)%parameter)), &
                     stat, msg)
            call put(u, "  parameter_max = "//rtoa(maxval(res%points(1:res%npoints)%parameter)), &
                     stat, msg)
            call put(u, "  unstable_points = "//itoa(count(res%points(1:res%npoints)%stable == 0)), &
                     stat, msg)
            call put(u, "  unknown_stability_points = "// &
                     itoa(count(res%points(1:res%npoints)%stable == -1)), stat, msg)
            call put(u, "  max_residual = "//rtoa(maxval(res%points(1:res%npoints)%residual)), &
                     stat, msg)
        end if
        call put(u, "  folds = "//itoa(res%folds), stat, msg)
        call put(u, "  rejected_steps = "//itoa(res%state%rejected), stat, msg)
        call put(u, "  cpu_seconds = "//rtoa(res%seconds), stat, msg)
        call put(u, "  stability_cpu_seconds = "//rtoa(res%stability_seconds), stat, msg)
        if (allocated(res%diagnosis)) then
            call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
        end if
        if (allocated(res%notes)) then
            call put(u, "  notes = '"//quote(res%notes)//"'", stat, msg)
        end if
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_sweep_summary

    !> Write `dir`/frc.gp, the gnuplot script that draws `dir`/frc.png from frc.csv: the
    !> amplitude of every DOF against the parameter (log scale), unstable points marked with
    !> red crosses. `parameter` labels the axis. Error: stat io.
    subroutine write_frc_plot_script(dir, parameter, ndof, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> Name of the swept parameter.
        character(len=*), intent(in) :: parameter
        !> Number of DOFs (columns amp_1..amp_N).
        integer, intent(in) :: ndof
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, k
        character(len=512) :: msg
        stat = 0
        msg = ''
        call open_temporary(dir, "frc.gp", u, error)
        if (allocated(error)) return
        call put(u, "# Forced-response curve from frc.csv: gnuplot frc.gp (in this directory)", &
                 stat, msg)
        call put(u, "set terminal pngcairo size 1100,700 enhanced font ',11'", stat, msg)
        call put(u, "if (!exists('suffix')) suffix = ''", stat, msg)
        call put(u, "set output 'frc.png'.suffix", stat, msg)
        call put(u, "set datafile separator ','", stat, msg)
        call put(u, "set key autotitle columnhead top right", stat, msg)
        call put(u, "set grid lc rgb '#dddddd'", stat, msg)
        call put(u, "set logscale y", stat, msg)
        call put(u, "f = 'frc.csv'", stat, msg)
        call put(u, "# the y range: four decades below the largest amplitude (a contact stuck "// &
                 "all period drives its DOF to roundoff)", stat, msg)
        call put(u, "ymax = 0", stat, msg)
        call put(u, "do for [k=2:"//itoa(1 + ndof)//"] { stats f using k nooutput; "// &
                 "if (STATS_max > ymax) { ymax = STATS_max } }", stat, msg)
        call put(u, "if (ymax > 0) set yrange [ymax*1e-4:ymax*2]", stat, msg)
        call put(u, "set xlabel '"//parameter//"'", stat, msg)
        call put(u, "set ylabel 'amplitude max |x_k(t)|'", stat, msg)
        call put(u, "set title 'Forced-response curve (red crosses: unstable, Floquet)'", &
                 stat, msg)
        call put(u, "# the column 'stable' (1, 0 unstable, -1 unknown)", stat, msg)
        call put(u, "unstable(k) = (column('stable') == 0 ? column(k) : 1/0)", stat, msg)
        do k = 1, ndof
            if (k == 1) then
                call put(u, "plot f using 1:"//itoa(1 + k)//" with lines lw 1.5 title 'amp_"// &
                         itoa(k)//"', \", stat, msg)
            else
                call put(u, "     f using 1:"//itoa(1 + k)//" with lines lw 1.5 title 'amp_"// &
                         itoa(k)//"', \", stat, msg)
            end if
            if (k < ndof) then
                call put(u, "     f using 1:(unstable("//itoa(1 + k)//")) with points pt 2 "// &
                         "ps 0.8 lc rgb 'red' notitle, \", stat, msg)
            else
                call put(u, "     f using 1:(unstable("//itoa(1 + k)//")) with points pt 2 "// &
                         "ps 0.8 lc rgb 'red' title 'unstable'", stat, msg)
            end if
        end do
        call close_and_rename(dir, "frc.gp", u, stat, msg, error)
    end subroutine write_frc_plot_script

    !> Write `dir`/robustness.csv: header
    !> method,omega,mu,harmonics,rho,rho_auto,samples,converged,success,iterations,
    !> cpu_seconds,err_amplitude,diagnosis and one row per run (logicals T/F; success:
    !> converged and, against the reference, err_amplitude <= wrong_tol; rho NaN for 'euler';
    !> err_amplitude NaN when unknown; diagnosis quoted, empty for a success). Written under
    !> a temporary name and renamed when complete. Error: stat io.
    subroutine write_robustness_csv(dir, rows, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The runs.
        type(robustness_row_t), intent(in) :: rows(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        character(len=*), parameter :: fmt = '(a,",",' // real_fmt // ',",",' // real_fmt // &
            ',",",i0,",",' // real_fmt // ',",",a,",",i0,",",a,",",a,",",i0,",",' // real_fmt // &
            ',",",' // real_fmt // ',",",a)'
        integer :: u, k, stat
        character(len=512) :: msg
        call open_temporary(dir, "robustness.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) "method,omega,mu,harmonics,rho,rho_auto,"// &
            "samples,converged,success,iterations,cpu_seconds,err_amplitude,diagnosis"
        do k = 1, size(rows)
            if (stat /= 0) exit
            associate (row => rows(k))
                write (u, fmt, iostat=stat, iomsg=msg) trim(row%method), row%omega, row%mu, &
                    row%harmonics, row%rho, merge("T", "F", row%rho_auto), row%samples, &
                    merge("T", "F", row%converged), merge("T", "F", row%success), &
                    row%iterations, row%cpu_seconds, &
                    row%err_amplitude, csv_quote(row%diagnosis)
            end associate
        end do
        call close_and_rename(dir, "robustness.csv", u, stat, msg, error)
    end subroutine write_robustness_csv

    !> A CSV field in double quotes, inner double quotes doubled (RFC 4180).
    pure function csv_quote(s) result(t)
        character(len=:), allocatable, intent(in) :: s
        character(len=:), allocatable :: t
        integer :: i
        t = '"'
        if (allocated(s)) then
            do i = 1, len(s)
                if (s(i:i) == '"') then
                    t = t//'""'
                else
                    t = t//s(i:i)
                end if
            end do
        end if
        t = t//'"'
    end function csv_quote
    !> Write `dir`/summary.nml for a robustness study: &summary (method = 'robustness', rows,
    !> then per method runs_<m> and successes_<m>, m = hbm_cold, hbm_warm, euler), then the
    !> effective case. Error: stat io.
    subroutine write_robustness_summary(dir, case, rows, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case.
        type(case_t), intent(in) :: case
        !> The runs.
        type(robustness_row_t), intent(in) :: rows(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        character(len=8), parameter :: methods(3) = [character(len=8) :: 'hbm-cold', &
                                                     'hbm-warm', 'euler']
        character(len=8), parameter :: keys(3) = [character(len=8) :: 'hbm_cold', &
                                                  'hbm_warm', 'euler']
        integer :: u, stat, k
        character(len=512) :: msg
        call begin_summary(dir, "robustness", u, stat, msg, error)
        if (allocated(error)) return
        call put(u, "  rows = "//itoa(size(rows)), stat, msg)
        do k = 1, 3
            call put(u, "  runs_"//trim(keys(k))//" = "//itoa(count(rows%method == methods(k))), &
                     stat, msg)
            call put(u, "  successes_"//trim(keys(k))//" = "// &
                     itoa(count(rows%method == methods(k) .and. rows%success)), stat, msg)
        end do
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_robustness_summary

    !> Write `dir`/robustness.gp, the gnuplot script that draws robustness_cold.png and
    !> robustness_warm.png from robustness.csv: one panel per (rho, H), omega across and mu
    !> up (log), each run a square: green success, orange converged to a wrong solution, red
    !> not converged. Error: stat io.
    subroutine write_robustness_plot_script(dir, opts, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The grid.
        type(robustness_options_t), intent(in) :: opts
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, i, j, m
        character(len=512) :: msg
        character(len=8), parameter :: methods(2) = [character(len=8) :: 'hbm-cold', 'hbm-warm']
        character(len=4), parameter :: tags(2) = [character(len=4) :: 'cold', 'warm']
        character(len=:), allocatable :: sel, label
        stat = 0
        msg = ''
        call open_temporary(dir, "robustness.gp", u, error)
        if (allocated(error)) return
        call put(u, "# Robustness maps from robustness.csv: gnuplot robustness.gp (in this "// &
                 "directory)", stat, msg)
        call put(u, "# green: converged to the right solution; orange: converged, error > "// &
                 "wrong_tol; red: not converged", stat, msg)
        call put(u, "if (!exists('suffix')) suffix = ''", stat, msg)
        call put(u, "set datafile separator ','", stat, msg)
        call put(u, "set logscale y", stat, msg)
        call put(u, "set key off", stat, msg)
        call put(u, "set tics font ',8'", stat, msg)
        call put(u, "set offsets graph 0.04, graph 0.04, graph 0.08, graph 0.08", stat, msg)
        call put(u, "colour(c, s) = (s eq 'T' ? 0x2ca02c : (c eq 'T' ? 0xff7f0e : 0xd62728))", &
                 stat, msg)
        call put(u, "f = 'robustness.csv'", stat, msg)
        do m = 1, 2
            if (m == 2 .and. .not. opts%warm) exit
            call put(u, "set terminal pngcairo size "//itoa(260*size(opts%harmonics) + 80)// &
                     ","//itoa(200*size(opts%rhos) + 60)//" font ',9'", stat, msg)
            call put(u, "set output 'robustness_"//trim(tags(m))//".png'.suffix", stat, msg)
            call put(u, "set multiplot layout "//itoa(size(opts%rhos))//","// &
                     itoa(size(opts%harmonics))//" title 'weighted residual, "// &
                     trim(tags(m))//" starts: x omega [rad/s], y mu'", stat, msg)
            do i = 1, size(opts%rhos)
                do j = 1, size(opts%harmonics)
                    if (opts%rhos(i) == 0.0_dp) then
                        sel = "strcol(6) eq 'T'"
                        label = "rho auto"
                    else
                        sel = "strcol(6) eq 'F' && abs($5 - "//rtoa(opts%rhos(i))//") <= 1e-12*"// &
                              rtoa(opts%rhos(i))
                        label = "rho "//trim(adjustl(gfmt(opts%rhos(i))))
                    end if
                    call put(u, "set title '"//label//", H = "//itoa(opts%harmonics(j))//"'", &
                             stat, msg)
                    call put(u, "plot f using 2:((strcol(1) eq '"//trim(methods(m))// &
                             "' && $4 == "//itoa(opts%harmonics(j))//" && "//sel// &
                             ") ? $3 : 1/0):(colour(strcol(8), strcol(9))) "// &
                             "every ::1 with points pt 5 ps 1.2 lc rgb variable", stat, msg)
                end do
            end do
            call put(u, "unset multiplot", stat, msg)
        end do
        call close_and_rename(dir, "robustness.gp", u, stat, msg, error)
    end subroutine write_robustness_plot_script

    !> A short real for labels: 0.02, 0.2, 1, 5, 1.5e-05.
    pure function gfmt(x) result(s)
        real(dp), intent(in) :: x
        character(len=16) :: s
        integer :: k
        if (abs(x) >= 1.0e-3_dp .and. abs(x) < 1.0e5_dp) then
            write (s, '(f16.6)') x
            s = adjustl(s)
            k = len_trim(s)
            do while (s(k:k) == '0')
                s(k:k) = ' '
                k = k - 1
            end do
            if (s(k:k) == '.') s(k:k) = ' '
        else
            write (s, '(es10.2)') x
            s = adjustl(s)
        end if
    end function gfmt

    !> Open the temporary summary.nml and write its first lines, up to `method = '...'`.
    subroutine begin_summary(dir, method, u, stat, msg, error)
        character(len=*), intent(in) :: dir, method
        integer, intent(out) :: u, stat
        character(len=*), intent(out) :: msg
        type(error_type), allocatable, intent(out) :: error
        stat = 0
        msg = ""
        call open_temporary(dir, "summary.nml", u, error)
        if (allocated(error)) return
        call put(u, "! stickslip summary: the group &summary (and for several methods "// &
                 "&summary_<method>), then the effective case (&system ... &study)", stat, msg)
        call put(u, "&summary", stat, msg)
        call put(u, "  method = '"//method//"'", stat, msg)
    end subroutine begin_summary

    !> Close the group &summary, echo the effective case, close and rename summary.nml.
    subroutine end_summary(dir, case, u, stat, msg, error)
        character(len=*), intent(in) :: dir
        type(case_t), intent(in) :: case
        integer, intent(in) :: u
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        type(error_type), allocatable, intent(out) :: error
        call put(u, "/", stat, msg)
        if (stat == 0) call write_case(u, case, stat, msg)
        call close_and_rename(dir, "summary.nml", u, stat, msg, error)
    end subroutine end_summary

    !> Double the single quotes of a string for a namelist character value.
    pure function quote(s) result(t)
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: t
        integer :: i
        t = ""
        do i = 1, len(s)
            if (s(i:i) == "'") then
                t = t//"''"
            else
                t = t//s(i:i)
            end if
        end do
    end function quote
end module stickslip_output
