!> Files of an output directory: creating it (mkdir -p), atomic writes (a temporary with a
!> unique name, created exclusively, then renamed over the final name, so a reader sees the
!> complete old file or the complete new one, and two runs never share a temporary), removing
!> the result files of an earlier run that the current run does not write, and the directory
!> lock `.stickslip.lock` that refuses a directory another run is writing.
!> Knows the result file names, nothing of their contents. Talks to the C library (mkdir,
!> rename, link, unlink, getpid, kill, getpgid) through bind(C); never starts a process.
module stickslip_files
    use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    implicit none
    private
    public :: make_directory, open_temporary, close_and_rename, remove_file
    public :: result_file_names, remove_stale_results
    public :: staging_name, begin_staging, commit_staging
    public :: directory_lock_t, acquire_lock, release_lock, lock_name, process_id, &
              process_alive, process_start_time

    !> File name of the directory lock.
    character(len=*), parameter :: lock_name = ".stickslip.lock"

    !> Every result file stickslip writes into an output directory (doc/outputs.md):
    !> the files that a run removes when it does not write them itself. Never the case
    !> file, the sweep checkpoint or anything else.
    character(len=*), parameter :: result_file_names(25) = [character(len=24) :: &
        "hbm.csv", "coefficients.csv", "full_field.mtx", "euler.csv", "reference.csv", "events.csv", &
        "study.csv", "frc.csv", "frc_harmonics.csv", "frc.gp", "frc.png", &
        "frc_dissipation.png", &
        "robustness.csv", "robustness.gp", "robustness_cold.png", "robustness_warm.png", &
        "modes.csv", "modes_harmonics.csv", "modes.gp", "modes.png", &
        "family.csv", "family.gp", "frc_family.png", "family.png", "summary.nml"]

    !> Checkpoints of a family's curves, frc_family_<k>.checkpoint, k = 1 to this (the most
    !> curves a family has, stickslip_sweep_family's max_family_curves).
    integer, parameter :: family_checkpoints = 200

    !> The lock of an output directory, held from acquire_lock to release_lock.
    type :: directory_lock_t
        !> Path of the lock file (unallocated: not held).
        character(len=:), allocatable :: path
        !> Whether this run holds it.
        logical :: held = .false.
    end type directory_lock_t

    interface
        function c_mkdir(path, mode) bind(c, name='mkdir') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: mode
            integer(c_int) :: stat
        end function c_mkdir

        function c_rename(old, new) bind(c, name='rename') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: old(*), new(*)
            integer(c_int) :: stat
        end function c_rename

        function c_link(old, new) bind(c, name='link') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: old(*), new(*)
            integer(c_int) :: stat
        end function c_link

        function c_rmdir(path) bind(c, name='rmdir') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: stat
        end function c_rmdir

        function c_unlink(path) bind(c, name='unlink') result(stat)
            import :: c_char, c_int
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: stat
        end function c_unlink

        function c_getpid() bind(c, name='getpid') result(pid)
            import :: c_int
            integer(c_int) :: pid
        end function c_getpid

        function c_kill(pid, sig) bind(c, name='kill') result(stat)
            import :: c_int
            integer(c_int), value :: pid, sig
            integer(c_int) :: stat
        end function c_kill

        function c_getpgid(pid) bind(c, name='getpgid') result(pgid)
            import :: c_int
            integer(c_int), value :: pid
            integer(c_int) :: pgid
        end function c_getpgid
    end interface

    !> Tries at unique temporary names before giving up.
    integer, parameter :: max_tries = 10000

