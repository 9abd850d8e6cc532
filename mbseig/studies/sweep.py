"""Parameter sweeps: continuation along each line, modes at every point, mode tracking by MAC,
stability boundaries where Re s = 0, folds, branch points and two-parameter boundary curves.

For parameter values p on a grid (the Cartesian product of the ``axes``), the first axis varies
along a *line* and the others are fixed per line.  Each line is one pure computation
(:func:`mbseig.studies.continuation.sweep_line`): it follows one equilibrium branch through the
grid by continuation (tangent predictor from the previous equilibrium, pseudo-arclength through
folds, switches at branch points to the stable branch, a fresh solve past a fold that does not
turn forward again), and gives all 2n eigenpairs at every grid point.  Lines run in-process, on
local processes or on a Dask cluster with the same results.  ``continuation=False`` solves every
point on its own from the case's positions instead (:func:`evaluate_point`).

Tracking.  Consecutive points of a line are matched by the modal assurance criterion of the mode
shapes in full coordinates (q = N x, independent of the null-space basis):

    MAC(a, b) = |aᴴ b|² / ((aᴴ a)(bᴴ b))

A complex pair has conjugate shapes (MAC ≈ 1 between them when lightly damped), so a match that
would jump across the real axis costs ``CONJUGATE_PENALTY``; a tiny eigenvalue-distance term
(``DISTANCE_WEIGHT`` · |Δs| / scale) only breaks exact ties.  The assignment is a linear sum
assignment on cost = 1 − MAC + penalties (scipy.optimize.linear_sum_assignment).  Sort order is
never used.

Boundaries.  A tracked eigenvalue is unstable where h = δ + tol < 0 (δ = −Re s, tol of
:func:`mbseig.modal.tolerances`, the same that decides ``mbseig modes``).  Where h changes sign
between two grid points of one branch segment, the boundary is located where Re s = 0 of the
crossing mode (:mod:`mbseig.studies.boundaries`: Re s for a transversal crossing, the pair's
squared distance for a collision on the imaginary axis) by Brent's method to
``xtol = xtol_rel · |stop − start|``, with the tolerance band (where the mode is critical)
reported beside it; conjugate duplicates are merged.  A fold of the branch with degrees of
freedom is a divergence boundary (a real eigenvalue through zero, the branch turning back),
located on the branch itself; so is a branch point.  Folds of a branch without degrees of
freedom (a driven mechanism's dead point) are listed in ``folds`` only.

Two-parameter curves.  With two swept parameters, each boundary of the first line where
stability is lost is followed across the second parameter's range
(:func:`mbseig.studies.boundaries.follow_boundary`): the curve p₁*(p₂) in ``curves``, from which
the stability chart is drawn.
"""

from __future__ import annotations

import itertools
import uuid

import numpy as np

from ..arguments import check
from ..errors import CaseError
from ..model.assembly import UNITS
from .boundaries import (
    AMBIGUOUS_MAC,
    BEND,
    CONJUGATE_PENALTY,
    DISTANCE_WEIGHT,
    MAX_INSERT,
    mac_matrix,
)
from .continuation import release, sweep_line
from .point import as_spec
from .records import Boundary, BoundaryCurve, Fold
from .runners import Runner, progress_bar
from .sweep_outputs import write_outputs
from .sweep_result import SweepResult
from .tracking import (
    curve_task,
    evaluate_point,
    locate_task,
    parse_range,
    track_line,
    track_shapes,
)

__all__ = ["parse_range", "SweepResult", "run_sweep", "evaluate_point", "mac_matrix",
           "track_line", "write_outputs", "progress_bar"]


def _lines(axes, fixed):
    names = [n for n, _ in axes]
    if len(set(names)) != len(names):
        raise CaseError("a parameter is swept twice", element="--param")
    for n in names:
        if n in fixed:
            raise CaseError(f"parameter {n!r} is both swept and fixed", element="--param")
    others = axes[1:]
    return [dict(zip([n for n, _ in others], combo, strict=True))
            for combo in itertools.product(*[v for _, v in others])] or [{}]


