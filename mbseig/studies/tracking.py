"""Points of a sweep solved on their own, and the eigenvalues tracked along a line by MAC (with
the conjugate and distance penalties of :mod:`mbseig.studies.boundaries`)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import CaseError, MbseigError
from ..statics import equilibrium
from .boundaries import (
    CONJUGATE_PENALTY,
    DISTANCE_WEIGHT,
    Evaluator,
    follow_boundary,
    locate,
    match_cost,
)
from .continuation import modal_point
from .records import SweepPoint


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

    fast = _track_whole(points, linear_sum_assignment)
    if fast is not None:
        return fast
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
        for r, c in zip(rows, cols, strict=True):
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
    for j, (ts, tt) in enumerate(zip(tracks_s, tracks_t, strict=True)):
        for k, v in ts.items():
            S[k, j] = v
            T[k, j] = tt[k]
    return S, T, ref


#: a consecutive pair is assigned by its row minima where each row's minimum beats the row's
#: other entries by this: any other assignment then costs at least this much more, far beyond
#: the rounding (≈ 1e-15) by which two ways of forming the cost differ, so the loop's assignment
#: is the same; a pair with a nearer entry takes the loop's own cost and assignment
MARGIN = 1e-8


def _stacked_costs(Sa, X):
    """The cost matrices of :func:`match_cost` of all consecutive pairs (P − 1, k, k), in the
    points' own order, formed at once (equal to the loop's to rounding)."""
    A, Bm = X[:-1], X[1:]
    num = np.abs(np.einsum("pni,pnj->pij", A.conj(), Bm)) ** 2
    na = np.einsum("pni,pni->pi", A.conj(), A).real
    nb = np.einsum("pnj,pnj->pj", Bm.conj(), Bm).real
    mac = num / np.maximum(na[:, :, None] * nb[:, None, :], np.finfo(float).tiny)
    rs, s = Sa[:-1], Sa[1:]
    real_tol = 1e-8 * np.maximum(np.abs(rs)[:, :, None], np.abs(s)[:, None, :]) + 1e-300
    crossing = ((rs.imag[:, :, None] * s.imag[:, None, :] < 0)
                & (np.abs(rs.imag)[:, :, None] > real_tol)
                & (np.abs(s.imag)[:, None, :] > real_tol))
    scale = np.maximum(np.maximum(np.abs(rs).max(axis=1), np.abs(s).max(axis=1)), 1e-300)
    return (1.0 - mac) + CONJUGATE_PENALTY * crossing \
        + DISTANCE_WEIGHT * np.abs(rs[:, :, None] - s[:, None, :]) / scale[:, None, None]


def _track_whole(points, assign):
    """:func:`track_line` for a line whose points all hold the same number of eigenvalues (no
    failed point): every track is matched at every point, so the reference of a point is the
    previous point in track order.  The cost matrices of all consecutive pairs are formed at
    once; a pair whose row minima are distinct columns, each ahead of its row by ``MARGIN``, is
    assigned by them (the unique optimum, whatever the rounding); any other pair takes the
    loop's own cost (:func:`match_cost` on the same arrays) and assignment.  None for any other
    line."""
    if not points or any(pt.get("error") for pt in points):
        return None
    S = [pt["eigenvalues"] for pt in points]
    k = S[0].size
    if k == 0 or any(s.size != k for s in S):
        return None
    X = [pt["shapes"] for pt in points]
    Sa = np.stack(S)  # (P, k)
    T = np.stack([pt["tol"] for pt in points])
    cost = _stacked_costs(Sa, np.stack(X)) if len(points) > 1 else np.zeros((0, k, k))
    part = np.partition(cost, 1, axis=2) if k > 1 else np.concatenate([cost, cost + 1], axis=2)
    best = np.argmin(cost, axis=2)  # (P − 1, k): per previous eigenvalue its nearest
    clear = (part[:, :, 1] - part[:, :, 0] >= MARGIN).all(axis=1)
    clear &= (np.sort(best, axis=1) == np.arange(k)).all(axis=1)  # the minima: a permutation
    order = np.arange(k)  # order[j]: the index of track j's eigenvalue at the current point
    idx = np.empty((len(points), k), int)
    idx[0] = order
    for p in range(1, len(points)):
        if clear[p - 1]:
            order = best[p - 1][order]
        else:
            ref_s, ref_X = Sa[p - 1][order], X[p - 1][:, order]  # (as the loop's column_stack)
            s = Sa[p]
            scale = max(float(np.max(np.abs(ref_s), initial=0.0)),
                        float(np.max(np.abs(s), initial=0.0)), 1e-300)
            rows, cols = assign(_match_cost(ref_s, ref_X, s, X[p], scale))
            nxt = np.empty(k, int)
            nxt[rows] = cols
            order = nxt
        idx[p] = order
    S_tr = np.take_along_axis(Sa, idx, axis=1)
    T_tr = np.take_along_axis(T, idx, axis=1)
    ref = [(S_tr[-1, j], X[-1][:, idx[-1, j]]) for j in range(k)]
    return S_tr, T_tr, ref


def track_shapes(points, S, only=None):
    """Shape of each track at each point (for boundary location), None where absent; ``only``:
    the (point, track) pairs wanted (default all)."""
    out = {}
    pts = range(len(points)) if only is None else sorted({k for k, _ in only})
    for k in pts:
        pt = points[k]
        if pt.get("error"):
            continue
        s, X = pt["eigenvalues"], pt["shapes"]  # read once: a record's lookup is not free
        for j in np.flatnonzero(~np.isnan(S[k])):
            if only is not None and (k, int(j)) not in only:
                continue
            c = int(np.flatnonzero(s == S[k, j])[0])
            out[(k, int(j))] = X[:, c]
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
