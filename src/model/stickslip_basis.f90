!> The truncated Fourier basis and its uniform quadrature.
!>
!> A periodic function of period T = 2 pi / omega is held as its coefficients on the basis
!> {1, cos(h omega t), sin(h omega t) : h in the harmonic set}:
!>     u(t) = c0 + sum_h ( a_h cos(h omega t) + b_h sin(h omega t) ),
!> stored as coef = [c0, a_h1, b_h1, a_h2, b_h2, ...] (c0 only when the set holds h = 0).
!> The set is {0, 1, .., H} or the odd harmonics {1, 3, .., <= H}. Samples are taken at
!> t_k = k T / nt, k = 0 .. nt-1, with nt >= 2H + 1 so that synthesis followed by analysis is
!> the identity and the quadrature of any product of two basis functions is exact.
!> Analysis (projection) and synthesis are real FFTs (stickslip_fft).
module stickslip_basis
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_fft, only: fft_plan_t
    implicit none
    private
    public :: basis_t, new_basis

    !> Harmonic set, sample count and the FFT plans. Read-only once built, so one basis may be
    !> shared by several threads; the complex work array is always the caller's.
    type :: basis_t
        !> Highest harmonic H.
        integer :: harmonics = 0
        !> Odd harmonics only (no constant term).
        logical :: odd_only = .false.
        !> Samples per period nt.
        integer :: nt = 0
        !> Number of harmonics h > 0 in the set.
        integer :: nharm = 0
        !> Whether the constant term is in the basis.
        logical :: has_zero = .false.
        !> Number of basis functions (length of a coefficient vector).
        integer :: nb = 0
        !> The harmonics h > 0 of the set, ascending.
        integer, allocatable :: harm(:)
        !> Position of the constant term in a coefficient vector (0 when absent).
        integer :: i0 = 0
        !> Position of cos(h_i omega t) for the i-th harmonic of `harm`; sin is at icos(i) + 1.
        integer, allocatable :: icos(:)
        !> The FFT plans of length nt.
        type(fft_plan_t) :: fft
    contains
        procedure :: synthesize
        procedure :: analyse
        procedure :: derivative
        procedure :: stick_product
        procedure :: harmonic_of
        procedure :: destroy => basis_destroy
    end type basis_t

