#!/usr/bin/env bash
# Rerun what the README and doc/ print, and rewrite it in place (release build):
#   - the pictures of doc/: Figure 3 of the paper (examples/seed.nml, the three methods side by
#     side), the work-precision diagrams of examples/seed_study.nml and chain4_study.nml, the
#     forced-response curves of seed_frc.nml and designer_damper.nml, the family of
#     damper_family.nml (doc/family_damper.png, doc/frc_family_damper.png) and the robustness
#     maps of seed_robustness.nml; examples/calculix_beam/frc.png (doc/fe-models.md) and
#     examples/calculix_sector/frc.png and modes.png, doc/modes_bladed_disk.png and
#     doc/modes_bladed_disk_damper.png (doc/cyclic.md);
#   - every figure between markers in README.md and doc/*.md: an inline figure is written
#     <!--fig:KEY-->value<!--/fig-->, a block (a program's output) sits between the lines
#     <!--fig:KEY:begin--> and <!--fig:KEY:end-->. The keys: machine (this machine, e.g.
#     "2-core Intel Xeon VM"), time:<example> (the whole-process wall time of the example,
#     median of 3 runs one after the other, each without a reduction cache: as a first run),
#     output:<example> (what it prints on stdout, in a
#     fenced block), warning:<example> (the first warning it prints on stderr), and the values read from the runs' summary.nml and family.csv listed in
#     `values` below. A marker with a key this script does not know is an error (exit 1), so
#     no figure in the docs is left without its source;
#   - the convergence table of doc/convergence.md (doc/convergence_table.txt, bench_convergence
#     on the cases of bench/convergence; --quick leaves it).
# The benchmarks' own figures (doc/benchmarks.md) come from the bench/ programs each section
# names; this script does not rerun those.
# Usage: doc/make_figures.sh [--quick]   (--quick: one run per example instead of 3, no
# convergence table). Then `git diff README.md doc/` shows what changed.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
[ "${1:-}" = "--quick" ] && quick=1
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
export STICKSLIP_FIGURES_EXE="$exe" STICKSLIP_FIGURES_QUICK="$quick"
if [ "$quick" = 0 ]; then
    # the convergence table of doc/convergence.md ("When the first attempt fails"): 14 cases
    # and the impact case at H = 10..150 (about 1.5 min on 2 cores; iwan.nml is left out)
    fpm run --example bench_convergence --profile release -- \
        $(ls bench/convergence/*.nml | grep -v iwan) > doc/convergence_table.txt
fi
python3 - <<'PYTHON'
import os, re, statistics, subprocess, sys, time, glob, csv

exe = os.environ["STICKSLIP_FIGURES_EXE"]
repeats = 1 if os.environ["STICKSLIP_FIGURES_QUICK"] == "1" else 3
docs = ["README.md"] + sorted(glob.glob("doc/*.md"))
inline = re.compile(r"<!--fig:([^>]*?)(?<!:begin)(?<!:end)-->(.*?)<!--/fig-->", re.S)
block = re.compile(r"(<!--fig:([^>]*?):begin-->\n)(.*?)(<!--fig:\2:end-->)", re.S)

def keys_in(text):
    return [m.group(1) for m in inline.finditer(text)] + \
           [m.group(2) for m in block.finditer(text)]

wanted = set()
for d in docs:
    wanted.update(keys_in(open(d).read()))

examples = sorted({k.split(":", 1)[1] for k in wanted if ":" in k and
                   k.split(":", 1)[0] in ("time", "output", "warning")})
# examples whose pictures doc/ shows run even when no marker times them
for e in ["examples/seed.nml", "examples/seed_study.nml", "examples/chain4_study.nml",
          "examples/seed_frc.nml", "examples/designer_damper.nml",
          "examples/damper_family.nml", "examples/seed_robustness.nml",
          "examples/calculix_beam/case.nml", "examples/calculix_sector/case.nml",
          "examples/calculix_sector/modes.nml", "examples/bladed_disk_modes.nml",
          "examples/bladed_disk_damper_modes.nml"]:
    if e not in examples:
        examples.append(e)

def run(case):
    # every run as a first run: no reduction cache from the run before
    for cache in glob.glob("out/**/reduction.cache", recursive=True):
        os.remove(cache)
    t0 = time.perf_counter()
    p = subprocess.run([exe, case], capture_output=True, text=True)
    t = time.perf_counter() - t0
    if p.returncode not in (0, 2):
        sys.exit(f"make_figures: {case} failed (exit {p.returncode}):\n{p.stderr}")
    return t, p.stdout, p.stderr

seconds, output, warning = {}, {}, {}
for e in examples:
    times = []
    for _ in range(repeats):
        t, out, err = run(e)
        times.append(t)
    seconds[e] = statistics.median(times)
    output[e] = out
    # the first warning it prints on stderr (one line)
    lines = [l for l in err.splitlines() if l.startswith("stickslip: warning:")]
    warning[e] = "`" + lines[0] + "`" if lines else "(none)"
    print(f"make_figures: {e}: {seconds[e]:.3g} s (median of {repeats})", file=sys.stderr)

def summary(directory):
    values = {}
    for line in open(os.path.join(directory, "summary.nml")):
        m = re.match(r"\s*(\w+)\s*=\s*(.*?)\s*$", line)
        if m and m.group(1) not in values:
            values[m.group(1)] = m.group(2).strip("'")
    return values

def sig(x, n=2):
    """x to n significant digits, as a reader would write it (0.21, 6.3, 17)."""
    if x == 0:
        return "0"
    if abs(x) >= 10**n:
        return str(round(x))
    s = f"{x:.{n}g}"
    if "e" in s:
        m, e = s.split("e")
        return f"{m}e{int(e)}"
    return s

def sci(x, n=3):
    """x in scientific notation with n significant digits (9.04e-3)."""
    m, e = f"{x:.{n - 1}e}".split("e")
    return f"{m}e{int(e)}"

def wall(x):
    return f"{sig(x)} s"

def machine():
    info = open("/proc/cpuinfo").read()
    model = re.search(r"model name\s*:\s*(.*)", info).group(1)
    cores = os.cpu_count()
    if "EPYC" in model:
        name = "AMD EPYC"
    elif "Xeon" in model:
        name = "Intel Xeon"
    else:
        name = model.split("@")[0].strip()
    vm = " VM" if re.search(r"^flags.*\bhypervisor\b", info, re.M) else ""
    return f"{cores}-core {name}{vm}"

values = {"machine": machine()}
for e in examples:
    values[f"time:{e}"] = wall(seconds[e])
    values[f"output:{e}"] = "```\n" + output[e] + "```\n"
    values[f"warning:{e}"] = warning[e]
seed = output["examples/seed.nml"]
for key, pattern in [("hbm", r"weighted residual:.*?([0-9.]+) ms CPU"),
                     ("euler", r"implicit Euler:.*?([0-9.]+) ms CPU"),
                     ("reference", r"exact reference:.*? in ([0-9.]+) ms CPU")]:
    values[f"seed:{key}_ms"] = sig(float(re.search(pattern, seed).group(1))) + " ms"
s = summary("out/seed_frc")
values["seed_frc:points"] = s["points"]
s = summary("out/calculix_beam")
values["calculix_beam:points"] = s["points"]
values["calculix_beam:cpu"] = sig(float(s["cpu_seconds"])) + " s"
values["calculix_beam:stability_cpu"] = sig(float(s["stability_cpu_seconds"])) + " s"
values["calculix_beam:stability_per_point"] = \
    f"{1000 * float(s['stability_cpu_seconds']) / int(s['points']):.0f} ms"
values["calculix_beam:reduction_error"] = sci(float(s["reduction_error"]))
values["calculix_beam:reduction_seconds"] = sig(float(s["reduction_seconds"])) + " s"
s = summary("out/calculix_sector")
values["calculix_sector:points"] = s["points"]
values["calculix_sector:reduced_dof"] = s["reduced_dof"]
values["calculix_sector:interface_dof"] = s["reduction_interface_dof"]
values["calculix_sector:error_nd3"] = sci(float(s["reduction_error_nd3"]))
values["calculix_sector:error_nd9"] = sci(float(s["reduction_error_nd9"]))
# the backbones per nodal diameter: points, and the largest damping ratio of each example
for name, out in [("bladed_disk_modes", "out/bladed_disk_modes"),
                  ("bladed_disk_damper_modes", "out/bladed_disk_damper_modes"),
                  ("calculix_sector_modes", "out/calculix_sector_modes")]:
    s = summary(out)
    values[name + ":points"] = s["points"]
    values[name + ":damping_max"] = f"{float(s['damping_ratio_max']):.3g}"
    values[name + ":cpu"] = sig(float(s["cpu_seconds"])) + " s"
# the convergence table: answers converged at H = 10..150 on its cases, impact left out
converged = total = 0
for line in open("doc/convergence_table.txt"):
    m = re.match(r"\| (\w+) \| `[^`]*` \| (\d+)/(\d+) \|", line)
    if m and m.group(1) != "impact":
        converged += int(m.group(2))
        total += int(m.group(3))
values["convergence:converged"] = str(converged)
values["convergence:total"] = str(total)
s = summary("out/damper_family")
rows = list(csv.DictReader(open("out/damper_family/family.csv")))
peaks = [float(r["peak_1"]) for r in rows]
best = min(range(len(peaks)), key=peaks.__getitem__)
values["damper_family:best_value"] = sig(float(rows[best]["family_value"]))
values["damper_family:best_peak"] = sig(peaks[best], 3)
values["damper_family:stuck_ratio"] = sig(float(rows[-1]["stuck_peak_1"]) / peaks[best])
values["damper_family:slipping_ratio"] = sig(float(rows[0]["slipping_peak_1"]) / peaks[best])
values["damper_family:points"] = s["points"]

unknown = sorted(k for k in wanted if k not in values)
if unknown:
    sys.exit("make_figures: markers without a source: " + ", ".join(unknown))
for d in docs:
    text = open(d).read()
    new = inline.sub(lambda m: f"<!--fig:{m.group(1)}-->{values[m.group(1)]}<!--/fig-->", text)
    new = block.sub(lambda m: m.group(1) + values[m.group(2)] + m.group(4), new)
    if new != text:
        open(d, "w").write(new)
        print(f"make_figures: rewrote {d}", file=sys.stderr)
PYTHON

# the pictures, from the runs above (their files are in out/)
gnuplot -e "dir='out/seed'" examples/figure3.gp
cp out/seed/figure3.png doc/figure3.png
for c in seed_study chain4_study; do
    gnuplot -e "dir='out/$c'" examples/work_precision.gp
    cp "out/$c/work_precision.png" "doc/work_precision_${c%_study}.png"
done
cp out/seed_frc/frc.png doc/frc_seed.png
cp out/calculix_beam/frc.png examples/calculix_beam/frc.png
cp out/calculix_sector/frc.png examples/calculix_sector/frc.png
cp out/calculix_sector_modes/modes.png examples/calculix_sector/modes.png
cp out/bladed_disk_modes/modes.png doc/modes_bladed_disk.png
cp out/bladed_disk_damper_modes/modes.png doc/modes_bladed_disk_damper.png
cp out/designer_damper/frc.png doc/frc_designer.png
cp out/damper_family/family.png doc/family_damper.png
cp out/damper_family/frc_family.png doc/frc_family_damper.png
cp out/seed_robustness/robustness_cold.png doc/robustness_cold.png
cp out/seed_robustness/robustness_warm.png doc/robustness_warm.png
echo "make_figures: wrote examples/calculix_beam/frc.png examples/calculix_sector/frc.png" \
     "examples/calculix_sector/modes.png doc/modes_bladed_disk.png" \
     "doc/modes_bladed_disk_damper.png" \
     "doc/figure3.png doc/work_precision_seed.png" \
     "doc/work_precision_chain4.png doc/frc_seed.png doc/frc_designer.png" \
     "doc/family_damper.png doc/frc_family_damper.png doc/robustness_cold.png" \
     "doc/robustness_warm.png$([ "$quick" = 0 ] && echo ' doc/convergence_table.txt')"
