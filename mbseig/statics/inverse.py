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

The final model has no driver, the commanded elements set, and q* as its initial guess, so its
equilibrium is the commanded posture (to the stopping tolerance).  The record (one dict per
driver) names the driver, the target angle, the effort, the free length or locked length and the
iterations, and is kept on ``Model.drivers`` for reports.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import EquilibriumError
from ..model.driver import check_command

__all__ = ["resolve_commands"]


def resolve_commands(model, equilibrium, *, tol=1e-12, max_iter=30):
    """The model with every pending command (``model.commands``) resolved: commanded elements
    set, ``drivers`` holding one record per driver, ``q_init`` at the commanded posture.

    equilibrium(model, q_init=...) is the static solve (:func:`mbseig.statics.newton.solve_statics`).
    """
    drivers = model.commands

    def make_model(forces, constraints, q_init=None):
        return dataclasses.replace(model, forces=tuple(forces), constraints=tuple(constraints),
                                   q_init=model.q_init if q_init is None else q_init, commands=())

    forces, constraints = list(model.forces), list(model.constraints)
    q_guess, records = None, []
    for driver, targets in drivers:
        springs, locks = check_command(driver, targets, forces, constraints)
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
    return dataclasses.replace(make_model(forces, constraints, q_guess), drivers=tuple(records))
