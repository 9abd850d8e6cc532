"""A sweep of a periodic case over one parameter: the Floquet verdict at every grid point and
where it changes (DESIGN §8: ``flip`` at μ = −1, ``fold`` at μ = +1, ``secondary`` for a
complex pair on |μ| = 1), each located to a relative tolerance by Brent's method on the
characteristic function of its kind (:func:`mbseig.studies.floquet_sweep.verdict_changes`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .floquet_sweep import verdict_changes
from .periodic import periodic_analysis, periodic_linearization

__all__ = ["PeriodicSweep", "periodic_sweep"]


@dataclass(frozen=True)
class PeriodicSweep:
    """Grid points (value, FloquetResult) and the verdict changes between them."""

    case: str
    parameter: str
    values: np.ndarray
    results: tuple
    boundaries: tuple
    rel_tol: float

    def to_dict(self) -> dict:
        return {
            "case": self.case,
            "parameter": self.parameter,
            "points": [{"value": float(v), "verdict": r.verdict,
                        "spectral_radius": r.spectral_radius, "error_bound": r.error_bound,
                        "multipliers": [[float(m.real), float(m.imag)] for m in r.multipliers]}
                       for v, r in zip(self.values, self.results)],
            "boundaries": [{"value": b.value, "kind": b.kind, "stability": b.stability,
                            "bracket": list(b.bracket), "method": b.method, "xtol": b.xtol,
                            "verdicts": list(b.verdicts)} for b in self.boundaries],
            "rel_tol": self.rel_tol,
        }


def periodic_sweep(spec, name, values, *, config=None, fixed=None, rel_tol=1e-8,
                   progress=None) -> PeriodicSweep:
    """Floquet verdicts of a periodic case over ``values`` of parameter ``name`` and the
    parameter values where the verdict changes, located to ``rel_tol``."""
    fixed = dict(fixed or {})
    values = np.sort(np.asarray(values, dtype=float))

    def params(p):
        return {**fixed, name: repr(float(p))}

    results = []
    for k, p in enumerate(values):
        results.append(periodic_analysis(spec, config=config, params=params(p)).floquet)
        if progress:
            progress(k + 1, len(values))

    def build(p):
        return periodic_linearization(spec, config=config, params=params(p)).system.system, None

    found = verdict_changes(build, values, rel_tol=rel_tol, results=results)
    return PeriodicSweep(spec.name, name, values, tuple(results), found, rel_tol)
