!> Real discrete Fourier transforms of one fixed length on FFTW3 (system libfftw3).
!> Only this module talks to FFTW.
!>
!> How. An even length nt = 2m (every power of two) is transformed as one complex FFT of
!> length m of the samples taken in pairs (x_2k + i x_2k+1) and an O(m) twiddle pass that
!> splits even and odd samples; an odd length by FFTW's real-to-complex plans. Why: FFTW
!> plans a complex transform about 20 times faster than a real one (FFTW_ESTIMATE, 1024
!> points, the benchmark machine: about 50 us for the forward and backward complex plans
!> of 512 points against 1.5 ms for the real pair), and planning dominates a short run,
!> while the transform itself costs about 1.3 us against 0.95 us (the CLI run of the seed
!> case makes about 230 transforms). Plans are of the aligned kind (no FFTW_UNALIGNED:
!> SIMD codelets, 2.4x faster than unaligned plans), made once per length and process and
!> kept in a small cache, so every basis of a length shares one set of plans. Execution
!> uses FFTW's new-array interface, which is thread-safe, so one plan can be used by
!> several OpenMP threads at once, each on its own arrays. FFTW requires the new arrays to
!> have the alignment of the planning arrays (fftw_malloc'd: fftw_alignment_of = 0);
!> arrays that do not (an array section starting at an odd element, or a strided
!> section) go through aligned temporaries, so any array works.
!>
!> The plan cache is the one piece of global mutable state here, and it is acceptable
!> because: FFTW's planner is itself global and not thread-safe, so creating plans must be
!> serialized anyway; every lookup and insertion runs inside the named critical section
!> `stickslip_fftw_planner` (the only section that calls the planner); entries are
!> immutable once inserted (a length, its plans and twiddles), and cached plans are never
!> destroyed while the process runs, so what an fft_plan_t copied out of the cache stays
!> valid without further locking; its size is bounded (fft_cache_capacity lengths; beyond
!> that the plans belong to their fft_plan_t and are destroyed with it, as before the
!> cache). In a build without OpenMP the critical section is a no-op and the library is
!> serial-only (doc/library.md, "Threads").
module stickslip_fft
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: iso_c_binding, only: c_ptr, c_int, c_double, c_double_complex, &
        c_null_ptr, c_associated, c_size_t, c_loc, c_f_pointer
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    implicit none
    private
    public :: fft_plan_t, fft_cached_lengths, fft_cache_capacity, dft_forward, dft_inverse

    integer(c_int), parameter :: fftw_estimate = 64
    integer(c_int), parameter :: fftw_forward = -1, fftw_backward = 1

    !> Most distinct transform lengths whose plans are cached per process.
    integer, parameter :: fft_cache_capacity = 64

    !> The transforms of length `nt`. Unnormalized, as FFTW: forward gives
    !> c_j = sum_k x_k exp(-2 pi i j k / nt), j = 0..nt/2; inverse gives
    !> x_k = sum_j c_j exp(2 pi i j k / nt) over the full Hermitian spectrum (the imaginary
    !> parts of c_0 and, for even nt, c_nt/2 are ignored). Read-only once initialized: one
    !> object (or copies of it) may be used by several threads at once. The plans are
    !> normally the process-wide cached ones (copies and destroy are then harmless); only
    !> past fft_cache_capacity lengths does an object own its plans, and then copies share
    !> them: destroy only one of them.
    type :: fft_plan_t
        !> Transform length.
        integer :: nt = 0
        !> Even nt: complex forward and backward plans of length nt/2; odd nt: FFTW's
        !> real-to-complex and complex-to-real plans of length nt.
        type(c_ptr), private :: fwd = c_null_ptr
        type(c_ptr), private :: bwd = c_null_ptr
        !> Even nt: exp(-2 pi i j / nt), j = 0 .. nt/4.
        complex(dp), allocatable, private :: w(:)
        !> The plans belong to this object (the cache was full), not to the cache.
        logical, private :: owned = .false.
    contains
        procedure :: init => fft_init
        procedure :: forward => fft_forward
        procedure :: inverse => fft_inverse
        procedure :: destroy => fft_destroy
    end type fft_plan_t

    !> One cached length: immutable once inserted.
    type :: cache_entry_t
        integer :: nt = 0
        type(c_ptr) :: fwd = c_null_ptr
        type(c_ptr) :: bwd = c_null_ptr
        complex(dp), allocatable :: w(:)
    end type cache_entry_t

    !> The process-wide plan cache; read and written only inside the critical section
    !> stickslip_fftw_planner (see the module header for why this state is acceptable).
    type(cache_entry_t), save :: cache(fft_cache_capacity)
    !> Entries of `cache` in use.
    integer, save :: ncached = 0

    interface
        function fftw_plan_dft_1d(n, in, out, sign, flags) bind(c, name='fftw_plan_dft_1d')
            import :: c_ptr, c_int
            integer(c_int), value :: n
            type(c_ptr), value :: in, out
            integer(c_int), value :: sign, flags
            type(c_ptr) :: fftw_plan_dft_1d
        end function fftw_plan_dft_1d

        function fftw_plan_dft_r2c_1d(n, in, out, flags) bind(c, name='fftw_plan_dft_r2c_1d')
            import :: c_ptr, c_int
            integer(c_int), value :: n
            type(c_ptr), value :: in, out
            integer(c_int), value :: flags
            type(c_ptr) :: fftw_plan_dft_r2c_1d
        end function fftw_plan_dft_r2c_1d

        function fftw_plan_dft_c2r_1d(n, in, out, flags) bind(c, name='fftw_plan_dft_c2r_1d')
            import :: c_ptr, c_int
            integer(c_int), value :: n
            type(c_ptr), value :: in, out
            integer(c_int), value :: flags
            type(c_ptr) :: fftw_plan_dft_c2r_1d
        end function fftw_plan_dft_c2r_1d

        subroutine fftw_execute_dft(p, in, out) bind(c, name='fftw_execute_dft')
            import :: c_ptr
            type(c_ptr), value :: p, in, out
        end subroutine fftw_execute_dft

        subroutine fftw_execute_dft_r2c(p, in, out) bind(c, name='fftw_execute_dft_r2c')
            import :: c_ptr
            type(c_ptr), value :: p, in, out
        end subroutine fftw_execute_dft_r2c

        subroutine fftw_execute_dft_c2r(p, in, out) bind(c, name='fftw_execute_dft_c2r')
            import :: c_ptr
            type(c_ptr), value :: p, in, out
        end subroutine fftw_execute_dft_c2r

        subroutine fftw_destroy_plan(p) bind(c, name='fftw_destroy_plan')
            import :: c_ptr
            type(c_ptr), value :: p
        end subroutine fftw_destroy_plan

        function fftw_malloc(n) bind(c, name='fftw_malloc')
            import :: c_ptr, c_size_t
            integer(c_size_t), value :: n
            type(c_ptr) :: fftw_malloc
        end function fftw_malloc

        subroutine fftw_free(p) bind(c, name='fftw_free')
            import :: c_ptr
            type(c_ptr), value :: p
        end subroutine fftw_free

        !> FFTW's own alignment class of an array (0 for fftw_malloc'd memory).
        function fftw_alignment_of(p) bind(c, name='fftw_alignment_of')
            import :: c_ptr, c_int
            type(c_ptr), value :: p
            integer(c_int) :: fftw_alignment_of
        end function fftw_alignment_of
    end interface

