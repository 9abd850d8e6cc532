"""Inverse statics: set an actuator from a commanded posture (docs/design.md, "Equilibrium").

A case may hold an ``angle_driver`` joint with ``sets = [...]`` naming the actuator elements it
commands.  The driver is then used only in a pre-solve and is not part of the final model:

1. Pre-solve: the model with the driver (Φ_d = θ − θ* = 0) and with the commanded elements
   released (a spring's force removed, a locking distance joint left out).  Its equilibrium q*
   is the commanded posture and the driver multiplier λ_d is the effort the actuator must supply.
2. A commanded spring (``spring`` / ``spring_damper``): its free length l0 is the root of
   λ_d(l0) = 0 in the model with the driver and the spring, i.e. the free length at which the
   spring alone holds the posture and the driver carries nothing.  λ_d is affine in l0 when the
   driver fixes the spring's end points (the crank-slider of the finger device), so the secant
   iteration stops after one or two steps; in general it converges superlinearly.  Stopping test:
   |λ_d| ≤ ``tol`` · |λ_d at zero actuator force|.
3. A commanded ``distance`` joint (an actuator locked at its length): its length is the distance
   between its points at q*.

A command is a *position command*: it is resolved on the device without its follower loads
(force elements with a ``magnitude``, e.g. a tendon load at the fingertip), and the final model
applies them to the actuator as set.  So the setting is the one the unloaded device needs, and
it is held as the load changes: the series-elastic spring of an actuator stays in the load path
and the posture moves with the load (hand_device.md, C4).  Gravity is part of the device and is
kept.  The record names the loads left out (``unloaded``).

The final model has no driver, the commanded elements set, and q* as its initial guess, so its
equilibrium is the commanded posture (to the stopping tolerance).  The record (one dict per
driver) names the driver, the target angle, the effort, the free length or locked length and the
iterations, and is kept on ``Model.drivers`` for reports.
"""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np

from ..errors import EquilibriumError
from ..model.driver import check_command
from .cache import Memo
from .linalg import NewtonMatrix, augmented

__all__ = ["resolve_commands", "reuse_commands", "command_settings", "held_tension"]


