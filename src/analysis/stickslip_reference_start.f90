!> Where the exact reference starts: the start strategy around solve_reference
!> (stickslip_reference), which takes its start as an argument and knows none of the
!> methods it judges.
!>
!> &reference start = 'auto' shoots from the weighted-residual solution and, when that
!> cannot be computed or the shooting from it does not converge, from the periodic state
!> of implicit Euler; 'hbm' and 'euler' use one of the two only. Solutions already computed
!> (method = 'all') are reused instead of solving again. Each attempt is a fresh
!> solve_reference: the result returned is the converged one, or the last attempt's with
!> every attempt's diagnosis.
module stickslip_reference_start
    use stickslip_kinds, only: dp
    use stickslip_thread_clock, only: thread_cpu_seconds
    use stickslip_diagnostics, only: level_untrusted
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t, validate_model
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_euler, only: euler_options_t, euler_result_t, integrate_euler
    use stickslip_reference, only: reference_options_t, reference_result_t, solve_reference, &
        validate_reference_options
    implicit none
    private
    public :: reference_start_options_t, validate_reference_start_options
    public :: solve_reference_from_starts

    !> Options of the exact reference with its start strategy (&reference): the options of
    !> solve_reference and the start, which only solve_reference_from_starts uses.
    type, extends(reference_options_t) :: reference_start_options_t
        !> Start of the shooting: 'auto' (the weighted residual, then implicit Euler if the
        !> shooting from it fails), 'hbm' or 'euler'.
        character(len=8) :: start = 'auto'
    end type reference_start_options_t