contains

    !> Set up the transforms of length `nt` (>= 1): the cached plans of that length, planned
    !> on first use in the process. Error (stat input) for nt < 1, (stat internal) if FFTW
    !> returns no plan.
    subroutine fft_init(self, nt, error)
        !> The transforms.
        class(fft_plan_t), intent(inout) :: self
        !> Transform length.
        integer, intent(in) :: nt
        !> Set when FFTW cannot plan.
        type(error_type), allocatable, intent(out) :: error
        type(cache_entry_t) :: made
        integer :: k
        logical :: found
        call self%destroy()
        if (nt < 1) then
            call fatal_error(error, "fft: length must be >= 1", stickslip_stat%input)
            return
        end if
        found = .false.
        !$omp critical (stickslip_fftw_planner)
        do k = 1, ncached
            if (cache(k)%nt == nt) then
                self%fwd = cache(k)%fwd
                self%bwd = cache(k)%bwd
                if (allocated(cache(k)%w)) self%w = cache(k)%w
                found = .true.
                exit
            end if
        end do
        if (.not. found) then
            call make_plans(nt, made)
            self%fwd = made%fwd
            self%bwd = made%bwd
            if (allocated(made%w)) self%w = made%w
            if (c_associated(made%fwd) .and. c_associated(made%bwd)) then
                if (ncached < fft_cache_capacity) then
                    ncached = ncached + 1
                    cache(ncached) = made
                else
                    self%owned = .true.
                end if
            end if
        end if
        !$omp end critical (stickslip_fftw_planner)
        if (.not. (c_associated(self%fwd) .and. c_associated(self%bwd))) then
            call fatal_error(error, "fft: FFTW could not create a plan", stickslip_stat%internal)
            call self%destroy()
            return
        end if
        self%nt = nt
    end subroutine fft_init

    !> The plans of length nt, planned on fftw_malloc'd (aligned) arrays (null pointers when
    !> FFTW cannot), and the twiddles of an even length. Call only inside the critical
    !> section stickslip_fftw_planner.
    subroutine make_plans(nt, made)
        integer, intent(in) :: nt
        type(cache_entry_t), intent(out) :: made
        type(c_ptr) :: px, pc
        integer :: m, j
        made%nt = nt
        ! FFTW_ESTIMATE planning does not touch the arrays
        px = fftw_malloc(int(8, c_size_t)*int(2*(nt/2 + 1), c_size_t))
        pc = fftw_malloc(int(16, c_size_t)*int(nt/2 + 1, c_size_t))
        if (c_associated(px) .and. c_associated(pc)) then
            if (mod(nt, 2) == 0) then
                m = nt/2
                made%fwd = fftw_plan_dft_1d(int(m, c_int), px, pc, fftw_forward, fftw_estimate)
                made%bwd = fftw_plan_dft_1d(int(m, c_int), pc, px, fftw_backward, fftw_estimate)
                allocate (made%w(0:m/2))
                do j = 0, m/2
                    made%w(j) = cmplx(cos(two_pi*real(j, dp)/real(nt, dp)), &
                                      -sin(two_pi*real(j, dp)/real(nt, dp)), dp)
                end do
            else
                made%fwd = fftw_plan_dft_r2c_1d(int(nt, c_int), px, pc, fftw_estimate)
                made%bwd = fftw_plan_dft_c2r_1d(int(nt, c_int), pc, px, fftw_estimate)
            end if
            if (.not. (c_associated(made%fwd) .and. c_associated(made%bwd))) then
                if (c_associated(made%fwd)) call fftw_destroy_plan(made%fwd)
                if (c_associated(made%bwd)) call fftw_destroy_plan(made%bwd)
                made%fwd = c_null_ptr
                made%bwd = c_null_ptr
            end if
        end if
        if (c_associated(px)) call fftw_free(px)
        if (c_associated(pc)) call fftw_free(pc)
    end subroutine make_plans

    !> Forward real transform: x(1:nt) -> c(1:nt/2+1) (c(j+1) is the coefficient j).
    !> x is not modified.
    subroutine fft_forward(self, x, c)
        !> The transforms.
        class(fft_plan_t), intent(in) :: self
        !> Real samples, length nt.
        real(dp), intent(inout), target :: x(:)
        !> Spectrum, length nt/2 + 1.
        complex(dp), intent(out), target :: c(:)
        type(c_ptr) :: px, pc
        real(c_double), pointer :: xt(:)
        complex(c_double_complex), pointer :: ct(:)
        integer :: nt, nc
        nt = self%nt
        nc = nt/2 + 1
        if (aligned(x, c)) then
            call execute_forward(self, c_loc(x(1)), c_loc(c(1)))
            if (mod(nt, 2) == 0) call split_spectrum(self%w, c(1:nc))
        else
            ! the plans' alignment through aligned temporaries
            call aligned_work(nt, px, pc, xt, ct)
            if (.not. (c_associated(px) .and. c_associated(pc))) then
                ! no memory for them (cannot happen in practice): the same transform by sums
                call free_work(px, pc)
                call dft_forward(x(1:nt), c(1:nc))
                return
            end if
            xt = x(1:nt)
            call execute_forward(self, px, pc)
            if (mod(nt, 2) == 0) call split_spectrum(self%w, ct)
            c(1:nc) = ct
            call free_work(px, pc)
        end if
    end subroutine fft_forward

    !> Inverse real transform (unnormalized): c(1:nt/2+1) -> x(1:nt). c is overwritten.
    subroutine fft_inverse(self, c, x)
        !> The transforms.
        class(fft_plan_t), intent(in) :: self
        !> Half spectrum; destroyed on output.
        complex(dp), intent(inout), target :: c(:)
        !> Real samples, length nt.
        real(dp), intent(out), target :: x(:)
        type(c_ptr) :: px, pc
        real(c_double), pointer :: xt(:)
        complex(c_double_complex), pointer :: ct(:)
        integer :: nt, nc
        nt = self%nt
        nc = nt/2 + 1
        if (aligned(x, c)) then
            if (mod(nt, 2) == 0) call join_spectrum(self%w, c(1:nc))
            call execute_inverse(self, c_loc(c(1)), c_loc(x(1)))
        else
            call aligned_work(nt, px, pc, xt, ct)
            if (.not. (c_associated(px) .and. c_associated(pc))) then
                ! no memory for them (cannot happen in practice): the same transform by sums
                call free_work(px, pc)
                call dft_inverse(c(1:nc), x(1:nt))
                return
            end if
            ct = c(1:nc)
            if (mod(nt, 2) == 0) call join_spectrum(self%w, ct)
            call execute_inverse(self, pc, px)
            x(1:nt) = xt
            call free_work(px, pc)
        end if
    end subroutine fft_inverse

    !> FFTW's part of the forward transform, real samples at px to the spectrum at pc (even
    !> nt: the complex transform Z of length nt/2 into pc(1:nt/2)).
    subroutine execute_forward(self, px, pc)
        type(fft_plan_t), intent(in) :: self
        type(c_ptr), intent(in) :: px, pc
        if (mod(self%nt, 2) == 0) then
            call fftw_execute_dft(self%fwd, px, pc)
        else
            call fftw_execute_dft_r2c(self%fwd, px, pc)
        end if
    end subroutine execute_forward

    !> FFTW's part of the inverse transform, the (joined) spectrum at pc to the samples at px.
    subroutine execute_inverse(self, pc, px)
        type(fft_plan_t), intent(in) :: self
        type(c_ptr), intent(in) :: pc, px
        if (mod(self%nt, 2) == 0) then
            call fftw_execute_dft(self%bwd, pc, px)
        else
            call fftw_execute_dft_c2r(self%bwd, pc, px)
        end if
    end subroutine execute_inverse

    !> Even nt = 2m: c(1:m) holds Z = DFT_m(x_even + i x_odd); on return c(1:m+1) is the
    !> spectrum X_j = E_j + w^j O_j of x, where E_j = (Z_j + conj Z_(m-j))/2 and
    !> O_j = (Z_j - conj Z_(m-j))/(2i) are the transforms of the even and odd samples, and
    !> X_(m-j) = conj(E_j - w^j O_j), w = exp(-2 pi i / nt).
    pure subroutine split_spectrum(w, c)
        complex(dp), intent(in) :: w(0:)
        complex(dp), intent(inout) :: c(0:)
        integer :: m, j
        real(dp) :: zr, zi
        complex(dp) :: a, b, e, o, t
        m = size(c) - 1
        zr = real(c(0), dp)
        zi = aimag(c(0))
        c(0) = cmplx(zr + zi, 0.0_dp, dp)
        c(m) = cmplx(zr - zi, 0.0_dp, dp)
        do j = 1, m/2
            a = c(j)
            b = conjg(c(m - j))
            e = 0.5_dp*(a + b)
            ! o = (a - b)/(2i)
            o = cmplx(0.5_dp*aimag(a - b), -0.5_dp*real(a - b, dp), dp)
            t = w(j)*o
            c(j) = e + t
            c(m - j) = conjg(e - t)
        end do
    end subroutine split_spectrum

    !> The inverse of split_spectrum, times 2: from the half spectrum X in c(1:m+1) (the
    !> imaginary parts of X_0 and X_m ignored), Z_j = (X_j + conj X_(m-j)) +
    !> i conj(w^j) (X_j - conj X_(m-j)) in c(1:m), whose unnormalized inverse transform of
    !> length m is nt (x_2k + i x_2k+1).
    pure subroutine join_spectrum(w, c)
        complex(dp), intent(in) :: w(0:)
        complex(dp), intent(inout) :: c(0:)
        integer :: m, j
        real(dp) :: a0, am
        complex(dp) :: a, b, s, d, t
        m = size(c) - 1
        a0 = real(c(0), dp)
        am = real(c(m), dp)
        c(0) = cmplx(a0 + am, a0 - am, dp)
        do j = 1, m/2
            a = c(j)
            b = conjg(c(m - j))
            s = a + b
            d = a - b
            ! t = i conj(w^j) d
            t = conjg(w(j))*cmplx(-aimag(d), real(d, dp), dp)
            c(j) = s + t
            c(m - j) = conjg(s - t)
        end do
    end subroutine join_spectrum

    !> Both arrays contiguous (so FFTW gets them, not a packed copy) with the alignment of
    !> the planning arrays.
    logical function aligned(x, c)
        real(dp), intent(in), target :: x(:)
        complex(dp), intent(in), target :: c(:)
        aligned = .false.
        if (.not. (is_contiguous(x) .and. is_contiguous(c))) return
        aligned = fftw_alignment_of(c_loc(x(1))) == 0 .and. fftw_alignment_of(c_loc(c(1))) == 0
    end function aligned

    !> fftw_malloc'd work arrays of nt (rounded up to even) reals and nt/2 + 1 complexes
    !> (px or pc null when memory is exhausted: the caller then falls back to naive sums).
    subroutine aligned_work(nt, px, pc, xt, ct)
        integer, intent(in) :: nt
        type(c_ptr), intent(out) :: px, pc
        real(c_double), pointer, intent(out) :: xt(:)
        complex(c_double_complex), pointer, intent(out) :: ct(:)
        px = fftw_malloc(int(8, c_size_t)*int(2*(nt/2 + 1), c_size_t))
        pc = fftw_malloc(int(16, c_size_t)*int(nt/2 + 1, c_size_t))
        nullify (xt, ct)
        if (.not. (c_associated(px) .and. c_associated(pc))) return
        call c_f_pointer(px, xt, [nt])
        call c_f_pointer(pc, ct, [nt/2 + 1])
    end subroutine aligned_work

    !> Free what aligned_work got (either may be null).
    subroutine free_work(px, pc)
        type(c_ptr), intent(inout) :: px, pc
        if (c_associated(px)) call fftw_free(px)
        if (c_associated(pc)) call fftw_free(pc)
        px = c_null_ptr
        pc = c_null_ptr
    end subroutine free_work

    !> c_k = sum_j x_j exp(-2 pi i j k / nt), k = 0 .. nt/2, by direct sums (O(nt^2); the
    !> fallback when no aligned work memory can be had).
    pure subroutine dft_forward(x, c)
        real(dp), intent(in) :: x(:)
        complex(dp), intent(out) :: c(:)
        integer :: j, k, nt
        real(dp) :: a
        nt = size(x)
        do k = 0, size(c) - 1
            c(k + 1) = (0.0_dp, 0.0_dp)
            do j = 0, nt - 1
                a = -two_pi*real(modulo(int(j, int64)*k, int(nt, int64)), dp)/nt
                c(k + 1) = c(k + 1) + x(j + 1)*cmplx(cos(a), sin(a), dp)
            end do
        end do
    end subroutine dft_forward

    !> The unnormalized inverse of dft_forward as FFTW's c2r computes it (the imaginary
    !> parts of c_0 and, nt even, c_nt/2 ignored), by direct sums.
    pure subroutine dft_inverse(c, x)
        complex(dp), intent(in) :: c(:)
        real(dp), intent(out) :: x(:)
        integer :: j, k, nt
        real(dp) :: a
        nt = size(x)
        do j = 0, nt - 1
            x(j + 1) = real(c(1), dp)
            do k = 1, (nt - 1)/2
                a = two_pi*real(modulo(int(j, int64)*k, int(nt, int64)), dp)/nt
                x(j + 1) = x(j + 1) + 2.0_dp*real(c(k + 1)*cmplx(cos(a), sin(a), dp), dp)
            end do
            if (mod(nt, 2) == 0) x(j + 1) = x(j + 1) + real(c(nt/2 + 1), dp)*(1 - 2*mod(j, 2))
        end do
    end subroutine dft_inverse

    !> Forget the plans (safe to call on an unplanned object). Cached plans stay in the
    !> cache for the next object of that length; plans the object owns are destroyed.
    subroutine fft_destroy(self)
        !> The transforms.
        class(fft_plan_t), intent(inout) :: self
        if (self%owned) then
            !$omp critical (stickslip_fftw_planner)
            if (c_associated(self%fwd)) call fftw_destroy_plan(self%fwd)
            if (c_associated(self%bwd)) call fftw_destroy_plan(self%bwd)
            !$omp end critical (stickslip_fftw_planner)
        end if
        self%fwd = c_null_ptr
        self%bwd = c_null_ptr
        if (allocated(self%w)) deallocate (self%w)
        self%owned = .false.
        self%nt = 0
    end subroutine fft_destroy

    !> Number of transform lengths whose plans are cached in this process (at most
    !> fft_cache_capacity).
    integer function fft_cached_lengths() result(n)
        !$omp critical (stickslip_fftw_planner)
        n = ncached
        !$omp end critical (stickslip_fftw_planner)
    end function fft_cached_lengths
end module stickslip_fft
