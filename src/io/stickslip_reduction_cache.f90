!> The reduction cache: a Craig-Bampton model (its reduced matrices, its basis and what the
!> reduction and its error estimate reported) kept in one binary file, so that a second run
!> of the same model skips the reduction. Knows the file format and the hashing of input
!> files; what goes into the key is the caller's (stickslip_case_reduction).
!>
!> The file (unformatted stream, native byte order): the text 'stickslip reduction cache',
!> the format version and the integer 1 (another version or byte order reads as another
!> format), the 64-bit key, the sizes (n, nb, nm, nl, nr, number of error frequencies, of
!> nodal diameters measured), the boundary and interior DOFs, the reduced M, K, C, the
!> constraint modes, the modes and their frequencies, the load vectors, the modal damping
!> ratio, the report (a sector's with its error per nodal diameter), and last the FNV-1a
!> checksum of everything after the key. It is written under a temporary name (created
!> exclusively) and renamed over the final one, so a reader sees a whole file, an old or a
!> new one. A reader checks the header, the key, the file size against the sizes, the sizes
!> against each other and against N, the DOF lists, that every value is finite, and the
!> checksum: a file that fails is reported as damaged (with why) and never used.
module stickslip_reduction_cache
    use, intrinsic :: iso_fortran_env, only: int8, int32, int64
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_hash, only: hash_t
    use stickslip_reduced_model, only: reduced_model_t
    use stickslip_reduction, only: reduction_report_t
    use stickslip_files, only: open_temporary, close_and_rename
    implicit none
    private
    public :: hash_file, write_reduction_cache, read_reduction_cache
    public :: cache_hit, cache_absent, cache_stale, cache_damaged, cache_foreign, cache_format

    !> Outcomes of read_reduction_cache: used; no file; a file of another key or format
    !> (another model or other options: recomputed silently); a cache file that fails a
    !> check; a file that is not a reduction cache at all (not to be overwritten).
    integer, parameter :: cache_hit = 0, cache_absent = 1, cache_stale = 2, cache_damaged = 3, &
                          cache_foreign = 4
    !> The format version (part of the header): raise it with any change of the layout, so
    !> that an older file reads as another format (replaced silently), not as a damaged one.
    integer(int32), parameter :: cache_format = 2
    character(len=*), parameter :: magic = 'stickslip reduction cache'
    !> Bytes read at a time when hashing a file.
    integer, parameter :: chunk = 8*1024*1024
    !> Most error frequencies a file may announce (the rule takes at most 8), and most nodal
    !> diameters (at most max_sectors / 2 + 1).
    integer, parameter :: max_frequencies = 1000, max_diameters = 1000

contains

    !> Feed the bytes of file `path` to `hash`, then its size (read in chunks of 8 MiB).
    !> Error (stat io): the file cannot be opened or read.
    subroutine hash_file(path, hash, error)
        !> The file.
        character(len=*), intent(in) :: path
        !> The running hash.
        type(hash_t), intent(inout) :: hash
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer(int8), allocatable :: buf(:)
        integer(int64) :: total, done
        integer :: u, stat, m
        character(len=512) :: msg
        open (newunit=u, file=path, access='stream', form='unformatted', status='old', &
              action='read', iostat=stat, iomsg=msg)
        if (stat /= 0) then
            call fatal_error(error, path//": cannot open: "//trim(msg), stickslip_stat%io)
            return
        end if
        inquire (unit=u, size=total)
        if (total < 0) then
            close (u)
            call fatal_error(error, path//": cannot tell its size", stickslip_stat%io)
            return
        end if
        allocate (buf(int(min(int(chunk, int64), max(total, 1_int64)))))
        done = 0
        do while (done < total)
            m = int(min(int(size(buf), int64), total - done))
            read (u, iostat=stat, iomsg=msg) buf(1:m)
            if (stat /= 0) then
                close (u)
                call fatal_error(error, path//": read failed: "//trim(msg), stickslip_stat%io)
                return
            end if
            call hash%add(buf(1:m))
            done = done + m
        end do
        close (u)
        call hash%add(total)
    end subroutine hash_file

    !> Write the reduced model `reduced` (with its basis) and `report` under `key` to the
    !> file `name` in directory `dir` (which must exist), atomically. Error (stat io): the
    !> file cannot be written (the old one, if any, is kept).
    subroutine write_reduction_cache(dir, name, key, reduced, report, error)
        !> Directory of the file.
        character(len=*), intent(in) :: dir
        !> File name.
        character(len=*), intent(in) :: name
        !> The key of the inputs.
        integer(int64), intent(in) :: key
        !> The reduced model and its basis.
        type(reduced_model_t), intent(in) :: reduced
        !> What the reduction and its error estimate reported.
        type(reduction_report_t), intent(in) :: report
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        type(hash_t) :: h
        integer :: u, stat, nf, nd
        character(len=512) :: msg
        character(len=4096) :: temporary
        call open_temporary(dir, name, u, error, binary=.true.)
        if (allocated(error)) return
        inquire (unit=u, name=temporary)
        nf = 0
        if (allocated(report%error_frequencies)) nf = size(report%error_frequencies)
        nd = 0
        if (allocated(report%diameters) .and. allocated(report%diameter_errors) .and. &
            allocated(report%diameter_lowest)) nd = size(report%diameters)
        stat = 0
        msg = ''
        write (u, iostat=stat, iomsg=msg) magic, cache_format, 1_int32, key
        associate (r => reduced)
            call put_i([r%n, r%nb, r%nm, r%nl, r%nr, nf, nd])
            call put_i(r%boundary)
            call put_i(r%interior)
            call put_r(r%mass)
            call put_r(r%stiffness)
            call put_r(r%damping)
            call put_r(r%constraint)
            call put_r(r%modes)
            call put_r(reshape(r%frequencies, [r%nm, 1]))
            call put_r(r%loads)
            call put_r(reshape([r%modal_damping_ratio, r%next_frequency], [2, 1]))
        end associate
        associate (p => report)
            call put_i([p%full_dof, p%reduced_dof, p%boundary_dof, p%modes, p%load_vectors, &
                        merge(1, 0, p%capped), p%error_levels])
            call put_r(reshape([p%seconds, p%highest_mode_frequency, p%frequency_limit, &
                                p%error, p%error_seconds, p%error_change], [6, 1]))
            if (nf > 0) call put_r(reshape(p%error_frequencies, [nf, 1]))
            call put_c(p%method)
            call put_c(p%error_method)
            call put_i([p%diameter_faces])
            call put_r(reshape([p%diameter_band], [1, 1]))
            if (nd > 0) then
                call put_i(p%diameters)
                call put_r(reshape([p%diameter_errors, p%diameter_lowest], [nd, 2]))
            end if
        end associate
        if (stat == 0) write (u, iostat=stat, iomsg=msg) h%value()
        call close_and_rename(dir, name, u, stat, msg, error)

    contains

        subroutine put_i(x)
            integer, intent(in) :: x(:)
            if (stat /= 0) return
            write (u, iostat=stat, iomsg=msg) x
            call h%add(x)
        end subroutine put_i

        subroutine put_r(x)
            real(dp), intent(in) :: x(:, :)
            if (stat /= 0) return
            write (u, iostat=stat, iomsg=msg) x
            call h%add(x)
        end subroutine put_r

        subroutine put_c(x)
            character(len=16), intent(in) :: x
            if (stat /= 0) return
            write (u, iostat=stat, iomsg=msg) x
            call h%add(x)
        end subroutine put_c
    end subroutine write_reduction_cache

    !> Read the cache file `path` for `key` and a full model of `n` DOFs. `status`:
    !> cache_hit (`reduced` and `report` set), cache_absent (no file), cache_stale (a file of
    !> another key, format or byte order), cache_damaged (`why` says what failed),
    !> cache_foreign (the file does not start as a reduction cache: someone else's file,
    !> which the caller must not overwrite). Never an error: a file that cannot be used is
    !> reported in `status`.
    subroutine read_reduction_cache(path, key, n, reduced, report, status, why)
        !> The file.
        character(len=*), intent(in) :: path
        !> The key of this run's inputs.
        integer(int64), intent(in) :: key
        !> DOFs of the full model.
        integer, intent(in) :: n
        !> The reduced model and its basis (on a hit).
        type(reduced_model_t), intent(out) :: reduced
        !> The report stored with it (on a hit).
        type(reduction_report_t), intent(out) :: report
        !> cache_hit, cache_absent, cache_stale or cache_damaged.
        integer, intent(out) :: status
        !> Why the file is damaged (or stale), for a message.
        character(len=:), allocatable, intent(out) :: why
        type(hash_t) :: h
        character(len=len(magic)) :: text
        integer(int32) :: format, one
        integer(int64) :: stored_key, stored_sum, total
        integer :: u, stat, ni, nf, nd, dims(7), ints(7), j, faces(1)
        real(dp), allocatable :: col(:, :), per_nd(:, :)
        real(dp) :: reals(6, 1), ratio(2, 1), band(1, 1)
        logical :: exists
        logical, allocatable :: seen(:)
        why = ''
        inquire (file=path, exist=exists)
        if (.not. exists) then
            status = cache_absent
            return
        end if
        status = cache_damaged
        open (newunit=u, file=path, access='stream', form='unformatted', status='old', &
              action='read', iostat=stat)
        if (stat /= 0) then
            why = "cannot be opened"
            return
        end if
        inquire (unit=u, size=total)
        text = ''
        read (u, iostat=stat) text
        if (stat /= 0 .or. text /= magic) then
            status = cache_foreign
            why = "not a reduction cache (its first bytes)"
            call done()
            return
        end if
        read (u, iostat=stat) format, one, stored_key
        if (stat /= 0) then
            why = "shorter than its header"
            call done()
            return
        end if
        if (format /= cache_format .or. one /= 1_int32) then
            status = cache_stale
            why = "another format or byte order"
            call done()
            return
        end if
        if (stored_key /= key) then
            status = cache_stale
            why = "made for other inputs"
            call done()
            return
        end if
        status = cache_damaged
        call get_i(dims)
        if (stat /= 0) then
            why = "truncated in its sizes"
            call done()
            return
        end if
        ni = dims(1) - dims(2)
        nf = dims(6)
        nd = dims(7)
        if (dims(1) /= n .or. dims(2) < 1 .or. ni < 1 .or. dims(3) < 0 .or. dims(4) < 0 .or. &
            dims(3) + dims(4) > ni .or. dims(5) /= dims(2) + dims(3) + dims(4) .or. nf < 0 .or. &
            nf > max_frequencies .or. nd < 0 .or. nd > max_diameters) then
            why = "sizes that do not fit together (or another model: N = "// &
                  itoa(dims(1))//", expected "//itoa(n)//")"
            call done()
            return
        end if
        if (total /= expected_size(dims)) then
            why = "of "//itoa(total)//" bytes where its sizes need "// &
                  itoa(expected_size(dims))//" (truncated or extended)"
            call done()
            return
        end if
        reduced%n = dims(1)
        reduced%nb = dims(2)
        reduced%nm = dims(3)
        reduced%nl = dims(4)
        reduced%nr = dims(5)
        associate (r => reduced, nb => dims(2), nm => dims(3), nl => dims(4), nr => dims(5))
            allocate (r%boundary(nb), r%interior(ni), r%mass(nr, nr), r%stiffness(nr, nr), &
                      r%damping(nr, nr), r%constraint(ni, nb), r%modes(ni, nm), &
                      r%frequencies(nm), r%loads(ni, nl))
            call get_i(r%boundary)
            call get_i(r%interior)
            call get_r(r%mass)
            call get_r(r%stiffness)
            call get_r(r%damping)
            call get_r(r%constraint)
            call get_r(r%modes)
            allocate (col(nm, 1))
            call get_r(col)
            r%frequencies = col(:, 1)
            call get_r(r%loads)
            call get_r(ratio)
            r%modal_damping_ratio = ratio(1, 1)
            r%next_frequency = ratio(2, 1)
        end associate
        call get_i(ints)
        call get_r(reals)
        if (nf > 0) then
            deallocate (col)
            allocate (col(nf, 1))
            call get_r(col)
        end if
        call get_c(report%method)
        call get_c(report%error_method)
        call get_i(faces)
        call get_r(band)
        allocate (report%diameters(nd), per_nd(nd, 2))
        if (nd > 0) then
            call get_i(report%diameters)
            call get_r(per_nd)
        end if
        if (stat == 0) read (u, iostat=stat) stored_sum
        if (stat /= 0) then
            why = "truncated"
            call done()
            return
        end if
        call done()
        if (stored_sum /= h%value()) then
            why = "its checksum does not match its contents"
            return
        end if
        ! the DOF lists: boundary and interior ascending, together 1..n once each
        allocate (seen(n))
        seen = .false.
        do j = 1, size(reduced%boundary)
            if (.not. ok_dof(reduced%boundary(j), j, reduced%boundary)) return
        end do
        do j = 1, size(reduced%interior)
            if (.not. ok_dof(reduced%interior(j), j, reduced%interior)) return
        end do
        if (.not. (all(ieee_is_finite(reduced%mass)) .and. &
                   all(ieee_is_finite(reduced%stiffness)) .and. &
                   all(ieee_is_finite(reduced%damping)) .and. &
                   all(ieee_is_finite(reduced%constraint)) .and. &
                   all(ieee_is_finite(reduced%modes)) .and. &
                   all(ieee_is_finite(reduced%frequencies)) .and. &
                   all(ieee_is_finite(reduced%loads)) .and. all(ieee_is_finite(reals)) .and. &
                   all(ieee_is_finite(ratio)) .and. all(ieee_is_finite(band)) .and. &
                   all(ieee_is_finite(per_nd)))) then
            why = "a value that is not finite"
            return
        end if
        report%full_dof = ints(1)
        report%reduced_dof = ints(2)
        report%boundary_dof = ints(3)
        report%modes = ints(4)
        report%load_vectors = ints(5)
        report%capped = ints(6) /= 0
        report%error_levels = ints(7)
        report%seconds = reals(1, 1)
        report%highest_mode_frequency = reals(2, 1)
        report%frequency_limit = reals(3, 1)
        report%error = reals(4, 1)
        report%error_seconds = reals(5, 1)
        report%error_change = reals(6, 1)
        if (nf > 0) then
            report%error_frequencies = col(:, 1)
        else
            allocate (report%error_frequencies(0))
        end if
        report%diameter_faces = faces(1)
        report%diameter_band = band(1, 1)
        report%diameter_errors = per_nd(:, 1)
        report%diameter_lowest = per_nd(:, 2)
        if (nd == 0) deallocate (report%diameters, report%diameter_errors, &
                                 report%diameter_lowest)
        if (report%full_dof /= n .or. report%reduced_dof /= reduced%nr .or. &
            report%modes /= reduced%nm .or. report%load_vectors /= reduced%nl) then
            why = "a report that does not match its model"
            return
        end if
        status = cache_hit

    contains

        subroutine done()
            integer :: s
            close (u, iostat=s)
        end subroutine done

        logical function ok_dof(dof, j, list) result(ok)
            integer, intent(in) :: dof, j, list(:)
            ok = dof >= 1 .and. dof <= n
            if (ok) ok = .not. seen(dof)
            if (ok .and. j > 1) ok = dof > list(j - 1)
            if (ok) then
                seen(dof) = .true.
            else
                why = "a DOF list that is not ascending within 1.."//itoa(n)//" or repeats"
            end if
        end function ok_dof

        subroutine get_i(x)
            integer, intent(out) :: x(:)
            if (stat /= 0) return
            read (u, iostat=stat) x
            if (stat == 0) call h%add(x)
        end subroutine get_i

        subroutine get_r(x)
            real(dp), intent(out) :: x(:, :)
            if (stat /= 0) return
            read (u, iostat=stat) x
            if (stat == 0) call h%add(x)
        end subroutine get_r

        subroutine get_c(x)
            character(len=16), intent(out) :: x
            if (stat /= 0) return
            read (u, iostat=stat) x
            if (stat == 0) call h%add(x)
        end subroutine get_c
    end subroutine read_reduction_cache

    !> Bytes of a cache file with sizes dims = [n, nb, nm, nl, nr, nf, nd].
    pure integer(int64) function expected_size(dims) result(bytes)
        !> The sizes as the file gives them.
        integer, intent(in) :: dims(7)
        integer(int64) :: n, nb, nm, nl, nr, nf, ni, nd
        n = dims(1)
        nb = dims(2)
        nm = dims(3)
        nl = dims(4)
        nr = dims(5)
        nf = dims(6)
        nd = dims(7)
        ni = n - nb
        bytes = len(magic) + 4 + 4 + 8                      ! header and key
        bytes = bytes + 7*4 + 4*n                           ! sizes, boundary and interior
        bytes = bytes + 8*(3*nr*nr + ni*nb + ni*nm + nm + ni*nl + 2)
        bytes = bytes + 7*4 + 6*8 + 8*nf + 2*16             ! the report
        bytes = bytes + 4 + 8 + nd*(4 + 2*8)                ! its error per nodal diameter
        bytes = bytes + 8                                   ! checksum
    end function expected_size
end module stickslip_reduction_cache
