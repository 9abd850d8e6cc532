"""Stage 1: static equilibrium, inverse statics (actuator commands) and reactions.

    equilibrium(model) ─► Equilibrium(q₀, λ₀, residuals, rank, redundancy, model)

- :mod:`~mbseig.statics.newton`: the robust Newton (position solve first, trust region in the
  model's scales, projection after steps, a scale-aware convergence test) and the failure
  diagnosis (docs/design.md, "Equilibrium"); :mod:`~mbseig.statics.solve` puts it together
  with the load continuation;
- :mod:`~mbseig.statics.position`: the position solve of Φ = 0;
- :mod:`~mbseig.statics.loads`: continuation in the loads from the unloaded state;
- :mod:`~mbseig.statics.stiffness`: static stability, self-stress of redundant constraints;
- :mod:`~mbseig.statics.continuation`: equilibrium branches along a parameter
  (pseudo-arclength, folds, branch points);
- :mod:`~mbseig.statics.inverse`: commanded postures → actuator settings (``angle_driver`` with
  ``sets``), resolved here, never while loading;
- :mod:`~mbseig.statics.reactions`: posture, range of motion, joint reactions, actuator effort;
- :mod:`~mbseig.statics.failures`: the error classes and the instability warning.

``eq.model`` is the model the equilibrium belongs to (with the commands resolved); the later
stages work on it (:func:`solved`).
"""

from __future__ import annotations

from ..arguments import check
from ..errors import MbseigError
from .examine import examine
from .failures import (
    ConstraintsUnsatisfiable,
    NoStaticEquilibrium,
    NotConverged,
    StaticInstabilityWarning,
    UndeterminedSelfStress,
)
from .inverse import resolve_commands
from .result import Equilibrium, solved
from .solve import solve_statics

__all__ = ["Equilibrium", "equilibrium", "solved", "resolve", "examine", "ConstraintsUnsatisfiable",
           "NoStaticEquilibrium", "NotConverged", "UndeterminedSelfStress",
           "StaticInstabilityWarning"]


def equilibrium(model, *, tol: float = 1e-12, max_iter: int = 50, rank_tol: float = 1e-10,
                q_init=None, xtol=None, floor_tol: float = 1e-8, continuation: bool = True,
                offer_stable: bool = True, self_stress: str = "refuse",
                compliance: dict | None = None, blas: int | None = 1) -> Equilibrium:
    """Find the static equilibrium of ``model``, resolving its inverse-statics commands first.

    Parameters
    ----------
    model : Model
        The built model (:func:`mbseig.load_case`).
    tol : float
        Constraint residual relative to each constraint's scale (e.g. L² for a rigid length);
        also the force outside the range of the tangent stiffness relative to force_scale.
    max_iter : int
        Newton iterations before the load continuation takes over.
    rank_tol : float
        Relative singular-value threshold for the rank of Φ_q (redundancy count).
    q_init : array_like, optional
        Start of the iteration (default: the case's positions, or the commanded posture found
        by inverse statics).
    xtol : float, optional
        The Newton correction at convergence, in the model's length and angle scales
        (default: tol).
    floor_tol : float
        The correction accepted where rounding stops its decrease.
    continuation : bool
        When Newton fails, continue in the loads from the unloaded state.
    offer_stable : bool
        When the equilibrium is statically unstable, look for a stable one (load continuation
        from the unloaded state, then descent from the unstable direction) and attach it as
        ``stable_alternative``; a :class:`StaticInstabilityWarning` says so.
    self_stress : {"refuse", "report"}
        "refuse" raises :class:`UndeterminedSelfStress` when redundant constraints carry a
        self-stress that changes the stiffness; "report" returns the minimum-norm multipliers
        with the states recorded in ``self_stress``.
    compliance : dict, optional
        {constraint name: compliance} of redundant constraints (extension per unit of the force
        the element reports), which determines their self-stress
        (:func:`mbseig.statics.stiffness.compliant_multipliers`).
    blas : int or None
        BLAS threads while it runs (:func:`mbseig.statics.linalg.blas_threads`; None leaves them
        as they are).

    Returns
    -------
    Equilibrium
        q₀, λ₀ with their residuals, the rank of Φ_q(q₀), the static stability and how the
        equilibrium was reached; ``eq.model`` is the model with its commands resolved.

    Raises
    ------
    EquilibriumError
        Naming the case file and the constraint or coordinates (docs/design.md,
        "Equilibrium"): :class:`ConstraintsUnsatisfiable` only where that was shown,
        :class:`NotConverged` otherwise, with where it started.

    Examples
    --------
    >>> from mbseig.casefile.examples import pendulum
    >>> eq = equilibrium(pendulum().build())
    >>> eq.kind, [round(float(x), 12) + 0.0 for x in eq.q]   # the bob hangs below the pivot
    ('rest', [0.0, -1.0])
    """
    check("equilibrium", locals())
    from .linalg import blas_threads

    with blas_threads(blas):
        return _equilibrium_api(model, tol=tol, max_iter=max_iter, rank_tol=rank_tol,
                                q_init=q_init, xtol=xtol, floor_tol=floor_tol,
                                continuation=continuation, offer_stable=offer_stable,
                                self_stress=self_stress, compliance=compliance)


def _equilibrium_api(model, *, tol, max_iter, rank_tol, q_init, xtol, floor_tol, continuation,
                     offer_stable, self_stress, compliance):
    opts = {"tol": tol, "max_iter": max_iter, "rank_tol": rank_tol, "xtol": xtol,
            "floor_tol": floor_tol, "continuation": continuation}
    if getattr(model, "commands", ()):
        try:
            model = resolve_commands(model,
                                     lambda m, q_init: solve_statics(m, q_init=q_init, **opts))
        except MbseigError as exc:
            raise exc.located(file=model.source) from None
    if any(c.single_sided for c in model.constraints):
        from .contacts import solve_with_contacts

        eq = solve_with_contacts(model, lambda m: solve_statics(m, q_init=q_init, **opts))
    else:
        eq = solve_statics(model, q_init=q_init, **opts)
    try:
        return examine(eq, offer_stable=offer_stable, self_stress=self_stress,
                       compliance=compliance, opts=opts)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None


def resolve(model, *, tol: float = 1e-12, max_iter: int = 50, rank_tol: float = 1e-10, hint=None,
            cache=None):
    """``model`` with its inverse-statics commands resolved (:mod:`~mbseig.statics.inverse`),
    without solving its final equilibrium; the model itself when it has none.  ``hint``: a
    resolved neighbour of the same family to start from; ``cache``: a dict kept across one
    family's calls (:func:`resolve_commands`)."""
    if not getattr(model, "commands", ()):
        return model
    opts = {"tol": tol, "max_iter": max_iter, "rank_tol": rank_tol}
    try:
        return resolve_commands(model, lambda m, q_init: solve_statics(m, q_init=q_init, **opts),
                                hint=hint, cache=cache)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
