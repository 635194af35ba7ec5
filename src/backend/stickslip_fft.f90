!> Real discrete Fourier transforms of one fixed length on FFTW3 (system libfftw3).
!> Only this module talks to FFTW.
!>
!> Plans. FFTW_ESTIMATE plans of the aligned kind (no FFTW_UNALIGNED: SIMD codelets, about
!> 2.4x faster per transform than unaligned plans on the benchmark machine), made once per
!> length and process and kept in a small cache, so that every basis of the same length
!> shares one pair of plans (planning a 1024-point pair costs about 1.5 ms, a transform about
!> 1 us). Execution uses FFTW's new-array interface, which is thread-safe, so one plan can be
!> used by several OpenMP threads at once, each on its own arrays. FFTW requires the new
!> arrays to have the alignment of the planning arrays (fftw_malloc'd: fftw_alignment_of = 0);
!> arrays that do not (an array section starting at an odd element, or a strided section)
!> go through aligned temporaries, so any array works.
!>
!> The plan cache is the one piece of global mutable state here, and it is acceptable
!> because: FFTW's planner is itself global and not thread-safe, so creating plans must be
!> serialized anyway; every lookup and insertion runs inside the named critical section
!> `stickslip_fftw_planner` (the only section that calls the planner); entries are
!> immutable once inserted (a length and two plans), and cached plans are never destroyed
!> while the process runs, so the plan pointers an fft_plan_t copied out of the cache stay
!> valid without further locking; its size is bounded (fft_cache_capacity lengths; beyond
!> that a plan belongs to its fft_plan_t and is destroyed with it, as before the cache).
!> In a build without OpenMP the critical section is a no-op and the library is serial-only
!> (README, "Threads").
module stickslip_fft
    use, intrinsic :: iso_c_binding, only: c_ptr, c_int, c_double, c_double_complex, &
        c_null_ptr, c_associated, c_size_t, c_loc, c_f_pointer
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    implicit none
    private
    public :: fft_plan_t, fft_cached_lengths, fft_cache_capacity

    integer(c_int), parameter :: fftw_estimate = 64

    !> Most distinct transform lengths whose plans are cached per process.
    integer, parameter :: fft_cache_capacity = 64

    !> A pair of real-to-complex / complex-to-real plans of length `nt`.
    !> Unnormalized, as FFTW: forward gives c_j = sum_k x_k exp(-2 pi i j k / nt),
    !> j = 0..nt/2; inverse gives x_k = sum_j c_j exp(2 pi i j k / nt) over the full
    !> Hermitian spectrum. Read-only once initialized: one object (or copies of it) may be
    !> used by several threads at once. The plans are normally the process-wide cached ones
    !> (copies and destroy are then harmless); only past fft_cache_capacity lengths does an
    !> object own its plans, and then copies share them: destroy only one of them.
    type :: fft_plan_t
        !> Transform length.
        integer :: nt = 0
        type(c_ptr), private :: r2c = c_null_ptr
        type(c_ptr), private :: c2r = c_null_ptr
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
        type(c_ptr) :: r2c = c_null_ptr
        type(c_ptr) :: c2r = c_null_ptr
    end type cache_entry_t

    !> The process-wide plan cache; read and written only inside the critical section
    !> stickslip_fftw_planner (see the module header for why this state is acceptable).
    type(cache_entry_t), save :: cache(fft_cache_capacity)
    !> Entries of `cache` in use.
    integer, save :: ncached = 0

    interface
        function fftw_plan_dft_r2c_1d(n, in, out, flags) bind(c, name='fftw_plan_dft_r2c_1d')
            import :: c_ptr, c_int, c_double, c_double_complex
            integer(c_int), value :: n
            real(c_double), intent(inout) :: in(*)
            complex(c_double_complex), intent(inout) :: out(*)
            integer(c_int), value :: flags
            type(c_ptr) :: fftw_plan_dft_r2c_1d
        end function fftw_plan_dft_r2c_1d

        function fftw_plan_dft_c2r_1d(n, in, out, flags) bind(c, name='fftw_plan_dft_c2r_1d')
            import :: c_ptr, c_int, c_double, c_double_complex
            integer(c_int), value :: n
            complex(c_double_complex), intent(inout) :: in(*)
            real(c_double), intent(inout) :: out(*)
            integer(c_int), value :: flags
            type(c_ptr) :: fftw_plan_dft_c2r_1d
        end function fftw_plan_dft_c2r_1d

        subroutine fftw_execute_dft_r2c(p, in, out) bind(c, name='fftw_execute_dft_r2c')
            import :: c_ptr, c_double, c_double_complex
            type(c_ptr), value :: p
            real(c_double), intent(inout) :: in(*)
            complex(c_double_complex), intent(out) :: out(*)
        end subroutine fftw_execute_dft_r2c

        subroutine fftw_execute_dft_c2r(p, in, out) bind(c, name='fftw_execute_dft_c2r')
            import :: c_ptr, c_double, c_double_complex
            type(c_ptr), value :: p
            complex(c_double_complex), intent(inout) :: in(*)
            real(c_double), intent(out) :: out(*)
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
        !> The plan pair.
        class(fft_plan_t), intent(inout) :: self
        !> Transform length.
        integer, intent(in) :: nt
        !> Set when FFTW cannot plan.
        type(error_type), allocatable, intent(out) :: error
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
                self%r2c = cache(k)%r2c
                self%c2r = cache(k)%c2r
                found = .true.
                exit
            end if
        end do
        if (.not. found) then
            call make_plans(nt, self%r2c, self%c2r)
            if (c_associated(self%r2c) .and. c_associated(self%c2r)) then
                if (ncached < fft_cache_capacity) then
                    ncached = ncached + 1
                    cache(ncached) = cache_entry_t(nt, self%r2c, self%c2r)
                else
                    self%owned = .true.
                end if
            end if
        end if
        !$omp end critical (stickslip_fftw_planner)
        if (.not. (c_associated(self%r2c) .and. c_associated(self%c2r))) then
            call fatal_error(error, "fft: FFTW could not create a plan", stickslip_stat%internal)
            call self%destroy()
            return
        end if
        self%nt = nt
    end subroutine fft_init

    !> Plan the pair of length nt on fftw_malloc'd (aligned) arrays; a null pointer when
    !> FFTW cannot. Call only inside the critical section stickslip_fftw_planner.
    subroutine make_plans(nt, r2c, c2r)
        integer, intent(in) :: nt
        type(c_ptr), intent(out) :: r2c, c2r
        type(c_ptr) :: px, pc
        real(c_double), pointer :: x(:)
        complex(c_double_complex), pointer :: c(:)
        r2c = c_null_ptr
        c2r = c_null_ptr
        px = fftw_malloc(int(8, c_size_t)*int(nt, c_size_t))
        pc = fftw_malloc(int(16, c_size_t)*int(nt/2 + 1, c_size_t))
        if (c_associated(px) .and. c_associated(pc)) then
            call c_f_pointer(px, x, [nt])
            call c_f_pointer(pc, c, [nt/2 + 1])
            ! FFTW_ESTIMATE planning does not touch the arrays
            r2c = fftw_plan_dft_r2c_1d(int(nt, c_int), x, c, fftw_estimate)
            c2r = fftw_plan_dft_c2r_1d(int(nt, c_int), c, x, fftw_estimate)
            if (.not. (c_associated(r2c) .and. c_associated(c2r))) then
                if (c_associated(r2c)) call fftw_destroy_plan(r2c)
                if (c_associated(c2r)) call fftw_destroy_plan(c2r)
                r2c = c_null_ptr
                c2r = c_null_ptr
            end if
        end if
        if (c_associated(px)) call fftw_free(px)
        if (c_associated(pc)) call fftw_free(pc)
    end subroutine make_plans

    !> Forward real transform: x(1:nt) -> c(1:nt/2+1) (c(j+1) is the coefficient j).
    !> x is not modified.
    subroutine fft_forward(self, x, c)
        !> The plan pair.
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
            call fftw_execute_dft_r2c(self%r2c, x, c)
        else
            ! the plan's alignment through aligned temporaries
            call aligned_work(nt, px, pc, xt, ct)
            xt = x(1:nt)
            call fftw_execute_dft_r2c(self%r2c, xt, ct)
            c(1:nc) = ct
            call fftw_free(px)
            call fftw_free(pc)
        end if
    end subroutine fft_forward

    !> Inverse real transform (unnormalized): c(1:nt/2+1) -> x(1:nt). c is overwritten.
    subroutine fft_inverse(self, c, x)
        !> The plan pair.
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
            call fftw_execute_dft_c2r(self%c2r, c, x)
        else
            call aligned_work(nt, px, pc, xt, ct)
            ct = c(1:nc)
            call fftw_execute_dft_c2r(self%c2r, ct, xt)
            x(1:nt) = xt
            call fftw_free(px)
            call fftw_free(pc)
        end if
    end subroutine fft_inverse

    !> Both arrays contiguous (so FFTW gets them, not a packed copy) with the alignment of
    !> the planning arrays.
    logical function aligned(x, c)
        real(dp), intent(in), target :: x(:)
        complex(dp), intent(in), target :: c(:)
        aligned = .false.
        if (.not. (is_contiguous(x) .and. is_contiguous(c))) return
        aligned = fftw_alignment_of(c_loc(x(1))) == 0 .and. fftw_alignment_of(c_loc(c(1))) == 0
    end function aligned

    !> fftw_malloc'd work arrays of nt reals and nt/2 + 1 complexes (error stop if memory
    !> is exhausted: an impossible state for arrays the caller already holds twice over).
    subroutine aligned_work(nt, px, pc, xt, ct)
        integer, intent(in) :: nt
        type(c_ptr), intent(out) :: px, pc
        real(c_double), pointer, intent(out) :: xt(:)
        complex(c_double_complex), pointer, intent(out) :: ct(:)
        px = fftw_malloc(int(8, c_size_t)*int(nt, c_size_t))
        pc = fftw_malloc(int(16, c_size_t)*int(nt/2 + 1, c_size_t))
        if (.not. (c_associated(px) .and. c_associated(pc))) &
            error stop "stickslip_fft: out of memory for an aligned work array"
        call c_f_pointer(px, xt, [nt])
        call c_f_pointer(pc, ct, [nt/2 + 1])
    end subroutine aligned_work

    !> Forget the plans (safe to call on an unplanned object). Cached plans stay in the
    !> cache for the next object of that length; plans the object owns are destroyed.
    subroutine fft_destroy(self)
        !> The plan pair.
        class(fft_plan_t), intent(inout) :: self
        if (self%owned) then
            !$omp critical (stickslip_fftw_planner)
            if (c_associated(self%r2c)) call fftw_destroy_plan(self%r2c)
            if (c_associated(self%c2r)) call fftw_destroy_plan(self%c2r)
            !$omp end critical (stickslip_fftw_planner)
        end if
        self%r2c = c_null_ptr
        self%c2r = c_null_ptr
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
