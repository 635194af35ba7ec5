!> Progress of a long run (a sweep, a study, a robustness study, the reading of a large
!> Matrix Market file): a hook the host passes to the loop, which calls `report` after each
!> point (each block read). Nothing is printed unless the host
!> gives a unit; then one line `stickslip: <what> <done>/<total> ..., <elapsed> s` on it once
!> `delay` seconds of wall time have passed since `start`, and at most once per `interval`
!> seconds. The library never prints behind its host's back: off by default (unit -1).
!> Long single steps (the phases of a model reduction: reading the matrices, factorizing,
!> the eigensolve, the error estimate, the cache) report themselves with `phase` once done,
!> one line `stickslip: <text> in <seconds> s` each, for the phases that took at least
!> `min_phase` seconds.
module stickslip_progress
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: progress_t

    !> Where and how often progress is printed.
    type :: progress_t
        !> Unit of the progress lines (-1: off; units from open(newunit=) are negative too).
        integer :: unit = -1
        !> What progresses, e.g. 'sweep' (the word after 'stickslip: ').
        character(len=:), allocatable :: label
        !> What is counted ('points' of a sweep or study, 'periods' of a time integration).
        character(len=:), allocatable :: items
        !> Wall time before the first line [s] (short runs print nothing).
        real(dp) :: delay = 2.0_dp
        !> Shortest wall time between two lines [s].
        real(dp) :: interval = 1.0_dp
        !> system_clock count at the start (-1: set by the first report).
        integer(int64) :: start = -1
        !> system_clock count of the last line (-1: none yet).
        integer(int64) :: last = -1
        !> Lines printed.
        integer :: lines = 0
        !> Shortest phase `phase` reports [s].
        real(dp) :: min_phase = 1.0_dp
    contains
        !> Start the clock now.
        procedure :: begin => progress_begin
        !> A point is done: print a line when it is time.
        procedure :: report => progress_report
        !> A phase is done: print a line when it took at least min_phase.
        procedure :: phase => progress_phase
        !> The same unit and pace for another loop, started now: `stage(label, items)`.
        procedure :: stage => progress_stage
    end type progress_t

contains

    !> Start the clock of `self` now (elapsed times are counted from here).
    subroutine progress_begin(self)
        !> The progress.
        class(progress_t), intent(inout) :: self
        call system_clock(self%start)
        self%last = -1
    end subroutine progress_begin

    !> A progress on the unit and with the pace of `self` for another loop (a stage of the
    !> run: the harmonics of a condensation, the stability of a curve's points), labelled
    !> `label`, counting `items`, its clock started now.
    function progress_stage(self, label, items) result(p)
        !> The host's progress.
        class(progress_t), intent(in) :: self
        !> What progresses and what is counted (e.g. 'stability', 'points').
        character(len=*), intent(in) :: label, items
        type(progress_t) :: p
        p = self
        p%label = label
        p%items = items
        p%lines = 0
        call p%begin()
    end function progress_stage

    !> `done` of `total` points are done (total <= 0: unknown); `text` describes the last
    !> one (e.g. 'omega = 2.35'). Prints `stickslip: <label> <done>/<total> points, <text>,
    !> <elapsed> s` when the unit is on, `delay` seconds have passed since the start and
    !> `interval` seconds since the last line.
    subroutine progress_report(self, done, total, text)
        !> The progress.
        class(progress_t), intent(inout) :: self
        !> Points done.
        integer, intent(in) :: done
        !> Points in all (<= 0 when not known in advance).
        integer, intent(in) :: total
        !> The last point, for a person.
        character(len=*), intent(in) :: text
        integer(int64) :: now, rate
        real(dp) :: elapsed
        character(len=32) :: count, seconds
        character(len=:), allocatable :: items
        if (self%unit == -1) return
        items = "points"
        if (allocated(self%items)) items = self%items
        call system_clock(now, rate)
        if (self%start < 0) self%start = now
        elapsed = real(now - self%start, dp)/real(max(rate, 1_int64), dp)
        if (elapsed < self%delay) return
        if (self%last >= 0) then
            if (real(now - self%last, dp) < self%interval*real(rate, dp)) return
        end if
        self%last = now
        if (total > 0) then
            write (count, '(i0,"/",i0)') done, total
        else
            write (count, '(i0)') done
        end if
        write (seconds, '(f0.1)') elapsed
        if (seconds(1:1) == '.') seconds = '0'//seconds(1:len(seconds) - 1)
        if (allocated(self%label)) then
            write (self%unit, '(a)') "stickslip: "//self%label//" "//trim(count)// &
                " "//items//", "//text//", "//trim(seconds)//" s"
        else
            write (self%unit, '(a)') "stickslip: progress "//trim(count)//" "//items//", "// &
                text//", "//trim(seconds)//" s"
        end if
        flush (self%unit)
        self%lines = self%lines + 1
    end subroutine progress_report

    !> A phase of `seconds` seconds of wall time is done: print `stickslip: <text> in
    !> <seconds> s` when the unit is on and seconds >= min_phase.
    subroutine progress_phase(self, text, seconds)
        !> The progress.
        class(progress_t), intent(inout) :: self
        !> What was done, for a person (e.g. 'reduction: K_ii factorized, 61081 DOFs').
        character(len=*), intent(in) :: text
        !> Its wall time [s].
        real(dp), intent(in) :: seconds
        character(len=32) :: buf
        if (self%unit == -1) return
        if (.not. (seconds >= self%min_phase)) return
        write (buf, '(f0.1)') seconds
        if (buf(1:1) == '.') buf = '0'//buf(1:len(buf) - 1)
        write (self%unit, '(a)') "stickslip: "//text//" in "//trim(buf)//" s"
        flush (self%unit)
        self%lines = self%lines + 1
    end subroutine progress_phase
end module stickslip_progress
