"""``mbseig sweep CASE --param NAME=START:STOP:COUNT`` on a periodic case: the Floquet verdict
at every point and the ``boundaries`` where it changes (flip / fold / secondary, loss /
recovery), located to 1e-8 relative; ``--out DIR`` also gets ``sweep.json``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..casefile import parse_param_overrides
from ..errors import CaseError
from ..numerics import jsonable
from ..studies.periodic_sweep import periodic_sweep
from ..studies.tracking import parse_range
from .common import print_json


def run(args, spec) -> int:
    ranges = [parse_range(item) for item in args.param if ":" in item]
    fixed = parse_param_overrides([item for item in args.param if ":" not in item])
    if len(ranges) != 1:
        raise CaseError("a sweep of a periodic case takes one range --param NAME=START:STOP:COUNT "
                        f"(got {len(ranges)})", element="--param", file=spec.source)
    (name, values), = ranges
    if name not in spec.parameters:
        raise CaseError(f"unknown parameter {name!r}", element="--param", file=spec.source)
    show = args.progress if args.progress is not None else sys.stderr.isatty()

    def progress(done, total):
        print(f"\rpoint {done}/{total}", end="" if done < total else "\n", file=sys.stderr)

    sweep = periodic_sweep(spec, name, values, config=args.config, fixed=fixed,
                           progress=progress if show else None)
    out = sweep.to_dict()
    if args.out:
        folder = Path(args.out)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "sweep.json").write_text(json.dumps(jsonable(out), indent=1) + "\n")
    if args.json:
        print_json(out)
        return 0
    print(f"case {sweep.case}: Floquet verdict over {name} ({len(values)} points)")
    for pt in out["points"]:
        print(f"  {name} = {pt['value']:<14.8g} {pt['verdict']:<9} max|mu| = "
              f"{pt['spectral_radius']:.10g} ± {pt['error_bound']:.1e}")
    for b in out["boundaries"]:
        print(f"boundary: {name} = {b['value']:.12g} ({b['kind']}, {b['stability']}; {b['method']})")
    if not out["boundaries"]:
        print("no verdict change on this grid")
    return 0
