!> Signal dispositions of the stickslip program (not of the library, which never touches a
!> process-wide setting behind its host's back).
!>
!> SIGXFSZ: a file size limit (`ulimit -f`) kills a process with SIGXFSZ at the write that
!> crosses it, and gfortran's handler prints a backtrace. Ignored, the write fails with EFBIG
!> instead; the output files then see a short file and report it (stickslip_files,
!> close_and_rename: exit 3, one message, the temporary removed, the old file kept).
!>
!> SIGINT, SIGTERM, SIGHUP (Ctrl-C, a batch system's kill, a closed terminal): the program
!> removes the directory locks it holds, its temporaries and its staging directory (the
!> result files not yet moved into place) in the output directories it registered, then
!> dies of the signal as it would have (exit status 128 + n). The handler
!> only calls async-signal-safe C functions (open, read, close, unlink, signal, raise) on
!> paths prepared beforehand, when the directory was registered. This is the one place with
!> module state in the program: a signal handler has no other way to know the paths.
module stickslip_signals
    use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_intptr_t, c_char, c_null_char, &
        c_size_t, c_long, c_funloc
    use stickslip_files, only: result_file_names, lock_name, process_id
    implicit none
    private
    public :: ignore_file_size_signal, install_signal_handlers, register_output_directory, &
        remove_own_files

    !> Signal numbers on Linux (x86_64, aarch64, ...).
    integer(c_int), parameter :: sighup = 1, sigint = 2, sigterm = 15, sigxfsz = 25
    !> Most output directories registered, longest path kept.
    integer, parameter :: max_directories = 256, path_length = 1024

    !> NUL-terminated lock paths of the registered directories, and the temporary names
    !> this process may create there (NAME.<pid>.<n>.tmp, n = 1..3).
    character(kind=c_char, len=path_length), allocatable, save :: locks(:), stages(:), &
        temporaries(:)
    integer, save :: nlocks = 0, ntemporaries = 0
    !> This process id, as digits.
    character(len=24), save :: own_pid = ''

    interface
        function c_signal(sig, handler) bind(c, name='signal') result(old)
            import :: c_int, c_funptr
            integer(c_int), value :: sig
            type(c_funptr), value :: handler
            type(c_funptr) :: old
        end function c_signal
        function c_raise(sig) bind(c, name='raise') result(stat)
            import :: c_int
            integer(c_int), value :: sig
            integer(c_int) :: stat
        end function c_raise
        function c_unlink(path) bind(c, name='unlink') result(stat)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: stat
        end function c_unlink
        function c_rmdir(path) bind(c, name='rmdir') result(stat)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: stat
        end function c_rmdir
        function c_open(path, flags) bind(c, name='open') result(fd)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: flags
            integer(c_int) :: fd
        end function c_open
        function c_read(fd, buf, count) bind(c, name='read') result(got)
            import :: c_int, c_char, c_size_t, c_long
            integer(c_int), value :: fd
            character(kind=c_char), intent(out) :: buf(*)
            integer(c_size_t), value :: count
            integer(c_long) :: got
        end function c_read
        function c_close(fd) bind(c, name='close') result(stat)
            import :: c_int
            integer(c_int), value :: fd
            integer(c_int) :: stat
        end function c_close
    end interface

contains

    !> Ignore SIGXFSZ (SIG_IGN), so that a file size limit makes writes fail instead of
    !> killing the program.
    subroutine ignore_file_size_signal()
        type(c_funptr) :: old
        ! SIG_IGN is the handler value 1
        old = c_signal(sigxfsz, transfer(1_c_intptr_t, old))
    end subroutine ignore_file_size_signal

    !> Catch SIGINT, SIGTERM and SIGHUP: remove this run's locks and temporaries in the
    !> registered directories, then die of the signal.
    subroutine install_signal_handlers()
        type(c_funptr) :: old
        old = c_signal(sigint, c_funloc(on_signal))
        old = c_signal(sigterm, c_funloc(on_signal))
        old = c_signal(sighup, c_funloc(on_signal))
    end subroutine install_signal_handlers

    !> Register output directory `dir`: a signal then removes this process's lock and
    !> temporaries there. Idempotent; directories beyond max_directories or with paths
    !> longer than path_length are not registered (their lock is left for the next run to
    !> take over, as after a SIGKILL).
    subroutine register_output_directory(dir)
        !> The output directory.
        character(len=*), intent(in) :: dir
        character(kind=c_char, len=path_length) :: lock
        character(len=:), allocatable :: stage
        !$omp critical (stickslip_signal_registry)
        if (.not. allocated(locks)) then
            allocate (locks(max_directories), stages(max_directories), temporaries(0))
            write (own_pid, '(i0)') process_id()
        end if
        stage = dir//'/.stickslip.staging.'//trim(own_pid)
        if (len(stage) + 64 < path_length .and. nlocks < max_directories) then
            lock = dir//'/'//lock_name//c_null_char
            if (.not. any(locks(1:nlocks) == lock)) then
                nlocks = nlocks + 1
                locks(nlocks) = lock
                stages(nlocks) = stage//c_null_char
                ! the temporaries of this run in the directory and in its staging directory,
                ! and the result files staged there
                call add_names(dir, .true.)
                call add_names(stage, .true.)
                call add_names(stage, .false.)
            end if
        end if
        !$omp end critical (stickslip_signal_registry)
    contains
        !> Append the result files of `where` (with `temporary`: their temporaries
        !> NAME.<pid>.<n>.tmp, n = 1..3, and those of the checkpoint and the lock).
        subroutine add_names(where, temporary)
            character(len=*), intent(in) :: where
            logical, intent(in) :: temporary
            character(kind=c_char, len=path_length), allocatable :: grown(:)
            character(len=:), allocatable :: stem
            integer :: k, n, m, nnames
            nnames = size(result_file_names)
            if (temporary) nnames = 3*(nnames + 2)
            allocate (grown(ntemporaries + nnames))
            grown(1:ntemporaries) = temporaries(1:ntemporaries)
            m = ntemporaries
            do n = 1, merge(3, 1, temporary)
                do k = 1, size(result_file_names) + merge(2, 0, temporary)
                    if (k <= size(result_file_names)) then
                        stem = trim(result_file_names(k))
                    else if (k == size(result_file_names) + 1) then
                        stem = "frc.checkpoint"
                    else
                        stem = lock_name
                    end if
                    m = m + 1
                    if (temporary) then
                        grown(m) = where//'/'//stem//'.'//trim(own_pid)//'.'//achar(48 + n)// &
                                   '.tmp'//c_null_char
                    else
                        grown(m) = where//'/'//stem//c_null_char
                    end if
                end do
            end do
            call move_alloc(grown, temporaries)
            ntemporaries = m
        end subroutine add_names
    end subroutine register_output_directory

    !> The handler: unlink this process's temporaries and the locks that hold its pid, then
    !> restore the default disposition and raise the signal again.
    subroutine on_signal(sig) bind(c)
        integer(c_int), value :: sig
        integer(c_int) :: r
        type(c_funptr) :: old
        call remove_own_files()
        ! SIG_DFL is the handler value 0
        old = c_signal(sig, transfer(0_c_intptr_t, old))
        r = c_raise(sig)
    end subroutine on_signal

    !> What the handler does before it dies: unlink this process's temporaries in the
    !> registered directories and the locks that hold its pid (async-signal-safe calls only).
    subroutine remove_own_files()
        integer :: k
        integer(c_int) :: r
        do k = 1, ntemporaries
            r = c_unlink(temporaries(k))
        end do
        do k = 1, nlocks
            r = c_rmdir(stages(k))
            if (holds_own_pid(locks(k))) r = c_unlink(locks(k))
        end do
    end subroutine remove_own_files

    !> The lock file `path` (NUL-terminated) starts with this process's id.
    logical function holds_own_pid(path) result(own)
        character(kind=c_char, len=*), intent(in) :: path
        character(kind=c_char) :: buf(32)
        integer(c_int) :: fd, r
        integer(c_long) :: got
        integer :: k, n
        own = .false.
        fd = c_open(path, 0_c_int)
        if (fd < 0) return
        got = c_read(fd, buf, int(size(buf), c_size_t))
        r = c_close(fd)
        n = len_trim(own_pid)
        if (got <= n) return
        do k = 1, n
            if (buf(k) /= own_pid(k:k)) return
        end do
        own = buf(n + 1) == ' ' .or. buf(n + 1) == achar(10)
    end function holds_own_pid
end module stickslip_signals
