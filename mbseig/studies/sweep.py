"""Parameter sweeps: modes at every point, mode tracking by MAC, stability boundaries.

For parameter values p on a grid (the Cartesian product of the ``axes``; tracking and boundaries
run along the first axis, one line per combination of the others), every point is an independent
pure computation (:func:`evaluate_point`: load → equilibrium → linearize → all 2n eigenpairs), so
it runs the same in-process, on local processes or on a Dask cluster.

Tracking.  Consecutive points are matched by the modal assurance criterion of the mode shapes in
full coordinates (q = N x, independent of the null-space basis):

    MAC(a, b) = |aᴴ b|² / ((aᴴ a)(bᴴ b))

A complex pair has conjugate shapes (MAC ≈ 1 between them when lightly damped), so a match that
would jump across the real axis costs ``CONJUGATE_PENALTY``; a tiny eigenvalue-distance term
(``DISTANCE_WEIGHT`` · |Δs| / scale) only breaks exact ties.  The assignment is a linear sum
assignment on cost = 1 − MAC + penalties (scipy.optimize.linear_sum_assignment).  Sort order is
never used.

Boundaries.  A tracked eigenvalue is unstable where h = δ + tol < 0, with δ = −Re s and tol the
per-eigenvalue stability tolerance of :func:`mbseig.modal.tolerances`, the same that decides
``mbseig modes``.  Where h changes sign between two grid points, the crossing is located by Brent's method on
h(p) (each evaluation re-solves the model and picks the eigenvalue matching the track by MAC; where
several match within ``AMBIGUOUS_MAC``, as the partners of a collision do, the least stable one) to
``xtol = xtol_rel · |stop − start|``; conjugate duplicates are merged.  For a damped crossing the
root is δ = −tol, within tol/|dδ/dp| of δ = 0; for an undamped flutter onset (δ ≡ 0 before the
collision) it is the collision itself to O(tol²).
"""

from __future__ import annotations

import csv
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import plots
from ..eigen import solve_qep
from ..errors import CaseError, MbseigError
from ..linear import linearize
from ..modal import stability, tolerances, worst
from ..numerics import jsonable
from ..statics import equilibrium, solved
from ..statics.reactions import rom_flags
from .point import as_spec
from .runners import Runner, progress_bar

__all__ = ["parse_range", "SweepResult", "run_sweep", "evaluate_point", "mac_matrix",
           "track_line", "write_outputs", "progress_bar"]

CONJUGATE_PENALTY = 2.0
DISTANCE_WEIGHT = 1e-3
AMBIGUOUS_MAC = 0.05


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
def evaluate_point(case, config, params, *, safety=10.0, stability_rtol=1e-12):
    """All eigenpairs at one parameter point (a pure function, picklable for workers).

    case : a :class:`~mbseig.casefile.CaseSpec` (a model factory: the case is not read again).
    Returns a dict: eigenvalues (2n, complex), shapes (n_full × 2n, unit columns), tol (per
    eigenvalue: the δ tolerance of :func:`mbseig.modal.tolerances`), verdict (as ``mbseig
    modes`` gives it), out_of_range (joints outside their range of motion, from the case's
    [report] table), error (None or a one-line message).
    """
    try:
        model = case.build(config, **params)
        eq = equilibrium(model)
        lin = linearize(model, eq)
        sol = solve_qep(lin.M, lin.P, lin.Q)
    except MbseigError as exc:
        return {"params": dict(params), "error": exc.one_line()}
    s = sol.eigenvalues
    _, _, tol, rigid = tolerances(sol, safety=safety, stability_rtol=stability_rtol)
    X = lin.N @ sol.vectors
    X = X / np.maximum(np.linalg.norm(X, axis=0), np.finfo(float).tiny)
    verdict = worst(stability(-s.real, tol, rigid))
    model = solved(model, eq)
    out_of_range = rom_flags(model, eq.q) if getattr(model, "report", {}).get("angles") else []
    return {"params": dict(params), "error": None, "eigenvalues": s, "shapes": X, "tol": tol,
            "verdict": verdict, "out_of_range": out_of_range, "solver": sol.solver}


