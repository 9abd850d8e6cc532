"""Inverse statics: set an actuator from a commanded posture (DESIGN §3).

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

The final model has no driver, the commanded elements set, and q* as its initial guess, so its
equilibrium is the commanded posture (to the stopping tolerance).  The record (one dict per
driver) names the driver, the target angle, the effort, the free length or locked length and the
iterations, and is kept on ``Model.drivers`` for reports.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .errors import CaseError, EquilibriumError
from .model.elements import DistanceConstraint, SpringDamper

__all__ = ["resolve_drivers"]


def resolve_drivers(make_model, forces, constraints, drivers, *, tol=1e-12, max_iter=30):
    """(forces, constraints, q_guess, records) with every driver's commanded elements set.

    make_model(forces, constraints, q_init) builds a :class:`~mbseig.model.Model`; ``drivers`` is a
    list of ``(driver, targets)`` with targets a list of ``("force" | "joint", index, label)``
    into ``forces`` / ``constraints``.
    """
    from .statics import equilibrium

    forces, constraints = list(forces), list(constraints)
    q_guess, records = None, []
    for driver, targets in drivers:
        springs = [t for t in targets if t[0] == "force"]
        locks = [t for t in targets if t[0] == "joint"]
        if len(springs) > 1:
            raise CaseError("an angle_driver can set the free length of one spring only",
                            element=driver.name)
        for kind, k, label in springs:
            if not isinstance(forces[k], SpringDamper) or forces[k].diff.dim == 1:
                raise CaseError(f"sets {label}: only a planar spring or spring_damper can be set",
                                element=driver.name)
        for kind, k, label in locks:
            if not isinstance(constraints[k], DistanceConstraint):
                raise CaseError(f"sets {label}: only a distance joint can be set",
                                element=driver.name)
        lock_idx = {k for _, k, _ in locks}
        pre_constraints = [c for k, c in enumerate(constraints) if k not in lock_idx] + [driver]
        row = sum(c.n_eq for c in pre_constraints) - 1  # the driver's multiplier (last row)

        def solve(pre_forces, q_init):
            model = make_model(pre_forces, pre_constraints, q_init)
            try:
                eq = equilibrium(model, q_init=q_init)
            except EquilibriumError as exc:
                raise EquilibriumError(f"inverse statics (pre-solve) failed: {exc.message}",
                                       element=driver.name) from None
            return eq, float(eq.lam[row])

        spring_k = springs[0][1] if springs else None
        released = [f for k, f in enumerate(forces) if k != spring_k]
        eq, lam0 = solve(released, q_guess)
        rec = {"driver": driver.name, "angle_target": driver.angle_target,
               "effort": -lam0, "effort_unit": "N m (torque in the driver's sense)",
               "iterations": 0, "tol": tol, "sets": []}
        if spring_k is not None:
            spring = forces[spring_k]
            l_star = float(np.linalg.norm(spring.diff(eq.q)))
            a_l0, a_lam = l_star, lam0  # zero tension at q*: λ_d is the released effort
            b_l0 = l_star * (1.0 - 1e-3)
            eq_b, b_lam = solve(forces[:spring_k] + [dataclasses.replace(spring, free_length=b_l0)]
                                + forces[spring_k + 1:], eq.q)
            it, scale = 1, max(abs(lam0), np.finfo(float).tiny)
            while abs(b_lam) > tol * scale:
                if it >= max_iter or b_lam == a_lam:
                    raise EquilibriumError(
                        f"inverse statics: free length of {spring.name} not found after {it} "
                        f"secant steps (driver effort {b_lam:.3g})", element=driver.name)
                new = b_l0 - b_lam * (b_l0 - a_l0) / (b_lam - a_lam)
                a_l0, a_lam = b_l0, b_lam
                b_l0 = new
                trial = dataclasses.replace(spring, free_length=b_l0)
                eq_b, b_lam = solve(forces[:spring_k] + [trial] + forces[spring_k + 1:], eq_b.q)
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
    return forces, constraints, q_guess, records
