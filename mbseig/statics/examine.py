"""Examination of a converged equilibrium (docs/design.md, "Equilibrium"): self-stress of redundant
constraints, static stability (:mod:`~mbseig.statics.stiffness`) and, where it is unstable, a
stable rest position offered beside it (load continuation, then descent from the unstable
direction)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from ..errors import MbseigError
from ..model.linear_case import LinearCase
from .failures import (
    StaticInstabilityWarning,
    UndeterminedSelfStress,
)
from .linalg import DENSE_LIMIT
from .newton import static_multipliers
from .result import StaticStability, reaction_records


def examine(eq, *, offer_stable=True, self_stress="refuse", compliance=None, opts=None):
    """Self-stress of redundant constraints, static stability and a stable alternative
    (:mod:`~mbseig.statics.stiffness`) for a converged equilibrium."""
    from .stiffness import (
        SELF_STRESS_TOL,
        compliant_multipliers,
        self_stress_states,
        static_stability,
    )

    model = eq.model
    if isinstance(model, LinearCase) or model is None:
        return eq
    if model.n + model.n_constraints > DENSE_LIMIT:
        return dataclasses.replace(eq, static=StaticStability(
            verdict="not examined", reason=f"above the dense limit of {DENSE_LIMIT}"))
    rank_tol = eq.tolerances.get("rank_tol", 1e-10)
    notes, states, lam = list(eq.notes), [], eq.lam
    if eq.n_redundant:
        free = None
        if compliance:
            unknown = sorted(set(compliance) - {c.name for c in model.constraints})
            if unknown:
                raise UndeterminedSelfStress(f"compliance given for unknown constraint "
                                             f"{unknown[0]!r}", element="equilibrium")
            lam, free = compliant_multipliers(model, eq.q, eq.lam, compliance, rank_tol=rank_tol)
        states = self_stress_states(model, eq.q, rank_tol=rank_tol, states=free)
        if states and self_stress == "refuse":
            st = states[0]
            names = ", ".join(repr(n) for n in st["constraints"])
            raise UndeterminedSelfStress(
                f"redundant constraints {names} carry a self-stress that statics cannot "
                f"determine: every λ + t·μ balances the loads and the reduced stiffness changes "
                f"with t ({st['stiffness_change']:.3g} of the constraint stiffness per unit μ), so "
                f"a verdict would depend on an arbitrary choice; give them a compliance (a stiff "
                f"spring instead of one joint, or equilibrium(model, compliance={{name: c}}))",
                element=st["constraints"][0])
        if states:
            notes.append("multipliers not determined by statics: self-stress in "
                         + "; ".join(", ".join(s["constraints"]) for s in states))
    if lam is not eq.lam:
        eq = dataclasses.replace(eq, lam=lam, reactions=reaction_records(model, lam),
                                 tolerances={**eq.tolerances, "compliance": dict(compliance)})
    static = static_stability(model, eq.q, eq.lam, rank_tol=rank_tol)
    alt = None
    if static["verdict"] == "unstable":
        gyro = _gyroscopic(model, eq.q)
        static = dataclasses.replace(static, gyroscopic=gyro)
        what = ("gyroscopic forces may stabilize it" if gyro else
                "a divergence for any mass and damping" if static["index"] % 2 or
                not static["symmetric"] else "a divergence: the potential energy is not a minimum")
        msg = (f"the equilibrium found is statically unstable ({static['index']} direction(s) of "
               f"negative stiffness; {what})")
        if offer_stable and not gyro:
            alt = stable_alternative(model, eq, opts or {})
            if alt is not None:
                msg += (f"; a stable rest position exists ({alt.method}), offered as "
                        f"eq.stable_alternative")
        notes.append(msg)
        if not gyro:
            warnings.warn(msg, StaticInstabilityWarning, stacklevel=3)
    direction = static.get("direction")
    record = dataclasses.replace(
        static, direction=None if direction is None else [float(x) for x in direction],
        self_stress_tol=SELF_STRESS_TOL)
    return dataclasses.replace(eq, static=record, notes=tuple(notes), stable_alternative=alt,
                               self_stress=tuple({"constraints": s["constraints"],
                                                  "stiffness_change": s["stiffness_change"]}
                                                 for s in states))


def _gyroscopic(model, q) -> bool:
    """Whether the velocity Jacobian has a skew-symmetric (gyroscopic) part at q."""
    _, C = model.force_jacobians(q)
    if not C.nnz:
        return False
    skew = abs(C - C.T).max()
    return bool(skew > 1e-12 * abs(C).max())


def stable_alternative(model, eq, opts):
    """A statically stable equilibrium other than ``eq``: the one the load continuation from
    the unloaded state reaches from the case's positions, else the one reached by descending
    from ``eq`` along its unstable direction (each side) and following the unbalanced force
    until the tangent stiffness is positive, then Newton.  None when neither finds one."""
    from .loads import continue_loads, has_loads
    from .newton import Stall, newton, settings_for, static_multipliers
    from .result import finish
    from .stiffness import static_stability

    kw = {k: opts.get(k, d) for k, d in (("tol", 1e-12), ("xtol", None), ("floor_tol", 1e-8),
                                          ("max_iter", 50), ("rank_tol", 1e-10))}
    s = settings_for(model, model.q_init, **kw)

    def accept(sol, how):
        if s.scales.size(sol.q - eq.q) <= 1e-6:
            return None
        st = static_stability(model, sol.q, static_multipliers(model, sol.q, s),
                              rank_tol=s.rank_tol)
        if st["verdict"] != "stable":
            return None
        alt = finish(model, sol.q, s, iterations=sol.iterations, correction=sol.correction,
                     method=how, path={"start": "stable alternative"})
        return dataclasses.replace(alt, static=dataclasses.replace(st, direction=None))

    if has_loads(model):
        try:
            sol, _ = continue_loads(model, model.q_init, s)
            found = accept(sol, "load continuation from the unloaded state")
            if found is not None:
                return found
        except (Stall, MbseigError):
            pass
    v = np.asarray(eq.static.get("direction") if eq.static and
                   eq.static.get("direction") is not None else
                   static_stability(model, eq.q, eq.lam, rank_tol=s.rank_tol)["direction"])
    for sign in (1.0, -1.0):
        q = _descend(model, eq.q, sign * v, s)
        if q is None:
            continue
        try:
            sol = newton(model, q, s, prove=False)
        except (Stall, MbseigError):
            continue
        found = accept(sol, "descent from the unstable equilibrium along its unstable direction")
        if found is not None:
            return found
    return None


DESCENT_STEPS = 60  # steps of the descent before it gives up


DESCENT_STEP = 0.05  # step of the descent in the model's scales


def _descend(model, q, v, s):
    """From q along v, then along the unbalanced force, until the tangent stiffness is positive
    (the start of a Newton that ends at a stable equilibrium); None when it never is."""
    from .position import position_solve
    from .stiffness import static_stability

    size = s.scales.size(v)
    if not size:
        return None
    d = v * (DESCENT_STEP / size)
    for _ in range(DESCENT_STEPS):
        q, _ = position_solve(model, q + d, s.scales, tol=s.tol, max_iter=20, prove=False)
        if q is None:
            return None
        lam = static_multipliers(model, q, s)
        if static_stability(model, q, lam, rank_tol=s.rank_tol)["verdict"] == "stable":
            return q
        r = model.generalized_force(q) - model.phi_q(q).T @ lam
        size = s.scales.size(r)
        if not size:
            return None
        d = r * (DESCENT_STEP / size)
    return None
