!> The backbones of a bladed disk's nonlinear modes per nodal diameter (&run method =
!> 'modes' on one sector, &cyclic model = 'sector'): run_modes on the sector's travelling
!> wave of each diameter of &modes nodal_diameters (default every diameter 0 .. N/2), gathered
!> into one result whose points carry their diameter (modes.csv's column nodal_diameter).
module stickslip_run_sector_modes
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_progress, only: progress_t
    use stickslip_case, only: case_t
    use stickslip_case_studies, only: diameter_mode
    use stickslip_cyclic, only: cyclic_t
    use stickslip_modes, only: modes_options_t, modes_result_t, mode_point_t, run_modes, &
        refine_factor, max_refined_samples
    use stickslip_solution, only: hbm_options_t
    use stickslip_diagnostics, only: level_note
    implicit none
    private
    public :: sector_backbones, sector_diameters

contains

    !> The nodal diameters whose backbones a sector's case traces: &modes nodal_diameters,
    !> or every diameter 0 .. N/2.
    function sector_diameters(case) result(nd)
        !> The case (one sector of a disk).
        type(case_t), intent(in) :: case
        integer, allocatable :: nd(:)
        integer :: k
        if (allocated(case%modes%nodal_diameters)) then
            nd = case%modes%nodal_diameters
        else
            nd = [(k, k=0, case%cyclic%cyc%sectors/2)]
        end if
    end function sector_diameters

    !> The backbones of the sector `case%model` in the diameters `diameters`, with `opts`
    !> (its mode replaced by diameter_mode, stickslip_case_studies, in each diameter; a
    !> backbone the automatic weight rho could not carry to the end traced again with its
    !> wave's held weight, see retry_held):
    !> `per(i)` diameter i's (a diameter whose modes leave the contacts unloaded has no
    !> points, per(i)%unloaded; one whose start or continuation failed keeps its diagnosis),
    !> and `res` all their points in that order, each with its nodal_diameter, complete
    !> when every loaded diameter is, its diagnosis the diameters' joined, its counts and
    !> CPU time the sums. Errors: stat numerical when no diameter has a point (the first
    !> diameter's error, or that every diameter is unloaded).
    subroutine sector_backbones(case, opts, diameters, res, per, error, progress)
        !> The case (one sector of a disk).
        type(case_t), intent(in) :: case
        !> The modal-analysis options.
        type(modes_options_t), intent(in) :: opts
        !> The nodal diameters (each 0 .. N/2).
        integer, intent(in) :: diameters(:)
        !> All points.
        type(modes_result_t), intent(out) :: res
        !> Each diameter's backbone.
        type(modes_result_t), allocatable, intent(out) :: per(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> Progress hook, told after every point.
        type(progress_t), intent(inout), optional :: progress
        type(cyclic_t) :: cyc
        type(modes_options_t) :: one
        type(error_type), allocatable :: e, first
        integer :: i, k, total
        real(dp) :: rho_auto
        character(len=:), allocatable :: diagnosis
        allocate (per(size(diameters)))
        cyc = case%cyclic%cyc
        res%complete = .true.
        diagnosis = ""
        do i = 1, size(diameters)
            cyc%engine_order = diameters(i)
            one = opts
            one%mode = diameter_mode(case%modes, i)
            ! the cheap remedy first: the held weight on the case's samples; then both
            ! weights continued on more samples (run_modes' refinements)
            one%refinements = 0
            call run_modes(case%model, case%hbm, one, per(i), e, progress, cyclic=cyc)
            rho_auto = per(i)%rho
            if (.not. allocated(e)) call retry_held(per(i), one)
            one%refinements = opts%refinements
            if (.not. allocated(e)) call retry_refined(per(i), one, rho_auto)
            if (allocated(e)) then
                per(i)%npoints = 0
                per(i)%complete = per(i)%unloaded
                per(i)%diagnosis = e%message
                if (.not. allocated(first) .and. .not. per(i)%unloaded) call move_alloc(e, first)
                if (allocated(e)) deallocate (e)
            end if
            if (.not. (per(i)%complete .or. per(i)%unloaded)) then
                res%complete = .false.
                diagnosis = diagnosis//merge("; ", "  ", len(diagnosis) > 0)// &
                            "nodal diameter "//itoa(diameters(i))//": "//per(i)%diagnosis
            end if
        end do
        total = sum(per%npoints)
        allocate (res%points(max(1, total)))
        do i = 1, size(diameters)
            do k = 1, per(i)%npoints
                res%npoints = res%npoints + 1
                res%points(res%npoints) = per(i)%points(k)
                res%points(res%npoints)%nodal_diameter = diameters(i)
            end do
            res%factorizations = res%factorizations + per(i)%factorizations
            res%rejected = res%rejected + per(i)%rejected
            res%folds = res%folds + per(i)%folds
            res%seconds = res%seconds + per(i)%seconds
            ! each finding named with its diameter
            if (allocated(per(i)%diagnostics%items)) then
                do k = 1, size(per(i)%diagnostics%items)
                    associate (item => per(i)%diagnostics%items(k))
                        call res%diagnostics%add(item%level, item%key, "nodal diameter "// &
                                                 itoa(diameters(i))//": "//item%message)
                    end associate
                end do
            end if
            if (per(i)%npoints > 0 .and. res%rho == 0.0_dp) then
                res%rho = per(i)%rho
                res%odd_only = per(i)%odd_only
                res%start = per(i)%start
            end if
        end do
        res%diagnosis = trim(adjustl(diagnosis))
        if (res%npoints == 0) then
            if (allocated(first)) then
                call move_alloc(first, error)
            else
                call fatal_error(error, "nonlinear modes: in every nodal diameter asked for, "// &
                                 "the modes leave the contacts still and unloaded (their "// &
                                 "backbones are the linear modes)", stickslip_stat%numerical)
            end if
        end if

    contains

        !> The remedy of a backbone `b` that the automatic weight stopped short of the end
        !> (the continuation failed): the diameter traced again with the held weight of its
        !> wave (modes_result_t%rho_held, when below half the automatic one), which takes
        !> its place when it completes or reaches a larger amplitude; b%first_try then says
        !> what stopped the first, and b's CPU time and counts hold both. A retry that does
        !> no better leaves b, its diagnosis saying so.
        subroutine retry_held(b, one)
            type(modes_result_t), intent(inout) :: b
            type(modes_options_t), intent(in) :: one
            type(modes_result_t) :: again
            type(hbm_options_t) :: ho
            type(error_type), allocatable :: e2
            character(len=12) :: reach
            if (b%complete .or. case%hbm%rho /= 0.0_dp) return
            if (.not. (b%rho_held > 0.0_dp .and. b%rho_held < 0.5_dp*b%rho)) return
            ho = case%hbm
            ho%rho = b%rho_held
            call run_modes(case%model, ho, one, again, e2, progress, cyclic=cyc)
            if (.not. allocated(e2)) then
                if (again%complete .or. last_amplitude(again) > last_amplitude(b)) then
                    again%first_try = "the automatic weight rho = "// &
                                      trim(adjustl(rtext(b%rho)))//" stopped: "//b%diagnosis
                    again%rho_held = b%rho_held
                    again%seconds = again%seconds + b%seconds
                    again%factorizations = again%factorizations + b%factorizations
                    again%rejected = again%rejected + b%rejected
                    if (again%complete) then
                        reach = " to the end"
                    else
                        reach = " further"
                    end if
                    call again%diagnostics%add(level_note, "held_weight", "the automatic "// &
                                               "weight rho = "//trim(adjustl(rtext(b%rho)))// &
                                               " stopped the backbone at modal amplitude "// &
                                               trim(adjustl(rtext(last_amplitude(b))))// &
                                               "; traced again with the wave's held weight "// &
                                               trim(adjustl(rtext(b%rho_held)))//trim(reach))
                    b = again
                    return
                end if
            end if
            b%diagnosis = b%diagnosis//"; traced again with the wave's held weight rho = "// &
                          trim(adjustl(rtext(b%rho_held)))//", it did no better"
        end subroutine retry_held

        !> The remedy of a backbone `b` that stopped short of the end on the case's samples
        !> with either weight (retry_held): the diameter traced again with `one`'s
        !> refinements (run_modes: continued on 4 times the samples where it stops), with
        !> the weight that got further (b's), then with the other (when retry_held used the
        !> held one), each taking b's place when it completes or reaches a larger amplitude
        !> (run_modes' note says where it was refined); b%first_try then says what stopped
        !> on the case's samples, and b's CPU time and counts hold every trace. A retry that
        !> does no better leaves b, its diagnosis saying so. `rho_auto`: the weight of the
        !> first trace.
        subroutine retry_refined(b, one, rho_auto)
            type(modes_result_t), intent(inout) :: b
            type(modes_options_t), intent(in) :: one
            real(dp), intent(in) :: rho_auto
            type(modes_result_t) :: again, best
            type(hbm_options_t) :: ho
            type(error_type), allocatable :: e2
            character(len=:), allocatable :: before
            real(dp) :: held, seconds, weights(2)
            integer :: w, factorizations, rejected
            if (b%complete .or. b%unloaded .or. one%refinements == 0) return
            before = b%diagnosis
            if (allocated(b%first_try)) before = b%first_try//"; then "//before
            seconds = b%seconds
            factorizations = b%factorizations
            rejected = b%rejected
            held = b%rho_held
            best = b
            ! the weight whose trace got further first (b's), then the other one where
            ! retry_held tried it
            weights = [b%rho, rho_auto + held - b%rho]
            do w = 1, 2
                ho = case%hbm
                if (w == 2 .and. (case%hbm%rho /= 0.0_dp .or. .not. (held > 0.0_dp .and. &
                                                                      held < 0.5_dp*rho_auto))) &
                    exit
                if (case%hbm%rho == 0.0_dp) ho%rho = weights(w)
                call run_modes(case%model, ho, one, again, e2, progress, cyclic=cyc)
                if (allocated(e2)) then
                    deallocate (e2)
                    cycle
                end if
                seconds = seconds + again%seconds
                factorizations = factorizations + again%factorizations
                rejected = rejected + again%rejected
                if (again%complete .or. last_amplitude(again) > last_amplitude(best)) &
                    best = again
                if (best%complete) exit
            end do
            if (.not. (best%complete .or. last_amplitude(best) > last_amplitude(b))) then
                b%seconds = seconds
                b%factorizations = factorizations
                b%rejected = rejected
                b%diagnosis = b%diagnosis//"; traced again on more samples (at most "// &
                              itoa(min(case%hbm%samples*refine_factor**one%refinements, &
                                       max_refined_samples))//"), it did no better"
                return
            end if
            best%first_try = "on "//itoa(case%hbm%samples)//" samples: "//before
            best%rho_held = held
            best%seconds = seconds
            best%factorizations = factorizations
            best%rejected = rejected
            b = best
        end subroutine retry_refined
    end subroutine sector_backbones

    !> The modal amplitude of a backbone's last point (0 without points).
    real(dp) function last_amplitude(b)
        type(modes_result_t), intent(in) :: b
        last_amplitude = 0.0_dp
        if (b%npoints > 0) last_amplitude = b%points(b%npoints)%p%parameter
    end function last_amplitude

    !> A weight or an amplitude in three digits.
    function rtext(x) result(s)
        real(dp), intent(in) :: x
        character(len=16) :: s
        write (s, '(g0.3)') x
    end function rtext
end module stickslip_run_sector_modes
