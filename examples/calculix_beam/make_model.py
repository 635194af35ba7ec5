#!/usr/bin/env python3
"""Mesh a cantilever steel strip, let CalculiX export its matrices, convert them for stickslip.

Standard library only; needs CalculiX's solver `ccx` on the PATH (Debian: apt-get install
calculix-ccx) for the export, not for stickslip. Units SI throughout: m, kg, s, N, Pa.

The structure: a blade-like steel strip, 200 mm long (x), 40 mm wide (y), 4 mm thick (z),
clamped at its root x = 0, meshed with 25 x 4 x 1 twenty-node bricks (C3D20R, reduced
integration: quadratic through the thickness, so one layer bends well). E = 210 GPa,
nu = 0.3, rho = 7800 kg/m^3. The tip face is a rigid body (*RIGID BODY, like a tip shroud
or the block a damper is pressed on), its reference node TIP_NODE at the face centre
(x = L, y = W/2, z = t/2); a friction damper rubs on it in the bending direction z (a single
node of a solid mesh as a contact would be a point load: its local, mesh-dependent
flexibility would be the contact's). A shaker drives the strip in z at the centre line two
elements before the tip.

What it does:
 1. writes blade_mesh.inp (nodes, elements, the tip's reference nodes, node sets ROOT,
    TIPFACE, DRIVE), included by the hand-written decks blade_matrices.inp and
    blade_modes.inp;
 2. runs `ccx blade_matrices` (*FREQUENCY, SOLVER=MATRIXSTORAGE: K and M of the constrained
    model to blade_matrices.sti/.mas, one line "i j value" per entry of the upper triangle,
    1-based, explicit zeros included; blade_matrices.dof: "node.direction" of row k on line k)
    and `ccx blade_modes` (*FREQUENCY with CalculiX's own eigensolver), in a scratch folder;
 3. writes, in this script's folder:
      stiffness.mtx, mass.mtx   Matrix Market, coordinate real symmetric, upper triangle as
                                CalculiX stores it (the values copied digit for digit, its
                                zeros and roundoff-level entries dropped: see convert); K in
                                N/m, M in kg for translations (the rows of the rotation node
                                TIP_ROT_NODE are the rigid tip's rotations [rad]: N m/rad,
                                kg m^2 and the mixed units between);
      dofs.csv                  row,node,direction,x,y,z: the row (= DOF number of stickslip)
                                of each node and direction (1 = x, 2 = y, 3 = z) and the
                                node's coordinates [m];
      calculix_frequencies.txt  the natural frequencies of blade_modes.dat (mode, rad/s, Hz);
    and prints the DOF numbers of the contact and the drive.

Usage: python3 make_model.py   (about a second)
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

LENGTH, WIDTH, THICK = 0.200, 0.040, 0.004   # m
NX, NY, NZ = 25, 4, 1                         # elements along x, y, z
TIP_NODE, TIP_ROT_NODE = 9001, 9002          # the rigid tip's reference and rotation nodes
HERE = os.path.dirname(os.path.abspath(__file__))


def mesh():
    """Nodes of a structured 20-node brick mesh: half-step grid points with at most one odd
    index (corners: none odd, mid-edge nodes: one). Returns ({(i, j, k): id}, [(id, x, y, z)],
    [element connectivity])."""
    ids, nodes = {}, []
    for i in range(2 * NX + 1):
        for j in range(2 * NY + 1):
            for k in range(2 * NZ + 1):
                if (i % 2) + (j % 2) + (k % 2) > 1:
                    continue
                ids[(i, j, k)] = len(nodes) + 1
                nodes.append((len(nodes) + 1, LENGTH * i / (2 * NX), WIDTH * j / (2 * NY),
                              THICK * k / (2 * NZ)))
    # C3D20 node order: corners of the bottom face counter-clockwise seen from +z, then the
    # top face, then the mid-edge nodes of the bottom edges, the top edges, the vertical edges
    offsets = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2),
               (0, 2, 2), (1, 0, 0), (2, 1, 0), (1, 2, 0), (0, 1, 0), (1, 0, 2), (2, 1, 2),
               (1, 2, 2), (0, 1, 2), (0, 0, 1), (2, 0, 1), (2, 2, 1), (0, 2, 1)]
    elements = []
    for ex in range(NX):
        for ey in range(NY):
            for ez in range(NZ):
                elements.append([ids[(2 * ex + a, 2 * ey + b, 2 * ez + c)]
                                 for (a, b, c) in offsets])
    return ids, nodes, elements


def write_mesh(path, ids, nodes, elements):
    drive = ids[(2 * NX - 4, NY, NZ)]        # centre line, two elements before the tip
    with open(path, "w") as f:
        f.write("** blade_mesh.inp: written by make_model.py (do not edit; rerun it)\n")
        f.write(f"** strip {LENGTH} x {WIDTH} x {THICK} m, {NX} x {NY} x {NZ} C3D20R\n")
        f.write("*NODE, NSET=NALL\n")
        for (n, x, y, z) in nodes:
            f.write(f"{n}, {x:.10g}, {y:.10g}, {z:.10g}\n")
        f.write("*ELEMENT, TYPE=C3D20R, ELSET=EALL\n")
        for e, conn in enumerate(elements, start=1):
            # at most 16 entries on a data line: the element continues on a second line
            f.write(f"{e}, " + ", ".join(map(str, conn[:15])) + ",\n")
            f.write(", ".join(map(str, conn[15:])) + "\n")
        # the rigid tip's reference node (its translations) and rotation node (its
        # translations are the rotations), at the centre of the tip face
        f.write("*NODE\n")
        for n in (TIP_NODE, TIP_ROT_NODE):
            f.write(f"{n}, {LENGTH:.10g}, {WIDTH / 2:.10g}, {THICK / 2:.10g}\n")
        for name, i in (("ROOT", 0), ("TIPFACE", 2 * NX)):
            members = [ids[key] for key in sorted(ids) if key[0] == i]
            f.write(f"*NSET, NSET={name}\n")
            for a in range(0, len(members), 10):
                f.write(", ".join(map(str, members[a:a + 10])) + "\n")
        f.write(f"*NSET, NSET=DRIVE\n{drive}\n")
    return drive


def run_ccx(job, work, folder=HERE, mesh="blade_mesh.inp", env=None, caller="make_model.py"):
    """Run `ccx -i job` in the scratch folder work on copies of folder's mesh and job.inp (the
    deck that includes the mesh), with the environment env (None: this process's); exit with
    ccx's last output, the message starting with caller, if ccx is missing or fails."""
    ccx = shutil.which("ccx")
    if ccx is None:
        sys.exit(f"{caller}: CalculiX's ccx is not on the PATH (Debian: apt-get install "
                 "calculix-ccx)")
    for name in (mesh, job + ".inp"):
        shutil.copy(os.path.join(folder, name), work)
    run = subprocess.run([ccx, "-i", job], cwd=work, capture_output=True, text=True, env=env)
    if run.returncode != 0 or "Job finished" not in run.stdout:
        sys.exit(f"{caller}: ccx {job} failed:\n{run.stdout[-2000:]}{run.stderr}")


def convert(source, target, unit, dofs):
    """CalculiX's "i j value" upper-triangle lines to a Matrix Market symmetric file, the
    values copied digit for digit; returns the number of entries written. An off-diagonal
    entry below 1e-12 sqrt(|A_ii A_jj|) is dropped (write_triangle): CalculiX stores every
    entry of the sparsity pattern, and those are zeros or the roundoff of the element
    integration (1e-17 of the diagonal in K here), a fifth of K's entries."""
    raw = []
    with open(source) as f:
        for number, line in enumerate(f, start=1):
            parts = line.split()
            if len(parts) != 3:
                sys.exit(f"make_model.py: {source}:{number}: expected 'i j value'")
            i, j, text = int(parts[0]), int(parts[1]), parts[2]
            if not (1 <= i <= j <= dofs):
                sys.exit(f"make_model.py: {source}:{number}: ({i},{j}) not in the upper "
                         f"triangle of a {dofs} x {dofs} matrix")
            raw.append((i, j, float(text), text))
    return write_triangle(target, raw, dofs,
                          f"{unit} of the CalculiX model blade_matrices.inp (*FREQUENCY, "
                          "SOLVER=MATRIXSTORAGE),\nconverted by make_model.py: upper triangle, "
                          "row k = line k of dofs.csv")


def write_triangle(path, entries, dofs, header):
    """Matrix Market coordinate real symmetric file of a dofs x dofs matrix from its upper
    triangle entries [(i, j, value, text)] (1-based, i <= j; text: how value is written),
    column by column, without the off-diagonal entries below 1e-12 sqrt(|A_ii A_jj|). header:
    the comment lines after the banner, each written after "% ". Returns the number of
    entries written."""
    diag = [0.0] * (dofs + 1)
    for (i, j, value, _) in entries:
        if i == j:
            diag[i] = abs(value)
    kept = sorted(((i, j, text) for (i, j, value, text) in entries
                   if i == j or abs(value) > 1e-12 * (diag[i] * diag[j]) ** 0.5),
                  key=lambda e: (e[1], e[0]))
    with open(path, "w") as f:
        f.write("%%MatrixMarket matrix coordinate real symmetric\n")
        for comment in header.split("\n"):
            f.write(f"% {comment}\n")
        f.write(f"{dofs} {dofs} {len(kept)}\n")
        for (i, j, text) in kept:
            f.write(f"{i} {j} {text}\n")
    return len(kept)


def frequencies(dat):
    """(mode, omega [rad/s], f [Hz]) from the eigenvalue table of a CalculiX .dat file."""
    rows, inside = [], False
    with open(dat) as f:
        for line in f:
            if "E I G E N V A L U E   O U T P U T" in line:
                inside = True
                continue
            if inside:
                parts = line.split()
                if len(parts) >= 4 and re.fullmatch(r"\d+", parts[0]):
                    rows.append((int(parts[0]), parts[2], parts[3]))
                elif rows and not parts:
                    break
    if not rows:
        sys.exit(f"make_model.py: no eigenvalue table in {dat}")
    return rows


def main():
    ids, nodes, elements = mesh()
    drive = write_mesh(os.path.join(HERE, "blade_mesh.inp"), ids, nodes, elements)
    xyz = {n: (x, y, z) for (n, x, y, z) in nodes}
    for n in (TIP_NODE, TIP_ROT_NODE):
        xyz[n] = (LENGTH, WIDTH / 2, THICK / 2)
    contact = TIP_NODE
    with tempfile.TemporaryDirectory(prefix="ccx_") as work:
        run_ccx("blade_matrices", work)
        run_ccx("blade_modes", work)
        with open(os.path.join(work, "blade_matrices.dof")) as f:
            rows = [line.split(".") for line in f.read().split()]
        dofs = len(rows)
        nk = convert(os.path.join(work, "blade_matrices.sti"),
                     os.path.join(HERE, "stiffness.mtx"), "stiffness K [N/m]", dofs)
        nm = convert(os.path.join(work, "blade_matrices.mas"),
                     os.path.join(HERE, "mass.mtx"), "mass M [kg]", dofs)
        modes = frequencies(os.path.join(work, "blade_modes.dat"))
    row_of = {}
    with open(os.path.join(HERE, "dofs.csv"), "w") as f:
        f.write("row,node,direction,x,y,z\n")
        for row, (node, direction) in enumerate(rows, start=1):
            n, d = int(node), int(direction)
            row_of[(n, d)] = row
            f.write(f"{row},{n},{d},{xyz[n][0]:.10g},{xyz[n][1]:.10g},{xyz[n][2]:.10g}\n")
    with open(os.path.join(HERE, "calculix_frequencies.txt"), "w") as f:
        f.write("# natural frequencies of blade_modes.inp, from CalculiX's blade_modes.dat\n")
        f.write("# (ccx *FREQUENCY, its own eigensolver; the digits CalculiX prints)\n")
        f.write("# mode  omega [rad/s]  f [Hz]\n")
        for (mode, omega, hz) in modes:
            f.write(f"{mode} {omega} {hz}\n")
    print(f"{len(nodes)} nodes, {len(elements)} C3D20R elements, {dofs} DOFs "
          f"(K: {nk} entries, M: {nm} entries in one triangle)")
    print(f"first natural frequency (CalculiX): {modes[0][1]} rad/s = {modes[0][2]} Hz")
    print(f"contact: node {contact} (the rigid tip's reference node), z -> DOF "
          f"{row_of[(contact, 3)]}")
    print(f"drive:   node {drive} (centre line, x = {xyz[drive][0]:g} m), z -> DOF "
          f"{row_of[(drive, 3)]}")


if __name__ == "__main__":
    main()
