#!/usr/bin/env python3
"""Fuzz the stickslip command line with generated case files (python3, standard library only).

Builds the release CLI once, generates --count case files (mutations of cases shaped like
examples/*.nml and of hand-written valid but ill-conditioned cases), runs each (at most --jobs
at a time, each with a timeout) in its own folder of a temporary directory, and classifies
every run. A run is fine when it ends in

    exit 0  (stderr only `stickslip: warning:` lines),
    exit 1  with exactly one `stickslip: error: <case file>...` line,
    exit 2  with a `stickslip: error:` diagnosis,
    exit 3  with a `stickslip: error:` message,

and leaves no `*.tmp`, no `.stickslip.lock`, no file outside its output directory, and (exit 0)
a summary.nml that does not say `trusted = F` and result files without NaN. Anything else is a
failure class; every failing case is written to the report folder with its stdout and stderr.

    python3 bench/fuzz_cases.py [--count 2000] [--seed 1] [--jobs 2] [--timeout 20]
                                [--report build/fuzz_report] [--keep] [--no-build] [--binary PATH]

Deterministic for a given --seed (the cases; run times and timeouts depend on the machine).
"""
import argparse
import csv
import concurrent.futures
import glob
import math
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

CRASH_PATTERNS = ("Fortran runtime error", "At line", "Error termination", "Backtrace",
                  "Program received signal", "Attempting to allocate already allocated",
                  "Segmentation fault", "malloc", "Operating system error",
                  "Fortran runtime warning")

# ---------------------------------------------------------------------------------------------
# Base cases: an ordered list of (group, [(variable, value text)]).
# ---------------------------------------------------------------------------------------------

SEED_SYSTEM = [("ndof", "2"), ("mass", "1,0,0,1"), ("stiffness", "2,-1,-1,1"),
               ("damping", "0,0,0,0")]
DAMPED_SYSTEM = [("ndof", "2"), ("mass", "1,0,0,1"), ("stiffness", "2,-1,-1,1"),
                 ("damping", "0.06,-0.02,-0.02,0.04")]
CHAIN4_SYSTEM = [("ndof", "4"), ("mass", "1,0,0,0,  0,1.25,0,0,  0,0,1.5,0,  0,0,0,1.75"),
                 ("stiffness", "2,-1,0,0, -1,2,-1,0,  0,-1,2,-1,  0,0,-1,1"),
                 ("damping", "0.05,-0.02,0,0, -0.02,0.0525,-0.02,0, 0,-0.02,0.055,-0.02, "
                             "0,0,-0.02,0.0375")]
MIRROR_SYSTEM = [("ndof", "4"), ("mass", "1,0,0,0,  0,1,0,0,  0,0,1,0,  0,0,0,1"),
                 ("stiffness", "2,-1,0,0, -1,1,0,0, 0,0,2,-1, 0,0,-1,1")]


def seed_case():
    return [("system", list(SEED_SYSTEM)),
            ("forcing", [("omega", "4.5"), ("force_dof", "1"), ("force_amplitude", "10.0")]),
            ("friction", [("contact_dof", "2"), ("mu", "0.45"), ("normal_load", "1.0")]),
            ("hbm", [("harmonics", "30"), ("odd_only", ".false."), ("rho", "0.2"),
                     ("samples", "1024")])]


def chain4_case():
    return [("system", list(CHAIN4_SYSTEM)),
            ("forcing", [("omega", "0.5"), ("force_dof", "1, 3"), ("force_harmonic", "1, 3"),
                         ("force_amplitude", "2.0, 0.6666666666666666"),
                         ("force_phase", "0.0, 0.7")]),
            ("friction", [("contact_dof", "2, 4"), ("contact_dof2", "0, 3"), ("mu", "0.3, 0.5"),
                          ("normal_load", "1.5, 1.0")]),
            ("hbm", [("harmonics", "25"), ("samples", "512"), ("rho", "0.2")])]


def mirrored_case():
    return [("system", list(MIRROR_SYSTEM)),
            ("forcing", [("omega", "4.5"), ("force_dof", "1, 3"),
                         ("force_amplitude", "10.0, 10.0"),
                         ("force_phase", "0.0, 3.141592653589793")]),
            ("friction", [("contact_dof", "2"), ("contact_dof2", "4"), ("mu", "0.45"),
                          ("normal_load", "1.0")]),
            ("hbm", [("harmonics", "29"), ("odd_only", ".true."), ("rho", "0.2"),
                     ("samples", "512")])]


def many_sticks_case():
    return [("system", [("ndof", "2"), ("mass", "1,0,0,1"), ("stiffness", "2,-1,-1,1"),
                        ("damping", "0.02,0,0,0.02")]),
            ("forcing", [("omega", "0.5"), ("force_dof", "1, 2"), ("force_harmonic", "1, 7"),
                         ("force_amplitude", "1.0, 0.72"), ("force_phase", "0.0, 0.0")]),
            ("friction", [("contact_dof", "2"), ("mu", "0.6"), ("normal_load", "1.0")]),
            ("hbm", [("harmonics", "30"), ("samples", "1024")])]


def with_group(case, group, items):
    """Replace or add a group."""
    case = [(g, list(v)) for g, v in case if g != group]
    case.append((group, items))
    return case


def set_var(case, group, var, value):
    out = []
    found = False
    for g, items in case:
        if g == group:
            items = [(n, value if n == var else v) for n, v in items]
            if var not in [n for n, _ in items]:
                items.append((var, value))
            found = True
        out.append((g, items))
    if not found:
        out.append((group, [(var, value)]))
    return out


