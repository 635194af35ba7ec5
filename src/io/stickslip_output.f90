!> Compatibility facade over the writers of result files, which live in modules of one
!> concept each: stickslip_files (directories, atomic writes, stale results, the directory
!> lock), stickslip_csv (the CSV files), stickslip_summary (summary.nml) and
!> stickslip_plot_scripts (frc.gp, robustness.gp). New code uses those modules directly;
!> this one only re-exports their names for code written against the former single module.
module stickslip_output
    use stickslip_files, only: make_directory, open_temporary, close_and_rename
    use stickslip_csv, only: write_hbm_csv, write_samples_csv, write_coefficients_csv, &
        write_events_csv, write_study_csv, write_frc_csv, write_robustness_csv, real_fmt
    use stickslip_summary, only: write_summary, write_euler_summary, &
        write_reference_summary, write_side_by_side_summary, write_study_summary, &
        write_sweep_summary, write_robustness_summary, energy_balance_error, &
        reference_balance_error
    use stickslip_plot_scripts, only: write_frc_plot_script, write_robustness_plot_script
    implicit none
    private
    public :: make_directory, write_hbm_csv, write_samples_csv, write_coefficients_csv, &
              write_summary, write_euler_summary, energy_balance_error
    public :: write_events_csv, write_reference_summary, write_side_by_side_summary
    public :: write_study_csv, write_study_summary, reference_balance_error
    public :: open_temporary, close_and_rename, real_fmt
    public :: write_frc_csv, write_sweep_summary, write_frc_plot_script
    public :: write_robustness_csv, write_robustness_summary, write_robustness_plot_script
end module stickslip_output
