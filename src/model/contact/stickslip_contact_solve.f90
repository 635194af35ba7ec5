!> The friction forces of one implicit step with Coulomb contacts: Coulomb's law between the
!> forces r and the slip velocities u = u_free + D r, D a Delassus matrix. Shared by the
!> implicit Euler stepper (stickslip_euler) and the exact flow's stuck-force solve
!> (stickslip_flow). Pure numerics: no model, no files.
module stickslip_contact_solve
    use stickslip_kinds, only: dp
    implicit none
    private
    public :: contact_forces

contains

    !> Friction forces r of one step: the minimizer of 1/2 r^T D r + u_free^T r over the box
    !> |r_j| <= limit_j, i.e. Coulomb's law between r and u = u_free + D r. Closed form for
    !> one contact; projected Gauss-Seidel from the given r for several (converges for D
    !> symmetric positive definite), stopped when no force changes by more than
    !> tol * max(limit) in a sweep or after max_sweeps sweeps.
    pure subroutine contact_forces(d, ufree, limit, r, tol, max_sweeps, sweeps)
        !> Delassus matrix h W^T S^{-1} W, n_c x n_c [m/(N s)].
        real(dp), intent(in) :: d(:, :)
        !> Slip velocities without friction [m/s].
        real(dp), intent(in) :: ufree(:)
        !> Friction limits mu N [N].
        real(dp), intent(in) :: limit(:)
        !> Friction forces: start on entry, solution on exit [N].
        real(dp), intent(inout) :: r(:)
        !> Relative tolerance of the sweeps.
        real(dp), intent(in) :: tol
        !> Sweeps at most.
        integer, intent(in) :: max_sweeps
        !> Sweeps done (0 for one contact).
        integer, intent(out) :: sweeps
        integer :: j, nc
        real(dp) :: change, rnew, scale
        nc = size(r)
        sweeps = 0
        if (nc == 1) then
            r(1) = max(-limit(1), min(limit(1), -ufree(1)/d(1, 1)))
            return
        end if
        scale = max(maxval(limit), tiny(1.0_dp))
        do sweeps = 1, max_sweeps
            change = 0.0_dp
            do j = 1, nc
                rnew = r(j) - (ufree(j) + dot_product(d(j, :), r))/d(j, j)
                rnew = max(-limit(j), min(limit(j), rnew))
                change = max(change, abs(rnew - r(j)))
                r(j) = rnew
            end do
            if (change <= tol*scale) exit
        end do
        sweeps = min(sweeps, max_sweeps)
    end subroutine contact_forces
end module stickslip_contact_solve
