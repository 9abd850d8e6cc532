"""Stability boundaries: located where Re s = 0 of the crossing mode, with the tolerance band
reported beside them, and followed as a second parameter changes (docs/design.md,
"Equilibrium": boundaries).

Locating.  Between two grid points where a tracked eigenvalue changes stability, the boundary is
the root of a smooth test function of the crossing mode, found to ``xtol`` with Brent's
guarantee in rounds of values solved together (:func:`~mbseig.studies.roots.root_in_rounds`;
each round's equilibria re-solved from the bracket's own equilibria as a sweep line's grid points
are, so they stay on the branch, a value the batch declines solved on its own; the eigenvalue
matching the track picked by MAC):

- a transversal crossing (Hopf: a complex pair; or a damped real root): Re s = 0;
- a collision on the imaginary axis (undamped flutter onset, where two eigenvalues iω₁, iω₂
  merge and leave the axis as ±σ + iω, or an undamped divergence, where ±iω merge at 0):
  Re (s₁ − s₂)² = 0, s₂ the eigenvalue nearest s₁.  Re s itself is zero to rounding on the
  stable side there, and grows as √(p − p*) after it, so it has no usable sign change; the
  squared distance of the pair, −(ω₁ − ω₂)² before and 4σ² after, crosses zero linearly, and
  being a symmetric function of the pair it is well conditioned where each eigenvalue alone is
  not (a double eigenvalue).

The kind is chosen at the stable end of the bracket: collision when the crossing eigenvalue is
critical there (|Re s| within its tolerance), transversal otherwise.  The boundary sits at the
root, not where δ + tol = 0; the tolerance band beside it is the interval of the parameter where
the crossing mode is "critical" (|Re s| ≤ tol, tol of :func:`mbseig.modal.tolerances` at the
root): ±tol/|d Re s/dp| for a transversal crossing, [p*, p* + 4 tol²/|d(s₁ − s₂)²/dp|] for a
collision.

Following.  :func:`follow_boundary` continues a located boundary in a second parameter p₂: at
each next value the boundary's p₁ is predicted by the secant of the last two points, bracketed
by the test function's sign around the prediction (the bracket widened until it changes sign),
and located again; the reference eigenvalue and shape are updated from each root, and
intermediate values of p₂ are inserted where the curve bends (its p₁ moves by more than
``bend`` of the first axis' span between two points).
"""

from __future__ import annotations

import math
import threading

import numpy as np

from ..errors import MbseigError
from ..statics import equilibrium
from .continuation import family_maker, modal_point
from .roots import ROOT_POINTS, root_in_rounds

__all__ = ["Evaluator", "locate", "follow_boundary", "match"]

BEND = 0.05  # a curve point moving by more than this × the first axis' span gets a midpoint
MAX_INSERT = 2  # midpoints inserted per given value of the second parameter, at most
CONJUGATE_PENALTY = 2.0
DISTANCE_WEIGHT = 1e-3
AMBIGUOUS_MAC = 0.05
EPS = np.finfo(float).eps


def mac_matrix(A, B):
    """MAC between the columns of A and of B (complex), |aᴴb|²/((aᴴa)(bᴴb))."""
    num = np.abs(A.conj().T @ B) ** 2
    den = np.outer(np.sum(np.abs(A) ** 2, axis=0), np.sum(np.abs(B) ** 2, axis=0))
    return num / np.maximum(den, np.finfo(float).tiny)


def match_cost(ref_s, ref_shapes, s, shapes, scale):
    """1 − MAC, a penalty for jumping across the real axis, a tiny distance tie-break."""
    cost = 1.0 - mac_matrix(ref_shapes, shapes)
    real_tol = 1e-8 * np.maximum(np.abs(ref_s)[:, None], np.abs(s)[None, :]) + 1e-300
    crossing = ((ref_s.imag[:, None] * s.imag[None, :] < 0)
                & (np.abs(ref_s.imag)[:, None] > real_tol) & (np.abs(s.imag)[None, :] > real_tol))
    cost = cost + CONJUGATE_PENALTY * crossing
    return cost + DISTANCE_WEIGHT * np.abs(ref_s[:, None] - s[None, :]) / scale


