!> Benchmark of models from FE matrices (a program that prints figures, not a test): a
!> cantilever plate of FIXED physical size (0.4 m x 0.1 m x 10 mm steel, plane stress,
!> bilinear Q4 elements, 2 DOFs per node, consistent mass, clamped at x = 0) meshed ever finer,
!> N ~ 1e3, 1e4, 1e5 DOFs, with 1, 5 or 20 friction contacts against the ground on the
!> transverse (y) DOFs of the upper edge (the first at the tip, the others spread over the
!> outer half), a harmonic transverse force at the lower tip corner and mass-proportional
!> damping (1 % at the first resonance w1). The matrices are assembled in-process from
!> triplets into sparse_matrix_t (no files) by bench/bench_plate.f90 (module
!> stickslip_bench_plate, shared with bench_solver), which also places the contacts and the
!> force and builds the reduced dense model.
!>
!> For each case: the Craig-Bampton reduction with the default mode-count rule (&hbm
!> harmonics = 30, sweep up to 1.1 w1: every fixed-interface mode below 3 x 30 x 1.1 w1),
!> its size and time (median over repeats, one run at 1e5), the reduction error measure at
!> w1 (receptance_error, as the command line does it), one cold weighted-residual solve at
!> w1 with the default &hbm options (median of 5) and a sweep 0.9 w1 -> 1.1 w1 in 30 steps
!> without stability and truncation (median of 3), per point. CPU times of one thread.
!> Then the anatomy of the reduction with one contact: the sparse LU of K_ii, the
!> fixed-interface eigenpairs below the limit, the rest (constraint modes, projection).
!>
!> The sweep is cut at 20 points (it reaches 0.90 to 0.98 w1); the cases with 20 contacts
!> run their sweep once and their solve 3 times. With a threaded BLAS (OpenBLAS's OpenMP
!> build behind liblapack.so.3) set OMP_NUM_THREADS=1: its idle threads spin and the CPU
!> times would count them.
!>
!> Run from the project root: OMP_NUM_THREADS=1 fpm run --example bench_reduction
!>     --profile release [-- max_level [repeats]]
!>     (max_level 1, 2, 3 = up to 1e3, 1e4, 1e5 DOFs; default 3, repeats default 3;
!>     about 15 min CPU for all three levels, most of it in the sweeps with 20 contacts
!>     and the reductions at 1e5)
program bench_reduction
    use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
    use stickslip, only: dp, error_type, model_t, sparse_matrix_t, new_sparse_from_triplets, &
        reduction_options_t, reduction_report_t, reduced_model_t, craig_bampton, &
        receptance_error, hbm_options_t, hbm_solution_t, solve_periodic, &
        sweep_options_t, sweep_result_t, run_sweep, reference_options_t
    use stickslip_study, only: median
    use stickslip_umfpack, only: sparse_lu_t
    use stickslip_arpack, only: eigen_options_t
    use stickslip_sparse_eigen, only: sparse_eigenpairs_below, eigen_range_report_t
    use stickslip_blas_threads, only: limit_blas_threads
    use stickslip_bench_plate, only: plate, first_frequency, plate_damping, case_dofs, &
        plate_model
    implicit none

    !> Elements through the height per level (nx = 4 ny): N = 2 nx (ny + 1).
    integer, parameter :: levels(3) = [11, 35, 112]
    integer, parameter :: contact_counts(3) = [1, 5, 20]
    integer, parameter :: harmonics = 30, sweep_steps = 30, max_points = 20

    type(sparse_matrix_t) :: kmat, mmat, cmat
    type(error_type), allocatable :: error
    integer :: lev, ic, max_level, repeats, nx, ny
    real(dp) :: w1, base_point(3), point(3, 3), reduction(3, 3), solve(3, 3)
    character(len=32) :: arg
    integer :: stat

    call limit_blas_threads()
    max_level = 3
    repeats = 3
    if (command_argument_count() >= 1) then
        call get_command_argument(1, arg)
        read (arg, *) max_level
    end if
    if (command_argument_count() >= 2) then
        call get_command_argument(2, arg)
        read (arg, *) repeats
    end if
    call get_environment_variable("OMP_NUM_THREADS", arg, status=stat)
    if (stat /= 0 .or. trim(arg) /= "1") write (output_unit, '(a)') "note: OMP_NUM_THREADS "// &
        "is not 1: a threaded BLAS (OpenBLAS) may spin and the CPU times add up its threads"
    point = 0.0_dp
    reduction = 0.0_dp
    solve = 0.0_dp
    write (output_unit, '(a)') "cantilever plate 0.4 x 0.1 x 0.01 m steel, Q4 plane stress, "// &
        "contacts on y DOFs of the upper edge, force at the lower tip"
    write (output_unit, '(a)') "|      N | contacts | w1 [rad/s] | reduction [s] | modes | "// &
        "reduced DOFs | error measure [s] | rel. error | solve [ms] | points | "// &
        "per point [ms] | point / N=1e3 | reduce + solve [s] |"
    write (output_unit, '(a)') "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    base_point = 0.0_dp
    do lev = 1, min(max_level, size(levels))
        ny = levels(lev)
        nx = 4*ny
        call plate(nx, ny, kmat, mmat, error)
        if (allocated(error)) call fail("plate")
        call say("plate assembled")
        call first_frequency(kmat, mmat, w1, error)
        if (allocated(error)) call fail("first frequency")
        call say("first frequency")
        cmat = plate_damping(mmat, w1)
        do ic = 1, size(contact_counts)
            call run_case(lev, contact_counts(ic), base_point(ic), point(lev, ic), &
                          reduction(lev, ic), solve(lev, ic))
        end do
        call anatomy(reduction(lev, 1))
    end do
    if (max_level >= 2) write (output_unit, '(a,f0.2,a)') "target: N = 1e4, 1 contact, "// &
        "reduced and solved in ", reduction(2, 1) + solve(2, 1), " s (< 10 s)"
    if (max_level >= 3) write (output_unit, '(a,3(f0.2,1x),a)') "target: point cost "// &
        "N = 1e5 / N = 1e3 for 1, 5, 20 contacts: ", point(3, :)/point(1, :), "(within 1.5)"

