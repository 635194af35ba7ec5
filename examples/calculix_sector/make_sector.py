#!/usr/bin/env python3
"""Mesh one sector of a tuned bladed disk, export its matrices with CalculiX, write a case.

Standard library only; needs CalculiX's solver `ccx` on the PATH (Debian: apt-get install
calculix-ccx) for the export, not for stickslip. Reuses the running of ccx, the reading of
CalculiX's matrices and the Matrix Market writer of ../calculix_beam/make_model.py. Units SI
throughout: m, kg, s, N, Pa.

The structure: one of N = 24 sectors (15 degrees, theta from -pi/N to +pi/N about the z axis)
of a steel bladed disk, E = 210 GPa, nu = 0.3, rho = 7800 kg/m^3, meshed with twenty-node
bricks (C3D20R) on a structured grid in (r, theta, z), mapped to x = r cos theta,
y = r sin theta, z (the mid-side nodes placed by the mapping: curved edges). The grid's cells
make up
  the disk       r 0.120 .. 0.200, the whole sector, z -0.010 .. 0.010 (3 x 7 x 2 cells),
                 clamped at the hub r = 0.12 (node set HUB);
  the platforms  r 0.200 .. 0.205, |theta| <= 0.85 pi/N, z -0.020 .. 0.020 (1 x 5 x 4): they
                 leave a gap at both cyclic faces;
  the blade      r 0.205 .. 0.350, a band 4 mm thick about theta = 0 (its faces at
                 theta = +-0.002/r: constant thickness), z -0.020 .. 0.020 (6 x 1 x 4).
Each platform's free edge face (theta = -+0.85 pi/N) is a *RIGID BODY whose reference node
sits exactly at the sector's edge angle, r = 0.2025, z = 0: node 9001 at theta = -pi/N,
9003 at +pi/N (each with its rotation node, 9002 and 9004; with more than 9000 mesh nodes the
next power of ten plus 1 to 4), so the right platform's reference node of
sector s is the left one's of sector s + 1: the two rub there. The cyclic faces LEFT
(theta = -pi/N) and RIGHT (+pi/N) are the disk's, without the clamped hub line; the right
node of each pair is the left one turned by 2 pi/N. A shaker drives the blade's surface
(theta = +0.002/r) at mid-chord z = 0 one element below the tip, tangentially.

What it does:
 1. writes sector_mesh.inp (nodes, elements, the platforms' reference nodes, node sets HUB,
    LEFT, RIGHT, LPLAT, RPLAT, DRIVE), included by the hand-written decks
    sector_matrices.inp (*FREQUENCY, SOLVER=MATRIXSTORAGE: K and M) and sector_modes.inp
    (*CYCLIC SYMMETRY MODEL, N=24: the bladed disk's natural frequencies, nodal diameters 0
    to 12, by CalculiX's own eigensolver, the platforms free of each other);
 2. runs both with `ccx` in a scratch folder and turns the matrices, Cartesian in CalculiX,
    into every node's own cylindrical frame: K' = Q^T K Q, Q block diagonal with, per node,
    the rotation by the node's angle theta (the reference and rotation nodes of a rigid body
    by their reference node's angle, -+pi/N; a rotation node's three rows are the rigid
    body's rotation vector). A left DOF and its paired right DOF are then the same
    component of the same physical point of two neighbouring sectors, as stickslip's
    &cyclic wants (doc/cyclic.md). Checks: the trace of every node's diagonal block is kept,
    and the paired left and right DOFs (and the two platforms' reference and rotation nodes,
    mirror images) have the same diagonal in K and M (the sector is symmetric about
    theta = 0);
 3. writes, in this script's folder:
      stiffness.mtx, mass.mtx   Matrix Market, coordinate real symmetric, upper triangle,
                                1-based, in the nodes' frames; entries below
                                1e-12 sqrt(|A_ii A_jj|) dropped as make_model.py does; K in
                                N/m, M in kg for translations (the rotation nodes' rows are
                                rotations [rad]);
      dofs.csv                  row,node,direction,x,y,z: the row (= DOF number of stickslip)
                                of each node and direction, 1 = r (radial), 2 = theta
                                (tangential, towards increasing angle), 3 = z (axial), in the
                                frame at the node's angle, and the node's Cartesian
                                coordinates [m];
      case.nml                  the stickslip case: the sector with its &cyclic boundary
                                (left_dofs, right_dofs in pairs), the platform contact
                                against the next sector, engine order 3, the sector
                                reduced by Craig-Bampton;
      calculix_frequencies.txt  the natural frequencies of sector_modes.dat per nodal
                                diameter (nd, mode, rad/s, Hz);
    and prints the DOF counts, the checks and the DOF numbers of the contact and the drive.

Options:
  --refine K  split every cell of the grid into K x K x K cells (K >= 1, default 1: the
              example): the same sector with about 1.2 K^3 thousand DOFs (10734, 33414 and
              75894 at K = 2, 3, 4; each face about K^2 times the example's 72 DOFs), for
              measuring the program on FE sectors of 10^4 to 10^5 DOFs. With
              K > 1 CalculiX's cyclic modes are computed in the engine order's nodal diameter
              only (the case needs its frequencies), and the case writes its results to
              out/calculix_sector_rK;
  --out DIR   write every file into DIR (created if missing; default: this script's folder),
              the two decks copied there beside the mesh.

Usage: python3 make_sector.py [--refine K] [--out DIR]   (K = 1: about 6 s, 4 s the cyclic
       modes in ccx, 1.5 s the rotation)
"""
import argparse
import math
import os
import re
import shutil
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))   # the project's root
sys.dont_write_bytecode = True        # no __pycache__ left in ../calculix_beam
sys.path.insert(0, os.path.join(HERE, "..", "calculix_beam"))
import make_model  # noqa: E402  (run_ccx, convert, write_triangle)

