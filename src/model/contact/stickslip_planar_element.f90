!> 2D (in-plane) Coulomb friction under a constant normal load (doc/contacts.md): the
!> channels [w, t2], the friction force (r, s) in the disk of radius mu N, following the slip
!> direction as it turns (the projection onto the disk, stickslip_contact_law). Rigid.
module stickslip_planar_element
    use stickslip_kinds, only: dp
    use stickslip_friction_contact, only: friction_contact_t, init_friction_contact
    implicit none
    private
    public :: planar_element_t, new_planar_element

    !> 2D friction, constant normal load, rigid.
    type, extends(friction_contact_t) :: planar_element_t
    contains
        procedure :: law_name => planar_name
        procedure :: exact_support => planar_exact_support
    end type planar_element_t

contains

    !> The element of friction coefficient mu >= 0 and normal load >= 0 [N].
    function new_planar_element(mu, normal_load) result(self)
        !> Friction coefficient and normal load [N].
        real(dp), intent(in) :: mu, normal_load
        type(planar_element_t) :: self
        call init_friction_contact(self, 2, .false., mu, normal_load, 0.0_dp, 0.0_dp, &
                                   0.0_dp, 0.0_dp)
    end function new_planar_element

    !> Not yet in the exact flow.
    function planar_exact_support(self) result(why)
        class(planar_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = "the exact reference does not handle 2D friction yet"
    end function planar_exact_support

    pure function planar_name(self) result(name)
        class(planar_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "planar"
    end function planar_name
end module stickslip_planar_element
