!> The &microslip group of a case file: contacts of &friction that are microslip joints, the
!> discrete Iwan element of stickslip_iwan_element (doc/contacts.md, "The microslip (Iwan)
!> element"; doc/case-file.md).
!>
!>     contact   the &friction contacts (1-based) that are microslip joints (one or more)
!>     stiffness the joint's stiffness K_T [N/m], one per listed contact (4-parameter form)
!>     chi       the exponent of the slip-force density, in (-1, 0] (default -0.5)
!>     beta      the ratio of the slip force held by the last slider, >= 0 (default 0)
!>     sliders   sliders per listed contact, >= 1 (default 20)
!> The macroslip force is F_S = mu N of the contact in &friction (mu and normal_load: the
!> joint's friction coefficient and its normal load, which sweeps of mu and normal_load
!> move). Or an explicit list of sliders instead of stiffness, chi and beta:
!>     slider_stiffness, slider_force   k_i [N/m] and f_i [N] (f increasing), the sliders of
!>                                      the listed contacts one after the other, `sliders`
!>                                      of each (required for more than one contact)
!> with mu = 0 and normal_load = 0 for those contacts in &friction (F_S = sum f_i).
!> Every message names the case file, &microslip and the variable.
module stickslip_case_microslip
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, itoa, real_text
    use stickslip_model, only: model_t, is_unilateral, is_planar, tangential_stiffness_of
    use stickslip_namelist, only: nml_file_t
    use stickslip_namelist_values, only: check_names, get_integers, get_reals
    use stickslip_case_model, only: group_error, max_terms
    use stickslip_iwan_element, only: new_iwan_element, new_iwan_element_4p
    implicit none
    private
    public :: read_microslip_group, microslip_variables

    !> The variables of &microslip.
    character(len=*), parameter :: microslip_variables(7) = [character(len=16) :: &
        "contact", "stiffness", "chi", "beta", "sliders", "slider_stiffness", "slider_force"]

contains

    !> Read &microslip (optional) into model%laws for the &friction contacts it lists (the
    !> model's contacts read). Errors (stat input) name the file, the group and the
    !> variable: an unknown or misspelled variable, a contact out of range or listed twice,
    !> a contact with a normal direction, a second tangent or a tangential stiffness, lists
    !> of the wrong length, K_T <= 0, chi out of (-1, 0], beta < 0, sliders < 1, mu N = 0 in
    !> the 4-parameter form or not 0 in the explicit form, k_i <= 0, f_i <= 0, slip forces
    !> not increasing.
    subroutine read_microslip_group(nml, model, error)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model: its contacts read; laws set for the microslip contacts.
        type(model_t), intent(inout) :: model
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer, allocatable :: contact(:), sliders(:)
        real(dp), allocatable :: kt(:), chi(:), beta(:), ks(:), fs(:)
        logical :: found, explicit, given_k, given_f
        integer :: m, k, j, i, first, nc
        if (nml%find("microslip") == 0) return
        call check_names(nml, "microslip", microslip_variables, error)
        if (allocated(error)) return
        call get_integers(nml, "microslip", "contact", contact, found, max_terms, error)
        if (allocated(error)) return
        if (.not. found .or. size(contact) == 0) then
            call group_error(nml, error, "&microslip contact: missing (the &friction contacts "// &
                             "that are microslip joints)")
            return
        end if
        m = size(contact)
        nc = model%ncontact()
        do k = 1, m
            j = contact(k)
            if (j < 1 .or. j > nc) then
                call group_error(nml, error, "&microslip contact("//itoa(k)//") = "//itoa(j)// &
                                 ": not a contact of &friction (1.."//itoa(nc)//")")
                return
            end if
            if (count(contact == j) > 1) then
                call group_error(nml, error, "&microslip contact("//itoa(k)//") = "//itoa(j)// &
                                 ": listed twice")
                return
            end if
            if (is_unilateral(model, j) .or. is_planar(model, j) .or. &
                tangential_stiffness_of(model, j) /= 0.0_dp) then
                call group_error(nml, error, "&microslip contact("//itoa(k)//") = "//itoa(j)// &
                                 ": contact "//itoa(j)//" also has a normal direction, a "// &
                                 "second tangent or a tangential_stiffness in &friction; a "// &
                                 "microslip joint is 1D under its own slip forces")
                return
            end if
        end do
        call get_reals(nml, "microslip", "slider_stiffness", ks, given_k, max_terms, error)
        if (allocated(error)) return
        call get_reals(nml, "microslip", "slider_force", fs, given_f, max_terms, error)
        if (allocated(error)) return
        explicit = given_k .or. given_f
        if (explicit) then
            call read_explicit()
        else
            call read_four_parameters()
        end if

    contains

        !> The 4-parameter form: stiffness, chi, beta, sliders per contact; F_S = mu N.
        subroutine read_four_parameters()
            call per_contact("stiffness", .true., 0.0_dp, kt)
            if (allocated(error)) return
            call per_contact("chi", .false., -0.5_dp, chi)
            if (allocated(error)) return
            call per_contact("beta", .false., 0.0_dp, beta)
            if (allocated(error)) return
            call slider_counts(.false.)
            if (allocated(error)) return
            call prepare_laws()
            do k = 1, m
                j = contact(k)
                if (.not. (kt(k) > 0.0_dp .and. kt(k) <= huge(1.0_dp))) then
                    call bad("stiffness", k, kt(k), "must be finite and > 0 (the joint's "// &
                             "stiffness K_T)")
                else if (.not. (chi(k) > -1.0_dp .and. chi(k) <= 0.0_dp)) then
                    call bad("chi", k, chi(k), "must be in (-1, 0] (the exponent of the "// &
                             "slip-force density)")
                else if (.not. (beta(k) >= 0.0_dp .and. beta(k) <= huge(1.0_dp))) then
                    call bad("beta", k, beta(k), "must be finite and >= 0")
                else if (.not. (model%mu(j)*model%normal_load(j) > 0.0_dp)) then
                    call group_error(nml, error, "&microslip contact("//itoa(k)//") = "// &
                                     itoa(j)//": the macroslip force F_S = mu N of contact "// &
                                     itoa(j)//" in &friction is 0: give it mu > 0 and "// &
                                     "normal_load > 0")
                end if
                if (allocated(error)) return
                allocate (model%laws(j)%e, source=new_iwan_element_4p(0.0_dp, kt(k), chi(k), &
                          beta(k), sliders(k), mu=model%mu(j), normal_load=model%normal_load(j)))
            end do
        end subroutine read_four_parameters

        !> The explicit form: slider_stiffness and slider_force, `sliders` of each contact.
        subroutine read_explicit()
            do i = 1, size(microslip_variables)
                select case (microslip_variables(i))
                case ("stiffness", "chi", "beta")
                    call no_variable(trim(microslip_variables(i)), "the explicit form "// &
                                     "(slider_stiffness, slider_force) gives the sliders")
                    if (allocated(error)) return
                end select
            end do
            if (.not. (given_k .and. given_f)) then
                call group_error(nml, error, "&microslip "//trim(merge("slider_force    ", &
                                 "slider_stiffness", given_k))//": missing (the explicit "// &
                                 "form needs slider_stiffness and slider_force, one value per "// &
                                 "slider)")
                return
            end if
            if (size(fs) /= size(ks)) then
                call group_error(nml, error, "&microslip slider_force: "//itoa(size(fs))// &
                                 " values given, expected "//itoa(size(ks))//" (one per "// &
                                 "value of slider_stiffness)")
                return
            end if
            call slider_counts(.true.)
            if (allocated(error)) return
            if (sum(sliders) /= size(ks)) then
                call group_error(nml, error, "&microslip sliders: "//itoa(sum(sliders))// &
                                 " sliders in all, but slider_stiffness has "// &
                                 itoa(size(ks))//" values")
                return
            end if
            call prepare_laws()
            first = 0
            do k = 1, m
                j = contact(k)
                if (model%mu(j) /= 0.0_dp .or. model%normal_load(j) /= 0.0_dp) then
                    call group_error(nml, error, "&microslip contact("//itoa(k)//") = "// &
                                     itoa(j)//": the explicit sliders carry their own slip "// &
                                     "forces; give contact "//itoa(j)//" mu = 0 and "// &
                                     "normal_load = 0 in &friction")
                    return
                end if
                do i = first + 1, first + sliders(k)
                    if (.not. (ks(i) > 0.0_dp .and. ks(i) <= huge(1.0_dp))) then
                        call bad("slider_stiffness", i, ks(i), "must be finite and > 0")
                    else if (.not. (fs(i) > 0.0_dp .and. fs(i) <= huge(1.0_dp))) then
                        call bad("slider_force", i, fs(i), "must be finite and > 0")
                    else if (i > first + 1) then
                        if (.not. (fs(i) > fs(i - 1))) call bad("slider_force", i, fs(i), &
                            "the slip forces of a joint must increase (slider_force("// &
                            itoa(i - 1)//") = "//real_text(fs(i - 1), '(g0.6)')//")")
                    end if
                    if (allocated(error)) return
                end do
                allocate (model%laws(j)%e, source=new_iwan_element(ks(first + 1:first + &
                          sliders(k)), fs(first + 1:first + sliders(k))))
                first = first + sliders(k)
            end do
        end subroutine read_explicit

        !> `sliders`: one count per contact (required with several contacts in the explicit
        !> form; default 20, or all the values for one explicit contact), each >= 1.
        subroutine slider_counts(explicit_form)
            logical, intent(in) :: explicit_form
            logical :: given
            call get_integers(nml, "microslip", "sliders", sliders, given, max_terms, error)
            if (allocated(error)) return
            if (.not. given) then
                if (explicit_form .and. m > 1) then
                    call group_error(nml, error, "&microslip sliders: missing (the explicit "// &
                                     "sliders of "//itoa(m)//" contacts need each one's count)")
                    return
                end if
                allocate (sliders(m))
                sliders = 20
                if (explicit_form) sliders = size(ks)
            else if (size(sliders) /= m) then
                call group_error(nml, error, "&microslip sliders: "//itoa(size(sliders))// &
                                 " values given, expected "//itoa(m)//" (one per entry of "// &
                                 "contact)")
                return
            end if
            do k = 1, m
                if (sliders(k) < 1 .or. sliders(k) > 10000) then
                    call group_error(nml, error, "&microslip sliders("//itoa(k)//") = "// &
                                     itoa(sliders(k))//": must be in 1..10000")
                    return
                end if
            end do
        end subroutine slider_counts

        !> A real per listed contact (default when absent and not required).
        subroutine per_contact(name, required, default, a)
            character(len=*), intent(in) :: name
            logical, intent(in) :: required
            real(dp), intent(in) :: default
            real(dp), allocatable, intent(out) :: a(:)
            logical :: given
            call get_reals(nml, "microslip", name, a, given, max_terms, error)
            if (allocated(error)) return
            if (.not. given) then
                if (required) then
                    call group_error(nml, error, "&microslip "//name//": missing (one value "// &
                                     "per entry of contact)")
                    return
                end if
                allocate (a(m))
                a = default
            else if (size(a) /= m) then
                call group_error(nml, error, "&microslip "//name//": "//itoa(size(a))// &
                                 " values given, expected "//itoa(m)//" (one per entry of "// &
                                 "contact)")
            end if
        end subroutine per_contact

        !> A variable the form does not take: an error naming it.
        subroutine no_variable(name, why)
            character(len=*), intent(in) :: name, why
            real(dp), allocatable :: a(:)
            logical :: given
            call get_reals(nml, "microslip", name, a, given, max_terms, error)
            if (allocated(error)) return
            if (given) call group_error(nml, error, "&microslip "//name//": not used here ("// &
                                        why//")")
        end subroutine no_variable

        !> model%laws with one empty slot per contact.
        subroutine prepare_laws()
            if (.not. allocated(model%laws)) allocate (model%laws(nc))
        end subroutine prepare_laws

        subroutine bad(name, k, value, why)
            character(len=*), intent(in) :: name, why
            integer, intent(in) :: k
            real(dp), intent(in) :: value
            call group_error(nml, error, "&microslip "//name//"("//itoa(k)//") = "// &
                             real_text(value, '(g0.6)')//": "//why)
        end subroutine bad
    end subroutine read_microslip_group
end module stickslip_case_microslip