def match(pt, ref_s, ref_shape):
    """Index of the eigenvalue of point ``pt`` matching (ref_s, ref_shape): the best MAC match;
    among those within AMBIGUOUS_MAC of it (the partners of a collision) the least stable."""
    s, X, tol = pt["eigenvalues"], pt["shapes"], pt["tol"]
    scale = max(abs(ref_s), float(np.max(np.abs(s), initial=0.0)), 1e-300)
    cost = match_cost(np.array([ref_s]), ref_shape[:, None], s, X, scale)[0]
    cand = np.flatnonzero(cost <= cost.min() + AMBIGUOUS_MAC)
    h = -s[cand].real + tol[cand]
    return int(cand[np.argmin(h)])


def _partner(s, c):
    """Index of the eigenvalue nearest s[c] (other than c)."""
    d = np.abs(s - s[c])
    d[c] = np.inf
    return int(np.argmin(d))


def test_value(kind, pt, c):
    """The test function of mode c at point pt (module docstring)."""
    s = pt["eigenvalues"]
    if kind == "collision":
        return float(((s[c] - s[_partner(s, c)]) ** 2).real)
    return float(s[c].real)


_MAKERS: dict = {}  # the last few lines' model makers of each thread (key → (case, make))
_MAKERS_KEPT = 4


def _maker(case, config, params, axis):
    """family_maker(case, config, params, axis)'s make, one per line in a process: the boundary
    searches of one line (and the curves' evaluators at one value of the second parameter)
    build the case and resolve its commands once, not once each (make(p) gives the models a
    build gives, whichever maker forms them)."""
    try:
        key = (threading.get_ident(), id(case), config, axis,  # (a maker is not thread-safe)
               tuple(sorted((k, float(v)) for k, v in params.items())))
    except (TypeError, ValueError):  # (a parameter that is not a number: not kept)
        return family_maker(case, config, params, axis)[0]
    hit = _MAKERS.get(key)
    if hit is not None and hit[0] is case:
        return hit[1]
    make = family_maker(case, config, params, axis)[0]
    _MAKERS[key] = (case, make)
    while len(_MAKERS) > _MAKERS_KEPT:
        _MAKERS.pop(next(iter(_MAKERS)))
    return make


class Evaluator:
    """Points of one line at any value of the axis, each equilibrium started from the nearest
    known equilibrium of the same branch (linear interpolation between two)."""

    def __init__(self, case, config, params, axis, anchors, *, safety=10.0, stability_rtol=1e-12):
        self.case, self.config, self.params, self.axis = case, config, dict(params), axis
        self.make = _maker(case, config, self.params, axis)
        self.anchors = sorted(anchors, key=lambda a: a[0])  # [(p, q), ...] on one branch
        self.opts = {"safety": safety, "stability_rtol": stability_rtol}
        self.calls = 0
        self.cache = {}

    def q_start(self, p):
        a = self.anchors
        if len(a) == 1:
            return a[0][1]
        for (p0, q0), (p1, q1) in zip(a, a[1:], strict=False):
            if p0 <= p <= p1:
                w = (p - p0) / (p1 - p0) if p1 != p0 else 0.0
                return (1 - w) * q0 + w * q1
        return a[0][1] if p < a[0][0] else a[-1][1]

    def many(self, ps):
        """The points at the values ``ps`` (as :meth:`__call__` gives them); those not known yet
        solved together where the batch takes them, as a sweep line's grid points are
        (:func:`~mbseig.studies.batch_line.batch_line` from the start at the first value, with its
        checks: every point reached again from its neighbour, no fold or branch point between
        them, none statically unstable; then the batched modes); any value the batch declines
        by :meth:`__call__`."""
        ps = [float(p) for p in ps]
        todo = sorted({p for p in ps if p not in self.cache})
        if len(todo) > 1:
            try:
                self._together(todo)
            except (MbseigError, np.linalg.LinAlgError, ValueError, FloatingPointError):
                pass  # (each value alone, below: its own result or error)
        return [self(p) for p in ps]

    def _together(self, values):
        from ..model import Model
        from ..statics.family import Family
        from .batch_line import batch_line
        from .continuation import _kept_postures, batched_points

        model0 = self.make(values[0])
        if not isinstance(model0, Model):  # (a linear case: matrices, no equilibrium branch)
            return
        q0 = self.q_start(values[0])
        fam = Family(self.make, abs(values[-1] - values[0]) or 1.0, model0, q0)
        eqs, lins, _ = batch_line(fam, values, _Start(q0))
        if eqs is None:
            return
        pts = batched_points(eqs, lins, values, lambda v: {**self.params, self.axis: float(v)},
                             self.opts, _kept_postures(), ["grid"] * len(values))
        for p, pt in zip(values, pts, strict=True):
            if not pt.get("error"):
                self.cache[p] = pt
                self.calls += 1

    def __call__(self, p):
        p = float(p)
        if p in self.cache:
            return self.cache[p]
        self.calls += 1
        model = self.make(p)
        try:
            eq = equilibrium(model, q_init=self.q_start(p), offer_stable=False,
                             self_stress="report")
        except MbseigError as exc:
            raise MbseigError(f"boundary search at {self.axis} = {p!r}: {exc.message}",
                              element="sweep") from None
        pt = modal_point(eq.model, eq, {**self.params, self.axis: p}, **self.opts)
        self.cache[p] = pt
        return pt


