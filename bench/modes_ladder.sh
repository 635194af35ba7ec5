#!/usr/bin/env bash
# The backbones' per-point error estimates (&modes error_estimate, doc/modes.md) against the
# same backbone at 4x the harmonics and samples: for each case, how many points are flagged
# 'truncation', how many lie within their own estimate, and how many are off the finer
# backbone beyond the warning thresholds (1e-3 of omega, 5 % of D and 1e-4) without a flag
# (the number that must be 0). The finer backbone is interpolated at each point's modal
# amplitude (linearly in ln a; D in ln D). Release build; needs python3.
#
#   bench/modes_ladder.sh [CASE.nml ...]     (default: the four cases below)
set -euo pipefail
cd "$(dirname "$0")/.."
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
cases=${*:-examples/seed_modes.nml examples/degenerate_modes.nml bench/modes_ladder/liftoff_modes.nml examples/calculix_beam/modes.nml}
for c in $cases; do
    dir=$(dirname "$c")
    tmp_lo="$dir/.ladder_lo.nml"
    tmp_hi="$dir/.ladder_hi.nml"
    trap 'rm -f "$tmp_lo" "$tmp_hi"' EXIT
    h=$(sed -n 's/.*harmonics *= *\([0-9]*\).*/\1/p' "$c" | head -n 1)
    s=$(sed -n 's/.*samples *= *\([0-9]*\).*/\1/p' "$c" | head -n 1)
    sed -e "s#directory *= *'[^']*'#directory = 'out/ladder_lo'#" "$c" > "$tmp_lo"
    sed -e "s/harmonics *= *$h/harmonics = $((4 * h))/" -e "s/samples *= *$s/samples = $((4 * s))/" \
        -e "s#directory *= *'[^']*'#directory = 'out/ladder_hi'#" \
        -e "s/&modes/\&modes error_estimate = .false.,/" "$c" > "$tmp_hi"
    "$exe" --quiet "$tmp_lo" >/dev/null 2>&1 || true
    "$exe" --quiet "$tmp_hi" >/dev/null 2>&1 || true
    rm -f "$tmp_lo" "$tmp_hi"
    python3 - "$c" "$h" "$s" <<'PY'
import csv, math, sys
name, h, s = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
lo = list(csv.DictReader(open('out/ladder_lo/modes.csv')))
hi = list(csv.DictReader(open('out/ladder_hi/modes.csv')))
la_hi = [math.log(float(r['amplitude'])) for r in hi]
def interp(key, la):
    for i in range(len(hi) - 1):
        a0, a1 = la_hi[i], la_hi[i + 1]
        if (a0 - la) * (a1 - la) <= 0 and a0 != a1:
            w = (la - a0) / (a1 - a0)
            u, v = float(hi[i][key]), float(hi[i + 1][key])
            if key == 'damping_ratio' and u > 0 and v > 0:
                return math.exp((1 - w) * math.log(u) + w * math.log(v))
            return (1 - w) * u + w * v
    return float('nan')
n = flagged = within = bad = 0
for r in lo:
    la = math.log(float(r['amplitude']))
    wt, dt = interp('omega', la), interp('damping_ratio', la)
    if math.isnan(wt):
        continue
    w, d = float(r['omega']), float(r['damping_ratio'])
    ew, ed = abs(w - wt) / wt, abs(d - dt)
    n += 1
    f = 'truncation' in r['check']
    flagged += f
    if ew <= float(r['omega_error']) * (1 + 1e-9) and ed <= float(r['damping_error']) * (1 + 1e-9) + 1e-15:
        within += 1
    if (ew > 1e-3 or ed > max(0.05 * abs(d), 1e-4)) and not f:
        bad += 1
print(f"{name}: H = {h} ({s} samples) against H = {4*h} ({4*s}): {n} points, {flagged} flagged, "
      f"{within} within their estimate, {bad} unflagged beyond the thresholds")
PY
done
