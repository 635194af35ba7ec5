!> Cyclic symmetry against the full disk: a lumped 24-sector disk (a ring of disk masses, a
!> blade on each) whose sector's cyclic frequencies over the nodal diameters 0..12 are the
!> assembled disk's eigenfrequencies (dense dsygv), each diameter 1..11 twice; the travelling
!> wave: the disk's linear forced response under engine order 3 (and 0, 12, 7 aliased to 17)
!> is the sector's with the phased boundary, every sector the phased copy; contacts copied
!> and reaching into the next sector; the checks of the description.
module test_cyclic
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, real_text, itoa
    use stickslip_model, only: model_t, validate_model, force_direction
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, nodal_diameter, disk_dof, &
        assemble_disk, cyclic_frequencies, sector_phase, cyclic_basis, cyclic_projection, &
        hermitian_pencil
    use stickslip_lapack, only: dsygv, zgesv, dsyev, dgeev, dgesv
    use stickslip_diagnostics, only: level_untrusted, level_warning
    use testing, only: test_counter_t, check, check_error
    use stickslip_case, only: case_t, read_case, write_case
    use stickslip_solution, only: hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic, disk_solution
    use stickslip_stability, only: floquet_t, periodic_stability
    use stickslip_wave_symmetry, only: wave_symmetry_t, wave_spans
    use stickslip_orbit_growth, only: orbit_growth_t, orbit_growth
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference, reference_energy_error
    use stickslip_sweep, only: sweep_options_t, sweep_result_t, run_sweep
    use stickslip_truncation, only: truncation_t, estimate_truncation
    use stickslip_sweep_family, only: family_options_t, family_result_t, family_peak_t, &
        run_family, curve_peaks
    use stickslip_solution, only: hbm_options_t
    use fixtures, only: scratch, write_lines, project_path, enter_project_root
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_dynamics, only: dynamics_t
    use stickslip_cyclic_dynamics, only: new_cyclic_dynamics, cyclic_projections_t
    use stickslip_cyclic_modal, only: prepare_cyclic_modes
    use stickslip_rho, only: automatic_rho, cyclic_held_rho, cyclic_mobility_matrix, &
        rho_fraction
    use stickslip_linear_response, only: limit_peak_t, linear_limit_peaks
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_contact_element, only: along_tangent, along_normal
    implicit none
    private
    public :: run_cyclic_tests, add_spring, model_frequencies

    integer, parameter :: ns = 24

