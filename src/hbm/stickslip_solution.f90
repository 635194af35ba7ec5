!> What a weighted-residual solve is asked (options) and what it returns (solution):
!> coefficients, the convergence report, per-contact diagnostics, the energy balance and,
!> on request, time samples. Plain data; filled by stickslip_hbm.
module stickslip_solution
    use stickslip_kinds, only: dp
    use stickslip_diagnostics, only: diagnostics_t
    use stickslip_contact_set, only: contact_set_t
    implicit none
    private
    public :: hbm_options_t, hbm_solution_t

    !> Options of the weighted-residual (harmonic balance) solve.
    type :: hbm_options_t
        !> Highest harmonic H of the basis.
        integer :: harmonics = 30
        !> Use only the odd harmonics 1, 3, .., <= H (no constant term).
        logical :: odd_only = .false.
        !> Weight rho of the friction equality Psi [m/(N s)]: > 0 to fix it, 0 (the default)
        !> for the automatic choice from the model, the contact mobility at the forcing
        !> frequency (stickslip_rho, automatic_rho). The value used is hbm_solution_t%rho.
        real(dp) :: rho = 0.0_dp
        !> Quadrature samples per period nt (>= 2 H + 1).
        integer :: samples = 1024
        !> Convergence: ||F||_2 <= tol * fscale (see hbm_solution_t%fscale).
        real(dp) :: tol = 1.0e-9_dp
        !> hybrj's relative step tolerance.
        real(dp) :: xtol = 1.0e-13_dp
        !> Maximum residual evaluations per hybrj call (0: 200 * (n + 1)).
        integer :: maxfev = 0
        !> Start strategy: 'auto' (cold start at H, then the harmonic ladder if that fails),
        !> 'direct' (only the cold start) or 'ladder' (always climb from few harmonics).
        character(len=8) :: start = 'auto'
        !> Nonlinear solver: 'auto' (hybrj below newton_min_unknowns unknowns, 'newton'
        !> from there on), 'hybrj' (MINPACK's Powell hybrid method only, the reference) or
        !> 'newton' (semismooth Newton with LU from warm starts: the halving ladder H/2^k,
        !> a start r_start; cold stages and every Newton failure go to hybrj).
        character(len=8) :: solver = 'auto'
        !> Stop hybrj as soon as a residual meets the tolerance (reported as hybrj info -1);
        !> .false. lets hybrj run to its own step-size test (info 1, or 4/5 at a kink).
        !> The Newton path (solver) always stops at the tolerance.
        logical :: stop_at_tol = .true.
        !> Also return time samples of x, v, r and the stick indicator.
        logical :: want_samples = .true.
    end type hbm_options_t

    !> Result of a weighted-residual solve. Coefficient vectors follow stickslip_basis:
    !> [c0, a_h1, b_h1, ...], u(t) = c0 + sum a_h cos(h omega t) + b_h sin(h omega t).
    type :: hbm_solution_t
        !> The residual met the tolerance.
        logical :: converged = .false.
        !> hybrj's info of the last call: -1 stopped by stickslip because the residual met
        !> the tolerance (the usual outcome, also when Newton met it), 1 xtol met, 2 maxfev reached, 4 or 5 no
        !> progress (doc/convergence.md).
        integer :: info = 0
        !> Residual evaluations, all stages and restarts included.
        integer :: nfev = 0
        !> Jacobian evaluations, all stages and restarts included.
        integer :: njev = 0
        !> Number of hybrj calls made (ladder stages and restarts).
        integer :: hybrj_calls = 0
        !> Number of semismooth Newton calls made (hbm_options_t%solver; 0 on the hybrj
        !> path).
        integer :: newton_calls = 0
        !> Newton calls that ended without meeting the target (singular Jacobian, stall)
        !> and were continued by hybrj.
        integer :: newton_fallbacks = 0
        !> The fallback that found the answer when the start and ladder did not
        !> (stickslip_hbm_fallback): 'newton', 'load' (the homotopy in the load), 'rho'
        !> (another weight, then continued to rho), 'rho_kept' (the root at another
        !> weight, kept: sol%rho is that weight) or 'arclength' (the load homotopy past
        !> turning points); 'none' when none was needed.
        character(len=9) :: rescue = 'none'
        !> Final residual norm ||F||_2 of the projected friction equations [m/s].
        real(dp) :: fnorm = huge(1.0_dp)
        !> Residual scale: min(||V0||_2, rho Rs), V0 the contact velocities of the structure
        !> without friction forces, Rs the force scale min(max_j mu_j N_j, the force that
        !> stops V0) (stickslip_hbm, convergence_scale) [m/s].
        real(dp) :: fscale = 0.0_dp
        !> Weight rho of Psi used: hbm_options_t%rho, or the automatic choice when that
        !> is 0 [m/(N s)].
        real(dp) :: rho = 0.0_dp
        !> Wall-clock seconds spent in the solve (condensation, hybrj, recovery).
        real(dp) :: seconds = 0.0_dp
        !> Wall-clock seconds of the exact sparse condensation within `seconds` (the sparse
        !> LU factorizations and solves, solve_periodic_sparse; 0 for the dense path) [s].
        real(dp) :: condensation_seconds = 0.0_dp
        !> Empty when converged, otherwise what went wrong and what to try.
        character(len=:), allocatable :: diagnosis
        !> Highest harmonic H.
        integer :: harmonics = 0
        !> Odd harmonics only.
        logical :: odd_only = .false.
        !> Samples per period nt.
        integer :: samples = 0
        !> Number of basis functions per unknown function.
        integer :: nb = 0
        !> Fundamental angular frequency [rad/s].
        real(dp) :: omega = 0.0_dp
        !> Harmonic of each coefficient index (0 for the constant), length nb.
        integer, allocatable :: harmonic(:)
        !> The DOFs of the columns of xcoef, vcoef, x and v when they do not hold all N
        !> (the exact sparse condensation, solve_periodic_sparse: the DOFs asked for, then
        !> the contact and forced DOFs); unallocated: columns 1..N.
        integer, allocatable :: dofs(:)
        !> Displacement coefficients, nb x N (nb x size(dofs) when dofs is set) [m].
        real(dp), allocatable :: xcoef(:, :)
        !> Velocity coefficients, nb x N [m/s].
        real(dp), allocatable :: vcoef(:, :)
        !> Friction force coefficients, nb x n_c [N] (the unknowns of the nonlinear solve).
        !> With contact laws, the coefficients of every force channel, nb x n_ch (contact
        !> after contact: first tangential force, second tangential force of a planar
        !> contact, normal force of a unilateral one; `contacts` tells which).
        real(dp), allocatable :: rcoef(:, :)
        !> The contacts and their force channels (stickslip_contact_set; plain: one channel
        !> per contact).
        type(contact_set_t) :: contacts
        !> Fraction of the samples in the stick region, per contact.
        real(dp), allocatable :: stick_fraction(:)
        !> Fractions of the samples where the contact is open (unilateral contacts; 0
        !> otherwise) and where it slips, per contact: open + stick + slip = 1.
        real(dp), allocatable :: open_fraction(:), slip_fraction(:)
        !> Number of stick phases per period, per contact.
        integer, allocatable :: stick_phases(:)
        !> True for a contact that sticks over the whole period while the basis holds the
        !> constant: its mean force is undetermined and the admissible value closest to zero
        !> was chosen (doc/convergence.md, "Undetermined offset").
        logical, allocatable :: offset_undetermined(:)
        !> Work of the forcing over one period [J].
        real(dp) :: work_forcing = 0.0_dp
        !> Gross work of the forcing over one period, integral |f . v| dt [J]: the scale of
        !> the energy balance when the net work is ~0 (a contact stuck all period).
        real(dp) :: work_gross = 0.0_dp
        !> The solve's velocity resolution 100 max(tol, 1e-12) fscale [m/s]: the convergence
        !> test holds the residual, a stuck contact's velocity coefficients, to tol fscale
        !> in norm, so velocities below this (a margin for the sum over the coefficients
        !> and the dynamics' condition) are its noise (0 when unknown: no floor).
        real(dp) :: velocity_resolution = 0.0_dp
        !> The work the forcing does over one period on a velocity error of
        !> velocity_resolution at every forced DOF [J]: the floor of the energy checks' scale
        !> (works below it are roundoff of the solve, e.g. a structure at rest).
        real(dp) :: work_resolution = 0.0_dp
        !> The structure does not move within the solve's resolution: every DOF's velocity
        !> bound sum_h |V_h| <= velocity_resolution. The contacts hold the forcing (stuck,
        !> or closed, all period); every work is 0 to roundoff, so the energy balance and
        !> Coulomb dissipation checks are not graded (doc/convergence.md, "At rest").
        logical :: at_rest = .false.
        !> Energy dissipated by friction over one period, -integral r . W^T v dt [J].
        real(dp) :: diss_friction = 0.0_dp
        !> Coulomb dissipation over one period, integral mu N |W^T v| dt [J]; equals
        !> diss_friction for an exact solution of Coulomb's law.
        real(dp) :: diss_coulomb = 0.0_dp
        !> Relative mismatch of the friction dissipation and Coulomb's, |D_C - diss_friction|
        !> / max(D_C, |diss_friction| + |diss_damping|, 1e-6 work_gross), D_C = integral of
        !> mu N |v| where the contacts slip and |r v| where they stick (dimensionless; ~1%
        !> for a sound solution, O(1) when the force and velocity do not obey Coulomb's law).
        real(dp) :: coulomb_check = 0.0_dp
        !> Largest max_t |r_j(t)| / (mu_j N_j) over the contacts with mu_j N_j > 0
        !> (dimensionless; slightly above 1 from the Gibbs overshoot of the truncated force).
        real(dp) :: max_force_ratio = 0.0_dp
        !> Energy dissipated by viscous damping over one period, integral v^T C v dt [J].
        real(dp) :: diss_damping = 0.0_dp
        !> Largest violation of the normal contact law over the unilateral contacts
        !> (dimensionless): a pulling normal force relative to the largest normal force, a
        !> penetration (of the gap + lambda / k_n) relative to the normal displacement
        !> amplitude; ~the Gibbs ripple of the truncated series for a sound solution.
        real(dp) :: signorini_check = 0.0_dp
        !> Largest normal velocity of a rigid unilateral contact at the instant it closes,
        !> relative to its normal velocity amplitude (dimensionless; an impact: the
        !> truncated series cannot carry its velocity jump).
        real(dp) :: impact_check = 0.0_dp
        !> Sample instants t_k = k T / nt [s] (when samples were asked for).
        real(dp), allocatable :: t(:)
        !> Displacements at the samples, nt x N [m].
        real(dp), allocatable :: x(:, :)
        !> Velocities at the samples, nt x N [m/s].
        real(dp), allocatable :: v(:, :)
        !> Friction forces at the samples, nt x n_c [N] (with contact laws: every force
        !> channel, nt x n_ch, in the order of rcoef).
        real(dp), allocatable :: r(:, :)
        !> Stick indicator (1 stick, 0 slip or open) at the samples, nt x n_c.
        real(dp), allocatable :: stick(:, :)
        !> Contact state at the samples, nt x n_c: state_open (0), state_stick (1),
        !> state_slip (2) of stickslip_contact_law.
        integer, allocatable :: state(:, :)
        !> Normal force at the samples, nt x n_c [N]: the constant normal load of a plain
        !> contact, the normal force lambda(t) of a unilateral one.
        real(dp), allocatable :: normal(:, :)
        !> Gap at the samples, nt x n_c [m]: gap + n^T x of a unilateral contact (negative:
        !> the compression of an elastic contact), 0 for the others.
        real(dp), allocatable :: gap(:, :)
        !> What the checks found: notes, warnings, distrust (stickslip_diagnostics).
        type(diagnostics_t) :: diagnostics
    end type hbm_solution_t
end module stickslip_solution
