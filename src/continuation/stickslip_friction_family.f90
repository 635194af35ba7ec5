!> The projected friction equations of a model as a family in a sweep's parameter (omega, a
!> forcing amplitude, mu or the normal load): the parametric_system_t whose curve the
!> pseudo-arclength predictor and corrector of stickslip_continuation follow, with the
!> recovery of a failed point by the harmonic ladder.
!>
!> The friction-force coefficients R are the unknowns, as in a single solve; the parameter
!> derivative dF/dlambda is analytic: P diag(s) Q dV/dlambda for omega (dV/domega from the
!> condensed dynamics) and a forcing amplitude (V0 is linear in it), P dPsi/dg Q dg/dlambda
!> for mu and the normal load (g = mu N, the friction limit).
!>
!> In omega the family keeps the dynamics at the last few omega values met (the corrector,
!> the tangent and the residual scale come back to them) and counts its factorizations.
!>
!> A contact stuck over the whole period holds any mean tangential force within its limits
!> (the equations leave it free: a family of equally admissible answers at one parameter
!> value). The continuation keeps the mean the branch arrived with: the rows of the
!> tangential channels' mean forces get the term w rho (R_0 - R_0 of the last accepted
!> point), w = pin_share times the solver tolerance: it pins a free mean (the rest of that
!> row is roundoff) and moves a determined one (a contact with slip phases) by less than
!> the tolerance, so that the reported point's solve starts at its answer. The points the
!> sweep reports are settled by the single solve's rule (stickslip_hbm_finish).
module stickslip_friction_family
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_model, only: model_t
    use stickslip_solution, only: hbm_options_t, hbm_solution_t
    use stickslip_hbm, only: solve_periodic
    use stickslip_hb_residual, only: hb_problem_t, new_hb_problem, new_condensed_problem
    use stickslip_dynamics, only: dynamics_t, new_dynamics
    use stickslip_basis, only: basis_t, new_basis
    use stickslip_sparse_model, only: sparse_model_t
    use stickslip_sparse_dynamics, only: new_sparse_dynamics
    use stickslip_umfpack, only: sparse_zlu_t
    use stickslip_progress, only: progress_t
    use stickslip_hbm_sparse, only: solve_periodic_sparse, kept_dofs
    use stickslip_cyclic, only: cyclic_t
    use stickslip_cyclic_dynamics, only: new_cyclic_dynamics, cyclic_projections_t
    use stickslip_hbm_cyclic, only: solve_periodic_cyclic
    use stickslip_friction, only: psi_limit_derivative
    use stickslip_contact_set, only: contact_set_t, new_contact_set
    use stickslip_contact_element, only: state_stick
    use stickslip_model, only: preload_force
    use stickslip_continuation, only: parametric_system_t
    use stickslip_sweep_options, only: set_sweep_parameter
    implicit none
    private
    public :: friction_family_t, new_friction_family

    !> Dynamics kept by a friction family in omega (distinct omega values).
    integer, parameter, public :: dynamics_cache_size = 4

    !> Weight of the term that pins the tangential mean forces to the last accepted point's,
    !> as a share of the solver tolerance (&hbm tol).
    real(dp), parameter :: pin_share = 0.1_dp

    !> The projected friction equations as a family in the parameter.
    type, extends(parametric_system_t) :: friction_family_t
        !> The model at the family's current parameter.
        type(model_t) :: model
        !> Weighted-residual options of the points (rho fixed along the family).
        type(hbm_options_t) :: opts
        !> 'omega', 'force_amplitude', 'mu', 'normal_load' or 'preload'.
        character(len=16) :: parameter = ''
        !> The condensed friction equations (basis, dynamics, limits, work arrays).
        type(hb_problem_t) :: prob
        !> Dynamics at unit amplitude of forcing term 1 ('force_amplitude').
        type(dynamics_t) :: unit
        !> The parameter the problem is set at, when have_current.
        real(dp) :: current = 0.0_dp
        logical :: have_current = .false.
        !> How many times the family factorized the dynamic stiffnesses Z_h of its basis
        !> (new_dynamics calls, the unit dynamics of 'force_amplitude' included): once per
        !> distinct omega met ('omega'), once at the start otherwise.
        integer :: factorizations = 0
        !> The dynamics at the last few omega values met ('omega'): the corrector, the
        !> tangent and the residual scale come back to an omega already seen; a value is
        !> looked up exactly (==), the oldest entry is replaced.
        type(dynamics_t) :: cached(dynamics_cache_size)
        real(dp) :: cached_omega(dynamics_cache_size) = 0.0_dp
        !> Per cached entry, the clock when last used (0: empty); the clock counts look-ups.
        integer :: cached_age(dynamics_cache_size) = 0
        integer :: clock = 0
        !> s(K), s(M) of the model (see dynamics_t%smin_k; -1: not yet known).
        real(dp) :: singular_values(2) = -1.0_dp
        !> The forcing amplitudes of the case [N], and work arrays of the Jacobian.
        real(dp), allocatable :: amplitude0(:), rs(:, :), vs(:, :), ss(:, :), dv(:, :), &
                                 dvs(:)
        integer, allocatable :: states(:, :)
        complex(dp), allocatable :: cw(:)
        !> The model's sparse matrices (a sweep of the exact sparse condensation; its
        !> %model follows `model`), and the DOFs whose rows the dynamics keep.
        type(sparse_model_t), allocatable :: sparse
        !> The analysis (ordering) of the sparse model's dynamic stiffness, kept from one
        !> parameter to the next (release it with the family: analysis%release()).
        type(sparse_zlu_t) :: analysis
        !> Progress of the sparse condensations (per harmonic; unit off by default).
        type(progress_t) :: progress
        integer, allocatable :: kept(:)
        !> One sector of a tuned bladed disk (its travelling wave: stickslip_cyclic_dynamics
        !> condenses it), when allocated.
        type(cyclic_t), allocatable :: cyclic
        !> On a sector with prepared modes: the projections its builds keep from one
        !> parameter value to the next (the continuation's dynamics keep its channels only).
        type(cyclic_projections_t) :: projections
        !> Rows of the tangential channels' mean forces, and the point they are pinned to
        !> (empty until the continuation anchors the family).
        integer, allocatable :: mean_rows(:)
        real(dp), allocatable :: anchor_y(:)
    contains
        procedure :: anchor => family_anchor
        procedure :: residual => family_residual
        procedure :: jacobian => family_jacobian
        procedure :: recover => family_recover
        procedure :: residual_scale => family_scale
        procedure :: set => family_set
        procedure :: point_dynamics => family_point_dynamics
        procedure :: destroy => family_destroy
    end type friction_family_t

contains

    !> Build the friction equations of `model` as a family in `parameter` ('omega',
    !> 'force_amplitude', 'mu' or 'normal_load'), set at `p`, on the basis of `hbm` with the
    !> weight `rho` > 0 (fixed along the family). Errors: as new_hb_problem and
    !> new_dynamics.
    !> With `sparse` (and `dofs`, see run_sweep), the dynamics are the exact sparse
    !> condensation; `build` = .false. only sets the family's data (no dynamics, no basis).
    subroutine new_friction_family(fam, model, hbm, parameter, p, rho, error, sparse, dofs, &
                                   build, cyclic)
        !> The family.
        type(friction_family_t), intent(out) :: fam
        !> A validated model with friction contacts.
        type(model_t), intent(in) :: model
        !> Basis and tolerance options.
        type(hbm_options_t), intent(in) :: hbm
        !> The parameter.
        character(len=*), intent(in) :: parameter
        !> Its value.
        real(dp), intent(in) :: p
        !> Weight of Psi [m/(N s)].
        real(dp), intent(in) :: rho
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        !> The model's sparse matrices.
        type(sparse_model_t), intent(in), optional :: sparse
        !> With `sparse`: the DOFs to keep (then the contact and forced ones).
        integer, intent(in), optional :: dofs(:)
        !> Build the problem (default .true.).
        logical, intent(in), optional :: build
        !> `model` is one sector of this disk (its travelling wave).
        type(cyclic_t), intent(in), optional :: cyclic
        integer :: nb, nc, stat
        fam%model = model
        fam%opts = hbm
        fam%opts%rho = rho
        fam%parameter = parameter
        fam%amplitude0 = model%force_amplitude
        call set_sweep_parameter(fam%model, parameter, p, fam%amplitude0)
        if (present(cyclic)) fam%cyclic = cyclic
        if (present(sparse)) then
            fam%sparse = sparse
            fam%sparse%model = fam%model
            if (present(dofs)) then
                fam%kept = kept_dofs(sparse, dofs, error)
            else
                fam%kept = kept_dofs(sparse, [integer ::], error)
            end if
            if (allocated(error)) return
        end if
        if (present(build)) then
            if (.not. build) return
        end if
        if (allocated(fam%sparse) .or. allocated(fam%cyclic)) then
            block
                type(basis_t) :: basis
                type(dynamics_t) :: dyn
                type(contact_set_t) :: cs
                call new_basis(basis, hbm%harmonics, hbm%odd_only, hbm%samples, error)
                if (allocated(error)) return
                if (allocated(fam%cyclic)) then
                    call new_cyclic_dynamics(dyn, fam%model, fam%cyclic, basis, error)
                else
                    call new_sparse_dynamics(dyn, fam%sparse, basis, fam%kept, error, &
                                             analysis=fam%analysis, progress=fam%progress)
                end if
                call basis%destroy()
                if (allocated(error)) return
                call new_contact_set(cs, fam%model)
                call new_condensed_problem(fam%prob, dyn, cs, hbm%harmonics, hbm%odd_only, &
                                           hbm%samples, rho, error, fam%model%force_harmonic)
            end block
        else
            call new_hb_problem(fam%prob, fam%model, hbm%harmonics, hbm%odd_only, &
                                hbm%samples, rho, error)
        end if
        fam%factorizations = 1
        if (allocated(error)) return
        nb = fam%prob%basis%nb
        nc = fam%prob%nc
        fam%mean_rows = fam%prob%tangential_mean_rows()
        allocate (fam%states(hbm%samples, fam%prob%contacts%ncontact))
        allocate (fam%rs(hbm%samples, nc), fam%vs(hbm%samples, nc), fam%ss(hbm%samples, nc), &
                  fam%dv(nb, nc), fam%dvs(hbm%samples), fam%cw(hbm%samples/2 + 1))
        if (parameter == 'force_amplitude' .and. .not. any(preload_force(fam%model) /= 0.0_dp)) then
            block
                type(model_t) :: m1
                m1 = fam%model
                m1%force_amplitude = fam%amplitude0/fam%amplitude0(1)
                if (allocated(fam%cyclic)) then
                    call new_cyclic_dynamics(fam%unit, m1, fam%cyclic, fam%prob%basis, error)
                else if (allocated(fam%sparse)) then
                    fam%sparse%model = m1
                    call new_sparse_dynamics(fam%unit, fam%sparse, fam%prob%basis, fam%kept, &
                                             error, analysis=fam%analysis, &
                                             progress=fam%progress)
                    fam%sparse%model = fam%model
                else
                    call new_dynamics(fam%unit, m1, fam%prob%basis, error)
                end if
                fam%factorizations = fam%factorizations + 1
                if (allocated(error)) return
            end block
        end if
        stat = 0
        call fam%set(p, stat)
        if (stat /= 0) call fatal_error(error, "sweep: the structure has no dynamics at "// &
                                        "the start of the range", stickslip_stat%numerical)
    end subroutine new_friction_family

    !> Move the family to parameter p (rebuild or rescale what depends on it).
    subroutine family_set(self, p, stat)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        !> The parameter value.
        real(dp), intent(in) :: p
        !> Set to 1 when the family has no point there (p not finite or out of range,
        !> singular dynamics).
        integer, intent(inout) :: stat
        integer :: k
        if (self%have_current .and. p == self%current) return
        if (.not. ieee_is_finite(p)) then
            stat = 1
            return
        end if
        if (p < 0.0_dp .or. (self%parameter == 'omega' .and. .not. (p > 0.0_dp))) then
            stat = 1
            return
        end if
        call set_sweep_parameter(self%model, self%parameter, p, self%amplitude0)
        select case (self%parameter)
        case ('omega', 'preload')
            ! the condensed dynamics (the preload is in the static load), built once per
            ! value and cached; the kinematics of gap channels and contact stiffnesses follow
            ! the dynamics' omega
            call set_omega_dynamics(self, p, stat)
            if (stat /= 0) return
        case ('force_amplitude')
            if (allocated(self%unit%v0)) then
                call scale_forcing(self, p)
            else
                call set_omega_dynamics(self, p, stat)
                if (stat /= 0) return
            end if
        end select
        select case (self%parameter)
        case ('mu', 'normal_load', 'preload')
            call self%prob%contacts%set_parameter(self%parameter, p, k)
        end select
        self%current = p
        self%have_current = .true.
    end subroutine family_set

    !> The dynamics at forcing amplitude p scaled from those at unit amplitude (the
    !> response to the forcing is linear in it; no preload: the static load is forcing
    !> alone).
    subroutine scale_forcing(self, p)
        !> The family in the forcing amplitude.
        class(friction_family_t), intent(inout) :: self
        !> The amplitude of forcing term 1 [N].
        real(dp), intent(in) :: p
            self%prob%dyn%v0 = p*self%unit%v0
            self%prob%dyn%x0 = p*self%unit%x0
            if (allocated(self%unit%x0_static)) self%prob%dyn%x0_static = p*self%unit%x0_static
            if (allocated(self%unit%u_static)) self%prob%dyn%u_static = p*self%unit%u_static
            if (allocated(self%unit%forcing_gram)) then
                ! the Gram matrices of [X0, Y]: the X0 row and column scale with p
                self%prob%dyn%forcing_gram(1, :) = p*p*self%unit%forcing_gram(1, :)
                self%prob%dyn%forcing_gram(2:, :) = p*self%unit%forcing_gram(2:, :)
                self%prob%dyn%damping_gram = self%unit%damping_gram
                self%prob%dyn%damping_gram(1, :, :) = p*self%unit%damping_gram(1, :, :)
                self%prob%dyn%damping_gram(:, 1, :) = p*self%unit%damping_gram(:, 1, :)
                self%prob%dyn%damping_gram(1, 1, :) = p*p*self%unit%damping_gram(1, 1, :)
            end if
    end subroutine scale_forcing

    !> The dynamics of a family in omega at omega = p (self%model%omega already p): from
    !> the cache when p was met before (exactly), else factorized and cached. stat = 1 when
    !> Z_h is singular there.
    subroutine set_omega_dynamics(self, p, stat)
        !> The family in omega.
        class(friction_family_t), intent(inout) :: self
        !> omega [rad/s].
        real(dp), intent(in) :: p
        !> Set to 1 when Z_h is singular.
        integer, intent(inout) :: stat
        type(error_type), allocatable :: error
        integer :: k
        self%clock = self%clock + 1
        do k = 1, dynamics_cache_size
            if (self%cached_age(k) > 0 .and. self%cached_omega(k) == p) then
                self%prob%dyn = self%cached(k)
                self%cached_age(k) = self%clock
                return
            end if
        end do
        ! K and M do not change along the family: their smallest singular values neither
        if (allocated(self%cyclic)) then
            call new_cyclic_dynamics(self%prob%dyn, self%model, self%cyclic, self%prob%basis, &
                                     error, with_omega_derivative=.true., &
                                     channels_only=.true., projections=self%projections)
        else if (allocated(self%sparse)) then
            self%sparse%model = self%model
            if (self%singular_values(1) >= 0.0_dp) then
                call new_sparse_dynamics(self%prob%dyn, self%sparse, self%prob%basis, &
                                         self%kept, error, singular_values=self%singular_values, &
                                         with_omega_derivative=.true., &
                                         analysis=self%analysis, progress=self%progress)
            else
                call new_sparse_dynamics(self%prob%dyn, self%sparse, self%prob%basis, &
                                         self%kept, error, with_omega_derivative=.true., &
                                         analysis=self%analysis, progress=self%progress)
            end if
        else if (self%singular_values(1) >= 0.0_dp) then
            call new_dynamics(self%prob%dyn, self%model, self%prob%basis, error, &
                              with_omega_derivative=.true., &
                              singular_values=self%singular_values)
        else
            call new_dynamics(self%prob%dyn, self%model, self%prob%basis, error, &
                              with_omega_derivative=.true.)
        end if
        self%singular_values = [self%prob%dyn%smin_k, self%prob%dyn%smin_m]
        self%factorizations = self%factorizations + 1
        if (allocated(error)) then
            ! a singular dynamic stiffness (undamped resonance at h omega): no point here
            stat = 1
            self%have_current = .false.
            return
        end if
        k = minloc(self%cached_age, 1)
        self%cached(k) = self%prob%dyn
        self%cached_omega(k) = p
        self%cached_age(k) = self%clock
    end subroutine set_omega_dynamics

    !> The condensed dynamics at the family's current parameter with the N-row responses
    !> that recover the displacements: the family's own, or on a sector (whose
    !> continuation keeps the channels only) built here. Errors: those of
    !> new_cyclic_dynamics.
    subroutine family_point_dynamics(self, dyn, error)
        !> The family, at the point's parameter.
        class(friction_family_t), intent(inout) :: self
        !> The dynamics.
        type(dynamics_t), intent(out) :: dyn
        !> Set on failure.
        type(error_type), allocatable, intent(out) :: error
        if (allocated(self%prob%dyn%x0) .or. .not. allocated(self%cyclic)) then
            dyn = self%prob%dyn
        else
            call new_cyclic_dynamics(dyn, self%model, self%cyclic, self%prob%basis, error, &
                                     projections=self%projections)
        end if
    end subroutine family_point_dynamics

    !> ||V0||_2 at lambda, the contact velocities without friction (as solve_periodic's
    !> fscale): near a resonance the residual cannot be computed more accurately than that
    !> allows.
    real(dp) function family_scale(self, lambda) result(s)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        !> The parameter value (0 returned when the family has no point there).
        real(dp), intent(in) :: lambda
        integer :: stat
        stat = 0
        s = 0.0_dp
        call self%set(lambda, stat)
        if (stat /= 0) return
        self%dv = 0.0_dp
        call self%prob%dyn%contact_velocity(self%prob%basis, 0.0_dp*self%dv, self%dv)
        s = norm2(self%dv)
    end function family_scale

    !> Release the FFT plans.
    subroutine family_destroy(self)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        call self%prob%destroy()
    end subroutine family_destroy

    !> F(y, lambda): the projected friction equations at parameter lambda.
    subroutine family_residual(self, y, lambda, f, stat)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        !> Friction-force coefficients R [N], and the parameter value.
        real(dp), intent(in) :: y(:), lambda
        !> The residual (huge when the family has no point at lambda).
        real(dp), intent(out) :: f(:)
        !> Nonzero on failure.
        integer, intent(inout) :: stat
        call self%set(lambda, stat)
        if (stat /= 0) then
            f = huge(1.0_dp)
            return
        end if
        call self%prob%residual(y, f, stat)
        if (allocated(self%anchor_y)) f(self%mean_rows) = f(self%mean_rows) + &
            pin_share*self%opts%tol*self%prob%rho*(y(self%mean_rows) - &
                                                   self%anchor_y(self%mean_rows))
    end subroutine family_residual

    !> Pin the tangential mean forces to those of y (the point the continuation goes on from).
    subroutine family_anchor(self, y, lambda)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        !> Friction-force coefficients R [N] of the point, and its parameter value.
        real(dp), intent(in) :: y(:), lambda
        self%anchor_y = y
    end subroutine family_anchor

    !> dF/dy (the exact generalized Jacobian of a single solve) and dF/dlambda.
    subroutine family_jacobian(self, y, lambda, jy, jl, stat)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        !> Friction-force coefficients R [N], and the parameter value.
        real(dp), intent(in) :: y(:), lambda
        !> dF/dy and dF/dlambda.
        real(dp), intent(out) :: jy(:, :), jl(:)
        !> Nonzero on failure (no point at lambda, dF/dlambda not finite).
        integer, intent(inout) :: stat
        integer :: j, nb, nc
        call self%set(lambda, stat)
        if (stat /= 0) then
            jy = 0.0_dp
            jl = 0.0_dp
            return
        end if
        call self%prob%jacobian(y, jy, stat)
        if (allocated(self%anchor_y)) then
            do j = 1, size(self%mean_rows)
                jy(self%mean_rows(j), self%mean_rows(j)) = &
                    jy(self%mean_rows(j), self%mean_rows(j)) + &
                    pin_share*self%opts%tol*self%prob%rho
            end do
        end if
        if (.not. self%prob%contacts%coulomb_only) then
            call laws_parameter_derivative(self, y, lambda, jl, stat)
            return
        end if
        ! Coulomb contacts only: the analytic derivative (their stick indicators and limits)
        nb = self%prob%basis%nb
        nc = self%prob%nc
        call self%prob%law_samples(y, self%rs, self%vs, self%states)
        self%ss = merge(1.0_dp, 0.0_dp, self%states == state_stick)
        select case (self%parameter)
        case ('omega')
            call self%prob%dyn%contact_velocity_derivative(self%prob%basis, &
                                                           reshape(y, [nb, nc]), self%dv)
        case ('force_amplitude')
            ! dV/dp = V0 at unit amplitude (V = p V0_unit + G R)
            call self%unit%contact_velocity(self%prob%basis, 0.0_dp*reshape(y, [nb, nc]), &
                                            self%dv)
        end select
        do j = 1, nc
            select case (self%parameter)
            case ('omega', 'force_amplitude')
                ! dPsi/dv = s
                call self%prob%basis%synthesize(self%dv(:, j), self%dvs, self%cw)
                self%dvs = self%ss(:, j)*self%dvs
            case ('mu')
                self%dvs = psi_limit_derivative(self%rs(:, j), self%vs(:, j), &
                           self%prob%contacts%elements(j)%e%force_scale(), self%prob%rho)* &
                           self%prob%contacts%elements(j)%e%normal_load()
            case default
                self%dvs = psi_limit_derivative(self%rs(:, j), self%vs(:, j), &
                           self%prob%contacts%elements(j)%e%force_scale(), self%prob%rho)* &
                           self%model%mu(j)
            end select
            call self%prob%basis%analyse(self%dvs, jl((j - 1)*nb + 1:j*nb), self%cw)
        end do
        if (.not. all(ieee_is_finite(jl))) stat = 1
    end subroutine family_jacobian

    !> dF/dlambda of a family with contact laws by central differences of the residual at
    !> fixed y, step 1e-6 max(|lambda|, 1e-3) (one-sided at a parameter's lower bound 0):
    !> the laws' dependence on omega (the gap term omega g), on the preload (the static
    !> load) and on the forcing runs through the condensed dynamics and the laws together.
    !> The family is left at lambda.
    subroutine laws_parameter_derivative(self, y, lambda, jl, stat)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        !> Channel-force coefficients [N], and the parameter value.
        real(dp), intent(in) :: y(:), lambda
        !> dF/dlambda.
        real(dp), intent(out) :: jl(:)
        !> Nonzero on failure.
        integer, intent(inout) :: stat
        real(dp) :: h, fp(size(jl)), fm(size(jl))
        logical :: central
        h = 1.0e-6_dp*max(abs(lambda), 1.0e-3_dp)
        central = lambda - h > 0.0_dp
        call self%set(lambda + h, stat)
        if (stat == 0) call self%prob%residual(y, fp, stat)
        if (central) then
            if (stat == 0) call self%set(lambda - h, stat)
            if (stat == 0) call self%prob%residual(y, fm, stat)
        else
            if (stat == 0) call self%set(lambda, stat)
            if (stat == 0) call self%prob%residual(y, fm, stat)
        end if
        if (stat == 0) call self%set(lambda, stat)
        if (stat /= 0) then
            jl = 0.0_dp
            return
        end if
        jl = (fp - fm)/merge(2.0_dp*h, h, central)
        if (.not. all(ieee_is_finite(jl))) stat = 1
    end subroutine laws_parameter_derivative

    !> Recovery at a fixed parameter: the harmonic ladder (warm starts from fewer harmonics,
    !> the lowest stage starting from the truncated y).
    subroutine family_recover(self, y, lambda, ok, error)
        !> The family.
        class(friction_family_t), intent(inout) :: self
        !> Friction-force coefficients R [N]: the start, the solution when ok.
        real(dp), intent(inout) :: y(:)
        !> The parameter value.
        real(dp), intent(in) :: lambda
        !> A solution was found.
        logical, intent(out) :: ok
        !> Set on failure (not for a singular dynamic stiffness: then not ok).
        type(error_type), allocatable, intent(out) :: error
        type(model_t) :: m
        type(hbm_options_t) :: o
        type(hbm_solution_t) :: s
        ok = .false.
        if (.not. ieee_is_finite(lambda)) return
        if (self%parameter == 'omega' .and. .not. (lambda > 0.0_dp)) return
        if ((self%parameter == 'mu' .or. self%parameter == 'normal_load' .or. &
             self%parameter == 'preload') .and. lambda < 0.0_dp) return
        m = self%model
        call set_sweep_parameter(m, self%parameter, lambda, self%amplitude0)
        o = self%opts
        o%start = 'ladder'
        o%want_samples = .false.
        if (allocated(self%cyclic)) then
            call solve_periodic_cyclic(m, self%cyclic, o, s, error, &
                                       r_start=reshape(y, [self%prob%basis%nb, self%prob%nc]))
        else if (allocated(self%sparse)) then
            self%sparse%model = m
            call solve_periodic_sparse(self%sparse, o, self%kept, s, error, &
                                       r_start=reshape(y, [self%prob%basis%nb, self%prob%nc]))
        else
            call solve_periodic(m, o, s, error, r_start=reshape(y, [self%prob%basis%nb, &
                                                                   self%prob%nc]))
        end if
        if (allocated(error)) then
            ! a singular dynamic stiffness at this parameter: no recovery here
            if (error%stat == stickslip_stat%numerical) deallocate (error)
            return
        end if
        if (.not. s%converged) return
        y = reshape(s%rcoef, [size(y)])
        ok = .true.
    end subroutine family_recover
end module stickslip_friction_family