def run_sweep(case, axes, *, config=None, fixed=None, jobs=None, scheduler=None, progress=None,
              xtol_rel=1e-10, safety=10.0, stability_rtol=1e-12, continuation=True,
              curves=True, curve_values=None, diagram=None, resume=None, lean=True) -> SweepResult:
    """Sweep ``case`` over ``axes`` = [(name, values), ...] (see the module docstring).

    Parameters
    ----------
    case : str, pathlib.Path or CaseSpec
        A path (read and parsed once, here) or a read case; the lines and boundary searches
        receive the parsed case, never the path.
    axes : list of (str, sequence of float)
        The swept parameters: the first is followed by continuation and tracked; a second
        gives a stability map and the boundaries followed across it.
    config : str, optional
        The configuration (``[configurations.NAME]``).
    fixed : dict, optional
        Parameters held at other values than the case's {name: value or expression}.
    jobs : int, optional
        Local worker processes; None decides per stage from its first tasks whether a pool of
        the usable CPUs is faster than in-process (:mod:`mbseig.studies.runners`); 1 runs
        in-process.
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (or a client) to run on.
    progress : callable or tqdm, optional
        The progress bar (or a callback) the runners update.
    xtol_rel : float
        Boundary tolerance relative to the first axis' span.
    safety : float
        The factor on each eigenvalue's error bound in its tolerance (:func:`mbseig.modes`).
    stability_rtol : float
        The relative floor of each eigenvalue's tolerance (:func:`mbseig.modes`).
    continuation : bool
        Follow the branch along each line (default); False solves each point alone.
    curves : bool
        With two axes, follow each first-line boundary across the second axis.
    curve_values : sequence of float, optional
        The second axis' values the curves are followed at (default its grid values; more are
        inserted where a curve bends).
    diagram : str, optional
        The coordinate or named angle of the bifurcation diagram (default: the named angle,
        else the coordinate, that varies most along the branch).
    resume : str, pathlib.Path or Checkpoint, optional
        A directory (:mod:`mbseig.studies.resume`): every line, point, boundary search and curve
        is written there as it completes, and the ones it already holds are read instead of
        computed; the result equals that of an uninterrupted sweep bit for bit.  Interrupted
        (Ctrl-C), the sweep raises :class:`~mbseig.studies.runners.Interrupted` (a
        KeyboardInterrupt) saying how many grid points finished.
    lean : bool
        Build the case once per line and update only the force scalars the swept parameter
        enters (:func:`~mbseig.studies.continuation.family_maker`; the same numbers to
        rounding); False builds and resolves every value (the general path, for comparison).

    Returns
    -------
    SweepResult
        The points (modes, verdicts), the tracked modes, the stability boundaries with their
        crossing eigenvalues, folds and branch points, and the boundary curves.

    Examples
    --------
    >>> from mbseig.casefile.examples import damped_pendulum
    >>> res = run_sweep(damped_pendulum(), [("c", [0.0, 0.1, 0.2])], jobs=1)
    >>> [str(p.verdict) for p in res.points[0]]   # δ = c/(2m): 0 (within its bound), then > 0
    ['critical', 'stable', 'stable']
    """
    check("run_sweep", locals())
    spec = as_spec(case)
    case_arg, case = spec.source, spec
    fixed = dict(fixed or {})
    lines = _lines(axes, fixed)
    axis0, values0 = axes[0]
    values0 = np.asarray(values0, dtype=float)
    opts = {"safety": safety, "stability_rtol": stability_rtol}
    # build one point first so that a bad case or parameter fails fast with its own message
    first = spec.build(config, **{**fixed, **lines[0], axis0: float(values0[0])})
    span = abs(float(values0[-1] - values0[0]))
    xtol = xtol_rel * span
    n0 = len(values0)
    checkpoint = None
    if resume is not None:
        from .resume import Checkpoint, study_identity

        identity = study_identity(
            spec, config=config, axes=[(n, np.asarray(v, dtype=float)) for n, v in axes],
            fixed=fixed, xtol_rel=xtol_rel, safety=safety, stability_rtol=stability_rtol,
            continuation=bool(continuation), curves=bool(curves), curve_values=curve_values)
        checkpoint = (resume.bind(identity) if isinstance(resume, Checkpoint)
                      else Checkpoint(resume, identity))
    # Ctrl-C: the runner raises Interrupted (a KeyboardInterrupt) with the grid points held
    with Runner(jobs=jobs, scheduler=scheduler, progress=progress, checkpoint=checkpoint,
                points=len(lines) * n0) as runner:
        if continuation:
            share = uuid.uuid4().hex  # lines that differ only in damping share their statics
            try:
                points, branches, events, records = _followed_lines(
                    runner, case, config, fixed, lines, axis0, values0,
                    {**opts, "lean": bool(lean), "share": share})
            finally:
                release(share)
        else:
            calls = [((case, config, {**fixed, **line, axis0: float(v)}), opts)
                     for line in lines for v in values0]
            flat = runner.map(evaluate_point, calls, "points", points=1)
            points = [flat[li * n0:(li + 1) * n0] for li in range(len(lines))]
            branches, events, records = ([[] for _ in lines], [[] for _ in lines],
                                         [{} for _ in lines])
        tracks, tols, searches = [], [], []
        for li, line in enumerate(lines):
            S, T, _ = track_line(points[li])
            tracks.append(S)
            tols.append(T)
            searches += _crossing_searches(case, config, {**fixed, **line}, axis0, values0,
                                           points[li], S, T, events[li], li, xtol, opts)
        found = runner.map(locate_task, [(a, kw) for _, a, kw in searches], "boundaries")
        boundaries = _merge_conjugates(
            _crossings(searches, found, tracks, tols, lines, axis0, values0, xtol), xtol)
        folds, at_events = _event_records(events, lines, axis0, xtol)
        boundaries = sorted(boundaries + at_events, key=lambda b: (b["line"], b["value"]))
        curve_list = []
        if curves and len(axes) == 2 and continuation:
            curve_list = _curves(runner, case, config, fixed, axes, lines, boundaries, span, xtol,
                                 opts, curve_values)
    diag = _diagram(first, branches, diagram)
    return SweepResult(case=case_arg, config=config, fixed=fixed,
                       axes=[(n, np.asarray(v, dtype=float)) for n, v in axes], lines=lines,
                       points=points, tracks=tracks, tolerances_track=tols, boundaries=boundaries,
                       tolerances={"xtol": xtol, "xtol_rel": xtol_rel, "safety": safety,
                                   "stability_rtol": stability_rtol,
                                   "conjugate_penalty": CONJUGATE_PENALTY,
                                   "ambiguous_mac": AMBIGUOUS_MAC,
                                   "distance_weight": DISTANCE_WEIGHT,
                                   "continuation": bool(continuation)},
                       runner=runner.kind, branches=branches, events=events, folds=folds,
                       curves=curve_list, records=records, diagram=diag)


