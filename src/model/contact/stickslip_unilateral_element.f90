!> The unilateral (Signorini) contact with friction (doc/contacts.md): the channels [w, (t2),
!> n]; gap g = gap + n^T x >= 0, normal force lambda >= 0, lambda g = 0 (elastic with a
!> normal stiffness k_n: lambda = max(0, -k_n g)); friction in 1D or in the disk with the
!> varying limit mu lambda(t), rigid or behind a tangential stiffness k_t; a static preload
!> -P n pressing it closed.
module stickslip_unilateral_element
    use stickslip_kinds, only: dp
    use stickslip_friction_contact, only: friction_contact_t, init_friction_contact
    implicit none
    private
    public :: unilateral_element_t, new_unilateral_element

    !> A unilateral contact with 1D or 2D friction.
    type, extends(friction_contact_t) :: unilateral_element_t
    contains
        procedure :: law_name => unilateral_name
    end type unilateral_element_t

contains

    !> The element with `ntangent` (1 or 2) tangential directions, friction coefficient mu
    !> >= 0, initial gap [m], preload >= 0 [N], normal and tangential stiffness >= 0 [N/m]
    !> (0: rigid).
    function new_unilateral_element(ntangent, mu, gap, preload, kn, kt) result(self)
        !> Tangential directions.
        integer, intent(in) :: ntangent
        !> Friction coefficient, gap [m], preload [N], stiffnesses [N/m].
        real(dp), intent(in) :: mu, gap, preload, kn, kt
        type(unilateral_element_t) :: self
        call init_friction_contact(self, ntangent, .true., mu, 0.0_dp, gap, preload, kn, kt)
    end function new_unilateral_element

    pure function unilateral_name(self) result(name)
        class(unilateral_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "unilateral"
    end function unilateral_name
end module stickslip_unilateral_element
