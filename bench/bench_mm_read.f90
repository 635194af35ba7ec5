!> Benchmark of the Matrix Market reader (a program that prints figures, not a test): reads
!> one file `repeats` times with read_matrix_market and prints the wall time of each read,
!> the median, and the file size over the median [MB/s, 1 MB = 10**6 bytes]. Wall time: the
!> reader is meant to be bound by the disk (or the page cache, after the first read), so
!> the first read of a file not yet cached is the slowest; the median hides it once repeats
!> >= 3. The process's CPU time per read (user + system) is printed beside it: on a machine
!> shared with other jobs the wall time also counts the waits for a core.
!>
!> With a third argument other than '-' the matrix read is also written to that path as raw
!> stream data (nrows, ncols, nnz, row_start, col, val: int32 and float64, native byte
!> order), so that two revisions of the reader can be compared bit for bit with `cmp`. A
!> fourth argument sets the block size of the reader [bytes] (default mm_chunk_bytes;
!> leave it out for a revision before issue 25, whose reader has no such argument).
!>
!> Run from the project root: fpm run --example bench_mm_read --profile release --
!>     <file.mtx> [repeats [dump_path|- [chunk_bytes]]]    (repeats default 5)
program bench_mm_read
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit, int64
    use stickslip, only: dp, error_type, sparse_matrix_t
    use stickslip_io, only: read_matrix_market
    use stickslip_study, only: median
    implicit none

    type(sparse_matrix_t) :: a
    type(error_type), allocatable :: error
    character(len=4096) :: path, dump
    character(len=32) :: arg
    real(dp), allocatable :: seconds(:), cpu(:)
    real(dp) :: mb, c0, c1
    integer(int64) :: bytes, t0, t1, rate
    integer :: repeats, k, u, stat, chunk
    logical :: exists

    if (command_argument_count() < 1) then
        write (error_unit, '(a)') "usage: bench_mm_read <file.mtx> [repeats [dump_path]]"
        stop 1
    end if
    call get_command_argument(1, path)
    repeats = 5
    if (command_argument_count() >= 2) then
        call get_command_argument(2, arg)
        read (arg, *, iostat=stat) repeats
        if (stat /= 0 .or. repeats < 1) then
            write (error_unit, '(a)') "bench_mm_read: repeats must be a positive integer"
            stop 1
        end if
    end if
    dump = ""
    if (command_argument_count() >= 3) call get_command_argument(3, dump)
    if (dump == "-") dump = ""
    chunk = 0
    if (command_argument_count() >= 4) then
        call get_command_argument(4, arg)
        read (arg, *, iostat=stat) chunk
        if (stat /= 0 .or. chunk < 1) then
            write (error_unit, '(a)') "bench_mm_read: chunk_bytes must be a positive integer"
            stop 1
        end if
    end if
    inquire (file=trim(path), exist=exists, size=bytes)
    if (.not. exists) then
        write (error_unit, '(a)') "bench_mm_read: no file "//trim(path)
        stop 1
    end if
    mb = real(bytes, dp)/1.0e6_dp
    allocate (seconds(repeats), cpu(repeats))
    do k = 1, repeats
        call cpu_time(c0)
        call system_clock(t0, rate)
        if (chunk > 0) then
            call read_matrix_market(trim(path), a, error, chunk=chunk)
        else
            call read_matrix_market(trim(path), a, error)
        end if
        call system_clock(t1)
        call cpu_time(c1)
        if (allocated(error)) then
            write (error_unit, '(a)') "bench_mm_read: "//error%message
            stop 1
        end if
        seconds(k) = real(t1 - t0, dp)/real(rate, dp)
        cpu(k) = c1 - c0
        write (output_unit, '(a,i0,a,f8.3,a,f8.1,a,f8.3,a)') "read ", k, ": ", seconds(k), &
            " s, ", mb/seconds(k), " MB/s (CPU ", cpu(k), " s)"
    end do
    write (output_unit, '(a,i0,a,i0,a,i0,a,f0.1,a)') "file "//trim(path)//": ", a%nrows, &
        " x ", a%ncols, ", ", size(a%val), " stored entries (full storage), ", mb, " MB"
    write (output_unit, '(a,i0,a,f8.3,a,f8.1,a,f8.3,a,f8.1,a)') "median of ", repeats, &
        " reads: ", median(seconds), " s, ", mb/median(seconds), " MB/s (CPU ", median(cpu), &
        " s, ", mb/median(cpu), " MB per CPU second)"
    if (len_trim(dump) > 0) then
        open (newunit=u, file=trim(dump), status='replace', access='stream', &
              form='unformatted', action='write', iostat=stat)
        if (stat == 0) write (u, iostat=stat) a%nrows, a%ncols, size(a%val), a%row_start, &
            a%col, a%val
        if (stat == 0) close (u, iostat=stat)
        if (stat /= 0) then
            write (error_unit, '(a)') "bench_mm_read: cannot write "//trim(dump)
            stop 1
        end if
        write (output_unit, '(a)') "matrix written to "//trim(dump)
    end if
end program bench_mm_read
