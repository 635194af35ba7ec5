!> Cost of a sector's stability (issue 27): the Floquet multipliers of the assembled disk
!> from the exact flow over the whole period, against the flow over T / m by the travelling
!> wave's symmetry (periodic_stability with `symmetry`, m = N / gcd(EO, N)), on the shrouded
!> disk of examples/bladed_disk.nml (3 DOFs a sector, tip shrouds rubbing on the next blade)
!> with 24 sectors in engine orders 1, 2, 3, 48 in 1, 2, 3, 6 and 80 in 1, at the example's omega
!> (an unknown verdict prints its diagnosis). Each stability is repeated R times (default
!> 3) in this process; prints per case the disk's DOFs, m, the median CPU seconds of both,
!> their ratio, the largest multiplier moduli and, where sectors in phase switch at one
!> instant, the growth a period of perturbations followed by the exact flow over T / m
!> (stickslip_orbit_growth: the check of the verdict, part of both CPU times).
!> Usage: fpm run --example bench_wave_stability --profile release [-- R]
program bench_wave_stability
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_case, only: case_t, read_case
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic, disk_solution
    use stickslip_stability, only: floquet_t, periodic_stability
    use stickslip_wave_symmetry, only: wave_symmetry_t, wave_spans
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_sorting, only: sort_ascending
    implicit none
    type(case_t) :: c
    type(model_t) :: disk
    type(hbm_solution_t) :: sec, dsol
    type(hbm_options_t) :: ho
    type(floquet_t) :: f1, f2
    type(error_type), allocatable :: error
    integer, parameter :: sectors(8) = [24, 24, 24, 48, 48, 48, 48, 80]
    integer, parameter :: orders(8) = [1, 2, 3, 1, 2, 3, 6, 1]
    integer :: i, r, repeats, m, u
    real(dp), allocatable :: t_full(:), t_wave(:)
    character(len=32) :: arg

    repeats = 3
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        read (arg, *) repeats
    end if
    allocate (t_full(repeats), t_wave(repeats))
    call read_case("examples/bladed_disk.nml", c, error)
    if (allocated(error)) error stop "bench_wave_stability: run it from the project root"
    ho = c%hbm
    ho%rho = 0.5_dp
    write (*, '(a)') "sectors  EO  disk DOFs   m   full [s]   wave [s]  full/wave  "// &
        "max |mu| full, wave; perturbed flow"
    do i = 1, size(sectors)
        c%cyclic%cyc%sectors = sectors(i)
        c%cyclic%cyc%engine_order = orders(i)
        ho%samples = 48*sectors(i)
        call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
        if (.not. allocated(error)) call disk_solution(c%model, c%cyclic%cyc, ho, sec, &
                                                       disk, dsol, error)
        if (allocated(error)) error stop "bench_wave_stability: the solve failed"
        do r = 1, repeats
            t_full(r) = thread_cpu_seconds()
            call periodic_stability(disk, dsol, c%reference%reference_options_t, f1, error)
            t_full(r) = thread_cpu_seconds() - t_full(r)
            t_wave(r) = thread_cpu_seconds()
            call periodic_stability(disk, dsol, c%reference%reference_options_t, f2, error, &
                                    symmetry=wave_symmetry_t(sectors(i), orders(i)))
            t_wave(r) = thread_cpu_seconds() - t_wave(r)
            if (allocated(error)) error stop "bench_wave_stability: the stability failed"
        end do
        call wave_spans(wave_symmetry_t(sectors(i), orders(i)), m, u)
        write (*, '(i7,i4,i11,i4,2f11.3,f11.1,2x,a,", ",a,"; ",a)') sectors(i), orders(i), &
            disk%ndof, m, median(t_full), median(t_wave), median(t_full)/median(t_wave), &
            modulus(f1), modulus(f2), growth(f2)
        if (f1%verdict == 'unknown') write (*, '(2x,a)') f1%diagnosis
        if (f2%verdict == 'unknown') write (*, '(2x,a)') f2%diagnosis
    end do

contains

    real(dp) function median(a)
        real(dp), intent(in) :: a(:)
        real(dp) :: b(size(a))
        b = a
        call sort_ascending(b)
        median = 0.5_dp*(b((size(b) + 1)/2) + b(size(b)/2 + 1))
    end function median

    !> The perturbed flow's growth a period, or '-' when it was not followed.
    function growth(f) result(s)
        type(floquet_t), intent(in) :: f
        character(len=:), allocatable :: s
        character(len=16) :: buf
        s = '-'
        if (f%flow_growth < 0.0_dp) return
        write (buf, '(f12.8)') f%flow_growth
        s = trim(adjustl(buf))
    end function growth

    !> The largest modulus, or the verdict when unknown.
    function modulus(f) result(s)
        type(floquet_t), intent(in) :: f
        character(len=:), allocatable :: s
        character(len=16) :: buf
        if (f%verdict == 'unknown') then
            s = 'unknown'
        else
            write (buf, '(f12.8)') f%max_modulus
            s = trim(adjustl(buf))
        end if
    end function modulus
end program bench_wave_stability
