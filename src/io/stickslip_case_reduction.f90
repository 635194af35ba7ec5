!> The &reduction group of a case file and the reduction of a model read from Matrix Market
!> files (stickslip_reduction, Craig-Bampton) to the small dense model_t every method runs on.
!>
!> &reduction method = 'auto' (default) | 'craig-bampton' | 'none', modes = 0,
!> max_frequency = 0 [rad/s], damping_ratio = 0. 'auto' reduces a model from files with
!> N > max_file_dof (2000) DOFs and keeps smaller ones unreduced; 'none' keeps the full model
!> (dense, so N <= 2000 for now). Boundary DOFs = every contact DOF (contact_dof, contact_dof2
!> > 0, or every DOF where a column of the &friction direction_file matrix W is nonzero) and
!> every forced DOF (force_dof), and the &output dofs when given; the reduced model numbers them 1..nb in ascending order of
!> their full-model numbers, then the nm fixed-interface modes, then the nl static
!> load-correction vectors of a &forcing force_file F (one per column with a nonzero
!> interior part, see stickslip_reduction; its DOFs are NOT boundary DOFs). The contact and
!> force DOF numbers of the case's model_t are remapped to that numbering (the full-model
!> numbers are kept in reduction_case_t for the echo); directions become W_r = T^T W (the
!> boundary rows of W) and load shapes F_r = T^T F, so the reduced model's static response
!> to F is the full one. The result files hold the &output dofs, given in
!> FULL-model numbers (default: the contact and forced DOFs; given ones are boundary DOFs):
!> reduce_case_model keeps the rows of the basis T for them (output_rows, nsel x nr; never the
!> whole basis) and recover_outputs gives their values from reduced samples or coefficients,
!> x_full = T(dof, :) q (for boundary DOFs a unit row).
!> modes = 0 chooses the mode count by the rule of stickslip_reduction: every fixed-interface
!> mode below 3 x the highest harmonic frequency of the run, H_max omega_max, with H_max the
!> larger of &hbm harmonics and the forcing harmonics and omega_max the larger of &forcing
!> omega and, for a sweep over omega, its start and stop; max_frequency > 0 overrides.
!> The measured reduction error is taken at error_frequencies: 1, 3 and 5 times the forcing
!> harmonics' frequencies (sweep ends for a sweep over omega), at most 8, by
!> estimate_reduction_error (stickslip_reduction_estimate: an enriched Galerkin model on the
!> factorization of K_ii the reduction made, the exact complex sparse LU of the full model
!> only when its levels disagree); error_estimate = .false. skips it (reduction_error -1).
!>
!> The reduction cache (&reduction cache = 'auto', the default: the file reduction.cache in
!> the &output directory; 'off'; or a file path): the reduced model, its basis and its
!> report, keyed on a 64-bit FNV-1a hash of the bytes of the matrix files and of every
!> input that changes the reduction or its error estimate (cache_key). A run whose key
!> matches reads the model from the file and does not even read the matrix files; a file
!> of another key is replaced silently, a damaged one with a warning; the file is written
!> (atomically: a temporary, then renamed) by write_reduction_cache_of, which the command
!> line calls once read_case has read and validated the whole case (read_case writes
!> nothing: an input error found there writes no cache). Module stickslip_reduction_cache
!> owns the file format.
module stickslip_case_reduction
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t
    use stickslip_cyclic, only: cyclic_t
    use stickslip_cyclic_interface, only: face_reduction_t, reduce_cyclic_faces
    use stickslip_diagnostics, only: diagnostics_t, level_warning, level_note
    use stickslip_namelist, only: nml_file_t
    use stickslip_namelist_values, only: check_names, get_integer, get_real, get_string, &
        get_logical
    use stickslip_case_model, only: group_error, sparse_system_t, system_files_t, &
        load_sparse_system
    use stickslip_reduction, only: reduction_options_t, reduction_report_t, reduced_model_t, &
        craig_bampton, reduced_dof_of, recover_dofs, reduce_vectors, reduction_estimate_t, &
        estimate_reduction_error
    use stickslip_sparse_factor, only: sparse_factor_t
    use stickslip_progress, only: progress_t
    use stickslip_hash, only: hash_t
    use stickslip_version_info, only: stickslip_version
    use stickslip_files, only: make_directory
    use stickslip_reduction_cache, only: hash_file, write_reduction_cache, read_reduction_cache, &
        cache_hit, cache_absent, cache_stale, cache_damaged, cache_foreign
    implicit none
    private
    !> Measured reduction error above which the reduction is reported (warning
    !> 'reduction_error'): the reduced contact receptance is off by more than 5 %.
    real(dp), parameter, public :: reduction_error_warning = 0.05_dp

    public :: reduction_case_t, read_reduction_group, reduce_case_model, recover_outputs, &
        recover_full_field, error_frequencies, write_reduction_cache_of, reduce_case_faces
    !> File name of the default cache (&reduction cache = 'auto') in the output directory.
    character(len=*), parameter, public :: default_cache_name = "reduction.cache"

    !> The &reduction group as read, what the reduction did, and the full-model DOF numbers.
    type :: reduction_case_t
        !> 'auto', 'craig-bampton' or 'none'.
        character(len=16) :: method = 'auto'
        !> Fixed-interface modes (0: the rule).
        integer :: modes = 0
        !> Frequency limit of the rule [rad/s] (0: 3 H omega).
        real(dp) :: max_frequency = 0.0_dp
        !> Modal damping ratio of the fixed-interface modes.
        real(dp) :: damping_ratio = 0.0_dp
        !> Measure the reduction error (&reduction error_estimate).
        logical :: error_estimate = .true.
        !> Interface modes per cyclic face of a sector (&reduction interface_modes; 0: every
        !> face DOF kept).
        integer :: interface_modes = 0
        !> With interface_modes: what the faces' reduction did and its transformation
        !> (reduce_case_faces; stickslip_cyclic_interface).
        type(face_reduction_t), allocatable :: faces
        !> &reduction cache as given: 'auto' (reduction.cache in the output directory),
        !> 'off', or the path of the cache file.
        character(len=:), allocatable :: cache
        !> The cache file used ('' when off).
        character(len=:), allocatable :: cache_path
        !> What became of the cache: 'off', 'hit' (the model was read from it), 'written'
        !> (made or replaced by this run), 'not written' (the write failed: a warning),
        !> 'pending' (to be written by write_reduction_cache_of).
        character(len=16) :: cache_status = 'off'
        !> Wall time of reading the matrix files [s] (0 on a cache hit).
        real(dp) :: read_seconds = 0.0_dp
        !> Wall time of hashing the inputs and reading or writing the cache [s].
        real(dp) :: cache_seconds = 0.0_dp
        !> The key of this run's inputs and, while the cache is pending, the model to write.
        integer(int64) :: cache_key = 0
        type(reduced_model_t), allocatable :: cache_model
        !> What the reduction did (method 'none' when the model was not reduced).
        type(reduction_report_t) :: report
        !> The model's contact_dof, contact_dof2, force_dof in FULL-model numbering (allocated
        !> only when the model was reduced; write_case echoes these).
        integer, allocatable :: contact_dof(:), contact_dof2(:), force_dof(:)
        !> The &output dofs (full numbers) and, for each, its reduced DOF (0: an interior DOF)
        !> and its row of the basis T (output_rows(k, :), size nr), allocated only when the
        !> model was reduced.
        integer, allocatable :: output_dofs(:), output_reduced(:)
        real(dp), allocatable :: output_rows(:, :)
        !> What the checks of the reduction found (warnings 'reduction_capped': the mode-count
        !> rule stopped at its cap; 'reduction_error': the measured error above
        !> reduction_error_warning); the summary and the CLI report them with every method.
        type(diagnostics_t) :: diagnostics
        !> Keep the whole reduction basis (set by read_case for &output full_field).
        logical :: keep_basis = .false.
        !> The reduction basis T (its reduced matrices dropped), allocated only when the model
        !> was reduced with keep_basis: recover_full_field reads it.
        type(reduced_model_t), allocatable :: basis
    end type reduction_case_t

