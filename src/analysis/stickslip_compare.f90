!> Differences between two solutions of the same model on a common time grid: the max and
!> RMS error of every quantity (x and v of every DOF, r of every contact), relative to that
!> quantity's amplitude in the solution compared against. Also evaluates a weighted-residual
!> solution (a truncated Fourier series) on any uniform grid, exactly.
module stickslip_compare
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp, two_pi
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_solution, only: hbm_solution_t
    implicit none
    private
    public :: comparison_t, compare_samples, evaluate_series, quantity_names

    !> Errors of one solution against another, per quantity in the order x1..xN, v1..vN,
    !> r1..r_nc, relative to the amplitude max_t |q| of the solution compared against.
    type :: comparison_t
        !> Names of the two solutions ('hbm', 'euler', 'reference').
        character(len=:), allocatable :: method, against
        !> Points of the common grid per period.
        integer :: grid = 0
        !> Degrees of freedom and contacts.
        integer :: n = 0, nc = 0
        !> max_k |q(t_k) - q_against(t_k)| / amplitude, per quantity.
        real(dp), allocatable :: max_error(:)
        !> sqrt(mean_k (q(t_k) - q_against(t_k))^2) / amplitude, per quantity.
        real(dp), allocatable :: rms_error(:)
        !> Amplitude max_k |q_against(t_k)| of each quantity [m, m/s, N].
        real(dp), allocatable :: amplitude(:)
    contains
        procedure :: worst
    end type comparison_t