class _Start:
    """The start of a batch of values (:func:`~mbseig.studies.batch_line.batch_line` reads its
    ``q``): the branch's equilibrium interpolated at the first value."""

    def __init__(self, q):
        self.q = q


def _kind_at(pt, c):
    s, tol = pt["eigenvalues"][c], pt["tol"][c]
    return "collision" if abs(s.real) <= tol else "transversal"


def locate(ev, lo, hi, ref_lo, ref_hi, xtol, stable_end):
    """The boundary between lo and hi (module docstring).

    ev : an :class:`Evaluator`; ref_lo, ref_hi : (s, shape) of the tracked eigenvalue at the
    bracket ends; stable_end : "lo" or "hi".  Returns the boundary fields: value, eigenvalue,
    method, band, tolerance, converged, function_calls."""
    p_st, p_un = (lo, hi) if stable_end == "lo" else (hi, lo)
    ref_st, ref_un = (ref_lo, ref_hi) if stable_end == "lo" else (ref_hi, ref_lo)
    ev.many([p_st, p_un])  # (the bracket's ends together)
    pt_st = ev(p_st)
    kind = _kind_at(pt_st, match(pt_st, *ref_st))
    ref = {"s": ref_un[0], "shape": ref_un[1]}

    def crossing(p, pt):
        r = (ref_st if abs(p - p_st) < abs(p - p_un) else ref_un)
        return test_value(kind, pt, match(pt, r[0], r[1]))

    def margin(p, pt):  # (the old δ + tol root, where the test function does not change sign)
        r = (ref_st if abs(p - p_st) < abs(p - p_un) else ref_un)
        c = match(pt, r[0], r[1])
        return float(-pt["eigenvalues"][c].real + pt["tol"][c])

    value = crossing
    f_st, f_un = crossing(p_st, pt_st), crossing(p_un, ev(p_un))
    method = ("Re (s₁ − s₂)² = 0 (collision on the imaginary axis)" if kind == "collision"
              else "Re s = 0 (transversal crossing)")
    if f_st * f_un > 0:  # no sign change of the test function: the old δ + tol root
        kind, method = "tolerance", "δ + tol = 0 (the test function did not change sign)"
        value = margin
        f_st, f_un = margin(p_st, pt_st), margin(p_un, ev(p_un))
        if f_st * f_un > 0:
            return None

    def f(p):
        return value(p, ev(p))

    def fs(ps):  # a round's values together (the batch), each by its own test
        return [value(p, pt) for p, pt in zip(ps, ev.many(ps), strict=True)]

    calls0 = ev.calls
    f_lo, f_hi = (f_st, f_un) if stable_end == "lo" else (f_un, f_st)
    a, b, fa, fb = (lo, hi, f_lo, f_hi) if lo <= hi else (hi, lo, f_hi, f_lo)
    try:
        root = root_in_rounds(fs, a, b, fa, fb, xtol, ROOT_POINTS)
    except ArithmeticError as exc:  # (every round at least halves the bracket: not expected)
        raise MbseigError(f"boundary search along {ev.axis}: {exc}", element="sweep") from None
    pt = ev(root)
    c = match(pt, ref["s"], ref["shape"])
    s = complex(pt["eigenvalues"][c])
    tol = float(pt["tol"][c])
    # slope of the test function at the root, for the band (a central difference)
    h = max(1e3 * xtol, 1e-7 * abs(hi - lo))
    right, left = min(root + h, max(lo, hi)), max(root - h, min(lo, hi))
    try:
        ev.many([left, right])
        slope = (f(right) - f(left)) / (right - left)
    except MbseigError:
        slope = math.nan
    if kind == "collision":
        width = 4.0 * tol**2 / abs(slope) if slope else math.inf
        band = sorted([root, root + math.copysign(width, p_un - p_st)])
    elif kind == "transversal":
        width = tol / abs(slope) if slope else math.inf
        band = [root - width, root + width]
    else:
        band = [root, root]
    return {"value": float(root), "eigenvalue": [s.real, s.imag], "method": method,
            "test": kind, "band": [float(band[0]), float(band[1])], "tolerance": tol,
            "converged": True, "function_calls": int(ev.calls - calls0),
            "shape": pt["shapes"][:, c], "q": pt["q"]}