def ill_conditioned_cases():
    """Valid but ill-conditioned cases (name, case)."""
    c = []
    s = seed_case()
    # undamped 2-DOF at a natural frequency, forcing above the friction limit
    c.append(("resonance2", set_var(set_var(s, "forcing", "omega", "0.6180339887"),
                                     "forcing", "force_amplitude", "1.0")))
    # 1-DOF undamped at its natural frequency, force below mu N: stuck
    one = [("system", [("ndof", "1"), ("mass", "1"), ("stiffness", "2")]),
           ("forcing", [("omega", "1.4142135623730951"), ("force_dof", "1"),
                        ("force_amplitude", "0.5")]),
           ("friction", [("contact_dof", "1"), ("mu", "1"), ("normal_load", "1")]),
           ("hbm", [("harmonics", "10"), ("samples", "128")])]
    c.append(("resonance1", one))
    c.append(("resonance1_nofriction", [g for g in one if g[0] != "friction"]))
    c.append(("mu0", set_var(s, "friction", "mu", "0")))
    c.append(("mu_huge", set_var(s, "friction", "mu", "1e10")))
    c.append(("load0", set_var(s, "friction", "normal_load", "0")))
    c.append(("rho_huge", set_var(s, "hbm", "rho", "1e300")))
    c.append(("rho_tiny", set_var(s, "hbm", "rho", "1e-300")))
    c.append(("omega_tiny", set_var(s, "forcing", "omega", "1e-6")))
    c.append(("omega_huge", set_var(s, "forcing", "omega", "1e6")))
    c.append(("h1", set_var(set_var(s, "hbm", "harmonics", "1"), "hbm", "samples", "3")))
    c.append(("samples_2h1", set_var(set_var(s, "hbm", "harmonics", "15"), "hbm", "samples",
                                     "31")))
    c.append(("samples_odd", set_var(s, "hbm", "samples", "1001")))
    c.append(("relative", mirrored_case()))
    c.append(("chain4", chain4_case()))
    c.append(("many_sticks", many_sticks_case()))
    scaled = with_group(s, "system", [("ndof", "2"), ("mass", "1e-9,0,0,1e-9"),
                                      ("stiffness", "2e-9,-1e-9,-1e-9,1e-9")])
    scaled = set_var(set_var(scaled, "forcing", "force_amplitude", "1e-8"), "friction",
                     "normal_load", "1e-9")
    c.append(("scaled_soft", scaled))
    stiff = with_group(s, "system", [("ndof", "2"), ("mass", "1e6,0,0,1e6"),
                                     ("stiffness", "2e9,-1e9,-1e9,1e9")])
    stiff = set_var(set_var(stiff, "forcing", "force_amplitude", "1e7"), "friction",
                    "normal_load", "1e6")
    stiff = set_var(stiff, "forcing", "omega", "142")
    c.append(("scaled_stiff", stiff))
    c.append(("zero_force", set_var(s, "forcing", "force_amplitude", "0")))
    c.append(("static_force", set_var(set_var(set_var(s, "forcing", "force_harmonic", "0, 1"),
                                              "forcing", "force_dof", "1, 1"),
                                      "forcing", "force_amplitude", "0.3, 10")))
    free = [("system", [("ndof", "1"), ("mass", "1"), ("stiffness", "0")]),
            ("forcing", [("omega", "1"), ("force_dof", "1, 1"), ("force_harmonic", "0, 1"),
                         ("force_amplitude", "1, 1")]),
            ("friction", [("contact_dof", "1"), ("mu", "0.5"), ("normal_load", "1")]),
            ("hbm", [("harmonics", "5"), ("samples", "64")])]
    c.append(("free_body_static", free))
    # many contacts on an 8-DOF chain, a few relative
    n = 8
    m = ",".join("1" if i == j else "0" for j in range(n) for i in range(n))
    k = []
    for j in range(n):
        for i in range(n):
            if i == j:
                k.append("2" if i < n - 1 else "1")
            elif abs(i - j) == 1:
                k.append("-1")
            else:
                k.append("0")
    d = ",".join("0.02" if i == j else "0" for j in range(n) for i in range(n))
    many = [("system", [("ndof", str(n)), ("mass", m), ("stiffness", ",".join(k)),
                        ("damping", d)]),
            ("forcing", [("omega", "0.8"), ("force_dof", "1"), ("force_amplitude", "3")]),
            ("friction", [("contact_dof", "1,2,3,4,5,6,7,8"),
                          ("contact_dof2", "0,0,0,5,0,0,8,0"),
                          ("mu", "8*0.3"), ("normal_load", "8*1")]),
            ("hbm", [("harmonics", "9"), ("samples", "128")])]
    c.append(("many_contacts", many))
    nofric = [g for g in s if g[0] != "friction"]
    c.append(("no_contact", nofric))
    c.append(("tol_tiny", set_var(s, "hbm", "tol", "1e-300")))
    c.append(("maxfev1", set_var(s, "hbm", "maxfev", "1")))
    return c


def random_physical_case(rng):
    """A valid case with random physics: a chain of 1..5 DOFs with random masses, springs
    (some zero), damping (often none), forcing terms and contacts (some relative)."""
    n = rng.randint(1, 5)
    lg = lambda a, b: 10 ** rng.uniform(a, b)
    scale = lg(-6, 6) if rng.random() < 0.3 else 1.0
    m = [lg(-1, 1) * scale for _ in range(n)]
    springs = [0.0 if rng.random() < 0.1 else lg(-1, 1) * scale for _ in range(n)]
    M = [[0.0] * n for _ in range(n)]
    K = [[0.0] * n for _ in range(n)]
    for i in range(n):
        M[i][i] = m[i]
        K[i][i] += springs[i]
        if i > 0:
            K[i][i] += springs[i - 1] * 0.5
            K[i - 1][i - 1] += springs[i - 1] * 0.5
            K[i][i - 1] -= springs[i - 1] * 0.5
            K[i - 1][i] -= springs[i - 1] * 0.5
    flat = lambda A: ", ".join("%.9g" % A[i][j] for j in range(n) for i in range(n))
    system = [("ndof", str(n)), ("mass", flat(M)), ("stiffness", flat(K))]
    if rng.random() < 0.5:
        a, b = rng.choice([0, lg(-4, -1)]), rng.choice([0, lg(-4, -1)])
        system.append(("damping", flat([[a * M[i][j] + b * K[i][j] for j in range(n)]
                                         for i in range(n)])))
    nf = rng.randint(1, 3)
    forcing = [("omega", "%.9g" % lg(-2, 1.5)),
               ("force_dof", ", ".join(str(rng.randint(1, n)) for _ in range(nf))),
               ("force_amplitude", ", ".join("%.6g" % (lg(-2, 2) * scale) for _ in range(nf))),
               ("force_harmonic", ", ".join(str(rng.choice([0, 1, 1, 1, 2, 3, 5]))
                                            for _ in range(nf))),
               ("force_phase", ", ".join("%.4g" % rng.uniform(-7, 7) for _ in range(nf)))]
    case = [("system", system), ("forcing", forcing)]
    nc = rng.randint(0, 3)
    if nc:
        d1 = [rng.randint(1, n) for _ in range(nc)]
        d2 = [rng.choice([0, 0] + [k for k in range(1, n + 1) if k != d1[c]]) for c in range(nc)]
        case.append(("friction", [("contact_dof", ", ".join(map(str, d1))),
                                  ("contact_dof2", ", ".join(map(str, d2))),
                                  ("mu", ", ".join("%.4g" % lg(-3, 1) for _ in range(nc))),
                                  ("normal_load", ", ".join("%.4g" % (lg(-2, 2) * scale)
                                                            for _ in range(nc)))]))
    h = rng.choice([1, 2, 3, 5, 8, 15, 30, 40])
    samples = rng.choice([2 * h + 1, 2 * h + 2, 4 * h, 64, 256, 1024])
    samples = max(samples, 2 * h + 1)
    hbm = [("harmonics", str(h)), ("samples", str(samples)),
           ("rho", rng.choice(["0", "0", "0.2", "%.3g" % lg(-3, 3)]))]
    if rng.random() < 0.3:
        hbm.append(("odd_only", ".true."))
    if rng.random() < 0.2:
        hbm.append(("start", rng.choice(["'direct'", "'ladder'"])))
    if rng.random() < 0.2:
        hbm.append(("stability", ".true."))
    if rng.random() < 0.1:
        hbm.append(("verify_periods", "3"))
    case.append(("hbm", hbm))
    return case