def _followed_lines(runner, case, config, fixed, lines, axis0, values0, opts):
    """Every line followed by continuation (:func:`sweep_line`): (points, branches, events,
    records) per line; a line whose first point fails is solved point by point instead."""
    results = runner.map(sweep_line, [((case, config, {**fixed, **line}, axis0, values0), opts)
                                      for line in lines], "lines", points=len(values0))
    opts = {k: v for k, v in opts.items() if k not in ("lean", "share")}
    points, branches, events, records = [], [], [], []
    for line, r in zip(lines, results, strict=True):
        if r.get("points") is None:  # the first point failed: every point on its own
            r = {"points": [evaluate_point(case, config, {**fixed, **line, axis0: float(v)},
                                           **opts) for v in values0],
                 "branch": [], "events": [], "record": {"continuation": r.get("error")}}
        points.append(r["points"])
        branches.append(r["branch"])
        events.append(r["events"])
        records.append(r["record"])
    return points, branches, events, records


def _crossing_searches(case, config, params, axis0, values0, points, S, T, events, li, xtol,
                       opts):
    """The boundary searches of line ``li``: every bracket where a tracked eigenvalue's
    δ + tol changes sign on one branch segment, away from folds, branch points and jumps."""
    H = -S.real + T
    event_ps = [e["p"] for e in events if e.get("type") in ("fold", "branch point", "jump")]
    searches = []
    # the brackets where δ + tol changes sign (in the order of the loop over tracks, then points)
    with np.errstate(invalid="ignore"):
        change = (~np.isnan(H[:-1]) & ~np.isnan(H[1:]) & ((H[:-1] < 0) != (H[1:] < 0)))
    js, ks = (x.tolist() for x in np.nonzero(change.T))
    wanted = {(k, j) for j, k in zip(js, ks, strict=True)}
    shapes = track_shapes(points, S, only=wanted | {(k + 1, j) for k, j in wanted})
    for j, k in zip(js, ks, strict=True):
        a = H[k, j]
        pa, pb = points[k], points[k + 1]
        if pa.get("segment") != pb.get("segment"):
            continue  # a jump or a switch between them: no crossing on one branch
        lo, hi = float(values0[k]), float(values0[k + 1])
        if any(min(lo, hi) <= p <= max(lo, hi) for p in event_ps):
            continue  # a fold or branch point: reported from the branch itself
        anchors = [(lo, pa["q"]), (hi, pb["q"])]
        refs = [(complex(S[k, j]), shapes[(k, j)]), (complex(S[k + 1, j]), shapes[(k + 1, j)])]
        stable_end = "lo" if a >= 0 else "hi"
        searches.append(((li, j, k), (case, config, params, axis0, lo, hi,
                                     anchors, refs[0], refs[1], xtol, stable_end), opts))
    return searches


