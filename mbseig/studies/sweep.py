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

import csv
import itertools
import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .. import plots
from ..errors import CaseError, MbseigError
from ..numerics import jsonable
from ..statics import equilibrium
from .boundaries import (
    AMBIGUOUS_MAC,
    BEND,
    CONJUGATE_PENALTY,
    DISTANCE_WEIGHT,
    MAX_INSERT,
    Evaluator,
    follow_boundary,
    locate,
    mac_matrix,
    match_cost,
)
from .continuation import modal_point, sweep_line
from .point import as_spec
from .records import Boundary, BoundaryCurve, Fold, SweepPoint
from .runners import Runner, progress_bar

__all__ = ["parse_range", "SweepResult", "run_sweep", "evaluate_point", "mac_matrix",
           "track_line", "write_outputs", "progress_bar"]


def parse_range(text: str):
    """``"k_a=1e3:1e4:10"`` → ("k_a", array of 10 values from 1e3 to 1e4 inclusive)."""
    name, sep, rng = text.partition("=")
    parts = rng.split(":")
    if not sep or not name.strip() or len(parts) != 3:
        raise CaseError(f"--param expects NAME=START:STOP:COUNT for a sweep, got {text!r}",
                        element="--param")
    try:
        start, stop = float(parts[0]), float(parts[1])
        count = int(parts[2])
    except ValueError:
        raise CaseError(f"START and STOP must be numbers and COUNT an integer in {text!r}",
                        element="--param") from None
    if count < 2 or not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise CaseError(f"a sweep needs COUNT ≥ 2 and START ≠ STOP (finite), got {text!r}",
                        element="--param")
    return name.strip(), np.linspace(start, stop, count)


# ---------------------------------------------------------------------------------------------
def evaluate_point(case, config, params, *, safety=10.0, stability_rtol=1e-12, q_init=None):
    """All eigenpairs at one parameter point, solved on its own (a pure, picklable function).

    case : a :class:`~mbseig.casefile.CaseSpec` (a model factory: the case is not read again).
    Returns the point dict of :func:`mbseig.studies.continuation.modal_point` (eigenvalues,
    unit shapes in full coordinates, per-eigenvalue tolerances, verdict, joints outside their
    range of motion, q), or {"params", "error"} with a one-line message.
    """
    try:
        model = case.build(config, **params)
        eq = equilibrium(model, q_init=q_init, offer_stable=False, self_stress="report")
        pt = modal_point(eq.model, eq, params, safety=safety, stability_rtol=stability_rtol)
        return replace(pt, statics="cold")
    except MbseigError as exc:
        return SweepPoint.failed(params, exc.one_line())


def _match_cost(ref_s, ref_shapes, s, shapes, scale):
    return match_cost(ref_s, ref_shapes, s, shapes, scale)


def track_line(points):
    """Track eigenvalues along a line of point results by MAC.

    Returns (S, T, shapes_last) with S[k, j] the eigenvalue of track j at point k (NaN where the
    track does not exist or the point failed) and T the matching tolerances.
    """
    from scipy.optimize import linear_sum_assignment

    n_pts = len(points)
    tracks_s, tracks_t = [], []  # per track: dict k → value
    ref = []  # per track: (s, shape) at its last point
    for k, pt in enumerate(points):
        if pt.get("error"):
            continue
        s, X, tol = pt["eigenvalues"], pt["shapes"], pt["tol"]
        if not ref:
            for j in range(s.size):
                tracks_s.append({k: s[j]})
                tracks_t.append({k: tol[j]})
                ref.append((s[j], X[:, j]))
            continue
        ref_s = np.array([r[0] for r in ref])
        ref_X = np.column_stack([r[1] for r in ref])
        scale = max(float(np.max(np.abs(ref_s), initial=0.0)),
                    float(np.max(np.abs(s), initial=0.0)), 1e-300)
        rows, cols = linear_sum_assignment(_match_cost(ref_s, ref_X, s, X, scale))
        matched = set()
        for r, c in zip(rows, cols):
            tracks_s[r][k] = s[c]
            tracks_t[r][k] = tol[c]
            ref[r] = (s[c], X[:, c])
            matched.add(int(c))
        for c in range(s.size):
            if c not in matched:
                tracks_s.append({k: s[c]})
                tracks_t.append({k: tol[c]})
                ref.append((s[c], X[:, c]))
    S = np.full((n_pts, len(tracks_s)), np.nan + 1j * np.nan)
    T = np.full((n_pts, len(tracks_s)), np.nan)
    for j, (ts, tt) in enumerate(zip(tracks_s, tracks_t)):
        for k, v in ts.items():
            S[k, j] = v
            T[k, j] = tt[k]
    return S, T, ref


