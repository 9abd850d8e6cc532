"""One parameter point of a study: a built model through equilibrium, linearization and modes.

    Model ─► equilibrium ─► linearize ─► modes          (analyze_model → Analysis)

Every stage boundary is checked (README, "Input rules"): the model's elements are finite at the
case's positions before the equilibrium, the equilibrium's q₀, λ₀ are finite and its arithmetic
did not overflow, the linearization checks its own output (:func:`mbseig.linear.linearize`),
and the listed modes are finite and not empty.  A failed check is one
:class:`~mbseig.errors.NumericalError` naming the stage and the likely cause, never a traceback
or a listing of NaNs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..casefile import CaseSpec, read_case
from ..eigen import Request
from ..errors import MbseigError, NumericalError
from ..linear import LinearModel, linearize
from ..modal import Modes, modes
from ..model import Model
from ..numerics import DOUBLE_RANGE, require_finite, watched
from ..statics import Equilibrium, equilibrium

__all__ = ["Analysis", "analyze_model", "as_spec", "equilibrium_stage", "linear_stage",
           "eigen_stage", "MODEL_CAUSE", "EIGEN_CAUSE"]

MODEL_CAUSE = (f"the case's values are too large or too small together (forces, stiffnesses, "
               f"masses and lengths multiply beyond {DOUBLE_RANGE})")
EIGEN_CAUSE = f"M, P and Q span more orders of magnitude than {DOUBLE_RANGE} allows"


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


def equilibrium_stage(model) -> Equilibrium:
    """:func:`mbseig.equilibrium` between its two boundary checks: every element finite at the
    case's positions before, finite q₀ and λ₀ and no overflow inside."""
    if isinstance(model, Model):
        bad = model.nonfinite_element(model.q_init)
        if bad is not None:
            name, what = bad
            raise NumericalError(f"{what} is not finite at the case's positions; likely cause: "
                                 f"{MODEL_CAUSE}", element=name)
    with watched("equilibrium", MODEL_CAUSE):
        eq = equilibrium(model)
    require_finite("equilibrium", MODEL_CAUSE, q0=eq.q, lam0=eq.lam)
    return eq


def linear_stage(model, *, constraint_stiffness=True):
    """(equilibrium, linear model) with the boundary checks of both stages."""
    eq = equilibrium_stage(model)
    return eq, linearize(model, eq, constraint_stiffness=constraint_stiffness)


def eigen_stage(lin: LinearModel, *, solver="auto", modes_options=None) -> Modes:
    """:func:`mbseig.modes` on ``lin``; the listing is checked: every listed eigenvalue and
    backward error finite, and a full spectrum of a model with degrees of freedom lists at
    least one mode (a verdict on an empty listing is refused)."""
    extra = {} if lin.constraint_jacobian is None else {"constraints": lin.constraint_jacobian}
    # the eigensolvers judge their own numpy warnings (issue 13/17, eigen part); only their
    # arithmetic exceptions become the one-line error here
    with watched("eigen", EIGEN_CAUSE, float_warnings=False):
        md = modes(lin.M, lin.P, lin.Q, solver=solver, N=lin.N,
                   coordinate_names=lin.coordinate_names, rigid=lin.rigid, display=lin.display, **extra,
                   **(modes_options or {}))
    bad = ~(np.isfinite(md.eigenvalues) & ~np.isnan(md.backward_error))
    if np.any(bad):
        k = int(np.argmax(bad))
        raise NumericalError(f"mode {k + 1} of {len(md)}: eigenvalue {md.eigenvalues[k]} with "
                             f"backward error {md.backward_error[k]} is not a finite result; "
                             f"likely cause: {EIGEN_CAUSE}", element="eigen")
    partial = bool(modes_options) or bool(extra) or Request(solver).family() == "partial"
    if not partial and lin.dof > 0 and len(md) == 0:
        raise NumericalError(
            f"no finite mode among the {lin.dof} degrees of freedom ({md.n_infinite} infinite "
            f"eigenvalues dropped): no verdict can be given; likely cause: a singular or "
            f"negligible mass matrix, or {EIGEN_CAUSE}", element="eigen")
    return md


def analyze_model(model, *, solver="auto", constraint_stiffness=True, modes_options=None):
    """equilibrium → linearize → modes on a built model, every stage boundary checked."""
    try:
        eq, lin = linear_stage(model, constraint_stiffness=constraint_stiffness)
        md = eigen_stage(lin, solver=solver, modes_options=modes_options)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
    return Analysis(eq.model if eq.model is not None else model, eq, lin, md)
