!> Matrix Market files (https://math.nist.gov/MatrixMarket/formats.html) read into and
!> written from a sparse_matrix_t (full storage: a symmetric file's triangle is mirrored).
!>
!> Read: the header `%%MatrixMarket matrix <format> <field> <symmetry>` (words in any case)
!> with format `coordinate` or `array`, field `real`, `double` or `integer` (integers are read
!> as reals), symmetry `general` or `symmetric`; then `%` comment lines and blank lines
!> anywhere; the size line (`rows cols entries` for coordinate, `rows cols` for array); the
!> entries, 1-based `i j value` (coordinate) or one value per line, column by column (array;
!> a symmetric array gives the lower triangle, column by column: (j..n, j) for j = 1..n).
!> A symmetric coordinate file gives ONE triangle, lower or upper (the first off-diagonal
!> entry decides); an entry of the other triangle is an error naming both lines. A duplicate
!> entry is REJECTED in a symmetric file (naming both lines) and SUMMED in a general file (the
!> usual assembly convention of coordinate lists). Lines end with LF, CR LF or a lone CR.
!> Errors (stat input; stat io when the file cannot be opened or read) start "<file>:<line>: "
!> and say what is wrong: a missing or wrong header, an unsupported format, field (complex,
!> pattern) or symmetry (skew-symmetric, hermitian), a malformed size line, a symmetric matrix
!> that is not square, more entries than max_mm_entries (coordinate) or rows x cols above
!> max_dense_entries (array), fewer or more entries than announced, an index out of range, a
!> malformed or non-finite value (NaN, Inf), a line longer than max_mm_line, a byte that is
!> not printable ASCII. A directory, and a file of size 0 (empty, or a pipe or a device) are
!> refused before the file is opened.
!>
!> Speed (issue 25): the file is read in blocks of mm_chunk_bytes (stickslip_line_reader),
!> and an entry line of the common form (plain indices, a value stickslip_decimal scans
!> exactly) is parsed straight from the block; any other line (comments, signs on indices,
!> a value of more than 18 digits, `1.5+3`, errors) goes through the general line-by-line
!> path, with Fortran's own read of the value, so the values and the messages are those of
!> a plain formatted read. About 120-180 MB/s on the 113 MB Rotor 37 matrices (a 2-core
!> VM; doc/benchmarks.md), 20 times the formatted reader.
module stickslip_matrix_market
    use, intrinsic :: iso_fortran_env, only: int64, iostat_end
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_progress, only: progress_t
    use stickslip_decimal, only: decimal_powers_t, scan_decimal, scan_digits
    use stickslip_line_reader, only: line_reader_t, open_line_reader, line_end_of_file, &
        line_too_long, line_read_error
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, &
        sparse_symmetry_defect, max_dense_entries
    implicit none
    private
    public :: read_matrix_market, read_matrix_market_size, write_matrix_market, &
        write_matrix_market_array
    public :: max_mm_entries, max_mm_line, mm_chunk_bytes

    !> Most entries a coordinate file may announce (10**8: 1.6 GB of triplets).
    integer(int64), parameter :: max_mm_entries = 100000000_int64
    !> Longest line read [characters].
    integer, parameter :: max_mm_line = 4096
    !> Bytes read at once by read_matrix_market (8 MiB; read_matrix_market_size reads 64 KiB).
    integer, parameter :: mm_chunk_bytes = 8*1024*1024

contains

    !> Read the Matrix Market file `path` into `a` (full storage). Errors: see the module.
    !> Quiet unless `progress` has a unit: then, once the read has taken progress%delay
    !> seconds, a line `stickslip: reading <MB read>/<MB> MB, <path>, <elapsed> s` at most
    !> every progress%interval seconds, looked at when a block has been read
    !> (stickslip_progress; the caller's label is kept; kB or bytes for files under 10 MB).
    subroutine read_matrix_market(path, a, error, symmetric, progress, chunk)
        !> Path of the file.
        character(len=*), intent(in) :: path
        !> The matrix read.
        type(sparse_matrix_t), intent(out) :: a
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> The file declared the matrix symmetric.
        logical, intent(out), optional :: symmetric
        !> Where and how often to report the progress of a long read (unit, delay and
        !> interval are used; its `lines` count grows by the lines printed).
        type(progress_t), intent(inout), optional :: progress
        !> Bytes read at once (default mm_chunk_bytes; taken into 1 .. 2**30). Any size
        !> gives the same result; small ones are for tests of lines across blocks.
        integer, intent(in), optional :: chunk
        integer :: bytes
        bytes = mm_chunk_bytes
        if (present(chunk)) bytes = max(chunk, 1)
        call read_file(path, .false., bytes, a, error, symmetric, progress=progress)
    end subroutine read_matrix_market

    !> The size of the matrix of the Matrix Market file `path` from its header and size line
    !> only (the entries are not read), e.g. to refuse a model too large before reading it.
    !> Errors: those of the header and the size line (see the module).
    subroutine read_matrix_market_size(path, nrows, ncols, error, entries, size_line)
        !> Path of the file.
        character(len=*), intent(in) :: path
        !> Rows and columns announced.
        integer, intent(out) :: nrows, ncols
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> The entries the size line announces (coordinate), or rows x cols (array).
        integer(int64), intent(out), optional :: entries
        !> Line number of the size line.
        integer, intent(out), optional :: size_line
        type(sparse_matrix_t) :: a
        integer(int64) :: announced
        integer :: line_of_size
        announced = 0
        line_of_size = 0
        call read_file(path, .true., 65536, a, error, entries_out=announced, &
                       size_line_out=line_of_size)
        nrows = a%nrows
        ncols = a%ncols
        if (present(entries)) entries = announced
        if (present(size_line)) size_line = line_of_size
    end subroutine read_matrix_market_size

    !> The reader: the whole file, or (size_only) the header and size line (a%nrows,
    !> a%ncols set, no entries); blocks of `chunk` bytes.
    subroutine read_file(path, size_only, chunk, a, error, symmetric, entries_out, &
                         size_line_out, progress)
        character(len=*), intent(in) :: path
        logical, intent(in) :: size_only
        integer, intent(in) :: chunk
        type(sparse_matrix_t), intent(out) :: a
        type(error_type), allocatable, intent(out) :: error
        logical, intent(out), optional :: symmetric
        integer(int64), intent(out), optional :: entries_out
        integer, intent(out), optional :: size_line_out
        type(progress_t), intent(inout), optional :: progress
        integer :: stat, line_no, size_line, k, m, n, i, j, tri_line, tri, nvals, ntok
        integer :: fi, fj, reads_reported, room, total
        integer(int64) :: announced, bytes, unit_bytes
        character(len=:), allocatable :: line, tok(:), msg
        character(len=16) :: format, field, symmetry
        logical :: sym, is_int, is_open, coordinate
        integer, allocatable :: rows(:), cols(:), lines(:)
        real(dp), allocatable :: vals(:)
        real(dp) :: v
        type(line_reader_t) :: lr
        type(decimal_powers_t) :: powers
        type(progress_t) :: reading

        if (present(symmetric)) symmetric = .false.
        inquire (file=path//'/.', exist=is_open)
        if (is_open) then
            call fatal_error(error, path//": a directory, not a Matrix Market file", &
                             stickslip_stat%input)
            return
        end if
        ! a pipe would block the open, a device be read forever: both report size 0, as
        ! an empty file does, and none is a Matrix Market file
        inquire (file=path, exist=is_open, size=bytes)
        if (is_open .and. bytes <= 0) then
            call fatal_error(error, path//": empty, or not a regular file (a pipe or a "// &
                             "device): expected a Matrix Market file", stickslip_stat%input)
            return
        end if
        call open_line_reader(lr, path, chunk, max_mm_line, stat, msg)
        if (stat /= 0) then
            call fatal_error(error, path//": cannot open the matrix file: "//msg, &
                             stickslip_stat%io)
            return
        end if
        is_open = .true.
        line_no = 0
        if (present(progress)) then
            reading = progress
            reading%label = "reading"
            ! MB for files of 10 MB and more (those that take long), kB or bytes below
            unit_bytes = 1000000_int64
            reading%items = "MB"
            if (lr%size < 10000000_int64) then
                unit_bytes = merge(1000_int64, 1_int64, lr%size >= 10000_int64)
                reading%items = trim(merge("kB   ", "bytes", lr%size >= 10000_int64))
            end if
            reading%lines = 0
            call reading%begin()
        end if
        reads_reported = 0
        ! the header
        call next_line(.false., stat)
        if (allocated(error)) return
        if (stat /= 0) then
            call fail(1, "empty file: expected the header '%%MatrixMarket matrix "// &
                      "coordinate|array real|integer general|symmetric'")
            return
        end if
        call split(line, tok, ntok)
        if (ntok < 1) then
            call bad_header()
            return
        end if
        if (lower(tok(1)) /= "%%matrixmarket") then
            call bad_header()
            return
        end if
        if (ntok /= 5) then
            call fail(line_no, "the header must have 5 words, '%%MatrixMarket matrix "// &
                      "<format> <field> <symmetry>'; got "//itoa(ntok))
            return
        end if
        if (lower(tok(2)) /= "matrix") then
            call fail(line_no, "object '"//trim(tok(2))//"' not supported (only 'matrix')")
            return
        end if
        format = lower(tok(3))
        field = lower(tok(4))
        symmetry = lower(tok(5))
        if (format /= "coordinate" .and. format /= "array") then
            call fail(line_no, "format '"//trim(tok(3))//"' not supported (coordinate or array)")
            return
        end if
        if (field /= "real" .and. field /= "double" .and. field /= "integer") then
            call fail(line_no, "field '"//trim(tok(4))//"' not supported (real or integer; "// &
                      "not complex nor pattern)")
            return
        end if
        if (symmetry /= "general" .and. symmetry /= "symmetric") then
            call fail(line_no, "symmetry '"//trim(tok(5))//"' not supported (general or "// &
                      "symmetric; not skew-symmetric nor hermitian)")
            return
        end if
        sym = symmetry == "symmetric"
        is_int = field == "integer"
        coordinate = format == "coordinate"
        if (present(symmetric)) symmetric = sym

        ! the size line
        call next_line(.true., stat)
        if (allocated(error)) return
        if (stat /= 0) then
            call fail(line_no, "end of file before the size line")
            return
        end if
        size_line = line_no
        call split(line, tok, ntok)
        if (format == "coordinate") then
            if (ntok /= 3) then
                call fail(line_no, "size line must be 'rows columns entries' (3 integers); "// &
                          "got '"//clip(line)//"'")
                return
            end if
        else if (ntok /= 2) then
            call fail(line_no, "size line must be 'rows columns' (2 integers) for an array "// &
                      "file; got '"//clip(line)//"'")
            return
        end if
        if (.not. (to_int(tok(1), m) .and. to_int(tok(2), n))) then
            call fail(line_no, "size line: not integers: '"//clip(line)//"'")
            return
        end if
        if (m < 0 .or. n < 0) then
            call fail(line_no, "size line: negative size "//itoa(m)//" x "//itoa(n))
            return
        end if
        if (sym .and. m /= n) then
            call fail(line_no, "a symmetric matrix must be square; the size line says "// &
                      itoa(m)//" x "//itoa(n))
            return
        end if
        if (format == "coordinate") then
            if (.not. to_int64(tok(3), announced)) then
                call fail(line_no, "size line: entry count '"//clip(tok(3))//"' not an integer")
                return
            end if
            if (announced < 0) then
                call fail(line_no, "size line: negative entry count "//trim(tok(3)))
                return
            end if
            if (announced > max_mm_entries) then
                call fail(line_no, "size line: "//trim(tok(3))//" entries, more than "// &
                          "10**8 (the most this version reads)")
                return
            end if
            if (announced > int(m, int64)*int(n, int64)) then
                call fail(line_no, "size line: "//trim(tok(3))//" entries, more than the "// &
                          itoa(m)//" x "//itoa(n)//" matrix holds")
                return
            end if
            nvals = int(announced)
        else
            if (int(m, int64)*int(n, int64) > max_dense_entries) then
                call fail(line_no, "size line: a dense "//itoa(m)//" x "//itoa(n)// &
                          " array is larger than 2**25 values (256 MiB), the most this "// &
                          "version reads")
                return
            end if
            if (sym) then
                nvals = n*(n + 1)/2
            else
                nvals = m*n
            end if
        end if

        if (present(size_line_out)) size_line_out = size_line
        if (present(entries_out)) then
            if (format == "coordinate") then
                entries_out = announced
            else
                entries_out = int(m, int64)*int(n, int64)
            end if
        end if
        if (size_only) then
            call lr%close()
            a%nrows = m
            a%ncols = n
            return
        end if
        ! the entries
        ! room for as many entries as the file can hold (an entry line takes at least 6
        ! bytes, 'i j v' and its end, a value line 2): a size line that claims more than
        ! the file holds costs at most about 3 times the file's size before the end of the
        ! file says so. A symmetric file gets room for the mirrored entries too (appended
        ! in place); the arrays grow (doubling up to nvals) should the room be short.
        room = int(min(int(nvals, int64), lr%size/merge(6, 2, coordinate) + 1))
        allocate (rows(merge(2, 1, sym)*room), cols(merge(2, 1, sym)*room), &
                  vals(merge(2, 1, sym)*room), lines(room))
        tri = 0
        tri_line = 0
        i = 1
        j = 1
        do k = 1, nvals
            if (present(progress)) then
                if (lr%reads /= reads_reported) then
                    reads_reported = lr%reads
                    call reading%report(int(lr%done/unit_bytes), int(lr%size/unit_bytes), &
                                        path)
                end if
            end if
            ! the common line straight from the block; anything else line by line
            if (fast_entry(fi, fj, v)) then
                if (coordinate) then
                    i = fi
                    j = fj
                    if (.not. in_range()) return
                end if
            else
                call next_line(.true., stat)
                if (allocated(error)) return
                if (stat /= 0) then
                    call fail(line_no, "end of file after "//itoa(k - 1)//" of the "// &
                              itoa(nvals)//" entries announced on line "//itoa(size_line))
                    return
                end if
                call split(line, tok, ntok)
                if (coordinate) then
                    if (ntok /= 3) then
                        call fail(line_no, "an entry must be 'row column value'; got '"// &
                                  clip(line)//"'")
                        return
                    end if
                    if (.not. (to_int(tok(1), i) .and. to_int(tok(2), j))) then
                        call fail(line_no, "row and column must be integers; got '"// &
                                  clip(line)//"'")
                        return
                    end if
                    if (.not. in_range()) return
                    if (.not. value_of(tok(3), v, line_no)) return
                else
                    if (ntok /= 1) then
                        call fail(line_no, "an array file has one value per line; got '"// &
                                  clip(line)//"'")
                        return
                    end if
                    if (.not. value_of(tok(1), v, line_no)) return
                end if
            end if
            if (coordinate .and. sym .and. i /= j) then
                if (tri == 0) then
                    tri = merge(1, 2, i > j)
                    tri_line = line_no
                else if (merge(1, 2, i > j) /= tri) then
                    call fail(line_no, "entry ("//itoa(i)//","//itoa(j)//") is in the "// &
                              trim(merge("lower", "upper", i > j))//" triangle, but line "// &
                              itoa(tri_line)//" gave one in the "// &
                              trim(merge("lower", "upper", tri == 1))//" triangle: a "// &
                              "symmetric file gives one triangle only (non-symmetric "// &
                              "data in a file declared symmetric?)")
                    return
                end if
            end if
            if (k > size(lines)) call grow(min(2*size(lines), nvals))
            rows(k) = i
            cols(k) = j
            vals(k) = v
            lines(k) = line_no
            if (.not. coordinate) then
                ! next position, column by column (lower triangle when symmetric)
                i = i + 1
                if (i > m) then
                    j = j + 1
                    i = merge(j, 1, sym)
                end if
            end if
        end do
        call next_line(.true., stat)
        if (allocated(error)) return
        if (stat == 0) then
            call fail(line_no, "more entries than the "//itoa(nvals)//" announced on line "// &
                      itoa(size_line))
            return
        end if
        call lr%close()
        is_open = .false.
        if (present(progress)) progress%lines = progress%lines + reading%lines
        if (sym .and. coordinate) then
            call reject_duplicates()
            if (allocated(error)) return
        end if
        total = nvals
        ! mirror the off-diagonal entries: full storage
        if (sym) call mirror()
        call new_sparse_from_triplets(a, m, n, rows(1:total), cols(1:total), vals(1:total), &
                                      error)
        if (allocated(error)) error%message = path//": "//error%message

    contains

        !> The entry arrays enlarged to hold `m` entries (rows, cols, vals at least; lines
        !> exactly), their contents kept.
        subroutine grow(m)
            integer, intent(in) :: m
            integer, allocatable :: ibig(:)
            real(dp), allocatable :: rbig(:)
            if (m > size(rows)) then
                allocate (ibig(m))
                ibig(1:size(rows)) = rows
                call move_alloc(ibig, rows)
                allocate (ibig(m))
                ibig(1:size(cols)) = cols
                call move_alloc(ibig, cols)
                allocate (rbig(m))
                rbig(1:size(vals)) = vals
                call move_alloc(rbig, vals)
            end if
            allocate (ibig(m))
            ibig(1:size(lines)) = lines
            call move_alloc(ibig, lines)
        end subroutine grow

        !> The entry line at the reader's position when it has the common form (blanks,
        !> `row column value` or `value` with plain unsigned indices of at most 9 digits, a
        !> value scan_decimal reads exactly, blanks, the line's end): true, the line
        !> consumed. Otherwise false and nothing consumed (the general path reads the line).
        logical function fast_entry(row, col, x) result(ok)
            integer, intent(out) :: row, col
            real(dp), intent(out) :: x
            integer :: p
            logical :: got
            ok = .false.
            row = 0
            col = 0
            x = 0.0_dp
            call lr%ensure()
            if (lr%stat /= 0) return
            p = lr%pos
            call skip_blanks(p)
            if (coordinate) then
                call scan_digits(lr%text(1:lr%fill), p, row, got)
                if (.not. got) return
                if (.not. blank_at(p)) return
                call skip_blanks(p)
                call scan_digits(lr%text(1:lr%fill), p, col, got)
                if (.not. got) return
                if (.not. blank_at(p)) return
                call skip_blanks(p)
            end if
            call scan_decimal(lr%text(1:lr%fill), p, powers, is_int, x, got)
            if (.not. got) return
            call skip_blanks(p)
            if (.not. lr%end_line(p)) return
            line_no = lr%line_no
            ok = .true.
        end function fast_entry

        !> p moved past blanks and tabs.
        subroutine skip_blanks(p)
            integer, intent(inout) :: p
            integer :: c
            do while (p <= lr%fill)
                c = iachar(lr%text(p:p))
                if (c /= 32 .and. c /= 9) exit
                p = p + 1
            end do
        end subroutine skip_blanks

        logical function blank_at(p)
            integer, intent(in) :: p
            integer :: c
            blank_at = .false.
            if (p > lr%fill) return
            c = iachar(lr%text(p:p))
            blank_at = c == 32 .or. c == 9
        end function blank_at

        !> (i, j) inside the matrix; else an error.
        logical function in_range()
            in_range = .not. (i < 1 .or. i > m .or. j < 1 .or. j > n)
            if (.not. in_range) call fail(line_no, "entry ("//itoa(i)//","//itoa(j)// &
                                          ") outside the "//itoa(m)//" x "//itoa(n)// &
                                          " matrix (indices are 1-based)")
        end function in_range

        !> The next line into `line` (stat /= 0 at the end of the file); skips `%` comments
        !> and blank lines when `skip`. Sets error on a read failure, an overlong line, a
        !> non-printable byte.
        subroutine next_line(skip, stat)
            logical, intent(in) :: skip
            integer, intent(out) :: stat
            integer :: c, p, first, last
            do
                call lr%next_line(first, last, stat)
                select case (stat)
                case (line_end_of_file)
                    return
                case (line_too_long)
                    call fail(line_no + 1, "line longer than "//itoa(max_mm_line)// &
                              " characters (not a Matrix Market file?)")
                    stat = 1
                    return
                case (line_read_error)
                    call fatal_error(error, path//":"//itoa(line_no + 1)//": cannot read: "// &
                                     lr%msg, stickslip_stat%io)
                    call lr%close()
                    is_open = .false.
                    return
                end select
                stat = 0
                line_no = lr%line_no
                line = lr%text(first:last)
                do p = 1, len(line)
                    c = iachar(line(p:p))
                    if (c == 9) then
                        line(p:p) = ' '
                    else if (c < 32 .or. c > 126) then
                        call fail(line_no, "non-printable or non-ASCII byte (not a Matrix "// &
                                  "Market text file?)")
                        stat = 1
                        return
                    end if
                end do
                if (.not. skip) return
                p = verify(line, ' ')
                if (p == 0) cycle
                if (line(p:p) == '%') cycle
                return
            end do
        end subroutine next_line

        !> A finite real from token s (an integer when the field is integer).
        logical function value_of(s, x, at) result(ok)
            character(len=*), intent(in) :: s
            real(dp), intent(out) :: x
            integer, intent(in) :: at
            integer :: st
            ok = .false.
            x = 0.0_dp
            if (is_int) then
                if (len_trim(s) == 0 .or. verify(trim(s), "+-0123456789") /= 0) then
                    call fail(at, "value '"//clip(s)//"' is not an integer (the header "// &
                              "says field integer)")
                    return
                end if
            else if (len_trim(s) == 0 .or. verify(lower(trim(s)), "+-0123456789.edinfaty") /= 0) then
                call fail(at, "value '"//clip(s)//"' is not a real number")
                return
            end if
            read (s, *, iostat=st) x
            if (st /= 0) then
                call fail(at, "value '"//clip(s)//"' is not a real number")
                return
            end if
            if (.not. ieee_is_finite(x)) then
                call fail(at, "value '"//clip(s)//"' is not a finite number (NaN or Inf)")
                return
            end if
            ok = .true.
        end function value_of

        !> Duplicates of a symmetric coordinate file: an error naming both lines. Entries
        !> in strictly increasing order, by rows or by columns (as FE codes write them),
        !> have none: checked in one pass before any sort.
        subroutine reject_duplicates()
            integer(int64), allocatable :: key(:)
            integer, allocatable :: order(:)
            integer :: q, p1, p2
            if (increasing(rows(1:nvals), cols(1:nvals)) .or. &
                increasing(cols(1:nvals), rows(1:nvals))) return
            key = int(rows(1:nvals) - 1, int64)*int(max(n, 1), int64) + int(cols(1:nvals), int64)
            call sort_order(key, order)
            do q = 2, size(order)
                p1 = order(q - 1)
                p2 = order(q)
                if (key(p1) == key(p2)) then
                    call fail(max(lines(p1), lines(p2)), "entry ("//itoa(rows(p2))//","// &
                              itoa(cols(p2))//") given twice (lines "// &
                              itoa(min(lines(p1), lines(p2)))//" and "// &
                              itoa(max(lines(p1), lines(p2)))//"): duplicates are rejected "// &
                              "in a symmetric file")
                    return
                end if
            end do
        end subroutine reject_duplicates

        !> The off-diagonal entries (i, j) appended as (j, i), in the order read; `total`
        !> entries in all.
        subroutine mirror()
            integer :: q
            integer, allocatable :: ibig(:)
            real(dp), allocatable :: rbig(:)
            total = nvals + count(rows(1:nvals) /= cols(1:nvals))
            if (total > size(rows)) then
                allocate (ibig(total))
                ibig(1:nvals) = rows(1:nvals)
                call move_alloc(ibig, rows)
                allocate (ibig(total))
                ibig(1:nvals) = cols(1:nvals)
                call move_alloc(ibig, cols)
                allocate (rbig(total))
                rbig(1:nvals) = vals(1:nvals)
                call move_alloc(rbig, vals)
            end if
            total = nvals
            do q = 1, nvals
                if (rows(q) == cols(q)) cycle
                total = total + 1
                rows(total) = cols(q)
                cols(total) = rows(q)
                vals(total) = vals(q)
            end do
        end subroutine mirror

        subroutine bad_header()
            call fail(line_no, "missing header: the first line must be '%%MatrixMarket "// &
                      "matrix coordinate|array real|integer general|symmetric'; got '"// &
                      clip(line)//"'")
        end subroutine bad_header

        subroutine fail(at, message)
            integer, intent(in) :: at
            character(len=*), intent(in) :: message
            call fatal_error(error, path//":"//itoa(at)//": "//message, stickslip_stat%input)
            if (is_open) call lr%close()
            is_open = .false.
        end subroutine fail
    end subroutine read_file

    !> Write `a` to `path` as `coordinate real general`, or `coordinate real symmetric` (the
    !> lower triangle, i >= j) when `symmetric`. Values with 17 significant digits. Errors:
    !> stat input when `symmetric` and a is not symmetric (defect above 1e-14 of its
    !> largest entry); stat io when the file cannot be written.
    subroutine write_matrix_market(path, a, symmetric, error)
        !> Path of the file (replaced).
        character(len=*), intent(in) :: path
        !> The matrix.
        type(sparse_matrix_t), intent(in) :: a
        !> Write the lower triangle of a symmetric matrix.
        logical, intent(in) :: symmetric
        !> Set on a failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, i, p, count
        character(len=512) :: msg
        if (symmetric) then
            if (.not. (sparse_symmetry_defect(a) <= 1.0e-14_dp)) then
                call fatal_error(error, path//": cannot write a non-symmetric matrix as "// &
                                 "symmetric", stickslip_stat%input)
                return
            end if
        end if
        count = 0
        do i = 1, a%nrows
            do p = a%row_start(i), a%row_start(i + 1) - 1
                if (.not. symmetric .or. a%col(p) <= i) count = count + 1
            end do
        end do
        u = -1
        open (newunit=u, file=path, status='replace', action='write', iostat=stat, iomsg=msg)
        if (stat /= 0) u = -1
        if (stat == 0) write (u, '(a)', iostat=stat, iomsg=msg) "%%MatrixMarket matrix "// &
            "coordinate real "//trim(merge("symmetric", "general  ", symmetric))
        if (stat == 0) write (u, '(a)', iostat=stat, iomsg=msg) "% written by stickslip"
        if (stat == 0) write (u, '(i0,1x,i0,1x,i0)', iostat=stat, iomsg=msg) a%nrows, &
            a%ncols, count
        do i = 1, a%nrows
            if (stat /= 0) exit
            do p = a%row_start(i), a%row_start(i + 1) - 1
                if (symmetric .and. a%col(p) > i) cycle
                write (u, '(i0,1x,i0,1x,es25.17e3)', iostat=stat, iomsg=msg) i, a%col(p), &
                    a%val(p)
                if (stat /= 0) exit
            end do
        end do
        call finish(u, path, stat, msg, error)
    end subroutine write_matrix_market

    !> Write the dense matrix `d` to `path` as `array real general` (every value, column by
    !> column), or `array real symmetric` (the lower triangle, column by column) when
    !> `symmetric`. Errors: stat input when `symmetric` and d is not square and symmetric
    !> (to 1e-14 of its largest entry); stat io when the file cannot be written.
    subroutine write_matrix_market_array(path, d, symmetric, error)
        !> Path of the file (replaced).
        character(len=*), intent(in) :: path
        !> The matrix.
        real(dp), intent(in) :: d(:, :)
        !> Write the lower triangle of a symmetric matrix.
        logical, intent(in) :: symmetric
        !> Set on a failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, i, j
        character(len=512) :: msg
        if (symmetric) then
            if (size(d, 1) /= size(d, 2)) then
                call fatal_error(error, path//": cannot write a non-square matrix as "// &
                                 "symmetric", stickslip_stat%input)
                return
            end if
            if (size(d) > 0) then
                if (.not. (maxval(abs(d - transpose(d))) <= 1.0e-14_dp*maxval(abs(d)))) then
                    call fatal_error(error, path//": cannot write a non-symmetric matrix "// &
                                     "as symmetric", stickslip_stat%input)
                    return
                end if
            end if
        end if
        u = -1
        open (newunit=u, file=path, status='replace', action='write', iostat=stat, iomsg=msg)
        if (stat /= 0) u = -1
        if (stat == 0) write (u, '(a)', iostat=stat, iomsg=msg) "%%MatrixMarket matrix "// &
            "array real "//trim(merge("symmetric", "general  ", symmetric))
        if (stat == 0) write (u, '(a)', iostat=stat, iomsg=msg) "% written by stickslip"
        if (stat == 0) write (u, '(i0,1x,i0)', iostat=stat, iomsg=msg) size(d, 1), size(d, 2)
        do j = 1, size(d, 2)
            if (stat /= 0) exit
            do i = merge(j, 1, symmetric), size(d, 1)
                write (u, '(es25.17e3)', iostat=stat, iomsg=msg) d(i, j)
                if (stat /= 0) exit
            end do
        end do
        call finish(u, path, stat, msg, error)
    end subroutine write_matrix_market_array

    subroutine finish(u, path, stat, msg, error)
        integer, intent(in) :: u
        character(len=*), intent(in) :: path
        integer, intent(inout) :: stat
        character(len=*), intent(inout) :: msg
        type(error_type), allocatable, intent(out) :: error
        integer :: st2
        if (u /= -1) then
            close (u, iostat=st2)
            if (stat == 0 .and. st2 /= 0) then
                stat = st2
                msg = "close failed"
            end if
        end if
        if (stat /= 0) call fatal_error(error, path//": cannot write the matrix file: "// &
                                        trim(msg), stickslip_stat%io)
    end subroutine finish

    !> The blank-separated words of s.
    subroutine split(s, words, n)
        character(len=*), intent(in) :: s
        character(len=:), allocatable, intent(out) :: words(:)
        integer, intent(out) :: n
        integer :: i, j, k, longest
        n = 0
        longest = 1
        i = 1
        do while (i <= len(s))
            if (s(i:i) == ' ') then
                i = i + 1
                cycle
            end if
            j = i
            do while (j < len(s))
                if (s(j + 1:j + 1) == ' ') exit
                j = j + 1
            end do
            n = n + 1
            longest = max(longest, j - i + 1)
            i = j + 1
        end do
        allocate (character(len=longest) :: words(max(n, 1)))
        words = ""
        k = 0
        i = 1
        do while (i <= len(s))
            if (s(i:i) == ' ') then
                i = i + 1
                cycle
            end if
            j = i
            do while (j < len(s))
                if (s(j + 1:j + 1) == ' ') exit
                j = j + 1
            end do
            k = k + 1
            words(k) = s(i:j)
            i = j + 1
        end do
    end subroutine split

    !> An integer from the token s (digits with an optional sign, in range).
    logical function to_int(s, i) result(ok)
        character(len=*), intent(in) :: s
        integer, intent(out) :: i
        integer :: st
        i = 0
        ok = .false.
        if (len_trim(s) == 0 .or. verify(trim(s), "+-0123456789") /= 0) return
        read (s, *, iostat=st) i
        ok = st == 0
    end function to_int

    logical function to_int64(s, i) result(ok)
        character(len=*), intent(in) :: s
        integer(int64), intent(out) :: i
        integer :: st
        i = 0
        ok = .false.
        if (len_trim(s) == 0 .or. verify(trim(s), "+-0123456789") /= 0) return
        read (s, *, iostat=st) i
        ok = st == 0
    end function to_int64

    !> The pairs (major(k), minor(k)) are strictly increasing in k (lexicographic order).
    pure logical function increasing(major, minor)
        integer, intent(in) :: major(:), minor(:)
        integer :: k
        increasing = .false.
        do k = 2, size(major)
            if (major(k) < major(k - 1)) return
            if (major(k) == major(k - 1) .and. minor(k) <= minor(k - 1)) return
        end do
        increasing = .true.
    end function increasing

    !> The order that sorts key increasingly (stable bottom-up merge sort).
    subroutine sort_order(key, order)
        integer(int64), intent(in) :: key(:)
        integer, allocatable, intent(out) :: order(:)
        integer, allocatable :: tmp(:)
        integer :: n, width, lo, mid, hi, i, j, k
        n = size(key)
        order = [(i, i=1, n)]
        allocate (tmp(n))
        width = 1
        do while (width < n)
            lo = 1
            do while (lo <= n)
                mid = min(lo + width - 1, n)
                hi = min(lo + 2*width - 1, n)
                i = lo
                j = mid + 1
                k = lo
                do while (k <= hi)
                    if (j > hi) then
                        tmp(k) = order(i); i = i + 1
                    else if (i > mid) then
                        tmp(k) = order(j); j = j + 1
                    else if (key(order(j)) < key(order(i))) then
                        tmp(k) = order(j); j = j + 1
                    else
                        tmp(k) = order(i); i = i + 1
                    end if
                    k = k + 1
                end do
                lo = lo + 2*width
            end do
            order = tmp
            width = 2*width
        end do
    end subroutine sort_order

    !> s cut to 40 characters for a message.
    pure function clip(s) result(t)
        character(len=*), intent(in) :: s
        character(len=:), allocatable :: t
        t = trim(adjustl(s))
        if (len(t) > 40) t = t(1:40)//"..."
    end function clip

    pure function lower(s) result(t)
        character(len=*), intent(in) :: s
        character(len=len(s)) :: t
        integer :: i
        t = s
        do i = 1, len(s)
            if (s(i:i) >= 'A' .and. s(i:i) <= 'Z') t(i:i) = achar(iachar(s(i:i)) + 32)
        end do
    end function lower
end module stickslip_matrix_market
