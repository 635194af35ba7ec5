!> Tests of stickslip_decimal, the fast scanner of decimal numbers: whenever it accepts a
!> number its value is bit for bit the one of Fortran's list-directed read (which rounds
!> correctly), for every exponent letter, signs, many digits, tiny and huge exponents,
!> midpoints between doubles; the forms it refuses; its table of powers of ten.
module test_decimal
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_decimal, only: decimal_powers_t, new_decimal_powers, scan_decimal, &
        scan_digits, min_table_exponent, max_table_exponent
    use testing, only: test_counter_t, check
    implicit none
    private
    public :: run_decimal_tests

contains

    subroutine run_decimal_tests(t)
        type(test_counter_t), intent(inout) :: t
        call test_forms(t)
        call test_refused(t)
        call test_hard_values(t)
        call test_random_values(t)
        call test_table(t)
        call test_digits(t)
    end subroutine run_decimal_tests

    !> s scanned whole and equal, bit for bit, to read(s, *); `accepted`: the scanner must
    !> accept it (else it may refuse it, but must not return another value).
    subroutine same_as_read(t, s, accepted, powers)
        type(test_counter_t), intent(inout) :: t
        character(len=*), intent(in) :: s
        logical, intent(in) :: accepted
        type(decimal_powers_t), intent(inout) :: powers
        real(dp) :: x, y
        integer :: pos, stat
        logical :: ok
        pos = 1
        call scan_decimal(s, pos, powers, .false., x, ok)
        read (s, *, iostat=stat) y
        if (accepted) call check(t, ok, "decimal: '"//s//"' accepted")
        if (.not. ok) return
        call check(t, stat == 0 .and. pos == len(s) + 1 .and. &
                   transfer(x, 1_int64) == transfer(y, 1_int64), &
                   "decimal: '"//s//"' as read(s, *)")
    end subroutine same_as_read

    subroutine test_forms(t)
        type(test_counter_t), intent(inout) :: t
        type(decimal_powers_t) :: powers
        ! accepted: every exponent letter, signs, points, leading zeros, 18 digits, the
        ! short path and the table (q = -22 and -23 are the blade matrices' two cases)
        character(len=24), parameter :: forms(*) = [character(len=24) :: &
            "5.5215441313185e+04", "5.5215441313185E+04", "5.5215441313185d+04", &
            "5.5215441313185D+04", "5.5215441313185e4", "5.5215441313185e-04", &
            "-3.4844662247620e+03", "+3.4844662247620e+03", "6.5475585120464e-10", &
            "2.0436814886855e-08", "0.0000000000000e+00", "-0.0", "+0", "0d0", "1", &
            "-17", "42.", ".5", "-.5e-3", "+7.", "1.e1", "1E0001", "007.50", "1e-0", &
            "0.000123456789", "123456789012345678", "1.23456789012345678", "1.0e23", &
            "8.589973e9", "1e-270", "1e290", "-1.23456789012345678e-250"]
        ! maybe refused (then read by the caller): an exact tie, the ends of the range,
        ! subnormals, overflow
        character(len=24), parameter :: edges(*) = [character(len=24) :: &
            "9007199254740993", "1.7976931348623157e308", "2.2250738585072014e-308", &
            "4.9406564584124654e-324", "1e-400", "-2.5e-324", "1e-271", "1e291"]
        integer :: k
        do k = 1, size(forms)
            call same_as_read(t, trim(forms(k)), .true., powers)
        end do
        do k = 1, size(edges)
            call same_as_read(t, trim(edges(k)), .false., powers)
        end do
        ! a signed zero keeps its sign
        block
            real(dp) :: x
            integer :: pos
            logical :: ok
            pos = 1
            call scan_decimal("-0.000e+00", pos, powers, .false., x, ok)
            call check(t, ok .and. x == 0.0_dp .and. sign(1.0_dp, x) < 0.0_dp, &
                       "decimal: -0.000e+00 is -0")
            ! the scan stops at the first character after the number
            pos = 3
            call scan_decimal("1 2.5x", pos, powers, .false., x, ok)
            call check(t, ok .and. x == 2.5_dp .and. pos == 6, "decimal: stops before 'x'")
            ! integer_only: no point, no exponent
            pos = 1
            call scan_decimal("-12", pos, powers, .true., x, ok)
            call check(t, ok .and. x == -12.0_dp .and. pos == 4, "decimal: integer -12")
            pos = 1
            call scan_decimal("12.5", pos, powers, .true., x, ok)
            call check(t, ok .and. pos == 3, "decimal: integer_only stops at the point")
        end block
    end subroutine test_forms

    !> Forms left to the caller's slow path (not ok), including every one Fortran reads
    !> differently or not at all.
    subroutine test_refused(t)
        type(test_counter_t), intent(inout) :: t
        type(decimal_powers_t) :: powers
        character(len=32), parameter :: refused(*) = [character(len=32) :: "", ".", "-", &
            "+.", "e5", ".e5", "1e", "1e+", "1.5d", "--1", "NaN", "Inf", "infinity", &
            "1234567890123456789", "1.0000000000000000000001", "1e100000", "1e-99999", &
            "9007199254740993", "4503599627370497.5"]
        real(dp) :: x
        integer :: k, pos
        logical :: ok, any_accepted
        any_accepted = .false.
        do k = 1, size(refused)
            pos = 1
            call scan_decimal(trim(refused(k)), pos, powers, .false., x, ok)
            ! "1e" etc. may scan as "1" followed by an 'e': then pos must stop before it
            if (ok .and. pos == len_trim(refused(k)) + 1) then
                any_accepted = .true.
                call check(t, .false., "decimal: '"//trim(refused(k))//"' refused")
            end if
        end do
        call check(t, .not. any_accepted, "decimal: unusual forms refused or cut short")
    end subroutine test_refused

    !> Values next to midpoints between doubles (the hard cases of correct rounding):
    !> every double's midpoint with its neighbour written with 16 to 18 digits, exact ties
    !> (refused), powers of two where the spacing halves.
    subroutine test_hard_values(t)
        type(test_counter_t), intent(inout) :: t
        type(decimal_powers_t) :: powers
        integer, parameter :: qp = selected_real_kind(30)
        real(dp) :: z, x, y, r
        real(qp) :: m
        character(len=40) :: s
        character(len=16), parameter :: formats(3) = [character(len=16) :: "(es40.17e3)", &
            "(es40.16e3)", "(es40.15e3)"]
        integer :: k, f, pos, stat, wrong, accepted
        logical :: ok
        wrong = 0
        accepted = 0
        do k = 1, 3000
            call random_number(r)
            z = (1.0_dp + r)*2.0_dp**int(1800*r - 900)
            if (mod(k, 7) == 0) z = 2.0_dp**int(600*r - 300)
            do f = 1, size(formats)
                m = real(z, qp) + real(spacing(z), qp)/2
                if (mod(k, 2) == 0) m = real(z, qp) - real(spacing(z), qp)/4
                write (s, formats(f)) m
                s = adjustl(s)
                pos = 1
                call scan_decimal(trim(s), pos, powers, .false., x, ok)
                if (.not. ok) cycle
                accepted = accepted + 1
                read (s, *, iostat=stat) y
                if (stat /= 0 .or. transfer(x, 1_int64) /= transfer(y, 1_int64)) wrong = wrong + 1
            end do
        end do
        call check(t, wrong == 0, "decimal: values next to midpoints as read(s, *)")
        call check(t, accepted > 6000, "decimal: most values next to midpoints accepted")
    end subroutine test_hard_values

    !> Random numbers in random forms (digits 1..20, point anywhere or none, e/E/d/D or no
    !> exponent, signs, exponents -330..330): those accepted equal read(s, *) bit for bit.
    subroutine test_random_values(t)
        type(test_counter_t), intent(inout) :: t
        type(decimal_powers_t) :: powers
        character(len=1), parameter :: letters(4) = ['e', 'E', 'd', 'D']
        character(len=48) :: s
        real(dp) :: x, y, r(6)
        integer :: trial, k, digits, pos, stat, wrong, accepted, point
        logical :: ok
        wrong = 0
        accepted = 0
        do trial = 1, 100000
            call random_number(r)
            s = ""
            if (r(1) < 0.3_dp) s = "-"
            if (r(1) > 0.9_dp) s = "+"
            digits = 1 + int(r(2)*20)
            point = int(r(3)*(digits + 2))
            do k = 1, digits
                if (k == point) s = trim(s)//"."
                call random_number(r(6))
                s = trim(s)//achar(48 + int(10*r(6)))
            end do
            if (r(4) < 0.8_dp) then
                if (r(5) < 0.7_dp) then
                    write (s(len_trim(s) + 1:), '(a,i0)') letters(1 + int(4*r(4)/0.8_dp)), &
                        int(60*r(5)/0.7_dp) - 30
                else
                    write (s(len_trim(s) + 1:), '(a,sp,i0)') letters(1 + int(4*r(4)/0.8_dp)), &
                        int(660*(r(5) - 0.7_dp)/0.3_dp) - 330
                end if
            end if
            pos = 1
            call scan_decimal(trim(s), pos, powers, .false., x, ok)
            if (.not. ok) cycle
            accepted = accepted + 1
            read (s, *, iostat=stat) y
            if (stat /= 0 .or. pos /= len_trim(s) + 1 .or. &
                transfer(x, 1_int64) /= transfer(y, 1_int64)) then
                wrong = wrong + 1
                if (wrong <= 3) call check(t, .false., "decimal: random '"//trim(s)//"'")
            end if
        end do
        call check(t, wrong == 0, "decimal: 100000 random numbers as read(s, *)")
        call check(t, accepted > 80000, "decimal: most random numbers accepted")
    end subroutine test_random_values

    !> The table: exact for 10**0..10**29 (< 2**99), 99 bits otherwise.
    subroutine test_table(t)
        type(test_counter_t), intent(inout) :: t
        type(decimal_powers_t) :: powers
        integer, parameter :: qp = selected_real_kind(30)
        real(qp) :: sum, exact
        integer :: q
        logical :: good
        call new_decimal_powers(powers)
        good = powers%ready
        do q = 0, 22
            good = good .and. powers%part(0, q) + powers%part(1, q) + powers%part(2, q) == &
                   10.0_dp**q .and. powers%part(2, q) == 0.0_dp
        end do
        call check(t, good, "decimal: table exact for 10**0..10**22")
        good = .true.
        do q = -30, 30
            sum = real(powers%part(0, q), qp) + real(powers%part(1, q), qp) + &
                  real(powers%part(2, q), qp)
            exact = 10.0_qp**q
            good = good .and. sum <= exact*(1 + 2.0_qp**(-110)) .and. &
                   exact - sum <= exact*2.0_qp**(-97)
        end do
        call check(t, good, "decimal: table within 2**-97 below 10**q")
        call check(t, all(powers%part(:, min_table_exponent) > 0.0_dp) .and. &
                   all(powers%part(:, max_table_exponent) < huge(1.0_dp)), &
                   "decimal: table ends are normal doubles")
    end subroutine test_table

    subroutine test_digits(t)
        type(test_counter_t), intent(inout) :: t
        integer :: i, pos
        logical :: ok
        pos = 3
        call scan_digits("  61098 1", pos, i, ok)
        call check(t, ok .and. i == 61098 .and. pos == 8, "decimal: digits 61098")
        pos = 1
        call scan_digits("123456789", pos, i, ok)
        call check(t, ok .and. i == 123456789 .and. pos == 10, "decimal: 9 digits")
        pos = 1
        call scan_digits("1234567890", pos, i, ok)
        call check(t, .not. ok .and. pos == 1, "decimal: 10 digits refused")
        pos = 1
        call scan_digits("+1", pos, i, ok)
        call check(t, .not. ok, "decimal: a sign is not a plain index")
        pos = 1
        call scan_digits("", pos, i, ok)
        call check(t, .not. ok, "decimal: no digits")
    end subroutine test_digits
end module test_decimal