contains

    !> Read &reduction (optional). Errors (stat input) name the variable: an unknown method,
    !> a negative modes, max_frequency or damping_ratio.
    subroutine read_reduction_group(nml, red, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The options read (defaults when the group is absent).
        type(reduction_case_t), intent(out) :: red
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: method
        character(len=*), parameter :: g = "reduction"
        type(reduction_options_t), parameter :: defaults = reduction_options_t()
        call check_names(nml, g, [character(len=16) :: "method", "modes", "max_frequency", &
                                 "damping_ratio", "error_estimate", "cache", &
                                 "interface_modes"], error)
        if (allocated(error)) return
        method = trim(red%method)
        call get_string(nml, g, "method", method, error)
        if (allocated(error)) return
        select case (trim(method))
        case ('auto', 'craig-bampton', 'none')
            red%method = trim(method)
        case default
            call group_error(nml, error, "&reduction method = '"//trim(method)//"': must be "// &
                             "'auto', 'craig-bampton' or 'none'")
            return
        end select
        call get_integer(nml, g, "modes", red%modes, error)
        if (allocated(error)) return
        if (red%modes < 0) then
            call group_error(nml, error, "&reduction modes = "//itoa(red%modes)//": must be "// &
                             ">= 0 (0: all fixed-interface modes below 3 H omega)")
            return
        end if
        if (red%modes > defaults%max_modes) then
            call group_error(nml, error, "&reduction modes = "//itoa(red%modes)//": must be "// &
                             "<= "//itoa(defaults%max_modes)//" (the most "// &
                             "fixed-interface modes a reduction keeps: the reduced model is "// &
                             "dense)")
            return
        end if
        call get_real(nml, g, "max_frequency", red%max_frequency, error)
        if (allocated(error)) return
        if (.not. (red%max_frequency >= 0.0_dp)) then
            call group_error(nml, error, "&reduction max_frequency: must be >= 0 [rad/s]")
            return
        end if
        call get_real(nml, g, "damping_ratio", red%damping_ratio, error)
        if (allocated(error)) return
        if (.not. (red%damping_ratio >= 0.0_dp .and. red%damping_ratio < 1.0_dp)) then
            call group_error(nml, error, "&reduction damping_ratio: must be in [0, 1)")
            return
        end if
        call get_logical(nml, g, "error_estimate", red%error_estimate, error)
        if (allocated(error)) return
        call get_integer(nml, g, "interface_modes", red%interface_modes, error)
        if (allocated(error)) return
        if (red%interface_modes < 0) then
            call group_error(nml, error, "&reduction interface_modes = "// &
                             itoa(red%interface_modes)//": must be >= 0 (0: every DOF of a "// &
                             "sector's cyclic faces kept)")
            return
        end if
        red%cache = 'auto'
        call get_string(nml, g, "cache", red%cache, error)
        if (allocated(error)) return
        red%cache = trim(red%cache)
        if (len(red%cache) == 0) then
            call group_error(nml, error, "&reduction cache = '': must be 'auto' (the file "// &
                             default_cache_name//" in the &output directory), 'off' or the "// &
                             "path of the cache file")
            return
        end if
        if (red%cache(len(red%cache):) == '/') then
            call group_error(nml, error, "&reduction cache = '"//red%cache//"': a file "// &
                             "path, not a directory (ends in '/')")
            return
        end if
    end subroutine read_reduction_group

    !> Reduce the sparse model `sparse` (read by read_system_group, its entries read here when
    !> needed) to the dense `model`: boundary = contact DOFs (of the DOF lists or of the
    !> directions W) and forced DOFs (force_dof), remapped; W and the load shapes F of a
    !> force_file projected (T^T W, T^T F; F adds load vectors to the basis); report and
    !> error estimate in red%report. With the cache on (red%cache not 'off'), a cache file
    !> whose key matches gives the reduced model instead (the matrix files are then not
    !> read); otherwise the model reduced here waits in red%cache_model for
    !> write_reduction_cache_of. `harmonics` is &hbm harmonics. Errors (input): a contact or
    !> force DOF outside 1..N (named), no boundary DOF (e.g. a force_file without contacts);
    !> (numerical): the reduction failing; (io): a matrix file that cannot be read; all
    !> start "<path>: ". `output_dofs` (full numbers, checked in 1..N by the caller) are the
    !> DOFs the result files hold; not `output_given`: set here to the contact and forced
    !> DOFs. `directory` is the &output directory (the default cache's folder); `progress`
    !> reports the phases that take a second or more.
    subroutine reduce_case_model(nml, red, sparse, files, harmonics, model, output_dofs, &
                                 output_given, directory, error, progress, keep_dofs)
        !> The parsed case file (its path, and &sweep for the frequency range).
        type(nml_file_t), intent(in) :: nml
        !> The options; on return the report and the full-model DOF numbers.
        type(reduction_case_t), intent(inout) :: red
        !> The full sparse matrices (read here when not yet loaded and needed).
        type(sparse_system_t), intent(inout) :: sparse
        !> The matrix files and Rayleigh factors of &system.
        type(system_files_t), intent(in) :: files
        !> &hbm harmonics.
        integer, intent(in) :: harmonics
        !> In: ndof = N, contacts and forcing in full numbering; out: the reduced dense model.
        type(model_t), intent(inout) :: model
        !> &output dofs in full numbers; the default selection on return when not given.
        integer, allocatable, intent(inout) :: output_dofs(:)
        !> &output dofs was given.
        logical, intent(in) :: output_given
        !> The &output directory.
        character(len=*), intent(in) :: directory
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Where the phases are reported (optional).
        type(progress_t), intent(inout), optional :: progress
        !> More DOFs kept as boundary DOFs (full numbers, checked in 1..N by the caller;
        !> e.g. a sector's cyclic boundaries); on return their reduced numbers.
        integer, intent(inout), optional :: keep_dofs(:)
        type(reduction_options_t) :: opts
        real(dp), allocatable :: unit_q(:), column(:)
        type(reduced_model_t) :: rm
        type(reduction_report_t) :: cached_report
        type(reduction_estimate_t) :: estimate
        class(sparse_factor_t), allocatable :: interior_lu
        ! [alpha, beta] when C is Rayleigh's alone (no damping file): unallocated otherwise,
        ! then absent as an optional argument
        real(dp), allocatable :: rayleigh(:)
        type(hash_t) :: hk
        integer, allocatable :: bset(:)
        real(dp), allocatable :: freqs(:), directions(:, :)
        real(dp) :: omega_max, start, stop
        character(len=:), allocatable :: parameter, why
        logical :: found_start, found_stop, have_model, want_estimate, may_write
        integer :: n, k, h, i, status
        integer(int64) :: t0, t1, rate
        real(dp), allocatable :: reduced_shape(:, :)

        n = model%ndof
        call check_range("&forcing force_dof", model%force_dof)
        if (allocated(error)) return
        call check_range("&friction contact_dof", model%contact_dof)
        if (allocated(error)) return
        call check_range("&friction contact_dof2", pack(model%contact_dof2, &
                                                        model%contact_dof2 /= 0))
        if (allocated(error)) return
        bset = [model%contact_dof, pack(model%contact_dof2, model%contact_dof2 > 0), &
                model%force_dof]
        if (allocated(model%contact_direction)) bset = [bset, &
            pack([(i, i=1, n)], any(model%contact_direction /= 0.0_dp, dim=2))]
        ! the normal and second tangential directions of the contact laws
        if (allocated(model%normal_direction)) bset = [bset, &
            pack([(i, i=1, n)], any(model%normal_direction /= 0.0_dp, dim=2))]
        if (allocated(model%tangent2_direction)) bset = [bset, &
            pack([(i, i=1, n)], any(model%tangent2_direction /= 0.0_dp, dim=2))]
        if (present(keep_dofs)) bset = [bset, keep_dofs]
        ! the DOFs the user asks for are boundary DOFs too: exact static response there
        if (output_given) then
            call check_range("&output dofs", output_dofs)
            if (allocated(error)) return
            bset = [bset, output_dofs]
        end if
        if (size(bset) == 0) then
            call group_error(nml, error, "&reduction method = '"//trim(red%method)//"': no "// &
                             "boundary DOF (no contact and no force_dof; a force_file alone "// &
                             "gives none): give the contacts, or reduce with &reduction "// &
                             "method = 'none'")
            return
        end if

        ! a case of nonlinear modes without &forcing has no frequency of its own
        if (model%nforce() == 0 .and. red%modes == 0 .and. red%max_frequency == 0.0_dp) then
            call group_error(nml, error, "&reduction: a case of nonlinear modes without "// &
                             "&forcing gives no frequency to choose the fixed-interface "// &
                             "modes from: give &reduction max_frequency [rad/s] (about 3 H "// &
                             "times the mode's frequency) or modes, or a &forcing group whose "// &
                             "omega is near the mode (its terms are not applied by method "// &
                             "'modes')")
            return
        end if
        ! the run's highest harmonic frequency
        omega_max = abs(model%omega)
        parameter = ""
        call get_string(nml, "sweep", "parameter", parameter, error)
        if (allocated(error)) return
        if (trim(parameter) == "omega" .or. (nml%find("sweep") > 0 .and. &
                                             len_trim(parameter) == 0)) then
            start = 0.0_dp
            stop = 0.0_dp
            call get_real(nml, "sweep", "start", start, error, found_start)
            if (allocated(error)) return
            call get_real(nml, "sweep", "stop", stop, error, found_stop)
            if (allocated(error)) return
            omega_max = max(omega_max, abs(start), abs(stop))
        end if
        h = max(harmonics, maxval([1, model%force_harmonic]))
        opts = reduction_options_t(modes=red%modes, max_frequency=red%max_frequency, &
                                   highest_frequency=h*omega_max, &
                                   damping_ratio=red%damping_ratio)
        ! the error measure at the run's frequencies (error_frequencies) for the contact
        ! directions (every force channel with contact laws)
        if (omega_max > abs(model%omega)) then
            freqs = error_frequencies(model%force_harmonic, [min(abs(start), abs(stop)), &
                                      omega_max], harmonics)
        else
            freqs = error_frequencies(model%force_harmonic, [abs(model%omega)], harmonics)
        end if
        directions = measured_directions(model)
        want_estimate = red%error_estimate .and. size(directions, 2) > 0 .and. size(freqs) > 0

        ! the cache: a model reduced before from the same inputs
        have_model = .false.
        may_write = red%cache /= 'off'
        red%cache_status = 'off'
        red%cache_path = ''
        if (red%cache /= 'off') then
            call system_clock(t0, rate)
            if (red%cache == 'auto') then
                red%cache_path = directory//'/'//default_cache_name
            else
                red%cache_path = red%cache
            end if
            call cache_key(red%cache_key)
            if (allocated(error)) return
            call read_reduction_cache(red%cache_path, red%cache_key, n, rm, cached_report, &
                                      status, why)
            select case (status)
            case (cache_hit)
                have_model = .true.
                red%cache_status = 'hit'
                call red%diagnostics%add(level_note, "reduction_cache_hit", "reduction: "// &
                    "the reduced model was read from the cache "//red%cache_path//" (the "// &
                    "reduction was skipped)")
            case (cache_damaged)
                call red%diagnostics%add(level_warning, "reduction_cache_damaged", &
                    "reduction: the cache "//red%cache_path//" is damaged ("//why//"): "// &
                    "ignored; the model was reduced again and the cache replaced")
            case (cache_foreign)
                ! someone else's file: never overwritten
                may_write = .false.
                call red%diagnostics%add(level_warning, "reduction_cache_foreign", &
                    "reduction: "//red%cache_path//" is not a reduction cache: left as it "// &
                    "is, and the reduced model not cached (give &reduction cache another "// &
                    "file)")
            case (cache_absent, cache_stale)
                continue
            end select
            call system_clock(t1)
            red%cache_seconds = real(t1 - t0, dp)/real(max(rate, 1_int64), dp)
            if (present(progress)) call progress%phase("reduction: cache "// &
                red%cache_path//": "//trim(merge("used        ", "not usable  ", have_model)), &
                red%cache_seconds)
        end if

        if (have_model) then
            red%report = cached_report
            red%report%seconds = red%cache_seconds
            red%report%error_seconds = 0.0_dp
            if (want_estimate .and. (cached_report%error_method == 'off')) then
                ! cached without its estimate: measure it now, and store it
                call load_matrices()
                if (allocated(error)) return
                call measure(.false.)
                if (allocated(error)) return
                call keep_for_cache()
            end if
        else
            call load_matrices()
            if (allocated(error)) return
            if (sparse%has_damping .and. allocated(model%force_shape)) then
                call craig_bampton(sparse%stiffness, sparse%mass, bset, opts, rm, red%report, &
                                   error, cmat=sparse%damping, loads=model%force_shape, &
                                   interior_lu=interior_lu, progress=progress, rayleigh=rayleigh)
            else if (sparse%has_damping) then
                call craig_bampton(sparse%stiffness, sparse%mass, bset, opts, rm, red%report, &
                                   error, cmat=sparse%damping, interior_lu=interior_lu, &
                                   progress=progress, rayleigh=rayleigh)
            else if (allocated(model%force_shape)) then
                call craig_bampton(sparse%stiffness, sparse%mass, bset, opts, rm, red%report, &
                                   error, loads=model%force_shape, interior_lu=interior_lu, &
                                   progress=progress)
            else
                call craig_bampton(sparse%stiffness, sparse%mass, bset, opts, rm, red%report, &
                                   error, interior_lu=interior_lu, progress=progress)
            end if
            if (allocated(error)) then
                if (allocated(interior_lu)) call interior_lu%release()
                if (index(error%message, "craig_bampton: options%") == 1) then
                    ! an option of &reduction at fault: name it
                    error%message = nml%path//": &reduction "// &
                                    error%message(len("craig_bampton: options%") + 1:)
                    k = index(error%message, "options%max_modes")
                    if (k > 0) error%message = error%message(1:k - 1)//"the"// &
                                               error%message(k + len("options%max_modes = ") - 1:)
                    k = index(error%message, "the number of modes")
                    if (k > 0) error%message = error%message(1:k - 1)//"modes"// &
                                               error%message(k + len("the number of modes"):)
                else
                    error%message = nml%path//": &reduction method = '"//trim(red%method)// &
                                    "': "//error%message
                end if
                return
            end if
            red%report%error_frequencies = freqs
            if (want_estimate) then
                call measure(.true.)
                if (allocated(error)) return
            else if (red%error_estimate) then
                red%report%error_method = 'none'
            else
                red%report%error_method = 'off'
            end if
            if (allocated(interior_lu)) call interior_lu%release()
            if (may_write) call keep_for_cache()
        end if
        if (.not. red%error_estimate) then
            ! not asked for: not reported, even when the cache holds one
            red%report%error = -1.0_dp
            red%report%error_method = 'off'
            red%report%error_seconds = 0.0_dp
            red%report%error_levels = 0
            red%report%error_change = 0.0_dp
            call red%diagnostics%add(level_note, "reduction_error_off", "reduction: the "// &
                "error of the reduced model was not estimated (&reduction error_estimate "// &
                "= .false.; reduction_error = -1)")
        end if
        call reduction_findings(red)

        ! the reduced dense model, DOFs remapped
        red%contact_dof = model%contact_dof
        red%contact_dof2 = model%contact_dof2
        red%force_dof = model%force_dof
        do k = 1, size(model%contact_dof)
            model%contact_dof(k) = reduced_dof_of(rm, model%contact_dof(k))
            if (model%contact_dof2(k) > 0) model%contact_dof2(k) = &
                reduced_dof_of(rm, model%contact_dof2(k))
        end do
        do k = 1, size(model%force_dof)
            model%force_dof(k) = reduced_dof_of(rm, model%force_dof(k))
        end do
        if (present(keep_dofs)) then
            do k = 1, size(keep_dofs)
                keep_dofs(k) = reduced_dof_of(rm, keep_dofs(k))
            end do
        end if
        ! directions and load shapes: T^T W (the boundary rows of W), T^T F
        if (allocated(model%contact_direction)) then
            call reduce_vectors(rm, model%contact_direction, reduced_shape, error)
            if (allocated(error)) return
            call move_alloc(reduced_shape, model%contact_direction)
        end if
        if (allocated(model%force_shape)) then
            call reduce_vectors(rm, model%force_shape, reduced_shape, error)
            if (allocated(error)) return
            call move_alloc(reduced_shape, model%force_shape)
        end if
        if (allocated(model%normal_direction)) then
            call reduce_vectors(rm, model%normal_direction, reduced_shape, error)
            if (allocated(error)) return
            call move_alloc(reduced_shape, model%normal_direction)
        end if
        if (allocated(model%tangent2_direction)) then
            call reduce_vectors(rm, model%tangent2_direction, reduced_shape, error)
            if (allocated(error)) return
            call move_alloc(reduced_shape, model%tangent2_direction)
        end if
        ! the rows of T for the output DOFs: column r of them is T(dofs, :) e_r
        if (.not. output_given) output_dofs = rm%boundary
        red%output_dofs = output_dofs
        allocate (red%output_reduced(size(output_dofs)), &
                  red%output_rows(size(output_dofs), rm%nr), unit_q(rm%nr), &
                  column(size(output_dofs)))
        do k = 1, size(output_dofs)
            red%output_reduced(k) = reduced_dof_of(rm, output_dofs(k))
        end do
        do k = 1, rm%nr
            unit_q = 0.0_dp
            unit_q(k) = 1.0_dp
            call recover_dofs(rm, output_dofs, unit_q, column, error)
            if (allocated(error)) then
                error%message = nml%path//": &output dofs: "//error%message
                return
            end if
            red%output_rows(:, k) = column
        end do
        model%ndof = rm%nr
        if (red%keep_basis) then
            allocate (red%basis)
            red%basis%n = rm%n
            red%basis%nb = rm%nb
            red%basis%nm = rm%nm
            red%basis%nr = rm%nr
            red%basis%boundary = rm%boundary
            red%basis%interior = rm%interior
            red%basis%constraint = rm%constraint
            red%basis%modes = rm%modes
            red%basis%frequencies = rm%frequencies
            red%basis%nl = rm%nl
            if (allocated(rm%loads)) red%basis%loads = rm%loads
        end if
        call move_alloc(rm%mass, model%mass)
        call move_alloc(rm%stiffness, model%stiffness)
        call move_alloc(rm%damping, model%damping)

    contains

        subroutine check_range(what, dofs)
            character(len=*), intent(in) :: what
            integer, intent(in) :: dofs(:)
            integer :: j
            do j = 1, size(dofs)
                if (dofs(j) < 1 .or. dofs(j) > n) then
                    call group_error(nml, error, what//"("//itoa(j)//") = "//itoa(dofs(j))// &
                                     ": must be in 1.."//itoa(n)//" (the model from files "// &
                                     "has N = "//itoa(n)//" DOFs)")
                    return
                end if
            end do
        end subroutine check_range

        !> The matrix files read (unless they were), timed; the Rayleigh factors noted when
        !> they make C alone.
        subroutine load_matrices()
            integer(int64) :: s0, s1, r
            if (files%rayleigh_alpha /= 0.0_dp .or. files%rayleigh_beta /= 0.0_dp) then
                if (.not. allocated(files%damping_file)) &
                    rayleigh = [files%rayleigh_alpha, files%rayleigh_beta]
            end if
            if (sparse%loaded) return
            call system_clock(s0, r)
            call load_sparse_system(nml, files, n, sparse, error, progress)
            if (allocated(error)) return
            call system_clock(s1)
            red%read_seconds = real(s1 - s0, dp)/real(max(r, 1_int64), dp)
            if (present(progress)) call progress%phase("reduction: matrix files read ("// &
                itoa(n)//" DOFs, "//itoa(sparse%stiffness%nnz())//" entries of K)", &
                red%read_seconds)
        end subroutine load_matrices

        !> The error estimate of rm into red%report (on the reduction's factorization of
        !> K_ii when `reuse`, else on one made for it).
        subroutine measure(reuse)
            logical, intent(in) :: reuse
            logical :: proportional
            ! C without a damping file is alpha M + beta K: no damping vectors needed
            proportional = .not. allocated(files%damping_file)
            if (sparse%has_damping .and. reuse) then
                call estimate_reduction_error(sparse%stiffness, sparse%mass, rm, directions, &
                                              freqs, estimate, error, cmat=sparse%damping, &
                                              proportional=proportional, &
                                              interior_lu=interior_lu, progress=progress, &
                                              rayleigh=rayleigh)
            else if (sparse%has_damping) then
                call estimate_reduction_error(sparse%stiffness, sparse%mass, rm, directions, &
                                              freqs, estimate, error, cmat=sparse%damping, &
                                              proportional=proportional, progress=progress, &
                                              rayleigh=rayleigh)
            else if (reuse) then
                call estimate_reduction_error(sparse%stiffness, sparse%mass, rm, directions, &
                                              freqs, estimate, error, &
                                              interior_lu=interior_lu, progress=progress)
            else
                call estimate_reduction_error(sparse%stiffness, sparse%mass, rm, directions, &
                                              freqs, estimate, error, progress=progress)
            end if
            if (allocated(error)) then
                if (allocated(interior_lu)) call interior_lu%release()
                error%message = nml%path//": &reduction: reduction error measure: "// &
                                error%message
                return
            end if
            red%report%error = estimate%error
            red%report%error_frequencies = freqs
            red%report%error_method = estimate%method
            red%report%error_seconds = estimate%seconds
            red%report%error_levels = estimate%levels
            red%report%error_change = estimate%change
        end subroutine measure

        !> rm (with the report) kept for write_reduction_cache_of.
        subroutine keep_for_cache()
            if (allocated(red%cache_model)) deallocate (red%cache_model)
            allocate (red%cache_model, source=rm)
            red%cache_status = 'pending'
        end subroutine keep_for_cache

        !> The key of every input of the reduction and of its error estimate: the version,
        !> the bytes of the matrix files, the Rayleigh factors, the boundary DOFs, the
        !> options (mode count or rule and its highest frequency, damping ratio), the load
        !> shapes, the frequencies and directions of the estimate.
        subroutine cache_key(key)
            integer(int64), intent(out) :: key
            logical, allocatable :: is_boundary(:)
            integer(int64) :: s0, s1, r
            call system_clock(s0, r)
            call hk%add("stickslip reduction cache key")
            call hk%add(stickslip_version)
            call hk%add(n)
            call add_file(files%mass_path)
            if (allocated(error)) return
            call add_file(files%stiffness_path)
            if (allocated(error)) return
            call hk%add(allocated(files%damping_file))
            if (allocated(files%damping_file)) call add_file(files%damping_path)
            if (allocated(error)) return
            call hk%add(files%rayleigh_alpha)
            call hk%add(files%rayleigh_beta)
            allocate (is_boundary(n))
            is_boundary = .false.
            is_boundary(bset) = .true.
            call hk%add(pack([(i, i=1, n)], is_boundary))
            call hk%add(opts%modes)
            call hk%add(opts%max_frequency)
            call hk%add(opts%highest_frequency)
            call hk%add(opts%cutoff_factor)
            call hk%add(opts%damping_ratio)
            call hk%add(opts%max_modes)
            call hk%add(allocated(model%force_shape))
            if (allocated(model%force_shape)) call hk%add(model%force_shape)
            call hk%add(freqs)
            call hk%add(directions)
            key = hk%value()
            call system_clock(s1)
            if (present(progress)) call progress%phase("reduction: inputs hashed for the "// &
                "cache", real(s1 - s0, dp)/real(max(r, 1_int64), dp))
        end subroutine cache_key

        subroutine add_file(path)
            character(len=*), intent(in) :: path
            call hash_file(path, hk, error)
            if (allocated(error)) error%message = nml%path//": &reduction cache: "// &
                error%message
        end subroutine add_file
    end subroutine reduce_case_model

    !> Write the cache of a reduction made by reduce_case_model (red%cache_status
    !> 'pending'), creating its folder when missing: red%cache_status becomes 'written', or
    !> 'not written' with a warning 'reduction_cache_write' (never an error: the run goes
    !> on without it). Nothing happens otherwise.
    subroutine write_reduction_cache_of(red, progress)
        !> The reduction of a case just read.
        type(reduction_case_t), intent(inout) :: red
        !> Where the phase is reported (optional).
        type(progress_t), intent(inout), optional :: progress
        type(error_type), allocatable :: error
        character(len=:), allocatable :: dir, name
        integer :: k
        integer(int64) :: t0, t1, rate
        if (red%cache_status /= 'pending' .or. .not. allocated(red%cache_model)) return
        call system_clock(t0, rate)
        k = index(red%cache_path, '/', back=.true.)
        if (k == 0) then
            dir = '.'
            name = red%cache_path
        else if (k == 1) then
            dir = '/'
            name = red%cache_path(2:)
        else
            dir = red%cache_path(1:k - 1)
            name = red%cache_path(k + 1:)
        end if
        call make_directory(dir, error)
        if (.not. allocated(error)) call write_reduction_cache(dir, name, red%cache_key, &
                                                               red%cache_model, red%report, &
                                                               error)
        deallocate (red%cache_model)
        if (allocated(error)) then
            red%cache_status = 'not written'
            call red%diagnostics%add(level_warning, "reduction_cache_write", "reduction: "// &
                "the cache "//red%cache_path//" was not written ("//error%message// &
                "): the next run reduces the model again")
            return
        end if
        red%cache_status = 'written'
        call system_clock(t1)
        red%cache_seconds = red%cache_seconds + real(t1 - t0, dp)/real(max(rate, 1_int64), dp)
        if (present(progress)) call progress%phase("reduction: cache "//red%cache_path// &
            " written", real(t1 - t0, dp)/real(max(rate, 1_int64), dp))
    end subroutine write_reduction_cache_of

    !> The values of the output DOFs from reduced values: y(:, k) = sum_r q(:, r) T(dofs(k), r)
    !> for every row (sample or basis function) of `q` (rows x nr) — exact, the recovery is
    !> linear. Result rows x size(red%output_dofs).
    pure function recover_outputs(red, q) result(y)
        !> A reduction with output rows (the model was reduced).
        type(reduction_case_t), intent(in) :: red
        !> Reduced values, rows x nr.
        real(dp), intent(in) :: q(:, :)
        real(dp), allocatable :: y(:, :)
        y = matmul(q, transpose(red%output_rows))
    end function recover_outputs

    !> The full-field harmonic coefficients, N x nb (row i: DOF i of the full model; column k:
    !> basis function k of the solution) from the reduced coefficients `qcoef` (nb x nr, the
    !> layout of hbm_solution_t%xcoef): x_full = T q, exact for the reduced model. Without a
    !> kept basis (the model was not reduced) qcoef is returned transposed. Error (stat
    !> input): the columns of qcoef are not the reduced DOFs.
    subroutine recover_full_field(red, qcoef, coef, error)
        !> The reduction of the case (its basis kept: keep_basis).
        type(reduction_case_t), intent(in) :: red
        !> Reduced (or, unreduced, full) coefficients, nb x nr.
        real(dp), intent(in) :: qcoef(:, :)
        !> Full-field coefficients, N x nb [m].
        real(dp), allocatable, intent(out) :: coef(:, :)
        !> Set on a size mismatch.
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: q(:, :)
        if (.not. allocated(red%basis)) then
            coef = transpose(qcoef)
            return
        end if
        if (allocated(red%faces)) then
            ! the faces' interface modes back to the Craig-Bampton coordinates
            if (size(qcoef, 2) /= size(red%faces%basis, 2)) then
                call fatal_error(error, "recover_full_field: the coefficients have "// &
                                 itoa(size(qcoef, 2))//" columns, the reduced model "// &
                                 itoa(size(red%faces%basis, 2))//" DOFs", stickslip_stat%input)
                return
            end if
            q = matmul(qcoef, transpose(red%faces%basis))
        else
            q = qcoef
        end if
        if (size(q, 2) /= red%basis%nr) then
            call fatal_error(error, "recover_full_field: the coefficients have "// &
                             itoa(size(q, 2))//" columns, the reduced model "// &
                             itoa(red%basis%nr)//" DOFs", stickslip_stat%input)
            return
        end if
        associate (b => red%basis, qcoef => q)
            allocate (coef(b%n, size(qcoef, 1)))
            coef(b%boundary, :) = transpose(qcoef(:, 1:b%nb))
            if (size(b%interior) > 0) then
                coef(b%interior, :) = matmul(b%constraint, transpose(qcoef(:, 1:b%nb)))
                if (b%nm > 0) coef(b%interior, :) = coef(b%interior, :) + &
                    matmul(b%modes, transpose(qcoef(:, b%nb + 1:b%nb + b%nm)))
                if (b%nl > 0) coef(b%interior, :) = coef(b%interior, :) + &
                    matmul(b%loads, transpose(qcoef(:, b%nb + b%nm + 1:b%nr)))
            end if
        end associate
    end subroutine recover_full_field

    !> &reduction interface_modes on a reduced sector (stickslip_cyclic_interface): its
    !> cyclic faces replaced by red%interface_modes interface modes each, `model` and `cyc`
    !> renumbered, the output DOFs kept physical and their rows of the basis composed with
    !> the faces' transformation; red%faces keeps it (the full field). Errors (stat input or
    !> numerical, those of reduce_cyclic_faces) start "<path>: &reduction interface_modes =
    !> p: ".
    subroutine reduce_case_faces(nml, red, model, cyc, band, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The reduction of the case (interface_modes > 0; output rows and DOFs set).
        type(reduction_case_t), intent(inout) :: red
        !> The reduced sector; its faces reduced on return.
        type(model_t), intent(inout) :: model
        !> Its symmetry in its numbers; renumbered on return.
        type(cyclic_t), intent(inout) :: cyc
        !> The run's highest harmonic frequency [rad/s]: the cyclic modes below it shape the
        !> interface modes.
        real(dp), intent(in) :: band
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: keep(:)
        integer :: k
        allocate (red%faces)
        keep = [integer ::]
        if (allocated(red%output_reduced)) keep = red%output_reduced
        call reduce_cyclic_faces(model, cyc, red%interface_modes, keep, band, red%faces, &
                                 error)
        if (allocated(error)) then
            error%message = nml%path//": &reduction interface_modes = "// &
                            itoa(red%interface_modes)//": "//error%message
            deallocate (red%faces)
            return
        end if
        if (allocated(red%output_rows)) red%output_rows = matmul(red%output_rows, &
                                                                 red%faces%basis)
        if (allocated(red%output_reduced)) then
            do k = 1, size(red%output_reduced)
                if (red%output_reduced(k) > 0) red%output_reduced(k) = &
                    red%faces%new_of_old(red%output_reduced(k))
            end do
        end if
    end subroutine reduce_case_faces

    !> The frequencies where the reduction error is measured [rad/s]: m h omega for every
    !> distinct forcing harmonic h > 0 (a static load alone: h = 1), m = 1, 3, 5 (the
    !> fundamental and the first odd harmonics friction generates, m <= max(harmonics, 1)),
    !> omega each of `omegas` (the forcing omega, or the ends of a sweep over omega);
    !> distinct, at most max_error_frequencies (the lowest first: each costs one sparse
    !> complex LU of the full model).
    pure function error_frequencies(force_harmonic, omegas, harmonics) result(freqs)
        !> Harmonic of every forcing term.
        integer, intent(in) :: force_harmonic(:)
        !> The forcing frequencies of the run [rad/s].
        real(dp), intent(in) :: omegas(:)
        !> &hbm harmonics.
        integer, intent(in) :: harmonics
        real(dp), allocatable :: freqs(:)
        integer, parameter :: max_error_frequencies = 8
        integer, allocatable :: hs(:)
        integer :: i, j, m
        real(dp) :: f
        hs = pack(force_harmonic, force_harmonic > 0)
        if (size(hs) == 0) hs = [1]
        allocate (freqs(0))
        do m = 1, min(5, max(harmonics, 1)), 2
            do i = 1, size(hs)
                do j = 1, size(omegas)
                    f = m*hs(i)*omegas(j)
                    if (.not. (f > 0.0_dp)) cycle
                    if (any(freqs == f)) cycle
                    if (size(freqs) >= max_error_frequencies) return
                    freqs = [freqs, f]
                end do
            end do
        end do
    end function error_frequencies

    !> The checks of a reduction done (red%report) into red%diagnostics: 'reduction_capped'
    !> when the mode-count rule stopped at its cap before its frequency limit, and
    !> 'reduction_error' when the measured error exceeds reduction_error_warning.
    subroutine reduction_findings(red)
        !> The reduction (report in, diagnostics out).
        type(reduction_case_t), intent(inout) :: red
        character(len=400) :: buf
        associate (r => red%report)
            if (r%capped) then
                write (buf, '(a,i0,a,es10.3,a,es10.3,a)') "reduction: the mode-count rule "// &
                    "stopped at its cap of ", r%modes, " fixed-interface modes (highest ", &
                    r%highest_mode_frequency, " rad/s) below its limit ", r%frequency_limit, &
                    " rad/s: modes that respond may be missing (stiffness-proportional "// &
                    "damping, rayleigh_beta with 9 H omega beta >= 1, makes every mode count); "// &
                    "give &reduction modes or max_frequency"
                call red%diagnostics%add(level_warning, "reduction_capped", trim(buf))
            end if
            if (r%error > reduction_error_warning) then
                write (buf, '(a,es10.3,a,i0,a)') "reduction: the measured error of the "// &
                    "reduced model (contact receptance) is ", r%error, " > ", &
                    nint(100*reduction_error_warning), "%: keep more modes (&reduction "// &
                    "modes, max_frequency)"
                call red%diagnostics%add(level_warning, "reduction_error", trim(buf))
            end if
        end associate
    end subroutine reduction_findings
    !> The directions whose receptance measures the reduction error, N x m: every force
    !> channel with contact laws (all_contact_directions), else the contact directions W,
    !> else e_dof1 - e_dof2 of every contact (N x 0 without contacts).
    function measured_directions(model) result(d)
        type(model_t), intent(in) :: model
        real(dp), allocatable :: d(:, :)
        integer :: j, nc
        d = all_contact_directions(model)
        if (size(d, 2) > 0) return
        if (allocated(model%contact_direction)) then
            d = model%contact_direction
            return
        end if
        nc = size(model%contact_dof)
        deallocate (d)
        allocate (d(model%ndof, nc))
        d = 0.0_dp
        do j = 1, nc
            d(model%contact_dof(j), j) = 1.0_dp
            if (model%contact_dof2(j) > 0) d(model%contact_dof2(j), j) = &
                d(model%contact_dof2(j), j) - 1.0_dp
        end do
    end function measured_directions

    !> Every force channel direction of the model's contacts when it has normal or second
    !> tangential directions (the tangential columns w_j, then the nonzero normal and second
    !> tangential columns), N x m; N x 0 for a model without them (its error is measured on
    !> the contact directions as before). The model is not validated yet: DOF lists are
    !> read with their ranges checked by the caller.
    function all_contact_directions(model) result(d)
        type(model_t), intent(in) :: model
        real(dp), allocatable :: d(:, :)
        integer :: j, n, nc
        real(dp), allocatable :: col(:)
        n = model%ndof
        allocate (d(n, 0))
        if (.not. (allocated(model%normal_direction) .or. allocated(model%tangent2_direction))) &
            return
        nc = size(model%mu)
        allocate (col(n))
        do j = 1, nc
            if (allocated(model%contact_direction)) then
                col = model%contact_direction(:, j)
            else
                col = 0.0_dp
                col(model%contact_dof(j)) = 1.0_dp
                if (model%contact_dof2(j) > 0) col(model%contact_dof2(j)) = -1.0_dp
            end if
            d = reshape([d, col], [n, size(d, 2) + 1])
        end do
        if (allocated(model%normal_direction)) call append(model%normal_direction)
        if (allocated(model%tangent2_direction)) call append(model%tangent2_direction)
    contains
        subroutine append(a)
            real(dp), intent(in) :: a(:, :)
            integer :: k
            do k = 1, size(a, 2)
                if (any(a(:, k) /= 0.0_dp)) d = reshape([d, a(:, k)], [n, size(d, 2) + 1])
            end do
        end subroutine append
    end function all_contact_directions
end module stickslip_case_reduction
