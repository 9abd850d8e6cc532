"""``mbseig sweep CASE --param NAME=START:STOP:COUNT ...``: branches followed by continuation,
tracked modes, stability boundaries, folds, two-parameter boundary curves."""

from __future__ import annotations

from ..numerics import jsonable
import json
import sys
from ..studies.tracking import parse_range

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
                   help="run the points on a Dask distributed scheduler "
                        "(pip install 'mbseig[dask]')")
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


def run_rest(args, spec) -> int:
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
    batch = sum(1 for line in res.points for pt in line if pt.get("statics") == "batch")
    how = "by continuation" if args.continuation else "each on its own"
    print(f"sweep {stem}: {n_pts} points {how} ({failed} failed"
          + (f", {batch} solved together with their line" if batch else "")
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


# ---- steady motion (steady reference: [motion] with speed)
# ``mbseig sweep CASE --param v=START:STOP:COUNT`` on a steady motion (DESIGN §8): the modes at
# every grid value, the flutter (Hopf), divergence and lift-off boundaries refined between them
# (:mod:`mbseig.studies.steady_sweep`), as JSON (``--json``) and ``sweep.json`` in ``--out``.
def run_steady(args, spec) -> int:
    from ..studies.runners import progress_bar
    from ..studies.steady_sweep import steady_sweep
    from ..studies.tracking import parse_range

    ranges = [parse_range(item) for item in args.param if ":" in item]
    fixed = parse_param_overrides([item for item in args.param if ":" not in item])
    if len(ranges) != 1:
        raise CaseError("a steady-motion sweep takes one --param NAME=START:STOP:COUNT",
                        element="--param")
    name, values = ranges[0]
    span = abs(values[-1] - values[0])
    xtol = float(getattr(args, "xtol_rel", 1e-10) or 1e-10) * span
    folder = Path(args.out) if args.out else Path(f"sweep-{spec.name}"
                                                  + (f"-{args.config}" if args.config else ""))
    bar = progress_bar() if show_progress(args) else None
    # Ctrl-C: the finished points kept (--resume DIR, else OUT-resume) and said in one line
    with KeptStudy(getattr(args, "resume", None), resume_dir(folder), len(values),
                   close=bar.close if bar is not None else None) as kept:
        try:
            try:
                res = steady_sweep(spec, name, values, config=args.config, fixed=fixed,
                                   xtol=min(xtol, 1e-11 * max(1.0, abs(values[-1]))),
                                   jobs=getattr(args, "jobs", None), progress=bar,
                                   resume=kept.checkpoint)
            finally:
                if bar is not None:
                    bar.close()
            return _write(args, spec, res, name, values, folder)
        except KeyboardInterrupt as exc:
            return kept.say(exc)


def _write(args, spec, res, name, values, folder) -> int:
    out = {"case": spec.name, **res.as_dict()}
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sweep.json").write_text(json.dumps(jsonable(out), indent=1, allow_nan=False))
    out["outputs"] = [str(folder / "sweep.json")]
    if args.json:
        print_json(out)
        return 0
    print(f"case {spec.name}: steady motion swept over {name} = {values[0]:g} … {values[-1]:g} "
          f"({len(values)} points)")
    print(f"  points analysed together (the case built once: {name} enters [motion] alone)"
          if res.batch is None else f"  points analysed one at a time ({res.batch})")
    for b in res.boundaries:
        extra = f", {b['contact']}" if "contact" in b else (
            f", ω = {b['frequency']:.6g} rad/s" if "frequency" in b else "")
        print(f"  {b['kind']} ({b['stability']}) at {name} = {b['value']:.12g}{extra}")
    if not res.boundaries:
        print("  no boundary in the range")
    print(f"written: {folder / 'sweep.json'}")
    return 0


# ---- periodic motion (periodic reference: [motion] with period)
# ``mbseig sweep CASE --param NAME=START:STOP:COUNT`` on a periodic case: the Floquet verdict
# at every point and the ``boundaries`` where it changes (flip / fold / secondary, loss /
# recovery), located to 1e-8 relative; ``--out DIR`` also gets ``sweep.json``.
#
# With two ranges (``--param A=...:...:n --param B=...:...:m``) it writes the stability chart over
# the grid (the Ince–Strutt chart of a Mathieu-type system): ``chart.png`` and ``chart.json`` (the
# verdict, max|μ| and the deciding bound at every point, and where the verdict changes along
# the first parameter, each grid bracket located to 1e-8 relative) in ``--out DIR`` (default
# ``sweep-CASE``).
def run_periodic(args, spec) -> int:
    ranges = [parse_range(item) for item in args.param if ":" in item]
    fixed = parse_param_overrides([item for item in args.param if ":" not in item])
    if len(ranges) not in (1, 2):
        raise CaseError("a sweep of a periodic case takes one range --param NAME=START:STOP:COUNT "
                        f"(or two for a stability chart; got {len(ranges)})", element="--param",
                        file=spec.source)
    for name, _ in ranges:
        if name not in spec.parameters:
            raise CaseError(f"unknown parameter {name!r}", element="--param", file=spec.source)
    if len(ranges) == 2 and ranges[0][0] == ranges[1][0]:
        raise CaseError(f"the two ranges sweep the same parameter {ranges[0][0]!r}",
                        element="--param", file=spec.source)
    show = show_progress(args)
    open_line = []  # a progress line not ended yet

    def progress(done, total):
        print(f"\rpoint {done}/{total}", end="" if done < total else "\n", file=sys.stderr)
        open_line[:] = [True] if done < total else []

    def end_line():
        if open_line:
            print(file=sys.stderr)
            open_line.clear()

    total = 1
    for _, values in ranges:
        total *= len(values)
    stem = spec.name + (f"-{args.config}" if args.config else "")
    folder = args.out or f"sweep-{stem}"
    # Ctrl-C: the finished points kept (--resume DIR, else OUT-resume) and said in one line
    with KeptStudy(getattr(args, "resume", None), resume_dir(folder), total,
                   close=end_line) as kept:
        study = {"progress": progress if show else None, "jobs": getattr(args, "jobs", None),
                 "resume": kept.checkpoint}
        try:
            if len(ranges) == 2:
                return _chart(args, spec, ranges, fixed, study)
            return _periodic_sweep(args, spec, ranges, fixed, study)
        except KeyboardInterrupt as exc:
            return kept.say(exc)


def _periodic_sweep(args, spec, ranges, fixed, study) -> int:
    from ..studies.periodic_sweep import periodic_sweep

    (name, values), = ranges
    sweep = periodic_sweep(spec, name, values, config=args.config, fixed=fixed, **study)
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
        print(f"boundary: {name} = {b['value']:.12g} ({b['kind']}, {b['stability']}; "
              f"{b['method']})")
    if not out["boundaries"]:
        print("no verdict change on this grid")
    return 0


def _chart(args, spec, ranges, fixed, study) -> int:
    from ..plots import save
    from ..plots.charts import chart_figure
    from ..studies.periodic_sweep import periodic_chart

    res = periodic_chart(spec, ranges[0], ranges[1], config=args.config, fixed=fixed, **study)
    out = res.to_dict()
    stem = spec.name + (f"-{args.config}" if args.config else "")
    folder = Path(args.out or f"sweep-{stem}")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "chart.json").write_text(json.dumps(jsonable(out), indent=1) + "\n")
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", element="--out",
                        file=str(folder)) from None
    fig = chart_figure(res.chart)
    fig.axes[0].set_title(f"{spec.name}: Floquet stability chart")
    save(fig, folder / "chart.png", element="--out")
    out["files"] = [str(folder / "chart.json"), str(folder / "chart.png")]
    if args.json:
        return print_json(out)
    (n1, v1), (n2, v2) = ranges
    counts = {v: sum(1 for row in out["verdicts"] for x in row if x == v)
              for v in ("stable", "critical", "unstable")}
    print(f"case {res.case}: Floquet stability chart over {n1} ({len(v1)}) x {n2} ({len(v2)}): "
          + ", ".join(f"{n} {v}" for v, n in counts.items()))
    for e in out["boundaries"]:
        print(f"  {e['verdicts'][0]} -> {e['verdicts'][1]} ({e['kind']}) at {n2} = "
              f"{e['at'][n2]:.8g}: {n1} = {e['value']:.12g} (in [{e['bracket'][0]:.8g}, "
              f"{e['bracket'][1]:.8g}]; {e['method']})")
    print(f"wrote {folder / 'chart.json'} and {folder / 'chart.png'}")
    return 0


#: the command on every reference the case declares (its [motion] table)
run = case_command("sweep", rest=run_rest, steady=run_steady, periodic=run_periodic)