def example_cases():
    return [("seed", seed_case()), ("chain4", chain4_case()), ("mirrored", mirrored_case()),
            ("many_sticks", many_sticks_case()),
            ("seed_damped", with_group(seed_case(), "system", list(DAMPED_SYSTEM)))]


# Method groups kept small so that a run takes well under ~5 s.
def method_groups(rng, method):
    g = []
    if method in ("euler", "all"):
        g.append(("euler", [("steps_per_period", str(rng.choice([16, 64, 200, 500]))),
                            ("max_periods", str(rng.choice([5, 50, 200])))]))
    if method in ("reference", "all"):
        g.append(("reference", [("samples", str(rng.choice([8, 64, 256]))),
                                ("bracket_steps", str(rng.choice([8, 100, 400])))]))
    if method == "study":
        g.append(("study", [("harmonics", "1, 3, 5"), ("samples", rng.choice(["64", "0"])),
                            ("steps_per_period", rng.choice(["50, 100", "0"])),
                            ("error_samples", "256"), ("repeats", "1"),
                            ("repeat_below", "0")]))
        g.append(("euler", [("max_periods", "50")]))
    if method == "sweep":
        g.append(("sweep", [("parameter", rng.choice(["'omega'", "'mu'", "'normal_load'",
                                                      "'force_amplitude'"])),
                            ("start", rng.choice(["4.0", "0.5", "1"])),
                            ("stop", rng.choice(["4.3", "0.8", "1.2"])),
                            ("max_points", "25"),
                            ("stability", rng.choice([".true.", ".false."])),
                            ("plot", rng.choice([".true.", ".false.", ".false."]))]))
    if method == "robustness":
        g.append(("robustness", [("omegas", "1.5, 4.5"), ("mus", "0.45"),
                                 ("harmonics", "5"), ("rhos", rng.choice(["0.2", "0.2, 0"])),
                                 ("steps_per_period", rng.choice(["0", "50"])),
                                 ("error_samples", "128")]))
        g.append(("euler", [("max_periods", "30")]))
    return g


# Sizes at, just above and far above the documented limits (doc/case-file.md, "Limits").
SIZES = [("hbm", "harmonics", ["4096", "4097", "100000", "2147483647", "0", "-3"]),
         ("hbm", "samples", ["1048577", "2147483647", "100000000", "-1", "0", "3"]),
         ("hbm", "max_harmonics", ["4097", "2147483647"]),
         ("hbm", "maxfev", ["2147483647", "-1", "1"]),
         ("hbm", "verify_periods", ["1001", "2147483647", "-1", "3"]),
         ("euler", "steps_per_period", ["10000001", "2000000000", "2147483647", "1", "2"]),
         ("euler", "max_periods", ["2147483647", "0", "-1", "1"]),
         ("reference", "samples", ["1000001", "100000000", "2147483647", "0", "1"]),
         ("reference", "bracket_steps", ["100001", "2000000000", "7", "8"]),
         ("reference", "maxfev", ["1", "0", "2147483647"]),
         ("reference", "tol", ["1e-300", "1", "0", "0.5"]),
         ("study", "harmonics", ["4097", "0", "2147483647", "1, 1, 1"]),
         ("study", "error_samples", ["1000001", "2147483647", "1", "2"]),
         ("study", "repeats", ["1001", "2147483647", "0"]),
         ("sweep", "max_points", ["100001", "2147483647", "1", "2"]),
         ("sweep", "max_failures", ["0", "2147483647"]),
         ("sweep", "step", ["1e-300", "1e300", "-0.1", "0"]),
         ("sweep", "min_step", ["1e-300", "1e300", "-1"]),
         ("robustness", "omegas", ["0", "-1, 2", "1e-300", "1e300"]),
         ("robustness", "harmonics", ["4097", "2147483647"]),
         ("robustness", "error_samples", ["1000001", "2147483647"]),
         ("robustness", "wrong_tol", ["-1", "0", "1e300"]),
         ("system", "ndof", ["65", "2147483647", "0", "-1", "1", "3"])]

METHODS = ["hbm", "euler", "reference", "all", "sweep", "study", "robustness"]

GROUP_NAMES = ["system", "forcing", "friction", "hbm", "euler", "reference", "run", "output",
               "study", "sweep", "robustness"]

WEIRD_DIRS = ["out dir", "out/q'; touch PWNED; echo '", 'o"q', "o$(touch PWNED2)", "o`touch PWNED3`",
              "o;ls", "o|x", "o&x", "o*?[x]", "o\\b", "-o", "o/../o2", "o/./p", "o//p", "  o ",
              "ü/ö", "o\tt", "o,p", "o=p", "o!p /&end"]

NUMBERS = ["0", "-1", "1e308", "1e309", "-1e309", "1e-308", "1e-320", "NaN", "nan", "Inf",
           "-Inf", "+inf", "2147483647", "2147483648", "-2147483648", "99999999999",
           "1d400", "1.0E+5", ".5", "-0", "3.5", "1e", "1.2.3", "0x10", "'str'", ".true.", "T",
           "1,,2", "4*", "*3", "2*1", "-5*1", "1e-5", "100000000", "2000000000", "1048576",
           "1e10", "-1e-10", "'hbm             x'", "hbm", "''", "1 2", "(1,2)"]


