!> The CalculiX bladed-disk sector (examples/calculix_sector: a blade, two platforms and a
!> disk sector of C3D20R bricks, 1662 DOFs in cylindrical frames, 24 sectors; make_sector.py)
!> against independent truths: its natural frequencies per nodal diameter 0..12 from the
!> sparse sector (the real form of the Hermitian cyclic pencil, block Lanczos) equal
!> CalculiX's own *CYCLIC SYMMETRY MODEL frequencies (calculix_frequencies.txt, the 7
!> digits it prints), and the 29 lowest natural frequencies of the full disk that
!> sparse_disk assembles from it (38160 DOFs, one eigensolve) are the sector's, every
!> diameter 1..11 twice. The case's Craig-Bampton reduction keeps the cyclic faces: its
!> sector's frequencies per forced diameter agree with the full sector's within the error
!> the case measures (reduction_error_nd), which is small (< 1e-2), and the sector's cyclic
!> modes are prepared (the modal condensation).
module test_cyclic_fe
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, real_text
    use stickslip_sparse, only: sparse_matrix_t
    use stickslip_matrix_market, only: read_matrix_market
    use stickslip_arpack, only: eigen_options_t, eigen_report_t
    use stickslip_sparse_eigen, only: sparse_eigenpairs
    use stickslip_cyclic, only: cyclic_t, cyclic_frequencies, cyclic_basis, sector_phase, &
        assemble_disk
    use stickslip_model, only: model_t, force_direction
    use stickslip_cyclic_interface, only: face_reduction_t, reduce_cyclic_faces
    use stickslip_cyclic_sparse, only: cyclic_sparse_frequencies, sparse_disk
    use stickslip_namelist, only: nml_file_t, read_namelist_file
    use stickslip_namelist_values, only: get_integers
    use stickslip_case, only: case_t, read_case, modes_band
    use stickslip_case_reduction, only: write_reduction_cache_of
    use stickslip_case_cyclic, only: forced_diameters
    use stickslip_sorting, only: sort_ascending
    use testing, only: test_counter_t, check, check_error
    use fixtures, only: project_path, scratch, write_lines, enter_project_root, msg
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t
    use stickslip_cyclic_dynamics, only: new_cyclic_dynamics
    use test_cli, only: scratch_copy
    use test_cyclic, only: add_spring, model_frequencies
    implicit none
    private
    public :: run_cyclic_fe_tests

    character(len=*), parameter :: folder = "examples/calculix_sector/"
    !> CalculiX prints 7 significant digits.
    real(dp), parameter :: print_rtol = 1.0e-6_dp