def resolve_commands(model, equilibrium, *, tol=1e-12, max_iter=30, hint=None, cache=None):
    """The model with every pending command (``model.commands``) resolved: commanded elements
    set, ``drivers`` holding one record per driver, ``q_init`` at the commanded posture.

    equilibrium(model, q_init=...) is the static solve
    (:func:`mbseig.statics.newton.solve_statics`).
    hint : a resolved model of the same family (a neighbouring point of a sweep): its commanded
        posture starts the first static solve and its free lengths the secant, so that a sweep
        continues from the previous point instead of from the reference configuration.  The
        result is the same to the tolerances (the secant still runs until the driver's effort
        vanishes); a hint whose elements differ is ignored.
    cache : a dict kept across the calls of one family (a sweep line): the pre-solve of the
        released device is keyed by the exact content of its model (pickled elements and
        constant forces) and reused when a later model's released device is identical — the
        swept parameter enters only the commanded element (an actuator stiffness) — since a
        solve of the same model from its own equilibrium returns that equilibrium.
    """
    drivers = model.commands
    hint = hint if hint is not None and _same_elements(model, hint) else None

    def make_model(forces, constraints, q_init=None):
        return dataclasses.replace(model, forces=tuple(forces), constraints=tuple(constraints),
                                   q_init=model.q_init if q_init is None else q_init, commands=())

    forces, constraints = list(model.forces), list(model.constraints)
    followers = {k for k, f in enumerate(forces) if f.scalable_load}
    q_guess, records = (None if hint is None else np.asarray(hint.q_init, float)), []
    for driver, targets in drivers:
        springs, locks = check_command(driver, targets, forces, constraints)
        lock_idx = {k for _, k, _ in locks}
        pre_constraints = [c for k, c in enumerate(constraints) if k not in lock_idx] + [driver]
        row = sum(c.n_eq for c in pre_constraints) - 1  # the driver's multiplier (last row)

        def solve(pre_forces, q_init, pre_constraints=pre_constraints, driver=driver, row=row):
            model = make_model(pre_forces, pre_constraints, q_init)
            try:
                eq = equilibrium(model, q_init=q_init)
            except EquilibriumError as exc:
                raise EquilibriumError(f"inverse statics (pre-solve) failed: {exc.message}",
                                       element=driver.name) from None
            return eq, float(eq.lam[row])

        spring_k = springs[0][1] if springs else None
        released = [f for k, f in enumerate(forces) if k != spring_k and k not in followers]
        key = None
        if cache is not None:
            try:
                key = pickle.dumps((driver.name, released, pre_constraints, model.g_const,
                                    model.length_scale, model.coordinate_names))
            except (pickle.PicklingError, TypeError, AttributeError):
                key = None
        if key is not None and key in cache:
            eq, lam0 = cache[key]
        else:
            eq, lam0 = solve(released, q_guess)
            if key is not None:
                if len(cache) >= 4:
                    cache.pop(next(iter(cache)))
                cache[key] = (eq, lam0)
        rec = {"driver": driver.name, "angle_target": driver.angle_target,
               "effort": -lam0, "effort_unit": "N m (torque in the driver's sense)",
               "iterations": 0, "tol": tol, "sets": [],
               "unloaded": [forces[k].name for k in sorted(followers)]}

        def with_spring(l0, spring_k=spring_k):
            """The pre-solve forces with the commanded spring at free length l0."""
            return [dataclasses.replace(f, free_length=l0) if k == spring_k else f
                    for k, f in enumerate(forces) if k not in followers]

        if spring_k is not None:
            spring = forces[spring_k]
            l_star = float(np.linalg.norm(spring.diff(eq.q)))
            a_l0, a_lam = l_star, lam0  # zero tension at q*: λ_d is the released effort
            b_l0 = _newton_free_length(make_model, with_spring, pre_constraints, eq, row, l_star,
                                       lam0)
            if b_l0 is None:
                b_l0 = l_star * (1.0 - 1e-3)
                if hint is not None:  # the neighbour's free length: a secant step or two from here
                    h = float(hint.forces[spring_k].free_length)
                    if np.isfinite(h) and h > 0 and abs(h - l_star) > 1e-9 * l_star:
                        b_l0 = h
            eq_b, b_lam = solve(with_spring(b_l0), eq.q)
            it, scale = 1, max(abs(lam0), np.finfo(float).tiny)
            while abs(b_lam) > tol * scale:
                if it >= max_iter or b_lam == a_lam:
                    raise EquilibriumError(
                        f"inverse statics: free length of {spring.name} not found after {it} "
                        f"secant steps (driver effort {b_lam:.3g})", element=driver.name)
                new = b_l0 - b_lam * (b_l0 - a_l0) / (b_lam - a_lam)
                a_l0, a_lam = b_l0, b_lam
                b_l0 = new
                eq_b, b_lam = solve(with_spring(b_l0), eq_b.q)
                it += 1
            forces[spring_k] = dataclasses.replace(spring, free_length=b_l0)
            length = float(np.linalg.norm(spring.diff(eq_b.q)))
            rec["iterations"] = it
            rec["residual_effort"] = -b_lam
            rec["sets"].append({"element": spring.name, "free_length": b_l0, "length": length,
                                "tension": spring.stiffness * (length - b_l0)})
            eq = eq_b
        for _, k, _ in locks:
            c = constraints[k]
            length = float(np.linalg.norm(c.diff(eq.q)))
            constraints[k] = dataclasses.replace(c, length=length)
            rec["sets"].append({"element": c.name, "length": length})
        q_guess = eq.q
        records.append(rec)
    return dataclasses.replace(make_model(forces, constraints, q_guess), drivers=tuple(records))


def _newton_free_length(make_model, with_spring, pre_constraints, eq, row, l_star, lam0):
    """The free length from Newton's step on the driver's effort λ_d(l0) at the released
    equilibrium (q*, λ*), where the spring at l0 = l* has no tension and λ_d = λ_0:
    l0 = l* − λ_0 / (dλ_d/dl0).  The slope from the Newton matrix of the device with the spring
    (its stiffness at zero tension), A [dq; dλ] = [∂g/∂l0; 0], ∂g/∂l0 by a difference of the
    spring's force (affine in l0, so exact to rounding).  When the driver holds the spring's end
    points λ_d is affine in l0 and this is its root: the first solve with the spring then ends
    the iteration.  None (the secant starts as before) when the matrix is singular or the slope
    is not usable."""
    m_star = make_model(with_spring(l_star), pre_constraints)
    h = 1e-3 * l_star
    m_h = make_model(with_spring(l_star + h), pre_constraints)
    try:
        with np.errstate(all="ignore"):
            g_l = (m_h.generalized_force(eq.q) - m_star.generalized_force(eq.q)) / h
            A, _ = augmented(Memo(m_star), eq.q, eq.lam)  # (dense for a small model)
            x, e = NewtonMatrix(A).solve(np.concatenate([g_l, np.zeros(A.shape[0] - g_l.size)]))
    except (EquilibriumError, ArithmeticError, ValueError):
        return None
    slope = float(x[m_star.n + row])
    if (not np.isfinite(slope) or slope == 0.0
            or float(np.linalg.norm(e)) > 1e-8 * float(np.linalg.norm(g_l))):
        return None
    l0 = l_star - lam0 / slope
    return l0 if np.isfinite(l0) and l0 > 0 else None


