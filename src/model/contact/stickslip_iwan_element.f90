!> The microslip joint: a discrete Iwan element, n Jenkins elements in parallel on one
!> contact direction (doc/contacts.md, "The microslip (Iwan) element"). Slider i is a
!> spring k_i in series with a Coulomb slider of slip force f_i (slip displacement phi_i =
!> f_i / k_i); the joint's force on the structure is r = sum_i r_i, r_i = -k_i (w^T x - s_i),
!> |r_i| <= f_i. The joint is stiff (K_T = sum k_i) at small amplitude and slips whole at
!> r = F_S = sum f_i; in between its sliders yield one after the other (microslip), which
!> gives the Masing hysteresis loops and, for the 4-parameter Iwan density of Segalman
!> (2005), the power law of the dissipation per cycle at small amplitude, D ~ A^(3 + chi).
!>
!> Its parameters: an explicit list of (k_i, f_i), or the 4-parameter model (F_S, K_T, chi,
!> beta) discretized into n sliders (iwan_sliders): the density
!>     rho(phi) = R phi^chi on (0, phi_max) + S delta(phi - phi_max),
!>     phi_max = F_S (1 + beta) / (K_T (beta + (chi + 1) / (chi + 2))),
!>     R = F_S (chi + 1) / (phi_max^(chi + 2) (beta + (chi + 1) / (chi + 2))),
!>     S = F_S beta / (phi_max (beta + (chi + 1) / (chi + 2))),
!> a slider of stiffness rho(phi) dphi yielding at phi. The power-law part is cut at
!> geometrically spaced phi_k (phi_1 = 1e-3 phi_max) into n - 1 sliders (n without beta),
!> each the integral of its interval (k = integral of rho, f = integral of phi rho), the
!> delta one more slider (k = S, f = S phi_max): K_T and F_S are kept exactly.
!>
!> Each slider is one force channel along w with the compliance 1 / k_i (its kinematic
!> quantity the slider velocity), each a code slot and an internal state in the exact flow
!> (the Jenkins element's slider, stickslip_jenkins_element). The implicit Euler step is
!> solved exactly: with the structure's slip velocity V after the step, each slider's force
!> is clamp(r_i - h k_i V, -f_i, f_i), and V = v_free + D sum_i r_i has one root, found on
!> the sorted breakpoints of the piecewise linear, increasing function.
module stickslip_iwan_element
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa, real_text
    use stickslip_basis, only: basis_t
    use stickslip_sorting, only: sort_ascending
    use stickslip_friction, only: psi, psi_stick
    use stickslip_contact_element, only: contact_element_t, channel_t, hb_work_t, &
        state_stick, state_slip, element_step_forces
    use stickslip_contact_modes, only: element_geometry_t, mode_terms_t, event_list_t
    use stickslip_jenkins_element, only: slider_terms, slider_events, slider_start, &
        slider_project, slider_decide
    implicit none
    private
    public :: iwan_element_t, new_iwan_element, new_iwan_element_4p, iwan_discretize
    public :: iwan_first_node

    !> The smallest node of the discretized power-law part, relative to phi_max.
    real(dp), parameter :: iwan_first_node = 1.0e-3_dp

    !> A discrete Iwan element (n Jenkins elements in parallel along w).
    type, extends(contact_element_t) :: iwan_element_t
        !> Number of sliders.
        integer :: n = 0
        !> Slider stiffnesses k_i [N/m] and slip forces f_i [N].
        real(dp), allocatable :: k(:), f(:)
        !> The 4-parameter model it was built from (fs > 0), else an explicit list: the
        !> slip force F_S [N], stiffness K_T [N/m], exponent chi, ratio beta.
        real(dp) :: fs = 0.0_dp, kt = 0.0_dp, chi = 0.0_dp, beta = 0.0_dp
        !> A 4-parameter model whose F_S is mu N (a friction coefficient and a normal load
        !> [N], sweepable): mu_n = .true.
        real(dp) :: mu = 0.0_dp, normal = 0.0_dp
        logical :: mu_n = .false.
    contains
        procedure :: law_name => iwan_name
        procedure :: validate => iwan_validate
        procedure :: psi => iwan_psi
        procedure :: psi_jacobian => iwan_psi_jacobian
        procedure :: states => iwan_states
        procedure :: coulomb_dissipation => iwan_dissipation
        procedure :: force_ratio => iwan_force_ratio
        procedure :: force_scale => iwan_force_scale
        procedure :: rest_limit => iwan_rest_limit
        procedure :: set_parameter => iwan_set_parameter
        procedure :: settle_offset => iwan_settle_offset
        procedure :: step_forces => iwan_step_forces
        procedure :: exact_support => iwan_exact_support
        procedure :: ncode => iwan_ncode
        procedure :: nstate => iwan_nstate
        procedure :: state_scales => iwan_state_scales
        procedure :: initial_states => iwan_initial_states
        procedure :: mode_terms => iwan_mode_terms
        procedure :: event_rows => iwan_event_rows
        procedure :: start_code => iwan_start_code
        procedure :: start_states => iwan_start_states
        procedure :: local_decide => iwan_local_decide
    end type iwan_element_t

contains

    !> The element of the sliders (k_i [N/m], f_i [N]) (checked by validate).
    function new_iwan_element(k, f) result(self)
        !> Slider stiffnesses and slip forces.
        real(dp), intent(in) :: k(:), f(:)
        type(iwan_element_t) :: self
        call set_sliders(self, k, f)
    end function new_iwan_element

    !> The element of the 4-parameter Iwan model: macroslip force F_S [N], stiffness K_T
    !> [N/m], exponent chi (-1 < chi <= 0), ratio beta (>= 0), discretized into n sliders
    !> (iwan_discretize). With mu and normal_load [N], F_S = mu N (fs is then not used) and
    !> sweeps of mu and the normal load move it. Parameters out of range leave the element
    !> without sliders; validate says which.
    function new_iwan_element_4p(fs, kt, chi, beta, n, mu, normal_load) result(self)
        !> Parameters.
        real(dp), intent(in) :: fs, kt, chi, beta
        !> Sliders.
        integer, intent(in) :: n
        !> Friction coefficient and normal load [N] whose product is F_S.
        real(dp), intent(in), optional :: mu, normal_load
        type(iwan_element_t) :: self
        self%fs = fs
        if (present(mu) .and. present(normal_load)) then
            self%mu = mu
            self%normal = normal_load
            self%mu_n = .true.
            self%fs = mu*normal_load
        end if
        self%kt = kt
        self%chi = chi
        self%beta = beta
        self%n = n
        call rediscretize(self)
    end function new_iwan_element_4p

    !> The sliders of the element's 4-parameter model (none when out of range).
    subroutine rediscretize(self)
        type(iwan_element_t), intent(inout) :: self
        real(dp), allocatable :: k(:), f(:)
        if (.not. four_parameters_ok(self%fs, self%kt, self%chi, self%beta, self%n)) return
        call iwan_discretize(self%fs, self%kt, self%chi, self%beta, self%n, k, f)
        call set_sliders(self, k, f)
    end subroutine rediscretize

    !> The parameters of the 4-parameter model are in range (validate names the culprit).
    pure logical function four_parameters_ok(fs, kt, chi, beta, n) result(ok)
        real(dp), intent(in) :: fs, kt, chi, beta
        integer, intent(in) :: n
        ok = fs > 0.0_dp .and. fs <= huge(fs) .and. kt > 0.0_dp .and. kt <= huge(kt) .and. &
             chi > -1.0_dp .and. chi <= 0.0_dp .and. beta >= 0.0_dp .and. &
             beta <= huge(beta) .and. n >= 1
    end function four_parameters_ok

    !> The n sliders (k, f) of the 4-parameter Iwan model (F_S [N], K_T [N/m], chi, beta):
    !> n - 1 sliders of the power-law part on geometrically spaced intervals of (0, phi_max)
    !> (iwan_first_node phi_max the first node) and one of the delta when beta > 0 (n
    !> sliders of the power law when beta = 0); one slider (K_T, F_S) when n = 1. The sums
    !> of k and f are K_T and F_S (to roundoff).
    pure subroutine iwan_discretize(fs, kt, chi, beta, n, k, f)
        !> Parameters (in range).
        real(dp), intent(in) :: fs, kt, chi, beta
        !> Sliders (>= 1).
        integer, intent(in) :: n
        !> Slider stiffnesses [N/m] and slip forces [N], ascending slip displacements.
        real(dp), allocatable, intent(out) :: k(:), f(:)
        real(dp) :: a, phimax, r, s, q, lo, hi
        integer :: m, i
        allocate (k(n), f(n))
        if (n == 1) then
            k(1) = kt
            f(1) = fs
            return
        end if
        a = (chi + 1.0_dp)/(chi + 2.0_dp)
        phimax = fs*(1.0_dp + beta)/(kt*(beta + a))
        r = fs*(chi + 1.0_dp)/(phimax**(chi + 2.0_dp)*(beta + a))
        s = fs*beta/(phimax*(beta + a))
        m = n
        if (beta > 0.0_dp) m = n - 1
        q = 1.0_dp
        if (m > 1) q = iwan_first_node**(1.0_dp/real(m - 1, dp))
        lo = 0.0_dp
        do i = 1, m
            hi = phimax*q**(m - i)
            k(i) = r*(hi**(chi + 1.0_dp) - lo**(chi + 1.0_dp))/(chi + 1.0_dp)
            f(i) = r*(hi**(chi + 2.0_dp) - lo**(chi + 2.0_dp))/(chi + 2.0_dp)
            lo = hi
        end do
        if (m < n) then
            k(n) = s
            f(n) = s*phimax
        end if
    end subroutine iwan_discretize

    !> Take the sliders: one channel each along w, compliance 1 / k_i.
    subroutine set_sliders(self, k, f)
        type(iwan_element_t), intent(inout) :: self
        real(dp), intent(in) :: k(:), f(:)
        integer :: i
        self%n = size(k)
        self%k = k
        self%f = f
        if (allocated(self%channel)) deallocate (self%channel)
        allocate (self%channel(self%n))
        do i = 1, self%n
            self%channel(i) = channel_t(compliance=1.0_dp/k(i), holds=f(i) > 0.0_dp)
        end do
    end subroutine set_sliders

    pure function iwan_name(self) result(name)
        class(iwan_element_t), intent(in) :: self
        character(len=:), allocatable :: name
        name = "iwan"
    end function iwan_name

    !> The parameters: the 4-parameter model's F_S > 0, K_T > 0, -1 < chi <= 0, beta >= 0,
    !> n >= 1; an explicit list: at least one slider, k_i > 0 and f_i > 0 finite, the slip
    !> forces increasing. Messages name model%laws(j) and the parameter.
    subroutine iwan_validate(self, j, error)
        class(iwan_element_t), intent(in) :: self
        integer, intent(in) :: j
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: at
        integer :: i
        at = "model%laws("//itoa(j)//")"
        if (self%mu_n) then
            if (.not. (self%mu > 0.0_dp .and. self%mu <= huge(1.0_dp))) then
                call bad("%mu", self%mu, "must be finite and > 0 (F_S = mu N)")
            else if (.not. (self%normal > 0.0_dp .and. self%normal <= huge(1.0_dp))) then
                call bad("%normal", self%normal, "must be finite and > 0 (F_S = mu N)")
            end if
            if (allocated(error)) return
        end if
        if (self%fs > 0.0_dp .or. self%kt /= 0.0_dp .or. self%mu_n) then
            if (.not. (self%fs > 0.0_dp .and. self%fs <= huge(1.0_dp))) then
                call bad("%fs", self%fs, "must be finite and > 0 (the macroslip force)")
            else if (.not. (self%kt > 0.0_dp .and. self%kt <= huge(1.0_dp))) then
                call bad("%kt", self%kt, "must be finite and > 0 (the joint's stiffness)")
            else if (.not. (self%chi > -1.0_dp .and. self%chi <= 0.0_dp)) then
                call bad("%chi", self%chi, "must be in (-1, 0] (the exponent of the slip "// &
                         "force density)")
            else if (.not. (self%beta >= 0.0_dp .and. self%beta <= huge(1.0_dp))) then
                call bad("%beta", self%beta, "must be finite and >= 0")
            else if (self%n < 1) then
                call fatal_error(error, at//"%n = "//itoa(self%n)//": must be >= 1 (sliders)", &
                                 stickslip_stat%input)
            end if
            if (allocated(error)) return
        end if
        if (self%n < 1 .or. .not. allocated(self%k)) then
            call fatal_error(error, at//": a microslip element needs at least one slider", &
                             stickslip_stat%input)
            return
        end if
        do i = 1, self%n
            if (.not. (self%k(i) > 0.0_dp .and. self%k(i) <= huge(1.0_dp))) then
                call bad("%k("//itoa(i)//")", self%k(i), "must be finite and > 0 (a slider's "// &
                         "stiffness)")
            else if (.not. (self%f(i) > 0.0_dp .and. self%f(i) <= huge(1.0_dp))) then
                call bad("%f("//itoa(i)//")", self%f(i), "must be finite and > 0 (a slider's "// &
                         "slip force)")
            else if (i > 1) then
                if (.not. (self%f(i) > self%f(i - 1)) .and. self%fs == 0.0_dp) &
                    call bad("%f("//itoa(i)//")", self%f(i), "the slip forces must increase "// &
                             "(f("//itoa(i - 1)//") = "//real_text(self%f(i - 1), '(g0.6)')//")")
            end if
            if (allocated(error)) return
        end do

    contains

        subroutine bad(what, value, why)
            character(len=*), intent(in) :: what, why
            real(dp), intent(in) :: value
            call fatal_error(error, at//what//" = "//real_text(value, '(g0.6)')//": "//why, &
                             stickslip_stat%input)
        end subroutine bad
    end subroutine iwan_validate

    !> Psi of every slider (1D Coulomb with its own limit f_i) [m/s].
    subroutine iwan_psi(self, rho, r, u, p)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        real(dp), intent(out) :: p(:, :)
        integer :: i
        do i = 1, self%n
            p(:, i) = psi(r(:, i), u(:, i), self%f(i), rho)
        end do
    end subroutine iwan_psi

    !> Per slider: dPsi/du = s_i, dPsi/dr = rho (1 - s_i) (diagonal).
    subroutine iwan_psi_jacobian(self, rho, r, u, p, jr, ju)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        real(dp), intent(out) :: p(:, :), jr(:, :, :), ju(:, :, :)
        integer :: i
        jr = 0.0_dp
        ju = 0.0_dp
        do i = 1, self%n
            p(:, i) = psi(r(:, i), u(:, i), self%f(i), rho)
            ju(i, i, :) = psi_stick(r(:, i), u(:, i), self%f(i), rho)
            jr(i, i, :) = rho*(1.0_dp - ju(i, i, :))
        end do
    end subroutine iwan_psi_jacobian

    !> Stuck when every slider sticks, slipping (micro or macro) otherwise.
    subroutine iwan_states(self, rho, r, u, state)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :)
        integer, intent(out) :: state(:)
        integer :: i
        state = state_stick
        do i = 1, self%n
            where (psi_stick(r(:, i), u(:, i), self%f(i), rho) < 0.5_dp) state = state_slip
        end do
    end subroutine iwan_states

    !> The sum over the sliders of f_i |u_i| (u_i the slider velocity); what the law
    !> dissipates: that where a slider slips, |r_i u_i| where it sticks.
    subroutine iwan_dissipation(self, rho, r, u, state, period, diss, law_diss)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: rho, r(:, :), u(:, :), period
        integer, intent(in) :: state(:)
        real(dp), intent(out) :: diss, law_diss
        integer :: i, nt
        nt = size(r, 1)
        diss = 0.0_dp
        law_diss = 0.0_dp
        do i = 1, self%n
            diss = diss + self%f(i)*period*sum(abs(u(:, i)))/nt
            law_diss = law_diss + period*sum(merge(abs(r(:, i)*u(:, i)), &
                                                   self%f(i)*abs(u(:, i)), &
                                                   psi_stick(r(:, i), u(:, i), self%f(i), &
                                                             rho) > 0.5_dp))/nt
        end do
    end subroutine iwan_dissipation

    !> The largest max |r_i| / f_i over the sliders.
    real(dp) function iwan_force_ratio(self, r) result(ratio)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: r(:, :)
        integer :: i
        ratio = 0.0_dp
        do i = 1, self%n
            ratio = max(ratio, maxval(abs(r(:, i)))/self%f(i))
        end do
    end function iwan_force_ratio

    !> The macroslip force F_S = sum f_i [N].
    pure real(dp) function iwan_force_scale(self) result(fs)
        class(iwan_element_t), intent(in) :: self
        fs = 0.0_dp
        if (allocated(self%f)) fs = sum(self%f)
    end function iwan_force_scale

    !> Slider k's slip force [N].
    pure real(dp) function iwan_rest_limit(self, k) result(g)
        class(iwan_element_t), intent(in) :: self
        integer, intent(in) :: k
        g = self%f(k)
    end function iwan_rest_limit

    !> A 4-parameter element takes the macroslip force F_S = mu N ('mu' and 'normal_load'
    !> scale it: value / old value) and is discretized anew; an explicit list has no such
    !> parameter.
    subroutine iwan_set_parameter(self, name, value, done)
        class(iwan_element_t), intent(inout) :: self
        character(len=*), intent(in) :: name
        real(dp), intent(in) :: value
        logical, intent(out) :: done
        done = .false.
        if (.not. self%mu_n) return
        select case (name)
        case ('mu')
            self%mu = value
        case ('normal_load')
            self%normal = value
        case default
            return
        end select
        done = .true.
        self%fs = self%mu*self%normal
        call rediscretize(self)
    end subroutine iwan_set_parameter

    !> Every slider stuck over the whole period holds any mean force that keeps |r_i(t)| <=
    !> f_i: the admissible value closest to zero (minimum norm). `settled` when one was.
    subroutine iwan_settle_offset(self, rho, r, u, mean, settled)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: rho
        real(dp), intent(inout) :: r(:, :), u(:, :), mean(:)
        logical, intent(out) :: settled
        real(dp) :: lo, hi, shift
        integer :: i
        settled = .false.
        do i = 1, self%n
            if (.not. all(psi_stick(r(:, i), u(:, i), self%f(i), rho) > 0.5_dp)) cycle
            lo = -self%f(i) - minval(r(:, i) - mean(i))
            hi = self%f(i) - maxval(r(:, i) - mean(i))
            shift = min(max(0.0_dp, lo), hi) - mean(i)
            mean(i) = mean(i) + shift
            r(:, i) = r(:, i) + shift
            settled = .true.
        end do
    end subroutine iwan_settle_offset

    !> The forces of one implicit step, exactly. The element's block of the step matrix is
    !> A = D 1 1^T + diag(c_i / h) (one direction, compliances c_i = 1 / k_i): with V = D
    !> sum_j r_j, u_i = q_i + V + (c_i / h) r_i, a stuck slider has r_i = -(h / c_i)(q_i +
    !> V) and every slider r_i = clamp(-(h / c_i)(q_i + V), -f_i, f_i). g(V) = V - D sum_i
    !> r_i(V) increases (piecewise linearly) and has one root: found on the sorted
    !> breakpoints, then on its linear piece. A block of another shape: the Newton iteration
    !> of contact_element_t.
    subroutine iwan_step_forces(self, a, q, r, scale)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: a(:, :), q(:)
        real(dp), intent(inout) :: r(:)
        real(dp), intent(in) :: scale
        real(dp) :: d, c(self%n), bp(2*self%n), glo, ghi, vlo, vhi, v
        integer :: i, n, lo, hi, mid
        n = self%n
        if (n == 1) then
            r(1) = max(-self%f(1), min(self%f(1), -q(1)/a(1, 1)))
            return
        end if
        d = a(1, 2)
        do i = 1, n
            c(i) = a(i, i) - d
        end do
        if (.not. (d > 0.0_dp .and. all(c > 0.0_dp)) .or. &
            maxval(abs(a - d - diag(c))) > 1.0e-12_dp*maxval(abs(a))) then
            call element_step_forces(self, a, q, r, scale)
            return
        end if
        ! breakpoints: where slider i reaches -f_i or +f_i
        do i = 1, n
            bp(2*i - 1) = -q(i) - self%f(i)*c(i)
            bp(2*i) = -q(i) + self%f(i)*c(i)
        end do
        call sort_ascending(bp)
        ! g at the breakpoints increases: bisect for the interval with the sign change
        if (g(bp(1)) >= 0.0_dp) then
            vhi = bp(1)
            vlo = vhi - 1.0_dp
            do while (g(vlo) > 0.0_dp)
                vlo = vhi - 2.0_dp*(vhi - vlo)
            end do
        else if (g(bp(2*n)) <= 0.0_dp) then
            vlo = bp(2*n)
            vhi = vlo + 1.0_dp
            do while (g(vhi) < 0.0_dp)
                vhi = vlo + 2.0_dp*(vhi - vlo)
            end do
        else
            lo = 1
            hi = 2*n
            do while (hi - lo > 1)
                mid = (lo + hi)/2
                if (g(bp(mid)) < 0.0_dp) then
                    lo = mid
                else
                    hi = mid
                end if
            end do
            vlo = bp(lo)
            vhi = bp(hi)
        end if
        ! g is linear on [vlo, vhi]
        glo = g(vlo)
        ghi = g(vhi)
        v = vlo
        if (ghi /= glo) v = vlo - glo*(vhi - vlo)/(ghi - glo)
        do i = 1, n
            r(i) = force_at(i, v)
        end do

    contains

        real(dp) function force_at(i, vv)
            integer, intent(in) :: i
            real(dp), intent(in) :: vv
            force_at = max(-self%f(i), min(self%f(i), -(q(i) + vv)/c(i)))
        end function force_at

        real(dp) function g(vv)
            real(dp), intent(in) :: vv
            integer :: j
            g = vv
            do j = 1, n
                g = g - d*force_at(j, vv)
            end do
        end function g

        pure function diag(x) result(m)
            real(dp), intent(in) :: x(:)
            real(dp) :: m(size(x), size(x))
            integer :: j
            m = 0.0_dp
            do j = 1, size(x)
                m(j, j) = x(j)
            end do
        end function diag
    end subroutine iwan_step_forces

    !> Handled by the exact flow.
    function iwan_exact_support(self) result(why)
        class(iwan_element_t), intent(in) :: self
        character(len=:), allocatable :: why
        why = ""
    end function iwan_exact_support

    !> One code slot per slider.
    pure integer function iwan_ncode(self) result(k)
        class(iwan_element_t), intent(in) :: self
        k = self%n
    end function iwan_ncode

    !> One internal state per slider (its position).
    pure integer function iwan_nstate(self) result(k)
        class(iwan_element_t), intent(in) :: self
        k = self%n
    end function iwan_nstate

    !> sqrt(k_i).
    pure subroutine iwan_state_scales(self, c)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(out) :: c(:)
        c = sqrt(self%k)
    end subroutine iwan_state_scales

    !> s_i = w^T x + r_i / k_i.
    pure subroutine iwan_initial_states(self, dx, r, s)
        class(iwan_element_t), intent(in) :: self
        real(dp), intent(in) :: dx(:), r(:)
        real(dp), intent(out) :: s(:)
        s = dx(1) + r(1:self%n)/self%k
    end subroutine iwan_initial_states

    !> Every slider's mode (stickslip_jenkins_element, slider_terms).
    subroutine iwan_mode_terms(self, code, geom, terms)
        class(iwan_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        type(mode_terms_t), intent(inout) :: terms
        integer :: i
        do i = 1, self%n
            call slider_terms(code(i), self%k(i), self%f(i), i, i, geom%first + i - 1, geom, &
                              terms)
        end do
    end subroutine iwan_mode_terms

    !> Every slider's events.
    subroutine iwan_event_rows(self, code, geom, fb, events)
        class(iwan_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        type(event_list_t), intent(inout) :: events
        integer :: i
        do i = 1, self%n
            call slider_events(code(i), self%f(i), i, fb(i, :), geom, events)
        end do
    end subroutine iwan_event_rows

    !> Every slider's code at the start.
    subroutine iwan_start_code(self, geom, y, code, decide)
        class(iwan_element_t), intent(in) :: self
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:)
        integer, intent(out) :: code(:)
        logical, intent(out) :: decide
        integer :: i
        do i = 1, self%n
            code(i) = slider_start(self%k(i), self%f(i), i, geom, y)
        end do
        decide = .false.
    end subroutine iwan_start_code

    !> Every slipping slider's spring on its limit, and a stuck one's beyond it
    !> (slider_project).
    subroutine iwan_start_states(self, code, geom, fb, y, pj)
        class(iwan_element_t), intent(in) :: self
        integer, intent(in) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: fb(:, :)
        real(dp), intent(inout) :: y(:)
        real(dp), intent(inout) :: pj(:, :)
        integer :: i
        do i = 1, self%n
            call slider_project(self%k(i), self%f(i), code(i), i, geom, y, pj)
        end do
    end subroutine iwan_start_states

    !> The slipping sliders whose slip velocity reached zero (all at once: they share w^T
    !> v) stick, unless the structure accelerates on in their direction.
    subroutine iwan_local_decide(self, code, geom, y, ydot)
        class(iwan_element_t), intent(in) :: self
        integer, intent(inout) :: code(:)
        type(element_geometry_t), intent(in) :: geom
        real(dp), intent(in) :: y(:), ydot(:)
        integer :: i
        do i = 1, self%n
            call slider_decide(code(i), geom, y, ydot)
        end do
    end subroutine iwan_local_decide
end module stickslip_iwan_element
