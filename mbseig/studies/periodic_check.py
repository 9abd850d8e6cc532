"""The time-domain check of a Floquet prediction (DESIGN §7 for periodic motions).

The nonlinear model is started from the periodic reference perturbed along the Floquet vector
v of a multiplier μ (small amplitude, on the constraint manifold: the independent coordinates
of δq = N y, δq̇ of the Floquet state) and integrated over whole periods.  The deviation
x(kT) − x*(0) is projected on the invariant subspace of μ (span{Re v, Im v}, or v when μ is
real); in that basis the linear map of one period is a scaling by |μ| times a rotation, so the
norm of the projection grows by exactly |μ| per period in the linear limit.  The measured
growth per period, (‖c_K‖/‖c_0‖)^(1/K), is compared with |μ|; K stops before the deviation
has grown 100-fold (nonlinear terms stay below about 100 × amplitude, relative).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .periodic_motion import simulate

__all__ = ["FloquetCheck", "check_floquet"]


@dataclass(frozen=True)
class FloquetCheck:
    """|μ| against the simulated growth per period of the perturbation along its vector."""

    index: int
    multiplier: complex
    modulus: float
    growth: float
    relative_error: float
    rtol: float
    periods: int
    amplitude: float
    off_subspace: float  # largest part of the deviation outside the subspace, relative
    passed: bool

    def to_dict(self) -> dict:
        return {"index": self.index, "multiplier": [self.multiplier.real, self.multiplier.imag],
                "modulus": self.modulus, "simulated_growth_per_period": self.growth,
                "relative_error": self.relative_error, "rtol": self.rtol,
                "periods": self.periods, "amplitude": self.amplitude,
                "off_subspace": self.off_subspace, "passed": self.passed}


def check_floquet(analysis, *, index=0, amplitude=1e-4, periods=8, rtol=1e-3,
                  ode_rtol=1e-11) -> FloquetCheck:
    """Simulate along the Floquet vector of multiplier ``index`` (0: the largest |μ|) and
    compare the growth per period with |μ| (module docstring)."""
    res, ref = analysis.floquet, analysis.reference
    part = ref.partition
    mu = complex(res.multipliers[index])
    v = analysis.basis @ res.floquet_vectors[:, index]  # (δq, δq̇), complex
    n = part.timed.n
    cols = np.concatenate([part.ind, n + part.ind])
    w = v[cols]
    V = np.column_stack([w.real, w.imag]) if abs(mu.imag) > 1e-12 * abs(mu) else \
        np.real(w * np.exp(-1j * np.angle(w[np.argmax(np.abs(w))])))[:, None]
    scale = amplitude * max(1.0, part.timed.base.length_scale)
    start_dir = V[:, 0] / np.linalg.norm(V[:, 0])
    x0 = ref.x0 + scale * start_dir
    xs = simulate(ref, x0, periods, rtol=ode_rtol)
    d = xs - ref.x0[None, :]
    c, *_ = np.linalg.lstsq(V, d.T, rcond=None)
    norms = np.linalg.norm(c, axis=0)
    off = float(np.max(np.linalg.norm(d.T - V @ c, axis=0)
                       / np.maximum(np.linalg.norm(d, axis=1), 1e-300)))
    K = periods
    while K > 1 and norms[K] > 100 * norms[0]:
        K -= 1
    growth = float((norms[K] / norms[0]) ** (1.0 / K))
    err = abs(growth - abs(mu)) / abs(mu)
    return FloquetCheck(index, mu, abs(mu), growth, err, rtol, K, scale, off, bool(err <= rtol))
