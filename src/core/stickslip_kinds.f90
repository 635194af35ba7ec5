!> Kinds and constants shared by every stickslip module.
!> This is the leaf of the module tree: it knows nothing else.
module stickslip_kinds
    use, intrinsic :: iso_fortran_env, only: real32, real64
    implicit none
    private
    public :: dp, sp, pi, two_pi

    !> Double precision real kind used throughout stickslip.
    integer, parameter :: dp = real64
    !> Single precision, only for the factorization that preconditions the Newton steps of
    !> large systems (stickslip_newton); every residual and result is in dp.
    integer, parameter :: sp = real32
    !> pi
    real(dp), parameter :: pi = 3.141592653589793238462643383279502884_dp
    !> 2 pi
    real(dp), parameter :: two_pi = 2.0_dp*pi
end module stickslip_kinds
