!> Shared test fixtures: the models the suites solve (the seed case, its damped variant, the
!> 4-DOF chain, a 1-DOF oscillator) and paths that do not depend on the working directory
!> (the project root found from the working directory or the executable's path; files of the
!> project tree such as examples/*.nml; the scratch directory build/test-scratch), so
!> `cd /tmp && <build>/test/tester` runs the suites as `fpm test` does.
module fixtures
    use, intrinsic :: iso_fortran_env, only: error_unit
    use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_size_t, c_ptr, &
        c_associated
    use stickslip_kinds, only: dp
    use stickslip_error, only: error_type
    use stickslip_model, only: model_t
    implicit none
    private
    public :: seed_model, damped_seed, chain_model, one_dof_model
    public :: unilateral_seed, liftoff_model, planar_model, liftoff_2d_model
    public :: scratch_dir, project_path, project_root, enter_project_root
    public :: scratch, write_lines, first_line, good_system, good_forcing, good_friction, sweep_case
    public :: msg, rt, file_text, count_commas

    !> Scratch directory of the suites that write files, relative to the project root that
    !> they enter first (enter_project_root). A constant: gfortran 12 corrupts memory on
    !> [character(len=n) :: s//"x"] with a variable s.
    character(len=*), parameter :: scratch = "build/test-scratch"
    !> The seed case as case-file groups: the structure, its forcing, its contact.
    character(len=*), parameter :: good_system = &
        "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1 /"
    character(len=*), parameter :: good_forcing = "&forcing omega = 4.5, force_dof = 1, " // &
        "force_amplitude = 10.0 /"
    character(len=*), parameter :: good_friction = "&friction contact_dof = 2, mu = 0.45, " // &
        "normal_load = 1.0 /"
    !> A small forced-response curve of the damped seed structure (11 points or so).
    character(len=*), parameter :: sweep_case(6) = [character(len=120) :: &
        "&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1, damping = 0.06,-0.02,-0.02,0.04 /", &
        "&forcing omega = 2.0, force_dof = 1, force_amplitude = 10.0 /", &
        "&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /", &
        "&hbm harmonics = 10, rho = 0.2, samples = 64 /", &
        "&run method = 'sweep' /", &
        "&sweep parameter = 'omega', start = 2.0, stop = 3.0, step = 0.1, max_step = 0.1 /"]

    !> Whether enter_project_root changed the working directory.
    logical, save :: entered = .false.
    !> The project root, once looked for ('' when not found).
    character(len=:), allocatable, save :: root_cache

    interface
        function c_mkdir(path, mode) bind(c, name='mkdir') result(stat)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int), value :: mode
            integer(c_int) :: stat
        end function c_mkdir
        function c_chdir(path) bind(c, name='chdir') result(stat)
            import :: c_int, c_char
            character(kind=c_char), intent(in) :: path(*)
            integer(c_int) :: stat
        end function c_chdir
        function c_getcwd(buf, size) bind(c, name='getcwd') result(p)
            import :: c_char, c_size_t, c_ptr
            character(kind=c_char), intent(out) :: buf(*)
            integer(c_size_t), value :: size
            type(c_ptr) :: p
        end function c_getcwd
    end interface

contains

    !> The seed case of DESIGN.md (examples/seed.nml): 2 DOF, M = I, K = [2 -1; -1 1],
    !> undamped, force 10 cos(4.5 t) on DOF 1, one contact DOF 2 to ground with mu = 0.45,
    !> N = 1.
    function seed_model() result(m)
        type(model_t) :: m
        m%ndof = 2
        m%mass = reshape([1.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [2, 2])
        m%stiffness = reshape([2.0_dp, -1.0_dp, -1.0_dp, 1.0_dp], [2, 2])
        m%damping = 0.0_dp*m%mass
        m%omega = 4.5_dp
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [10.0_dp]
        m%force_phase = [0.0_dp]
        m%contact_dof = [2]
        m%contact_dof2 = [0]
        m%mu = [0.45_dp]
        m%normal_load = [1.0_dp]
    end function seed_model

    !> The seed structure with its contact made unilateral (doc/contacts.md): a third DOF,
    !> decoupled from the others (mass 1, grounded by a spring 5), is the contact's normal
    !> (n = e_3, gap 0), pressed by the preload 1 (normal_stiffness `kn`, 0: rigid). Its
    !> contact never opens and carries lambda = 1: the seed case's answer.
    function unilateral_seed(kn) result(m)
        real(dp), intent(in) :: kn
        type(model_t) :: m
        m = seed_model()
        m%ndof = 3
        m%mass = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1]*1.0_dp, [3, 3])
        m%stiffness = reshape([2, -1, 0, -1, 1, 0, 0, 0, 5]*1.0_dp, [3, 3])
        m%damping = 0.0_dp*m%mass
        m%normal_load = [0.0_dp]
        allocate (m%normal_direction(3, 1))
        m%normal_direction = 0.0_dp
        m%normal_direction(3, 1) = 1.0_dp
        m%preload = [1.0_dp]
        m%normal_stiffness = [kn]
    end function unilateral_seed

    !> A damper-like contact that opens part of the period: a platform with a tangential
    !> DOF 1 and a normal DOF 2 (masses 1, grounded springs 1 and 1.5 coupled by 0.3, damping
    !> 0.02 M + 0.002 K), pressed by the preload 1 on a ground contact (n = e_2, gap 0,
    !> normal stiffness `kn`, tangential stiffness `kt`, mu 0.5), forced on both DOFs at
    !> omega = 1.5 (1 on DOF 1, 2 on DOF 2 with phase 0.4): the normal force it carries when
    !> closed, about kn 0.23, exceeds the preload's share, so the contact lifts off.
    function liftoff_model(kn, kt) result(m)
        real(dp), intent(in) :: kn, kt
        type(model_t) :: m
        m%ndof = 2
        m%mass = reshape([1, 0, 0, 1]*1.0_dp, [2, 2])
        m%stiffness = reshape([1.3_dp, -0.3_dp, -0.3_dp, 1.8_dp], [2, 2])
        m%damping = 0.02_dp*m%mass + 0.002_dp*m%stiffness
        m%omega = 1.5_dp
        m%force_dof = [1, 2]
        m%force_harmonic = [1, 1]
        m%force_amplitude = [1.0_dp, 2.0_dp]
        m%force_phase = [0.0_dp, 0.4_dp]
        m%contact_dof = [1]
        m%contact_dof2 = [0]
        m%mu = [0.5_dp]
        m%normal_load = [0.0_dp]
        allocate (m%normal_direction(2, 1))
        m%normal_direction = reshape([0.0_dp, 1.0_dp], [2, 1])
        m%preload = [1.0_dp]
        m%normal_stiffness = [kn]
        m%tangential_stiffness = [kt]
    end function liftoff_model

    !> 2D friction: a point mass 1 on two orthogonal springs k = 1 (x = DOF 1, y = DOF 2),
    !> damping c = 0.1, forced by (fx cos(omega t), fy sin(omega t)) at omega = 1.7, a ground
    !> contact in the plane (w = e_1, t = e_2, mu = 0.3, N = 1, tangential stiffness `kt`):
    !> fx = fy gives a circular path, fx /= fy an elliptical one.
    function planar_model(fx, fy, kt) result(m)
        real(dp), intent(in) :: fx, fy, kt
        type(model_t) :: m
        m%ndof = 2
        m%mass = reshape([1, 0, 0, 1]*1.0_dp, [2, 2])
        m%stiffness = m%mass
        m%damping = 0.1_dp*m%mass
        m%omega = 1.7_dp
        m%force_dof = [1, 2]
        m%force_harmonic = [1, 1]
        m%force_amplitude = [fx, fy]
        m%force_phase = [0.0_dp, -2.0_dp*atan(1.0_dp)]
        m%contact_dof = [1]
        m%contact_dof2 = [0]
        m%mu = [0.3_dp]
        m%normal_load = [1.0_dp]
        allocate (m%tangent2_direction(2, 1))
        m%tangent2_direction = reshape([0.0_dp, 1.0_dp], [2, 1])
        m%tangential_stiffness = [kt]
    end function planar_model

    !> 2D friction on a contact that lifts off: a point mass 1 (x = DOF 1, y = DOF 2 in the
    !> plane, z = DOF 3 normal) on grounded springs 1, 1, 1.5, damping 0.1 M, forced by (fx
    !> cos(omega t), fy sin(omega t), fz cos(omega t + 0.4)) at omega = 1.7, pressed by the
    !> preload 1 on a ground contact (w = e_1, t2 = e_2, n = e_3, gap 0, normal stiffness
    !> 10, mu = 0.3): fz = 1 opens it about 15 % of the period.
    function liftoff_2d_model(fx, fy, fz) result(m)
        real(dp), intent(in) :: fx, fy, fz
        type(model_t) :: m
        m%ndof = 3
        m%mass = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1]*1.0_dp, [3, 3])
        m%stiffness = m%mass
        m%stiffness(3, 3) = 1.5_dp
        m%damping = 0.1_dp*m%mass
        m%omega = 1.7_dp
        m%force_dof = [1, 2, 3]
        m%force_harmonic = [1, 1, 1]
        m%force_amplitude = [fx, fy, fz]
        m%force_phase = [0.0_dp, -2.0_dp*atan(1.0_dp), 0.4_dp]
        m%contact_dof = [1]
        m%contact_dof2 = [0]
        m%mu = [0.3_dp]
        m%normal_load = [0.0_dp]
        allocate (m%normal_direction(3, 1), m%tangent2_direction(3, 1))
        m%normal_direction = reshape([0.0_dp, 0.0_dp, 1.0_dp], [3, 1])
        m%tangent2_direction = reshape([0.0_dp, 1.0_dp, 0.0_dp], [3, 1])
        m%preload = [1.0_dp]
        m%normal_stiffness = [10.0_dp]
        m%tangential_stiffness = [0.0_dp]
    end function liftoff_2d_model

    !> The seed system with light Rayleigh damping C = 0.02 M + 0.02 K.
    function damped_seed() result(m)
        type(model_t) :: m
        m = seed_model()
        m%damping = 0.02_dp*m%mass + 0.02_dp*m%stiffness
    end function damped_seed

    !> A 4-DOF chain with masses 1, 1.25, 1.5, 1.75, Rayleigh damping 0.01 M + 0.02 K, forcing
    !> on harmonics 1 and 3 at omega = 0.5, a ground contact (DOF 2) and a relative one
    !> (DOF 4 on DOF 3).
    function chain_model() result(m)
        type(model_t) :: m
        integer :: i
        m%ndof = 4
        allocate (m%mass(4, 4), m%stiffness(4, 4))
        m%mass = 0.0_dp
        m%stiffness = 0.0_dp
        do i = 1, 4
            m%mass(i, i) = 1.0_dp + 0.25_dp*(i - 1)
            m%stiffness(i, i) = 2.0_dp
            if (i < 4) then
                m%stiffness(i, i + 1) = -1.0_dp
                m%stiffness(i + 1, i) = -1.0_dp
            end if
        end do
        m%stiffness(4, 4) = 1.0_dp
        m%damping = 0.02_dp*m%stiffness + 0.01_dp*m%mass
        m%omega = 0.5_dp
        m%force_dof = [1, 3]
        m%force_harmonic = [1, 3]
        m%force_amplitude = [2.0_dp, 2.0_dp/3.0_dp]
        m%force_phase = [0.0_dp, 0.7_dp]
        m%contact_dof = [2, 4]
        m%contact_dof2 = [0, 3]
        m%mu = [0.3_dp, 0.5_dp]
        m%normal_load = [1.5_dp, 1.0_dp]
    end function chain_model

    !> A 1-DOF oscillator m x'' + c x' + k x = force cos(omega t) + r with one contact to the
    !> ground (friction limit mu * normal_load).
    function one_dof_model(mass, stiffness, damping, omega, force, mu, normal_load) result(m)
        !> Mass m [kg], stiffness k [N/m], damping c [N s/m].
        real(dp), intent(in) :: mass, stiffness, damping
        !> Forcing frequency [rad/s] and amplitude [N].
        real(dp), intent(in) :: omega, force
        !> Friction coefficient and normal load [N] of the contact.
        real(dp), intent(in) :: mu, normal_load
        type(model_t) :: m
        m%ndof = 1
        m%mass = reshape([mass], [1, 1])
        m%stiffness = reshape([stiffness], [1, 1])
        m%damping = reshape([damping], [1, 1])
        m%omega = omega
        m%force_dof = [1]
        m%force_harmonic = [1]
        m%force_amplitude = [force]
        m%force_phase = [0.0_dp]
        m%contact_dof = [1]
        m%contact_dof2 = [0]
        m%mu = [mu]
        m%normal_load = [normal_load]
    end function one_dof_model

    !> Make the project root the working directory (once; nothing happens when the root is
    !> not found). Suites that write under "build/test-scratch" or read "examples/..." call it
    !> first, so the tester runs the same from any directory (`cd /tmp && .../test/tester`).
    !> Why not an absolute scratch path: the suites pass paths in constructors such as
    !> `[character(len=200) :: scratch//"/x.nml"]`, and gfortran 12 corrupts the heap on those
    !> unless `scratch` is a constant (it sizes the temporary by the element's own length).
    subroutine enter_project_root()
        character(len=:), allocatable :: root
        root = project_root()
        if (len(root) == 0 .or. entered) return
        if (c_chdir(root//c_null_char) /= 0) then
            write (error_unit, '(a)') "fixtures: cannot change directory to "//root
            return
        end if
        entered = .true.
    end subroutine enter_project_root

    !> The absolute path of the tests' scratch directory, <project root>/build/test-scratch,
    !> created on first use (a directory shared by the runs of one checkout; do not put it in
    !> a `[character(len=n) :: ...]` constructor, see enter_project_root).
    function scratch_dir() result(path)
        character(len=:), allocatable :: path
        integer :: k, stat
        path = project_path("build/test-scratch")
        do k = 2, len(path)
            if (path(k:k) == "/") stat = c_mkdir(path(1:k - 1)//c_null_char, int(o'755', c_int))
        end do
        stat = c_mkdir(path//c_null_char, int(o'755', c_int))
        if (.not. is_directory(path)) error stop "fixtures: cannot create the scratch directory"
    end function scratch_dir

    !> The absolute path of `relative` (e.g. "examples/seed.nml") in the project tree: the
    !> first folder holding an fpm.toml of name "stickslip", looking up from the test
    !> executable's folder and then from the working directory. When no such folder is found,
    !> `relative` is returned unchanged (after a line on stderr).
    function project_path(relative) result(path)
        !> A path relative to the project root.
        character(len=*), intent(in) :: relative
        character(len=:), allocatable :: path
        character(len=:), allocatable :: root
        root = project_root()
        if (len(root) == 0) then
            path = relative
        else
            path = root//"/"//relative
        end if
    end function project_path

    !> The absolute path of the project root ('' when not found; see project_path): looked
    !> for above the test executable first (the checkout that built it), then above the
    !> working directory.
    function project_root() result(root)
        character(len=:), allocatable :: root
        character(len=:), allocatable :: cwd, exe
        character(len=4096) :: arg
        integer :: n
        if (.not. allocated(root_cache)) then
            cwd = current_directory()
            root_cache = ""
            call get_command_argument(0, arg, length=n)
            exe = trim(arg)
            if (index(exe, "/") > 0) then
                if (exe(1:1) /= "/") exe = cwd//"/"//exe
                root_cache = find_root(exe(1:index(exe, "/", back=.true.) - 1))
            end if
            if (len(root_cache) == 0) root_cache = find_root(cwd)
            if (len(root_cache) == 0) write (error_unit, '(a)') &
                "fixtures: no fpm.toml of stickslip above the executable nor above "//cwd
        end if
        root = root_cache
    end function project_root

    !> The first of `start` and its parents that holds stickslip's fpm.toml ('' if none).
    function find_root(start) result(root)
        character(len=*), intent(in) :: start
        character(len=:), allocatable :: root
        character(len=:), allocatable :: dir
        integer :: k
        dir = start
        do while (len(dir) > 1 .and. dir(len(dir):len(dir)) == "/")
            dir = dir(1:len(dir) - 1)
        end do
        do
            if (is_stickslip_manifest(dir//"/fpm.toml")) then
                root = dir
                return
            end if
            k = index(dir, "/", back=.true.)
            if (k <= 1) exit
            dir = dir(1:k - 1)
        end do
        root = ""
    end function find_root

    !> Whether `path` is an fpm.toml with the line name = "stickslip".
    logical function is_stickslip_manifest(path)
        character(len=*), intent(in) :: path
        character(len=512) :: line
        integer :: u, stat
        is_stickslip_manifest = .false.
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        do
            read (u, '(a)', iostat=stat) line
            if (stat /= 0) exit
            line = adjustl(line)
            if (line(1:4) /= "name") cycle
            line = adjustl(line(5:))
            if (line(1:1) /= "=") cycle
            line = adjustl(line(2:))
            is_stickslip_manifest = line == '"stickslip"' .or. line == "'stickslip'"
            exit
        end do
        close (u)
    end function is_stickslip_manifest

    !> The working directory (absolute), from getcwd.
    function current_directory() result(cwd)
        character(len=:), allocatable :: cwd
        character(kind=c_char) :: buf(4096)
        integer :: i
        cwd = ""
        if (.not. c_associated(c_getcwd(buf, int(size(buf), c_size_t)))) return
        do i = 1, size(buf)
            if (buf(i) == c_null_char) exit
            cwd = cwd//buf(i)
        end do
    end function current_directory

    logical function is_directory(path)
        character(len=*), intent(in) :: path
        inquire (file=path//"/.", exist=is_directory)
    end function is_directory

    !> Write `lines` (each trimmed) as the text file `path`.
    subroutine write_lines(path, lines)
        character(len=*), intent(in) :: path
        character(len=*), intent(in) :: lines(:)
        integer :: u, i
        open (newunit=u, file=path, status='replace', action='write')
        do i = 1, size(lines)
            write (u, '(a)') trim(lines(i))
        end do
        close (u)
    end subroutine write_lines

    !> The first line of a file ('' when it cannot be read).
    function first_line(path) result(line)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: line
        character(len=4000) :: buf
        integer :: u, stat
        line = ''
        open (newunit=u, file=path, status='old', action='read', iostat=stat)
        if (stat /= 0) return
        read (u, '(a)', iostat=stat) buf
        close (u)
        if (stat == 0) line = trim(buf)
    end function first_line

    !> The message of an error, '' when none (for test messages).
    function msg(error) result(s)
        type(error_type), allocatable, intent(in) :: error
        character(len=:), allocatable :: s
        s = ""
        if (allocated(error)) s = error%message
    end function msg

    !> A real as es10.3 text (for test messages).
    function rt(x) result(s)
        real(dp), intent(in) :: x
        character(len=:), allocatable :: s
        character(len=32) :: buf
        write (buf, '(es10.3)') x
        s = trim(adjustl(buf))
    end function rt
    !> The whole text of a file ('' when absent).
    function file_text(path) result(text)
        character(len=*), intent(in) :: path
        character(len=:), allocatable :: text
        integer :: u, stat
        integer(8) :: n
        logical :: there
        inquire (file=path, exist=there, size=n)
        if (.not. there .or. n <= 0) then
            text = ''
            return
        end if
        allocate (character(len=n) :: text)
        open (newunit=u, file=path, access='stream', form='unformatted', action='read', &
              iostat=stat)
        if (stat /= 0) return
        read (u, iostat=stat) text
        close (u)
    end function file_text

    !> The number of commas in s (fields of a CSV line minus one).
    pure integer function count_commas(s)
        character(len=*), intent(in) :: s
        integer :: i
        count_commas = 0
        do i = 1, len(s)
            if (s(i:i) == ',') count_commas = count_commas + 1
        end do
    end function count_commas
end module fixtures
