"""Posture, range of motion, joint reactions and actuator effort at an equilibrium.

Driven by the case's ``[report]`` table (README, "Case files")::

    [report]
    actuator = ["actuator", "actuator lock"]      # elements whose force is the actuator effort
    [[report.angles]]                             # joint angles and their range of motion
    name = "MCP"
    bodies = ["ground", "proximal"]               # same definition as a torsional spring
    sense = "cw"
    range = [0, 90]                               # degrees
    [[report.pins]]                               # pin reactions by outboard statics
    name = "PIP"
    point = "B"
    outboard = ["middle", "distal"]

An angle is θ = s·atan2(a × b, a · b) from the direction of the first body (or the ground
direction) to the second, s = +1 ccw, −1 cw.  A pin reaction is the force the inboard side
exerts on the outboard bodies through the pin, from their static balance:

    R = −Σ_{b ∈ outboard} ( m_b g + follower loads on b + attach-joint forces on b )

so it counts gravity, follower forces and ``attach`` joints of the outboard bodies; other loads on
them (springs to body markers, constant point forces) are not counted, so declare pins only
where those three are the only loads (tests/test_hand_device.py checks the global balance).
Element names in ``actuator`` that are disabled by the configuration are skipped.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
)
from .result import solved

__all__ = ["posture", "reactions", "actuator_effort", "rom_flags", "pin_reactions",
           "reaction_forces"]


# ---------------------------------------------------------------------------------------------
def posture(model, q) -> list[dict]:
    """Joint angles (degrees) at q with their range of motion and whether they are inside it."""
    out = []
    for a in model.report.get("angles", []):
        deg = math.degrees(a["driver"].angle(q))
        rng = a["range_deg"]
        row = {"name": a["name"], "angle_deg": deg, "range_deg": rng, "in_range": True,
               "margin_deg": None}
        if rng is not None:
            row["margin_deg"] = min(deg - rng[0], rng[1] - deg)
            row["in_range"] = row["margin_deg"] >= 0.0
        out.append(row)
    return out


def rom_flags(model, q) -> list[str]:
    """Names of the joints outside their range of motion at q (empty: all inside)."""
    return [p["name"] for p in posture(model, q) if not p["in_range"]]


def _constraint_multipliers(model, lam):
    out, k = {}, 0
    for c in getattr(model, "constraints", ()):
        out[c.name] = (c, np.asarray(lam[k:k + c.n_eq], float))
        k += c.n_eq
    return out


def reaction_forces(model, eq) -> list[dict]:
    """Per constraint element, at the equilibrium: its multipliers λ, what they carry as the
    element states it (:meth:`mbseig.model.base.Constraint.reaction`: the axial force of a rigid
    length, the force on the point of a fixed/slider/attach joint, the torque of a driver, ...)
    under its own key and as ``reaction`` {key, label, value, unit}, and the force −Φ_qᵀλ it
    exerts on each point (``forces``: point → components).  The one table of reactions that
    ``mbseig check``, ``mbseig modes --reactions`` and the reports print."""
    model = solved(model, eq)
    names = model.coordinate_names
    rows = []
    for name, (c, lam) in _constraint_multipliers(model, eq.lam).items():
        forces: dict = {}
        for i, val in zip(c.idx, -(c.jac(eq.q).T @ lam)):
            point, _, axis = names[i].rpartition(".")
            forces.setdefault(point, {})[axis] = float(val) + 0.0  # + 0.0: no "-0" in reports
        r = c.reaction(eq.q, lam)
        rows.append({"element": name, "multipliers": [float(x) for x in lam], r["key"]: r["value"],
                     "reaction": r,
                     "forces": {p: [v.get(ax, 0.0) for ax in "xyz"[:model.dimension]]
                                for p, v in forces.items()}})
    return rows


def pin_reactions(model, eq) -> list[dict]:
    """Force [N] that the inboard side exerts on the outboard bodies through each pin."""
    model = solved(model, eq)
    rep = model.report
    gravity = rep.get("gravity")
    g = np.zeros(2) if gravity is None else np.asarray(gravity, dtype=float)
    mult = _constraint_multipliers(model, eq.lam)
    body_of = model.report.get("element_body", {})
    rows = []
    for pin in rep.get("pins", []):
        S = set(pin["outboard"])
        ext = sum((model.bodies[b]["mass"] * g for b in S), np.zeros(2))
        for f in model.forces:
            if isinstance(f, FollowerForce) and body_of.get(f.name) in S:
                ext = ext + f.magnitude * f.stacked(eq.q)[2:]
        for name, (c, lam) in mult.items():
            if isinstance(c, LinearConstraint) and body_of.get(name) in S:
                ext = ext + lam  # Φ = r_P − r_body: the constraint force on the body point is +λ
        R = -ext
        rows.append({"name": pin["name"], "point": pin["point"], "force": [float(x) for x in R],
                     "magnitude": float(np.linalg.norm(R))})
    return rows


def actuator_effort(model, eq) -> list[dict]:
    """Tension [N] of each actuator element at equilibrium (spring: k (l − l0); lock: 2 λ L)."""
    model = solved(model, eq)
    rows = []
    mult = _constraint_multipliers(model, eq.lam)
    for kind, index, label in model.report.get("actuator", []):
        if kind == "force":
            f = model.forces[index]
            if not isinstance(f, SpringDamper):
                continue
            length = float(np.linalg.norm(f.diff(eq.q)))
            rows.append({"element": f.name, "kind": "spring", "length": length,
                         "free_length": f.free_length,
                         "tension": f.stiffness * (length - f.free_length)})
        else:
            c = model.constraints[index]
            lam = mult[c.name][1]
            if isinstance(c, DistanceConstraint):
                rows.append({"element": c.name, "kind": "locked length", "length": c.length,
                             "tension": 2.0 * float(lam[0]) * c.length})
    return rows


def reactions(model, eq) -> dict:
    """Posture, pin reactions, constraint forces, actuator effort and driver records."""
    model = solved(model, eq)
    return {
        "posture": posture(model, eq.q),
        "out_of_range": rom_flags(model, eq.q),
        "pins": pin_reactions(model, eq),
        "constraints": reaction_forces(model, eq),
        "actuator": actuator_effort(model, eq),
        "drivers": [dict(d) for d in model.drivers],
    }
