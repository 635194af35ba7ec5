!> The exact reference and the stability on the lumped disk with underplatform dampers of
!> examples/bladed_disk_damper.nml (unilateral contacts on elastic normals, lifting off;
!> issue 27), at omega = 2.3 rad/s:
!>   - on 6 sectors in engine order 1 (no two sectors in phase): the disk's exact orbit shot
!>     from the sector's wave (H = 20), then against it the weighted residual on one sector
!>     and on the assembled disk at H = 10, 20, 40 (with the sector's truncation estimate),
!>     and implicit Euler on the disk from rest at 500, 1000, 2000 steps a period (the
!>     largest error of sector 0's displacements over the period / their amplitude);
!>   - on 6 sectors in engine order 3 and the example's 24 sectors in engine order 3
!>     (sectors 2 and 8 apart in phase, switching at one instant): the disk's stability from
!>     the sector's wave (its flow over T / 2 and T / 8) with the growth of perturbations
!>     followed by the exact flow that checks it; on 6 sectors, the flow map's response over
!>     a period to perturbations of 1e-5, 1e-7 and 1e-9 of the amplitude against the
!>     monodromy's (piecewise smooth: a difference that does not shrink with the
!>     perturbation); on 24 sectors, implicit Euler on the disk
!>     started from that wave (1000 steps a period): where it settles, against the wave's
!>     amplitude.
!> Usage: fpm run --example bench_damper_disk --profile release
program bench_damper_disk
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_case, only: case_t, read_case
    use stickslip_cyclic, only: disk_dof
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic, disk_solution
    use stickslip_truncation, only: truncation_t, estimate_truncation
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_stability, only: floquet_t, periodic_stability
    use stickslip_wave_symmetry, only: wave_symmetry_t
    implicit none
    type(case_t) :: c
    type(model_t) :: disk
    type(error_type), allocatable :: error
    type(hbm_options_t) :: ho
    type(hbm_solution_t) :: sec, dsol, full
    type(truncation_t) :: est
    type(reference_options_t) :: ro
    type(reference_result_t) :: ref
    type(euler_options_t) :: eo
    type(euler_result_t) :: eul
    type(floquet_t) :: fl
    real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
    integer, allocatable :: cols(:)
    integer :: j, k, steps, a4
    integer, parameter :: sectors(2) = [6, 24]
    real(dp) :: amp, t0, t1

    call load(6, 1)
    ho = c%hbm
    ho%samples = 1020
    call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
    call stop_on(error)
    call disk_solution(c%model, c%cyclic%cyc, ho, sec, disk, dsol, error)
    call stop_on(error)
    cols = [(disk_dof(c%cyclic%cyc, c%model%ndof, j, 0), j=1, c%model%ndof)]
    ro = c%reference%reference_options_t
    ro%samples = ho%samples
    call cpu_time(t0)
    call solve_reference(disk, ro, dsol%x, dsol%v, ref, error)
    call stop_on(error)
    call cpu_time(t1)
    write (*, '(a,l1,a,es9.2,a,f7.2,a)') "6 sectors, EO 1: exact reference on the 42-DOF "// &
        "disk: converged ", ref%converged, ", periodicity defect ", ref%defect, ", ", &
        t1 - t0, " s CPU"
    write (*, '(a)') ""
    write (*, '(a)') "weighted residual against it (sector 0's DOFs, error / amplitude)"
    write (*, '(a)') "    H   on the sector   on the disk   sector's truncation estimate"
    do k = 1, 3
        ho%harmonics = 10*2**(k - 1)
        ho%samples = 2040
        call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
        call stop_on(error)
        call estimate_truncation(c%model, ho, sec, est, error, cyclic=c%cyclic%cyc)
        call stop_on(error)
        call solve_periodic(disk, ho, full, error)
        call stop_on(error)
        call sample_reference(ref, ho%samples, xr, vr, rr, error)
        call stop_on(error)
        amp = maxval(abs(xr(:, cols)))
        if (est%available) then
            write (*, '(i5,2es16.3,es21.3)') ho%harmonics, maxval(abs(xr(:, cols) - sec%x))/amp, &
                maxval(abs(xr(:, cols) - full%x(:, cols)))/amp, est%estimate
        else
            write (*, '(i5,2es16.3,a21)') ho%harmonics, maxval(abs(xr(:, cols) - sec%x))/amp, &
                maxval(abs(xr(:, cols) - full%x(:, cols)))/amp, "none"
        end if
    end do
    write (*, '(a)') ""
    write (*, '(a)') "implicit Euler on the disk from rest against it"
    write (*, '(a)') " steps/period   error / amplitude   periods   CPU [s]"
    do k = 1, 3
        steps = 500*2**(k - 1)
        eo = c%euler
        eo%steps_per_period = steps
        eo%max_periods = 600
        call integrate_euler(disk, eo, eul, error)
        call stop_on(error)
        call sample_reference(ref, steps, xr, vr, rr, error)
        call stop_on(error)
        write (*, '(i13,es20.3,i10,f10.2)') steps, maxval(abs(eul%x(1:steps, cols) - &
            xr(:, cols)))/maxval(abs(xr(:, cols))), eul%periods, eul%seconds
    end do

    write (*, '(a)') ""
    do k = 1, 2
        call load(sectors(k), 3)
        ho = c%hbm
        call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
        call stop_on(error)
        call disk_solution(c%model, c%cyclic%cyc, ho, sec, disk, dsol, error)
        call stop_on(error)
        call cpu_time(t0)
        call periodic_stability(disk, dsol, c%reference%reference_options_t, fl, error, &
                                symmetry=wave_symmetry_t(sectors(k), 3))
        call stop_on(error)
        call cpu_time(t1)
        write (*, '(i0,a,i0,a,f7.2,a)') sectors(k), " sectors, EO 3 (H = 20): the ", &
            disk%ndof, "-DOF disk's stability from the sector's wave (", t1 - t0, &
            " s CPU): "//fl%verdict//", largest multiplier "//fixed(fl%max_modulus)// &
            ", perturbations followed by the exact flow grow by "//fixed(fl%flow_growth)// &
            " a period"
        if (k == 1) call piecewise_map()
    end do
    write (*, '(a)') "  the diagnosis: "//fl%diagnosis
    a4 = disk_dof(c%cyclic%cyc, c%model%ndof, 4, 0)
    eo = c%euler
    eo%steps_per_period = 1000
    eo%max_periods = 600
    call integrate_euler(disk, eo, eul, error, x0=dsol%x(1, :), v0=dsol%v(1, :))
    call stop_on(error)
    write (*, '(a,l1,a,i0,a,f7.4,a,f7.4)') "implicit Euler (1000 steps a period) from that "// &
        "wave: periodic ", eul%periodic, " after ", eul%periods, " periods, airfoil amplitude ", &
        maxval(abs(eul%x(:, a4))), "; the wave's ", maxval(abs(dsol%x(:, a4)))
    call integrate_euler(disk, eo, eul, error)
    call stop_on(error)
    write (*, '(a,l1,a,i0,a,f7.4)') "implicit Euler from rest: periodic ", eul%periodic, &
        " after ", eul%periods, " periods, airfoil amplitude ", maxval(abs(eul%x(:, a4)))

contains

    !> The example with N sectors forced in engine order eo, at omega = 2.3 rad/s.
    subroutine load(n, order)
        integer, intent(in) :: n, order
        call read_case("examples/bladed_disk_damper.nml", c, error)
        call stop_on(error)
        c%model%omega = 2.3_dp
        c%cyclic%cyc%sectors = n
        c%cyclic%cyc%engine_order = order
    end subroutine load

    !> On the disk of `disk` and `dsol` (6 sectors, EO 3): the exact flow's response over a
    !> period, (P(z + e d) - P(z)) / e, to 3 pseudo-random directions d (each entry of the
    !> size of its amplitude) with both signs, against the monodromy's J d, for e = 1e-5,
    !> 1e-7, 1e-9: the largest relative difference for each e.
    subroutine piecewise_map()
        type(reference_result_t) :: rs
        real(dp), allocatable :: zs(:), z1(:), zp(:), d(:), jd(:), sc(:)
        real(dp) :: e, worst(3)
        integer :: nz, n, i, q, sgn, dirn
        call solve_reference(disk, c%reference%reference_options_t, dsol%x, dsol%v, rs, &
                             error, start_name='hbm', light=.true., r_start=dsol%r, &
                             symmetry=wave_symmetry_t(6, 3))
        call stop_on(error)
        n = disk%ndof
        nz = rs%flow%nz
        zs = rs%orbit%phase_y(1:nz, 1)
        allocate (z1(nz), zp(nz), sc(nz))
        sc(1:n) = maxval(abs(rs%x))
        sc(n + 1:2*n) = maxval(abs(rs%v))
        sc(2*n + 1:) = maxval(abs(rs%x))
        call rs%flow%period_map(rs%t_section, zs, z1, error)
        call stop_on(error)
        worst = 0.0_dp
        do dirn = 1, 3
            d = [(cos(1.7_dp*real(i + 100*dirn, dp)**2), i=1, nz)]*sc
            jd = matmul(rs%monodromy, d)
            do q = 1, 3
                e = 10.0_dp**(-3 - 2*q)
                do sgn = -1, 1, 2
                    call rs%flow%period_map(rs%t_section, zs + sgn*e*d, zp, error)
                    call stop_on(error)
                    worst(q) = max(worst(q), maxval(abs((zp - z1)/(sgn*e) - jd)/sc)/ &
                                   maxval(abs(jd)/sc))
                end do
            end do
        end do
        write (*, '(a,3es10.2)') "  its flow map over a period against its monodromy, "// &
            "perturbations of 1e-5, 1e-7, 1e-9 (3 directions, both signs): largest "// &
            "relative difference", worst
    end subroutine piecewise_map

    !> x with 6 decimals.
    function fixed(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=24) :: buf
        write (buf, '(f12.6)') x
        s = trim(adjustl(buf))
    end function fixed

    subroutine stop_on(e)
        type(error_type), allocatable, intent(in) :: e
        if (.not. allocated(e)) return
        write (*, '(a)') "bench_damper_disk: "//e%message
        error stop 1
    end subroutine stop_on
end program bench_damper_disk
