"""The trigonometric interpolant of one period (:class:`TrigSeries`), with which
:mod:`mbseig.model.timed` and the periodic studies hold a T-periodic number or matrix as a
function of time, and :func:`in_range`, the check that its time derivatives stay doubles."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import CaseError
from ..numerics import DOUBLE_RANGE

__all__ = ["TrigSeries", "in_range", "DERIVATIVE_MAX"]


@dataclass(frozen=True)
class TrigSeries:
    """f(t) = s t / T + Σ_|k|<N/2 c_k exp(2πi k t / T) from N samples of one period (values of
    any shape stacked on the first axis): exact for trigonometric polynomials of degree below
    N/2, spectrally accurate for smooth periodic f; ``offset`` is the first sample's instant."""

    coeffs: np.ndarray  # rfft / N, shape (N//2 + 1, *value shape)
    samples: int
    period: float
    drift: np.ndarray | float = 0.0  # f(T) − f(0): whole turns of a driver angle, else 0

    @classmethod
    def fit(cls, values, period, *, offset=0.0, drift=0.0):
        values = np.asarray(values, dtype=float)
        N = values.shape[0]
        times = offset + np.arange(N) * period / N
        shape = (-1,) + (1,) * (values.ndim - 1)
        periodic = values - np.asarray(drift) * (times / period).reshape(shape)
        coeffs = np.fft.rfft(periodic, axis=0) / N
        if offset:
            k = np.arange(coeffs.shape[0])
            coeffs = coeffs * np.exp(-2j * math.pi * k * offset / period).reshape(shape)
        return cls(coeffs, N, float(period), drift)

    @functools.cached_property
    def _real(self):
        """(Re c, Im c) as (K, size), k and the weights: two matrix-vector products a value."""
        flat = self.coeffs.reshape(self.coeffs.shape[0], -1)
        k = np.arange(flat.shape[0])
        weight = np.full(k.size, 2.0)
        weight[0] = 1.0
        if self.samples % 2 == 0:
            weight[-1] = 1.0  # the Nyquist cosine; its derivatives are left out (ambiguous)
        return np.ascontiguousarray(flat.real), np.ascontiguousarray(flat.imag), k, weight

    def __call__(self, t, order=0):
        """The value (order 0) or its first / second time derivative at t."""
        re, im, k, weight = self._real
        w = 2.0 * math.pi / self.period
        z = weight * (1j * w * k) ** order * np.exp(1j * w * k * t)
        if order and self.samples % 2 == 0:
            z[-1] = 0.0
        value = z.real @ re - z.imag @ im
        slope = (t, 1.0, 0.0)[order] / self.period  # of the secular part s t / T
        return value.reshape(self.coeffs.shape[1:]) + np.asarray(self.drift) * slope


# the largest second time derivative a model holds: the integrators of the periodic motion
# divide the accelerations by their absolute tolerance, never below ε times the state's scale
# (≥ 1), and square the quotient in a norm, which must stay a double: ε √(max double) = 3e138
DERIVATIVE_MAX = float(np.finfo(float).eps) * math.sqrt(np.finfo(float).max)


def in_range(series, name):
    """``series``, or a one-line refusal naming the element when the bound of its second time
    derivative Σ_k w_k (2πk/T)² |c_k| (≥ |f''(t)| at every t) exceeds DERIVATIVE_MAX = 3e138
    (so no evaluation can overflow, nor an integrator's error norm of it)."""
    re, im, k, weight = series._real
    with np.errstate(over="ignore", invalid="ignore"):  # an infinite bound is the answer
        bound = (weight * (2 * math.pi * k / series.period) ** 2) @ np.hypot(re, im)
    if not np.all(bound <= DERIVATIVE_MAX):
        big = float(np.max(np.nan_to_num(bound, nan=np.inf)))
        raise CaseError(f"its motion's second time derivative reaches {big:.3g} (period "
                        f"{series.period:.6g} s), beyond {DERIVATIVE_MAX:.3g}: an "
                        f"integrator's error norm of it would leave {DOUBLE_RANGE}",
                        element=name)
    return series