SECTORS = 24
EDGE = math.pi / SECTORS                              # half the sector angle [rad]
R_DISK = [0.120, 0.1466666666667, 0.1733333333333, 0.200]   # radial grid lines [m]
R_PLAT, R_TIP, NR_BLADE = 0.205, 0.350, 6
Z_LINES = [-0.020, -0.010, 0.0, 0.010, 0.020]         # axial grid lines [m]
DISK_Z = 0.010                                        # the disk's half thickness [m]
PLATFORM_EDGE = 0.85 * EDGE                           # the platforms end at |theta| = this
HALF_BLADE = 0.002                                    # the blade's half thickness [m]
R_REF = 0.5 * (R_DISK[-1] + R_PLAT)                   # the reference nodes' radius [m]
ENGINE_ORDER, ZETA = 3, 0.003


def reference_nodes(count):
    """The platforms' reference and rotation node numbers (left reference, its rotation, right
    reference, its rotation) above a mesh of count nodes numbered from 1: 9001 .. 9004 when
    count < 9000 (the example's), else the next power of ten plus 1 .. 4."""
    base = 9000 if count < 9000 else 10 ** len(str(count))
    return base + 1, base + 2, base + 3, base + 4


def subdivide(lines, k):
    """Grid lines with each interval of lines split into k equal ones."""
    return [lines[i] + (lines[i + 1] - lines[i]) * m / k
            for i in range(len(lines) - 1) for m in range(k)] + [lines[-1]]


def theta_line(j, r):
    """The angle [rad] of theta grid line j (0 .. 7) at radius r: the sector's edges, the
    platforms' edges, two lines halfway to the blade, the blade's faces at +-HALF_BLADE / r
    (nearly the straight lines y = +-HALF_BLADE: the blade as thick at the tip as at the
    root)."""
    blade = HALF_BLADE / r
    middle = 0.5 * (PLATFORM_EDGE + blade)
    return [-EDGE, -PLATFORM_EDGE, -middle, -blade, blade, middle, PLATFORM_EDGE, EDGE][j]


