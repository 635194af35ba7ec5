!> The CSV result files: hbm.csv, euler.csv and reference.csv (one period of samples, the
!> format of hbm.csv), coefficients.csv (Fourier coefficients of x and r), events.csv (the
!> reference's events), study.csv (the work-precision study), frc.csv (a forced-response
!> curve) and robustness.csv (the robustness study). Each file is written under a unique
!> temporary name and renamed when complete (stickslip_files). Columns are contracts
!> (doc/outputs.md). The per-DOF columns are those of the DOFs selected by the optional
!> `dofs` (&output dofs), named by DOF number (x7, v7, amp_7); absent: every DOF, 1..N.
!> Knows nothing of how the results are computed.
module stickslip_csv
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    use stickslip_kinds, only: dp, two_pi
    use stickslip_diagnostics, only: level_untrusted
    use stickslip_error, only: error_type, itoa
    use stickslip_solution, only: hbm_solution_t
    use stickslip_reference, only: reference_result_t
    use stickslip_flow, only: event_name
    use stickslip_compare, only: quantity_names
    use stickslip_study, only: study_result_t
    use stickslip_sweep, only: sweep_result_t, frc_point_t
    use stickslip_sweep_result, only: vibration_samples_t
    use stickslip_modes, only: modes_result_t
    use stickslip_robustness, only: robustness_row_t
    use stickslip_case, only: ltoa
    use stickslip_files, only: open_temporary, close_and_rename
    use stickslip_contact_set, only: contact_set_t
    use stickslip_contact_element, only: along_tangent, along_tangent2
    implicit none
    private
    public :: write_hbm_csv, write_samples_csv, write_coefficients_csv, write_events_csv
    public :: write_study_csv, write_frc_csv, write_frc_harmonics_csv, write_robustness_csv
    public :: write_modes_csv, write_modes_harmonics_csv
    public :: real_fmt
    public :: format_real, real_width, contact_columns, columns, column_numbers, selection

    !> Edit descriptor of every real in the result files: full double precision.
    character(len=*), parameter :: real_fmt = 'es25.17e3'
    !> Width of a real written with real_fmt.
    integer, parameter :: real_width = 25

    ! format_real: 10^k = (hi + lo) 2^e for the decimal exponents a double can need, as a
    ! double-double mantissa in [0.5, 1) (about 106 bits) and a binary exponent, folded by
    ! the compiler from the correctly rounded quadruple-precision value (113 bits).
    integer, parameter :: qp = selected_real_kind(33, 4931)
    integer, parameter :: pow_min = -300, pow_max = 350
    integer :: k_
    real(qp), parameter :: pow_q(pow_min:pow_max) = [(fraction(10.0_qp**k_), k_=pow_min, pow_max)]
    integer, parameter :: pow_e(pow_min:pow_max) = [(exponent(10.0_qp**k_), k_=pow_min, pow_max)]
    real(dp), parameter :: pow_hi(pow_min:pow_max) = real(pow_q, dp)
    real(dp), parameter :: pow_lo(pow_min:pow_max) = real(pow_q - real(pow_hi, qp), dp)
    !> "00", "01", .., "99".
    character(len=200), parameter :: digit_pairs = &
        '00010203040506070809101112131415161718192021222324252627282930313233343536373839' // &
        '40414243444546474849505152535455565758596061626364656667686970717273747576777879' // &
        '8081828384858687888990919293949596979899'

