!> The only module that talks to ARPACK (system libarpack): a few eigenpairs of the
!> generalized symmetric problem K phi = lambda M phi (K symmetric, M symmetric positive
!> (semi)definite) by implicitly restarted Lanczos in shift-invert mode (dsaupd/dseupd,
!> mode 3): the eigenvalues nearest a shift sigma, through the operator (K - sigma M)^-1 M.
!>
!> The caller supplies the operator as a `shift_invert_operator_t` (solve with the
!> factorization of K - sigma M, multiply by M), typically from a sparse LU
!> (stickslip_umfpack); this module knows nothing about how the matrices are stored.
!> ARPACK's reverse communication hands the vectors back to us, so no callback thunk and no
!> module state are needed here.
!>
!> **Not thread-safe:** ARPACK's dsaupd/dseupd keep their iteration state in SAVEd local
!> variables (and timing/debug COMMON blocks) between the reverse-communication calls, so two
!> eigensolves must never run at once. Built with OpenMP, `smallest_eigenpairs` serializes
!> itself (named critical section `stickslip_arpack` around the ARPACK calls; the operator's
!> callbacks run inside it, so they must not start another eigensolve); built without
!> OpenMP it must be called from one thread at a time. Each call starts ARPACK afresh
!> (ido = 0), so calls one after another are independent, also after an aborted one. The
!> start vector is a fixed pseudo-random sequence, so results do not depend on earlier calls
!> or on the caller's random_number state.
module stickslip_arpack
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa
    implicit none
    private
    public :: shift_invert_operator_t, eigen_options_t, eigen_report_t, smallest_eigenpairs, &
        arpack_info_text

    !> The two products ARPACK needs in shift-invert mode. Implementations own their
    !> factorization and work arrays (one instance per thread).
    type, abstract :: shift_invert_operator_t
    contains
        !> y = (K - sigma M)^-1 x.
        procedure(apply_iface), deferred :: solve_shifted
        !> y = M x.
        procedure(apply_iface), deferred :: apply_mass
    end type shift_invert_operator_t

    abstract interface
        !> Apply a linear operator: y = A x. Set stat /= 0 to stop the eigensolver.
        subroutine apply_iface(self, x, y, stat)
            import :: shift_invert_operator_t, dp
            !> The operator.
            class(shift_invert_operator_t), intent(inout) :: self
            !> Input vector, size n.
            real(dp), intent(in) :: x(:)
            !> Result, size n.
            real(dp), intent(out) :: y(:)
            !> Status: leave 0 to continue, set nonzero to stop.
            integer, intent(inout) :: stat
        end subroutine apply_iface
    end interface

    !> Options of the Lanczos iteration (defaults are ARPACK's usual choices).
    type :: eigen_options_t
        !> Relative accuracy of the Ritz values (ARPACK's tol); 0: machine precision.
        real(dp) :: tol = 0.0_dp
        !> Maximum implicit restarts (ARPACK's iparam(3)); 0: max(300, 10 nev).
        integer :: maxiter = 0
        !> Lanczos basis size (ARPACK's ncv, nev < ncv <= n); 0: min(n, max(2 nev + 1, nev + 20)).
        integer :: ncv = 0
    end type eigen_options_t

    !> What one eigensolve did.
    type :: eigen_report_t
        !> Converged Ritz values (iparam(5)).
        integer :: converged = 0
        !> Implicit restarts done (iparam(3) on return).
        integer :: iterations = 0
        !> Applications of the operator OP (iparam(9)).
        integer :: op_applications = 0
        !> Lanczos basis size used.
        integer :: ncv = 0
        !> Last ARPACK info (dsaupd, or dseupd if dsaupd succeeded).
        integer :: info = 0
        !> Block solves when stickslip_sparse_eigen ran its block Lanczos instead (0: ARPACK).
        integer :: block_solves = 0
    end type eigen_report_t

    interface
        !> ARPACK dsaupd: reverse-communication implicitly restarted Lanczos (legacy Fortran).
        subroutine dsaupd(ido, bmat, n, which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, &
                          workd, workl, lworkl, info)
            import :: dp
            integer, intent(inout) :: ido
            character(len=1), intent(in) :: bmat
            integer, intent(in) :: n
            character(len=2), intent(in) :: which
            integer, intent(in) :: nev
            real(dp), intent(inout) :: tol
            real(dp), intent(inout) :: resid(n)
            integer, intent(in) :: ncv, ldv
            real(dp), intent(inout) :: v(ldv, ncv)
            integer, intent(inout) :: iparam(11)
            integer, intent(inout) :: ipntr(11)
            real(dp), intent(inout) :: workd(3*n)
            integer, intent(in) :: lworkl
            real(dp), intent(inout) :: workl(lworkl)
            integer, intent(inout) :: info
        end subroutine dsaupd

        !> ARPACK dseupd: Ritz values and vectors after dsaupd converged (legacy Fortran).
        subroutine dseupd(rvec, howmny, select, d, z, ldz, sigma, bmat, n, which, nev, tol, &
                          resid, ncv, v, ldv, iparam, ipntr, workd, workl, lworkl, info)
            import :: dp
            logical, intent(in) :: rvec
            character(len=1), intent(in) :: howmny
            integer, intent(in) :: ncv
            logical, intent(inout) :: select(ncv)
            integer, intent(in) :: nev
            real(dp), intent(out) :: d(nev)
            integer, intent(in) :: ldz
            real(dp), intent(out) :: z(ldz, nev)
            real(dp), intent(in) :: sigma
            character(len=1), intent(in) :: bmat
            integer, intent(in) :: n
            character(len=2), intent(in) :: which
            real(dp), intent(in) :: tol
            real(dp), intent(inout) :: resid(n)
            integer, intent(in) :: ldv
            real(dp), intent(inout) :: v(ldv, ncv)
            integer, intent(inout) :: iparam(11)
            integer, intent(inout) :: ipntr(11)
            real(dp), intent(inout) :: workd(2*n)
            integer, intent(in) :: lworkl
            real(dp), intent(inout) :: workl(lworkl)
            integer, intent(inout) :: info
        end subroutine dseupd
    end interface

contains

    !> A person's reading of an ARPACK info code of dsaupd (`routine = "dsaupd"`) or dseupd.
    pure function arpack_info_text(routine, info) result(text)
        !> "dsaupd" or "dseupd".
        character(len=*), intent(in) :: routine
        !> The info returned.
        integer, intent(in) :: info
        character(len=:), allocatable :: text
        select case (info)
        case (0)
            text = "normal exit"
        case (1)
            text = "maximum number of restarts reached before all eigenvalues converged"
        case (3)
            text = "no shifts could be applied in a restart (increase ncv)"
        case (-1)
            text = "n must be positive"
        case (-2)
            text = "nev must be positive"
        case (-3)
            text = "ncv must satisfy nev < ncv <= n"
        case (-4)
            text = "the maximum number of restarts must be positive"
        case (-5)
            text = "invalid 'which'"
        case (-6)
            text = "bmat must be 'I' or 'G'"
        case (-7)
            text = "workl is too short"
        case (-8)
            text = "the tridiagonal eigenvalue computation (LAPACK dsteqr) failed"
        case (-9)
            text = "the starting vector is zero (or in the null space of OP)"
        case (-10)
            text = "iparam(7) (mode) must be 1 to 5"
        case (-11)
            text = "mode 1 and bmat = 'G' are incompatible"
        case (-12)
            if (routine == "dsaupd") then
                text = "iparam(1) must be 0 or 1"
            else
                text = "nev and which = 'BE' are incompatible"
            end if
        case (-13)
            text = "nev and which = 'BE' are incompatible"
        case (-14)
            text = "dsaupd found no eigenvalue to sufficient accuracy"
        case (-15)
            text = "howmny must be 'A' or 'S'"
        case (-16)
            text = "howmny = 'S' is not implemented"
        case (-17)
            text = "dseupd counted a different number of converged Ritz values than dsaupd"
        case (-9999)
            text = "could not build a Lanczos factorization (increase ncv)"
        case default
            text = "unknown ARPACK info"
        end select
        text = routine//": "//text//" (info "//itoa(info)//")"
    end function arpack_info_text

    !> The nev eigenpairs of K phi = lambda M phi nearest the shift sigma, by shift-invert
    !> Lanczos: with sigma below the spectrum (sigma = 0 for a structure fixed against rigid
    !> motion, sigma slightly negative for a free one) they are the nev smallest. values are
    !> returned ascending and the vectors M-orthonormal (phi_i^T M phi_j = delta_ij).
    !> Errors: bad sizes or options (input), an operator that stopped (callback), fewer than
    !> nev converged or any other ARPACK failure (numerical; the message gives ARPACK's
    !> reading of its info code). Concurrent calls are serialized with OpenMP and forbidden
    !> without it (see the module header).
    subroutine smallest_eigenpairs(op, n, nev, sigma, opts, values, vectors, report, error)
        !> The operator: (K - sigma M)^-1 x and M x.
        class(shift_invert_operator_t), intent(inout) :: op
        !> Order of K and M.
        integer, intent(in) :: n
        !> Number of eigenpairs wanted, 1 <= nev < n.
        integer, intent(in) :: nev
        !> The shift the operator was factorized at [same units as lambda, e.g. rad^2/s^2].
        real(dp), intent(in) :: sigma
        !> Iteration options (`eigen_options_t()` for ARPACK's defaults).
        type(eigen_options_t), intent(in) :: opts
        !> Eigenvalues lambda, ascending (size nev).
        real(dp), allocatable, intent(out) :: values(:)
        !> Eigenvectors, n x nev, M-orthonormal; column j belongs to values(j).
        real(dp), allocatable, intent(out) :: vectors(:, :)
        !> Counts of the run.
        type(eigen_report_t), intent(out) :: report
        !> Error (last).
        type(error_type), allocatable, intent(out) :: error
        integer :: ncv, maxiter, stage, stat, i, j
        integer, allocatable :: perm(:)
        real(dp), allocatable :: d(:), z(:, :)

        if (n < 2) then
            call fatal_error(error, "eigenpairs: n = "//itoa(n)//": must be >= 2", &
                             stickslip_stat%input)
            return
        end if
        if (nev < 1 .or. nev >= n) then
            call fatal_error(error, "eigenpairs: nev = "//itoa(nev)//": must be in 1.." &
                             //itoa(n - 1)//" (ARPACK needs nev < n)", stickslip_stat%input)
            return
        end if
        ncv = opts%ncv
        if (ncv == 0) ncv = min(n, max(2*nev + 1, nev + 20))
        if (ncv <= nev .or. ncv > n) then
            call fatal_error(error, "eigenpairs: opts%ncv = "//itoa(ncv)//": must satisfy nev = " &
                             //itoa(nev)//" < ncv <= n = "//itoa(n), stickslip_stat%input)
            return
        end if
        if (opts%maxiter < 0 .or. .not. (opts%tol >= 0.0_dp)) then
            call fatal_error(error, "eigenpairs: opts%maxiter and opts%tol must be >= 0", &
                             stickslip_stat%input)
            return
        end if
        report%ncv = ncv
        maxiter = opts%maxiter
        if (maxiter == 0) maxiter = max(300, 10*nev)
        allocate (d(nev), z(n, nev))
        ! ARPACK keeps SAVEd state between its reverse-communication calls: with OpenMP,
        ! concurrent eigensolves are serialized here (no early exit may leave this block)
        !$omp critical (stickslip_arpack)
        call run_lanczos(op, n, nev, sigma, ncv, maxiter, opts%tol, d, z, report, stage, stat)
        !$omp end critical (stickslip_arpack)
        select case (stage)
        case (-1)
            call fatal_error(error, "eigenpairs: dsaupd asked for ido = "//itoa(report%info) &
                             //" (not used in mode 3)", stickslip_stat%internal)
            return
        case (0)
            call fatal_error(error, "eigenpairs: the operator stopped the iteration (status " &
                             //itoa(stat)//")", stickslip_stat%callback)
            return
        case (1)
            if (report%info == 1) then
                call fatal_error(error, "eigenpairs: "//itoa(report%converged)//" of " &
                                 //itoa(nev)//" eigenvalues converged: " &
                                 //arpack_info_text("dsaupd", report%info) &
                                 //"; raise opts%maxiter or opts%ncv", stickslip_stat%numerical)
                return
            end if
            if (report%info /= 0) then
                call fatal_error(error, "eigenpairs: "//arpack_info_text("dsaupd", report%info), &
                                 info_category(report%info))
                return
            end if
        case (2)
            if (report%info /= 0) then
                call fatal_error(error, "eigenpairs: "//arpack_info_text("dseupd", report%info), &
                                 info_category(report%info))
                return
            end if
        end select
        if (report%converged < nev) then
            call fatal_error(error, "eigenpairs: only "//itoa(report%converged)//" of " &
                             //itoa(nev)//" eigenvalues converged; raise opts%maxiter or " &
                             //"opts%ncv", stickslip_stat%numerical)
            return
        end if
        ! sort ascending by a permutation (dseupd returns the Ritz values of OP ascending, that
        ! is lambda descending above sigma), then one gather of the vectors
        allocate (perm(nev))
        perm = [(i, i=1, nev)]
        do i = 2, nev
            j = i - 1
            do while (j >= 1)
                if (d(perm(j)) <= d(perm(j + 1))) exit
                perm([j, j + 1]) = perm([j + 1, j])
                j = j - 1
            end do
        end do
        allocate (values(nev), vectors(n, nev))
        values = d(perm)
        do i = 1, nev
            vectors(:, i) = z(:, perm(i))
        end do
    end subroutine smallest_eigenpairs

    !> The ARPACK calls of one eigensolve (dsaupd's reverse-communication loop, then dseupd),
    !> with no early exit so that the caller can hold a critical section around it. stage on
    !> return: -1 unexpected ido (in report%info), 0 the operator stopped (stat), 1 dsaupd
    !> failed (report%info), 2 dseupd ran (report%info its info).
    subroutine run_lanczos(op, n, nev, sigma, ncv, maxiter, tol_in, d, z, report, stage, stat)
        class(shift_invert_operator_t), intent(inout) :: op
        integer, intent(in) :: n, nev, ncv, maxiter
        real(dp), intent(in) :: sigma, tol_in
        real(dp), intent(out) :: d(nev), z(n, nev)
        type(eigen_report_t), intent(inout) :: report
        integer, intent(out) :: stage, stat
        integer :: ido, lworkl, info, iparam(11), ipntr(11), i
        real(dp) :: tol, tmpv
        real(dp), allocatable :: resid(:), v(:, :), workd(:), workl(:), tmp(:)
        logical, allocatable :: select(:)
        lworkl = ncv*(ncv + 8)
        allocate (resid(n), v(n, ncv), workd(3*n), workl(lworkl), tmp(n), select(ncv))
        ! a fixed start vector with no structure (golden-ratio sequence), so that no
        ! symmetric or antisymmetric mode is missed and the result is reproducible
        do i = 1, n
            tmpv = real(i, dp)*0.6180339887498949_dp
            resid(i) = tmpv - aint(tmpv) - 0.5_dp
        end do
        iparam = 0
        iparam(1) = 1                                   ! exact shifts
        iparam(3) = maxiter
        iparam(7) = 3                                   ! shift-invert, generalized
        ipntr = 0
        tol = tol_in
        ido = 0
        info = 1                                        ! resid holds the start vector
        stat = 0
        stage = 1
        do
            call dsaupd(ido, 'G', n, 'LM', nev, tol, resid, ncv, v, n, iparam, ipntr, workd, &
                        workl, lworkl, info)
            select case (ido)
            case (-1)
                ! y = OP x = (K - sigma M)^-1 M x (x at ipntr(1), y at ipntr(2))
                call op%apply_mass(workd(ipntr(1):ipntr(1) + n - 1), tmp, stat)
                if (stat == 0) call op%solve_shifted(tmp, workd(ipntr(2):ipntr(2) + n - 1), stat)
            case (1)
                ! y = (K - sigma M)^-1 (M x), M x already at ipntr(3)
                call op%solve_shifted(workd(ipntr(3):ipntr(3) + n - 1), &
                                      workd(ipntr(2):ipntr(2) + n - 1), stat)
            case (2)
                ! y = M x
                call op%apply_mass(workd(ipntr(1):ipntr(1) + n - 1), &
                                   workd(ipntr(2):ipntr(2) + n - 1), stat)
            case (99)
                exit
            case default
                stage = -1
                info = ido
                exit
            end select
            if (stat /= 0) then
                stage = 0
                exit
            end if
        end do
        report%info = info
        report%iterations = iparam(3)
        report%converged = iparam(5)
        report%op_applications = iparam(9)
        if (stage /= 1 .or. info /= 0) return
        stage = 2
        select = .true.
        call dseupd(.true., 'A', select, d, z, n, sigma, 'G', n, 'LM', nev, tol, resid, ncv, v, &
                    n, iparam, ipntr, workd, workl, lworkl, info)
        report%info = info
        if (info == 0) report%converged = iparam(5)
    end subroutine run_lanczos

    !> Error category of an ARPACK info: argument errors are ours (internal, since they are
    !> checked before the call), the rest numerical.
    pure integer function info_category(info) result(stat)
        integer, intent(in) :: info
        select case (info)
        case (-7, -6, -5, -4, -3, -2, -1, -10, -11, -12, -13, -15, -16)
            stat = stickslip_stat%internal
        case default
            stat = stickslip_stat%numerical
        end select
    end function info_category
end module stickslip_arpack
