!> The command line of app/ (app/stickslip_cli.inc) compiled into the test driver as module
!> test_app_cli, so that the tests run it in-process: fpm 0.12 resolves a test's modules only
!> in test/ and refuses one module name in two files.
module test_app_cli
    use stickslip_driver, only: run_method
    include '../app/stickslip_cli.inc'
end module test_app_cli