contains

    !> Compare samples (x, v, r) with (xa, va, ra) taken at the same instants: relative max
    !> and RMS errors per quantity. A quantity whose amplitude is below 1e-8 of the largest
    !> of its kind (a DOF at rest, up to roundoff) is measured against that largest
    !> amplitude. Error (stat input) when the shapes differ or the grid is empty.
    subroutine compare_samples(method, x, v, r, against, xa, va, ra, cmp, error)
        !> Name of the solution compared.
        character(len=*), intent(in) :: method
        !> Its samples: x, v (grid x N) [m, m/s], r (grid x n_c) [N].
        real(dp), intent(in) :: x(:, :), v(:, :), r(:, :)
        !> Name of the solution compared against.
        character(len=*), intent(in) :: against
        !> Its samples at the same instants.
        real(dp), intent(in) :: xa(:, :), va(:, :), ra(:, :)
        !> The errors.
        type(comparison_t), intent(out) :: cmp
        !> Set on mismatched shapes.
        type(error_type), allocatable, intent(out) :: error
        integer :: ng, n, nc

        ng = size(x, 1)
        n = size(x, 2)
        nc = size(r, 2)
        if (ng < 1 .or. any(shape(v) /= shape(x)) .or. any(shape(xa) /= shape(x)) .or. &
            any(shape(va) /= shape(x)) .or. any(shape(ra) /= shape(r)) .or. &
            (nc > 0 .and. size(r, 1) /= ng)) then
            call fatal_error(error, "compare_samples: the two solutions are not sampled on "// &
                             "the same grid", stickslip_stat%input)
            return
        end if
        cmp%method = method
        cmp%against = against
        cmp%grid = ng
        cmp%n = n
        cmp%nc = nc
        allocate (cmp%max_error(2*n + nc), cmp%rms_error(2*n + nc), cmp%amplitude(2*n + nc))
        call block(x, xa, 0)
        call block(v, va, n)
        if (nc > 0) call block(r, ra, 2*n)

    contains

        subroutine block(q, qa, offset)
            real(dp), intent(in) :: q(:, :), qa(:, :)
            integer, intent(in) :: offset
            real(dp) :: floor, amp
            integer :: i
            floor = maxval(abs(qa))*1.0e-8_dp
            if (.not. (floor > 0.0_dp)) floor = tiny(1.0_dp)
            do i = 1, size(q, 2)
                amp = maxval(abs(qa(:, i)))
                cmp%amplitude(offset + i) = amp
                if (amp <= floor) amp = maxval(abs(qa))
                if (.not. (amp > 0.0_dp)) amp = 1.0_dp
                cmp%max_error(offset + i) = maxval(abs(q(:, i) - qa(:, i)))/amp
                cmp%rms_error(offset + i) = sqrt(sum((q(:, i) - qa(:, i))**2)/real(ng, dp))/amp
            end do
        end subroutine block
    end subroutine compare_samples

    !> The largest relative error over one kind of quantity: kind 'x', 'v' or 'r'; rms
    !> selects the RMS errors instead of the max errors. 0 for a kind with no quantity.
    pure real(dp) function worst(self, kind, rms) result(e)
        !> A comparison.
        class(comparison_t), intent(in) :: self
        !> 'x', 'v' or 'r'.
        character(len=1), intent(in) :: kind
        !> Take the RMS errors.
        logical, intent(in), optional :: rms
        integer :: lo, hi
        logical :: use_rms
        use_rms = .false.
        if (present(rms)) use_rms = rms
        select case (kind)
        case ('x')
            lo = 1
            hi = self%n
        case ('v')
            lo = self%n + 1
            hi = 2*self%n
        case default
            lo = 2*self%n + 1
            hi = 2*self%n + self%nc
        end select
        e = 0.0_dp
        if (hi < lo .or. .not. allocated(self%max_error)) return
        if (use_rms) then
            e = maxval(self%rms_error(lo:hi))
        else
            e = maxval(self%max_error(lo:hi))
        end if
    end function worst

    !> Names of the compared quantities, in the order of comparison_t: x1..xN, v1..vN, r1..
    pure function quantity_names(n, nc) result(names)
        !> Degrees of freedom and contacts.
        integer, intent(in) :: n, nc
        character(len=12) :: names(2*n + nc)
        integer :: i
        do i = 1, n
            names(i) = "x"//itoa(i)
            names(n + i) = "v"//itoa(i)
        end do
        do i = 1, nc
            names(2*n + i) = "r"//itoa(i)
        end do
    end function quantity_names

    !> The weighted-residual solution evaluated at t_k = k T / ng, k = 0..ng-1, from its
    !> Fourier coefficients (exact for the truncated series, any ng): x, v (ng x N) [m, m/s]
    !> and r (ng x n_c) [N]. Error (stat input) when the solution holds no coefficients.
    subroutine evaluate_series(sol, ng, x, v, r, error)
        !> A weighted-residual solution.
        type(hbm_solution_t), intent(in) :: sol
        !> Points per period (>= 1).
        integer, intent(in) :: ng
        !> The samples.
        real(dp), allocatable, intent(out) :: x(:, :), v(:, :), r(:, :)
        !> Set when there is nothing to evaluate.
        type(error_type), allocatable, intent(out) :: error
        real(dp), allocatable :: table(:, :)
        integer :: k, i, h
        if (.not. (allocated(sol%xcoef) .and. allocated(sol%vcoef) .and. &
                   allocated(sol%rcoef) .and. allocated(sol%harmonic)) .or. ng < 1) then
            call fatal_error(error, "evaluate_series: the solution holds no coefficients", &
                             stickslip_stat%input)
            return
        end if
        allocate (table(ng, sol%nb))
        do i = 1, sol%nb
            h = sol%harmonic(i)
            if (h == 0) then
                table(:, i) = 1.0_dp
            else if (i > 1 .and. sol%harmonic(max(i - 1, 1)) == h) then
                table(:, i) = [(sin(angle(h, k, ng)), k=0, ng - 1)]
            else
                table(:, i) = [(cos(angle(h, k, ng)), k=0, ng - 1)]
            end if
        end do
        x = matmul(table, sol%xcoef)
        v = matmul(table, sol%vcoef)
        r = matmul(table, sol%rcoef)
    end subroutine evaluate_series

    !> The angle h omega t_k = 2 pi (h k mod ng) / ng, reduced exactly before the sine.
    pure real(dp) function angle(h, k, ng)
        integer, intent(in) :: h, k, ng
        angle = two_pi*real(modulo(int(h, int64)*int(k, int64), int(ng, int64)), dp)/real(ng, dp)
    end function angle
end module stickslip_compare
