"""The largest Floquet multipliers of a periodic case without forming the monodromy matrix
(DESIGN §8; ``mbseig modes CASE --n-modes K`` on a periodic case).

ARPACK (implicitly restarted Arnoldi, ``scipy.sparse.linalg.eigs``) runs on the operator
v ↦ Φ v, each product one integration of the projected variational equations for one vector
(:func:`mbseig.studies.floquet.floquet_partial`).  Two independent estimates, as for the full
monodromy (:mod:`mbseig.studies.periodic`): the linearization sampled on N instants at the tighter
tolerance and on the grid shifted by half a step at the looser one.  The bound of multiplier k is
the largest of

(i)   |μ_k − μ̃_k|, the difference between the two estimates (matched by assignment);
(ii)  ‖Φ v_k − μ_k v_k‖/‖v_k‖, the residual of the Ritz pair (a fresh product), which bounds the
      error of a well-conditioned multiplier; a defective one (a Jordan block at μ = ±1) is
      not bounded by it, as with any residual;

and a rounding floor 64 ε_mach |μ_k|.  The verdict reads only the K largest |μ|, which hold the
spectral radius: unstable when some |μ_k| − b_k > 1, stable when the largest |μ_k| + b_k < 1,
critical otherwise.

Cost: a product costs one integration of 2r numbers (r = n − m), the full monodromy one of
(2r)² numbers.  Both integrate the Chebyshev interpolants of the projected A(t)
(:mod:`mbseig.studies.floquet_chebyshev`: A itself is evaluated once per interpolation point,
not at every stage), so a product costs O((2r)² d) per stage for an interpolant of degree d.
ARPACK needs a few times K products, many more where the largest |μ| are clustered
(measured in benchmarks/periodic_scaling.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..errors import CaseError, MbseigError
from .floquet import FloquetError, floquet_partial
from .floquet_chebyshev import chebyshev_system
from .periodic import periodic_linearization
from .periodic_listing import reduced_exponents

__all__ = ["PartialAnalysis", "periodic_partial", "PARTIAL_RTOLS"]

PARTIAL_RTOLS = (1e-9, 1e-11)  # the two estimates (shifted sampling at the looser one)


@dataclass(frozen=True)
class PartialAnalysis:
    """The K largest multipliers of a periodic case, their bounds and the verdict."""

    name: str
    parameters: dict
    linearization: object
    period: float
    multipliers: np.ndarray
    error_bounds: np.ndarray
    residuals: np.ndarray
    verdict: str
    decided_by: tuple
    products: int
    tolerances: tuple
    method: str

    def to_dict(self) -> dict:
        """The §8 ``"floquet"`` object of the K largest multipliers (and the partial record)."""
        mu, b = self.multipliers, self.error_bounds
        lin = self.linearization
        ref = lin.reference
        return {
            "period": self.period,
            "multipliers": [[float(m.real), float(m.imag)] for m in mu],
            "exponents": reduced_exponents(mu, self.period),
            "error_bound": float(np.max(b)),
            "verdict": self.verdict,
            "error_bounds": [float(x) for x in b],
            "decided_by": {"index": int(self.decided_by[0]), "modulus": self.decided_by[1],
                           "bound": self.decided_by[2], "margin": self.decided_by[3]},
            "method": self.method,
            "tolerances": list(self.tolerances),
            "partial": {"count": int(mu.size), "of": int(lin.system.system.size),
                        "products": int(self.products),
                        "residuals": [float(x) for x in self.residuals]},
            "samples": lin.samples,
            "sampling_difference": lin.sampling_difference,
            "reference": {"method": ref.method, "residual": ref.residual,
                          "iterations": ref.iterations},
            "time_dependent": list(lin.timed.time_dependent),
        }


def _with_pairs(result, k):
    """The first ``k`` multipliers of ``result``, plus the conjugate of a complex one whose
    partner ARPACK left out (a pair is reported whole)."""
    mu, res = list(result.multipliers[:k]), list(result.residuals[:k])
    for m, r in zip(list(mu), list(res), strict=True):
        if abs(m.imag) > 1e-12 * abs(m) and not any(abs(x - m.conjugate()) <= 1e-9 * abs(m)
                                                     for x in mu):
            mu.append(m.conjugate())
            res.append(r)
    return np.array(mu), np.array(res)


def _verdict(mu, b):
    mod = np.abs(mu)
    lower, upper = mod - b, mod + b
    if np.any(lower > 1.0):
        j = int(np.argmax(lower))
        return "unstable", (j, float(mod[j]), float(b[j]), float(lower[j] - 1.0))
    j = int(np.argmax(upper))
    if upper[j] < 1.0:
        return "stable", (j, float(mod[j]), float(b[j]), float(1.0 - upper[j]))
    return "critical", (j, float(mod[j]), float(b[j]), float(min(upper[j] - 1.0, 1.0 - lower[j])))


def periodic_partial(spec, *, k, config=None, params=None, rtols=PARTIAL_RTOLS,
                     tol=1e-10) -> PartialAnalysis:
    """The ``k`` Floquet multipliers of largest modulus of a periodic case (module docstring);
    ``tol`` is ARPACK's relative accuracy of the Ritz values."""
    lin = periodic_linearization(spec, config=config, params=params)
    size = lin.system.system.size
    if not 0 < k < size - 1:
        raise CaseError(f"--n-modes must be between 1 and 2·DOF − 2 = {size - 2} for the partial "
                        f"Floquet method (this case has {size} multipliers; run modes without "
                        f"--n-modes for all of them), got {k}", element="command line",
                        file=spec.source)
    lo, hi = sorted(rtols)
    try:
        # A(t) by its Chebyshev interpolants: every product integrates a cheap A
        first = floquet_partial(chebyshev_system(lin.system.system)[0], k=k, rtol=lo, tol=tol)
        second = floquet_partial(chebyshev_system(lin.check.system)[0], k=k, rtol=hi, tol=tol)
    except MbseigError as exc:
        raise exc.located(file=spec.source) from None
    except (np.linalg.LinAlgError, ArithmeticError, RuntimeError) as exc:
        raise FloquetError(f"the partial Floquet method failed: {exc}", element="monodromy",
                           file=spec.source) from None
    mu, res = _with_pairs(first, k)
    mu2, _ = _with_pairs(second, k)
    cost = np.abs(mu[:, None] - mu2[None, :])
    rows, cols = linear_sum_assignment(cost)
    diff = np.full(mu.size, np.inf)  # a multiplier the second estimate did not find: unbounded
    diff[rows] = cost[rows, cols]
    bounds = np.maximum.reduce([diff, res, 64 * np.finfo(float).eps * np.abs(mu)])
    order = np.lexsort((np.angle(mu), -np.abs(mu)))
    mu, bounds, res = mu[order], bounds[order], res[order]
    verdict, decided = _verdict(mu, bounds)
    method = (f"{first.method}; {k} largest |μ|, {first.products + second.products} products; "
              f"{lin.samples} samples of the linearization per period")
    return PartialAnalysis(spec.name, lin.parameters, lin, lin.timed.period, mu, bounds, res,
                           verdict, decided, first.products + second.products, (lo, hi), method)
