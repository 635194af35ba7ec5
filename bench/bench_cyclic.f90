!> Convergence of the sector's travelling wave against the exact event-driven periodic orbit
!> of the assembled disk (issue 27): examples/bladed_disk.nml (24 sectors, tip shrouds rubbing
!> on the next blade, EO 3). The disk's exact reference is started from the disk's weighted
!> residual at H = 30; then, on its samples:
!>   - the weighted residual on one sector at H = 5 .. 160 (at least 50 samples a period of
!>     the highest harmonic): the largest error of sector 0's displacements over the period,
!>     relative to their amplitude;
!>   - implicit Euler on the disk at 256 .. 4096 steps a period: the same error (first order).
!> Prints the two tables and the reference's own checks.
!> Usage: fpm run --example bench_cyclic --profile release
program bench_cyclic
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_case, only: case_t, read_case
    use stickslip_cyclic, only: assemble_disk, disk_dof
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    implicit none
    type(case_t) :: c
    type(model_t) :: disk
    type(error_type), allocatable :: error
    type(hbm_options_t) :: ho
    type(hbm_solution_t) :: sol
    type(reference_options_t) :: ro
    type(reference_result_t) :: ref
    type(euler_options_t) :: eo
    type(euler_result_t) :: eul
    real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
    integer, parameter :: hs(6) = [5, 10, 20, 40, 80, 160], steps(5) = [256, 512, 1024, 2048, 4096]
    integer, allocatable :: cols(:)
    integer :: k, j
    real(dp) :: amp, err, t0, t1

    call read_case("examples/bladed_disk.nml", c, error)
    call stop_on(error)
    call assemble_disk(c%cyclic%sector, c%cyclic%cyc, disk, error)
    call stop_on(error)
    cols = [(disk_dof(c%cyclic%cyc, 4, j, 0), j=1, 4)]
    ! the exact reference on the disk, from its weighted residual
    ho = c%hbm
    ho%harmonics = 30
    ho%samples = 2048
    call solve_periodic(disk, ho, sol, error)
    call stop_on(error)
    ro%samples = 2048
    call cpu_time(t0)
    call solve_reference(disk, ro, sol%x, sol%v, ref, error)
    call stop_on(error)
    call cpu_time(t1)
    write (*, '(a,l1,a,es9.2,a,f7.2,a)') "exact reference on the 72-DOF disk: converged ", &
        ref%converged, ", periodicity defect ", ref%defect, ", ", t1 - t0, " s CPU"

    write (*, '(a)') ""
    write (*, '(a)') "weighted residual on one sector against it (sector 0's DOFs)"
    write (*, '(a)') "    H   samples   max error / amplitude   CPU [ms]"
    call sample_reference(ref, 2048, xr, vr, rr, error)
    call stop_on(error)
    amp = maxval(abs(xr(:, cols)))
    do k = 1, size(hs)
        ho = c%hbm
        ho%harmonics = hs(k)
        ! 50 samples a period of the highest harmonic, at least 2048
        ho%samples = max(2048, 2**ceiling(log(50.0_dp*hs(k))/log(2.0_dp)))
        call sample_reference(ref, ho%samples, xr, vr, rr, error)
        call stop_on(error)
        call solve_periodic_cyclic(c%cyclic%sector, c%cyclic%cyc, ho, sol, error)
        call stop_on(error)
        err = maxval(abs(sol%x(:, 1:4) - xr(:, cols)))/amp
        write (*, '(i5,i10,es24.3,f11.2)') hs(k), ho%samples, err, 1000.0_dp*sol%seconds
    end do

    write (*, '(a)') ""
    write (*, '(a)') "implicit Euler on the disk against it (sector 0's DOFs)"
    write (*, '(a)') " steps/period   max error / amplitude   periods   CPU [s]"
    do k = 1, size(steps)
        eo = c%euler
        eo%steps_per_period = steps(k)
        call integrate_euler(disk, eo, eul, error)
        call stop_on(error)
        call sample_reference(ref, steps(k), xr, vr, rr, error)
        call stop_on(error)
        err = maxval(abs(eul%x(1:steps(k), cols) - xr(:, cols)))/amp
        write (*, '(i13,es24.3,i10,f10.2)') steps(k), err, eul%periods, eul%seconds
    end do

contains

    subroutine stop_on(e)
        type(error_type), allocatable, intent(in) :: e
        if (.not. allocated(e)) return
        write (*, '(a)') "bench_cyclic: "//e%message
        error stop 1
    end subroutine stop_on
end program bench_cyclic
