!> Readers of the case-file groups that build the model: &system, &forcing (&friction in
!> stickslip_case_friction, with the shared helpers here). Each
!> reads one group of a parsed namelist file into `model_t`, with messages that start
!> "<path>[:<line>]: &<group> <variable>: ". The whole-model checks (symmetry, definiteness,
!> DOF ranges) are validate_model's, called by read_case once the three groups are read.
!> &system may take its matrices from Matrix Market files (stickslip_matrix_market), converted
!> to the dense model_t up to max_file_dof DOFs, or kept sparse (sparse_system_t) for the
!> reduction of stickslip_case_reduction.
module stickslip_case_model
    use, intrinsic :: iso_c_binding, only: c_char, c_size_t, c_ptr, c_null_char, c_associated
    use, intrinsic :: iso_fortran_env, only: int64
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type, fatal_error, stickslip_stat, itoa, real_text
    use stickslip_model, only: model_t
    use stickslip_namelist, only: nml_file_t
    use stickslip_namelist_values, only: check_names, get_integer, get_real, get_integers, &
        get_reals, get_string
    use stickslip_sparse, only: sparse_matrix_t, sparse_to_dense, sparse_symmetry_defect, &
        sparse_scaled_sum
    use stickslip_progress, only: progress_t
    use stickslip_matrix_market, only: read_matrix_market, read_matrix_market_size
    implicit none
    private
    public :: read_system_group, read_forcing_group
    public :: take_reals, take_integers, take_file_variable, read_column_file, not_beside_file
    public :: max_dof, max_terms, group_error, max_file_dof, system_files_t, resolve_path
    public :: sparse_system_t, load_sparse_system

    !> Largest ndof a case file can hold (host codes calling the library have no limit).
    integer, parameter :: max_dof = 64
    !> Largest N of an UNREDUCED model read from Matrix Market files (&system mass_file,
    !> stiffness_file) converted to the dense model_t; larger models are reduced
    !> (&reduction method = 'craig-bampton' or 'auto') or kept sparse (method = 'none':
    !> condensed exactly per harmonic by sparse LU, weighted residual only).
    integer, parameter :: max_file_dof = 2000
    !> Largest number of forcing terms or contacts (and of entries of a list) in a case file.
    integer, parameter :: max_terms = 256

    !> The file variables of a case's model: &system mass_file, stiffness_file,
    !> damping_file and the Rayleigh factors, &friction direction_file and &forcing
    !> force_file (unallocated: not given).
    type :: system_files_t
        !> mass_file, stiffness_file, damping_file as written in the case.
        character(len=:), allocatable :: mass_file, stiffness_file, damping_file
        !> The same resolved against the case file's folder (what is read; in messages).
        character(len=:), allocatable :: mass_path, stiffness_path, damping_path
        !> The same as absolute paths (what write_case echoes).
        character(len=:), allocatable :: mass_absolute, stiffness_absolute, damping_absolute
        !> &friction direction_file and &forcing force_file: as written, resolved against
        !> the case file's folder, absolute.
        character(len=:), allocatable :: direction_file, direction_path, direction_absolute
        character(len=:), allocatable :: force_file, force_path, force_absolute
        !> C += rayleigh_alpha M + rayleigh_beta K [1/s], [s].
        real(dp) :: rayleigh_alpha = 0.0_dp
        real(dp) :: rayleigh_beta = 0.0_dp
    end type system_files_t

    !> The matrices of a model from files kept sparse (for the reduction), damping including
    !> the Rayleigh terms.
    type :: sparse_system_t
        !> The model comes from files kept sparse (model%mass etc. are then NOT set,
        !> model%ndof is N); the matrices are here once `loaded`.
        logical :: read = .false.
        !> The matrices were read (read_system_group without `defer`, or
        !> load_sparse_system): with `defer` only the files' size lines were checked, so that
        !> a reduction found in its cache need not read them.
        logical :: loaded = .false.
        !> Damping was given (damping_file or a Rayleigh factor).
        logical :: has_damping = .false.
        !> M, K, C (N x N, full storage).
        type(sparse_matrix_t) :: mass, stiffness, damping
    end type sparse_system_t

    interface
        function c_getcwd(buf, size) bind(c, name='getcwd') result(p)
            import :: c_char, c_size_t, c_ptr
            character(kind=c_char), intent(out) :: buf(*)
            integer(c_size_t), value :: size
            type(c_ptr) :: p
        end function c_getcwd
    end interface

