!> Benchmark of the implicit Euler stepper (a program that prints figures, not a test):
!> steps per second on the seed case (examples/seed.nml) at the paper's setting
!> (h = 1e-4 s, about 2 million steps) and on a 100-DOF chain with 10 contacts.
!> Run from the project root: fpm run --example bench_euler --profile release
program bench_euler
    use, intrinsic :: iso_fortran_env, only: output_unit
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_case, only: case_t, read_case
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    implicit none
    type(case_t) :: c
    type(model_t) :: m
    type(euler_options_t) :: o
    type(euler_result_t) :: res
    type(error_type), allocatable :: error
    integer :: i, n, steps

    call read_case("examples/seed.nml", c, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    o%steps_per_period = nint(two_pi/c%model%omega/1.0e-4_dp)
    o%max_periods = 2000000/o%steps_per_period
    o%tol = 1.0e-15_dp
    call integrate_euler(c%model, o, res, error)
    steps = o%steps_per_period*res%periods
    write (output_unit, '(a,i0,a,i0,a,f0.3,a,es9.2,a)') "seed, h = 1e-4 s: ", steps, &
        " steps (", res%periods, " periods) in ", res%seconds, " s = ", &
        steps/res%seconds, " steps/s"

    ! 100-DOF chain, 10 grounded contacts on every 10th DOF, light damping
    n = 100
    m%ndof = n
    allocate (m%mass(n, n), m%stiffness(n, n))
    m%mass = 0.0_dp
    m%stiffness = 0.0_dp
    do i = 1, n
        m%mass(i, i) = 1.0_dp
        m%stiffness(i, i) = 2.0_dp
        if (i < n) then
            m%stiffness(i, i + 1) = -1.0_dp
            m%stiffness(i + 1, i) = -1.0_dp
        end if
    end do
    m%damping = 0.01_dp*m%stiffness
    m%omega = 0.8_dp
    m%force_dof = [1]
    m%force_harmonic = [1]
    m%force_amplitude = [5.0_dp]
    m%force_phase = [0.0_dp]
    m%contact_dof = [(10*i, i=1, 10)]
    m%contact_dof2 = [(0, i=1, 10)]
    m%mu = [(0.3_dp, i=1, 10)]
    m%normal_load = [(1.0_dp, i=1, 10)]
    o = euler_options_t()
    o%steps_per_period = 1000
    o%max_periods = 50
    o%tol = 1.0e-15_dp
    call integrate_euler(m, o, res, error)
    if (allocated(error)) then
        write (output_unit, '(a)') "error: "//error%message
        stop 1
    end if
    steps = o%steps_per_period*res%periods
    write (output_unit, '(a,i0,a,f0.3,a,es9.2,a,i0)') "100-DOF chain, 10 contacts: ", steps, &
        " steps in ", res%seconds, " s = ", steps/res%seconds, &
        " steps/s; most Gauss-Seidel sweeps in a step: ", res%max_sweeps
end program bench_euler
