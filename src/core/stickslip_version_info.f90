!> What a host code may ask of the library it linked: its version and whether it is safe to call
!> from several threads at once.
!>
!> The nonlinear solver reaches the system being solved through one module-level slot
!> (src/backend/stickslip_minpack.f90). That slot is `threadprivate` only when the library is
!> compiled with OpenMP (`fpm build --flag -fopenmp`, or `-fopenmp` in the host's build of the
!> sources): then each thread has its own, and the methods may be called from several threads
!> at once (one model, options and result per thread; the FFTW planner calls are serialized in
!> src/backend/stickslip_fft.f90). Without
!> OpenMP the slot is shared: the library is re-entrant but must be called from one thread at a
!> time. `stickslip_thread_safe()` tells which build the host linked.
module stickslip_version_info
    implicit none
    private
    public :: stickslip_version, stickslip_thread_safe

    !> The library's version (the `version` of fpm.toml; the tests check they agree).
    character(len=*), parameter :: stickslip_version = "0.1.0"

contains

    !> True when the library was compiled with OpenMP, so that its solvers may be called from
    !> several OpenMP threads at once; false for a serial build (then call it from one thread
    !> at a time). Decided at compile time through the `!$` conditional-compilation sentinel.
    pure logical function stickslip_thread_safe()
        stickslip_thread_safe = .false.
        !$ stickslip_thread_safe = .true.
    end function stickslip_thread_safe
end module stickslip_version_info
