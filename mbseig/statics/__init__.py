"""Stage 1: static equilibrium, inverse statics (actuator commands) and reactions.

    equilibrium(model) ─► Equilibrium(q₀, λ₀, residuals, rank, redundancy, model)

- :mod:`~mbseig.statics.newton`: Newton on the augmented system (docs/design.md, "Equilibrium");
- :mod:`~mbseig.statics.inverse`: commanded postures → actuator settings (``angle_driver`` with
  ``sets``), resolved here, never while loading;
- :mod:`~mbseig.statics.reactions`: posture, range of motion, joint reactions, actuator effort.

``eq.model`` is the model the equilibrium belongs to (with the commands resolved); the later
stages work on it (:func:`solved`).
"""

from __future__ import annotations

from ..errors import MbseigError
from .inverse import resolve_commands
from .newton import Equilibrium, solve_statics, solved

__all__ = ["Equilibrium", "equilibrium", "solved"]


def equilibrium(model, *, tol: float = 1e-12, max_iter: int = 50, rank_tol: float = 1e-10,
                q_init=None) -> Equilibrium:
    """Find the static equilibrium of ``model``, resolving its inverse-statics commands first.

    tol : relative residual at which Newton stops (forces scaled by ``force_scale``, each
        constraint by its own scale, e.g. L² for a rigid length).
    rank_tol : relative singular-value threshold for the rank of Φ_q (redundancy count).
    q_init : start of the Newton iteration (default: the case's positions, or the commanded
        posture found by inverse statics).
    Errors name the case file and the constraint or coordinate that could not be balanced.
    """
    opts = {"tol": tol, "max_iter": max_iter, "rank_tol": rank_tol}
    if getattr(model, "commands", ()):
        try:
            model = resolve_commands(model, lambda m, q_init: solve_statics(m, q_init=q_init, **opts))
        except MbseigError as exc:
            raise exc.located(file=getattr(model, "source", None)) from None
    return solve_statics(model, q_init=q_init, **opts)
