"""A root of a function evaluated at several values a round (a sweep's batch evaluates a
round's values together, as it evaluates a line's points): Brent's guarantee, fewer rounds.

:func:`root_in_rounds` locates the stability boundaries of steady lines
(:mod:`mbseig.studies.steady_sweep`) and of lines at rest (:mod:`mbseig.studies.boundaries`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["root_in_rounds", "ROOT_POINTS", "RTOL"]

#: values evaluated together in a round
ROOT_POINTS = 8
RTOL = 4 * np.finfo(float).eps  # the relative part of a root's tolerance (brentq's smallest)


def root_in_rounds(fun, lo, hi, flo, fhi, xtol, many=1, rtol=RTOL, rounds=200,
                   known=()):
    """A root of the continuous function f on [lo, hi], f(lo) = flo and f(hi) = fhi of opposite
    signs, returned within xtol + rtol·|x| of a sign change of f (brentq's guarantee): a value
    where f was evaluated, at the end of a bracket [a, b] of f values of opposite signs whose
    width is at most that.  ``fun(ps)`` evaluates f at ``many`` values together each round:

    - the estimate x̂ is the inverse interpolation (x as a polynomial in f, at f = 0) through the
      four evaluated points nearest the bracket, its error the distance to that through three;
      with fewer than three points near it, or an estimate outside the bracket, the next points
      are spread evenly over it (regula falsi with one point a round);
    - the points of a round straddle x̂ at multiples of its error (never closer than a quarter of
      the tolerance), so a good estimate ends in a bracket as narrow as its error;
    - a round that does not halve the bracket makes the next one spread evenly (bisection with
      one point): the bracket shrinks every round, whatever f does.

    ``known``: (x, f(x)) pairs outside [lo, hi] that join the interpolation (never the
    bracket)."""
    a, b, fa, fb = float(lo), float(hi), float(flo), float(fhi)
    xs = [a, b, *(float(x) for x, _ in known)]
    fs = [fa, fb, *(float(f) for _, f in known)]
    slow = False
    for _ in range(rounds):
        if fa == 0.0:
            return a
        if fb == 0.0:
            return b
        tol = xtol + rtol * max(abs(a), abs(b))
        if b - a <= tol:
            return a if abs(fa) <= abs(fb) else b
        est, err = _estimate(xs, fs, a, b)
        if slow or est is None:
            if many == 1:
                est = 0.5 * (a + b) if slow else a - fa * (b - a) / (fb - fa)
                ps = [est]
            else:
                ps = list(a + (b - a) * np.arange(1, many + 1) / (many + 1))
        else:
            h = max(err, 0.25 * tol)
            offs = np.arange(many) - (many - 1) / 2.0 if many > 1 else np.zeros(1)
            ps = list(est + h * offs * (2.0 if many > 1 else 1.0))
        ps = sorted({min(max(p, a + 0.25 * tol), b - 0.25 * tol) for p in ps} - {a, b})
        if not ps:
            ps = [0.5 * (a + b)]
        vals = [float(v) for v in fun(ps)]
        xs += ps
        fs += vals
        width = b - a
        inner = sorted(zip([a, *ps, b], [fa, *vals, fb], strict=True))
        for (x0, f0), (x1, f1) in zip(inner, inner[1:], strict=False):
            if f1 == 0.0:
                a, b, fa, fb = x1, x1, f1, f1
                break
            if (f0 < 0) != (f1 < 0):
                a, b, fa, fb = x0, x1, f0, f1
                break
        slow = (b - a) > 0.5 * width
    raise ArithmeticError(f"no root within {rounds} rounds on [{lo}, {hi}]")


def _estimate(xs, fs, a, b):
    """(x̂, error) of :func:`root_in_rounds`: inverse interpolation through the four evaluated points
    nearest [a, b] (error: against three), or (None, None)."""
    mid = 0.5 * (a + b)
    pts = sorted(zip(xs, fs, strict=True), key=lambda t: abs(t[0] - mid))
    near = []
    for x, f in pts:
        if all(f != g for _, g in near):
            near.append((x, f))
        if len(near) == 4:
            break
    if len(near) < 3:
        return None, None

    def neville(pairs):  # x(f) at f = 0 through the pairs (f_i, x_i)
        f = [p[1] for p in pairs]
        x = [p[0] for p in pairs]
        for k in range(1, len(pairs)):
            x = [(f[i + k] * x[i] - f[i] * x[i + 1]) / (f[i + k] - f[i])
                 for i in range(len(x) - 1)]
        return x[0]

    hi_ = neville(near)
    lo_ = neville(near[:3])
    if not (np.isfinite(hi_) and a < hi_ < b):
        return None, None
    return hi_, abs(hi_ - lo_) if np.isfinite(lo_) else (b - a)
