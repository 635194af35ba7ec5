!> Powell's hybrid method with the factorization on LAPACK's blocked QR: the algorithm of
!> MINPACK's hybrj (dogleg steps in a trust region, Broyden rank-1 updates of the QR factors
!> between Jacobians, the same rules for the trust radius, the Jacobian refresh after two
!> failed steps, the scaling of the unknowns and the five stopping tests), with hybrj's
!> unblocked Householder QR (qrfac) and its forming of Q (qform) replaced by LAPACK's dgeqrf
!> and dorgqr on the linked BLAS. MINPACK's own dogleg, r1updt, r1mpyq and enorm do the rest
!> (system libminpack), so the iterates are hybrj's up to roundoff: same options, same report,
!> same info codes (stickslip_minpack's hybrj_options_t and hybrj_report_t).
!>
!> Why: at a few hundred unknowns hybrj spends most of a solve in qrfac + qform (about
!> 1.9 GFlop/s; MINPACK calls no BLAS); dgeqrf + dorgqr on OpenBLAS is 10x+ faster at 140
!> unknowns. The weighted-residual solve uses it for the Powell stages of its Newton path
!> (`&hbm solver = 'newton'`, or 'auto' from newton_min_unknowns); `solver = 'hybrj'` keeps
!> MINPACK's hybrj itself everywhere.
!>
!> No module state (unlike the hybrj wrapper, no callback slot): re-entrant and thread-safe.
module stickslip_powell
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat
    use stickslip_nonlinear, only: nonlinear_system_t
    use stickslip_minpack, only: hybrj_options_t, hybrj_report_t, check_hybrj_options
    use stickslip_lapack, only: dgeqrf, dorgqr
    implicit none
    private
    public :: solve_powell

    interface
        !> MINPACK: the dogleg step of the trust region of radius delta (x out).
        subroutine dogleg(n, r, lr, diag, qtb, delta, x, wa1, wa2)
            import :: dp
            integer, intent(in) :: n, lr
            real(dp), intent(in) :: r(lr), diag(n), qtb(n), delta
            real(dp), intent(out) :: x(n)
            real(dp), intent(inout) :: wa1(n), wa2(n)
        end subroutine dogleg

        !> MINPACK: the rank-1 update of the packed triangular factor (rotations out in
        !> v and w).
        subroutine r1updt(m, n, s, ls, u, v, w, sing)
            import :: dp
            integer, intent(in) :: m, n, ls
            real(dp), intent(inout) :: s(ls), v(m), w(m)
            real(dp), intent(in) :: u(m)
            logical, intent(out) :: sing
        end subroutine r1updt

        !> MINPACK: apply the rotations of r1updt to the columns of a (m x n).
        subroutine r1mpyq(m, n, a, lda, v, w)
            import :: dp
            integer, intent(in) :: m, n, lda
            real(dp), intent(inout) :: a(lda, n)
            real(dp), intent(in) :: v(n), w(n)
        end subroutine r1mpyq

        !> MINPACK: the Euclidean norm, safe from overflow and underflow.
        function enorm(n, x)
            import :: dp
            integer, intent(in) :: n
            real(dp), intent(in) :: x(n)
            real(dp) :: enorm
        end function enorm
    end interface

contains

    !> Solve sys%residual(x) = 0 from the start x by Powell's hybrid method with the exact
    !> Jacobian and LAPACK's QR. Options and report as solve_hybrj's (xtol, maxfev, mode,
    !> factor, diag, ftarget; info 1-5, nfev, njev, fnorm, target_met). A solve that does
    !> not converge is an outcome, not an error. Errors: stat input for bad options or sizes,
    !> stat callback when the system's callback returned a nonzero status, stat lapack for a
    !> LAPACK argument error.
    subroutine solve_powell(sys, x, opts, report, error)
        !> The system F(x) = 0.
        class(nonlinear_system_t), intent(inout) :: sys
        !> Start on entry, last accepted iterate on exit (or the point that met ftarget).
        real(dp), intent(inout) :: x(:)
        !> Options (those of hybrj).
        type(hybrj_options_t), intent(in) :: opts
        !> What happened.
        type(hybrj_report_t), intent(out) :: report
        !> Set on misuse, callback failure or a LAPACK argument error.
        type(error_type), allocatable, intent(out) :: error
        real(dp), parameter :: p1 = 0.1_dp, p5 = 0.5_dp, p001 = 1.0e-3_dp, &
            p0001 = 1.0e-4_dp
        real(dp), allocatable :: fvec(:), q(:, :), diag(:), r(:), qtf(:), tau(:), work(:), &
            wa1(:), wa2(:), wa3(:), wa4(:)
        integer :: n, maxfev, lr, lwork, info, stat, iter, ncsuc, ncfail, nslow1, nslow2, &
            i, j, l
        real(dp) :: epsmch, fnorm, fnorm1, xnorm, delta, pnorm, actred, prered, ratio, &
            total, query(1)
        logical :: jeval, sing
        character(len=80) :: buf

        n = size(x)
        call check_hybrj_options(opts, n, "solve_powell", error)
        if (allocated(error)) return
        maxfev = opts%maxfev
        if (maxfev <= 0) maxfev = 200*(n + 1)
        lr = n*(n + 1)/2
        allocate (fvec(n), q(n, n), diag(n), r(lr), qtf(n), tau(n), wa1(n), wa2(n), wa3(n), &
                  wa4(n))
        call dgeqrf(n, n, q, n, tau, query, -1, info)
        lwork = max(n, int(query(1)))
        call dorgqr(n, n, n, q, n, tau, query, -1, info)
        lwork = max(lwork, int(query(1)))
        allocate (work(lwork))
        epsmch = epsilon(1.0_dp)
        if (opts%mode == 2) then
            diag = opts%diag
        else
            diag = 1.0_dp
        end if

        ! the start
        stat = 0
        call sys%residual(x, fvec, stat)
        report%nfev = 1
        if (stat /= 0) then
            call stopped_by_callback()
            return
        end if
        fnorm = enorm(n, fvec)
        report%fnorm = fnorm
        if (met_target(x, fvec, fnorm)) return
        iter = 1
        ncsuc = 0
        ncfail = 0
        nslow1 = 0
        nslow2 = 0
        xnorm = 0.0_dp
        delta = 0.0_dp
        info = 0

        outer: do
            jeval = .true.
            call sys%jacobian(x, q, stat)
            report%njev = report%njev + 1
            if (stat /= 0) then
                call stopped_by_callback()
                return
            end if
            ! column norms of the Jacobian (the scaling of mode 1), then J = Q R
            do j = 1, n
                wa2(j) = enorm(n, q(:, j))
            end do
            call dgeqrf(n, n, q, n, tau, work, lwork, info)
            if (info /= 0) then
                call lapack_error("dgeqrf")
                return
            end if
            if (iter == 1) then
                if (opts%mode /= 2) then
                    diag = wa2
                    where (wa2 == 0.0_dp) diag = 1.0_dp
                end if
                wa3 = diag*x
                xnorm = enorm(n, wa3)
                delta = opts%factor*xnorm
                if (delta == 0.0_dp) delta = opts%factor
            end if
            ! R packed by rows (MINPACK's layout: R(i, j), i <= j, at
            ! j + sum_{k < i} (n - k))
            do j = 1, n
                l = j
                do i = 1, j - 1
                    r(l) = q(i, j)
                    l = l + n - i
                end do
                r(l) = q(j, j)
            end do
            call dorgqr(n, n, n, q, n, tau, work, lwork, info)
            if (info /= 0) then
                call lapack_error("dorgqr")
                return
            end if
            qtf = matmul(fvec, q)
            if (opts%mode /= 2) diag = max(diag, wa2)

            inner: do
                ! the dogleg step p = wa1 and its scaled length
                call dogleg(n, r, lr, diag, qtf, delta, wa1, wa2, wa3)
                wa1 = -wa1
                wa2 = x + wa1
                wa3 = diag*wa1
                pnorm = enorm(n, wa3)
                if (iter == 1) delta = min(delta, pnorm)
                call sys%residual(wa2, wa4, stat)
                report%nfev = report%nfev + 1
                if (stat /= 0) then
                    call stopped_by_callback()
                    return
                end if
                fnorm1 = enorm(n, wa4)
                if (met_target(wa2, wa4, fnorm1)) return
                ! actual and predicted reductions
                actred = -1.0_dp
                if (fnorm1 < fnorm) actred = 1.0_dp - (fnorm1/fnorm)**2
                l = 1
                do i = 1, n
                    total = 0.0_dp
                    do j = i, n
                        total = total + r(l)*wa1(j)
                        l = l + 1
                    end do
                    wa3(i) = qtf(i) + total
                end do
                total = enorm(n, wa3)
                prered = 0.0_dp
                if (total < fnorm) prered = 1.0_dp - (total/fnorm)**2
                ratio = 0.0_dp
                if (prered > 0.0_dp) ratio = actred/prered
                ! the trust radius
                if (ratio < p1) then
                    ncsuc = 0
                    ncfail = ncfail + 1
                    delta = p5*delta
                else
                    ncfail = 0
                    ncsuc = ncsuc + 1
                    if (ratio >= p5 .or. ncsuc > 1) delta = max(delta, pnorm/p5)
                    if (abs(ratio - 1.0_dp) <= p1) delta = pnorm/p5
                end if
                ! a successful step
                if (ratio >= p0001) then
                    x = wa2
                    wa2 = diag*x
                    fvec = wa4
                    xnorm = enorm(n, wa2)
                    fnorm = fnorm1
                    iter = iter + 1
                end if
                ! progress
                nslow1 = nslow1 + 1
                if (actred >= p001) nslow1 = 0
                if (jeval) nslow2 = nslow2 + 1
                if (actred >= p1) nslow2 = 0
                ! convergence, then the other stopping tests
                if (delta <= opts%xtol*xnorm .or. fnorm == 0.0_dp) info = 1
                if (info == 0) then
                    if (report%nfev >= maxfev) info = 2
                    if (p1*max(p1*delta, pnorm) <= epsmch*xnorm) info = 3
                    if (nslow2 == 5) info = 4
                    if (nslow1 == 10) info = 5
                end if
                if (info /= 0) exit outer
                ! two failures in a row: a new Jacobian
                if (ncfail == 2) cycle outer
                ! Broyden's rank-1 update of R, Q and Q^T F
                do j = 1, n
                    total = dot_product(q(:, j), wa4)
                    wa2(j) = (total - wa3(j))/pnorm
                    wa1(j) = diag(j)*((diag(j)*wa1(j))/pnorm)
                    if (ratio >= p0001) qtf(j) = total
                end do
                call r1updt(n, n, r, lr, wa1, wa2, wa3, sing)
                call r1mpyq(n, n, q, n, wa2, wa3)
                call r1mpyq(1, n, qtf, 1, wa2, wa3)
                jeval = .false.
            end do inner
        end do outer
        report%info = info
        report%fnorm = fnorm

    contains

        !> With ftarget set, stop at the first evaluation that meets it: x and the report
        !> take that point (info -1, as hybrj's answer to the stop in solve_hybrj).
        logical function met_target(xt, ft, fn)
            real(dp), intent(in) :: xt(:), ft(:), fn
            met_target = opts%ftarget > 0.0_dp .and. fn <= opts%ftarget
            if (.not. met_target) return
            x = xt
            report%target_met = .true.
            report%info = -1
            report%fnorm = norm2(ft)
        end function met_target

        subroutine stopped_by_callback()
            report%callback_stat = stat
            report%info = -1
            call fatal_error(error, "solve_powell: the system's callback stopped the solve", &
                             stickslip_stat%callback)
        end subroutine stopped_by_callback

        subroutine lapack_error(name)
            character(len=*), intent(in) :: name
            write (buf, '(a,i0)') "solve_powell: "//name//" rejected argument ", -info
            call fatal_error(error, trim(buf), stickslip_stat%lapack)
        end subroutine lapack_error
    end subroutine solve_powell
end module stickslip_powell
