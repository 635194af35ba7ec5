!> What a contact element puts into the modes of the exact event-driven flow (doc/contacts.md,
!> section 5), in the flow's balanced modal coordinates. The flow (src/exact/) steps the
!> augmented state
!>     y = [p (n); u (n); sigma (n_s); e~ (n_e)],
!> x = Phi S^-1 p, v = Phi u (Phi the M-orthonormal modes of (K, M), S = diag(s)), sigma_k =
!> c_k s_k the internal states of the elements (the slider positions of a Jenkins or
!> microslip element, scaled by c_k = sqrt(k_t)), e~ = se e the exosystem of the harmonic
!> forcing (e(1) = 1, then cos/sin pairs). Between events every contact is in one mode (an
!> integer code per code slot of its element: 0 stuck, +1 / -1 slipping in that direction,
!> 2 open) and the motion is linear:
!>     u' = hb y + Ft Lambda,  sigma' = sb y,  channel forces = fb y (+ Lambda),
!> Lambda the forces of the velocity constraints Ct^T u = 0 (stuck rigid friction, closed
!> rigid normals), solved by the flow. An element adds, for its codes:
!> - forces linear in y along its directions (mode_terms_t%add_force), its channel forces
!>   (fb rows) and the rates of its internal states (sb rows), its constraints (constrain);
!> - its event functions, rows in y that stay positive while the mode lasts, each with the
!>   scale of its values and what happens at its zero (event_list_t);
!> - at an event or at the start, its codes (start_code, candidates and consistent for the
!>   joint decisions of rigid contacts, local_decide for elastic ones).
!> element_geometry_t gives an element its directions in these coordinates and the rows of
!> its kinematic quantities (disp_row, vel_row, const_row, state_row).
module stickslip_contact_modes
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: element_geometry_t, mode_terms_t, event_list_t
    public :: action_decide, action_close, action_none, action_memory, code_unloaded

    !> A code of a contact closed but carrying less than its element's force floor (the
    !> friction unloaded; reported as open: events, states).
    integer, parameter :: code_unloaded = 3

    !> What happens at the zero of an event row besides a code switch: the codes of the
    !> contacts there are decided anew (action_decide), or an open contact closes (its
    !> codes decided, with an impact when it is rigid and closes with a velocity:
    !> action_close), or the element's slip memory is updated at that state, its codes kept
    !> (action_memory: a 2D slip started from rest begins to follow its velocity). A value
    !> >= -1 and <= code_unloaded switches the slot to that code.
    integer, parameter :: action_decide = 100, action_close = 101, action_none = 102, &
                          action_memory = 103

    !> An element's place in the flow's coordinates.
    type :: element_geometry_t
        !> DOFs n, augmented size na, internal states of all elements n_s.
        integer :: n = 0, na = 0, ns = 0
        !> The element's index among the contacts; its internal states are y(2n + s0 + 1 :
        !> 2n + s0 + nstate); its first force channel is first; its first code slot slot0 + 1.
        integer :: index = 0, s0 = 0, first = 0, slot0 = 0
        !> Index of the exosystem's constant in y (2n + n_s + 1) and its value there (se).
        integer :: ic = 0
        real(dp) :: se = 1.0_dp
        !> Fundamental angular frequency [rad/s].
        real(dp) :: omega = 0.0_dp
        !> Modal scales s (x = Phi S^-1 p), n.
        real(dp), allocatable :: s(:)
        !> The contact's directions in modal coordinates Phi^T w, Phi^T t2, Phi^T n, n x 3
        !> (zero columns where the contact has none).
        real(dp), allocatable :: dt(:, :)
        !> Scales c_k of the element's internal states (sigma_k = c_k s_k).
        real(dp), allocatable :: cs(:)
        !> Scales of the element's slip velocities [m/s], gaps [m] and forces [N] (event
        !> tests and tolerances).
        real(dp) :: vref = 1.0_dp, gref = 1.0_dp, fref = 1.0_dp
    contains
        !> d^T x along a direction (1 w, 2 t2, 3 n) as a row of y.
        procedure :: disp_row
        !> d^T v along a direction as a row of y.
        procedure :: vel_row
        !> A constant as a row of y.
        procedure :: const_row
        !> The element's internal state s_k (model units) as a row of y.
        procedure :: state_row
    end type element_geometry_t

    !> The linear dynamics a mode's elements put on the structure, before the constraints
    !> are solved (built by the flow, filled by the elements' mode_terms).
    type :: mode_terms_t
        !> Modal accelerations u' = hb y, n x na.
        real(dp), allocatable :: hb(:, :)
        !> Rates of the internal states sigma' = sb y, n_s x na.
        real(dp), allocatable :: sb(:, :)
        !> Channel forces fb y, n_ch x na [N].
        real(dp), allocatable :: fb(:, :)
        !> Velocity constraints: direction ctm(:, k) (Ct^T u = 0), force direction ftm(:, k),
        !> the channel its force is (and slip_factor times it on channel slip_ch when > 0).
        real(dp), allocatable :: ctm(:, :), ftm(:, :)
        integer, allocatable :: chan(:), slip_ch(:)
        real(dp), allocatable :: slip_factor(:)
        !> Nonlinear inputs (some element's force or slider rate in this mode is not linear
        !> in y: a 2D slip): input k (its value q_k(y) given by its element's `inputs`) adds
        !> gu(:, k) q_k to u', gs(:, k) q_k to sigma' and gf(:, k) q_k to the channel
        !> forces; in_elem(k) its element. The flow integrates such a mode numerically.
        real(dp), allocatable :: gu(:, :), gs(:, :), gf(:, :)
        integer, allocatable :: in_elem(:)
        !> Internal-state rates from the rate of a channel force (a slider behind a spring
        !> whose force is a constraint force: s' = w^T v + factor lambda'): sigma'(rate_state)
        !> += rate_factor lambda', lambda the force of channel rate_chan, added once the
        !> constraints are solved (lambda' = fb(rate_chan) . y').
        integer, allocatable :: rate_state(:), rate_chan(:)
        real(dp), allocatable :: rate_factor(:)
        !> Event rows on an internal state's rate (its row known once the constraints are
        !> solved): rev_factor sigma'(rev_state), of element rev_elem, with the scale, code
        !> slot (of the element) and action of event_list_t.
        integer, allocatable :: rev_state(:), rev_elem(:), rev_slot(:), rev_action(:)
        real(dp), allocatable :: rev_factor(:), rev_scale(:)
    contains
        !> A force along a modal direction, linear in y.
        procedure :: add_force
        !> A velocity constraint and the force that holds it.
        procedure :: constrain
        !> A nonlinear input.
        procedure :: add_input
        !> An internal state's rate from the rate of a channel force.
        procedure :: add_force_rate
        !> An event row on an internal state's rate.
        procedure :: add_rate_event
        !> Reset for a new mode.
        procedure :: reset
        !> Whether the mode has nonlinear inputs.
        procedure :: nonlinear
    end type mode_terms_t

    !> The event functions of one element in one mode: rows of y (positive while the mode
    !> lasts), the scale of their values, the code slot they concern and the action; and
    !> quadratic ones, g(y) = y^T Q y + c (a force reaching a circle, a 2D slider stopping).
    type :: event_list_t
        integer :: count = 0
        real(dp), allocatable :: rows(:, :)
        real(dp), allocatable :: scale(:)
        integer, allocatable :: slot(:), action(:)
        !> Quadratic events: Q (na x na x nq), c, scale, slot, action.
        integer :: nq = 0
        real(dp), allocatable :: qmat(:, :, :), qc(:), qscale(:)
        integer, allocatable :: qslot(:), qaction(:)
    contains
        !> Add an event row.
        procedure :: add => event_add
        !> Add a quadratic event.
        procedure :: add_quadratic => event_add_quadratic
        !> Empty the list (rows of length na).
        procedure :: clear => event_clear
    end type event_list_t

contains

    !> d^T x as a row of y: (Phi^T d / s) on p.
    pure function disp_row(self, along) result(row)
        !> The geometry.
        class(element_geometry_t), intent(in) :: self
        !> 1: w, 2: t2, 3: n.
        integer, intent(in) :: along
        real(dp) :: row(self%na)
        row = 0.0_dp
        row(1:self%n) = self%dt(:, along)/self%s
    end function disp_row

    !> d^T v as a row of y: Phi^T d on u.
    pure function vel_row(self, along) result(row)
        !> The geometry.
        class(element_geometry_t), intent(in) :: self
        !> 1: w, 2: t2, 3: n.
        integer, intent(in) :: along
        real(dp) :: row(self%na)
        row = 0.0_dp
        row(self%n + 1:2*self%n) = self%dt(:, along)
    end function vel_row

    !> The constant c as a row of y (the exosystem's constant, se).
    pure function const_row(self, c) result(row)
        !> The geometry.
        class(element_geometry_t), intent(in) :: self
        !> The constant.
        real(dp), intent(in) :: c
        real(dp) :: row(self%na)
        row = 0.0_dp
        row(self%ic) = c/self%se
    end function const_row

    !> The element's internal state s_k [m] as a row of y (sigma_k / c_k).
    pure function state_row(self, k) result(row)
        !> The geometry.
        class(element_geometry_t), intent(in) :: self
        !> Internal state of the element (1..nstate).
        integer, intent(in) :: k
        real(dp) :: row(self%na)
        row = 0.0_dp
        row(2*self%n + self%s0 + k) = 1.0_dp/self%cs(k)
    end function state_row

    !> u' += dir (row . y): a force (row . y) along the modal direction dir.
    pure subroutine add_force(self, dir, row)
        !> The terms.
        class(mode_terms_t), intent(inout) :: self
        !> Modal direction (n) and the force's row (na).
        real(dp), intent(in) :: dir(:), row(:)
        integer :: q
        do q = 1, size(row)
            if (row(q) /= 0.0_dp) self%hb(:, q) = self%hb(:, q) + dir*row(q)
        end do
    end subroutine add_force

    !> A constraint: modal direction cdir (cdir . u held at zero) and force direction fdir,
    !> its force being channel ch (and slip_factor times it channel slip_ch when > 0).
    pure subroutine constrain(self, cdir, fdir, ch, slip_ch, slip_factor)
        !> The terms.
        class(mode_terms_t), intent(inout) :: self
        !> Constraint and force directions (n).
        real(dp), intent(in) :: cdir(:), fdir(:)
        !> Channels.
        integer, intent(in) :: ch, slip_ch
        !> Factor of the second channel.
        real(dp), intent(in) :: slip_factor
        integer :: n, k
        n = size(cdir)
        k = size(self%chan)
        self%ctm = reshape([self%ctm, cdir], [n, k + 1])
        self%ftm = reshape([self%ftm, fdir], [n, k + 1])
        self%chan = [self%chan, ch]
        self%slip_ch = [self%slip_ch, slip_ch]
        self%slip_factor = [self%slip_factor, slip_factor]
    end subroutine constrain

    !> A nonlinear input of element j: its columns in u' (ucol, n), in sigma' (scol, n_s) and
    !> in the channel forces (fcol, n_ch).
    pure subroutine add_input(self, j, ucol, scol, fcol)
        !> The terms.
        class(mode_terms_t), intent(inout) :: self
        !> The element.
        integer, intent(in) :: j
        !> Its columns.
        real(dp), intent(in) :: ucol(:), scol(:), fcol(:)
        integer :: k
        k = size(self%in_elem)
        self%gu = reshape([self%gu, ucol], [size(ucol), k + 1])
        self%gs = reshape([self%gs, scol], [size(scol), k + 1])
        self%gf = reshape([self%gf, fcol], [size(fcol), k + 1])
        self%in_elem = [self%in_elem, j]
    end subroutine add_input

    !> sigma'(is) += factor lambda', lambda the force of channel ch (resolved once the mode's
    !> constraints are solved).
    pure subroutine add_force_rate(self, is, ch, factor)
        !> The terms.
        class(mode_terms_t), intent(inout) :: self
        !> Internal state (1..n_s) and channel.
        integer, intent(in) :: is, ch
        !> The factor [(model state unit) c_k / N].
        real(dp), intent(in) :: factor
        self%rate_state = [self%rate_state, is]
        self%rate_chan = [self%rate_chan, ch]
        self%rate_factor = [self%rate_factor, factor]
    end subroutine add_force_rate

    !> An event row factor sigma'(is) of element j (positive while the mode lasts), the
    !> scale of its values, the code slot (of the element) and the action at its zero.
    pure subroutine add_rate_event(self, j, is, factor, scale, slot, action)
        !> The terms.
        class(mode_terms_t), intent(inout) :: self
        !> Element, internal state (1..n_s).
        integer, intent(in) :: j, is
        !> Factor and scale of the values.
        real(dp), intent(in) :: factor, scale
        !> Code slot and action.
        integer, intent(in) :: slot, action
        self%rev_elem = [self%rev_elem, j]
        self%rev_state = [self%rev_state, is]
        self%rev_factor = [self%rev_factor, factor]
        self%rev_scale = [self%rev_scale, scale]
        self%rev_slot = [self%rev_slot, slot]
        self%rev_action = [self%rev_action, action]
    end subroutine add_rate_event

    !> The mode has nonlinear inputs.
    pure logical function nonlinear(self)
        !> The terms.
        class(mode_terms_t), intent(in) :: self
        nonlinear = .false.
        if (allocated(self%in_elem)) nonlinear = size(self%in_elem) > 0
    end function nonlinear

    !> Empty terms for n DOFs, na augmented entries, ns internal states, nch channels.
    pure subroutine reset(self, n, na, ns, nch)
        !> The terms.
        class(mode_terms_t), intent(inout) :: self
        !> Sizes.
        integer, intent(in) :: n, na, ns, nch
        if (allocated(self%hb)) deallocate (self%hb)
        if (allocated(self%sb)) deallocate (self%sb)
        if (allocated(self%fb)) deallocate (self%fb)
        allocate (self%hb(n, na), self%sb(ns, na), self%fb(nch, na))
        self%hb = 0.0_dp
        self%sb = 0.0_dp
        self%fb = 0.0_dp
        if (allocated(self%ctm)) deallocate (self%ctm, self%ftm, self%chan, self%slip_ch, &
                                             self%slip_factor)
        allocate (self%ctm(n, 0), self%ftm(n, 0), self%chan(0), self%slip_ch(0), &
                  self%slip_factor(0))
        if (allocated(self%gu)) deallocate (self%gu, self%gs, self%gf, self%in_elem)
        allocate (self%gu(n, 0), self%gs(ns, 0), self%gf(nch, 0), self%in_elem(0))
        self%rate_state = [integer ::]
        self%rate_chan = [integer ::]
        self%rate_factor = [real(dp) ::]
        self%rev_state = [integer ::]
        self%rev_elem = [integer ::]
        self%rev_slot = [integer ::]
        self%rev_action = [integer ::]
        self%rev_factor = [real(dp) ::]
        self%rev_scale = [real(dp) ::]
    end subroutine reset

    !> Add an event row of y (positive while the mode lasts), the scale of its values, the
    !> code slot it concerns (of the element) and the action at its zero (a code, or
    !> action_decide / action_close).
    pure subroutine event_add(self, row, scale, slot, action)
        !> The list.
        class(event_list_t), intent(inout) :: self
        !> The row (na).
        real(dp), intent(in) :: row(:)
        !> Scale of its values (> 0).
        real(dp), intent(in) :: scale
        !> Code slot and action.
        integer, intent(in) :: slot, action
        real(dp), allocatable :: grown(:, :), gscale(:)
        integer, allocatable :: gslot(:), gaction(:)
        integer :: m, cap
        m = self%count
        if (m == size(self%scale)) then
            cap = 2*m + 4
            allocate (grown(size(row), cap), gscale(cap), gslot(cap), gaction(cap))
            grown(:, 1:m) = self%rows(:, 1:m)
            gscale(1:m) = self%scale(1:m)
            gslot(1:m) = self%slot(1:m)
            gaction(1:m) = self%action(1:m)
            call move_alloc(grown, self%rows)
            call move_alloc(gscale, self%scale)
            call move_alloc(gslot, self%slot)
            call move_alloc(gaction, self%action)
        end if
        self%count = m + 1
        self%rows(:, m + 1) = row
        self%scale(m + 1) = scale
        self%slot(m + 1) = slot
        self%action(m + 1) = action
    end subroutine event_add

    !> Add a quadratic event g(y) = y^T Q y + c (positive while the mode lasts).
    pure subroutine event_add_quadratic(self, q, c, scale, slot, action)
        !> The list.
        class(event_list_t), intent(inout) :: self
        !> Q (na x na, symmetric) and c.
        real(dp), intent(in) :: q(:, :), c
        !> Scale of its values (> 0).
        real(dp), intent(in) :: scale
        !> Code slot and action.
        integer, intent(in) :: slot, action
        real(dp), allocatable :: grown(:, :, :)
        integer :: m
        m = self%nq
        if (m == size(self%qmat, 3)) then
            allocate (grown(size(q, 1), size(q, 2), m + 2))
            grown(:, :, 1:m) = self%qmat(:, :, 1:m)
            call move_alloc(grown, self%qmat)
        end if
        self%nq = m + 1
        self%qmat(:, :, m + 1) = q
        self%qc = [self%qc(1:m), c]
        self%qscale = [self%qscale(1:m), scale]
        self%qslot = [self%qslot(1:m), slot]
        self%qaction = [self%qaction(1:m), action]
    end subroutine event_add_quadratic

    !> Empty the list for rows of length na.
    pure subroutine event_clear(self, na)
        !> The list.
        class(event_list_t), intent(inout) :: self
        !> Row length.
        integer, intent(in) :: na
        self%count = 0
        self%nq = 0
        if (allocated(self%qmat)) deallocate (self%qmat, self%qc, self%qscale, self%qslot, &
                                              self%qaction)
        allocate (self%qmat(na, na, 0), self%qc(0), self%qscale(0), self%qslot(0), &
                  self%qaction(0))
        if (allocated(self%rows)) then
            if (size(self%rows, 1) == na) return
            deallocate (self%rows, self%scale, self%slot, self%action)
        end if
        allocate (self%rows(na, 4), self%scale(4), self%slot(4), self%action(4))
    end subroutine event_clear
end module stickslip_contact_modes
