!> The reduction cache (stickslip_reduction_cache, and its use by read_case and the command
!> line) and the switch &reduction error_estimate, on a 3000-DOF chain from Matrix Market
!> files: the hash (FNV-1a test vectors); a second read of the same case gets the model from
!> the cache, bit for bit, without reading the matrix files; a changed stiffness file, and
!> another boundary, are recomputed; a damaged cache (a flipped byte, a truncated file,
!> another file's bytes) is ignored with a warning and replaced; cache = 'off' writes
!> nothing; a cache made without the error estimate gets it later; error_estimate = .false.
!> reports -1 and 'off' (also from a cache that holds an estimate); the command line says
!> 'hit' in summary.nml and on its summary; a path with blanks and shell characters is a
!> plain file name.
module test_reduction_cache
    use, intrinsic :: iso_fortran_env, only: int8, int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_sparse, only: sparse_matrix_t
    use stickslip_matrix_market, only: write_matrix_market
    use stickslip_hash, only: hash_t
    use stickslip_case, only: case_t, read_case
    use stickslip_case_reduction, only: write_reduction_cache_of
    use stickslip_files, only: remove_file
    use stickslip_cli, only: run_cli, string_t
    use testing, only: test_counter_t, check, check_close
    use fixtures, only: enter_project_root, scratch, write_lines, msg, rt, file_text
    use test_reduction, only: chain_matrices
    implicit none
    private
    public :: run_reduction_cache_tests

    character(len=*), parameter :: case_path = scratch//"/rc.nml"
    character(len=*), parameter :: cache_path = scratch//"/rc.cache"

contains

    subroutine run_reduction_cache_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_hash(t)
        call enter_project_root()
        call write_model(1.0_dp)
        call test_hit(t)
        call test_stale(t)
        call test_damaged(t)
        call test_switch(t)
        call test_off_and_names(t)
        call test_command_line(t)
        call remove_file(cache_path)
    end subroutine run_reduction_cache_tests

    !> FNV-1a 64 of '', 'a' and 'foobar' (the published test vectors).
    subroutine test_hash(t)
        type(test_counter_t), intent(inout) :: t
        type(hash_t) :: h0, ha, hf
        call ha%add(transfer('a', [0_int8], 1))
        call hf%add(transfer('foobar', [0_int8], 6))
        call check(t, h0%hex() == 'cbf29ce484222325' .and. ha%hex() == 'af63dc4c8601ec8c' &
                   .and. hf%hex() == '85944171f73967e8', "cache: FNV-1a 64 test vectors", &
                   h0%hex()//" "//ha%hex()//" "//hf%hex())
    end subroutine test_hash

    !> The chain's files, K scaled by `scale` (a changed model).
    subroutine write_model(scale)
        real(dp), intent(in) :: scale
        type(sparse_matrix_t) :: k, m, c
        type(error_type), allocatable :: error
        call chain_matrices(3000, k, m, c)
        k%val = scale*k%val
        call write_matrix_market(scratch//"/rc_m.mtx", m, .true., error)
        call write_matrix_market(scratch//"/rc_k.mtx", k, .true., error)
    end subroutine write_model

    !> The case, with `extra` lines in &reduction (after cache = rc.cache) and the contact
    !> at `contact`.
    subroutine write_case_file(extra, contact)
        character(len=*), intent(in) :: extra
        integer, intent(in) :: contact
        integer :: u
        ! line by line: gfortran 12 mishandles array constructors of variable concatenations
        open (newunit=u, file=case_path, status='replace', action='write')
        write (u, '(a)') "&system mass_file = 'rc_m.mtx', stiffness_file = 'rc_k.mtx',"
        write (u, '(a)') "  rayleigh_alpha = 0.01 /"
        write (u, '(a)') "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /"
        write (u, '(a)') "&friction contact_dof = "//itoa(contact)//", mu = 0.3, "// &
            "normal_load = 1.0 /"
        write (u, '(a)') "&reduction cache = '"//cache_path//"' "//extra//" /"
        write (u, '(a)') "&hbm harmonics = 3 /"
        write (u, '(a)') "&output directory = '"//scratch//"/out_rc' /"
        close (u)
    end subroutine write_case_file

    !> Read the case and write its cache (what the command line does).
    subroutine read_and_write(cs, error)
        type(case_t), intent(out) :: cs
        type(error_type), allocatable, intent(out) :: error
        call read_case(case_path, cs, error)
        if (.not. allocated(error)) call write_reduction_cache_of(cs%reduction)
    end subroutine read_and_write

    !> First read: reduced, the cache written; second read: from the cache, bit for bit the
    !> same reduced matrices, report and error estimate, and the matrix files not read.
    subroutine test_hit(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: first, second
        type(error_type), allocatable :: error
        logical :: there
        call remove_file(cache_path)
        call write_case_file("", 2990)
        call read_and_write(first, error)
        call check(t, .not. allocated(error), "cache: first read", msg(error))
        if (allocated(error)) return
        inquire (file=cache_path, exist=there)
        call check(t, first%reduction%cache_status == 'written' .and. there, &
                   "cache: written by the first run", first%reduction%cache_status)
        call check(t, first%reduction%read_seconds > 0.0_dp .and. &
                   first%reduction%report%error >= 0.0_dp .and. &
                   first%reduction%report%error_method == 'enriched', &
                   "cache: first run read the files and estimated the error", &
                   trim(first%reduction%report%error_method))
        call read_and_write(second, error)
        call check(t, .not. allocated(error), "cache: second read", msg(error))
        if (allocated(error)) return
        call check(t, second%reduction%cache_status == 'hit' .and. &
                   second%reduction%read_seconds == 0.0_dp, &
                   "cache: second run used it, files not read", second%reduction%cache_status)
        call check(t, same_model(first, second), "cache: bit-identical reduced model")
        call check(t, second%reduction%report%error == first%reduction%report%error .and. &
                   second%reduction%report%modes == first%reduction%report%modes .and. &
                   second%reduction%report%error_method == 'enriched' .and. &
                   all(second%reduction%report%error_frequencies == &
                       first%reduction%report%error_frequencies), &
                   "cache: the same report and error estimate")
        call check(t, second%reduction%diagnostics%has("reduction_cache_hit"), &
                   "cache: a note says it was used")
    end subroutine test_hit

    !> A changed stiffness file, and a case with another contact DOF, are not served from
    !> the cache; the cache then holds the new model (a third read hits).
    subroutine test_stale(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: before, changed, again, other
        type(error_type), allocatable :: error
        call write_case_file("", 2990)
        call read_and_write(before, error)
        call write_model(1.5_dp)
        call read_and_write(changed, error)
        call check(t, .not. allocated(error), "cache stale: reads", msg(error))
        if (allocated(error)) return
        call check(t, changed%reduction%cache_status == 'written' .and. &
                   changed%reduction%read_seconds > 0.0_dp .and. &
                   .not. changed%reduction%diagnostics%has("reduction_cache_damaged"), &
                   "cache stale: a changed matrix file is recomputed, silently", &
                   changed%reduction%cache_status)
        call check(t, .not. same_model(before, changed), "cache stale: a new reduced model")
        call read_and_write(again, error)
        call check(t, again%reduction%cache_status == 'hit' .and. same_model(again, changed), &
                   "cache stale: the new model cached")
        call write_model(1.0_dp)
        call write_case_file("", 2980)
        call read_and_write(other, error)
        call check(t, .not. allocated(error) .and. other%reduction%cache_status == 'written', &
                   "cache stale: another boundary DOF recomputed", msg(error))
    end subroutine test_stale

    !> A flipped byte in the matrices, a truncated file, a changed size: each ignored with
    !> the warning reduction_cache_damaged (no error), the model reduced again
    !> (bit-identical to a clean run) and the cache replaced. A file that is not a cache at
    !> all (someone else's) is left as it is, with the warning reduction_cache_foreign.
    subroutine test_damaged(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: clean, hurt
        type(error_type), allocatable :: error
        character(len=:), allocatable :: bytes
        integer :: how, u
        character(len=16), parameter :: names(3) = [character(len=16) :: "flipped byte", &
                                                    "truncated", "a size changed"]
        call write_case_file("", 2990)
        call read_and_write(clean, error)
        do how = 1, 3
            bytes = file_bytes(cache_path)
            select case (how)
            case (1)
                bytes(len(bytes)/2:len(bytes)/2) = achar(ieor(iachar(bytes(len(bytes)/2: &
                                                          len(bytes)/2)), 1))
            case (2)
                bytes = bytes(1:len(bytes) - 100)
            case (3)
                ! the first size (n) after the header and the key
                bytes(46:46) = achar(ieor(iachar(bytes(46:46)), 2))
            end select
            open (newunit=u, file=cache_path, access='stream', form='unformatted', &
                  status='replace', action='write')
            write (u) bytes
            close (u)
            call read_and_write(hurt, error)
            call check(t, .not. allocated(error), "cache damaged ("//trim(names(how))// &
                       "): no error", msg(error))
            if (allocated(error)) return
            call check(t, hurt%reduction%diagnostics%has("reduction_cache_damaged") .and. &
                       hurt%reduction%cache_status == 'written', "cache damaged ("// &
                       trim(names(how))//"): a warning, the cache replaced", &
                       hurt%reduction%cache_status)
            call check(t, same_model(clean, hurt), "cache damaged ("//trim(names(how))// &
                       "): the model reduced again")
        end do
        ! not a cache: never overwritten
        open (newunit=u, file=cache_path, access='stream', form='unformatted', &
              status='replace', action='write')
        write (u) repeat("someone else's data ", 50)
        close (u)
        call read_and_write(hurt, error)
        call check(t, .not. allocated(error) .and. &
                   hurt%reduction%diagnostics%has("reduction_cache_foreign") .and. &
                   hurt%reduction%cache_status == 'off' .and. same_model(clean, hurt) .and. &
                   file_bytes(cache_path) == repeat("someone else's data ", 50), &
                   "cache: a file that is not a cache is left alone, with a warning", msg(error))
    end subroutine test_damaged

    !> error_estimate = .false.: reduction_error -1 and 'off' with a note (also from a cache
    !> that holds an estimate); a cache written without the estimate gets it when a later
    !> run asks (and keeps the model).
    subroutine test_switch(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: off, on, off_hit
        type(error_type), allocatable :: error
        call remove_file(cache_path)
        call write_case_file(", error_estimate = .false.", 2990)
        call read_and_write(off, error)
        call check(t, .not. allocated(error), "error_estimate off: reads", msg(error))
        if (allocated(error)) return
        call check(t, off%reduction%report%error == -1.0_dp .and. &
                   off%reduction%report%error_method == 'off' .and. &
                   off%reduction%report%error_seconds == 0.0_dp .and. &
                   off%reduction%diagnostics%has("reduction_error_off"), &
                   "error_estimate off: not estimated, said so", &
                   trim(off%reduction%report%error_method)//" "//rt(off%reduction%report%error))
        call write_case_file("", 2990)
        call read_and_write(on, error)
        call check(t, .not. allocated(error) .and. on%reduction%report%error >= 0.0_dp .and. &
                   on%reduction%report%error_method == 'enriched' .and. &
                   on%reduction%read_seconds > 0.0_dp .and. same_model(on, off), &
                   "error_estimate: a cache without it, estimated now on the cached model", &
                   msg(error))
        call write_case_file(", error_estimate = .false.", 2990)
        call read_and_write(off_hit, error)
        call check(t, .not. allocated(error) .and. off_hit%reduction%cache_status == 'hit' &
                   .and. off_hit%reduction%report%error == -1.0_dp .and. &
                   off_hit%reduction%report%error_method == 'off', &
                   "error_estimate off: -1 also from a cache holding one", msg(error))
    end subroutine test_switch

    !> cache = 'off' writes and reads nothing; a path with blanks, quotes and shell
    !> characters is a plain file name; an empty cache or a directory refused.
    subroutine test_off_and_names(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: cs
        type(error_type), allocatable :: error
        character(len=*), parameter :: odd = scratch//"/odd $(touch x); name.cache"
        logical :: there
        call remove_file(cache_path)
        call write_lines(case_path, [character(len=120) :: &
            "&system mass_file = 'rc_m.mtx', stiffness_file = 'rc_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction cache = 'off' /", &
            "&output directory = '"//scratch//"/out_rc' /"])
        call read_and_write(cs, error)
        inquire (file=scratch//"/out_rc/reduction.cache", exist=there)
        call check(t, .not. allocated(error) .and. cs%reduction%cache_status == 'off' .and. &
                   .not. there, "cache off: nothing written", msg(error))
        call remove_file(odd)
        call write_lines(case_path, [character(len=120) :: &
            "&system mass_file = 'rc_m.mtx', stiffness_file = 'rc_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction cache = '"//odd//"' /", &
            "&output directory = '"//scratch//"/out_rc' /"])
        call read_and_write(cs, error)
        inquire (file=odd, exist=there)
        call check(t, .not. allocated(error) .and. there .and. &
                   cs%reduction%cache_status == 'written', &
                   "cache: a name with blanks and shell characters is a file name", msg(error))
        inquire (file="x", exist=there)
        call check(t, .not. there, "cache: no shell ran the name")
        call remove_file(odd)
        call write_lines(case_path, [character(len=120) :: &
            "&system mass_file = 'rc_m.mtx', stiffness_file = 'rc_k.mtx' /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&reduction cache = '' /"])
        call read_case(case_path, cs, error)
        call check(t, allocated(error), "cache: '' refused")
        if (allocated(error)) call check(t, index(error%message, "&reduction cache") > 0, &
                                         "cache: ... naming the variable", error%message)
    end subroutine test_off_and_names

    !> The command line, twice: summary.nml says reduction_cache = 'written' then 'hit', the
    !> human summary notes the cache, and the results are the same bytes.
    subroutine test_command_line(t)
        type(test_counter_t), intent(inout) :: t
        type(string_t), allocatable :: args(:)
        character(len=:), allocatable :: first_csv, summary, out
        integer :: uo, ue, code
        character(len=*), parameter :: dir = scratch//"/out_rc_cli"
        call remove_file(dir//"/reduction.cache")
        call write_lines(case_path, [character(len=120) :: &
            "&system mass_file = 'rc_m.mtx', stiffness_file = 'rc_k.mtx',", &
            "  rayleigh_alpha = 0.01 /", &
            "&forcing omega = 0.03, force_dof = 3000, force_amplitude = 1.0 /", &
            "&friction contact_dof = 2990, mu = 0.3, normal_load = 1.0 /", &
            "&hbm harmonics = 3 /", &
            "&output directory = '"//dir//"' /"])
        allocate (args(1))
        args(1)%s = case_path
        open (newunit=uo, status='scratch', action='readwrite')
        open (newunit=ue, status='scratch', action='readwrite')
        code = run_cli(args, uo, ue)
        close (uo)
        close (ue)
        summary = file_text(dir//"/summary.nml")
        call check(t, code == 0 .and. index(summary, "reduction_cache = 'written'") > 0 .and. &
                   index(summary, "reduction_error_method = 'enriched'") > 0, &
                   "cache cli: first run writes it", itoa(code))
        first_csv = file_text(dir//"/hbm.csv")
        open (newunit=uo, file=scratch//"/rc_cli_out.txt", status='replace', action='readwrite')
        open (newunit=ue, status='scratch', action='readwrite')
        code = run_cli(args, uo, ue)
        close (uo)
        close (ue)
        summary = file_text(dir//"/summary.nml")
        out = file_text(scratch//"/rc_cli_out.txt")
        call check(t, code == 0 .and. index(summary, "reduction_cache = 'hit'") > 0 .and. &
                   index(summary, "reduction_read_seconds = 0.0") > 0, &
                   "cache cli: second run hits", itoa(code))
        call check(t, index(out, "read from the cache") > 0, &
                   "cache cli: the summary says the cache was used", out)
        call check(t, first_csv == file_text(dir//"/hbm.csv") .and. len(first_csv) > 0, &
                   "cache cli: the same hbm.csv, byte for byte")
    end subroutine test_command_line

    !> The reduced matrices, DOF maps and output rows of two cases, bit for bit.
    logical function same_model(a, b) result(same)
        type(case_t), intent(in) :: a, b
        same = a%model%ndof == b%model%ndof
        if (.not. same) return
        same = all(a%model%mass == b%model%mass) .and. &
               all(a%model%stiffness == b%model%stiffness) .and. &
               all(a%model%damping == b%model%damping) .and. &
               all(a%model%contact_dof == b%model%contact_dof) .and. &
               all(a%model%force_dof == b%model%force_dof) .and. &
               all(a%reduction%output_rows == b%reduction%output_rows)
    end function same_model

    !> The bytes of a file.
    function file_bytes(path) result(bytes)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: bytes
        integer :: u
        integer(int64) :: n
        inquire (file=path, size=n)
        allocate (character(len=n) :: bytes)
        open (newunit=u, file=path, access='stream', form='unformatted', status='old', &
              action='read')
        read (u) bytes
        close (u)
    end function file_bytes
end module test_reduction_cache
