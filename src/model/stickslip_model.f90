!> The mechanical model: a linear structure M x'' + C x' + K x = f(t) + W r(t) with Coulomb
!> friction contacts and harmonic forcing. Plain data plus validation; it knows nothing of
!> how the periodic solution is computed nor of files.
module stickslip_model
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_lapack, only: dpotrf
    implicit none
    private
    public :: model_t, validate_model, contact_velocity_direction

    !> A structure with friction contacts, forced at angular frequency `omega`.
    !> Field names follow the case-file namelist variables (README).
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
        !> Forcing terms: amplitude * cos(harmonic * omega * t + phase) on DOF `force_dof`.
        integer, allocatable :: force_dof(:)
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
        !> Friction coefficient of each contact (>= 0).
        real(dp), allocatable :: mu(:)
        !> Normal load of each contact (>= 0) [N].
        real(dp), allocatable :: normal_load(:)
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
        if (allocated(self%contact_dof)) ncontact = size(self%contact_dof)
    end function ncontact

    !> Number of forcing terms of the model.
    pure integer function nforce(self)
        !> The model.
        class(model_t), intent(in) :: self
        nforce = 0
        if (allocated(self%force_dof)) nforce = size(self%force_dof)
    end function nforce

    !> Column j of W: the direction whose velocity is contact j's slip velocity.
    pure function contact_velocity_direction(model, j) result(w)
        !> The model.
        type(model_t), intent(in) :: model
        !> Contact index.
        integer, intent(in) :: j
        real(dp) :: w(model%ndof)
        w = 0.0_dp
        w(model%contact_dof(j)) = 1.0_dp
        if (model%contact_dof2(j) > 0) w(model%contact_dof2(j)) = -1.0_dp
    end function contact_velocity_direction

    !> Check a model for consistency: sizes, finite values, M symmetric positive definite,
    !> C and K symmetric-shaped and finite, DOF indices in range, mu >= 0, normal loads >= 0,
    !> omega > 0. Errors (stat input) name the argument and its component, e.g.
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

        if (.not. (allocated(model%force_dof) .and. allocated(model%force_harmonic) .and. &
                   allocated(model%force_amplitude) .and. allocated(model%force_phase))) then
            call fatal_error(error, "model%force_dof, model%force_harmonic, "// &
                             "model%force_amplitude, model%force_phase: not all allocated", &
                             stickslip_stat%input)
            return
        end if
        if (any([size(model%force_harmonic), size(model%force_amplitude), &
                 size(model%force_phase)] /= size(model%force_dof))) then
            call fatal_error(error, "model%force_dof, model%force_harmonic, "// &
                             "model%force_amplitude and model%force_phase: must have the same "// &
                             "length", stickslip_stat%input)
            return
        end if
        do i = 1, size(model%force_dof)
            if (model%force_dof(i) < 1 .or. model%force_dof(i) > n) then
                write (buf, '(a,i0,a,i0,a,i0,a)') "model%force_dof(", i, ") = ", &
                    model%force_dof(i), ": must be a DOF in 1..", n, " (ndof)"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
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

        if (.not. (allocated(model%contact_dof) .and. allocated(model%contact_dof2) .and. &
                   allocated(model%mu) .and. allocated(model%normal_load))) then
            call fatal_error(error, "model%contact_dof, model%contact_dof2, model%mu, "// &
                             "model%normal_load: not all allocated", stickslip_stat%input)
            return
        end if
        if (any([size(model%contact_dof2), size(model%mu), size(model%normal_load)] &
                /= size(model%contact_dof))) then
            call fatal_error(error, "model%contact_dof, model%contact_dof2, model%mu and "// &
                             "model%normal_load: must have the same length", stickslip_stat%input)
            return
        end if
        do j = 1, size(model%contact_dof)
            if (model%contact_dof(j) < 1 .or. model%contact_dof(j) > n) then
                write (buf, '(a,i0,a,i0,a,i0,a)') "model%contact_dof(", j, ") = ", &
                    model%contact_dof(j), ": must be a DOF in 1..", n, " (ndof)"
                call fatal_error(error, trim(buf), stickslip_stat%input)
                return
            end if
            if (model%contact_dof2(j) < 0 .or. model%contact_dof2(j) > n) then
                write (buf, '(a,i0,a,i0,a,i0,a)') "model%contact_dof2(", j, ") = ", &
                    model%contact_dof2(j), ": must be 0 (ground) or a DOF in 1..", n, " (ndof)"
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

    contains

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
