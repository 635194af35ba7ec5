!> The CalculiX example (examples/calculix_beam): the committed matrices that CalculiX
!> exported (*FREQUENCY, SOLVER=MATRIXSTORAGE) and make_model.py converted read as a
!> symmetric 2412-DOF pair with a positive diagonal; dofs.csv maps the case file's contact and
!> force DOFs to the nodes it names; the natural frequencies of the full model (ARPACK on the
!> files) equal the ones CalculiX's own eigensolver printed (calculix_frequencies.txt, 7
!> digits), an independent truth: another program's eigensolver on its own assembly; the
!> Craig-Bampton model that case.nml builds bounds the first one from above within its
!> reduction error (1.6e-5), and with 30 fixed-interface modes equals it to the digits. The
!> picture's key shows amp_2409, not gnuplot's subscript of "_2". The nonlinear mode of the
!> reduced strip with its damper slipping has CalculiX's first frequency.
module test_calculix
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_sparse, only: sparse_matrix_t, sparse_symmetry_defect
    use stickslip_matrix_market, only: read_matrix_market
    use stickslip_arpack, only: eigen_options_t, eigen_report_t
    use stickslip_sparse_eigen, only: sparse_eigenpairs
    use stickslip_lapack, only: dsygv
    use stickslip_case, only: case_t, read_case
    use stickslip_reduction, only: craig_bampton, reduction_options_t, reduced_model_t, &
        reduction_report_t
    use testing, only: test_counter_t, check, check_close
    use stickslip_files, only: make_directory
    use stickslip_plot_scripts, only: write_frc_plot_script
    use fixtures, only: project_path, scratch_dir, write_lines
    use test_cli, only: cli
    implicit none
    private
    public :: run_calculix_tests

    !> The example's folder, relative to the project root.
    character(len=*), parameter :: folder = "examples/calculix_beam/"
    !> DOFs of the export (the constrained model: 848 nodes and the rigid tip's 2 nodes).
    integer, parameter :: ndof = 2412
    !> The case file's contact DOF (node 9001, z) and forced DOF (node 771, z).
    integer, parameter :: contact_row = 2409, force_row = 2244
    !> CalculiX prints 7 significant digits: 5e-7 relative, and the export's 14 digits.
    real(dp), parameter :: print_rtol = 1.0e-6_dp
    !> The Craig-Bampton error of the first frequency with the modes of the rule (measured
    !> 1.6e-5: 6 fixed-interface modes up to 2.0e4 rad/s, the case's 3 x 15 x 620 rad/s limit
    !> with C = 2 M).
    real(dp), parameter :: rule_rtol = 3.0e-5_dp

contains

    subroutine run_calculix_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: kmat, mmat
        real(dp), allocatable :: reference(:)
        logical :: ok
        call test_plot_titles(t)
        call read_matrices(t, kmat, mmat, ok)
        if (.not. ok) return
        call read_reference(t, reference)
        if (size(reference) < 4) return
        call test_dof_map(t)
        call test_full_frequencies(t, kmat, mmat, reference)
        call test_reduced_frequency(t, reference)
        call test_retrace(t)
        call test_more_modes(t, kmat, mmat, reference)
        call test_nonlinear_mode(t, reference)
    end subroutine run_calculix_tests

    !> modes.nml on the reduced strip (20 points over a = 1e-2 .. 1e-4 here): exit 0, the
    !> amplitude columns of the full-model DOFs 2409 and 2244 recovered through the
    !> reduction basis, and at large amplitude, where the damper slips all period, the
    !> frequency of CalculiX's first mode with the tip free (within the reduction error),
    !> the energy balance at every point.
    subroutine test_nonlinear_mode(t, reference)
        type(test_counter_t), intent(inout) :: t
        real(dp), intent(in) :: reference(:)
        character(len=:), allocatable :: dir, out, err, line
        character(len=512) :: buf
        integer :: code, u, stat
        real(dp) :: values(11), worst
        character(len=300) :: lines(6), args(1)
        dir = scratch_dir()//"/calculix_modes"
        ! (arrays assigned line by line: gfortran 12 corrupts memory on an array
        ! constructor of concatenations with variables, see fixtures)
        lines(1) = "&system mass_file = '"//project_path(folder//"mass.mtx")// &
                   "', stiffness_file = '"//project_path(folder//"stiffness.mtx")// &
                   "', rayleigh_alpha = 2.0 /"
        lines(2) = "&forcing omega = 534.7, force_dof = 2244, force_amplitude = 0.2 /"
        lines(3) = "&friction contact_dof = 2409, mu = 0.5, normal_load = 0.24 /"
        lines(4) = "&hbm harmonics = 15, samples = 256 /"
        lines(5) = "&modes amplitude_start = 1e-2, amplitude_stop = 1e-4, points = 20 /"
        lines(6) = "&output directory = '"//dir//"', dofs = 2409, 2244 /"
        call write_lines(dir//".nml", lines)
        args(1) = dir//".nml"
        call cli(args, code, out, err)
        call check(t, code == 0, "calculix modes: exit 0", err)
        if (code /= 0) return
        open (newunit=u, file=dir//"/modes.csv", status='old', action='read', iostat=stat)
        if (stat /= 0) return
        read (u, '(a)') buf
        line = trim(buf)
        call check(t, index(line, "amplitude,omega,frequency,xi,damping_ratio,amp_2409,"// &
                   "amp_2244,") == 1, "calculix modes: full-model DOF columns", line)
        read (u, *, iostat=stat) values
        call check(t, stat == 0 .and. abs(values(2) - reference(1)) <= &
                   (rule_rtol + 1.0e-5_dp)*reference(1), "calculix modes: slipping damper: "// &
                   "CalculiX's first frequency (tip free)")
        worst = values(11)
        do
            read (u, *, iostat=stat) values
            if (stat /= 0) exit
            worst = max(worst, values(11))
        end do
        close (u)
        call check(t, worst <= 1.0e-10_dp, "calculix modes: energy balance at every point")
    end subroutine test_nonlinear_mode

    !> The example's sweep at H = 45 (1024 samples, checks off) reaches 620 rad/s. With
    !> OpenBLAS's AVX-512 kernels it turns back at a kink of the sampled friction equations
    !> near 555 rad/s and would retrace its curve down to the start ("the branch left the
    !> range", exit 2); the sweep notes the retrace and steps past the kink instead. With
    !> other kernels (OPENBLAS_CORETYPE=Haswell, Zen, Nehalem) the roundoff differs and the
    !> curve does not turn there, or turns and comes back as a fold; either way the sweep
    !> must end at 620 rad/s. (The retrace logic itself is tested on synthetic curves in
    !> suite continuation.)
    subroutine test_retrace(t)
        type(test_counter_t), intent(inout) :: t
        character(len=:), allocatable :: dir, out, err
        character(len=4096) :: lines(8), arg(1), line, last
        integer :: code, u, stat
        real(dp) :: omega_end
        dir = scratch_dir()//"/calculix_retrace"
        lines(1) = "&system mass_file = '"//project_path("examples/calculix_beam/mass.mtx")//"',"
        lines(2) = "  stiffness_file = '"//project_path("examples/calculix_beam/stiffness.mtx")// &
                   "', rayleigh_alpha = 2.0 /"
        lines(3) = "&forcing omega = 534.7, force_dof = 2244, force_amplitude = 0.2 /"
        lines(4) = "&friction contact_dof = 2409, mu = 0.5, normal_load = 0.24 /"
        lines(5) = "&hbm harmonics = 45, odd_only = T, samples = 1024 /"
        lines(6) = "&sweep parameter = 'omega', start = 470.0, stop = 620.0, max_step = 1.5, "// &
                   "stability = F, truncation = F /"
        lines(7) = "&output directory = '"//dir//"', dofs = 2409, 2244 /"
        lines(8) = "&run method = 'sweep' /"
        call write_lines(dir//".nml", lines)
        ! through a variable: gfortran 12 sizes a typed constructor of a deferred-length
        ! expression by the expression and copies the declared length into it
        arg(1) = dir//".nml"
        call cli(arg, code, out, err)
        call check(t, code == 0, "calculix H = 45 sweep: complete (exit 0)", err)
        ! the last point of frc.csv is the stop value
        last = ""
        open (newunit=u, file=dir//"/frc.csv", status='old', action='read', iostat=stat)
        do while (stat == 0)
            read (u, '(a)', iostat=stat) line
            if (stat == 0) last = line
        end do
        if (stat > 0 .or. len_trim(last) == 0) last = "none"
        close (u)
        omega_end = -1.0_dp
        read (last, *, iostat=stat) omega_end
        call check(t, abs(omega_end - 620.0_dp) < 1.0e-9_dp, &
                   "calculix H = 45 sweep: ends at 620 rad/s (past the kink)", trim(last))
    end subroutine test_retrace

    !> frc.gp of the example's sweep (full-model labels 2409, 2244) names its curves
    !> "full-model DOF 2409" and "... 2244" and labels its axes with units, all as plain
    !> text: the terminal is noenhanced (gnuplot's enhanced mode would make "_2" of a label
    !> a subscript).
    subroutine test_plot_titles(t)
        type(test_counter_t), intent(inout) :: t
        type(error_type), allocatable :: error
        character(len=:), allocatable :: dir
        character(len=256) :: line
        integer :: u, stat, found
        logical :: noenhanced, units
        dir = scratch_dir()//"/calculix_plot"
        call make_directory(dir, error)
        if (.not. allocated(error)) call write_frc_plot_script(dir, "normal_load", 10, error, &
                                                                [1, 2], [2409, 2244])
        call check(t, .not. allocated(error), "calculix: frc.gp written")
        if (allocated(error)) return
        found = 0
        noenhanced = .false.
        units = .false.
        open (newunit=u, file=dir//"/frc.gp", status='old', action='read', iostat=stat)
        do while (stat == 0)
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (index(line, "title 'full-model DOF 2409'") > 0) found = found + 1
            if (index(line, "title 'full-model DOF 2244'") > 0) found = found + 1
            if (index(line, "set terminal pngcairo") == 1) noenhanced = index(line, " noenhanced") > 0
            if (index(line, "set xlabel 'normal load N [N]'") == 1) units = .true.
        end do
        close (u)
        call check(t, found == 4, "calculix: frc.gp names its curves full-model DOF 2409, "// &
                   "2244 in both pictures")
        call check(t, noenhanced, "calculix: frc.gp draws its text plain (noenhanced)")
        call check(t, units, "calculix: frc.gp labels a normal_load sweep 'normal load N [N]'")
    end subroutine test_plot_titles

    !> stiffness.mtx and mass.mtx: declared symmetric, N x N, exactly symmetric after the
    !> expansion, positive diagonals.
    subroutine read_matrices(t, kmat, mmat, ok)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t), intent(out) :: kmat, mmat
        logical, intent(out) :: ok
        type(error_type), allocatable :: error
        logical :: symk, symm
        ok = .false.
        call read_matrix_market(project_path(folder//"stiffness.mtx"), kmat, error, symk)
        call check(t, .not. allocated(error), "calculix: stiffness.mtx reads")
        if (allocated(error)) then
            write (*, '(a)') error%message
            return
        end if
        call read_matrix_market(project_path(folder//"mass.mtx"), mmat, error, symm)
        call check(t, .not. allocated(error), "calculix: mass.mtx reads")
        if (allocated(error)) return
        call check(t, symk .and. symm, "calculix: both files declared symmetric")
        call check(t, kmat%nrows == ndof .and. kmat%ncols == ndof .and. mmat%nrows == ndof &
                   .and. mmat%ncols == ndof, "calculix: K and M are 2412 x 2412")
        if (kmat%nrows /= ndof .or. mmat%nrows /= ndof) return
        call check(t, sparse_symmetry_defect(kmat) == 0.0_dp .and. &
                   sparse_symmetry_defect(mmat) == 0.0_dp, "calculix: K and M symmetric")
        call check(t, all(diagonal(kmat) > 0.0_dp), "calculix: K diagonal positive")
        call check(t, all(diagonal(mmat) > 0.0_dp), "calculix: M diagonal positive")
        ok = .true.
    end subroutine read_matrices

    !> dofs.csv: one row per DOF, and the case file's contact and force DOFs are the nodes
    !> and directions its comments name.
    subroutine test_dof_map(t)
        type(test_counter_t), intent(inout) :: t
        character(len=256) :: line
        integer :: u, stat, row, node, direction, rows, contact_node, force_node
        contact_node = 0
        force_node = 0
        rows = 0
        open (newunit=u, file=project_path(folder//"dofs.csv"), status='old', action='read', &
              iostat=stat)
        call check(t, stat == 0, "calculix: dofs.csv opens")
        if (stat /= 0) return
        read (u, '(a)', iostat=stat) line
        call check(t, trim(line) == "row,node,direction,x,y,z", "calculix: dofs.csv header")
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            read (line, *, iostat=stat) row, node, direction
            if (stat /= 0) exit
            rows = rows + 1
            if (row /= rows) exit
            if (row == contact_row .and. direction == 3) contact_node = node
            if (row == force_row .and. direction == 3) force_node = node
        end do
        close (u)
        call check(t, rows == ndof, "calculix: dofs.csv has a row per DOF, in order")
        call check(t, contact_node == 9001, "calculix: DOF 2409 is node 9001 z (rigid tip)")
        call check(t, force_node == 771, "calculix: DOF 2244 is node 771 z (the drive)")
    end subroutine test_dof_map

    !> The four lowest natural frequencies of the files (shift-invert Lanczos on the full
    !> sparse model) equal CalculiX's to its printed digits.
    subroutine test_full_frequencies(t, kmat, mmat, reference)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        real(dp), intent(in) :: reference(:)
        real(dp), allocatable :: values(:), vectors(:, :)
        type(eigen_report_t) :: report
        type(error_type), allocatable :: error
        integer :: k
        character(len=8) :: tag
        ! full storage of a symmetric matrix: its CSR arrays are its CSC arrays
        call sparse_eigenpairs(ndof, kmat%row_start, kmat%col, kmat%val, mmat%row_start, &
                               mmat%col, mmat%val, 4, 0.0_dp, eigen_options_t(), values, &
                               vectors, report, error)
        call check(t, .not. allocated(error), "calculix: full-model eigenpairs")
        if (allocated(error)) return
        do k = 1, 4
            write (tag, '(i0)') k
            call check_close(t, sqrt(values(k)), reference(k), &
                             "calculix: full model mode "//trim(tag)//" = CalculiX's", &
                             rtol=print_rtol)
        end do
    end subroutine test_full_frequencies

    !> case.nml (2412 DOFs > 2000: reduced by Craig-Bampton, the contact and the drive as
    !> boundary, the modes of the rule): the reduced model's first natural frequency is a
    !> Rayleigh-Ritz upper bound of CalculiX's, within rule_rtol.
    subroutine test_reduced_frequency(t, reference)
        type(test_counter_t), intent(inout) :: t
        real(dp), intent(in) :: reference(:)
        type(case_t) :: cs
        type(error_type), allocatable :: error
        real(dp), allocatable :: a(:, :), b(:, :), w(:), work(:)
        integer :: n, info
        call read_case(project_path(folder//"case.nml"), cs, error)
        call check(t, .not. allocated(error), "calculix: case.nml reads")
        if (allocated(error)) then
            write (*, '(a)') error%message
            return
        end if
        call check(t, cs%reduction%report%method == 'craig-bampton' .and. &
                   cs%reduction%report%full_dof == ndof, "calculix: case.nml reduced (auto)")
        call check(t, cs%reduction%contact_dof(1) == contact_row .and. &
                   cs%reduction%force_dof(1) == force_row, "calculix: case.nml DOFs")
        n = cs%model%ndof
        call check(t, n >= 3 .and. n <= 40, "calculix: a small reduced model")
        a = cs%model%stiffness
        b = cs%model%mass
        allocate (w(n), work(64*n))
        call dsygv(1, 'N', 'U', n, a, n, b, n, w, work, size(work), info)
        call check(t, info == 0, "calculix: reduced eigenproblem solved")
        if (info /= 0) return
        ! Rayleigh-Ritz: the reduced frequency bounds the full one from above
        call check(t, sqrt(w(1)) >= reference(1)*(1.0_dp - print_rtol) .and. &
                   sqrt(w(1)) <= reference(1)*(1.0_dp + rule_rtol), &
                   "calculix: case.nml's reduced first mode within 3e-5 above CalculiX's")
    end subroutine test_reduced_frequency

    !> Craig-Bampton on the files with the case's boundary (contact and drive) and 30
    !> fixed-interface modes: the first natural frequency equals CalculiX's to its digits.
    subroutine test_more_modes(t, kmat, mmat, reference)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        real(dp), intent(in) :: reference(:)
        type(reduced_model_t) :: reduced
        type(reduction_report_t) :: report
        type(error_type), allocatable :: error
        real(dp), allocatable :: a(:, :), b(:, :), w(:), work(:)
        integer :: n, info
        call craig_bampton(kmat, mmat, [contact_row, force_row], reduction_options_t(modes=30), &
                           reduced, report, error)
        call check(t, .not. allocated(error), "calculix: Craig-Bampton with 30 modes")
        if (allocated(error)) return
        n = reduced%nr
        a = reduced%stiffness
        b = reduced%mass
        allocate (w(n), work(64*n))
        call dsygv(1, 'N', 'U', n, a, n, b, n, w, work, size(work), info)
        call check(t, info == 0, "calculix: 32-DOF eigenproblem solved")
        if (info /= 0) return
        call check_close(t, sqrt(w(1)), reference(1), &
                         "calculix: 30-mode reduced first mode = CalculiX's", rtol=print_rtol)
    end subroutine test_more_modes

    !> calculix_frequencies.txt: omega [rad/s] of each mode, in order ('#' lines skipped).
    subroutine read_reference(t, omega)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable, intent(out) :: omega(:)
        character(len=256) :: line
        integer :: u, stat, mode
        real(dp) :: value, hz
        allocate (omega(0))
        open (newunit=u, file=project_path(folder//"calculix_frequencies.txt"), &
              status='old', action='read', iostat=stat)
        call check(t, stat == 0, "calculix: calculix_frequencies.txt opens")
        if (stat /= 0) return
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (line(1:1) == '#' .or. len_trim(line) == 0) cycle
            read (line, *, iostat=stat) mode, value, hz
            if (stat /= 0 .or. mode /= size(omega) + 1) exit
            omega = [omega, value]
        end do
        close (u)
        call check(t, size(omega) == 10, "calculix: ten CalculiX frequencies")
    end subroutine read_reference

    !> The diagonal of a square sparse matrix (0 where none is stored).
    function diagonal(a) result(d)
        type(sparse_matrix_t), intent(in) :: a
        real(dp), allocatable :: d(:)
        integer :: i, p
        allocate (d(a%nrows))
        d = 0.0_dp
        do i = 1, a%nrows
            do p = a%row_start(i), a%row_start(i + 1) - 1
                if (a%col(p) == i) d(i) = a%val(p)
            end do
        end do
    end function diagonal
end module test_calculix
