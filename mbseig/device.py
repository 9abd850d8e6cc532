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

from .case import _Fields
from .errors import CaseError
from .model.driver import AngleDriver
from .model.elements import DistanceConstraint, FollowerForce, LinearConstraint, SpringDamper

__all__ = ["parse_report", "posture", "reactions", "actuator_effort", "rom_flags"]

_REPORT_KEYS = {"actuator", "angles", "pins", "studies"}
_STUDY_KEYS = {"title", "config", "sweep", "range", "count", "lines", "xtol_rel", "compare"}


def parse_report(table, builder) -> dict:
    """Validate a ``[report]`` table against the model being built (``case._Builder``)."""
    if not isinstance(table, dict):
        raise CaseError("[report] must be a table", element="report")
    unknown = sorted(set(table) - _REPORT_KEYS)
    if unknown:
        raise CaseError(f"unknown field {unknown[0]!r} ({', '.join(sorted(_REPORT_KEYS))})",
                        element="report")
    names = builder.params
    out = {"angles": [], "pins": [], "actuator": [], "studies": [], "gravity": builder._gravity(),
           "element_body": dict(builder.element_body)}
    act = table.get("actuator", [])
    act = [act] if isinstance(act, str) else act
    if not isinstance(act, list) or not all(isinstance(a, str) for a in act):
        raise CaseError("actuator must be an element name or a list of names", element="report.actuator")
    declared = {item.get("name") for sec in ("joints", "forces")
                for item in builder.data.get(sec, []) if isinstance(item, dict)}
    for a in act:
        if a in builder.named:
            out["actuator"].append(builder.named[a])
        elif a not in declared:
            raise CaseError(f"unknown element {a!r}", element="report.actuator")
    for k, item in enumerate(_table_list(table.get("angles", []), "report.angles")):
        f = _Fields(item, f"report.angles[{k}]", names)
        name = f.text("name")
        stacked, sense = builder._angle_pair(f)
        rng = f.vec("range", 2, None)
        f.done()
        if rng is not None and not rng[0] < rng[1]:
            raise f.error(f"range must be [min, max] in degrees with min < max, got {list(rng)}")
        out["angles"].append({"name": name, "driver": AngleDriver(name, stacked, 0.0, sense),
                              "range_deg": None if rng is None else (float(rng[0]), float(rng[1]))})
    for k, item in enumerate(_table_list(table.get("pins", []), "report.pins")):
        f = _Fields(item, f"report.pins[{k}]", names)
        name = f.text("name")
        point = f.text("point")
        outboard = f.raw("outboard")
        f.done()
        if point not in builder.point_index:
            raise f.error(f"unknown point {point!r}")
        if not isinstance(outboard, list) or not outboard:
            raise f.error("outboard must be a non-empty list of body names")
        for b in outboard:
            builder._body(f, b)
        out["pins"].append({"name": name, "point": point, "outboard": list(outboard)})
    configs = builder.data.get("configurations", {})
    for k, item in enumerate(_table_list(table.get("studies", []), "report.studies")):
        label = f"report.studies[{k}]"
        unknown = sorted(set(item) - _STUDY_KEYS)
        if unknown:
            raise CaseError(f"unknown field {unknown[0]!r}", element=label)
        if item.get("config") is not None and item["config"] not in configs:
            raise CaseError(f"unknown configuration {item['config']!r}", element=label)
        if "compare" in item:
            if item["compare"] != "constraint_stiffness":
                raise CaseError("compare must be \"constraint_stiffness\"", element=label)
        else:
            if item.get("sweep") not in builder.params:
                raise CaseError(f"sweep must name a parameter, got {item.get('sweep')!r}", element=label)
            rng, count = item.get("range"), item.get("count")
            if (not isinstance(rng, list) or len(rng) != 2
                    or not all(isinstance(x, (int, float)) for x in rng) or rng[0] == rng[1]):
                raise CaseError("range must be [start, stop] with start ≠ stop", element=label)
            if not isinstance(count, int) or count < 2:
                raise CaseError("count must be an integer ≥ 2", element=label)
            lines = item.get("lines", {})
            if not isinstance(lines, dict) or not all(
                    n in builder.params and isinstance(v, list) and v for n, v in lines.items()):
                raise CaseError("lines must be {parameter = [values, ...]}", element=label)
        out["studies"].append(dict(item))
    return out


def _table_list(value, label):
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise CaseError("must be an array of tables", element=label)
    return value


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
    for c in model.constraints:
        out[c.name] = (c, lam[k:k + c.n_eq])
        k += c.n_eq
    return out


def element_forces(model, eq) -> list[dict]:
    """Every constraint's multiplier and what it carries: axial force (tension +) of a rigid
    length or distance joint, the force vector on the point of a fixed/slider/attach joint, the
    torque of a driver."""
    rows = []
    for name, (c, lam) in _constraint_multipliers(model, eq.lam).items():
        row = {"element": name, "multipliers": [float(x) for x in lam]}
        if isinstance(c, DistanceConstraint):
            row["axial_force"] = 2.0 * float(lam[0]) * c.length
        elif isinstance(c, LinearConstraint):
            row["force"] = [float(x) for x in -(c.G.T @ lam)]
        elif isinstance(c, AngleDriver):
            row["torque"] = -float(lam[0])
        rows.append(row)
    return rows


def pin_reactions(model, eq) -> list[dict]:
    """Force [N] that the inboard side exerts on the outboard bodies through each pin."""
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
    return {
        "posture": posture(model, eq.q),
        "out_of_range": rom_flags(model, eq.q),
        "pins": pin_reactions(model, eq),
        "constraints": element_forces(model, eq),
        "actuator": actuator_effort(model, eq),
        "drivers": [dict(d) for d in model.drivers],
    }