def half_step(lines, i):
    """Grid coordinate at half index i: a line (i even) or the middle of two (i odd)."""
    return lines[i // 2] if i % 2 == 0 else 0.5 * (lines[i // 2] + lines[i // 2 + 1])


def fine_theta_line(j, r, refine):
    """The angle [rad] of the refined grid's theta line j (0 .. 7 refine) at radius r: line
    j // refine of theta_line and the next, split in refine equal angles."""
    coarse, m = divmod(j, refine)
    if m == 0:
        return theta_line(coarse, r)
    low, high = theta_line(coarse, r), theta_line(coarse + 1, r)
    return low + (high - low) * m / refine


def mesh(refine):
    """The sector's C3D20R mesh on the structured grid, each cell of the coarse grid split in
    refine^3: the cells of the disk, the platforms and the blade, their nodes at half-step
    grid points with at most one odd index (as make_model.mesh), numbered in grid order.
    Returns ({(i, j, k): id}, {id: (r, theta, z)}, [element connectivity])."""
    r_lines = subdivide(R_DISK + [R_PLAT] + [R_PLAT + (R_TIP - R_PLAT) * n / NR_BLADE
                                             for n in range(1, NR_BLADE + 1)], refine)
    z_lines = subdivide(Z_LINES, refine)
    nr, nt, nz = len(r_lines) - 1, 7 * refine, len(z_lines) - 1
    plat = len(R_DISK) - 1                            # the platforms' coarse cell in r
    cells = []
    for ci in range(nr):
        for cj in range(nt):
            for ck in range(nz):
                cr, ct = ci // refine, cj // refine     # the coarse cell
                in_disk = cr < plat and abs(half_step(z_lines, 2 * ck + 1)) < DISK_Z
                in_plat = cr == plat and 1 <= ct <= 5
                in_blade = cr > plat and ct == 3
                if in_disk or in_plat or in_blade:
                    cells.append((ci, cj, ck))
    # C3D20 node order (make_model.mesh) with (r, theta, z) for (x, y, z): right-handed
    offsets = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2),
               (0, 2, 2), (1, 0, 0), (2, 1, 0), (1, 2, 0), (0, 1, 0), (1, 0, 2), (2, 1, 2),
               (1, 2, 2), (0, 1, 2), (0, 0, 1), (2, 0, 1), (2, 2, 1), (0, 2, 1)]
    used = sorted({(2 * ci + a, 2 * cj + b, 2 * ck + c)
                   for (ci, cj, ck) in cells for (a, b, c) in offsets})
    ids, cyl = {}, {}
    for n, (i, j, k) in enumerate(used, start=1):
        r = half_step(r_lines, i)
        ids[(i, j, k)] = n
        cyl[n] = (r, half_step([fine_theta_line(m, r, refine) for m in range(nt + 1)], j),
                  half_step(z_lines, k))
    elements = [[ids[(2 * ci + a, 2 * cj + b, 2 * ck + c)] for (a, b, c) in offsets]
                for (ci, cj, ck) in cells]
    return ids, cyl, elements


