!> Drawing the pictures: gnuplot is started directly (fork, chdir into the output
!> directory, execvp with a fixed argument vector, waitpid), never through a shell, so no
!> text of a case file (the directory name above all) is ever parsed as a command. gnuplot
!> gets `-e "suffix='.tmp'" SCRIPT`: the script writes its PNGs under temporary names, and
!> rename_pictures renames the complete ones. gnuplot's own output goes to /dev/null. Part
!> of the program (app/): the library never starts a process.
module stickslip_gnuplot
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_ptr, c_null_char, c_null_ptr, &
        c_loc
    implicit none
    private
    public :: run_gnuplot, rename_pictures

    interface
        function c_fork() bind(c, name='fork') result(pid)
            import :: c_int
            integer(c_int) :: pid
        end function c_fork

        function c_execvp(file, argv) bind(c, name='execvp') result(stat)
            import :: c_char, c_int, c_ptr
            character(kind=c_char), intent(in) :: file(*)
            type(c_ptr), intent(in) :: argv(*)
            integer(c_int) :: stat
        end function c_execvp

        function c_chdir(path) bind(c, name='chdir') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: stat
        end function c_chdir

        ! open(2) is variadic; called with two arguments (no O_CREAT), as C callers do
        function c_open(path, flags) bind(c, name='open') result(fd)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: flags
            integer(c_int) :: fd
        end function c_open

        function c_dup2(old, new) bind(c, name='dup2') result(fd)
            import :: c_int
            integer(c_int), value :: old, new
            integer(c_int) :: fd
        end function c_dup2

        subroutine c_exit(status) bind(c, name='_exit')
            import :: c_int
            integer(c_int), value :: status
        end subroutine c_exit

        function c_waitpid(pid, status, options) bind(c, name='waitpid') result(r)
            import :: c_int
            integer(c_int), value :: pid
            integer(c_int), intent(out) :: status
            integer(c_int), value :: options
            integer(c_int) :: r
        end function c_waitpid

        function c_rename(old, new) bind(c, name='rename') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: old(*), new(*)
            integer(c_int) :: stat
        end function c_rename
    end interface

    !> O_WRONLY of open(2) (Linux, the BSDs and macOS).
    integer(c_int), parameter :: o_wronly = 1

contains

    !> Run `gnuplot -e "suffix='.tmp'" <script>` in `directory` and wait for it. Returns
    !> gnuplot's exit status: 0 when it drew the pictures, 127 when it could not be started
    !> (not installed), 126 when the directory cannot be entered, -1 when no process could
    !> be created or waited for, 128 + n when it was killed by signal n.
    integer function run_gnuplot(directory, script) result(status)
        !> The output directory (any characters: it is never parsed).
        character(len=*), intent(in) :: directory
        !> The script's file name in `directory` (e.g. frc.gp).
        character(len=*), intent(in) :: script
        character(kind=c_char), allocatable, target :: dir(:), program(:), option(:), &
            suffix(:), file(:)
        type(c_ptr) :: argv(5)
        integer(c_int) :: pid, wstatus, r, fd
        integer :: tries
        call to_c(directory, dir)
        call to_c("gnuplot", program)
        call to_c("-e", option)
        call to_c("suffix='.tmp'", suffix)
        call to_c(script, file)
        argv = [c_loc(program), c_loc(option), c_loc(suffix), c_loc(file), c_null_ptr]
        pid = c_fork()
        if (pid < 0) then
            status = -1
            return
        end if
        if (pid == 0) then
            ! the child: only async-signal-safe C calls from here on
            if (c_chdir(dir) /= 0) call c_exit(126_c_int)
            fd = c_open("/dev/null"//c_null_char, o_wronly)
            if (fd >= 0) then
                r = c_dup2(fd, 1_c_int)
                r = c_dup2(fd, 2_c_int)
            end if
            r = c_execvp(program, argv)
            call c_exit(127_c_int)
        end if
        status = -1
        do tries = 1, 1000
            r = c_waitpid(pid, wstatus, 0_c_int)
            if (r == pid) exit
            if (r < 0 .and. tries > 100) return
        end do
        if (r /= pid) return
        if (iand(wstatus, 127) == 0) then
            status = iand(ishft(wstatus, -8), 255)
        else
            status = 128 + iand(wstatus, 127)
        end if
    end function run_gnuplot

    !> Rename `directory/<png>.tmp` to `directory/<png>` for each of `pngs` that gnuplot
    !> wrote (a missing one is skipped: robustness_warm.png without warm starts).
    subroutine rename_pictures(directory, pngs)
        !> The output directory.
        character(len=*), intent(in) :: directory
        !> The pictures' names.
        character(len=*), intent(in) :: pngs(:)
        integer :: k
        integer(c_int) :: r
        logical :: exists
        do k = 1, size(pngs)
            inquire (file=directory//'/'//trim(pngs(k))//'.tmp', exist=exists)
            if (.not. exists) cycle
            r = c_rename(directory//'/'//trim(pngs(k))//'.tmp'//c_null_char, &
                         directory//'/'//trim(pngs(k))//c_null_char)
        end do
    end subroutine rename_pictures

    !> `s` as a NUL-terminated C string.
    subroutine to_c(s, c)
        character(len=*), intent(in) :: s
        character(kind=c_char), allocatable, intent(out) :: c(:)
        integer :: i
        allocate (c(len(s) + 1))
        do i = 1, len(s)
            c(i) = s(i:i)
        end do
        c(len(s) + 1) = c_null_char
    end subroutine to_c
end module stickslip_gnuplot
