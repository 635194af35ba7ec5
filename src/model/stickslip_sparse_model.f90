!> A structure kept sparse: the full model of an FE code (N up to ~1e5 DOFs), condensed
!> exactly per harmonic by sparse factorizations (stickslip_sparse_dynamics) instead of being
!> reduced. It holds a `model_t` for everything but the matrices (ndof, omega, forcing,
!> contacts, friction; its dense mass, stiffness and damping stay unallocated) and the sparse
!> M, K, C. The contact directions W and the load vectors F_h are built in ONE place each
!> (sparse_directions, sparse_load), from contact_velocity_direction and the forcing arrays
!> of model_t. Plain data and validation: no solver, no file.
module stickslip_sparse_model
    use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    use stickslip_model, only: model_t, validate_model, force_direction, preload_force
    use stickslip_contact_set, only: contact_set_t, new_contact_set, channel_directions
    use stickslip_sparse, only: sparse_matrix_t, sparse_symmetry_defect
    implicit none
    private
    public :: sparse_model_t, validate_sparse_model, sparse_directions, sparse_load

    !> A model with sparse matrices.
    type :: sparse_model_t
        !> ndof, omega, forcing, contacts and friction (dense matrices unallocated).
        type(model_t) :: model
        !> Mass matrix M (N x N, full storage), symmetric, positive diagonal [kg].
        type(sparse_matrix_t) :: mass
        !> Stiffness matrix K (N x N, full storage) [N/m].
        type(sparse_matrix_t) :: stiffness
        !> Viscous damping matrix C (N x N, full storage; 0 x 0 or no entries: undamped)
        !> [N s/m].
        type(sparse_matrix_t) :: damping
    end type sparse_model_t

contains

    !> Check a sparse model: the model_t data (validate_model without its dense matrices),
    !> M and K N x N, C N x N or empty, every value finite, M symmetric (to 1e-12 of its
    !> largest entry) with a positive diagonal. (That M is positive definite is found by the
    !> factorization of stickslip_sparse_dynamics.) Errors: stat input, naming the component
    !> ("smodel%mass: 10 x 12, expected ndof x ndof = 10 squared").
    subroutine validate_sparse_model(smodel, error)
        !> The model to check.
        type(sparse_model_t), intent(in) :: smodel
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer :: n, i, p
        logical :: found
        call validate_model(smodel%model, error, dense=.false.)
        if (allocated(error)) return
        n = smodel%model%ndof
        call check_matrix("mass", smodel%mass, .false.)
        if (allocated(error)) return
        call check_matrix("stiffness", smodel%stiffness, .false.)
        if (allocated(error)) return
        call check_matrix("damping", smodel%damping, .true.)
        if (allocated(error)) return
        if (.not. (sparse_symmetry_defect(smodel%mass) <= 1.0e-12_dp)) then
            call fatal_error(error, "smodel%mass: not symmetric", stickslip_stat%input)
            return
        end if
        do i = 1, n
            found = .false.
            do p = smodel%mass%row_start(i), smodel%mass%row_start(i + 1) - 1
                if (smodel%mass%col(p) == i) then
                    found = smodel%mass%val(p) > 0.0_dp
                    exit
                end if
            end do
            if (.not. found) then
                call fatal_error(error, "smodel%mass("//itoa(i)//","//itoa(i)// &
                                 "): diagonal masses must be > 0", stickslip_stat%input)
                return
            end if
        end do

    contains

        subroutine check_matrix(name, a, may_be_empty)
            character(len=*), intent(in) :: name
            type(sparse_matrix_t), intent(in) :: a
            logical, intent(in) :: may_be_empty
            if (may_be_empty .and. a%nnz() == 0) return
            if (a%nrows /= n .or. a%ncols /= n .or. .not. allocated(a%row_start)) then
                call fatal_error(error, "smodel%"//name//": "//itoa(a%nrows)//" x "// &
                                 itoa(a%ncols)//", expected ndof x ndof = "//itoa(n)// &
                                 " squared", stickslip_stat%input)
                return
            end if
            if (a%nnz() > 0) then
                if (.not. all(ieee_is_finite(a%val))) then
                    call fatal_error(error, "smodel%"//name//": not a finite number (NaN "// &
                                     "or Inf)", stickslip_stat%input)
                    return
                end if
            end if
        end subroutine check_matrix
    end subroutine validate_sparse_model

    !> The contact directions W (N x n_c): column j is the direction whose velocity is
    !> contact j's slip velocity (contact_velocity_direction). The one place the sparse
    !> condensation builds W.
    function sparse_directions(smodel) result(w)
        !> A validated sparse model.
        type(sparse_model_t), intent(in) :: smodel
        real(dp), allocatable :: w(:, :)
        type(contact_set_t) :: cs
        call new_contact_set(cs, smodel%model)
        w = channel_directions(smodel%model, cs)
    end function sparse_directions

    !> The complex load amplitude F_h (size N) of harmonic h: the forcing terms of that
    !> harmonic, amplitude * exp(i phase) times their load shape (force_direction: a DOF or a
    !> force_shape column; f(t) = Re(F_h exp(i h omega t))) [N].
    !> The one place the sparse condensation builds F_h.
    function sparse_load(smodel, h) result(f)
        !> A validated sparse model.
        type(sparse_model_t), intent(in) :: smodel
        !> Harmonic (>= 0).
        integer, intent(in) :: h
        complex(dp), allocatable :: f(:)
        integer :: i
        allocate (f(smodel%model%ndof))
        f = (0.0_dp, 0.0_dp)
        associate (m => smodel%model)
            do i = 1, m%nforce()
                if (m%force_harmonic(i) == h) f = f + m%force_amplitude(i)* &
                    exp(cmplx(0.0_dp, m%force_phase(i), dp))*force_direction(m, i)
            end do
            ! the static preload of the unilateral contacts (zero for a plain model)
            if (h == 0) f = f + preload_force(m)
        end associate
    end function sparse_load
end module stickslip_sparse_model