contains

    !> Write `dir`/hbm.csv: header t,x1..xN,v1..vN,r1..rC (with `dofs`: t,x<d>..,v<d>..,
    !> r1..rC for the DOFs d selected, in their order) and one row per sample
    !> t_k = k T / nt, full double precision. Needs the solution's samples. Error: stat io.
    subroutine write_hbm_csv(dir, sol, error, dofs, labels)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> A solution with samples.
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs written (each in 1..N); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (size of the selection; default: the DOF
        !> numbers themselves), e.g. full-model numbers of a reduced model's recovered DOFs.
        integer, intent(in), optional :: labels(:)
        call write_samples_csv(dir, "hbm.csv", sol%t, sol%x, sol%v, sol%r, error, dofs, labels, &
                               sol%contacts, sol%gap)
    end subroutine write_hbm_csv

    !> Write `dir`/`name`: header t,x1..xN,v1..vN,r1..rC (with `dofs`: t,x<d>..,v<d>..,r1..rC
    !> for the DOFs d selected, in their order) and one row per instant, full double
    !> precision (the format of hbm.csv, also used for euler.csv). Error: stat io.
    subroutine write_samples_csv(dir, name, t, x, v, r, error, dofs, labels, contacts, gap)
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
        !> The DOFs written (each in 1..N); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (size of the selection; default: the DOF
        !> numbers themselves), e.g. full-model numbers of a reduced model's recovered DOFs.
        integer, intent(in), optional :: labels(:)
        !> The contacts' channel layout: with contact laws, r holds the channel forces
        !> (instants x n_channel) and the columns are contact_columns' (r<j>, r<j>_2,
        !> normal<j>, gap<j>); absent or plain: r1..rC.
        type(contact_set_t), intent(in), optional :: contacts
        !> Gap of each contact, instants x n_c [m] (with `contacts`).
        real(dp), intent(in), optional :: gap(:, :)
        integer :: u, k, i, n, nc, stat, ncol, pos
        character(len=512) :: msg
        character(len=:), allocatable :: header, line
        integer, allocatable :: sel(:), numbers(:), channel(:), gap_of(:)
        character(len=16), allocatable :: rnames(:)

        sel = selection(size(x, 2), dofs)
        numbers = column_numbers(sel, labels)
        n = size(sel)
        call contact_columns(size(r, 2), rnames, channel, gap_of, contacts)
        if (.not. present(gap)) gap_of = 0*gap_of
        nc = size(rnames)
        header = "t"
        header = header//columns("x", numbers(1:n))
        header = header//columns("v", numbers(1:n))
        do i = 1, nc
            header = header//","//trim(rnames(i))
        end do
        ncol = 1 + 2*n + nc
        allocate (character(len=ncol*(real_width + 1)) :: line)
        call open_temporary(dir, name, u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, size(t)
            if (stat /= 0) exit
            ! the text of '(ncol(es25.17e3,:,","))', built by format_real
            pos = 0
            call put(t(k))
            do i = 1, n
                call put(x(k, sel(i)))
            end do
            do i = 1, n
                call put(v(k, sel(i)))
            end do
            do i = 1, nc
                if (channel(i) > 0) then
                    call put(column_force(r(k, :), channel(i)))
                else if (gap_of(i) > 0) then
                    call put(gap(k, gap_of(i)))
                else
                    call put(0.0_dp)
                end if
            end do
            write (u, '(a)', iostat=stat, iomsg=msg) line(1:pos - 1)
        end do
        call close_and_rename(dir, name, u, stat, msg, error)
    contains
        !> The column of primary channel c at one instant (summed over its sliders).
        real(dp) function column_force(row, c)
            real(dp), intent(in) :: row(:)
            integer, intent(in) :: c
            real(dp) :: v(1)
            v = summed(row, [c], contacts)
            column_force = v(1)
        end function column_force

        !> Append one field and its comma to line(1:pos).
        subroutine put(value)
            real(dp), intent(in) :: value
            line(pos + 1:pos + real_width) = format_real(value)
            line(pos + real_width + 1:pos + real_width + 1) = ','
            pos = pos + real_width + 1
        end subroutine put
    end subroutine write_samples_csv

    !> Write `dir`/coefficients.csv: header harmonic,kind,x1..xN,r1..rC (with `dofs`:
    !> x<d>.. for the DOFs d selected, in their order) and one row per basis function, kind
    !> c0 (constant), cos or sin; u(t) = c0 + sum a cos(h omega t) + b sin(...). Error: io.
    subroutine write_coefficients_csv(dir, sol, error, dofs, labels)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The solution.
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs written (each in 1..N); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (size of the selection; default: the DOF
        !> numbers themselves), e.g. full-model numbers of a reduced model's recovered DOFs.
        integer, intent(in), optional :: labels(:)
        integer :: u, k, i, n, nc, stat
        character(len=512) :: msg
        character(len=:), allocatable :: header, kind
        character(len=80) :: fmt
        integer, allocatable :: sel(:), numbers(:), channel(:), gap_of(:)
        character(len=16), allocatable :: rnames(:)

        sel = selection(size(sol%xcoef, 2), dofs)
        numbers = column_numbers(sel, labels)
        n = size(sel)
        call contact_columns(size(sol%rcoef, 2), rnames, channel, gap_of, sol%contacts)
        ! the gap is not a force channel: no coefficients column
        rnames = pack(rnames, channel > 0)
        channel = pack(channel, channel > 0)
        nc = size(channel)
        header = "harmonic,kind"
        header = header//columns("x", numbers(1:n))
        do i = 1, nc
            header = header//","//trim(rnames(i))
        end do
        write (fmt, '(a,i0,a)') '(i0,",",a,",",', n + nc, '(' // real_fmt // ',:,","))'
        call open_temporary(dir, "coefficients.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, sol%nb
            if (stat /= 0) exit
            kind = basis_kind(sol%harmonic, k)
            write (u, fmt, iostat=stat, iomsg=msg) sol%harmonic(k), kind, sol%xcoef(k, sel), &
                summed(sol%rcoef(k, :), channel, sol%contacts)
        end do
        call close_and_rename(dir, "coefficients.csv", u, stat, msg, error)
    end subroutine write_coefficients_csv

    !> Write `dir`/events.csv: header t,contact,kind,direction,force,velocity and one row per
    !> event of the reference in one period, sorted by time in [0, T): kind is stick, slip,
    !> reversal or graze, and with contact laws open, close or impact (a rigid contact that
    !> closes with a normal velocity), direction the slip direction after the event (0 stuck
    !> or open, +1, -1),
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

    !> Write `dir`/study.csv: header method,parameter,samples,converged,cpu_seconds,repeats,
    !> iterations,err_x,err_v,err_r,rms_x,rms_v,rms_r, then err_<q> for every quantity q
    !> (x1..xN, v1..vN, r1..; with `dofs`: x<d>.., v<d>.. for the DOFs d selected, in their
    !> order, then r1..); one row per run. err_* are max errors relative to the reference
    !> amplitude of each quantity (err_x: the worst of all DOFs, selected or not), rms_* the
    !> RMS ones; NaN when the run produced no solution. Error: stat io.
    subroutine write_study_csv(dir, study, n, nc, error, dofs, labels)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The study.
        type(study_result_t), intent(in) :: study
        !> Degrees of freedom and contacts of the model.
        integer, intent(in) :: n, nc
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs whose err_x<d>, err_v<d> columns are written (each in 1..n); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (size of the selection; default: the DOF
        !> numbers themselves), e.g. full-model numbers of a reduced model's recovered DOFs.
        integer, intent(in), optional :: labels(:)
        integer :: u, k, i, stat
        character(len=512) :: msg
        character(len=12), allocatable :: names(:)
        character(len=:), allocatable :: header
        character(len=80) :: fmt
        real(dp), allocatable :: e(:)
        real(dp) :: nan
        integer, allocatable :: sel(:), columns(:)
        nan = ieee_value(1.0_dp, ieee_quiet_nan)
        sel = selection(n, dofs)
        ! the quantities written, as indices into quantity_names(n, nc): x, v, then r
        columns = [sel, n + sel, (2*n + i, i=1, nc)]
        names = quantity_names(n, nc)
        names = names(columns)
        if (present(labels)) then
            do i = 1, size(sel)
                names(i) = "x"//itoa(labels(i))
                names(size(sel) + i) = "v"//itoa(labels(i))
            end do
        end if
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
                         row%cmp%worst('r', .true.), row%cmp%max_error(columns)]
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

    !> Write `dir`/frc.csv, one row per point of the forced-response curve: parameter,
    !> amp_1..amp_N (max_t |x_k| [m]; with `dofs`: amp_<d> for the DOFs d selected, in their
    !> order), dissipation (energy dissipated per period, friction +
    !> viscous [J]), rmax_1..rmax_C (max_t |r_j| [N]), stick_1..stick_C (stick fraction),
    !> harmonics, residual (||F|| / fscale), status, floquet_max (largest Floquet
    !> multiplier modulus, NaN when not computed), stable (1 stable, 0 unstable, -1 unknown),
    !> truncation (relative harmonic truncation error estimate, NaN when not computed), then
    !> arclength, diss_friction, diss_damping [J], nfev; with contact laws then open_1..
    !> open_C, slip_1..slip_C (shares of the period) and normal_max_1..normal_max_C (max_t
    !> lambda_j [N]); then omega [rad/s] and frequency = omega / 2 pi [Hz] of the point,
    !> vib_<d> (half the peak-to-peak, (max_t x - min_t x) / 2 [m]) and
    !> h1_<d> (the first harmonic's modulus [m]) of the same DOFs as amp_<d>
    !> (frc_point_t%vibration); last trusted and check. Error: stat io.
    subroutine write_frc_csv(dir, res, error, dofs, labels, curve, family_value)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The curve.
        type(sweep_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs written (each in 1..N); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (size of the selection; default: the DOF
        !> numbers themselves), e.g. full-model numbers of a reduced model's recovered DOFs.
        integer, intent(in), optional :: labels(:)
        !> The curves of a family in one table: each point's curve (1..) and the value of the
        !> family's parameter, columns curve,family_value before trusted,check.
        integer, intent(in), optional :: curve(:)
        real(dp), intent(in), optional :: family_value(:)
        integer :: u, k, i, stat, n, nc
        character(len=512) :: msg
        character(len=:), allocatable :: header
        character(len=200) :: fmt, vfmt
        logical :: laws
        integer, allocatable :: sel(:), numbers(:)
        real(dp), allocatable :: half_range(:), first(:)
        type(vibration_samples_t) :: samples
        stat = 0
        msg = ''
        n = 0
        nc = 0
        if (res%npoints > 0) then
            n = size(res%points(1)%amplitude)
            nc = size(res%points(1)%rmax)
        end if
        if (present(dofs)) then
            ! the header names the selection even for a curve without points
            sel = dofs
        else
            sel = selection(n)
        end if
        numbers = column_numbers(sel, labels)
        n = size(sel)
        header = "parameter"
        header = header//columns("amp_", numbers(1:n))
        header = header//",dissipation"
        header = header//columns("rmax_", [(i, i=1, nc)])
        header = header//columns("stick_", [(i, i=1, nc)])
        header = header//",harmonics,residual,status,floquet_max,stable,truncation,"// &
                 "arclength,diss_friction,diss_damping,nfev"
        ! contact laws: each contact's open and slip shares and largest normal force
        laws = .false.
        if (res%npoints > 0) laws = allocated(res%points(1)%open)
        if (laws) header = header//law_columns(nc)
        ! the point's frequency, angular and in cycles; the vibration amplitudes: half the
        ! peak-to-peak and the first harmonic's modulus
        header = header//",omega,frequency"
        header = header//columns("vib_", numbers(1:n))//columns("h1_", numbers(1:n))
        if (present(curve)) header = header//",curve,family_value"
        header = header//",trusted,check"
        write (vfmt, '(a,i0,a)') '(', max(1, 2*n), '(",",' // real_fmt // '))'
        write (fmt, '(a,i0,a)') '(', 2 + n + 2*nc, '(' // real_fmt // ',","),i0,",",' // &
            real_fmt // ',",",a,",",' // real_fmt // ',",",i0,",",4(' // real_fmt // &
            ',","),i0)'
        if (laws) write (fmt, '(a,i0,a,i0,a)') '(', 2 + n + 2*nc, '(' // real_fmt // &
            ',","),i0,",",' // real_fmt // ',",",a,",",' // real_fmt // ',",",i0,",",4(' // &
            real_fmt // ',","),i0,', 3*nc, '(",",' // real_fmt // '))'
        call open_temporary(dir, "frc.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, res%npoints
            if (stat /= 0) exit
            associate (p => res%points(k))
                if (laws) then
                    write (u, fmt, iostat=stat, iomsg=msg, advance='no') p%parameter, &
                        p%amplitude(sel), &
                        p%dissipation, p%rmax, p%stick, p%harmonics, p%residual, &
                        trim(p%status), p%floquet_max, p%stable, p%truncation, p%arclength, &
                        p%diss_friction, p%diss_damping, p%nfev, p%open, &
                        1.0_dp - p%open - p%stick, p%normal_max
                else
                    write (u, fmt, iostat=stat, iomsg=msg, advance='no') p%parameter, &
                        p%amplitude(sel), p%dissipation, &
                        p%rmax, p%stick, p%harmonics, p%residual, trim(p%status), &
                        p%floquet_max, p%stable, p%truncation, p%arclength, p%diss_friction, &
                        p%diss_damping, p%nfev
                end if
                call p%vibration(half_range, first, samples)
                if (stat == 0) write (u, '(2(",",' // real_fmt // '))', iostat=stat, &
                                      iomsg=msg, advance='no') p%omega, p%omega/two_pi
                if (stat == 0 .and. n > 0) write (u, vfmt, iostat=stat, iomsg=msg, &
                                                  advance='no') half_range(sel), first(sel)
                if (stat == 0 .and. present(curve)) write (u, '(",",i0,",",' // real_fmt // &
                                                           ')', iostat=stat, iomsg=msg, &
                                                           advance='no') curve(k), &
                    family_value(k)
                ! the point's own verdict: 1 unless a check distrusts it, and that check
                if (stat == 0) write (u, '(",",i0,",",a)', iostat=stat, iomsg=msg) &
                    merge(0, 1, p%check_level >= level_untrusted), trim(p%check)
            end associate
        end do
        call close_and_rename(dir, "frc.csv", u, stat, msg, error)
    end subroutine write_frc_csv

    !> Write `dir`/frc_harmonics.csv, the Fourier coefficients of every point of the
    !> forced-response curve (frc.csv's rows, numbered 1.. in the column point): header
    !> point,parameter,omega,harmonic,kind, then x<d> for the DOFs of frc.csv's amp_<d>
    !> columns [m], the force channels r<j> (r<j>_2, normal<j> with contact laws) [N] and
    !> the displacements along them u<j> (u<j>_2, un<j>) [m]; one row per basis function
    !> of the point, kind c0, cos or sin: q(t) = c0 + sum_h a_h cos(h omega t) + b_h
    !> sin(h omega t). Points without coefficients (none in a curve of this version) are
    !> skipped. Error: stat io.
    subroutine write_frc_harmonics_csv(dir, res, error, dofs, labels, contacts)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The curve.
        type(sweep_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs written (columns of the points' xcoef, as frc.csv's); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (default: `dofs`).
        integer, intent(in), optional :: labels(:)
        !> The contacts' channel layout (absent: one tangential channel per contact).
        type(contact_set_t), intent(in), optional :: contacts
        if (res%npoints == 0) then
            call write_harmonics_csv(dir, "frc_harmonics.csv", "parameter", [frc_point_t ::], &
                                     error, dofs, labels, contacts)
        else
            call write_harmonics_csv(dir, "frc_harmonics.csv", "parameter", &
                                     res%points(1:res%npoints), error, dofs, labels, contacts)
        end if
    end subroutine write_frc_harmonics_csv

    !> Write `dir`/`name`: the Fourier coefficients of `points` (frc_harmonics.csv,
    !> modes_harmonics.csv), header point,<parameter_name>,omega,harmonic,kind,x<d>..,
    !> r<j>..,u<j>.. (see write_frc_harmonics_csv). Error: stat io.
    subroutine write_harmonics_csv(dir, name, parameter_name, points, error, dofs, labels, &
                                   contacts)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> File name, and the title of the second column (the points' parameter).
        character(len=*), intent(in) :: name, parameter_name
        !> The points.
        type(frc_point_t), intent(in) :: points(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs written (columns of the points' xcoef, as frc.csv's); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (default: `dofs`).
        integer, intent(in), optional :: labels(:)
        !> The contacts' channel layout (absent: one tangential channel per contact).
        type(contact_set_t), intent(in), optional :: contacts
        integer :: u, k, i, m, stat, n, nch
        character(len=512) :: msg
        character(len=:), allocatable :: header, kind
        character(len=80) :: fmt
        integer, allocatable :: sel(:), numbers(:), channel(:), gap_of(:)
        character(len=16), allocatable :: rnames(:)
        stat = 0
        msg = ''
        n = 0
        nch = 0
        do k = 1, size(points)
            if (.not. allocated(points(k)%xcoef)) cycle
            n = size(points(k)%xcoef, 2)
            nch = size(points(k)%rcoef, 2)
            exit
        end do
        if (present(dofs)) then
            sel = dofs
        else
            sel = selection(n)
        end if
        numbers = column_numbers(sel, labels)
        call contact_columns(nch, rnames, channel, gap_of, contacts)
        rnames = pack(rnames, channel > 0)
        channel = pack(channel, channel > 0)
        header = "point,"//parameter_name//",omega,harmonic,kind"
        header = header//columns("x", numbers)
        do i = 1, size(channel)
            header = header//","//trim(rnames(i))
        end do
        do i = 1, size(channel)
            if (rnames(i)(1:1) == 'n') then
                header = header//",un"//trim(rnames(i)(7:))
            else
                header = header//",u"//trim(rnames(i)(2:))
            end if
        end do
        write (fmt, '(a,i0,a)') '(i0,",",2(' // real_fmt // ',","),i0,",",a,",",', &
            size(sel) + 2*size(channel), '(' // real_fmt // ',:,","))'
        call open_temporary(dir, name, u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, size(points)
            associate (p => points(k))
                if (.not. allocated(p%xcoef)) cycle
                do m = 1, size(p%harmonic)
                    if (stat /= 0) exit
                    kind = basis_kind(p%harmonic, m)
                    write (u, fmt, iostat=stat, iomsg=msg) k, p%parameter, p%omega, &
                        p%harmonic(m), kind, p%xcoef(m, sel), &
                        summed(p%rcoef(m, :), channel, contacts), p%ucoef(m, channel)
                end do
            end associate
            if (stat /= 0) exit
        end do
        call close_and_rename(dir, name, u, stat, msg, error)
    end subroutine write_harmonics_csv

    !> Write `dir`/modes.csv, one row per point of a backbone (nonlinear modal analysis):
    !> amplitude (modal amplitude a [m sqrt(kg)]), omega [rad/s], frequency [Hz], xi
    !> (negative modal damping [1/s]), damping_ratio (D = xi / (2 omega)), amp_<d> (max_t
    !> |x_d| [m] of the DOFs selected, as frc.csv's), dissipation, diss_friction,
    !> diss_viscous [J per cycle], energy_error (|input - dissipation| / input),
    !> rmax_1..rmax_C [N], stick_1..stick_C, harmonics, residual, status, nfev; with contact
    !> laws then open_1..open_C, slip_1..slip_C, normal_max_1..normal_max_C; then trusted,
    !> check, omega_error (relative) and damping_error (of D) as estimated against half the
    !> harmonics (NaN when not estimated); with backbones of a disk's sector last
    !> nodal_diameter (points with mode_point_t%nodal_diameter >= 0). Error: stat io.
    subroutine write_modes_csv(dir, res, error, dofs, labels)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The backbone.
        type(modes_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs written (each in 1..N); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (default: the DOF numbers).
        integer, intent(in), optional :: labels(:)
        integer :: u, k, i, stat, n, nc
        character(len=512) :: msg
        character(len=:), allocatable :: header
        logical :: laws, diameters
        integer, allocatable :: sel(:), numbers(:)
        stat = 0
        msg = ''
        n = 0
        nc = 0
        laws = .false.
        if (res%npoints > 0) then
            n = size(res%points(1)%p%amplitude)
            nc = size(res%points(1)%p%rmax)
            laws = allocated(res%points(1)%p%open)
        end if
        if (present(dofs)) then
            sel = dofs
        else
            sel = selection(n)
        end if
        numbers = column_numbers(sel, labels)
        header = "amplitude,omega,frequency,xi,damping_ratio"//columns("amp_", numbers)// &
                 ",dissipation,diss_friction,diss_viscous,energy_error"// &
                 columns("rmax_", [(i, i=1, nc)])//columns("stick_", [(i, i=1, nc)])// &
                 ",harmonics,residual,status,nfev"
        if (laws) header = header//law_columns(nc)
        header = header//",trusted,check,omega_error,damping_error"
        ! backbones of several nodal diameters of a sector
        diameters = .false.
        if (res%npoints > 0) diameters = any(res%points(1:res%npoints)%nodal_diameter >= 0)
        if (diameters) header = header//",nodal_diameter"
        call open_temporary(dir, "modes.csv", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) header
        do k = 1, res%npoints
            if (stat /= 0) exit
            associate (m => res%points(k), p => res%points(k)%p)
                write (u, '(*(' // real_fmt // ',:,","))', iostat=stat, iomsg=msg, &
                    advance='no') p%parameter, p%omega, p%omega/two_pi, m%xi, &
                    m%damping_ratio, p%amplitude(sel), p%dissipation, p%diss_friction, &
                    p%diss_damping, m%energy_error, p%rmax, p%stick
                if (stat == 0) write (u, '(",",i0,",",' // real_fmt // ',",",a,",",i0)', &
                                      iostat=stat, iomsg=msg, advance='no') p%harmonics, &
                    p%residual, trim(p%status), p%nfev
                if (stat == 0 .and. laws) write (u, '(*(:,",",' // real_fmt // '))', &
                                                 iostat=stat, iomsg=msg, advance='no') &
                    p%open, 1.0_dp - p%open - p%stick, p%normal_max
                if (stat == 0) write (u, '(",",i0,",",a,2(",",' // real_fmt // '))', &
                                      iostat=stat, iomsg=msg, advance='no') &
                    merge(0, 1, p%check_level >= level_untrusted), trim(p%check), &
                    m%omega_error, m%damping_error
                if (stat == 0 .and. diameters) write (u, '(",",i0)', iostat=stat, iomsg=msg, &
                                                      advance='no') m%nodal_diameter
                if (stat == 0) write (u, '()', iostat=stat, iomsg=msg)
            end associate
        end do
        call close_and_rename(dir, "modes.csv", u, stat, msg, error)
    end subroutine write_modes_csv

    !> Write `dir`/modes_harmonics.csv: the shape of the mode at every point of the
    !> backbone, as Fourier coefficients (the format of frc_harmonics.csv, second column
    !> `amplitude`, the modal amplitude of the point: row `point` of modes.csv). Error: stat
    !> io.
    subroutine write_modes_harmonics_csv(dir, res, error, dofs, labels, contacts)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The backbone.
        type(modes_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs written (columns of the points' xcoef); absent: all.
        integer, intent(in), optional :: dofs(:)
        !> Column numbers of the selected DOFs (default: `dofs`).
        integer, intent(in), optional :: labels(:)
        !> The contacts' channel layout.
        type(contact_set_t), intent(in), optional :: contacts
        type(frc_point_t), allocatable :: points(:)
        integer :: k
        allocate (points(res%npoints))
        do k = 1, res%npoints
            points(k) = res%points(k)%p
        end do
        call write_harmonics_csv(dir, "modes_harmonics.csv", "amplitude", points, error, dofs, &
                                 labels, contacts)
    end subroutine write_modes_harmonics_csv

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

    !> The text of `value` written with real_fmt (es25.17e3), byte for byte: what
    !> `write (s, '(es25.17e3)') value` gives with gfortran, about 15 times faster. The 18
    !> significant digits are those of the exact binary value rounded to nearest: the value
    !> is scaled by 10^(17 - E) in double-double arithmetic (relative error below 1e-30,
    !> about 1e-13 of the last digit) and the last digit rounded from the remainder. Zero,
    !> infinities, NaN and the rare values whose remainder lies within 1e-9 of a half (ties
    !> among them) or whose decimal exponent the scaled value cannot settle are written by
    !> the compiler's own edit descriptor, so the text is always the same. Checked against
    !> it over millions of random bit patterns and the edge values (test_csv_format).
    pure function format_real(value) result(s)
        !> Any double.
        real(dp), intent(in) :: value
        character(len=real_width) :: s
        real(dp), parameter :: split = 134217729.0_dp   ! 2^27 + 1 (Veltkamp)
        integer(int64), parameter :: n_upper = 1000000000000000000_int64
        integer(int64), parameter :: n_lower = 100000000000000000_int64
        integer(int64), parameter :: mantissa_bits = 4503599627370495_int64   ! 2^52 - 1
        integer(int64), parameter :: half_bits = 4602678819172646912_int64    ! bits of 0.5
        real(dp) :: a, fa, p, err, ahi, alo, bhi, blo, t, xh, xl, fl, frac, two_sc
        integer(int64) :: n, bits
        integer :: e10, q, i, ae, ea, sc, two, tries, biased

        a = abs(value)
        if (.not. (a > 0.0_dp .and. a <= huge(a))) then
            write (s, '(' // real_fmt // ')') value
            return
        end if
        ! a = fa 2^ea with fa in [0.5, 1), from the bits (exponent/fraction for subnormals)
        bits = transfer(a, bits)
        biased = int(ishft(bits, -52))
        if (biased > 0) then
            ea = biased - 1022
            fa = transfer(ior(iand(bits, mantissa_bits), half_bits), fa)
        else
            ea = exponent(a)
            fa = fraction(a)
        end if
        e10 = floor(real(ea - 1, dp)*0.30102999566398120_dp)
        t = split*fa
        ahi = t - (t - fa)
        alo = fa - ahi
        ! x = a 10^(17 - E) = xh + xl, in [1e17, 1e18) when E is the decimal exponent
        do tries = 1, 3
            q = 17 - e10
            p = fa*pow_hi(q)
            t = split*pow_hi(q)
            bhi = t - (t - pow_hi(q))
            blo = pow_hi(q) - bhi
            err = ((ahi*bhi - p) + ahi*blo + alo*bhi) + alo*blo   ! fa*pow_hi - p, exactly
            t = err + fa*pow_lo(q)
            ! times 2^sc (sc about 57 .. 63: the double 2^sc built from its bits), exactly
            sc = ea + pow_e(q)
            two_sc = transfer(ishft(int(sc + 1023, int64), 52), two_sc)
            xh = p*two_sc           ! an integer (>= 2^53)
            if (xh >= 2.0e18_dp) then   ! E estimated one low: x up to 1e19, beyond int64
                e10 = e10 + 1
                cycle
            end if
            xl = t*two_sc           ! |xl| <= about 1.5 ulp(xh)
            fl = floor(xl)
            n = int(xh, int64) + int(fl, int64)     ! floor(x)
            if (n < n_lower) then
                e10 = e10 - 1
            else if (n >= n_upper) then
                e10 = e10 + 1
            else
                exit
            end if
        end do
        if (tries > 3) then
            write (s, '(' // real_fmt // ')') value
            return
        end if
        frac = xl - fl
        if (abs(frac - 0.5_dp) < 1.0e-9_dp) then
            write (s, '(' // real_fmt // ')') value
            return
        end if
        if (frac > 0.5_dp) n = n + 1
        if (n == n_upper) then          ! rounded up to 10^18: 1.000.. E(E+1)
            n = n_lower
            e10 = e10 + 1
        end if
        ! the 18 digits d1 d2 .. d18 of n: s(2) = d1, s(3) = '.', s(4:20) = d2 .. d18
        do i = 20, 6, -2
            two = 2*int(mod(n, 100_int64))
            n = n/100
            s(i - 1:i) = digit_pairs(two + 1:two + 2)
        end do
        two = 2*int(n)
        s(2:2) = digit_pairs(two + 1:two + 1)
        s(3:3) = '.'
        s(4:4) = digit_pairs(two + 2:two + 2)
        if (value < 0.0_dp) then
            s(1:1) = '-'
        else
            s(1:1) = ' '
        end if
        s(21:21) = 'E'
        if (e10 < 0) then
            s(22:22) = '-'
        else
            s(22:22) = '+'
        end if
        ae = abs(e10)
        s(23:23) = achar(iachar('0') + ae/100)
        two = 2*mod(ae, 100)
        s(24:25) = digit_pairs(two + 1:two + 2)
    end function format_real

    !> The contact-law columns of frc.csv and modes.csv for `nc` contacts: open_1..,
    !> slip_1.., normal_max_1.. (each after a comma).
    pure function law_columns(nc) result(text)
        integer, intent(in) :: nc
        character(len=:), allocatable :: text
        integer :: i
        text = columns("open_", [(i, i=1, nc)])//columns("slip_", [(i, i=1, nc)])// &
               columns("normal_max_", [(i, i=1, nc)])
    end function law_columns

    !> The header columns prefix<k> for each k of `numbers`, each after a comma:
    !> columns("amp_", [7, 781]) = ",amp_7,amp_781".
    pure function columns(prefix, numbers) result(text)
        character(len=*), intent(in) :: prefix
        integer, intent(in) :: numbers(:)
        character(len=:), allocatable :: text
        integer :: i
        text = ""
        do i = 1, size(numbers)
            text = text//","//prefix//itoa(numbers(i))
        end do
    end function columns

    !> The kind of basis function k of a basis whose harmonic numbers are `harmonic`:
    !> 'c0' (the constant), 'cos' (the first of a harmonic) or 'sin' (the second).
    pure function basis_kind(harmonic, k) result(kind)
        integer, intent(in) :: harmonic(:), k
        character(len=:), allocatable :: kind
        kind = "cos"
        if (harmonic(k) == 0) then
            kind = "c0"
        else if (k > 1) then
            if (harmonic(k - 1) == harmonic(k)) kind = "sin"
        end if
    end function basis_kind

    !> The numbers naming the columns of the DOFs `sel`: `labels` when present, else `sel`.
    pure function column_numbers(sel, labels) result(numbers)
        integer, intent(in) :: sel(:)
        integer, intent(in), optional :: labels(:)
        integer, allocatable :: numbers(:)
        if (present(labels)) then
            numbers = labels
        else
            numbers = sel
        end if
    end function column_numbers

    !> The DOFs selected: `dofs` when present, otherwise 1..n.
    pure function selection(n, dofs) result(sel)
        !> Number of DOFs.
        integer, intent(in) :: n
        !> The selection (each in 1..n).
        integer, intent(in), optional :: dofs(:)
        integer, allocatable :: sel(:), numbers(:)
        integer :: i
        if (present(dofs)) then
            sel = dofs
        else
            sel = [(i, i=1, n)]
        end if
    end function selection

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
    !> The contact columns of the sample files for `nr` force columns: r1..r<nr> (channel
    !> k for column k) without `contacts` or for a plain contact set; with contact laws,
    !> r<j> (each contact's first tangential channel), then r<j>_2 (the second tangential
    !> channel of each planar contact), normal<j> (the normal force channel of each
    !> unilateral contact) and gap<j> (its gap: channel 0, gap_of = j).
    subroutine contact_columns(nr, names, channel, gap_of, contacts)
        !> Force columns of the result (channels).
        integer, intent(in) :: nr
        !> Column names.
        character(len=16), allocatable, intent(out) :: names(:)
        !> The channel of each column (0 for a gap column).
        integer, allocatable, intent(out) :: channel(:), gap_of(:)
        !> The contacts' channel layout.
        type(contact_set_t), intent(in), optional :: contacts
        integer :: j, k
        logical :: laws
        laws = .false.
        if (present(contacts)) laws = .not. contacts%coulomb_only .and. contacts%nchannel == nr
        if (.not. laws) then
            allocate (names(nr), channel(nr), gap_of(nr))
            do k = 1, nr
                names(k) = "r"//itoa(k)
                channel(k) = k
            end do
            gap_of = 0
            return
        end if
        associate (cs => contacts)
            allocate (names(0), channel(0), gap_of(0))
            do j = 1, cs%ncontact
                call add("r"//itoa(j), first_along(j, along_tangent), 0)
            end do
            do j = 1, cs%ncontact
                if (cs%ntangent(j) == 2) call add("r"//itoa(j)//"_2", &
                                                  first_along(j, along_tangent2), 0)
            end do
            do j = 1, cs%ncontact
                if (cs%normal(j) > 0) call add("normal"//itoa(j), cs%normal(j), 0)
            end do
            do j = 1, cs%ncontact
                if (cs%normal(j) > 0) call add("gap"//itoa(j), 0, j)
            end do
        end associate
    contains
        !> The first channel of contact j along `along`.
        integer function first_along(j, along) result(c)
            integer, intent(in) :: j, along
            do c = contacts%first(j), contacts%first(j) + contacts%width(j) - 1
                if (contacts%along(c) == along) return
            end do
            c = contacts%first(j)
        end function first_along

        subroutine add(name, c, g)
            character(len=*), intent(in) :: name
            integer, intent(in) :: c, g
            character(len=16) :: word
            word = name
            names = [character(len=16) :: names, word]
            channel = [channel, c]
            gap_of = [gap_of, g]
        end subroutine add
    end subroutine contact_columns


    !> The values of the force columns `channel` (contact_columns' primary channels) from one
    !> row of channel values: each column the sum over its contact's channels along the same
    !> direction (the sliders of a microslip element add up), or the value itself without
    !> `contacts`.
    pure function summed(row, channel, contacts) result(v)
        !> Channel values (forces or their coefficients).
        real(dp), intent(in) :: row(:)
        !> The columns' primary channels.
        integer, intent(in) :: channel(:)
        !> The contacts' channel layout.
        type(contact_set_t), intent(in), optional :: contacts
        real(dp) :: v(size(channel))
        integer :: i, c, j
        do i = 1, size(channel)
            v(i) = row(channel(i))
            if (.not. present(contacts)) cycle
            if (contacts%nchannel /= size(row)) cycle
            j = contacts%contact_of(channel(i))
            if (contacts%width(j) == 1) cycle
            v(i) = 0.0_dp
            do c = contacts%first(j), contacts%first(j) + contacts%width(j) - 1
                if (contacts%along(c) == contacts%along(channel(i))) v(i) = v(i) + row(c)
            end do
        end do
    end function summed
end module stickslip_csv
