!> One period of the exact flow, recorded (stickslip_flow, stickslip_flow_law_map): its
!> phases, its events and its energy balance, with the procedures that record them.
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
        !> A phase of a nonlinear mode is recorded step by step: the Taylor coefficients of
        !> each step's input polynomial followed by the elements' slip memories (phase_b(:,
        !> p), stickslip_flow_nonlinear; unused for a linear phase), and the sum of the
        !> steps' error estimates over the period (relative to the state's size; 0 without
        !> nonlinear phases).
        real(dp), allocatable :: phase_b(:, :)
        real(dp) :: integration_error = 0.0_dp
        !> Events of another contact at the instant of the one before (within 1e-12 of the
        !> period: sectors in phase, or contacts that reach their limits together), where
        !> the flow's linearization depends on the order it took them in; the first such
        !> instant [s] and its two contacts.
        integer :: simultaneous = 0
        real(dp) :: simultaneous_t = 0.0_dp
        integer :: simultaneous_contacts(2) = 0
    contains
        procedure :: start => orbit_start
        procedure :: add_phase => orbit_add_phase
        procedure :: add_event => orbit_add_event
    end type orbit_t

contains

    !> Start recording a period at t0 [s]: room for 16 phases of augmented states of size na
    !> and 16 events (both grow), stick and open times of nc contacts set to zero.
    subroutine orbit_start(self, t0, na, nc)
        !> The orbit (reset).
        class(orbit_t), intent(inout) :: self
        !> Start time [s].
        real(dp), intent(in) :: t0
        !> Augmented state size and number of contacts.
        integer, intent(in) :: na, nc
        self%t0 = t0
        self%nphase = 0
        self%simultaneous = 0
        self%simultaneous_t = 0.0_dp
        self%simultaneous_contacts = 0
        self%nevent = 0
        allocate (self%phase_t(16), self%phase_y(na, 16), self%phase_mode(16))
        allocate (self%event_t(16), self%event_force(16), self%event_velocity(16), &
                  self%event_contact(16), self%event_kind(16), self%event_direction(16))
        allocate (self%stick_time(nc), self%open_time(nc), self%phase_b(0, 16))
        self%stick_time = 0.0_dp
        self%open_time = 0.0_dp
        self%impact_loss = 0.0_dp
        self%integration_error = 0.0_dp
    end subroutine orbit_start

    !> A phase starting at ts [s] in state ys (augmented, model coordinates) and mode imode.
    subroutine orbit_add_phase(self, ts, ys, imode, b)
        !> The orbit.
        class(orbit_t), intent(inout) :: self
        !> Start time [s] and state of the phase.
        real(dp), intent(in) :: ts, ys(:)
        !> Its mode (index in the flow's cache).
        integer, intent(in) :: imode
        !> A nonlinear step: the Taylor coefficients of its input polynomial and the slip
        !> memories.
        real(dp), intent(in), optional :: b(:)
        real(dp), allocatable :: rt(:), ry(:, :), rb(:, :)
        integer, allocatable :: im2(:)
        integer :: m, nb
        m = self%nphase
        nb = 0
        if (present(b)) nb = size(b)
        if (.not. allocated(self%phase_b)) allocate (self%phase_b(0, size(self%phase_t)))
        if (nb > size(self%phase_b, 1)) then
            allocate (rb(nb, size(self%phase_t)))
            rb = 0.0_dp
            rb(1:size(self%phase_b, 1), 1:m) = self%phase_b(:, 1:m)
            call move_alloc(rb, self%phase_b)
        end if
        if (m == size(self%phase_t)) then
            allocate (rt(2*m), ry(size(ys), 2*m), im2(2*m), rb(size(self%phase_b, 1), 2*m))
            rt(1:m) = self%phase_t
            ry(:, 1:m) = self%phase_y
            im2(1:m) = self%phase_mode
            rb(:, 1:m) = self%phase_b(:, 1:m)
            call move_alloc(rt, self%phase_t)
            call move_alloc(ry, self%phase_y)
            call move_alloc(im2, self%phase_mode)
            call move_alloc(rb, self%phase_b)
        end if
        self%nphase = m + 1
        self%phase_t(m + 1) = ts
        self%phase_y(:, m + 1) = ys
        self%phase_mode(m + 1) = imode
        self%phase_b(:, m + 1) = 0.0_dp
        if (nb > 0) self%phase_b(1:nb, m + 1) = b
    end subroutine orbit_add_phase

    !> An event at ts [s] of `contact`: its kind, the slip direction after it, the friction
    !> force [N] and slip velocity [m/s] there.
    subroutine orbit_add_event(self, ts, contact, kind, direction, force, velocity)
        !> The orbit.
        class(orbit_t), intent(inout) :: self
        !> Time [s], friction force [N], slip velocity [m/s].
        real(dp), intent(in) :: ts, force, velocity
        !> Contact, kind and slip direction after the event.
        integer, intent(in) :: contact, kind, direction
        integer :: m
        m = self%nevent
        if (m == size(self%event_t)) then
            self%event_t = [self%event_t, self%event_t]
            self%event_force = [self%event_force, self%event_force]
            self%event_velocity = [self%event_velocity, self%event_velocity]
            self%event_contact = [self%event_contact, self%event_contact]
            self%event_kind = [self%event_kind, self%event_kind]
            self%event_direction = [self%event_direction, self%event_direction]
        end if
        self%nevent = m + 1
        self%event_t(m + 1) = ts
        self%event_contact(m + 1) = contact
        self%event_kind(m + 1) = kind
        self%event_direction(m + 1) = direction
        self%event_force(m + 1) = force
        self%event_velocity(m + 1) = velocity
    end subroutine orbit_add_event
end module stickslip_flow_orbit
