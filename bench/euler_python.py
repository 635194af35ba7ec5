#!/usr/bin/env python3
"""A plain Python implicit Euler (Moreau-Jean) stepper: the scheme of
src/time/stickslip_euler.f90 in pure Python (lists and floats, no NumPy), for
bench/euler_vs_python.sh.

    x_{n+1} = x_n + h v_{n+1}
    (M + h C + h^2 K) v_{n+1} = M v_n - h K x_n + h f(t_{n+1}) + h W r_{n+1}

with Coulomb's law for r (closed form for one contact, projected Gauss-Seidel
for several), from rest until the states one period apart differ by less than
tol times the amplitude over the period. The model is the seed case of
examples/seed.nml. Usage: euler_python.py [steps_per_period [tol]]
Prints the periods, the defect, the stepping time and the final state.
"""
import math
import sys
import time


def seed():
    return dict(mass=[[1.0, 0.0], [0.0, 1.0]],
                stiffness=[[2.0, -1.0], [-1.0, 1.0]],
                damping=[[0.0, 0.0], [0.0, 0.0]],
                omega=4.5,
                forces=[(1, 10.0, 0.0, [1.0, 0.0])],   # harmonic, amplitude, phase, shape
                contacts=[([0.0, 1.0], 0.45 * 1.0)])   # direction, limit mu N


def solve(a, b):
    """Solve a x = b (b a list of columns) by Gaussian elimination, partial pivoting."""
    n = len(a)
    m = [row[:] + [col[i] for col in b] for i, row in enumerate(a)]
    for k in range(n):
        p = max(range(k, n), key=lambda i: abs(m[i][k]))
        m[k], m[p] = m[p], m[k]
        for i in range(k + 1, n):
            f = m[i][k] / m[k][k]
            for j in range(k, len(m[i])):
                m[i][j] -= f * m[k][j]
    x = [[0.0] * n for _ in b]
    for c in range(len(b)):
        for i in reversed(range(n)):
            s = m[i][n + c] - sum(m[i][j] * x[c][j] for j in range(i + 1, n))
            x[c][i] = s / m[i][i]
    return x  # columns


def integrate(model, steps_per_period=1000, tol=1e-8, max_periods=2000):
    n = len(model["mass"])
    mass, stiff, damp = model["mass"], model["stiffness"], model["damping"]
    period_t = 2.0 * math.pi / model["omega"]
    h = period_t / steps_per_period
    s = [[mass[i][j] + h * damp[i][j] + h * h * stiff[i][j] for j in range(n)]
         for i in range(n)]
    # columns of S^{-1} [M, -h K, F] and S^{-1} W
    cols = [[mass[i][j] for i in range(n)] for j in range(n)]
    cols += [[-h * stiff[i][j] for i in range(n)] for j in range(n)]
    cols += [f[3] for f in model["forces"]]
    acols = solve(s, cols)
    a = [[acols[j][i] for j in range(len(acols))] for i in range(n)]  # rows
    w = [c[0] for c in model["contacts"]]
    limit = [c[1] for c in model["contacts"]]
    nc = len(w)
    sw = solve(s, w) if nc else []
    d = [[h * sum(w[i][k] * sw[j][k] for k in range(n)) for j in range(nc)]
         for i in range(nc)]
    forces = [(k * model["omega"], h * amp, ph) for k, amp, ph, _ in model["forces"]]

    v = [0.0] * n
    x = [0.0] * n
    r = [0.0] * nc
    ns = steps_per_period
    xs = [None] * ns
    vs = [None] * ns
    t0 = time.perf_counter()
    periods = 0
    defect = math.inf
    for period in range(1, max_periods + 1):
        xstart, vstart = x[:], v[:]
        for step in range(1, ns + 1):
            xs[step - 1] = x[:]
            vs[step - 1] = v[:]
            t = period_t * ((period - 1) + step / ns)
            y = v + x + [amp * math.cos(om * t + ph) for om, amp, ph in forces]
            vf = [sum(aij * yj for aij, yj in zip(row, y)) for row in a]
            if nc == 1:
                u = sum(wk * fk for wk, fk in zip(w[0], vf))
                r[0] = max(-limit[0], min(limit[0], -u / d[0][0]))
                v = [vf[k] + h * (sw[0][k] * r[0]) for k in range(n)]
            elif nc > 1:
                u = [sum(wk * fk for wk, fk in zip(w[j], vf)) for j in range(nc)]
                for _ in range(10000):  # projected Gauss-Seidel
                    change = 0.0
                    for j in range(nc):
                        rn = r[j] - (u[j] + sum(d[j][i] * r[i] for i in range(nc))) / d[j][j]
                        rn = max(-limit[j], min(limit[j], rn))
                        change = max(change, abs(rn - r[j]))
                        r[j] = rn
                    if change <= 1e-13 * max(limit):
                        break
                v = [vf[k] + h * sum(sw[j][k] * r[j] for j in range(nc)) for k in range(n)]
            else:
                v = vf
            x = [x[k] + h * v[k] for k in range(n)]
        periods = period
        ampx = max(abs(e) for row in xs for e in row)
        ampv = max(abs(e) for row in vs for e in row)
        dx = max(abs(a1 - a0) for a1, a0 in zip(x, xstart)) / max(ampx, 1e-300)
        dv = max(abs(a1 - a0) for a1, a0 in zip(v, vstart)) / max(ampv, 1e-300)
        defect = max(dx, dv)
        if defect <= tol:
            break
    return periods, defect, time.perf_counter() - t0, x, v


if __name__ == "__main__":
    spp = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    tol = float(sys.argv[2]) if len(sys.argv) > 2 else 1e-8
    periods, defect, seconds, x, v = integrate(seed(), spp, tol)
    print(f"periods {periods} defect {defect:.6e} seconds {seconds:.4f}")
    print("x " + " ".join(f"{e:.16e}" for e in x))
    print("v " + " ".join(f"{e:.16e}" for e in v))
