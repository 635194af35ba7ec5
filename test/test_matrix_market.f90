!> Tests of the Matrix Market reader and writers: every supported kind read against the
!> dense matrix written here, every class of bad file rejected with "<file>:<line>:" and
!> what is wrong, and the round trip writer -> reader exact. The block reader (issue 25):
!> every block size gives the same matrix and the same messages (lines across blocks, CR LF
!> and CR across blocks), values bit for bit those of read(s, *), progress lines.
module test_matrix_market
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_sparse, only: sparse_matrix_t, sparse_to_dense, sparse_from_dense
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_matrix_market, only: read_matrix_market, read_matrix_market_size, &
        write_matrix_market, &
        write_matrix_market_array, max_mm_line
    use stickslip_progress, only: progress_t
    use stickslip_files, only: make_directory
    use testing, only: test_counter_t, check, check_close, check_error
    use fixtures, only: enter_project_root, scratch, write_lines
    implicit none
    private
    public :: run_matrix_market_tests

    character(len=*), parameter :: dir = scratch//"/mm"
    character(len=*), parameter :: sym_header = "%%MatrixMarket matrix coordinate real symmetric"
    character(len=*), parameter :: gen_header = "%%MatrixMarket matrix coordinate real general"

contains

    subroutine run_matrix_market_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(scratch, error)
        call make_directory(dir, error)
        call check_error(t, error, "mm: scratch directory", .false.)
        if (allocated(error)) return
        call test_good_files(t)
        call test_bad_files(t)
        call test_round_trip(t)
        call test_mutations(t)
        call test_blocks(t)
        call test_line_ends(t)
        call test_long_lines(t)
        call test_values_exact(t)
        call test_progress(t)
    end subroutine run_matrix_market_tests

    !> The bytes of `text` as the file `path`.
    subroutine write_raw(path, text)
        character(len=*), intent(in) :: path, text
        integer :: u
        open (newunit=u, file=path, status='replace', access='stream', form='unformatted')
        write (u) text
        close (u)
    end subroutine write_raw

    !> a and b hold the same entries, bit for bit.
    logical function same_matrix(a, b)
        type(sparse_matrix_t), intent(in) :: a, b
        same_matrix = .false.
        if (a%nrows /= b%nrows .or. a%ncols /= b%ncols) return
        if (.not. (allocated(a%row_start) .and. allocated(b%row_start))) return
        if (size(a%col) /= size(b%col)) return
        if (any(a%row_start /= b%row_start) .or. any(a%col /= b%col)) return
        same_matrix = all(transfer(a%val, 1_int64, size(a%val)) == &
                          transfer(b%val, 1_int64, size(b%val)))
    end function same_matrix

    !> Every block size from 1 byte up gives the matrix (and the error) of the default
    !> size: lines, numbers and CR LF pairs cut between two blocks; comments, blank lines,
    !> tabs, forms of the general path (signed indices, `1.5+3`) between the common ones.
    subroutine test_blocks(t)
        type(test_counter_t), intent(inout) :: t
        character(len=1), parameter :: lf = achar(10), cr = achar(13), tab = achar(9)
        character(len=:), allocatable :: text, bad_text
        type(sparse_matrix_t) :: a, b
        type(error_type), allocatable :: error, error2
        integer :: chunk
        logical :: same, same_errors
        text = sym_header//cr//lf//"% written by hand"//lf//lf//"  4 4 7"//lf// &
               "1 1 5.5215441313185e+04"//cr//lf//"2 1 -1.8960205527810e+04"//cr// &
               "2 2 9.1482364166893E+04"//lf//"%"//lf//"+3 01 -3.4844662247620d-10"//lf// &
               tab//"3"//tab//"3 4.78e+04 "//lf//"4 2 1.5+3"//lf//"4 4 2.0436814886855e-08"
        call write_raw(dir//"/blocks.mtx", text)
        call read_matrix_market(dir//"/blocks.mtx", a, error)
        call check_error(t, error, "mm blocks: read", .false.)
        if (allocated(error)) return
        call check(t, a%nrows == 4 .and. size(a%val) == 10, "mm blocks: 7 entries, 3 mirrored")
        same = .true.
        do chunk = 1, len(text) + 1
            call read_matrix_market(dir//"/blocks.mtx", b, error, chunk=chunk)
            same = same .and. .not. allocated(error)
            if (same) same = same_matrix(a, b)
        end do
        call check(t, same, "mm blocks: every block size gives the same matrix")
        ! an error found after a block boundary names the same line
        bad_text = text(1:index(text, "4 2 1.5+3") - 1)//"4 2 1.5+3x"//lf//"4 4 1"//lf
        call write_raw(dir//"/blocks_bad.mtx", bad_text)
        call read_matrix_market(dir//"/blocks_bad.mtx", b, error2)
        call check_error(t, error2, "mm blocks: bad value", .true., [character(len=40) :: &
                         dir//"/blocks_bad.mtx:11:", "'1.5+3x' is not a real number"])
        same_errors = allocated(error2)
        do chunk = 1, len(bad_text) + 1
            if (.not. same_errors) exit
            call read_matrix_market(dir//"/blocks_bad.mtx", b, error, chunk=chunk)
            same_errors = allocated(error)
            if (same_errors) same_errors = error%message == error2%message
        end do
        call check(t, same_errors, "mm blocks: every block size gives the same message")
    end subroutine test_blocks

    !> LF, CR LF and a lone CR end lines (as in gfortran's formatted reads); LF CR is two
    !> line ends (an empty line between); the last line needs no end.
    subroutine test_line_ends(t)
        type(test_counter_t), intent(inout) :: t
        character(len=1), parameter :: lf = achar(10), cr = achar(13)
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        real(dp), allocatable :: d(:, :)
        integer :: k
        character(len=2), parameter :: ends(4) = [character(len=2) :: lf, cr//lf, cr, lf//cr]
        character(len=8), parameter :: names(4) = [character(len=8) :: "lf", "crlf", "cr", &
                                                    "lfcr"]
        do k = 1, size(ends)
            call write_raw(dir//"/ends_"//trim(names(k))//".mtx", gen_header//trim(ends(k))// &
                           "2 2 2"//trim(ends(k))//"1 1 2.5"//trim(ends(k))//"2 2 -1")
            call read_matrix_market(dir//"/ends_"//trim(names(k))//".mtx", a, error, chunk=3)
            call check_error(t, error, "mm line ends "//trim(names(k)), .false.)
            if (allocated(error)) cycle
            call sparse_to_dense(a, d, error)
            call check(t, d(1, 1) == 2.5_dp .and. d(2, 2) == -1.0_dp .and. d(1, 2) == 0.0_dp, &
                       "mm line ends "//trim(names(k))//": values")
        end do
        ! line numbers count a lone CR and the empty line of LF CR
        call write_raw(dir//"/ends_count.mtx", gen_header//cr//"1 1 1"//lf//cr// &
                       "1 1 NaN"//cr//lf)
        call read_matrix_market(dir//"/ends_count.mtx", a, error)
        call check_error(t, error, "mm line ends: line numbers", .true., &
                         [character(len=60) :: dir//"/ends_count.mtx:4:", "'NaN'"])
        ! the last line without an end, 256 characters long (the formatted reader of
        ! commit 67986c6 failed there with "Sequential READ or WRITE not allowed after EOF")
        call write_raw(dir//"/ends_256.mtx", gen_header//lf//"1 1 1"//lf//"1 1 2.5"// &
                       repeat(" ", 249))
        call read_matrix_market(dir//"/ends_256.mtx", a, error)
        call check_error(t, error, "mm line ends: a last line of 256 characters", .false.)
    end subroutine test_line_ends

    !> A line of max_mm_line characters is read, one more is an error naming its line, for
    !> block sizes around the line's length; also for a comment line and a last line.
    subroutine test_long_lines(t)
        type(test_counter_t), intent(inout) :: t
        character(len=1), parameter :: lf = achar(10), cr = achar(13)
        integer, parameter :: chunks(6) = [1, 7, max_mm_line - 1, max_mm_line, &
                                           max_mm_line + 1, 8*1024*1024]
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        character(len=:), allocatable :: entry, comment
        logical :: good_ok, bad_ok
        integer :: c, extra
        good_ok = .true.
        bad_ok = .true.
        do extra = 0, 1
            entry = "1 1 2.5"//repeat(" ", max_mm_line - 7 + extra)
            comment = "%"//repeat("x", max_mm_line - 1 + extra)
            do c = 1, size(chunks)
                call write_raw(dir//"/long_entry.mtx", gen_header//cr//lf//"1 1 1"//cr//lf// &
                               entry//cr//lf)
                call read_matrix_market(dir//"/long_entry.mtx", a, error, chunk=chunks(c))
                call judge(dir//"/long_entry.mtx:3:")
                call write_raw(dir//"/long_comment.mtx", gen_header//lf//comment//lf// &
                               "1 1 1"//lf//"1 1 2")
                call read_matrix_market(dir//"/long_comment.mtx", a, error, chunk=chunks(c))
                call judge(dir//"/long_comment.mtx:2:")
                call write_raw(dir//"/long_last.mtx", gen_header//lf//"1 1 1"//lf//entry)
                call read_matrix_market(dir//"/long_last.mtx", a, error, chunk=chunks(c))
                call judge(dir//"/long_last.mtx:3:")
            end do
        end do
        call check(t, good_ok, "mm long lines: max_mm_line characters read")
        call check(t, bad_ok, "mm long lines: one more is an error naming the line")
    contains
        subroutine judge(where)
            character(len=*), intent(in) :: where
            if (extra == 0) then
                good_ok = good_ok .and. .not. allocated(error)
            else if (.not. allocated(error)) then
                bad_ok = .false.
            else
                bad_ok = bad_ok .and. index(error%message, where//" line longer than") == 1
            end if
        end subroutine judge
    end subroutine test_long_lines

    !> 3000 values in many forms (14, 17 and 18 digits, e/E/d/D, signs, exponents from
    !> -300 to 300, more than 18 digits, denormals) read through the file, in a general
    !> and a symmetric file: each stored value is bit for bit read(s, *) of its text.
    subroutine test_values_exact(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: nv = 3000
        character(len=16), parameter :: formats(6) = [character(len=16) :: "(es22.13e2)", &
            "(es25.17e3)", "(es24.16e3)", "(es30.22e3)", "(es12.4e3)", "(f0.9)"]
        character(len=32) :: s(nv)
        real(dp) :: expected(nv), x, r(3)
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        character(len=:), allocatable :: text
        character(len=24) :: index_text
        integer :: k, p, stat
        logical :: good
        do k = 1, nv
            call random_number(r)
            x = (2*r(1) - 1)*10.0_dp**int(600*r(2) - 300)
            if (int(6*r(3)) == 5) x = (2*r(1) - 1)*10.0_dp**int(20*r(2) - 10)  ! f0.9
            if (k <= 30) x = (2*r(1) - 1)*2.0_dp**(-1074 + k)       ! subnormals
            write (s(k), formats(1 + int(6*r(3)))) x
            s(k) = adjustl(s(k))
            p = scan(s(k), "E")
            if (p > 0 .and. mod(k, 3) == 0) s(k)(p:p) = "d"
            if (p > 0 .and. mod(k, 3) == 1) s(k)(p:p) = "e"
            read (s(k), *, iostat=stat) expected(k)
            if (stat /= 0 .or. .not. (abs(expected(k)) <= huge(x))) then
                s(k) = "0.5"
                expected(k) = 0.5_dp
            end if
        end do
        text = gen_header//new_line('a')//itoa_(nv)//" 1 "//itoa_(nv)//new_line('a')
        do k = 1, nv
            write (index_text, '(i0)') k
            text = text//trim(index_text)//" 1 "//trim(s(k))//new_line('a')
        end do
        call write_raw(dir//"/values.mtx", text)
        call read_matrix_market(dir//"/values.mtx", a, error)
        call check_error(t, error, "mm exact values: read", .false.)
        if (allocated(error)) return
        good = size(a%val) == nv
        if (good) good = all(transfer(a%val, 1_int64, nv) == transfer(expected, 1_int64, nv))
        call check(t, good, "mm exact values: bit for bit as read(s, *)")
        ! the same values on the diagonal of a symmetric file
        text = sym_header//new_line('a')//itoa_(nv)//" "//itoa_(nv)//" "//itoa_(nv)// &
               new_line('a')
        do k = 1, nv
            write (index_text, '(i0,1x,i0)') k, k
            text = text//trim(index_text)//" "//trim(s(k))//new_line('a')
        end do
        call write_raw(dir//"/values_sym.mtx", text)
        call read_matrix_market(dir//"/values_sym.mtx", a, error, chunk=1000)
        call check_error(t, error, "mm exact values: symmetric read", .false.)
        if (allocated(error)) return
        good = size(a%val) == nv
        if (good) good = all(transfer(a%val, 1_int64, nv) == transfer(expected, 1_int64, nv))
        call check(t, good, "mm exact values: symmetric, bit for bit as read(s, *)")
    end subroutine test_values_exact

    pure function itoa_(i) result(s)
        integer, intent(in) :: i
        character(len=:), allocatable :: s
        character(len=16) :: buffer
        write (buffer, '(i0)') i
        s = trim(buffer)
    end function itoa_

    !> Progress of a read: nothing without a unit; with one (no delay, every block) lines
    !> `stickslip: reading <done>/<size> MB, <path>, <s> s`, counted in progress%lines.
    subroutine test_progress(t)
        type(test_counter_t), intent(inout) :: t
        type(progress_t) :: progress
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        character(len=200) :: line
        character(len=60), allocatable :: lines(:)
        integer :: u, stat, lines_seen, k
        ! 2000 entries of 14 bytes: 28 kB, read in blocks of 1000 bytes
        allocate (lines(2002))
        lines(1) = gen_header
        lines(2) = "2000 2000 2000"
        do k = 1, 2000
            write (lines(k + 2), '(i4.4,1x,i4.4,1x,a)') k, k, "1.0"
        end do
        call write_lines(dir//"/progress.mtx", lines)
        open (newunit=u, status='scratch', action='readwrite', form='formatted')
        progress%label = "sweep"
        call read_matrix_market(dir//"/progress.mtx", a, error, progress=progress, chunk=1000)
        call check(t, .not. allocated(error) .and. progress%lines == 0, &
                   "mm progress: off without a unit")
        progress = progress_t(unit=u, delay=0.0_dp, interval=0.0_dp)
        progress%label = "sweep"
        call read_matrix_market(dir//"/progress.mtx", a, error, progress=progress, chunk=1000)
        call check(t, .not. allocated(error) .and. progress%lines >= 20, &
                   "mm progress: a line per block")
        call check(t, progress%label == "sweep", "mm progress: the caller's label kept")
        rewind (u)
        lines_seen = 0
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (index(line, "stickslip: reading ") == 1 .and. &
                index(line, "/28 kB, "//dir//"/progress.mtx, ") > 0) lines_seen = lines_seen + 1
        end do
        close (u)
        call check(t, lines_seen == progress%lines, "mm progress: the lines' text", line)
    end subroutine test_progress

    !> Random byte edits of a valid file: every outcome is a matrix or an error that names
    !> the file (never a crash, a hang or a message without the file).
    subroutine test_mutations(t)
        type(test_counter_t), intent(inout) :: t
        character(len=*), parameter :: base = sym_header//achar(10)//"% c"//achar(10)// &
            "3 3 4"//achar(10)//"1 1 4.0"//achar(10)//"2 1 -1.5e0"//achar(10)// &
            "2 2 3"//achar(10)//"3 3 2.25"//achar(10)
        character(len=*), parameter :: alphabet = "0123456789 -+.eE%"//achar(10)//"x,/"
        character(len=len(base)) :: text
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        integer :: trial, k, u, pos, bad_messages, accepted
        real(dp) :: r(3)
        bad_messages = 0
        accepted = 0
        do trial = 1, 300
            text = base
            do k = 1, 3
                call random_number(r)
                pos = 1 + int(r(1)*len(base))
                if (r(3) < 0.05_dp) then
                    text(pos:pos) = achar(int(r(2)*256))
                else
                    text(pos:pos) = alphabet(1 + int(r(2)*len(alphabet)):1 + int(r(2)*len(alphabet)))
                end if
            end do
            open (newunit=u, file=dir//"/fuzz.mtx", status='replace', access='stream', &
                  form='unformatted')
            write (u) text
            close (u)
            call read_matrix_market(dir//"/fuzz.mtx", a, error)
            if (allocated(error)) then
                if (index(error%message, dir//"/fuzz.mtx") /= 1) bad_messages = bad_messages + 1
            else
                accepted = accepted + 1
            end if
        end do
        call check(t, bad_messages == 0, "mm mutations: every error names the file")
        call check(t, accepted < 300, "mm mutations: some mutations rejected")
    end subroutine test_mutations

    !> Read `lines` as a file and compare with `expected` (exactly).
    subroutine good(t, name, lines, expected, symmetric)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: name
        character(len=*), intent(in) :: lines(:)
        real(dp), intent(in) :: expected(:, :)
        logical, intent(in) :: symmetric
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        real(dp), allocatable :: d(:, :)
        logical :: sym
        call write_lines(dir//"/"//name//".mtx", lines)
        call read_matrix_market(dir//"/"//name//".mtx", a, error, sym)
        call check_error(t, error, "mm good "//name//": read", .false.)
        if (allocated(error)) return
        call sparse_to_dense(a, d, error)
        if (size(d, 1) /= size(expected, 1) .or. size(d, 2) /= size(expected, 2)) then
            call check(t, .false., "mm good "//name//": size")
            return
        end if
        call check(t, all(d == expected) .and. (sym .eqv. symmetric), "mm good "//name//": values")
    end subroutine good

    subroutine test_good_files(t)
        type(test_counter_t), intent(inout) :: t
        real(dp) :: s(3, 3), g(2, 3)
        s = reshape([4.0_dp, -1.0_dp, 0.5_dp, -1.0_dp, 3.0_dp, 0.0_dp, 0.5_dp, 0.0_dp, 2.0_dp], &
                    [3, 3])
        g = reshape([1.0_dp, 0.0_dp, -2.0_dp, 3.5_dp, 0.0_dp, 1.0e-300_dp], [2, 3])
        ! symmetric, lower triangle, comments and blank lines, unsorted
        call good(t, "sym_lower", [character(len=60) :: sym_header, "% a comment", "", &
                  "  3 3 5", "% another", "3 1 0.5", "1 1 4", "2 1 -1.0", "", "2 2 3.0e0", &
                  "3 3 2"], s, .true.)
        ! symmetric, upper triangle, keywords in capitals, tabs
        call good(t, "sym_upper", [character(len=60) :: &
                  "%%MatrixMarket MATRIX Coordinate Real Symmetric", "3 3 5", &
                  "1"//achar(9)//"1 4", "1 2 -1", "1 3 0.5", "2 2 3", "3 3 2.0D0"], s, .true.)
        ! general with a duplicate (summed) and an explicit zero
        call good(t, "general", [character(len=60) :: gen_header, "2 3 5", "1 1 0.5", &
                  "2 2 3.5", "1 2 -2", "1 1 0.5", "2 3 1e-300"], g, .false.)
        ! integer field, read as reals
        call good(t, "integer", [character(len=60) :: &
                  "%%MatrixMarket matrix coordinate integer general", "2 3 3", "1 1 1", &
                  "1 2 -2", "2 2 +7"], reshape([1.0_dp, 0.0_dp, -2.0_dp, 7.0_dp, 0.0_dp, &
                                                0.0_dp], [2, 3]), .false.)
        ! dense arrays: general (column by column) and symmetric (lower triangle)
        call good(t, "array_general", [character(len=60) :: &
                  "%%MatrixMarket matrix array real general", "% dense", "2 3", "1", "0", &
                  "-2", "3.5", "0", "1e-300"], g, .false.)
        call good(t, "array_symmetric", [character(len=60) :: &
                  "%%MatrixMarket matrix array real symmetric", "3 3", "4", "-1", "0.5", "3", &
                  "0", "2"], s, .true.)
        ! an empty matrix, and a last line without newline is fine (write_lines always adds one)
        call good(t, "empty", [character(len=60) :: gen_header, "2 2 0"], &
                  reshape([0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], [2, 2]), .false.)
        ! CR LF line ends
        call good(t, "crlf", [character(len=60) :: gen_header//achar(13), "1 1 1"//achar(13), &
                  "1 1 2.5"//achar(13)], reshape([2.5_dp], [1, 1]), .false.)
    end subroutine test_good_files

    !> A bad file: the error names "<file>:<line>:" and contains every string of `what`.
    subroutine bad(t, name, lines, line, what, stat)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: name
        character(len=*), intent(in) :: lines(:)
        integer, intent(in) :: line
        character(len=*), intent(in) :: what(:)
        integer, intent(in), optional :: stat
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        character(len=16) :: at
        character(len=:), allocatable :: path
        character(len=120) :: expect(size(what) + 1)
        integer :: k
        path = dir//"/bad_"//name//".mtx"
        call write_lines(path, lines)
        call read_matrix_market(path, a, error)
        write (at, '(a,i0,a)') ":", line, ":"
        expect(1) = path//trim(at)
        do k = 1, size(what)
            expect(k + 1) = what(k)
        end do
        call check_error(t, error, "mm bad "//name, .true., expect)
        if (allocated(error)) call check(t, error%stat == merge(stat, stickslip_stat%input, &
                                         present(stat)), "mm bad "//name//": stat")
    end subroutine bad

    subroutine test_bad_files(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: a
        type(error_type), allocatable :: error
        ! an empty file (as a pipe or a device: size 0) is refused before it is opened
        call write_lines(dir//"/bad_empty.mtx", [character(len=1) ::])
        call read_matrix_market(dir//"/bad_empty.mtx", a, error)
        call check_error(t, error, "mm bad empty", .true., [character(len=60) :: &
                         dir//"/bad_empty.mtx: empty, or not a regular file"])
        call bad(t, "no_header", [character(len=60) :: "2 2 1", "1 1 1"], 1, &
                 [character(len=30) :: "missing header"])
        call bad(t, "short_header", [character(len=60) :: "%%MatrixMarket matrix coordinate", &
                 "1 1 1", "1 1 1"], 1, [character(len=30) :: "5 words"])
        call bad(t, "vector", [character(len=60) :: &
                 "%%MatrixMarket vector coordinate real general", "1 1 1", "1 1 1"], 1, &
                 [character(len=30) :: "object 'vector'"])
        call bad(t, "complex", [character(len=60) :: &
                 "%%MatrixMarket matrix coordinate complex general", "1 1 1", "1 1 1 0"], 1, &
                 [character(len=30) :: "field 'complex'"])
        call bad(t, "pattern", [character(len=60) :: &
                 "%%MatrixMarket matrix coordinate pattern general", "1 1 1", "1 1"], 1, &
                 [character(len=30) :: "field 'pattern'"])
        call bad(t, "format", [character(len=60) :: &
                 "%%MatrixMarket matrix sparse real general", "1 1 1", "1 1 1"], 1, &
                 [character(len=30) :: "format 'sparse'"])
        call bad(t, "skew", [character(len=60) :: &
                 "%%MatrixMarket matrix coordinate real skew-symmetric", "1 1 1", "1 1 1"], 1, &
                 [character(len=30) :: "symmetry 'skew-symmetric'"])
        call bad(t, "no_size", [character(len=60) :: gen_header, "% only a comment"], 2, &
                 [character(len=30) :: "before the size line"])
        call bad(t, "size_two", [character(len=60) :: gen_header, "% c", "2 2", "1 1 1"], 3, &
                 [character(len=30) :: "size line", "3 integers"])
        call bad(t, "size_real", [character(len=60) :: gen_header, "2 2.0 1", "1 1 1"], 2, &
                 [character(len=30) :: "size line", "not integers"])
        call bad(t, "size_negative", [character(len=60) :: gen_header, "2 -2 1", "1 1 1"], 2, &
                 [character(len=30) :: "negative size"])
        call bad(t, "sym_not_square", [character(len=60) :: sym_header, "2 3 1", "1 1 1"], 2, &
                 [character(len=30) :: "must be square"])
        call bad(t, "too_many_announced", [character(len=60) :: gen_header, "2 2 5", "1 1 1"], &
                 2, [character(len=30) :: "more than the 2 x 2"])
        call bad(t, "beyond_limit", [character(len=60) :: gen_header, &
                 "100000 100000 200000000", "1 1 1"], 2, [character(len=30) :: "10**8"])
        call bad(t, "array_too_big", [character(len=60) :: &
                 "%%MatrixMarket matrix array real general", "100000 100000", "1"], 2, &
                 [character(len=30) :: "2**25"])
        call bad(t, "fewer", [character(len=60) :: gen_header, "2 2 3", "1 1 1", "% c", &
                 "2 2 1"], 5, [character(len=40) :: "end of file after 2 of the 3", "line 2"])
        call bad(t, "more", [character(len=60) :: gen_header, "2 2 2", "1 1 1", "2 2 1", &
                 "", "1 2 1"], 6, [character(len=40) :: "more entries than the 2", "line 2"])
        call bad(t, "array_fewer", [character(len=60) :: &
                 "%%MatrixMarket matrix array real general", "2 2", "1", "2", "3"], 5, &
                 [character(len=40) :: "end of file after 3 of the 4"])
        call bad(t, "row_range", [character(len=60) :: gen_header, "2 2 2", "1 1 1", &
                 "3 1 1"], 4, [character(len=40) :: "entry (3,1) outside the 2 x 2"])
        call bad(t, "col_zero", [character(len=60) :: gen_header, "2 2 1", "1 0 1"], 3, &
                 [character(len=40) :: "entry (1,0) outside", "1-based"])
        call bad(t, "nan", [character(len=60) :: gen_header, "2 2 2", "1 1 1", "2 2 NaN"], 4, &
                 [character(len=40) :: "'NaN'", "not a finite number"])
        call bad(t, "inf", [character(len=60) :: sym_header, "2 2 1", "2 1 -Inf"], 3, &
                 [character(len=40) :: "not a finite number"])
        call bad(t, "overflow", [character(len=60) :: gen_header, "1 1 1", "1 1 1e999"], 3, &
                 [character(len=40) :: "1e999"])
        call bad(t, "word", [character(len=60) :: gen_header, "1 1 1", "1 1 one"], 3, &
                 [character(len=40) :: "'one' is not a real number"])
        call bad(t, "two_values", [character(len=60) :: gen_header, "1 1 1", "1 1 1 2"], 3, &
                 [character(len=40) :: "'row column value'"])
        call bad(t, "int_field", [character(len=60) :: &
                 "%%MatrixMarket matrix coordinate integer general", "1 1 1", "1 1 1.5"], 3, &
                 [character(len=40) :: "not an integer"])
        call bad(t, "both_triangles", [character(len=60) :: sym_header, "2 2 3", "2 1 1", &
                 "1 1 2", "1 2 1"], 5, [character(len=60) :: "(1,2) is in the upper triangle", &
                 "line 3", "non-symmetric data"])
        call bad(t, "sym_duplicate", [character(len=60) :: sym_header, "2 2 3", "1 1 1", &
                 "2 1 1", "1 1 1"], 5, [character(len=60) :: "(1,1) given twice (lines 3 and 5)", &
                 "rejected"])
        call bad(t, "binary", [character(len=60) :: gen_header, "1 1 1", "1 1 "//achar(1)], &
                 3, [character(len=40) :: "non-printable"])
        block
            integer :: m, n
            call write_lines(dir//"/size_only.mtx", [character(len=60) :: gen_header, &
                             "% c", "7 9 30", "1 1 1"])
            call read_matrix_market_size(dir//"/size_only.mtx", m, n, error)
            call check_error(t, error, "mm: size only, entries not read", .false.)
            call check(t, m == 7 .and. n == 9, "mm: size only: 7 x 9")
        end block
        call read_matrix_market(dir//"/does_not_exist.mtx", a, error)
        call check_error(t, error, "mm: missing file", .true., [character(len=60) :: &
                         dir//"/does_not_exist.mtx", "cannot open"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%io, "mm: missing file is io")
    end subroutine test_bad_files

    subroutine test_round_trip(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: a, b
        type(error_type), allocatable :: error
        real(dp) :: d(5, 5), g(4, 3)
        real(dp), allocatable :: back(:, :)
        logical :: sym
        call random_number(d)
        d = (d + transpose(d))*1.0e7_dp/3.0_dp
        d(2, 4) = 0.0_dp
        d(4, 2) = 0.0_dp
        call random_number(g)
        g = g - 0.5_dp
        g(1, 1) = -1.0e-200_dp
        call sparse_from_dense(d, a)
        call write_matrix_market(dir//"/trip_sym.mtx", a, .true., error)
        call check_error(t, error, "mm round trip: write symmetric", .false.)
        call read_matrix_market(dir//"/trip_sym.mtx", b, error, sym)
        call sparse_to_dense(b, back, error)
        call check(t, all(back == d) .and. sym, "mm round trip: coordinate symmetric, exact")
        call sparse_from_dense(g, a)
        call write_matrix_market(dir//"/trip_gen.mtx", a, .false., error)
        call read_matrix_market(dir//"/trip_gen.mtx", b, error, sym)
        call sparse_to_dense(b, back, error)
        call check(t, all(back == g) .and. .not. sym, "mm round trip: coordinate general, exact")
        call write_matrix_market(dir//"/trip_bad.mtx", a, .true., error)
        call check_error(t, error, "mm: writing a non-symmetric matrix as symmetric refused", &
                         .true., [character(len=30) :: "non-symmetric"])
        call write_matrix_market_array(dir//"/trip_arr.mtx", g, .false., error)
        call check_error(t, error, "mm round trip: write array", .false.)
        call read_matrix_market(dir//"/trip_arr.mtx", b, error)
        call sparse_to_dense(b, back, error)
        call check(t, all(back == g), "mm round trip: array general, exact")
        call write_matrix_market_array(dir//"/trip_arrs.mtx", d, .true., error)
        call read_matrix_market(dir//"/trip_arrs.mtx", b, error, sym)
        call sparse_to_dense(b, back, error)
        call check(t, all(back == d) .and. sym, "mm round trip: array symmetric, exact")
        call write_matrix_market_array(scratch//"/no/such/dir/x.mtx", g, .false., error)
        call check_error(t, error, "mm: unwritable path", .true., [character(len=30) :: &
                         "cannot write"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%io, "mm: unwritable is io")
    end subroutine test_round_trip
end module test_matrix_market
