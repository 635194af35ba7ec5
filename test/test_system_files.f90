!> Tests of the &system file variables (mass_file, stiffness_file, damping_file,
!> rayleigh_alpha, rayleigh_beta): a 4-element cantilever beam given inline and as Matrix
!> Market files reads to the same matrices and the same periodic solution; relative paths
!> resolve against the case file's folder; Rayleigh damping against dense arithmetic; every
!> inconsistency rejected naming the file (and line), the variables; the example runs.
module test_system_files
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_case, only: case_t, read_case, write_case
    use stickslip_files, only: make_directory
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_cli, only: run_cli, string_t
    use stickslip_checkpoint, only: case_fingerprint
    use stickslip_matrix_market, only: write_matrix_market_array
    use testing, only: test_counter_t, check, check_close, check_error
    use fixtures, only: enter_project_root, scratch, scratch_dir, project_path, write_lines, &
        good_forcing
    implicit none
    private
    public :: run_system_files_tests

    character(len=*), parameter :: dir = scratch//"/sysfiles"
    character(len=*), parameter :: beam_forcing = &
        "&forcing omega = 300.0, force_dof = 5, force_amplitude = 2.0 /"
    character(len=*), parameter :: beam_friction = &
        "&friction contact_dof = 7, mu = 0.3, normal_load = 1.0 /"
    character(len=*), parameter :: beam_hbm = "&hbm harmonics = 7, odd_only = T, samples = 64 /"

