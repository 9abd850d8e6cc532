"""Where the Floquet verdict changes along a parameter (flip, fold, secondary) and the stability
chart over two parameters (Ince–Strutt for a Mathieu-type system)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
from scipy.optimize import brentq

from .floquet import DEFAULT_RTOLS, floquet, monodromy

__all__ = ["Boundary", "verdict_changes", "StabilityChart", "stability_chart"]


# ---- verdict changes along a parameter ------------------------------------------------------
@dataclass(frozen=True)
class Boundary:
    """Where the verdict changes: ``value`` of the parameter, ``kind`` flip (μ → −1), fold
    (μ → +1) or secondary (a complex pair on |μ| = 1), ``stability`` loss / recovery (with the
    parameter increasing), the bracket it was located in, the method, and the tolerance."""

    value: float
    kind: str
    stability: str
    bracket: tuple
    method: str
    xtol: float
    verdicts: tuple


def _kind(result):
    mu = result.multipliers[int(np.argmax(np.abs(result.multipliers)))]
    scale = result.error_bounds[int(np.argmax(np.abs(result.multipliers)))]
    if abs(mu.imag) <= max(1e3 * scale, 1e-9 * abs(mu)):
        return "flip" if mu.real < 0 else "fold"
    return "secondary"


def _char_function(kind, build, *, method, rtol):
    def g(p):
        A, T = build(p)
        Phi = monodromy(A, T, method=method, rtol=rtol)
        Id = np.eye(Phi.shape[0])
        if kind == "flip":
            return float(np.linalg.det(Id + Phi))
        if kind == "fold":
            return float(np.linalg.det(Phi - Id))
        return float(np.max(np.abs(la.eigvals(Phi))) - 1.0)
    return g


def verdict_changes(build, values, *, rel_tol=1e-8, method="DOP853", rtols=DEFAULT_RTOLS,
                    results=None):
    """Where the Floquet verdict changes along a parameter, each located to ``rel_tol``.

    ``build(p)`` returns (A, T) (a callable A(t) and the period, or a LinearPeriodicSystem and
    None).  The verdict is evaluated on ``values`` (sorted); on each interval where it changes,
    the kind is read from the dominant multiplier on the less stable side and the root of a
    smooth characteristic function is found by Brent's method (scipy.optimize.brentq):
    det(I + Φ) for a flip, det(Φ − I) for a fold, max|μ| − 1 for a secondary change.  Where that
    function does not change sign in the bracket (a Krein collision of an undamped system, two
    crossings in one interval) the verdict itself is bisected instead, and said so.  A grid
    interval with two changes that cancel is not seen: refine ``values``.
    """
    values = np.sort(np.asarray(values, dtype=float))
    if results is None:
        results = [floquet(*build(p), method=method, rtols=rtols) for p in values]
    rank = {"stable": 0, "critical": 1, "unstable": 2}
    out = []
    for i in range(len(values) - 1):
        a, b = values[i], values[i + 1]
        ra, rb = results[i], results[i + 1]
        if ra.verdict == rb.verdict:
            continue
        worse = ra if rank[ra.verdict] > rank[rb.verdict] else rb
        kind = _kind(worse)
        xtol = rel_tol * max(abs(a), abs(b)) * 0.25
        g = _char_function(kind, build, method=method, rtol=rtols[1])
        ga, gb = g(a), g(b)
        if np.sign(ga) != np.sign(gb) and ga != 0 and gb != 0:
            root = brentq(g, a, b, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=200)
            how = {"flip": "Brent on det(I + Φ)", "fold": "Brent on det(Φ − I)",
                   "secondary": "Brent on max|μ| − 1"}[kind]
        else:
            lo, hi, vlo = a, b, ra.verdict
            while hi - lo > xtol:
                mid = 0.5 * (lo + hi)
                if floquet(*build(mid), method=method, rtols=rtols).verdict == vlo:
                    lo = mid
                else:
                    hi = mid
            root, how = 0.5 * (lo + hi), "bisection on the verdict"
        stability = "loss" if rank[rb.verdict] > rank[ra.verdict] else "recovery"
        out.append(Boundary(float(root), kind, stability, (float(a), float(b)), how, xtol,
                            (ra.verdict, rb.verdict)))
    return tuple(out)


# ---- stability chart ------------------------------------------------------------------------
@dataclass(frozen=True)
class StabilityChart:
    """Verdicts on a grid of two parameters (Ince–Strutt chart of a Mathieu-type system):
    ``verdicts[i, j]`` and ``spectral_radius[i, j]`` at (p1[i], p2[j])."""

    p1: np.ndarray
    p2: np.ndarray
    verdicts: np.ndarray
    spectral_radius: np.ndarray
    names: tuple = ("p1", "p2")


def stability_chart(build, p1, p2, *, names=("p1", "p2"), method="DOP853",
                    rtols=(1e-8, 1e-10)):
    """Floquet verdicts over the grid p1 × p2; ``build(p1, p2)`` returns (A, T)."""
    p1, p2 = np.asarray(p1, dtype=float), np.asarray(p2, dtype=float)
    verdicts = np.empty((p1.size, p2.size), dtype=object)
    rho = np.empty((p1.size, p2.size))
    for i, a in enumerate(p1):
        for j, b in enumerate(p2):
            res = floquet(*build(a, b), method=method, rtols=rtols)
            verdicts[i, j] = res.verdict
            rho[i, j] = res.spectral_radius
    return StabilityChart(p1, p2, verdicts, rho, tuple(names))