def _same_elements(model, other):
    return (len(model.forces) == len(other.forces)
            and len(model.constraints) == len(other.constraints)
            and [f.name for f in model.forces] == [f.name for f in other.forces]
            and [c.name for c in model.constraints] == [c.name for c in other.constraints]
            and np.shape(getattr(other, "q_init", None)) == np.shape(model.q_init))


def reuse_commands(model, resolved):
    """``model`` (with pending commands) set as ``resolved`` was: the commanded springs' free
    lengths and distance joints' lengths copied element by element, the drivers' records and
    the commanded posture taken over.  For a family of models that differ only in parameters
    the commands do not depend on (a sweep that found the settings equal at two values);
    None when the two models do not have the same elements."""
    if (len(model.forces) != len(resolved.forces)
            or len(model.constraints) != len(resolved.constraints)
            or [f.name for f in model.forces] != [f.name for f in resolved.forces]
            or [c.name for c in model.constraints] != [c.name for c in resolved.constraints]):
        return None
    forces, constraints = list(model.forces), list(model.constraints)
    for _, targets in model.commands:
        for kind, k, _ in targets:
            if kind == "force":
                forces[k] = dataclasses.replace(forces[k],
                                                free_length=resolved.forces[k].free_length)
            else:
                constraints[k] = dataclasses.replace(constraints[k],
                                                     length=resolved.constraints[k].length)
    return dataclasses.replace(model, forces=tuple(forces), constraints=tuple(constraints),
                               q_init=resolved.q_init, commands=(), drivers=resolved.drivers)


def command_settings(model) -> tuple:
    """The values a resolved model's commands set (free lengths and lengths), in order."""
    return tuple(s.get("free_length", s.get("length")) for d in model.drivers for s in d["sets"])


def held_tension(model, prev, *, tol=1e-12, posture_tol=1e-10, cache=None):
    """``model`` (its one command pending) set from ``prev`` (resolved at another value of a
    parameter that enters the commanded spring's stiffness alone, and perhaps damping values and
    follower loads, which do not enter the device at rest), or None.

    The same tension T at the same posture q* gives the same forces, so ``prev``'s posture and
    tension solve the command for any stiffness k of the spring: its free length is
    l₀ = l* − T/k (the root the resolve's secant finds where the root is unique, as on the
    crank-slider of the finger device, whose driver holds the spring's ends).  Taken only when
    every other element gives ``prev``'s forces at rest (:func:`_same_at_rest`), and checked
    as :func:`resolve_commands` checks its own result: at q*, on the device with the driver
    and without follower loads, the driver's effort (unique: no redundant constraint) is at
    most ``tol`` × the released effort and the posture is in equilibrium (residual ≤
    ``posture_tol`` × the forces).  Else the command is resolved (by the caller).
    ``cache``: a dict kept by the caller across the values of one sweep line, which holds the
    device's Φ_q at q* (the constraints, the driver and q* are ``prev``'s at every value, so it
    is the same matrix)."""
    if prev is None or len(model.commands) != 1 or len(prev.drivers) != 1:
        return None
    driver, targets = model.commands[0]
    rec = prev.drivers[0]
    springs = [t for t in targets if t[0] == "force"]
    if len(springs) != 1 or len(targets) != 1 or len(rec["sets"]) != 1:
        return None
    k = springs[0][1]
    spring, old = model.forces[k], prev.forces[k]
    if (len(model.forces) != len(prev.forces) or model.constraints != prev.constraints
            or any(not _same_at_rest(a, b)
                   for j, (a, b) in enumerate(zip(model.forces, prev.forces, strict=True))
                   if j != k)
            or spring.diff is not old.diff or not spring.stiffness > 0
            or model.g_const is not prev.g_const or model.mass is not prev.mass):
        return None
    length, tension = rec["sets"][0]["length"], rec["sets"][0]["tension"]
    l0 = length - tension / spring.stiffness
    forces = list(model.forces)
    forces[k] = dataclasses.replace(spring, free_length=l0)
    q = np.asarray(prev.q_init, float)
    device = dataclasses.replace(model, forces=tuple(f for f in forces if not f.scalable_load),
                                 constraints=model.constraints + (driver,), commands=())
    with np.errstate(all="ignore"):
        g = _device_force(device, prev, driver, q, k, cache)
        G = _device_phi_q(device, prev, driver, q, cache)
        pinv, rank = _least_squares(G.T, cache)
        lam = pinv @ g
        r = g - G.T @ lam
        scale = max(float(np.max(np.abs(g))), float(np.max(np.abs(G.T) @ np.abs(lam))))
    effort = abs(float(rec["effort"]))
    if not (rank == G.shape[0]  # the driver's effort unique (no redundant constraint)
            and abs(lam[-1]) <= tol * max(effort, np.finfo(float).tiny)
            and float(np.max(np.abs(r))) <= posture_tol * scale and l0 > 0):
        return None
    length_now = float(np.linalg.norm(spring.diff(q)))
    record = {**rec, "iterations": 0, "residual_effort": -float(lam[-1]),
              "sets": [{"element": spring.name, "free_length": l0, "length": length_now,
                        "tension": spring.stiffness * (length_now - l0)}]}
    return dataclasses.replace(model, forces=tuple(forces), q_init=q, commands=(),
                               drivers=(record,))


