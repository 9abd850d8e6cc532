"""``mbseig sweep CASE --param v=START:STOP:COUNT`` on a steady motion (DESIGN §8): the modes at
every grid value, the flutter (Hopf), divergence and lift-off boundaries refined between them
(:mod:`mbseig.studies.steady_sweep`), as JSON (``--json``) and ``sweep.json`` in ``--out``."""

from __future__ import annotations

import json
from pathlib import Path

from ..casefile import parse_param_overrides
from ..errors import CaseError
from ..numerics import jsonable
from .common import KeptStudy, print_json, resume_dir, show_progress

__all__ = ["run"]


def run(args, spec) -> int:
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
    for b in res.boundaries:
        extra = f", {b['contact']}" if "contact" in b else (
            f", ω = {b['frequency']:.6g} rad/s" if "frequency" in b else "")
        print(f"  {b['kind']} ({b['stability']}) at {name} = {b['value']:.12g}{extra}")
    if not res.boundaries:
        print("  no boundary in the range")
    print(f"written: {folder / 'sweep.json'}")
    return 0
