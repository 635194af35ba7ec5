!> The gnuplot scripts of the pictures: frc.gp (frc.png, a forced-response curve, and
!> frc_dissipation.png, the dissipation per cycle against amplitude) and
!> robustness.gp (robustness_cold.png, robustness_warm.png, the robustness maps) and
!> modes.gp (modes.png, the backbone of a nonlinear mode) and family.gp (frc_family.png, the
!> curves of a family coloured by its parameter, and family.png, their peaks against it). Each
!> script reads its CSV file by a relative name, so it runs in the output directory
!> (`cd DIR && gnuplot frc.gp`), and writes its PNGs with the name suffix held by the
!> gnuplot variable `suffix` ('' unless given with -e). Writing a script starts nothing:
!> the command line draws the pictures.
module stickslip_plot_scripts
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa
    use stickslip_robustness, only: robustness_options_t
    use stickslip_case, only: put, rtoa
    use stickslip_files, only: open_temporary, close_and_rename
    use stickslip_plot_units, only: plot_units_t, energy_unit, cycles_unit, mass_unit
    implicit none
    private
    public :: write_frc_plot_script, write_robustness_plot_script, write_modes_plot_script
    public :: write_sector_modes_plot_script
    public :: write_family_plot_script

contains

    !> Write `dir`/frc.gp, the gnuplot script that draws two pictures from frc.csv:
    !> frc.png, the amplitude [m] of every DOF of frc.csv (all N, or the `dofs` selected, in
    !> their order; `amplitude` chooses the columns: vib_<d>, half the peak-to-peak, by
    !> default; h1_<d> the first harmonic's modulus; amp_<d> max_t |x|) against the swept
    !> parameter (amplitude on a log scale), unstable points marked with red crosses
    !> (columns read by name); frc_dissipation.png, the energy the
    !> friction contacts dissipate per cycle [J] against the amplitude of each of these DOFs
    !> (log-log), with the total (friction + viscous) against the first. Curves are named
    !> "DOF <d>" and the axes carry their units; no text is read as gnuplot markup.
    !> Error: stat io.
    subroutine write_frc_plot_script(dir, parameter, ndof, error, dofs, labels, amplitude, &
                                     units, stability)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> Name of the swept parameter ('omega', 'force_amplitude', 'mu', 'normal_load',
        !> 'preload').
        character(len=*), intent(in) :: parameter
        !> Number of DOFs (columns amp_1..amp_N when `dofs` is absent).
        integer, intent(in) :: ndof
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs of frc.csv (its columns amp_<d>, in this order); absent: 1..ndof.
        integer, intent(in), optional :: dofs(:)
        !> The numbers in the column titles amp_<d> (default: `dofs`), e.g. full-model
        !> numbers of a reduced model.
        integer, intent(in), optional :: labels(:)
        !> The amplitude drawn (&output plot_amplitude): 'half_peak_to_peak' (the columns
        !> vib_<d>, the default), 'first_harmonic' (h1_<d>) or 'max_abs' (amp_<d>).
        character(len=*), intent(in), optional :: amplitude
        !> The units the labels name (default SI, omega in rad/s).
        type(plot_units_t), intent(in), optional :: units
        !> Stability was computed (default .true.): the unstable points are drawn and named.
        logical, intent(in), optional :: stability
        type(plot_units_t) :: un
        logical :: floquet
        integer :: u, stat, k, nsel
        character(len=512) :: msg
        character(len=:), allocatable :: sep, dof_name, prefix, label, names, xcol, lu
        integer, allocatable :: sel(:)
        call drawn_dofs(ndof, sel, dof_name, dofs, labels)
        nsel = size(sel)
        if (present(units)) un = units
        floquet = .true.
        if (present(stability)) floquet = stability
        lu = " ["//trim(un%length)//"]"
        call amplitude_columns(amplitude, prefix, label)
        label = label//lu
        ! the x column: the parameter, or for a sweep in omega on a cycles axis the frequency
        xcol = "1"
        if (parameter == 'omega' .and. un%cycles) xcol = "(column('frequency'))"
        names = ""
        do k = 1, nsel
            if (k > 1) names = names//" "
            names = names//prefix//itoa(sel(k))
        end do
        call begin_script(dir, "frc", "Forced-response curve and dissipation per cycle "// &
                          "(frc.png, frc_dissipation.png)", u, stat, msg, error)
        if (allocated(error)) return
        call put(u, "set terminal pngcairo size 1100,700 noenhanced font ',11'", stat, msg)
        call put(u, "set key autotitle columnhead outside right top box opaque", stat, msg)
        call put(u, "set grid lc rgb '#dddddd'", stat, msg)
        call put(u, "# the amplitude range: from the smallest amplitude, but at most four "// &
                 "decades below the largest (a contact stuck all period drives its DOF to "// &
                 "roundoff)", stat, msg)
        call put(u, "ymax = 0; ymin = 1e300", stat, msg)
        call put(u, "# the amplitude drawn (&output plot_amplitude): the columns "//names, &
                 stat, msg)
        call put(u, "# (a column without a valid value, NaN throughout, leaves STATS_ undefined)", &
                 stat, msg)
        call put(u, "do for [name in '"//names//"'] { stats f using (column(name)) nooutput; "// &
                 "if (exists('STATS_records') && STATS_records > 0) { "// &
                 "if (STATS_max > ymax) { ymax = STATS_max }; "// &
                 "if (STATS_min > 0 && STATS_min < ymin) { ymin = STATS_min } } }", stat, msg)
        call put(u, "alo = (ymin/1.5 > ymax*1e-4 ? ymin/1.5 : ymax*1e-4); ahi = ymax*1.5", &
                 stat, msg)
        call put(u, "", stat, msg)
        call put(u, "# frc.png: amplitude against the parameter", stat, msg)
        call put(u, "set output 'frc.png'.suffix", stat, msg)
        call put(u, "set logscale y", stat, msg)
        call put(u, "if (ymax > 0) set yrange [alo:ahi]", stat, msg)
        call put(u, "# labels at 1, 2 and 5 of each decade when the range spans fewer than "// &
                 "three (gnuplot's own: one a decade)", stat, msg)
        call put(u, decade_tics("y"), stat, msg)
        call put(u, "set xlabel '"//parameter_label(parameter, un)//"'", stat, msg)
        call put(u, "set ylabel '"//label//"'", stat, msg)
        if (floquet) then
            call put(u, "set title 'Forced-response curve (red crosses: unstable, Floquet; "// &
                     "orange circles: untrusted, column check)'", stat, msg)
        else
            call put(u, "set title 'Forced-response curve (orange circles: untrusted, column "// &
                     "check; stability not computed)'", stat, msg)
        end if
        call put(u, "# the column 'stable' (1, 0 unstable, -1 unknown), the column 'trusted' "// &
                 "(0: a check distrusts the point)", stat, msg)
        call put(u, "unstable(name) = (column('stable') == 0 ? column(name) : 1/0)", stat, msg)
        call put(u, "untrusted(name) = (column('trusted') == 0 ? column(name) : 1/0)", stat, &
                 msg)
        do k = 1, nsel
            sep = merge("plot ", "     ", k == 1)
            call put(u, sep//"f using "//xcol//":(column('"//prefix//itoa(sel(k))//"')) "// &
                     "with lines lw 1.5 title '"//dof_name//itoa(sel(k))//"', \", stat, msg)
            call put(u, "     f using "//xcol//":(untrusted('"//prefix//itoa(sel(k))//"')) "// &
                     "with points pt 6 ps 1.0 lc rgb 'orange' "//merge("title 'untrusted'", &
                     "notitle          ", k == nsel)//trim(merge(", \", "   ", &
                                                                floquet .or. k < nsel)), &
                     stat, msg)
            if (floquet) call put(u, "     f using "//xcol//":(unstable('"//prefix// &
                                  itoa(sel(k))//"')) with points "// &
                                  "pt 2 ps 0.8 lc rgb 'red' "//merge("title 'unstable'", &
                                  "notitle         ", k == nsel)// &
                                  trim(merge("   ", ", \", k == nsel)), stat, msg)
        end do
        call put(u, "", stat, msg)
        call put(u, "# frc_dissipation.png: friction dissipation per cycle against amplitude", &
                 stat, msg)
        call put(u, "set output 'frc_dissipation.png'.suffix", stat, msg)
        call put(u, "set logscale xy", stat, msg)
        call put(u, "# the dissipation range: at most five decades below the largest (a stuck "// &
                 "contact dissipates roundoff)", stat, msg)
        call put(u, "unset yrange", stat, msg)
        call put(u, "stats f using (column('dissipation')) nooutput", stat, msg)
        call put(u, "if (STATS_max > 0) { set yrange [STATS_max*1e-5:STATS_max*2] } "// &
                 "else { unset yrange }", stat, msg)
        call put(u, "if (ymax > 0) set xrange [alo:ahi]", stat, msg)
        call put(u, "set ytics autofreq; set format y '%g'", stat, msg)
        call put(u, decade_tics("x"), stat, msg)
        call put(u, "set xlabel '"//label//"'", stat, msg)
        call put(u, "set ylabel 'energy dissipated per cycle ["//energy_unit(un)//"]'", stat, &
                 msg)
        call put(u, "set title 'Dissipation per cycle (solid: friction contacts; dashed: "// &
                 "friction + viscous)'", stat, msg)
        call put(u, "set key outside right top", stat, msg)
        call put(u, "positive(y) = (y > 0 ? y : 1/0)", stat, msg)
        do k = 1, nsel
            sep = merge("plot ", "     ", k == 1)
            call put(u, sep//"f using (column('"//prefix//itoa(sel(k))//"')):"// &
                     "(positive(column('diss_friction')))"// &
                     " with lines lw 1.5 title '"//dof_name//itoa(sel(k))//"', \", &
                     stat, msg)
        end do
        call put(u, "     f using (column('"//prefix//itoa(sel(1))//"')):"// &
                 "(positive(column('dissipation'))) with lines "// &
                 "dt 2 lc rgb 'black' title 'total, against "//dof_name//itoa(sel(1))//"'", &
                 stat, msg)
        call close_and_rename(dir, "frc.gp", u, stat, msg, error)
    end subroutine write_frc_plot_script

    !> Write `dir`/family.gp, the gnuplot script that draws two pictures of a family of
    !> forced-response curves: frc_family.png from frc.csv, the amplitude of the first DOF of
    !> the selection against omega (or the frequency), one line per curve coloured by the
    !> value of the family's parameter (a colour scale), untrusted points circled; and
    !> family.png from family.csv, each selected DOF's peak against the parameter (log axis
    !> when the values are positive and span more than a factor 20) with the stuck and
    !> slipping linear limits' peaks as dashed and dotted lines (for a family in the forcing
    !> amplitude, every peak divided by the amplitude: a receptance). `amplitude` and `units`
    !> as write_frc_plot_script. Error: stat io.
    subroutine write_family_plot_script(dir, parameter, values, ndof, error, dofs, labels, &
                                        amplitude, units)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The family's parameter ('normal_load', 'preload', 'mu', 'force_amplitude').
        character(len=*), intent(in) :: parameter
        !> Its values.
        real(dp), intent(in) :: values(:)
        !> Number of DOFs (columns 1..ndof when `dofs` is absent).
        integer, intent(in) :: ndof
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The DOFs of frc.csv and family.csv; absent: 1..ndof.
        integer, intent(in), optional :: dofs(:)
        !> Their numbers in the column titles (default: `dofs`).
        integer, intent(in), optional :: labels(:)
        !> The amplitude drawn (&output plot_amplitude).
        character(len=*), intent(in), optional :: amplitude
        !> The units the labels name.
        type(plot_units_t), intent(in), optional :: units
        type(plot_units_t) :: un
        integer :: u, stat, k, nsel
        character(len=512) :: msg
        character(len=:), allocatable :: prefix, label, xcol, lu, dof_name, sep, scale, &
                                         ylabel, d, names
        integer, allocatable :: sel(:)
        logical :: receptance
        call drawn_dofs(ndof, sel, dof_name, dofs, labels)
        nsel = size(sel)
        if (present(units)) un = units
        lu = " ["//trim(un%length)//"]"
        call amplitude_columns(amplitude, prefix, label)
        xcol = "1"
        if (un%cycles) xcol = "(column('frequency'))"
        receptance = parameter == 'force_amplitude'
        call begin_script(dir, "family", "A family of forced-response curves and their "// &
                          "peaks (frc_family.png from frc.csv, family.png)", u, stat, msg, &
                          error)
        if (allocated(error)) return
        call put(u, "g = f; f = 'frc.csv'", stat, msg)
        call put(u, "set terminal pngcairo size 1100,700 noenhanced font ',11'", stat, msg)
        call put(u, "set grid lc rgb '#dddddd'", stat, msg)
        call put(u, "n = "//itoa(size(values)), stat, msg)
        call put(u, "", stat, msg)
        call put(u, "# frc_family.png: "//dof_name//itoa(sel(1))//" against the excitation "// &
                 "frequency, one line per curve (column curve), coloured by family_value", &
                 stat, msg)
        call put(u, "set output 'frc_family.png'.suffix", stat, msg)
        call put(u, "ymax = 0; ymin = 1e300", stat, msg)
        call put(u, "stats f using (column('"//prefix//itoa(sel(1))//"')) nooutput", stat, msg)
        call put(u, "if (exists('STATS_records') && STATS_records > 0) { ymax = STATS_max; "// &
                 "ymin = (STATS_min > 0 ? STATS_min : ymax*1e-4) }", stat, msg)
        call put(u, "alo = (ymin/1.5 > ymax*1e-4 ? ymin/1.5 : ymax*1e-4); ahi = ymax*1.5", &
                 stat, msg)
        call put(u, "set logscale y", stat, msg)
        call put(u, "if (ymax > 0) set yrange [alo:ahi]", stat, msg)
        call put(u, decade_tics("y"), stat, msg)
        call put(u, "set xlabel '"//parameter_label('omega', un)//"'", stat, msg)
        call put(u, "set ylabel '"//label//lu//"'", stat, msg)
        call put(u, "set cblabel '"//parameter_label(parameter, un)//"'", stat, msg)
        call put(u, "set palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21918c', "// &
                 "0.75 '#5ec962', 1 '#fde725')", stat, msg)
        call put(u, "set title 'A family of forced-response curves, "//dof_name// &
                 itoa(sel(1))//" (orange circles: untrusted, column check)'", stat, msg)
        call put(u, "set key outside right top", stat, msg)
        call put(u, "on(k, name) = (column('curve') == k ? column(name) : 1/0)", stat, msg)
        call put(u, "untrusted(name) = (column('trusted') == 0 ? column(name) : 1/0)", stat, &
                 msg)
        call put(u, "plot for [k=1:n] f using "//xcol//":(on(k, '"//prefix//itoa(sel(1))// &
                 "')):(column('family_value')) with lines lw 1.5 lc palette notitle, \", &
                 stat, msg)
        call put(u, "     f using "//xcol//":(untrusted('"//prefix//itoa(sel(1))// &
                 "')) with points pt 6 ps 1.0 lc rgb 'orange' title 'untrusted'", stat, msg)
        call put(u, "", stat, msg)
        call put(u, "# family.png: the peaks against the parameter, with the linear limits "// &
                 "(stuck: dashed, slipping: dotted)", stat, msg)
        call put(u, "set output 'family.png'.suffix", stat, msg)
        call put(u, "unset colorbox; unset cblabel; unset yrange; unset ytics; set ytics", &
                 stat, msg)
        if (all(values > 0.0_dp) .and. maxval(values) > 20.0_dp*minval(values)) &
            call put(u, "set logscale x", stat, msg)
        call put(u, "set xlabel '"//parameter_label(parameter, un)//"'", stat, msg)
        if (receptance) then
            scale = "/column('family_value')"
            ylabel = "peak "//label//" / force amplitude ["//trim(un%length)//"/"// &
                     trim(un%force)//"]"
        else
            scale = ""
            ylabel = "peak "//label//lu
        end if
        call put(u, "set ylabel '"//ylabel//"'", stat, msg)
        call put(u, "set title 'Resonance peak against the "//parameter_words(parameter)// &
                 " (dashed: every contact stuck; dotted: every contact slipping; linear)'", &
                 stat, msg)
        ! the range: every peak and reference drawn, at most four decades below the largest
        names = ""
        do k = 1, nsel
            d = itoa(sel(k))
            names = names//" peak_"//d//" stuck_peak_"//d//" slipping_peak_"//d
        end do
        call put(u, "ymax = 0; ymin = 1e300", stat, msg)
        call put(u, "do for [name in '"//trim(adjustl(names))//"'] { "// &
                 "stats g using (column(name)"//scale//") nooutput; "// &
                 "if (exists('STATS_records') && STATS_records > 0) "// &
                 "{ if (STATS_max > ymax) { ymax = STATS_max }; if (STATS_min > 0 && "// &
                 "STATS_min < ymin) { ymin = STATS_min } } }", stat, msg)
        call put(u, "alo = (ymin/1.5 > ymax*1e-4 ? ymin/1.5 : ymax*1e-4); ahi = ymax*1.5", &
                 stat, msg)
        call put(u, "set logscale y; if (ymax > 0) set yrange [alo:ahi]", stat, msg)
        call put(u, decade_tics("y"), stat, msg)
        call put(u, "set key outside right top", stat, msg)
        do k = 1, nsel
            d = itoa(sel(k))
            sep = merge("plot ", "     ", k == 1)
            call put(u, sep//"g using (column('family_value')):(column('peak_"//d//"')"// &
                     scale//") with linespoints lw 1.5 pt 7 lc "//itoa(k)//" title 'peak, "// &
                     dof_name//d//"', \", stat, msg)
            call put(u, "     g using (column('family_value')):(untrusted('peak_"//d//"')"// &
                     scale//") with points pt 6 ps 1.5 lc rgb 'orange' "// &
                     merge("title 'untrusted'", "notitle          ", k == 1)//", \", stat, msg)
            call put(u, "     g using (column('family_value')):(column('stuck_peak_"//d// &
                     "')"//scale//") with lines dt 2 lc "//itoa(k)//" title 'stuck, "// &
                     dof_name//d//"', \", stat, msg)
            call put(u, "     g using (column('family_value')):(column('slipping_peak_"//d// &
                     "')"//scale//") with lines dt 3 lc "//itoa(k)//" title 'slipping, "// &
                     dof_name//d//"'"//trim(merge("   ", ", \", k == nsel)), stat, msg)
        end do
        call close_and_rename(dir, "family.gp", u, stat, msg, error)
    end subroutine write_family_plot_script

    !> Write `dir`/modes.gp, the gnuplot script that draws modes.png from modes.csv: the
    !> backbone's frequency (upper panel: omega [rad/s], or with `units`%cycles the
    !> frequency omega / 2 pi [Hz]) and modal damping ratio (lower panel) against the modal
    !> amplitude (log scale, [length sqrt(mass)] in the units of `units`), with the linear
    !> limits of the contacts stuck and slipping (`omega_stuck`, `omega_slipping` [rad/s],
    !> 0: none) as dashed lines. Error: stat io.
    subroutine write_modes_plot_script(dir, mode, omega_stuck, omega_slipping, error, units)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The mode's number (for the title).
        integer, intent(in) :: mode
        !> The linear limits [rad/s].
        real(dp), intent(in) :: omega_stuck, omega_slipping
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The units the labels name (default SI, the frequency in rad/s; with
        !> units%cycles the frequency axis is modes.csv's frequency, omega / 2 pi).
        type(plot_units_t), intent(in), optional :: units
        type(plot_units_t) :: un
        integer :: u, stat
        character(len=512) :: msg
        character(len=:), allocatable :: fcol, funit, scale
        if (present(units)) un = units
        if (un%cycles) then
            fcol = "3"
            funit = cycles_unit(un)
            scale = "/(2*pi)"
        else
            fcol = "2"
            funit = "rad/"//trim(un%time)
            scale = ""
        end if
        call begin_script(dir, "modes", "Backbone of a nonlinear mode (modes.png)", u, stat, &
                          msg, error)
        if (allocated(error)) return
        call put(u, "set terminal pngcairo size 1000,800 noenhanced font ',11'", stat, msg)
        call put(u, "set output 'modes.png'.suffix", stat, msg)
        call put(u, "set key autotitle columnhead", stat, msg)
        call put(u, "set grid lc rgb '#dddddd'", stat, msg)
        call put(u, "set logscale x", stat, msg)
        call put(u, "w_stuck = "//rtoa(omega_stuck)//scale//"; w_slip = "// &
                 rtoa(omega_slipping)//scale, stat, msg)
        call put(u, "set multiplot layout 2,1 title 'Nonlinear mode "//itoa(mode)// &
                 " (EPMC): frequency and damping against the modal amplitude'", stat, msg)
        call put(u, "# the frequency range: the backbone's (a linear limit far outside it is "// &
                 "named in the key, not drawn)", stat, msg)
        call put(u, "stats f using "//fcol//" nooutput", stat, msg)
        call put(u, "pad = (STATS_max - STATS_min)*0.08 + 1e-3*STATS_max", stat, msg)
        call put(u, "set yrange [STATS_min - pad:STATS_max + pad]", stat, msg)
        if (un%cycles) then
            call put(u, "set ylabel 'frequency f = omega / 2 pi ["//funit//"]'", stat, msg)
        else
            call put(u, "set ylabel 'frequency omega ["//funit//"]'", stat, msg)
        end if
        call put(u, "set format x ''", stat, msg)
        call put(u, "set key bottom right box opaque", stat, msg)
        call put(u, "plot f using 1:"//fcol//" with linespoints lw 1.5 pt 7 ps 0.4 title "// &
                 "'backbone', \", stat, msg)
        call put(u, "     (w_stuck > 0 ? w_stuck : 1/0) with lines dt 2 lc rgb 'gray40' "// &
                 "title sprintf('contacts stuck (linear): %.6g "//funit//"', w_stuck), \", &
                 stat, msg)
        call put(u, "     (w_slip > 0 ? w_slip : 1/0) with lines dt 3 lc rgb 'gray20' "// &
                 "title sprintf('contacts slipping (linear): %.6g "//funit//"', w_slip)", &
                 stat, msg)
        call put(u, "unset yrange", stat, msg)
        call put(u, "set format x '%g'", stat, msg)
        call put(u, "set xlabel 'modal amplitude a = sqrt(x1^T M x1) ["//trim(un%length)// &
                 " sqrt("//mass_unit(un)//")]'", stat, msg)
        call put(u, "set ylabel 'modal damping ratio D = xi / (2 omega) [-]'", stat, msg)
        call put(u, "set key top right box opaque", stat, msg)
        call put(u, "plot f using 1:5 with linespoints lw 1.5 pt 7 ps 0.4 lc rgb '#d62728' "// &
                 "title 'damping ratio'", stat, msg)
        call put(u, "unset multiplot", stat, msg)
        call close_and_rename(dir, "modes.gp", u, stat, msg, error)
    end subroutine write_modes_plot_script

    !> Write `dir`/modes.gp for the backbones of a disk's sector per nodal diameter (modes.csv
    !> with its column nodal_diameter): frequency (upper panel, as write_modes_plot_script)
    !> and modal damping ratio (lower panel) against the modal amplitude, one curve per
    !> diameter of `diameters` (those with points). Error: stat io.
    subroutine write_sector_modes_plot_script(dir, modes, diameters, error, units)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The mode traced in each diameter (for the title and the keys).
        integer, intent(in) :: modes(:)
        !> The nodal diameters drawn.
        integer, intent(in) :: diameters(:)
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The units the labels name (as write_modes_plot_script).
        type(plot_units_t), intent(in), optional :: units
        type(plot_units_t) :: un
        integer :: u, stat
        character(len=512) :: msg
        character(len=:), allocatable :: fcol, funit, key
        logical :: one
        if (present(units)) un = units
        if (un%cycles) then
            fcol = "'frequency'"
            funit = cycles_unit(un)
        else
            fcol = "'omega'"
            funit = "rad/"//trim(un%time)
        end if
        call begin_script(dir, "modes", "Backbones per nodal diameter of a bladed disk's "// &
                          "sector (modes.png)", u, stat, msg, error)
        if (allocated(error)) return
        call put(u, "set terminal pngcairo size 1000,900 noenhanced font ',11'", stat, msg)
        call put(u, "set output 'modes.png'.suffix", stat, msg)
        call put(u, "set grid lc rgb '#dddddd'", stat, msg)
        call put(u, "set logscale x", stat, msg)
        call put(u, "array nd["//itoa(max(1, size(diameters)))//"] = ["// &
                 ilist_text(diameters)//"]", stat, msg)
        call put(u, "# the rows of diameter d: column nodal_diameter = d", stat, msg)
        call put(u, "of(d, c) = (column('nodal_diameter') == d ? column(c) : 1/0)", stat, msg)
        call put(u, "set autoscale xfix", stat, msg)
        if (size(modes) > 0) then
            one = all(modes == modes(1))
        else
            one = .true.
        end if
        if (one) then
            call put(u, "set multiplot layout 2,1 title 'Nonlinear mode "// &
                     itoa(merge(modes(1), 1, size(modes) > 0))//" of each nodal diameter "// &
                     "(EPMC on the sector): frequency and damping against the modal "// &
                     "amplitude'", stat, msg)
            call put(u, "set key outside right top title 'nodal diameter'", stat, msg)
            key = "sprintf('%d', nd[i])"
        else
            call put(u, "array md["//itoa(size(modes))//"] = ["//ilist_text(modes)//"]", &
                     stat, msg)
            call put(u, "set multiplot layout 2,1 title 'Nonlinear modes per nodal diameter "// &
                     "(EPMC on the sector; the mode of each in the key)'", stat, msg)
            call put(u, "set key outside right top title 'diameter (mode)'", stat, msg)
            key = "sprintf('%d (%d)', nd[i], md[i])"
        end if
        if (un%cycles) then
            call put(u, "set ylabel 'frequency f = omega / 2 pi ["//funit//"]'", stat, msg)
        else
            call put(u, "set ylabel 'frequency omega ["//funit//"]'", stat, msg)
        end if
        call put(u, "set format x ''", stat, msg)
        call put(u, "# one colour per diameter, from blue (the lowest) to red", stat, msg)
        call put(u, "set palette defined (0 '#1f77b4', 0.35 '#2ca02c', 0.7 '#ff7f0e', "// &
                 "1 '#d62728')", stat, msg)
        call put(u, "unset colorbox", stat, msg)
        call put(u, "hue(i) = (|nd| > 1 ? (i - 1.0)/(|nd| - 1) : 0)", stat, msg)
        call put(u, "plot for [i=1:|nd|] f using 1:(of(nd[i], "//fcol//")) with lines "// &
                 "lw 1.5 lc palette frac hue(i) title "//key, stat, msg)
        call put(u, "set format x '%g'", stat, msg)
        call put(u, "set xlabel 'modal amplitude of the sector a = sqrt(x1^H M x1) ["// &
                 trim(un%length)//" sqrt("//mass_unit(un)//")]'", stat, msg)
        call put(u, "set ylabel 'modal damping ratio D = xi / (2 omega) [-]'", stat, msg)
        call put(u, "plot for [i=1:|nd|] f using 1:(of(nd[i], 'damping_ratio')) with lines "// &
                 "lw 1.5 lc palette frac hue(i) title "//key, stat, msg)
        call put(u, "unset multiplot", stat, msg)
        call close_and_rename(dir, "modes.gp", u, stat, msg, error)
    end subroutine write_sector_modes_plot_script

    !> Integers separated by commas (gnuplot array text).
    pure function ilist_text(v) result(t)
        integer, intent(in) :: v(:)
        character(len=:), allocatable :: t
        integer :: k
        t = ""
        do k = 1, size(v)
            t = t//merge(",", " ", k > 1)//itoa(v(k))
        end do
        t = trim(adjustl(t))
    end function ilist_text

    !> Open `dir`/<name>.gp (a temporary until close_and_rename) and write what every script
    !> starts with: a comment saying what it draws and how to run it, the PNG name suffix
    !> (variable `suffix`, '' unless given with -e), CSV input and `f` = '<name>.csv'.
    !> Error: stat io (the file cannot be created).
    subroutine begin_script(dir, name, what, u, stat, msg, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The script's and its table's name without extension ('frc': frc.gp, frc.csv).
        character(len=*), intent(in) :: name
        !> What the script draws (for the comment).
        character(len=*), intent(in) :: what
        !> The open unit.
        integer, intent(out) :: u
        !> The write status and message so far (0, '': put keeps the first failure).
        integer, intent(out) :: stat
        character(len=*), intent(out) :: msg
        !> Set when the file cannot be created.
        type(error_type), allocatable, intent(out) :: error
        stat = 0
        msg = ''
        call open_temporary(dir, name//".gp", u, error)
        if (allocated(error)) return
        call put(u, "# "//what//" from "//name//".csv:", stat, msg)
        call put(u, "#   gnuplot "//name//".gp   (in this directory)", stat, msg)
        call put(u, "if (!exists('suffix')) suffix = ''", stat, msg)
        call put(u, "set datafile separator ','", stat, msg)
        call put(u, "f = '"//name//".csv'", stat, msg)
    end subroutine begin_script

    !> The axis label of a swept parameter, with its unit.
    !> A gnuplot line that labels the log `axis` ('x' or 'y') over the amplitude range [alo,
    !> ahi] at 1, 2 and 5 of each decade when it spans fewer than three decades.
    pure function decade_tics(axis) result(line)
        character(len=1), intent(in) :: axis
        character(len=:), allocatable :: line
        line = "if (ymax > 0 && ahi/alo < 1000) { set "//axis//"tics format '%g'; "// &
               "do for [d=floor(log10(alo)):ceil(log10(ahi))] { do for [m=1:3] { "// &
               "v = (m == 1 ? 1 : (m == 2 ? 2 : 5))*10.0**d; set "//axis// &
               "tics add (sprintf('%g', v) v) } } }"
    end function decade_tics

    !> The DOF numbers a script's curves are named by (`labels`, else `dofs`, else 1..ndof)
    !> and the word for them: 'full-model DOF ' when the labels are not the columns (a
    !> reduced model's recovered DOFs), else 'DOF '.
    pure subroutine drawn_dofs(ndof, sel, dof_name, dofs, labels)
        integer, intent(in) :: ndof
        integer, allocatable, intent(out) :: sel(:)
        character(len=:), allocatable, intent(out) :: dof_name
        integer, intent(in), optional :: dofs(:), labels(:)
        integer :: k
        if (present(dofs)) then
            sel = dofs
        else
            sel = [(k, k=1, ndof)]
        end if
        if (present(labels)) sel = labels
        dof_name = "DOF "
        if (present(labels) .and. present(dofs)) then
            if (any(labels /= dofs)) dof_name = "full-model DOF "
        end if
    end subroutine drawn_dofs

    !> The columns and the axis label (without its unit) of an amplitude measure
    !> (&output plot_amplitude): 'half_peak_to_peak' (vib_<d>, the default when absent),
    !> 'first_harmonic' (h1_<d>) or 'max_abs' (amp_<d>).
    pure subroutine amplitude_columns(amplitude, prefix, label)
        character(len=*), intent(in), optional :: amplitude
        character(len=:), allocatable, intent(out) :: prefix, label
        prefix = "vib_"
        label = "vibration amplitude (max_t x - min_t x) / 2"
        if (.not. present(amplitude)) return
        select case (amplitude)
        case ('first_harmonic')
            prefix = "h1_"
            label = "first-harmonic amplitude |x_1|"
        case ('max_abs')
            prefix = "amp_"
            label = "amplitude max_t |x(t)|"
        end select
    end subroutine amplitude_columns

    !> A swept parameter in words ('normal load', 'friction coefficient').
    pure function parameter_words(parameter) result(words)
        character(len=*), intent(in) :: parameter
        character(len=:), allocatable :: words
        select case (parameter)
        case ('force_amplitude')
            words = "forcing amplitude"
        case ('mu')
            words = "friction coefficient"
        case ('normal_load')
            words = "normal load"
        case default
            words = parameter
        end select
    end function parameter_words

    pure function parameter_label(parameter, units) result(label)
        character(len=*), intent(in) :: parameter
        type(plot_units_t), intent(in) :: units
        character(len=:), allocatable :: label, f
        f = " ["//trim(units%force)//"]"
        select case (parameter)
        case ('omega')
            if (units%cycles) then
                label = "excitation frequency f = omega / 2 pi ["//cycles_unit(units)//"]"
            else
                label = "excitation frequency omega [rad/"//trim(units%time)//"]"
            end if
        case ('force_amplitude')
            label = "force amplitude (first forcing term)"//f
        case ('mu')
            label = "friction coefficient mu [-]"
        case ('normal_load')
            label = "normal load N"//f
        case ('preload')
            label = "preload of the unilateral contacts"//f
        case default
            label = parameter
        end select
    end function parameter_label


    !> Write `dir`/robustness.gp, the gnuplot script that draws robustness_cold.png and
    !> robustness_warm.png from robustness.csv: one panel per (rho, H), omega across and mu
    !> up (log), each run a square: green success, orange converged to a wrong solution, red
    !> not converged, the colours explained in a legend below the panels. Error: stat io.
    subroutine write_robustness_plot_script(dir, opts, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> The grid.
        type(robustness_options_t), intent(in) :: opts
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, i, j, m
        character(len=512) :: msg
        character(len=8), parameter :: methods(2) = [character(len=8) :: 'hbm-cold', 'hbm-warm']
        character(len=4), parameter :: tags(2) = [character(len=4) :: 'cold', 'warm']
        character(len=:), allocatable :: sel, label, legend
        integer :: width, height
        call begin_script(dir, "robustness", "Robustness maps (robustness_cold.png, "// &
                          "robustness_warm.png)", u, stat, msg, error)
        if (allocated(error)) return
        call put(u, "# green: converged to the right solution; orange: converged, error > "// &
                 "wrong_tol; red: not converged", stat, msg)
        call put(u, "set logscale y", stat, msg)
        call put(u, "set key off", stat, msg)
        call put(u, "set tics font ',8'", stat, msg)
        call put(u, "set offsets graph 0.04, graph 0.04, graph 0.08, graph 0.08", stat, msg)
        call put(u, "colour(c, s) = (s eq 'T' ? 0x2ca02c : (c eq 'T' ? 0xff7f0e : 0xd62728))", &
                 stat, msg)
        do m = 1, 2
            if (m == 2 .and. .not. opts%warm) exit
            ! the canvas: 260 x 215 pixels a panel, a band on top for the title and one at
            ! the bottom for the colour legend (margins and spacing in screen fractions)
            width = 260*size(opts%harmonics) + 80
            height = 215*size(opts%rhos) + 135
            call put(u, "set terminal pngcairo size "//itoa(width)//","//itoa(height)// &
                     " noenhanced font ',9'", stat, msg)
            call put(u, "set output 'robustness_"//trim(tags(m))//".png'.suffix", stat, msg)
            call put(u, "set multiplot layout "//itoa(size(opts%rhos))//","// &
                     itoa(size(opts%harmonics))//" title 'weighted residual, "// &
                     trim(tags(m))//" starts: omega [rad/s] across, friction coefficient "// &
                     "mu [-] up' margins "//screen_fraction(60, width)//", "// &
                     screen_fraction(width - 15, width)//", "// &
                     screen_fraction(75, height)//", "// &
                     screen_fraction(height - 60, height)//" spacing "// &
                     screen_fraction(45, width)//", "//screen_fraction(60, height), stat, msg)
            do i = 1, size(opts%rhos)
                do j = 1, size(opts%harmonics)
                    ! the colour legend, drawn once below the panels
                    if (i == 1 .and. j == 1) then
                        call put(u, "set key at screen 0.5, screen "// &
                                 screen_fraction(8, height)//" center bottom vertical "// &
                                 "Left reverse samplen 1 font ',9'", stat, msg)
                        legend = ", 1/0 with points pt 5 ps 1.2 lc rgb '#2ca02c' title "// &
                                 "'converged to the right solution', 1/0 with points pt 5 "// &
                                 "ps 1.2 lc rgb '#ff7f0e' title 'converged to a wrong "// &
                                 "solution', 1/0 with points pt 5 ps 1.2 lc rgb '#d62728' "// &
                                 "title 'not converged'"
                    else
                        call put(u, "set key off", stat, msg)
                        legend = ""
                    end if
                    if (opts%rhos(i) == 0.0_dp) then
                        sel = "strcol(6) eq 'T'"
                        label = "rho auto"
                    else
                        sel = "strcol(6) eq 'F' && abs($5 - "//rtoa(opts%rhos(i))//") <= 1e-12*"// &
                              rtoa(opts%rhos(i))
                        label = "rho "//trim(adjustl(gfmt(opts%rhos(i))))
                    end if
                    call put(u, "set title '"//label//", H = "//itoa(opts%harmonics(j))//"'", &
                             stat, msg)
                    call put(u, "plot f using 2:((strcol(1) eq '"//trim(methods(m))// &
                             "' && $4 == "//itoa(opts%harmonics(j))//" && "//sel// &
                             ") ? $3 : 1/0):(colour(strcol(8), strcol(9))) "// &
                             "every ::1 with points pt 5 ps 1.2 lc rgb variable notitle"// &
                             legend, stat, msg)
                end do
            end do
            call put(u, "unset multiplot", stat, msg)
        end do
        call close_and_rename(dir, "robustness.gp", u, stat, msg, error)
    end subroutine write_robustness_plot_script

    !> `pixels` / `total` as a screen fraction with three decimals: 0.125.
    pure function screen_fraction(pixels, total) result(s)
        integer, intent(in) :: pixels, total
        character(len=:), allocatable :: s
        character(len=8) :: buf
        write (buf, '(f5.3)') real(pixels, dp)/real(total, dp)
        s = trim(adjustl(buf))
    end function screen_fraction

    !> A short real for labels: 0.02, 0.2, 1, 5, 1.5e-05.
    pure function gfmt(x) result(s)
        real(dp), intent(in) :: x
        character(len=16) :: s
        integer :: k
        if (abs(x) >= 1.0e-3_dp .and. abs(x) < 1.0e5_dp) then
            write (s, '(f16.6)') x
            s = adjustl(s)
            k = len_trim(s)
            do while (s(k:k) == '0')
                s(k:k) = ' '
                k = k - 1
            end do
            if (s(k:k) == '.') s(k:k) = ' '
        else
            write (s, '(es11.2e3)') x
            s = adjustl(s)
        end if
    end function gfmt
end module stickslip_plot_scripts
