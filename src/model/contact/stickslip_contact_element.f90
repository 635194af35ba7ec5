!> The contact element: everything a contact law means to the methods, behind one abstract
!> type (doc/contacts.md; how to add a law: doc/layout.md, "Adding a contact law").
!>
!> An element acts on the structure through its force channels (one to n unknown forces per
!> instant), each along one of its contact's directions (the first tangent w, the second
!> tangent t2 or the normal n: channel_t%along) with a force r_c [N] and a kinematic quantity
!> u_c in velocity units [m/s] (channel_t%kinematics):
!> - kinematics_velocity: u = d^T x' + compliance r' (a slider velocity behind a spring of
!>   stiffness 1 / compliance; d^T x' for a rigid channel);
!> - kinematics_gap: u = omega (gap + d^T x + compliance r) (omega times the gap, the
!>   compliance of an elastic normal inside).
!> u is affine in the channel forces through the condensed structure, which the methods
!> build from the channels alone. The law itself is what the element adds:
!> - the equalities Psi(r, u) = 0 of its channels and their generalized Jacobians on a batch
!>   of samples (psi, psi_jacobian: the weighted residual; the local solve of one implicit
!>   Euler step, step_forces, and of the event decisions of the exact flow);
!> - the state of the contact at each sample (open, stick, slip), the dissipation Coulomb's
!>   law assigns to the samples and the force-limit ratio (the one definition of each,
!>   stickslip_contact_measures), its force scale, its preload, the settling of a mean force
!>   a contact stuck all period leaves undetermined;
!> - for the exact event-driven reference, its modes (extended in later files).
!> The defaults below are written once for every law; an element overrides what it can do
!> faster or what is its own (the rigid Coulomb contact under a constant load keeps the
!> batched kernels of before: stickslip_coulomb_element).
module stickslip_contact_element
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_basis, only: basis_t
    use stickslip_contact_law, only: state_open, state_stick, state_slip
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t, &
        code_unloaded
    implicit none
    private
    public :: contact_element_t, element_box_t, channel_t, hb_work_t
    public :: kinematics_velocity, kinematics_gap, along_tangent, along_tangent2, along_normal
    public :: state_open, state_stick, state_slip, element_step_forces
    public :: accel_none, accel_box, accel_alone, accel_keep

    !> How an element takes part in a joint decision at rest (accel_law): not at
    !> acceleration level (the enumeration of candidates decides); by a law on some of its
    !> channels, solved with the others' (a box of the Coulomb or disk kind); alone after
    !> the others (it carries no force at that instant); its code stands (it moves).
    integer, parameter :: accel_none = 0, accel_box = 1, accel_alone = 2, accel_keep = 3

    !> Kinematic quantity of a channel: a (slider) velocity, or omega times a gap.
    integer, parameter :: kinematics_velocity = 1, kinematics_gap = 2
    !> The contact direction a channel acts along.
    integer, parameter :: along_tangent = 1, along_tangent2 = 2, along_normal = 3

    !> One force channel of an element.
    type :: channel_t
        !> The direction it acts along: along_tangent, along_tangent2 or along_normal.
        integer :: along = along_tangent
        !> Its kinematic quantity: kinematics_velocity or kinematics_gap.
        integer :: kinematics = kinematics_velocity
        !> Compliance [m/N] in series (1 / contact stiffness; 0: rigid).
        real(dp) :: compliance = 0.0_dp
        !> Initial gap [m] (kinematics_gap).
        real(dp) :: gap = 0.0_dp
        !> The channel can carry a force (a friction limit or a normal law): the channels
        !> that weigh the automatic rho (stickslip_rho).
        logical :: holds = .true.
    end type channel_t

    !> Work arrays of the weighted-residual Jacobian of one element (owned by the problem:
    !> one per thread).
    type :: hb_work_t
        !> P diag(w) Q, nb x nb.
        real(dp), allocatable :: a(:, :)
        !> A weight function at the samples (nt).
        real(dp), allocatable :: w(:)
        !> FFT work (nt/2 + 1).
        complex(dp), allocatable :: cw(:)
    end type hb_work_t

    !> A contact law. Extended once per law, one file each (src/model/contact/).
    type, abstract :: contact_element_t
        !> The force channels, set by the element's constructor.
        type(channel_t), allocatable :: channel(:)
    contains
        !> Number of force channels.
        procedure :: nchannel => element_nchannel
        !> The law's name (messages, doc/contacts.md).
        procedure(law_name_i), deferred :: law_name
        !> Psi at a batch of samples.
        procedure(psi_i), deferred :: psi
        !> Psi and its generalized Jacobians at a batch of samples.
        procedure(psi_jacobian_i), deferred :: psi_jacobian
        !> The contact's state at a batch of samples.
        procedure(states_i), deferred :: states
        !> The state after implicit steps (default: states).
        procedure :: step_states => element_step_states
        !> Coulomb's dissipation at a batch of samples, integrated over a period.
        procedure(dissipation_i), deferred :: coulomb_dissipation
        !> The force-limit ratio of a batch of samples.
        procedure(ratio_i), deferred :: force_ratio
        !> The force the element carries at most [N].
        procedure(scale_i), deferred :: force_scale
        !> The friction limit of a channel at rest [N] (0 for a normal channel).
        procedure :: rest_limit => element_rest_limit
        !> The constant normal load [N] (0 when the normal force is a channel or absent).
        procedure :: normal_load => element_normal_load
        !> The static preload along the normal [N] (0: none).
        procedure :: preload => element_preload
        !> Check the parameters (an element given explicitly by a host code or case).
        procedure :: validate => element_validate
        !> Set a sweep parameter (mu, normal_load, preload) when the law has it.
        procedure :: set_parameter => element_set_parameter
        !> Settle the mean forces of a contact stuck over the whole period.
        procedure :: settle_offset => element_settle_offset
        !> The forces of one implicit step: Psi(r, q + A r) = 0.
        procedure :: step_forces => element_step_forces
        !> The fallback of step_forces when its Newton iteration stalls.
        procedure :: project => element_project
        !> The element's rows of the weighted-residual Jacobian.
        procedure :: hb_jacobian => element_hb_jacobian
        ! --- the exact event-driven flow (stickslip_contact_modes) ---
        !> Why the exact flow cannot take the law ('' when it can).
        procedure :: exact_support => element_exact_support
        !> Code slots of the element's modes (default 1).
        procedure :: ncode => element_ncode
        !> Internal states (slider positions; default none).
        procedure :: nstate => element_nstate
        !> Scales c_k of the internal states in the flow's coordinates.
        procedure :: state_scales => element_state_scales
        !> The internal states of a start from its displacements and channel forces.
        procedure :: initial_states => element_initial_states
        !> What a mode puts on the structure.
        procedure :: mode_terms => element_mode_terms
        !> The event rows of a mode.
        procedure :: event_rows => element_event_rows
        !> Events of a mode that need its linear dynamics (a slider's rate that follows a
        !> constraint force's rate in a nonlinear phase; default none).
        procedure :: dynamics_events => element_dynamics_events
        !> The codes at a start state.
        procedure :: start_code => element_start_code
        !> Takes part in the joint decisions of rigid contacts (a rigid constraint).
        procedure :: coupled => element_coupled
        !> Holds a rigid constraint in a mode (its code may change when another's does).
        procedure :: holds_constraint => element_holds_constraint
        !> The candidate codes of a joint decision.
        procedure :: candidates => element_candidates
        !> Whether a trial mode is consistent with the law at a state.
        procedure :: consistent => element_consistent
        !> The codes of an elastic element at an event, decided alone.
        procedure :: local_decide => element_local_decide
        !> The contact state (open, stick, slip) of a mode.
        procedure :: code_state => element_code_state
        !> A rigid normal closing with a velocity at an event: an impact.
        procedure :: impacts => element_impacts
        !> The element whose law its impacts obey (default: itself).
        procedure :: impact_law => element_impact_law
        !> A rigid normal, closed in the mode (part of an impact).
        procedure :: rigid_closed => element_rigid_closed
        !> A rigid normal at a zero or negative gap at the start (projected onto the gap).
        procedure :: start_gap => element_start_gap
        !> The internal states of a start put on the set its codes allow (a slipping
        !> slider's spring on its limit).
        procedure :: start_states => element_start_states
        !> The internal states after an event switched its codes (a slider unloaded as
        !> its contact opens; default: kept).
        procedure :: event_states => element_event_states
        !> The values of the element's nonlinear inputs in a mode (a 2D slip) and their
        !> Jacobian.
        procedure :: inputs => element_inputs
        !> Event rows of a nonlinear mode that depend on the slip direction of the step.
        procedure :: step_rows => element_step_rows
        !> The slip direction on entering a 2D slip.
        procedure :: slip_direction => element_slip_direction
        !> Decides its codes at rest from its forces at acceleration level (with
        !> accel_code).
        procedure :: accel_decision => element_accel_decision
        !> Its codes from its forces and accelerations at rest.
        procedure :: accel_code => element_accel_code
        !> How it takes part in a joint decision at a state (accel_none, ...).
        procedure :: accel_law => element_accel_law
    end type contact_element_t

    !> A slot holding one element (arrays of polymorphic elements).
    type :: element_box_t
        class(contact_element_t), allocatable :: e
    end type element_box_t

    abstract interface
        !> The law's name ('coulomb', 'planar', 'jenkins', 'unilateral', 'iwan', ...).
        pure function law_name_i(self) result(name)
            import :: contact_element_t
            class(contact_element_t), intent(in) :: self
            character(len=:), allocatable :: name
        end function law_name_i

        !> Psi(r, u) at nt samples [m/s]: forces r (nt x m) [N], kinematic quantities u
        !> (nt x m) [m/s], weight rho [m/(N s)]; p (nt x m).
        subroutine psi_i(self, rho, r, u, p)
            import :: contact_element_t, dp
            class(contact_element_t), intent(in) :: self
            real(dp), intent(in) :: rho, r(:, :), u(:, :)
            real(dp), intent(out) :: p(:, :)
        end subroutine psi_i

        !> Psi and its generalized Jacobians jr = dPsi/dr [m/(N s)] and ju = dPsi/du
        !> (m x m x nt; Clarke elements, the slip/open side on region boundaries).
        subroutine psi_jacobian_i(self, rho, r, u, p, jr, ju)
            import :: contact_element_t, dp
            class(contact_element_t), intent(in) :: self
            real(dp), intent(in) :: rho, r(:, :), u(:, :)
            real(dp), intent(out) :: p(:, :), jr(:, :, :), ju(:, :, :)
        end subroutine psi_jacobian_i

        !> The state at nt samples: state_open, state_stick or state_slip (the regions of Psi
        !> with weight rho).
        subroutine states_i(self, rho, r, u, state)
            import :: contact_element_t, dp
            class(contact_element_t), intent(in) :: self
            real(dp), intent(in) :: rho, r(:, :), u(:, :)
            integer, intent(out) :: state(:)
        end subroutine states_i

        !> Over one period of `period` [s] sampled uniformly (r, u: nt x m; state from
        !> states with the weight rho): `diss` the dissipation Coulomb's law gives the slip
        !> velocities, the integral of g(t) |u_t(t)| (g the friction limit, u_t the slip
        !> velocity) [J]; and `law_diss`, what the law dissipates, g |u_t| where the contact
        !> slips and |r . u_t| where it sticks [J] (the scale of the Coulomb check).
        subroutine dissipation_i(self, rho, r, u, state, period, diss, law_diss)
            import :: contact_element_t, dp
            class(contact_element_t), intent(in) :: self
            real(dp), intent(in) :: rho, r(:, :), u(:, :), period
            integer, intent(in) :: state(:)
            real(dp), intent(out) :: diss, law_diss
        end subroutine dissipation_i

        !> max_t (|r_t(t)| - g(t)) / max_t g(t) + 1 over the samples (1 at the limit), 0
        !> when the element can hold no friction force (dimensionless).
        real(dp) function ratio_i(self, r) result(ratio)
            import :: contact_element_t, dp
            class(contact_element_t), intent(in) :: self
            real(dp), intent(in) :: r(:, :)
        end function ratio_i

        !> The force the element carries at most or at rest [N] (scales of tolerances).
        pure real(dp) function scale_i(self) result(f)
            import :: contact_element_t, dp
            class(contact_element_t), intent(in) :: self
        end function scale_i
    end interface

contains

    !> Number of force channels of the element.
    pure integer function element_nchannel(self) result(m)
        !> The element.
        class(contact_element_t), intent(in) :: self
        m = 0
        if (allocated(self%channel)) m = size(self%channel)
    end function element_nchannel

    !> The friction limit of channel k at rest [N]: the force scale for every tangential
    !> channel, 0 for a normal one.
    pure real(dp) function element_rest_limit(self, k) result(g)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Channel of the element.
        integer, intent(in) :: k
        g = 0.0_dp
        if (self%channel(k)%along /= along_normal) g = self%force_scale()
    end function element_rest_limit

    !> The constant normal load [N]: 0 unless the law carries one.
    pure real(dp) function element_normal_load(self) result(n)
        !> The element.
        class(contact_element_t), intent(in) :: self
        n = 0.0_dp
    end function element_normal_load

    !> The static preload [N]: 0 unless the law has one.
    pure real(dp) function element_preload(self) result(p)
        !> The element.
        class(contact_element_t), intent(in) :: self
        p = 0.0_dp
    end function element_preload

    !> No parameter to check (the laws built from a model's arrays are checked with it).
    subroutine element_validate(self, j, error)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its contact's index (for messages).
        integer, intent(in) :: j
        !> Set on the first problem found (stat input, naming the variable).
        type(error_type), allocatable, intent(out) :: error
    end subroutine element_validate

    !> The states after implicit steps of forces r and kinematic quantities u (nt x m), the
    !> weight rho the mean diagonal of the element's Delassus block: those of states.
    subroutine element_step_states(self, rho, r, u, state)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Weight [m/(N s)], forces [N] and kinematic quantities [m/s] after each step.
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        !> The states.
        integer, intent(out) :: state(:)
        call self%states(rho, r, u, state)
    end subroutine element_step_states

    !> A law without the parameter: `done` = .false.
    subroutine element_set_parameter(self, name, value, done)
        !> The element.
        class(contact_element_t), intent(inout) :: self
        !> 'mu', 'normal_load' or 'preload'.
        character(len=*), intent(in) :: name
        !> Its value.
        real(dp), intent(in) :: value
        !> Whether the law has the parameter (and took the value).
        logical, intent(out) :: done
        done = .false.
    end subroutine element_set_parameter

    !> Nothing to settle (a law whose stuck state leaves no mean force free). An element
    !> that settles does it for what sticks over the whole period in its samples (weight
    !> rho of its states).
    subroutine element_settle_offset(self, rho, r, u, mean, settled)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Weight of the states [m/(N s)].
        real(dp), intent(in) :: rho
        !> The channel forces (shifted with the mean) and kinematic quantities at the
        !> samples (nt x m) [N], [m/s].
        real(dp), intent(inout) :: r(:, :), u(:, :)
        !> The channels' mean forces [N], settled.
        real(dp), intent(inout) :: mean(:)
        !> Whether a mean force was settled.
        logical, intent(out) :: settled
        settled = .false.
    end subroutine element_settle_offset

    !> The channel forces r of one implicit step with u = q + A r and Psi(r, u) = 0, the
    !> other elements' forces fixed (they are inside q): a semismooth Newton iteration on
    !> Psi (its exact generalized Jacobian jr + ju A, backtracking on |Psi|), weight rho the
    !> mean diagonal of A; when it stalls, the element's projection iteration (project).
    !> `r` holds the start on entry. `scale` [N] is the force scale of the tolerances.
    subroutine element_step_forces(self, a, q, r, scale)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The element's block of the Delassus matrix with the compliances, m x m [m/(N s)].
        real(dp), intent(in) :: a(:, :)
        !> The free kinematic quantities with the other elements' forces, m [m/s].
        real(dp), intent(in) :: q(:)
        !> The channel forces: start on entry, solution on exit [N].
        real(dp), intent(inout) :: r(:)
        !> Force scale [N] (> 0).
        real(dp), intent(in) :: scale
        integer, parameter :: max_newton = 30, max_halvings = 30
        integer :: m, it, k, info
        real(dp) :: z(size(r), 1), zt(size(r), 1), p(1, size(r)), pt(1, size(r)), &
                    jr(size(r), size(r), 1), ju(size(r), size(r), 1), jac(size(r), size(r)), &
                    dz(size(r)), rho, f0, ft, step, vscale
        logical :: done
        m = size(r)
        rho = 0.0_dp
        do k = 1, m
            rho = rho + a(k, k)
        end do
        rho = max(rho/m, tiny(1.0_dp))
        vscale = max(maxval(abs(q)), rho*scale, tiny(1.0_dp))
        z(:, 1) = r
        call self%psi(rho, transpose(z), transpose(reshape(q + matmul(a, z(:, 1)), [m, 1])), p)
        f0 = norm2(p)
        done = f0 <= 1.0e-15_dp*vscale
        ft = f0
        do it = 1, max_newton
            if (done) exit
            call self%psi_jacobian(rho, transpose(z), &
                                   transpose(reshape(q + matmul(a, z(:, 1)), [m, 1])), p, jr, ju)
            jac = jr(:, :, 1) + matmul(ju(:, :, 1), a)
            dz = -p(1, :)
            call small_solve(m, jac, dz, info)
            if (info /= 0) exit
            step = 1.0_dp
            do k = 1, max_halvings
                zt(:, 1) = z(:, 1) + step*dz
                call self%psi(rho, transpose(zt), &
                              transpose(reshape(q + matmul(a, zt(:, 1)), [m, 1])), pt)
                ft = norm2(pt)
                if (ft <= (1.0_dp - 1.0e-4_dp*step)*f0) exit
                step = 0.5_dp*step
            end do
            if (.not. (ft < f0)) exit
            z = zt
            f0 = ft
            done = f0 <= 1.0e-15_dp*vscale
        end do
        r = z(:, 1)
        if (.not. done) call self%project(a, q, r, scale)
    end subroutine element_step_forces

    !> No projection iteration: the Newton iterate stays.
    subroutine element_project(self, a, q, r, scale)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Block of the Delassus matrix, free kinematic quantities.
        real(dp), intent(in) :: a(:, :), q(:)
        !> The channel forces [N].
        real(dp), intent(inout) :: r(:)
        !> Force scale [N].
        real(dp), intent(in) :: scale
    end subroutine element_project

    !> The element's rows of the weighted-residual Jacobian, dF/dR (m nb rows, one block of
    !> nb per channel, every channel's nb columns): J = A[ju] kappa + A[jr], A[f] = P diag(f)
    !> Q from one FFT of each nonzero weight function f of the generalized Jacobians at the
    !> samples, kappa the receptance of the element's kinematic quantities to every channel
    !> force: kap(b, c, ih) at harmonic ih (complex, velocity units per N), kap0(b, c) of the
    !> constant (gap channels; 0 for the others). `first` is the element's first channel
    !> among all (its own columns); `jac` is zero on entry.
    subroutine element_hb_jacobian(self, basis, rho, rs, us, kap, kap0, first, jac, work)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The basis (its FFT plans).
        type(basis_t), intent(in) :: basis
        !> Weight of the equalities [m/(N s)].
        real(dp), intent(in) :: rho
        !> The element's channel forces and kinematic quantities at the samples (nt x m).
        real(dp), intent(in) :: rs(:, :), us(:, :)
        !> Receptances per harmonic (m x n_ch x nharm) and of the constant (m x n_ch).
        complex(dp), intent(in) :: kap(:, :, :)
        real(dp), intent(in) :: kap0(:, :)
        !> The element's first channel among all.
        integer, intent(in) :: first
        !> The rows, (m nb) x (n_ch nb).
        real(dp), intent(inout) :: jac(:, :)
        !> Work arrays.
        type(hb_work_t), intent(inout) :: work
        real(dp), allocatable :: p(:, :), jr(:, :, :), ju(:, :, :)
        integer :: m, nb, nt, a, b, c, nch, ra, col, ih, kk, i0
        complex(dp) :: kp
        m = self%nchannel()
        nb = basis%nb
        nt = basis%nt
        nch = size(kap, 2)
        i0 = basis%i0
        allocate (p(nt, m), jr(m, m, nt), ju(m, m, nt))
        call self%psi_jacobian(rho, rs, us, p, jr, ju)
        do a = 1, m
            ra = (a - 1)*nb
            do b = 1, m
                ! d Psi_a / d u_b, through the receptance of channel b's kinematic quantity
                work%w = ju(a, b, :)
                if (any(work%w /= 0.0_dp)) then
                    call product_matrix()
                    do c = 1, nch
                        col = (c - 1)*nb
                        do ih = 1, basis%nharm
                            kk = basis%icos(ih)
                            kp = kap(b, c, ih)
                            jac(ra + 1:ra + nb, col + kk) = jac(ra + 1:ra + nb, col + kk) + &
                                real(kp, dp)*work%a(:, kk) - aimag(kp)*work%a(:, kk + 1)
                            jac(ra + 1:ra + nb, col + kk + 1) = jac(ra + 1:ra + nb, col + kk + 1) + &
                                aimag(kp)*work%a(:, kk) + real(kp, dp)*work%a(:, kk + 1)
                        end do
                        if (basis%has_zero .and. self%channel(b)%kinematics == kinematics_gap) &
                            jac(ra + 1:ra + nb, col + i0) = jac(ra + 1:ra + nb, col + i0) + &
                            kap0(b, c)*work%a(:, i0)
                    end do
                end if
                ! d Psi_a / d r_b directly
                work%w = jr(a, b, :)
                if (any(work%w /= 0.0_dp)) then
                    call product_matrix()
                    col = (first + b - 2)*nb
                    jac(ra + 1:ra + nb, col + 1:col + nb) = jac(ra + 1:ra + nb, col + 1:col + nb) + &
                                                            work%a
                end if
            end do
        end do

    contains

        !> work%a = P diag(work%w) Q from one FFT of the weight function (it may be
        !> overwritten by the transform).
        subroutine product_matrix()
            call basis%fft%forward(work%w, work%cw)
            work%cw = work%cw/real(nt, dp)
            call basis%stick_product(work%cw, work%a)
        end subroutine product_matrix
    end subroutine element_hb_jacobian

    !> The exact flow handles no law by default: the reason.
    function element_exact_support(self) result(why)
        !> The element.
        class(contact_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = "the exact reference does not handle the law '"//self%law_name()//"'"
    end function element_exact_support

    !> One code slot.
    pure integer function element_ncode(self) result(k)
        !> The element.
        class(contact_element_t), intent(in) :: self
        k = 1
    end function element_ncode

    !> No internal state.
    pure integer function element_nstate(self) result(k)
        !> The element.
        class(contact_element_t), intent(in) :: self
        k = 0
    end function element_nstate

    !> The scales c_k of the internal states (sigma_k = c_k s_k): 1.
    pure subroutine element_state_scales(self, c)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The scales (nstate).
        real(dp), intent(out) :: c(:)
        c = 1.0_dp
    end subroutine element_state_scales

    !> The internal states of a start (none by default): from the displacements along the
    !> contact's directions dx = (w^T x, t2^T x, n^T x) [m] and the channel forces r [N].
    pure subroutine element_initial_states(self, dx, r, s)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Displacements along the directions [m], channel forces [N].
        real(dp), intent(in) :: dx(:), r(:)
        !> Internal states [m] (nstate).
        real(dp), intent(out) :: s(:)
        s = 0.0_dp
    end subroutine element_initial_states

    !> No terms (an element the exact flow does not handle: exact_support says why).
    subroutine element_mode_terms(self, code, geom, terms)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The element's codes in the mode.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The mode's terms, added to.
        type(mode_terms_t), intent(inout) :: terms
    end subroutine element_mode_terms

    !> No events.
    subroutine element_event_rows(self, code, geom, fb, events)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The element's codes in the mode.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> Its channel forces as rows of y (m x na) in the mode, constraint forces included.
        real(dp), intent(in) :: fb(:, :)
        !> The events, added to.
        type(event_list_t), intent(inout) :: events
    end subroutine element_event_rows

    !> No events that need the mode's dynamics.
    subroutine element_dynamics_events(self, code, geom, fb, b, events)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The element's codes in the mode.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> Its channel forces as rows of y (m x na) in the mode, constraint forces included.
        real(dp), intent(in) :: fb(:, :)
        !> The mode's linear dynamics y' = b y (na x na, balanced; without its nonlinear
        !> inputs).
        real(dp), intent(in) :: b(:, :)
        !> The events, added to.
        type(event_list_t), intent(inout) :: events
    end subroutine element_dynamics_events

    !> Codes 1 (slipping) at the start, nothing to decide.
    subroutine element_start_code(self, geom, y, code, decide)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The start state (balanced).
        real(dp), intent(in) :: y(:)
        !> Its codes.
        integer, intent(out) :: code(:)
        !> Whether the joint decision must settle them.
        logical, intent(out) :: decide
        code = 1
        decide = .false.
    end subroutine element_start_code

    !> Not coupled (no rigid constraint).
    pure logical function element_coupled(self) result(c)
        !> The element.
        class(contact_element_t), intent(in) :: self
        c = .false.
    end function element_coupled

    !> No rigid constraint held.
    pure logical function element_holds_constraint(self, code) result(h)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes.
        integer, intent(in) :: code(:)
        h = .false.
    end function element_holds_constraint

    !> The candidate codes of a joint decision at state y: ncand code vectors in the
    !> columns of cand (ncode x ncand), tried in that order. Default: the current codes.
    subroutine element_candidates(self, code, geom, y, cand, ncand)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The codes before.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The state (balanced).
        real(dp), intent(in) :: y(:)
        !> Candidates.
        integer, intent(out) :: cand(:, :)
        integer, intent(out) :: ncand
        ncand = 1
        cand(:, 1) = code
    end subroutine element_candidates

    !> Every trial is consistent by default.
    logical function element_consistent(self, code, moving, geom, fb, y, ydot) result(ok)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The trial codes, and whether the contact moves (nonzero slip velocity) there.
        integer, intent(in) :: code(:)
        logical, intent(in) :: moving
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> Its channel forces as rows of y in the trial mode (m x na).
        real(dp), intent(in) :: fb(:, :)
        !> The state and its rate in the trial mode (balanced).
        real(dp), intent(in) :: y(:), ydot(:)
        ok = .true.
    end function element_consistent

    !> Nothing to decide alone.
    subroutine element_local_decide(self, code, geom, y, ydot)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes, updated.
        integer, intent(inout) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The state and its rate (balanced).
        real(dp), intent(in) :: y(:), ydot(:)
    end subroutine element_local_decide

    !> Stick when every slot sticks, open when a slot is open (code 2, or code_unloaded: closed
    !> below the element's force floor), slip otherwise.
    pure integer function element_code_state(self, code) result(state)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes.
        integer, intent(in) :: code(:)
        if (any(code == 2 .or. code == code_unloaded)) then
            state = state_open
        else if (all(code == 0)) then
            state = state_stick
        else
            state = state_slip
        end if
    end function element_code_state

    !> No impact.
    logical function element_impacts(self, code, geom, y) result(imp)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes before the event.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The state (balanced).
        real(dp), intent(in) :: y(:)
        imp = .false.
    end function element_impacts

    !> No rigid normal.
    pure logical function element_rigid_closed(self, code) result(c)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes.
        integer, intent(in) :: code(:)
        c = .false.
    end function element_rigid_closed

    !> No gap to close at the start: active = .false.
    subroutine element_start_gap(self, geom, y, active, gap)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The start state (balanced).
        real(dp), intent(in) :: y(:)
        !> A rigid normal at a zero or negative gap, and its gap there [m].
        logical, intent(out) :: active
        real(dp), intent(out) :: gap
        active = .false.
        gap = 0.0_dp
    end subroutine element_start_gap

    !> No internal state to correct at the start.
    subroutine element_start_states(self, code, geom, fb, y, pj)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes at the start.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> Its channel forces in the start mode (channels x na, balanced).
        real(dp), intent(in) :: fb(:, :)
        !> The start state (balanced), corrected in place.
        real(dp), intent(inout) :: y(:)
        !> The Jacobian of the start's corrections (nz x nz, balanced), composed with this
        !> one's: pj <- P pj.
        real(dp), intent(inout) :: pj(:, :)
    end subroutine element_start_states

    !> The internal states are kept at an event.
    subroutine element_event_states(self, old, code, geom, fb, y, jump)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes before and after the event.
        integer, intent(in) :: old(:), code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> Its channel forces as rows of y in the new mode (m x na, balanced).
        real(dp), intent(in) :: fb(:, :)
        !> The state at the event (balanced), corrected in place.
        real(dp), intent(inout) :: y(:)
        !> The Jacobian of the event's jump (nz x nz, balanced), composed with this one's:
        !> jump <- P jump.
        real(dp), intent(inout) :: jump(:, :)
    end subroutine element_event_states

    !> Its impacts obey its own law: e is a copy of it.
    subroutine element_impact_law(self, e)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> The law of its impacts.
        class(contact_element_t), allocatable, intent(out) :: e
        allocate (e, source=self)
    end subroutine element_impact_law

    !> No nonlinear input.
    subroutine element_inputs(self, code, geom, y, dir, fb, fq, q, dq, yd0, dyd0, gj)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The state (balanced).
        real(dp), intent(in) :: y(:)
        !> Its slip memory (3: a direction and a regime flag).
        real(dp), intent(in) :: dir(:)
        !> Its channel forces in the mode: the part linear in y (channels x na, balanced)
        !> and per unit of each of its inputs (channels x inputs; the constraint forces of
        !> a rigid normal respond to them).
        real(dp), intent(in) :: fb(:, :), fq(:, :)
        !> The inputs' values and Jacobian (inputs x na).
        real(dp), intent(out) :: q(:), dq(:, :)
        !> With the mode's dynamics: y' at y without the element's own inputs (na), its
        !> Jacobian (na x na) and y' per unit of each of its inputs (na x inputs); a slip
        !> starting from rest takes its direction from them.
        real(dp), intent(in), optional :: yd0(:), dyd0(:, :), gj(:, :)
        q = 0.0_dp
        dq = 0.0_dp
    end subroutine element_inputs

    !> No event row depending on the step's slip direction.
    subroutine element_step_rows(self, code, geom, dir, events)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> Its slip memory (3: a direction and a regime flag).
        real(dp), intent(in) :: dir(:)
        !> The events, added to.
        type(event_list_t), intent(inout) :: events
    end subroutine element_step_rows

    !> The slip direction is kept.
    subroutine element_slip_direction(self, code, geom, fb, y, dir)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its new codes.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> Its channel forces as rows of y in the mode it leaves (m x na).
        real(dp), intent(in) :: fb(:, :)
        !> The state (balanced).
        real(dp), intent(in) :: y(:)
        !> Its slip memory (3: a direction and a regime flag), updated.
        real(dp), intent(inout) :: dir(:)
    end subroutine element_slip_direction

    !> Not decided at acceleration level (the enumeration of candidates decides).
    pure logical function element_accel_decision(self) result(yes)
        !> The element.
        class(contact_element_t), intent(in) :: self
        yes = .false.
    end function element_accel_decision

    !> No codes from forces (not an acceleration-level element).
    subroutine element_accel_code(self, r, u, code, dir)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its channel forces [N] and accelerations at the solution.
        real(dp), intent(in) :: r(:), u(:)
        !> Its codes.
        integer, intent(inout) :: code(:)
        !> Its slip memory (3: a direction and a regime flag).
        real(dp), intent(inout) :: dir(:)
    end subroutine element_accel_code

    !> How the element takes part in a joint decision at state y: by its own law on every
    !> channel (box = a copy of itself) when it decides at acceleration level
    !> (accel_decision), else by the enumeration of candidates (accel_none). No errors.
    subroutine element_accel_law(self, code, geom, y, kind, box, chans)
        !> The element.
        class(contact_element_t), intent(in) :: self
        !> Its codes.
        integer, intent(in) :: code(:)
        !> Its geometry.
        type(element_geometry_t), intent(in) :: geom
        !> The state (balanced).
        real(dp), intent(in) :: y(:)
        !> accel_none, accel_box, accel_alone or accel_keep.
        integer, intent(out) :: kind
        !> With accel_box: the law at acceleration level (its accel_code gives the codes).
        class(contact_element_t), allocatable, intent(out) :: box
        !> With accel_box: the element's channels the law acts on (1-based).
        integer, allocatable, intent(out) :: chans(:)
        integer :: k
        kind = accel_none
        if (.not. self%accel_decision()) return
        kind = accel_box
        allocate (box, source=self)
        chans = [(k, k=1, size(self%channel))]
    end subroutine element_accel_law

    !> Solve the small system a x = b (m <= a few) by Gaussian elimination with partial
    !> pivoting; info = 1 when a pivot vanishes.
    pure subroutine small_solve(m, a, b, info)
        integer, intent(in) :: m
        real(dp), intent(in) :: a(m, m)
        real(dp), intent(inout) :: b(m)
        integer, intent(out) :: info
        real(dp) :: w(m, m), f, t
        integer :: i, k, p
        w = a
        info = 0
        do k = 1, m
            p = k - 1 + maxloc(abs(w(k:m, k)), 1)
            if (.not. (abs(w(p, k)) > 1.0e-300_dp)) then
                info = 1
                return
            end if
            if (p /= k) then
                do i = 1, m
                    t = w(k, i)
                    w(k, i) = w(p, i)
                    w(p, i) = t
                end do
                t = b(k)
                b(k) = b(p)
                b(p) = t
            end if
            do i = k + 1, m
                f = w(i, k)/w(k, k)
                w(i, k:m) = w(i, k:m) - f*w(k, k:m)
                b(i) = b(i) - f*b(k)
            end do
        end do
        do i = m, 1, -1
            b(i) = (b(i) - dot_product(w(i, i + 1:m), b(i + 1:m)))/w(i, i)
        end do
    end subroutine small_solve
end module stickslip_contact_element
