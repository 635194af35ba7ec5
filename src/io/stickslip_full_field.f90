!> The full-field result file full_field.mtx: the harmonic coefficients of every DOF of the
!> model, for an FE post-processor (&output full_field).
!>
!> Format: Matrix Market `array real general`, N rows (DOF i of the model: of the full model
!> from files when it was reduced) by nb columns (the basis functions of the weighted-residual
!> solution, in the order of coefficients.csv), column-major, 17 significant digits; comment
!> lines name omega and every column ("% column k: harmonic h cos|sin|c0"): the displacement
!> of DOF i is x_i(t) = sum_k F(i, k) phi_k(t), phi = 1, cos(h omega t), sin(h omega t) [m].
module stickslip_full_field
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_solution, only: hbm_solution_t
    use stickslip_files, only: open_temporary, close_and_rename
    implicit none
    private
    public :: write_full_field

contains

    !> Write `dir`/full_field.mtx from the full-field coefficients `coef` (N x nb, see the
    !> module header) of the solution `sol` (its basis names the columns), under a temporary
    !> name then renamed. Errors: stat input when coef has not sol%nb columns; stat io.
    subroutine write_full_field(dir, coef, sol, error)
        !> Output directory (must exist).
        character(len=*), intent(in) :: dir
        !> Coefficients, N x nb [m].
        real(dp), intent(in) :: coef(:, :)
        !> The solution (basis and omega).
        type(hbm_solution_t), intent(in) :: sol
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        integer :: u, stat, i, k
        character(len=512) :: msg
        character(len=3) :: kind
        if (size(coef, 2) /= sol%nb) then
            call fatal_error(error, "write_full_field: coef has "//itoa(size(coef, 2))// &
                             " columns, the solution's basis "//itoa(sol%nb), &
                             stickslip_stat%input)
            return
        end if
        call open_temporary(dir, "full_field.mtx", u, error)
        if (allocated(error)) return
        write (u, '(a)', iostat=stat, iomsg=msg) "%%MatrixMarket matrix array real general"
        if (stat == 0) write (u, '(a)', iostat=stat, iomsg=msg) "% stickslip full-field "// &
            "harmonic coefficients [m]: row i = DOF i, x_i(t) = sum_k F(i,k) phi_k(t)"
        if (stat == 0) write (u, '(a,es25.17e3)', iostat=stat, iomsg=msg) "% omega = ", &
            sol%omega
        do k = 1, sol%nb
            if (stat /= 0) exit
            kind = "cos"
            if (sol%harmonic(k) == 0) then
                kind = "c0"
            else if (k > 1) then
                if (sol%harmonic(k - 1) == sol%harmonic(k)) kind = "sin"
            end if
            write (u, '(a,i0,a,i0,1x,a)', iostat=stat, iomsg=msg) "% column ", k, &
                ": harmonic ", sol%harmonic(k), trim(kind)
        end do
        if (stat == 0) write (u, '(i0,1x,i0)', iostat=stat, iomsg=msg) size(coef, 1), &
            size(coef, 2)
        do k = 1, size(coef, 2)
            if (stat /= 0) exit
            do i = 1, size(coef, 1)
                write (u, '(es25.17e3)', iostat=stat, iomsg=msg) coef(i, k)
                if (stat /= 0) exit
            end do
        end do
        call close_and_rename(dir, "full_field.mtx", u, stat, msg, error)
    end subroutine write_full_field
end module stickslip_full_field
