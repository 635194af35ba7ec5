!> A 64-bit FNV-1a hash of bytes (Fowler-Noll-Vo, variant 1a: for each byte b,
!> h = (h xor b) * 0x100000001b3, from h = 0xcbf29ce484222325), for content keys such as the
!> reduction cache's (stickslip_reduction_cache). Not cryptographic: it tells a changed
!> input from an unchanged one, not a forged one from a true one.
!>
!> The state is kept in two 32-bit limbs held in 64-bit integers, so that the arithmetic
!> modulo 2^64 never overflows a signed integer (which Fortran leaves undefined): with
!> h = hi 2^32 + lo and the prime p = 2^40 + 435, h p mod 2^64 has the low limb
!> (435 lo) mod 2^32 and the high limb (435 hi + carry + 2^8 lo) mod 2^32. About 1 GB/s.
!> Arrays of other types are hashed through their bytes (`transfer`), so a value's bits
!> count, not its printed form (0.0 and -0.0 differ).
module stickslip_hash
    use, intrinsic :: iso_fortran_env, only: int8, int32, int64, real64
    implicit none
    private
    public :: hash_t

    integer(int64), parameter :: mask32 = 4294967295_int64
    !> The FNV-1a 64 offset basis 0xcbf29ce484222325 as two limbs.
    integer(int64), parameter :: basis_hi = 3421674724_int64, basis_lo = 2216829733_int64

    !> A running FNV-1a 64 hash.
    type :: hash_t
        integer(int64), private :: hi = basis_hi
        integer(int64), private :: lo = basis_lo
    contains
        procedure, private :: add_bytes, add_text, add_int32, add_int32s, add_real, add_reals, &
            add_reals2, add_logical, add_int64
        !> Feed bytes, text, integers, reals (scalars, vectors, matrices) or a logical.
        generic :: add => add_bytes, add_text, add_int32, add_int32s, add_real, add_reals, &
            add_reals2, add_logical, add_int64
        !> The hash of everything fed so far.
        procedure :: value => hash_value
        !> The hash as 16 hexadecimal digits.
        procedure :: hex => hash_hex
    end type hash_t

contains

    !> Feed bytes.
    pure subroutine add_bytes(self, bytes)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The bytes.
        integer(int8), intent(in) :: bytes(:)
        integer(int64) :: hi, lo, t, u
        integer :: k
        hi = self%hi
        lo = self%lo
        do k = 1, size(bytes)
            lo = ieor(lo, iand(int(bytes(k), int64), 255_int64))
            t = lo*435_int64
            u = hi*435_int64 + ishft(t, -32) + ishft(lo, 8)
            lo = iand(t, mask32)
            hi = iand(u, mask32)
        end do
        self%hi = hi
        self%lo = lo
    end subroutine add_bytes

    !> Feed the bytes of a text, then its length (so that 'ab', 'c' differs from 'a', 'bc').
    pure subroutine add_text(self, text)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The text.
        character(len=*), intent(in) :: text
        if (len(text) > 0) call self%add_bytes(transfer(text, [0_int8], len(text)))
        call self%add_int64(int(len(text), int64))
    end subroutine add_text

    !> Feed an integer (its 4 bytes).
    pure subroutine add_int32(self, x)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The value.
        integer(int32), intent(in) :: x
        call self%add_bytes(transfer(x, [0_int8], 4))
    end subroutine add_int32

    !> Feed a 64-bit integer (its 8 bytes).
    pure subroutine add_int64(self, x)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The value.
        integer(int64), intent(in) :: x
        call self%add_bytes(transfer(x, [0_int8], 8))
    end subroutine add_int64

    !> Feed the size of an integer vector, then its values.
    pure subroutine add_int32s(self, x)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The values.
        integer(int32), intent(in) :: x(:)
        call self%add_int64(int(size(x), int64))
        if (size(x) > 0) call self%add_bytes(transfer(x, [0_int8], 4*size(x)))
    end subroutine add_int32s

    !> Feed a real (its 8 bytes).
    pure subroutine add_real(self, x)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The value.
        real(real64), intent(in) :: x
        call self%add_bytes(transfer(x, [0_int8], 8))
    end subroutine add_real

    !> Feed the size of a real vector, then its values.
    pure subroutine add_reals(self, x)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The values.
        real(real64), intent(in) :: x(:)
        call self%add_int64(int(size(x), int64))
        if (size(x) > 0) call self%add_bytes(transfer(x, [0_int8], 8*size(x)))
    end subroutine add_reals

    !> Feed the shape of a real matrix, then its values (column by column).
    pure subroutine add_reals2(self, x)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The values.
        real(real64), intent(in) :: x(:, :)
        call self%add_int64(int(size(x, 1), int64))
        call self%add_int64(int(size(x, 2), int64))
        if (size(x) > 0) call self%add_bytes(transfer(x, [0_int8], 8*size(x)))
    end subroutine add_reals2

    !> Feed a logical (one byte, 0 or 1).
    pure subroutine add_logical(self, x)
        !> The hash.
        class(hash_t), intent(inout) :: self
        !> The value.
        logical, intent(in) :: x
        call self%add_bytes([merge(1_int8, 0_int8, x)])
    end subroutine add_logical

    !> The hash of everything fed so far (the 64 bits as a signed integer).
    pure integer(int64) function hash_value(self) result(h)
        !> The hash.
        class(hash_t), intent(in) :: self
        h = ior(ishft(self%hi, 32), self%lo)
    end function hash_value

    !> The hash as 16 lowercase hexadecimal digits.
    pure function hash_hex(self) result(text)
        !> The hash.
        class(hash_t), intent(in) :: self
        character(len=16) :: text
        character(len=*), parameter :: digits = '0123456789abcdef'
        integer :: k
        integer(int64) :: limb
        do k = 1, 8
            limb = iand(ishft(self%hi, -4*(8 - k)), 15_int64)
            text(k:k) = digits(limb + 1:limb + 1)
            limb = iand(ishft(self%lo, -4*(8 - k)), 15_int64)
            text(k + 8:k + 8) = digits(limb + 1:limb + 1)
        end do
    end function hash_hex
end module stickslip_hash