contains

    !> Check reference options and the start strategy. Errors (stat input) name the
    !> component ("opts%start = 'cold': must be 'auto', 'hbm' or 'euler'", and those of
    !> validate_reference_options).
    subroutine validate_reference_start_options(opts, error)
        !> Options to check.
        type(reference_start_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        call validate_reference_options(opts%reference_options_t, error)
        if (allocated(error)) return
        if (opts%start /= 'auto' .and. opts%start /= 'hbm' .and. opts%start /= 'euler') &
            call fatal_error(error, "opts%start = '"//trim(opts%start)// &
                             "': must be 'auto', 'hbm' or 'euler'", stickslip_stat%input)
    end subroutine validate_reference_start_options

    !> The exact periodic solution of `model`, shot from the starts opts%start asks for
    !> ('auto': the weighted residual, then implicit Euler; 'hbm'; 'euler'). A start comes
    !> from `hbm_start` / `euler_start` when given (solutions already computed; used when
    !> converged / periodic and sampled), else it is computed with `hbm_opts` / `euler_opts`
    !> (defaults otherwise; the weighted-residual start gets samples and at least the
    !> forcing harmonics). res%nfev, res%njev and res%seconds add up every attempt,
    !> res%start_seconds the CPU time of computing starts. Not converging is an outcome
    !> (res%converged = F, res%diagnosis naming every attempt, a diagnostics item
    !> 'not_converged' of level untrusted). Errors: stat input (invalid model or options);
    !> stat numerical (dependent stuck contact directions). A start that cannot be computed
    !> (e.g. a singular dynamic stiffness for the weighted residual) is not an error: the
    !> next start is tried, and its failure is part of the diagnosis.
    subroutine solve_reference_from_starts(model, opts, res, error, hbm_opts, euler_opts, &
                                           hbm_start, euler_start)
        !> The structure, its contacts and forcing.
        type(model_t), intent(in) :: model
        !> Reference options (opts%start chooses the starts).
        type(reference_start_options_t), intent(in) :: opts
        !> The reference solution.
        type(reference_result_t), intent(out) :: res
        !> Set on invalid input or numerical breakdown.
        type(error_type), allocatable, intent(out) :: error
        !> Options of the weighted-residual start.
        type(hbm_options_t), intent(in), optional :: hbm_opts
        !> Options of the implicit Euler start.
        type(euler_options_t), intent(in), optional :: euler_opts
        !> A weighted-residual solution to start from (with samples).
        type(hbm_solution_t), intent(in), optional :: hbm_start
        !> An implicit Euler solution to start from.
        type(euler_result_t), intent(in), optional :: euler_start
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: hs
        type(euler_options_t) :: eo
        type(euler_result_t) :: es
        type(reference_result_t) :: trial
        type(error_type), allocatable :: start_error
        character(len=:), allocatable :: notes, tried
        real(dp) :: c0, c1, start_seconds, seconds
        integer :: attempt, nfev, njev
        logical :: shot

        call validate_model(model, error)
        if (allocated(error)) return
        call validate_reference_start_options(opts, error)
        if (allocated(error)) return
        notes = ""
        tried = ""
        start_seconds = 0.0_dp
        seconds = 0.0_dp
        nfev = 0
        njev = 0
        shot = .false.
        do attempt = 1, 2
            if (attempt == 1 .and. opts%start == 'euler') cycle
            if (attempt == 2 .and. opts%start == 'hbm') exit
            c0 = thread_cpu_seconds()
            if (attempt == 1) then
                if (given_hbm()) then
                    call shoot("hbm", hbm_start%x, hbm_start%v, hbm_start%r)
                else
                    if (present(hbm_opts)) ho = hbm_opts
                    ho%want_samples = .true.
                    ho%harmonics = max(ho%harmonics, maxval([0, model%force_harmonic]))
                    if (ho%samples < 2*ho%harmonics + 1) ho%samples = 4*ho%harmonics
                    call solve_periodic(model, ho, hs, start_error)
                    c1 = thread_cpu_seconds()
                    start_seconds = start_seconds + (c1 - c0)
                    if (allocated(start_error)) then
                        call note("the weighted-residual start failed: "//start_error%message)
                        deallocate (start_error)
                    else if (.not. hs%converged) then
                        call note("the weighted-residual start did not converge")
                    else
                        call shoot("hbm", hs%x, hs%v, hs%r)
                    end if
                end if
            else
                if (given_euler()) then
                    call shoot("euler", euler_start%x, euler_start%v, euler_start%r)
                else
                    if (present(euler_opts)) eo = euler_opts
                    call integrate_euler(model, eo, es, start_error)
                    c1 = thread_cpu_seconds()
                    start_seconds = start_seconds + (c1 - c0)
                    if (allocated(start_error)) then
                        call note("the implicit Euler start failed: "//start_error%message)
                        deallocate (start_error)
                    else if (.not. es%periodic) then
                        call note("the implicit Euler start reached no periodic state")
                    else
                        call shoot("euler", es%x, es%v, es%r)
                    end if
                end if
            end if
            if (allocated(error)) return
            if (res%converged) exit
        end do
        res%nfev = nfev
        res%njev = njev
        res%seconds = seconds
        res%start_seconds = start_seconds
        if (res%converged) return
        if (.not. shot) then
            res%start = ""
            res%diagnosis = "no start for the shooting could be computed"
            if (len(notes) > 0) res%diagnosis = res%diagnosis//": "//notes
        else
            res%diagnosis = tried
            if (len(notes) > 0) res%diagnosis = res%diagnosis//"; "//notes
        end if
        if (.not. res%diagnostics%has("not_converged")) &
            call res%diagnostics%add(level_untrusted, "not_converged", res%diagnosis)

    contains

        !> A converged weighted-residual solution with samples was given.
        logical function given_hbm()
            given_hbm = .false.
            if (.not. present(hbm_start)) return
            given_hbm = hbm_start%converged .and. allocated(hbm_start%x) .and. &
                        allocated(hbm_start%v)
        end function given_hbm

        !> A periodic implicit Euler state was given.
        logical function given_euler()
            given_euler = .false.
            if (.not. present(euler_start)) return
            given_euler = euler_start%periodic .and. allocated(euler_start%x) .and. &
                          allocated(euler_start%v)
        end function given_euler

        !> One fresh shooting from the samples (xs, vs); its result becomes res.
        subroutine shoot(name, xs, vs, rs)
            character(len=*), intent(in) :: name
            real(dp), intent(in) :: xs(:, :), vs(:, :), rs(:, :)
            call solve_reference(model, opts%reference_options_t, xs, vs, trial, error, &
                                 start_name=name, r_start=rs)
            if (allocated(error)) return
            shot = .true.
            nfev = nfev + trial%nfev
            njev = njev + trial%njev
            seconds = seconds + trial%seconds
            if (.not. trial%converged) then
                if (len(tried) > 0) tried = tried//"; "
                tried = tried//trial%diagnosis
            end if
            res = trial
        end subroutine shoot

        !> Add a reason why a start could not be used.
        subroutine note(text)
            character(len=*), intent(in) :: text
            if (len(notes) > 0) notes = notes//"; "
            notes = notes//text
        end subroutine note
    end subroutine solve_reference_from_starts
end module stickslip_reference_start