def render(case, rng, style=None):
    """Case (list of groups) to namelist text."""
    style = style if style is not None else rng.randrange(4)
    lines = []
    if rng.random() < 0.3:
        lines.append("! generated by fuzz_cases.py: the &hbm group / is a comment")
    for g, items in case:
        if style == 0:
            lines.append("&%s %s /" % (g, ", ".join("%s = %s" % (n, v) for n, v in items)))
        elif style == 1:
            lines.append("&%s" % g)
            for n, v in items:
                lines.append("  %s = %s" % (n, v))
            lines.append("/")
        elif style == 2:
            lines.append("&%s" % g.upper())
            for n, v in items:
                lines.append("  %s=%s," % (n.upper(), v))
            lines.append("&end")
        else:
            lines.append("&%s %s /  ! group %s" % (g, " ".join("%s = %s" % (n, v) for n, v in items), g))
    return "\n".join(lines) + "\n"


def quote(s, rng):
    if "'" in s and '"' not in s:
        return '"%s"' % s
    return "'%s'" % s.replace("'", "''")


# ---------------------------------------------------------------------------------------------
# Mutations
# ---------------------------------------------------------------------------------------------

def structural_mutation(case, rng):
    """One mutation of the group list; returns (case, description)."""
    case = [(g, list(v)) for g, v in case]
    kind = rng.choice(["delete_group", "dup_group", "rename_group", "delete_var", "dup_var",
                       "rename_var", "number", "number", "number", "swap_type", "matrix_size",
                       "bad_mass", "unknown_group", "unknown_var", "long_string", "dof_range",
                       "list_length", "many_values", "method_mismatch", "extra_method_group",
                       "size", "size", "scale", "scale", "scale"])
    gi = rng.randrange(len(case))
    g, items = case[gi]
    if kind == "delete_group":
        del case[gi]
        return case, "delete &%s" % g
    if kind == "dup_group":
        case.insert(rng.randrange(len(case) + 1), (g, list(items)))
        return case, "duplicate &%s" % g
    if kind == "rename_group":
        new = rng.choice([g + g[-1], g[:-1], g + "s", g.upper(), "solver", g[1:], "summary",
                          "summary_hbm", g.replace("e", "3")])
        case[gi] = (new, items)
        return case, "rename &%s -> &%s" % (g, new)
    if kind == "unknown_group":
        case.insert(rng.randrange(len(case) + 1), (rng.choice(["solver", "runs", "hbmm", "x"]),
                                                   [("a", "1")]))
        return case, "unknown group"
    if not items:
        return case, "noop"
    vi = rng.randrange(len(items))
    n, v = items[vi]
    if kind == "delete_var":
        del items[vi]
        return case, "delete %s %s" % (g, n)
    if kind == "dup_var":
        items.insert(rng.randrange(len(items) + 1), (n, v))
        return case, "duplicate %s %s" % (g, n)
    if kind == "rename_var":
        new = rng.choice([n + "s", n[:-1], n.upper(), n + "(1)", n + "(1:2)", "bogus_variable",
                          n.replace("_", ""), "%" + n])
        items[vi] = (new, v)
        return case, "rename %s %s -> %s" % (g, n, new)
    if kind == "unknown_var":
        items.insert(rng.randrange(len(items) + 1), ("bogus_variable", "3"))
        return case, "unknown variable in %s" % g
    if kind == "number":
        parts = [p for p in re.split(r"[,\s]+", v) if p]
        if not parts:
            parts = [v]
        k = rng.randrange(len(parts))
        parts[k] = rng.choice(NUMBERS)
        items[vi] = (n, ", ".join(parts))
        return case, "number %s %s = %s" % (g, n, items[vi][1])
    if kind == "swap_type":
        new = rng.choice(["'fast'", ".true.", "1.5", "7", "'hbm'", "x"])
        items[vi] = (n, new)
        return case, "type %s %s = %s" % (g, n, new)
    if kind == "long_string":
        new = quote(rng.choice(["a", "hbm", "omega"]) * rng.choice([17, 300, 1025, 5000]), rng)
        items[vi] = (n, new)
        return case, "long string %s %s" % (g, n)
    if kind == "dof_range":
        new = rng.choice(["0", "-1", "3", "5", "65", "2147483647"])
        case = set_var(case, rng.choice(["forcing", "friction"]),
                       rng.choice(["force_dof", "contact_dof", "contact_dof2"]), new)
        return case, "dof %s" % new
    if kind == "list_length":
        grp = rng.choice(["forcing", "friction"])
        var = rng.choice(["force_amplitude", "force_phase", "force_harmonic", "mu",
                          "normal_load", "contact_dof2"])
        case = set_var(case, grp, var, "1, 2, 3")
        return case, "list length %s %s" % (grp, var)
    if kind == "many_values":
        cnt = rng.choice([257, 300, 1000, 65])
        case = set_var(case, rng.choice(["forcing", "friction", "system"]),
                       rng.choice(["force_amplitude", "mu", "mass", "damping"]),
                       ", ".join(["0.1"] * cnt))
        return case, "%d values" % cnt
    if kind == "matrix_size":
        var = rng.choice(["mass", "stiffness", "damping"])
        for gg, it in case:
            if gg == "system":
                for j, (nn, vv) in enumerate(it):
                    if nn == var:
                        parts = [p for p in re.split(r"[,\s]+", vv) if p]
                        if rng.random() < 0.5 and len(parts) > 1:
                            parts = parts[:-1]
                        else:
                            parts = parts + ["0"]
                        it[j] = (nn, ", ".join(parts))
        return case, "matrix size %s" % var
    if kind == "bad_mass":
        nd = 2
        for gg, it in case:
            if gg == "system":
                for nn, vv in it:
                    if nn == "ndof" and vv.strip().isdigit():
                        nd = int(vv)
        nd = nd if 1 <= nd <= 64 else 2
        vals = ["0"] * (nd * nd)
        for i in range(nd):
            vals[i * nd + i] = "1"
        kindm = rng.choice(["nonsym", "indef", "zero", "singular_k", "nonsym_k"])
        if kindm == "nonsym" and nd > 1:
            vals[1] = "0.5"
        elif kindm == "indef":
            vals[-1] = "-1"
        elif kindm == "zero":
            vals = ["0"] * (nd * nd)
        var = "stiffness" if kindm.endswith("_k") else "mass"
        if kindm == "singular_k":
            vals = ["0"] * (nd * nd)
        if kindm == "nonsym_k" and nd > 1:
            vals[1] = "3"
        case = set_var(case, "system", var, ", ".join(vals))
        return case, "matrix %s" % kindm
    if kind == "method_mismatch":
        new = rng.choice(METHODS + ["HBM", "bogus", ""])
        case = set_var(case, "run", "method", quote(new, rng))
        have = [gg for gg, _ in case]
        case += [grp for grp in method_groups(rng, new) if grp[0] not in have]
        return case, "method changed to %r" % new
    if kind == "extra_method_group":
        new = rng.choice(["sweep", "study", "robustness"])
        case += method_groups(rng, new)
        return case, "extra &%s group" % new
    if kind == "scale":
        # a valid but badly scaled value: a number times 10**U(-12, 12)
        nums = [(gi2, vi2) for gi2, (g2, it2) in enumerate(case) for vi2, (n2, v2) in enumerate(it2)
                if re.fullmatch(r"[-+]?(\d+\.?\d*|\.\d+)([eEdD][-+]?\d+)?", v2.strip())
                and "." in v2 + "e"]
        if not nums:
            return case, "noop"
        gi2, vi2 = rng.choice(nums)
        g2, it2 = case[gi2]
        n2, v2 = it2[vi2]
        try:
            x = float(v2.replace("d", "e").replace("D", "e")) * 10 ** rng.uniform(-12, 12)
        except ValueError:
            return case, "noop"
        it2[vi2] = (n2, "%.6g" % x if n2 not in ("ndof", "harmonics", "samples") else v2)
        return case, "scale %s %s = %s" % (g2, n2, it2[vi2][1])
    if kind == "size":
        grp, var, vals = rng.choice(SIZES)
        val = rng.choice(vals)
        case = set_var(case, grp, var, val)
        return case, "size %s %s = %s" % (grp, var, val)
    return case, "noop"