contains

    subroutine run_system_files_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        call enter_project_root()
        call make_directory(scratch, error)
        call make_directory(dir, error)
        call make_directory(dir//"/sub", error)
        call make_directory(dir//"/other", error)
        call check_error(t, error, "system files: scratch directories", .false.)
        if (allocated(error)) return
        call test_beam_both_ways(t)
        call test_paths(t)
        call test_bad_cases(t)
        call test_example(t)
    end subroutine run_system_files_tests

    !> Cantilever beam of ne Euler-Bernoulli elements (length 1, EI = 700, rho A = 3.12),
    !> clamped node removed: 2 ne DOFs (w, theta per node).
    subroutine beam(ne, k, m)
        integer, intent(in) :: ne
        real(dp), allocatable, intent(out) :: k(:, :), m(:, :)
        real(dp) :: le, ke(4, 4), me(4, 4)
        integer :: e, a, b, dofs(4)
        le = 1.0_dp/ne
        ke = reshape([12.0_dp, 6*le, -12.0_dp, 6*le, 6*le, 4*le**2, -6*le, 2*le**2, &
                      -12.0_dp, -6*le, 12.0_dp, -6*le, 6*le, 2*le**2, -6*le, 4*le**2], &
                     [4, 4])*700.0_dp/le**3
        me = reshape([156.0_dp, 22*le, 54.0_dp, -13*le, 22*le, 4*le**2, 13*le, -3*le**2, &
                      54.0_dp, 13*le, 156.0_dp, -22*le, -13*le, -3*le**2, -22*le, 4*le**2], &
                     [4, 4])*3.12_dp*le/420.0_dp
        allocate (k(2*ne, 2*ne), m(2*ne, 2*ne))
        k = 0.0_dp
        m = 0.0_dp
        do e = 1, ne
            dofs = [2*e - 3, 2*e - 2, 2*e - 1, 2*e]
            do a = 1, 4
                do b = 1, 4
                    if (dofs(a) < 1 .or. dofs(b) < 1) cycle
                    k(dofs(a), dofs(b)) = k(dofs(a), dofs(b)) + ke(a, b)
                    m(dofs(a), dofs(b)) = m(dofs(a), dofs(b)) + me(a, b)
                end do
            end do
        end do
    end subroutine beam

    !> A 17-digit real as text.
    function r17(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: buf
        write (buf, '(es25.17e3)') x
        s = trim(adjustl(buf))
    end function r17

    !> `a` as a coordinate real symmetric file (lower triangle, nonzeros), written here.
    subroutine write_symmetric(path, a)
        character(len=*), intent(in) :: path
        real(dp), intent(in) :: a(:, :)
        integer :: u, i, j, n
        n = size(a, 1)
        open (newunit=u, file=path, status='replace', action='write')
        write (u, '(a)') "%%MatrixMarket matrix coordinate real symmetric"
        write (u, '(i0,1x,i0,1x,i0)') n, n, count([((a(i, j) /= 0.0_dp .and. i >= j, i=1, n), &
                                                   j=1, n)])
        do j = 1, n
            do i = j, n
                if (a(i, j) /= 0.0_dp) write (u, '(i0,1x,i0,1x,a)') i, j, r17(a(i, j))
            end do
        end do
        close (u)
    end subroutine write_symmetric

    !> The matrix flattened as a namelist list of 17-digit reals.
    function inline(a) result(s)
        real(dp), intent(in) :: a(:, :)
        character(len=:), allocatable :: s
        integer :: i, j
        s = ""
        do j = 1, size(a, 2)
            do i = 1, size(a, 1)
                s = s//r17(a(i, j))//", "
            end do
        end do
        s = s(1:len(s) - 2)
    end function inline

    subroutine test_beam_both_ways(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: k(:, :), m(:, :)
        type(case_t) :: a, b
        type(error_type), allocatable :: error
        type(hbm_options_t) :: opts
        type(hbm_solution_t) :: sa, sb
        real(dp), parameter :: alpha = 0.7_dp, beta = 2.0e-5_dp
        character(len=8000) :: text(4)
        call beam(4, k, m)
        call write_symmetric(dir//"/beam_m.mtx", m)
        call write_symmetric(dir//"/beam_k.mtx", k)
        ! (no variable text in an array constructor: gfortran 12 corrupts memory on it)
        text(1) = "&system ndof = 8, mass = "//inline(m)//", stiffness = "//inline(k)// &
                  ", rayleigh_alpha = 0.7, rayleigh_beta = 2e-5 /"
        text(2) = beam_forcing
        text(3) = beam_friction
        text(4) = beam_hbm
        call write_lines(dir//"/beam_inline.nml", text)
        call write_lines(dir//"/beam_files.nml", [character(len=200) :: &
            "&system mass_file = 'beam_m.mtx', stiffness_file = 'beam_k.mtx', "// &
            "rayleigh_alpha = 0.7, rayleigh_beta = 2e-5 /", beam_forcing, beam_friction, &
            beam_hbm])
        call read_case(dir//"/beam_inline.nml", a, error)
        call check_error(t, error, "beam inline: read", .false.)
        if (allocated(error)) return
        call read_case(dir//"/beam_files.nml", b, error)
        call check_error(t, error, "beam files: read", .false.)
        if (allocated(error)) return
        call check(t, b%model%ndof == 8, "beam files: ndof from the files")
        call check(t, all(a%model%mass == b%model%mass) .and. &
                   all(a%model%stiffness == b%model%stiffness), &
                   "beam: inline and file matrices identical")
        call check_close(t, reshape(b%model%mass, [64]), reshape(m, [64]), &
                         "beam files: M as assembled", rtol=1e-15_dp, atol=1e-300_dp)
        call check_close(t, reshape(b%model%damping, [64]), &
                         reshape(alpha*m + beta*k, [64]), "beam files: C = alpha M + beta K", &
                         rtol=1e-14_dp, atol=1e-14_dp*maxval(abs(beta*k)))
        call check(t, all(a%model%damping == b%model%damping), &
                   "beam: Rayleigh damping inline = files")
        ! the same beam as dense superelement files (array symmetric, array general)
        block
            type(case_t) :: c
            call write_matrix_market_array(dir//"/beam_m_array.mtx", m, .true., error)
            call write_matrix_market_array(dir//"/beam_k_array.mtx", k, .false., error)
            call write_lines(dir//"/beam_array.nml", [character(len=200) :: &
                "&system mass_file = 'beam_m_array.mtx', stiffness_file = 'beam_k_array.mtx', "// &
                "ndof = 8 /", beam_forcing, beam_friction, beam_hbm])
            call read_case(dir//"/beam_array.nml", c, error)
            call check_error(t, error, "beam array files: read", .false.)
            if (.not. allocated(error)) call check(t, all(c%model%mass == m) .and. &
                all(c%model%stiffness == k), "beam array files: M and K exact")
        end block
        opts = a%hbm
        call solve_periodic(a%model, opts, sa, error)
        call check_error(t, error, "beam inline: solve", .false.)
        if (allocated(error)) return
        call solve_periodic(b%model, opts, sb, error)
        call check_error(t, error, "beam files: solve", .false.)
        if (allocated(error)) return
        call check(t, sa%converged .and. sb%converged, "beam: both solves converge")
        call check_close(t, reshape(sb%x, [size(sb%x)]), reshape(sa%x, [size(sa%x)]), &
                         "beam: same displacements both ways", rtol=0.0_dp, &
                         atol=1e-12_dp*maxval(abs(sa%x)))
        call check(t, maxval(abs(sa%x(:, 7))) > 0.0_dp, "beam: the contact DOF moves")
        ! a sweep checkpoint of a model from files is tied to the matrices, not only the names
        block
            character(len=16) :: fp
            fp = case_fingerprint(b, error)
            b%model%stiffness(3, 3) = b%model%stiffness(3, 3)*(1.0_dp + epsilon(1.0_dp))
            call check(t, case_fingerprint(b, error) /= fp, "beam files: fingerprint follows the "// &
                       "matrix values")
        end block
    end subroutine test_beam_both_ways

    !> Relative paths from the case file's folder; absolute paths; the echo reads back from
    !> another folder.
    subroutine test_paths(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: k(:, :), m(:, :)
        type(case_t) :: a, b
        type(error_type), allocatable :: error
        integer :: u, stat
        character(len=300) :: msg
        character(len=400) :: text(3)
        call beam(2, k, m)
        call write_symmetric(dir//"/sub/m.mtx", m)
        call write_symmetric(dir//"/other/k.mtx", k)
        call write_symmetric(dir//"/other/c.mtx", 0.01_dp*k)
        ! the case sits in sub/; the working directory is the project root
        ! damping_file absolute (no variable text in an array constructor: gfortran 12)
        text(1) = "&system mass_file = 'm.mtx', stiffness_file = '../other/k.mtx', "// &
                  "damping_file = '"//scratch_dir()//"/sysfiles/other/c.mtx', rayleigh_beta = 1e-3 /"
        text(2) = "&forcing omega = 100.0, force_dof = 1, force_amplitude = 1.0 /"
        text(3) = "&output directory = '"//dir//"/out' /"
        call write_lines(dir//"/sub/case.nml", text)
        call read_case(dir//"/sub/case.nml", a, error)
        call check_error(t, error, "paths: relative to the case file's folder", .false.)
        if (allocated(error)) return
        call check(t, a%system_files%mass_path == dir//"/sub/m.mtx" .and. &
                   a%system_files%stiffness_path == dir//"/sub/../other/k.mtx", &
                   "paths: resolved against the case folder", a%system_files%mass_path)
        call check(t, a%system_files%mass_absolute(1:1) == "/", "paths: echoed absolute")
        call check_close(t, reshape(a%model%damping, [16]), &
                         reshape(0.01_dp*k + 1.0e-3_dp*k, [16]), &
                         "paths: damping_file plus beta K", rtol=1e-14_dp, atol=1e-10_dp)
        ! write_case's echo, read from another folder
        open (newunit=u, file=dir//"/other/echo.nml", status='replace', action='write')
        msg = ""
        call write_case(u, a, stat, msg)
        close (u)
        call check(t, stat == 0, "paths: echo written")
        call read_case(dir//"/other/echo.nml", b, error)
        call check_error(t, error, "paths: echo reads back from another folder", .false.)
        if (allocated(error)) return
        call check(t, all(a%model%mass == b%model%mass) .and. &
                   all(a%model%stiffness == b%model%stiffness) .and. &
                   all(a%model%damping == b%model%damping) .and. &
                   b%system_files%rayleigh_beta == 1.0e-3_dp .and. &
                   allocated(b%system_files%damping_file), "paths: echo gives the same model")
    end subroutine test_paths

    !> A case whose &system is `system` (forcing on DOF 1): the error contains `what`.
    subroutine bad(t, name, system, what, stat)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: name, system
        character(len=*), intent(in) :: what(:)
        integer, intent(in), optional :: stat
        type(case_t) :: c
        type(error_type), allocatable :: error
        character(len=400) :: text(2)
        text(1) = system
        text(2) = good_forcing
        call write_lines(dir//"/bad.nml", text)
        call read_case(dir//"/bad.nml", c, error)
        call check_error(t, error, "system files bad: "//name, .true., what)
        if (allocated(error)) call check(t, error%stat == merge(stat, stickslip_stat%input, &
                                         present(stat)), "system files bad: "//name//": stat")
    end subroutine bad

    subroutine test_bad_cases(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: k(:, :), m(:, :)
        integer :: u, i
        call beam(4, k, m)
        call write_symmetric(dir//"/m8.mtx", m)
        call write_symmetric(dir//"/k8.mtx", k)
        call beam(2, k, m)
        call write_symmetric(dir//"/k4.mtx", k)
        m(1, 1) = -m(1, 1)
        call write_symmetric(dir//"/m_indefinite.mtx", m)
        call bad(t, "ndof disagrees", "&system ndof = 5, mass_file = 'm8.mtx', "// &
                 "stiffness_file = 'k8.mtx' /", [character(len=80) :: "&system ndof = 5", &
                 "mass_file '"//dir//"/m8.mtx'", "8 x 8", "must agree"])
        call bad(t, "inline and file", "&system mass_file = 'm8.mtx', stiffness_file = "// &
                 "'k8.mtx', mass = 1 /", [character(len=80) :: dir//"/bad.nml:1:", &
                 "&system mass and mass_file both given"])
        call bad(t, "inline damping beside files", "&system mass_file = 'm8.mtx', "// &
                 "stiffness_file = 'k8.mtx', damping = 0 /", [character(len=80) :: &
                 "&system damping and damping_file"])
        call bad(t, "mass_file alone", "&system mass_file = 'm8.mtx' /", &
                 [character(len=80) :: "&system stiffness_file: missing"])
        call bad(t, "sizes differ", "&system mass_file = 'm8.mtx', stiffness_file = "// &
                 "'k4.mtx' /", [character(len=80) :: "stiffness_file '"//dir//"/k4.mtx'", &
                 "4 x 4", "sizes must agree"])
        call bad(t, "missing file", "&system mass_file = 'nope.mtx', stiffness_file = "// &
                 "'k8.mtx' /", [character(len=80) :: dir//"/bad.nml: &system mass_file", &
                 dir//"/nope.mtx", "cannot open"], stickslip_stat%io)
        call bad(t, "indefinite mass", "&system mass_file = 'm_indefinite.mtx', "// &
                 "stiffness_file = 'k4.mtx' /", [character(len=80) :: "&system mass", &
                 "m_indefinite.mtx", "diagonal masses must be > 0"])
        call bad(t, "negative rayleigh", "&system ndof = 1, mass = 1, stiffness = 1, "// &
                 "rayleigh_alpha = -0.1 /", [character(len=80) :: "&system rayleigh_alpha", &
                 "finite and >= 0"])
        call bad(t, "inline limit", "&system ndof = 65 /", [character(len=80) :: &
                 "&system ndof = 65", "use mass_file/stiffness_file for larger models"])
        call bad(t, "empty name", "&system mass_file = '', stiffness_file = 'k8.mtx' /", &
                 [character(len=80) :: "&system mass_file = ''"])
        ! a bad file: its line
        call write_lines(dir//"/m_nan.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real symmetric", "% c", "2 2 2", "1 1 1", &
            "2 2 nan"])
        call bad(t, "NaN in the file", "&system mass_file = 'm_nan.mtx', stiffness_file = "// &
                 "'k8.mtx' /", [character(len=80) :: dir//"/m_nan.mtx:5:", "not a finite"])
        ! non-symmetric general mass
        call write_lines(dir//"/m_gen.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real general", "2 2 3", "1 1 1", "2 2 1", &
            "2 1 0.1"])
        call bad(t, "non-symmetric mass", "&system mass_file = 'm_gen.mtx', stiffness_file "// &
                 "= 'm_gen.mtx' /", [character(len=80) :: "m_gen.mtx'", "M is not symmetric"])
        ! beyond the DOF limit of this increment
        open (newunit=u, file=dir//"/big.mtx", status='replace', action='write')
        write (u, '(a)') "%%MatrixMarket matrix coordinate real symmetric"
        write (u, '(a)') "2001 2001 2001"
        do i = 1, 2001
            write (u, '(i0,1x,i0,a)') i, i, " 1.0"
        end do
        close (u)
        ! beyond it, 'none' keeps the model sparse: only the weighted residual runs
        call bad(t, "beyond 2000 DOFs", "&system mass_file = 'big.mtx', stiffness_file = "// &
                 "'big.mtx' / &reduction method = 'none' / &run method = 'euler' /", &
                 [character(len=80) :: "&run method = 'euler'", "N = 2001", &
                 "&reduction method = 'none'", "'craig-bampton'"])
        ! read sparse then ('none'): a truncated file is named with its line
        call write_lines(dir//"/huge.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real symmetric", "5000 5000 50000", "1 1 1"])
        call bad(t, "'none' reads large files sparse", "&system mass_file = 'huge.mtx', "// &
                 "stiffness_file = 'huge.mtx' / &reduction method = 'none' /", &
                 [character(len=80) :: "huge.mtx:3:", "end of file"])
        ! size claims the entries cannot back fail at once (issue 17): a mass matrix
        ! needs its N diagonal entries; a stiffness of another size than M is named
        call write_lines(dir//"/m_claims.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real symmetric", "% claims 1e9 DOFs", &
            "1000000000 1000000000 2", "1 1 1", "2 2 1"])
        call bad(t, "a size the entries cannot back", "&system mass_file = 'm_claims.mtx', "// &
                 "stiffness_file = 'm_claims.mtx' /", [character(len=80) :: &
                 "&system mass_file '"//dir//"/m_claims.mtx':3:", "1000000000 x 1000000000", &
                 "with 2 entries", "needs its 1000000000 diagonal entries"])
        call write_lines(dir//"/k_claims.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real symmetric", "2147483647 2147483647 2", &
            "1 1 1", "2 2 1"])
        call bad(t, "a stiffness claiming 2**31-1 rows", "&system mass_file = 'm8.mtx', "// &
                 "stiffness_file = 'k_claims.mtx' /", [character(len=80) :: &
                 "&system stiffness_file '"//dir//"/k_claims.mtx'", "2147483647 x 2147483647", &
                 "N = 8", "sizes must agree"])
        ! a size line announcing 10**8 entries of a file holding 2: read as the entries
        ! come, it ends at the end of the file, without allocating for 10**8 first
        call write_lines(dir//"/m_e8.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix coordinate real symmetric", "100000000 100000000 100000000", &
            "1 1 1", "2 2 1"])
        call bad(t, "10**8 entries announced, 2 given", "&system mass_file = 'm_e8.mtx', "// &
                 "stiffness_file = 'm_e8.mtx' /", [character(len=80) :: "m_e8.mtx:4:", &
                 "end of file after 2 of the 100000000 entries"])
        block
            type(error_type), allocatable :: ignored
            call make_directory(dir//"/a_directory", ignored)
        end block
        call bad(t, "a directory given as mass_file", "&system mass_file = 'a_directory', "// &
                 "stiffness_file = 'k8.mtx' /", [character(len=80) :: &
                 "&system mass_file: "//dir//"/a_directory: a directory, not a Matrix Market "// &
                 "file"])
        ! a direction of length 1e-300 underflows every mobility: named, not "rho = 0"
        call write_lines(dir//"/w_tiny.mtx", [character(len=60) :: &
            "%%MatrixMarket matrix array real general", "8 1", "1e-300", "0", "0", "0", "0", &
            "0", "0", "0"])
        call bad(t, "a direction out of scale", "&system mass_file = 'm8.mtx', "// &
                 "stiffness_file = 'k8.mtx' / &friction direction_file = 'w_tiny.mtx', "// &
                 "mu = 0.3, normal_load = 1 /", [character(len=80) :: &
                 "&friction direction_file '"//dir//"/w_tiny.mtx' column 1: largest entry", &
                 "out of scale"])
        call bad(t, "reduction modes bounded", "&system mass_file = 'm8.mtx', "// &
                 "stiffness_file = 'k8.mtx' / &reduction method = 'craig-bampton', "// &
                 "modes = 2147483647 /", [character(len=80) :: &
                 "&reduction modes = 2147483647", "must be <= 500"])
        ! a damping file of another size than the model
        call bad(t, "damping size", "&system mass_file = 'm8.mtx', stiffness_file = "// &
                 "'k8.mtx', damping_file = 'k4.mtx' /", [character(len=80) :: &
                 "&system damping_file", "4 x 4", "N = 8", "sizes must agree"])
    end subroutine test_bad_cases

    !> examples/beam_mm/beam.nml reads, with its files, and solves.
    subroutine test_example(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(error_type), allocatable :: error
        type(hbm_solution_t) :: s
        call read_case("examples/beam_mm/beam.nml", c, error)
        call check_error(t, error, "example beam_mm: reads", .false.)
        if (allocated(error)) return
        call check(t, c%model%ndof == 80 .and. c%method == 'hbm', "example beam_mm: 80 DOFs, hbm")
        call solve_periodic(c%model, c%hbm, s, error)
        call check_error(t, error, "example beam_mm: solves", .false.)
        if (.not. allocated(error)) call check(t, s%converged, "example beam_mm: converged")
        ! the command line on a copy (files by absolute path, output in the scratch area):
        ! exit 0 (converged and trusted), and summary.nml reads back as the case
        block
            integer :: ui, uo, ue, stat, code
            character(len=1000) :: line
            type(string_t), allocatable :: args(:)
            type(case_t) :: back
            open (newunit=ui, file="examples/beam_mm/beam.nml", status='old', action='read')
            open (newunit=uo, file=dir//"/beam_copy.nml", status='replace', action='write')
            do
                read (ui, '(a)', iostat=stat) line
                if (stat /= 0) exit
                if (index(line, "&output") > 0) line = "&output directory = '"//dir//"/out_beam' /"
                if (index(line, "mass_file") > 0) line = "mass_file = '"// &
                    project_path("examples/beam_mm/mass.mtx")//"'"
                if (index(line, "stiffness_file") > 0) line = "stiffness_file = '"// &
                    project_path("examples/beam_mm/stiffness.mtx")//"'"
                write (uo, '(a)') trim(line)
            end do
            close (ui)
            close (uo)
            allocate (args(1))
            args(1)%s = dir//"/beam_copy.nml"
            open (newunit=uo, status='scratch', action='readwrite')
            open (newunit=ue, status='scratch', action='readwrite')
            code = run_cli(args, uo, ue)
            close (uo)
            close (ue)
            call check(t, code == 0, "example beam_mm: the command line exits 0")
            call read_case(dir//"/out_beam/summary.nml", back, error)
            call check_error(t, error, "example beam_mm: summary.nml reads back", .false.)
            if (.not. allocated(error)) call check(t, all(back%model%mass == c%model%mass) &
                .and. all(back%model%damping == c%model%damping), &
                "example beam_mm: summary.nml gives the same model")
        end block
    end subroutine test_example
end module test_system_files
