!> The units the pictures' labels name (&output length_unit, force_unit, time_unit,
!> frequency_unit): the model's own, SI by default. Labels only: stickslip computes in
!> whatever consistent units the model is given in and converts nothing.
module stickslip_plot_units
    implicit none
    private
    public :: plot_units_t, energy_unit, cycles_unit, mass_unit

    !> Units of length, force and time, and the frequency axis.
    type :: plot_units_t
        character(len=32) :: length = 'm', force = 'N', time = 's'
        !> The frequency axis of a sweep in omega in cycles per time unit (frc.csv's
        !> frequency, omega / 2 pi; Hz when the time unit is s) instead of omega.
        logical :: cycles = .false.
    end type plot_units_t

contains

    !> The unit of energy of `units`: J for N and m, else force and length side by side
    !> ('N mm').
    pure function energy_unit(units) result(unit)
        type(plot_units_t), intent(in) :: units
        character(len=:), allocatable :: unit
        if (trim(units%force) == 'N' .and. trim(units%length) == 'm') then
            unit = 'J'
        else
            unit = trim(units%force)//" "//trim(units%length)
        end if
    end function energy_unit

    !> Cycles per time unit: Hz for s, else 1/<time>.
    pure function cycles_unit(units) result(unit)
        type(plot_units_t), intent(in) :: units
        character(len=:), allocatable :: unit
        if (trim(units%time) == 's') then
            unit = 'Hz'
        else
            unit = "1/"//trim(units%time)
        end if
    end function cycles_unit

    !> The unit of mass of `units` (force time^2 / length): kg for N, s and m, t for N, s and
    !> mm (the tonne of mm-t-s models), else 'N s^2/mm' written out.
    pure function mass_unit(units) result(unit)
        type(plot_units_t), intent(in) :: units
        character(len=:), allocatable :: unit
        if (trim(units%force) == 'N' .and. trim(units%time) == 's' .and. &
            trim(units%length) == 'm') then
            unit = 'kg'
        else if (trim(units%force) == 'N' .and. trim(units%time) == 's' .and. &
                 trim(units%length) == 'mm') then
            unit = 't'
        else
            unit = trim(units%force)//" "//trim(units%time)//"^2/"//trim(units%length)
        end if
    end function mass_unit
end module stickslip_plot_units
