!> stickslip: periodic vibration of structures with Coulomb dry friction by the
!> equality-based weighted-residual method. The host API: what a structural code needs to
!> build a model in memory, call the methods and read their results. Case files, result
!> writers and the one dispatch of `&run method` are in `stickslip_io`; the command line is
!> not part of the library.
module stickslip
    ! core: kinds, errors, findings, progress, version
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, stickslip_stat
    use stickslip_diagnostics, only: diagnosis_t, diagnostics_t, level_note, level_warning, &
        level_untrusted
    use stickslip_progress, only: progress_t
    use stickslip_version_info, only: stickslip_version, stickslip_thread_safe
    use stickslip_blas_threads, only: blas_library, blas_thread_safe, limit_blas_threads, &
        blas_core_advice
    ! the model
    use stickslip_model, only: model_t, validate_model, contact_velocity_direction, &
        force_direction
    use stickslip_sparse, only: sparse_matrix_t, new_sparse_from_triplets, sparse_matvec, &
        sparse_to_dense, sparse_from_dense, sparse_transpose, sparse_scaled_sum, &
        sparse_symmetry_defect
    use stickslip_sparse_model, only: sparse_model_t, validate_sparse_model
    use stickslip_reduction, only: reduction_options_t, reduction_report_t, reduced_model_t, &
        craig_bampton, recover_dofs, receptance_error, reduced_dof_of, reduce_vectors, &
        reduction_estimate_t, estimate_reduction_error
    ! the weighted residual
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic, validate_options
    use stickslip_hbm_sparse, only: solve_periodic_sparse
    use stickslip_rho, only: automatic_rho
    ! implicit Euler
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    ! the exact reference and stability
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        sample_reference
    use stickslip_flow, only: event_name
    use stickslip_stability, only: floquet_t, periodic_stability, verify_periodicity
    use stickslip_wave_symmetry, only: wave_symmetry_t
    ! checks of a solution, comparisons
    use stickslip_reference_start, only: reference_start_options_t, solve_reference_from_starts
    use stickslip_checks, only: check_options_t, hbm_checks_t, solve_and_check
    use stickslip_truncation, only: truncation_t, estimate_truncation, solve_to_tolerance
    use stickslip_compare, only: comparison_t, compare_samples
    ! forced-response curves
    use stickslip_sweep, only: sweep_options_t, frc_point_t, sweep_result_t, sweep_observer_t, &
        run_sweep
    use stickslip_sweep_family, only: family_options_t, family_peak_t, family_result_t, &
        observer_slot_t, run_family, curve_peaks
    use stickslip_linear_response, only: limit_peak_t, linear_limit_peaks
    use stickslip_cyclic, only: cyclic_t, validate_cyclic, nodal_diameter, disk_dof, &
        assemble_disk, cyclic_frequencies, sector_phase
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic
    ! nonlinear modes
    use stickslip_modes, only: modes_options_t, mode_point_t, modes_result_t, run_modes
    use stickslip_linear_modes, only: linear_modes
    ! studies
    use stickslip_side_by_side, only: side_by_side_t, solve_side_by_side
    use stickslip_study, only: study_options_t, study_row_t, study_result_t, run_study, &
        default_study_options
    use stickslip_robustness, only: robustness_options_t, robustness_row_t, run_robustness, &
        default_robustness_options
    implicit none
    private
    public :: dp, error_type, stickslip_stat
    public :: diagnosis_t, diagnostics_t, level_note, level_warning, level_untrusted
    public :: progress_t, stickslip_version, stickslip_thread_safe, blas_library, &
        blas_thread_safe, limit_blas_threads, blas_core_advice
    public :: model_t, validate_model, contact_velocity_direction, force_direction
    public :: sparse_matrix_t, new_sparse_from_triplets, sparse_matvec, sparse_to_dense, &
              sparse_from_dense, sparse_transpose, sparse_scaled_sum, sparse_symmetry_defect
    public :: sparse_model_t, validate_sparse_model, solve_periodic_sparse
    public :: reduction_options_t, reduction_report_t, reduced_model_t, craig_bampton, &
              recover_dofs, receptance_error, reduced_dof_of, reduce_vectors, &
              reduction_estimate_t, estimate_reduction_error
    public :: hbm_options_t, hbm_solution_t, solve_periodic, validate_options, automatic_rho
    public :: euler_options_t, euler_result_t, integrate_euler
    public :: reference_options_t, reference_result_t, solve_reference, sample_reference, &
              reference_start_options_t, solve_reference_from_starts, event_name
    public :: floquet_t, periodic_stability, verify_periodicity, wave_symmetry_t
    public :: check_options_t, hbm_checks_t, solve_and_check
    public :: truncation_t, estimate_truncation, solve_to_tolerance
    public :: comparison_t, compare_samples
    public :: sweep_options_t, frc_point_t, sweep_result_t, sweep_observer_t, run_sweep
    public :: family_options_t, family_peak_t, family_result_t, observer_slot_t, run_family, &
        curve_peaks, limit_peak_t, linear_limit_peaks
    public :: cyclic_t, validate_cyclic, nodal_diameter, disk_dof, assemble_disk, &
        cyclic_frequencies, sector_phase, solve_periodic_cyclic
    public :: modes_options_t, mode_point_t, modes_result_t, run_modes, linear_modes
    public :: side_by_side_t, solve_side_by_side
    public :: study_options_t, study_row_t, study_result_t, run_study, default_study_options
    public :: robustness_options_t, robustness_row_t, run_robustness, default_robustness_options
end module stickslip
