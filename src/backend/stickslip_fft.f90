!> Real discrete Fourier transforms of one fixed length on FFTW3 (system libfftw3).
!> Only this module talks to FFTW. Plans are created once (FFTW_ESTIMATE, FFTW_UNALIGNED) and
!> executed with the new-array interface, so one plan can be shared by several OpenMP threads
!> that each own their arrays (FFTW manual, "Thread safety": only execution is thread-safe;
!> plan creation and destruction are serialized here in a named critical section).
module stickslip_fft
    use, intrinsic :: iso_c_binding, only: c_ptr, c_int, c_double, c_double_complex, &
        c_null_ptr, c_associated
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    implicit none
    private
    public :: fft_plan_t

    integer(c_int), parameter :: fftw_estimate = 64
    integer(c_int), parameter :: fftw_unaligned = 2

    !> A pair of real-to-complex / complex-to-real plans of length `nt`.
    !> Unnormalized, as FFTW: forward gives c_j = sum_k x_k exp(-2 pi i j k / nt),
    !> j = 0..nt/2; inverse gives x_k = sum_j c_j exp(2 pi i j k / nt) over the full
    !> Hermitian spectrum. Copies of a plan share the FFTW plans: destroy only one of them.
    type :: fft_plan_t
        !> Transform length.
        integer :: nt = 0
        type(c_ptr), private :: r2c = c_null_ptr
        type(c_ptr), private :: c2r = c_null_ptr
    contains
        procedure :: init => fft_init
        procedure :: forward => fft_forward
        procedure :: inverse => fft_inverse
        procedure :: destroy => fft_destroy
    end type fft_plan_t

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
    end interface

contains

    !> Create the plans for length `nt` (>= 1). Error (stat internal) if FFTW returns no plan.
    subroutine fft_init(self, nt, error)
        !> The plan pair.
        class(fft_plan_t), intent(inout) :: self
        !> Transform length.
        integer, intent(in) :: nt
        !> Set when FFTW cannot plan.
        type(error_type), allocatable, intent(out) :: error
        real(c_double), allocatable :: x(:)
        complex(c_double_complex), allocatable :: c(:)
        call self%destroy()
        if (nt < 1) then
            call fatal_error(error, "fft: length must be >= 1", stickslip_stat%input)
            return
        end if
        allocate (x(nt), c(nt/2 + 1))
        x = 0.0_dp
        c = (0.0_dp, 0.0_dp)
        !$omp critical (stickslip_fftw_planner)
        self%r2c = fftw_plan_dft_r2c_1d(int(nt, c_int), x, c, ior(fftw_estimate, fftw_unaligned))
        self%c2r = fftw_plan_dft_c2r_1d(int(nt, c_int), c, x, ior(fftw_estimate, fftw_unaligned))
        !$omp end critical (stickslip_fftw_planner)
        if (.not. (c_associated(self%r2c) .and. c_associated(self%c2r))) then
            call fatal_error(error, "fft: FFTW could not create a plan", stickslip_stat%internal)
            return
        end if
        self%nt = nt
    end subroutine fft_init

    !> Forward real transform: x(1:nt) -> c(1:nt/2+1) (c(j+1) is the coefficient j).
    !> x is not modified.
    subroutine fft_forward(self, x, c)
        !> The plan pair.
        class(fft_plan_t), intent(in) :: self
        !> Real samples, length nt.
        real(dp), intent(inout) :: x(:)
        !> Spectrum, length nt/2 + 1.
        complex(dp), intent(out) :: c(:)
        call fftw_execute_dft_r2c(self%r2c, x, c)
    end subroutine fft_forward

    !> Inverse real transform (unnormalized): c(1:nt/2+1) -> x(1:nt). c is overwritten.
    subroutine fft_inverse(self, c, x)
        !> The plan pair.
        class(fft_plan_t), intent(in) :: self
        !> Half spectrum; destroyed on output.
        complex(dp), intent(inout) :: c(:)
        !> Real samples, length nt.
        real(dp), intent(out) :: x(:)
        call fftw_execute_dft_c2r(self%c2r, c, x)
    end subroutine fft_inverse

    !> Release the FFTW plans (safe to call on an unplanned object).
    subroutine fft_destroy(self)
        !> The plan pair.
        class(fft_plan_t), intent(inout) :: self
        !$omp critical (stickslip_fftw_planner)
        if (c_associated(self%r2c)) call fftw_destroy_plan(self%r2c)
        if (c_associated(self%c2r)) call fftw_destroy_plan(self%c2r)
        !$omp end critical (stickslip_fftw_planner)
        self%r2c = c_null_ptr
        self%c2r = c_null_ptr
        self%nt = 0
    end subroutine fft_destroy
end module stickslip_fft
