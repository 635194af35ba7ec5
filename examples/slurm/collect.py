#!/usr/bin/env python3
"""Collect the results of every case of a campaign into one CSV (standard library only).

    collect.py --cases CASES_DIR [--status STATUS_DIR] [--case-keys ...] > out.csv
    collect.py RESULTS_DIR [RESULTS_DIR ...] [--case-keys forcing.omega,friction.mu] > out.csv

With --cases (what job.sh runs: every *.nml of CASES_DIR, sorted), one row per case FILE,
whether it produced results or not: its summary.nml is looked for in the case's &output
directory, its exit code in STATUS_DIR/<case>.exit (written by job.sh; default: status). A
case without a summary.nml is a row too, with status 'failed' (its exit code says why: 1
input, 2 numerical, 3 I/O) or 'not run' (no exit code either: the task never ran or was
killed). Without --cases, every summary.nml under the RESULTS_DIRs (sorted by path), and a
'failed' row for every case folder without one (a folder with no subfolder).
Columns: case (the case file's name, or the folder relative to the RESULTS_DIR), status ('ok',
'warnings', 'untrusted', 'failed', 'not run'), exit_code (when known), method, trusted,
warnings, diagnosis; then the values of the echoed case named by --case-keys (group.key,
default forcing.omega and friction.mu: the campaign's parameters); then every other scalar of
&summary and of the &summary_<method> groups, named <method>_<key> for the latter (hbm_nfev,
euler_periods, reference_defect, ...), in the order first met. A list of numbers (the
per-quantity errors hbm_vs_reference_max, ...) becomes its largest absolute value; a list of
strings is joined with ';'. Logicals stay T/F; a case without a value has an empty cell.
Exit 1 when no case is found or a summary.nml cannot be read (the file is named on stderr).
"""
import argparse
import csv
import os
import re
import sys

KEY = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*)$")
FIRST = ["case", "status", "exit_code", "method", "trusted", "warnings", "diagnosis"]
DIRECTORY = re.compile(r"""\bdirectory\s*=\s*(['"])(.*?)\1""", re.IGNORECASE)


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


def status_of(row):
    """ok, warnings or untrusted from a summary's trusted and warnings."""
    if row.get("trusted") == "F":
        return "untrusted"
    return "warnings" if row.get("warnings") else "ok"


def output_directory(case_file):
    """The &output directory of a case file ('out' when not given), as stickslip takes it
    (relative to the working directory)."""
    text = open(case_file).read()
    m = re.search(r"&output\b", text, re.IGNORECASE)
    if not m:
        return "out"
    group, quote, i = [], None, m.end()
    while i < len(text):
        c = text[i]
        if quote:
            quote = None if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c == "!":
            i = text.find("\n", i)
            if i < 0:
                break
            continue
        elif c == "/":
            break
        group.append(c)
        i += 1
    d = DIRECTORY.search("".join(group))
    return d.group(2) if d else "out"


def failed_row(case, exit_code, reason):
    return {"case": case, "exit_code": exit_code,
            "status": "failed" if exit_code not in ("", None) else "not run",
            "diagnosis": reason}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("dirs", nargs="*")
    p.add_argument("--cases", help="the folder of the campaign's case files (job.sh's cases/)")
    p.add_argument("--status", default="status", help="job.sh's folder of exit codes")
    p.add_argument("--case-keys", default="forcing.omega,friction.mu")
    args = p.parse_args(argv)
    if not args.dirs and not args.cases:
        p.error("give --cases CASES_DIR or RESULTS_DIR")
    case_keys = [k.strip().lower() for k in args.case_keys.split(",") if k.strip()]
    rows, columns = [], list(FIRST) + [k.replace(".", "_") for k in case_keys]

    def add(row):
        for key in row:
            if key not in columns:
                columns.append(key)
        rows.append(row)

    def summary_row(path, case):
        row = row_of(read_summary(path), case_keys)
        row["case"] = case
        row["status"] = status_of(row)
        return row

    try:
        if args.cases:
            files = sorted(f for f in os.listdir(args.cases) if f.endswith(".nml"))
            for f in files:
                case = f[:-len(".nml")]
                exit_path = os.path.join(args.status, case + ".exit")
                exit_code = open(exit_path).read().strip() if os.path.exists(exit_path) else ""
                path = os.path.join(output_directory(os.path.join(args.cases, f)), "summary.nml")
                if os.path.exists(path):
                    row = summary_row(path, case)
                    row["exit_code"] = exit_code
                    add(row)
                else:
                    add(failed_row(case, exit_code, "no summary.nml in " + os.path.dirname(path) +
                                   ": the case failed before it wrote results (its log says "
                                   "why)" if exit_code else "no summary.nml and no exit code: "
                                   "the case did not run (or was killed)"))
        for top in args.dirs:
            found, bare = [], []
            for root, subdirs, files in os.walk(top):
                if "summary.nml" in files:
                    found.append(os.path.join(root, "summary.nml"))
                elif not subdirs and root != top:
                    bare.append(root)
            for path in sorted(found):
                add(summary_row(path, os.path.relpath(os.path.dirname(path), top)))
            for folder in sorted(bare):
                add(failed_row(os.path.relpath(folder, top), "",
                               "no summary.nml in the case folder: the case failed before it "
                               "wrote results"))
                rows[-1]["status"] = "failed"
    except (OSError, ValueError, UnicodeDecodeError) as e:
        print(f"collect.py: error: {e}", file=sys.stderr)
        return 1
    if not rows:
        where = args.cases or ", ".join(args.dirs)
        print(f"collect.py: error: no case found under {where}", file=sys.stderr)
        return 1
    w = csv.DictWriter(sys.stdout, fieldnames=columns, restval="", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
