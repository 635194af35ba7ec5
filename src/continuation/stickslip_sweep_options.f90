!> Options of a forced-response sweep (&sweep): the swept parameter and its range, the
!> continuation steps, the checks of every point; their validation, the continuation options
!> they give (stickslip_continuation), and the swept parameter of a model read and set.
module stickslip_sweep_options
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t, is_unilateral, contact_preload
    use stickslip_continuation, only: continuation_options_t, validate_continuation_options
    use stickslip_reference, only: reference_handles
    implicit none
    private
    public :: sweep_options_t, validate_sweep_options, continuation_options_of
    public :: sweep_parameter_value, set_sweep_parameter

    !> Options of a sweep (&sweep).
    type :: sweep_options_t
        !> The parameter: 'omega' [rad/s], 'force_amplitude' [N] (every forcing term scaled
        !> so that term 1 has this amplitude), 'mu' (every contact), 'normal_load' [N]
        !> (every contact with a constant normal load) or 'preload' [N] (every unilateral
        !> contact).
        character(len=16) :: parameter = 'omega'
        !> Range of the parameter, from start to stop.
        real(dp) :: start = 0.0_dp, stop = 0.0_dp
        !> First, smallest and largest continuation step in parameter units
        !> (0: |stop - start| / 100, / 1e5 and / 25).
        real(dp) :: step = 0.0_dp, min_step = 0.0_dp, max_step = 0.0_dp
        !> Most points, and failed points in a row before the sweep gives up.
        integer :: max_points = 2000, max_failures = 3
        !> Floquet multipliers of every point (exact event-driven monodromy).
        logical :: stability = .true.
        !> Harmonic truncation error estimate of every point (stickslip_truncation).
        logical :: truncation = .true.
        !> Observed combinations of DOFs, nobs x ndof (optional): when allocated, the
        !> amplitudes of a point are max_t |observe(i, :) x(t)|, i = 1..nobs, instead of one
        !> per DOF (e.g. the rows of a reduction basis: full-model DOFs of a reduced model).
        real(dp), allocatable :: observe(:, :)
    end type sweep_options_t

