!> The structure as the weighted-residual solve sees it beside its condensed dynamics
!> (condensed_structure_t: frequency, friction limits, automatic rho, forcing), and where a
!> weight rho stands against the structure's contact mobility (rho_ratio, rho_out_of_band).
!> Plain data and two functions of it: built by stickslip_hbm (dense model) and
!> stickslip_hbm_sparse (sparse model); knows nothing of the solve itself.
module stickslip_condensed_structure
    use stickslip_kinds, only: dp
    use stickslip_rho, only: rho_fraction
    use stickslip_contact_set, only: contact_set_t
    implicit none
    private
    public :: condensed_structure_t, rho_ratio, rho_out_of_band

    !> What the weighted-residual solve needs of a structure beside its condensed dynamics
    !> (solve_condensed): built from a dense model_t by solve_periodic, from a
    !> sparse_model_t by solve_periodic_sparse.
    type :: condensed_structure_t
        !> Fundamental angular frequency [rad/s].
        real(dp) :: omega = 0.0_dp
        !> Number of contacts.
        integer :: ncontact = 0
        !> The contact elements and their force channels.
        type(contact_set_t) :: contacts
        !> The automatic rho of the structure (stickslip_rho) [m/(N s)].
        real(dp) :: rho_auto = 1.0_dp
        !> Load shape of each forcing term on the displacement columns (all N DOFs, or the
        !> kept DOFs of a sparse condensation), ncols x nforce: force_direction restricted.
        real(dp), allocatable :: force_rows(:, :)
        !> Harmonic, amplitude [N] and phase [rad] of each forcing term.
        integer, allocatable :: force_harmonic(:)
        real(dp), allocatable :: force_amplitude(:), force_phase(:)
    end type condensed_structure_t

    !> Band of rho / contact mobility in which the friction equality keeps its digits.
    real(dp), parameter, public :: rho_ratio_min = 1.0e-6_dp, rho_ratio_max = 1.0e6_dp

contains

    !> rho / (the geometric mean of the resonance-free contact mobilities) (dimensionless).
    real(dp) function rho_ratio(s, rho)
        !> The structure (its automatic rho).
        type(condensed_structure_t), intent(in) :: s
        !> The weight of the friction equality [m/(N s)].
        real(dp), intent(in) :: rho
        rho_ratio = rho*rho_fraction/s%rho_auto
    end function rho_ratio

    !> rho is outside [rho_ratio_min, rho_ratio_max] times the contact mobility.
    logical function rho_out_of_band(s, rho)
        !> The structure (its contacts and automatic rho).
        type(condensed_structure_t), intent(in) :: s
        !> The weight of the friction equality [m/(N s)].
        real(dp), intent(in) :: rho
        real(dp) :: q
        rho_out_of_band = .false.
        if (s%ncontact == 0) return
        q = rho_ratio(s, rho)
        rho_out_of_band = .not. (q >= rho_ratio_min .and. q <= rho_ratio_max)
    end function rho_out_of_band
end module stickslip_condensed_structure
