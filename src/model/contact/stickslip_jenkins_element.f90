!> The Jenkins element (doc/contacts.md): a spring of stiffness k_t in series with a Coulomb
!> slider, in 1D (channel w) or 2D (channels [w, t2], the slider force in the disk), under a
!> constant normal load. Stuck, the contact is the spring; slipping, the force is on the
!> limit mu N and the slider moves. The channel's kinematic quantity is the slider velocity
!> w^T x' + r' / k_t (its compliance 1 / k_t).
module stickslip_jenkins_element
    use stickslip_kinds, only: dp
    use stickslip_friction_contact, only: friction_contact_t, init_friction_contact
    implicit none
    private
    public :: jenkins_element_t, new_jenkins_element

    !> A spring k_t in series with a Coulomb slider, 1D or 2D, constant normal load.
    type, extends(friction_contact_t) :: jenkins_element_t
    contains
        procedure :: law_name => jenkins_name
    end type jenkins_element_t

contains

    !> The element with `ntangent` (1 or 2) tangential directions, friction coefficient mu >=
    !> 0, normal load >= 0 [N] and tangential stiffness k_t > 0 [N/m].
    function new_jenkins_element(ntangent, mu, normal_load, kt) result(self)
        !> Tangential directions.
        integer, intent(in) :: ntangent
        !> Friction coefficient, normal load [N], tangential stiffness [N/m].
        real(dp), intent(in) :: mu, normal_load, kt
        type(jenkins_element_t) :: self
        call init_friction_contact(self, ntangent, .false., mu, normal_load, 0.0_dp, 0.0_dp, &
                                   0.0_dp, kt)
    end function new_jenkins_element

    pure function jenkins_name(self) result(name)
        class(jenkins_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "jenkins"
    end function jenkins_name
end module stickslip_jenkins_element
