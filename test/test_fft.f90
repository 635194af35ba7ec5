!> stickslip_fft against a naive DFT (the definition, summed directly) for even, odd, prime
!> and power-of-two lengths: forward, inverse, the unnormalized round trip, a shared plan
!> used for several arrays, destroy and re-init, and the refused length; arrays whose
!> alignment differs from the planning arrays' (sections starting at an odd element) give
!> the same transforms; one cached plan pair per length.
module test_fft
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_fft, only: fft_plan_t, fft_cached_lengths, fft_cache_capacity, &
        dft_forward, dft_inverse
    use testing, only: test_counter_t, check, check_close, check_error
    implicit none
    private
    public :: run_fft_tests

contains

    subroutine run_fft_tests(t)
        type(test_counter_t), intent(inout) :: t
        integer :: k
        integer, parameter :: lengths(9) = [1, 2, 6, 7, 16, 31, 100, 1024, 4096]
        do k = 1, size(lengths)
            call test_length(t, lengths(k))
        end do
        call test_plan_reuse(t)
        call test_misaligned(t, 16)
        call test_misaligned(t, 15)
        call test_cache(t)
        call test_concurrent(t)
        call test_bad_length(t)
    end subroutine run_fft_tests

    !> Forward and inverse of random data of length nt against the naive sums.
    subroutine test_length(t, nt)
        type(test_counter_t), intent(inout) :: t
        integer, intent(in) :: nt
        type(fft_plan_t) :: p
        type(error_type), allocatable :: error
        real(dp) :: x(nt), x0(nt), y(nt), yre(nt), yd(nt)
        complex(dp) :: c(nt/2 + 1), ref(nt/2 + 1), full(nt), cin(nt/2 + 1), cd(nt/2 + 1)
        real(dp) :: ur(nt/2 + 1), ui(nt/2 + 1)
        character(len=16) :: tag
        integer :: j, k
        write (tag, '("nt = ",i0)') nt
        call p%init(nt, error)
        call check_error(t, error, "fft: init "//trim(tag), .false.)
        if (allocated(error)) return
        call random_number(x)
        x = x - 0.5_dp
        x0 = x
        call p%forward(x, c)
        do j = 0, nt/2
            ref(j + 1) = sum([(x0(k + 1)*exp(cmplx(0.0_dp, -two_pi*real(mod(j*k, nt), dp) &
                                                   /real(nt, dp), dp)), k=0, nt - 1)])
        end do
        call check_close(t, [real(c), aimag(c)], [real(ref), aimag(ref)], &
                         "fft: forward = naive DFT, "//trim(tag), rtol=0.0_dp, atol=1.0e-13_dp*nt)
        call check(t, all(x == x0), "fft: forward leaves its input, "//trim(tag))
        ! inverse of a Hermitian half spectrum (imaginary parts of c_0 and c_{nt/2} ignored)
        call random_number(ur)
        call random_number(ui)
        cin = cmplx(ur - 0.5_dp, ui - 0.5_dp, dp)
        cin(1) = cmplx(real(cin(1)), 0.0_dp, dp)
        if (mod(nt, 2) == 0) cin(nt/2 + 1) = cmplx(real(cin(nt/2 + 1)), 0.0_dp, dp)
        full(1:nt/2 + 1) = cin
        do j = nt/2 + 2, nt
            full(j) = conjg(cin(nt - j + 2))
        end do
        do k = 0, nt - 1
            yre(k + 1) = real(sum([(full(j + 1)*exp(cmplx(0.0_dp, two_pi*real(mod(j*k, nt), dp) &
                                                        /real(nt, dp), dp)), j=0, nt - 1)]))
        end do
        ! the library's own direct sums (the fallback without aligned work memory)
        call dft_inverse(cin, yd)
        call check_close(t, yd, yre, "fft: dft_inverse = naive inverse DFT, "//trim(tag), &
                         rtol=0.0_dp, atol=1.0e-13_dp*nt)
        call dft_forward(x0, cd)
        call check_close(t, [real(cd), aimag(cd)], [real(ref), aimag(ref)], &
                         "fft: dft_forward = naive DFT, "//trim(tag), rtol=0.0_dp, &
                         atol=1.0e-13_dp*nt)
        call p%inverse(cin, y)
        call check_close(t, y, yre, "fft: inverse = naive inverse DFT, "//trim(tag), rtol=0.0_dp, &
                         atol=1.0e-13_dp*nt)
        ! round trip: inverse(forward(x)) = nt x
        call p%forward(x, c)
        call p%inverse(c, y)
        call check_close(t, y/real(nt, dp), x0, "fft: round trip gives nt x, "//trim(tag), &
                         rtol=0.0_dp, atol=1.0e-14_dp*nt)
        call p%destroy()
        call check(t, p%nt == 0, "fft: destroy resets the length, "//trim(tag))
    end subroutine test_length

    !> One plan, several arrays (the new-array interface), and a plan re-initialized to
    !> another length.
    subroutine test_plan_reuse(t)
        type(test_counter_t), intent(inout) :: t
        type(fft_plan_t) :: p
        type(error_type), allocatable :: error
        real(dp) :: a(12), b(12), c5(5)
        complex(dp) :: ca(7), cb(7), cc(3)
        integer :: k
        call p%init(12, error)
        call check_error(t, error, "fft: init 12", .false.)
        if (allocated(error)) return
        a = [(real(k, dp), k=1, 12)]
        b = 2.0_dp*a
        call p%forward(a, ca)
        call p%forward(b, cb)
        call check_close(t, [real(cb), aimag(cb)], 2.0_dp*[real(ca), aimag(ca)], &
                         "fft: one plan, two arrays (linearity)", rtol=0.0_dp, atol=1.0e-12_dp)
        call check_close(t, real(ca(1)), 78.0_dp, "fft: c_0 is the sum", rtol=1.0e-15_dp)
        call p%init(5, error)
        call check_error(t, error, "fft: re-init to length 5", .false.)
        if (allocated(error)) return
        call check(t, p%nt == 5, "fft: re-init sets the new length")
        c5 = 1.0_dp
        call p%forward(c5, cc)
        call check_close(t, [real(cc), aimag(cc)], [5.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], &
                         "fft: constant of length 5 -> (5, 0, 0)", rtol=0.0_dp, atol=1.0e-14_dp)
        call p%destroy()
        call check(t, p%nt == 0, "fft: destroy resets the plan")
        ! a second destroy of the reset plan finds nothing to free (a crash would end the
        ! run); the plan can be made again afterwards
        call p%destroy()
        call p%init(5, error)
        call check(t, .not. allocated(error) .and. p%nt == 5, &
                   "fft: destroy twice is harmless, init works after it")
        if (.not. allocated(error)) then
            call p%forward(c5, cc)
            call check_close(t, real(cc(1)), 5.0_dp, "fft: the plan made again transforms", &
                             rtol=1.0e-15_dp)
            call p%destroy()
        end if
    end subroutine test_plan_reuse

    !> Arrays starting at an odd element (8 bytes off the planning arrays' alignment) and
    !> aligned arrays give the same transforms (the misaligned ones go through aligned
    !> temporaries), equal to the naive sums.
    subroutine test_misaligned(t, nt)
        type(test_counter_t), intent(inout) :: t
        integer, intent(in) :: nt
        type(fft_plan_t) :: p
        type(error_type), allocatable :: error
        real(dp) :: xa(nt), xbuf(nt + 1), ya(nt), ybuf(nt + 1), xs(2*nt)
        complex(dp) :: ca(nt/2 + 1), cbuf(nt/2 + 2), cin(nt/2 + 1), ref(nt/2 + 1), cs(nt + 2)
        character(len=16) :: tag
        integer :: j, k
        write (tag, '("nt = ",i0)') nt
        call p%init(nt, error)
        call check_error(t, error, "fft: init "//trim(tag), .false.)
        if (allocated(error)) return
        call random_number(xa)
        xbuf(2:nt + 1) = xa
        call p%forward(xa, ca)
        call p%forward(xbuf(2:nt + 1), cbuf(2:nt/2 + 2))
        do j = 0, nt/2
            ref(j + 1) = sum([(xa(k + 1)*exp(cmplx(0.0_dp, -two_pi*real(mod(j*k, nt), dp) &
                                                   /real(nt, dp), dp)), k=0, nt - 1)])
        end do
        call check(t, all(cbuf(2:nt/2 + 2) == ca), &
                   "fft: forward of misaligned arrays = aligned, "//trim(tag))
        call check_close(t, [real(cbuf(2:)), aimag(cbuf(2:))], [real(ref), aimag(ref)], &
                         "fft: misaligned forward = naive DFT, "//trim(tag), rtol=0.0_dp, &
                         atol=1.0e-13_dp*nt)
        call check(t, all(xbuf(2:nt + 1) == xa), "fft: misaligned forward leaves its input, "// &
                   trim(tag))
        xs = 0.0_dp
        xs(1:2*nt:2) = xa
        call p%forward(xs(1:2*nt:2), cs(1:2*(nt/2) + 1:2))
        call check(t, all(cs(1:2*(nt/2) + 1:2) == ca), "fft: forward of strided arrays = contiguous, "// &
                   trim(tag))
        cin = ca
        cbuf(2:nt/2 + 2) = ca
        call p%inverse(cin, ya)
        call p%inverse(cbuf(2:nt/2 + 2), ybuf(2:nt + 1))
        call check(t, all(ybuf(2:nt + 1) == ya), &
                   "fft: inverse of misaligned arrays = aligned, "//trim(tag))
        call check_close(t, ybuf(2:nt + 1)/real(nt, dp), xa, &
                         "fft: misaligned round trip gives nt x, "//trim(tag), rtol=0.0_dp, &
                         atol=1.0e-14_dp*nt)
        call p%destroy()
    end subroutine test_misaligned

    !> One plan pair per length and process: a second object of a length already planned
    !> adds nothing to the cache, a new length adds one; destroy keeps the cached plans.
    subroutine test_cache(t)
        type(test_counter_t), intent(inout) :: t
        type(fft_plan_t) :: p, q
        type(error_type), allocatable :: error
        integer :: n0
        real(dp) :: x(24), y(24)
        complex(dp) :: c(13)
        call p%init(24, error)
        if (allocated(error)) return
        n0 = fft_cached_lengths()
        call p%destroy()
        call q%init(24, error)
        if (allocated(error)) return
        call check(t, fft_cached_lengths() == n0, "fft: a cached length is not planned again")
        call random_number(x)
        call q%forward(x, c)
        call q%inverse(c, y)
        call check_close(t, y/24.0_dp, x, "fft: a cached plan after destroy of another "// &
                         "object still works", rtol=0.0_dp, atol=1.0e-14_dp)
        call p%init(2*3*5*7*11, error)
        if (allocated(error)) return
        call check(t, fft_cached_lengths() == n0 + 1 .or. n0 == fft_cache_capacity, &
                   "fft: a new length adds one cache entry")
        call p%destroy()
        call q%destroy()
    end subroutine test_cache

    !> Plans created and used by several OpenMP threads at once (lengths new to the cache and
    !> repeated ones, so that threads race for the same entry) give the serial transforms
    !> bit for bit. In a build without OpenMP the loop runs serially.
    subroutine test_concurrent(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: ntask = 16
        integer, parameter :: lengths(ntask) = [96, 97, 96, 98, 97, 160, 96, 161, 98, 160, &
                                                 96, 97, 162, 161, 98, 162]
        real(dp) :: x(162), y(162, ntask)
        real(dp) :: serial(162, ntask)
        logical :: ok(ntask)
        integer :: i
        x = [(sin(0.37_dp*i) + 0.01_dp*i, i=1, 162)]
        serial = 0.0_dp
        y = 0.0_dp
        do i = 1, ntask
            call transform(lengths(i), serial(:, i), ok(i))
        end do
        !$omp parallel do private(i) schedule(static, 1) num_threads(4)
        do i = 1, ntask
            call transform(lengths(i), y(:, i), ok(i))
        end do
        !$omp end parallel do
        call check(t, all(ok), "fft: plans made and used by several threads at once")
        call check(t, all(y == serial), "fft: several threads at once give the serial transforms")
    contains
        subroutine transform(nt, out, good)
            integer, intent(in) :: nt
            real(dp), intent(out) :: out(:)
            logical, intent(out) :: good
            type(fft_plan_t) :: q
            type(error_type), allocatable :: err
            real(dp) :: xi(nt)
            complex(dp) :: ci(nt/2 + 1)
            out = 0.0_dp
            call q%init(nt, err)
            good = .not. allocated(err)
            if (.not. good) return
            xi = x(1:nt)
            call q%forward(xi, ci)
            out(1:nt/2 + 1) = real(ci)
            call q%inverse(ci, out(1:nt))
            call q%destroy()
        end subroutine transform
    end subroutine test_concurrent

    subroutine test_bad_length(t)
        type(test_counter_t), intent(inout) :: t
        type(fft_plan_t) :: p
        type(error_type), allocatable :: error
        call p%init(0, error)
        call check_error(t, error, "fft: length 0 refused", .true., [character(len=8) :: ">= 1"])
        if (allocated(error)) call check(t, error%stat == stickslip_stat%input, &
                                         "fft: length 0 is an input error")
    end subroutine test_bad_length
end module test_fft
