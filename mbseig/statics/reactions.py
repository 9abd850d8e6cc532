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
import scipy.sparse as sp

from ..model.elements import (
    DistanceConstraint,
    FollowerForce,
    LinearConstraint,
    SpringDamper,
)
from ..model.spatial_body import FRAME_SIZE, point_matrix
from ..model.spatial_joints import frame_wrench
from .reaction_bounds import EPS, bounded, linear_map, multiplier_error, zeroed
from .result import solved

__all__ = ["posture", "reactions", "actuator_effort", "rom_flags", "pin_reactions",
           "reaction_forces", "multiplier_error"]


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
    ``mbseig check``, ``mbseig modes --reactions`` and the reports print.

    Each row also says where it acts (:func:`_where`): ``kind`` (``joint``: a spatial joint,
    force and moment on one body about the joint point; ``shared point``: a basic point a
    spatial body carries, the force on that body there; ``on body``: another spatial
    constraint, its wrench about the body's origin; ``body``: a planar body's rigid length;
    ``constraint``: point forces only; ``internal``: a spatial body's normalization conditions
    (u, v, w unit and orthogonal), no force at any joint), ``on`` (the body), ``at`` (global,
    at the equilibrium), ``force`` / ``moment`` in global axes, ``force_body`` /
    ``moment_body`` in the body's axes (spatial: u, v, w, parallel to global x, y, z at the
    reference; planar: x along its first → second point, y normal, counter-clockwise) and
    ``error``, each value's bound (:func:`multiplier_error`): a value within it is set to 0."""
    model = solved(model, eq)
    names, dim = model.coordinate_names, "xyz"[:getattr(model, "dimension", 3)]
    dlam = multiplier_error(model, eq)["lambda_bound"]
    # the configuration's uncertainty: the last Newton correction (directions; × ℓ: positions)
    ddir = max(float(getattr(eq, "correction", 0.0) or 0.0), 8 * EPS)
    unc = (dlam, ddir * float(getattr(model, "length_scale", 1.0)), ddir)
    rows = []
    for name, (c, lam) in _constraint_multipliers(model, eq.lam).items():
        gen, gen_err = bounded(-_dense(c.jac(eq.q)).T, lam, dlam)
        forces, errors = {}, {}
        for i, val, err in zip(c.idx, gen, gen_err, strict=True):
            point, _, axis = names[i].rpartition(".")
            forces.setdefault(point, {})[axis] = val
            errors.setdefault(point, {})[axis] = err
        value, value_err = _reaction_value(c, eq.q, lam, dlam)
        r = {**c.reaction(eq.q, lam), "value": value}
        where = _where(model, c, eq.q, lam, unc, forces, errors)
        if where["kind"] == "joint":  # the wrench with its term-by-term rounding bound
            value = r["value"] = where["force"] + where["moment"]
            value_err = where["error"]["force"] + where["error"]["moment"]
        if "at" in where:  # a position within the statics' tolerance of 0 is 0
            where["at"] = zeroed(where["at"], [unc[1]] * len(where["at"]))
        rows.append({"element": name, "multipliers": bounded(np.eye(lam.size), lam, dlam)[0],
                     r["key"]: value, "reaction": r, "reaction_error": value_err,
                     "lambda_bound": dlam,
                     "forces": {p: [v.get(ax, 0.0) for ax in dim] for p, v in forces.items()},
                     "forces_error": {p: [v.get(ax, 0.0) for ax in dim]
                                      for p, v in errors.items()}, **where})
    return rows


def _reaction_value(c, q, lam, dlam):
    """The element's own reaction (a number or a list, linear in λ) and its bounds."""
    scalar = not isinstance(c.reaction(q, lam)["value"], list)
    def own(x):
        return np.atleast_1d(np.asarray(c.reaction(q, x)["value"], float))

    _, err = bounded(linear_map(own, lam.size), lam, dlam)
    value = zeroed(own(lam), err)
    return (value[0], err[0]) if scalar else (value, err)


# ---------------------------------------------------------------------------------------------
# Where a constraint acts: joint wrenches on bodies, in global and body axes
# ---------------------------------------------------------------------------------------------
def _where(model, c, q, lam, unc, forces, errors) -> dict:
    """Where a constraint acts and its force and moment there (:func:`reaction_forces`)."""
    bodies = getattr(model, "bodies", {}) or {}
    role = c.role or ()
    if role[:1] == ("triad",):  # a frame's rigid-body conditions: internal to its body
        return {"kind": "internal", "on": role[1] if role[1] in bodies else None}
    if c.wrench is not None:  # a spatial joint (model.spatial_joints)
        off, local, body = c.wrench
        z = c.aff(q)
        return _wrench(z[off:off + FRAME_SIZE], c.rows.grad(z)[:, off:off + FRAME_SIZE], lam,
                       unc, local, body)
    if role[:1] == ("carries",) and role[1] in bodies:  # a point a spatial body carries
        return _carried(model, role[1], role[2], c, q, lam, unc)
    if model.dimension == 2:
        return _planar(model, c, bodies, q, forces, errors, unc[2])
    return _on_frame(model, c, q, lam, unc)


def _axes(frame_z):
    """R = [u v w] of a frame vector [r₀; u; v; w]."""
    return np.asarray(frame_z, float).reshape(4, 3)[1:].T


def _dense(J):
    return J.toarray() if sp.issparse(J) else np.asarray(J, float)


