"""One static solve of a model as it is (docs/design.md, "Equilibrium"): Newton from the given
positions (:mod:`~mbseig.statics.newton`), and when it fails the continuation in the loads from
the unloaded state (:mod:`~mbseig.statics.loads`), then the true failure message.
"""

from __future__ import annotations

import numpy as np

from ..errors import MbseigError
from ..model.linear_case import LinearCase
from .cache import Memo
from .diagnosis import diagnose
from .loads import continue_loads
from .newton import Stall, newton, settings_for
from .result import Equilibrium, finish

__all__ = ["solve_statics"]


def solve_statics(model, *, tol: float = 1e-12, max_iter: int = 50, rank_tol: float = 1e-10,
                  q_init=None, xtol=None, floor_tol=1e-8, continuation=True) -> Equilibrium:
    """Find the static equilibrium of ``model`` as it is (module docstring), without the checks
    of :func:`mbseig.statics.equilibrium` (static stability, self-stress).

    tol : constraint residual relative to each constraint's scale, and the force outside the
        range of the tangent stiffness relative to force_scale.
    xtol : Newton correction in the model's length and angle scales (default: tol).
    floor_tol : a correction below it is accepted where rounding stops it from decreasing.
    rank_tol : relative singular-value threshold for the rank of Φ_q (redundancy count).
    continuation : on failure, continue in the loads from the unloaded state.
    Errors (docs/design.md, "Equilibrium") name the case file and the constraint or coordinates.
    """
    try:
        return _equilibrium(model, tol=tol, xtol=xtol, floor_tol=floor_tol, max_iter=max_iter,
                            rank_tol=rank_tol, q_init=q_init, continuation=continuation)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None


def _equilibrium(model, *, tol, xtol, floor_tol, max_iter, rank_tol, q_init, continuation):
    if isinstance(model, LinearCase):
        return Equilibrium(q=np.zeros(model.n), lam=np.zeros(0), residual=0.0, force_residual=0.0,
                           constraint_residual=0.0, iterations=0, rank=0, n_redundant=0,
                           tolerances={"tol": tol, "rank_tol": rank_tol}, method="linear case",
                           model=model)
    q0 = np.array(model.q_init if q_init is None else q_init, dtype=float)
    real, model = model, Memo(model)
    s = settings_for(model, q0, tol=tol, xtol=xtol, floor_tol=floor_tol, max_iter=max_iter,
                     rank_tol=rank_tol)
    path = {"start": "given positions" if q_init is None else "q_init"}
    try:
        sol = newton(model, q0, s)
        method = "newton"
    except Stall as first:
        if not continuation or first.reason.startswith("free motion"):
            raise diagnose(model, q0, first, None, s) from None
        try:
            sol, record = continue_loads(model, q0, s)
        except Stall as second:
            raise diagnose(model, q0, first, second, s) from None
        method = "load continuation from the unloaded state"
        path.update(record)
        path["direct"] = first.reason
    path.update({"position_iterations": sol.position_iterations, "rounding_floor": sol.rounding,
                 "newton_matrix_condition": sol.cond})
    iterations = path.get("total_iterations", sol.iterations)
    return finish(real, sol.q, s, iterations=iterations, correction=sol.correction,
                  method=method, path=path, memo=model)


