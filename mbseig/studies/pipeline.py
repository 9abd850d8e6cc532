"""The whole pipeline on one case and parameter point, and its JSON form (the fixed `mbseig modes --json` interface).

Each mode of the JSON has ``freq_hz`` = ω_d/2π (damped, as fixed in DESIGN §8) and
``freq_n_hz`` = ω_n/2π = |s|/2π (natural), and, when the case names angles (report angles,
torsional elements, angle outputs), ``angles``: the mode shape in those angles [re, im] with
the normalization of the coordinate shape (largest coordinate component 1).

    case ─► Model ─► equilibrium ─► linearize ─► modes        (analyze)

``case`` is a path (read once here), a parsed :class:`~mbseig.casefile.CaseSpec` (a model
factory) or an already built model.
"""

from __future__ import annotations

import math

from ..arguments import check
from ..numerics import jsonable
from .point import Analysis, analyze_model, as_spec

__all__ = ["Analysis", "analyze", "analyze_model", "modes_json", "as_spec"]


def analyze(case=None, *, config=None, params=None, solver="auto", constraint_stiffness=True,
            modes_options=None, model=None, refine=None) -> Analysis:
    """Run the pipeline on ``case`` (a path or a :class:`CaseSpec`), or on a built ``model``.

    refine : {"modes", "f_max", "accuracy", "max_elements"} to refine the case's
        ``elements = "auto"`` beams for those modes (:mod:`mbseig.studies.refine`); a case's own
        ``[refinement]`` table does the same.
    """
    check("analyze", locals())
    opts = {"solver": solver, "constraint_stiffness": constraint_stiffness,
            "modes_options": modes_options}
    if model is not None:
        return analyze_model(model, **opts)
    spec = as_spec(case)
    model = spec.build(config, **(params or {}))
    if refine or (getattr(model, "flexible", None) or {}).get("refinement"):
        from .refine import refine_analysis  # cases with beams to refine only

        return refine_analysis(spec, config=config, params=params, request=refine, model=model,
                               **opts)
    return analyze_model(model, **opts)


def modes_json(a: Analysis) -> dict:
    """The fixed ``mbseig modes --json`` object (extra keys only extend it)."""
    from ..model.spatial_whirl import whirl  # spatial models only: off the start-up path

    md, lin, eq, model = a.modes, a.linear, a.eq, a.model
    out = {
        "case": model.name,
        "parameters": dict(model.parameters),
        "n_coordinates": int(model.n),
        "n_constraints": int(model.n_constraints),
        "n_redundant": int(eq.n_redundant),
        "dof": int(lin.dof),
        "solver": md.solver,
        "equilibrium": {"residual": float(eq.residual), "iterations": int(eq.iterations),
                        "notes": [str(n) for n in (getattr(eq, "notes", None) or ())]},
        "verdict": md.verdict,
        # what the verdict covers: a partial spectrum, the rigid-body modes by construction
        "verdict_scope": getattr(md.verdict, "full_scope", ""),
        "coverage": md.coverage,
        "accounting": md.accounting,
        "modes": [],
        "solver_reason": md.solver_reason,
        "n_infinite": int(md.n_infinite),
        "redundant_constraints": list(eq.redundant),
        "tolerances": {k: float(v) for k, v in md.tolerances.items() if isinstance(v, (int, float))},
    }
    if eq.contacts:  # DESIGN §8: each single-sided contact's force and state
        out["contacts"] = [dict(c) for c in eq.contacts]
    flexible = (getattr(model, "flexible", None) or {}).get("bodies")
    if flexible:  # extension: theory, slenderness and mesh of each beam / FE body
        out["flexible_bodies"] = {nm: dict(r) for nm, r in flexible.items()}
    if a.refinement is not None:
        out["refinement"] = a.refinement.as_dict()
    rows = getattr(lin, "angle_rows", None)
    angle_shapes = None
    if rows is not None and rows.shape[0] and md.shapes.shape[0] == rows.shape[1]:
        angle_shapes = rows @ md.shapes  # the named angles of each mode (same normalization)
    for k in range(len(md)):
        s = md.eigenvalues[k]
        # extension: the whirl of each mode of a model with a rotor (docs/spatial.md)
        w = whirl(model, eq.q, md.shapes[:, k], s) if md.shapes.shape[0] == model.n else None
        out["modes"].append({
            "index": k + 1,
            "eigenvalue": [float(s.real), float(s.imag)],
            "delta": float(md.delta[k]),
            "omega_n": float(md.omega_n[k]),
            "omega_d": float(md.omega_d[k]),
            "freq_hz": float(md.freq_hz[k]),  # damped: omega_d / 2 pi
            "freq_n_hz": float(md.omega_n[k] / (2 * math.pi)),  # natural: omega_n / 2 pi
            "zeta": float(md.zeta[k]),
            "stability": md.stability[k],
            "kind": md.kind[k],
            # the declared rigid-body direction this mode is (left out of the verdict), or None
            "rigid_body": md.rigid_body[k] if md.rigid_body else None,
            "backward_error": float(md.backward_error[k]),
            "condition": float(md.condition[k]),
            "tolerance": float(md.tolerance[k]),
            "dominant": [[nm, float(v)] for nm, v in md.dominant[k]],
            "multiplicity": int(md.multiplicity[k]) if md.multiplicity is not None else 1,
            "flags": list(md.flags[k]) if md.flags else [],
            **({} if w is None else {"whirl": w}),
            **({} if angle_shapes is None else {"angles": {
                nm: [float(angle_shapes[i, k].real), float(angle_shapes[i, k].imag)]
                for i, nm in enumerate(lin.angle_names)}}),
        })
    return jsonable(out)