def _track_shapes(points, S):
    """Shape of each track at each point (for boundary location), None where absent."""
    out = {}
    for k, pt in enumerate(points):
        if pt.get("error"):
            continue
        for j in range(S.shape[1]):
            if np.isnan(S[k, j]):
                continue
            c = int(np.flatnonzero(pt["eigenvalues"] == S[k, j])[0])
            out[(k, j)] = pt["shapes"][:, c]
    return out


def locate_task(case, config, params, axis, lo, hi, anchors, ref_lo, ref_hi, xtol, stable_end,
                *, safety=10.0, stability_rtol=1e-12):
    """One boundary search (a pure function for the runners): :func:`boundaries.locate`."""
    ev = Evaluator(case, config, params, axis, anchors, safety=safety,
                   stability_rtol=stability_rtol)
    try:
        return locate(ev, lo, hi, ref_lo, ref_hi, xtol, stable_end)
    except (MbseigError, ValueError) as exc:
        msg = exc.one_line() if isinstance(exc, MbseigError) else str(exc)
        return {"error": msg}


def curve_task(case, config, fixed, axis, axis2, values2, start, span, xtol, *, safety=10.0,
               stability_rtol=1e-12):
    """One two-parameter boundary curve (a pure function for the runners)."""
    return follow_boundary(case, config, fixed, axis, axis2, values2, start, span=span,
                           xtol=xtol, safety=safety, stability_rtol=stability_rtol)


# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SweepResult:
    """A sweep: grid, per-point results, tracked eigenvalues per line, stability boundaries, and
    the followed branches (continuation), folds and two-parameter boundary curves.

    ``tracks[l]`` is (n_points × n_tracks) complex for line l (the first axis varying, the other
    axes fixed at ``lines[l]``); ``boundaries`` lists every loss or recovery of stability;
    ``branches[l]`` the branch points of line l for the bifurcation diagram; ``folds`` every
    fold located on a branch; ``curves`` the boundaries followed across the second axis.
    """

    case: str
    config: str | None
    fixed: dict
    axes: list  # [(name, values), ...]
    lines: list  # per line: dict of the other axes' values
    points: list  # per line: list of point dicts
    tracks: list
    tolerances_track: list
    boundaries: list
    tolerances: dict = field(default_factory=dict)
    runner: str = "serial"
    branches: list = field(default_factory=list)
    events: list = field(default_factory=list)
    folds: list = field(default_factory=list)
    curves: list = field(default_factory=list)
    records: list = field(default_factory=list)
    diagram: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)  # parameter → unit, for the plots' axis labels

    @property
    def axis(self):
        return self.axes[0][0]

    @property
    def values(self):
        return self.axes[0][1]

    def abscissa_grid(self):
        """Spectral abscissa max Re s on the grid, shape (len(axis 0), len(lines))."""
        out = np.full((len(self.values), len(self.lines)), np.nan)
        for l, line in enumerate(self.points):
            for k, pt in enumerate(line):
                if not pt.get("error") and pt["eigenvalues"].size:
                    out[k, l] = float(np.max(pt["eigenvalues"].real))
        return out

    @staticmethod
    def listed_tracks(S):
        """Tracks to list: drop the mirror image (Im < 0 on average) of a complex-pair track."""
        keep = []
        for j in range(S.shape[1]):
            col = S[:, j]
            im = col.imag[~np.isnan(col)]
            if im.size and np.mean(im) < 0 and np.any(np.abs(im) > 0):
                continue
            keep.append(j)
        return keep

    def mode_numbers(self, line=0) -> dict:
        """Track → mode number along ``line``, numbered as the mode tables (``mbseig modes``)
        at the line's first point where the track exists: listed tracks sorted by ω_n = |s|,
        then by δ; tracks that appear later are numbered after them in order of appearance.
        Every plot and table of the sweep uses these numbers."""
        S = self.tracks[line]
        listed = self.listed_tracks(S)
        first = {}
        for j in listed:
            ok = np.flatnonzero(~np.isnan(S[:, j]))
            if ok.size:
                first[j] = int(ok[0])
        k0 = min(first.values(), default=0)
        at_start = sorted((j for j in first if first[j] == k0),
                          key=lambda j: (abs(S[k0, j]), -S[k0, j].real, j))
        later = sorted((j for j in first if first[j] != k0), key=lambda j: (first[j], abs(S[first[j], j]), j))
        return {j: i + 1 for i, j in enumerate(at_start + later)}

    def to_dataframe(self):
        """The tracked eigenvalues as a long pandas DataFrame, one row per (line, point, mode):
        the other axes' values, the swept parameter, ``mode`` (:meth:`mode_numbers`), ``track``,
        ``re``, ``im``, ``delta`` [1/s], ``omega_n`` [rad/s], ``omega_d`` [rad/s], ``fn_hz``
        (ω_n/2π), ``fd_hz`` (ω_d/2π), ``zeta``, ``stable`` (δ + tol ≥ 0), the point's
        ``verdict`` and ``out_of_range``.  pandas is optional: it is imported here."""
        try:
            import pandas as pd
        except ImportError:
            raise MbseigError("SweepResult.to_dataframe needs pandas (pip install pandas)",
                              element="to_dataframe") from None
        others = [n for n, _ in self.axes[1:]]
        rows = []
        for l, line in enumerate(self.lines):
            S, T = self.tracks[l], self.tolerances_track[l]
            numbers = self.mode_numbers(l)
            for k, v in enumerate(self.values):
                pt = self.points[l][k]
                for j in self.listed_tracks(S):
                    s = S[k, j]
                    if np.isnan(s):
                        continue
                    wn = abs(s)
                    rows.append({**{n: float(line[n]) for n in others}, self.axis: float(v),
                                 "mode": numbers.get(j), "track": int(j), "re": float(s.real),
                                 "im": float(s.imag), "delta": float(-s.real),
                                 "omega_n": float(wn), "omega_d": float(abs(s.imag)),
                                 "fn_hz": float(wn / (2 * math.pi)),
                                 "fd_hz": float(abs(s.imag) / (2 * math.pi)),
                                 "zeta": float(-s.real / wn) if wn > 0 else 0.0,
                                 "stable": bool(-s.real + T[k, j] >= 0),
                                 "verdict": pt.get("verdict"),
                                 "out_of_range": ", ".join(pt.get("out_of_range") or [])})
        cols = others + [self.axis, "mode", "track", "re", "im", "delta", "omega_n", "omega_d",
                         "fn_hz", "fd_hz", "zeta", "stable", "verdict", "out_of_range"]
        return pd.DataFrame(rows, columns=cols)

    def __repr__(self) -> str:
        n_pts = sum(len(p) for p in self.points)
        failed = sum(1 for line in self.points for pt in line if pt.get("error"))
        axes = ", ".join(f"{n} {float(v[0]):g}…{float(v[-1]):g} ({len(v)})" for n, v in self.axes)
        losses = [b for b in self.boundaries if b["stability"] == "loss"]
        first = (f", first loss at {self.axis} = {min(b['value'] for b in losses):.6g}"
                 if losses else "")
        return (f"<SweepResult {Path(str(self.case)).stem}"
                + (f" [{self.config}]" if self.config else "")
                + f": {axes}; {n_pts} points ({failed} failed), {len(self.boundaries)} "
                  f"boundaries{first}, {len(self.folds)} folds, {len(self.curves)} curves; "
                  f"runner {self.runner}>")

    __str__ = __repr__

    def _repr_html_(self) -> str:
        import html

        return f"<pre>{html.escape(repr(self))}</pre>"

    def to_json(self) -> dict:
        lines = []
        for l, fixed in enumerate(self.lines):
            S = self.tracks[l]
            tracks = [{"track": int(j),
                       "eigenvalue": [[None, None] if np.isnan(v) else [float(v.real), float(v.imag)]
                                      for v in S[:, j]]}
                      for j in self.listed_tracks(S)]
            pts = [{"params": {k: float(v) for k, v in pt["params"].items()},
                    "verdict": pt.get("verdict"), "error": pt.get("error"),
                    "out_of_range": pt.get("out_of_range", []),
                    "statics": pt.get("statics"), "static": pt.get("static"),
                    "iterations": pt.get("iterations"), "segment": pt.get("segment")}
                   for pt in self.points[l]]
            branch = [{k: b[k] for k in ("p", "kind", "segment", "static", "verdict", "angles")}
                      | {"value": b.get("value")} for b in (self.branches[l] if self.branches else [])]
            lines.append({"fixed": {k: float(v) for k, v in fixed.items()}, "points": pts,
                          "tracks": tracks, "branch": branch,
                          "continuation": self.records[l] if self.records else None})
        bounds = [b.to_json() for b in self.boundaries]
        return jsonable({
            "case": self.case, "config": self.config,
            "fixed": {k: v for k, v in self.fixed.items()},
            "axes": [{"name": n, "values": [float(x) for x in v]} for n, v in self.axes],
            "lines": lines, "boundaries": bounds, "folds": [f.to_json() for f in self.folds],
            "curves": [c.to_json() for c in self.curves],
            "diagram": self.diagram, "tolerances": self.tolerances,
        })


