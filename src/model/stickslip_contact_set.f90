!> The contacts of a model as the methods see them: each contact is one to three force
!> channels (doc/contacts.md), in contact order,
!>     [tangent 1, (tangent 2), (normal)],
!> each channel c with a direction d_c (a column of the channel direction matrix, N x
!> n_channel) along which its force acts on the structure. A model whose contacts are all
!> rigid 1D friction under a constant normal load has one channel per contact, channel j =
!> contact j, direction w_j: exactly the contacts of before (`plain`).
!>
!> Plain data built from a validated model_t (new_contact_set); every method reads the
!> contact laws' parameters from here, never from the optional arrays of model_t.
module stickslip_contact_set
    use stickslip_kinds, only: dp
    use stickslip_model, only: model_t, contact_velocity_direction, contact_normal_direction, &
        contact_tangent2_direction, is_unilateral, is_planar, contact_gap, contact_preload, &
        normal_stiffness_of, tangential_stiffness_of
    use stickslip_contact_law, only: contact_law_t
    implicit none
    private
    public :: contact_set_t, new_contact_set, channel_directions
    public :: channel_tangent, channel_tangent2, channel_normal

    !> Kinds of channel.
    integer, parameter :: channel_tangent = 1, channel_tangent2 = 2, channel_normal = 3

    !> The channel layout and the law parameters of every contact.
    type :: contact_set_t
        !> Contacts n_c and channels (force unknowns per time instant).
        integer :: ncontact = 0, nchannel = 0
        !> Every contact is rigid 1D friction under a constant normal load (one channel per
        !> contact, the layout and laws of before).
        logical :: plain = .true.
        !> First channel of contact j (its first tangential direction), length n_c.
        integer, allocatable :: first(:)
        !> Tangential channels of contact j (1 or 2), length n_c.
        integer, allocatable :: ntangent(:)
        !> Channel of the normal force of contact j, 0 under a constant normal load.
        integer, allocatable :: normal(:)
        !> Number of channels of contact j (ntangent + 1 when unilateral).
        integer, allocatable :: width(:)
        !> Contact of each channel and its kind (channel_tangent, channel_tangent2,
        !> channel_normal), length n_channel.
        integer, allocatable :: contact_of(:), kind(:)
        !> Friction coefficient, constant normal load [N] (0 for a unilateral contact),
        !> initial gap [m], preload [N], normal and tangential contact stiffness [N/m]
        !> (0: rigid) of each contact.
        real(dp), allocatable :: mu(:), normal_load(:), gap(:), preload(:), kn(:), kt(:)
    contains
        !> Friction limit mu N of a constant-load contact [N] (0 for a unilateral one).
        procedure :: constant_limit
        !> The law of contact j (stickslip_contact_law).
        procedure :: law
    end type contact_set_t

contains

    !> The contact set of a validated `model`. No error can occur.
    subroutine new_contact_set(self, model)
        !> The contact set.
        type(contact_set_t), intent(out) :: self
        !> A validated model.
        type(model_t), intent(in) :: model
        integer :: nc, j, c
        nc = model%ncontact()
        self%ncontact = nc
        allocate (self%first(nc), self%ntangent(nc), self%normal(nc), self%width(nc))
        allocate (self%mu(nc), self%normal_load(nc), self%gap(nc), self%preload(nc), &
                  self%kn(nc), self%kt(nc))
        c = 0
        do j = 1, nc
            self%first(j) = c + 1
            self%ntangent(j) = 1
            if (is_planar(model, j)) self%ntangent(j) = 2
            c = c + self%ntangent(j)
            self%normal(j) = 0
            if (is_unilateral(model, j)) then
                c = c + 1
                self%normal(j) = c
            end if
            self%width(j) = c - self%first(j) + 1
            self%mu(j) = model%mu(j)
            self%normal_load(j) = model%normal_load(j)
            self%gap(j) = contact_gap(model, j)
            self%preload(j) = contact_preload(model, j)
            self%kn(j) = normal_stiffness_of(model, j)
            self%kt(j) = tangential_stiffness_of(model, j)
        end do
        self%nchannel = c
        allocate (self%contact_of(c), self%kind(c))
        do j = 1, nc
            self%contact_of(self%first(j):self%first(j) + self%width(j) - 1) = j
            self%kind(self%first(j)) = channel_tangent
            if (self%ntangent(j) == 2) self%kind(self%first(j) + 1) = channel_tangent2
            if (self%normal(j) > 0) self%kind(self%normal(j)) = channel_normal
        end do
        self%plain = self%nchannel == nc .and. all(self%kt == 0.0_dp)
    end subroutine new_contact_set

    !> mu_j N_j of contact j under a constant normal load, 0 for a unilateral contact [N].
    elemental real(dp) function constant_limit(self, j)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        !> Contact index.
        integer, intent(in) :: j
        constant_limit = 0.0_dp
        if (self%normal(j) == 0) constant_limit = self%mu(j)*self%normal_load(j)
    end function constant_limit

    !> The law of contact j: its channels and friction parameters.
    pure function law(self, j) result(l)
        !> The contact set.
        class(contact_set_t), intent(in) :: self
        !> Contact index.
        integer, intent(in) :: j
        type(contact_law_t) :: l
        l%ntangent = self%ntangent(j)
        l%unilateral = self%normal(j) > 0
        l%mu = self%mu(j)
        l%normal_load = self%normal_load(j)
    end function law

    !> The channel directions of a validated `model`, N x n_channel (contact_set_t order):
    !> w_j, t2_j, n_j. For a plain model the columns are contact_velocity_direction's.
    function channel_directions(model, cs) result(d)
        !> A validated model.
        type(model_t), intent(in) :: model
        !> Its contact set.
        type(contact_set_t), intent(in) :: cs
        real(dp) :: d(model%ndof, cs%nchannel)
        integer :: j, c
        do j = 1, cs%ncontact
            c = cs%first(j)
            d(:, c) = contact_velocity_direction(model, j)
            if (cs%ntangent(j) == 2) d(:, c + 1) = contact_tangent2_direction(model, j)
            if (cs%normal(j) > 0) d(:, cs%normal(j)) = contact_normal_direction(model, j)
        end do
    end function channel_directions
end module stickslip_contact_set
