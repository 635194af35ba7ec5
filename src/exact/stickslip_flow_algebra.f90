!> The algebra of the exact flow's contact modes (doc/contacts.md, section 5): a mode's
!> dynamics from its elements' terms (mode_index), the elements' codes at the start and at
!> events (start_codes, decide_codes), impacts of rigid normals (impact_jump), and the
!> projections of a start onto the constraints of its mode (close_rigid_gaps,
!> project_velocities). In balanced modal coordinates (M = I) every mode is
!>     u' = hb y + Ft Lambda,   Lambda = -(Ct^T Ft)^-1 Ct^T hb y,
!> Ct and Ft the directions of the elements' velocity constraints and of the forces that
!> hold them (stickslip_contact_modes).
!>
!> The decision at an event concerns the element whose event fired and every element
!> holding a rigid constraint (its code may change with the others'). The rigid ones
!> (contact_element_t%coupled) decide jointly: by their laws at acceleration level where
!> each has one (contact_element_t%accel_law: Coulomb's box QP, the disk of 2D friction,
!> and a unilateral contact on an elastic normal as Coulomb's law with its current limit
!> mu lambda; for any number of contacts),
!> others by trying their candidate codes (stuck and closed first) until a combination is
!> consistent with every law (at most 8 contacts at once enumerated). Elastic ones (a
!> Jenkins or microslip slider) then decide alone with the accelerations of the new mode:
!> their force is continuous at the event, so the structure's acceleration does not
!> depend on their codes.
module stickslip_flow_algebra
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_lapack, only: dgesv
    use stickslip_flow_modes, only: mode_t, flow_modes_t, build_ladder, identity_matrix, &
        tune_mode
    use stickslip_flow_modal, only: project_velocity_rows, gram_solve, constraint_solve
    use stickslip_contact_modes, only: mode_terms_t, event_list_t
    use stickslip_contact_set, only: contact_set_t, new_element_set
    use stickslip_contact_element, only: element_box_t, state_stick, along_normal, &
        accel_none, accel_box, accel_alone
    implicit none
    private
    public :: mode_index, assemble, start_codes, decide_codes, impact_jump, &
        close_rigid_gaps, project_velocities, eval_inputs, rate_of

    !> Most elements decided jointly by enumeration (beyond: the first combination only).
    integer, parameter :: max_enumerated = 8

contains

    !> The terms of the mode `code` with its constraints solved: hb, sb, fb of `terms`
    !> hold the dynamics, the constraint forces added (ok = .false. when the constraint
    !> matrix Ct^T Ft is singular and its constraints inconsistent: Painleve's paradox;
    !> dependent consistent ones get the minimum-norm forces, constraint_solve). Elements
    !> flagged in `skip` add nothing (their forces left out: the free accelerations of a
    !> joint decision).
    subroutine assemble(self, code, terms, ok, skip)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The codes of every slot.
        integer, intent(in) :: code(:)
        !> The terms.
        type(mode_terms_t), intent(inout) :: terms
        !> The constraints could be solved.
        logical, intent(out) :: ok
        !> Elements left out.
        logical, intent(in), optional :: skip(:)
        real(dp), allocatable :: l(:, :)
        integer :: n, na, j, k, m
        n = self%n
        na = self%na
        ok = .true.
        call terms%reset(n, na, self%ns, self%cs%nchannel)
        do j = 1, n
            terms%hb(j, j) = -self%lam(j)/self%s(j)
        end do
        terms%hb(:, n + 1:2*n) = -self%ct
        terms%hb(:, self%nz + 1:) = self%ft/self%se
        do j = 1, self%nc
            if (present(skip)) then
                if (skip(j)) cycle
            end if
            call self%cs%elements(j)%e%mode_terms(code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                  self%geom(j), terms)
        end do
        k = size(terms%chan)
        if (k == 0) then
            call force_rates()
            return
        end if
        ! Lambda = -(Ct^T Ft)^-1 Ct^T [hb, gu] (the nonlinear inputs' part too)
        m = size(terms%in_elem)
        ! (dependent constraints, a ring of stuck contacts: the minimum-norm forces)
        call constraint_solve(matmul(transpose(terms%ctm), terms%ftm), &
                              -matmul(transpose(terms%ctm), &
                                      reshape([terms%hb, terms%gu], [n, na + m])), l, ok)
        if (.not. ok) return
        terms%hb = terms%hb + matmul(terms%ftm, l(:, 1:na))
        if (m > 0) terms%gu = terms%gu + matmul(terms%ftm, l(:, na + 1:))
        do j = 1, k
            terms%fb(terms%chan(j), :) = terms%fb(terms%chan(j), :) + l(j, 1:na)
            if (m > 0) terms%gf(terms%chan(j), :) = terms%gf(terms%chan(j), :) + l(j, na + 1:)
            if (terms%slip_ch(j) > 0) then
                terms%fb(terms%slip_ch(j), :) = terms%fb(terms%slip_ch(j), :) + &
                                                terms%slip_factor(j)*l(j, 1:na)
                if (m > 0) terms%gf(terms%slip_ch(j), :) = terms%gf(terms%slip_ch(j), :) + &
                                                           terms%slip_factor(j)*l(j, na + 1:)
            end if
        end do
        call force_rates()

    contains

        !> The internal-state rates from the rates of channel forces: lambda' = fb(ch) . b y
        !> (a linear mode; the state itself does not enter the force).
        subroutine force_rates()
            real(dp), allocatable :: b(:, :)
            integer :: q
            if (size(terms%rate_state) == 0) return
            b = dynamics_of(self, terms)
            do q = 1, size(terms%rate_state)
                terms%sb(terms%rate_state(q), :) = terms%sb(terms%rate_state(q), :) + &
                    terms%rate_factor(q)*matmul(terms%fb(terms%rate_chan(q), :), b)
            end do
        end subroutine force_rates
    end subroutine assemble

    !> The balanced dynamics b (na x na) of assembled terms: p' = S u, u' = hb y, sigma' =
    !> sb y, the exosystem's rotations.
    function dynamics_of(self, terms) result(b)
        class(flow_modes_t), intent(in) :: self
        type(mode_terms_t), intent(in) :: terms
        real(dp) :: b(self%na, self%na)
        integer :: j, k, e0
        b = 0.0_dp
        do j = 1, self%n
            b(j, self%n + j) = self%s(j)
        end do
        b(self%n + 1:2*self%n, :) = terms%hb
        if (self%ns > 0) b(2*self%n + 1:self%nz, :) = terms%sb
        e0 = self%nz
        do k = 1, size(self%eharm)
            b(e0 + 2*k, e0 + 2*k + 1) = -self%eharm(k)*self%omega
            b(e0 + 2*k + 1, e0 + 2*k) = self%eharm(k)*self%omega
        end do
    end function dynamics_of

    !> Index of the mode with codes `code` in the cache, built on first use: its dynamics,
    !> channel forces, constraint directions, event rows and ladder. Errors (stat
    !> numerical): dependent constraints (Painleve), a non-finite exponential (the mode is
    !> then not kept in the cache).
    integer function mode_index(self, code, error) result(im)
        !> The dynamics (its mode cache grows).
        class(flow_modes_t), intent(inout) :: self
        !> Codes of every slot.
        integer, intent(in) :: code(:)
        !> Set on failure.
        type(error_type), allocatable, intent(inout) :: error
        type(mode_t), allocatable :: grown(:)
        type(mode_terms_t) :: terms
        type(event_list_t) :: events
        logical :: ok
        integer :: j, m, k, c0, w
        do im = 1, self%nmodes
            if (all(self%modes(im)%code == code)) then
                ! at this omega (the cache may have been retuned since it was last used)
                if (self%modes(im)%m == 0) call tune_mode(self, self%modes(im))
                return
            end if
        end do
        call assemble(self, code, terms, ok)
        if (.not. ok) then
            call fatal_error(error, "reference: a contact mode has dependent constraints "// &
                             "(the stuck and closed contact directions are not independent, "// &
                             "or Painleve's paradox: a slipping rigid contact whose friction "// &
                             "pushes it closed harder than it holds)", stickslip_stat%numerical)
            im = 0
            return
        end if
        if (self%nmodes == size(self%modes)) then
            allocate (grown(2*size(self%modes)))
            grown(1:self%nmodes) = self%modes(1:self%nmodes)
            call move_alloc(grown, self%modes)
        end if
        self%nmodes = self%nmodes + 1
        im = self%nmodes
        self%modes(im) = mode_t()
        associate (md => self%modes(im))
            md%code = code
            md%b = dynamics_of(self, terms)
            md%force = matmul(terms%fb, self%tb)
            md%fbal = terms%fb
            md%ctm = terms%ctm
            if (allocated(md%gauss)) deallocate (md%gauss)
            ! the event rows and quadratic events of every element, with the forces of its
            ! channels
            m = 0
            allocate (md%rows(self%na, 0), md%row_scale(0), md%row_element(0), md%row_slot(0), &
                      md%row_action(0))
            allocate (md%qmat(self%na, self%na, 0), md%qc(0), md%q_scale(0), md%q_element(0), &
                      md%q_slot(0), md%q_action(0))
            do j = 1, self%nc
                c0 = self%cs%first(j)
                w = self%cs%width(j)
                call events%clear(self%na)
                call self%cs%elements(j)%e%event_rows(code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                      self%geom(j), &
                                                      terms%fb(c0:c0 + w - 1, :), events)
                call self%cs%elements(j)%e%dynamics_events( &
                    code(self%slot0(j) + 1:self%slot_hi(j)), self%geom(j), &
                    terms%fb(c0:c0 + w - 1, :), md%b, events)
                do k = 1, events%count
                    m = m + 1
                    md%rows = reshape([md%rows, events%rows(:, k)], [self%na, m])
                    md%row_scale = [md%row_scale, events%scale(k)]
                    md%row_element = [md%row_element, j]
                    md%row_slot = [md%row_slot, self%slot0(j) + events%slot(k)]
                    md%row_action = [md%row_action, events%action(k)]
                end do
                do k = 1, events%nq
                    md%qmat = reshape([md%qmat, events%qmat(:, :, k)], &
                                      [self%na, self%na, size(md%qc) + 1])
                    md%qc = [md%qc, events%qc(k)]
                    md%q_scale = [md%q_scale, events%qscale(k)]
                    md%q_element = [md%q_element, j]
                    md%q_slot = [md%q_slot, self%slot0(j) + events%qslot(k)]
                    md%q_action = [md%q_action, events%qaction(k)]
                end do
            end do
            ! the rows on internal-state rates (known once the constraints are solved)
            do k = 1, size(terms%rev_state)
                m = m + 1
                j = terms%rev_elem(k)
                md%rows = reshape([md%rows, terms%rev_factor(k)*terms%sb(terms%rev_state(k), :)], &
                                  [self%na, m])
                md%row_scale = [md%row_scale, terms%rev_scale(k)]
                md%row_element = [md%row_element, j]
                md%row_slot = [md%row_slot, self%slot0(j) + terms%rev_slot(k)]
                md%row_action = [md%row_action, terms%rev_action(k)]
            end do
            md%drows = matmul(transpose(md%b), md%rows)
            ! the nonlinear inputs (a 2D slip): their columns in y' and the channel forces
            md%m = size(terms%in_elem)
            allocate (md%gin(self%na, md%m), md%fin(self%cs%nchannel, md%m))
            md%gin = 0.0_dp
            if (md%m > 0) then
                md%gin(self%n + 1:2*self%n, :) = terms%gu
                if (self%ns > 0) md%gin(2*self%n + 1:self%nz, :) = terms%gs
                md%fin = terms%gf
            end if
            md%in_elem = terms%in_elem
            allocate (md%nl_elements(0), md%nl_first(0))
            do k = 1, md%m
                if (any(md%nl_elements == md%in_elem(k))) cycle
                md%nl_elements = [md%nl_elements, md%in_elem(k)]
                md%nl_first = [md%nl_first, k]
            end do
            ! the ladder of a linear mode is built on first use (tune_ladder): its phases
            ! may all be tracked in modal coordinates
            md%omega_b = self%omega
            if (md%m > 0) then
                call build_ladder(self, md, error)
                md%omega_ladder = self%omega
            end if
        end associate
        ! never leave a broken mode in the cache
        if (allocated(error)) self%nmodes = self%nmodes - 1
    end function mode_index

    !> The values of the nonlinear inputs `in_elem` (their elements, grouped) of the mode
    !> `code` at yb (balanced), q (m), and their Jacobian dq (m x na); dirs the elements'
    !> slip memories (3 x n_c: a direction and a regime); fb and fin the mode's channel
    !> forces, linear part and per unit input (each element gets its channels' rows). With
    !> the mode's dynamics (y' = bmat y + gmat q) each element also gets y' without its own
    !> inputs, its Jacobian and its input columns (the direction of a slip starting from
    !> rest).
    subroutine eval_inputs(self, code, in_elem, yb, dirs, fb, fin, q, dq, bmat, gmat)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> Codes of every slot, the element of each input.
        integer, intent(in) :: code(:), in_elem(:)
        !> State, slip directions.
        real(dp), intent(in) :: yb(:), dirs(:, :)
        !> Channel forces: fb y (n_ch x na, balanced) + fin q (n_ch x m).
        real(dp), intent(in) :: fb(:, :), fin(:, :)
        !> Values and Jacobian.
        real(dp), intent(out) :: q(:), dq(:, :)
        !> The mode's linear dynamics (na x na) and input columns (na x m).
        real(dp), intent(in), optional :: bmat(:, :), gmat(:, :)
        real(dp), allocatable :: yd0(:), dyd0(:, :)
        integer :: pass, k, k1, j
        do pass = 1, merge(2, 1, present(bmat) .and. present(gmat))
            if (pass == 2) then
                yd0 = matmul(bmat, yb) + matmul(gmat, q)
                dyd0 = bmat + matmul(gmat, dq)
            end if
            k = 1
            do while (k <= size(in_elem))
                j = in_elem(k)
                k1 = k
                do while (k1 < size(in_elem))
                    if (in_elem(k1 + 1) /= j) exit
                    k1 = k1 + 1
                end do
                associate (c => code(self%slot0(j) + 1:self%slot_hi(j)), &
                           c0 => self%cs%first(j), c1 => self%cs%first(j) + self%cs%width(j) - 1)
                    if (pass == 1) then
                        call self%cs%elements(j)%e%inputs(c, self%geom(j), yb, dirs(:, j), &
                                                          fb(c0:c1, :), fin(c0:c1, k:k1), &
                                                          q(k:k1), dq(k:k1, :))
                    else
                        ! without this element's own inputs (those of the first pass)
                        call self%cs%elements(j)%e%inputs( &
                            c, self%geom(j), yb, dirs(:, j), fb(c0:c1, :), fin(c0:c1, k:k1), &
                            q(k:k1), dq(k:k1, :), yd0 - matmul(gmat(:, k:k1), q(k:k1)), &
                            dyd0 - matmul(gmat(:, k:k1), dq(k:k1, :)), gmat(:, k:k1))
                    end if
                end associate
                k = k1 + 1
            end do
        end do
    end subroutine eval_inputs

    !> The rate y' of assembled terms at yb: the linear dynamics and the nonlinear inputs.
    function rate_of(self, code, terms, yb, dirs) result(ydot)
        class(flow_modes_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(mode_terms_t), intent(in) :: terms
        real(dp), intent(in) :: yb(:), dirs(:, :)
        real(dp) :: ydot(self%na)
        real(dp) :: q(size(terms%in_elem)), dq(size(terms%in_elem), self%na), &
                    bmat(self%na, self%na), gmat(self%na, size(terms%in_elem))
        bmat = dynamics_of(self, terms)
        ydot = matmul(bmat, yb)
        if (size(q) == 0) return
        gmat = 0.0_dp
        gmat(self%n + 1:2*self%n, :) = terms%gu
        if (self%ns > 0) gmat(2*self%n + 1:self%nz, :) = terms%gs
        call eval_inputs(self, code, terms%in_elem, yb, dirs, terms%fb, terms%gf, q, dq, bmat, &
                         gmat)
        ydot = ydot + matmul(gmat, q)
    end function rate_of

    !> The codes of every element at the start state yb (balanced): each element's own
    !> (contact_element_t%start_code), those it cannot settle alone decided jointly; the
    !> slip directions of the elements that start slipping in 2D.
    !> Errors: no consistent mode.
    subroutine start_codes(self, yb, code, dirs, error)
        !> The dynamics.
        class(flow_modes_t), intent(inout) :: self
        !> Start state in balanced coordinates.
        real(dp), intent(in) :: yb(:)
        !> The codes.
        integer, intent(out) :: code(:)
        !> The elements' slip memories (3 x n_c: a direction and a regime).
        real(dp), intent(inout) :: dirs(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(inout) :: error
        integer :: j
        integer, allocatable :: zset(:)
        logical :: decide
        allocate (zset(0))
        do j = 1, self%nc
            call self%cs%elements(j)%e%start_code(self%geom(j), yb, &
                                                  code(self%slot0(j) + 1:self%slot_hi(j)), decide)
            if (decide) zset = [zset, j]
            call self%cs%elements(j)%e%slip_direction(code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                      self%geom(j), &
                                                      reshape([real(dp) ::], [0, self%na]), &
                                                      yb, dirs(:, j))
        end do
        call decide_codes(self, yb, zset, code, dirs, error)
    end subroutine start_codes

    !> New codes for the elements `zset` at state yb (balanced): the rigid ones jointly
    !> (by their laws at acceleration level when all can and no other constraint is held:
    !> Coulomb's law, the disk of 2D friction; else the first consistent combination of
    !> candidates), then the elastic ones alone with the accelerations of that mode.
    !> Errors (stat numerical): no consistent combination.
    subroutine decide_codes(self, yb, zset, code, dirs, error)
        !> The dynamics.
        class(flow_modes_t), intent(inout) :: self
        !> State in balanced coordinates.
        real(dp), intent(in) :: yb(:)
        !> The elements to decide.
        integer, intent(in) :: zset(:)
        !> Codes of every slot; those of zset replaced.
        integer, intent(inout) :: code(:)
        !> The elements' slip memories (3 x n_c: a direction and a regime).
        real(dp), intent(inout) :: dirs(:, :)
        !> Set on failure.
        type(error_type), allocatable, intent(inout) :: error
        integer, allocatable :: rigid(:), elastic(:)
        type(mode_terms_t) :: terms
        real(dp), allocatable :: ydot(:)
        logical :: ok
        integer :: k, j
        if (size(zset) == 0) return
        allocate (rigid(0), elastic(0))
        do k = 1, size(zset)
            j = zset(k)
            if (any(rigid == j) .or. any(elastic == j)) cycle
            if (self%cs%elements(j)%e%coupled()) then
                rigid = [rigid, j]
            else
                elastic = [elastic, j]
            end if
        end do
        if (size(rigid) > 0) then
            call at_acceleration_level(ok)
            if (.not. ok) call enumerate(ok)
            if (.not. ok) then
                call fatal_error(error, "reference: no consistent contact mode at an event "// &
                                 "(contacts "//itoa(rigid(1))//" ...)", stickslip_stat%numerical)
                return
            end if
        end if
        if (size(elastic) == 0) return
        call assemble(self, code, terms, ok)
        if (.not. ok) return
        ydot = rate_of(self, code, terms, yb, dirs)
        do k = 1, size(elastic)
            j = elastic(k)
            call self%cs%elements(j)%e%local_decide(code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                    self%geom(j), yb, ydot)
        end do

    contains

        !> Every rigid element decides by its law at acceleration level (contact_element_t
        !> %accel_law) and no other constraint is held: the laws of those at rest (accel_box)
        !> between their forces r and the accelerations of their channels a = a_free + D r
        !> (D the modal Delassus matrix of their channels, a_free the accelerations without
        !> their forces, nor those of the elements that carry none now) solved together by
        !> their own local solves (contact_set_t%step_forces: Coulomb's box QP of
        !> stickslip_contact_solve, the disk), each one's codes from its forces
        !> (accel_code); then those that carry no force at this instant (accel_alone: a
        !> contact that opens or closes) by the enumeration of their candidates, the
        !> others' codes fixed. Those that move keep their codes (accel_keep). Not ok, and
        !> the codes unchanged, when an element cannot (accel_none) or the enumeration
        !> finds no consistent combination.
        subroutine at_acceleration_level(ok)
            logical, intent(out) :: ok
            logical :: skip(self%nc)
            real(dp), allocatable :: dirsub(:, :), accel(:), f(:), r(:), u(:)
            type(element_box_t), allocatable :: boxes(:), boxed(:)
            type(contact_set_t) :: sub
            integer, allocatable :: kinds(:), chans(:, :), nchan(:), saved(:), all_rigid(:), &
                                    inbox(:), cj(:)
            integer :: q, c, nch, a, sweeps, c0
            ok = .false.
            allocate (kinds(size(rigid)), boxes(size(rigid)), nchan(size(rigid)), &
                      chans(maxval(self%cs%width(rigid)), size(rigid)))
            do q = 1, size(rigid)
                j = rigid(q)
                call self%cs%elements(j)%e%accel_law(code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                     self%geom(j), yb, kinds(q), boxes(q)%e, cj)
                if (kinds(q) == accel_none) return
                nchan(q) = 0
                if (kinds(q) == accel_box) then
                    nchan(q) = size(cj)
                    chans(1:size(cj), q) = cj
                end if
            end do
            skip = .false.
            skip(pack(rigid, kinds == accel_box .or. kinds == accel_alone)) = .true.
            call assemble(self, code, terms, ok, skip)
            if (.not. ok) return
            ok = .false.
            if (size(terms%chan) > 0) return
            saved = code
            inbox = pack([(q, q=1, size(rigid))], kinds == accel_box)
            if (size(inbox) > 0) then
                ! the boxed elements' channels and their modal directions
                nch = sum(nchan(inbox))
                allocate (dirsub(self%n, nch))
                c = 0
                do q = 1, size(inbox)
                    j = rigid(inbox(q))
                    do a = 1, nchan(inbox(q))
                        c = c + 1
                        dirsub(:, c) = self%geom(j)%dt(:, self%cs%along(self%cs%first(j) + &
                                                                        chans(a, inbox(q)) - 1))
                    end do
                end do
                accel = rate_of(self, code, terms, yb, dirs)
                f = accel(self%n + 1:2*self%n)
                boxed = boxes(inbox)
                call new_element_set(sub, boxed)
                allocate (r(nch))
                r = 0.0_dp
                call sub%step_forces(matmul(transpose(dirsub), dirsub), matmul(f, dirsub), r, &
                                     max(sub%force_scale(), tiny(1.0_dp)), 1.0e-15_dp, &
                                     1000000, sweeps)
                if (.not. all(abs(r) <= huge(1.0_dp))) return
                u = matmul(f, dirsub) + matmul(matmul(transpose(dirsub), dirsub), r)
                c0 = 0
                do q = 1, size(inbox)
                    j = rigid(inbox(q))
                    associate (w => nchan(inbox(q)))
                        call boxes(inbox(q))%e%accel_code(r(c0 + 1:c0 + w), u(c0 + 1:c0 + w), &
                                                          code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                          dirs(:, j))
                        c0 = c0 + w
                    end associate
                end do
            end if
            ok = .true.
            if (.not. any(kinds == accel_alone)) return
            all_rigid = rigid
            rigid = pack(rigid, kinds == accel_alone)
            call enumerate(ok)
            rigid = all_rigid
            if (.not. ok) code = saved
        end subroutine at_acceleration_level

        !> Every combination of the rigid elements' candidates, in order; the first
        !> consistent one is kept. An element that slips in it gets its slip memory from the
        !> forces it carried in the last combination tried where it held a constraint (a
        !> slip from rest starts against the force it could not hold), else from its forces
        !> in the mode kept.
        subroutine enumerate(ok)
            logical, intent(out) :: ok
            integer :: nz, q, total, combo, rem, mslot, wmax
            integer, allocatable :: ncand(:), trial(:)
            integer, allocatable :: cand(:, :, :)
            logical, allocatable :: moving(:), held(:)
            real(dp), allocatable :: yd(:), heldfb(:, :, :)
            logical :: good
            ok = .false.
            nz = size(rigid)
            mslot = maxval(self%nslots(rigid))
            wmax = maxval(self%cs%width(rigid))
            allocate (ncand(nz), cand(mslot, 4, nz), moving(nz), held(nz), &
                      heldfb(wmax, self%na, nz))
            held = .false.
            cand = 0
            do q = 1, nz
                j = rigid(q)
                call self%cs%elements(j)%e%candidates(code(self%slot0(j) + 1:self%slot_hi(j)), &
                                                      self%geom(j), yb, &
                                                      cand(1:self%nslots(j), :, q), ncand(q))
                moving(q) = abs(dot_product(self%geom(j)%dt(:, 1), yb(self%n + 1:2*self%n))) > &
                            1.0e-12_dp*self%geom(j)%vref
            end do
            total = product(ncand)
            if (nz > max_enumerated) total = 1
            do combo = 0, total - 1
                trial = code
                rem = combo
                do q = 1, nz
                    j = rigid(q)
                    trial(self%slot0(j) + 1:self%slot_hi(j)) = &
                        cand(1:self%nslots(j), mod(rem, ncand(q)) + 1, q)
                    rem = rem/ncand(q)
                end do
                call assemble(self, trial, terms, good)
                if (.not. good) cycle
                do q = 1, nz
                    j = rigid(q)
                    if (.not. self%cs%elements(j)%e%holds_constraint( &
                        trial(self%slot0(j) + 1:self%slot_hi(j)))) cycle
                    associate (c0 => self%cs%first(j), w => self%cs%width(j))
                        heldfb(1:w, :, q) = terms%fb(c0:c0 + w - 1, :)
                    end associate
                    held(q) = .true.
                end do
                yd = rate_of(self, trial, terms, yb, dirs)
                do q = 1, nz
                    j = rigid(q)
                    associate (c0 => self%cs%first(j), w => self%cs%width(j))
                        good = self%cs%elements(j)%e%consistent( &
                               trial(self%slot0(j) + 1:self%slot_hi(j)), &
                               moving(q), self%geom(j), &
                               terms%fb(c0:c0 + w - 1, :), &
                               yb, yd)
                    end associate
                    if (.not. good) exit
                end do
                if (good) then
                    do q = 1, nz
                        j = rigid(q)
                        associate (c0 => self%cs%first(j), w => self%cs%width(j))
                            if (held(q)) then
                                call self%cs%elements(j)%e%slip_direction( &
                                    trial(self%slot0(j) + 1:self%slot_hi(j)), self%geom(j), &
                                    heldfb(1:w, :, q), yb, dirs(:, j))
                            else
                                call self%cs%elements(j)%e%slip_direction( &
                                    trial(self%slot0(j) + 1:self%slot_hi(j)), self%geom(j), &
                                    terms%fb(c0:c0 + w - 1, :), yb, dirs(:, j))
                            end if
                        end associate
                    end do
                    code = trial
                    ok = .true.
                    return
                end if
            end do
        end subroutine enumerate
    end subroutine decide_codes

    !> A rigid normal closing with a normal velocity (an impact) at state yb (balanced):
    !> the plastic impact with the laws of the element `jimp` and of the rigid normals
    !> already closed (code), at velocity level, solved as one step of zero length by their
    !> own local solves (contact_set_t%step_forces: u+ = u- + A P, A the modal Delassus
    !> matrix of their channels, every channel of each: 1D or 2D friction and the normal).
    !> yb's velocities are replaced by the ones after the impact; `jump` (nz x nz) is the
    !> Jacobian of the jump map of the state for the active impulses: stuck, every
    !> direction held; sliding, the normal held by F = n + T P_t / P_n, and in 2D the
    !> impulse's direction turning with the slip after it (P_t = -mu P_n e, e = T^T u+ /
    !> |T^T u+|): (I + L) du+ = du- + F dP_n, L = mu P_n T (I - e e^T) T^T / |T^T u+|;
    !> `loss` the kinetic energy lost [J] (>= 0).
    subroutine impact_jump(self, yb, jimp, code, jump, loss)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> State in balanced coordinates; its velocities updated.
        real(dp), intent(inout) :: yb(:)
        !> The element that closes.
        integer, intent(in) :: jimp
        !> Codes before the impact.
        integer, intent(in) :: code(:)
        !> The Jacobian of the jump.
        real(dp), intent(out) :: jump(:, :)
        !> Kinetic energy lost.
        real(dp), intent(out) :: loss
        integer, allocatable :: involved(:), ipiv(:), first(:), it(:)
        integer :: state(1)
        real(dp), allocatable :: dirs(:, :), a(:, :), q(:), p(:), ctm(:, :), ftm(:, :), &
                                 g(:, :), l(:, :), u(:), xl(:, :), ut(:), e(:), proj(:, :)
        type(element_box_t), allocatable :: boxes(:)
        type(contact_set_t) :: impacts
        integer :: n, j, k, m, sweeps, info, c, w, nch, inorm
        real(dp) :: ke0, resid, scale, pn, rho, un
        n = self%n
        allocate (involved(0))
        do j = 1, self%nc
            if (j == jimp .or. &
                self%cs%elements(j)%e%rigid_closed(code(self%slot0(j) + 1:self%slot_hi(j)))) &
                involved = [involved, j]
        end do
        m = size(involved)
        allocate (boxes(m), first(m + 1))
        nch = 0
        do k = 1, m
            first(k) = nch + 1
            nch = nch + self%cs%width(involved(k))
            call self%cs%elements(involved(k))%e%impact_law(boxes(k)%e)
        end do
        first(m + 1) = nch + 1
        allocate (dirs(n, nch))
        do k = 1, m
            j = involved(k)
            do c = 1, self%cs%width(j)
                dirs(:, first(k) + c - 1) = &
                    self%geom(j)%dt(:, self%cs%along(self%cs%first(j) + c - 1))
            end do
        end do
        call new_element_set(impacts, boxes)
        a = matmul(transpose(dirs), dirs)
        q = matmul(yb(n + 1:2*n), dirs)
        allocate (p(nch))
        p = 0.0_dp
        scale = max(maxval(abs(q))/max(maxval(abs(a)), tiny(1.0_dp)), tiny(1.0_dp))
        call impacts%step_forces(a, q, p, scale, 1.0e-14_dp, 1000, sweeps, resid)
        u = q + matmul(a, p)
        ke0 = 0.5_dp*dot_product(yb(n + 1:2*n), yb(n + 1:2*n))
        yb(n + 1:2*n) = yb(n + 1:2*n) + matmul(dirs, p)
        loss = ke0 - 0.5_dp*dot_product(yb(n + 1:2*n), yb(n + 1:2*n))
        ! the jump map of the active impulses: (I + L) du+ = du- + Ft dLambda, Ct^T du+ = 0
        allocate (ctm(n, 0), ftm(n, 0), xl(n, n))
        xl = identity_matrix(n)
        do k = 1, m
            j = involved(k)
            w = self%cs%width(j)
            inorm = 0
            do c = 1, w
                if (self%cs%along(self%cs%first(j) + c - 1) == along_normal) inorm = c
            end do
            if (inorm == 0) cycle
            pn = p(first(k) + inorm - 1)
            if (pn <= 0.0_dp) cycle
            ! the element's state at the impulse
            rho = 0.0_dp
            do c = first(k), first(k + 1) - 1
                rho = rho + a(c, c)/w
            end do
            call impacts%elements(k)%e%states(rho, reshape(p(first(k):first(k + 1) - 1), [1, w]), &
                                              reshape(u(first(k):first(k + 1) - 1), [1, w]), &
                                              state)
            if (state(1) == state_stick) then
                ctm = reshape([ctm, dirs(:, first(k):first(k + 1) - 1)], [n, size(ctm, 2) + w])
                ftm = reshape([ftm, dirs(:, first(k):first(k + 1) - 1)], [n, size(ftm, 2) + w])
            else
                ! sliding: the normal held by n + T P_t / P_n; the impulse turns with the slip
                ! after it, e = T^T u+ / |T^T u+| (L = |P_t| T (I - e e^T) T^T / |T^T u+|,
                ! mu P_n = |P_t| on the limit; zero in 1D, where e e^T = 1)
                it = pack([(first(k) + c - 1, c=1, w)], [(c /= inorm, c=1, w)])
                ctm = reshape([ctm, dirs(:, first(k) + inorm - 1)], [n, size(ctm, 2) + 1])
                ftm = reshape([ftm, dirs(:, first(k) + inorm - 1) + &
                               matmul(dirs(:, it), p(it))/pn], [n, size(ftm, 2) + 1])
                ut = matmul(yb(n + 1:2*n), dirs(:, it))
                un = norm2(ut)
                if (un > 0.0_dp) then
                    e = ut/un
                    proj = -spread(e, 2, size(e))*spread(e, 1, size(e))
                    do c = 1, size(e)
                        proj(c, c) = proj(c, c) + 1.0_dp
                    end do
                    xl = xl + norm2(p(it))/un*matmul(dirs(:, it), &
                                                     matmul(proj, transpose(dirs(:, it))))
                end if
            end if
        end do
        jump = identity_matrix(size(jump, 1))
        if (size(ctm, 2) == 0) return
        ! X = (I + L)^-1; du+ = (X - X Ft (Ct^T X Ft)^-1 Ct^T X) du-
        allocate (ipiv(n))
        l = identity_matrix(n)
        g = xl
        call dgesv(n, n, g, n, ipiv, l, n, info)
        if (info /= 0) return
        xl = l
        g = matmul(transpose(ctm), matmul(xl, ftm))
        l = matmul(transpose(ctm), xl)
        deallocate (ipiv)
        allocate (ipiv(size(g, 1)))
        call dgesv(size(g, 1), n, g, size(g, 1), ipiv, l, size(g, 1), info)
        if (info /= 0) return
        jump(n + 1:2*n, n + 1:2*n) = xl - matmul(matmul(xl, ftm), l)
    end subroutine impact_jump

    !> Put every rigid normal at a zero or negative gap (contact_element_t%start_gap) at zero
    !> gap: the M-orthogonal projection of the displacement, in balanced coordinates p = S q
    !> (x = Phi q): q <- q - Nt G^-1 (Nt^T q + gap), G = Nt^T Nt. pj (nz x nz) is set to
    !> the Jacobian of the map of the state.
    subroutine close_rigid_gaps(self, yb, pj)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> Balanced state, corrected in place.
        real(dp), intent(inout) :: yb(:)
        !> The Jacobian of the correction.
        real(dp), intent(out) :: pj(:, :)
        real(dp), allocatable :: nt(:, :), rhs(:), q(:), x(:, :)
        integer :: j, n, m, k
        logical :: ok, active
        real(dp) :: gap
        n = self%n
        pj = identity_matrix(size(pj, 1))
        allocate (nt(n, 0), rhs(0))
        q = yb(1:n)/self%s
        do j = 1, self%nc
            call self%cs%elements(j)%e%start_gap(self%geom(j), yb, active, gap)
            if (.not. active) cycle
            nt = reshape([nt, self%geom(j)%dt(:, 3)], [n, size(nt, 2) + 1])
            rhs = [rhs, gap]
        end do
        m = size(nt, 2)
        if (m == 0) return
        ! X = G^-1 [Nt^T q + gap, Nt^T]
        call gram_solve(nt, reshape([rhs, transpose(nt)], [m, n + 1]), x, ok)
        if (.not. ok) return
        q = q - matmul(nt, x(:, 1))
        yb(1:n) = q*self%s
        ! d p_new / d p = S (I - Nt G^-1 Nt^T) S^-1
        do k = 1, n
            pj(1:n, k) = pj(1:n, k) - self%s*matmul(nt, x(:, k + 1))/self%s(k)
        end do
    end subroutine close_rigid_gaps

    !> Remove from the balanced state the velocity along the constraint directions of the
    !> mode md: u <- u - Ct (Ct^T Ct)^-1 Ct^T u (a roundoff-sized correction after an event;
    !> at the start, the projection of a perturbation off the constraints). With pj: pj <-
    !> P pj, P the Jacobian on the state.
    subroutine project_velocities(self, md, yb, pj)
        !> The dynamics.
        class(flow_modes_t), intent(in) :: self
        !> The mode.
        type(mode_t), intent(in) :: md
        !> Balanced state, corrected in place.
        real(dp), intent(inout) :: yb(:)
        !> Jacobian of the start corrections, composed with this one's.
        real(dp), intent(inout), optional :: pj(:, :)
        real(dp), allocatable :: x(:, :)
        integer :: m, n
        logical :: ok
        n = self%n
        m = size(md%ctm, 2)
        if (m == 0) return
        ! X = G^-1 [Ct^T u, Ct^T]
        call gram_solve(md%ctm, reshape(matmul(yb(n + 1:2*n), md%ctm), [m, 1]), x, ok)
        if (.not. ok) return
        yb(n + 1:2*n) = yb(n + 1:2*n) - matmul(md%ctm, x(:, 1))
        ! P = I - Ct G^-1 Ct^T on the velocities (applied in low rank)
        if (present(pj)) call project_velocity_rows(md%ctm, n, pj)
    end subroutine project_velocities
end module stickslip_flow_algebra
