#!/usr/bin/env python3
"""Write the FE matrices of a cantilever beam as Matrix Market files (standard library only).

Euler-Bernoulli beam elements (2 nodes, transverse displacement w and rotation theta per
node, cubic Hermite shape functions, consistent mass), clamped at x = 0: the clamped node is
removed, so DOF 2k-1 is w and DOF 2k is theta of node k = 1..ne (node ne is the free tip).
Steel strip 1 m x 40 mm x 10 mm, bending about the thin axis: EI = 700 N m^2, rho A =
3.12 kg/m, first bending mode 52.7 rad/s (8.4 Hz), second 330 rad/s. Forty elements by default
(cond(K) = 6e7: the check of the dynamic stiffness measures the distance to a resonance,
not the mesh's conditioning).

Usage: python3 make_beam.py [elements]   (default 40: 80 DOFs; writes mass.mtx and
stiffness.mtx, coordinate real symmetric, lower triangle, in this script's folder)
"""
import os
import sys

E, RHO = 210e9, 7800.0          # Pa, kg/m^3
LENGTH, WIDTH, HEIGHT = 1.0, 0.04, 0.01  # m
EI = E * WIDTH * HEIGHT**3 / 12.0
RHOA = RHO * WIDTH * HEIGHT


def element(le):
    """Element stiffness and consistent mass (4 x 4: w1, theta1, w2, theta2)."""
    k = [[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
         [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]]
    m = [[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
         [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]]
    ck, cm = EI / le**3, RHOA * le / 420.0
    return [[ck * v for v in row] for row in k], [[cm * v for v in row] for row in m]


def assemble(ne):
    """Global K and M (dicts (i, j) -> value, 1-based, lower triangle) without the clamp."""
    le = LENGTH / ne
    ke, me = element(le)
    kg, mg = {}, {}
    for e in range(ne):
        # global DOFs of the element's (w1, theta1, w2, theta2); node 0 is clamped (0 = removed)
        dofs = [2 * e - 1, 2 * e, 2 * e + 1, 2 * e + 2] if e > 0 else [0, 0, 1, 2]
        for a in range(4):
            for b in range(4):
                i, j = dofs[a], dofs[b]
                if i == 0 or j == 0 or i < j:
                    continue
                kg[(i, j)] = kg.get((i, j), 0.0) + ke[a][b]
                mg[(i, j)] = mg.get((i, j), 0.0) + me[a][b]
    return kg, mg


def write(path, n, entries):
    with open(path, "w") as f:
        f.write("%%MatrixMarket matrix coordinate real symmetric\n")
        f.write("% cantilever Euler-Bernoulli beam, written by make_beam.py\n")
        f.write(f"{n} {n} {len(entries)}\n")
        for (i, j) in sorted(entries, key=lambda ij: (ij[1], ij[0])):
            f.write(f"{i} {j} {entries[(i, j)]:.17e}\n")


def main():
    ne = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    here = os.path.dirname(os.path.abspath(__file__))
    kg, mg = assemble(ne)
    write(os.path.join(here, "stiffness.mtx"), 2 * ne, kg)
    write(os.path.join(here, "mass.mtx"), 2 * ne, mg)


if __name__ == "__main__":
    main()
