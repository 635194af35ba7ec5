!> The contacts of a model as the methods see them: a list of contact elements
!> (stickslip_contact_element, one per contact, built once from a validated model) and the
!> layout of their force channels. The channels of all elements, element after element, are
!> the unknown forces of every method; channel c acts along a direction d_c of its contact
!> (w, t2 or n: a column of the channel direction matrix, N x n_channel, channel_directions).
!> A model whose contacts are all rigid 1D Coulomb contacts under a constant normal load has
!> one channel per contact, channel j = contact j, direction w_j (`coulomb_only`: the
!> batched kernels of the Coulomb element).
!>
!> Which element a contact gets: the law the model gives it explicitly (model_t%laws, e.g.
!> the microslip element), else the law its arrays describe: unilateral with a normal
!> direction, Jenkins with a tangential stiffness, planar with a second tangent, else
!> Coulomb. The methods see the elements only, never these flags.
module stickslip_contact_set
    use stickslip_kinds, only: dp
    use stickslip_model, only: model_t, contact_velocity_direction, contact_normal_direction, &
        contact_tangent2_direction, is_unilateral, is_planar, contact_gap, contact_preload, &
        normal_stiffness_of, tangential_stiffness_of
    use stickslip_contact_element, only: contact_element_t, element_box_t, channel_t, &
        along_tangent, along_tangent2, along_normal, kinematics_gap
    use stickslip_coulomb_element, only: coulomb_element_t, new_coulomb_element
    use stickslip_planar_element, only: new_planar_element
    use stickslip_jenkins_element, only: new_jenkins_element
    use stickslip_unilateral_element, only: new_unilateral_element
    use stickslip_lifting_jenkins_element, only: new_lifting_jenkins_element
    use stickslip_rigid_jenkins_element, only: new_rigid_jenkins_element
    use stickslip_contact_solve, only: contact_forces
    implicit none
    private
    public :: contact_set_t, new_contact_set, new_element_set, channel_directions

    !> The elements and their channel layout.
    type :: contact_set_t
        !> Contacts n_c and channels (force unknowns per time instant).
        integer :: ncontact = 0, nchannel = 0
        !> The element of each contact.
        type(element_box_t), allocatable :: elements(:)
        !> Every element is a rigid 1D Coulomb contact under a constant load (the batched
        !> kernels of stickslip_coulomb_element apply).
        logical :: coulomb_only = .true.
        !> First channel and number of channels of contact j, length n_c.
        integer, allocatable :: first(:), width(:)
        !> Tangential directions of contact j (1, or 2 when a channel acts along t2), and the
        !> channel of its normal force (0: none), length n_c.
        integer, allocatable :: ntangent(:), normal(:)
        !> Contact of each channel and the direction it acts along (along_tangent,
        !> along_tangent2, along_normal), length n_channel.
        integer, allocatable :: contact_of(:), along(:)
    contains
        !> The description of channel c.
        procedure :: channel => set_channel
        !> Some channel is a gap channel: the basis needs the constant term.
        procedure :: needs_constant => set_needs_constant
        !> The largest force the elements carry [N].
        procedure :: force_scale => set_force_scale
        !> Set a sweep parameter on every element that has it.
        procedure :: set_parameter => set_set_parameter
        !> The forces of one implicit step of all channels.
        procedure :: step_forces => set_step_forces
        !> The friction force components and the normal force of contact j at samples.
        procedure :: contact_forces => set_contact_forces
        !> Channel forces summed per contact and direction (the sliders of a joint add up).
        procedure :: direction_forces => set_direction_forces
    end type contact_set_t