contains

    !> Create directory `path` and its missing parents (like mkdir -p). Error (stat io) when
    !> a component cannot be created: "cannot create the output directory '<path>': <part>
    !> exists and is not a directory" (or "...: cannot create <part>").
    subroutine make_directory(path, error)
        !> Directory path.
        character(len=*), intent(in) :: path
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: k, stat, ncreated
        integer, allocatable :: created(:)
        logical :: exists
        ! the ends of the components this call creates, to take them back on failure
        allocate (created(count([(path(k:k) == '/', k=1, len(path))]) + 1))
        ncreated = 0
        do k = 1, len(path)
            if (k < len(path) .and. path(k:k) /= '/') cycle
            if (k == 1 .and. path(1:1) == '/') cycle
            if (path(k:k) == '/') then
                if (is_directory(path(1:k - 1))) cycle
                stat = c_mkdir(path(1:k - 1)//c_null_char, int(o'755', c_int))
                if (stat == 0) then
                    ncreated = ncreated + 1
                    created(ncreated) = k - 1
                end if
            else
                if (is_directory(path)) cycle
                stat = c_mkdir(path//c_null_char, int(o'755', c_int))
                if (stat == 0) then
                    ncreated = ncreated + 1
                    created(ncreated) = k
                end if
            end if
        end do
        if (is_directory(path)) return
        ! failed (a component in the way, a name too long, no permission): remove the empty
        ! directories this call made, deepest first, so that nothing is left behind
        do k = ncreated, 1, -1
            stat = c_rmdir(path(1:created(k))//c_null_char)
        end do
        ! say which component is in the way
        do k = 1, len(path)
            if (k < len(path) .and. path(k:k) /= '/') cycle
            if (k == 1 .and. path(1:1) == '/') cycle
            if (path(k:k) == '/') then
                if (is_directory(path(1:k - 1))) cycle
                inquire (file=path(1:k - 1), exist=exists)
                if (exists) then
                    call fatal_error(error, "cannot create the output directory '"//path// &
                                     "': '"//path(1:k - 1)//"' exists and is not a directory", &
                                     stickslip_stat%io)
                else
                    call fatal_error(error, "cannot create the output directory '"//path// &
                                     "': cannot create '"//path(1:k - 1)//"'", stickslip_stat%io)
                end if
                return
            end if
        end do
        inquire (file=path, exist=exists)
        if (exists) then
            call fatal_error(error, "cannot create the output directory '"//path//"': it "// &
                             "exists and is not a directory", stickslip_stat%io)
        else
            call fatal_error(error, "cannot create the output directory '"//path//"' "// &
                             "(permission denied, read-only file system or name too long)", &
                             stickslip_stat%io)
        end if
    end subroutine make_directory

    logical function is_directory(path)
        character(len=*), intent(in) :: path
        inquire (file=path//'/.', exist=is_directory)
    end function is_directory

    !> The process id of this program.
    integer function process_id() result(pid)
        pid = int(c_getpid())
    end function process_id

    !> Whether a process with id `pid` exists (kill(pid, 0) succeeds, or getpgid finds it
    !> when it belongs to another user). False for pid <= 0.
    logical function process_alive(pid) result(alive)
        !> A process id.
        integer, intent(in) :: pid
        alive = .false.
        if (pid <= 0) return
        alive = c_kill(int(pid, c_int), 0_c_int) == 0
        if (.not. alive) alive = c_getpgid(int(pid, c_int)) >= 0
    end function process_alive

    !> Open a new temporary file for `dir/name` for writing: `dir/name.<pid>.<n>.tmp`,
    !> created exclusively (O_CREAT|O_EXCL) with the first free n, so that two runs (or two
    !> writers in one run) never write the same temporary. Finish with close_and_rename.
    !> Error: stat io. With `binary` true the unit is an unformatted stream.
    subroutine open_temporary(dir, name, unit, error, binary)
        !> Directory (must exist).
        character(len=*), intent(in) :: dir
        !> Final file name.
        character(len=*), intent(in) :: name
        !> The unit opened.
        integer, intent(out) :: unit
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Open an unformatted stream (default: formatted sequential).
        logical, intent(in), optional :: binary
        integer :: stat, k
        character(len=512) :: msg
        character(len=:), allocatable :: stem
        logical :: exists, stream
        stream = .false.
        if (present(binary)) stream = binary
        stem = dir//'/'//name//'.'//itoa(process_id())//'.'
        do k = 1, max_tries
            if (stream) then
                open (newunit=unit, file=stem//itoa(k)//'.tmp', status='new', action='write', &
                      access='stream', form='unformatted', iostat=stat, iomsg=msg)
            else
                open (newunit=unit, file=stem//itoa(k)//'.tmp', status='new', action='write', &
                      iostat=stat, iomsg=msg)
            end if
            if (stat == 0) return
            inquire (file=stem//itoa(k)//'.tmp', exist=exists)
            if (.not. exists) exit
        end do
        call fatal_error(error, dir//'/'//name//": cannot open a temporary file for writing: "// &
                         trim(msg), stickslip_stat%io)
    end subroutine open_temporary

    !> Close `unit` (opened by open_temporary) and rename its temporary to `dir/name`; when
    !> stat_write /= 0 (a write failed) delete the temporary instead. Error: stat io.
    subroutine close_and_rename(dir, name, unit, stat_write, msg_write, error)
        !> Directory.
        character(len=*), intent(in) :: dir
        !> Final file name.
        character(len=*), intent(in) :: name
        !> The unit of the temporary.
        integer, intent(in) :: unit
        !> iostat of the writes (0: all written).
        integer, intent(in) :: stat_write
        !> iomsg of the failed write.
        character(len=*), intent(in) :: msg_write
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: stat
        integer(int64) :: logical_size, disk_size
        character(len=512) :: msg
        character(len=4096) :: temporary
        if (stat_write /= 0) then
            close (unit, status='delete', iostat=stat)
            call fatal_error(error, dir//'/'//name//": write failed: "//trim(msg_write), &
                             stickslip_stat%io)
            return
        end if
        inquire (unit=unit, name=temporary)
        ! gfortran reports neither a full file system (ENOSPC) nor a file size limit (EFBIG)
        ! on write, flush or close: it drops the bytes. Compare the size it believes it
        ! wrote with the size of the file on disk.
        flush (unit, iostat=stat)
        logical_size = -1
        if (stat == 0) inquire (unit=unit, size=logical_size, iostat=stat)
        close (unit, iostat=stat, iomsg=msg)
        if (stat /= 0) then
            stat = c_unlink(trim(temporary)//c_null_char)
            call fatal_error(error, dir//'/'//name//": close failed: "//trim(msg), &
                             stickslip_stat%io)
            return
        end if
        disk_size = -2
        inquire (file=trim(temporary), size=disk_size, iostat=stat)
        if (logical_size < 0 .or. disk_size /= logical_size) then
            stat = c_unlink(trim(temporary)//c_null_char)
            call fatal_error(error, dir//'/'//name//": write failed: "// &
                             itoa(logical_size)//" bytes were written and the file on disk "// &
                             "holds "//itoa(disk_size)//" (the file system is full, or a file "// &
                             "size limit was reached); the old file, if any, is kept", &
                             stickslip_stat%io)
            return
        end if
        if (c_rename(trim(temporary)//c_null_char, dir//'/'//name//c_null_char) /= 0) then
            stat = c_unlink(trim(temporary)//c_null_char)
            call fatal_error(error, dir//'/'//name//": cannot rename the temporary file", &
                             stickslip_stat%io)
        end if
    end subroutine close_and_rename

    !> Delete file `path` if it exists (nothing happens otherwise).
    subroutine remove_file(path)
        !> The file.
        character(len=*), intent(in) :: path
        integer :: stat
        stat = c_unlink(path//c_null_char)
    end subroutine remove_file

    !> Remove from `dir` every result file of result_file_names (and the temporaries of
    !> pictures) that is not in `keep`: the files of an earlier run that would otherwise
    !> lie beside this run's summary. Other files, and frc.checkpoint, are never touched.
    subroutine remove_stale_results(dir, keep)
        !> Output directory.
        character(len=*), intent(in) :: dir
        !> The result files this run writes.
        character(len=*), intent(in) :: keep(:)
        integer :: k
        do k = 1, size(result_file_names)
            if (any(keep == result_file_names(k))) cycle
            call remove_file(dir//'/'//trim(result_file_names(k)))
        end do
        call remove_picture_temporaries(dir)
    end subroutine remove_stale_results

    !> Remove the temporaries of the pictures (<name>.png.tmp, drawn by gnuplot) from `dir`.
    subroutine remove_picture_temporaries(dir)
        !> The directory.
        character(len=*), intent(in) :: dir
        integer :: k
        do k = 1, size(result_file_names)
            if (index(result_file_names(k), '.png') > 0) &
                call remove_file(dir//'/'//trim(result_file_names(k))//'.tmp')
        end do
    end subroutine remove_picture_temporaries

    !> The staging directory of this process in output directory `dir`:
    !> `dir/.stickslip.staging.<pid>`. A run writes its whole set of result files there and
    !> commit_staging moves them into `dir` together.
    function staging_name(dir) result(path)
        !> Output directory.
        character(len=*), intent(in) :: dir
        character(len=:), allocatable :: path
        path = dir//'/.stickslip.staging.'//itoa(process_id())
    end function staging_name

    !> Create the (empty) staging directory of this process in `dir` (which must exist and
    !> be locked by this run). Error: stat io.
    subroutine begin_staging(dir, error)
        !> Output directory.
        character(len=*), intent(in) :: dir
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        call clear_staging(staging_name(dir))
        call make_directory(staging_name(dir), error)
    end subroutine begin_staging

    !> Replace the set of result files of `dir` by the set a run wrote into its staging
    !> directory, then remove the staging directory. With a summary.nml staged (the run has
    !> results): the old summary.nml is removed first, every staged file is renamed into
    !> `dir`, the result files of the old set that are not in the new one are removed, and
    !> the new summary.nml is renamed last, so that a summary always stands beside its own
    !> files (a run killed before this step leaves the old set whole; during it, a few
    !> renames, leaves no summary). Without a staged summary: a run that failed with stat
    !> `failed_stat` numerical (no result) removes the old set, as its results would
    !> otherwise pass for this run's; an input or io failure (a full disk) keeps it.
    !> Error: stat io when a rename fails.
    subroutine commit_staging(dir, failed_stat, error)
        !> Output directory.
        character(len=*), intent(in) :: dir
        !> The run's error status (0: none).
        integer, intent(in) :: failed_stat
        !> Set when a staged file cannot be moved.
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: stage
        logical :: staged(size(result_file_names)), has_summary
        integer :: k, isummary
        stage = staging_name(dir)
        isummary = findloc(result_file_names, "summary.nml", 1)
        do k = 1, size(result_file_names)
            inquire (file=stage//'/'//trim(result_file_names(k)), exist=staged(k))
        end do
        has_summary = staged(isummary)
        if (has_summary) then
            call remove_file(dir//'/summary.nml')
            do k = 1, size(result_file_names)
                if (k == isummary .or. .not. staged(k)) cycle
                call move(trim(result_file_names(k)))
                if (allocated(error)) exit
            end do
            if (.not. allocated(error)) then
                call remove_stale_results(dir, pack(result_file_names, staged))
                call move("summary.nml")
            end if
        else if (failed_stat == stickslip_stat%numerical) then
            call remove_stale_results(dir, [character(len=24) ::])
        end if
        call clear_staging(stage)
    contains
        subroutine move(name)
            character(len=*), intent(in) :: name
            if (c_rename(stage//'/'//name//c_null_char, dir//'/'//name//c_null_char) /= 0) &
                call fatal_error(error, dir//'/'//name//": cannot move the new result file "// &
                                 "into place", stickslip_stat%io)
        end subroutine move
    end subroutine commit_staging

    !> Remove a staging directory: the result files and this process's (or a killed
    !> run's) temporaries in it, then the directory (nothing happens when it is absent).
    subroutine clear_staging(stage)
        character(len=*), intent(in) :: stage
        integer :: k, stat, pid, n
        logical :: exists
        inquire (file=stage//'/.', exist=exists)
        if (.not. exists) return
        do k = 1, size(result_file_names)
            call remove_file(stage//'/'//trim(result_file_names(k)))
        end do
        call remove_picture_temporaries(stage)
        ! the temporaries of the run that made it (its pid ends the directory's name)
        k = index(stage, '.', back=.true.)
        read (stage(k + 1:), *, iostat=stat) pid
        if (stat == 0) then
            do n = 1, 3
                do k = 1, size(result_file_names)
                    call remove_file(stage//'/'//trim(result_file_names(k))//'.'//itoa(pid)// &
                                     '.'//itoa(n)//'.tmp')
                end do
            end do
        end if
        stat = c_rmdir(stage//c_null_char)
    end subroutine clear_staging

    !> Take the lock of output directory `dir` (which must exist): create `dir/.stickslip.lock`
    !> holding this process id, atomically (written under a unique name, then hard-linked to
    !> the lock name, which fails when the lock exists). A lock whose process is gone (a
    !> killed run) is taken over. Error (stat io) "directory X is being written by another
    !> stickslip run (pid N)" when a live process holds it, or when it cannot be created.
    !> Taking over a stale lock also removes the temporaries its run left.
    subroutine acquire_lock(lock, dir, error)
        !> The lock, held on return without error.
        type(directory_lock_t), intent(inout) :: lock
        !> Output directory.
        character(len=*), intent(in) :: dir
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, attempt, owner, close_stat
        integer(int64) :: started, written, on_disk
        character(len=512) :: msg
        character(len=4096) :: temporary
        lock%path = dir//'/'//lock_name
        lock%held = .false.
        owner = -1
        call open_temporary(dir, lock_name, u, error)
        if (allocated(error)) return
        ! the process id and its start time: a pid is reused, the pair is not
        write (u, '(i0,1x,i0)', iostat=stat, iomsg=msg) process_id(), &
            process_start_time(process_id())
        inquire (unit=u, name=temporary)
        ! written whole or not taken: an empty lock (a full disk) would hold nobody's pid
        if (stat == 0) then
            flush (u, iostat=stat, iomsg=msg)
            written = -1
            if (stat == 0) inquire (unit=u, size=written, iostat=stat)
        end if
        close (u, iostat=close_stat)
        on_disk = -2
        if (stat == 0 .and. close_stat == 0) inquire (file=trim(temporary), size=on_disk, &
                                                      iostat=stat)
        if (stat /= 0 .or. close_stat /= 0 .or. written <= 0 .or. on_disk /= written) then
            stat = c_unlink(trim(temporary)//c_null_char)
            call fatal_error(error, lock%path//": cannot write the directory lock (the "// &
                             "file system is full, or a file size limit was reached)", &
                             stickslip_stat%io)
            return
        end if
        do attempt = 1, 3
            if (c_link(trim(temporary)//c_null_char, lock%path//c_null_char) == 0) then
                lock%held = .true.
                exit
            end if
            owner = lock_owner(lock%path, started)
            if (owner == -2) cycle
            ! held: its process lives and is the one that wrote the lock (same start time;
            ! a lock without one, or whose pid now names another process, is stale)
            if (process_alive(owner) .and. started >= 0) then
                if (process_start_time(owner) == started) exit
            end if
            ! a stale lock (its process is gone, or the file is damaged): take it over, with
            ! the temporaries the killed run left
            if (owner > 0 .and. owner /= process_id()) then
                call remove_temporaries(dir, owner)
                call clear_staging(dir//'/.stickslip.staging.'//itoa(owner))
            end if
            call remove_file(lock%path)
        end do
        stat = c_unlink(trim(temporary)//c_null_char)
        if (lock%held) return
        if (owner > 0) then
            call fatal_error(error, "directory "//dir//" is being written by another "// &
                             "stickslip run (pid "//itoa(owner)//"); if no such run is "// &
                             "going on, delete "//lock%path, stickslip_stat%io)
        else
            call fatal_error(error, lock%path//": cannot create the directory lock", &
                             stickslip_stat%io)
        end if
    end subroutine acquire_lock

    !> Remove the temporaries that a run with process id `pid` (killed) left in `dir`: the
    !> first names open_temporary tries for every result file, the checkpoint and the lock.
    subroutine remove_temporaries(dir, pid)
        character(len=*), intent(in) :: dir
        integer, intent(in) :: pid
        integer :: k, n
        do n = 1, 3
            do k = 1, size(result_file_names)
                call remove_file(dir//'/'//trim(result_file_names(k))//'.'//itoa(pid)//'.'// &
                                 itoa(n)//'.tmp')
            end do
            call remove_file(dir//'/frc.checkpoint.'//itoa(pid)//'.'//itoa(n)//'.tmp')
            do k = 1, family_checkpoints
                call remove_file(dir//'/frc_family_'//itoa(k)//'.checkpoint.'//itoa(pid)// &
                                 '.'//itoa(n)//'.tmp')
            end do
            call remove_file(dir//'/'//lock_name//'.'//itoa(pid)//'.'//itoa(n)//'.tmp')
        end do
    end subroutine remove_temporaries

    !> Process id held by the lock file: -2 when the file does not exist, -1 when it cannot
    !> be read as a process id; `started` the start time it records (-1 when none).
    integer function lock_owner(path, started) result(pid)
        character(len=*), intent(in) :: path
        integer(int64), intent(out), optional :: started
        integer :: u, stat
        integer(int64) :: t0, bytes
        logical :: exists
        character(len=64) :: line
        pid = -2
        if (present(started)) started = -1
        inquire (file=path, exist=exists)
        if (.not. exists) return
        pid = -1
        ! an empty file or one that is not a regular file (a pipe would block the open, a
        ! device be read forever; both report size 0) is a damaged lock: never opened
        inquire (file=path, size=bytes, iostat=stat)
        if (stat /= 0 .or. bytes <= 0) return
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        read (u, '(a)', iostat=stat) line
        close (u)
        if (stat /= 0) return
        read (line, *, iostat=stat) pid
        if (stat /= 0) then
            pid = -1
            return
        end if
        t0 = -1
        read (line, *, iostat=stat) pid, t0
        if (stat /= 0) t0 = -1
        if (present(started)) started = t0
    end function lock_owner

    !> Start time of process `pid` in clock ticks after boot (field 22 of /proc/<pid>/stat):
    !> with the pid, it names one process (a pid is reused, the pair is not). 0 where /proc
    !> does not tell (another system), -2 when the process does not exist.
    function process_start_time(pid) result(started)
        !> A process id.
        integer, intent(in) :: pid
        integer(int64) :: started
        integer :: u, stat, k, field
        character(len=1024) :: line
        started = 0
        open (newunit=u, file="/proc/"//itoa(pid)//"/stat", status='old', action='read', &
              iostat=stat)
        if (stat /= 0) then
            if (.not. process_alive(pid)) started = -2
            return
        end if
        read (u, '(a)', iostat=stat) line
        close (u)
        if (stat /= 0) return
        ! fields after the command name, which is in parentheses and may hold blanks
        k = index(line, ')', back=.true.)
        if (k == 0) return
        field = 2
        do while (field < 22)
            k = k + 1
            if (k > len_trim(line)) return
            if (line(k:k) == ' ') then
                field = field + 1
                do while (k < len(line))
                    if (line(k + 1:k + 1) /= ' ') exit
                    k = k + 1
                end do
            end if
        end do
        read (line(k + 1:), *, iostat=stat) started
        if (stat /= 0) started = 0
    end function process_start_time

    !> Give the lock back: remove the lock file when this run holds it. Safe to call when
    !> the lock is not held.
    subroutine release_lock(lock)
        !> The lock.
        type(directory_lock_t), intent(inout) :: lock
        if (.not. lock%held) return
        if (lock_owner(lock%path) == process_id()) call remove_file(lock%path)
        lock%held = .false.
    end subroutine release_lock
end module stickslip_files