contains

    !> Build the basis of highest harmonic `harmonics` (all, or odd only) sampled `samples`
    !> times per period. Errors (stat input): harmonics < 0, odd_only with harmonics < 1,
    !> samples < 2*harmonics + 1.
    subroutine new_basis(self, harmonics, odd_only, samples, error)
        !> The basis to build.
        type(basis_t), intent(out) :: self
        !> Highest harmonic H.
        integer, intent(in) :: harmonics
        !> Only odd harmonics 1, 3, .., <= H.
        logical, intent(in) :: odd_only
        !> Samples per period nt (quadrature points).
        integer, intent(in) :: samples
        !> Set on bad sizes or FFT planning failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: h, i, step, first
        character(len=160) :: buf

        if (harmonics < 0 .or. (odd_only .and. harmonics < 1)) then
            write (buf, '(a,i0,a)') "harmonics = ", harmonics, &
                ": must be >= 0 (>= 1 with odd_only)"
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        if (samples < 2*harmonics + 1) then
            write (buf, '(a,i0,a,i0,a,i0,a)') "samples = ", samples, &
                ": too few samples for the harmonics: need samples >= 2*harmonics+1 = ", &
                2*harmonics + 1, " (harmonics = ", harmonics, ")"
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        self%harmonics = harmonics
        self%odd_only = odd_only
        self%nt = samples
        self%has_zero = .not. odd_only
        if (odd_only) then
            first = 1
            step = 2
        else
            first = 1
            step = 1
        end if
        self%harm = [(h, h=first, harmonics, step)]
        self%nharm = size(self%harm)
        allocate (self%icos(self%nharm))
        if (self%has_zero) then
            self%i0 = 1
            self%icos = [(2*i, i=1, self%nharm)]
        else
            self%i0 = 0
            self%icos = [(2*i - 1, i=1, self%nharm)]
        end if
        self%nb = 2*self%nharm + merge(1, 0, self%has_zero)
        call self%fft%init(samples, error)
    end subroutine new_basis

    !> Harmonic index of basis function k (0 for the constant).
    elemental integer function harmonic_of(self, k) result(h)
        !> The basis.
        class(basis_t), intent(in) :: self
        !> Position in a coefficient vector.
        integer, intent(in) :: k
        if (k == self%i0) then
            h = 0
        else if (self%has_zero) then
            h = self%harm(k/2)
        else
            h = self%harm((k + 1)/2)
        end if
    end function harmonic_of

    !> Samples u(t_k), k = 0..nt-1, of the function with coefficients `coef`.
    subroutine synthesize(self, coef, u, cwork)
        !> The basis.
        class(basis_t), intent(in) :: self
        !> Coefficients (length nb).
        real(dp), intent(in) :: coef(:)
        !> Samples (length nt).
        real(dp), intent(out) :: u(:)
        !> Work array, length nt/2 + 1.
        complex(dp), intent(inout) :: cwork(:)
        integer :: i, k
        cwork = (0.0_dp, 0.0_dp)
        if (self%has_zero) cwork(1) = cmplx(coef(self%i0), 0.0_dp, dp)
        do i = 1, self%nharm
            k = self%icos(i)
            cwork(self%harm(i) + 1) = 0.5_dp*cmplx(coef(k), -coef(k + 1), dp)
        end do
        call self%fft%inverse(cwork, u)
    end subroutine synthesize

    !> Projection (Galerkin analysis) of samples u(t_k) onto the basis: coef = P u, the
    !> uniform-quadrature Fourier coefficients. Exact for trigonometric polynomials of
    !> degree < nt - H.
    subroutine analyse(self, u, coef, cwork)
        !> The basis.
        class(basis_t), intent(in) :: self
        !> Samples (length nt); not modified.
        real(dp), intent(inout) :: u(:)
        !> Coefficients (length nb).
        real(dp), intent(out) :: coef(:)
        !> Work array, length nt/2 + 1.
        complex(dp), intent(inout) :: cwork(:)
        integer :: i, k
        real(dp) :: scale
        call self%fft%forward(u, cwork)
        scale = 2.0_dp/real(self%nt, dp)
        if (self%has_zero) coef(self%i0) = 0.5_dp*scale*real(cwork(1), dp)
        do i = 1, self%nharm
            k = self%icos(i)
            coef(k) = scale*real(cwork(self%harm(i) + 1), dp)
            coef(k + 1) = -scale*aimag(cwork(self%harm(i) + 1))
        end do
    end subroutine analyse

    !> Coefficients of the time derivative du/dt of the function with coefficients `coef`
    !> at fundamental angular frequency `omega` [rad/s].
    pure subroutine derivative(self, coef, omega, dcoef)
        !> The basis.
        class(basis_t), intent(in) :: self
        !> Coefficients of u.
        real(dp), intent(in) :: coef(:)
        !> Fundamental angular frequency [rad/s].
        real(dp), intent(in) :: omega
        !> Coefficients of du/dt.
        real(dp), intent(out) :: dcoef(:)
        integer :: i, k
        real(dp) :: w
        if (self%has_zero) dcoef(self%i0) = 0.0_dp
        do i = 1, self%nharm
            k = self%icos(i)
            w = self%harm(i)*omega
            dcoef(k) = w*coef(k + 1)
            dcoef(k + 1) = -w*coef(k)
        end do
    end subroutine derivative

    !> The matrix A = P diag(s) Q (nb x nb) of the product with a sampled function s(t_k):
    !> A coef = analyse(s * synthesize(coef)). Built from the spectrum of s alone,
    !> spec(j+1) = (1/nt) sum_k s_k exp(-2 pi i j k / nt), j = 0..nt/2, in O(nb^2) work:
    !> products of trigonometric functions couple harmonics h - q and h + q (aliased mod nt,
    !> exactly as the quadrature does).
    pure subroutine stick_product(self, spec, a)
        !> The basis.
        class(basis_t), intent(in) :: self
        !> Normalized half spectrum of s, length nt/2 + 1.
        complex(dp), intent(in) :: spec(:)
        !> The product matrix, nb x nb.
        real(dp), intent(out) :: a(:, :)
        integer :: iq, ih, q, h, kq, kh
        complex(dp) :: gc, gs
        complex(dp), parameter :: half_over_i = (0.0_dp, -0.5_dp)

        ! column: constant
        if (self%has_zero) then
            a(self%i0, self%i0) = real(spec(1), dp)
            do ih = 1, self%nharm
                h = self%harm(ih)
                kh = self%icos(ih)
                gc = s_at(h)
                a(kh, self%i0) = 2.0_dp*real(gc, dp)
                a(kh + 1, self%i0) = -2.0_dp*aimag(gc)
            end do
        end if
        do iq = 1, self%nharm
            q = self%harm(iq)
            kq = self%icos(iq)
            if (self%has_zero) then
                ! row constant: g_0 for cos q is Re S_q, for sin q is -Im S_q
                gc = s_at(q)
                a(self%i0, kq) = real(gc, dp)
                a(self%i0, kq + 1) = -aimag(gc)
            end if
            do ih = 1, self%nharm
                h = self%harm(ih)
                kh = self%icos(ih)
                gc = 0.5_dp*(s_at(h - q) + s_at(h + q))
                gs = half_over_i*(s_at(h - q) - s_at(h + q))
                a(kh, kq) = 2.0_dp*real(gc, dp)
                a(kh + 1, kq) = -2.0_dp*aimag(gc)
                a(kh, kq + 1) = 2.0_dp*real(gs, dp)
                a(kh + 1, kq + 1) = -2.0_dp*aimag(gs)
            end do
        end do

    contains

        pure complex(dp) function s_at(n)
            integer, intent(in) :: n
            integer :: m
            m = modulo(n, self%nt)
            if (m <= self%nt/2) then
                s_at = spec(m + 1)
            else
                s_at = conjg(spec(self%nt - m + 1))
            end if
        end function s_at
    end subroutine stick_product

    !> Release the FFT plans.
    subroutine basis_destroy(self)
        !> The basis.
        class(basis_t), intent(inout) :: self
        call self%fft%destroy()
    end subroutine basis_destroy
end module stickslip_basis