def text_mutation(text, rng):
    """One mutation of the text; returns (text, description)."""
    kind = rng.choice(["truncate", "bytes", "unbalanced_quote", "comment", "crlf", "tabs",
                       "no_newline", "delete_slash", "delete_amp", "empty", "bom", "nul",
                       "long_line", "comment_in_array", "cr_only", "dup_text", "ampend",
                       "utf8"])
    if kind == "truncate":
        k = rng.randrange(len(text) + 1)
        return text[:k], "truncate at %d" % k
    if kind == "bytes":
        k = rng.randrange(len(text) + 1)
        junk = "".join(chr(rng.randrange(256)) for _ in range(rng.randrange(1, 40)))
        return text[:k] + junk + text[k:], "random bytes at %d" % k
    if kind == "unbalanced_quote":
        qs = [m.start() for m in re.finditer("['\"]", text)]
        if qs:
            k = rng.choice(qs)
            return text[:k] + text[k + 1:], "quote removed at %d" % k
        k = rng.randrange(len(text) + 1)
        return text[:k] + "'" + text[k:], "quote added at %d" % k
    if kind == "comment":
        lines = text.split("\n")
        k = rng.randrange(len(lines))
        lines.insert(k, rng.choice(["! &euler / is not needed", "!&run method='x' /", "!",
                                    "   ! 'unbalanced", "! &end", "&", "/", "&/", "!/&hbm"]))
        return "\n".join(lines), "comment line %d" % k
    if kind == "comment_in_array":
        k = text.find(",")
        if k >= 0:
            return text[:k + 1] + " ! comment, 1, 2\n   " + text[k + 1:], "comment after comma"
        return text, "noop"
    if kind == "crlf":
        return text.replace("\n", "\r\n"), "CRLF"
    if kind == "cr_only":
        return text.replace("\n", "\r"), "CR only"
    if kind == "tabs":
        return text.replace(" ", "\t"), "tabs"
    if kind == "no_newline":
        return text.rstrip("\n"), "no final newline"
    if kind == "delete_slash":
        s = [m.start() for m in re.finditer("/", text)]
        if s:
            k = rng.choice(s)
            return text[:k] + text[k + 1:], "slash removed at %d" % k
        return text, "noop"
    if kind == "delete_amp":
        s = [m.start() for m in re.finditer("&", text)]
        if s:
            k = rng.choice(s)
            return text[:k] + text[k + 1:], "ampersand removed at %d" % k
        return text, "noop"
    if kind == "ampend":
        return text.replace("/", "&end"), "&end everywhere"
    if kind == "empty":
        return rng.choice(["", "\n", "   \n\n", "!\n", "&\n", "/\n"]), "empty"
    if kind == "bom":
        return "\ufeff" + text, "BOM"
    if kind == "nul":
        k = rng.randrange(len(text) + 1)
        return text[:k] + "\0" + text[k:], "NUL at %d" % k
    if kind == "long_line":
        k = text.find("\n")
        return text[:k] + " " * rng.choice([300, 5000, 70000]) + text[k:], "long line"
    if kind == "dup_text":
        return text + text, "text twice"
    if kind == "utf8":
        k = rng.randrange(len(text) + 1)
        return text[:k] + rng.choice(["é", "€", "\u2013", "ω"]) + text[k:], "utf8 at %d" % k
    return text, "noop"


MAX_MUTATIONS = [3]


def generate(i, rng):
    """Case number i: (text bytes, description, output directory relative to the run folder)."""
    pool = example_cases() + ill_conditioned_cases()
    if rng.random() < 0.3:
        name, case = "random_physics", random_physical_case(rng)
    else:
        name, case = rng.choice(pool)
    method = rng.choice(METHODS + ["hbm", "hbm", "all", "reference"])
    case = case + method_groups(rng, method)
    if method != "hbm" or rng.random() < 0.5:
        case.append(("run", [("method", "'%s'" % method)]))
    if rng.random() < 0.15:
        outdir = rng.choice(WEIRD_DIRS)
    else:
        outdir = "out"
    if rng.random() < 0.9:
        case.append(("output", [("directory", quote(outdir, rng))]))
    else:
        outdir = "out"
    desc = ["%s/%s" % (name, method)]
    r = rng.random()
    if r < 0.2:
        nmut = 0  # valid (or ill-conditioned) case as is
    else:
        nmut = rng.choice([1, 1, 1, 2, 3] if MAX_MUTATIONS[0] <= 3
                          else list(range(1, MAX_MUTATIONS[0] + 1)))
    textmuts = []
    for _ in range(nmut):
        if rng.random() < 0.65:
            case, d = structural_mutation(case, rng)
            desc.append(d)
        else:
            textmuts.append(None)
    text = render(case, rng)
    for _ in textmuts:
        text, d = text_mutation(text, rng)
        desc.append(d)
    data = text.encode("latin-1", errors="replace") if all(ord(ch) < 256 for ch in text) \
        else text.encode("utf-8", errors="surrogateescape")
    return data, "; ".join(desc), outdir


# ---------------------------------------------------------------------------------------------
# Running and classifying
# ---------------------------------------------------------------------------------------------