def mac_matrix(A, B):
    """MAC between the columns of A and of B (complex), |aᴴb|²/((aᴴa)(bᴴb))."""
    num = np.abs(A.conj().T @ B) ** 2
    den = np.outer(np.sum(np.abs(A) ** 2, axis=0), np.sum(np.abs(B) ** 2, axis=0))
    return num / np.maximum(den, np.finfo(float).tiny)


def _match_cost(ref_s, ref_shapes, s, shapes, scale):
    cost = 1.0 - mac_matrix(ref_shapes, shapes)
    real_tol = 1e-8 * np.maximum(np.abs(ref_s)[:, None], np.abs(s)[None, :]) + 1e-300
    crossing = ((ref_s.imag[:, None] * s.imag[None, :] < 0)
                & (np.abs(ref_s.imag)[:, None] > real_tol) & (np.abs(s.imag)[None, :] > real_tol))
    cost = cost + CONJUGATE_PENALTY * crossing
    return cost + DISTANCE_WEIGHT * np.abs(ref_s[:, None] - s[None, :]) / scale


def track_line(points):
    """Track eigenvalues along a line of point results by MAC.

    Returns (S, T, shapes_last) with S[k, j] the eigenvalue of track j at point k (NaN where the
    track does not exist or the point failed) and T the matching tolerances.
    """
    from scipy.optimize import linear_sum_assignment

    n_pts = len(points)
    tracks_s, tracks_t = [], []  # per track: list of (k, s, tol)
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
        scale = max(float(np.max(np.abs(ref_s), initial=0.0)), float(np.max(np.abs(s), initial=0.0)), 1e-300)
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
    """Shape of each track at each point (for boundary refinement), None where absent."""
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


def boundary_residual(case, config, params, axis, p, ref_s, ref_shape, *, safety=10.0,
                      stability_rtol=1e-12):
    """(h, s) at axis = p for the eigenvalue matching (ref_s, ref_shape): h = δ + tol."""
    pt = evaluate_point(case, config, {**params, axis: p}, safety=safety,
                        stability_rtol=stability_rtol)
    if pt.get("error"):
        raise MbseigError(f"boundary search at {axis} = {p!r}: {pt['error']}", element="sweep")
    s, X, tol = pt["eigenvalues"], pt["shapes"], pt["tol"]
    scale = max(abs(ref_s), float(np.max(np.abs(s))), 1e-300)
    cost = _match_cost(np.array([ref_s]), ref_shape[:, None], s, X, scale)[0]
    # near a collision (flutter onset) the two partners have nearly equal shapes: among the
    # eigenvalues matching within AMBIGUOUS_MAC, the least stable one decides
    cand = np.flatnonzero(cost <= cost.min() + AMBIGUOUS_MAC)
    h = -s[cand].real + tol[cand]
    c = int(cand[np.argmin(h)])
    return float(-s[c].real + tol[c]), complex(s[c])


def locate_boundary(case, config, params, axis, lo, hi, ref_s, ref_shape, xtol, h_lo=None,
                    h_hi=None, *, safety=10.0, stability_rtol=1e-12):
    """Brent's method on h(p) = δ + tol of the tracked eigenvalue in [lo, hi] (a pure function).

    h_lo, h_hi : the tracked values at the bracket ends (from the grid), so that the bracket's
    signs are those the tracker saw even where h is at the level of the tolerance.
    """
    from scipy.optimize import brentq

    def h(p):
        if p == lo and h_lo is not None:
            return h_lo
        if p == hi and h_hi is not None:
            return h_hi
        return boundary_residual(case, config, params, axis, p, ref_s, ref_shape, safety=safety,
                                 stability_rtol=stability_rtol)[0]

    root, info = brentq(h, lo, hi, xtol=xtol, full_output=True, disp=False)
    _, s = boundary_residual(case, config, params, axis, root, ref_s, ref_shape, safety=safety,
                             stability_rtol=stability_rtol)
    return {"value": float(root), "eigenvalue": [float(s.real), float(s.imag)],
            "converged": bool(info.converged), "function_calls": int(info.function_calls)}


# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SweepResult:
    """A sweep: grid, per-point results, tracked eigenvalues per line and stability boundaries.

    ``tracks[l]`` is (n_points × n_tracks) complex for line l (the first axis varying, the other
    axes fixed at ``lines[l]``); ``boundaries`` lists every crossing of the imaginary axis.
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
                if not pt.get("error"):
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

    def to_json(self) -> dict:
        lines = []
        for l, fixed in enumerate(self.lines):
            S = self.tracks[l]
            keep = self.listed_tracks(S)
            tracks = []
            for j in keep:
                col = S[:, j]
                tracks.append({
                    "track": int(j),
                    "eigenvalue": [[None, None] if np.isnan(v) else [float(v.real), float(v.imag)]
                                   for v in col],
                })
            pts = [{"params": {k: float(v) for k, v in pt["params"].items()},
                    "verdict": pt.get("verdict"), "error": pt.get("error"),
                    "out_of_range": pt.get("out_of_range", [])} for pt in self.points[l]]
            lines.append({"fixed": {k: float(v) for k, v in fixed.items()}, "points": pts,
                          "tracks": tracks})
        return jsonable({
            "case": self.case, "config": self.config,
            "fixed": {k: v for k, v in self.fixed.items()},
            "axes": [{"name": n, "values": [float(x) for x in v]} for n, v in self.axes],
            "lines": lines, "boundaries": self.boundaries, "tolerances": self.tolerances,
        })


def run_sweep(case, axes, *, config=None, fixed=None, jobs=None, scheduler=None, progress=None,
              xtol_rel=1e-10, safety=10.0, stability_rtol=1e-12) -> SweepResult:
    """Sweep ``case`` over ``axes`` = [(name, values), ...] (see the module docstring).

    case : a path (read and parsed once, here) or a :class:`~mbseig.casefile.CaseSpec`; the
        points and boundary searches receive the parsed case, never the path.
    jobs : local worker processes (default: CPU count; 1 runs in-process).
    scheduler : a Dask scheduler address (or a ``distributed.Client``) to run the points on.
    xtol_rel : boundary tolerance relative to the first axis' span.
    """
    spec = as_spec(case)
    case_arg, case = spec.source, spec
    fixed = dict(fixed or {})
    names = [n for n, _ in axes]
    if len(set(names)) != len(names):
        raise CaseError("a parameter is swept twice", element="--param")
    for n in names:
        if n in fixed:
            raise CaseError(f"parameter {n!r} is both swept and fixed", element="--param")
    axis0, values0 = axes[0]
    others = axes[1:]
    lines = [dict(zip([n for n, _ in others], combo))
             for combo in itertools.product(*[v for _, v in others])] or [{}]
    opts = {"safety": safety, "stability_rtol": stability_rtol}
    calls = [((case, config, {**fixed, **line, axis0: float(v)}), opts)
             for line in lines for v in values0]
    # build one point first so that a bad case or parameter fails fast with its own message
    spec.build(config, **calls[0][0][2])
    span = abs(float(values0[-1] - values0[0]))
    xtol = xtol_rel * span
    with Runner(jobs=jobs, scheduler=scheduler, progress=progress) as runner:
        flat = runner.map(evaluate_point, calls, "points")
        n0 = len(values0)
        points = [flat[l * n0:(l + 1) * n0] for l in range(len(lines))]
        tracks, tols, searches = [], [], []
        for l, line in enumerate(lines):
            S, T, _ = track_line(points[l])
            tracks.append(S)
            tols.append(T)
            shapes = _track_shapes(points[l], S)
            H = -S.real + T
            for j in range(S.shape[1]):
                for k in range(n0 - 1):
                    a, b = H[k, j], H[k + 1, j]
                    if np.isnan(a) or np.isnan(b) or (a < 0) == (b < 0):
                        continue
                    searches.append(((l, j, k), (case, config, {**fixed, **line}, axis0,
                                                 float(values0[k]), float(values0[k + 1]),
                                                 complex(S[k, j]), shapes[(k, j)], xtol,
                                                 float(a), float(b)), opts))
        found = runner.map(locate_boundary, [(a, kw) for _, a, kw in searches], "boundaries")
    boundaries = []
    for ((l, j, k), _, _), res in zip(searches, found):
        S = tracks[l]
        onset = "loss" if -S[k, j].real + tols[l][k, j] >= 0 else "recovery"
        s = complex(*res["eigenvalue"])
        boundaries.append({
            "line": l, "fixed": {n: float(v) for n, v in lines[l].items()},
            "parameter": axis0, "value": res["value"], "track": int(j),
            "bracket": [float(values0[k]), float(values0[k + 1])],
            "eigenvalue": res["eigenvalue"],
            "kind": "divergence" if abs(s.imag) <= 1e-8 * max(abs(s), 1e-300) else "flutter",
            "stability": onset, "converged": res["converged"],
            "function_calls": res["function_calls"], "xtol": xtol,
        })
    boundaries = _merge_conjugates(boundaries, xtol)
    return SweepResult(case=case_arg, config=config, fixed=fixed,
                       axes=[(n, np.asarray(v, dtype=float)) for n, v in axes], lines=lines,
                       points=points, tracks=tracks, tolerances_track=tols, boundaries=boundaries,
                       tolerances={"xtol": xtol, "xtol_rel": xtol_rel, "safety": safety,
                                   "stability_rtol": stability_rtol,
                                   "conjugate_penalty": CONJUGATE_PENALTY,
                                   "ambiguous_mac": AMBIGUOUS_MAC,
                                   "distance_weight": DISTANCE_WEIGHT},
                       runner=runner.kind)


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


# ---------------------------------------------------------------------------------------------
def write_outputs(res: SweepResult, out_dir) -> list[Path]:
    """sweep.json, tracks.csv, boundaries.csv, root_locus.png, modes_vs_parameter.png and, for
    two swept parameters, stability_map.png.  Returns the written paths."""
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
        w.writerow(others + [res.axis, "track", "re", "im", "delta", "omega_n", "freq_hz", "zeta"])
        for l, line in enumerate(res.lines):
            S = res.tracks[l]
            for j in res.listed_tracks(S):
                for k, v in enumerate(res.values):
                    s = S[k, j]
                    if np.isnan(s):
                        continue
                    wn = abs(s)
                    w.writerow([repr(float(line[n])) for n in others] + [
                        repr(float(v)), j, repr(float(s.real)), repr(float(s.imag)),
                        repr(float(-s.real)), repr(float(wn)), repr(float(abs(s.imag) / (2 * math.pi))),
                        repr(float(-s.real / wn)) if wn > 0 else "0.0"])
    paths.append(p)
    p = out / "boundaries.csv"
    with p.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(others + ["parameter", "value", "track", "re", "im", "kind", "stability", "xtol"])
        for b in res.boundaries:
            w.writerow([repr(b["fixed"][n]) for n in others] + [
                b["parameter"], repr(b["value"]), b["track"], repr(b["eigenvalue"][0]),
                repr(b["eigenvalue"][1]), b["kind"], b["stability"], repr(b["xtol"])])
    paths.append(p)
    paths.append(plots.save(plots.root_locus(res), out / "root_locus.png"))
    paths.append(plots.save(plots.modes_vs_parameter(res), out / "modes_vs_parameter.png"))
    if len(res.axes) == 2:
        paths.append(plots.save(plots.stability_map(res), out / "stability_map.png"))
    return paths
