!> The mechanical model: a linear structure M x'' + C x' + K x = f(t) + W r(t) with Coulomb
!> friction contacts and harmonic forcing. Plain data plus validation; it knows nothing of
!> how the periodic solution is computed nor of files.
!>
!> The contact directions W (N x n_c) and the load shapes F (N x n_terms) come either from
!> DOF lists (contact_dof/contact_dof2: w_j = e_dof - e_dof2; force_dof: f_i = e_dof) or
!> from dense matrices (contact_direction, force_shape: oblique or local-frame contacts,
!> distributed loads). Every method reads them only through contact_velocity_direction and
!> force_direction, so both forms give the same results (bitwise for unit columns).
!>
!> Contact laws beyond rigid Coulomb friction under a constant normal load (doc/contacts.md):
!> a contact may have a normal direction n_j (a unilateral, Signorini contact: gap
!> g_j = gap_j + n_j^T x >= 0, normal force lambda_j >= 0 acting as n_j lambda_j, lambda_j g_j
!> = 0; friction limit mu_j lambda_j(t)), a second tangential direction (2D friction in the
!> plane of w_j and t2_j, the force in the disk of radius mu N), a normal contact stiffness
!> and a tangential contact stiffness (Jenkins element). All of it is optional: a model
!> without these fields is the model of before, and every method gives the same numbers.
!> A contact may instead be given its law explicitly as a contact element (`laws`, e.g. the
!> microslip element): the arrays then give its directions only. The methods see every
!> contact as an element (stickslip_contact_set), never these arrays' flags.
module stickslip_model
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa, real_text
    use stickslip_lapack, only: dpotrf
    use stickslip_contact_element, only: element_box_t
    implicit none
    private
    public :: model_t, validate_model, contact_velocity_direction, force_direction
    public :: contact_normal_direction, contact_tangent2_direction, is_unilateral, is_planar, &
        contact_gap, contact_preload, normal_stiffness_of, tangential_stiffness_of, &
        has_contact_laws, preload_force

    !> A structure with friction contacts, forced at angular frequency `omega`.
    !> Field names follow the case-file namelist variables (doc/case-file.md).
    type :: model_t
        !> Number of degrees of freedom N.
        integer :: ndof = 0
        !> Mass matrix M (N x N), symmetric positive definite [kg].
        real(dp), allocatable :: mass(:, :)
        !> Viscous damping matrix C (N x N), may be zero [N s/m].
        real(dp), allocatable :: damping(:, :)
        !> Stiffness matrix K (N x N) [N/m].
        real(dp), allocatable :: stiffness(:, :)
        !> Fundamental angular frequency of the forcing and of the response [rad/s].
        real(dp) :: omega = 0.0_dp
        !> Forcing terms: amplitude * cos(harmonic * omega * t + phase) on DOF `force_dof`
        !> (unallocated or empty when force_shape is given).
        integer, allocatable :: force_dof(:)
        !> Load shapes, N x n_terms (optional): term i is amplitude(i) * cos(harmonic(i)
        !> omega t + phase(i)) * force_shape(:, i) [dimensionless scale of the amplitude;
        !> force = amplitude x shape in N]. When allocated it replaces force_dof.
        real(dp), allocatable :: force_shape(:, :)
        !> Harmonic index of each forcing term (>= 0; 0 is a static load).
        integer, allocatable :: force_harmonic(:)
        !> Amplitude of each forcing term [N].
        real(dp), allocatable :: force_amplitude(:)
        !> Phase of each forcing term [rad].
        real(dp), allocatable :: force_phase(:)
        !> First DOF of each contact (its slip velocity is v(dof) - v(dof2)).
        integer, allocatable :: contact_dof(:)
        !> Second DOF of each contact, 0 for a contact with the ground.
        integer, allocatable :: contact_dof2(:)
        !> Contact directions W, N x n_c (optional): contact j slips with velocity
        !> contact_direction(:, j)^T x' and its friction force acts as contact_direction(:, j)
        !> r_j. When allocated it replaces contact_dof and contact_dof2 (unallocated or empty).
        real(dp), allocatable :: contact_direction(:, :)
        !> Friction coefficient of each contact (>= 0).
        real(dp), allocatable :: mu(:)
        !> Normal load of each contact (>= 0) [N]; 0 for a unilateral contact (its normal
        !> force comes from its gap and preload).
        real(dp), allocatable :: normal_load(:)
        !> Normal directions, N x n_c (optional): column j nonzero makes contact j unilateral,
        !> with gap g_j = gap(j) + normal_direction(:, j)^T x >= 0 [m] and a normal force
        !> lambda_j >= 0 acting on the structure as normal_direction(:, j) lambda_j; a zero
        !> column (or no array) keeps the constant normal_load(j).
        real(dp), allocatable :: normal_direction(:, :)
        !> Second tangential directions, N x n_c (optional): column j nonzero makes contact j
        !> slip in a plane (2D friction): slip velocity (w_j^T x', t2_j^T x'), friction force
        !> (r_j, s_j) acting as w_j r_j + t2_j s_j, in the disk |(r_j, s_j)| <= mu_j N_j.
        !> Orthogonal to w_j and of the same length.
        real(dp), allocatable :: tangent2_direction(:, :)
        !> Initial gap of each unilateral contact at x = 0 [m] (default 0).
        real(dp), allocatable :: gap(:)
        !> Static preload of each unilateral contact [N] (>= 0, default 0): a constant force
        !> -preload(j) normal_direction(:, j) pressing the contact closed; the static solve
        !> with it gives the mean normal force.
        real(dp), allocatable :: preload(:)
        !> Normal contact stiffness of each unilateral contact [N/m] (>= 0; 0 = rigid, the
        !> Signorini law): lambda = max(0, -k_n g) for k_n > 0.
        real(dp), allocatable :: normal_stiffness(:)
        !> Tangential contact stiffness of each contact [N/m] (>= 0; 0 = rigid Coulomb): a
        !> spring k_t in series with the Coulomb slider (Jenkins element), in 1D and 2D.
        real(dp), allocatable :: tangential_stiffness(:)
        !> Explicit contact laws (optional; empty, or one slot per contact): an allocated
        !> slot j gives contact j its law (a contact element, e.g. stickslip_iwan_element),
        !> whose channels act along the contact's directions; mu(j) and normal_load(j) are
        !> then not used (give 0), and the contact has no normal, second tangent or contact
        !> stiffness of the arrays. Unallocated slots: the law the arrays describe.
        type(element_box_t), allocatable :: laws(:)
    contains
        !> Number of contacts.
        procedure :: ncontact
        !> Number of forcing terms.
        procedure :: nforce
    end type model_t

