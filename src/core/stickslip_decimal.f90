!> Decimal numbers read from text fast, for readers of large numeric files (Matrix Market):
!> a hand-written scanner of the common forms that returns the CORRECTLY ROUNDED double, the
!> value a Fortran internal read `read(text, *) x` gives (gfortran hands the digits to
!> strtod, which rounds correctly), bit for bit; or says it cannot (`ok = .false.`), and the
!> caller then reads the token the slow way. It never returns a value it cannot guarantee.
!>
!> Accepted: `[+|-] digits [. [digits]] [(e|E|d|D) [+|-] digits]` and `[+|-] . digits [...]`
!> (at least one mantissa digit), at most max_decimal_digits significant digits (leading
!> zeros do not count; more: not ok), exponents up to 99999 in magnitude. Not accepted (not
!> ok): anything else Fortran may read (`1.5+3`, `inf`, `nan`), values whose result would
!> be outside [1e-270, 1e290] without being exactly representable by the short path below,
!> and the rare values within 2**-80 (relative) of the midpoint between two doubles.
!>
!> How: the significant digits form an integer w (< 10**18) and the value is w 10**q.
!> When w <= 2**53 and |q| <= 22, both w and 10**|q| are exact doubles and one IEEE
!> multiplication or division rounds correctly (Clinger's fast path). Otherwise w is split
!> into three 20-bit parts and 10**q is taken from a table of its leading 99 bits in three
!> 33-bit parts (truncated, computed exactly with integers by new_decimal_powers): the nine
!> partial products are exact doubles and are summed error-free (TwoSum: additions only, so
!> a compiler's fused multiply-add changes nothing), which gives w 10**q within 2**-97 of
!> itself; the rounding of that sum is the correctly rounded value unless the sum lies
!> within 2**-80 of a midpoint (then not ok). Knows nothing of files.
module stickslip_decimal
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: decimal_powers_t, new_decimal_powers, scan_decimal, scan_digits
    public :: max_decimal_digits, min_table_exponent, max_table_exponent

    !> Most significant digits scanned (w < 10**18 < 2**60).
    integer, parameter :: max_decimal_digits = 18
    !> Exponent range of the table of powers of ten (every part a normal double).
    integer, parameter :: min_table_exponent = -270, max_table_exponent = 290

    !> 10**q for q in [min_table_exponent, max_table_exponent], its leading 99 bits in three
    !> parts of 33 bits each (truncated: part(0,q) + part(1,q) + part(2,q) <= 10**q, less
    !> by under 2**-98 of it). Built on first use by scan_decimal (`ready`).
    type :: decimal_powers_t
        !> The table has been built.
        logical :: ready = .false.
        !> The three parts of 10**q, largest first.
        real(dp) :: part(0:2, min_table_exponent:max_table_exponent) = 0.0_dp
    end type decimal_powers_t

    !> 10**k, k = 0..22: exact doubles.
    real(dp), parameter :: exact_power(0:22) = [1.0e0_dp, 1.0e1_dp, 1.0e2_dp, 1.0e3_dp, &
        1.0e4_dp, 1.0e5_dp, 1.0e6_dp, 1.0e7_dp, 1.0e8_dp, 1.0e9_dp, 1.0e10_dp, 1.0e11_dp, &
        1.0e12_dp, 1.0e13_dp, 1.0e14_dp, 1.0e15_dp, 1.0e16_dp, 1.0e17_dp, 1.0e18_dp, &
        1.0e19_dp, 1.0e20_dp, 1.0e21_dp, 1.0e22_dp]
    !> Limbs of the exact integers of new_decimal_powers: base 2**30.
    integer, parameter :: limb_bits = 30
    integer(int64), parameter :: limb_base = 2_int64**limb_bits
    !> 10**-k is built from floor(2**scale_bits / 10**k).
    integer, parameter :: scale_bits = 1200

contains

    !> Build the table of `self` (exact integer arithmetic; about 0.1 ms).
    pure subroutine new_decimal_powers(self)
        !> The table.
        type(decimal_powers_t), intent(inout) :: self
        integer(int64) :: big(scale_bits/limb_bits + 2)
        integer :: q, top
        ! 10**q, q >= 0: multiplied by ten step by step
        big = 0
        big(1) = 1
        top = 1
        do q = 0, max_table_exponent
            if (q > 0) call times_ten(big, top)
            call take_parts(big, top, 0, self%part(:, q))
        end do
        ! 10**-k = floor(2**scale_bits / 10**k) 2**-scale_bits: floors of floors are exact
        big = 0
        top = scale_bits/limb_bits + 1
        big(top) = 2_int64**(scale_bits - limb_bits*(top - 1))
        do q = -1, min_table_exponent, -1
            call over_ten(big, top)
            call take_parts(big, top, scale_bits, self%part(:, q))
        end do
        self%ready = .true.
    end subroutine new_decimal_powers

    pure subroutine times_ten(big, top)
        integer(int64), intent(inout) :: big(:)
        integer, intent(inout) :: top
        integer(int64) :: carry, x
        integer :: k
        carry = 0
        do k = 1, top
            x = 10*big(k) + carry
            big(k) = modulo(x, limb_base)
            carry = x/limb_base
        end do
        if (carry > 0) then
            top = top + 1
            big(top) = carry
        end if
    end subroutine times_ten

    pure subroutine over_ten(big, top)
        integer(int64), intent(inout) :: big(:)
        integer, intent(inout) :: top
        integer(int64) :: rest, x
        integer :: k
        rest = 0
        do k = top, 1, -1
            x = rest*limb_base + big(k)
            big(k) = x/10
            rest = modulo(x, 10_int64)
        end do
        do while (top > 1 .and. big(top) == 0)
            top = top - 1
        end do
    end subroutine over_ten

    !> The leading 99 bits of big 2**-shift in three truncated 33-bit parts.
    pure subroutine take_parts(big, top, shift, part)
        integer(int64), intent(in) :: big(:)
        integer, intent(in) :: top, shift
        real(dp), intent(out) :: part(0:2)
        integer :: length, p
        length = limb_bits*(top - 1) + (int(bit_size(big(top))) - leadz(big(top)))
        do p = 0, 2
            part(p) = scale(real(bits_at(length - 33*(p + 1)), dp), length - 33*(p + 1) - shift)
        end do
    contains
        !> The 33 bits of big from bit `low` up (bits below 0 are zero).
        pure integer(int64) function bits_at(low) result(v)
            integer, intent(in) :: low
            integer :: k
            v = 0
            do k = low + 32, low, -1
                v = 2*v
                if (k >= 0) v = v + ibits(big(k/limb_bits + 1), mod(k, limb_bits), 1)
            end do
        end function bits_at
    end subroutine take_parts

    !> Scan the unsigned decimal integer at text(pos:) (digits only, at most 9, so that it
    !> fits a default integer): ok and its value in `i`, pos after it; not ok (pos unchanged)
    !> when text(pos:pos) is not a digit or there are more than 9 digits.
    pure subroutine scan_digits(text, pos, i, ok)
        !> The text.
        character(len=*), intent(in) :: text
        !> Where the integer starts; on success, just after it.
        integer, intent(inout) :: pos
        !> Its value.
        integer, intent(out) :: i
        !> A plain integer of at most 9 digits was there.
        logical, intent(out) :: ok
        integer :: p, d
        i = 0
        ok = .false.
        p = pos
        do while (p <= len(text))
            d = iachar(text(p:p)) - 48
            if (d < 0 .or. d > 9) exit
            if (p - pos >= 9) return
            i = 10*i + d
            p = p + 1
        end do
        if (p == pos) return
        pos = p
        ok = .true.
    end subroutine scan_digits

    !> Scan the decimal number at text(pos:) (the forms of the module; only `[+|-] digits`
    !> when `integer_only`): ok and its correctly rounded value in `x`, pos just after it;
    !> not ok when the text there is not such a number or the value cannot be guaranteed
    !> (the caller reads it otherwise). The character after the number is not looked at:
    !> "1.5x" gives 1.5 with pos at 'x'. Builds the table of `powers` when first needed.
    pure subroutine scan_decimal(text, pos, powers, integer_only, x, ok)
        !> The text.
        character(len=*), intent(in) :: text
        !> Where the number starts; on success, just after it.
        integer, intent(inout) :: pos
        !> The table of powers of ten (built here when needed and not yet built).
        type(decimal_powers_t), intent(inout) :: powers
        !> Accept only an optionally signed integer (no point, no exponent).
        logical, intent(in) :: integer_only
        !> The value.
        real(dp), intent(out) :: x
        !> The value is the correctly rounded one.
        logical, intent(out) :: ok
        integer(int64) :: w
        integer :: p, d, digits, mantissa, q, e, c, n, start
        logical :: negative, negative_exponent, run_ok
        x = 0.0_dp
        ok = .false.
        n = len(text)
        p = pos
        if (p > n) return
        negative = .false.
        c = iachar(text(p:p))
        if (c == 43 .or. c == 45) then       ! + -
            negative = c == 45
            p = p + 1
        end if
        w = 0
        digits = 0       ! significant digits in w
        mantissa = 0     ! mantissa digits seen
        q = 0
        call digit_run(text, n, 0, p, w, digits, mantissa, q, run_ok)
        if (.not. run_ok) return
        if (.not. integer_only .and. p <= n) then
            if (text(p:p) == '.') then
                p = p + 1
                ! each fraction digit lowers the decimal exponent by one
                call digit_run(text, n, -1, p, w, digits, mantissa, q, run_ok)
                if (.not. run_ok) return
            end if
        end if
        if (mantissa == 0) return
        if (.not. integer_only .and. p <= n) then
            c = iachar(text(p:p))
            if (c == 101 .or. c == 69 .or. c == 100 .or. c == 68) then     ! e E d D
                p = p + 1
                if (p > n) return
                negative_exponent = .false.
                c = iachar(text(p:p))
                if (c == 43 .or. c == 45) then
                    negative_exponent = c == 45
                    p = p + 1
                end if
                e = 0
                start = p
                do while (p <= n)
                    d = iachar(text(p:p)) - 48
                    if (d < 0 .or. d > 9) exit
                    if (e >= 10000) return
                    e = 10*e + d
                    p = p + 1
                end do
                if (p == start) return
                if (negative_exponent) e = -e
                q = q + e
            end if
        end if
        if (w == 0) then
            x = 0.0_dp
        else if (w <= 2_int64**53 .and. q >= -22 .and. q <= 22) then
            if (q >= 0) then
                x = real(w, dp)*exact_power(q)
            else
                x = real(w, dp)/exact_power(-q)
            end if
        else
            if (q < min_table_exponent .or. q > max_table_exponent) return
            if (.not. powers%ready) call new_decimal_powers(powers)
            call round_product(w, powers%part(:, q), x, ok)
            if (.not. ok) return
        end if
        if (negative) x = -x
        pos = p
        ok = .true.
    end subroutine scan_decimal

    !> The digits of text(p:n) from p on into w (leading zeros skipped, at most
    !> max_decimal_digits significant ones: ok false beyond), counting them in mantissa and
    !> adding dq to the decimal exponent q for each; p is left on the first non-digit.
    pure subroutine digit_run(text, n, dq, p, w, digits, mantissa, q, ok)
        character(len=*), intent(in) :: text
        integer, intent(in) :: n, dq
        integer, intent(inout) :: p, digits, mantissa, q
        integer(int64), intent(inout) :: w
        logical, intent(out) :: ok
        integer :: d
        ok = .false.
        do while (p <= n)
            d = iachar(text(p:p)) - 48
            if (d < 0 .or. d > 9) exit
            mantissa = mantissa + 1
            if (w > 0 .or. d > 0) then
                if (digits >= max_decimal_digits) return
                w = 10*w + d
                digits = digits + 1
            end if
            q = q + dq
            p = p + 1
        end do
        ok = .true.
    end subroutine digit_run

    !> The correctly rounded w (parts(0) + parts(1) + parts(2)) when the sum shows it (ok).
    pure subroutine round_product(w, parts, x, ok)
        integer(int64), intent(in) :: w
        real(dp), intent(in) :: parts(0:2)
        real(dp), intent(out) :: x
        logical, intent(out) :: ok
        integer(int64), parameter :: mask = 2_int64**20 - 1
        real(dp) :: wp(0:2), hi, lo, r, gap
        integer(int64) :: bits
        integer :: a, b
        ok = .false.
        ! w in 20-bit parts (each exact, at most 20 significant bits)
        wp(0) = real(ishft(w, -40), dp)*2.0_dp**40
        wp(1) = real(iand(ishft(w, -20), mask), dp)*2.0_dp**20
        wp(2) = real(iand(w, mask), dp)
        hi = 0.0_dp
        lo = 0.0_dp
        ! the nine products are exact (20 + 33 bits); summed without error, smallest first
        do a = 2, 0, -1
            do b = 2, 0, -1
                call two_sum(hi, wp(a)*parts(b), lo)
            end do
        end do
        x = hi + lo
        if (.not. (x <= huge(x))) return
        ! r = hi + lo - x exactly (|lo| << |hi|: Fast2Sum)
        r = lo - (x - hi)
        ! half the spacing of the doubles at x (normal: x >= 1e-270), from its bits
        bits = transfer(x, bits)
        gap = transfer(ishft(ishft(bits, -52) - 53, 52), gap)
        if (r >= 0.0_dp) then
            ok = gap - r > x*2.0_dp**(-80)
        else
            ! below a power of two the doubles are twice as dense
            if (iand(bits, 2_int64**52 - 1) == 0) gap = 0.5_dp*gap
            ok = gap + r > x*2.0_dp**(-80)
        end if
    end subroutine round_product

    !> hi + t as hi (rounded) and its exact error added to lo (Knuth's TwoSum).
    pure subroutine two_sum(hi, t, lo)
        real(dp), intent(inout) :: hi
        real(dp), intent(in) :: t
        real(dp), intent(inout) :: lo
        real(dp) :: s, bb
        s = hi + t
        bb = s - hi
        lo = lo + ((hi - (s - bb)) + (t - bb))
        hi = s
    end subroutine two_sum
end module stickslip_decimal