contains

    !> Progress on stderr (the table goes to stdout).
    subroutine say(what)
        character(len=*), intent(in) :: what
        real(dp) :: t
        call cpu_time(t)
        write (error_unit, '(f9.2,1x,a)') t, what
        flush (error_unit)
    end subroutine say

    !> Stop with a message.
    subroutine fail(what)
        character(len=*), intent(in) :: what
        write (output_unit, '(a)') "error: "//what//": "//error%message
        stop 1
    end subroutine fail

    !> One case: reduce, measure the error, solve, sweep; a row of the table.
    subroutine run_case(lev, nc, base, point, reduction, solve)
        integer, intent(in) :: lev, nc
        !> Point time of N = 1e3 (set at level 1) [s].
        real(dp), intent(inout) :: base
        !> Time per sweep point, of the reduction, of one solve [s].
        real(dp), intent(out) :: point, reduction, solve
        type(reduction_options_t) :: opts
        type(reduction_report_t) :: rep
        type(reduced_model_t) :: rm
        type(model_t) :: model
        type(hbm_options_t) :: ho
        type(hbm_solution_t) :: sol
        type(sweep_options_t) :: so
        type(sweep_result_t) :: res
        integer, allocatable :: contact(:)
        integer :: forced, r, nrep, nsolve, nsweep, k
        real(dp) :: t0, t1, tred(repeats), tsolve(5), tsweep(repeats), terr, err
        call case_dofs(nx, ny, nc, contact, forced)
        opts = reduction_options_t(highest_frequency=harmonics*1.1_dp*w1)
        nrep = repeats
        if (lev == 3) nrep = 1
        do r = 1, nrep
            call cpu_time(t0)
            call craig_bampton(kmat, mmat, [contact, forced], opts, rm, rep, error, cmat=cmat)
            call cpu_time(t1)
            if (allocated(error)) call fail("craig_bampton")
            tred(r) = t1 - t0
        end do
        call say("reduced")
        call cpu_time(t0)
        call receptance_error(kmat, mmat, rm, contact, [(0, k=1, nc)], [w1], err, error, &
                              cmat=cmat)
        call cpu_time(t1)
        if (allocated(error)) call fail("receptance_error")
        terr = t1 - t0
        ! the reduced dense model
        model = plate_model(rm, contact, forced, w1)
        call say("error measure")
        ho = hbm_options_t()
        ho%harmonics = harmonics
        nsolve = merge(5, 3, nc < 20)
        nsweep = merge(repeats, 1, nc < 20)
        do r = 1, nsolve
            call cpu_time(t0)
            call solve_periodic(model, ho, sol, error)
            call cpu_time(t1)
            if (allocated(error)) call fail("solve_periodic")
            tsolve(r) = t1 - t0
        end do
        write (error_unit, '(a,l1,a,i0,a,i0)') "solve: converged ", sol%converged, &
            " nfev ", sol%nfev, " njev ", sol%njev
        call say("solved")
        so = sweep_options_t()
        so%parameter = 'omega'
        so%start = 0.9_dp*w1
        so%stop = 1.1_dp*w1
        so%step = (so%stop - so%start)/sweep_steps
        so%max_step = so%step
        so%stability = .false.
        so%truncation = .false.
        so%max_points = max_points
        do r = 1, nsweep
            call cpu_time(t0)
            call run_sweep(model, ho, reference_options_t(), so, res, error)
            call cpu_time(t1)
            if (allocated(error)) call fail("run_sweep")
            tsweep(r) = t1 - t0
            write (error_unit, '(a,i0,a,i0,a,i0,a,f0.1,a,l1,a,i0,a,f0.4)') "sweep: points ", &
                res%npoints, " rejected ", res%state%rejected, " failures ", &
                res%state%failures, " s ", tsweep(r), " complete ", res%complete, &
                " factorizations ", res%factorizations, " last omega/w1 ", &
                res%points(res%npoints)%parameter/w1
        end do
        point = median(tsweep(1:nsweep))/max(res%npoints, 1)
        if (lev == 1) base = point
        write (output_unit, '("| ",i6," | ",i8," | ",f10.1," | ",f13.3," | ",i5," | ",i12, &
            &" | ",f17.3," | ",es10.2," | ",f10.1," | ",i6," | ",f14.1," | ",f13.2," | ",f18.2," |",a)') &
            rm%n, nc, w1, median(tred(1:nrep)), rep%modes, rep%reduced_dof, terr, err, &
            1.0e3_dp*median(tsolve(1:nsolve)), res%npoints, 1.0e3_dp*point, point/base, &
            median(tred(1:nrep)) + median(tsolve(1:nsolve)), &
            merge("        ", " capped!", .not. rep%capped)
        reduction = median(tred(1:nrep))
        solve = median(tsolve(1:nsolve))
        flush (output_unit)
    end subroutine run_case

    !> Where the reduction time goes (one contact, its measured time `total`): the sparse
    !> LU of K_ii, the fixed-interface eigenpairs below the limit (with their own LU of
    !> K_ii), the rest (constraint modes, projections).
    subroutine anatomy(total)
        real(dp), intent(in) :: total
        integer, allocatable :: contact(:), loc(:), ri(:), ci(:)
        real(dp), allocatable :: kv(:), mv(:), values(:), vectors(:, :)
        type(sparse_matrix_t) :: kii, mii
        type(sparse_lu_t) :: lu
        type(eigen_range_report_t) :: erep
        integer :: forced, n, ni, row, p, t, nev
        real(dp) :: t0, t1, tlu, teig, limit
        call case_dofs(nx, ny, 1, contact, forced)
        n = kmat%nrows
        allocate (loc(n))
        loc = 0
        loc(contact) = -1
        loc(forced) = -1
        ni = 0
        do row = 1, n
            if (loc(row) == 0) then
                ni = ni + 1
                loc(row) = ni
            end if
        end do
        allocate (ri(kmat%nnz()), ci(kmat%nnz()), kv(kmat%nnz()), mv(kmat%nnz()))
        t = 0
        do row = 1, n
            if (loc(row) <= 0) cycle
            do p = kmat%row_start(row), kmat%row_start(row + 1) - 1
                if (loc(kmat%col(p)) <= 0) cycle
                t = t + 1
                ri(t) = loc(row)
                ci(t) = loc(kmat%col(p))
                kv(t) = kmat%val(p)
                mv(t) = mmat%val(p)
            end do
        end do
        ! K and M share their pattern here
        call new_sparse_from_triplets(kii, ni, ni, ri(1:t), ci(1:t), kv(1:t), error)
        if (allocated(error)) call fail("K_ii")
        call new_sparse_from_triplets(mii, ni, ni, ri(1:t), ci(1:t), mv(1:t), error)
        if (allocated(error)) call fail("M_ii")
        call cpu_time(t0)
        call lu%factorize(ni, kii%row_start, kii%col, kii%val, error)
        call cpu_time(t1)
        if (allocated(error)) call fail("LU of K_ii")
        call lu%release()
        tlu = t1 - t0
        limit = 3.0_dp*harmonics*1.1_dp*w1
        call cpu_time(t0)
        call sparse_eigenpairs_below(ni, kii%row_start, kii%col, kii%val, mii%row_start, &
                                     mii%col, mii%val, limit**2, 500, 0.0_dp, &
                                     eigen_options_t(), values, vectors, erep, error)
        call cpu_time(t1)
        if (allocated(error)) call fail("eigenpairs below the limit")
        teig = t1 - t0
        nev = count(values <= limit**2)
        write (output_unit, '("  N = ",i0,", 1 contact: reduction ",f0.3," s; measured ", &
            &"alone: ",i0," eigenpairs below the limit ",f0.3," s (",i0," Lanczos runs, ",i0, &
            &" solves with the LU of K_ii, the LU itself ",f0.3," s), the rest of the ", &
            &"reduction (constraint modes, projections) ~",f0.3," s")') n, total, nev, teig, &
            erep%runs, erep%op_applications, tlu, max(total - teig, 0.0_dp)
        flush (output_unit)
    end subroutine anatomy
end program bench_reduction