contains

    !> Number of friction contacts of the model.
    pure integer function ncontact(self)
        !> The model.
        class(model_t), intent(in) :: self
        ncontact = 0
        if (allocated(self%contact_direction)) then
            ncontact = size(self%contact_direction, 2)
        else if (allocated(self%contact_dof)) then
            ncontact = size(self%contact_dof)
        end if
    end function ncontact

    !> Number of forcing terms of the model.
    pure integer function nforce(self)
        !> The model.
        class(model_t), intent(in) :: self
        nforce = 0
        if (allocated(self%force_shape)) then
            nforce = size(self%force_shape, 2)
        else if (allocated(self%force_dof)) then
            nforce = size(self%force_dof)
        end if
    end function nforce

    !> Column j of W: the direction whose velocity is contact j's slip velocity (and along
    !> which its friction force acts): contact_direction(:, j) when given, else
    !> e_{contact_dof(j)} - e_{contact_dof2(j)} (no second term for the ground, dof2 = 0).
    pure function contact_velocity_direction(model, j) result(w)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index (1..ncontact()).
        integer, intent(in) :: j
        real(dp) :: w(model%ndof)
        if (allocated(model%contact_direction)) then
            w = model%contact_direction(:, j)
            return
        end if
        w = 0.0_dp
        w(model%contact_dof(j)) = 1.0_dp
        if (model%contact_dof2(j) > 0) w(model%contact_dof2(j)) = -1.0_dp
    end function contact_velocity_direction

    !> Column i of the load shapes: force term i is force_amplitude(i) * cos(force_harmonic(i)
    !> omega t + force_phase(i)) times this vector; force_shape(:, i) when given, else
    !> e_{force_dof(i)}.
    pure function force_direction(model, i) result(f)
        !> The model.
        type(model_t), intent(in) :: model
        !> Forcing term index (1..nforce()).
        integer, intent(in) :: i
        real(dp) :: f(model%ndof)
        if (allocated(model%force_shape)) then
            f = model%force_shape(:, i)
            return
        end if
        f = 0.0_dp
        f(model%force_dof(i)) = 1.0_dp
    end function force_direction

    !> Normal direction n_j of contact j (zeros for a contact under a constant normal load).
    pure function contact_normal_direction(model, j) result(nv)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index (1..ncontact()).
        integer, intent(in) :: j
        real(dp) :: nv(model%ndof)
        nv = 0.0_dp
        if (allocated(model%normal_direction)) then
            if (size(model%normal_direction, 2) >= j) nv = model%normal_direction(:, j)
        end if
    end function contact_normal_direction

    !> Second tangential direction t2_j of contact j (zeros for 1D friction).
    pure function contact_tangent2_direction(model, j) result(tv)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index (1..ncontact()).
        integer, intent(in) :: j
        real(dp) :: tv(model%ndof)
        tv = 0.0_dp
        if (allocated(model%tangent2_direction)) then
            if (size(model%tangent2_direction, 2) >= j) tv = model%tangent2_direction(:, j)
        end if
    end function contact_tangent2_direction

    !> Contact j has a normal direction (unilateral contact, varying normal force).
    pure logical function is_unilateral(model, j)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index.
        integer, intent(in) :: j
        is_unilateral = .false.
        if (allocated(model%normal_direction)) then
            if (size(model%normal_direction, 2) >= j) &
                is_unilateral = any(model%normal_direction(:, j) /= 0.0_dp)
        end if
    end function is_unilateral

    !> Contact j slips in a plane (2D friction).
    pure logical function is_planar(model, j)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index.
        integer, intent(in) :: j
        is_planar = .false.
        if (allocated(model%tangent2_direction)) then
            if (size(model%tangent2_direction, 2) >= j) &
                is_planar = any(model%tangent2_direction(:, j) /= 0.0_dp)
        end if
    end function is_planar

    !> Initial gap of contact j [m] (0 when not given).
    pure real(dp) function contact_gap(model, j)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index.
        integer, intent(in) :: j
        contact_gap = entry_or_zero(model%gap, j)
    end function contact_gap

    !> Static preload of contact j [N] (0 when not given).
    pure real(dp) function contact_preload(model, j)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index.
        integer, intent(in) :: j
        contact_preload = entry_or_zero(model%preload, j)
    end function contact_preload

    !> Normal contact stiffness of contact j [N/m] (0: rigid).
    pure real(dp) function normal_stiffness_of(model, j)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index.
        integer, intent(in) :: j
        normal_stiffness_of = entry_or_zero(model%normal_stiffness, j)
    end function normal_stiffness_of

    !> Tangential contact stiffness of contact j [N/m] (0: rigid).
    pure real(dp) function tangential_stiffness_of(model, j)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index.
        integer, intent(in) :: j
        tangential_stiffness_of = entry_or_zero(model%tangential_stiffness, j)
    end function tangential_stiffness_of

    !> Some contact of the model is unilateral, planar or has a contact stiffness: the
    !> methods take their general contact path (otherwise the rigid constant-load path of
    !> before, bitwise unchanged).
    pure logical function has_contact_laws(model)
        !> The model.
        type(model_t), intent(in) :: model
        integer :: j
        has_contact_laws = .false.
        do j = 1, model%ncontact()
            if (is_unilateral(model, j) .or. is_planar(model, j) .or. &
                tangential_stiffness_of(model, j) /= 0.0_dp) then
                has_contact_laws = .true.
                return
            end if
        end do
    end function has_contact_laws

    !> The static preload force on the structure, -sum_j preload_j n_j (N-vector) [N].
    pure function preload_force(model) result(f)
        !> The model.
        type(model_t), intent(in) :: model
        real(dp) :: f(model%ndof)
        integer :: j
        f = 0.0_dp
        do j = 1, model%ncontact()
            if (contact_preload(model, j) /= 0.0_dp) &
                f = f - contact_preload(model, j)*contact_normal_direction(model, j)
        end do
    end function preload_force

    !> a(j) when a is allocated with at least j entries, else 0.
    pure real(dp) function entry_or_zero(a, j)
        real(dp), allocatable, intent(in) :: a(:)
        integer, intent(in) :: j
        entry_or_zero = 0.0_dp
        if (allocated(a)) then
            if (size(a) >= j) entry_or_zero = a(j)
        end if
    end function entry_or_zero

    !> Check a model for consistency: sizes, finite values, M symmetric positive definite,
    !> C and K symmetric-shaped and finite, DOF indices in range, mu >= 0, normal loads >= 0,
    !> omega > 0; contact_direction and force_shape (when given): ndof rows, finite, not
    !> beside a non-empty contact_dof/contact_dof2 or force_dof, no zero contact direction,
    !> one mu, normal_load (force_harmonic, force_amplitude, force_phase) per column. Errors (stat input) name the argument and its component, e.g.
    !> "model%mu(2) = -0.1: must be >= 0" (a case file reports "&friction mu(2) = ...").
    !> With `dense` = .false. the dense matrices are not checked (they are left unallocated
    !> by a sparse_model_t, whose validate_sparse_model checks its sparse ones).
    subroutine validate_model(model, error, dense)
        !> The model to check.
        type(model_t), intent(in) :: model
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Check the dense mass, stiffness and damping (default .true.).
        logical, intent(in), optional :: dense
        integer :: n, i, j
        logical :: check_dense
        character(len=160) :: buf

        n = model%ndof
        if (n < 1) then
            call fatal_error(error, "model%ndof: must be >= 1", stickslip_stat%input)
            return
        end if
        check_dense = .true.
        if (present(dense)) check_dense = dense
        if (check_dense) then
            call check_dense_matrices(error)
            if (allocated(error)) return
        end if
        if (.not. (model%omega > 0.0_dp) .or. model%omega > huge(1.0_dp)) then
            write (buf, '(a,g0.6,a)') "model%omega = ", model%omega, ": must be finite and > 0"
            call fatal_error(error, trim(buf), stickslip_stat%input)
            return
        end if

        if (allocated(model%force_shape)) then
            if (allocated(model%force_dof)) then
                if (size(model%force_dof) > 0) then
                    call fatal_error(error, "model%force_shape and model%force_dof: both "// &
                                     "given (give the load shapes or the forced DOFs)", &
                                     stickslip_stat%input)
                    return
                end if
            end if
            call check_shape("force_shape", model%force_shape, .false., error)
            if (allocated(error)) return
        else if (.not. allocated(model%force_dof)) then
            call fatal_error(error, "model%force_dof: not allocated (or give "// &
                             "model%force_shape)", stickslip_stat%input)
            return
        end if
        if (.not. (allocated(model%force_harmonic) .and. allocated(model%force_amplitude) &
                   .and. allocated(model%force_phase))) then
            call fatal_error(error, "model%force_harmonic, model%force_amplitude, "// &
                             "model%force_phase: not all allocated", stickslip_stat%input)
            return
        end if
        if (any([size(model%force_harmonic), size(model%force_amplitude), &
                 size(model%force_phase)] /= model%nforce())) then
            if (allocated(model%force_shape)) then
                call fatal_error(error, "model%force_harmonic, model%force_amplitude and "// &
                                 "model%force_phase: need one entry per column of "// &
                                 "model%force_shape ("//itoa(model%nforce())//")", &
                                 stickslip_stat%input)
            else
                call fatal_error(error, "model%force_dof, model%force_harmonic, "// &
                                 "model%force_amplitude and model%force_phase: must have "// &
                                 "the same length", stickslip_stat%input)
            end if
            return
        end if
        do i = 1, model%nforce()
            if (.not. allocated(model%force_shape)) then
                if (model%force_dof(i) < 1 .or. model%force_dof(i) > n) then
                    write (buf, '(a,i0,a,i0,a,i0,a)') "model%force_dof(", i, ") = ", &
                        model%force_dof(i), ": must be a DOF in 1..", n, " (ndof)"
                    call fatal_error(error, trim(buf), stickslip_stat%input)
                    return
                end if
            end if
            if (model%force_harmonic(i) < 0) then
                write (buf, '(a,i0,a,i0,a)') "model%force_harmonic(", i, ") = ", &
                    model%force_harmonic(i), ": must be >= 0"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
            if (.not. finite(model%force_amplitude(i))) then
                write (buf, '(a,i0,a)') "model%force_amplitude(", i, "): not a finite number"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
            if (.not. finite(model%force_phase(i))) then
                write (buf, '(a,i0,a)') "model%force_phase(", i, "): not a finite number"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
        end do

        if (allocated(model%contact_direction)) then
            if (allocated(model%contact_dof)) then
                if (size(model%contact_dof) > 0) then
                    call fatal_error(error, "model%contact_direction and model%contact_dof: "// &
                                     "both given (give the directions or the contact DOFs)", &
                                     stickslip_stat%input)
                    return
                end if
            end if
            if (allocated(model%contact_dof2)) then
                if (size(model%contact_dof2) > 0) then
                    call fatal_error(error, "model%contact_direction and model%contact_dof2: "// &
                                     "both given (give the directions or the contact DOFs)", &
                                     stickslip_stat%input)
                    return
                end if
            end if
            call check_shape("contact_direction", model%contact_direction, .true., error)
            if (allocated(error)) return
        else if (.not. (allocated(model%contact_dof) .and. allocated(model%contact_dof2))) then
            call fatal_error(error, "model%contact_dof, model%contact_dof2: not both "// &
                             "allocated (or give model%contact_direction)", stickslip_stat%input)
            return
        end if
        if (.not. (allocated(model%mu) .and. allocated(model%normal_load))) then
            call fatal_error(error, "model%mu, model%normal_load: not both allocated", &
                             stickslip_stat%input)
            return
        end if
        if (allocated(model%contact_direction)) then
            if (any([size(model%mu), size(model%normal_load)] /= model%ncontact())) then
                call fatal_error(error, "model%mu and model%normal_load: need one entry per "// &
                                 "column of model%contact_direction ("// &
                                 itoa(model%ncontact())//")", stickslip_stat%input)
                return
            end if
        else if (any([size(model%contact_dof2), size(model%mu), size(model%normal_load)] &
                     /= size(model%contact_dof))) then
            call fatal_error(error, "model%contact_dof, model%contact_dof2, model%mu and "// &
                             "model%normal_load: must have the same length", stickslip_stat%input)
            return
        end if
        do j = 1, model%ncontact()
            if (.not. allocated(model%contact_direction)) then
                if (model%contact_dof(j) < 1 .or. model%contact_dof(j) > n) then
                    write (buf, '(a,i0,a,i0,a,i0,a)') "model%contact_dof(", j, ") = ", &
                        model%contact_dof(j), ": must be a DOF in 1..", n, " (ndof)"
                    call fatal_error(error, trim(buf), stickslip_stat%input)
                    return
                end if
                if (model%contact_dof2(j) < 0 .or. model%contact_dof2(j) > n) then
                    write (buf, '(a,i0,a,i0,a,i0,a)') "model%contact_dof2(", j, ") = ", &
                        model%contact_dof2(j), ": must be 0 (ground) or a DOF in 1..", n, &
                        " (ndof)"
                    call fatal_error(error, trim(buf), stickslip_stat%input)
                    return
                end if
                if (model%contact_dof2(j) == model%contact_dof(j)) then
                    write (buf, '(a,i0,a)') "model%contact_dof2(", j, &
                        "): equals model%contact_dof: a contact needs two different DOFs or "// &
                        "the ground (0)"
                    call fatal_error(error, trim(buf), stickslip_stat%input)
                    return
                end if
            end if
            if (.not. finite(model%mu(j)) .or. model%mu(j) < 0.0_dp) then
                write (buf, '(a,i0,a,g0.6,a)') "model%mu(", j, ") = ", model%mu(j), &
                    ": must be finite and >= 0"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
            if (.not. finite(model%normal_load(j)) .or. model%normal_load(j) < 0.0_dp) then
                write (buf, '(a,i0,a,g0.6,a)') "model%normal_load(", j, ") = ", &
                    model%normal_load(j), ": must be finite and >= 0"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
        end do
        call check_contact_laws(error)
        if (allocated(error)) return
        call check_explicit_laws(error)

    contains

        !> The explicit laws: one slot per contact (or none); an element's own parameters
        !> (its validate); no array law beside it.
        subroutine check_explicit_laws(error)
            type(error_type), allocatable, intent(out) :: error
            integer :: q
            if (.not. allocated(model%laws)) return
            if (size(model%laws) == 0) return
            if (size(model%laws) /= model%ncontact()) then
                call fatal_error(error, "model%laws: "//itoa(size(model%laws))//" slots, "// &
                                 "expected one per contact ("//itoa(model%ncontact())//")", &
                                 stickslip_stat%input)
                return
            end if
            do q = 1, size(model%laws)
                if (.not. allocated(model%laws(q)%e)) cycle
                if (is_unilateral(model, q) .or. is_planar(model, q) .or. &
                    tangential_stiffness_of(model, q) /= 0.0_dp) then
                    call fatal_error(error, "model%laws("//itoa(q)//"): contact "//itoa(q)// &
                                     " has the law '"//model%laws(q)%e%law_name()//"' and "// &
                                     "also a normal direction, a second tangent or a "// &
                                     "tangential stiffness: give one law per contact", &
                                     stickslip_stat%input)
                    return
                end if
                call model%laws(q)%e%validate(q, error)
                if (allocated(error)) return
            end do
        end subroutine check_explicit_laws

        !> The optional contact-law data: one entry per contact, finite, signs; normal and
        !> second tangential directions N x n_c; per contact, a unilateral contact has no
        !> normal_load and a gap >= 0 unless preloaded, its tangential directions are
        !> orthogonal to its normal; a contact without normal has no gap, preload or normal
        !> stiffness; a second tangential direction is orthogonal to the first and as long.
        subroutine check_contact_laws(error)
            type(error_type), allocatable, intent(out) :: error
            integer :: nc, q
            real(dp) :: w(n), nv(n), t2(n)
            nc = model%ncontact()
            call check_list("gap", model%gap, .false.)
            if (allocated(error)) return
            call check_list("preload", model%preload, .true.)
            if (allocated(error)) return
            call check_list("normal_stiffness", model%normal_stiffness, .true.)
            if (allocated(error)) return
            call check_list("tangential_stiffness", model%tangential_stiffness, .true.)
            if (allocated(error)) return
            call check_columns("normal_direction", model%normal_direction)
            if (allocated(error)) return
            call check_columns("tangent2_direction", model%tangent2_direction)
            if (allocated(error)) return
            do q = 1, nc
                w = contact_velocity_direction(model, q)
                if (is_unilateral(model, q)) then
                    nv = contact_normal_direction(model, q)
                    if (model%normal_load(q) /= 0.0_dp) then
                        call fatal_error(error, "model%normal_load("//itoa(q)//") = "// &
                                         real_text(model%normal_load(q), '(g0.6)')// &
                                         ": contact "//itoa(q)//" is unilateral (it has a "// &
                                         "normal direction): its normal force comes from "// &
                                         "its gap and preload, not from a given normal "// &
                                         "load; set it to 0", stickslip_stat%input)
                        return
                    end if
                    if (contact_gap(model, q) < 0.0_dp .and. contact_preload(model, q) == 0.0_dp) then
                        call fatal_error(error, "model%gap("//itoa(q)//") = "// &
                                         real_text(contact_gap(model, q), '(g0.6)')// &
                                         ": a negative gap (an initial interference) "// &
                                         "needs a preload: give model%preload("//itoa(q)// &
                                         ") > 0, or a gap >= 0", stickslip_stat%input)
                        return
                    end if
                    if (.not. orthogonal(w, nv)) then
                        call fatal_error(error, "model%normal_direction(:, "//itoa(q)// &
                                         "): not orthogonal to the tangential direction of "// &
                                         "contact "//itoa(q)//" (cosine "// &
                                         cosine_text(w, nv)//"): the slip directions must "// &
                                         "lie in the contact plane", stickslip_stat%input)
                        return
                    end if
                    if (is_planar(model, q)) then
                        t2 = contact_tangent2_direction(model, q)
                        if (.not. orthogonal(t2, nv)) then
                            call fatal_error(error, "model%tangent2_direction(:, "//itoa(q)// &
                                             "): not orthogonal to the normal direction of "// &
                                             "contact "//itoa(q)//" (cosine "// &
                                             cosine_text(t2, nv)//"): the slip directions "// &
                                             "must lie in the contact plane", &
                                             stickslip_stat%input)
                            return
                        end if
                    end if
                else
                    if (contact_gap(model, q) /= 0.0_dp) then
                        call no_normal("gap", q)
                        return
                    end if
                    if (contact_preload(model, q) /= 0.0_dp) then
                        call no_normal("preload", q)
                        return
                    end if
                    if (normal_stiffness_of(model, q) /= 0.0_dp) then
                        call no_normal("normal_stiffness", q)
                        return
                    end if
                end if
                if (is_planar(model, q)) then
                    t2 = contact_tangent2_direction(model, q)
                    if (.not. orthogonal(w, t2)) then
                        call fatal_error(error, "model%tangent2_direction(:, "//itoa(q)// &
                                         "): not orthogonal to the first tangential "// &
                                         "direction of contact "//itoa(q)//" (cosine "// &
                                         cosine_text(w, t2)//")", stickslip_stat%input)
                        return
                    end if
                    if (abs(norm2(t2) - norm2(w)) > 1.0e-8_dp*norm2(w)) then
                        call fatal_error(error, "model%tangent2_direction(:, "//itoa(q)// &
                                         "): length "//real_text(norm2(t2), '(g0.6)')// &
                                         " differs from the first tangential direction's "// &
                                         real_text(norm2(w), '(g0.6)')//": the friction "// &
                                         "disk needs two orthogonal directions of equal "// &
                                         "length", stickslip_stat%input)
                        return
                    end if
                end if
            end do
        end subroutine check_contact_laws

        !> A per-contact list: none, or one finite entry per contact (>= 0 when signed).
        subroutine check_list(name, a, nonnegative)
            character(len=*), intent(in) :: name
            real(dp), allocatable, intent(in) :: a(:)
            logical, intent(in) :: nonnegative
            integer :: q
            if (.not. allocated(a)) return
            if (size(a) == 0) return
            if (size(a) /= model%ncontact()) then
                call fatal_error(error, "model%"//name//": "//itoa(size(a))//" entries, "// &
                                 "expected one per contact ("//itoa(model%ncontact())//")", &
                                 stickslip_stat%input)
                return
            end if
            do q = 1, size(a)
                if (.not. finite(a(q)) .or. (nonnegative .and. a(q) < 0.0_dp)) then
                    call fatal_error(error, "model%"//name//"("//itoa(q)//") = "// &
                                     real_text(a(q), "(g0.6)")//": must be finite"// &
                                     trim(merge(" and >= 0", "         ", nonnegative)), &
                                     stickslip_stat%input)
                    return
                end if
            end do
        end subroutine check_list

        !> N x n_c directions (or none): the size and finite entries.
        subroutine check_columns(name, a)
            character(len=*), intent(in) :: name
            real(dp), allocatable, intent(in) :: a(:, :)
            if (.not. allocated(a)) return
            if (size(a) == 0) return
            if (size(a, 2) /= model%ncontact()) then
                call fatal_error(error, "model%"//name//": "//itoa(size(a, 2))//" columns, "// &
                                 "expected one per contact ("//itoa(model%ncontact())//")", &
                                 stickslip_stat%input)
                return
            end if
            call check_shape(name, a, .false., error)
        end subroutine check_columns

        subroutine no_normal(name, q)
            character(len=*), intent(in) :: name
            integer, intent(in) :: q
            call fatal_error(error, "model%"//name//"("//itoa(q)//"): contact "//itoa(q)// &
                             " has no normal direction (it carries the constant "// &
                             "normal_load): give its normal direction, or leave "//name// &
                             " at 0", stickslip_stat%input)
        end subroutine no_normal

        !> |a . b| <= 1e-8 |a| |b|.
        pure logical function orthogonal(a, b)
            real(dp), intent(in) :: a(:), b(:)
            orthogonal = abs(dot_product(a, b)) <= 1.0e-8_dp*norm2(a)*norm2(b)
        end function orthogonal

        function cosine_text(a, b) result(text)
            real(dp), intent(in) :: a(:), b(:)
            character(len=:), allocatable :: text
            text = real_text(dot_product(a, b)/(norm2(a)*norm2(b)), '(g0.6)')
        end function cosine_text

        !> An N x m matrix of directions: ndof rows, finite, (nonzero_columns) no zero column.
        subroutine check_shape(name, a, nonzero_columns, error)
            character(len=*), intent(in) :: name
            real(dp), intent(in) :: a(:, :)
            logical, intent(in) :: nonzero_columns
            type(error_type), allocatable, intent(out) :: error
            integer :: p, q
            if (size(a, 1) /= n) then
                call fatal_error(error, "model%"//name//": has "//itoa(size(a, 1))// &
                                 " rows, expected ndof = "//itoa(n), stickslip_stat%input)
                return
            end if
            do q = 1, size(a, 2)
                do p = 1, n
                    if (.not. finite(a(p, q))) then
                        call fatal_error(error, "model%"//name//"("//itoa(p)//", "// &
                                         itoa(q)//"): not a finite number (NaN or Inf)", &
                                         stickslip_stat%input)
                        return
                    end if
                end do
                if (nonzero_columns .and. all(a(:, q) == 0.0_dp)) then
                    call fatal_error(error, "model%"//name//"(:, "//itoa(q)//"): a zero "// &
                                     "column (contact "//itoa(q)//" has no direction)", &
                                     stickslip_stat%input)
                    return
                end if
                ! a direction is dimensionless, of length about 1: a length like 1e-300
                ! underflows every velocity and mobility built from it
                if (nonzero_columns .or. name == "normal_direction" .or. &
                    name == "tangent2_direction") then
                    if (any(a(:, q) /= 0.0_dp) .and. &
                        .not. (maxval(abs(a(:, q))) >= 1.0e-100_dp .and. &
                               maxval(abs(a(:, q))) <= 1.0e100_dp)) then
                        call fatal_error(error, "model%"//name//"(:, "//itoa(q)//"): largest "// &
                                         "entry "//real_text(maxval(abs(a(:, q))), &
                                                             '(es10.3e3)')//" out of scale "// &
                                         "(a direction is dimensionless, of length about 1; "// &
                                         "1e-100 .. 1e100 accepted)", &
                                         stickslip_stat%input)
                        return
                    end if
                end if
            end do
        end subroutine check_shape

        !> M symmetric positive definite, C and K square and finite.
        subroutine check_dense_matrices(error)
            type(error_type), allocatable, intent(out) :: error
            real(dp), allocatable :: chol(:, :)
            integer :: i, info
            call check_matrix("mass", model%mass, .true., error)
            if (allocated(error)) return
            call check_matrix("stiffness", model%stiffness, .false., error)
            if (allocated(error)) return
            call check_matrix("damping", model%damping, .false., error)
            if (allocated(error)) return
            do i = 1, n
                if (model%mass(i, i) <= 0.0_dp) then
                    write (buf, '(a,i0,a,i0,a,g0.6,a)') "model%mass(", i, ",", i, ") = ", &
                        model%mass(i, i), ": diagonal masses must be > 0"
                    call fatal_error(error, trim(buf), stickslip_stat%input)
                    return
                end if
            end do
            allocate (chol(n, n))
            chol = model%mass
            call dpotrf('U', n, chol, n, info)
            if (info /= 0) then
                call fatal_error(error, "model%mass: not positive definite", stickslip_stat%input)
                return
            end if
        end subroutine check_dense_matrices

        subroutine check_matrix(name, a, must_be_symmetric, error)
            character(len=*), intent(in) :: name
            real(dp), allocatable, intent(in) :: a(:, :)
            logical, intent(in) :: must_be_symmetric
            type(error_type), allocatable, intent(out) :: error
            integer :: p, q
            real(dp) :: scale
            if (.not. allocated(a)) then
                call fatal_error(error, "model%"//name//": not given", stickslip_stat%input)
                return
            end if
            if (size(a, 1) /= n .or. size(a, 2) /= n) then
                write (buf, '(a,i0,a,i0,a,i0,a)') "model%"//name//": is ", size(a, 1), " x ", &
                    size(a, 2), ", expected ndof x ndof = ", n, " squared"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
            do q = 1, n
                do p = 1, n
                    if (.not. finite(a(p, q))) then
                        write (buf, '(a,i0,a,i0,a)') "model%"//name//"(", p, ",", q, &
                            "): not a finite number (NaN or Inf)"
                        call fatal_error(error, trim(buf), stickslip_stat%input)
                        return
                    end if
                end do
            end do
            if (must_be_symmetric) then
                scale = maxval(abs(a))
                do q = 1, n
                    do p = q + 1, n
                        if (abs(a(p, q) - a(q, p)) > 1.0e-12_dp*scale) then
                            write (buf, '(a,i0,a,i0,a,g0.6,a,i0,a,i0,a,g0.6,a)') "model%"//name// &
                                ": not symmetric: model%"//name//"(", p, ",", q, ") = ", a(p, q), &
                                " but model%"//name//"(", q, ",", p, ") = ", a(q, p), &
                                " (column-major order)"
                            call fatal_error(error, trim(buf), stickslip_stat%input)
                            return
                        end if
                    end do
                end do
            end if
        end subroutine check_matrix

    end subroutine validate_model

    !> True when x is neither NaN nor infinite.
    elemental logical function finite(x)
        real(dp), intent(in) :: x
        finite = ieee_is_finite(x)
    end function finite

end module stickslip_model
