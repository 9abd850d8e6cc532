"""One parameter point of a study: a built model through equilibrium, linearization and modes.

    Model ─► equilibrium ─► linearize ─► modes          (analyze_model → Analysis)

Every stage boundary is checked (README, "Input rules"): the model's elements are finite at the
case's positions before the equilibrium, the equilibrium's q₀, λ₀ are finite and its arithmetic
did not overflow, the linearization checks its own output (:func:`mbseig.linear.linearize`),
and the listed modes are finite and not empty.  A failed check is one
:class:`~mbseig.errors.NumericalError` naming the stage and the likely cause, never a traceback
or a listing of NaNs.
"""

from __future__ import annotations

import math
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np

from ..casefile import CaseSpec, read_case
from ..eigen import Request
from ..errors import MbseigError, NumericalError
from ..linear import LinearModel, linearize
from ..modal import Modes, modes
from ..model import Model
from ..numerics import DOUBLE_RANGE, jsonable, require_finite, watched
from ..statics import Equilibrium, equilibrium
from .mesh_rounding import mesh_rounding

__all__ = ["Analysis", "analyze_model", "as_spec", "modes_json", "equilibrium_stage",
           "linear_stage", "eigen_stage", "MODEL_CAUSE", "EIGEN_CAUSE"]

MODEL_CAUSE = (f"the case's values are too large or too small together (forces, stiffnesses, "
               f"masses and lengths multiply beyond {DOUBLE_RANGE})")
EIGEN_CAUSE = f"M, P and Q span more orders of magnitude than {DOUBLE_RANGE} allows"


@dataclass(frozen=True, eq=False)
class Analysis:
    """Model → equilibrium → linear model → modes for one case and parameter set.

    ``model`` is the model the equilibrium belongs to (inverse-statics commands resolved).
    """

    #: the reference motion this belongs to (mbseig.studies.reference): an equilibrium
    kind = "rest"

    @property
    def reference(self) -> Equilibrium:
        """The reference motion: the equilibrium."""
        return self.eq

    @property
    def verdict(self) -> str:
        """The stability verdict (mbseig.modal.scope)."""
        return self.modes.verdict

    def to_json(self) -> dict:
        """The fixed ``mbseig modes --json`` object."""
        return modes_json(self)

    model: object
    eq: Equilibrium
    linear: LinearModel
    modes: Modes
    refinement: object = None  # mbseig.studies.refine.Refinement when beams were refined


def as_spec(case) -> CaseSpec:
    """A :class:`CaseSpec` from a path or a spec (a path is read and parsed here, once)."""
    return case if isinstance(case, CaseSpec) else read_case(case)


def equilibrium_stage(model) -> Equilibrium:
    """:func:`mbseig.equilibrium` between its two boundary checks: every element finite at the
    case's positions before, finite q₀ and λ₀ and no overflow inside."""
    if isinstance(model, Model):
        bad = model.nonfinite_element(model.q_init)
        if bad is not None:
            name, what = bad
            raise NumericalError(f"{what} is not finite at the case's positions; likely cause: "
                                 f"{MODEL_CAUSE}", element=name)
    with watched("equilibrium", MODEL_CAUSE):
        eq = equilibrium(model)
    require_finite("equilibrium", MODEL_CAUSE, q0=eq.q, lam0=eq.lam)
    return eq


def linear_stage(model, *, constraint_stiffness=True):
    """(equilibrium, linear model) with the boundary checks of both stages (a model's sparse
    K and C at q₀ assembled once for the check, the solve and the linearization:
    :meth:`~mbseig.model.system.Model.keeping_jacobians`)."""
    with model.keeping_jacobians() if isinstance(model, Model) else nullcontext():
        eq = equilibrium_stage(model)
        return eq, linearize(model, eq, constraint_stiffness=constraint_stiffness)


def eigen_stage(lin: LinearModel, *, solver="auto", modes_options=None) -> Modes:
    """:func:`mbseig.modes` on ``lin``; the listing is checked: every listed eigenvalue and
    backward error finite, and a full spectrum of a model with degrees of freedom lists at
    least one mode (a verdict on an empty listing is refused)."""
    extra = {} if lin.constraint_jacobian is None else {"constraints": lin.constraint_jacobian}
    # the eigensolvers judge their own numpy warnings (issue 13/17, eigen part); only their
    # arithmetic exceptions become the one-line error here
    with watched("eigen", EIGEN_CAUSE, float_warnings=False):
        md = modes(lin.M, lin.P, lin.Q, solver=solver, N=lin.N,
                   coordinate_names=lin.coordinate_names, rigid=lin.rigid, display=lin.display,
                   **extra, **(modes_options or {}))
    bad = ~(np.isfinite(md.eigenvalues) & ~np.isnan(md.backward_error))
    if np.any(bad):
        k = int(np.argmax(bad))
        raise NumericalError(f"mode {k + 1} of {len(md)}: eigenvalue {md.eigenvalues[k]} with "
                             f"backward error {md.backward_error[k]} is not a finite result; "
                             f"likely cause: {EIGEN_CAUSE}", element="eigen")
    partial = bool(modes_options) or bool(extra) or Request(solver).family() == "partial"
    if not partial and lin.dof > 0 and len(md) == 0:
        raise NumericalError(
            f"no finite mode among the {lin.dof} degrees of freedom ({md.n_infinite} infinite "
            f"eigenvalues dropped): no verdict can be given; likely cause: a singular or "
            f"negligible mass matrix, or {EIGEN_CAUSE}", element="eigen")
    return md


def analyze_model(model, *, solver="auto", constraint_stiffness=True, modes_options=None):
    """equilibrium → linearize → modes on a built model, every stage boundary checked."""
    try:
        eq, lin = linear_stage(model, constraint_stiffness=constraint_stiffness)
        md = eigen_stage(lin, solver=solver, modes_options=modes_options)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
    return Analysis(eq.model if eq.model is not None else model, eq, lin, md)


def modes_json(a: Analysis) -> dict:
    """The fixed ``mbseig modes --json`` object (extra keys only extend it)."""
    from ..model.spatial_whirl import whirls  # spatial models only: off the start-up path

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
        "tolerances": {k: float(v) for k, v in md.tolerances.items()
                       if isinstance(v, (int, float))},
    }
    if eq.contacts:  # DESIGN §8: each single-sided contact's force and state
        out["contacts"] = [dict(c) for c in eq.contacts]
    flexible = (model.flexible or {}).get("bodies")
    if flexible:  # extension: theory, slenderness and mesh of each beam / FE body
        out["flexible_bodies"] = {nm: dict(r) for nm, r in flexible.items()}
        rounding = mesh_rounding(model, lin, md)
        if rounding is not None:  # extension: the digits the mesh keeps against rounding
            out["mesh_rounding"] = rounding.record()
    if a.refinement is not None:
        out["refinement"] = a.refinement.as_dict()
    rows = getattr(lin, "angle_rows", None)
    angle_shapes = None
    if rows is not None and rows.shape[0] and md.shapes.shape[0] == rows.shape[1]:
        angle_shapes = rows @ md.shapes  # the named angles of each mode (same normalization)
    # extension: the whirl of each mode of a model with a rotor (docs/spatial.md)
    whirl_of = (whirls(model, eq.q, md.shapes, md.eigenvalues)
                if md.shapes.shape[0] == model.n else [None] * len(md))
    for k in range(len(md)):
        s = md.eigenvalues[k]
        w = whirl_of[k]
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
