!> The stickslip program restarted with OpenBLAS kernels that match the CPU.
!>
!> OpenBLAS chooses its kernels when the process loads it, and runs its generic 'Prescott'
!> kernels on a CPU it does not recognise (Debian 12's OpenBLAS 0.3.21 on Intel
!> Sapphire/Emerald Rapids: dgemm 3-4 times slower, the Rotor 37 blade's reduction 1.6 times
!> slower). The environment variable OPENBLAS_CORETYPE names the kernels instead, but only
!> for a new process: `restart_for_blas` sets it to what `blas_core_advice` says and executes
!> the same program with the same arguments (execvp: no shell, the arguments passed as they
!> came). It does nothing when there is nothing to fix, when the user set OPENBLAS_CORETYPE
!> (OPENBLAS_CORETYPE=Prescott keeps the generic kernels), or when the program's own name is
!> unknown; when execvp fails it returns and the run goes on with the kernels it has.
module stickslip_blas_restart
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_ptr, c_null_char, c_null_ptr, c_loc
    use stickslip_blas_threads, only: blas_core_advice
    implicit none
    private
    public :: restart_for_blas

    interface
        !> int setenv(const char *name, const char *value, int overwrite)
        function c_setenv(name, value, overwrite) bind(c, name='setenv')
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: name(*), value(*)
            integer(c_int), value :: overwrite
            integer(c_int) :: c_setenv
        end function c_setenv
        !> int execvp(const char *file, char *const argv[]): returns only on failure
        function c_execvp(file, argv) bind(c, name='execvp')
            import :: c_char, c_int, c_ptr
            character(kind=c_char), intent(in) :: file(*)
            type(c_ptr), intent(in) :: argv(*)
            integer(c_int) :: c_execvp
        end function c_execvp
    end interface

contains

    !> If the linked OpenBLAS runs generic kernels on a CPU that has better ones (see
    !> blas_core_advice), set OPENBLAS_CORETYPE and execute this program again with the same
    !> arguments; the new process finds the variable set and goes on. Call it first thing in
    !> the main program, before any output or file is opened. Returns when there is nothing
    !> to do or the restart failed (the run then goes on here). No errors.
    subroutine restart_for_blas()
        character(len=:), allocatable :: core
        character(kind=c_char), allocatable, target :: chars(:)
        type(c_ptr), allocatable :: argv(:)
        integer :: nargs, i, k, n, total, start
        integer(c_int) :: stat

        core = blas_core_advice()
        if (len(core) == 0) return
        nargs = command_argument_count()
        total = 0
        do i = 0, nargs
            call get_command_argument(i, length=n)
            if (i == 0 .and. n == 0) return
            total = total + n + 1
        end do
        ! every argument as a C string, one after the other in one buffer
        allocate (chars(total), argv(nargs + 2))
        start = 1
        do i = 0, nargs
            call get_command_argument(i, length=n)
            block
                character(len=n) :: arg
                call get_command_argument(i, arg)
                do k = 1, n
                    chars(start + k - 1) = arg(k:k)
                end do
            end block
            chars(start + n) = c_null_char
            argv(i + 1) = c_loc(chars(start))
            start = start + n + 1
        end do
        argv(nargs + 2) = c_null_ptr
        stat = c_setenv("OPENBLAS_CORETYPE"//c_null_char, core//c_null_char, 1_c_int)
        if (stat /= 0) return
        stat = c_execvp(chars, argv)
    end subroutine restart_for_blas
end module stickslip_blas_restart
