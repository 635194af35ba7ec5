!> The README's host program: the seed structure built in memory, solved by the weighted
!> residual, the x2 amplitude printed. Built by `fpm build` ([[example]] host_program) and by
!> .ci/check_install against an installed library with the README's gfortran line.
program host_program
    use stickslip, only: dp, error_type, model_t, hbm_options_t, hbm_solution_t, solve_periodic
    implicit none
    type(model_t) :: model
    type(hbm_options_t) :: opts
    type(hbm_solution_t) :: sol
    type(error_type), allocatable :: error

    model%ndof = 2                                             ! 2 DOF, M = I, K = [2 -1; -1 1]
    model%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
    model%stiffness = reshape([2.0_dp, -1.0_dp, -1.0_dp, 1.0_dp], [2, 2])
    model%damping = 0.0_dp*model%mass
    model%omega = 4.5_dp                                       ! forcing 10 cos(4.5 t) on DOF 1
    model%force_dof = [1]; model%force_harmonic = [1]
    model%force_amplitude = [10.0_dp]; model%force_phase = [0.0_dp]
    model%contact_dof = [2]; model%contact_dof2 = [0]          ! DOF 2 rubs on the ground
    model%mu = [0.45_dp]; model%normal_load = [1.0_dp]
    opts%harmonics = 30; opts%samples = 1024; opts%rho = 0.2_dp

    call solve_periodic(model, opts, sol, error)
    if (allocated(error)) error stop error%message
    if (.not. sol%converged) error stop sol%diagnosis
    print '(a, f10.6)', "x2 amplitude [m]: ", maxval(abs(sol%x(:, 2)))
end program host_program
