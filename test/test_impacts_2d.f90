!> 2D friction on a rigid unilateral contact (impacts with 2D friction) in the exact
!> reference against independent truth. Slipping, the normal force is the constraint force
!> of the closed normal, and it responds to the friction force through the structure (the
!> mass couples the normal and the plane here: lambda = lambda_0 / (1 + mu kappa . d));
!> closing with a velocity, the contact takes a plastic impact whose impulse obeys the disk
!> (stuck or sliding in the direction of the slip after it). Two orbits of a point mass
!> pressed by a preload on a rigid ground contact and forced in its three directions (M
!> coupling the normal with the plane): one that opens, impacts and sticks, then slips; one
!> that impacts sliding and slips the whole closed time (also without the coupling). For
!> each: at every sample no force when open, zero gap and lambda >= 0 when closed, stuck
!> inside the disk of radius mu lambda at rest, slipping on its edge against the slip; the
!> energy balance with the impact losses; the monodromy against central differences of the
!> period map at the section (through the impacts, the slips and the sticking); implicit
!> Euler started on the orbit converging to it at first order (the sliding impacts without
!> the coupling only: run_impacts_2d_tests says why). A 2D Jenkins element on the same
!> contact (sliders in the state, frictionless impacts): the law, the balance, the monodromy
!> and Euler at first order.
module test_impacts_2d
    use stickslip_kinds, only: dp
    use stickslip_error, only: real_text
    use stickslip_model, only: model_t
    use stickslip_reference, only: reference_result_t
    use stickslip_flow, only: flow_t
    use fixtures, only: liftoff_2d_model
    use test_reference_2d, only: test_euler_first_order, compare_monodromy, test_disk_law, &
        reference, test_jenkins_disk_law
    use testing, only: test_counter_t, check
    implicit none
    private
    public :: run_impacts_2d_tests