contains

    !> Check sweep options against the model. Errors (stat input) name the component
    !> ("opts%step, opts%min_step, ...: must be >= 0").
    subroutine validate_sweep_options(model, opts, error)
        !> The model swept.
        type(model_t), intent(in) :: model
        !> Options to check.
        type(sweep_options_t), intent(in) :: opts
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Most points of one sweep.
        integer, parameter :: max_points = 100000
        character(len=400) :: buf
        real(dp) :: smallest
        integer :: j
        character(len=:), allocatable :: why
        buf = ""
        select case (opts%parameter)
        case ('omega')
            if (.not. (min(opts%start, opts%stop) > 0.0_dp)) &
                buf = "opts%start, opts%stop: omega must stay > 0"
        case ('mu', 'normal_load', 'preload')
            if (.not. (min(opts%start, opts%stop) >= 0.0_dp)) &
                buf = "opts%start, opts%stop: "//trim(opts%parameter)//" must stay >= 0"
            if (model%ncontact() == 0) then
                buf = "opts%parameter = '"//trim(opts%parameter)//"': the model has no contact"
            else if (opts%parameter == 'preload' .and. &
                     .not. any([(is_unilateral(model, j), j=1, model%ncontact())])) then
                buf = "opts%parameter = 'preload': the model has no unilateral contact "// &
                      "(normal_dof, normal_direction or normal_file)"
            else if (opts%parameter == 'normal_load' .and. &
                     all([(is_unilateral(model, j), j=1, model%ncontact())])) then
                buf = "opts%parameter = 'normal_load': every contact is unilateral (its "// &
                      "normal force comes from the normal law); sweep 'preload' instead"
            end if
        case ('force_amplitude')
            if (model%nforce() == 0) then
                buf = "opts%parameter = 'force_amplitude': the model has no forcing term"
            else if (model%force_amplitude(1) == 0.0_dp) then
                buf = "opts%parameter = 'force_amplitude': force_amplitude(1) is 0, so the "// &
                      "forcing terms cannot be scaled from it"
            end if
        case default
            buf = "opts%parameter = '"//trim(opts%parameter)// &
                  "': must be 'omega', 'force_amplitude', 'mu', 'normal_load' or 'preload'"
        end select
        if (len_trim(buf) == 0 .and. opts%stability) then
            ! the multipliers come from the exact reference's monodromy
            if (.not. reference_handles(model, why)) buf = "opts%stability = .true.: "//why
        end if
        if (len_trim(buf) == 0) then
            if (opts%step < 0.0_dp .or. opts%min_step < 0.0_dp .or. opts%max_step < 0.0_dp) &
                buf = "opts%step, opts%min_step, opts%max_step: must be >= 0 (0: automatic)"
        end if
        ! a step the range cannot be walked with: below 1e-9 of it (at most max_points
        ! points, the step grows by halvings' inverse), or one that leaves the parameter
        ! unchanged in floating point
        if (len_trim(buf) == 0 .and. opts%stop /= opts%start) then
            smallest = max(1.0e-9_dp*abs(opts%stop - opts%start), &
                           4.0_dp*epsilon(1.0_dp)*max(abs(opts%start), abs(opts%stop)))
            if (opts%step > 0.0_dp .and. opts%step < smallest) then
                write (buf, '(a,es10.3e3,a,es10.3e3,a)') "opts%step = ", opts%step, &
                    ": must be 0 (automatic) or >= ", smallest, " (1e-9 of the range)"
            else if (opts%min_step > 0.0_dp .and. opts%min_step < smallest) then
                write (buf, '(a,es10.3e3,a,es10.3e3,a)') "opts%min_step = ", opts%min_step, &
                    ": must be 0 (automatic) or >= ", smallest, " (1e-9 of the range)"
            end if
        end if
        if (len_trim(buf) == 0 .and. opts%max_points > max_points) &
            write (buf, '(a,i0,a,i0)') "opts%max_points = ", opts%max_points, &
            ": must be <= ", max_points
        if (len_trim(buf) == 0 .and. allocated(opts%observe)) then
            if (size(opts%observe, 2) /= model%ndof) then
                write (buf, '(a,i0,a,i0,a)') "opts%observe: has ", size(opts%observe, 2), &
                    " columns, the model ", model%ndof, " DOFs"
            else if (.not. all(ieee_is_finite(opts%observe))) then
                buf = "opts%observe: not finite"
            end if
        end if
        if (len_trim(buf) > 0) then
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if
        block
            type(continuation_options_t) :: co
            co = continuation_options_of(opts)
            call validate_continuation_options(co, error)
        end block
    end subroutine validate_sweep_options

    !> The continuation options of a sweep (automatic steps filled in).
    pure function continuation_options_of(opts) result(co)
        !> Sweep options.
        type(sweep_options_t), intent(in) :: opts
        type(continuation_options_t) :: co
        real(dp) :: range
        range = abs(opts%stop - opts%start)
        co%start = opts%start
        co%stop = opts%stop
        co%step = opts%step
        co%min_step = opts%min_step
        co%max_step = opts%max_step
        if (co%step == 0.0_dp) then
            ! automatic: within the bounds the case gives
            co%step = range/100.0_dp
            if (co%max_step > 0.0_dp) co%step = min(co%step, co%max_step)
            if (co%min_step > 0.0_dp) co%step = max(co%step, co%min_step)
        end if
        if (co%max_step == 0.0_dp) co%max_step = max(range/25.0_dp, co%step)
        ! a quarter of the pace the case asks for: below it the step would trace the kinks
        ! of the nonsmooth discrete curve (sample switches of many contacts, measured on a
        ! blade with 16 contacts: a crawl at 1e-3 of the step), while the recovery at the
        ! smallest step (a solve at the predicted parameter, then a jump over the spot)
        ! passes them
        if (co%min_step == 0.0_dp) co%min_step = min(co%step, max(range*1.0e-5_dp, &
                                                                  0.25_dp*min(co%step, co%max_step)))
        co%max_points = opts%max_points
        co%max_failures = opts%max_failures
    end function continuation_options_of

    !> The value of the swept parameter in `model`.
    pure real(dp) function sweep_parameter_value(model, parameter) result(p)
        !> The model.
        type(model_t), intent(in) :: model
        !> 'omega', 'force_amplitude', 'mu', 'normal_load' or 'preload'.
        character(len=*), intent(in) :: parameter
        integer :: j
        select case (parameter)
        case ('omega')
            p = model%omega
        case ('force_amplitude')
            p = model%force_amplitude(1)
        case ('mu')
            p = model%mu(1)
        case ('preload')
            p = 0.0_dp
            do j = 1, model%ncontact()
                if (is_unilateral(model, j)) then
                    p = contact_preload(model, j)
                    return
                end if
            end do
        case default
            p = model%normal_load(1)
        end select
    end function sweep_parameter_value

    !> Set the swept parameter of `model` to p ('force_amplitude' scales every term from
    !> the amplitudes `amplitude0` of the case, term 1 taking the value p; mu, the normal
    !> load and the preload also on the explicit laws that have them).
    subroutine set_sweep_parameter(model, parameter, p, amplitude0)
        !> The model, changed.
        type(model_t), intent(inout) :: model
        !> 'omega', 'force_amplitude', 'mu', 'normal_load' or 'preload'.
        character(len=*), intent(in) :: parameter
        !> The value.
        real(dp), intent(in) :: p
        !> The forcing amplitudes of the case.
        real(dp), intent(in) :: amplitude0(:)
        integer :: j
        logical :: done
        if (allocated(model%laws)) then
            do j = 1, size(model%laws)
                if (allocated(model%laws(j)%e)) &
                    call model%laws(j)%e%set_parameter(parameter, p, done)
            end do
        end if
        select case (parameter)
        case ('omega')
            model%omega = p
        case ('force_amplitude')
            model%force_amplitude = amplitude0*(p/amplitude0(1))
        case ('mu')
            model%mu = p
        case ('preload')
            ! every unilateral contact's preload
            if (.not. allocated(model%preload)) then
                allocate (model%preload(model%ncontact()))
                model%preload = 0.0_dp
            end if
            do j = 1, model%ncontact()
                if (is_unilateral(model, j)) model%preload(j) = p
            end do
        case default
            ! the constant loads of the contacts that carry one (not the unilateral ones)
            do j = 1, model%ncontact()
                if (.not. is_unilateral(model, j)) model%normal_load(j) = p
            end do
        end select
    end subroutine set_sweep_parameter
end module stickslip_sweep_options