def build(root, build=True):
    """Path of the release CLI (build/gfortran_<hash>/app/stickslip), built unless `build` is
    false (then the release build must be up to date)."""
    if build:
        subprocess.run(["fpm", "build", "--profile", "release"], cwd=root, check=True,
                       stdout=subprocess.DEVNULL)
    # fpm prints the executable's path with a runner; the hash differs per profile
    r = subprocess.run(["fpm", "run", "--profile", "release", "--runner", "echo"], cwd=root,
                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    paths = [l.strip() for l in r.stdout.splitlines() if l.strip().endswith("stickslip")]
    if r.returncode != 0 or not paths:
        sys.exit("fuzz_cases: cannot find the release build of the stickslip program")
    return os.path.join(root, paths[-1])


def listing(folder):
    out = set()
    for base, dirs, files in os.walk(folder):
        for f in dirs + files:
            out.add(os.path.relpath(os.path.join(base, f), folder))
    return out


def printable(s):
    return all(ch == "\n" or (" " <= ch <= "~") or ch == "\t" for ch in s)


def classify(rc, out, err, elapsed, timed_out, folder, outdirs, before, planted):
    """List of failure classes of one run (empty: fine)."""
    cls = []
    text = out + err
    if timed_out:
        cls.append("timeout")
    elif rc < 0 or rc not in (0, 1, 2, 3):
        cls.append("crash:signal_or_code")
    if any(p in text for p in CRASH_PATTERNS):
        cls.append("crash:runtime_error")
    lines = [l for l in err.split("\n") if l.strip()]
    errors = [l for l in lines if l.startswith("stickslip: error:")]
    # informational lines ("stickslip: the summary was written to ...") carry the prefix too
    other = [l for l in lines if not (l.startswith("stickslip: ") or l.startswith("  "))]
    if not printable(err):
        cls.append("msg:non_printable")
    if not timed_out:
        if rc == 1:
            if len(errors) != 1:
                cls.append("msg:exit1_not_one_error_line")
            elif "case.nml" not in errors[0]:
                cls.append("msg:exit1_no_file_name")
            if len(lines) > 3:
                cls.append("msg:exit1_long")
        if rc in (2, 3) and not errors:
            cls.append("msg:exit%d_no_error_line" % rc)
        if rc == 0 and errors:
            cls.append("msg:exit0_with_error_line")
        if other:
            cls.append("msg:stray_stderr")
        if any(len(l) > 2000 for l in lines):
            cls.append("msg:line_too_long")
    after = listing(folder)
    new = after - before
    allowed = set()
    outdirs = list(outdirs) + [d.rstrip() for d in outdirs]
    for d in list(outdirs):
        parts = d.split("/")
        for k in range(1, len(parts)):
            outdirs.append("/".join(parts[:k]))
    for d in outdirs:
        d = os.path.normpath(d)
        while d not in ("", ".", os.sep):
            allowed.add(d)
            d = os.path.dirname(d)
    roots = [os.path.normpath(d) + os.sep for d in outdirs]
    bad_place = [p for p in new if not (os.path.normpath(p) in allowed
                                         or any(os.path.normpath(p).startswith(r) for r in roots))]
    if bad_place:
        cls.append("files:outside_output")
    if any(os.path.basename(p).startswith("PWNED") for p in after) or \
            os.path.exists(os.path.join(folder, "..", "PWNED")):
        cls.append("security:shell")
    if any(p.endswith(".tmp") and os.path.normpath(p) not in planted for p in after):
        cls.append("files:tmp_left")
    if not timed_out and any(os.path.basename(p) == ".stickslip.lock"
                             and os.path.normpath(p) not in planted
                             for p in after):
        cls.append("files:lock_left")
    if not timed_out:
        for p in after:
            if p.endswith(".csv") and os.path.getsize(os.path.join(folder, p)) < 20_000_000:
                with open(os.path.join(folder, p), newline="", errors="replace") as f:
                    rows = list(csv.reader(f))
                if rows and any(len(r) != len(rows[0]) for r in rows[1:]):
                    cls.append("files:ragged_csv")
    if rc == 0 and not timed_out:
        summaries = [p for p in after if os.path.basename(p) == "summary.nml"]
        if not summaries:
            cls.append("answer:exit0_no_summary")
        for p in summaries:
            with open(os.path.join(folder, p), errors="replace") as f:
                s = f.read()
            if re.search(r"trusted\s*=\s*F", s):
                cls.append("answer:exit0_untrusted")
            if re.search(r"\bnan\b|\binfinity\b", s, re.I):
                cls.append("answer:exit0_nan_in_summary")
            # method = 'all': the methods must not disagree grossly on the displacements
            q = re.search(r"quantities\s*=\s*(.*)", s)
            if q:
                names = [w.strip(" '") for w in q.group(1).split(",")]
                for m in re.finditer(r"(\w+_vs_\w+)_max\s*=\s*(.*)", s):
                    try:
                        vals = [float(v) for v in m.group(2).split(",")]
                    except ValueError:
                        continue
                    if any(n.startswith("x") and not v <= 1.0 for n, v in zip(names, vals)):
                        cls.append("answer:exit0_methods_disagree")
        for p in after:
            # study.csv, frc.csv and robustness.csv mark "not computed" with NaN (doc/outputs.md)
            if os.path.basename(p) in ("hbm.csv", "euler.csv", "reference.csv",
                                       "coefficients.csv", "events.csv"):
                fp = os.path.join(folder, p)
                if os.path.getsize(fp) < 20_000_000:
                    with open(fp, errors="replace") as f:
                        if re.search(r"\bnan\b|\binf", f.read(), re.I):
                            cls.append("answer:exit0_nan_in_csv")
                            break
    return sorted(set(cls))


def plant(folder, outdir, state, checkpoint):
    """Put the output directory into `state` before the run; returns {relative path: bytes}."""
    planted = {}
    if not state:
        return planted
    od = os.path.join(folder, outdir)
    if state == "file_in_place":
        os.makedirs(os.path.dirname(od) or folder, exist_ok=True)
        with open(od, "wb") as f:
            f.write(b"not a directory\n")
        return planted
    os.makedirs(od, exist_ok=True)
    files = {}
    if state == "stale_results":
        for n in ("hbm.csv", "coefficients.csv", "euler.csv", "reference.csv", "events.csv",
                  "study.csv", "frc.csv", "robustness.csv"):
            files[n] = b"stale,from,an,earlier,run\n"
    elif state == "stale_lock":
        files[".stickslip.lock"] = b"999999999\n"
    elif state == "garbage_lock":
        files[".stickslip.lock"] = bytes(range(256))
    elif state == "stale_tmp":
        files["hbm.csv.999999999.1.tmp"] = b"partial"
    elif state.startswith("checkpoint"):
        files["frc.checkpoint"] = checkpoint
    for n, content in files.items():
        with open(os.path.join(od, n), "wb") as f:
            f.write(content)
        planted[os.path.normpath(os.path.join(outdir, n))] = content
    return planted


def damage_checkpoint(good, rng):
    """A damaged copy of a sweep checkpoint (bytes) and a description."""
    lines = good.split(b"\n")
    kind = rng.choice(["counts", "counts", "counts", "truncate", "bytes", "number", "magic",
                       "fingerprint", "drop_line", "empty", "swap"])
    if kind == "counts" and len(lines) > 2:
        c = lines[2].split()
        k = rng.randrange(len(c))
        c[k] = rng.choice([b"2147483647", b"-1", b"0", b"99999999999", b"1000000", b"x",
                           b"1e3", b"3"])
        lines[2] = b" ".join(c)
        return b"\n".join(lines), "checkpoint counts %s" % lines[2].decode()
    if kind == "truncate":
        k = rng.randrange(len(good))
        return good[:k], "checkpoint truncated at %d" % k
    if kind == "bytes":
        k = rng.randrange(len(good))
        return good[:k] + bytes(rng.randrange(256) for _ in range(20)) + good[k:], \
            "checkpoint bytes at %d" % k
    if kind == "number" and len(lines) > 4:
        k = rng.randrange(3, len(lines) - 1)
        w = lines[k].split()
        if w:
            w[rng.randrange(len(w))] = rng.choice([b"NaN", b"Inf", b"1e400", b"-", b"1.0.0"])
        lines[k] = b" ".join(w)
        return b"\n".join(lines), "checkpoint number on line %d" % (k + 1)
    if kind == "magic":
        lines[0] = b"stickslip sweep checkpoint 2"
        return b"\n".join(lines), "checkpoint magic"
    if kind == "fingerprint" and len(lines) > 1:
        lines[1] = b"0000000000000000"
        return b"\n".join(lines), "checkpoint fingerprint"
    if kind == "drop_line" and len(lines) > 4:
        k = rng.randrange(3, len(lines))
        del lines[k]
        return b"\n".join(lines), "checkpoint line %d dropped" % (k + 1)
    if kind == "swap" and len(lines) > 5:
        a, b = rng.randrange(3, len(lines) - 1), rng.randrange(3, len(lines) - 1)
        lines[a], lines[b] = lines[b], lines[a]
        return b"\n".join(lines), "checkpoint lines swapped"
    return b"", "checkpoint empty"


CHECKPOINT_CASE = """&system ndof = 2, mass = 1,0,0,1, stiffness = 2,-1,-1,1, damping = 0.06,-0.02,-0.02,0.04 /
&forcing omega = 4.5, force_dof = 1, force_amplitude = 10.0 /
&friction contact_dof = 2, mu = 0.45, normal_load = 1.0 /
&hbm harmonics = 30, rho = 0.2, samples = 128 /
&sweep parameter = 'omega', start = 0.2, stop = 6.0, step = 0.001, max_step = 0.001,
       max_points = %d, plot = .false. /
&output directory = 'out' /
"""


def make_checkpoint(binary, tmp):
    """Run a long sweep and cut it off once its checkpoint exists; returns the checkpoint."""
    folder = os.path.join(tmp, "checkpoint_source")
    os.makedirs(folder)
    with open(os.path.join(folder, "case.nml"), "w") as f:
        f.write(CHECKPOINT_CASE % 20000)
    p = subprocess.Popen([binary, "case.nml", "--quiet"], cwd=folder, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, start_new_session=True)
    path = os.path.join(folder, "out", "frc.checkpoint")
    t0 = time.monotonic()
    while not os.path.exists(path) and time.monotonic() - t0 < 30 and p.poll() is None:
        time.sleep(0.05)
    time.sleep(0.3)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    if not os.path.exists(path):
        return b""
    with open(path, "rb") as f:
        return f.read()


def run_one(binary, tmp, i, data, desc, outdir, timeout, state=None, checkpoint=b""):
    folder = os.path.join(tmp, "run%05d" % i)
    os.makedirs(folder)
    with open(os.path.join(folder, "case.nml"), "wb") as f:
        f.write(data)
    planted = plant(folder, outdir, state, checkpoint)
    before = listing(folder)
    t0 = time.monotonic()
    timed_out = False
    p = subprocess.Popen([binary, "case.nml", "--quiet"], cwd=folder, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, start_new_session=True)
    second = None
    if state == "concurrent":
        # a second run of the same case into the same directory at the same time
        second = subprocess.Popen([binary, "case.nml", "--quiet"], cwd=folder,
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                  start_new_session=True)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        timed_out = True
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
    extra = []
    if second is not None:
        try:
            out2, err2 = second.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(second.pid, signal.SIGKILL)
            out2, err2 = second.communicate()
            extra.append("timeout")
        err2 = err2.decode("utf-8", "replace")
        if second.returncode not in (0, 1, 2, 3) or any(c in err2 for c in CRASH_PATTERNS):
            extra.append("crash:concurrent_run")
        if second.returncode == 3 and "stickslip: error:" not in err2:
            extra.append("concurrent:unexplained_exit3")
        err = err + b"--- stderr of the concurrent run (exit %d)\n" % second.returncode + \
            err2.encode()
    elapsed = time.monotonic() - t0
    out = out.decode("utf-8", "replace")
    err = err.decode("utf-8", "replace")
    # the output directory as declared, and as the (possibly mutated) text spells it
    outdirs = [outdir, "out"]
    text = data.decode("latin-1")
    for m in re.finditer(r"directory\s*=\s*('((?:[^']|'')*)'|\"((?:[^\"]|\"\")*)\")", text, re.I):
        d = m.group(2).replace("''", "'") if m.group(2) is not None \
            else m.group(3).replace('""', '"')
        outdirs.append(os.fsdecode(d.encode("latin-1")))  # the bytes the program sees
    cls = classify(p.returncode, out, err.split("--- stderr of the concurrent")[0], elapsed,
                   timed_out, folder, outdirs, before, planted)
    cls = sorted(set(cls + extra))
    # result files planted as if by an earlier run must be gone after a run that wrote a summary
    summary = os.path.join(folder, outdir, "summary.nml")
    if os.path.exists(summary) and not timed_out and p.returncode in (0, 2):
        for name, content in planted.items():
            fp = os.path.join(folder, name)
            if name.endswith(".csv") and os.path.exists(fp):
                with open(fp, "rb") as f:
                    if f.read() == content:
                        cls = sorted(set(cls + ["files:stale_result_left"]))
    # every 5th run that wrote a summary: the summary.nml read back as a case (doc/outputs.md: "a
    # summary.nml reads back as its case") must run again, into another directory
    if i % 5 == 0 and os.path.exists(summary) and not timed_out and p.returncode in (0, 2) \
            and not state:
        with open(summary, "rb") as f:
            text = f.read()
        text, n = re.subn(rb"(?im)^(\s*directory\s*=\s*).*$", rb"\1'rerun'", text)
        with open(os.path.join(folder, "summary_case.nml"), "wb") as f:
            f.write(text)
        q = subprocess.Popen([binary, "summary_case.nml", "--quiet"], cwd=folder,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             start_new_session=True)
        try:
            _, err3 = q.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(q.pid, signal.SIGKILL)
            _, err3 = q.communicate()
            cls.append("roundtrip:timeout")
        err3 = err3.decode("utf-8", "replace")
        if q.returncode not in (0, 1, 2, 3) or any(c in err3 for c in CRASH_PATTERNS):
            cls.append("crash:summary_as_case")
        elif q.returncode == 1:
            cls.append("roundtrip:summary_rejected")
        elif q.returncode != p.returncode and p.returncode == 0:
            cls.append("roundtrip:different_exit")
        err += "--- stderr of the summary run as a case (exit %d)\n%s" % (q.returncode, err3)
        cls = sorted(set(cls))
    return i, p.returncode, out, err, elapsed, cls, desc + ("; state %s" % state if state else ""), data


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--count", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--report", default=os.path.join(ROOT, "build", "fuzz_report"),
                    help="folder for the failing cases (its case* files of an earlier "
                         "campaign are removed first)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary directory")
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--binary")
    ap.add_argument("--state-share", type=float, default=0.10,
                    help="share of runs whose output directory holds an earlier run's state")
    ap.add_argument("--checkpoint-share", type=float, default=0.03,
                    help="share of runs that resume a sweep from a damaged checkpoint")
    ap.add_argument("--max-mutations", type=int, default=3,
                    help="most mutations per case (default 3: 1 to 3, mostly 1)")
    args = ap.parse_args()
    MAX_MUTATIONS[0] = args.max_mutations

    if args.binary:
        binary = os.path.abspath(args.binary)
    else:
        binary = build(ROOT, not args.no_build)
    print("binary:", binary)
    rng = random.Random(args.seed)
    cases = [(i,) + generate(i, rng) for i in range(args.count)]
    tmp = tempfile.mkdtemp(prefix="stickslip_fuzz_")
    good_checkpoint = make_checkpoint(binary, tmp)
    print("checkpoint for the resume cases: %d bytes" % len(good_checkpoint))
    # about 10% of the runs find their output directory in a state left by an earlier run;
    # about 3% resume a sweep from a damaged checkpoint
    srng = random.Random(args.seed + 1)
    jobs = []
    for i, data, desc, od in cases:
        r = srng.random()
        state, cp = None, b""
        if r < args.state_share:
            state = srng.choice(["concurrent", "concurrent", "stale_results", "stale_lock", "garbage_lock", "stale_tmp",
                                 "file_in_place"])
        elif r < args.state_share + args.checkpoint_share and good_checkpoint:
            cp, d = damage_checkpoint(good_checkpoint, srng)
            data = (CHECKPOINT_CASE % 800).encode()
            desc, od, state = "sweep resume; " + d, "out", "checkpoint"
        jobs.append((i, data, desc, od, state, cp))
    os.makedirs(args.report, exist_ok=True)
    for old in glob.glob(os.path.join(args.report, "case[0-9]*.nml")) + \
            glob.glob(os.path.join(args.report, "case[0-9]*.txt")):
        os.remove(old)
    t0 = time.monotonic()
    counts = {}
    exits = {}
    slow = []
    failures = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        futs = [ex.submit(run_one, binary, tmp, i, data, desc, od, args.timeout, state, cp)
                for i, data, desc, od, state, cp in jobs]
        for done, fut in enumerate(concurrent.futures.as_completed(futs), 1):
            i, rc, out, err, elapsed, cls, desc, data = fut.result()
            exits[rc] = exits.get(rc, 0) + 1
            if elapsed > 5:
                slow.append((elapsed, i, desc))
            low = data.decode("latin-1").lower()
            grid = re.search(r"&robustness\b[^/]*?(omegas|mus)\s*=", low) or \
                re.search(r"&study\b[^/]*?steps_per_period\s*=", low)
            if cls == ["timeout"] and (re.search(r"delete &(robustness|study)|"
                                                 r"rename &(robustness|study)", desc) or
                                       ((re.search(r"&(robustness|study)\b", low) or
                                         re.search(r"method\s*=\s*['\"](robustness|study)",
                                                   low)) and not grid)):
                # the method's default grid (README: ~17 s for the robustness example) was
                # asked for: slow by request, not a hang
                cls = []
                counts["slow:default_grid"] = counts.get("slow:default_grid", 0) + 1
            for c in cls or ["ok"]:
                counts[c] = counts.get(c, 0) + 1
            if cls:
                failures += 1
                with open(os.path.join(args.report, "case%05d.nml" % i), "wb") as f:
                    f.write(data)
                with open(os.path.join(args.report, "case%05d.txt" % i), "w") as f:
                    f.write("classes: %s\nmutation: %s\nexit: %s\ntime: %.2f s\n"
                            "--- stderr\n%s--- stdout\n%s" % (", ".join(cls), desc, rc, elapsed,
                                                              err, out[-5000:]))
            if done % 100 == 0:
                print("  %d/%d runs, %d failing, %.0f s" % (done, args.count, failures,
                                                            time.monotonic() - t0), flush=True)
    total = time.monotonic() - t0
    print("\n%d cases, seed %d, %d jobs, %.0f s wall" % (args.count, args.seed, args.jobs, total))
    print("exit codes: " + ", ".join("%s: %d" % (k, v) for k, v in sorted(exits.items())))
    print("%-36s %6s" % ("class", "runs"))
    for c in sorted(counts):
        print("%-36s %6d" % (c, counts[c]))
    if slow:
        print("runs over 5 s: %d (slowest %.1f s: case %d, %s)" % (len(slow), max(slow)[0],
                                                                    max(slow)[1], max(slow)[2]))
    print("failing cases: %d (in %s/)" % (failures, args.report))
    if args.keep:
        print("runs kept in", tmp)
    else:
        shutil.rmtree(tmp, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
