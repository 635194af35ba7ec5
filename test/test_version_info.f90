!> stickslip_version_info: the version constant agrees with fpm.toml, and
!> stickslip_thread_safe() answers what the build did (the OpenMP suite checks the same against
!> the tests' own build).
module test_version_info
    use stickslip_version_info, only: stickslip_version, stickslip_thread_safe
    use testing, only: test_counter_t, check
    use fixtures, only: project_path
    implicit none
    private
    public :: run_version_info_tests

contains

    subroutine run_version_info_tests(t)
        type(test_counter_t), intent(inout) :: t
        character(len=512) :: line
        character(len=:), allocatable :: manifest
        integer :: u, stat, k
        logical :: found, openmp
        manifest = project_path("fpm.toml")
        found = .false.
        open (newunit=u, file=manifest, status='old', action='read', iostat=stat)
        call check(t, stat == 0, "version: fpm.toml found from any directory", manifest)
        if (stat /= 0) return
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            line = adjustl(line)
            if (line(1:7) /= "version") cycle
            k = index(line, '"')
            found = line(k + 1:k + len(stickslip_version) + 1) == stickslip_version//'"'
            exit
        end do
        close (u)
        call check(t, found, "version: stickslip_version "//stickslip_version// &
                   " is fpm.toml's version", trim(line))
        openmp = .false.
        !$ openmp = .true.
        call check(t, stickslip_thread_safe() .eqv. openmp, "version: stickslip_thread_safe()")
    end subroutine run_version_info_tests
end module test_version_info