def _sign_at(ev, p, ref, kind):
    pt = ev(p)
    c = match(pt, *ref)
    return test_value(kind, pt, c), pt, c


def follow_boundary(case, config, fixed, axis, axis2, values2, start, *, span, xtol,
                    safety=10.0, stability_rtol=1e-12, bend=BEND, max_insert=MAX_INSERT):
    """Continue the boundary ``start`` (a located boundary of the line axis2 = values2[0]) over
    the values of ``axis2`` (module docstring).  Returns a list of curve points
    {axis2 value, value, eigenvalue, test, band} (None values where it was lost)."""
    ref = (complex(*start["eigenvalue"]), start["shape"])
    curve = [{"p2": float(values2[0]), "value": start["value"], "eigenvalue": start["eigenvalue"],
              "test": start.get("test"), "band": start.get("band")}]
    q_prev = start["q"]
    todo = [float(v) for v in values2[1:]]
    inserted = 0
    prev2 = [float(values2[0])]
    prev1 = [start["value"]]
    prev_test = [start.get("test")]
    while todo:
        p2 = todo[0]
        if len(prev2) >= 2 and prev2[-1] != prev2[-2]:
            slope = (prev1[-1] - prev1[-2]) / (prev2[-1] - prev2[-2])
            pred = prev1[-1] + slope * (p2 - prev2[-1])
        else:
            pred = prev1[-1]
        ev = Evaluator(case, config, {**fixed, axis2: p2}, axis, [(pred, q_prev)], safety=safety,
                       stability_rtol=stability_rtol)
        found = None
        try:
            kind = _kind_at(ev(pred), match(ev(pred), *ref))
            # the stable side is where the test function is negative (collision) or the crossing
            # eigenvalue's Re s is negative (transversal): bracket around the prediction
            delta = max(1e-3 * span, 10 * xtol)
            for _ in range(14):
                lo, hi = pred - delta, pred + delta
                flo, ptlo, clo = _sign_at(ev, lo, ref, kind)
                fhi, pthi, chi = _sign_at(ev, hi, ref, kind)
                if flo * fhi < 0:
                    stable_end = "lo" if flo < 0 else "hi"
                    ref_lo = (ptlo["eigenvalues"][clo], ptlo["shapes"][:, clo])
                    ref_hi = (pthi["eigenvalues"][chi], pthi["shapes"][:, chi])
                    found = locate(ev, lo, hi, ref_lo, ref_hi, xtol, stable_end)
                    break
                delta *= 2.0
        except MbseigError:
            found = None
        # a bend: refine between the two values, unless the test changes kind there (the
        # boundary of a damped system need not tend to the undamped one: Ziegler's paradox)
        if found is not None and abs(found["value"] - prev1[-1]) > bend * span \
                and found["test"] == prev_test[-1] and inserted < max_insert * len(values2):
            mid = 0.5 * (prev2[-1] + p2)
            if mid not in prev2 and abs(mid - prev2[-1]) > 1e-9 * abs(span):
                todo.insert(0, mid)
                inserted += 1
                continue
        todo.pop(0)
        if found is None:
            curve.append({"p2": p2, "value": None, "eigenvalue": None, "test": None, "band": None})
            continue
        curve.append({"p2": p2, "value": found["value"], "eigenvalue": found["eigenvalue"],
                      "test": found["test"], "band": found["band"]})
        ref = (complex(*found["eigenvalue"]), found["shape"])
        q_prev = found["q"]
        prev2.append(p2)
        prev1.append(found["value"])
        prev_test.append(found["test"])
    return sorted(curve, key=lambda c: c["p2"])
