!> stickslip_diagnostics: findings kept in order with their level, key and message; count,
!> worst and has on empty and filled lists; extend with and without a key prefix.
module test_diagnostics
    use stickslip_diagnostics, only: diagnostics_t, level_note, level_warning, level_untrusted
    use testing, only: test_counter_t, check
    implicit none
    private
    public :: run_diagnostics_tests

contains

    subroutine run_diagnostics_tests(t)
        type(test_counter_t), intent(inout) :: t
        type(diagnostics_t) :: d, e, all
        call check(t, d%worst() == 0 .and. d%count(level_note) == 0 .and. .not. d%has("x"), &
                   "diagnostics: an empty list has nothing")
        call check(t, level_note < level_warning .and. level_warning < level_untrusted, &
                   "diagnostics: levels ordered note < warning < untrusted")
        call d%add(level_note, "truncation", "estimate 1e-3")
        call d%add(level_warning, "energy_balance", "energy balance off by 5%")
        call d%add(level_note, "rho", "automatic rho 0.04")
        call check(t, size(d%items) == 3, "diagnostics: three findings")
        call check(t, d%items(2)%key == "energy_balance" .and. d%items(2)%level == level_warning &
                   .and. d%items(2)%message == "energy balance off by 5%", &
                   "diagnostics: a finding keeps its level, key and message, in order")
        call check(t, d%count(level_note) == 2 .and. d%count(level_warning) == 1 .and. &
                   d%count(level_untrusted) == 0, "diagnostics: count per level")
        call check(t, d%worst() == level_warning, "diagnostics: worst is the warning")
        call check(t, d%has("rho") .and. .not. d%has("rh") .and. .not. d%has("rho_x"), &
                   "diagnostics: has matches whole keys")
        call e%add(level_untrusted, "disagreement", "methods disagree by 250%")
        all = d
        call all%extend(e, prefix="hbm_")
        call check(t, size(all%items) == 4 .and. all%has("hbm_disagreement") .and. &
                   .not. all%has("disagreement"), "diagnostics: extend prefixes the keys")
        call check(t, all%worst() == level_untrusted, "diagnostics: worst after extend")
        call check(t, size(d%items) == 3, "diagnostics: extend leaves the source list alone")
        call all%extend(e)
        call check(t, all%has("disagreement") .and. all%count(level_untrusted) == 2, &
                   "diagnostics: extend without a prefix keeps the keys")
        call all%extend(diagnostics_t())
        call check(t, size(all%items) == 5, "diagnostics: extending by an empty list adds nothing")
    end subroutine run_diagnostics_tests
end module test_diagnostics
