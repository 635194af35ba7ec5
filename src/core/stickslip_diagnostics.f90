!> What the checks of a result found: notes (information), warnings (the result is usable but
!> doubtful: a check failed its threshold) and distrust (the result cannot be trusted).
!> Plain data filled by the methods and analyses; the summary writer turns every item into a
!> key, the command line prints warnings as `stickslip: warning: ...` lines on standard
!> error and exits 2 on distrust. Knows nothing of files or units.
module stickslip_diagnostics
    implicit none
    private
    public :: diagnosis_t, diagnostics_t, level_note, level_warning, level_untrusted

    !> Information: printed on the human summary only.
    integer, parameter :: level_note = 1
    !> A check failed its threshold: the result is written, a warning goes to standard error.
    integer, parameter :: level_warning = 2
    !> The result cannot be trusted: written with the diagnosis, exit code 2.
    integer, parameter :: level_untrusted = 3

    !> One finding.
    type :: diagnosis_t
        !> level_note, level_warning or level_untrusted.
        integer :: level = level_note
        !> Short identifier, a valid namelist name (e.g. 'energy_balance', 'truncation').
        character(len=:), allocatable :: key
        !> One line of text for a person, without the 'stickslip: warning: ' prefix.
        character(len=:), allocatable :: message
    end type diagnosis_t

    !> The findings about one result, in the order found.
    type :: diagnostics_t
        type(diagnosis_t), allocatable :: items(:)
    contains
        !> Add a finding.
        procedure :: add => diagnostics_add
        !> Number of findings of a level.
        procedure :: count => diagnostics_count
        !> Highest level found (0 when none).
        procedure :: worst => diagnostics_worst
        !> Whether a finding with this key was added.
        procedure :: has => diagnostics_has
        !> Append every finding of another list.
        procedure :: extend => diagnostics_extend
    end type diagnostics_t

contains

    !> Add the finding (`level`, `key`, `message`).
    pure subroutine diagnostics_add(self, level, key, message)
        !> The list.
        class(diagnostics_t), intent(inout) :: self
        !> level_note, level_warning or level_untrusted.
        integer, intent(in) :: level
        !> Short identifier (a valid namelist name).
        character(len=*), intent(in) :: key
        !> The text.
        character(len=*), intent(in) :: message
        type(diagnosis_t) :: item
        item%level = level
        item%key = key
        item%message = message
        if (.not. allocated(self%items)) allocate (self%items(0))
        self%items = [self%items, item]
    end subroutine diagnostics_add

    !> Number of findings of `level`.
    pure integer function diagnostics_count(self, level) result(n)
        !> The list.
        class(diagnostics_t), intent(in) :: self
        !> The level counted.
        integer, intent(in) :: level
        integer :: k
        n = 0
        if (.not. allocated(self%items)) return
        do k = 1, size(self%items)
            if (self%items(k)%level == level) n = n + 1
        end do
    end function diagnostics_count

    !> Highest level found, 0 when the list is empty.
    pure integer function diagnostics_worst(self) result(level)
        !> The list.
        class(diagnostics_t), intent(in) :: self
        integer :: k
        level = 0
        if (.not. allocated(self%items)) return
        do k = 1, size(self%items)
            level = max(level, self%items(k)%level)
        end do
    end function diagnostics_worst

    !> Whether a finding with `key` is in the list.
    pure logical function diagnostics_has(self, key) result(found)
        !> The list.
        class(diagnostics_t), intent(in) :: self
        !> The key looked for.
        character(len=*), intent(in) :: key
        integer :: k
        found = .false.
        if (.not. allocated(self%items)) return
        do k = 1, size(self%items)
            if (self%items(k)%key == key) found = .true.
        end do
    end function diagnostics_has

    !> Append every finding of `other`, each key prefixed with `prefix` when given (e.g.
    !> 'hbm_' when a side-by-side result gathers the findings of its methods).
    pure subroutine diagnostics_extend(self, other, prefix)
        !> The list.
        class(diagnostics_t), intent(inout) :: self
        !> The findings appended.
        type(diagnostics_t), intent(in) :: other
        !> Prefix of the appended keys.
        character(len=*), intent(in), optional :: prefix
        integer :: k
        if (.not. allocated(other%items)) return
        do k = 1, size(other%items)
            if (present(prefix)) then
                call self%add(other%items(k)%level, prefix//other%items(k)%key, &
                              other%items(k)%message)
            else
                call self%add(other%items(k)%level, other%items(k)%key, other%items(k)%message)
            end if
        end do
    end subroutine diagnostics_extend
end module stickslip_diagnostics
