!> Results written completely or not at all when the disk refuses bytes: gfortran reports
!> neither a full file system nor a file size limit on write or close (it drops the bytes),
!> so close_and_rename compares the size it wrote with the size on disk. Simulated here by a
!> file size limit (setrlimit RLIMIT_FSIZE, soft limit lowered and restored, SIGXFSZ
!> ignored as the program does): the writer returns an io error naming the file, the
!> temporary is removed and the old file kept whole.
module test_file_faults
    use, intrinsic :: iso_c_binding, only: c_int, c_long, c_funptr, c_intptr_t, c_char, &
        c_null_char
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_files, only: make_directory, directory_lock_t, acquire_lock, release_lock, &
        lock_name, remove_file
    use stickslip_matrix_market, only: read_matrix_market
    use stickslip_sparse, only: sparse_matrix_t
    use stickslip_case, only: case_t, read_case
    use stickslip_checkpoint, only: case_fingerprint
    use stickslip_csv, only: write_samples_csv
    use fixtures, only: enter_project_root, scratch, first_line, write_lines, good_system, &
        good_forcing, good_friction, file_text
    use test_cli, only: cli
    use testing, only: test_counter_t, check
    implicit none
    private
    public :: run_file_faults_tests

    !> An error holder for calls whose failure the checks see otherwise.
    type(error_type), allocatable :: error_holder

    !> struct rlimit of Linux (rlim_t is unsigned long).
    type, bind(c) :: rlimit_t
        integer(c_long) :: cur, max
    end type rlimit_t

    integer(c_int), parameter :: rlimit_fsize = 1, sigxfsz = 25

    interface
        function c_getrlimit(resource, rlim) bind(c, name='getrlimit') result(stat)
            import :: c_int, rlimit_t
            integer(c_int), value :: resource
            type(rlimit_t), intent(out) :: rlim
            integer(c_int) :: stat
        end function c_getrlimit
        function c_setrlimit(resource, rlim) bind(c, name='setrlimit') result(stat)
            import :: c_int, rlimit_t
            integer(c_int), value :: resource
            type(rlimit_t), intent(in) :: rlim
            integer(c_int) :: stat
        end function c_setrlimit
        function c_mkfifo(path, mode) bind(c, name='mkfifo') result(stat)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: mode
            integer(c_int) :: stat
        end function c_mkfifo
        function c_signal(sig, handler) bind(c, name='signal') result(old)
            import :: c_int, c_funptr
            integer(c_int), value :: sig
            type(c_funptr), value :: handler
            type(c_funptr) :: old
        end function c_signal
    end interface

