!> Folds and retraces of a forced-response curve. A turn back in the parameter (a sign
!> change of the tangent's parameter component) is a fold, or a kink of the sampled friction
!> equations where the corrector came back onto the branch already traced: then the points
!> after the turn retrace the earlier ones. After max_retrace_hits of them in a row the
!> sweep returns to the last point before the turn and steps the parameter past it.
module stickslip_sweep_retrace
    use stickslip_kinds, only: dp
    use stickslip_error, only: real_text
    use stickslip_diagnostics, only: level_note
    use stickslip_continuation, only: continuation_state_t, reason_end
    use stickslip_sweep_result, only: frc_point_t, sweep_result_t
    implicit none
    private
    public :: fold_watch_t, new_fold_watch

    !> Points in a row after a turn back that must retrace the curve before the sweep takes
    !> the turn for a kink (not a fold) and steps past it; at most max_retrace_jumps times.
    integer, parameter :: max_retrace_hits = 3, max_retrace_jumps = 5
    !> Relative amplitude agreement that makes a point lie on the curve already traced.
    real(dp), parameter :: retrace_tolerance = 1.0e-3_dp

    !> What a sweep remembers of its last turn back: the direction of the range, the state
    !> before the turn and how many points since retraced the curve.
    type :: fold_watch_t
        !> The direction of the range: sign(1, stop - start).
        real(dp) :: dir = 1.0_dp
        !> The curve turned back against `dir` and has not been stepped past the turn.
        logical :: turned = .false.
        !> Points of the curve before the turn, points in a row since that retrace it, and
        !> steps past a turn so far (at most max_retrace_jumps).
        integer :: turn_points = 0, retrace_hits = 0, jumps = 0
        !> The continuation state before the turn.
        type(continuation_state_t) :: before_turn
    contains
        procedure :: accepted => watch_accepted
        procedure :: check_retrace => watch_check_retrace
    end type fold_watch_t

contains

    !> A watch for a sweep from `start` to `stop` (no turn yet).
    pure subroutine new_fold_watch(watch, start, stop)
        !> The watch.
        type(fold_watch_t), intent(out) :: watch
        !> The range of the parameter, from start to stop [parameter units].
        real(dp), intent(in) :: start, stop
        watch%dir = sign(1.0_dp, stop - start)
        watch%turned = .false.
        watch%turn_points = 0
        watch%retrace_hits = 0
        watch%jumps = 0
    end subroutine new_fold_watch

    !> After an accepted step from `before` to res%state, before its point is added: a sign
    !> change of the parameter's tangent component is a fold (res%folds + 1); a turn against
    !> the range's direction is remembered (the state before it, the points so far).
    subroutine watch_accepted(self, before, res)
        !> The watch.
        class(fold_watch_t), intent(inout) :: self
        !> The continuation state before the step.
        type(continuation_state_t), intent(in) :: before
        !> The curve, its state after the step.
        type(sweep_result_t), intent(inout) :: res
        if (before%tl*res%state%tl < 0.0_dp) then
            res%folds = res%folds + 1
            self%turned = before%tl*self%dir > 0.0_dp
            if (self%turned) then
                self%before_turn = before
                self%turn_points = res%npoints
                self%retrace_hits = 0
            end if
        end if
    end subroutine watch_accepted

    !> After the point of an accepted step is added: when the curve turned back, count
    !> whether the point retraces the curve before the turn; after max_retrace_hits in a row
    !> the turn is a kink, not a fold: res%state goes back before the turn with a parameter
    !> step past it (twice the step there, at most `max_step`), the fold is uncounted and a
    !> note 'retrace' added to res%diagnostics.
    subroutine watch_check_retrace(self, res, max_step, parameter)
        !> The watch.
        class(fold_watch_t), intent(inout) :: self
        !> The curve, its last point just added.
        type(sweep_result_t), intent(inout) :: res
        !> The largest continuation step [parameter units].
        real(dp), intent(in) :: max_step
        !> The swept parameter's name (for the note).
        character(len=*), intent(in) :: parameter
        if (self%turned .and. self%jumps < max_retrace_jumps .and. &
            res%state%reason /= reason_end) then
            if (retraces(res%points(res%npoints), res%points(1:self%turn_points))) then
                self%retrace_hits = self%retrace_hits + 1
            else
                self%retrace_hits = 0
            end if
            if (self%retrace_hits >= max_retrace_hits) then
                ! not a fold: back before the turn, a parameter step past it
                res%state = self%before_turn
                res%state%ty = 0.0_dp
                res%state%tl = self%dir
                res%state%ds = min(2.0_dp*self%before_turn%ds, max_step)
                res%state%points = res%npoints
                res%folds = res%folds - 1
                self%jumps = self%jumps + 1
                self%turned = .false.
                call res%diagnostics%add(level_note, "retrace", "sweep: the curve "// &
                    "turned back at "//trim(parameter)//" = "// &
                    real_text(self%before_turn%lambda)//" and retraced itself (a kink of the "// &
                    "sampled friction equations, not a fold): continued past it by "// &
                    "a parameter step")
            end if
        end if
    end subroutine watch_check_retrace

    !> Whether point p lies on the curve of the points `earlier` (in continuation order):
    !> some pair of consecutive earlier points brackets p's parameter and their amplitudes,
    !> interpolated linearly, agree with p's, each to retrace_tolerance of its own size (at
    !> least 1e-3 of the largest amplitude): the two sides of a fold may agree on the large
    !> amplitudes and differ on a small one (the normal motion of a contact that lifts off).
    pure logical function retraces(p, earlier)
        !> The point [parameter units, m].
        type(frc_point_t), intent(in) :: p
        !> The curve before it.
        type(frc_point_t), intent(in) :: earlier(:)
        integer :: k
        real(dp) :: w, scale
        real(dp), allocatable :: q(:)
        retraces = .false.
        do k = 1, size(earlier) - 1
            associate (a => earlier(k), b => earlier(k + 1))
                if ((p%parameter - a%parameter)*(p%parameter - b%parameter) > 0.0_dp) cycle
                if (a%parameter == b%parameter) cycle
                if (size(a%amplitude) /= size(p%amplitude) .or. &
                    size(b%amplitude) /= size(p%amplitude)) cycle
                w = (p%parameter - a%parameter)/(b%parameter - a%parameter)
                scale = max(maxval(abs(a%amplitude)), maxval(abs(b%amplitude)), tiny(1.0_dp))
                q = (1.0_dp - w)*a%amplitude + w*b%amplitude
                if (all(abs(p%amplitude - q) <= &
                        retrace_tolerance*max(abs(q), 1.0e-3_dp*scale))) then
                    retraces = .true.
                    return
                end if
            end associate
        end do
    end function retraces
end module stickslip_sweep_retrace
