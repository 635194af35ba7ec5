!> The findings (diagnostics) of a run of a case, gathered from its result and its parts
!> into one list: what summary.nml reports (trusted, warnings) and run_result_t holds for
!> the caller. A finding whose key is already in the list is not added again; the findings
!> of the parts of a side-by-side run or of a study's reference have their keys prefixed
!> (hbm_, euler_, reference_).
module stickslip_run_findings
    use stickslip_diagnostics, only: diagnostics_t
    use stickslip_solution, only: hbm_solution_t
    use stickslip_checks, only: hbm_checks_t
    use stickslip_side_by_side, only: side_by_side_t
    use stickslip_study, only: study_result_t
    implicit none
    private
    public :: hbm_findings, side_by_side_findings, study_findings, add_new

contains

    !> The findings of a weighted-residual solution and of its checks.
    function hbm_findings(sol, checks) result(found)
        !> The solution.
        type(hbm_solution_t), intent(in) :: sol
        !> Its checks.
        type(hbm_checks_t), intent(in) :: checks
        type(diagnostics_t) :: found
        call add_new(found, sol%diagnostics)
        call add_new(found, checks%diagnostics)
    end function hbm_findings

    !> The findings of the three methods side by side (keys prefixed hbm_, euler_,
    !> reference_) and of their comparison.
    function side_by_side_findings(res) result(found)
        !> The three solutions.
        type(side_by_side_t), intent(in) :: res
        type(diagnostics_t) :: found
        call add_new(found, res%diagnostics)
        call add_new(found, res%hbm%diagnostics, 'hbm_')
        call add_new(found, res%euler%diagnostics, 'euler_')
        call add_new(found, res%reference%diagnostics, 'reference_')
    end function side_by_side_findings

    !> The findings of a study and of its reference (keys prefixed reference_).
    function study_findings(res) result(found)
        !> The study.
        type(study_result_t), intent(in) :: res
        type(diagnostics_t) :: found
        call add_new(found, res%diagnostics)
        call add_new(found, res%reference%diagnostics, 'reference_')
    end function study_findings

    !> Append the findings of `other` (keys prefixed) whose key is not in `found` yet.
    subroutine add_new(found, other, prefix)
        !> The findings gathered so far, appended to.
        type(diagnostics_t), intent(inout) :: found
        !> The findings to add.
        type(diagnostics_t), intent(in) :: other
        !> Put before the keys of `other` (optional; e.g. 'hbm_').
        character(len=*), intent(in), optional :: prefix
        integer :: k
        if (.not. allocated(other%items)) return
        do k = 1, size(other%items)
            associate (item => other%items(k))
                if (present(prefix)) then
                    if (found%has(prefix//item%key) .or. found%has(item%key)) cycle
                    call found%add(item%level, prefix//item%key, item%message)
                else
                    if (found%has(item%key)) cycle
                    call found%add(item%level, item%key, item%message)
                end if
            end associate
        end do
    end subroutine add_new
end module stickslip_run_findings