contains

    subroutine run_file_faults_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()
        call test_size_limit(t)
        call test_long_directory(t)
        call test_result_set(t)
        call test_special_files(t)
    end subroutine run_file_faults_tests

    !> Files that are not what they should be (issue 24): a named pipe as a Matrix Market
    !> file or as the directory lock would block the open forever (these checks would hang
    !> without the fix); an empty lock (a full disk) is a damaged one, taken over; a lock
    !> that cannot be written whole (a file size limit of 0, as a full disk) is an io error
    !> that leaves no lock; the case's fingerprint under a file size limit is an io error,
    !> not another fingerprint (a checkpoint refused as "another case").
    subroutine test_special_files(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/file_faults_special"
        type(sparse_matrix_t) :: a
        type(directory_lock_t) :: lock
        type(case_t) :: c
        type(rlimit_t) :: saved, small
        type(c_funptr) :: old_handler, ignore
        type(error_type), allocatable :: error
        character(len=16) :: fp
        integer :: stat
        logical :: exists
        call make_directory(dir, error)
        if (allocated(error)) return
        ! a pipe as a Matrix Market file
        call remove_file(dir//"/k.mtx")
        stat = c_mkfifo(dir//"/k.mtx"//c_null_char, int(o'600', c_int))
        call check(t, stat == 0, "file_faults: a pipe made")
        call read_matrix_market(dir//"/k.mtx", a, error)
        call check(t, allocated(error), "file_faults: a pipe as a Matrix Market file refused")
        if (allocated(error)) call check(t, index(error%message, dir//"/k.mtx") > 0 .and. &
                                         index(error%message, "not a regular file") > 0, &
                                         "file_faults: the pipe named", error%message)
        ! a pipe as the lock: taken over as damaged
        call remove_file(dir//"/"//lock_name)
        stat = c_mkfifo(dir//"/"//lock_name//c_null_char, int(o'600', c_int))
        call acquire_lock(lock, dir, error)
        call check(t, .not. allocated(error) .and. lock%held, &
                   "file_faults: a pipe as the lock taken over")
        call release_lock(lock)
        ! an empty lock (left by a full disk): taken over
        call write_lines(dir//"/"//lock_name, [character(len=1) ::])
        call acquire_lock(lock, dir, error)
        call check(t, .not. allocated(error) .and. lock%held, &
                   "file_faults: an empty lock taken over")
        if (lock%held) call check(t, first_line(dir//"/"//lock_name) /= "", &
                                  "file_faults: the lock holds a pid")
        call release_lock(lock)
        if (c_getrlimit(rlimit_fsize, saved) /= 0) then
            call check(t, .false., "file_faults: getrlimit")
            return
        end if
        ! a lock that cannot be written: an io error, no lock and no temporary left
        small = saved
        small%cur = 0
        ignore = transfer(1_c_intptr_t, ignore)
        old_handler = c_signal(sigxfsz, ignore)
        stat = c_setrlimit(rlimit_fsize, small)
        call acquire_lock(lock, dir, error)
        stat = c_setrlimit(rlimit_fsize, saved)
        old_handler = c_signal(sigxfsz, old_handler)
        call check(t, allocated(error) .and. .not. lock%held, &
                   "file_faults: a lock that cannot be written is an error")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%io .and. &
                                         index(error%message, "cannot write the directory "// &
                                               "lock") > 0, "file_faults: the lock's message", &
                                         error%message)
        inquire (file=dir//"/"//lock_name, exist=exists)
        call check(t, .not. exists, "file_faults: no empty lock left")
        ! the fingerprint under a file size limit below the case's echo
        call read_case("examples/seed.nml", c, error)
        if (allocated(error)) return
        fp = case_fingerprint(c, error)
        call check(t, .not. allocated(error) .and. len_trim(fp) == 16, &
                   "file_faults: a fingerprint")
        small%cur = 512
        old_handler = c_signal(sigxfsz, ignore)
        stat = c_setrlimit(rlimit_fsize, small)
        fp = case_fingerprint(c, error)
        stat = c_setrlimit(rlimit_fsize, saved)
        old_handler = c_signal(sigxfsz, old_handler)
        call check(t, allocated(error) .and. len_trim(fp) == 0, &
                   "file_faults: the fingerprint under a size limit is an error")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%io .and. &
                                         index(error%message, "size limit") > 0, &
                                         "file_faults: the fingerprint's message", error%message)
    end subroutine test_special_files

    !> The result files are replaced as a set: a run that cannot write its files (a file
    !> size limit, as a full disk) leaves the old set whole, summary included, and exits 3;
    !> a run killed before its files were moved into place (its staging directory left, its
    !> process gone) leaves the old set whole too, and the next run clears its staging.
    subroutine test_result_set(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/file_faults_set"
        character(len=*), parameter :: nml = scratch//"/file_faults_set.nml"
        character(len=:), allocatable :: out, err, old_summary, old_hbm
        type(rlimit_t) :: saved, small
        type(c_funptr) :: old_handler, ignore
        integer :: code, stat
        logical :: exists
        ! the three methods side by side: hbm.csv (~20 kB), coefficients.csv, euler.csv
        ! (~1.5 MB), reference.csv, events.csv, summary.nml, written in that order
        call write_lines(nml, [character(len=120) :: good_system, good_forcing, good_friction, &
            "&hbm harmonics = 10, samples = 128 /", "&euler steps_per_period = 10000 /", &
            "&run method = 'all' /", "&output directory = '"//dir//"' /"])
        call cli([character(len=200) :: nml], code, out, err)
        call check(t, code == 0, "file_faults: the old set written", err)
        old_summary = file_text(dir//"/summary.nml")
        old_hbm = file_text(dir//"/hbm.csv")
        ! another H: a new hbm.csv; under a 100 kB limit euler.csv cannot be written, after
        ! hbm.csv and coefficients.csv were
        call write_lines(nml, [character(len=120) :: good_system, good_forcing, good_friction, &
            "&hbm harmonics = 12, samples = 128 /", "&euler steps_per_period = 10000 /", &
            "&run method = 'all' /", "&output directory = '"//dir//"' /"])
        stat = c_getrlimit(rlimit_fsize, saved)
        small = saved
        small%cur = 100000
        ignore = transfer(1_c_intptr_t, ignore)
        old_handler = c_signal(sigxfsz, ignore)
        stat = c_setrlimit(rlimit_fsize, small)
        call cli([character(len=200) :: nml], code, out, err)
        stat = c_setrlimit(rlimit_fsize, saved)
        old_handler = c_signal(sigxfsz, old_handler)
        call check(t, code == 3 .and. index(err, dir//"/euler.csv: write failed") > 0 .and. &
                   index(err, "staging") == 0, &
                   "file_faults: a run that cannot write its files exits 3 naming the file", err)
        call check(t, file_text(dir//"/summary.nml") == old_summary .and. &
                   file_text(dir//"/hbm.csv") == old_hbm, &
                   "file_faults: the old set is kept whole, hbm.csv and summary included "// &
                   "(not a new hbm.csv beside the old summary)")
        ! a run killed while writing: its staging directory and lock are left, its process
        ! is gone (pid 999999999)
        call make_directory(dir//"/.stickslip.staging.999999999", error_holder)
        call write_lines(dir//"/.stickslip.staging.999999999/hbm.csv", &
                         [character(len=8) :: "t,x1"])
        call write_lines(dir//"/.stickslip.lock", [character(len=24) :: "999999999 5"])
        call check(t, file_text(dir//"/summary.nml") == old_summary .and. &
                   file_text(dir//"/hbm.csv") == old_hbm, &
                   "file_faults: a run killed before its commit leaves the old set")
        call cli([character(len=200) :: nml], code, out, err)
        inquire (file=dir//"/.stickslip.staging.999999999/.", exist=exists)
        call check(t, code == 0 .and. .not. exists .and. file_text(dir//"/hbm.csv") /= old_hbm, &
                   "file_faults: the next run clears the killed run's staging and commits", err)
    end subroutine test_result_set


    !> An output directory whose path is too long to create (ENAMETOOLONG deep down): an
    !> io error, and none of the nested directories made on the way is left behind.
    subroutine test_long_directory(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: path
        type(error_type), allocatable :: error
        logical :: exists
        integer :: k
        path = scratch//"/long_top"
        do k = 1, 40
            path = path//"/"//repeat("d", 200)
        end do
        call make_directory(path, error)
        call check(t, allocated(error), "file_faults: a path too long to create fails")
        if (allocated(error)) call check(t, error%stat == stickslip_stat%io, &
                                         "file_faults: too long a path is an io error")
        inquire (file=scratch//"/long_top/.", exist=exists)
        call check(t, .not. exists, "file_faults: no nested directories left behind")
    end subroutine test_long_directory

    !> A file size limit below the file's size: io error, no temporary, the old file kept.
    subroutine test_size_limit(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: dir = scratch//"/file_faults"
        type(error_type), allocatable :: error
        type(rlimit_t) :: saved, small
        type(c_funptr) :: old_handler, ignore
        real(dp) :: tt(400), x(400, 2), v(400, 2), r(400, 1)
        integer :: k, stat
        character(len=:), allocatable :: head
        call make_directory(dir, error)
        call check(t, .not. allocated(error), "file_faults: scratch directory")
        if (allocated(error)) return
        do k = 1, 400
            tt(k) = k
        end do
        x = 1.0_dp
        v = 2.0_dp
        r = 3.0_dp
        ! a complete old file
        call write_samples_csv(dir, "samples.csv", tt(1:2), x(1:2, :), v(1:2, :), r(1:2, :), &
                               error)
        call check(t, .not. allocated(error), "file_faults: the old file written")
        if (c_getrlimit(rlimit_fsize, saved) /= 0) then
            call check(t, .false., "file_faults: getrlimit")
            return
        end if
        small = saved
        small%cur = 8192
        ignore = transfer(1_c_intptr_t, ignore)
        old_handler = c_signal(sigxfsz, ignore)
        stat = c_setrlimit(rlimit_fsize, small)
        call write_samples_csv(dir, "samples.csv", tt, x, v, r, error)
        stat = c_setrlimit(rlimit_fsize, saved)
        old_handler = c_signal(sigxfsz, old_handler)
        call check(t, allocated(error), "file_faults: a write beyond the size limit fails")
        if (.not. allocated(error)) return
        call check(t, error%stat == stickslip_stat%io .and. &
                   index(error%message, "samples.csv: write failed") > 0 .and. &
                   index(error%message, "the file on disk holds") > 0, &
                   "file_faults: one io error naming the file", error%message)
        ! the old file is kept whole, no temporary is left
        head = first_line(dir//"/samples.csv")
        call check(t, head == "t,x1,x2,v1,v2,r1", "file_faults: the old file kept", head)
        call check(t, .not. any_temporary(dir), "file_faults: no temporary left")
    end subroutine test_size_limit

    !> A temporary samples.csv.*.tmp is left in `dir`.
    logical function any_temporary(dir)
        character(len=*), intent(in) :: dir
        integer :: k, pid
        logical :: exists
        any_temporary = .false.
        pid = getpid()
        do k = 1, 5
            inquire (file=dir//"/samples.csv."//itoa(pid)//"."//itoa(k)//".tmp", exist=exists)
            any_temporary = any_temporary .or. exists
        end do
    contains
        pure function itoa(i) result(s)
            integer, intent(in) :: i
            character(len=:), allocatable :: s
            character(len=12) :: buf
            write (buf, '(i0)') i
            s = trim(buf)
        end function itoa
    end function any_temporary
end module test_file_faults