contains

    !> The contact set of a validated `model`: one element per contact (its explicit law, or
    !> the law its arrays describe) and their channel layout. No error can occur.
    subroutine new_contact_set(self, model)
        !> The contact set.
        type(contact_set_t), intent(out) :: self
        !> A validated model.
        type(model_t), intent(in) :: model
        type(element_box_t), allocatable :: boxes(:)
        integer :: j
        allocate (boxes(model%ncontact()))
        do j = 1, model%ncontact()
            call element_of(model, j, boxes(j))
        end do
        call new_element_set(self, boxes)
    end subroutine new_contact_set

    !> The contact set of the elements `boxes` (moved in): their channel layout.
    subroutine new_element_set(self, boxes)
        !> The contact set.
        type(contact_set_t), intent(out) :: self
        !> The elements, one per contact (deallocated on return).
        type(element_box_t), allocatable, intent(inout) :: boxes(:)
        integer :: nc, j, c, k, ntan
        nc = size(boxes)
        self%ncontact = nc
        call move_alloc(boxes, self%elements)
        allocate (self%first(nc), self%width(nc), self%ntangent(nc), self%normal(nc))
        c = 0
        do j = 1, nc
            self%first(j) = c + 1
            self%width(j) = self%elements(j)%e%nchannel()
            c = c + self%width(j)
        end do
        self%nchannel = c
        allocate (self%contact_of(c), self%along(c))
        self%coulomb_only = .true.
        do j = 1, nc
            ntan = 1
            self%normal(j) = 0
            do k = 1, self%width(j)
                c = self%first(j) + k - 1
                self%contact_of(c) = j
                self%along(c) = self%elements(j)%e%channel(k)%along
                if (self%along(c) == along_tangent2) ntan = 2
                if (self%along(c) == along_normal .and. self%normal(j) == 0) self%normal(j) = c
            end do
            self%ntangent(j) = ntan
            select type (e => self%elements(j)%e)
            type is (coulomb_element_t)
            class default
                self%coulomb_only = .false.
            end select
        end do
    end subroutine new_element_set

    !> The element of contact j of the model.
    subroutine element_of(model, j, box)
        type(model_t), intent(in) :: model
        integer, intent(in) :: j
        type(element_box_t), intent(out) :: box
        integer :: ntan
        if (allocated(model%laws)) then
            if (size(model%laws) >= j) then
                if (allocated(model%laws(j)%e)) then
                    allocate (box%e, source=model%laws(j)%e)
                    return
                end if
            end if
        end if
        ntan = merge(2, 1, is_planar(model, j))
        if (is_unilateral(model, j) .and. ntan == 2 .and. &
            tangential_stiffness_of(model, j) > 0.0_dp .and. &
            normal_stiffness_of(model, j) > 0.0_dp) then
            allocate (box%e, source=new_lifting_jenkins_element(model%mu(j), &
                      contact_gap(model, j), contact_preload(model, j), &
                      normal_stiffness_of(model, j), tangential_stiffness_of(model, j)))
        else if (is_unilateral(model, j) .and. ntan == 2 .and. &
                 tangential_stiffness_of(model, j) > 0.0_dp) then
            allocate (box%e, source=new_rigid_jenkins_element(model%mu(j), &
                      contact_gap(model, j), contact_preload(model, j), &
                      tangential_stiffness_of(model, j)))
        else if (is_unilateral(model, j)) then
            allocate (box%e, source=new_unilateral_element(ntan, model%mu(j), &
                      contact_gap(model, j), contact_preload(model, j), &
                      normal_stiffness_of(model, j), tangential_stiffness_of(model, j)))
        else if (tangential_stiffness_of(model, j) > 0.0_dp) then
            allocate (box%e, source=new_jenkins_element(ntan, model%mu(j), &
                      model%normal_load(j), tangential_stiffness_of(model, j)))
        else if (ntan == 2) then
            allocate (box%e, source=new_planar_element(model%mu(j), model%normal_load(j)))
        else
            allocate (box%e, source=new_coulomb_element(model%mu(j), model%normal_load(j)))
        end if
    end subroutine element_of

    !> The description of channel c (its element's channel_t).
    pure function set_channel(self, c) result(ch)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        !> Channel index (1..n_channel).
        integer, intent(in) :: c
        type(channel_t) :: ch
        integer :: j
        j = self%contact_of(c)
        ch = self%elements(j)%e%channel(c - self%first(j) + 1)
    end function set_channel

    !> Some channel's kinematic quantity is a gap (a unilateral contact): its gap, preload
    !> and mean normal force need the constant term of a Fourier basis.
    pure logical function set_needs_constant(self) result(needs)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        type(channel_t) :: ch
        integer :: c
        needs = .false.
        do c = 1, self%nchannel
            ch = self%channel(c)
            if (ch%kinematics == kinematics_gap) needs = .true.
        end do
    end function set_needs_constant

    !> The largest force scale of the elements [N] (0 without contacts).
    pure real(dp) function set_force_scale(self) result(f)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        integer :: j
        f = 0.0_dp
        do j = 1, self%ncontact
            f = max(f, self%elements(j)%e%force_scale())
        end do
    end function set_force_scale

    !> Set parameter `name` ('mu', 'normal_load', 'preload') to `value` on every element that
    !> has it; `count` the elements that took it.
    subroutine set_set_parameter(self, name, value, count)
        !> The contact set.
        class(contact_set_t), intent(inout) :: self
        !> The parameter and its value.
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: value
        !> Elements that have the parameter.
        integer, intent(out) :: count
        integer :: j
        logical :: done
        count = 0
        do j = 1, self%ncontact
            call self%elements(j)%e%set_parameter(name, value, done)
            if (done) count = count + 1
        end do
    end subroutine set_set_parameter

    !> The channel forces r of one implicit step, u = q + A r and every element's law Psi(r_j,
    !> u_j) = 0. A set of Coulomb contacts only: the projected Gauss-Seidel of
    !> stickslip_contact_solve (the box QP whose optimality conditions are Coulomb's law;
    !> tolerance tol times the largest limit). Otherwise block Gauss-Seidel over the elements,
    !> each element's block by its own local solve (step_forces), until no force changes by
    !> more than tol times `scale` [N] in a sweep, at most max_sweeps. `r` holds the start on
    !> entry. `sweeps` the sweeps made (0 for one Coulomb contact), `residual` the largest
    !> |Psi| left relative to the velocity and force scales (0 on the Coulomb path).
    subroutine set_step_forces(self, a, q, r, scale, tol, max_sweeps, sweeps, residual)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        !> Delassus matrix with the compliances, n_ch x n_ch [m/(N s)].
        real(dp), intent(in) :: a(:, :)
        !> Free kinematic quantities, n_ch [m/s].
        real(dp), intent(in) :: q(:)
        !> Channel forces: start on entry, solution on exit [N].
        real(dp), intent(inout) :: r(:)
        !> Force scale [N] (> 0) and relative tolerance of the sweeps.
        real(dp), intent(in) :: scale, tol
        !> Sweeps at most.
        integer, intent(in) :: max_sweeps
        !> Sweeps made.
        integer, intent(out) :: sweeps
        !> Largest relative |Psi| left (not computed when absent).
        real(dp), intent(out), optional :: residual
        integer :: j, c0, m, c, k
        real(dp) :: change, old(size(r)), qj(size(r)), acc
        real(dp), allocatable :: limit(:)
        if (present(residual)) residual = 0.0_dp
        if (self%coulomb_only) then
            allocate (limit(self%ncontact))
            do j = 1, self%ncontact
                limit(j) = self%elements(j)%e%force_scale()
            end do
            call contact_forces(a, q, limit, r, tol, max_sweeps, sweeps)
            return
        end if
        if (self%ncontact == 1) then
            ! one element: its own local solve on the whole system
            sweeps = 1
            call self%elements(1)%e%step_forces(a, q, r, scale)
        else
            sweeps = 0
            do sweeps = 1, max_sweeps
                change = 0.0_dp
                do j = 1, self%ncontact
                    c0 = self%first(j)
                    m = self%width(j)
                    ! q_j + sum over the other elements' channels of A_jl r_l
                    do k = 1, m
                        acc = q(c0 + k - 1)
                        do c = 1, size(r)
                            if (c >= c0 .and. c < c0 + m) cycle
                            acc = acc + a(c0 + k - 1, c)*r(c)
                        end do
                        qj(k) = acc
                        old(k) = r(c0 + k - 1)
                    end do
                    call self%elements(j)%e%step_forces(a(c0:c0 + m - 1, c0:c0 + m - 1), &
                                                        qj(1:m), r(c0:c0 + m - 1), scale)
                    do k = 1, m
                        change = max(change, abs(r(c0 + k - 1) - old(k)))
                    end do
                end do
                if (change <= tol*scale) exit
            end do
            sweeps = min(sweeps, max_sweeps)
        end if
        if (.not. present(residual)) return
        do j = 1, self%ncontact
            residual = max(residual, block_residual(self%first(j), self%width(j), j))
        end do

    contains

        !> |Psi| of element j at the current forces, relative to its velocity and force scales.
        real(dp) function block_residual(c0, m, j) result(res)
            integer, intent(in) :: c0, m, j
            real(dp) :: u(1, m), p(1, m), rr(1, m), rho
            integer :: k
            rho = 0.0_dp
            do k = 0, m - 1
                rho = rho + a(c0 + k, c0 + k)
            end do
            rho = max(rho/m, tiny(1.0_dp))
            u(1, :) = q(c0:c0 + m - 1) + matmul(a(c0:c0 + m - 1, :), r)
            rr(1, :) = r(c0:c0 + m - 1)
            call self%elements(j)%e%psi(rho, rr, u, p)
            res = maxval(abs(p))/max(maxval(abs(q(c0:c0 + m - 1))), rho*scale, tiny(1.0_dp))
        end function block_residual
    end subroutine set_step_forces

    !> At the samples of the channel forces rs (nt x n_ch): the friction force of contact j
    !> along w and along t2 (the sum of its channels along each: several sliders of a
    !> microslip element add up), f(nt, 2) [N] (f(:, 2) = 0 without t2), and its normal
    !> force lambda(nt) [N] (the constant normal load when it has no normal channel).
    subroutine set_contact_forces(self, rs, j, f, lambda)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        !> Channel forces at the samples [N].
        real(dp), intent(in) :: rs(:, :)
        !> Contact index.
        integer, intent(in) :: j
        !> Friction force components [N].
        real(dp), intent(out) :: f(:, :)
        !> Normal force [N].
        real(dp), intent(out) :: lambda(:)
        integer :: c
        f = 0.0_dp
        lambda = self%elements(j)%e%normal_load()
        if (self%normal(j) > 0) lambda = 0.0_dp
        do c = self%first(j), self%first(j) + self%width(j) - 1
            select case (self%along(c))
            case (along_tangent)
                f(:, 1) = f(:, 1) + rs(:, c)
            case (along_tangent2)
                f(:, 2) = f(:, 2) + rs(:, c)
            case default
                lambda = lambda + rs(:, c)
            end select
        end do
    end subroutine set_contact_forces

    !> The channel forces rs (nt x n_ch) [N] summed per contact and direction: one column
    !> per (contact, direction) in channel order, at the first channel along it (rs itself
    !> when every channel of a contact acts along its own direction; a microslip joint's
    !> sliders add up to one column). rs is returned unchanged when it is not n_ch wide.
    function set_direction_forces(self, rs) result(f)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        !> Channel forces at the samples [N].
        real(dp), intent(in) :: rs(:, :)
        real(dp), allocatable :: f(:, :)
        logical :: first(size(rs, 2))
        integer :: c, c2, k
        if (size(rs, 2) /= self%nchannel .or. self%coulomb_only) then
            f = rs
            return
        end if
        do c = 1, self%nchannel
            first(c) = .true.
            do c2 = self%first(self%contact_of(c)), c - 1
                if (self%along(c2) == self%along(c)) first(c) = .false.
            end do
        end do
        allocate (f(size(rs, 1), count(first)))
        f = 0.0_dp
        k = 0
        do c = 1, self%nchannel
            if (.not. first(c)) cycle
            k = k + 1
            do c2 = self%first(self%contact_of(c)), self%first(self%contact_of(c)) + &
                self%width(self%contact_of(c)) - 1
                if (self%along(c2) == self%along(c)) f(:, k) = f(:, k) + rs(:, c2)
            end do
        end do
    end function set_direction_forces

    !> The channel directions of a validated `model`, N x n_channel (contact_set_t order):
    !> w_j, t2_j or n_j as each channel acts along. For a Coulomb-only set the columns are
    !> contact_velocity_direction's.
    function channel_directions(model, cs) result(d)
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Its contact set.
        type(contact_set_t), intent(in) :: cs
        real(dp) :: d(model%ndof, cs%nchannel)
        integer :: c, j
        do c = 1, cs%nchannel
            j = cs%contact_of(c)
            select case (cs%along(c))
            case (along_tangent)
                d(:, c) = contact_velocity_direction(model, j)
            case (along_tangent2)
                d(:, c) = contact_tangent2_direction(model, j)
            case default
                d(:, c) = contact_normal_direction(model, j)
            end select
        end do
    end function channel_directions
end module stickslip_contact_set
