!> family.csv: one row per curve of a family of forced-response curves (stickslip_sweep_family)
!> with the curve's peak per observed DOF, where and at what dissipation it is reached, and
!> the peaks of the two linear limits (every contact stuck, every contact slipping).
module stickslip_family_csv
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp, two_pi
    use stickslip_diagnostics, only: level_untrusted
    use stickslip_error, only: error_type
    use stickslip_sweep_family, only: family_result_t
    use stickslip_files, only: open_temporary, close_and_rename
    use stickslip_csv, only: real_fmt, columns, column_numbers, selection
    implicit none
    private
    public :: write_family_csv

contains

    !> Write `dir`/family.csv: header curve,family_value,points,complete, then per observed
    !> DOF d of the selection peak_<d> (the curve's peak, measured as the family's
    !> measure) [length], peak_omega_<d> [rad/s], peak_frequency_<d> [cycles per time
    !> unit], peak_dissipation_<d> (energy per period there) [energy], refined_<d> (1: found
    !> by single solves between the largest point's neighbours, 0: the largest point),
    !> stuck_peak_<d> and slipping_peak_<d> (the linear limits' peaks over the range, NaN
    !> when unbounded or not computed) [length], then trusted (0 when a peak of the row is
    !> untrusted: the curve stopped short, or its largest point is) and check (the first
    !> failed check: 'incomplete', 'peak_at_end', a point's check; 'no_start' for a curve
    !> without points). Error: stat io.
    subroutine write_family_csv(dir, fam, error, dofs, labels)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The family.
        type(family_result_t), intent(in) :: fam
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The observed displacements written (each in 1..nobs); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Their column numbers (default: `dofs`).
        integer, intent(in), optional :: labels(:)
        integer :: u, k, stat, n, level, i
        character(len=512) :: msg
        character(len=:), allocatable :: header, check
        integer, allocatable :: sel(:), numbers(:)
        real(dp), allocatable :: stuck(:), slipping(:), row(:)
        stat = 0
        msg = ''
        if (present(dofs)) then
            sel = dofs
        else
            sel = selection(size(fam%peaks, 1))
        end if
        numbers = column_numbers(sel, labels)
        n = size(sel)
        header = "curve,family_value,points,complete"//columns("peak_", numbers)// &
                 columns("peak_omega_", numbers)//columns("peak_frequency_", numbers)// &
                 columns("peak_dissipation_", numbers)//columns("refined_", numbers)// &
                 columns("stuck_peak_", numbers)//columns("slipping_peak_", numbers)// &
                 ",trusted,check"
        call open_temporary(dir, "family.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, size(fam%values)
            if (stat /= 0) exit
            associate (c => fam%curves(k))
                write (u, '(i0,",",' // real_fmt // ',",",i0,",",i0)', iostat=stat, &
                       iomsg=msg, advance='no') k, fam%values(k), c%npoints, &
                    merge(1, 0, c%complete)
                if (c%npoints == 0) then
                    ! a curve without points: empty fields
                    if (stat == 0) write (u, '(a)', iostat=stat, iomsg=msg) &
                        repeat(",", 7*n)//",0,no_start"
                    cycle
                end if
                if (allocated(fam%stuck)) then
                    stuck = fam%stuck(sel, k)%amplitude
                    slipping = fam%slipping(sel, k)%amplitude
                else
                    stuck = [(ieee_value(1.0_dp, ieee_quiet_nan), i=1, n)]
                    slipping = stuck
                end if
                associate (p => fam%peaks(sel, k))
                    ! the row's values in the header's order, then its verdict: its worst peak's
                    row = [p%amplitude, p%omega, p%omega/two_pi, p%dissipation]
                    if (stat == 0) write (u, '(*(:",",' // real_fmt // '))', iostat=stat, &
                                          iomsg=msg, advance='no') row
                    if (stat == 0) write (u, '(*(:",",i0))', iostat=stat, iomsg=msg, &
                                          advance='no') merge(1, 0, p%refined)
                    if (stat == 0) write (u, '(*(:",",' // real_fmt // '))', iostat=stat, &
                                          iomsg=msg, advance='no') stuck, slipping
                    level = 0
                    check = ''
                    do i = 1, n
                        if (p(i)%check_level > level) then
                            level = p(i)%check_level
                            check = trim(p(i)%check)
                        end if
                    end do
                end associate
                if (stat == 0) write (u, '(",",i0,",",a)', iostat=stat, iomsg=msg) &
                    merge(0, 1, level >= level_untrusted), check
            end associate
        end do
        call close_and_rename(dir, "family.csv", u, stat, msg, error)
    end subroutine write_family_csv
end module stickslip_family_csv