def _in_body(R, vec, err, ddir):
    """A global vector in the body axes R, each within ‖global bounds‖₂ + (ddir + 4ε)‖v‖."""
    vec = np.asarray(vec, float)
    bound = float(np.linalg.norm(err)) + (ddir + 4 * EPS) * float(np.linalg.norm(vec))
    return zeroed(R.T @ vec, [bound] * vec.size), [bound] * vec.size


def _wrench(zf, G, lam, unc, local, body, kind="joint"):
    """Force F and moment M (about the body point ``local``) on a spatial body from the
    generalized forces f = −Gᵀλ on its frame zf = [r₀; u; v; w] (:func:`frame_wrench`), G the
    rows' gradient on zf.  Rounding counts every term: |F| ≤ ‖|f_r|‖, |M| ≤ Σ_e ‖e‖ ‖|f_e|‖ +
    ‖r₀ − r_P‖ ‖|f_r|‖ with |f| = |G|ᵀ|λ|; and the moment the position error gives, ‖F‖ δr."""
    fabs = (np.abs(G).T @ np.abs(lam)).reshape(4, 3)
    e = zf.reshape(4, 3)
    rP = point_matrix(local) @ zf
    f_scale = float(np.linalg.norm(fabs[0]))
    m_scale = (sum(float(np.linalg.norm(e[k]) * np.linalg.norm(fabs[k])) for k in (1, 2, 3))
               + float(np.linalg.norm(e[0] - rP)) * f_scale)

    def wrench(x):
        return np.concatenate(frame_wrench(zf, -(G.T @ x), local))
    A = linear_map(wrench, lam.size)
    _, err = bounded(A, lam, unc[0], scale=[f_scale] * 3 + [m_scale] * 3)
    arm = unc[1] * float(np.linalg.norm(A[:3] @ lam))
    err = err[:3] + [e + arm for e in err[3:]]
    return _wrench_row(kind, body, rP, zeroed(wrench(lam), err), err, _axes(zf), unc[2])


def _wrench_row(kind, body, at, values, err, R, ddir) -> dict:
    """The fields of a row with a force and moment (global, then in the body axes R)."""
    fb, fb_err = _in_body(R, values[:3], err[:3], ddir)
    mb, mb_err = _in_body(R, values[3:], err[3:], ddir)
    return {"kind": kind, "on": body, "at": [float(x) for x in at], "force": values[:3],
            "moment": values[3:], "force_body": fb, "moment_body": mb,
            "error": {"force": err[:3], "moment": err[3:], "force_body": fb_err,
                      "moment_body": mb_err}}


def _on_frame(model, c, q, lam, unc):
    """Any other spatial constraint on a body whose whole frame is coordinates it acts on (a
    contact, a rolling wheel): its force and moment on that body, about the body's origin."""
    cols = {int(i): k for k, i in enumerate(c.idx)}
    for b, rec in model.bodies.items():
        frame = rec.get("frame")
        C = np.zeros((0, 0)) if frame is None else np.asarray(frame.C, float)
        if (C.shape[0] != FRAME_SIZE or np.any((C != 0).sum(axis=1) != 1)
                or np.any(C[C != 0] != 1)):
            continue
        qi = frame.idx[np.argmax(C, axis=1)]  # z_k = q[qi_k]: a frame of free coordinates
        if any(int(i) not in cols for i in qi):
            continue
        G = _dense(c.jac(q))[:, [cols[int(i)] for i in qi]]
        return _wrench(frame(q), G, lam, unc, np.zeros(3), b, "on body")
    return {"kind": "constraint", "on": None}


def _carried(model, body, point, c, q, lam, unc):
    """A basic point a spatial body carries, Φ = G (r_P − r_body(ξ)): the force on the body
    there is +Gᵀλ (the point receives −Gᵀλ), no moment; a joint of the bodies carrying it."""
    values, err = bounded(np.asarray(c.G, float).T, lam, unc[0])
    row = _wrench_row("shared point", body, model.points[point](q), values + [0.0] * 3,
                      err + [0.0] * 3, _axes(model.bodies[body]["frame"](q)), unc[2])
    shared = [b for b, r in model.bodies.items() if point in (r.get("carried") or ())]
    return {**row, "point": point, "shared_by": shared}


def _planar(model, c, bodies, q, forces, errors, ddir):
    """A planar constraint's point forces in the axes of the body of each point (its own body
    for a rigid length, ``kind = "body"``; else the first body listing the point)."""
    own = next((b for b, r in bodies.items() if c.name == f"{r.get('label')} (rigid length)"), None)
    out, out_err, which = {}, {}, {}
    for p, comps in forces.items():
        b = own if own and p in bodies[own].get("points", ()) else next(
            (b for b, r in bodies.items() if p in (r.get("points") or ())), None)
        if b is None:
            continue
        pi, pj = bodies[b]["points"]
        d = np.asarray(model.points[pj](q), float) - np.asarray(model.points[pi](q), float)
        ex = d / max(float(np.linalg.norm(d)), 1e-300)
        R = np.column_stack([ex, [-ex[1], ex[0]]])
        vec = [comps.get(ax, 0.0) for ax in "xy"]
        out[p], out_err[p] = _in_body(R, vec, [errors[p].get(ax, 0.0) for ax in "xy"], ddir)
        which[p] = b
    return {"kind": "body" if own else "constraint", "on": own, "forces_body": out,
            "forces_body_error": out_err, "forces_body_on": which}


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
    for kind, index, _label in model.report.get("actuator", []):
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
