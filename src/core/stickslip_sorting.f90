!> Sorting of short real arrays in place (insertion: the tens to hundreds of values of a
!> slider set or a frequency grid, where it beats anything cleverer).
module stickslip_sorting
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: sort_ascending

contains

    !> Sort `x` increasing, in place (stable). No errors.
    pure subroutine sort_ascending(x)
        !> The values.
        real(dp), intent(inout) :: x(:)
        real(dp) :: t
        integer :: p, j
        do p = 2, size(x)
            t = x(p)
            j = p - 1
            do while (j >= 1)
                if (x(j) <= t) exit
                x(j + 1) = x(j)
                j = j - 1
            end do
            x(j + 1) = t
        end do
    end subroutine sort_ascending
end module stickslip_sorting