def _crossings(searches, found, tracks, tols, lines, axis0, values0, xtol):
    """The located crossings as :class:`Boundary` records (loss or recovery, flutter or
    divergence by the crossing eigenvalue)."""
    boundaries = []
    for ((li, j, k), _, _), res in zip(searches, found, strict=True):
        if res is None or "error" in res:
            continue
        S = tracks[li]
        onset = "loss" if -S[k, j].real + tols[li][k, j] >= 0 else "recovery"
        un = S[k + 1, j] if onset == "loss" else S[k, j]
        real = abs(un.imag) <= max(tols[li][k + 1 if onset == "loss" else k, j], 1e-12 * abs(un))
        boundaries.append(Boundary.crossing(
            line=li, fixed={n: float(v) for n, v in lines[li].items()}, parameter=axis0,
            track=int(j), bracket=[float(values0[k]), float(values0[k + 1])],
            kind="divergence" if real else "flutter", stability=onset, xtol=xtol,
            found=res))
    return boundaries


def _event_records(events, lines, axis0, xtol):
    """(folds, boundaries): every located fold and branch point of the followed branches, and
    a divergence boundary where one changes the stability."""
    folds, boundaries = [], []
    for li, evs in enumerate(events):
        for e in evs:
            if e.get("type") not in ("fold", "branch point") or e.get("located") is False:
                continue
            rec = Fold(line=li, fixed={n: float(v) for n, v in lines[li].items()},
                       parameter=axis0, value=float(e["p"]), type=e["type"],
                       branch=("turns " + e["turns"]) if e.get("turns") else
                              ("switched to the stable branch" if e.get("switched") else
                               "continues"),
                       before=e.get("before"), after=e.get("after"), dof=e.get("dof"),
                       angles=e.get("angles"))
            folds.append(rec)
            if not e.get("dof"):
                continue
            before, after = e.get("before"), e.get("after")
            if e["type"] == "fold" and before == after:
                continue
            onset = "recovery" if before == "unstable" and after != "unstable" else "loss"
            boundaries.append(Boundary.at_event(rec, stability=onset, xtol=xtol))
    return folds, boundaries