contains

    subroutine run_cyclic_fe_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t) :: kmat, mmat
        type(cyclic_t) :: cyc
        type(error_type), allocatable :: error
        call read_sector(kmat, mmat, cyc, error)
        call check_error(t, error, "cyclic FE: the sector's matrices and &cyclic", .false.)
        if (allocated(error)) return
        call test_calculix_diameters(t, kmat, mmat, cyc)
        call test_full_disk(t, kmat, mmat, cyc)
        call test_reduced_sector(t, kmat, mmat, cyc)
        call test_interface_modes(t, kmat, mmat, cyc)
        call test_interface_exact(t)
        call test_run_diameters(t)
        call test_modes_band(t)
        call test_cached_diameter_errors(t)
        call test_sparse_sector_refused(t)
    end subroutine run_cyclic_fe_tests

    !> A sector of more than 2000 DOFs from Matrix Market files with &reduction method =
    !> 'none' (kept sparse) is refused in one line naming &reduction method.
    subroutine test_sparse_sector_refused(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 2001
        type(case_t) :: c
        type(error_type), allocatable :: error
        integer :: u, i
        call enter_project_root()
        open (newunit=u, file=scratch//"/big_sector_k.mtx", status='replace', action='write')
        write (u, '(a)') "%%MatrixMarket matrix coordinate real symmetric"
        write (u, '(3i6)') n, n, n
        do i = 1, n
            write (u, '(2i6,a)') i, i, " 1000.0"
        end do
        close (u)
        open (newunit=u, file=scratch//"/big_sector_m.mtx", status='replace', action='write')
        write (u, '(a)') "%%MatrixMarket matrix coordinate real symmetric"
        write (u, '(3i6)') n, n, n
        do i = 1, n
            write (u, '(2i6,a)') i, i, " 1.0"
        end do
        close (u)
        call write_lines(scratch//"/big_sector.nml", [character(len=100) :: &
            "&system mass_file = 'big_sector_m.mtx', stiffness_file = 'big_sector_k.mtx' /", &
            "&forcing omega = 10.0, force_dof = 3, force_amplitude = 1.0 /", &
            "&friction contact_dof = 3, mu = 0.3, normal_load = 1.0 /", &
            "&cyclic sectors = 24, engine_order = 3, left_dofs = 1, right_dofs = 2 /", &
            "&reduction method = 'none' /", "&output directory = 'big_sector' /"])
        call read_case(scratch//"/big_sector.nml", c, error)
        call check_error(t, error, "cyclic FE: a sector kept sparse", .true., &
                         ["&reduction method = 'none'", "big_sector.nml            "])
    end subroutine test_sparse_sector_refused

    !> The sector's frequencies per nodal diameter 0..12 (the 3 lowest, distinct) against
    !> CalculiX's (modes 1, 3, 5 of each diameter: it lists each twice).
    subroutine test_calculix_diameters(t, kmat, mmat, cyc)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        type(cyclic_t), intent(in) :: cyc
        type(error_type), allocatable :: error
        real(dp), allocatable :: w(:)
        real(dp) :: ccx(0:12, 6), worst
        integer :: nd
        call read_calculix(ccx, error)
        call check_error(t, error, "cyclic FE: calculix_frequencies.txt", .false.)
        if (allocated(error)) return
        worst = 0.0_dp
        do nd = 0, 12
            call cyclic_sparse_frequencies(kmat, mmat, cyc, nd, 3, w, error)
            if (allocated(error)) exit
            worst = max(worst, maxval(abs(w - ccx(nd, [1, 3, 5]))/ccx(nd, [1, 3, 5])))
        end do
        call check_error(t, error, "cyclic FE: frequencies per nodal diameter", .false.)
        if (allocated(error)) return
        call check(t, worst < print_rtol, "cyclic FE: the sector's frequencies per nodal "// &
                   "diameter 0..12 = CalculiX's cyclic symmetry model's", &
                   "largest relative difference "//real_text(worst))
    end subroutine test_calculix_diameters

    !> The full disk's 29 lowest natural frequencies (one sparse eigensolve on the 24
    !> sectors assembled) = the sector's two lowest per diameter 0..12 and the next ones
    !> of 0..2, each diameter 1..11 twice (the lowest 29, as the next diameter's second
    !> frequency lies above them).
    subroutine test_full_disk(t, kmat, mmat, cyc)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        type(cyclic_t), intent(in) :: cyc
        type(sparse_matrix_t) :: kd, md
        type(error_type), allocatable :: error
        type(eigen_report_t) :: report
        real(dp), allocatable :: w(:), sector(:), values(:), vectors(:, :)
        integer, parameter :: nev = 29
        integer :: nd
        real(dp) :: worst
        call sparse_disk(kmat, cyc, kd, error)
        if (.not. allocated(error)) call sparse_disk(mmat, cyc, md, error)
        call check_error(t, error, "cyclic FE: the full disk assembled", .false.)
        if (allocated(error)) return
        allocate (sector(0))
        do nd = 0, 12
            call cyclic_sparse_frequencies(kmat, mmat, cyc, nd, 2, w, error)
            if (allocated(error)) exit
            if (nd == 0 .or. nd == 12) then
                sector = [sector, w]
            else
                sector = [sector, w, w]
            end if
        end do
        call check_error(t, error, "cyclic FE: the sector's two lowest per diameter", .false.)
        if (allocated(error)) return
        call sort_ascending(sector)
        call sparse_eigenpairs(kd%nrows, kd%row_start, kd%col, kd%val, md%row_start, md%col, &
                               md%val, nev, 0.0_dp, eigen_options_t(), values, vectors, &
                               report, error)
        call check_error(t, error, "cyclic FE: the full disk's eigensolve", .false.)
        if (allocated(error)) return
        worst = maxval(abs(sqrt(values) - sector(1:nev))/sector(1:nev))
        call check(t, kd%nrows == 24*(1662 - size(cyc%right)) .and. worst < 1.0e-8_dp, &
                   "cyclic FE: the full disk's 29 lowest frequencies (38160 DOFs) = the "// &
                   "sector's per diameter, 1..11 twice", "largest relative difference "// &
                   real_text(worst))
    end subroutine test_full_disk

    !> The case's reduced sector: the faces kept, its cyclic modes prepared, the error per
    !> forced diameter measured and below 1e-2, and its lowest frequencies there within it.
    subroutine test_reduced_sector(t, kmat, mmat, cyc)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        type(cyclic_t), intent(in) :: cyc
        type(case_t) :: c
        type(error_type), allocatable :: error
        real(dp), allocatable :: wr(:), wf(:)
        real(dp) :: worst, ccx_worst
        integer :: k
        type(cyclic_t) :: plain
        type(basis_t) :: basis
        type(dynamics_t) :: dm, dd
        complex(dp), allocatable :: tt(:, :), z(:, :), f(:)
        complex(dp) :: e
        real(dp) :: fscale, zscale, res_modal, res_lu
        ccx_worst = huge(1.0_dp)
        call read_case(faces_kept_copy(), c, error)
        call check_error(t, error, "cyclic FE: read the case", .false.)
        if (allocated(error)) return
        call check(t, c%reduction%report%reduced_dof < 300 .and. &
                   size(c%cyclic%cyc%left) == size(cyc%left) .and. &
                   allocated(c%cyclic%cyc%modes), "cyclic FE: the reduced sector keeps its "// &
                   "cyclic faces, its cyclic modes prepared")
        call check(t, allocated(c%cyclic%diameters), "cyclic FE: the reduction's error per "// &
                   "nodal diameter measured")
        if (.not. allocated(c%cyclic%diameters)) return
        worst = 0.0_dp
        do k = 1, size(c%cyclic%diameters)
            call cyclic_frequencies(c%cyclic%sector, c%cyclic%cyc, c%cyclic%diameters(k), wr, &
                                    error)
            if (allocated(error)) exit
            call cyclic_sparse_frequencies(kmat, mmat, cyc, c%cyclic%diameters(k), 3, wf, error)
            if (allocated(error)) exit
            ! (the reduced ones are not exactly above: the reduced matrices take the
            ! fixed-interface modes as exact, K_mm = Lambda, and they are to the
            ! eigensolver's tolerance; measured -1.6e-7 relative at ND 9)
            worst = max(worst, maxval(abs(wr(1:3) - wf)/wf/c%cyclic%diameter_errors(k)))
            if (c%cyclic%diameters(k) == 3) ccx_worst = maxval(abs(wr([1, 2]) - &
                [1003.840_dp, 4924.593_dp])/[1003.840_dp, 4924.593_dp])
        end do
        call check_error(t, error, "cyclic FE: reduced against full", .false.)
        if (allocated(error)) return
        call check(t, maxval(c%cyclic%diameter_errors) < 1.0e-2_dp .and. worst <= 1.0_dp, &
                   "cyclic FE: the reduced sector's frequencies per forced diameter within "// &
                   "its measured error", "errors "// &
                   real_text(maxval(c%cyclic%diameter_errors))//", worst ratio "// &
                   real_text(worst))
        call check(t, ccx_worst < print_rtol + c%cyclic%diameter_errors(1), &
                   "cyclic FE: the reduced sector's two lowest frequencies in diameter 3 = "// &
                   "CalculiX's", real_text(ccx_worst))
        ! the modal condensation (BLAS products of the 180-DOF sector's shapes) against the
        ! dense LU of the projected pencil, every harmonic 1..15 at the case's omega, its
        ! resonance. Backward errors at h = 1: the residuals T^H (Z X0 - F) over ||T^H Z T||
        ! ||X0|| + ||T^H F|| (infinity norms) are 3.0e-12 for the modal sum and 2.9e-18 for
        ! the LU: the sector's pencil spans ten decades and the modal sum loses about four
        ! digits of it (a refinement step brought it to the LU's, but moved X0 by no more
        ! than the two differ, at 2.3 times the cost per point, and was dropped). Their
        ! forward difference, 9.4e-8 of the largest entry, is that backward error times the
        ! condition of a damped resonance: far below the reduction's and the truncation's
        ! errors (1e-3, 1e-2).
        plain = c%cyclic%cyc
        deallocate (plain%modes)
        call new_basis(basis, 15, .false., 64, error)
        if (.not. allocated(error)) call new_cyclic_dynamics(dm, c%cyclic%sector, &
                                                             c%cyclic%cyc, basis, error, .true.)
        if (.not. allocated(error)) call new_cyclic_dynamics(dd, c%cyclic%sector, plain, &
                                                             basis, error, .true.)
        call check_error(t, error, "cyclic FE: the condensations", .false.)
        if (allocated(error)) return
        worst = max(maxval(abs(dm%x0 - dd%x0))/maxval(abs(dd%x0)), &
                    maxval(abs(dm%y - dd%y))/maxval(abs(dd%y)), &
                    maxval(abs(dm%g - dd%g))/maxval(abs(dd%g)), &
                    maxval(abs(dm%dg - dd%dg))/maxval(abs(dd%dg)), &
                    maxval(abs(dm%damping_gram - dd%damping_gram))/ &
                    maxval(abs(dd%damping_gram)))
        e = exp(cmplx(0.0_dp, sector_phase(1, 3, 24, 1), dp))
        associate (sec => c%cyclic%sector)
            tt = cyclic_basis(c%cyclic%cyc, sec%ndof, e)
            z = cmplx(sec%stiffness - sec%omega**2*sec%mass, sec%omega*sec%damping, dp)
            f = sec%force_amplitude(1)*exp(cmplx(0.0_dp, sec%force_phase(1), dp))* &
                force_direction(sec, 1)
        end associate
        fscale = maxval(abs(matmul(conjg(transpose(tt)), f)))
        zscale = maxval(sum(abs(matmul(conjg(transpose(tt)), matmul(z, tt))), 2))
        res_modal = maxval(abs(matmul(conjg(transpose(tt)), matmul(z, dm%x0(:, 1)) - f)))/ &
                    (zscale*maxval(abs(dm%x0(:, 1))) + fscale)
        res_lu = maxval(abs(matmul(conjg(transpose(tt)), matmul(z, dd%x0(:, 1)) - f)))/ &
                 (zscale*maxval(abs(dd%x0(:, 1))) + fscale)
        call check(t, res_modal < 1.0e-10_dp .and. res_lu < 1.0e-14_dp, "cyclic FE: the "// &
                   "modal and the dense condensation of the reduced sector: normwise "// &
                   "backward errors", &
                   "normwise residuals at h = 1: modal "//real_text(res_modal)//", LU "// &
                   real_text(res_lu))
        call check(t, worst < 1.0e-6_dp, "cyclic FE: the modal condensation of the reduced "// &
                   "sector = the dense LU", "largest difference "//real_text(worst))
        call basis%destroy()
    end subroutine test_reduced_sector

    !> The diameters where a reduced sector's error is measured: a forced run's (EO 3, N =
    !> 24, odd harmonics to 15: 3 and 9) and a run of the backbones of diameters 1..6 (their
    !> odd harmonics reach 1..7, 9..12; calculix_sector/modes.nml).
    subroutine test_run_diameters(t)
        type(test_counter_t), intent(inout) :: t
        type(cyclic_t) :: c
        integer :: k
        c%sectors = 24
        c%engine_order = 3
        call check(t, all_equal(forced_diameters(c, 15, .true.), [3, 9]) .and. &
                   all_equal(forced_diameters(c, 15, .true., [(k, k=1, 6)]), &
                             [1, 2, 3, 4, 5, 6, 7, 9, 10, 11, 12]) .and. &
                   all_equal(forced_diameters(c, 2, .false., [5]), [0, 5, 10]), &
                   "cyclic FE: the diameters a run's error is measured in (forced, backbones)")
    contains
        logical function all_equal(a, b)
            integer, intent(in) :: a(:), b(:)
            all_equal = size(a) == size(b)
            if (all_equal) all_equal = all(a == b)
        end function all_equal
    end subroutine test_run_diameters

    !> The band where a run of modes measures a reduced sector's error (modes_band): H times
    !> the highest frequency its backbones reach. On the damper disk's example (H = 20,
    !> diameters 1, 2, 5..11) every stuck frequency is 2.887 rad/s, and diameter 1's
    !> slipping one, 3.1397 (its backbone rises to it: summary.nml omega_slipping_nd1), is
    !> the highest: 62.79 rad/s. A forced run has none (0: H times its omega). And a
    !> &modes mode list of the wrong length on the CalculiX sector is refused before the
    !> reduction runs (nothing reduced), not after it.
    subroutine test_modes_band(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(nml_file_t) :: nml, forced
        type(error_type), allocatable :: error
        real(dp) :: band, none
        call read_case(project_path("examples/bladed_disk_damper_modes.nml"), c, error)
        if (.not. allocated(error)) call read_namelist_file(project_path( &
            "examples/bladed_disk_damper_modes.nml"), nml, error)
        if (.not. allocated(error)) call read_namelist_file(project_path( &
            "examples/bladed_disk_damper.nml"), forced, error)
        call check_error(t, error, "cyclic FE modes band: read the examples", .false.)
        if (allocated(error)) return
        band = modes_band(nml, c%cyclic%sector, c%cyclic%cyc, 20)
        none = modes_band(forced, c%cyclic%sector, c%cyclic%cyc, 20)
        call check(t, abs(band - 20.0_dp*3.1397075968891_dp) < 1.0e-9_dp*band .and. &
                   none == 0.0_dp, "cyclic FE modes band: H times the backbones' highest "// &
                   "frequency (diameter 1's slipping one), none for a sweep", &
                   "band "//real_text(band)//", sweep "//real_text(none))
        call read_case(edited_copy("fe_modelist_", "mode = 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3", &
                                   "mode = 2, 3", "calculix_sector/modes"), c, error)
        call check(t, message_has(error, "&modes mode: 2 values, but 12 nodal diameters "// &
                   "are traced (&modes nodal_diameters)") .and. &
                   c%reduction%report%reduced_dof == 0, "cyclic FE modes band: a wrong-length "// &
                   "&modes mode refused before the reduction", msg(error))
    end subroutine test_modes_band

    !> The error per nodal diameter on a reduction-cache hit: the CalculiX case read (the
    !> error measured on the full sector, kept with the reduced model), its cache written,
    !> then read again (a hit, the full matrices not read): the same diameters and errors,
    !> bit for bit. With engine order 5 (diameters the cache did not measure) the hit
    !> measures nothing and says so in a note.
    subroutine test_cached_diameter_errors(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: first, again, other
        type(error_type), allocatable :: error
        character(len=:), allocatable :: path, path5
        logical :: noted, same
        integer :: k, u
        path = edited_copy("fe_cache_nd_", "interface_modes = 12", "interface_modes = 12")
        call read_case(path, first, error)
        if (.not. allocated(error)) then
            if (first%reduction%cache_status == 'hit') then
                ! a cache left by an earlier run of the tests: removed, read again
                open (newunit=u, file=first%reduction%cache_path, status='old')
                close (u, status='delete')
                call read_case(path, first, error)
            end if
        end if
        if (.not. allocated(error)) call write_reduction_cache_of(first%reduction)
        if (.not. allocated(error)) call read_case(path, again, error)
        call check_error(t, error, "cyclic FE cache: read twice", .false.)
        if (allocated(error)) return
        same = allocated(first%cyclic%diameters) .and. allocated(again%cyclic%diameters)
        if (same) same = size(again%cyclic%diameters) == size(first%cyclic%diameters)
        if (same) same = all(again%cyclic%diameters == first%cyclic%diameters) .and. &
                         all(again%cyclic%diameter_errors == first%cyclic%diameter_errors)
        call check(t, first%reduction%cache_status /= 'hit' .and. &
                   again%reduction%cache_status == 'hit' .and. same, "cyclic FE cache: the "// &
                   "error per nodal diameter restored on a hit, bit for bit", "first "// &
                   trim(first%reduction%cache_status)//", then "// &
                   trim(again%reduction%cache_status)//", restored "//merge("T", "F", same))
        ! the same cache (its folder) for engine order 5: its diameters were not measured
        path5 = path(1:len(path) - 4)//"_eo5.nml"
        call copy_edited(path, path5, "engine_order = 3", "engine_order = 5")
        call read_case(path5, other, error)
        call check_error(t, error, "cyclic FE cache: engine order 5", .false.)
        if (allocated(error)) return
        noted = .false.
        if (allocated(other%reduction%diagnostics%items)) then
            do k = 1, size(other%reduction%diagnostics%items)
                noted = noted .or. other%reduction%diagnostics%items(k)%key == &
                        "reduction_error_nd_cached"
            end do
        end if
        call check(t, other%reduction%cache_status == 'hit' .and. &
                   .not. allocated(other%cyclic%diameters) .and. noted, "cyclic FE cache: "// &
                   "diameters the cache did not measure: none restored, a note says so")
    end subroutine test_cached_diameter_errors

    !> The interface reduction's exactness on a sector with 5-DOF faces (6 sectors; faces
    !> 1..5 and 6..10, three interior DOFs, springs within and across): with the band
    !> holding the two lowest cyclic modes (their face motion at most rank 4), 4 interface
    !> modes keep them exactly (Rayleigh-Ritz: 1e-10) and leave nothing out; and the disk
    !> assembled from the reduced sector (its interface pairs merged like DOF pairs) has the
    !> reduced sector's cyclic frequencies, each diameter 1, 2 twice (1e-10).
    subroutine test_interface_exact(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector, reduced, disk
        type(cyclic_t) :: cyc, rcyc
        type(face_reduction_t) :: red
        type(error_type), allocatable :: error
        real(dp), allocatable :: w(:), low(:), all(:), ev(:)
        integer, allocatable :: low_nd(:)
        real(dp) :: band, worst
        integer :: nd, j, info
        call wide_face_sector(sector, cyc)
        allocate (low(0), low_nd(0), all(0))
        do nd = 0, 3
            call cyclic_frequencies(sector, cyc, nd, w, error)
            if (allocated(error)) exit
            all = [all, w]
        end do
        call check_error(t, error, "cyclic interface exact: the sector's frequencies", .false.)
        if (allocated(error)) return
        call sort_ascending(all)
        band = 0.5_dp*(all(2) + all(3))
        reduced = sector
        rcyc = cyc
        call reduce_cyclic_faces(reduced, rcyc, 4, [integer ::], band, red, error)
        call check_error(t, error, "cyclic interface exact: reduce the faces", .false.)
        if (allocated(error)) return
        ! every mode of the band found again in its diameter
        worst = 0.0_dp
        do nd = 0, 3
            call cyclic_frequencies(sector, cyc, nd, w, error)
            if (allocated(error)) exit
            low = pack(w, w < band)
            if (size(low) == 0) cycle
            call cyclic_frequencies(reduced, rcyc, nd, w, error)
            if (allocated(error)) exit
            do j = 1, size(low)
                worst = max(worst, minval(abs(w - low(j)))/low(j))
            end do
        end do
        call check_error(t, error, "cyclic interface exact: the reduced frequencies", .false.)
        if (allocated(error)) return
        call check(t, worst < 1.0e-10_dp .and. red%share_left_out < 1.0e-12_dp .and. &
                   red%modes_in_band == 2 .and. reduced%ndof == 3 + 8 .and. &
                   size(rcyc%left) == 4, "cyclic interface exact: the band's modes kept "// &
                   "exactly by 4 interface modes of the 5-DOF faces", "largest relative "// &
                   "difference "//real_text(worst)//", share left out "// &
                   real_text(red%share_left_out))
        ! the disk of reduced sectors
        call assemble_disk(reduced, rcyc, disk, error)
        call check_error(t, error, "cyclic interface exact: assemble the disk", .false.)
        if (allocated(error)) return
        deallocate (all)
        allocate (all(0))
        do nd = 0, 3
            call cyclic_frequencies(reduced, rcyc, nd, w, error)
            if (allocated(error)) exit
            all = [all, w]
            if (nd == 1 .or. nd == 2) all = [all, w]
        end do
        call check_error(t, error, "cyclic interface exact: every diameter", .false.)
        if (allocated(error)) return
        call sort_ascending(all)
        call model_frequencies(disk, ev, info)
        if (info /= 0 .or. size(ev) /= size(all)) then
            call check(t, .false., "cyclic interface exact: the disk's eigenvalues", &
                       "info "//real_text(real(info, dp))//", sizes "// &
                       real_text(real(size(ev), dp))//" and "//real_text(real(size(all), dp)))
            return
        end if
        call check(t, maxval(abs(all - ev)/ev) < 1.0e-10_dp, "cyclic interface exact: the "// &
                   "disk of reduced sectors has their cyclic frequencies", "largest "// &
                   "relative difference "//real_text(maxval(abs(all - ev)/ev)))
    end subroutine test_interface_exact

    !> A sector of 6 with 5-DOF faces: left 1..5, right 6..10, interior 11..13; springs from
    !> each face DOF to an interior DOF, along each face, interior ones to the ground.
    subroutine wide_face_sector(m, c)
        type(model_t), intent(out) :: m
        type(cyclic_t), intent(out) :: c
        integer :: i
        m%ndof = 13
        allocate (m%mass(13, 13), m%stiffness(13, 13))
        m%mass = 0.0_dp
        m%stiffness = 0.0_dp
        do i = 1, 13
            m%mass(i, i) = 0.2_dp + 0.05_dp*i
        end do
        do i = 1, 5
            call add_spring(m%stiffness, i, 11 + mod(i, 3), 10.0_dp + i)
            call add_spring(m%stiffness, 5 + i, 11 + mod(i + 1, 3), 12.0_dp - i)
            if (i < 5) call add_spring(m%stiffness, i, i + 1, 3.0_dp + 0.5_dp*i)
            if (i < 5) call add_spring(m%stiffness, 5 + i, 6 + i, 2.0_dp + 0.7_dp*i)
        end do
        do i = 11, 13
            m%stiffness(i, i) = m%stiffness(i, i) + 4.0_dp*(i - 10)
        end do
        call add_spring(m%stiffness, 11, 12, 6.0_dp)
        call add_spring(m%stiffness, 12, 13, 5.0_dp)
        m%damping = 0.01_dp*m%mass + 0.001_dp*m%stiffness
        m%omega = 1.0_dp
        m%force_dof = [12]
        m%force_harmonic = [1]
        m%force_amplitude = [1.0_dp]
        m%force_phase = [0.0_dp]
        allocate (m%contact_dof(0), m%contact_dof2(0), m%mu(0), m%normal_load(0))
        c%sectors = 6
        c%engine_order = 1
        c%left = [1, 2, 3, 4, 5]
        c%right = [6, 7, 8, 9, 10]
    end subroutine wide_face_sector

    !> The example case with its cyclic faces kept (&reduction interface_modes = 0): a
    !> scratch copy; returns its path.
    function faces_kept_copy() result(path)
        character(len=:), allocatable :: path
        path = edited_copy("fe_kept_", "interface_modes = 12", "interface_modes = 0")
    end function faces_kept_copy

    !> A scratch copy of the example case (tag `tag`; `example`, default
    !> "calculix_sector/case") with the text `from` replaced by `to` on every line; returns
    !> its path.
    function edited_copy(tag, from, to, example) result(path)
        character(len=*), intent(in) :: tag, from, to
        character(len=*), intent(in), optional :: example
        character(len=:), allocatable :: path, source
        if (present(example)) then
            source = scratch_copy(example, tag)
        else
            source = scratch_copy("calculix_sector/case", tag)
        end if
        path = source(1:len(source) - 4)//"_edited.nml"
        call copy_edited(source, path, from, to)
    end function edited_copy

    !> The text file `source` copied to `path` with `from` replaced by `to` on every line.
    subroutine copy_edited(source, path, from, to)
        character(len=*), intent(in) :: source, path, from, to
        character(len=1000) :: line
        integer :: ui, uo, stat, a
        open (newunit=ui, file=source, status='old', action='read')
        open (newunit=uo, file=path, status='replace', action='write')
        do
            read (ui, '(a)', iostat=stat) line
            if (stat /= 0) exit
            a = index(line, from)
            if (a > 0) line = line(1:a - 1)//to//line(a + len(from):)
            write (uo, '(a)') trim(line)
        end do
        close (ui)
        close (uo)
    end subroutine copy_edited

    !> &reduction interface_modes = 12, the example's setting: each 72-DOF face by 12
    !> interface modes, the sector 60 DOFs instead of 180; its frequencies per forced
    !> diameter within its measured error of the full sector's, that error below 1e-2 and
    !> within 1e-3 of the faces-kept sector's (measured 4.6e-3 against 4.3e-3); its channel
    !> receptance G_h and free response V0_h at the case's omega (every harmonic) within 1e-2
    !> of the faces-kept sector's (the same channels; measured 5.6e-3 and 2.9e-3: the case's
    !> omega is the diameter-3 resonance at 0.3 % damping, which magnifies the frequency's
    !> 1.5e-4 shift); the output rows still recover the output DOFs (the contact's
    !> amplitude from either model agrees). Bad values: interface_modes = 72 (not less than
    !> the face's 72 DOFs) and -1 refused in one line naming the variable, and on a case
    !> without &cyclic.
    subroutine test_interface_modes(t, kmat, mmat, cyc)
        type(test_counter_t), intent(inout) :: t
        type(sparse_matrix_t), intent(in) :: kmat, mmat
        type(cyclic_t), intent(in) :: cyc
        type(case_t) :: c, k
        type(error_type), allocatable :: error
        real(dp), allocatable :: wr(:), wf(:)
        type(basis_t) :: basis
        type(dynamics_t) :: di, dk
        real(dp) :: worst, dg, dv, dx
        integer :: j, u
        character(len=:), allocatable :: path
        call read_case(scratch_copy("calculix_sector/case", "fe_if_"), c, error)
        call check_error(t, error, "cyclic FE: read the case with interface modes", .false.)
        if (allocated(error)) return
        call read_case(faces_kept_copy(), k, error)
        call check_error(t, error, "cyclic FE: read the case with the faces kept", .false.)
        if (allocated(error)) return
        call check(t, c%cyclic%sector%ndof == 60 .and. size(c%cyclic%cyc%left) == 12 .and. &
                   allocated(c%reduction%faces) .and. k%cyclic%sector%ndof == 180 .and. &
                   allocated(c%cyclic%cyc%modes), "cyclic FE interface: the sector by 12 "// &
                   "interface modes a face has 60 DOFs (180 with the faces kept), its "// &
                   "cyclic modes prepared")
        if (.not. (allocated(c%cyclic%diameters) .and. allocated(k%cyclic%diameters))) then
            call check(t, .false., "cyclic FE interface: the error per diameter measured")
            return
        end if
        worst = 0.0_dp
        do j = 1, size(c%cyclic%diameters)
            call cyclic_frequencies(c%cyclic%sector, c%cyclic%cyc, c%cyclic%diameters(j), &
                                    wr, error)
            if (allocated(error)) exit
            call cyclic_sparse_frequencies(kmat, mmat, cyc, c%cyclic%diameters(j), 3, wf, error)
            if (allocated(error)) exit
            worst = max(worst, maxval(abs(wr(1:3) - wf)/wf/c%cyclic%diameter_errors(j)))
        end do
        call check_error(t, error, "cyclic FE interface: reduced against full", .false.)
        if (allocated(error)) return
        call check(t, maxval(c%cyclic%diameter_errors) < 1.0e-2_dp .and. worst <= 1.0_dp .and. &
                   maxval(abs(c%cyclic%diameter_errors - k%cyclic%diameter_errors)) < &
                   1.0e-3_dp, "cyclic FE interface: its frequencies per forced diameter "// &
                   "within its measured error, near the faces-kept sector's", "errors "// &
                   real_text(maxval(c%cyclic%diameter_errors))//" (faces kept "// &
                   real_text(maxval(k%cyclic%diameter_errors))//"), worst ratio "// &
                   real_text(worst))
        call new_basis(basis, 15, .false., 64, error)
        if (.not. allocated(error)) call new_cyclic_dynamics(di, c%cyclic%sector, &
                                                             c%cyclic%cyc, basis, error)
        if (.not. allocated(error)) call new_cyclic_dynamics(dk, k%cyclic%sector, &
                                                             k%cyclic%cyc, basis, error)
        call check_error(t, error, "cyclic FE interface: the condensations", .false.)
        if (allocated(error)) return
        dg = maxval(abs(di%g - dk%g))/maxval(abs(dk%g))
        dv = maxval(abs(di%v0 - dk%v0))/maxval(abs(dk%v0))
        ! the output rows: the contact DOF (output 1) from the reduced coordinates
        dx = maxval(abs(matmul(c%reduction%output_rows(1:1, :), di%x0) - &
                        matmul(k%reduction%output_rows(1:1, :), dk%x0)))/ &
             maxval(abs(matmul(k%reduction%output_rows(1:1, :), dk%x0)))
        call check(t, max(dg, dv, dx) < 1.0e-2_dp, "cyclic FE interface: the channels' "// &
                   "receptance and free response, and the recovered contact DOF, near the "// &
                   "faces-kept sector's", "G "//real_text(dg)//", V0 "//real_text(dv)// &
                   ", x(1659) "//real_text(dx))
        call basis%destroy()
        call read_case(edited_copy("fe_if72_", "interface_modes = 12", "interface_modes = 72"), &
                       c, error)
        call check(t, message_has(error, "&reduction interface_modes = 72: must be less "// &
                   "than the 72 DOFs"), "cyclic FE interface: 72 interface modes refused "// &
                   "(the face has 72 DOFs)", msg(error))
        call read_case(edited_copy("fe_ifm1_", "interface_modes = 12", "interface_modes = -1"), &
                       c, error)
        call check(t, message_has(error, "&reduction interface_modes = -1: must be >= 0"), &
                   "cyclic FE interface: a negative count refused", msg(error))
        ! the lumped disk's inline sector: nothing to reduce
        path = scratch_copy("bladed_disk", "fe_if_lumped_")
        open (newunit=u, file=path, status='old', position='append', action='write')
        write (u, '(a)') "&reduction interface_modes = 2 /"
        close (u)
        call read_case(path, c, error)
        call check(t, message_has(error, "&reduction interface_modes = 2: reduces the "// &
                   "cyclic faces of a sector of a bladed disk (&cyclic) given by Matrix "// &
                   "Market files"), "cyclic FE interface: refused on an inline sector", &
                   msg(error))
    end subroutine test_interface_modes

    !> `e` is one line holding `text`.
    logical function message_has(e, text)
        type(error_type), allocatable, intent(in) :: e
        character(len=*), intent(in) :: text
        message_has = .false.
        if (allocated(e)) message_has = index(e%message, text) > 0 .and. &
                                        index(e%message, new_line('a')) == 0
    end function message_has

    !> The full sector's K and M, and its &cyclic in full numbers (from case.nml).
    subroutine read_sector(kmat, mmat, cyc, error)
        type(sparse_matrix_t), intent(out) :: kmat, mmat
        type(cyclic_t), intent(out) :: cyc
        type(error_type), allocatable, intent(out) :: error
        type(nml_file_t) :: nml
        logical :: found
        call read_matrix_market(project_path(folder//"stiffness.mtx"), kmat, error)
        if (allocated(error)) return
        call read_matrix_market(project_path(folder//"mass.mtx"), mmat, error)
        if (allocated(error)) return
        call read_namelist_file(project_path(folder//"case.nml"), nml, error)
        if (allocated(error)) return
        call get_integers(nml, "cyclic", "left_dofs", cyc%left, found, 10000, error)
        if (allocated(error)) return
        call get_integers(nml, "cyclic", "right_dofs", cyc%right, found, 10000, error)
        if (allocated(error)) return
        cyc%sectors = 24
        cyc%engine_order = 3
    end subroutine read_sector

    !> CalculiX's frequencies [rad/s]: ccx(nd, mode) for nd 0..12, modes 1..6.
    subroutine read_calculix(ccx, error)
        real(dp), intent(out) :: ccx(0:12, 6)
        type(error_type), allocatable, intent(out) :: error
        character(len=200) :: line
        integer :: u, stat, nd, mode, got
        real(dp) :: w, f
        ccx = 0.0_dp
        got = 0
        open (newunit=u, file=project_path(folder//"calculix_frequencies.txt"), status='old', &
              action='read', iostat=stat)
        if (stat /= 0) then
            allocate (error)
            error%message = "cannot open calculix_frequencies.txt"
            return
        end if
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            if (line(1:1) == '#') cycle
            read (line, *, iostat=stat) nd, mode, w, f
            if (stat /= 0) cycle
            if (nd < 0 .or. nd > 12 .or. mode < 1 .or. mode > 6) cycle
            ccx(nd, mode) = w
            got = got + 1
        end do
        close (u)
        if (got < 13*6 .or. any(ccx <= 0.0_dp)) then
            allocate (error)
            error%message = "calculix_frequencies.txt: not every diameter's 6 frequencies"
        end if
    end subroutine read_calculix
end module test_cyclic_fe
