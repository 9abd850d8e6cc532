"""Mesh refinement driven by the modes of interest: no bigger a model than the question needs.

The request names the modes (the lowest ``modes`` listed modes and/or those below ``f_max`` Hz)
and a relative ``accuracy``.  Every beam with ``elements = "auto"`` starts at
:data:`mbseig.casefile.flexible.AUTO_START_ELEMENTS` elements; one beam at a time is doubled
while the others are held, and the change Δ of the requested frequencies,

    Δ = max_k |ω_k(2n) − ω_k(n)| / ω_k(2n)       (sorted ω_n; rigid-body modes compared absolutely)

gives Richardson estimates of the error of either mesh, with p the observed order
log₂(Δ_prev/Δ) of that beam, clipped to [1, ``max_order``] (4: the rate of the cubic elements
without shear, h² with shear dominating), and ``assumed_order`` = 2 until two refinements of the
beam exist:

    e(n) ≈ Δ 2ᵖ/(2ᵖ − 1),        e(2n) ≈ Δ/(2ᵖ − 1).

A beam stops at the coarser mesh when e(n) meets its share of the accuracy (accuracy / number of
auto beams), at the finer one when e(2n) does, and is doubled again otherwise.  A beam whose
refinement does not move the requested modes is never refined.  Consistent-mass Ritz
approximations on nested meshes converge from above, so comparing sorted frequencies is sound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError
from .point import Analysis, analyze_model, as_spec

__all__ = ["Refinement", "refine_analysis", "requested_modes"]


@dataclass(frozen=True)
class Refinement:
    """What the refinement did: per beam its element count, history and estimated error."""

    modes: int | None
    f_max: float | None
    accuracy: float
    assumed_order: float
    max_order: float
    beams: dict = field(default_factory=dict)
    omega: tuple = ()  # requested ω_n on the final mesh
    estimated_error: float = 0.0
    converged: bool = True
    solves: int = 0

    def as_dict(self) -> dict:
        return {"modes": self.modes, "f_max": self.f_max, "accuracy": self.accuracy,
                "assumed_order": self.assumed_order, "max_order": self.max_order,
                "beams": self.beams,
                "omega_n": list(self.omega), "estimated_error": self.estimated_error,
                "converged": self.converged, "solves": self.solves}


def requested_modes(md, *, modes=None, f_max=None, count=None):
    """ω_n of the modes of interest (sorted): the lowest ``modes``, or all with f ≤ f_max, or
    (``count``) a fixed number, so that two meshes are compared mode for mode."""
    w = np.sort(np.asarray(md.omega_n, dtype=float))
    if count is not None:
        return w[:count]
    k = 0
    if modes is not None:
        k = max(k, int(modes))
    if f_max is not None:
        k = max(k, int(np.sum(w <= 2 * math.pi * f_max)))
    return w[:k]


def _change(w_coarse, w_fine, scale):
    if w_fine.size == 0:
        return 0.0
    k = min(w_coarse.size, w_fine.size)
    if k < w_fine.size:
        return math.inf  # the coarse mesh does not even have the modes
    den = np.maximum(w_fine, scale)
    return float(np.max(np.abs(w_coarse[:k] - w_fine[:k]) / den))


def refine_analysis(spec, *, config=None, params=None, request=None, solver="auto",
                    constraint_stiffness=True, modes_options=None, assumed_order=2.0,
                    max_order=4.0, model=None):
    """Refine the ``auto`` beams of the case ``spec`` (a path or a parsed
    :class:`~mbseig.casefile.CaseSpec`, rebuilt per mesh, never re-read) for ``request``; return
    the final :class:`~mbseig.studies.pipeline.Analysis` with its ``refinement`` record.

    request : {"modes": K, "f_max": Hz, "accuracy": a, "max_elements": n}; None takes the
        case's ``[refinement]`` table.
    model : the model already built from ``spec`` at these parameters, if the caller has it.
    """
    spec = as_spec(spec)
    path = spec.source
    if model is None:
        model = spec.build(config, **(params or {}))
    fl = model.flexible or {}
    req = dict(fl.get("refinement") or {})
    req.update({k: v for k, v in (request or {}).items() if v is not None})
    if req.get("modes") is None and req.get("f_max") is None:
        raise CaseError("refinement needs the modes of interest: [refinement] modes or f_max, "
                        "or --refine-modes / --refine-fmax", file=str(path), element="refinement")
    accuracy = float(req.get("accuracy", 1e-3))
    max_el = int(req.get("max_elements", 256))
    if not accuracy > 0:
        raise CaseError(f"accuracy must be positive, got {accuracy:g}", file=str(path),
                        element="refinement")
    bodies = fl.get("bodies", {})
    auto = [nm for nm, r in bodies.items() if r.get("type") == "beam" and r.get("auto")]

    def run(mesh):
        return analyze_model(spec.build(config, mesh=mesh, **(params or {})), solver=solver,
                             constraint_stiffness=constraint_stiffness, modes_options=modes_options)

    mesh = {nm: bodies[nm]["elements"] for nm in auto}
    current = run(mesh)
    solves = 1
    share = accuracy / max(len(auto), 1)
    state = {nm: {"history": [], "converged": False, "order": None, "error": None}
             for nm in auto}
    w_ref = requested_modes(current.modes, modes=req.get("modes"), f_max=req.get("f_max"))
    while True:
        pending = [nm for nm in auto if not state[nm]["converged"]]
        if not pending:
            break
        for nm in pending:
            st = state[nm]
            n = mesh[nm]
            if 2 * n > max_el:  # stop here; recorded as not converged
                st.update(converged=True, failed=True)
                continue
            trial = {**mesh, nm: 2 * n}
            a_fine = run(trial)
            solves += 1
            w_fine = requested_modes(a_fine.modes, modes=req.get("modes"), f_max=req.get("f_max"))
            w_coarse = requested_modes(current.modes, count=w_fine.size)
            scale = 1e-9 * max(float(w_fine.max(initial=0.0)), 1e-300)
            delta = _change(w_coarse, w_fine, scale)
            hist = st["history"]
            hist.append({"elements": n, "refined_to": 2 * n, "change": delta})
            p = assumed_order
            if len(hist) >= 2 and 0 < delta < hist[-2]["change"] < math.inf:
                p = min(max(math.log2(hist[-2]["change"] / delta), 1.0), max_order)
            f = 2.0**p
            e_coarse, e_fine = delta * f / (f - 1), delta / (f - 1)
            st["order"] = p
            if e_coarse <= share:
                st.update(converged=True, error=e_coarse)
            elif e_fine <= share:
                mesh, current, w_ref = trial, a_fine, w_fine
                st.update(converged=True, error=e_fine)
            else:
                mesh, current, w_ref = trial, a_fine, w_fine
                st["error"] = e_fine
    records = {}
    for nm in auto:
        st = state[nm]
        records[nm] = {"elements": mesh[nm], "estimated_error": st["error"],
                       "observed_order": st["order"], "history": st["history"],
                       "converged": not st.get("failed", False)}
    errors = [r["estimated_error"] or 0.0 for r in records.values()]
    ref = Refinement(modes=req.get("modes"), f_max=req.get("f_max"), accuracy=accuracy,
                     assumed_order=assumed_order, max_order=max_order, beams=records,
                     omega=tuple(float(x) for x in w_ref), estimated_error=float(sum(errors)),
                     converged=all(r["converged"] for r in records.values()), solves=solves)
    return Analysis(current.model, current.eq, current.linear, current.modes, refinement=ref)
