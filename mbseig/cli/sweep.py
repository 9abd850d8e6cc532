"""``mbseig sweep CASE --param NAME=START:STOP:COUNT ...``: branches followed by continuation,
tracked modes, stability boundaries, folds, two-parameter boundary curves."""

from __future__ import annotations

from pathlib import Path

from ..casefile import parse_param_overrides
from ..errors import CaseError
from .common import (
    KeptStudy,
    add_case_arguments,
    add_progress_options,
    add_study_options,
    case_command,
    parameter_units_of,
    print_json,
    resume_dir,
    show_progress,
)


def register(sub):
    p = sub.add_parser(
        "sweep", help="modes over a parameter grid by continuation, tracked by MAC, with "
                      "stability boundaries, folds and boundary curves",
        description="Sweep parameters: --param NAME=START:STOP:COUNT (repeatable; the first is the "
                    "continuation and tracking axis, a second gives a stability map and the "
                    "boundaries followed across it); --param NAME=VALUE fixes a parameter.")
    add_case_arguments(p)
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default: sweep-CASE[-CONFIG])")
    add_study_options(p)
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the points on a Dask distributed scheduler (pip install 'mbseig[dask]')")
    p.add_argument("--xtol-rel", type=float, default=1e-10, metavar="X",
                   help="boundary tolerance relative to the first axis' span (default 1e-10)")
    p.add_argument("--no-continuation", dest="continuation", action="store_false",
                   help="solve every point on its own from the case's positions (no branch "
                        "following, no folds)")
    p.add_argument("--no-curves", dest="curves", action="store_false",
                   help="with two swept parameters, do not follow the boundaries across the second")
    p.add_argument("--diagram", default=None, metavar="NAME",
                   help="coordinate or named angle of the bifurcation diagram (default: the one "
                        "that varies most along the branch)")
    add_progress_options(p)
    p.set_defaults(run=run)


@case_command("sweep")
def run(args, spec) -> int:
    from ..studies.sweep import parse_range, progress_bar

    ranges = [parse_range(item) for item in args.param if ":" in item]
    fixed = parse_param_overrides([item for item in args.param if ":" not in item])
    if not ranges:
        raise CaseError("give at least one --param NAME=START:STOP:COUNT", element="--param")
    stem = Path(args.case).stem + (f"-{args.config}" if args.config else "")
    out_dir = args.out or f"sweep-{stem}"
    bar = progress_bar() if show_progress(args) else None
    total = 1
    for _, values in ranges:
        total *= len(values)
    # Ctrl-C: the finished points are kept (in --resume DIR, else in OUT-resume) and one line
    # says where (KeptStudy); every output is written from the result, so a stop while they
    # are written keeps every point too
    with KeptStudy(args.resume, resume_dir(out_dir), total,
                   close=bar.close if bar is not None else None) as kept:
        try:
            return _sweep(args, spec, ranges, fixed, stem, out_dir, bar, kept)
        except KeyboardInterrupt as exc:
            return kept.say(exc)


