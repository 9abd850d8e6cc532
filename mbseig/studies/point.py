"""One parameter point of a study: a built model through equilibrium, linearization and modes.

    Model ─► equilibrium ─► linearize ─► modes          (analyze_model → Analysis)
"""

from __future__ import annotations

from dataclasses import dataclass

from ..casefile import CaseSpec, read_case
from ..errors import MbseigError
from ..linear import LinearModel, linearize
from ..modal import Modes, modes
from ..statics import Equilibrium, equilibrium

__all__ = ["Analysis", "analyze_model", "as_spec"]


@dataclass(frozen=True, eq=False)
class Analysis:
    """Model → equilibrium → linear model → modes for one case and parameter set.

    ``model`` is the model the equilibrium belongs to (inverse-statics commands resolved).
    """

    model: object
    eq: Equilibrium
    linear: LinearModel
    modes: Modes
    refinement: object = None  # mbseig.studies.refine.Refinement when beams were refined


def as_spec(case) -> CaseSpec:
    """A :class:`CaseSpec` from a path or a spec (a path is read and parsed here, once)."""
    return case if isinstance(case, CaseSpec) else read_case(case)


def analyze_model(model, *, solver="auto", constraint_stiffness=True, modes_options=None):
    """equilibrium → linearize → modes on a built model."""
    try:
        eq = equilibrium(model)
        lin = linearize(model, eq, constraint_stiffness=constraint_stiffness)
        extra = {} if lin.constraint_jacobian is None else {"constraints": lin.constraint_jacobian}
        md = modes(lin.M, lin.P, lin.Q, solver=solver, N=lin.N,
                   coordinate_names=lin.coordinate_names, **extra, **(modes_options or {}))
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
    return Analysis(eq.model if eq.model is not None else model, eq, lin, md)
