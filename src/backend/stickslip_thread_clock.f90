!> CPU time of the calling thread, for every run time stickslip reports (the summary's
!> hbm/euler/reference/stability/sweep CPU seconds, the studies' per-run times): runs share
!> the process with other OpenMP threads (the cases of a multi-case run, the points of a
!> study), and Fortran's cpu_time counts the whole process (with two threads busy it would
!> double every run's time). Linux/POSIX clock_gettime with CLOCK_THREAD_CPUTIME_ID; where
!> that clock is missing, cpu_time (the process) instead. Knows nothing of the methods.
module stickslip_thread_clock
    use, intrinsic :: iso_c_binding, only: c_int, c_long
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: thread_cpu_seconds

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
end module stickslip_thread_clock
