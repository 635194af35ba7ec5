!> One period of the exact flow, recorded (stickslip_flow, stickslip_flow_law_map): its
!> phases, its events and its energy balance. Plain data.
module stickslip_flow_orbit
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: orbit_t

    !> One period of the flow, recorded: its phases, its events and its energy balance.
    type :: orbit_t
        !> Start of the period [s].
        real(dp) :: t0 = 0.0_dp
        !> Number of phases; phase p starts at phase_t(p) in state phase_y(:, p) and mode
        !> phase_mode(p); the last one ends at t0 + T.
        integer :: nphase = 0
        real(dp), allocatable :: phase_t(:)
        real(dp), allocatable :: phase_y(:, :)
        integer, allocatable :: phase_mode(:)
        !> Events: time [s] (in [t0, t0 + T)), contact, kind (event_*), slip direction after
        !> the event (0: stuck), friction force at the event [N], slip velocity [m/s].
        integer :: nevent = 0
        real(dp), allocatable :: event_t(:), event_force(:), event_velocity(:)
        integer, allocatable :: event_contact(:), event_kind(:), event_direction(:)
        !> Work of the forcing, friction and viscous dissipation over the period [J].
        real(dp) :: work_forcing = 0.0_dp, diss_friction = 0.0_dp, diss_damping = 0.0_dp
        !> Gross work of the forcing, integral |f . v| dt [J].
        real(dp) :: work_gross = 0.0_dp
        !> Time spent stuck, per contact [s].
        real(dp), allocatable :: stick_time(:)
        !> Contact laws: time spent open, per contact [s], and the kinetic energy lost in the
        !> impacts of rigid unilateral contacts over the period [J] (the energy balance is
        !> then work_forcing = diss_friction + diss_damping + impact_loss).
        real(dp), allocatable :: open_time(:)
        real(dp) :: impact_loss = 0.0_dp
    end type orbit_t
end module stickslip_flow_orbit
