#!/usr/bin/env python3
"""Write one case file per parameter set from a template (standard library only).

    make_cases.py TEMPLATE.nml PARAMS.csv [--out DIR] [--prefix case]
    make_cases.py TEMPLATE.nml --grid omega=3,4.5,6 mu=0.45,1 [--out DIR]

Every {name} of the template is replaced by the value of column `name` of PARAMS.csv (one case
per row), or, with --grid, by each combination of the values given (the last name varies
fastest); {case} is replaced by the case's name (case_001, case_002, ...). The template must
use {case} (in &output directory, so that the cases write distinct directories) and every
other placeholder must get a value. Writes DIR/case_001.nml ... (DIR default: cases) and
prints the number of cases (the SLURM array is 1-<that number>). A DIR that already holds
case files (an earlier campaign: job.sh would run them too) is refused unless --clean, which
removes its *.nml files first. Exit 1 on a usage error.
"""
import argparse
import csv
import itertools
import os
import re
import sys

PLACEHOLDER = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)\}")


def parameter_sets(args):
    """The list of {name: value} dicts asked for."""
    if args.grid:
        names, values = [], []
        for item in args.grid:
            name, sep, vals = item.partition("=")
            if not sep or not name or not vals:
                raise ValueError(f"--grid {item!r}: expected name=v1,v2,...")
            names.append(name)
            values.append([v.strip() for v in vals.split(",")])
        return [dict(zip(names, combo)) for combo in itertools.product(*values)]
    if not args.params:
        raise ValueError("give PARAMS.csv or --grid")
    with open(args.params, newline="") as f:
        rows = [{k.strip(): v.strip() for k, v in row.items()} for row in csv.DictReader(f)]
    if not rows:
        raise ValueError(f"{args.params}: no parameter rows")
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("template")
    p.add_argument("params", nargs="?")
    p.add_argument("--grid", nargs="+", metavar="NAME=V1,V2")
    p.add_argument("--out", default="cases")
    p.add_argument("--prefix", default="case")
    p.add_argument("--clean", action="store_true",
                   help="remove the case files of an earlier campaign from --out first")
    args = p.parse_args(argv)
    try:
        with open(args.template) as f:
            template = f.read()
        if "{case}" not in template:
            raise ValueError(f"{args.template}: no {{case}} placeholder (put it in &output "
                             "directory so that every case writes its own directory)")
        sets = parameter_sets(args)
        os.makedirs(args.out, exist_ok=True)
        old = sorted(f for f in os.listdir(args.out) if f.endswith(".nml"))
        if old and not args.clean:
            raise ValueError(f"{args.out}/ already holds {len(old)} case files of an earlier "
                             "campaign (job.sh runs every case file there): remove them, "
                             "or give --clean")
        for f in old:
            os.remove(os.path.join(args.out, f))
        width = max(3, len(str(len(sets))))
        for i, values in enumerate(sets, start=1):
            name = f"{args.prefix}_{i:0{width}d}"
            values = dict(values, case=name)
            missing = sorted(set(PLACEHOLDER.findall(template)) - set(values))
            if missing:
                raise ValueError(f"{args.template}: no value for {', '.join(missing)}")
            text = PLACEHOLDER.sub(lambda m: values[m.group(1)], template)
            with open(os.path.join(args.out, name + ".nml"), "w") as f:
                f.write(text)
    except (OSError, ValueError) as e:
        print(f"make_cases.py: error: {e}", file=sys.stderr)
        return 1
    print(len(sets))
    return 0


if __name__ == "__main__":
    sys.exit(main())
