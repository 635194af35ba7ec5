#!/usr/bin/env python3
"""Collect the summary.nml of every case of a campaign into one CSV (standard library only).

    collect.py RESULTS_DIR [RESULTS_DIR ...] [--case-keys forcing.omega,friction.mu] > out.csv

Finds every summary.nml under the directories given (one per case: the &output directory),
sorted by path, and writes one CSV row per case on standard output. Columns: case (the
folder holding summary.nml, relative to the RESULTS_DIR it was found under), method, trusted,
warnings, diagnosis; then the values of the echoed case named by --case-keys (group.key,
default forcing.omega and friction.mu: the campaign's parameters); then every other scalar of
&summary and of the &summary_<method> groups, named <method>_<key> for the latter (hbm_nfev,
euler_periods, reference_defect, ...), in the order first met. A list of numbers (the
per-quantity errors hbm_vs_reference_max, ...) becomes its largest absolute value; a list of
strings is joined with ';'. Logicals stay T/F; a case without a value has an empty cell.
Exit 1 when no summary.nml is found or one cannot be read (the file is named on stderr).
"""
import argparse
import csv
import os
import re
import sys

KEY = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*)$")
FIRST = ["case", "method", "trusted", "warnings", "diagnosis"]


def fortran_items(text):
    """The items of a namelist value: strings unquoted ('' is a quote), others stripped."""
    items, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if c in " ,":
            i += 1
        elif c in "'\"":
            q, j, s = c, i + 1, []
            while j < n:
                if text[j] == q:
                    if j + 1 < n and text[j + 1] == q:
                        s.append(q)
                        j += 2
                        continue
                    break
                s.append(text[j])
                j += 1
            items.append(("str", "".join(s)))
            i = j + 1
        else:
            j = i
            while j < n and text[j] != ",":
                j += 1
            items.append(("raw", text[i:j].strip()))
            i = j
    return items


def scalar(text):
    """One CSV cell for a namelist value."""
    items = fortran_items(text)
    if not items:
        return ""
    if len(items) == 1:
        return items[0][1]
    if all(kind == "str" for kind, _ in items):
        return ";".join(v for _, v in items)
    try:
        return repr(max(abs(float(v.replace("d", "e").replace("D", "e"))) for _, v in items))
    except ValueError:
        return ";".join(v for _, v in items)


def read_summary(path):
    """{group: {key: raw value text}} of a summary.nml."""
    groups, group = {}, None
    with open(path) as f:
        for line in f:
            s = line.strip()
            if not s or s.startswith("!"):
                continue
            if s.startswith("&"):
                group = s[1:].split()[0].lower()
                groups.setdefault(group, {})
            elif s == "/":
                group = None
            elif group is not None:
                m = KEY.match(s)
                if m:
                    groups[group][m.group(1).lower()] = m.group(2)
    if "summary" not in groups:
        raise ValueError("no &summary group")
    return groups


def row_of(groups, case_keys):
    row = {}
    for key, value in groups["summary"].items():
        row[key] = scalar(value)
    for key in case_keys:
        g, _, k = key.partition(".")
        if k in groups.get(g, {}):
            row[key.replace(".", "_")] = scalar(groups[g][k])
    for g, values in groups.items():
        if g.startswith("summary_"):
            prefix = g[len("summary_"):]
            for key, value in values.items():
                row[f"{prefix}_{key}"] = scalar(value)
    return row


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("dirs", nargs="+")
    p.add_argument("--case-keys", default="forcing.omega,friction.mu")
    args = p.parse_args(argv)
    case_keys = [k.strip().lower() for k in args.case_keys.split(",") if k.strip()]
    rows, columns = [], list(FIRST) + [k.replace(".", "_") for k in case_keys]
    for top in args.dirs:
        found = []
        for root, _, files in os.walk(top):
            if "summary.nml" in files:
                found.append(os.path.join(root, "summary.nml"))
        for path in sorted(found):
            try:
                row = row_of(read_summary(path), case_keys)
            except (OSError, ValueError, UnicodeDecodeError) as e:
                print(f"collect.py: error: {path}: {e}", file=sys.stderr)
                return 1
            row["case"] = os.path.relpath(os.path.dirname(path), top)
            for key in row:
                if key not in columns:
                    columns.append(key)
            rows.append(row)
    if not rows:
        print(f"collect.py: error: no summary.nml under {', '.join(args.dirs)}", file=sys.stderr)
        return 1
    w = csv.DictWriter(sys.stdout, fieldnames=columns, restval="", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
