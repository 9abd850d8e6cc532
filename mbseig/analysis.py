"""One call for the whole pipeline on a case file, and its JSON form (DESIGN §8)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .case import load_case
from .errors import MbseigError
from .linear import LinearModel, linearize
from .modal import Modes, modes
from .statics import Equilibrium, equilibrium

__all__ = ["Analysis", "analyze", "modes_json", "jsonable"]


@dataclass(frozen=True, eq=False)
class Analysis:
    """Model → equilibrium → linear model → modes for one case and parameter set."""

    model: object
    eq: Equilibrium
    linear: LinearModel
    modes: Modes
    refinement: object = None  # mbseig.refine.Refinement when beams were refined

    @property
    def case_name(self) -> str:
        return self.model.name


def analyze(path, *, config=None, params=None, solver="auto", constraint_stiffness=True,
            modes_options=None, model=None, refine=None) -> Analysis:
    """Run the pipeline on ``path`` (or on an already loaded ``model``).

    refine : {"modes", "f_max", "accuracy", "max_elements"} to refine the case's
        ``elements = "auto"`` beams for those modes (:mod:`mbseig.refine`); a case's own
        ``[refinement]`` table does the same when ``path`` is given.
    """
    if model is None:
        model = load_case(path, config=config, **(params or {}))
        if refine or (getattr(model, "flexible", None) or {}).get("refinement"):
            from .refine import refine_analysis

            return refine_analysis(path, config=config, params=params, request=refine,
                                   solver=solver, constraint_stiffness=constraint_stiffness,
                                   modes_options=modes_options)
    try:
        eq = equilibrium(model)
        lin = linearize(model, eq, constraint_stiffness=constraint_stiffness)
        extra = {} if lin.constraint_jacobian is None else {"constraints": lin.constraint_jacobian}
        md = modes(lin.M, lin.P, lin.Q, solver=solver, N=lin.N,
                   coordinate_names=lin.coordinate_names, **extra, **(modes_options or {}))
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
    return Analysis(model, eq, lin, md)


def jsonable(x):
    """Floats with non-finite values as None, so that the output is strict JSON."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    return x


def modes_json(a: Analysis) -> dict:
    """The fixed ``mbseig modes --json`` object (extra keys only extend it)."""
    md, lin, eq, model = a.modes, a.linear, a.eq, a.model
    out = {
        "case": model.name,
        "parameters": dict(model.parameters),
        "n_coordinates": int(model.n),
        "n_constraints": int(model.n_constraints),
        "n_redundant": int(eq.n_redundant),
        "dof": int(lin.dof),
        "solver": md.solver,
        "equilibrium": {"residual": float(eq.residual), "iterations": int(eq.iterations)},
        "verdict": md.verdict,
        "modes": [],
        "solver_reason": md.solver_reason,
        "n_infinite": int(md.n_infinite),
        "redundant_constraints": list(eq.redundant),
        "tolerances": {k: float(v) for k, v in md.tolerances.items() if isinstance(v, (int, float))},
    }
    flexible = (getattr(model, "flexible", None) or {}).get("bodies")
    if flexible:  # extension: theory, slenderness and mesh of each beam / FE body
        out["flexible_bodies"] = {nm: dict(r) for nm, r in flexible.items()}
    if a.refinement is not None:
        out["refinement"] = a.refinement.as_dict()
    for k in range(len(md)):
        s = md.eigenvalues[k]
        out["modes"].append({
            "index": k + 1,
            "eigenvalue": [float(s.real), float(s.imag)],
            "delta": float(md.delta[k]),
            "omega_n": float(md.omega_n[k]),
            "omega_d": float(md.omega_d[k]),
            "freq_hz": float(md.freq_hz[k]),
            "zeta": float(md.zeta[k]),
            "stability": md.stability[k],
            "kind": md.kind[k],
            "backward_error": float(md.backward_error[k]),
            "condition": float(md.condition[k]),
            "tolerance": float(md.tolerance[k]),
            "dominant": [[nm, float(v)] for nm, v in md.dominant[k]],
        })
    return jsonable(out)
