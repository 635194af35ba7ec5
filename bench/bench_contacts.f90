!> Benchmark of the weighted residual with contact laws (issue 16; a program that prints
!> figures, not a test): the cost per solve of a varying normal load against the constant
!> load, side by side in one process. Rows: the 2-DOF seed (constant N = 1) against the seed
!> whose contact is unilateral on a normal DOF of its own (preload 1; rigid, and elastic
!> k_n = 20: the load never lifts off, so both solve the same motion); the damper of
!> examples/damper_liftoff.nml (lifts off 69% of the period) against the same damper under
!> the constant load of its preload; the reduced plate of bench_plate with 10 and 40 contacts
!> on its upper edge at H = 15, constant load against unilateral contacts (preload = that
!> load, elastic normal). Each row: median wall time of solve_periodic over repeats (until
!> 1 s and at least 3), residual evaluations, Jacobians, the residual, the open share, and
!> the ratio to its constant-load counterpart.
!> Run (from the project root): fpm run --example bench_contacts --profile release
program bench_contacts
    use, intrinsic :: iso_fortran_env, only: output_unit
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_case, only: case_t, read_case
    use stickslip_study, only: median
    use stickslip_blas_threads, only: limit_blas_threads
    use stickslip_bench_plate, only: reduced_plate, reduced_plate_unilateral
    implicit none
    integer, parameter :: plate_nx = 44, plate_ny = 11
    real(dp), parameter :: plate_omega = 0.3_dp
    type(case_t) :: c
    type(model_t) :: seed, uni, damper, constant, plain_plate, m
    type(error_type), allocatable :: error
    real(dp) :: base, w1, load, kn
    integer :: n, k, nc
    integer, parameter :: plate_contacts(2) = [10, 40]

    call limit_blas_threads()
    write (output_unit, '(a)') "| case | contacts | H | unknowns | median solve [ms] | "// &
        "repeats | nfev | njev | residual | open | ratio |"
    write (output_unit, '(a)') "|---|---|---|---|---|---|---|---|---|---|---|"

    call load_case("examples/seed.nml", seed)
    base = row("seed, constant N = 1", seed, 30, 1024, -1.0_dp)
    uni = unilateral_seed(seed, 0.0_dp)
    base = max(base, 0.0_dp)
    call row_ratio("seed, unilateral rigid (preload 1)", uni, 30, 1024, base)
    uni = unilateral_seed(seed, 20.0_dp)
    call row_ratio("seed, unilateral k_n = 20 (preload 1)", uni, 30, 1024, base)

    call load_case("examples/damper_liftoff.nml", damper)
    constant = damper
    constant%normal_load = damper%preload
    deallocate (constant%normal_direction, constant%preload, constant%normal_stiffness)
    base = row("damper, constant N = preload", constant, 40, 1024, -1.0_dp)
    call row_ratio("damper, lift-off (k_n = 10)", damper, 40, 1024, base)

    do k = 1, size(plate_contacts)
        nc = plate_contacts(k)
        call reduced_plate(plate_nx, plate_ny, nc, 15, plate_omega, plain_plate, w1, n, error)
        call stop_on(error)
        load = plain_plate%normal_load(1)
        ! an elastic normal as stiff as the plate's first mode over the edge's contacts
        kn = 100.0_dp*w1**2/nc
        call reduced_plate_unilateral(plate_nx, plate_ny, nc, 15, plate_omega, kn, load, &
                                      .true., m, w1, n, error)
        call stop_on(error)
        base = row("plate "//itoa(n)//" DOFs reduced, constant N", m, 15, 256, -1.0_dp)
        call reduced_plate_unilateral(plate_nx, plate_ny, nc, 15, plate_omega, kn, load, &
                                      .false., m, w1, n, error)
        call stop_on(error)
        call row_ratio("plate, unilateral k_n = "//rtext(kn), m, 15, 256, base)
    end do

contains

    !> One row; returns the median [s] (ratio printed against `ref` when ref > 0).
    real(dp) function row(name, model, harmonics, samples, ref) result(med)
        character(len=*), intent(in) :: name
        type(model_t), intent(in) :: model
        integer, intent(in) :: harmonics, samples
        real(dp), intent(in) :: ref
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        type(error_type), allocatable :: err
        real(dp) :: times(200), open
        integer :: nrep, i
        character(len=16) :: ratio
        o%harmonics = harmonics
        o%samples = samples
        o%want_samples = .false.
        nrep = 0
        do i = 1, size(times)
            call solve_periodic(model, o, s, err)
            call stop_on(err)
            nrep = i
            times(i) = s%seconds
            if (sum(times(1:i)) > 1.0_dp .and. i >= 3) exit
        end do
        med = median(times(1:nrep))
        open = 0.0_dp
        if (allocated(s%open_fraction)) open = maxval([0.0_dp, s%open_fraction])
        ratio = "1"
        if (ref > 0.0_dp) write (ratio, '(f0.2)') med/ref
        write (output_unit, '("| ",a," | ",i0," | ",i0," | ",i0," | ",f0.3," | ",i0," | ",i0, &
            &" | ",i0," | ",es9.2," | ",f0.3," | ",a," |")') name, model%ncontact(), harmonics, &
            size(s%rcoef), 1.0e3_dp*med, nrep, s%nfev, s%njev, s%fnorm, open, trim(ratio)
        if (.not. s%converged) write (output_unit, '(a)') "  (not converged: "// &
            s%diagnosis//")"
    end function row

    subroutine row_ratio(name, model, harmonics, samples, ref)
        character(len=*), intent(in) :: name
        type(model_t), intent(in) :: model
        integer, intent(in) :: harmonics, samples
        real(dp), intent(in) :: ref
        real(dp) :: med
        med = row(name, model, harmonics, samples, ref)
    end subroutine row_ratio

    !> The seed with its contact unilateral on a normal DOF 3 of its own (mass 1, grounded
    !> spring 5), pressed by a preload of 1 N (normal stiffness kn; 0 rigid).
    function unilateral_seed(s, kn) result(m)
        type(model_t), intent(in) :: s
        real(dp), intent(in) :: kn
        type(model_t) :: m
        m = s
        m%ndof = 3
        m%mass = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1]*1.0_dp, [3, 3])
        m%stiffness = reshape([2, -1, 0, -1, 1, 0, 0, 0, 5]*1.0_dp, [3, 3])
        m%damping = 0.0_dp*m%mass
        m%normal_load = [0.0_dp]
        allocate (m%normal_direction(3, 1))
        m%normal_direction = 0.0_dp
        m%normal_direction(3, 1) = 1.0_dp
        m%preload = [1.0_dp]
        m%normal_stiffness = [kn]
    end function unilateral_seed

    subroutine load_case(path, model)
        character(len=*), intent(in) :: path
        type(model_t), intent(out) :: model
        call read_case(path, c, error)
        call stop_on(error)
        model = c%model
    end subroutine load_case

    subroutine stop_on(err)
        type(error_type), allocatable, intent(in) :: err
        if (.not. allocated(err)) return
        write (output_unit, '(a)') "error: "//err%message
        stop 1
    end subroutine stop_on

    function itoa(i) result(s)
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=20) :: buf
        write (buf, '(i0)') i
        s = trim(buf)
    end function itoa

    function rtext(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=20) :: buf
        write (buf, '(g0.3)') x
        s = trim(buf)
    end function rtext
end program bench_contacts