def _curves(runner, case, config, fixed, axes, lines, boundaries, span, xtol, opts, values2):
    """Follow every crossing boundary of the first line across the second axis."""
    axis0 = axes[0][0]
    axis2 = axes[1][0]
    first = float(axes[1][1][0])
    values2 = [float(v) for v in (axes[1][1] if values2 is None else values2)]
    values2 = [first] + [v for v in values2 if v != first]
    starts = [b for b in boundaries if b["line"] == 0 and b.get("event") == "crossing"
              and b.get("shape") is not None]
    if not starts or len(values2) < 2:
        return []
    calls = [((case, config, {**fixed, **{k: v for k, v in lines[0].items() if k != axis2}},
               axis0, axis2, values2, b, span, xtol), opts) for b in starts]
    found = runner.map(curve_task, calls, "curves")
    out = []
    for b, pts in zip(starts, found, strict=True):
        out.append(BoundaryCurve(parameter=axis0, along=axis2, stability=b["stability"],
                                 kind=b["kind"], start=b["value"], points=pts, bend=BEND,
                                 max_insert=MAX_INSERT, xtol=xtol))
    return out


def _merge_conjugates(boundaries, xtol):
    """One boundary per event: a complex pair crosses with both of its tracks."""
    out = []
    for b in sorted(boundaries,
                    key=lambda b: (b["line"], b["value"], -b["eigenvalue"][1], b["track"])):
        dup = any(o["line"] == b["line"] and abs(o["value"] - b["value"]) <= 10 * xtol
                  and abs(o["eigenvalue"][0] - b["eigenvalue"][0])
                  <= 1e-6 * (1 + abs(o["eigenvalue"][0]))
                  and abs(o["eigenvalue"][1] + b["eigenvalue"][1])
                  <= 1e-6 * (1 + abs(o["eigenvalue"][1]))
                  and b["eigenvalue"][1] != 0 for o in out)
        if not dup:
            out.append(b)
    return out


def _diagram(model, branches, name):
    """The variable of the bifurcation diagram, its value at every branch point (in place);
    ``model``: the sweep's first point, built (names, kinds and the report's angles)."""
    pts = [b for br in branches for b in br]
    if not pts:
        return {}
    angles = sorted({a for b in pts for a in (b.get("angles") or {})})
    names = list(model.coordinate_names)
    if name is None:
        best, spread = None, -1.0
        for a in angles:
            v = [b["angles"][a] for b in pts if a in (b.get("angles") or {})]
            if v and max(v) - min(v) > spread:
                best, spread = a, max(v) - min(v)
        if best is None and pts[0].get("q") is not None:
            q = np.array([b["q"] for b in pts if b.get("q") is not None])
            best = names[int(np.argmax(np.ptp(q, axis=0)))]
        name = best
    if name is None:
        return {}
    extra = {}
    if name in angles:
        unit, get = "deg", (lambda b: (b.get("angles") or {}).get(name))
        rng = next((a["range_deg"] for a in model.report.get("angles", []) if a["name"] == name),
                   None)
        if rng is not None:
            extra["range"] = [float(rng[0]), float(rng[1])]
    elif name in names:
        i = names.index(name)
        unit = UNITS[model.coordinate_kinds[i]]
        def get(b):
            return None if b.get("q") is None else b["q"][i]
    else:
        raise CaseError(f"--diagram {name!r} is neither a named angle "
                        f"({', '.join(angles) or 'none'}) "
                        f"nor a coordinate of the model", element="--diagram")
    for br in branches:
        for b in br:
            b["value"] = get(b)
    return {"variable": name, "unit": unit, **extra}
