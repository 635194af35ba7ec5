!> stickslip_io: case files and result files, for a host that works with them. A case file
!> (namelist groups) is read into a `case_t` (the model plus every method's options);
!> `run_method` runs the method the case names (the one dispatch of `&run method`) and
!> writes its files atomically into the case's output directory under a lock; the writers
!> are also callable one by one. The numerics without files are in the umbrella `stickslip`.
module stickslip_io
    use stickslip_case, only: case_t, read_case, write_case, sweep_run_options_t, selected_dofs, &
        default_output_dofs
    use stickslip_driver, only: run_result_t, run_method, method_names, run_case, &
        run_euler_case, run_reference_case, run_side_by_side_case, run_study_case, &
        run_sweep_case, run_robustness_case
    use stickslip_files, only: make_directory
    use stickslip_case_reduction, only: write_reduction_cache_of
    use stickslip_csv, only: write_hbm_csv, write_coefficients_csv, write_samples_csv, &
        write_events_csv, write_study_csv, write_frc_csv, write_robustness_csv
    use stickslip_summary, only: write_summary, write_euler_summary, write_reference_summary, &
        write_side_by_side_summary, write_study_summary, write_sweep_summary, &
        write_robustness_summary, energy_balance_error, reference_balance_error
    use stickslip_plot_scripts, only: write_frc_plot_script, write_robustness_plot_script
    use stickslip_checkpoint, only: checkpoint_writer_t, read_checkpoint, case_fingerprint
    use stickslip_error, only: exit_code_of
    use stickslip_matrix_market, only: read_matrix_market, write_matrix_market, &
        write_matrix_market_array
    implicit none
    private
    public :: case_t, read_case, write_case, sweep_run_options_t, selected_dofs, &
              default_output_dofs
    public :: run_result_t, run_method, method_names, run_case, run_euler_case, &
              run_reference_case, run_side_by_side_case, run_study_case, run_sweep_case, &
              run_robustness_case, exit_code_of
    public :: write_reduction_cache_of
    public :: make_directory, write_hbm_csv, write_coefficients_csv, write_samples_csv, &
              write_events_csv, write_study_csv, write_frc_csv, write_robustness_csv
    public :: write_summary, write_euler_summary, write_reference_summary, &
              write_side_by_side_summary, write_study_summary, write_sweep_summary, &
              write_robustness_summary, energy_balance_error, reference_balance_error
    public :: write_frc_plot_script, write_robustness_plot_script
    public :: checkpoint_writer_t, read_checkpoint, case_fingerprint
    public :: read_matrix_market, write_matrix_market, write_matrix_market_array
end module stickslip_io
