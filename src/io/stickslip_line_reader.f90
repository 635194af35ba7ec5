!> The lines of a text file read in large binary blocks (`access='stream'`), for readers of
!> large files that parse the bytes themselves (stickslip_matrix_market): one `read` per
!> block of `chunk` bytes instead of one formatted read per line. Line ends are those of
!> gfortran's formatted reads: LF, CR LF and a lone CR each end a line; the last line needs
!> none. Lines hold at most `max_line` characters (the terminator not counted).
!>
!> The buffer `text(1:fill)` holds the bytes not consumed from `pos` on; `ensure` keeps at
!> least max_line + 2 of them there (or all that is left of the file), so that a whole line
!> and its terminator are always in the buffer and a parser can scan a line without
!> looking for its end first (`end_line` then checks and consumes the terminator). Knows
!> nothing of what the lines mean; prints nothing.
module stickslip_line_reader
    use, intrinsic :: iso_fortran_env, only: int64, iostat_end
    implicit none
    private
    public :: line_reader_t, open_line_reader, default_chunk_bytes
    public :: line_ok, line_end_of_file, line_too_long, line_read_error

    !> Bytes read at once unless the caller says otherwise (8 MiB).
    integer, parameter :: default_chunk_bytes = 8*1024*1024
    !> Outcomes of next_line: a line; the end of the file; a line longer than max_line;
    !> a read error (message in `msg`).
    integer, parameter :: line_ok = 0, line_end_of_file = iostat_end, line_too_long = 1, &
        line_read_error = 2

    !> An open file read by blocks. The parser reads text(pos:fill) directly.
    type :: line_reader_t
        !> The unit (-1: closed).
        integer :: unit = -1
        !> The buffer: bytes pos..fill are read and not yet consumed.
        character(len=:), allocatable :: text
        !> First byte not consumed.
        integer :: pos = 1
        !> Last byte read into `text`.
        integer :: fill = 0
        !> Bytes per read.
        integer :: chunk = default_chunk_bytes
        !> Longest line [characters].
        integer :: max_line = 4096
        !> Size of the file and bytes read so far [bytes].
        integer(int64) :: size = 0, done = 0
        !> Reads made (changes when a block arrives: a cue for progress reports).
        integer :: reads = 0
        !> Lines consumed.
        integer :: line_no = 0
        !> A read failed (iostat), and gfortran's message; later calls fail the same way.
        integer :: stat = 0
        character(len=:), allocatable :: msg
    contains
        !> At least max_line + 2 bytes (or the rest of the file) after pos.
        procedure :: ensure => reader_ensure
        !> The next line: its bounds in `text`, consumed.
        procedure :: next_line => reader_next_line
        !> A line scanned by the caller ends at the given byte: consume it.
        procedure :: end_line => reader_end_line
        !> Close the file (idempotent).
        procedure :: close => reader_close
    end type line_reader_t

