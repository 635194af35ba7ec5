!> The command line: `stickslip CASE.nml [--quiet] [--help] [--version]`. Parsing and the
!> whole run take the arguments as an array and write to units the caller gives, so tests run
!> them in-process. Part of the program (app/), not of the library: it turns errors and
!> findings into exit codes and stderr lines, prints progress, and draws the pictures
!> (stickslip_gnuplot, the only code that starts a process).
!> (The code is in stickslip_cli.inc, shared with the tests: see there.)
module stickslip_cli
    use stickslip_driver, only: run_method
    include 'stickslip_cli.inc'
end module stickslip_cli