def _lines(axes, fixed):
    names = [n for n, _ in axes]
    if len(set(names)) != len(names):
        raise CaseError("a parameter is swept twice", element="--param")
    for n in names:
        if n in fixed:
            raise CaseError(f"parameter {n!r} is both swept and fixed", element="--param")
    others = axes[1:]
    return [dict(zip([n for n, _ in others], combo))
            for combo in itertools.product(*[v for _, v in others])] or [{}]


def run_sweep(case, axes, *, config=None, fixed=None, jobs=None, scheduler=None, progress=None,
              xtol_rel=1e-10, safety=10.0, stability_rtol=1e-12, continuation=True,
              curves=True, curve_values=None, diagram=None) -> SweepResult:
    """Sweep ``case`` over ``axes`` = [(name, values), ...] (see the module docstring).

    case : a path (read and parsed once, here) or a :class:`~mbseig.casefile.CaseSpec`; the
        lines and boundary searches receive the parsed case, never the path.
    jobs : local worker processes (default: CPU count; 1 runs in-process).
    scheduler : a Dask scheduler address (or a ``distributed.Client``) to run on.
    xtol_rel : boundary tolerance relative to the first axis' span.
    continuation : follow the branch along each line (default); False solves each point alone.
    curves : with two axes, follow each first-line boundary across the second axis (at
        ``curve_values`` of it, default its grid values; more are inserted where it bends).
    diagram : the coordinate or named angle of the bifurcation diagram (default: the named angle,
        else the coordinate, that varies most along the branch).
    """
    spec = as_spec(case)
    case_arg, case = spec.source, spec
    fixed = dict(fixed or {})
    lines = _lines(axes, fixed)
    axis0, values0 = axes[0]
    values0 = np.asarray(values0, dtype=float)
    opts = {"safety": safety, "stability_rtol": stability_rtol}
    # build one point first so that a bad case or parameter fails fast with its own message
    spec.build(config, **{**fixed, **lines[0], axis0: float(values0[0])})
    span = abs(float(values0[-1] - values0[0]))
    xtol = xtol_rel * span
    n0 = len(values0)
    with Runner(jobs=jobs, scheduler=scheduler, progress=progress) as runner:
        if continuation:
            results = runner.map(sweep_line, [((case, config, {**fixed, **line}, axis0, values0),
                                               opts) for line in lines], "lines")
            points, branches, events, records = [], [], [], []
            for line, r in zip(lines, results):
                if r.get("points") is None:  # the first point failed: every point on its own
                    r = {"points": [evaluate_point(case, config, {**fixed, **line, axis0: float(v)},
                                                   **opts) for v in values0],
                         "branch": [], "events": [], "record": {"continuation": r.get("error")}}
                points.append(r["points"])
                branches.append(r["branch"])
                events.append(r["events"])
                records.append(r["record"])
        else:
            calls = [((case, config, {**fixed, **line, axis0: float(v)}), opts)
                     for line in lines for v in values0]
            flat = runner.map(evaluate_point, calls, "points")
            points = [flat[l * n0:(l + 1) * n0] for l in range(len(lines))]
            branches, events, records = [[] for _ in lines], [[] for _ in lines], [{} for _ in lines]
        tracks, tols, searches = [], [], []
        for l, line in enumerate(lines):
            S, T, _ = track_line(points[l])
            tracks.append(S)
            tols.append(T)
            shapes = _track_shapes(points[l], S)
            H = -S.real + T
            event_ps = [e["p"] for e in events[l] if e.get("type") in ("fold", "branch point", "jump")]
            for j in range(S.shape[1]):
                for k in range(n0 - 1):
                    a, b = H[k, j], H[k + 1, j]
                    if np.isnan(a) or np.isnan(b) or (a < 0) == (b < 0):
                        continue
                    pa, pb = points[l][k], points[l][k + 1]
                    if pa.get("segment") != pb.get("segment"):
                        continue  # a jump or a switch between them: no crossing on one branch
                    lo, hi = float(values0[k]), float(values0[k + 1])
                    if any(min(lo, hi) <= p <= max(lo, hi) for p in event_ps):
                        continue  # a fold or branch point: reported from the branch itself
                    anchors = [(lo, pa["q"]), (hi, pb["q"])]
                    refs = [(complex(S[k, j]), shapes[(k, j)]), (complex(S[k + 1, j]), shapes[(k + 1, j)])]
                    stable_end = "lo" if a >= 0 else "hi"
                    searches.append(((l, j, k), (case, config, {**fixed, **line}, axis0, lo, hi,
                                                 anchors, refs[0], refs[1], xtol, stable_end), opts))
        found = runner.map(locate_task, [(a, kw) for _, a, kw in searches], "boundaries")
        boundaries = []
        for ((l, j, k), _, _), res in zip(searches, found):
            if res is None or "error" in res:
                continue
            S = tracks[l]
            onset = "loss" if -S[k, j].real + tols[l][k, j] >= 0 else "recovery"
            un = S[k + 1, j] if onset == "loss" else S[k, j]
            real = abs(un.imag) <= max(tols[l][k + 1 if onset == "loss" else k, j], 1e-12 * abs(un))
            boundaries.append(Boundary.crossing(
                line=l, fixed={n: float(v) for n, v in lines[l].items()}, parameter=axis0,
                track=int(j), bracket=[float(values0[k]), float(values0[k + 1])],
                kind="divergence" if real else "flutter", stability=onset, xtol=xtol,
                found=res))
        boundaries = _merge_conjugates(boundaries, xtol)
        folds = []
        for l, evs in enumerate(events):
            for e in evs:
                if e.get("type") not in ("fold", "branch point") or e.get("located") is False:
                    continue
                rec = Fold(line=l, fixed={n: float(v) for n, v in lines[l].items()},
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
        boundaries.sort(key=lambda b: (b["line"], b["value"]))
        curve_list = []
        if curves and len(axes) == 2 and continuation:
            curve_list = _curves(runner, case, config, fixed, axes, lines, boundaries, span, xtol,
                                 opts, curve_values)
    diag = _diagram(case, config, fixed, lines, axis0, values0, branches, diagram)
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
    for b, pts in zip(starts, found):
        out.append(BoundaryCurve(parameter=axis0, along=axis2, stability=b["stability"],
                                 kind=b["kind"], start=b["value"], points=pts, bend=BEND,
                                 max_insert=MAX_INSERT, xtol=xtol))
    return out


def _merge_conjugates(boundaries, xtol):
    """One boundary per event: a complex pair crosses with both of its tracks."""
    out = []
    for b in sorted(boundaries, key=lambda b: (b["line"], b["value"], -b["eigenvalue"][1], b["track"])):
        dup = any(o["line"] == b["line"] and abs(o["value"] - b["value"]) <= 10 * xtol
                  and abs(o["eigenvalue"][0] - b["eigenvalue"][0]) <= 1e-6 * (1 + abs(o["eigenvalue"][0]))
                  and abs(o["eigenvalue"][1] + b["eigenvalue"][1]) <= 1e-6 * (1 + abs(o["eigenvalue"][1]))
                  and b["eigenvalue"][1] != 0 for o in out)
        if not dup:
            out.append(b)
    return out


def _diagram(case, config, fixed, lines, axis0, values0, branches, name):
    """The variable of the bifurcation diagram, its value at every branch point (in place)."""
    pts = [b for br in branches for b in br]
    if not pts:
        return {}
    angles = sorted({a for b in pts for a in (b.get("angles") or {})})
    model = case.build(config, **{**fixed, **lines[0], axis0: float(values0[0])})
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
        unit = "m" if name.rpartition(".")[2] in ("x", "y", "z") else "rad"
        get = (lambda b: None if b.get("q") is None else b["q"][i])
    else:
        raise CaseError(f"--diagram {name!r} is neither a named angle ({', '.join(angles) or 'none'}) "
                        f"nor a coordinate of the model", element="--diagram")
    for br in branches:
        for b in br:
            b["value"] = get(b)
    return {"variable": name, "unit": unit, **extra}


# ---------------------------------------------------------------------------------------------
def write_outputs(res: SweepResult, out_dir, *, units=None) -> list[Path]:
    """sweep.json, tracks.csv, boundaries.csv, root_locus.png, modes_vs_parameter.png,
    bifurcation.png (and branch.csv) when branches were followed, and, for two swept
    parameters, stability_map.png, with curves.csv and stability_chart.png when boundaries were
    followed across the second.  ``units`` ({parameter: unit}) labels the plots' axes.
    Returns the written paths."""
    if units:
        import dataclasses

        res = dataclasses.replace(res, units={**res.units, **units})
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    p = out / "sweep.json"
    p.write_text(json.dumps(res.to_json(), indent=1, allow_nan=False) + "\n")
    paths.append(p)
    others = [n for n, _ in res.axes[1:]]
    p = out / "tracks.csv"
    with p.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(others + [res.axis, "track", "re", "im", "delta", "omega_n", "freq_hz", "zeta",
                             "mode"])
        for l, line in enumerate(res.lines):
            S = res.tracks[l]
            numbers = res.mode_numbers(l)
            for j in res.listed_tracks(S):
                for k, v in enumerate(res.values):
                    s = S[k, j]
                    if np.isnan(s):
                        continue
                    wn = abs(s)
                    w.writerow([repr(float(line[n])) for n in others] + [
                        repr(float(v)), j, repr(float(s.real)), repr(float(s.imag)),
                        repr(float(-s.real)), repr(float(wn)), repr(float(abs(s.imag) / (2 * math.pi))),
                        repr(float(-s.real / wn)) if wn > 0 else "0.0", numbers.get(j, "")])
    paths.append(p)
    p = out / "boundaries.csv"
    with p.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(others + ["parameter", "value", "track", "re", "im", "kind", "stability", "xtol",
                             "event", "band_lo", "band_hi", "method"])
        for b in res.boundaries:
            w.writerow([repr(b["fixed"][n]) for n in others] + [
                b["parameter"], repr(b["value"]), "" if b["track"] is None else b["track"],
                repr(b["eigenvalue"][0]), repr(b["eigenvalue"][1]), b["kind"], b["stability"],
                repr(b["xtol"]), b.get("event", ""), repr(b["band"][0]), repr(b["band"][1]),
                b.get("method", "")])
    paths.append(p)
    paths.append(plots.save(plots.root_locus(res), out / "root_locus.png"))
    paths.append(plots.save(plots.modes_vs_parameter(res), out / "modes_vs_parameter.png"))
    if res.diagram:
        p = out / "branch.csv"
        with p.open("w", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(others + [res.axis, res.diagram["variable"], "kind", "segment", "static",
                                 "verdict"])
            for l, line in enumerate(res.lines):
                for b in res.branches[l]:
                    w.writerow([repr(float(line[n])) for n in others] + [
                        repr(float(b["p"])), "" if b.get("value") is None else repr(float(b["value"])),
                        b["kind"], b["segment"], b.get("static") or "", b.get("verdict") or ""])
        paths.append(p)
        paths.append(plots.save(plots.bifurcation_diagram(res), out / "bifurcation.png"))
    if len(res.axes) == 2:
        paths.append(plots.save(plots.stability_map(res), out / "stability_map.png"))
        if res.curves:
            p = out / "curves.csv"
            with p.open("w", newline="") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(["curve", res.curves[0]["along"], res.axis, "stability", "test",
                            "band_lo", "band_hi"])
                for i, c in enumerate(res.curves):
                    for pt in c["points"]:
                        band = pt.get("band") or [None, None]
                        w.writerow([i, repr(pt["p2"]), "" if pt["value"] is None else repr(pt["value"]),
                                    c["stability"], pt.get("test") or "",
                                    "" if band[0] is None else repr(band[0]),
                                    "" if band[1] is None else repr(band[1])])
            paths.append(p)
            paths.append(plots.save(plots.stability_chart(res), out / "stability_chart.png"))
    return paths
