!> The stickslip command: `stickslip CASE.nml [CASE.nml ...] [--quiet] [--help] [--version]`.
!> Gathers the arguments, runs them (stickslip_cli, in app/) and exits with the code it
!> returns.
program main
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use stickslip_cli, only: string_t, run_cli
    use stickslip_signals, only: ignore_file_size_signal, install_signal_handlers
    use stickslip_blas_restart, only: restart_for_blas
    implicit none
    type(string_t), allocatable :: args(:)
    integer :: i, n, code

    ! OpenBLAS's kernels for this CPU when it fell back to generic ones (a new process)
    call restart_for_blas()
    call ignore_file_size_signal()
    call install_signal_handlers()
    allocate (args(command_argument_count()))
    do i = 1, size(args)
        call get_command_argument(i, length=n)
        allocate (character(len=n) :: args(i)%s)
        call get_command_argument(i, args(i)%s)
    end do
    code = run_cli(args, output_unit, error_unit)
    if (code /= 0) stop code, quiet=.true.
end program main
