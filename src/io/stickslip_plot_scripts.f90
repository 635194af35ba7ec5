!> The gnuplot scripts of the pictures: frc.gp (frc.png, a forced-response curve) and
!> robustness.gp (robustness_cold.png, robustness_warm.png, the robustness maps). Each
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
    implicit none
    private
    public :: write_frc_plot_script, write_robustness_plot_script

contains

    !> Write `dir`/frc.gp, the gnuplot script that draws `dir`/frc.png from frc.csv: the
    !> amplitude of every DOF of frc.csv (all N, or the `dofs` selected, the columns amp_<d>
    !> in their order) against the parameter (log scale), unstable points marked with red
    !> crosses. `parameter` labels the axis. Error: stat io.
    subroutine write_frc_plot_script(dir, parameter, ndof, error, dofs, labels)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> Name of the swept parameter.
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
        integer :: u, stat, k, nsel
        character(len=512) :: msg
        integer, allocatable :: sel(:)
        if (present(dofs)) then
            sel = dofs
        else
            sel = [(k, k=1, ndof)]
        end if
        if (present(labels)) sel = labels
        nsel = size(sel)
        stat = 0
        msg = ''
        call open_temporary(dir, "frc.gp", u, error)
        if (allocated(error)) return
        call put(u, "# Forced-response curve from frc.csv: gnuplot frc.gp (in this directory)", &
                 stat, msg)
        call put(u, "set terminal pngcairo size 1100,700 enhanced font ',11'", stat, msg)
        call put(u, "if (!exists('suffix')) suffix = ''", stat, msg)
        call put(u, "set output 'frc.png'.suffix", stat, msg)
        call put(u, "set datafile separator ','", stat, msg)
        call put(u, "set key autotitle columnhead top right", stat, msg)
        call put(u, "set grid lc rgb '#dddddd'", stat, msg)
        call put(u, "set logscale y", stat, msg)
        call put(u, "f = 'frc.csv'", stat, msg)
        call put(u, "# the y range: four decades below the largest amplitude (a contact stuck "// &
                 "all period drives its DOF to roundoff)", stat, msg)
        call put(u, "ymax = 0", stat, msg)
        call put(u, "do for [k=2:"//itoa(1 + nsel)//"] { stats f using k nooutput; "// &
                 "if (STATS_max > ymax) { ymax = STATS_max } }", stat, msg)
        call put(u, "if (ymax > 0) set yrange [ymax*1e-4:ymax*2]", stat, msg)
        call put(u, "set xlabel '"//parameter//"'", stat, msg)
        call put(u, "set ylabel 'amplitude max |x_k(t)|'", stat, msg)
        call put(u, "set title 'Forced-response curve (red crosses: unstable, Floquet)'", &
                 stat, msg)
        call put(u, "# the column 'stable' (1, 0 unstable, -1 unknown)", stat, msg)
        call put(u, "unstable(k) = (column('stable') == 0 ? column(k) : 1/0)", stat, msg)
        do k = 1, nsel
            if (k == 1) then
                call put(u, "plot f using 1:"//itoa(1 + k)//" with lines lw 1.5 title 'amp_"// &
                         itoa(sel(k))//"' noenhanced, \", stat, msg)
            else
                call put(u, "     f using 1:"//itoa(1 + k)//" with lines lw 1.5 title 'amp_"// &
                         itoa(sel(k))//"' noenhanced, \", stat, msg)
            end if
            if (k < nsel) then
                call put(u, "     f using 1:(unstable("//itoa(1 + k)//")) with points pt 2 "// &
                         "ps 0.8 lc rgb 'red' notitle, \", stat, msg)
            else
                call put(u, "     f using 1:(unstable("//itoa(1 + k)//")) with points pt 2 "// &
                         "ps 0.8 lc rgb 'red' title 'unstable'", stat, msg)
            end if
        end do
        call close_and_rename(dir, "frc.gp", u, stat, msg, error)
    end subroutine write_frc_plot_script

    !> Write `dir`/robustness.gp, the gnuplot script that draws robustness_cold.png and
    !> robustness_warm.png from robustness.csv: one panel per (rho, H), omega across and mu
    !> up (log), each run a square: green success, orange converged to a wrong solution, red
    !> not converged. Error: stat io.
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
        character(len=:), allocatable :: sel, label
        stat = 0
        msg = ''
        call open_temporary(dir, "robustness.gp", u, error)
        if (allocated(error)) return
        call put(u, "# Robustness maps from robustness.csv: gnuplot robustness.gp (in this "// &
                 "directory)", stat, msg)
        call put(u, "# green: converged to the right solution; orange: converged, error > "// &
                 "wrong_tol; red: not converged", stat, msg)
        call put(u, "if (!exists('suffix')) suffix = ''", stat, msg)
        call put(u, "set datafile separator ','", stat, msg)
        call put(u, "set logscale y", stat, msg)
        call put(u, "set key off", stat, msg)
        call put(u, "set tics font ',8'", stat, msg)
        call put(u, "set offsets graph 0.04, graph 0.04, graph 0.08, graph 0.08", stat, msg)
        call put(u, "colour(c, s) = (s eq 'T' ? 0x2ca02c : (c eq 'T' ? 0xff7f0e : 0xd62728))", &
                 stat, msg)
        call put(u, "f = 'robustness.csv'", stat, msg)
        do m = 1, 2
            if (m == 2 .and. .not. opts%warm) exit
            call put(u, "set terminal pngcairo size "//itoa(260*size(opts%harmonics) + 80)// &
                     ","//itoa(200*size(opts%rhos) + 60)//" font ',9'", stat, msg)
            call put(u, "set output 'robustness_"//trim(tags(m))//".png'.suffix", stat, msg)
            call put(u, "set multiplot layout "//itoa(size(opts%rhos))//","// &
                     itoa(size(opts%harmonics))//" title 'weighted residual, "// &
                     trim(tags(m))//" starts: x omega [rad/s], y mu'", stat, msg)
            do i = 1, size(opts%rhos)
                do j = 1, size(opts%harmonics)
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
                             "every ::1 with points pt 5 ps 1.2 lc rgb variable", stat, msg)
                end do
            end do
            call put(u, "unset multiplot", stat, msg)
        end do
        call close_and_rename(dir, "robustness.gp", u, stat, msg, error)
    end subroutine write_robustness_plot_script

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
