"""``mbseig sweep CASE --param NAME=START:STOP:COUNT ...``: tracked modes and stability boundaries."""

from __future__ import annotations

import sys
from pathlib import Path

from ..casefile import parse_param_overrides
from ..errors import CaseError
from .common import add_case_arguments, print_json


def register(sub):
    p = sub.add_parser(
        "sweep", help="modes over a parameter grid, tracked by MAC, with stability boundaries",
        description="Sweep parameters: --param NAME=START:STOP:COUNT (repeatable; the first is the "
                    "tracking axis, two make a stability map); --param NAME=VALUE fixes a parameter.")
    add_case_arguments(p)
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default: sweep-CASE[-CONFIG])")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="local worker processes (default: CPU count; 1 runs in-process)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the points on a Dask distributed scheduler (pip install 'mbseig[dask]')")
    p.add_argument("--xtol-rel", type=float, default=1e-10, metavar="X",
                   help="boundary tolerance relative to the first axis' span (default 1e-10)")
    prog = p.add_mutually_exclusive_group()
    prog.add_argument("--progress", dest="progress", action="store_true", default=None,
                      help="always show the progress bar on stderr")
    prog.add_argument("--no-progress", dest="progress", action="store_false",
                      help="never show it (default: only when stderr is a terminal)")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..studies.sweep import parse_range, progress_bar, run_sweep, write_outputs

    ranges = [parse_range(item) for item in args.param if ":" in item]
    fixed = parse_param_overrides([item for item in args.param if ":" not in item])
    if not ranges:
        raise CaseError("give at least one --param NAME=START:STOP:COUNT", element="--param")
    show = args.progress if args.progress is not None else sys.stderr.isatty()
    res = run_sweep(args.case, ranges, config=args.config, fixed=fixed, jobs=args.jobs,
                    scheduler=args.scheduler, progress=progress_bar() if show else None,
                    xtol_rel=args.xtol_rel)
    stem = Path(args.case).stem + (f"-{args.config}" if args.config else "")
    paths = write_outputs(res, args.out or f"sweep-{stem}")
    if args.json:
        print_json(res.to_json())
        return 0
    n_pts = sum(len(line) for line in res.points)
    failed = sum(1 for line in res.points for pt in line if pt.get("error"))
    print(f"sweep {stem}: {n_pts} points ({failed} failed) on {res.runner}, "
          f"{len(res.boundaries)} stability boundaries (xtol {res.tolerances['xtol']:.3g})")
    for b in res.boundaries:
        where = ", ".join(f"{k} = {v:g}" for k, v in b["fixed"].items())
        print(f"  {b['parameter']} = {b['value']:.10g}{' at ' + where if where else ''}: "
              f"{b['kind']} ({b['stability']} of stability), s = {b['eigenvalue'][0]:.4g} "
              f"{b['eigenvalue'][1]:+.6g}i, track {b['track']}")
    print("wrote " + ", ".join(str(p) for p in paths))
    return 0
