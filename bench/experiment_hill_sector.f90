!> Experiment (issue 27): Hill's method on one sector of a tuned disk with Bloch wavenumbers,
!> against the assembled disk's exact Floquet multipliers (the exact event-driven flow),
!> on examples/bladed_disk.nml (24 sectors, tip shrouds rubbing on the next blade, EO 3)
!> at omega = 2.6, 2.9, 3.2. The perturbation of sector s is e^(lambda t) e^(i 2 pi k s / N)
!> p(t - s EO T / N) with p periodic, k = 0..N-1 (k = 0: the wave's own symmetry): harmonic h
!> of p then has the inter-sector phase 2 pi (k - h EO) / N and no delay is left. The
!> linearized weighted residual of the stick-slip equality is the descriptor pencil
!> [Y - lambda q; A_h q + B_h Y - T^H conj(D_h) R_h + lambda M_h Y; sum_l jr_(h-l) R_l +
!> ju_(h-l) D_l^T T_l (i l omega q_l + Y_l)] (jr, ju: dPsi/dr, dPsi/du at the samples, their
!> Fourier coefficients), solved by zggev; kept: the eigenvalues whose eigenvectors are
!> centred on harmonic 0. Prints, per omega, the 20 largest multiplier moduli of the disk and
!> of Hill's union over k at H = 10, 20, 30. Measured (doc/cyclic.md, "Still to come"): the
!> largest agrees to 8 digits (a mode the shrouds do not load), the ones the friction shapes
!> scatter by about 5e-3 without converging in H, with spurious ones: not offered.
!> Usage: fpm run --example experiment_hill_sector --profile release
program experiment_hill_sector
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t, cyclic_basis
    use stickslip_case, only: case_t, read_case
    use stickslip_solution, only: hbm_solution_t, hbm_options_t
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic, disk_solution
    use stickslip_stability, only: floquet_t, periodic_stability
    use stickslip_sorting, only: sort_ascending
    implicit none
    interface
        subroutine zggev(jobvl, jobvr, n, a, lda, b, ldb, alpha, beta, vl, ldvl, vr, ldvr, &
                         work, lwork, rwork, info)
            import :: dp
            character(len=1), intent(in) :: jobvl, jobvr
            integer, intent(in) :: n, lda, ldb, ldvl, ldvr, lwork
            complex(dp), intent(inout) :: a(lda, *), b(ldb, *)
            complex(dp), intent(out) :: alpha(*), beta(*), vl(ldvl, *), vr(ldvr, *), work(*)
            real(dp), intent(out) :: rwork(*)
            integer, intent(out) :: info
        end subroutine zggev
    end interface
    type(case_t) :: c
    type(model_t) :: disk
    type(hbm_solution_t) :: sec, dsol
    type(hbm_options_t) :: ho
    type(floquet_t) :: f1
    type(error_type), allocatable :: error
    real(dp) :: mu(24)
    complex(dp), allocatable :: all_mu(:)
    real(dp), allocatable :: a1(:), a2(:)
    real(dp), parameter :: omegas(3) = [2.6_dp, 2.9_dp, 3.2_dp]
    integer :: k, hh, ks(24), j
    ks = [(k, k=0, 23)]
    call read_case("examples/bladed_disk.nml", c, error)
    if (allocated(error)) error stop "experiment_hill_sector: run it from the project root"
    do j = 1, size(omegas)
        ho = c%hbm
        ho%rho = 0.5_dp
        ho%samples = 48*24
        c%model%omega = omegas(j)
        call solve_periodic_cyclic(c%model, c%cyclic%cyc, ho, sec, error)
        if (.not. allocated(error)) call disk_solution(c%model, c%cyclic%cyc, ho, sec, disk, &
                                                       dsol, error)
        if (.not. allocated(error)) call periodic_stability(disk, dsol, &
                                                            c%reference%reference_options_t, &
                                                            f1, error)
        if (allocated(error)) error stop "experiment_hill_sector: the disk's stability failed"
        print '(a,f6.3,a,f8.5)', 'omega ', omegas(j), ', stick fraction ', sec%stick_fraction(1)
        a1 = abs(f1%multipliers)
        call sort_desc(a1)
        print '(a,20f8.5)', '  disk (exact)  ', a1(1:20:2)
        do hh = 10, 30, 10
            call hill_sector_max(c%model, c%cyclic%cyc, sec, hh, ks, 2, 2, mu, all_mu)
            a2 = abs(all_mu)
            call sort_desc(a2)
            print '(a,i2,a,20f8.5)', '  Hill, H = ', hh, ' ', a2(1:20:2)
        end do
    end do

contains

    !> Sort descending.
    subroutine sort_desc(a)
        real(dp), intent(inout) :: a(:)
        call sort_ascending(a)
        a = a(size(a):1:-1)
    end subroutine sort_desc



    !> Largest Floquet multiplier modulus over the Bloch wavenumbers ks, by Hill's method
    !> with harmonics -hh..hh; one contact (dof cdof against next-sector dof ndof).
    subroutine hill_sector_max(sector, cyc, sol, hh, ks, cdof, ndof, mu_k, all_mu)
        type(model_t), intent(in) :: sector
        type(cyclic_t), intent(in) :: cyc
        type(hbm_solution_t), intent(in) :: sol
        integer, intent(in) :: hh, ks(:), cdof, ndof
        real(dp), intent(out) :: mu_k(:)
        complex(dp), allocatable, intent(out) :: all_mu(:)
        integer :: n, m, nt, shift, nblk, ntot, h, l, k, b, c, info, i, kk
        real(dp), allocatable :: r(:, :), u(:, :), p(:, :), jr(:, :, :), ju(:, :, :)
        complex(dp), allocatable :: jrc(:), juc(:), a(:, :), bm(:, :), alpha(:), beta(:), &
            vr(:, :), vl(:, :), work(:), t(:, :), d(:)
        real(dp), allocatable :: rwork(:)
        complex(dp), allocatable :: ts(:, :, :), ds(:, :)
        complex(dp) :: e, lam
        real(dp) :: w, period, best, cen, tot, nq
        n = sector%ndof
        m = n - size(cyc%right)
        nt = size(sol%r, 1)
        w = sol%omega
        period = two_pi/w
        shift = nt*cyc%engine_order/cyc%sectors
        allocate (r(nt, 1), u(nt, 1), p(nt, 1), jr(1, 1, nt), ju(1, 1, nt))
        r(:, 1) = sol%r(:, 1)
        u(:, 1) = sol%v(:, cdof) - cshift(sol%v(:, ndof), -shift)
        call sol%contacts%elements(1)%e%psi_jacobian(sol%rho, r, u, p, jr, ju)
        allocate (jrc(-2*hh:2*hh), juc(-2*hh:2*hh))
        do h = -2*hh, 2*hh
            jrc(h) = sum(jr(1, 1, :)*exp(cmplx(0.0_dp, -two_pi*h*[(i - 1, i=1, nt)]/ &
                                                      real(nt, dp), dp)))/nt
            juc(h) = sum(ju(1, 1, :)*exp(cmplx(0.0_dp, -two_pi*h*[(i - 1, i=1, nt)]/ &
                                                      real(nt, dp), dp)))/nt
        end do
        nblk = 2*m + 1
        ntot = nblk*(2*hh + 1)
        allocate (ts(n, m, -hh:hh), ds(n, -hh:hh), all_mu(0))
        do kk = 1, size(ks)
            k = ks(kk)
            do h = -hh, hh
                e = exp(cmplx(0.0_dp, two_pi*real(k - h*cyc%engine_order, dp)/ &
                              real(cyc%sectors, dp), dp))
                ts(:, :, h) = cyclic_basis(cyc, n, e)
                ds(:, h) = (0.0_dp, 0.0_dp)
                ds(cdof, h) = ds(cdof, h) + 1.0_dp
                ds(ndof, h) = ds(ndof, h) - e
            end do
            allocate (a(ntot, ntot), bm(ntot, ntot))
            a = (0.0_dp, 0.0_dp)
            bm = (0.0_dp, 0.0_dp)
            do h = -hh, hh
                b = (h + hh)*nblk
                t = ts(:, :, h)
                d = ds(:, h)
                ! Y - lambda q = 0
                do i = 1, m
                    a(b + i, b + m + i) = 1.0_dp
                    bm(b + i, b + i) = 1.0_dp
                end do
                ! A q + B Y - T^H conj(D) R = -lambda M Y
                a(b + m + 1:b + 2*m, b + 1:b + m) = matmul(conjg(transpose(t)), &
                    matmul(cmplx(sector%stiffness - (h*w)**2*sector%mass, h*w*sector%damping, &
                                 dp), t))
                a(b + m + 1:b + 2*m, b + m + 1:b + 2*m) = matmul(conjg(transpose(t)), &
                    matmul(cmplx(sector%damping, 2*h*w*sector%mass, dp), t))
                a(b + m + 1:b + 2*m, b + 2*m + 1) = -matmul(conjg(transpose(t)), conjg(d))
                bm(b + m + 1:b + 2*m, b + m + 1:b + 2*m) = -matmul(conjg(transpose(t)), &
                    matmul(cmplx(sector%mass, 0.0_dp, dp), t))
                ! sum_l jr_{h-l} R_l + ju_{h-l} D_l^T T_l (i l w q_l + Y_l) = 0
                do l = -hh, hh
                    c = (l + hh)*nblk
                    a(b + 2*m + 1, c + 2*m + 1) = jrc(h - l)
                    a(b + 2*m + 1, c + 1:c + m) = juc(h - l)*cmplx(0.0_dp, l*w, dp)* &
                                                  matmul(ds(:, l), ts(:, :, l))
                    a(b + 2*m + 1, c + m + 1:c + 2*m) = juc(h - l)*matmul(ds(:, l), ts(:, :, l))
                end do
            end do
            allocate (alpha(ntot), beta(ntot), vr(ntot, ntot), vl(1, 1), work(8*ntot), &
                      rwork(8*ntot))
            call zggev('N', 'V', ntot, a, ntot, bm, ntot, alpha, beta, vl, 1, vr, ntot, work, &
                       size(work), rwork, info)
            best = -huge(1.0_dp)
            do i = 1, ntot
                if (abs(beta(i)) <= 1.0e-12_dp*abs(alpha(i))) cycle
                lam = alpha(i)/beta(i)
                cen = 0.0_dp
                tot = 0.0_dp
                do h = -hh, hh
                    b = (h + hh)*nblk
                    nq = sum(abs(vr(b + 1:b + m, i))**2)
                    cen = cen + h*nq
                    tot = tot + nq
                end do
                if (tot <= 0.0_dp) cycle
                if (abs(cen/tot) > 0.5_dp) cycle
                best = max(best, real(lam, dp))
                all_mu = [all_mu, exp(lam*period)]
            end do
            mu_k(kk) = exp(best*period)
            deallocate (a, bm, alpha, beta, vr, vl, work, rwork)
        end do
    end subroutine hill_sector_max
end program experiment_hill_sector
