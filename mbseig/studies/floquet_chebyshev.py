"""A(t) of a periodic system as Chebyshev interpolants, segment by segment.

Evaluating A(t) of a projected periodic system (:func:`~mbseig.studies.floquet_paths.
constrained_system`) costs O(n² r) (the null-space basis and its derivative, the reduced
matrices), while the integrator needs A at every stage of every step: hundreds of evaluations
per period.  A(t) is analytic on each segment of the null-space path, so its Chebyshev
interpolant converges geometrically.  On each segment [t0, t1], A is evaluated at the d + 1
Chebyshev points of the second kind x_j = cos(π j / d) (d = 12 first), its Chebyshev
coefficients c_k follow from a type-I discrete cosine transform, and the degree is doubled
(the old points are reused) until the last three coefficients are below ``rtol`` times the
largest entry of A on the segment (or, from degree 64 on, stop falling below 1e-11: the
rounding of A itself).  The coefficients beyond the last one above that level are
dropped.  The interpolant then costs one matrix–vector product over the coefficients per
evaluation, O(d n²), against O(n² r) for A itself.

The trace of A is not interpolated: Liouville's identity det Φ = exp ∫ tr A keeps its own
quadrature of the exact trace, so it also checks the interpolation.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.fft as sfft

from .floquet import FloquetError, LinearPeriodicSystem

__all__ = ["INTERPOLATION_RTOL", "ChebyshevSegment", "chebyshev_segment", "chebyshev_system"]

INTERPOLATION_RTOL = 1e-14  # relative to the largest entry of A on the segment
_NOISE = 1e-11  # a tail that stops falling below this from degree 64 on is rounding
_MAX_DEGREE = 512


class ChebyshevSegment:
    """A(t) on [t0, t1] from its Chebyshev coefficients (a callable of t)."""

    def __init__(self, t0, t1, coeffs, shape, tail):
        self.t0, self.t1 = float(t0), float(t1)
        self.coeffs = np.ascontiguousarray(coeffs)  # (d + 1, n·n)
        self.shape = shape
        self.tail = float(tail)  # relative size of the dropped / last coefficients

    @property
    def degree(self):
        return self.coeffs.shape[0] - 1

    def __call__(self, t):
        x = (2.0 * t - self.t0 - self.t1) / (self.t1 - self.t0)
        x = min(1.0, max(-1.0, x))
        d = self.coeffs.shape[0]
        T = np.empty(d)
        T[0] = 1.0
        if d > 1:
            T[1] = x
        for k in range(2, d):
            T[k] = 2.0 * x * T[k - 1] - T[k - 2]
        return (T @ self.coeffs).reshape(self.shape)


def _coefficients(values, d):
    """Chebyshev coefficients from values at x_j = cos(π j / d), j = 0 … d."""
    c = sfft.dct(values, type=1, axis=0) / d
    c[0] /= 2.0
    c[d] /= 2.0
    return c


def chebyshev_segment(A, t0, t1, *, rtol=INTERPOLATION_RTOL, degree=12,
                      max_degree=_MAX_DEGREE):
    """The :class:`ChebyshevSegment` of A on [t0, t1] (module docstring); ``values`` are
    evaluated once per point, the doubled grid reusing the previous one."""
    mid, half = 0.5 * (t0 + t1), 0.5 * (t1 - t0)
    d = int(degree)
    x = np.cos(math.pi * np.arange(d + 1) / d)
    vals = np.array([np.asarray(A(mid + half * xj), dtype=float) for xj in x])
    shape = vals.shape[1:]
    vals = vals.reshape(d + 1, -1)
    evaluations = d + 1
    last = math.inf
    while True:
        c = _coefficients(vals, d)
        scale = max(float(np.max(np.abs(vals), initial=0.0)), 1e-300)
        size = np.max(np.abs(c), axis=1) / scale
        tail = float(np.max(size[-3:]))
        if tail <= rtol or (d >= 64 and tail <= _NOISE and tail > 0.1 * last):
            big = np.nonzero(size > max(rtol, tail))[0]
            keep = int(big[-1]) + 2 if big.size else 1
            return ChebyshevSegment(t0, t1, c[:keep], shape, tail), evaluations
        if 2 * d > max_degree or not np.isfinite(tail):
            raise FloquetError(f"A(t) on [{t0:g}, {t1:g}] is not resolved by a Chebyshev "
                               f"interpolant of degree {d} (last coefficients {tail:.2g} of its "
                               "largest entry): is it smooth there?", element="monodromy")
        x2 = np.cos(math.pi * np.arange(1, 2 * d, 2) / (2 * d))  # the new (odd) points
        new = np.array([np.asarray(A(mid + half * xj), dtype=float).ravel() for xj in x2])
        evaluations += new.shape[0]
        both = np.empty((2 * d + 1, vals.shape[1]))
        both[0::2] = vals
        both[1::2] = new
        vals, d, last = both, 2 * d, tail


def chebyshev_system(system: LinearPeriodicSystem, *, rtol=INTERPOLATION_RTOL):
    """The system with every segment's A replaced by its Chebyshev interpolant (same segments,
    closing and exact trace).  Returns (system, record): the evaluations of A and the degree
    and tail of every segment."""
    segs, record = [], {"evaluations": 0, "degrees": [], "tails": []}
    for t0, t1, A in system.segments:
        seg, count = chebyshev_segment(A, t0, t1, rtol=rtol)
        segs.append((t0, t1, seg))
        record["evaluations"] += count
        record["degrees"].append(seg.degree)
        record["tails"].append(seg.tail)
    trace = system.trace
    if trace is None:  # the exact trace of the original segments, not of the interpolants
        def trace(t, _segs=system.segments):
            for _a, b, A in _segs:
                if t <= b:
                    return float(np.trace(A(t)))
            return float(np.trace(_segs[-1][2](t)))
    return LinearPeriodicSystem(tuple(segs), system.size, system.closing, trace), record
