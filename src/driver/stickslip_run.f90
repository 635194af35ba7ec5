!> Compatibility name of the runs of one method each (run_case, run_euler_case, ...), which
!> live in stickslip_driver beside run_method, the one dispatch of &run method. New code
!> uses stickslip_driver.
module stickslip_run
    use stickslip_driver, only: run_case, run_euler_case, run_reference_case, &
        run_side_by_side_case, run_study_case, run_sweep_case, run_robustness_case
    implicit none
    private
    public :: run_case, run_euler_case, run_reference_case, run_side_by_side_case
    public :: run_study_case, run_sweep_case, run_robustness_case
end module stickslip_run