contains

    !> Open `path` for reading by blocks of `chunk` bytes with lines of at most `max_line`
    !> characters. stat /= 0 and gfortran's message in `msg` when it cannot be opened.
    subroutine open_line_reader(self, path, chunk, max_line, stat, msg)
        !> The reader.
        type(line_reader_t), intent(out) :: self
        !> The file.
        character(len=*), intent(in) :: path
        !> Bytes per read (taken into 1 .. 2**30).
        integer, intent(in) :: chunk
        !> Longest line [characters] (>= 1).
        integer, intent(in) :: max_line
        !> 0, or the iostat of the failed open.
        integer, intent(out) :: stat
        !> Why the open failed.
        character(len=:), allocatable, intent(out) :: msg
        character(len=512) :: buffer
        self%chunk = min(max(chunk, 1), 2**30)
        self%max_line = max(max_line, 1)
        open (newunit=self%unit, file=path, status='old', action='read', access='stream', &
              form='unformatted', iostat=stat, iomsg=buffer)
        if (stat /= 0) then
            self%unit = -1
            msg = trim(buffer)
            return
        end if
        inquire (unit=self%unit, size=self%size)
        self%size = max(self%size, 0_int64)
        allocate (character(len=self%chunk + self%max_line + 2) :: self%text)
        msg = ""
    end subroutine open_line_reader

    !> Read blocks until at least max_line + 2 bytes follow pos or the file is all read;
    !> the bytes before pos are dropped. A failed read sets `stat` and `msg`.
    subroutine reader_ensure(self)
        !> The reader.
        class(line_reader_t), intent(inout) :: self
        integer :: n
        character(len=512) :: buffer
        if (self%fill - self%pos + 1 >= self%max_line + 2) return
        if (self%done >= self%size .or. self%stat /= 0 .or. self%unit == -1) return
        if (self%pos > 1) then
            n = self%fill - self%pos + 1
            if (n > 0) self%text(1:n) = self%text(self%pos:self%fill)
            self%fill = n
            self%pos = 1
        end if
        do while (self%fill - self%pos + 1 < self%max_line + 2 .and. self%done < self%size)
            n = int(min(int(self%chunk, int64), int(len(self%text) - self%fill, int64), &
                        self%size - self%done))
            read (self%unit, iostat=self%stat, iomsg=buffer) self%text(self%fill + 1:self%fill + n)
            if (self%stat /= 0) then
                if (self%stat == iostat_end) then
                    self%msg = "the file ended before its "//size_text(self%size)// &
                               " bytes (changed while read?)"
                else
                    self%msg = trim(buffer)
                end if
                return
            end if
            self%fill = self%fill + n
            self%done = self%done + n
            self%reads = self%reads + 1
        end do
    end subroutine reader_ensure

    !> The next line, text(first:last) (last = first - 1: an empty line), consumed; `stat`
    !> line_ok, line_end_of_file, line_too_long (nothing consumed) or line_read_error (see
    !> `msg`). The bounds hold until the next call.
    subroutine reader_next_line(self, first, last, stat)
        !> The reader.
        class(line_reader_t), intent(inout) :: self
        !> The line is text(first:last).
        integer, intent(out) :: first, last
        !> What was found.
        integer, intent(out) :: stat
        integer :: k, stop_at
        character :: c
        first = 1
        last = 0
        call self%ensure()
        if (self%stat /= 0) then
            stat = line_read_error
            return
        end if
        if (self%pos > self%fill) then
            stat = line_end_of_file
            return
        end if
        stop_at = min(self%fill, self%pos + self%max_line)
        do k = self%pos, stop_at
            c = self%text(k:k)
            if (c == achar(10) .or. c == achar(13)) then
                first = self%pos
                last = k - 1
                self%pos = k + 1
                if (c == achar(13) .and. k < self%fill) then
                    if (self%text(k + 1:k + 1) == achar(10)) self%pos = k + 2
                end if
                self%line_no = self%line_no + 1
                stat = line_ok
                return
            end if
        end do
        if (self%fill - self%pos + 1 > self%max_line) then
            stat = line_too_long
            return
        end if
        ! the last line, without a terminator (ensure read the whole rest of the file)
        first = self%pos
        last = self%fill
        self%pos = self%fill + 1
        self%line_no = self%line_no + 1
        stat = line_ok
    end subroutine reader_next_line

    !> The caller scanned the line from pos up to (not including) byte k: when k is its end
    !> (a terminator, or the end of the file) and the line is not too long, consume the line
    !> and its terminator and return true; otherwise change nothing and return false.
    logical function reader_end_line(self, k) result(ended)
        !> The reader.
        class(line_reader_t), intent(inout) :: self
        !> The byte after the scanned characters.
        integer, intent(in) :: k
        character :: c
        ended = .false.
        if (k - self%pos > self%max_line) return
        if (k > self%fill) then
            if (self%done < self%size .or. self%stat /= 0) return
            self%pos = k
        else
            c = self%text(k:k)
            if (c == achar(10)) then
                self%pos = k + 1
            else if (c == achar(13)) then
                self%pos = k + 1
                if (k < self%fill) then
                    if (self%text(k + 1:k + 1) == achar(10)) self%pos = k + 2
                end if
            else
                return
            end if
        end if
        self%line_no = self%line_no + 1
        ended = .true.
    end function reader_end_line

    !> Close the file and free the buffer.
    subroutine reader_close(self)
        !> The reader.
        class(line_reader_t), intent(inout) :: self
        integer :: stat
        if (self%unit /= -1) close (self%unit, iostat=stat)
        self%unit = -1
        if (allocated(self%text)) deallocate (self%text)
        self%pos = 1
        self%fill = 0
    end subroutine reader_close

    pure function size_text(n) result(s)
        integer(int64), intent(in) :: n
        character(len=:), allocatable :: s
        character(len=24) :: buffer
        write (buffer, '(i0)') n
        s = trim(buffer)
    end function size_text
end module stickslip_line_reader
