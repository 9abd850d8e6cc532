"""``mbseig sweep CASE --param NAME=START:STOP:COUNT`` on a periodic case: the Floquet verdict
at every point and the ``boundaries`` where it changes (flip / fold / secondary, loss /
recovery), located to 1e-8 relative; ``--out DIR`` also gets ``sweep.json``.

With two ranges (``--param A=...:...:n --param B=...:...:m``) it writes the stability chart over
the grid (the Ince–Strutt chart of a Mathieu-type system): ``chart.png`` and ``chart.json`` (the
verdict, max|μ| and the deciding bound at every point, and where the verdict changes along
the first parameter, each grid bracket located to 1e-8 relative) in ``--out DIR`` (default
``sweep-CASE``)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..casefile import parse_param_overrides
from ..errors import CaseError
from ..numerics import jsonable
from ..studies.periodic_sweep import periodic_sweep
from ..studies.tracking import parse_range
from .common import KeptStudy, print_json, resume_dir, show_progress


def run(args, spec) -> int:
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
            return _sweep(args, spec, ranges, fixed, study)
        except KeyboardInterrupt as exc:
            return kept.say(exc)


def _sweep(args, spec, ranges, fixed, study) -> int:
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
        print(f"boundary: {name} = {b['value']:.12g} ({b['kind']}, {b['stability']}; {b['method']})")
    if not out["boundaries"]:
        print("no verdict change on this grid")
    return 0


def _chart(args, spec, ranges, fixed, study) -> int:
    from ..plots import save
    from ..studies.floquet_sweep import chart_figure
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
