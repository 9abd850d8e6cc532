"""The largest Floquet multipliers of a periodic case without forming the monodromy matrix
(DESIGN §8; ``mbseig modes CASE --n-modes K`` on a periodic case).

ARPACK (implicitly restarted Arnoldi, ``scipy.sparse.linalg.eigs``) runs on the operator
v ↦ Π Φ Π v in the model's own coordinates (:mod:`mbseig.studies.floquet_descriptor`: each
product one fixed-step integration of the linearized constrained equations in index-1 form,
with sparse solves whose factorizations every product shares; Π keeps the constraints at
t = 0 and adds only zeros to the spectrum).  Two independent estimates, as for the full
monodromy (:mod:`mbseig.studies.periodic`): the linearization sampled on N instants with the
steps that meet the tighter tolerance, and on the grid shifted by half a sample with half
those steps (so their difference holds the first's discretization error, not only the
sampling's).  The bound of multiplier k is the largest of

(i)   |μ_k − μ̃_k|, the difference between the two estimates (matched by assignment);
(ii)  ‖Φ v_k − μ_k v_k‖/‖v_k‖, the residual of the Ritz pair (a fresh product), which bounds the
      error of a well-conditioned multiplier; a defective one (a Jordan block at μ = ±1) is
      not bounded by it, as with any residual;

and a rounding floor 64 ε_mach |μ_k|.  The verdict reads only the K largest |μ|, which hold the
spectral radius: unstable when some |μ_k| − b_k > 1, stable when the largest |μ_k| + b_k < 1,
critical otherwise.

Cost: a product costs O(nnz) a stage (a sparse solve and one sparse product), against 2r
columns a stage for the full monodromy. ARPACK needs about one basis of products (21 at K = 1)
where the largest |μ| stand apart (the detuned chain of shaken pendulums, l2 = 0.5: 35 products
in all, both estimates, at every size), and a number that grows with the model where they are
clustered (the uniform chain: 127 and 297 products at 25 and 50 pendulums, 8,433 and 1,598 at
100 and 150). So ``--floquet auto`` (:func:`largest_multipliers`) tries the partial method from
``DESCRIPTOR_FROM_DOF`` on within :func:`partial_budget` products an estimate and falls back to
the full monodromy past it. Explicit steps suit models whose fastest mode the period resolves
in a few hundred steps; a stiff one (beams) needs thousands, and auto then leaves it to the
full monodromy too. Measured in benchmarks/periodic_scaling.py (docs/periodic.md, "Floquet at
scale").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..errors import CaseError, MbseigError
from .floquet import FloquetError
from .floquet_descriptor import descriptor_partial
from .periodic import periodic_linearization
from .periodic_listing import reduced_exponents

__all__ = ["PartialAnalysis", "periodic_partial", "PARTIAL_RTOL", "largest_multipliers",
           "partial_budget", "TRY_PRODUCTS_PER_DOF"]

#: the first estimate's steps change a probe product by at most 63 × this when halved (its own
#: error about 1/63 of that); the second runs at half those steps.  The full monodromy in the
#: model's coordinates uses the same (``max(periodic.RTOLS)``), so ``--floquet auto`` answers
#: to the same accuracy by either method (1e-11 doubled the steps, and the cost of a product,
#: on the uniform chain)
PARTIAL_RTOL = 1e-10


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
    steps: tuple = ()  # fixed steps a period of the two estimates

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
                        "steps": [int(x) for x in self.steps],
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


def periodic_partial(spec, *, k, config=None, params=None, rtol=PARTIAL_RTOL,
                     tol=1e-10, budget=None, max_steps=None) -> PartialAnalysis:
    """The ``k`` Floquet multipliers of largest modulus of a periodic case (module docstring);
    ``rtol`` sets the first estimate's steps (at most ``max_steps`` a period, else
    StepsNotSettled), ``tol`` is ARPACK's relative accuracy of the Ritz values; with
    ``budget``, each estimate's Arnoldi stops past that many products
    (:class:`~mbseig.studies.floquet_descriptor.BudgetSpent`, a FloquetError)."""
    lin = periodic_linearization(spec, config=config, params=params)
    size = lin.system.system.size
    if not 0 < k < size - 1:
        raise CaseError(f"--n-modes must be between 1 and 2·DOF − 2 = {size - 2} for the partial "
                        f"Floquet method (this case has {size} multipliers; run modes without "
                        f"--n-modes for all of them), got {k}", element="command line",
                        file=spec.source)
    M, T = lin.reference.partition.M, lin.timed.period
    try:
        # products in the model's own sparse coordinates (mbseig.studies.floquet_descriptor);
        # the second estimate at half the steps, so that the difference also holds the first's
        # discretization error (about 2⁶ times smaller than the second's).  The second starts
        # from the first's Ritz vectors with a short basis (2K + 4): a third of the products
        # on the detuned chain, and the same convergence test on its own operator, so its
        # values are its own
        first, steps, V = descriptor_partial(M, lin.fits[0], T, k=k, rtol=rtol, tol=tol,
                                             budget=budget, max_steps=max_steps)
        half = max(steps // 2, 1)
        second, _, _ = descriptor_partial(M, lin.fits[1], T, k=k, rtol=rtol, tol=tol,
                                          steps=half, budget=budget, start=V,
                                          ncv=min(size - 1, 2 * k + 4))
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
    method = (f"{first.method} (second estimate: {half}); {k} largest |μ|, "
              f"{first.products + second.products} products; {lin.samples} samples of the "
              "linearization per period")
    return PartialAnalysis(spec.name, lin.parameters, lin, lin.timed.period, mu, bounds, res,
                           verdict, decided, first.products + second.products, (rtol,), method,
                           (steps, half))


def partial_budget(k):
    """Products an estimate's Arnoldi may take when ``--floquet auto`` tries the partial method:
    three times ARPACK's default basis (2K + 1, at least 20).  Where the K largest |μ| stand
    apart ARPACK needs about one basis (21 on the detuned chain of shaken pendulums); where they
    are clustered it needs hundreds to thousands (the uniform chain), and the try costs at most
    this many products before the full monodromy answers."""
    return 3 * max(2 * k + 1, 20)


#: ``--floquet auto`` tries the partial method only while its budget is at most this many
#: products a degree of freedom: on the uniform chain at 100 DOF the 60-product try cost about
#: as much as the full monodromy (0.9 s against 1.0 s, docs/periodic.md), and the full method's
#: cost grows faster with the DOF than a product's.  So a try never costs much more than the
#: answer it might replace (K = 50 asks 303 products: from 505 DOF on)
TRY_PRODUCTS_PER_DOF = 0.6


def largest_multipliers(spec, *, k, floquet="auto", config=None, params=None) -> dict:
    """The modes JSON of ``mbseig modes CASE --n-modes K`` on a periodic case, the K largest
    |μ|: ``"full"`` from the full monodromy, ``"partial"`` by the partial method, ``"auto"``
    by the partial method within :func:`partial_budget` products an estimate from
    ``DESCRIPTOR_FROM_DOF`` degrees of freedom on (below, the full monodromy costs less than
    the partial method's products) while that budget is at most :data:`TRY_PRODUCTS_PER_DOF`
    products a DOF, and from the full monodromy otherwise or if the partial method does not
    converge within that budget (clustered |μ|) or its explicit steps do not settle within
    ``FULL_MAX_STEPS`` a period (a stiff model).  ``floquet.selected`` says which ran and why
    (docs/periodic.md)."""
    from . import floquet_descriptor, periodic
    from .floquet_descriptor import BudgetSpent, StepsNotSettled
    from .periodic_listing import largest_json, partial_json

    def partial(**kw):
        out = partial_json(periodic_partial(spec, k=k, config=config, params=params, **kw))
        fl = out["floquet"]
        fl["selected"] = {"count": len(fl["multipliers"]), "of": fl["partial"]["of"]}
        return out

    if floquet == "partial":
        out = partial()
        out["floquet"]["selected"]["method"] = "partial (Arnoldi) method, as asked"
        return out
    why = "full monodromy, as asked"
    if floquet == "auto":
        lin = periodic.periodic_linearization(spec, config=config, params=params)
        dof, size = lin.system.dof, lin.system.system.size
        if dof < periodic.DESCRIPTOR_FROM_DOF:
            why = (f"full monodromy, then the largest |μ|: below {periodic.DESCRIPTOR_FROM_DOF} "
                   f"DOF ({dof} here) it costs less than the partial method's products "
                   "(docs/periodic.md); --floquet partial runs the partial method")
        elif not 0 < k < size - 1:
            why = (f"full monodromy, then the largest |μ|: the partial method takes 1 to "
                   f"2·DOF − 2 = {size - 2} multipliers, {k} asked")
        elif partial_budget(k) > TRY_PRODUCTS_PER_DOF * dof:
            why = (f"full monodromy, then the largest |μ|: K = {k} would give the partial "
                   f"method's try {partial_budget(k)} products, more than "
                   f"{TRY_PRODUCTS_PER_DOF:g} a DOF ({dof} DOF here), where the try could cost "
                   "more than the full monodromy (docs/periodic.md); --floquet partial runs it")
        else:
            budget = partial_budget(k)
            try:
                # the full monodromy's step cap: a model that needs more explicit steps is
                # stiff, and the full method integrates it on the projected system
                out = partial(budget=budget, max_steps=floquet_descriptor.FULL_MAX_STEPS)
            except FloquetError as exc:  # the full monodromy answers, or says what fails
                if isinstance(exc, BudgetSpent):
                    what = (f"did not converge within its budget of {budget} products an "
                            "estimate (ARPACK needs many products where the largest |μ| lie "
                            "close together)")
                elif isinstance(exc, StepsNotSettled):
                    what = (f"could not run: its explicit steps did not settle within "
                            f"{floquet_descriptor.FULL_MAX_STEPS} a period, as for a stiff "
                            "model")
                else:
                    what = f"stopped: {exc.message}"
                why = (f"full monodromy, then the largest |μ|: from "
                       f"{periodic.DESCRIPTOR_FROM_DOF} DOF on the partial (Arnoldi) method is "
                       f"tried first, and here it {what}")
            else:
                out["floquet"]["selected"]["method"] = (
                    f"partial (Arnoldi) method: from {periodic.DESCRIPTOR_FROM_DOF} DOF on it is "
                    f"tried first, within {budget} products an estimate, and converged in "
                    f"{out['floquet']['partial']['products']} products in all (the step "
                    "probes included)")
                return out
    a = periodic.periodic_analysis(spec, config=config, params=params)
    return largest_json(a, k, why)
