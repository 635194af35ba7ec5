!> CPU time of the calling thread, for every run time stickslip reports (the summary's
!> hbm/euler/reference/stability/sweep CPU seconds, the studies' per-run times): runs share
!> the process with other OpenMP threads (the cases of a multi-case run, the points of a
!> study), and Fortran's cpu_time counts the whole process (with two threads busy it would
!> double every run's time). Linux/POSIX clock_gettime with CLOCK_THREAD_CPUTIME_ID; where
!> that clock is missing, cpu_time (the process) instead. Also `thread_nap`: the calling
!> thread waits a while without using the CPU (POSIX nanosleep), for a thread that waits
!> for work another one produces. Knows nothing of the methods.
module stickslip_thread_clock
    use, intrinsic :: iso_c_binding, only: c_int, c_long
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: thread_cpu_seconds, thread_nap

    !> struct timespec of Linux on 64-bit targets (time_t and long are both C long).
    type, bind(C) :: timespec_t
        integer(c_long) :: tv_sec = 0
        integer(c_long) :: tv_nsec = 0
    end type timespec_t

    !> Linux's clock id of the calling thread's CPU time.
    integer(c_int), parameter :: clock_thread_cputime_id = 3

    interface
        function clock_gettime(clock_id, tp) bind(C, name='clock_gettime') result(stat)
            import :: c_int, timespec_t
            integer(c_int), value :: clock_id
            type(timespec_t), intent(out) :: tp
            integer(c_int) :: stat
        end function clock_gettime
        function nanosleep(req, rem) bind(C, name='nanosleep') result(stat)
            import :: c_int, timespec_t
            type(timespec_t), intent(in) :: req
            type(timespec_t), intent(out) :: rem
            integer(c_int) :: stat
        end function nanosleep
    end interface

contains

    !> CPU seconds used so far by the calling thread [s] (differences of two calls time a
    !> run on this thread alone, whatever the other threads do).
    function thread_cpu_seconds() result(seconds)
        real(dp) :: seconds
        type(timespec_t) :: ts
        if (clock_gettime(clock_thread_cputime_id, ts) == 0) then
            seconds = real(ts%tv_sec, dp) + 1.0e-9_dp*real(ts%tv_nsec, dp)
        else
            call cpu_time(seconds)
        end if
    end function thread_cpu_seconds

    !> Wait `seconds` [s] (0 to 1; an interrupted wait ends early) without using the CPU.
    subroutine thread_nap(seconds)
        real(dp), intent(in) :: seconds
        type(timespec_t) :: req, rem
        integer(c_int) :: stat
        req%tv_sec = 0
        req%tv_nsec = int(min(max(seconds, 0.0_dp), 0.999_dp)*1.0e9_dp, c_long)
        stat = nanosleep(req, rem)
    end subroutine thread_nap
end module stickslip_thread_clock
