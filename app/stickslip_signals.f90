!> Signal dispositions of the stickslip program (not of the library, which never touches a
!> process-wide setting behind its host's back).
!>
!> SIGXFSZ: a file size limit (`ulimit -f`) kills a process with SIGXFSZ at the write that
!> crosses it, and gfortran's handler prints a backtrace. Ignored, the write fails with EFBIG
!> instead; the output files then see a short file and report it (stickslip_files,
!> close_and_rename: exit 3, one message, the temporary removed, the old file kept).
module stickslip_signals
    use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_intptr_t
    implicit none
    private
    public :: ignore_file_size_signal

    !> SIGXFSZ on Linux (x86_64, aarch64, ...).
    integer(c_int), parameter :: sigxfsz = 25

    interface
        function c_signal(sig, handler) bind(c, name='signal') result(old)
            import :: c_int, c_funptr
            integer(c_int), value :: sig
            type(c_funptr), value :: handler
            type(c_funptr) :: old
        end function c_signal
    end interface

contains

    !> Ignore SIGXFSZ (SIG_IGN), so that a file size limit makes writes fail instead of
    !> killing the program.
    subroutine ignore_file_size_signal()
        type(c_funptr) :: old
        ! SIG_IGN is the handler value 1
        old = c_signal(sigxfsz, transfer(1_c_intptr_t, old))
    end subroutine ignore_file_size_signal
end module stickslip_signals