contains

    !> Read &system (required). Either inline matrices: ndof (1..max_dof), mass, stiffness
    !> (ndof**2 values each, column-major, required) and damping (default 0); or Matrix
    !> Market files: mass_file and stiffness_file (both, square, of equal size N <=
    !> max_file_dof; ndof optional and then equal to N; inline mass/stiffness/damping not
    !> allowed beside them). damping_file (optional, N x N) replaces inline damping in either
    !> form. Relative file paths resolve against the case file's folder. Finally C += alpha M
    !> + beta K (rayleigh_alpha, rayleigh_beta, default 0, finite and >= 0). Errors (stat
    !> input; stat io for an unreadable file) name the variable, and the file and its line.
    !> With `sparse` present and `method` = 'craig-bampton', or 'auto' or 'none' and N >
    !> max_file_dof, the file matrices are kept sparse in `sparse` (no size limit) and model
    !> gets only ndof = N ('none': the exact sparse condensation, stickslip_sparse_dynamics).
    !> With `defer` true, a model kept sparse has its files' size lines checked only (sizes,
    !> square, equal); load_sparse_system reads the entries when they are needed.
    subroutine read_system_group(nml, model, files, error, method, sparse, defer, progress)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model: ndof, mass, stiffness, damping set.
        type(model_t), intent(inout) :: model
        !> The file variables and Rayleigh factors as read (echoed by write_case).
        type(system_files_t), intent(out) :: files
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> &reduction method ('none', 'craig-bampton', 'auto'; absent: 'none').
        character(len=*), intent(in), optional :: method
        !> The sparse matrices when the model is to be reduced.
        type(sparse_system_t), intent(out), optional :: sparse
        !> Leave the entries of a model kept sparse unread (load_sparse_system reads them).
        logical, intent(in), optional :: defer
        !> Progress of long reads of matrix files (stickslip_progress; absent: quiet).
        type(progress_t), intent(inout), optional :: progress
        integer :: n, rows, cols
        logical :: found, from_files, keep_sparse, later
        if (nml%find("system") == 0) then
            call group_error(nml, error, "&system: required group not found")
            return
        end if
        call check_names(nml, "system", [character(len=14) :: "ndof", "mass", "stiffness", &
                                        "damping", "mass_file", "stiffness_file", &
                                        "damping_file", "rayleigh_alpha", "rayleigh_beta"], error)
        if (allocated(error)) return
        call take_file("mass_file", files%mass_file, files%mass_path, files%mass_absolute)
        if (allocated(error)) return
        call take_file("stiffness_file", files%stiffness_file, files%stiffness_path, &
                       files%stiffness_absolute)
        if (allocated(error)) return
        call take_file("damping_file", files%damping_file, files%damping_path, &
                       files%damping_absolute)
        if (allocated(error)) return
        call take_factor("rayleigh_alpha", files%rayleigh_alpha)
        if (allocated(error)) return
        call take_factor("rayleigh_beta", files%rayleigh_beta)
        if (allocated(error)) return
        from_files = allocated(files%mass_file) .or. allocated(files%stiffness_file)

        n = 0
        call get_integer(nml, "system", "ndof", n, error, found)
        if (allocated(error)) return
        if (from_files) then
            if (.not. allocated(files%mass_file)) then
                call group_error(nml, error, "&system mass_file: missing (stiffness_file "// &
                                 "is given; the two come together)")
                return
            end if
            if (.not. allocated(files%stiffness_file)) then
                call group_error(nml, error, "&system stiffness_file: missing (mass_file "// &
                                 "is given; the two come together)")
                return
            end if
            call not_both("mass", "mass_file")
            if (allocated(error)) return
            call not_both("stiffness", "stiffness_file")
            if (allocated(error)) return
            call not_both("damping", "damping_file (the matrices come from files)")
            if (allocated(error)) return
            keep_sparse = .false.
            if (present(sparse) .and. present(method)) then
                call read_matrix_market_size(files%mass_path, rows, cols, error)
                if (allocated(error)) then
                    error%message = nml%path//": &system mass_file: "//error%message
                    return
                end if
                keep_sparse = method == 'craig-bampton' .or. &
                              ((method == 'auto' .or. method == 'none') .and. &
                               rows > max_file_dof)
            end if
            later = .false.
            if (present(defer)) later = defer
            if (keep_sparse) then
                ! the size line only: load_sparse_system reads the entries
                call sparse_file_header(nml, files%mass_path, "mass_file", 0, rows, error)
                if (allocated(error)) return
                model%ndof = rows
            else
                call read_dense(files%mass_path, "mass_file", 0, model%mass)
                if (allocated(error)) return
                model%ndof = size(model%mass, 1)
            end if
            if (found .and. n /= model%ndof) then
                call group_error(nml, error, "&system ndof = "//itoa(n)//" but mass_file '"// &
                                 files%mass_path//"' holds a "//itoa(model%ndof)//" x "// &
                                 itoa(model%ndof)//" matrix: they must agree (or leave "// &
                                 "ndof out)")
                return
            end if
            n = model%ndof
            if (keep_sparse) then
                sparse%read = .true.
                sparse%has_damping = allocated(files%damping_file) .or. &
                                     files%rayleigh_alpha /= 0.0_dp .or. files%rayleigh_beta /= 0.0_dp
                if (later) then
                    call sparse_file_header(nml, files%stiffness_path, "stiffness_file", n, &
                                            rows, error)
                    if (allocated(error)) return
                    if (allocated(files%damping_file)) call sparse_file_header(nml, &
                        files%damping_path, "damping_file", n, rows, error)
                    return
                end if
                call load_sparse_system(nml, files, n, sparse, error)
                return
            end if
            call read_dense(files%stiffness_path, "stiffness_file", n, model%stiffness)
            if (allocated(error)) return
        else
            if (.not. found) then
                call group_error(nml, error, "&system ndof: missing (number of degrees "// &
                                 "of freedom; or give mass_file and stiffness_file)")
                return
            end if
            if (n < 1 .or. n > max_dof) then
                call group_error(nml, error, "&system ndof = "//itoa(n)//": must be in 1.."// &
                                 itoa(max_dof)//" for inline matrices (use mass_file/"// &
                                 "stiffness_file for larger models)")
                return
            end if
            model%ndof = n
            call take_matrix("mass", .true., model%mass)
            if (allocated(error)) return
            call take_matrix("stiffness", .true., model%stiffness)
            if (allocated(error)) return
        end if
        if (allocated(files%damping_file)) then
            call not_both("damping", "damping_file")
            if (allocated(error)) return
            call read_dense(files%damping_path, "damping_file", n, model%damping)
            if (allocated(error)) return
        else
            call take_matrix("damping", .false., model%damping)
            if (allocated(error)) return
        end if
        if (files%rayleigh_alpha /= 0.0_dp) model%damping = model%damping + &
            files%rayleigh_alpha*model%mass
        if (files%rayleigh_beta /= 0.0_dp) model%damping = model%damping + &
            files%rayleigh_beta*model%stiffness

    contains

        subroutine take_matrix(name, required, a)
            character(len=*), intent(in) :: name
            logical, intent(in) :: required
            real(dp), allocatable, intent(out) :: a(:, :)
            real(dp), allocatable :: values(:)
            logical :: given
            call get_reals(nml, "system", name, values, given, max_dof**2, error)
            if (allocated(error)) return
            if (.not. given) then
                if (required) then
                    call group_error(nml, error, "&system "//name//": missing ("// &
                                     "ndof**2 = "//itoa(n*n)//" values, column-major)")
                    return
                end if
                allocate (a(n, n))
                a = 0.0_dp
                return
            end if
            if (size(values) /= n*n) then
                call group_error(nml, error, "&system "//name//": "//itoa(size(values))// &
                                 " values given, expected ndof**2 = "//itoa(n*n)// &
                                 " (column-major)")
                return
            end if
            a = reshape(values, [n, n])
        end subroutine take_matrix

        subroutine take_file(name, given, path, absolute)
            character(len=*), intent(in) :: name
            character(len=:), allocatable, intent(out) :: given, path, absolute
            call take_file_variable(nml, "system", name, given, path, absolute, error)
        end subroutine take_file

        subroutine take_factor(name, x)
            character(len=*), intent(in) :: name
            real(dp), intent(inout) :: x
            call get_real(nml, "system", name, x, error)
            if (allocated(error)) return
            if (.not. (x >= 0.0_dp .and. x <= huge(x))) call group_error(nml, error, &
                "&system "//name//" = "//real_text(x)//": must be finite and >= 0")
        end subroutine take_factor

        !> Error when the inline variable `inline` is given beside `file`.
        subroutine not_both(inline, file)
            character(len=*), intent(in) :: inline, file
            integer :: g, k
            g = nml%find("system")
            do k = 1, nml%groups(g)%nentries
                if (nml%groups(g)%entries(k)%name /= inline) cycle
                call fatal_error(error, nml%path//":"//itoa(nml%groups(g)%entries(k)%line)// &
                                 ": &system "//inline//" and "//file//" both given: give "// &
                                 "the matrix inline or in a file, not both", &
                                 stickslip_stat%input)
                return
            end do
        end subroutine not_both

        !> The dense square matrix of a Matrix Market file (N <= max_file_dof); n > 0: its
        !> required size.
        subroutine read_dense(path, name, n, a)
            character(len=*), intent(in) :: path, name
            integer, intent(in) :: n
            real(dp), allocatable, intent(out) :: a(:, :)
            type(sparse_matrix_t) :: s
            integer :: rows
            ! the size line first: a model too large for dense matrices fails before its
            ! entries are read
            call sparse_file_header(nml, path, name, n, rows, error)
            if (allocated(error)) return
            if (rows > max_file_dof) then
                call group_error(nml, error, "&system "//name//" '"//path//"': N = "// &
                                 itoa(rows)//" DOFs: more than "//itoa(max_file_dof)// &
                                 ", the largest unreduced model (dense matrices); use "// &
                                 "&reduction method = 'craig-bampton' or 'auto'")
                return
            end if
            call read_sparse_file(nml, path, name, n, s, error, progress)
            if (allocated(error)) return
            call sparse_to_dense(s, a, error)
            if (allocated(error)) error%message = nml%path//": &system "//name//" '"// &
                path//"': "//error%message
        end subroutine read_dense

    end subroutine read_system_group

    !> The matrices of a model from files kept sparse (read_system_group with `defer`): M, K
    !> (N x N, n given) and C (damping_file or 0, plus rayleigh_alpha M + rayleigh_beta K)
    !> read into `sparse` (sparse%loaded). Errors as read_system_group's for the files.
    subroutine load_sparse_system(nml, files, n, sparse, error, progress)
        !> The parsed case file (for messages).
        type(nml_file_t), intent(in) :: nml
        !> The file variables and Rayleigh factors (read_system_group).
        type(system_files_t), intent(in) :: files
        !> DOFs of the model.
        integer, intent(in) :: n
        !> The sparse matrices: read, has_damping set; the matrices on return.
        type(sparse_system_t), intent(inout) :: sparse
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Progress of the reads (absent: quiet).
        type(progress_t), intent(inout), optional :: progress
        type(sparse_matrix_t) :: tmp
        if (sparse%loaded) return
        call read_sparse_file(nml, files%mass_path, "mass_file", n, sparse%mass, error, progress)
        if (allocated(error)) return
        call read_sparse_file(nml, files%stiffness_path, "stiffness_file", n, sparse%stiffness, &
                              error, progress)
        if (allocated(error)) return
        if (allocated(files%damping_file)) then
            call read_sparse_file(nml, files%damping_path, "damping_file", n, sparse%damping, &
                                  error, progress)
            if (allocated(error)) return
        else
            call sparse_scaled_sum(0.0_dp, sparse%mass, 0.0_dp, sparse%mass, sparse%damping, &
                                   error)
            if (allocated(error)) return
        end if
        if (files%rayleigh_alpha /= 0.0_dp .or. files%rayleigh_beta /= 0.0_dp) then
            call sparse_scaled_sum(1.0_dp, sparse%damping, files%rayleigh_alpha, sparse%mass, &
                                   tmp, error)
            if (allocated(error)) return
            call sparse_scaled_sum(1.0_dp, tmp, files%rayleigh_beta, sparse%stiffness, &
                                   sparse%damping, error)
            if (allocated(error)) return
        end if
        sparse%loaded = .true.
    end subroutine load_sparse_system

    !> The size of the square matrix of Matrix Market file `path` (&system `name`) from its
    !> header and size line, checked: square, at least 1 x 1, of size n when n > 0, and (a
    !> mass file) with at least N entries.
    subroutine sparse_file_header(nml, path, name, n, rows, error)
        !> The parsed case file (for messages).
        type(nml_file_t), intent(in) :: nml
        !> The file, and its &system variable (mass_file, stiffness_file, damping_file).
        character(len=*), intent(in) :: path, name
        !> The size it must have (0: any).
        integer, intent(in) :: n
        !> Its size.
        integer, intent(out) :: rows
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        integer :: cols, line
        integer(int64) :: entries
        call read_matrix_market_size(path, rows, cols, error, entries, line)
        if (allocated(error)) then
            error%message = nml%path//": &system "//name//": "//error%message
            return
        end if
        ! a size the entries cannot back fails before anything of that size is made
        if (name == "mass_file" .and. entries < int(rows, int64)) then
            call group_error(nml, error, "&system "//name//" '"//path//"':"//itoa(line)// &
                             ": the size line claims a "//itoa(rows)//" x "//itoa(cols)// &
                             " matrix with "//itoa(entries)//" entries, but a positive "// &
                             "definite mass matrix needs its "//itoa(rows)//" diagonal "// &
                             "entries")
            return
        end if
        if (rows /= cols) then
            call group_error(nml, error, "&system "//name//" '"//path//"': a "// &
                             itoa(rows)//" x "//itoa(cols)//" matrix, not square")
            return
        end if
        if (n > 0 .and. rows /= n) then
            call group_error(nml, error, "&system "//name//" '"//path//"': a "// &
                             itoa(rows)//" x "//itoa(cols)//" matrix, but the model "// &
                             "has N = "//itoa(n)//" DOFs: sizes must agree")
            return
        end if
        if (rows < 1) then
            call group_error(nml, error, "&system "//name//" '"//path//"': an empty "// &
                             "0 x 0 matrix")
            return
        end if
    end subroutine sparse_file_header

    !> The sparse square matrix of a Matrix Market file; n > 0: its required size. The
    !> size is checked from the size line before the entries are read; a mass matrix must
    !> be symmetric.
    subroutine read_sparse_file(nml, path, name, n, s, error, progress)
        !> The parsed case file (for messages).
        type(nml_file_t), intent(in) :: nml
        !> The file, and its &system variable (mass_file, stiffness_file, damping_file).
        character(len=*), intent(in) :: path, name
        !> The size it must have (0: any).
        integer, intent(in) :: n
        !> The matrix read.
        type(sparse_matrix_t), intent(out) :: s
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> Progress of the read (absent: quiet).
        type(progress_t), intent(inout), optional :: progress
        integer :: rows
        call sparse_file_header(nml, path, name, n, rows, error)
        if (allocated(error)) return
        call read_matrix_market(path, s, error, progress=progress)
        if (allocated(error)) then
            error%message = nml%path//": &system "//name//": "//error%message
            return
        end if
        if (name == "mass_file") then
            if (.not. (sparse_symmetry_defect(s) <= 1.0e-12_dp)) then
                call group_error(nml, error, "&system "//name//" '"//path//"': M is "// &
                                 "not symmetric (max |M(i,j) - M(j,i)| is "// &
                                 real_text(sparse_symmetry_defect(s))//" of its "// &
                                 "largest entry)")
                return
            end if
        end if
    end subroutine read_sparse_file

    !> A file variable of `group`: as written, resolved against the case file's folder,
    !> absolute (all unallocated when not given). Error: an empty file name.
    subroutine take_file_variable(nml, group, name, given, path, absolute, error)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name
        character(len=:), allocatable, intent(out) :: given, path, absolute
        type(error_type), allocatable, intent(out) :: error
        character(len=:), allocatable :: value
        logical :: here
        call get_string(nml, group, name, value, error, here)
        if (allocated(error) .or. .not. here) return
        if (len_trim(value) == 0) then
            call group_error(nml, error, "&"//group//" "//name//" = '': an empty file name")
            return
        end if
        given = value
        path = resolve_path(nml%path, value)
        absolute = path
        if (path(1:1) /= '/') absolute = working_directory()//"/"//path
    end subroutine take_file_variable

    !> The dense N x m matrix of the Matrix Market file `path` (&`group` `name`): N rows (the
    !> model's DOFs), 1..max_terms columns, finite; with `nonzero_columns` no zero column.
    !> Errors (stat input; io for an unreadable file) name the case file, the group, the
    !> variable and the file (and its line for a bad entry).
    subroutine read_column_file(nml, group, name, path, n, nonzero_columns, a, error)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name, path
        integer, intent(in) :: n
        logical, intent(in) :: nonzero_columns
        real(dp), allocatable, intent(out) :: a(:, :)
        type(error_type), allocatable, intent(out) :: error
        type(sparse_matrix_t) :: s
        integer :: rows, cols, j
        character(len=:), allocatable :: what
        what = "&"//group//" "//name//" '"//path//"'"
        call read_matrix_market_size(path, rows, cols, error)
        if (allocated(error)) then
            error%message = nml%path//": &"//group//" "//name//": "//error%message
            return
        end if
        if (rows /= n) then
            call group_error(nml, error, what//": a "//itoa(rows)//" x "//itoa(cols)// &
                             " matrix, but the model has N = "//itoa(n)//" DOFs: it needs "// &
                             "N rows (one per DOF)")
            return
        end if
        if (cols < 1 .or. cols > max_terms) then
            call group_error(nml, error, what//": "//itoa(cols)//" columns, must be 1.."// &
                             itoa(max_terms))
            return
        end if
        call read_matrix_market(path, s, error)
        if (allocated(error)) then
            error%message = nml%path//": &"//group//" "//name//": "//error%message
            return
        end if
        call sparse_to_dense(s, a, error)
        if (allocated(error)) then
            error%message = nml%path//": "//what//": "//error%message
            return
        end if
        if (.not. nonzero_columns) return
        do j = 1, cols
            if (all(a(:, j) == 0.0_dp)) then
                call group_error(nml, error, what//": column "//itoa(j)//" is zero "// &
                                 "(contact "//itoa(j)//" has no direction)")
                return
            end if
        end do
    end subroutine read_column_file

    !> Error "&group a and b both given" when `name` is given beside `file_name`.
    subroutine not_beside_file(nml, group, name, file_name, error)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name, file_name
        type(error_type), allocatable, intent(out) :: error
        integer :: g, k
        g = nml%find(group)
        if (g == 0) return
        do k = 1, nml%groups(g)%nentries
            if (nml%groups(g)%entries(k)%name /= name) cycle
            call fatal_error(error, nml%path//":"//itoa(nml%groups(g)%entries(k)%line)// &
                             ": &"//group//" "//file_name//" and "//name//" both given: "// &
                             file_name//" replaces "//name, stickslip_stat%input)
            return
        end do
    end subroutine not_beside_file

    !> `file` resolved against the folder of `case_path`: unchanged when absolute (starts
    !> with '/') or when the case file has no folder part; else "<folder of case>/file".
    pure function resolve_path(case_path, file) result(path)
        !> Path of the case file.
        character(len=*), intent(in) :: case_path
        !> The file name as written in the case.
        character(len=*), intent(in) :: file
        character(len=:), allocatable :: path
        integer :: k
        path = file
        if (file(1:1) == '/') return
        k = index(case_path, '/', back=.true.)
        if (k > 0) path = case_path(1:k)//file
    end function resolve_path

    !> The working directory (absolute; '.' when getcwd fails).
    function working_directory() result(cwd)
        character(len=:), allocatable :: cwd
        character(kind=c_char) :: buf(4096)
        integer :: i
        cwd = "."
        if (.not. c_associated(c_getcwd(buf, int(size(buf), c_size_t)))) return
        cwd = ""
        do i = 1, size(buf)
            if (buf(i) == c_null_char) exit
            cwd = cwd//buf(i)
        end do
    end function working_directory


    !> Read &forcing (required): omega (required), and either force_dof (at least one),
    !> force_amplitude (one per force_dof, required), or force_file (a Matrix Market file, N x
    !> n_terms, column k the load shape of term k, relative paths against the case file's
    !> folder; force_dof not allowed beside it), force_amplitude (one per column, default 1);
    !> force_harmonic (default 1) and force_phase (default 0) one per term.
    !> With `optional_group` (a case of nonlinear modes, which need no forcing) an absent
    !> group leaves the model without forcing terms (omega 1 rad/s, a placeholder).
    subroutine read_forcing_group(nml, model, error, files, optional_group)
        !> The parsed case file.
        type(nml_file_t), intent(in) :: nml
        !> The model (ndof set): omega and the forcing terms set.
        type(model_t), intent(inout) :: model
        !> Set on the first problem found.
        type(error_type), allocatable, intent(out) :: error
        !> The file variables: force_file, force_path, force_absolute set when given.
        type(system_files_t), intent(inout), optional :: files
        !> The group may be absent (default .false.).
        logical, intent(in), optional :: optional_group
        logical :: found
        integer :: nf
        real(dp) :: omega
        character(len=:), allocatable :: given, path, absolute
        if (nml%find("forcing") == 0) then
            if (present(optional_group)) then
                if (optional_group) then
                    model%omega = 1.0_dp
                    allocate (model%force_dof(0), model%force_harmonic(0), &
                              model%force_amplitude(0), model%force_phase(0))
                    return
                end if
            end if
            call group_error(nml, error, "&forcing: required group not found (every "// &
                             "method but 'modes' needs it)")
            return
        end if
        call check_names(nml, "forcing", [character(len=15) :: "omega", "force_dof", &
                             "force_harmonic", "force_amplitude", "force_phase", &
                             "force_file"], error)
        if (allocated(error)) return
        omega = 0.0_dp
        call get_real(nml, "forcing", "omega", omega, error, found)
        if (allocated(error)) return
        if (.not. found) then
            call group_error(nml, error, &
                             "&forcing omega: missing (angular frequency of the forcing, rad/s)")
            return
        end if
        model%omega = omega
        call take_file_variable(nml, "forcing", "force_file", given, path, absolute, error)
        if (allocated(error)) return
        if (allocated(path)) then
            call not_beside_file(nml, "forcing", "force_dof", "force_file", error)
            if (allocated(error)) return
            call read_column_file(nml, "forcing", "force_file", path, model%ndof, .false., &
                                  model%force_shape, error)
            if (allocated(error)) return
            allocate (model%force_dof(0))
            if (present(files)) then
                files%force_file = given
                files%force_path = path
                files%force_absolute = absolute
            end if
            nf = size(model%force_shape, 2)
            call take_reals(nml, "forcing", "force_amplitude", nf, .false., 1.0_dp, &
                            model%force_amplitude, error, "column of force_file")
            if (allocated(error)) return
        else
            call get_integers(nml, "forcing", "force_dof", model%force_dof, found, max_terms, &
                              error)
            if (allocated(error)) return
            if (.not. found) then
                call group_error(nml, error, "&forcing force_dof: missing (at least one "// &
                                 "forcing term; or give force_file)")
                return
            end if
            nf = size(model%force_dof)
            call take_reals(nml, "forcing", "force_amplitude", nf, .true., 0.0_dp, &
                            model%force_amplitude, error)
            if (allocated(error)) return
        end if
        call take_reals(nml, "forcing", "force_phase", nf, .false., 0.0_dp, &
                        model%force_phase, error, per_file(allocated(path)))
        if (allocated(error)) return
        call take_integers(nml, "forcing", "force_harmonic", nf, 1, model%force_harmonic, &
                           error, per_file(allocated(path)))
    contains
        pure function per_file(from_file) result(per)
            logical, intent(in) :: from_file
            character(len=:), allocatable :: per
            per = "force_dof"
            if (from_file) per = "column of force_file"
        end function per_file
    end subroutine read_forcing_group

    !> `count` reals of a per-term list (one per force_dof or contact_dof, or `per`); `default`
    !> for each when absent and not required.
    subroutine take_reals(nml, group, name, count, required, default, a, error, per)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name
        integer, intent(in) :: count
        logical, intent(in) :: required
        real(dp), intent(in) :: default
        real(dp), allocatable, intent(out) :: a(:)
        type(error_type), allocatable, intent(out) :: error
        character(len=*), intent(in), optional :: per
        logical :: given
        call get_reals(nml, group, name, a, given, max_terms, error)
        if (allocated(error)) return
        if (.not. given) then
            allocate (a(count))
            a = default
            if (.not. required .or. count == 0) return
            call count_error(nml, group, name, 0, count, error, per)
            return
        end if
        if (size(a) /= count) call count_error(nml, group, name, size(a), count, error, per)
    end subroutine take_reals

    !> `count` integers of a per-term list; `default` for each when absent.
    subroutine take_integers(nml, group, name, count, default, a, error, per)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name
        integer, intent(in) :: count
        integer, intent(in) :: default
        integer, allocatable, intent(out) :: a(:)
        type(error_type), allocatable, intent(out) :: error
        character(len=*), intent(in), optional :: per
        logical :: given
        call get_integers(nml, group, name, a, given, max_terms, error)
        if (allocated(error)) return
        if (.not. given) then
            allocate (a(count))
            a = default
            return
        end if
        if (size(a) /= count) call count_error(nml, group, name, size(a), count, error, per)
    end subroutine take_integers

    subroutine count_error(nml, group, name, given, count, error, per)
        type(nml_file_t), intent(in) :: nml
        character(len=*), intent(in) :: group, name
        integer, intent(in) :: given, count
        type(error_type), allocatable, intent(out) :: error
        character(len=*), intent(in), optional :: per
        character(len=:), allocatable :: what
        what = "entry of contact_dof"
        if (group == "forcing") what = "entry of force_dof"
        if (present(per)) then
            what = "entry of "//per
            if (index(per, "column") == 1) what = per
        end if
        call group_error(nml, error, "&"//group//" "//name//": "//itoa(given)// &
                         " values given, expected "//itoa(count)//" (one per "// &
                         what//")")
    end subroutine count_error

    !> An input error "<path>: <message>".
    subroutine group_error(nml, error, message)
        !> The parsed case file (its path).
        type(nml_file_t), intent(in) :: nml
        !> The error made.
        type(error_type), allocatable, intent(out) :: error
        !> "&group variable: what is wrong".
        character(len=*), intent(in) :: message
        call fatal_error(error, nml%path//": "//message, stickslip_stat%input)
    end subroutine group_error
end module stickslip_case_model
