!> stickslip: periodic vibration of structures with Coulomb dry friction by the
!> equality-based weighted-residual method. The one module a host code needs.
module stickslip
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, exit_code_of
    use stickslip_model, only: model_t, validate_model
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options
    use stickslip_case, only: case_t, read_case, write_case
    use stickslip_output, only: make_directory, write_hbm_csv, write_coefficients_csv, &
        write_summary, energy_balance_error, write_samples_csv, write_euler_summary, &
        write_events_csv, write_reference_summary, write_side_by_side_summary, &
        write_study_csv, write_study_summary, reference_balance_error
    use stickslip_run, only: run_case, run_euler_case, run_reference_case, &
        run_side_by_side_case, run_study_case
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference
    use stickslip_flow, only: event_stick, event_slip, event_reversal, event_graze, event_name
    use stickslip_compare, only: comparison_t, compare_samples, evaluate_series, quantity_names
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side
    use stickslip_study, only: study_options_t, study_row_t, study_result_t, run_study, &
        default_study_options
    use stickslip_cli, only: string_t, run_cli, stickslip_version
    implicit none
    private
    public :: dp, error_type, fatal_error, stickslip_stat, exit_code_of
    public :: model_t, validate_model, hbm_options_t, hbm_solution_t
    public :: solve_periodic, validate_options
    public :: case_t, read_case, write_case, run_case, run_euler_case
    public :: euler_options_t, euler_result_t, integrate_euler
    public :: reference_options_t, reference_result_t, solve_reference, sample_reference
    public :: event_stick, event_slip, event_reversal, event_graze, event_name
    public :: comparison_t, compare_samples, evaluate_series, quantity_names
    public :: side_by_side_t, solve_side_by_side
    public :: study_options_t, study_row_t, study_result_t, run_study, default_study_options
    public :: run_reference_case, run_side_by_side_case, run_study_case
    public :: write_events_csv, write_reference_summary, write_side_by_side_summary, &
              write_study_csv, write_study_summary, reference_balance_error
    public :: make_directory, write_hbm_csv, write_coefficients_csv, write_summary, &
              energy_balance_error, write_samples_csv, write_euler_summary
    public :: string_t, run_cli, stickslip_version
end module stickslip
