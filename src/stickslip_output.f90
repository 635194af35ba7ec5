!> Result files: hbm.csv (one period of samples), coefficients.csv (Fourier coefficients of x
!> and r) and summary.nml (convergence report, diagnostics, energy balance and the effective
!> case). Every file is written under a temporary name in the output directory and renamed
!> when complete, so a reader never sees a partial file. Knows nothing of how results are
!> computed.
module stickslip_output
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_solution, only: hbm_solution_t
    use stickslip_euler, only: euler_result_t
    use stickslip_case, only: case_t, write_case, put, rtoa, ltoa, rlist, ilist, llist
    implicit none
    private
    public :: make_directory, write_hbm_csv, write_samples_csv, write_coefficients_csv, &
              write_summary, write_euler_summary, energy_balance_error

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

    !> Open `dir/name.tmp` for writing; finish with close_and_rename.
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

    !> Relative energy balance error over one period:
    !> |work_forcing - diss_friction - diss_damping| / max(|work_forcing|, tiny).
    pure real(dp) function energy_balance_error(sol) result(e)
        !> The solution.
        type(hbm_solution_t), intent(in) :: sol
        e = abs(sol%work_forcing - sol%diss_friction - sol%diss_damping)/ &
            max(abs(sol%work_forcing), tiny(1.0_dp))
    end function energy_balance_error

    !> Write `dir`/summary.nml: a namelist group &summary (one `key = value` per line) with
    !> the convergence report and diagnostics, followed by the effective case as namelist
    !> groups (read_case reads the file back as a case).
    subroutine write_summary(dir, case, sol, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The case solved.
        type(case_t), intent(in) :: case
        !> The solution (converged or not).
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, nc
        character(len=512) :: msg

        nc = 0
        if (allocated(sol%stick_fraction)) nc = size(sol%stick_fraction)
        call begin_summary(dir, "hbm", u, stat, msg, error)
        if (allocated(error)) return
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
        call put(u, "  ncontact = "//itoa(nc), stat, msg)
        if (nc > 0) then
            call put(u, "  stick_fraction = "//rlist(sol%stick_fraction), stat, msg)
            call put(u, "  stick_phases = "//ilist(sol%stick_phases), stat, msg)
            call put(u, "  offset_undetermined = "//llist(sol%offset_undetermined), stat, msg)
        end if
        call put(u, "  work_forcing = "//rtoa(sol%work_forcing), stat, msg)
        call put(u, "  diss_friction = "//rtoa(sol%diss_friction), stat, msg)
        call put(u, "  diss_damping = "//rtoa(sol%diss_damping), stat, msg)
        call put(u, "  diss_coulomb = "//rtoa(sol%diss_coulomb), stat, msg)
        call put(u, "  energy_balance_error = "//rtoa(energy_balance_error(sol)), stat, msg)
        call put(u, "  diagnosis = '"//quote(sol%diagnosis)//"'", stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_summary

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
        call put(u, "  periodic = "//ltoa(res%periodic), stat, msg)
        call put(u, "  periods = "//itoa(res%periods), stat, msg)
        call put(u, "  defect = "//rtoa(res%defect), stat, msg)
        call put(u, "  euler_seconds = "//rtoa(res%seconds), stat, msg)
        call put(u, "  steps_per_period = "//itoa(case%euler%steps_per_period), stat, msg)
        call put(u, "  max_sweeps = "//itoa(res%max_sweeps), stat, msg)
        call put(u, "  diagnosis = '"//quote(res%diagnosis)//"'", stat, msg)
        call end_summary(dir, case, u, stat, msg, error)
    end subroutine write_euler_summary

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
        call put(u, "! stickslip summary: the group &summary, then the effective case "// &
                 "(&system ... &euler)", stat, msg)
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
