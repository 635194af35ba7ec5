!> The checkpoint of a sweep: `<directory>/frc.checkpoint`, rewritten (atomically) after the
!> first point of a forced-response curve and then at most once a second, so that a batch
!> job cut off by its wall-time limit resumes where it stopped when it is run again on the
!> same case. The file holds a fingerprint of the case (model, &hbm, &sweep range and steps,
!> &reference): a checkpoint of another case is refused, never silently continued, and so is
!> a damaged one (every count is checked before anything is allocated). Text, full double
!> precision.
module stickslip_checkpoint
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_case, only: case_t, write_case
    use stickslip_continuation, only: continuation_state_t
    use stickslip_sweep, only: sweep_result_t, sweep_observer_t, frc_point_t
    use stickslip_files, only: open_temporary, close_and_rename, remove_file
    use stickslip_hbm, only: hbm_max_harmonics
    use stickslip_diagnostics, only: level_warning, level_untrusted
    use stickslip_csv, only: real_fmt
    implicit none
    private
    public :: checkpoint_writer_t, case_fingerprint, read_checkpoint, remove_checkpoint
    public :: checkpoint_name, family_checkpoint_name

    !> File name of the checkpoint in the output directory.
    character(len=*), parameter :: checkpoint_name = "frc.checkpoint"
    character(len=*), parameter :: magic = "stickslip sweep checkpoint 3"
    !> The first lines of checkpoints of earlier versions of stickslip: before the points
    !> held their Fourier coefficients (1), before they held their checks' verdict (2);
    !> refused with their own message.
    character(len=*), parameter :: magic_1 = "stickslip sweep checkpoint 1", &
                                   magic_2 = "stickslip sweep checkpoint 2"

    !> Writes the checkpoint after a point of a sweep: after the first, then whenever
    !> `interval` seconds of wall time, and 20 times the last write's own time, have passed
    !> since the last write. The file holds every point so far, so writing it after every
    !> point would cost O(points^2) (a reduced FE model's 400 points with their Fourier
    !> coefficients take about 0.5 s to write): writing costs at most 5 % of the sweep, and a
    !> job cut off loses at most max(interval, 20 x write time) of work.
    type, extends(sweep_observer_t) :: checkpoint_writer_t
        !> Output directory.
        character(len=:), allocatable :: directory
        !> Fingerprint of the case.
        character(len=16) :: fingerprint = ''
        !> File name (default checkpoint_name; a family's curve k: family_checkpoint_name(k)).
        character(len=:), allocatable :: name
        !> Shortest wall time between two writes [s] (0: after every point, whatever a write
        !> costs).
        real(dp) :: interval = 1.0_dp
        !> system_clock count of the last write (-1: none yet) and its duration (counts).
        integer(int64) :: last = -1, cost = 0
    contains
        procedure :: observe => write_checkpoint
    end type checkpoint_writer_t

contains

    !> A hash (16 hexadecimal digits: two 32-bit FNV-1a hashes with different offsets, in
    !> exact integer arithmetic) of the effective case as written by write_case, without the
    !> variables that may change between a run and its resumption (&output directory, dofs, &sweep
    !> max_points, max_failures, resume, plot; dofs is kept for a reduced model, whose points
    !> hold the amplitudes of the selected DOFs only). A model read from Matrix Market files is
    !> echoed by its file names only, so its M, K and C values are hashed too (a file changed
    !> between a run and its resumption gives another fingerprint).
    !> The echo goes through a scratch file, read back and checked byte for byte against
    !> what was written: a scratch file cut short (a full file system, a file size limit)
    !> would give another fingerprint, so it is an error (stat io) and fp is blank.
    function case_fingerprint(case, error) result(fp)
        !> The case.
        type(case_t), intent(in) :: case
        !> Set when the scratch file cannot be written or read back whole.
        type(error_type), allocatable, intent(out) :: error
        character(len=16) :: fp
        integer(int64), parameter :: prime = 16777619_int64, modulus = 4294967296_int64
        integer(int64) :: h(2), written, got
        integer :: u, stat, i, n
        character(len=4096) :: line, rest
        character(len=512) :: msg
        h = [2166136261_int64, 84696351_int64]
        fp = ''
        open (newunit=u, status='scratch', action='readwrite', iostat=stat, iomsg=msg)
        if (stat /= 0) then
            call fatal_error(error, "the case's fingerprint (for the checkpoint): cannot "// &
                             "open a scratch file: "//trim(msg), stickslip_stat%io)
            return
        end if
        call write_case(u, case, stat, msg)
        written = -1
        if (stat == 0) flush (u, iostat=stat)
        if (stat == 0) inquire (unit=u, size=written, iostat=stat)
        if (stat /= 0 .or. written < 0) then
            close (u, iostat=stat)
            call fatal_error(error, "the case's fingerprint (for the checkpoint): cannot "// &
                             "write the case to a scratch file: "//trim(msg), stickslip_stat%io)
            return
        end if
        rewind (u)
        got = 0
        do
            ! a record's first 4096 characters are hashed; every byte is counted
            read (u, '(a)', advance='no', size=n, iostat=stat) line
            got = got + n
            do while (stat == 0)
                read (u, '(a)', advance='no', size=n, iostat=stat) rest
                got = got + n
            end do
            if (.not. is_iostat_eor(stat)) exit
            got = got + 1
            line = adjustl(line)
            if (index(line, 'directory') == 1 .or. index(line, 'max_points') == 1 .or. &
                index(line, 'max_failures') == 1 .or. index(line, 'resume') == 1 .or. &
                index(line, 'plot') == 1) cycle
            ! the amplitudes of a reduced model's points are those of the selected DOFs
            if (index(line, 'dofs') == 1 .and. .not. allocated(case%reduction%output_rows)) &
                cycle
            do i = 1, len_trim(line)
                h = modulo(ieor(h, int(ichar(line(i:i)), int64))*prime, modulus)
            end do
        end do
        close (u)
        if (got /= written) then
            call fatal_error(error, "the case's fingerprint (for the checkpoint): the "// &
                             "scratch file holds "//itoa(got)//" bytes of the "// &
                             itoa(written)//" written (the file system is full, or a file "// &
                             "size limit was reached)", stickslip_stat%io)
            return
        end if
        if (allocated(case%sparse_model)) then
            ! the exact sparse condensation: the sparse values
            call mix(reshape(case%sparse_model%mass%val, [case%sparse_model%mass%nnz(), 1]))
            call mix(reshape(case%sparse_model%stiffness%val, &
                             [case%sparse_model%stiffness%nnz(), 1]))
            if (case%sparse_model%damping%nnz() > 0) call mix(reshape( &
                case%sparse_model%damping%val, [case%sparse_model%damping%nnz(), 1]))
        else if (allocated(case%system_files%mass_file)) then
            call mix(case%model%mass)
            call mix(case%model%stiffness)
            call mix(case%model%damping)
        end if
        ! directions and load shapes from files: the echo holds only the file names
        if (allocated(case%model%contact_direction)) call mix(case%model%contact_direction)
        if (allocated(case%model%force_shape)) call mix(case%model%force_shape)
        if (allocated(case%model%normal_direction)) call mix(case%model%normal_direction)
        if (allocated(case%model%tangent2_direction)) call mix(case%model%tangent2_direction)
        write (fp, '(2z8.8)') h

    contains

        !> Mix the bytes of every value of a into h.
        subroutine mix(a)
            real(dp), intent(in) :: a(:, :)
            integer :: p, q, b
            integer(int64) :: bits
            do q = 1, size(a, 2)
                do p = 1, size(a, 1)
                    bits = transfer(a(p, q), bits)
                    do b = 0, 7
                        h = modulo(ieor(h, iand(shiftr(bits, 8*b), 255_int64))*prime, modulus)
                    end do
                end do
            end do
        end subroutine mix
    end function case_fingerprint

    !> Save the curve so far into <directory>/frc.checkpoint (atomic). Error: stat io.
    subroutine write_checkpoint(self, res, error)
        !> The writer.
        class(checkpoint_writer_t), intent(inout) :: self
        !> The curve so far.
        type(sweep_result_t), intent(in) :: res
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, k, n
        integer(int64) :: now, rate, done
        character(len=512) :: msg
        character(len=*), parameter :: rf = '(*(' // real_fmt // ',:,1x))'
        call system_clock(now, rate)
        if (self%last >= 0 .and. self%interval > 0.0_dp) then
            if (real(now - self%last, dp) < max(self%interval*real(rate, dp), &
                                                20.0_dp*real(self%cost, dp))) return
        end if
        self%last = now
        stat = 0
        msg = ''
        if (.not. allocated(self%name)) self%name = checkpoint_name
        call open_temporary(self%directory, self%name, u, error)
        if (allocated(error)) return
        associate (st => res%state)
            n = size(st%y)
            write (u, '(a)', iostat=stat, iomsg=msg) magic
            if (stat == 0) write (u, '(a)', iostat=stat, iomsg=msg) self%fingerprint
            if (stat == 0) write (u, '(*(i0,:,1x))', iostat=stat, iomsg=msg) n, &
                size(res%points(1)%amplitude), size(res%points(1)%rmax), res%npoints, &
                st%reason, st%points, st%failures, st%rejected, res%folds
            if (stat == 0) write (u, rf, iostat=stat, iomsg=msg) st%lambda, st%tl, st%ds, &
                st%arclength, res%seconds, res%stability_seconds
            if (stat == 0) write (u, rf, iostat=stat, iomsg=msg) st%y
            if (stat == 0) write (u, rf, iostat=stat, iomsg=msg) st%ty
        end associate
        do k = 1, res%npoints
            if (stat /= 0) exit
            associate (p => res%points(k))
                write (u, '(a,1x,i0,1x,i0,1x,i0,1x,i0,1x,a)', iostat=stat, iomsg=msg) &
                    "'"//trim(p%status)//"'", p%harmonics, p%nfev, p%stable, p%check_level, &
                    "'"//trim(p%check)//"'"
                if (stat == 0) write (u, rf, iostat=stat, iomsg=msg) p%parameter, p%arclength, &
                    p%dissipation, p%diss_friction, p%diss_damping, p%residual, p%floquet_max, &
                    p%truncation, p%amplitude, p%rmax, p%stick
                ! contact laws: a line of open shares and largest normal forces
                if (stat == 0 .and. allocated(p%open)) write (u, rf, iostat=stat, iomsg=msg) &
                    p%open, p%normal_max
                ! the Fourier coefficients: counts and omega, harmonics, values
                if (stat == 0) write (u, '(i0,1x,i0,1x,' // real_fmt // ')', iostat=stat, &
                                      iomsg=msg) size(p%harmonic), size(p%rcoef, 2), p%omega
                if (stat == 0) write (u, '(*(i0,:,1x))', iostat=stat, iomsg=msg) p%harmonic
                if (stat == 0) write (u, rf, iostat=stat, iomsg=msg) p%xcoef, p%rcoef, p%ucoef
            end associate
        end do
        call close_and_rename(self%directory, self%name, u, stat, msg, error)
        call system_clock(done)
        self%cost = done - now
    end subroutine write_checkpoint

    !> Read <directory>/frc.checkpoint into `res` when it exists (found = .true.). Every
    !> count in the file is checked before anything is allocated: the numbers of DOFs and
    !> contacts against the case, the other counts against their bounds and against the
    !> size of the file (each value takes at least two characters). Errors: stat input when
    !> it belongs to another case (fingerprint), is not a checkpoint or is damaged (a count
    !> out of bounds, an unreadable value: "delete it"), stat io when it cannot be opened.
    subroutine read_checkpoint(directory, fingerprint, ndof, ncontact, res, found, error, &
                               laws, name)
        !> Output directory.
        character(len=*), intent(in) :: directory
        !> Fingerprint of the case being run.
        character(len=*), intent(in) :: fingerprint
        !> Degrees of freedom of the case's model.
        integer, intent(in) :: ndof
        !> Contacts of the case's model.
        integer, intent(in) :: ncontact
        !> The saved curve.
        type(sweep_result_t), intent(out) :: res
        !> A checkpoint was there.
        logical, intent(out) :: found
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The case has contact laws: each point has its line of open shares and largest
        !> normal forces (default .false.).
        logical, intent(in), optional :: laws
        !> File name (default checkpoint_name).
        character(len=*), intent(in), optional :: name
        character(len=:), allocatable :: path, problem
        character(len=128) :: line
        logical :: with_laws
        character(len=512) :: msg
        character(len=12) :: status
        character(len=32) :: check
        integer :: u, stat, n, nd, nc, k, npoints
        integer(int64) :: bytes
        type(frc_point_t) :: p
        path = directory//'/'//checkpoint_name
        if (present(name)) path = directory//'/'//name
        with_laws = .false.
        if (present(laws)) with_laws = laws
        inquire (file=path, exist=found, size=bytes)
        if (.not. found) return
        ! a checkpoint is a non-empty regular file: an empty file, a device (a link to
        ! /dev/zero would be read forever) or a pipe is refused before it is read
        if (bytes <= 0) then
            call fatal_error(error, path//": a damaged checkpoint (empty, or not a regular "// &
                             "file): delete it, or set &sweep resume = .false.", &
                             stickslip_stat%input)
            return
        end if
        open (newunit=u, file=path, status='old', action='read', iostat=stat, iomsg=msg)
        if (stat /= 0) then
            call fatal_error(error, path//": cannot open: "//trim(msg), stickslip_stat%io)
            return
        end if
        read (u, '(a)', iostat=stat) line
        if (stat == 0 .and. (line == magic_1 .or. line == magic_2)) then
            close (u)
            call fatal_error(error, path//": a checkpoint of an earlier version of stickslip "// &
                             "(without the points' Fourier coefficients or checks): delete "// &
                             "it, or set &sweep resume = .false.", stickslip_stat%input)
            return
        end if
        if (stat /= 0 .or. line /= magic) then
            close (u)
            call fatal_error(error, path//": not a stickslip sweep checkpoint (delete it)", &
                             stickslip_stat%input)
            return
        end if
        read (u, '(a)', iostat=stat) line
        if (stat /= 0 .or. trim(line) /= trim(fingerprint)) then
            close (u)
            call fatal_error(error, path//": a checkpoint of another case (the model, "// &
                             "&hbm, &sweep or &reference changed): delete it, or set "// &
                             "&sweep resume = .false. to start the curve again", &
                             stickslip_stat%input)
            return
        end if
        if (bytes < 0) bytes = huge(1_int64)
        problem = ""
        associate (st => res%state)
            read (u, *, iostat=stat, iomsg=msg) n, nd, nc, npoints, st%reason, &
                st%points, st%failures, st%rejected, res%folds
            if (stat /= 0) then
                problem = "its counts cannot be read"
            else if (nd /= ndof .or. nc /= ncontact) then
                problem = "its numbers of DOFs and contacts ("//itoa(nd)//", "//itoa(nc)// &
                          ") are not the case's ("//itoa(ndof)//", "//itoa(ncontact)//")"
            else if (n < 1 .or. 2_int64*n > bytes) then
                problem = "its number of unknowns ("//itoa(n)//") is out of bounds"
            else if (npoints < 1 .or. 2_int64*npoints*(13 + nd + 2*nc) > bytes) then
                problem = "its number of points ("//itoa(npoints)//") is out of bounds"
            else if (min(st%points, st%failures, st%rejected, res%folds) < 0) then
                problem = "a negative count"
            else if (st%points /= npoints) then
                ! every point of the curve is saved: a count that differs from the
                ! continuation's would resume with a gap in frc.csv
                problem = "it holds "//itoa(npoints)//" points, but its continuation "// &
                          "state counts "//itoa(st%points)
            end if
            if (len(problem) == 0) then
                res%npoints = npoints
                read (u, *, iostat=stat, iomsg=msg) st%lambda, st%tl, st%ds, &
                    st%arclength, res%seconds, res%stability_seconds
                if (stat == 0) then
                    allocate (st%y(n), st%ty(n))
                    read (u, *, iostat=stat, iomsg=msg) st%y
                end if
                if (stat == 0) read (u, *, iostat=stat, iomsg=msg) st%ty
            end if
        end associate
        if (len(problem) > 0) then
            close (u)
            call damaged(problem)
            return
        end if
        if (stat == 0) allocate (res%points(res%npoints))
        allocate (p%amplitude(nd), p%rmax(nc), p%stick(nc))
        do k = 1, res%npoints
            if (stat /= 0) exit
            read (u, *, iostat=stat, iomsg=msg) status, p%harmonics, p%nfev, p%stable, &
                p%check_level, check
            if (stat == 0) read (u, *, iostat=stat, iomsg=msg) p%parameter, p%arclength, &
                p%dissipation, p%diss_friction, p%diss_damping, p%residual, p%floquet_max, &
                p%truncation, p%amplitude, p%rmax, p%stick
            if (stat == 0 .and. with_laws) then
                if (.not. allocated(p%open)) allocate (p%open(nc), p%normal_max(nc))
                read (u, *, iostat=stat, iomsg=msg) p%open, p%normal_max
            end if
            if (stat == 0) then
                if (all(status /= [character(len=12) :: 'start', 'ok', 'halved', 'recovered', &
                                   'end'])) then
                    problem = "point "//itoa(k)//" has the status '"//trim(status)// &
                              "' (not start, ok, halved, recovered or end)"
                else if (p%harmonics < 0 .or. p%harmonics > hbm_max_harmonics) then
                    problem = "point "//itoa(k)//" has "//itoa(p%harmonics)//" harmonics "// &
                              "(not in 0 .. "//itoa(hbm_max_harmonics)//")"
                else if (p%stable < -1 .or. p%stable > 1) then
                    problem = "point "//itoa(k)//" has the stability flag "//itoa(p%stable)// &
                              " (not -1, 0 or 1)"
                else if (p%nfev < 0) then
                    problem = "point "//itoa(k)//" has a negative evaluation count"
                else if (all(p%check_level /= [0, level_warning, level_untrusted])) then
                    problem = "point "//itoa(k)//" has the check level "// &
                              itoa(p%check_level)//" (not 0, "//itoa(level_warning)//" or "// &
                              itoa(level_untrusted)//")"
                else if (verify(trim(check), "abcdefghijklmnopqrstuvwxyz0123456789_") /= 0) then
                    problem = "point "//itoa(k)//" names the check '"//trim(check)// &
                              "' (not a key)"
                end if
                p%check = check
                if (len(problem) > 0) exit
            end if
            if (stat == 0) call read_coefficients(p)
            if (len(problem) > 0) exit
            p%status = status
            res%points(k) = p
        end do
        close (u)
        if (len(problem) == 0 .and. stat /= 0) problem = "unreadable: "//trim(msg)
        if (len(problem) > 0) then
            call damaged(problem)
            return
        end if
        ! the values: finite where a curve holds numbers (floquet_max and truncation are NaN
        ! when not computed), and the last point where the continuation state stands
        problem = ""
        associate (st => res%state)
            if (.not. all(ieee_is_finite([st%lambda, st%tl, st%ds, st%arclength, st%y, &
                                          st%ty]))) problem = "a value of its continuation "// &
                                                               "state is not a finite number"
            do k = 1, res%npoints
                if (len(problem) > 0) exit
                associate (q => res%points(k))
                    if (.not. all(ieee_is_finite([q%parameter, q%arclength, q%dissipation, &
                                                  q%diss_friction, q%diss_damping, &
                                                  q%residual, q%amplitude, q%rmax, &
                                                  q%stick, q%omega, q%xcoef, q%rcoef, &
                                                  q%ucoef]))) &
                        problem = "point "//itoa(k)//" holds a value that is not a finite number"
                end associate
            end do
            if (len(problem) == 0) then
                if (res%points(res%npoints)%parameter /= st%lambda) problem = "its last "// &
                    "point is not where its continuation state stands"
            end if
        end associate
        if (len(problem) > 0) call damaged(problem)

    contains

        !> Refuse the checkpoint as damaged, saying why (no point taken from it).
        subroutine damaged(why)
            character(len=*), intent(in) :: why
            res%npoints = 0
            call fatal_error(error, path//": a damaged checkpoint ("//why//"): delete it, "// &
                             "or set &sweep resume = .false.", stickslip_stat%input)
        end subroutine damaged

        !> The coefficient lines of point `q` (counts checked against the contacts and the
        !> size of the file before anything is allocated; `problem` says what is wrong).
        subroutine read_coefficients(q)
            type(frc_point_t), intent(inout) :: q
            integer :: nb, nch
            read (u, *, iostat=stat, iomsg=msg) nb, nch, q%omega
            if (stat /= 0) return
            if (nb < 1 .or. nch < nc .or. nch > 3*nc .or. &
                2_int64*nb*(nd + 2*nch) > bytes) then
                problem = "a point's numbers of coefficients ("//itoa(nb)//", "//itoa(nch)// &
                          ") are out of bounds"
                return
            end if
            if (allocated(q%harmonic)) deallocate (q%harmonic, q%xcoef, q%rcoef, q%ucoef)
            allocate (q%harmonic(nb), q%xcoef(nb, nd), q%rcoef(nb, nch), q%ucoef(nb, nch))
            read (u, *, iostat=stat, iomsg=msg) q%harmonic
            if (stat == 0) read (u, *, iostat=stat, iomsg=msg) q%xcoef, q%rcoef, q%ucoef
            if (stat == 0 .and. (minval(q%harmonic) < 0 .or. q%harmonic(1) /= 0)) &
                problem = "a point's harmonic numbers are out of bounds"
        end subroutine read_coefficients
    end subroutine read_checkpoint

    !> Delete <directory>/frc.checkpoint (or <directory>/`name`) if present (the curve is
    !> finished).
    subroutine remove_checkpoint(directory, name)
        !> Output directory.
        character(len=*), intent(in) :: directory
        !> File name (default checkpoint_name).
        character(len=*), intent(in), optional :: name
        if (present(name)) then
            call remove_file(directory//'/'//name)
        else
            call remove_file(directory//'/'//checkpoint_name)
        end if
    end subroutine remove_checkpoint

    !> The checkpoint file name of curve k of a family: frc_family_<k>.checkpoint.
    pure function family_checkpoint_name(k) result(name)
        !> The curve (1..).
        integer, intent(in) :: k
        character(len=:), allocatable :: name
        name = "frc_family_"//itoa(k)//".checkpoint"
    end function family_checkpoint_name
end module stickslip_checkpoint
