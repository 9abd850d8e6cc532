"""``mbseig uncertainty CASE --param NAME=DIST ...``: the probability that the case is unstable
when some of its parameters are random, an interval for it, the distance to instability and
what drives it (DESIGN §8 "Stability under uncertainty")."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from ..casefile import parse_param_overrides
from ..errors import CaseError
from ..numerics import jsonable
from .common import (
    JOBS_HELP,
    KeptStudy,
    _jobs,
    add_progress_options,
    case_command,
    parameter_units_of,
    print_json,
    resume_dir,
    show_progress,
)

def register(sub):
    p = sub.add_parser(
        "uncertainty", help="probability of instability under random parameters, its 95 %% "
                            "interval, the reliability index and the drivers",
        description="The probability that the case is unstable when parameters are random: "
                    "--param NAME=normal(MU,SIGMA) | lognormal(MEDIAN,SIGMA_LOG) | "
                    "uniform(A,B) (independent inputs; ln X of a lognormal is normal with "
                    "mean ln MEDIAN and standard deviation SIGMA_LOG); --param NAME=VALUE "
                    "fixes a parameter as modes does.  Each sample's stability is the verdict "
                    "mbseig modes gives there.")
    p.add_argument("case", metavar="CASE", help="case file (TOML)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=DIST",
                   help="a random input NAME=normal(MU,SIGMA), lognormal(MEDIAN,SIGMA_LOG) or "
                        "uniform(A,B), or a fixed value NAME=VALUE (repeatable)")
    p.add_argument("--samples", type=_jobs, default=10_000, metavar="N",
                   help="Monte Carlo samples (default 10000); for subset simulation the "
                        "samples per level")
    p.add_argument("--seed", type=_seed, default=0, metavar="S",
                   help="seed of the random samples (default 0; the same seed gives the same "
                        "output)")
    p.add_argument("--method", default="auto",
                   choices=("auto", "monte-carlo", "form", "subset"),
                   help="auto (default: Monte Carlo, then subset simulation where it found "
                        "fewer than 10 unstable samples), monte-carlo, form (first-order "
                        "reliability: the design point and beta) or subset (subset simulation, "
                        "for small probabilities)")
    p.add_argument("--config", default=None, metavar="NAME",
                   help="a named configuration of the case's [configurations] table")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="write samples.csv, uncertainty.json, histogram.png and, for two "
                        "inputs, scatter.png to DIR (default: uncertainty-CASE[-CONFIG])")
    p.add_argument("--jobs", type=_jobs, default=None, metavar="N", help=JOBS_HELP)
    p.add_argument("--resume", default=None, metavar="DIR",
                   help="keep every batch of samples in DIR as it completes; rerun with the "
                        "same DIR to compute only the missing ones (the same output).  Without "
                        "it, Ctrl-C keeps the finished ones in OUT-resume next to --out")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the batches of samples on a Dask distributed scheduler "
                        "(pip install 'mbseig[dask]')")
    add_progress_options(p)
    p.set_defaults(run=run)


def _seed(text):
    import argparse

    try:
        n = int(text)
    except ValueError:
        n = -1
    if n < 0:
        raise argparse.ArgumentTypeError(f"must be a non-negative integer, got {text!r}")
    return n


def _inputs(args, spec):
    """(random inputs, fixed parameters) from the --param items."""
    from ..studies.uncertainty_methods import parse_input

    import re

    from ..casefile.expr import FUNCTIONS

    random_items, fixed_items = [], []
    for item in args.param:
        name, sep, value = item.partition("=")
        call = re.match(r"\s*([A-Za-z_]\w*)\s*\(", value)
        # a distribution, or a call of no function of the expressions (refused by parse_input
        # with the distributions it knows); an expression such as sqrt(2) fixes the parameter
        if sep and call and call.group(1) not in FUNCTIONS:
            random_items.append((name.strip(), value.strip()))
        else:
            fixed_items.append(item)
    fixed = parse_param_overrides(fixed_items)
    inputs = []
    for name, text in random_items:
        if not name:
            raise CaseError(f"--param expects NAME=DIST, got {name}={text!r}", element="--param")
        try:
            inputs.append(parse_input(name, text))
        except ValueError as exc:
            raise CaseError(f"{name}: {exc}", element="--param", file=spec.source) from None
    if not inputs:
        raise CaseError("give at least one random input --param NAME=normal(MU,SIGMA) "
                        "(or lognormal(MEDIAN,SIGMA_LOG), uniform(A,B))", element="--param",
                        file=spec.source)
    return inputs, fixed


def run_any(args, spec) -> int:
    from ..studies.runners import progress_bar

    inputs, fixed = _inputs(args, spec)
    stem = spec.name + (f"-{args.config}" if args.config else "")
    folder = Path(args.out or f"uncertainty-{stem}")
    bar = progress_bar() if show_progress(args) else None
    with KeptStudy(args.resume, resume_dir(folder), args.samples,
                   close=bar.close if bar is not None else None) as kept:
        try:
            try:
                from ..studies.uncertainty import uncertainty_study

                study = uncertainty_study(spec, inputs, config=args.config, fixed=fixed,
                                          samples=args.samples, seed=args.seed,
                                          method=args.method, jobs=args.jobs,
                                          scheduler=args.scheduler, progress=bar,
                                          resume=kept.checkpoint)
            finally:
                if bar is not None:
                    bar.close()
            return _write(args, spec, study, inputs, folder)
        except KeyboardInterrupt as exc:
            return kept.say(exc)


def _write(args, spec, study, inputs, folder) -> int:
    out = jsonable(study.to_json())
    paths = write_outputs(study, inputs, folder, units=parameter_units_of(spec))
    out["outputs"] = [str(p) for p in paths]
    (folder / "uncertainty.json").write_text(json.dumps(out, indent=1, allow_nan=False) + "\n")
    if args.json:
        return print_json(out)
    for line in summary_lines(study, inputs):
        print(line)
    print("wrote " + ", ".join(str(p) for p in paths))
    return 0


def summary_lines(study, inputs) -> list:
    """The text summary (values within their bound of 0 shown as 0: DESIGN §6)."""
    from ..plots.uncertainty import shown_damping

    r = study.result
    lines = [f"case {study.case}" + (f" ({study.config})" if study.config else "")
             + f": {study.kind} reference, {len(inputs)} random input"
             + ("s" if len(inputs) > 1 else "")]
    for i in inputs:
        lines.append(f"  {i.name} ~ {i.distribution}({', '.join(f'{a:g}' for a in i.arguments)})")
    v = r.verdicts
    lines.append(f"method: {r.method}, {r.evaluations} models solved (seed {r.seed}): "
                 f"{v['stable']} stable, {v['critical']} critical, {v['unstable']} unstable, "
                 f"{v['failed']} failed")
    ci = r.ci95
    ci_txt = f", 95 % interval [{ci[0]:.4g}, {ci[1]:.4g}]" if ci is not None else ""
    lines.append(f"P(unstable) = {r.p_unstable:.4g}{ci_txt}; P(not stable) = "
                 f"{r.p_not_stable:.4g}")
    if r.reliability_index is not None:
        dp = ", ".join(f"{k} = {x:.6g}" for k, x in (r.design_point or {}).items())
        lines.append(f"reliability index beta = {r.reliability_index:.6g}; design point: {dp}")
    if r.least_damping:
        ld = r.least_damping
        q = ld["quantiles"]
        show = [float(shown_damping(x, _bound(r))) for x in (ld["mean"], q["0.01"], q["0.5"],
                                                                q["0.99"])]
        lines.append(f"least damping: mean {show[0]:.4g} 1/s, 1 % {show[1]:.4g}, median "
                     f"{show[2]:.4g}, 99 % {show[3]:.4g} (std {ld['std']:.4g})")
    if r.drivers:
        lines.append("drivers (share of the variance of the least damping): "
                     + ", ".join(f"{d['name']} {d['share']:.3f}" for d in r.drivers))
    for note in r.notes:
        lines.append(f"note: {note}")
    failed = [e for e in study.errors if e]
    if failed:
        lines.append(f"first failure: {failed[0]}")
    return lines


def _bound(r):
    """The largest error bound of the evaluated least dampings (a summary value within it of 0
    is shown as 0)."""
    import numpy as np

    b = np.asarray(r.evaluated.bound, float)
    b = b[np.isfinite(b)]
    return float(b.max()) if b.size else 0.0


def write_outputs(study, inputs, folder, *, units=None) -> list:
    """samples.csv, histogram.png and (two inputs) scatter.png in ``folder``; the paths (the
    JSON is written by the caller, with these paths in it)."""
    import numpy as np

    from ..plots import save
    from ..plots.uncertainty import damping_histogram, shown_damping, verdict_scatter
    from ..studies.uncertainty_methods import CODES

    units = units or {}
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", element="--out",
                        file=str(folder)) from None
    ev = study.result.evaluated
    names = [i.name for i in inputs]
    label = study.case + (f" ({study.config})" if study.config else "")
    path = folder / "samples.csv"
    shown = shown_damping(ev.delta, ev.bound)
    errors = list(study.errors) + [None] * (len(ev.delta) - len(study.errors))
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "stage", *names, "least_damping", "least_damping_bound", "verdict",
                    "error"])
        for k in range(len(ev.delta)):
            d = shown[k]
            w.writerow([k, ev.stage[k], *(repr(float(x)) for x in ev.x[k]),
                        "" if not np.isfinite(d) else repr(float(d)),
                        "" if not np.isfinite(ev.bound[k]) else repr(float(ev.bound[k])),
                        CODES[int(ev.code[k])], errors[k] or ""])
    paths = [folder / "uncertainty.json", path]
    fig = damping_histogram(ev.delta, ev.bound, ev.code, case=label,
                            method=study.result.method)
    paths.append(save(fig, folder / "histogram.png", element="--out"))
    if len(inputs) == 2:
        grid = None
        if study.grid is not None:
            g1, g2, D, B = study.grid
            grid = (g1, g2, shown_damping(D, B))
        fig = verdict_scatter(ev.x, ev.code, names, grid=grid, case=label,
                              units=tuple(units.get(n, "") for n in names))
        paths.append(save(fig, folder / "scatter.png", element="--out"))
    return paths


#: the command on every reference motion the case declares
run = case_command("uncertainty", rest=run_any, steady=run_any, periodic=run_any)
