"""Continuation in the loads from the unloaded state (docs/design.md, "Equilibrium").

The loads of a model are its constant generalized forces (gravity and point forces, ``g_const``)
and the force elements with a ``magnitude`` (follower forces); springs, dampers, beams and
actuators are the structure.  ``model(t)`` scales every load by t.  Starting from the case's
positions, the unloaded model (t = 0) is solved first, then t is raised to 1 in adaptive steps:
a tangent predictor dq/dt = J⁻¹[∂g/∂t; 0] from the last equilibrium, bounded by the trust
radius, and a Newton corrector (:func:`~mbseig.statics.newton.newton`); a step that fails is
halved, a step that converged in few iterations is doubled.  When the step falls below
``DT_MIN`` the loads cannot be raised further along this path (a limit point): the failure
records the load factor reached.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .cache import Memo
from .linalg import NewtonMatrix, augmented
from .newton import Stall, newton

__all__ = ["scaled_loads", "has_loads", "continue_loads", "DT_START", "DT_MIN"]

DT_START = 0.125  # first load step
DT_MIN = 1e-5  # smallest load step before the continuation gives up
EASY = 4  # a corrector that converged in at most EASY iterations doubles the next step


def _is_load(f):
    return f.scalable_load  # declared on the element's class (mbseig.model.base)


def has_loads(model) -> bool:
    return bool(np.any(model.g_const != 0.0)) or any(_is_load(f) and f.magnitude != 0.0
                                                     for f in model.forces)


def scaled_loads(model, t: float):
    """The model with every load scaled by t (module docstring), behind its own
    :class:`~mbseig.statics.cache.Memo`."""
    base = model.model if isinstance(model, Memo) else model
    forces = tuple(dataclasses.replace(f, magnitude=t * f.magnitude) if _is_load(f) else f
                   for f in base.forces)
    return Memo(dataclasses.replace(base, g_const=t * base.g_const, forces=forces))


def _load_vector(model, q):
    """∂g/∂t at t = 1 for the scaling above: the loads' generalized force at q."""
    return model.generalized_force(q) - scaled_loads(model, 0.0).generalized_force(q)


def continue_loads(model, q_start, s, *, t_start=0.0):
    """(Solution at t = 1, record) or :class:`Stall` with ``load_factor`` (module docstring)."""
    if not has_loads(model):
        raise Stall("the model has no loads to continue in")
    t = float(t_start)
    try:
        sol = newton(scaled_loads(model, t), q_start, s, prove=False)
    except Stall as exc:
        exc.reason = f"even the unloaded model did not converge: {exc.reason}"
        exc.load_factor = 0.0
        raise
    q, lam = sol.q, sol.lam
    dt, steps, rejected, iters = DT_START, 0, 0, sol.iterations
    n = model.n
    while t < 1.0:
        dt = min(dt, 1.0 - t)
        mt = scaled_loads(model, t)
        A, _ = augmented(mt, q, lam)
        try:
            tangent = NewtonMatrix(A, weights=s.scales.weights(A.shape[0])).solve(
                np.concatenate([_load_vector(model, q), np.zeros(model.n_constraints)]))[0][:n]
        except Exception:  # a singular matrix: no predictor, the corrector starts at q
            tangent = np.zeros(n)
        pred = dt * tangent
        size = s.scales.size(pred)
        if size > s.radius_max:
            pred *= s.radius_max / size
        t_new = 1.0 if t + dt >= 1.0 - 1e-15 else t + dt
        try:
            sol = newton(scaled_loads(model, t_new), q + pred, s, max_iter=min(s.max_iter, 25),
                         prove=False)
        except Stall:
            rejected += 1
            dt *= 0.5
            if dt < DT_MIN:
                exc = Stall(f"the load continuation stopped at load factor {t:.6g}", q=q, lam=lam,
                            iterations=iters)
                exc.load_factor = t
                raise exc from None
            continue
        t, q, lam = t_new, sol.q, sol.lam
        steps += 1
        iters += sol.iterations
        if sol.iterations <= EASY:
            dt *= 2.0
    record = {"load_steps": steps, "rejected_load_steps": rejected, "total_iterations": iters,
              "dt_start": DT_START, "dt_min": DT_MIN}
    return sol, record
