!> The largest value of a function of one variable on an interval, by golden-section search
!> in reverse communication: the caller asks for the next abscissa (`next`), evaluates its
!> function there however it likes (a nonlinear solve, warm-started from the last one) and
!> tells the value (`tell`), until `done`. The bracket shrinks by 0.618 per evaluation; it
!> finds a local maximum of any function unimodal on the interval. No procedure arguments,
!> no state outside the object: callable from several threads at once.
module stickslip_golden
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: golden_search_t

    !> 1 / golden ratio.
    real(dp), parameter :: inv_phi = 0.6180339887498949_dp

    !> A golden-section search for a maximum.
    type :: golden_search_t
        !> Bracket [a, b], inner points c < d and their values.
        real(dp) :: a = 0.0_dp, b = 0.0_dp, c = 0.0_dp, d = 0.0_dp
        real(dp) :: fc = 0.0_dp, fd = 0.0_dp
        !> Width at which the search stops.
        real(dp) :: tol = 0.0_dp
        !> 0: f(c) wanted, 1: f(d) wanted, 2: the next inner point wanted, 3: done.
        integer :: stage = 3
        !> The inner point the next value belongs to (1: c, 2: d).
        integer :: pending = 0
        !> Evaluations told.
        integer :: nfev = 0
    contains
        !> Start on [a, b] with the stopping width `tol`.
        procedure :: begin => golden_begin
        !> The abscissa to evaluate next.
        procedure :: next => golden_next
        !> The value at the abscissa `next` gave.
        procedure :: tell => golden_tell
        !> The search is over.
        procedure :: done => golden_done
    end type golden_search_t

contains

    !> Start the search on [a, b] (either order); it stops when the bracket is narrower
    !> than tol (> 0). No errors.
    subroutine golden_begin(self, a, b, tol)
        !> The search.
        class(golden_search_t), intent(inout) :: self
        !> The interval.
        real(dp), intent(in) :: a, b
        !> Stopping width (same units as a and b).
        real(dp), intent(in) :: tol
        self%a = min(a, b)
        self%b = max(a, b)
        self%c = self%b - inv_phi*(self%b - self%a)
        self%d = self%a + inv_phi*(self%b - self%a)
        self%tol = tol
        self%stage = 0
        self%nfev = 0
    end subroutine golden_begin

    !> The abscissa whose value the search wants next (the bracket's middle once done).
    pure real(dp) function golden_next(self) result(x)
        !> The search.
        class(golden_search_t), intent(in) :: self
        select case (self%stage)
        case (0)
            x = self%c
        case (1, 2)
            x = merge(self%d, self%c, self%pending /= 1)
            if (self%stage == 1) x = self%d
        case default
            x = merge(self%c, self%d, self%fc >= self%fd)
        end select
    end function golden_next

    !> Tell the value at the abscissa golden_next gave (NaN counts as -infinity).
    subroutine golden_tell(self, f)
        !> The search.
        class(golden_search_t), intent(inout) :: self
        !> The function's value there.
        real(dp), intent(in) :: f
        real(dp) :: v
        v = f
        if (v /= v) v = -huge(1.0_dp)
        self%nfev = self%nfev + 1
        select case (self%stage)
        case (0)
            self%fc = v
            self%stage = 1
            return
        case (1)
            self%fd = v
        case (2)
            if (self%pending == 1) then
                self%fc = v
            else
                self%fd = v
            end if
        case default
            return
        end select
        ! shrink: keep the side of the larger value, one new inner point
        if (self%b - self%a <= self%tol) then
            self%stage = 3
            return
        end if
        if (self%fc >= self%fd) then
            self%b = self%d
            self%d = self%c
            self%fd = self%fc
            self%c = self%b - inv_phi*(self%b - self%a)
            self%pending = 1
        else
            self%a = self%c
            self%c = self%d
            self%fc = self%fd
            self%d = self%a + inv_phi*(self%b - self%a)
            self%pending = 2
        end if
        self%stage = 2
        if (self%b - self%a <= self%tol) self%stage = 3
    end subroutine golden_tell

    !> The search is over: golden_next gives the abscissa of the larger inner value.
    pure logical function golden_done(self)
        !> The search.
        class(golden_search_t), intent(in) :: self
        golden_done = self%stage == 3
    end function golden_done
end module stickslip_golden