contains

    subroutine run_impacts_2d_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        type(flow_t) :: flow
        call solved(t, rigid_model(0.3_dp, 0.15_dp, 1.5_dp), res, "stick-slip")
        if (res%converged) then
            call check(t, res%stick_phases(1) == 1 .and. res%stick_fraction(1) > 0.2_dp .and. &
                       1.0_dp - res%stick_fraction(1) - res%open_fraction(1) > 0.05_dp .and. &
                       res%open_fraction(1) > 0.3_dp, &
                       "impacts_2d: stick-slip: opens, sticks once and slips", &
                       real_text(res%open_fraction(1))//" open, "// &
                       real_text(res%stick_fraction(1))//" stuck")
            call test_disk_law(t, res, "rigid 2D stick-slip", 0.0_dp)
            ! at the section (open): through the impact, the sticking and the slip (a
            ! closed rigid contact is not differentiable off its constraints: a
            ! perturbation that opens it flies and impacts, one that closes it is projected)
            flow = res%flow
            call compare_monodromy(t, flow, res%t_section, res%orbit%phase_y(1:flow%nz, 1), &
                                   "rigid 2D stick-slip, at the section", res%monodromy)
            call test_euler_first_order(t, res, rigid_model(0.3_dp, 0.15_dp, 1.5_dp), &
                                        "rigid 2D stick-slip")
        end if
        call solved(t, rigid_model(1.0_dp, 0.5_dp, 1.5_dp), res, "sliding impacts")
        if (res%converged) call test_sliding(t, res, "sliding impacts")
        ! implicit Euler holds the gap at the end of each step: it splits an impact between
        ! two steps, and where the mass couples the normal with the plane the slip turns
        ! between them, so it converges to the one-shot impact only without that coupling
        call solved(t, rigid_model(1.0_dp, 0.5_dp, 1.5_dp, coupled=.false.), res, &
                    "sliding impacts, uncoupled")
        if (res%converged) then
            call test_sliding(t, res, "sliding impacts, uncoupled")
            call test_euler_first_order(t, res, rigid_model(1.0_dp, 0.5_dp, 1.5_dp, &
                                                            coupled=.false.), &
                                        "rigid 2D sliding impacts, uncoupled")
        end if
        call test_jenkins(t)
    end subroutine run_impacts_2d_tests

    !> A 2D Jenkins element on the rigid contact (the stick-slip orbit's case with k_t = 5:
    !> impact, stick, slip, open each period; its impacts frictionless, the spring carrying
    !> no impulse): the law at every sample (test_jenkins_disk_law), the energy balance with
    !> the impact loss to 1e-10, the monodromy of [x; v; s] at the section against central
    !> differences, implicit Euler started on the orbit converging to it at first order.
    subroutine test_jenkins(t)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t) :: res
        type(flow_t) :: flow
        type(model_t) :: m
        real(dp) :: bal
        m = rigid_model(0.3_dp, 0.15_dp, 1.5_dp)
        m%tangential_stiffness = [5.0_dp]
        call solved(t, m, res, "Jenkins")
        if (.not. res%converged) return
        call check(t, res%stick_phases(1) == 1 .and. res%open_fraction(1) > 0.3_dp .and. &
                   1.0_dp - res%stick_fraction(1) - res%open_fraction(1) > 0.1_dp, &
                   "impacts_2d: Jenkins: impacts, sticks once, slips and opens", &
                   real_text(res%open_fraction(1))//" open, "// &
                   real_text(res%stick_fraction(1))//" stuck")
        call test_jenkins_disk_law(t, res, "rigid 2D Jenkins", 0.0_dp, 5.0_dp)
        bal = abs(res%work_forcing - res%diss_friction - res%diss_damping - res%impact_loss)/ &
              res%work_forcing
        call check(t, bal <= 1.0e-10_dp, "impacts_2d: Jenkins: energy balance with the "// &
                   "impact loss", real_text(bal))
        flow = res%flow
        call check(t, flow%nz == 8, "impacts_2d: Jenkins: two slider states in the flow")
        call compare_monodromy(t, flow, res%t_section, res%orbit%phase_y(1:flow%nz, 1), &
                               "rigid 2D Jenkins, at the section", res%monodromy)
        call test_euler_first_order(t, res, m, "rigid 2D Jenkins")
    end subroutine test_jenkins

    !> liftoff_2d_model(fx, fy, fz) on a rigid normal (normal_stiffness 0), its mass
    !> coupling the normal with the plane (M_13 = 0.2, M_23 = 0.1) unless `coupled` is false.
    function rigid_model(fx, fy, fz, coupled) result(m)
        real(dp), intent(in) :: fx, fy, fz
        logical, intent(in), optional :: coupled
        type(model_t) :: m
        m = liftoff_2d_model(fx, fy, fz)
        m%normal_stiffness = [0.0_dp]
        if (present(coupled)) then
            if (.not. coupled) return
        end if
        m%mass(1, 3) = 0.2_dp
        m%mass(3, 1) = 0.2_dp
        m%mass(2, 3) = 0.1_dp
        m%mass(3, 2) = 0.1_dp
    end function rigid_model

    !> An orbit whose impacts slide: it never sticks; the law at every sample; the
    !> monodromy at the section against central differences (through the sliding impact,
    !> whose impulse turns with the slip after it).
    subroutine test_sliding(t, res, name)
        type(test_counter_t), intent(inout) :: t
        type(reference_result_t), intent(in) :: res
        character(len=*), intent(in) :: name
        type(flow_t) :: flow
        call check(t, res%stick_fraction(1) == 0.0_dp .and. res%open_fraction(1) < 0.7_dp, &
                   "impacts_2d: "//name//": slips the whole closed time", &
                   real_text(1.0_dp - res%open_fraction(1))//" slipping")
        call test_disk_law(t, res, "rigid 2D "//name, 0.0_dp)
        flow = res%flow
        call compare_monodromy(t, flow, res%t_section, res%orbit%phase_y(1:flow%nz, 1), &
                               "rigid 2D "//name//", at the section", res%monodromy)
    end subroutine test_sliding

    !> The reference from the implicit Euler start (the weighted residual does not resolve
    !> impacts), periodic, with an impact and its loss.
    subroutine solved(t, m, res, name)
        type(test_counter_t), intent(inout) :: t
        type(model_t), intent(in) :: m
        type(reference_result_t), intent(out) :: res
        character(len=*), intent(in) :: name
        call reference(t, m, res, "rigid 2D "//name, start='euler')
        if (.not. res%converged) return
        call check(t, res%impact_loss > 0.01_dp*res%work_forcing, "impacts_2d: "//name// &
                   ": an impact and its loss", real_text(res%impact_loss))
    end subroutine solved
end module test_impacts_2d