contains

    subroutine run_cyclic_tests(t)
        type(test_counter_t), intent(inout) :: t
        call enter_project_root()
        call test_nodal_diameter(t)
        call test_frequencies(t)
        call test_forced_wave(t)
        call test_disk_contacts(t)
        call test_checks(t)
        call test_disk_wave(t)
        call test_case_input(t)
        call test_sector_solve(t)
        call test_sector_laws(t)
        call test_sector_planar(t)
        call test_sector_sweep(t)
        call test_sector_stability(t)
        call test_wave_symmetry_stability(t)
        call test_damper_disk_reference(t)
        call test_stuck_ring(t)
        call test_sector_family(t)
        call test_modal_condensation(t)
        call test_channel_condensation(t)
        call test_wave_rho(t)
        call test_cyclic_projection(t)
    end subroutine run_cyclic_tests

    !> cyclic_projection (t^H A t from the cyclic basis' structure) against the dense
    !> product with cyclic_basis, on a random symmetric 9-DOF sector whose faces pair DOFs
    !> (2, 7), (5, 9), (1, 4) in no order, at three phases (1e-14 of the largest entry);
    !> and hermitian_pencil's two paths (zhegvd with the eigenvectors, zhegv without) give
    !> the same eigenvalues, its vectors B-orthonormal and A v = lambda B v.
    subroutine test_cyclic_projection(t)
        type(test_counter_t), intent(inout) :: t
        type(cyclic_t) :: cyc
        real(dp) :: a(9, 9), b(9, 9)
        complex(dp), allocatable :: tb(:, :), dense(:, :), kc(:, :), mc(:, :), v(:, :), &
                                    k0(:, :), m0(:, :)
        real(dp), allocatable :: w1(:), w2(:)
        complex(dp) :: e
        real(dp) :: worst, pencil, orth
        integer :: k, info1, info2, j
        cyc%sectors = 7
        cyc%left = [2, 5, 1]
        cyc%right = [7, 9, 4]
        call random_number(a)
        a = a + transpose(a)
        call random_number(b)
        b = matmul(transpose(b), b)
        do k = 1, 9
            b(k, k) = b(k, k) + 1.0_dp
        end do
        worst = 0.0_dp
        pencil = 0.0_dp
        orth = 0.0_dp
        do k = 0, 2
            e = exp(cmplx(0.0_dp, two_pi*real(k, dp)/7.0_dp, dp))
            tb = cyclic_basis(cyc, 9, e)
            dense = matmul(conjg(transpose(tb)), matmul(cmplx(a, 0.0_dp, dp), tb))
            worst = max(worst, maxval(abs(cyclic_projection(a, cyc, e) - dense))/maxval(abs(a)))
            k0 = cyclic_projection(a + 20.0_dp*b, cyc, e)
            m0 = cyclic_projection(b, cyc, e)
            kc = k0
            mc = m0
            call hermitian_pencil(kc, mc, w1, .true., info1)
            v = kc
            kc = k0
            mc = m0
            call hermitian_pencil(kc, mc, w2, .false., info2)
            call check(t, info1 == 0 .and. info2 == 0, "cyclic projection: both pencil paths "// &
                       "succeed at phase "//itoa(k))
            if (info1 /= 0 .or. info2 /= 0) return
            pencil = max(pencil, maxval(abs(w1 - w2))/maxval(abs(w2)))
            do j = 1, size(w1)
                pencil = max(pencil, maxval(abs(matmul(k0, v(:, j)) - &
                                                w1(j)*matmul(m0, v(:, j))))/maxval(abs(w2)))
            end do
            orth = max(orth, maxval(abs(matmul(conjg(transpose(v)), matmul(m0, v)) - &
                                        identity(size(w1)))))
        end do
        call check(t, worst < 1.0e-14_dp, "cyclic projection = t^H A t with the dense basis ("// &
                   real_text(worst, '(es9.2)')//")")
        call check(t, pencil < 1.0e-12_dp, "hermitian pencil: zhegvd's eigenvalues = zhegv's, "// &
                   "A v = lambda B v ("//real_text(pencil, '(es9.2)')//")")
        call check(t, orth < 1.0e-12_dp, "hermitian pencil: eigenvectors B-orthonormal ("// &
                   real_text(orth, '(es9.2)')//")")
    contains
        pure function identity(n) result(id)
            integer, intent(in) :: n
            complex(dp) :: id(n, n)
            integer :: i
            id = (0.0_dp, 0.0_dp)
            do i = 1, n
                id(i, i) = (1.0_dp, 0.0_dp)
            end do
        end function identity
    end subroutine test_cyclic_projection

    !> The sector's held weight (cyclic_held_rho) on the underplatform damper disk
    !> at the stuck frequency 2.887 rad/s, in the waves of nodal diameters 0, 1, 3 and 12:
    !> rho_fraction times the geometric mean of each channel's mobility with the other
    !> held, against the 2 x 2 Schur complements A_11 - |A_12|^2 / A_22 written out here
    !> (the damper's tangential pair and its normal pair, each normal with its compliance
    !> in series; the two pairs do not couple: checked), and at diameter 0, where both
    !> tangential channels measure the same slip (the platforms move together), their own
    !> mobilities. Held, the damper slips on a platform only as fast as that platform moves
    !> against the next: 0.020 m/(N s) at diameter 1 against its own 13.6.
    subroutine test_wave_rho(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(cyclic_t) :: cyc
        type(model_t) :: sector
        type(contact_set_t) :: cs
        type(error_type), allocatable :: error
        complex(dp), allocatable :: g(:, :)
        integer, parameter :: diameters(4) = [0, 1, 3, 12]
        real(dp) :: a(4, 4), m(4), expected, worst, coupling, held1, own1
        integer :: k, info, tang(2), norm(2), ch
        call read_case(project_path("examples/bladed_disk_damper.nml"), c, error)
        call check_error(t, error, "wave rho: read the example", .false.)
        if (allocated(error)) return
        sector = c%cyclic%sector
        sector%omega = 2.887_dp
        call new_contact_set(cs, sector)
        tang = pack([(ch, ch=1, cs%nchannel)], cs%along == along_tangent)
        norm = pack([(ch, ch=1, cs%nchannel)], cs%along == along_normal)
        worst = 0.0_dp
        coupling = 0.0_dp
        do k = 1, size(diameters)
            cyc = c%cyclic%cyc
            if (allocated(cyc%modes)) deallocate (cyc%modes)
            cyc%engine_order = diameters(k)
            call cyclic_mobility_matrix(sector, cyc, cs, 1, g, info)
            if (info /= 0) exit
            coupling = max(coupling, maxval(abs(g(tang, norm)))/maxval(abs(g)))
            ! the normals' compliance in series (h = 1: a gap channel's units are the
            ! velocity's)
            a = real(g, dp)
            a(norm(1), norm(1)) = a(norm(1), norm(1)) + sector%omega/40.0_dp
            a(norm(2), norm(2)) = a(norm(2), norm(2)) + sector%omega/40.0_dp
            m(1) = schur(tang(1), tang(2))
            m(2) = schur(tang(2), tang(1))
            m(3) = schur(norm(1), norm(2))
            m(4) = schur(norm(2), norm(1))
            if (diameters(k) == 0) m(1:2) = [a(tang(1), tang(1)), a(tang(2), tang(2))]
            if (diameters(k) == 1) then
                held1 = m(1)
                own1 = a(tang(1), tang(1))
            end if
            expected = rho_fraction*product(m)**0.25_dp
            worst = max(worst, abs(cyclic_held_rho(sector, cyc, 1) - expected)/expected)
        end do
        call check(t, info == 0 .and. worst < 1.0e-10_dp .and. coupling < 1.0e-12_dp, &
                   "wave rho: each channel held by the other (2 x 2 Schur complements), "// &
                   "diameters 0, 1, 3, 12", "largest relative difference "// &
                   real_text(worst)//", tangent-normal coupling "//real_text(coupling))
        call check(t, abs(held1 - 0.0199_dp) < 5.0e-4_dp .and. abs(own1 - 13.62_dp) < 0.01_dp, &
                   "wave rho: diameter 1, the damper held on one platform slips on the other "// &
                   "at 0.020 m/(N s), not its own 13.6", "held "//real_text(held1)// &
                   ", own "//real_text(own1))

    contains

        !> A_ii - |A_ij|^2 / A_jj.
        real(dp) function schur(i, j)
            integer, intent(in) :: i, j
            schur = a(i, i) - real(g(i, j)*conjg(g(i, j)), dp)/a(j, j)
        end function schur
    end subroutine test_wave_rho

    !> What a sweep's continuation builds at every omega on a sector with prepared modes:
    !> the channels' dynamics only (channels_only) from the projections kept since the
    !> first omega (cyclic_projections_t), on the underplatform damper example with EO 3,
    !> harmonics 0..15: V0, G, their omega derivatives, the static terms and the energy Gram
    !> matrices equal the dense LU's at three omegas (the cache made at the first, reused at
    !> the others, and remade for a doubled forcing) to 1e-10, and the N-row responses are
    !> not kept. The free sector's modes give its automatic rho (a modal sum instead of an
    !> LU): equal to the LU's to 1e-12 at each omega; the prepared cyclic modes give the
    !> wave's held rho, equal to the factorization's.
    subroutine test_channel_condensation(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(cyclic_t) :: plain
        type(model_t) :: sector
        type(basis_t) :: basis
        type(dynamics_t) :: dc, dd
        type(cyclic_projections_t) :: cache
        type(error_type), allocatable :: error
        real(dp), parameter :: omegas(3) = [2.1_dp, 2.6_dp, 2.6_dp]
        real(dp) :: worst, rho_worst, held_worst, fmax(3)
        integer :: k
        logical :: lean, reused
        call read_case(project_path("examples/bladed_disk_damper.nml"), c, error)
        call check_error(t, error, "cyclic channels: read the example", .false.)
        if (allocated(error)) return
        call new_basis(basis, 15, .false., 64, error)
        sector = c%cyclic%sector
        plain = c%cyclic%cyc
        deallocate (plain%modes)
        worst = 0.0_dp
        rho_worst = 0.0_dp
        held_worst = 0.0_dp
        lean = .true.
        reused = .true.
        do k = 1, size(omegas)
            sector%omega = omegas(k)
            if (k == 3) sector%force_amplitude = 2.0_dp*sector%force_amplitude
            call new_cyclic_dynamics(dc, sector, c%cyclic%cyc, basis, error, .true., &
                                     channels_only=.true., projections=cache)
            if (allocated(error)) exit
            reused = reused .and. all(cache%made)
            fmax(k) = maxval(abs(cache%f))
            call new_cyclic_dynamics(dd, sector, plain, basis, error, .true.)
            if (allocated(error)) exit
            lean = lean .and. .not. allocated(dc%x0) .and. .not. allocated(dc%y) .and. &
                   .not. allocated(dc%x0_static)
            worst = max(worst, differ(dc%v0, dd%v0), differ(dc%dv0, dd%dv0), &
                        maxval(abs(dc%g - dd%g))/maxval(abs(dd%g)), &
                        maxval(abs(dc%dg - dd%dg))/maxval(abs(dd%dg)), &
                        maxval(abs(dc%g_static - dd%g_static))/maxval(abs(dd%g_static)), &
                        maxval(abs(dc%u_static - dd%u_static))/ &
                        max(maxval(abs(dd%u_static)), tiny(1.0_dp)), &
                        maxval(abs(dc%damping_gram - dd%damping_gram))/ &
                        maxval(abs(dd%damping_gram)), &
                        differ(dc%forcing_gram, dd%forcing_gram))
            rho_worst = max(rho_worst, abs(automatic_rho(sector, c%cyclic%cyc%free_lambda, &
                                                         c%cyclic%cyc%free_shapes) - &
                                           automatic_rho(sector))/automatic_rho(sector))
            held_worst = max(held_worst, abs(cyclic_held_rho(sector, c%cyclic%cyc) - &
                                             cyclic_held_rho(sector, plain))/ &
                             cyclic_held_rho(sector, plain))
        end do
        call check_error(t, error, "cyclic channels: the condensations", .false.)
        if (allocated(error)) return
        ! the cache remade for the doubled forcing
        reused = reused .and. fmax(2) == fmax(1) .and. abs(fmax(3) - 2.0_dp*fmax(2)) <= &
                 1.0e-15_dp*fmax(3)
        call check(t, lean .and. reused .and. worst < 1.0e-10_dp, "cyclic channels: the "// &
                   "channels' dynamics from kept projections = the dense LU's (3 omegas, "// &
                   "a new forcing)", "largest difference "//real_text(worst))
        call check(t, allocated(c%cyclic%cyc%free_lambda) .and. rho_worst < 1.0e-12_dp, &
                   "cyclic channels: the automatic rho from the free sector's modes = the "// &
                   "LU's", "largest relative difference "//real_text(rho_worst))
        call check(t, held_worst < 1.0e-12_dp, "cyclic channels: the wave's held rho from "// &
                   "the prepared modes = the factorization's", "largest relative difference "// &
                   real_text(held_worst))
        call basis%destroy()
    end subroutine test_channel_condensation

    !> max |a - b| / max |b| (b = 0: max |a| / tiny).
    real(dp) function differ(a, b)
        complex(dp), intent(in) :: a(:, :), b(:, :)
        differ = maxval(abs(a - b))/max(maxval(abs(b)), tiny(1.0_dp))
    end function differ

    !> The sector's condensation as a modal sum over its prepared cyclic modes (a case file
    !> prepares them; Rayleigh damping) against the dense LU of the projected pencil (the
    !> modes dropped), on the underplatform damper example (8 DOFs, contacts against the
    !> next sector, EO 3 and 17 = 7 backwards, every harmonic 0..15): X0, Y, V0, G and their
    !> omega derivatives agree to 1e-10 of their largest entry. A non-proportional damping
    !> is not prepared (the dense path stays), nor are another sector's modes used.
    subroutine test_modal_condensation(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(cyclic_t) :: plain, modal
        type(model_t) :: other
        type(basis_t) :: basis
        type(dynamics_t) :: dm, dd
        type(error_type), allocatable :: error
        integer, parameter :: orders(2) = [3, 17]
        real(dp) :: worst
        integer :: e
        logical :: prepared, ok
        call read_case(project_path("examples/bladed_disk_damper.nml"), c, error)
        call check_error(t, error, "cyclic modal: read the example", .false.)
        if (allocated(error)) return
        call check(t, allocated(c%cyclic%cyc%modes), "cyclic modal: the case prepared the "// &
                   "sector's cyclic modes")
        call new_basis(basis, 15, .false., 64, error)
        worst = 0.0_dp
        do e = 1, size(orders)
            modal = c%cyclic%cyc
            modal%engine_order = orders(e)
            call prepare_cyclic_modes(c%cyclic%sector, modal, 15, error, prepared)
            if (allocated(error)) exit
            plain = modal
            deallocate (plain%modes)
            call new_cyclic_dynamics(dm, c%cyclic%sector, modal, basis, error, .true.)
            if (allocated(error)) exit
            call new_cyclic_dynamics(dd, c%cyclic%sector, plain, basis, error, .true.)
            if (allocated(error)) exit
            worst = max(worst, differ(dm%x0, dd%x0), differ(dm%v0, dd%v0), &
                        differ(dm%dv0, dd%dv0), &
                        maxval(abs(dm%dg - dd%dg))/maxval(abs(dd%dg)), &
                        maxval(abs(dm%y - dd%y))/maxval(abs(dd%y)), &
                        maxval(abs(dm%g - dd%g))/maxval(abs(dd%g)), &
                        maxval(abs(dm%x0_static - dd%x0_static))/ &
                        max(maxval(abs(dd%x0_static)), tiny(1.0_dp)), &
                        maxval(abs(dm%y_static - dd%y_static))/maxval(abs(dd%y_static)))
        end do
        call check_error(t, error, "cyclic modal: the condensations", .false.)
        if (allocated(error)) return
        call check(t, prepared .and. worst < 1.0e-10_dp, "cyclic modal: the modal sum = "// &
                   "the dense LU (EO 3 and 17, harmonics 0..15, omega derivatives)", &
                   "largest difference "//real_text(worst))
        ! a damping that is not proportional: not prepared
        other = c%cyclic%sector
        other%damping(1, 1) = other%damping(1, 1) + 0.05_dp
        modal = c%cyclic%cyc
        call prepare_cyclic_modes(other, modal, 15, error, prepared)
        call check(t, .not. allocated(error) .and. .not. prepared .and. &
                   .not. allocated(modal%modes), "cyclic modal: non-proportional damping "// &
                   "keeps the dense condensation")
        ! another sector with the first one's modes: they are ignored
        plain = c%cyclic%cyc
        deallocate (plain%modes)
        call new_cyclic_dynamics(dm, other, c%cyclic%cyc, basis, error)
        ok = .not. allocated(error)
        if (ok) then
            call new_cyclic_dynamics(dd, other, plain, basis, error)
            ok = .not. allocated(error)
        end if
        if (ok) ok = differ(dm%x0, dd%x0) == 0.0_dp
        call check(t, ok, "cyclic modal: another sector's modes are not used")
        call basis%destroy()
    end subroutine test_modal_condensation

    !> A family over the shrouds' normal load on one sector: both curves complete, their
    !> blade peak refined, and equal to the peak of a separate sweep on the sector at that
    !> load (1e-8); the linear limits (the shrouds stuck to the next blade, and slipping) of
    !> every DOF of the sector equal the assembled disk's for sector 0's DOFs (1e-8 of the
    !> largest slipping peak; stuck, the blades tied into a ring do not move in a wave).
    subroutine test_sector_family(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: m
        type(sweep_options_t) :: so
        type(family_options_t) :: fo
        type(family_result_t) :: fam
        type(sweep_result_t) :: single
        type(family_peak_t), allocatable :: peaks(:)
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        type(model_t) :: disk
        type(limit_peak_t), allocatable :: dstuck(:), dslip(:)
        real(dp), allocatable :: rows(:, :)
        real(dp) :: worst
        integer :: j
        call read_case(project_path("examples/bladed_disk.nml"), c, error)
        call check_error(t, error, "cyclic family: read the example", .false.)
        if (allocated(error)) return
        so%parameter = 'omega'
        so%start = 2.0_dp
        so%stop = 2.6_dp
        so%stability = .false.
        so%truncation = .false.
        fo%family_parameter = 'normal_load'
        fo%family_values = [0.05_dp, 0.2_dp]
        call run_family(c%model, c%hbm, c%reference%reference_options_t, so, fo, fam, error, &
                        cyclic=c%cyclic%cyc)
        call check_error(t, error, "cyclic family: run", .false.)
        if (allocated(error)) return
        m = c%model
        m%normal_load = [0.2_dp]
        call run_sweep(m, c%hbm, c%reference%reference_options_t, so, single, error, &
                       cyclic=c%cyclic%cyc)
        ho = c%hbm
        ho%rho = single%rho
        if (.not. allocated(error)) call curve_peaks(m, ho, so, 'half_peak_to_peak', single, &
                                                     peaks, error, c%cyclic%cyc)
        call check_error(t, error, "cyclic family: the separate sweep", .false.)
        if (allocated(error)) return
        call check(t, fam%complete .and. all(fam%peaks(2, :)%refined) .and. &
                   abs(fam%peaks(2, 2)%amplitude - peaks(2)%amplitude) < &
                   1.0e-8_dp*peaks(2)%amplitude, &
                   "cyclic family: the blade's peaks refined, = a separate sweep's", &
                   real_text(fam%peaks(2, 2)%amplitude)//" vs "//real_text(peaks(2)%amplitude))
        ! the linear limits against the assembled disk's, observed on sector 0's DOFs
        call assemble_disk(m, c%cyclic%cyc, disk, error)
        if (.not. allocated(error)) then
            allocate (rows(m%ndof, disk%ndof))
            rows = 0.0_dp
            do j = 1, m%ndof
                rows(j, disk_dof(c%cyclic%cyc, m%ndof, j, 0)) = 1.0_dp
            end do
            call linear_limit_peaks(disk, .true., so%start, so%stop, 'half_peak_to_peak', &
                                    dstuck, error, observe=rows)
        end if
        if (.not. allocated(error)) call linear_limit_peaks(disk, .false., so%start, so%stop, &
                                                            'half_peak_to_peak', dslip, error, &
                                                            observe=rows)
        call check_error(t, error, "cyclic family: the disk's linear limits", .false.)
        if (allocated(error)) return
        ! relative to the largest slipping response: with the shrouds stuck the blades are
        ! tied into a ring that a travelling wave's forces cannot move (every DOF 0 in both)
        worst = 0.0_dp
        do j = 1, m%ndof
            worst = max(worst, abs(fam%stuck(j, 1)%amplitude - dstuck(j)%amplitude)/ &
                        maxval(dslip%amplitude), abs(fam%slipping(j, 1)%amplitude - &
                        dslip(j)%amplitude)/maxval(dslip%amplitude))
        end do
        ! (a NaN anywhere fails)
        if (any(fam%stuck(:, 1)%amplitude /= fam%stuck(:, 1)%amplitude) .or. &
            any(fam%slipping(:, 1)%amplitude /= fam%slipping(:, 1)%amplitude) .or. &
            any(dstuck%amplitude /= dstuck%amplitude)) worst = huge(1.0_dp)
        call check(t, worst < 1.0e-8_dp, "cyclic family: the sector's linear limits = the "// &
                   "assembled disk's", "largest relative difference "//real_text(worst)// &
                   ", stuck at most "//real_text(maxval(dstuck%amplitude))//", blade "// &
                   "slipping "//real_text(fam%slipping(2, 1)%amplitude))
    end subroutine test_sector_family

    !> The stability of a sector's travelling wave is the assembled disk's: the Floquet
    !> multipliers of the disk expanded from the sector's solution (disk_solution) against
    !> those of the disk's own weighted residual, at the example's omega (largest modulus
    !> to 1e-8), and the disk solution's energies are N times the sector's.
    subroutine test_sector_stability(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: disk
        type(hbm_solution_t) :: sec, dsol, full
        type(hbm_options_t) :: ho
        type(floquet_t) :: f1, f2
        type(error_type), allocatable :: error
        call read_case(project_path("examples/bladed_disk.nml"), c, error)
        call check_error(t, error, "cyclic stability: read the example", .false.)
        if (allocated(error)) return
        ho = c%hbm
        ho%rho = 0.5_dp
        ho%samples = 48*ns
        call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
        if (.not. allocated(error)) call disk_solution(c%model, c%cyclic%cyc, ho, sec, disk, &
                                                       dsol, error)
        if (.not. allocated(error)) call periodic_stability(disk, dsol, &
                                                            c%reference%reference_options_t, &
                                                            f1, error)
        if (.not. allocated(error)) call solve_periodic(disk, ho, full, error)
        if (.not. allocated(error)) call periodic_stability(disk, full, &
                                                            c%reference%reference_options_t, &
                                                            f2, error)
        call check_error(t, error, "cyclic stability: the multipliers", .false.)
        if (allocated(error)) return
        call check(t, allocated(f1%multipliers) .and. allocated(f2%multipliers) .and. &
                   abs(f1%max_modulus - f2%max_modulus) < 1.0e-8_dp .and. &
                   abs(dsol%diss_friction - ns*sec%diss_friction) < 1.0e-10_dp*dsol%work_forcing, &
                   "cyclic stability: the sector's wave on the disk = the disk's own", &
                   real_text(f1%max_modulus)//" vs "//real_text(f2%max_modulus))
    end subroutine test_sector_stability

    !> The disk's multipliers from the flow over T / m by its wave's symmetry
    !> (periodic_stability with `symmetry`) = those of the flow over the period: every
    !> multiplier of modulus above 1e-3 of either within 1e-7 of one of the other's, on the
    !> shrouded disk (24 sectors) in engine orders 1, 2, 3 (m = 24, 12, 8) and on 6 sectors
    !> whose shrouds lift off the next blade (an elastic unilateral normal, preloaded) in
    !> engine orders 1, 2, 3 (m = 6, 3, 2). Each has sectors in phase whose contacts switch
    !> at one instant (except the lift-off in EO 1): perturbations followed by the exact
    !> flow grow by the largest multiplier's modulus to 1e-3, over T and over T / m; from
    !> an arbitrary direction (the lift-off in EO 3), to 1e-2 after 8 periods. A disk with
    !> one mass changed is refused, naming the mass matrix.
    subroutine test_wave_symmetry_stability(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: disk, sector
        type(cyclic_t) :: cyc
        type(hbm_solution_t) :: dsol
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(floquet_t) :: f2
        type(error_type), allocatable :: error
        type(reference_result_t) :: rref
        type(orbit_growth_t) :: g
        real(dp), allocatable :: st(:, :)
        integer :: k
        call read_case(project_path("examples/bladed_disk.nml"), c, error)
        call check_error(t, error, "wave symmetry: read the shrouded disk", .false.)
        if (allocated(error)) return
        ho = c%hbm
        ho%rho = 0.5_dp
        ho%samples = 48*ns
        do k = 1, 3
            c%cyclic%cyc%engine_order = k
            call compare(c%model, c%cyclic%cyc, ho, c%reference%reference_options_t, &
                         "shrouded disk, EO "//itoa(k), .true.)
        end do
        ! the shroud lifting off the next blade: DOF 5 the blade's normal motion
        sector = normal_sector()
        sector%contact_dof = [2]
        sector%contact_dof2 = [0]
        sector%mu = [0.3_dp]
        sector%normal_load = [0.0_dp]
        allocate (sector%normal_direction(5, 1))
        sector%normal_direction = 0.0_dp
        sector%normal_direction(5, 1) = 1.0_dp
        sector%gap = [0.0_dp]
        sector%preload = [0.3_dp]
        sector%normal_stiffness = [20.0_dp]
        ho = hbm_options_t()
        ho%harmonics = 12
        ho%rho = 0.5_dp
        ho%samples = 384
        do k = 1, 3
            cyc = lumped_cyclic(k)
            cyc%sectors = 6
            cyc%next_dof = [2]
            cyc%next_normal_dof = [5]
            call compare(sector, cyc, ho, ro, "lift-off on 6 sectors, EO "//itoa(k), k > 1)
        end do
        ! EO 3's orbit again, and the perturbed flow from an arbitrary direction instead of
        ! the dominant multiplier's (the power iteration of the flow map alone): after 8
        ! periods it grows by the largest modulus
        call solve_reference(disk, ro, dsol%x, dsol%v, rref, error, start_name='hbm', &
                             light=.true., r_start=dsol%r, symmetry=wave_symmetry_t(6, 3))
        if (.not. allocated(error)) then
            allocate (st(rref%flow%nz, 1))
            st(:, 1) = [(cos(1.7_dp*k**2), k=1, rref%flow%nz)]
            call orbit_growth(rref, st, 8, 8, g, error)
        end if
        call check_error(t, error, "wave symmetry: the perturbed flow from any direction", &
                         .false.)
        if (.not. allocated(error)) &
            call check(t, abs(g%rate - f2%max_modulus) <= 1.0e-2_dp*f2%max_modulus, &
                       "wave symmetry: lift-off, EO 3, the perturbed flow from any direction "// &
                       "grows by the largest multiplier", "growth "//real_text(g%rate)// &
                       " a period, largest multiplier "//real_text(f2%max_modulus)//", "// &
                       itoa(g%maps)//" maps")
        if (allocated(st)) then
            call orbit_growth(rref, st(1:3, :), 1, 0, g, error)
            call check(t, allocated(error), "wave symmetry: orbit_growth refuses a start "// &
                       "of the wrong size", "no error")
            if (allocated(error)) deallocate (error)
        end if
        ! not the disk of a sector: one mass changed
        disk%mass(1, 1) = 1.01_dp*disk%mass(1, 1)
        call periodic_stability(disk, dsol, ro, f2, error, symmetry=wave_symmetry_t(6, 3))
        call check(t, allocated(error), "wave symmetry: a disk with one mass changed refused", &
                   "no error")
        if (allocated(error)) call check(t, index(error%message, "mass matrix") > 0, &
                                         "wave symmetry: the refusal names the mass matrix", &
                                         error%message)

    contains

        !> in_phase: sectors in phase (their contacts switch together).
        subroutine compare(sec, cy, hopts, ref, what, in_phase)
            type(model_t), intent(in) :: sec
            type(cyclic_t), intent(in) :: cy
            type(hbm_options_t), intent(in) :: hopts
            type(reference_options_t), intent(in) :: ref
            character(len=*), intent(in) :: what
            logical, intent(in) :: in_phase
            type(hbm_solution_t) :: sol
            type(floquet_t) :: f1
            real(dp) :: worst
            integer :: m, u
            call solve_periodic_cyclic(sec, cy, hopts, sol, error)
            if (.not. allocated(error)) call disk_solution(sec, cy, hopts, sol, disk, dsol, error)
            if (.not. allocated(error)) call periodic_stability(disk, dsol, ref, f1, error)
            if (.not. allocated(error)) &
                call periodic_stability(disk, dsol, ref, f2, error, &
                                        symmetry=wave_symmetry_t(cy%sectors, cy%engine_order))
            call check_error(t, error, "wave symmetry: "//what, .false.)
            if (allocated(error)) return
            call wave_spans(wave_symmetry_t(cy%sectors, cy%engine_order), m, u)
            worst = huge(1.0_dp)
            if (allocated(f1%multipliers) .and. allocated(f2%multipliers) .and. &
                f1%verdict /= 'unknown' .and. f2%verdict /= 'unknown') &
                worst = max(apart(f1%multipliers, f2%multipliers), &
                            apart(f2%multipliers, f1%multipliers))
            call check(t, worst < 1.0e-7_dp .and. m > 1, "wave symmetry: "//what// &
                       ", the flow over T / "//itoa(m)//" = over T", "largest multiplier "// &
                       real_text(f2%max_modulus)//" vs "//real_text(f1%max_modulus)// &
                       ", worst distance "//real_text(worst)//", CPU "// &
                       real_text(f2%seconds)//" s vs "//real_text(f1%seconds)//" s; "// &
                       f1%diagnosis//" / "//f2%diagnosis)
            ! sectors in phase switch together: the perturbed exact flow checks the verdict
            ! (stickslip_orbit_growth), and grows as the largest multiplier says, over T
            ! and over T / m; without them it is not followed
            if (.not. in_phase) then
                call check(t, f1%flow_growth < 0.0_dp .and. f2%flow_growth < 0.0_dp, &
                           "wave symmetry: "//what//", no sectors in phase, no perturbed flow", &
                           "growth "//real_text(f1%flow_growth)//" and "// &
                           real_text(f2%flow_growth))
                return
            end if
            call check(t, near(f1) .and. near(f2), "wave symmetry: "//what// &
                       ", perturbations followed by the flow grow as the largest multiplier", &
                       "growth "//real_text(f1%flow_growth)//" and "// &
                       real_text(f2%flow_growth)//" a period, largest multiplier "// &
                       real_text(f1%max_modulus)//" and "//real_text(f2%max_modulus))
        end subroutine compare

        !> The perturbed flow was followed and grew by the largest multiplier, to 1e-3.
        logical function near(f)
            type(floquet_t), intent(in) :: f
            near = f%flow_growth >= 0.0_dp .and. &
                   abs(f%flow_growth - f%max_modulus) <= 1.0e-3_dp*f%max_modulus
        end function near

        !> The largest distance from a multiplier of a (modulus above 1e-3) to b's.
        real(dp) function apart(a, b)
            complex(dp), intent(in) :: a(:), b(:)
            integer :: i
            apart = 0.0_dp
            do i = 1, size(a)
                if (abs(a(i)) <= 1.0e-3_dp) cycle
                apart = max(apart, minval(abs(b - a(i))))
            end do
        end function apart
    end subroutine test_wave_symmetry_stability

    !> The exact reference on the lumped disk with underplatform dampers of
    !> examples/bladed_disk_damper.nml (unilateral contacts on elastic normals, pressed by
    !> the damper's static load, not by a preload of their own), before found "no
    !> consistent contact mode": on 6 sectors in engine order 1 the disk's exact orbit shot
    !> from the sector's wave (H = 20) converges and balances its energy, and the sector's
    !> wave approaches it as H grows (H = 10, 20, 40; within its truncation estimate at 10
    !> and 20, where one is given); on the example's 24 sectors (EO 3: 21
    !> stuck contacts decide at once at the start, beyond the 8 the enumeration takes) the
    !> disk's stability finds the exact orbit near the wave, unstable (1.60), confirmed by
    !> perturbations followed by the exact flow (growth within 1e-3 of the largest
    !> multiplier, though contacts switch at one instant). N is changed after the case
    !> was read with its cyclic modes of 24 sectors: the sector's condensation must ignore
    !> them (it did not, and the wave did not converge: 5.2, 3.9, 4.8 %).
    subroutine test_damper_disk_reference(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: disk
        type(hbm_solution_t) :: sec, dsol
        type(hbm_options_t) :: ho
        type(reference_options_t) :: ro
        type(reference_result_t) :: ref
        type(truncation_t) :: est
        type(floquet_t) :: fl
        type(error_type), allocatable :: error
        real(dp), allocatable :: xr(:, :), vr(:, :), rr(:, :)
        real(dp) :: dist(3), ests(3)
        integer, parameter :: hs(3) = [10, 20, 40]
        integer, allocatable :: cols(:)
        integer :: j, k
        call read_case(project_path("examples/bladed_disk_damper.nml"), c, error)
        call check_error(t, error, "damper disk reference: read the example", .false.)
        if (allocated(error)) return
        c%model%omega = 2.3_dp
        ho = c%hbm
        ho%samples = 1020
        c%cyclic%cyc%sectors = 6
        c%cyclic%cyc%engine_order = 1
        ! the cyclic modes read with the case are the 24 sectors' diameters: their key
        ! (structure_key with N) makes the condensation ignore them
        call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
        if (.not. allocated(error)) call estimate_truncation(c%model, ho, sec, est, error, &
                                                             cyclic=c%cyclic%cyc)
        if (.not. allocated(error)) call disk_solution(c%model, c%cyclic%cyc, ho, sec, disk, &
                                                       dsol, error)
        ro = c%reference%reference_options_t
        ro%samples = ho%samples
        if (.not. allocated(error)) call solve_reference(disk, ro, dsol%x, dsol%v, ref, error)
        call check_error(t, error, "damper disk reference: 6 sectors, EO 1", .false.)
        if (allocated(error)) return
        call check(t, ref%converged .and. ref%defect < 1.0e-9_dp .and. &
                   reference_energy_error(ref) < 1.0e-8_dp, &
                   "damper disk reference: 6 sectors, EO 1, converged, energy balanced", &
                   "converged "//merge("T", "F", ref%converged)//", defect "// &
                   real_text(ref%defect)//", energy "//real_text(reference_energy_error(ref)))
        ! the sector's wave approaches the exact orbit as H grows (sector 0's DOFs)
        cols = [(disk_dof(c%cyclic%cyc, c%model%ndof, j, 0), j=1, c%model%ndof)]
        do k = 1, size(hs)
            ho%harmonics = hs(k)
            ho%samples = 2040
            call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
            if (.not. allocated(error)) call estimate_truncation(c%model, ho, sec, est, error, &
                                                                 cyclic=c%cyclic%cyc)
            if (.not. allocated(error)) call sample_reference(ref, ho%samples, xr, vr, rr, &
                                                              error)
            if (allocated(error)) exit
            dist(k) = maxval(abs(xr(:, cols) - sec%x))/maxval(abs(xr(:, cols)))
            ests(k) = est%estimate
        end do
        call check_error(t, error, "damper disk reference: the sector at H = 10, 20, 40", &
                         .false.)
        if (allocated(error)) return
        call check(t, dist(3) < 0.5_dp*dist(1) .and. dist(3) < 0.01_dp .and. &
                   dist(1) <= ests(1) .and. dist(2) <= ests(2), &
                   "damper disk reference: the sector's wave converges to the disk's orbit", &
                   "distance / amplitude at H = 10, 20, 40: "//real_text(dist(1))//", "// &
                   real_text(dist(2))//", "//real_text(dist(3))//"; truncation estimates "// &
                   real_text(ests(1))//", "//real_text(ests(2))//", "//real_text(ests(3)))

        call read_case(project_path("examples/bladed_disk_damper.nml"), c, error)
        if (allocated(error)) return
        c%model%omega = 2.3_dp
        ho = c%hbm
        call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
        if (.not. allocated(error)) call disk_solution(c%model, c%cyclic%cyc, ho, sec, disk, &
                                                       dsol, error)
        if (.not. allocated(error)) call periodic_stability(disk, dsol, &
            c%reference%reference_options_t, fl, error, &
            symmetry=wave_symmetry_t(c%cyclic%cyc%sectors, c%cyclic%cyc%engine_order))
        call check_error(t, error, "damper disk reference: 24 sectors, EO 3", .false.)
        if (allocated(error)) return
        call check(t, allocated(fl%multipliers) .and. size(fl%multipliers) > 0 .and. &
                   fl%distance < 0.2_dp, &
                   "damper disk reference: 24 sectors, EO 3, the disk's exact orbit found", &
                   fl%verdict//": "//fl%diagnosis)
        ! sectors 8 apart switch together; perturbations followed by the exact flow grow as
        ! the multipliers say (implicit Euler at 1000 steps a period stays on the orbit: its
        ! numerical damping)
        call check(t, fl%verdict == 'unstable' .and. fl%flow_growth > 0.0_dp .and. &
                   abs(fl%flow_growth - fl%max_modulus) <= 1.0e-3_dp*fl%max_modulus, &
                   "damper disk reference: 24 sectors, EO 3, unstable, confirmed by the "// &
                   "perturbed flow", "growth "//real_text(fl%flow_growth)//" a period; "// &
                   fl%verdict//": "//fl%diagnosis)
    end subroutine test_damper_disk_reference

    !> A sweep in omega on one sector (EO 3): complete; three of its points (the first, the
    !> middle, the last) against the assembled disk solved at their omega with the curve's
    !> rho: sector 0's coefficients to 1e-8 of the largest, and the shroud's relative
    !> displacement coefficients (the point's ucoef) = blade 0 minus blade 1 of the disk.
    subroutine test_sector_sweep(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: disk, m
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        type(hbm_solution_t) :: full, sec, dsol
        type(hbm_options_t) :: ho
        type(floquet_t) :: fl
        type(error_type), allocatable :: error
        real(dp) :: worst, worst_u, scale
        integer :: k, j, q
        integer :: picks(3)
        call read_case(project_path("examples/bladed_disk.nml"), c, error)
        call check_error(t, error, "cyclic sweep: read the example", .false.)
        if (allocated(error)) return
        ho = c%hbm
        ho%rho = 0.5_dp
        ho%samples = 48*ns
        so%parameter = 'omega'
        so%start = 2.6_dp
        so%stop = 3.2_dp
        so%stability = .false.
        so%truncation = .false.
        call run_sweep(c%model, ho, c%reference%reference_options_t, so, res, error, &
                       cyclic=c%cyclic%cyc)
        call check_error(t, error, "cyclic sweep: run", .false.)
        if (allocated(error)) return
        call check(t, res%complete .and. res%npoints > 5, "cyclic sweep: complete")
        picks = [1, res%npoints/2, res%npoints]
        worst = 0.0_dp
        worst_u = 0.0_dp
        do q = 1, 3
            k = picks(q)
            m = c%model
            m%omega = res%points(k)%omega
            call assemble_disk(m, c%cyclic%cyc, disk, error)
            if (allocated(error)) exit
            ho%rho = res%rho
            call solve_periodic(disk, ho, full, error)
            if (allocated(error)) exit
            scale = maxval(abs(full%xcoef))
            do j = 1, 4
                worst = max(worst, maxval(abs(res%points(k)%xcoef(:, j) - &
                                              full%xcoef(:, disk_dof(c%cyclic%cyc, 4, j, 0))))/ &
                            scale)
            end do
            worst_u = max(worst_u, maxval(abs(res%points(k)%ucoef(:, 1) - &
                                              (full%xcoef(:, disk_dof(c%cyclic%cyc, 4, 2, 0)) - &
                                               full%xcoef(:, disk_dof(c%cyclic%cyc, 4, 2, 1)))))/ &
                          scale)
        end do
        call check_error(t, error, "cyclic sweep: the disk at three points", .false.)
        if (allocated(error)) return
        call check(t, worst < 1.0e-8_dp .and. worst_u < 1.0e-8_dp, &
                   "cyclic sweep: points = the disk's solves, the shroud's relative motion", &
                   "largest difference "//real_text(worst)//", relative displacement "// &
                   real_text(worst_u))
        ! with stability (the disk's flow over T / 8, the reference cache carried from point
        ! to point): the first and last points' largest multiplier = the disk's over T
        so%start = 2.85_dp
        so%stop = 2.95_dp
        so%stability = .true.
        call run_sweep(c%model, ho, c%reference%reference_options_t, so, res, error, &
                       cyclic=c%cyclic%cyc)
        call check_error(t, error, "cyclic sweep with stability: run", .false.)
        if (allocated(error)) return
        worst = huge(1.0_dp)
        if (res%complete .and. res%npoints >= 3) then
            worst = 0.0_dp
            picks(1:2) = [1, res%npoints]
            do q = 1, 2
                k = picks(q)
                m = c%model
                m%omega = res%points(k)%omega
                ho%rho = res%rho
                ho%want_samples = .true.
                call solve_periodic_cyclic(m, c%cyclic%cyc, ho, sec, error)
                if (.not. allocated(error)) call disk_solution(m, c%cyclic%cyc, ho, sec, &
                                                               disk, dsol, error)
                if (.not. allocated(error)) call periodic_stability(disk, dsol, &
                    c%reference%reference_options_t, fl, error)
                if (allocated(error)) exit
                if (res%points(k)%stable == -1 .or. fl%verdict == 'unknown') then
                    worst = huge(1.0_dp)
                else
                    worst = max(worst, abs(res%points(k)%floquet_max - fl%max_modulus))
                end if
            end do
        end if
        call check_error(t, error, "cyclic sweep with stability: the disk's", .false.)
        if (allocated(error)) return
        call check(t, worst < 1.0e-7_dp, "cyclic sweep with stability: the points' largest "// &
                   "multiplier = the disk's over the whole period", "largest difference "// &
                   real_text(worst)//", "//itoa(res%npoints)//" points, last "// &
                   real_text(res%points(res%npoints)%floquet_max))
    end subroutine test_sector_sweep

    !> The sector's weighted residual against the disk's with contact laws: a shroud against
    !> the next blade that lifts off (an elastic unilateral normal on the blade's normal DOF
    !> 5 against the next blade's, preloaded), and a 2D friction contact of the disk on the
    !> ground; EO = 0, 1, 7, 12; sector 0 to 1e-10 of the in-phase response, energies per
    !> sector, and the shroud open part of the period in some wave.
    subroutine test_sector_laws(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector
        type(cyclic_t) :: cyc
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        real(dp) :: worst, worst_energy, opened, slipped
        logical :: converged
        ! DOF 5: the blade's normal motion
        sector = normal_sector()
        ! contact 1: the shroud (tangential DOF 2, normal DOF 5, against the next blade);
        ! contact 2: the disk's middle on the ground in 2D (DOF 4, second tangent DOF 1)
        deallocate (sector%contact_dof, sector%contact_dof2, sector%mu, sector%normal_load)
        sector%contact_dof = [2, 4]
        sector%contact_dof2 = [0, 0]
        sector%mu = [0.3_dp, 0.2_dp]
        sector%normal_load = [0.0_dp, 2.0_dp]
        allocate (sector%normal_direction(5, 2), sector%tangent2_direction(5, 2))
        sector%normal_direction = 0.0_dp
        sector%normal_direction(5, 1) = 1.0_dp
        sector%tangent2_direction = 0.0_dp
        sector%tangent2_direction(1, 2) = 1.0_dp
        sector%gap = [0.0_dp, 0.0_dp]
        sector%preload = [0.3_dp, 0.0_dp]
        sector%normal_stiffness = [20.0_dp, 0.0_dp]
        call validate_model(sector, error)
        call check_error(t, error, "cyclic laws: the sector is a valid model", .false.)
        if (allocated(error)) return
        ho%harmonics = 12
        ho%rho = 0.5_dp
        ho%samples = 48*ns
        ho%tol = 1.0e-12_dp
        cyc = lumped_cyclic(0)
        cyc%next_dof = [2, 0]
        cyc%next_normal_dof = [5, 0]
        call waves_against_disk(sector, cyc, ho, worst, worst_energy, opened, slipped, &
                                converged, error)
        call check_error(t, error, "cyclic laws: EO = 0, 1, 7, 12", .false.)
        if (allocated(error)) return
        call check(t, converged .and. worst < 1.0e-10_dp .and. worst_energy < 1.0e-10_dp .and. &
                   opened > 0.05_dp, "cyclic laws: lift-off against the next blade and 2D "// &
                   "friction, the sector's answer = the disk's sector 0", &
                   "largest difference "//real_text(worst)//", energies "// &
                   real_text(worst_energy)//", largest open share "//real_text(opened))
    end subroutine test_sector_laws

    !> 2D friction against the next sector: the shroud of the 6-DOF sector rubs on the next
    !> blade in two tangents (the blade's tangential DOF 2 and axial DOF 6: next_dof,
    !> next_tangent2_dof) under an elastic unilateral normal on the next blade's normal DOF 5
    !> (next_normal_dof, preloaded, lifting off); EO = 0, 1, 7, 12; the sector's answer
    !> equals sector 0 of the assembled disk's to 1e-10 of the in-phase response, the
    !> energies per sector the disk's / N, and the shroud slips in both tangents in some wave.
    !> A 2D contact with next_dof alone is refused, naming next_tangent2_dof.
    subroutine test_sector_planar(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector
        type(cyclic_t) :: cyc
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        real(dp) :: worst, worst_energy, opened, slipped
        real(dp), allocatable :: m(:, :), k(:, :)
        logical :: converged
        sector = lumped_sector()
        ! DOF 5: the blade's normal motion, DOF 6: its axial motion
        allocate (m(6, 6), k(6, 6))
        m = 0.0_dp
        k = 0.0_dp
        m(1:4, 1:4) = sector%mass
        k(1:4, 1:4) = sector%stiffness
        m(5, 5) = 0.3_dp
        m(6, 6) = 0.3_dp
        k(5, 5) = 6.0_dp
        k(6, 6) = 4.0_dp
        sector%ndof = 6
        sector%mass = m
        sector%stiffness = k
        sector%damping = 0.01_dp*sector%mass + 0.002_dp*sector%stiffness
        sector%force_dof = [2, 5, 6]
        sector%force_harmonic = [1, 1, 1]
        sector%force_amplitude = [1.0_dp, 0.6_dp, 0.8_dp]
        sector%force_phase = [0.3_dp, 1.1_dp, -0.4_dp]
        deallocate (sector%contact_dof, sector%contact_dof2, sector%mu, sector%normal_load)
        sector%contact_dof = [2]
        sector%contact_dof2 = [0]
        sector%mu = [0.3_dp]
        sector%normal_load = [0.0_dp]
        allocate (sector%normal_direction(6, 1), sector%tangent2_direction(6, 1))
        sector%normal_direction = 0.0_dp
        sector%normal_direction(5, 1) = 1.0_dp
        sector%tangent2_direction = 0.0_dp
        sector%tangent2_direction(6, 1) = 1.0_dp
        sector%gap = [0.0_dp]
        sector%preload = [0.3_dp]
        sector%normal_stiffness = [20.0_dp]
        call validate_model(sector, error)
        call check_error(t, error, "cyclic 2D: the sector is a valid model", .false.)
        if (allocated(error)) return
        ho%harmonics = 12
        ho%rho = 0.5_dp
        ho%samples = 48*ns
        ho%tol = 1.0e-12_dp
        ! next_dof without next_tangent2_dof: refused
        cyc = lumped_cyclic(1)
        cyc%next_dof = [2]
        cyc%next_normal_dof = [5]
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic 2D: next_dof alone on a 2D contact", .true., &
                         [character(len=40) :: "cyc%next_tangent2_dof(1): missing"])
        cyc = lumped_cyclic(0)
        cyc%next_dof = [2]
        cyc%next_normal_dof = [5]
        cyc%next_tangent2_dof = [6]
        call waves_against_disk(sector, cyc, ho, worst, worst_energy, opened, slipped, &
                                converged, error)
        call check_error(t, error, "cyclic 2D: EO = 0, 1, 7, 12", .false.)
        if (allocated(error)) return
        call check(t, converged .and. worst < 1.0e-10_dp .and. worst_energy < 1.0e-10_dp .and. &
                   slipped > 0.05_dp, "cyclic 2D: 2D friction and lift-off against the next "// &
                   "blade, the sector's answer = the disk's sector 0", &
                   "largest difference "//real_text(worst)//", energies "// &
                   real_text(worst_energy)//", largest slip share "//real_text(slipped)// &
                   ", open share "//real_text(opened))
    end subroutine test_sector_planar

    !> The sector's travelling waves of EO = 0, 1, 7 and 12 (`cyc` with its engine order
    !> replaced) against the assembled disk's own solves: the largest difference of sector 0's
    !> coefficients relative to the in-phase response's largest, of the friction and viscous
    !> energies per sector relative to its forcing work, the largest open and slip shares of
    !> contact 1, and whether every solve converged.
    subroutine waves_against_disk(sector, cyc, ho, worst, worst_energy, opened, slipped, &
                                  converged, error)
        type(model_t), intent(in) :: sector
        type(cyclic_t), intent(in) :: cyc
        type(hbm_options_t), intent(in) :: ho
        real(dp), intent(out) :: worst, worst_energy, opened, slipped
        logical, intent(out) :: converged
        type(error_type), allocatable, intent(out) :: error
        integer, parameter :: orders(4) = [0, 1, 7, 12]
        type(cyclic_t) :: c
        type(hbm_solution_t) :: sec, full
        real(dp), allocatable :: disk0(:, :)
        real(dp) :: scale, work0
        integer :: e
        worst = 0.0_dp
        worst_energy = 0.0_dp
        opened = 0.0_dp
        slipped = 0.0_dp
        converged = .true.
        do e = 1, size(orders)
            c = cyc
            c%engine_order = orders(e)
            call sector_and_disk(sector, c, ho, sec, full, disk0, error)
            if (allocated(error)) return
            converged = converged .and. sec%converged .and. full%converged
            ! the scales: the in-phase response (EO = 0, first) and its forcing work
            if (e == 1) then
                scale = maxval(abs(full%xcoef))
                work0 = full%work_forcing/ns
            end if
            worst = max(worst, maxval(abs(sec%xcoef - disk0))/scale)
            worst_energy = max(worst_energy, &
                               abs(sec%diss_friction - full%diss_friction/ns)/work0, &
                               abs(sec%diss_damping - full%diss_damping/ns)/work0)
            opened = max(opened, sec%open_fraction(1))
            slipped = max(slipped, sec%slip_fraction(1))
        end do
    end subroutine waves_against_disk

    !> The sector's travelling wave `sec` and the assembled disk's weighted residual `full`
    !> with the same options, and `disk0`: the disk's coefficients of sector 0's DOFs (nb x
    !> the sector's DOFs, as sec%xcoef).
    subroutine sector_and_disk(sector, cyc, ho, sec, full, disk0, error)
        type(model_t), intent(in) :: sector
        type(cyclic_t), intent(in) :: cyc
        type(hbm_options_t), intent(in) :: ho
        type(hbm_solution_t), intent(out) :: sec, full
        real(dp), allocatable, intent(out) :: disk0(:, :)
        type(error_type), allocatable, intent(out) :: error
        type(model_t) :: disk
        integer :: j
        call solve_periodic_cyclic(sector, cyc, ho, sec, error)
        if (allocated(error)) return
        call assemble_disk(sector, cyc, disk, error)
        if (allocated(error)) return
        call solve_periodic(disk, ho, full, error)
        if (allocated(error)) return
        allocate (disk0(size(full%xcoef, 1), sector%ndof))
        do j = 1, sector%ndof
            disk0(:, j) = full%xcoef(:, disk_dof(cyc, sector%ndof, j, 0))
        end do
    end subroutine sector_and_disk

    !> The weighted residual on one sector (the travelling wave, contacts rubbing on the next
    !> blade) against the same solve on the assembled disk, for EO = 0, 1, 7 and 12 = N/2,
    !> the shrouds slipping: sector 0's coefficients of every DOF and harmonic agree to
    !> 1e-10 of the in-phase response (EO = 0), the friction and viscous dissipation per
    !> period is the disk's divided by N, and the sector's energy balance holds (1e-10 of
    !> the in-phase response's forcing work).
    subroutine test_sector_solve(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: disk, sector
        type(cyclic_t) :: cyc
        type(hbm_solution_t) :: sec, full
        type(hbm_options_t) :: ho
        type(error_type), allocatable :: error
        integer, parameter :: orders(4) = [0, 1, 7, 12]
        integer :: e
        real(dp) :: worst, worst_energy, scale, work0
        real(dp), allocatable :: disk0(:, :)
        logical :: converged
        type(truncation_t) :: est_sector, est_disk
        call read_case(project_path("examples/bladed_disk.nml"), c, error)
        call check_error(t, error, "cyclic sector solve: read the example", .false.)
        if (allocated(error)) return
        ! a drive five times the example's: the shrouds slip in every wave (with 0.2 N the
        ! waves of EO = 7 and 12 stick them, which holds every blade still)
        sector = c%cyclic%sector
        sector%force_amplitude = [1.0_dp]
        ho = c%hbm
        ho%rho = 0.5_dp
        ! samples a multiple of N: the disk's contacts are sampled at the same instants of
        ! their own cycles (a delay EO T / N is a whole number of samples), so that the
        ! disk's discrete equations are the sector's exactly
        ho%samples = 48*ns
        ho%tol = 1.0e-12_dp
        worst = 0.0_dp
        worst_energy = 0.0_dp
        converged = .true.
        do e = 1, size(orders)
            cyc = c%cyclic%cyc
            cyc%engine_order = orders(e)
            call sector_and_disk(sector, cyc, ho, sec, full, disk0, error)
            if (allocated(error)) exit
            converged = converged .and. sec%converged .and. full%converged
            ! the scales: the response without shroud slip (EO = 0, the shrouds in phase,
            ! first) and its forcing work
            if (e == 1) then
                scale = maxval(abs(full%xcoef))
                work0 = full%work_forcing/ns
            end if
            worst = max(worst, maxval(abs(sec%xcoef - disk0))/scale)
            worst_energy = max(worst_energy, &
                               abs(sec%diss_friction - full%diss_friction/ns)/work0, &
                               abs(sec%diss_damping - full%diss_damping/ns)/work0, &
                               abs(sec%work_forcing - sec%diss_friction - sec%diss_damping)/ &
                               work0)
        end do
        call check_error(t, error, "cyclic sector solve: EO = 0, 1, 7, 12", .false.)
        if (allocated(error)) return
        call check(t, converged .and. worst < 1.0e-10_dp, &
                   "cyclic sector solve: the sector's answer = the disk's sector 0", &
                   "largest difference "//real_text(worst)//" of the largest amplitude")
        call check(t, worst_energy < 1.0e-10_dp, &
                   "cyclic sector solve: energies per sector = the disk's / N, balanced", &
                   real_text(worst_energy))
        ! the truncation estimate of the sector (its coarse solve on the sector, the shroud's
        ! Coulomb defect on the relative motion) = the disk's, at EO = 1
        cyc = c%cyclic%cyc
        cyc%engine_order = 1
        call solve_periodic_cyclic(sector, cyc, ho, sec, error)
        if (.not. allocated(error)) call estimate_truncation(sector, ho, sec, est_sector, error, &
                                                              cyclic=cyc)
        if (.not. allocated(error)) call assemble_disk(sector, cyc, disk, error)
        if (.not. allocated(error)) call solve_periodic(disk, ho, full, error)
        if (.not. allocated(error)) call estimate_truncation(disk, ho, full, est_disk, error)
        call check_error(t, error, "cyclic sector solve: truncation estimates", .false.)
        if (allocated(error)) return
        call check(t, est_sector%available .and. est_disk%available .and. &
                   abs(est_sector%estimate - est_disk%estimate) < 1.0e-8_dp*est_disk%estimate &
                   .and. abs(est_sector%psi_rms - est_disk%psi_rms) < 1.0e-8_dp*est_disk%psi_rms, &
                   "cyclic sector solve: the sector's truncation estimate = the disk's", &
                   real_text(est_sector%estimate)//" vs "//real_text(est_disk%estimate))
    end subroutine test_sector_solve

    !> The shrouded disk (examples/bladed_disk.nml, 24 sectors, omega 2.9) where every shroud
    !> sticks to the next blade all period: in engine orders 6 and 12 the blades cannot
    !> move (a tip stuck to both neighbours moves in nodal diameter 0 only) and the forcing
    !> 0.2 N at the tip is held by the shrouds, |r| = 0.2 / (2 sin(pi EO / N)) = 0.141421 and
    !> 0.1 (< mu N = 0.15); in engine order 0 the disk moves in phase, the shrouds without
    !> force. At rest the sector's solution says so (at_rest), is trusted (no energy or
    !> Coulomb-dissipation finding: every work is roundoff) and its truncation estimate is
    !> small. The stuck shrouds close a ring (24 constraints, 23 independent): the exact
    !> flow runs (minimum-norm forces) and the disk's Floquet multipliers in all three
    !> engine orders are those of the disk with its shrouds held rigidly, computed here
    !> independently (the velocities in the null space of the 24 constraints, its 98
    !> eigenvalues, exp(lambda T)) and 23 of 1 (the stuck shrouds' offsets persist): the
    !> verdict 'marginal', every nonzero multiplier within 1e-7.
    subroutine test_stuck_ring(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(model_t) :: disk
        type(hbm_solution_t) :: sec, dsol
        type(hbm_options_t) :: ho
        type(floquet_t) :: fl
        type(truncation_t) :: est
        type(error_type), allocatable :: error
        real(dp), allocatable :: expected(:), got(:)
        real(dp) :: rmax, rexact, worst
        integer :: k, eo, nexp
        integer, parameter :: orders(3) = [6, 12, 0]
        call read_case(project_path("examples/bladed_disk.nml"), c, error)
        call check_error(t, error, "stuck ring: read the shrouded disk", .false.)
        if (allocated(error)) return
        ho = c%hbm
        do k = 1, size(orders)
            eo = orders(k)
            c%cyclic%cyc%engine_order = eo
            call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
            if (.not. allocated(error)) call estimate_truncation(c%model, ho, sec, est, error, &
                                                                 cyclic=c%cyclic%cyc)
            if (.not. allocated(error)) call disk_solution(c%model, c%cyclic%cyc, ho, sec, &
                                                           disk, dsol, error)
            if (.not. allocated(error)) call periodic_stability(disk, dsol, &
                                                                c%reference%reference_options_t, &
                                                                fl, error)
            call check_error(t, error, "stuck ring: EO "//itoa(eo), .false.)
            if (allocated(error)) return
            rmax = maxval(abs(sec%r(:, 1)))
            if (eo /= 0) then
                rexact = 0.2_dp/(2.0_dp*sin(two_pi/2.0_dp*eo/ns))
                call check(t, sec%converged .and. sec%at_rest .and. &
                           abs(rmax - rexact) < 1.0e-8_dp*rexact .and. &
                           minval(sec%stick_fraction) == 1.0_dp .and. &
                           .not. sec%diagnostics%has("energy_balance") .and. &
                           .not. sec%diagnostics%has("coulomb_dissipation") .and. &
                           sec%diagnostics%worst() < level_warning .and. &
                           est%estimate < 1.0e-3_dp, &
                           "stuck ring: EO "//itoa(eo)//", the disk at rest, the shrouds "// &
                           "holding the forcing, trusted", &
                           "at_rest "//merge("T", "F", sec%at_rest)//", max |r| "// &
                           real_text(rmax)//" vs "//real_text(rexact)//", truncation "// &
                           real_text(est%estimate)//", worst finding "// &
                           itoa(sec%diagnostics%worst()))
            else
                call check(t, sec%converged .and. .not. sec%at_rest .and. &
                           rmax < 1.0e-12_dp .and. sec%diagnostics%worst() < level_warning, &
                           "stuck ring: EO 0, the disk moves in phase, the shrouds idle", &
                           "max |r| "//real_text(rmax))
            end if
            if (k == 1) then
                call held_multipliers(disk, c%cyclic%cyc, expected, error)
                call check_error(t, error, "stuck ring: the held disk's multipliers", .false.)
                if (allocated(error)) return
            end if
            nexp = size(expected)
            worst = huge(1.0_dp)
            if (allocated(fl%multipliers)) then
                if (size(fl%multipliers) >= nexp) then
                    got = abs(fl%multipliers(1:nexp))
                    worst = maxval(abs(got - expected))
                end if
            end if
            call check(t, fl%verdict == 'marginal' .and. fl%nmarginal == ns - 1 .and. &
                       fl%nzero == 2*disk%ndof - nexp .and. worst < 1.0e-7_dp, &
                       "stuck ring: EO "//itoa(eo)//", the disk's multipliers = the held "// &
                       "disk's and 23 of 1", "verdict "//fl%verdict//", "//itoa(fl%nmarginal)// &
                       " on the circle, "//itoa(fl%nzero)//" zero, largest difference "// &
                       real_text(worst)//"; "//fl%diagnosis)
        end do

    contains

        !> Moduli of the multipliers exp(lambda T) of the disk with every shroud held (C^T v
        !> = 0, C the 24 relative tip directions), by decreasing modulus, with the 23 of 1
        !> of the held offsets among them.
        subroutine held_multipliers(disk, cyc, mods, error)
            type(model_t), intent(in) :: disk
            type(cyclic_t), intent(in) :: cyc
            real(dp), allocatable, intent(out) :: mods(:)
            type(error_type), allocatable, intent(out) :: error
            real(dp), allocatable :: cm(:, :), g(:, :), ev(:), work(:), z(:, :), mr(:, :), &
                                     kr(:, :), cr(:, :), a(:, :), wr(:), wi(:)
            real(dp) :: vl(1, 1), period
            integer, allocatable :: ipiv(:)
            integer :: n, s, info, nr, j, q
            n = disk%ndof
            allocate (cm(n, ns))
            cm = 0.0_dp
            do s = 0, ns - 1
                cm(disk_dof(cyc, 4, 2, s), s + 1) = 1.0_dp
                cm(disk_dof(cyc, 4, 2, mod(s + 1, ns)), s + 1) = -1.0_dp
            end do
            ! the null space of C^T: eigenvectors of C C^T with eigenvalue ~0
            g = matmul(cm, transpose(cm))
            allocate (ev(n), work(10*n))
            call dsyev('V', 'U', n, g, n, ev, work, size(work), info)
            if (info /= 0) then
                error = error_type(1, "dsyev failed")
                return
            end if
            z = g(:, pack([(j, j=1, n)], ev < 1.0e-10_dp*maxval(ev)))
            nr = size(z, 2)
            mr = matmul(transpose(z), matmul(disk%mass, z))
            kr = matmul(transpose(z), matmul(disk%stiffness, z))
            cr = matmul(transpose(z), matmul(disk%damping, z))
            ! A = [0 I; -Mr^-1 Kr, -Mr^-1 Cr]
            allocate (ipiv(nr), a(2*nr, 2*nr))
            g = reshape([kr, cr], [nr, 2*nr])
            call dgesv(nr, 2*nr, mr, nr, ipiv, g, nr, info)
            a = 0.0_dp
            do q = 1, nr
                a(q, nr + q) = 1.0_dp
            end do
            a(nr + 1:, :) = -g
            allocate (wr(2*nr), wi(2*nr))
            deallocate (work)
            allocate (work(20*nr))
            call dgeev('N', 'N', 2*nr, a, 2*nr, wr, wi, vl, 1, vl, 1, work, size(work), info)
            if (info /= 0) then
                error = error_type(1, "dgeev failed")
                return
            end if
            period = two_pi/disk%omega
            mods = [exp(wr*period), [(1.0_dp, j=1, n - nr)]]
            ! by decreasing modulus
            do j = 2, size(mods)
                do q = j, 2, -1
                    if (mods(q) <= mods(q - 1)) exit
                    call swap(mods(q), mods(q - 1))
                end do
            end do
        end subroutine held_multipliers

    end subroutine test_stuck_ring

    !> examples/bladed_disk.nml (24 sectors, a shroud contact rubbing on the next blade, EO 3)
    !> with &cyclic model = 'disk', solved by the weighted residual on the assembled disk:
    !> the answer is a travelling wave, every sector's harmonic h the first sector's times
    !> exp(-i h 2 pi 3 s / 24) (all DOFs, all 15 harmonics, to 1e-8 of the largest
    !> amplitude); every contact slips alike.
    subroutine test_disk_wave(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c
        type(hbm_solution_t) :: sol
        type(error_type), allocatable :: error
        complex(dp) :: x0, xs
        real(dp) :: worst, scale
        integer :: k, h, s, j
        character(len=300) :: lines(30)
        integer :: u, nl, stat
        ! the example with model = 'disk'
        open (newunit=u, file=project_path("examples/bladed_disk.nml"), status='old', &
              action='read')
        nl = 0
        do
            read (u, '(a)', iostat=stat) lines(nl + 1)
            if (stat /= 0) exit
            nl = nl + 1
            if (index(lines(nl), "&cyclic") == 1) lines(nl) = trim(lines(nl)(1:index( &
                lines(nl), "/", back=.true.) - 1))//", model = 'disk' /"
        end do
        close (u)
        call write_lines(scratch//"/cyclic_disk.nml", lines(1:nl))
        call read_case(scratch//"/cyclic_disk.nml", c, error)
        call check_error(t, error, "cyclic disk wave: read the example", .false.)
        if (allocated(error)) return
        call solve_periodic(c%model, c%hbm, sol, error)
        call check_error(t, error, "cyclic disk wave: solve", .false.)
        if (allocated(error)) return
        call check(t, sol%converged .and. c%model%ndof == 72 .and. c%model%ncontact() == 24, &
                   "cyclic disk wave: the 72-DOF disk with 24 contacts converged")
        scale = maxval(abs(sol%xcoef))
        worst = 0.0_dp
        do k = 1, size(sol%harmonic) - 1
            h = sol%harmonic(k)
            if (h == 0 .or. sol%harmonic(k + 1) /= h) cycle
            do j = 1, 4
                x0 = cmplx(sol%xcoef(k, disk_dof(c%cyclic%cyc, 4, j, 0)), &
                           -sol%xcoef(k + 1, disk_dof(c%cyclic%cyc, 4, j, 0)), dp)
                do s = 1, ns - 1
                    xs = cmplx(sol%xcoef(k, disk_dof(c%cyclic%cyc, 4, j, s)), &
                               -sol%xcoef(k + 1, disk_dof(c%cyclic%cyc, 4, j, s)), dp)
                    worst = max(worst, abs(xs - x0*exp(cmplx(0.0_dp, &
                                                              sector_phase(h, 3, ns, s), dp))))
                end do
            end do
        end do
        call check(t, worst < 1.0e-8_dp*scale .and. &
                   maxval(sol%stick_fraction) - minval(sol%stick_fraction) < 1.0e-9_dp, &
                   "cyclic disk wave: every sector the phased copy of the first", &
                   "largest difference "//real_text(worst/scale)//" of the largest amplitude")
    end subroutine test_disk_wave

    !> &cyclic in a case file: the model becomes the disk; its echo reads back to the same
    !> disk; bad input names &cyclic and the variable.
    subroutine test_case_input(t)
        type(test_counter_t), intent(inout) :: t
        type(case_t) :: c, back
        type(error_type), allocatable :: error
        character(len=*), parameter :: path = scratch//"/cyclic_case.nml"
        character(len=*), parameter :: echo = scratch//"/cyclic_echo.nml"
        character(len=100), parameter :: head(4) = [character(len=100) :: &
            "&system ndof = 4, mass = 0.25,0,0,0, 0,0.3,0,0, 0,0,0.25,0, 0,0,0,1.0,", &
            "  stiffness = 20,0,0,-20, 0,3,0,-3, 0,0,20,-20, -20,-3,-20,48 /", &
            "&forcing omega = 2.9, force_dof = 2, force_amplitude = 0.2 /", &
            "&friction contact_dof = 2, mu = 0.3, normal_load = 0.5 /"]
        character(len=120), parameter :: bad(8) = [character(len=120) :: &
            "&cyclic engine_order = 3, left_dofs = 1, right_dofs = 3, model = 'disk' /", &
            "&cyclic sectors = 24, engine_order = -1"// &
            ", left_dofs = 1, right_dofs = 3, model = 'disk' /", &
            "&cyclic sectors = 24, engine_order = 3"// &
            ", left_dofs = 1, 4, right_dofs = 3, model = 'disk' /", &
            "&cyclic sectors = 24, engine_order = 3"// &
            ", left_dofs = 1, 1, right_dofs = 3, 2, model = 'disk' /", &
            "&cyclic sectors = 1, engine_order = 3"// &
            ", left_dofs = 1, right_dofs = 3, model = 'disk' /", &
            "&cyclic sectors = 24, engine_order = 3"// &
            ", left_dofs = 1, right_dofs = 3, next_dof = 3, model = 'disk' /", &
            "&cyclic sectors = 24, engine_order = 3"// &
            ", left_dofs = 1, right_dofs = 3, model = 'ring' /", &
            "&cyclic sectors = 24, engine_order = 3, left_dofs = 1, right_dofs = 3"// &
            ", next_tangent2_dof = 4 /"]
        character(len=*), parameter :: good = "&cyclic sectors = 24, engine_order = 3, "// &
            "left_dofs = 1, right_dofs = 3, next_dof = 2, model = 'disk' /"
        character(len=40), parameter :: named(8) = [character(len=40) :: &
            "&cyclic sectors: missing", &
            "&cyclic engine_order = -1", "&cyclic left_dofs, right_dofs", &
            "&cyclic left_dofs(2) = 1: repeated", "&cyclic sectors = 1", &
            "&cyclic next_dof(1) = 3", "&cyclic model = 'ring'", &
            "&cyclic next_tangent2_dof(1)"]
        integer :: k, u
        character(len=200) :: msg_buffer
        msg_buffer = ''
        call write_lines(path, [character(len=120) :: head, good, &
                                "&output directory = '"//scratch//"/cyclic_case' /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic case: read", .false.)
        if (allocated(error)) return
        open (newunit=u, file=echo, status='replace', action='write')
        call write_case(u, c, k, msg_buffer)
        close (u)
        call read_case(echo, back, error)
        call check_error(t, error, "cyclic case: the echo reads back", .false.)
        if (allocated(error)) return
        call check(t, back%model%ndof == 72 .and. c%model%ndof == 72 .and. &
                   all(back%model%stiffness == c%model%stiffness) .and. &
                   all(back%model%contact_direction == c%model%contact_direction) .and. &
                   all(back%model%force_phase == c%model%force_phase), &
                   "cyclic case: the disk from the echo = the disk")
        do k = 1, size(bad)
            call write_lines(path, [character(len=120) :: head, bad(k)])
            call read_case(path, c, error)
            call check_error(t, error, "cyclic case: "//trim(bad(k)), .true., &
                             [named(k), "cyclic_case.nml                         "])
        end do
        ! one sector runs the weighted residual alone
        call write_lines(path, [character(len=120) :: head, &
            "&cyclic sectors = 24, engine_order = 3, left_dofs = 1, right_dofs = 3 /", &
            "&run method = 'euler' /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic case: euler on one sector", .true., &
                         [character(len=40) :: "&run method = 'euler'", "model = 'disk'"])
        ! a sector's stability is the assembled disk's: 24 x 3 DOFs are affordable, 48 x 3
        ! are not in engine order 24 (the flow over T / 2; the default &sweep stability named
        ! as such), nor an explicit &hbm one; in engine order 3 they are (the flow over T /
        ! 16), 80 x 3 are not (the limit 192 and the span named)
        call write_lines(path, [character(len=120) :: head, &
            "&cyclic sectors = 24, engine_order = 3, left_dofs = 1, right_dofs = 3 /", &
            "&run method = 'sweep' /", "&sweep start = 2, stop = 3 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic case: the stability of a 72-DOF disk", .false.)
        call write_lines(path, [character(len=120) :: head, &
            "&cyclic sectors = 48, engine_order = 24, left_dofs = 1, right_dofs = 3 /", &
            "&run method = 'sweep' /", "&sweep start = 2, stop = 3 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic case: the stability of a 144-DOF disk", .true., &
                         [character(len=40) :: "&sweep stability = .true. (the default)", &
                          "144 DOFs", "more than the 128", "over T/2 by the wave's", &
                          "stability = .false.", "cyclic_case.nml"])
        call write_lines(path, [character(len=120) :: head, &
            "&cyclic sectors = 48, engine_order = 3, left_dofs = 1, right_dofs = 3 /", &
            "&hbm samples = 768 /", "&run method = 'sweep' /", "&sweep start = 2, stop = 3 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic case: the stability of a 144-DOF disk in EO 3", &
                         .false.)
        call write_lines(path, [character(len=120) :: head, &
            "&cyclic sectors = 80, engine_order = 1, left_dofs = 1, right_dofs = 3 /", &
            "&hbm samples = 960 /", "&run method = 'sweep' /", "&sweep start = 2, stop = 3 /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic case: the stability of a 240-DOF disk in EO 1", &
                         .true., [character(len=40) :: "240 DOFs", "more than the 192", &
                                  "over T/80 by the wave's"])
        call write_lines(path, [character(len=120) :: head, &
            "&cyclic sectors = 48, engine_order = 24, left_dofs = 1, right_dofs = 3 /", &
            "&hbm stability = .true. /"])
        call read_case(path, c, error)
        call check_error(t, error, "cyclic case: an hbm stability on a 144-DOF disk", .true., &
                         [character(len=40) :: "&hbm stability = .true.: the stab", &
                          "144 DOFs"])
    end subroutine test_case_input

    !> The lumped sector: DOF 1 the left disk node, 2 the blade, 3 the right disk node, 4 the
    !> disk's middle node; the ring k_r / 2 from each boundary node to the middle, the blade
    !> on the middle (k_b), the middle on the shaft (k_g); half a boundary node's mass on each
    !> side; Rayleigh damping 0.01 M + 0.002 K; the blade forced at harmonic 1.
    function lumped_sector() result(m)
        type(model_t) :: m
        real(dp), parameter :: kr = 40.0_dp, kb = 3.0_dp, kg = 5.0_dp
        m%ndof = 4
        allocate (m%mass(4, 4), m%stiffness(4, 4))
        m%mass = 0.0_dp
        m%mass(1, 1) = 0.25_dp
        m%mass(3, 3) = 0.25_dp
        m%mass(2, 2) = 0.3_dp
        m%mass(4, 4) = 1.0_dp
        m%stiffness = 0.0_dp
        call add_spring(m%stiffness, 1, 4, 0.5_dp*kr)
        call add_spring(m%stiffness, 3, 4, 0.5_dp*kr)
        call add_spring(m%stiffness, 2, 4, kb)
        m%stiffness(4, 4) = m%stiffness(4, 4) + kg
        m%damping = 0.01_dp*m%mass + 0.002_dp*m%stiffness
        m%omega = 3.0_dp
        m%force_dof = [2]
        m%force_harmonic = [1]
        m%force_amplitude = [1.0_dp]
        m%force_phase = [0.3_dp]
        allocate (m%contact_dof(0), m%contact_dof2(0), m%mu(0), m%normal_load(0))
    end function lumped_sector

    !> The lumped sector with DOF 5, the blade's normal motion (mass 0.3, stiffness 6 to the
    !> ground), forced on the blade and on DOF 5; no contacts.
    function normal_sector() result(m)
        type(model_t) :: m
        m = lumped_sector()
        m%ndof = 5
        m%mass = reshape([m%mass(:, 1), 0.0_dp, m%mass(:, 2), 0.0_dp, m%mass(:, 3), 0.0_dp, &
                          m%mass(:, 4), 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.3_dp], [5, 5])
        m%stiffness = reshape([m%stiffness(:, 1), 0.0_dp, m%stiffness(:, 2), 0.0_dp, &
                               m%stiffness(:, 3), 0.0_dp, m%stiffness(:, 4), 0.0_dp, 0.0_dp, &
                               0.0_dp, 0.0_dp, 0.0_dp, 6.0_dp], [5, 5])
        m%damping = 0.01_dp*m%mass + 0.002_dp*m%stiffness
        m%force_dof = [2, 5]
        m%force_harmonic = [1, 1]
        m%force_amplitude = [1.0_dp, 0.6_dp]
        m%force_phase = [0.3_dp, 1.1_dp]
    end function normal_sector

    !> The undamped natural frequencies of a dense model, increasing [rad/s] (LAPACK dsygv;
    !> `info` its info, the frequencies undefined when nonzero).
    subroutine model_frequencies(model, omegas, info)
        type(model_t), intent(in) :: model
        real(dp), allocatable, intent(out) :: omegas(:)
        integer, intent(out) :: info
        real(dp), allocatable :: k(:, :), m(:, :), work(:)
        real(dp) :: q(1)
        k = model%stiffness
        m = model%mass
        allocate (omegas(model%ndof))
        call dsygv(1, 'N', 'U', model%ndof, k, model%ndof, m, model%ndof, omegas, q, -1, info)
        allocate (work(int(q(1))))
        call dsygv(1, 'N', 'U', model%ndof, k, model%ndof, m, model%ndof, omegas, work, &
                   size(work), info)
        omegas = sqrt(max(omegas, 0.0_dp))
    end subroutine model_frequencies

    !> Add a spring k between DOFs a and b to the stiffness matrix `stiffness`.
    pure subroutine add_spring(stiffness, a, b, k)
        real(dp), intent(inout) :: stiffness(:, :)
        integer, intent(in) :: a, b
        real(dp), intent(in) :: k
        stiffness(a, a) = stiffness(a, a) + k
        stiffness(b, b) = stiffness(b, b) + k
        stiffness(a, b) = stiffness(a, b) - k
        stiffness(b, a) = stiffness(b, a) - k
    end subroutine add_spring

    function lumped_cyclic(eo) result(c)
        integer, intent(in) :: eo
        type(cyclic_t) :: c
        c%sectors = ns
        c%engine_order = eo
        c%left = [1]
        c%right = [3]
    end function lumped_cyclic

    !> Nodal diameters: h EO modulo N folded to 0..N/2.
    subroutine test_nodal_diameter(t)
        type(test_counter_t), intent(inout) :: t
        call check(t, nodal_diameter(1, 3, 24) == 3 .and. nodal_diameter(1, 17, 24) == 7 .and. &
                   nodal_diameter(3, 5, 24) == 9 .and. nodal_diameter(5, 5, 24) == 1 .and. &
                   nodal_diameter(2, 12, 24) == 0 .and. nodal_diameter(1, 12, 24) == 12 .and. &
                   nodal_diameter(1, 0, 24) == 0, &
                   "cyclic: nodal diameters (aliasing above N/2, multiples of N)")
    end subroutine test_nodal_diameter

    !> The sector's cyclic frequencies for nd = 0..12 (1..11 twice) = the assembled disk's 72.
    subroutine test_frequencies(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector, disk
        type(cyclic_t) :: cyc
        type(error_type), allocatable :: error
        real(dp), allocatable :: w(:), all(:), ev(:)
        integer :: nd, info, i, j, v
        sector = lumped_sector()
        cyc = lumped_cyclic(3)
        call assemble_disk(sector, cyc, disk, error)
        call check_error(t, error, "cyclic frequencies: assemble", .false.)
        if (allocated(error)) return
        call validate_model(disk, error)
        call check_error(t, error, "cyclic frequencies: the disk is a valid model", .false.)
        if (allocated(error)) return
        allocate (all(0))
        do nd = 0, ns/2
            call cyclic_frequencies(sector, cyc, nd, w, error)
            if (allocated(error)) exit
            all = [all, w]
            if (nd > 0 .and. nd < ns/2) all = [all, w]
        end do
        call check_error(t, error, "cyclic frequencies: every nodal diameter", .false.)
        if (allocated(error)) return
        ! insertion sort
        do i = 2, size(all)
            v = i
            do j = i - 1, 1, -1
                if (all(j) <= all(v)) exit
                call swap(all(j), all(v))
                v = j
            end do
        end do
        call model_frequencies(disk, ev, info)
        call check(t, disk%ndof == 72 .and. size(all) == 72 .and. info == 0, &
                   "cyclic frequencies: 72 of the sector (3 a diameter), 72 of the disk")
        if (size(all) /= size(ev)) return
        call check(t, maxval(abs(all - ev)/ev) < 1.0e-10_dp, &
                   "cyclic frequencies: the sector's per nodal diameter = the disk's", &
                   "largest relative difference "//real_text(maxval(abs(all - ev)/ev)))
    end subroutine test_frequencies

    !> Exchange two reals.
    pure subroutine swap(a, b)
        real(dp), intent(inout) :: a, b
        real(dp) :: c
        c = a
        a = b
        b = c
    end subroutine swap

    !> The disk's linear response at the forced harmonic (Z_disk X = F_disk from the
    !> assembled, phased forcing) against the sector's: X_sector from the sector's pencil on
    !> the motions with X_right = exp(-i h 2 pi EO / N) X_left, each sector s the copy times
    !> exp(i sector_phase); for EO = 0, 3, 12 and 17 (aliased to 7, travelling backwards).
    subroutine test_forced_wave(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector, disk
        type(cyclic_t) :: cyc
        type(error_type), allocatable :: error
        complex(dp), allocatable :: zd(:, :), fd(:, :), tt(:, :), zs(:, :), fs(:, :), xs(:)
        integer, allocatable :: ipiv(:)
        integer :: info, s, j, e, eo
        integer, parameter :: orders(4) = [0, 3, 12, 17]
        real(dp) :: worst, w
        complex(dp) :: ph
        sector = lumped_sector()
        w = sector%omega
        worst = 0.0_dp
        do e = 1, size(orders)
            eo = orders(e)
            cyc = lumped_cyclic(eo)
            call assemble_disk(sector, cyc, disk, error)
            if (allocated(error)) exit
            ! the disk
            zd = cmplx(disk%stiffness - w**2*disk%mass, w*disk%damping, dp)
            allocate (fd(disk%ndof, 1), ipiv(disk%ndof))
            fd = (0.0_dp, 0.0_dp)
            do j = 1, disk%nforce()
                fd(:, 1) = fd(:, 1) + disk%force_amplitude(j)* &
                           exp(cmplx(0.0_dp, disk%force_phase(j), dp))*force_direction(disk, j)
            end do
            call zgesv(disk%ndof, 1, zd, disk%ndof, ipiv, fd, disk%ndof, info)
            deallocate (ipiv)
            ! the sector: DOFs 1, 2, 4 free, DOF 3 = exp(i phase) DOF 1
            ph = exp(cmplx(0.0_dp, sector_phase(1, eo, ns, 1), dp))
            allocate (tt(4, 3))
            tt = (0.0_dp, 0.0_dp)
            tt(1, 1) = 1.0_dp
            tt(3, 1) = ph
            tt(2, 2) = 1.0_dp
            tt(4, 3) = 1.0_dp
            zs = matmul(conjg(transpose(tt)), matmul(cmplx(sector%stiffness - &
                        w**2*sector%mass, w*sector%damping, dp), tt))
            allocate (fs(3, 1), ipiv(3))
            fs(:, 1) = matmul(conjg(transpose(tt)), exp(cmplx(0.0_dp, 0.3_dp, dp))* &
                              force_direction(sector, 1))
            call zgesv(3, 1, zs, 3, ipiv, fs, 3, info)
            xs = matmul(tt, fs(:, 1))
            do s = 0, ns - 1
                do j = 1, 4
                    worst = max(worst, abs(fd(disk_dof(cyc, 4, j, s), 1) - xs(j)* &
                                           exp(cmplx(0.0_dp, sector_phase(1, eo, ns, s), dp)))/ &
                                maxval(abs(xs)))
                end do
            end do
            deallocate (fd, ipiv, tt, fs)
        end do
        call check_error(t, error, "cyclic wave: assemble", .false.)
        call check(t, worst < 1.0e-10_dp, "cyclic wave: the disk's response under EO = 0, 3, "// &
                   "12, 17 = the sector's, each sector its phased copy", &
                   "largest relative difference "//real_text(worst))
    end subroutine test_forced_wave

    !> A contact of the blade against the next sector's blade: on the disk, contact j of
    !> sector s slips with v(blade_s) - v(blade_{s+1}), the last sector's against sector 0's;
    !> its friction data copied.
    subroutine test_disk_contacts(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector, disk
        type(cyclic_t) :: cyc
        type(error_type), allocatable :: error
        logical :: ok
        integer :: s, b0, b1
        sector = lumped_sector()
        sector%contact_dof = [2]
        sector%contact_dof2 = [0]
        sector%mu = [0.4_dp]
        sector%normal_load = [2.0_dp]
        cyc = lumped_cyclic(1)
        cyc%next_dof = [2]
        call assemble_disk(sector, cyc, disk, error)
        call check_error(t, error, "cyclic contacts: assemble", .false.)
        if (allocated(error)) return
        call validate_model(disk, error)
        call check_error(t, error, "cyclic contacts: the disk is a valid model", .false.)
        ok = disk%ncontact() == ns .and. all(disk%mu == 0.4_dp) .and. &
             all(disk%normal_load == 2.0_dp)
        do s = 0, ns - 1
            b0 = disk_dof(cyc, 4, 2, s)
            b1 = disk_dof(cyc, 4, 2, s + 1)
            ok = ok .and. disk%contact_direction(b0, s + 1) == 1.0_dp .and. &
                 disk%contact_direction(b1, s + 1) == -1.0_dp .and. &
                 count(disk%contact_direction(:, s + 1) /= 0.0_dp) == 2
        end do
        call check(t, ok, "cyclic contacts: blade s against blade s + 1, the last against "// &
                   "the first")
        call check(t, disk_dof(cyc, 4, 3, ns - 1) == disk_dof(cyc, 4, 1, 0) .and. &
                   disk_dof(cyc, 4, 3, 0) == disk_dof(cyc, 4, 1, 1), &
                   "cyclic contacts: the right boundary is the next sector's left")
    end subroutine test_disk_contacts

    !> The checks name the culprit.
    subroutine test_checks(t)
        type(test_counter_t), intent(inout) :: t
        type(model_t) :: sector
        type(cyclic_t) :: cyc
        type(error_type), allocatable :: error
        sector = lumped_sector()
        cyc = lumped_cyclic(1)
        cyc%sectors = 1
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: one sector", .true., ["cyc%sectors"])
        cyc = lumped_cyclic(-2)
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: EO < 0", .true., ["cyc%engine_order"])
        cyc = lumped_cyclic(1)
        cyc%right = [3, 4]
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: unpaired", .true., ["pair one to one"])
        cyc%left = [1, 1]
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: repeated", .true., ["cyc%left(2) = 1: repeated"])
        cyc%left = [1, 3]
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: on both boundaries", .true., &
                         ["also a left boundary DOF"])
        cyc = lumped_cyclic(1)
        cyc%right = [5]
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: out of range", .true., ["cyc%right(1) = 5"])
        sector%contact_dof = [2]
        sector%contact_dof2 = [0]
        sector%mu = [0.4_dp]
        sector%normal_load = [2.0_dp]
        cyc = lumped_cyclic(1)
        cyc%next_dof = [3]
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: next DOF on the right boundary", .true., &
                         ["cyc%next_dof(1) = 3"])
        cyc%next_dof = [2]
        cyc%next_normal_dof = [2]
        call validate_cyclic(sector, cyc, error)
        call check_error(t, error, "cyclic checks: a normal for a contact without one", .true., &
                         ["cyc%next_normal_dof(1)"])
    end subroutine test_checks
end module test_cyclic