def _same_at_rest(a, b) -> bool:
    """Force elements a and b give the same forces on the device at rest: the same element; two
    follower loads (the device leaves them out); or one element whose damping value alone
    differs (it multiplies a zero rate at rest: every other field is the same object, as the
    lean updates of a sweep or of the samples form them)."""
    if a is b:
        return True
    if type(a) is not type(b) or not dataclasses.is_dataclass(a):
        return False
    if a.scalable_load and b.scalable_load:
        return True
    return all(getattr(a, f.name) is getattr(b, f.name)
               for f in dataclasses.fields(a) if f.name != "damping")


def _device_force(device, prev, driver, q, k, cache):
    """g at q of the device: its forces other than the commanded spring (the same elements at
    every value of the line: kept in ``cache`` for the same ``prev``, driver and q) plus the
    spring's own, which is all that changes with its stiffness."""
    spring = device.forces[[j for j, f in enumerate(prev.forces) if not f.scalable_load].index(k)]
    rest = None
    if cache is not None:
        hit = cache.get("device_force")
        if hit is not None and hit[0] is prev and hit[1] is driver and hit[2] == q.tobytes():
            rest = hit[3]
    if rest is None:
        others = tuple(f for j, f in enumerate(prev.forces) if j != k and not f.scalable_load)
        rest = dataclasses.replace(device, forces=others).generalized_force(q)
        if cache is not None:
            cache["device_force"] = (prev, driver, q.tobytes(), rest)
    g = rest.copy()
    np.add.at(g, spring.idx, spring.force(q, np.zeros(q.size)))
    return g


def _least_squares(A, cache):
    """(A⁺, rank) with ``numpy.linalg.lstsq``'s cut-off (singular values above
    eps·max(m, n)·σ_max): A⁺ g is the minimum-norm least-squares solution lstsq gives.  Kept in
    ``cache`` for the same array A (the device's Φ_qᵀ, the same at every value of a line)."""
    hit = None if cache is None else cache.get("device_pinv")
    if hit is not None and hit[0] is A.base and hit[0] is not None:
        return hit[1], hit[2]
    U, sv, Vh = np.linalg.svd(A, full_matrices=False)
    cut = np.finfo(float).eps * max(A.shape) * (sv[0] if sv.size else 0.0)
    rank = int(np.sum(sv > cut))
    pinv = (Vh[:rank].T / sv[:rank]) @ U[:, :rank].T
    if cache is not None:
        cache["device_pinv"] = (A.base, pinv, rank)
    return pinv, rank


def _device_phi_q(device, prev, driver, q, cache):
    """Φ_q at q of the device (``prev``'s constraints and the driver): kept in ``cache`` for
    the same ``prev``, driver and q (then the same constraint elements at the same q)."""
    if cache is not None:
        hit = cache.get("device_phi_q")
        if (hit is not None and hit[0] is prev and hit[1] is driver
                and hit[2] is device.constraints[-1]
                and hit[3] == q.tobytes() and len(hit[4]) == len(device.constraints)
                and all(a is b for a, b in zip(hit[4], device.constraints, strict=True))):
            return hit[5]
    G = np.asarray(device.phi_q(q, dense=True))
    if cache is not None:
        cache["device_phi_q"] = (prev, driver, device.constraints[-1], q.tobytes(),
                                 device.constraints, G)
    return G