def _sweep(args, spec, ranges, fixed, stem, out_dir, bar, kept) -> int:
    from ..studies.sweep import run_sweep, write_outputs

    try:
        res = run_sweep(spec, ranges, config=args.config, fixed=fixed, jobs=args.jobs,
                        scheduler=args.scheduler, progress=bar, xtol_rel=args.xtol_rel,
                        continuation=args.continuation, curves=args.curves,
                        diagram=args.diagram, resume=kept.checkpoint)
    finally:  # (an error's line below the bars, not glued to them)
        if bar is not None:
            bar.close()
    kept.checkpoint.points[0] = kept.checkpoint.points[1]  # (every point finished)
    units = parameter_units_of(spec)
    paths = write_outputs(res, out_dir, units=units)
    camp = _campbell(args, spec, ranges, fixed, out_dir, paths, units)
    lift = _lift_offs(spec, ranges, fixed, args.config)
    if args.json:
        out = {**res.to_json(), **camp}
        out["boundaries"] = out["boundaries"] + [dict(b) for b in lift]
        print_json(out)
        return 0
    n_pts = sum(len(line) for line in res.points)
    failed = sum(1 for line in res.points for pt in line if pt.get("error"))
    cold = sum(1 for line in res.points for pt in line if pt.get("statics") == "cold")
    how = "by continuation" if args.continuation else "each on its own"
    print(f"sweep {stem}: {n_pts} points {how} ({failed} failed"
          + (f", {cold} solved on their own" if args.continuation and cold else "")
          + f") on {res.runner}, {len(res.boundaries)} stability boundaries "
          f"(xtol {res.tolerances['xtol']:.3g})")
    for b in res.boundaries:
        where = ", ".join(f"{k} = {v:g}" for k, v in b["fixed"].items())
        event = "" if b.get("event") == "crossing" else f" at a {b['event']}, branch {b['branch']}"
        band = b.get("band")
        band_txt = (f"; critical band [{band[0]:.10g}, {band[1]:.10g}]"
                    if band and band[0] != band[1] else "")
        print(f"  {b['parameter']} = {b['value']:.10g}{' at ' + where if where else ''}: "
              f"{b['kind']} ({b['stability']} of stability){event}, s = {b['eigenvalue'][0]:.4g} "
              f"{b['eigenvalue'][1]:+.6g}i{band_txt}")
    for b in lift:
        print(f"  {b['parameter']} = {b['value']:.10g}: lift-off of contact {b['contact']} "
              f"({'it stops pushing' if b['stability'] == 'loss' else 'it pushes again'})")
    for f in res.folds:
        if f["type"] == "fold" and not f.get("dof"):
            print(f"  {f['parameter']} = {f['value']:.10g}: fold without degrees of freedom "
                  f"(a dead point), branch {f['branch']}")
    for c in res.curves:
        ok = [p for p in c["points"] if p["value"] is not None]
        print(f"  boundary followed across {c['along']}: {len(ok)} of {len(c['points'])} points "
              f"({c['kind']}, {c['stability']} of stability)")
    for c in camp.get("critical_speeds", []):
        print(f"  critical speed {c['value']:.10g} (Omega = {c['speed']:.10g} rad/s): track "
              f"{c['mode']}, {c['whirl']} whirl")
    print("wrote " + ", ".join(str(p) for p in paths))
    return 0


def _lift_offs(spec, ranges, fixed, config) -> tuple:
    """Where a single-sided contact of a static case stops (or starts) pushing along the swept
    parameter (DESIGN §8: a boundary of kind ``lift-off``), for a sweep of one parameter."""
    joints = spec.data.get("joints", [])
    if len(ranges) != 1 or not any(isinstance(j, dict) and j.get("type") in ("contact", "rolling")
                                   for j in (joints if isinstance(joints, list) else [])):
        return ()
    from ..studies.steady_sweep import contact_boundaries

    name, values = ranges[0]
    return contact_boundaries(spec, name, values, config=config, fixed=fixed)


def _campbell(args, spec, ranges, fixed, out_dir, paths, units) -> dict:
    """A sweep of one parameter that sets a rotor's speed also gives the Campbell diagram
    (mbseig.studies.campbell): campbell.json, campbell.png and, in the sweep's JSON,
    ``campbell`` and ``critical_speeds``."""
    import json

    try:
        from ..plots import spatial as plots_spatial
        from ..studies.campbell import campbell, speed_parameter
    except ImportError:  # the spatial layer is not part of this installation
        return {}
    name, values = ranges[0]
    if len(ranges) != 1 or not speed_parameter(spec, name, values, config=args.config,
                                               fixed=fixed):
        return {}
    res = campbell(spec, name, values, config=args.config, fixed=fixed, jobs=args.jobs,
                   xtol_rel=args.xtol_rel)
    out = res.to_json()
    path = Path(out_dir) / "campbell.json"
    path.write_text(json.dumps(out, indent=1, allow_nan=False) + "\n")
    paths.append(path)
    figure = plots_spatial.campbell_diagram(res, units=units)
    paths.append(plots_spatial.save(figure, Path(out_dir) / "campbell.png"))
    return {"campbell": out, "critical_speeds": out["critical_speeds"]}
