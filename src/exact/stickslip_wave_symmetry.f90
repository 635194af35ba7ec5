!> The symmetry of a tuned disk's travelling wave, used by the exact flow of the assembled
!> disk (stickslip_cyclic's assemble_disk: the DOFs, contacts, force channels and internal
!> states of N sectors, sector after sector, in the same order within each).
!>
!> Forced in engine order EO, the disk's periodic orbit is a travelling wave: x_s(t) =
!> x_0(t - s EO T / N). With g = gcd(EO, N) (g = N for EO = 0) and u the shift with u EO = g
!> modulo N, it satisfies z(t + T / m) = S z(t), m = N / g, (S z)_s = z_(s - u): the state a
!> m-th of a period later is the state shifted by u sectors. The linearized flow inherits
!> it, Phi(t + T/m, t' + T/m) = S Phi(t, t') S^-1, so the monodromy over a period is
!> S^m G^m with G = S^-1 Phi(t0 + T/m, t0): the exact flow over T / m gives the multipliers
!> of every perturbation of the whole disk (not only those of the wave's symmetry), and
!> the orbit is the fixed point of z0 -> S^-1 z(t0 + T/m). Knows nothing of files.
module stickslip_wave_symmetry
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, contact_velocity_direction, contact_normal_direction, &
        contact_tangent2_direction, force_direction
    implicit none
    private
    public :: wave_symmetry_t, wave_spans, stability_spans, shifted, check_wave_symmetry

    !> A disk's travelling-wave symmetry: N sectors forced in engine order EO.
    type :: wave_symmetry_t
        !> Number of sectors N (0: no symmetry).
        integer :: sectors = 0
        !> Engine order of the forcing (>= 0).
        integer :: engine_order = 0
    end type wave_symmetry_t

contains

    !> The spans of the symmetry: m = N / gcd(EO, N) spans per period and the sector shift u
    !> (0 <= u < N) with z(t + T / m) = S z(t), (S z)_s = z_(s - u). No symmetry (N < 2):
    !> m = 1, u = 0. No errors.
    pure subroutine wave_spans(sym, m, u)
        !> The symmetry.
        type(wave_symmetry_t), intent(in) :: sym
        !> Spans per period, sector shift per span.
        integer, intent(out) :: m, u
        integer :: n, eo, g, a, b, t
        m = 1
        u = 0
        n = sym%sectors
        if (n < 2) return
        eo = modulo(sym%engine_order, n)
        if (eo == 0) return
        ! g = gcd(eo, n)
        a = n
        b = eo
        do while (b /= 0)
            t = modulo(a, b)
            a = b
            b = t
        end do
        g = a
        m = n/g
        do u = 1, n - 1
            if (modulo(u*eo, n) == g) exit
        end do
    end subroutine wave_spans

    !> The spans per period of the disk's exact flow in a stability with this symmetry
    !> (periodic_stability): m of wave_spans when it divides the `samples` of the weighted
    !> residual the orbit is shot from (its grid then holds whole spans), else 1 (the whole
    !> period). No errors.
    pure integer function stability_spans(sym, samples) result(m)
        !> The symmetry.
        type(wave_symmetry_t), intent(in) :: sym
        !> Samples of a period of the start.
        integer, intent(in) :: samples
        integer :: u
        call wave_spans(sym, m, u)
        if (samples < 1) then
            m = 1
        else if (modulo(samples, m) /= 0) then
            m = 1
        end if
    end function stability_spans

    !> S^k v for a vector of `nsec` equal blocks: block s of the result is block s - k
    !> (modulo nsec) of v. No errors (size(v) a multiple of nsec, by the caller's contract).
    pure function shifted(v, nsec, k) result(w)
        !> The vector.
        real(dp), intent(in) :: v(:)
        !> Number of blocks, shift.
        integer, intent(in) :: nsec, k
        real(dp) :: w(size(v))
        integer :: b, s, t
        b = size(v)/nsec
        do s = 0, nsec - 1
            t = modulo(s - k, nsec)
            w(s*b + 1:s*b + b) = v(t*b + 1:t*b + b)
        end do
    end function shifted

    !> Check that `model` has the symmetry `sym` of a disk assembled from a sector: its DOFs
    !> and contacts N equal blocks, M, K and C unchanged by a shift of one sector, contact
    !> j + n_c of sector s + 1 the shift of contact j of sector s (every direction, mu and
    !> normal load), and the forcing terms in N blocks, each the one before shifted by a
    !> sector with its phase lagging by h 2 pi EO / N. Tolerance 1e-12 of each quantity's
    !> largest entry. Errors (stat input): sizes that do not split into N sectors, dense
    !> matrices missing, or the first quantity that breaks the symmetry, named.
    subroutine check_wave_symmetry(model, sym, error)
        !> The disk.
        type(model_t), intent(in) :: model
        !> Its symmetry.
        type(wave_symmetry_t), intent(in) :: sym
        !> Set when the model does not have it.
        type(error_type), allocatable, intent(out) :: error
        integer :: n, nsec, nc, ncs, nf, nfs, s, j, c, c1
        real(dp) :: scale, dphase
        real(dp), parameter :: tol = 1.0e-12_dp
        nsec = sym%sectors
        n = model%ndof
        nc = model%ncontact()
        nf = model%nforce()
        if (nsec < 2 .or. sym%engine_order < 0) then
            call fail("N = "//itoa(nsec)//", EO = "//itoa(sym%engine_order)// &
                      ": a disk needs N >= 2 sectors and EO >= 0")
            return
        end if
        if (modulo(n, nsec) /= 0 .or. modulo(nc, nsec) /= 0 .or. modulo(nf, nsec) /= 0) then
            call fail(itoa(n)//" DOFs, "//itoa(nc)//" contacts and "//itoa(nf)// &
                      " forcing terms do not split into "//itoa(nsec)//" sectors")
            return
        end if
        if (.not. (allocated(model%mass) .and. allocated(model%stiffness))) then
            call fail("the check needs the dense mass and stiffness matrices")
            return
        end if
        if (.not. invariant(model%mass)) then
            call fail("the mass matrix changes under a shift of one sector")
            return
        end if
        if (.not. invariant(model%stiffness)) then
            call fail("the stiffness matrix changes under a shift of one sector")
            return
        end if
        if (allocated(model%damping)) then
            if (.not. invariant(model%damping)) then
                call fail("the damping matrix changes under a shift of one sector")
                return
            end if
        end if
        ncs = nc/nsec
        do c = 1, nc - ncs
            c1 = c + ncs
            if (.not. same(shifted(contact_velocity_direction(model, c), nsec, 1), &
                           contact_velocity_direction(model, c1)) .or. &
                .not. same(shifted(contact_normal_direction(model, c), nsec, 1), &
                           contact_normal_direction(model, c1)) .or. &
                .not. same(shifted(contact_tangent2_direction(model, c), nsec, 1), &
                           contact_tangent2_direction(model, c1))) then
                call fail("contact "//itoa(c1)//" is not contact "//itoa(c)// &
                          " shifted by one sector")
                return
            end if
            if (model%mu(c1) /= model%mu(c) .or. &
                model%normal_load(c1) /= model%normal_load(c)) then
                call fail("contact "//itoa(c1)//" has another mu or normal load than "// &
                          "contact "//itoa(c))
                return
            end if
        end do
        nfs = nf/nsec
        do s = 0, nsec - 2
            do j = 1, nfs
                c = s*nfs + j
                c1 = c + nfs
                dphase = model%force_phase(c1) - model%force_phase(c) + &
                         two_pi*real(model%force_harmonic(c)*sym%engine_order, dp)/ &
                         real(nsec, dp)
                dphase = modulo(dphase + 0.5_dp*two_pi, two_pi) - 0.5_dp*two_pi
                scale = max(abs(model%force_amplitude(c)), tiny(1.0_dp))
                if (model%force_harmonic(c1) /= model%force_harmonic(c) .or. &
                    abs(model%force_amplitude(c1) - model%force_amplitude(c)) > tol*scale .or. &
                    abs(dphase) > 1.0e-9_dp .or. &
                    .not. same(shifted(force_direction(model, c), nsec, 1), &
                               force_direction(model, c1))) then
                    call fail("forcing term "//itoa(c1)//" is not term "//itoa(c)// &
                              " shifted by one sector in engine order "// &
                              itoa(sym%engine_order))
                    return
                end if
            end do
        end do

    contains

        subroutine fail(why)
            character(len=*), intent(in) :: why
            call fatal_error(error, "wave symmetry: "//why, stickslip_stat%input)
        end subroutine fail

        !> a(S i, S j) = a(i, j) for a shift of one sector.
        logical function invariant(a)
            real(dp), intent(in) :: a(:, :)
            integer :: b, i, k, ii, kk
            b = n/nsec
            scale = max(maxval(abs(a)), tiny(1.0_dp))
            invariant = .true.
            do k = 1, n
                kk = modulo(k - 1 + b, n) + 1
                do i = 1, n
                    ii = modulo(i - 1 + b, n) + 1
                    if (abs(a(ii, kk) - a(i, k)) > tol*scale) then
                        invariant = .false.
                        return
                    end if
                end do
            end do
        end function invariant

        logical function same(p, q)
            real(dp), intent(in) :: p(:), q(:)
            same = maxval(abs(p - q)) <= tol*max(maxval(abs(p)), maxval(abs(q)), tiny(1.0_dp))
        end function same
    end subroutine check_wave_symmetry
end module stickslip_wave_symmetry
