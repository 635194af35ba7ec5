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
        run_side_by_side_case, run_study_case, run_sweep_case
    use stickslip_output, only: write_frc_csv, write_sweep_summary, write_frc_plot_script
    use stickslip_continuation, only: parametric_system_t, continuation_options_t, &
        continuation_state_t, continuation_report_t, start_continuation, continuation_step
    use stickslip_sweep, only: sweep_options_t, frc_point_t, sweep_result_t, sweep_observer_t, &
        run_sweep, friction_family_t, new_friction_family, set_sweep_parameter
    use stickslip_checkpoint, only: checkpoint_writer_t, read_checkpoint, case_fingerprint
    use stickslip_stability, only: floquet_t, floquet_multipliers, periodic_stability, &
        verify_periodicity
    use stickslip_truncation, only: truncation_t, estimate_truncation, solve_to_tolerance
    use stickslip_checks, only: hbm_checks_t, solve_and_check
    use stickslip_rho, only: automatic_rho
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference
    use stickslip_flow, only: event_stick, event_slip, event_reversal, event_graze, event_name
    use stickslip_compare, only: comparison_t, compare_samples, evaluate_series, quantity_names
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side
    use stickslip_study, only: study_options_t, study_row_t, study_result_t, run_study, &
        default_study_options
    use stickslip_version_info, only: stickslip_thread_safe
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
    public :: stickslip_thread_safe
    public :: run_sweep_case, write_frc_csv, write_sweep_summary, write_frc_plot_script
    public :: parametric_system_t, continuation_options_t, continuation_state_t, &
              continuation_report_t, start_continuation, continuation_step
    public :: sweep_options_t, frc_point_t, sweep_result_t, sweep_observer_t, run_sweep, &
              friction_family_t, new_friction_family, set_sweep_parameter
    public :: checkpoint_writer_t, read_checkpoint, case_fingerprint
    public :: floquet_t, floquet_multipliers, periodic_stability, verify_periodicity
    public :: truncation_t, estimate_truncation, solve_to_tolerance
    public :: hbm_checks_t, solve_and_check, automatic_rho
end module stickslip
