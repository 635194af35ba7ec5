!> format_real (stickslip_csv) against the compiler's own es25.17e3 edit descriptor, byte
!> for byte: edge values (zero and its sign, infinities, NaN, the largest and smallest
!> normal and subnormal numbers, every power of 2 and of 10 a double holds and their
!> neighbours, values at the top and bottom of the 18-digit range, three-digit exponents),
!> random bit patterns over the whole range with both signs, and typical results; and a
!> samples file (the writer of hbm.csv and euler.csv) read back against the rows written
!> by the format '(n(es25.17e3,:,","))' it replaced.
module test_csv_format
    use, intrinsic :: iso_fortran_env, only: int64
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_positive_inf, &
        ieee_negative_inf
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_csv, only: format_real, real_fmt, real_width, write_samples_csv
    use testing, only: test_counter_t, check, check_error
    use fixtures, only: scratch_dir
    implicit none
    private
    public :: run_csv_format_tests

contains

    subroutine run_csv_format_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_edges(t)
        call test_random_bits(t)
        call test_typical(t)
        call test_samples_file(t)
    end subroutine run_csv_format_tests

    !> The number of values among v whose format_real differs from the edit descriptor's
    !> text; the first difference in `first`.
    subroutine compare(v, bad, first)
        real(dp), intent(in) :: v(:)
        integer, intent(out) :: bad
        character(len=:), allocatable, intent(out) :: first
        character(len=real_width) :: expected, got
        integer :: i
        bad = 0
        first = ""
        do i = 1, size(v)
            write (expected, '(' // real_fmt // ')') v(i)
            got = format_real(v(i))
            if (got /= expected) then
                bad = bad + 1
                if (bad == 1) first = "expected '"//expected//"', got '"//got//"'"
            end if
        end do
    end subroutine compare

    subroutine test_edges(t)
        type(test_counter_t), intent(inout) :: t
        real(dp), allocatable :: v(:)
        real(dp) :: x, big
        integer :: k, bad
        character(len=:), allocatable :: first
        big = huge(1.0_dp)
        v = [0.0_dp, -0.0_dp, big, -big, tiny(1.0_dp), -tiny(1.0_dp), nearest(0.0_dp, 1.0_dp), &
             -nearest(0.0_dp, 1.0_dp), nearest(tiny(1.0_dp), -1.0_dp), &
             ieee_value(1.0_dp, ieee_quiet_nan), ieee_value(1.0_dp, ieee_positive_inf), &
             ieee_value(1.0_dp, ieee_negative_inf), 0.5_dp, 1.0_dp, -1.0_dp, 0.1_dp, 0.3_dp, &
             1.0_dp/3.0_dp, 2.0_dp/3.0_dp, 1.0e17_dp, 1.0e18_dp, 999999999999999999.0_dp, &
             123456789012345678.0_dp, 9.5_dp, 99999999999999999.5_dp, 1.0e-100_dp, 1.0e100_dp, &
             1.0e-300_dp, 1.0e300_dp, 4.9e-324_dp, 2.2250738585072014e-308_dp]
        ! powers of 10 and their neighbours: the decimal exponent's boundaries
        do k = -323, 308
            x = 10.0_dp**k
            v = [v, x, nearest(x, 1.0_dp), nearest(x, -1.0_dp), -x, 5.0_dp*x, &
                 9.999999999999999_dp*x, 9.9999999999999982_dp*x, 0.99999999999999989_dp*x, &
                 1.0000000000000002_dp*x, 1.0000000000000004_dp*x, 9.99999999999999999e-1_dp*x]
        end do
        ! powers of 2, subnormals included, and their neighbours
        do k = -1074, 1023
            x = 2.0_dp**k
            v = [v, x, nearest(x, 1.0_dp), nearest(x, -1.0_dp), 3.0_dp*x, -x]
        end do
        call compare(v, bad, first)
        call check(t, bad == 0, "csv_format: edge values as es25.17e3 (" // &
                   itoa(size(v)) // " values)", first)
    end subroutine test_edges

    !> Random 64-bit patterns (every exponent, both signs; NaN and infinities included).
    subroutine test_random_bits(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 200000
        real(dp), allocatable :: v(:)
        integer(int64) :: state
        integer :: i, bad
        character(len=:), allocatable :: first
        allocate (v(n))
        state = 88172645463325252_int64
        do i = 1, n
            state = ieor(state, ishft(state, 13))
            state = ieor(state, ishft(state, -7))
            state = ieor(state, ishft(state, 17))
            v(i) = transfer(state, 1.0_dp)
        end do
        call compare(v, bad, first)
        call check(t, bad == 0, "csv_format: 200000 random bit patterns as es25.17e3", first)
    end subroutine test_random_bits

    !> Values like the results: displacements, velocities, forces, times, small integers,
    !> binary fractions (exact decimal expansions, where ties can occur).
    subroutine test_typical(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: n = 60000
        real(dp) :: v(n), u(3)
        integer :: i, bad
        character(len=:), allocatable :: first
        do i = 1, n
            call random_number(u)
            select case (mod(i, 4))
            case (0)
                v(i) = (u(1) - 0.5_dp)*10.0_dp**int(u(2)*40.0_dp - 20.0_dp)
            case (1)
                v(i) = real(int(u(1)*1.0e6_dp), dp)/2.0_dp**int(u(2)*70.0_dp)
            case (2)
                v(i) = real(int(u(1)*2.0e4_dp) - 10000, dp)
            case default
                v(i) = real(int((u(1) - 0.5_dp)*2.0_dp**53), dp)*10.0_dp**int(u(3)*30.0_dp - 15.0_dp)
            end select
        end do
        call compare(v, bad, first)
        call check(t, bad == 0, "csv_format: typical values and exact binary fractions", first)
    end subroutine test_typical

    !> write_samples_csv against the rows of the edit descriptor it replaced.
    subroutine test_samples_file(t)
        type(test_counter_t), intent(inout) :: t
        integer, parameter :: nt = 50, n = 3, nc = 2
        real(dp) :: tt(nt), x(nt, n), v(nt, n), r(nt, nc)
        type(error_type), allocatable :: error
        character(len=:), allocatable :: dir
        character(len=400) :: got, expected, fmt
        integer :: u, k, stat, bad
        call random_number(tt)
        call random_number(x)
        call random_number(v)
        call random_number(r)
        x = (x - 0.5_dp)*1.0e-3_dp
        v(1, :) = 0.0_dp
        v(2, :) = -0.0_dp
        r(3, 1) = ieee_value(1.0_dp, ieee_quiet_nan)
        r(4, 2) = -huge(1.0_dp)
        r(5, 1) = nearest(0.0_dp, 1.0_dp)
        dir = scratch_dir()
        call write_samples_csv(dir, "csv_format.csv", tt, x, v, r, error, dofs=[3, 1])
        call check_error(t, error, "csv_format: samples file written", .false.)
        if (allocated(error)) return
        write (fmt, '(a,i0,a)') '(', 1 + 2*2 + nc, '(' // real_fmt // ',:,","))'
        open (newunit=u, file=dir//"/csv_format.csv", status='old', action='read')
        read (u, '(a)') got
        call check(t, trim(got) == "t,x3,x1,v3,v1,r1,r2", "csv_format: samples file header", &
                   trim(got))
        bad = 0
        do k = 1, nt
            read (u, '(a)', iostat=stat) got
            write (expected, fmt) tt(k), x(k, [3, 1]), v(k, [3, 1]), r(k, :)
            if (stat /= 0 .or. got /= expected) bad = bad + 1
        end do
        read (u, '(a)', iostat=stat) got
        close (u, status='delete')
        call check(t, bad == 0 .and. stat /= 0, &
                   'csv_format: samples file rows = the rows of "(n(es25.17e3,:,'',''))"')
    end subroutine test_samples_file
end module test_csv_format