def node_sets(ids, cyl, refine):
    """The named node sets of the mesh, and the (left, right) node pairs of the cyclic faces
    (same grid indices r and z: same r and z)."""
    jmax = max(j for (_, j, _) in ids)
    plat = 2 * refine * (len(R_DISK) - 1)             # half index of r = 0.200

    def face(j):
        """The nodes of the platform edge face at theta line half index j."""
        return [n for (i, jj, _), n in sorted(ids.items()) if jj == j and i >= plat]

    sets = {"HUB": [n for (i, _, _), n in sorted(ids.items()) if i == 0],
            "LEFT": [n for (i, j, _), n in sorted(ids.items()) if j == 0 and i > 0],
            "RIGHT": [n for (i, j, _), n in sorted(ids.items()) if j == jmax and i > 0],
            "LPLAT": face(2 * refine), "RPLAT": face(jmax - 2 * refine)}
    pairs = [(n, ids[(i, jmax, k)]) for (i, j, k), n in sorted(ids.items())
             if j == 0 and i > 0]
    imax = max(i for (i, _, _) in ids)
    # one coarse element below the tip, on the blade's face theta = +HALF_BLADE / r, z = 0
    drive = ids[(imax - 2 * refine, 8 * refine, max(k for (_, _, k) in ids) // 2)]
    sets["DRIVE"] = [drive]
    for (a, b) in pairs:
        (ra, _, za), (rb, _, zb) = cyl[a], cyl[b]
        if abs(ra - rb) > 1e-12 or abs(za - zb) > 1e-12:
            sys.exit(f"make_sector.py: cyclic pair {a}, {b} not at the same r, z")
    return sets, pairs, drive


def cartesian(r, theta, z):
    """(x, y, z) of a point given in cylindrical coordinates."""
    return (r * math.cos(theta), r * math.sin(theta), z)


def write_mesh(path, cyl, elements, sets, refs):
    """sector_mesh.inp: the nodes, the elements (16 nodes on the first line, as
    make_model.write_mesh), the rigid bodies' reference and rotation nodes and the sets."""
    with open(path, "w") as f:
        f.write("** sector_mesh.inp: written by make_sector.py (do not edit; rerun it)\n")
        f.write(f"** one of {SECTORS} sectors of a bladed disk, {len(elements)} C3D20R\n")
        f.write("*NODE, NSET=NALL\n")
        for n in sorted(cyl):
            x, y, z = cartesian(*cyl[n])
            f.write(f"{n}, {x:.12g}, {y:.12g}, {z:.12g}\n")
        f.write("*ELEMENT, TYPE=C3D20R, ELSET=EALL\n")
        for e, conn in enumerate(elements, start=1):
            f.write(f"{e}, " + ", ".join(map(str, conn[:15])) + ",\n")
            f.write(", ".join(map(str, conn[15:])) + "\n")
        # the platforms' reference nodes (translations) and rotation nodes (their
        # translations are the rotations), on the sector's edges
        f.write("*NODE\n")
        for n in refs:
            x, y, z = cartesian(*refs[n])
            f.write(f"{n}, {x:.12g}, {y:.12g}, {z:.12g}\n")
        for name, members in sets.items():
            f.write(f"*NSET, NSET={name}\n")
            for a in range(0, len(members), 10):
                f.write(", ".join(map(str, members[a:a + 10])) + "\n")


def read_triangle(path):
    """{(i, j): value} of a Matrix Market upper triangle written by make_model.convert."""
    entries = {}
    with open(path) as f:
        lines = [line for line in f if not line.startswith("%")]
    for line in lines[1:]:
        i, j, value = line.split()
        entries[(int(i), int(j))] = float(value)
    return entries


def rotate(entries, rows, angle):
    """Q^T A Q of a symmetric matrix given by its upper triangle {(i, j): value}, rows[k - 1]
    = (node, direction) of row k, Q the rotation about z by angle[node] on each node's three
    rows. Works on 3 x 3 blocks per pair of nodes (a diagonal block filled from its upper
    part); returns the upper triangle of the result."""
    row_of = {nd: k for k, nd in enumerate(rows, start=1)}
    blocks = {}
    for (i, j), value in entries.items():
        for (p, q) in {(i, j), (j, i)}:
            (a, da), (b, db) = rows[p - 1], rows[q - 1]
            blocks.setdefault((a, b), [[0.0] * 3 for _ in range(3)])[da - 1][db - 1] = value
    result = {}
    for (a, b), block in blocks.items():
        ca, sa = math.cos(angle[a]), math.sin(angle[a])
        cb, sb = math.cos(angle[b]), math.sin(angle[b])
        qa = [[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]]
        qb = [[cb, -sb, 0.0], [sb, cb, 0.0], [0.0, 0.0, 1.0]]
        bq = [[sum(block[k][m] * qb[m][d] for m in range(3)) for d in range(3)]
              for k in range(3)]
        for c in range(3):
            for d in range(3):
                p, q = row_of[(a, c + 1)], row_of[(b, d + 1)]
                if p <= q:
                    result[(p, q)] = sum(qa[k][c] * bq[k][d] for k in range(3))
    return result


def cyclic_frequencies(dat):
    """(nodal diameter, mode, omega [rad/s], f [Hz]) of every eigenvalue table of a
    CalculiX cyclic symmetry .dat file (columns: diameter, mode, eigenvalue, rad/time,
    cycles/time, imaginary part)."""
    rows = []
    with open(dat) as f:
        for line in f:
            parts = line.split()
            if len(parts) == 6 and re.fullmatch(r"\d+ \d+", " ".join(parts[:2])):
                rows.append((int(parts[0]), int(parts[1]), parts[3], parts[4]))
    if not rows:
        sys.exit(f"make_sector.py: no cyclic eigenvalue table in {dat}")
    return rows


def from_root(path):
    """path relative to the project's root when it is inside it, else absolute."""
    rel = os.path.relpath(os.path.abspath(path), ROOT)
    return os.path.abspath(path) if rel.startswith("..") else rel


def namelist_list(name, values, indent=2):
    """`name = v1, v2, ...` broken over lines under 100 characters (a namelist list)."""
    lines, line = [], " " * indent + f"{name} = "
    for n, v in enumerate(values):
        item = f"{v}," if n < len(values) - 1 else f"{v}"
        if len(line) + len(item) > 96:
            lines.append(line.rstrip())
            line = " " * (indent + len(name) + 3)
        line += item + " "
    lines.append(line.rstrip())
    return "\n".join(lines)


def write_case(path, dofs, cyclic, contact, drive, modes, refine, ref):
    """case.nml: the sector's forced response in engine order 3 across its axial family at
    nodal diameter 3 (the second distinct frequency of CalculiX's diameter 3; the first, the
    blades' tangential bending, leaves the platforms' z still: see the case's comment), the
    platforms rubbing axially, each cyclic face by 12 interface modes. cyclic = (left_dofs,
    right_dofs), contact = (contact_dof, next_dof), drive = the driven node's axial DOF,
    refine the mesh's (1: the example; otherwise the results go to out/calculix_sector_rK),
    ref the platforms' reference_nodes."""
    nd3 = sorted({float(m[2]) for m in modes if m[0] == ENGINE_ORDER})
    first, omega = nd3[0], nd3[1]
    alpha = 2.0 * ZETA * omega

    face = len(cyclic[0])
    size = (f"{dofs} DOFs is below the\n! 2000 at which 'auto' reduces" if dofs < 2000 else
            f"'auto' would choose it too at\n! {dofs} DOFs")
    mesh = "" if refine == 1 else f", each cell of the example's\n! mesh split in {refine}^3"
    out = "out/calculix_sector" + ("" if refine == 1 else f"_r{refine}")
    keeps = ") keeps the cyclic faces, the contact, its partner and the"

    def line(text, comment):
        """A namelist line with its comment from column 37, as ../calculix_beam/case.nml."""
        return f"  {text}".ljust(36) + f"! {comment}\n"

    with open(path, "w") as f:
        f.write(f"""\
! One sector of a tuned bladed disk of {SECTORS} sectors exported from CalculiX (make_sector.py:
! steel disk, platforms and a blade, C3D20R, {dofs} DOFs, SI units{mesh}), every DOF in its node's
! cylindrical frame (r, theta, z). The right platform's rigid edge rubs axially (z) on the
! left platform of the next sector, at the sectors' common edge. Forced in engine order
! {ENGINE_ORDER} near the blade tip, axially: swept across the axial (out-of-plane) family of nodal
! diameter {ENGINE_ORDER} (disk and blades bending in z; CalculiX, platforms free: {omega:.1f}
! rad/s).
! Not the first family ({first:.1f} rad/s, the blades bending tangentially): the sector is
! symmetric about z = 0 and that family moves in-plane, so the platforms' z stays exactly
! still (the contact sticks with zero force); its platforms' r and theta move 5e-5 of the tip.
! The reduction (Craig-Bampton, &reduction method = 'craig-bampton': {size}{keeps}
! drive as boundary DOFs, then describes each face by 12 interface modes (the faces' motion
! in the sector's cyclic modes; doc/cyclic.md); summary.nml reports its error per nodal
! diameter the harmonics reach (reduction_error_nd3, _nd9) against the full sector.
! normal_load: in CalculiX's mode the platforms' relative z motion is 0.8 % of the drive's,
! so an energy balance puts lock-up near mu N = 100 N per N of drive; with mu N = 30 N the
! platforms stick over part of the period.
! Run: fpm run -- {from_root(path)}   (writes {out}/)
&system
""")
        f.write(line("mass_file = 'mass.mtx'", "kg; relative paths: from this file's folder"))
        f.write(line("stiffness_file = 'stiffness.mtx'", "N/m"))
        f.write(line(f"rayleigh_alpha = {alpha:.1f}",
                     f"2 zeta omega: {100 * ZETA:.1f} % of critical at {omega:.1f} rad/s"))
        f.write("/\n&forcing\n")
        f.write(line(f"omega = {omega:.1f}", "rad/s (the sweep below moves it)"))
        f.write(line(f"force_dof = {drive}", "blade surface near the tip, mid-chord, z: dofs.csv"))
        f.write(line("force_amplitude = 1.0", "N"))
        f.write("/\n&friction\n")
        f.write(line(f"contact_dof = {contact[0]}", f"node {ref[2]} (right platform's edge), z"))
        f.write("  mu = 0.3\n")
        f.write(line("normal_load = 100.0", "N: mu N = 30 N"))
        f.write("/\n! left_dofs, right_dofs: the disk's cyclic faces without the hub line, node by "
                "node (r, theta, z)\n")
        f.write(f"&cyclic\n  sectors = {SECTORS}\n  engine_order = {ENGINE_ORDER}\n")
        f.write(line(f"next_dof = {contact[1]}", f"node {ref[0]} (left platform's edge) of "
                     "sector s + 1, z"))
        f.write(namelist_list("left_dofs", cyclic[0]) + "\n")
        f.write(namelist_list("right_dofs", cyclic[1]) + "\n")
        f.write("/\n&reduction\n")
        f.write(line("method = 'craig-bampton'", "keeps the contact, the drive and the cyclic "
                     "faces,"))
        f.write(line("interface_modes = 12", f"each face ({face} DOFs) by 12 interface modes"))
        f.write("/\n")
        f.write("&hbm\n  harmonics = 15\n")
        f.write(line("odd_only = T", "no static load: half-wave symmetric response"))
        f.write(line("samples = 384", f"a multiple of {SECTORS}: the sector is exact "
                     "(doc/cyclic.md)"))
        f.write("/\n&run method = 'sweep' /\n&sweep\n  parameter = 'omega'\n")
        f.write(f"  start = {0.9 * omega:.1f}\n  stop = {1.1 * omega:.1f}\n")
        f.write(line(f"max_step = {omega / 500:.1f}", "rad/s: about 100 points"))
        f.write(line("stability = F", f"the whole disk's Floquet multipliers: {SECTORS} x "
                     f"{dofs} DOFs"))
        f.write(f"/\n&output\n  directory = '{out}'\n")
        f.write(line(f"dofs = {contact[0]}, {contact[1]}, {drive}",
                     "the contact, its partner, the drive"))
        f.write("/\n")


def arguments():
    """The command line: (refine, output folder)."""
    parser = argparse.ArgumentParser(description="Mesh one sector of a bladed disk, export "
                                     "its matrices with CalculiX, write a stickslip case.")
    parser.add_argument("--refine", type=int, default=1, metavar="K",
                        help="split every cell of the grid into K^3 (default 1)")
    parser.add_argument("--out", default=HERE, metavar="DIR",
                        help="folder for the files (default: this script's)")
    args = parser.parse_args()
    if args.refine < 1:
        parser.error(f"--refine {args.refine}: K must be at least 1")
    if args.refine > 1 and os.path.abspath(args.out) == HERE:
        parser.error("--refine K > 1 needs --out DIR: this folder holds the example")
    return args.refine, os.path.abspath(args.out)


def prepare_decks(out, refine, ref):
    """Copy the two CalculiX decks to out (when it is not this folder) with the platforms'
    reference nodes ref; with refine > 1 the modes deck asks for the engine order's nodal
    diameter only."""
    for deck in ("sector_matrices.inp", "sector_modes.inp"):
        with open(os.path.join(HERE, deck)) as f:
            text = f.read()
        edits = [(f"REF NODE={9001 + 2 * side}, ROT NODE={9002 + 2 * side}",
                  f"REF NODE={ref[2 * side]}, ROT NODE={ref[2 * side + 1]}") for side in (0, 1)]
        if refine > 1 and deck == "sector_modes.inp":
            edits.append(("NMIN=0, NMAX=12", f"NMIN={ENGINE_ORDER}, NMAX={ENGINE_ORDER}"))
        for (old, new) in edits:
            if text.count(old) != 1:
                sys.exit(f"make_sector.py: {deck}: expected one '{old}'")
            text = text.replace(old, new)
        target = os.path.join(out, deck)
        if os.path.abspath(target) != os.path.join(HERE, deck):
            with open(target, "w") as f:
                f.write(text)


def main():
    """Mesh, run ccx, rotate and check the matrices, write the files, print the figures."""
    start = time.time()
    refine, out = arguments()
    os.makedirs(out, exist_ok=True)
    ids, cyl, elements = mesh(refine)
    sets, pairs, drive = node_sets(ids, cyl, refine)
    ref = reference_nodes(len(cyl))
    prepare_decks(out, refine, ref)
    refs = {ref[0]: (R_REF, -EDGE, 0.0), ref[1]: (R_REF, -EDGE, 0.0),
            ref[2]: (R_REF, EDGE, 0.0), ref[3]: (R_REF, EDGE, 0.0)}
    cyl.update(refs)
    write_mesh(os.path.join(out, "sector_mesh.inp"), cyl, elements, sets, refs)
    angle = {n: cyl[n][1] for n in cyl}
    one_core = dict(os.environ, OMP_NUM_THREADS="1")   # ccx on one core
    with tempfile.TemporaryDirectory(prefix="ccx_") as work:
        for job in ("sector_matrices", "sector_modes"):
            make_model.run_ccx(job, work, out, "sector_mesh.inp", one_core, "make_sector.py")
        with open(os.path.join(work, "sector_matrices.dof")) as f:
            rows = [tuple(map(int, line.split("."))) for line in f.read().split()]
        dofs = len(rows)
        cart = {}
        for name, ext, unit in (("K", "sti", "stiffness K [N/m]"), ("M", "mas", "mass M [kg]")):
            make_model.convert(os.path.join(work, "sector_matrices." + ext),
                               os.path.join(work, name + ".mtx"), unit, dofs)
            cart[name] = read_triangle(os.path.join(work, name + ".mtx"))
        modes = cyclic_frequencies(os.path.join(work, "sector_modes.dat"))
    row_of = {nd: k for k, nd in enumerate(rows, start=1)}
    if any((n, d) not in row_of for (n, _) in rows for d in (1, 2, 3)):
        sys.exit("make_sector.py: a node without all three directions in the .dof file")
    cylm = {name: rotate(cart[name], rows, angle) for name in cart}
    nnz = {}
    # write_triangle drops the off-diagonal entries below 1e-12 sqrt(|A_ii A_jj|) (convert's
    # rule): here also the roundoff of the rotation
    for name, unit, file in (("K", "stiffness K [N/m]", "stiffness.mtx"),
                             ("M", "mass M [kg]", "mass.mtx")):
        nnz[name] = make_model.write_triangle(
            os.path.join(out, file),
            [(i, j, v, f"{v:.15g}") for (i, j), v in cylm[name].items()], dofs,
            f"{unit} of the CalculiX model sector_matrices.inp (*FREQUENCY, "
            "SOLVER=MATRIXSTORAGE),\nturned into the nodes' cylindrical frames (r, theta, z) "
            "by make_sector.py:\nupper triangle, row k = line k of dofs.csv")
    # checks: the trace of each node's diagonal block is kept by the rotation; a left DOF
    # and its right partner (mirror images) have the same diagonal
    trace, match = 0.0, {"K": 0.0, "M": 0.0}
    for name in cart:
        for n in {n for (n, _) in rows}:
            before = sum(cart[name][(row_of[(n, d)],) * 2] for d in (1, 2, 3))
            after = sum(cylm[name][(row_of[(n, d)],) * 2] for d in (1, 2, 3))
            trace = max(trace, abs(after - before) / abs(before))
    node_pairs = [(a, b) for (a, b) in pairs if (a, 1) in row_of]
    mirrored = node_pairs + [(ref[0], ref[2]), (ref[1], ref[3])]
    for name in cylm:
        for (a, b) in mirrored:
            for d in (1, 2, 3):
                ka, kb = (cylm[name][(row_of[(n, d)],) * 2] for n in (a, b))
                match[name] = max(match[name], abs(ka - kb) / max(abs(ka), abs(kb)))
    if max(match.values()) > 1e-8 or trace > 1e-12:
        sys.exit(f"make_sector.py: check failed: paired diagonals {match}, trace {trace:.2e}")
    left = [row_of[(a, d)] for (a, _) in node_pairs for d in (1, 2, 3)]
    right = [row_of[(b, d)] for (_, b) in node_pairs for d in (1, 2, 3)]
    with open(os.path.join(out, "dofs.csv"), "w") as f:
        f.write("row,node,direction,x,y,z\n")
        for row, (n, d) in enumerate(rows, start=1):
            x, y, z = cartesian(*cyl[n])
            f.write(f"{row},{n},{d},{x:.10g},{y:.10g},{z:.10g}\n")
    with open(os.path.join(out, "calculix_frequencies.txt"), "w") as f:
        f.write("# natural frequencies of the bladed disk, sector_modes.inp (*CYCLIC SYMMETRY "
                f"MODEL, N={SECTORS}),\n# from CalculiX's sector_modes.dat (the digits it "
                "prints; a diameter 1..11 mode comes twice)\n# nd  mode  omega [rad/s]  f [Hz]\n")
        for (nd, mode, omega, hz) in modes:
            f.write(f"{nd} {mode} {omega} {hz}\n")
    contact, nxt = row_of[(ref[2], 3)], row_of[(ref[0], 3)]
    write_case(os.path.join(out, "case.nml"), dofs, (left, right), (contact, nxt),
               row_of[(drive, 3)], modes, refine, ref)
    print(f"{len(cyl) - 4} nodes and 4 reference nodes, {len(elements)} C3D20R elements, "
          f"{dofs} DOFs (K: {nnz['K']} entries, M: {nnz['M']} entries in one triangle)")
    print(f"cyclic boundary: {len(node_pairs)} node pairs, {len(left)} DOF pairs")
    print(f"largest relative mismatch of the paired (and mirrored) diagonals: K {match['K']:.2e}, "
          f"M {match['M']:.2e}; of a node block's trace after the rotation: {trace:.2e}")
    for n, what in zip(ref, ("left platform's reference", "its rotation",
                             "right platform's reference", "its rotation")):
        print(f"node {n} ({what}): r, theta, z -> DOFs "
              + ", ".join(str(row_of[(n, d)]) for d in (1, 2, 3)))
    print(f"contact: DOF {contact} (node {ref[2]}, z), next_dof {nxt} (node {ref[0]}, z)")
    print(f"drive:   node {drive} (r = {cyl[drive][0]:g} m, z = 0): theta -> DOF "
          f"{row_of[(drive, 2)]}, z -> DOF {row_of[(drive, 3)]} (case.nml)")
    for nd in sorted({m[0] for m in modes}):
        print(f"nodal diameter {nd:2d}: " + ", ".join(
            f"{float(m[3]):.1f}" for m in modes if m[0] == nd) + " Hz")
    print(f"{time.time() - start:.1f} s")


if __name__ == "__main__":
    main()
