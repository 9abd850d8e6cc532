"""One reference motion, one pipeline (DESIGN §8): rest, steady and periodic motion through the
same stages.

    case ─► model ─► reference ─► linearize(model, reference) ─► modes ─► verdict (modal.rules)

=========  ===================================  =========================================
kind       reference (``find_reference``)      linear problem (``linearize``)
=========  ===================================  =========================================
rest       :class:`~mbseig.statics.Equilibrium`  :class:`~mbseig.linear.LinearModel`:
                                                 quadratic M, P, Q with its basis N
steady     :class:`~.steady.SteadyState`         :class:`~.steady.SteadyLinearization`:
                                                 descriptor E, A
periodic   :class:`~.periodic_motion.            :class:`~.periodic.PeriodicLinearization`:
           ReferenceMotion`                      sampled A(t), the monodromy map
=========  ===================================  =========================================

Every reference, linear problem and analysis carries its ``kind``; every analysis its
``reference``, ``verdict`` and ``to_json()`` (the ``mbseig modes --json`` object).  The kind is
what the case declares (its ``[motion]`` table: ``speed`` a steady motion, ``period`` a periodic
one, none rest), never what a file is called; the commands take it from here.
"""

from __future__ import annotations

from typing import Protocol

from ..casefile import motion_kind
from ..errors import CaseError, MbseigError

__all__ = ["KINDS", "Reference", "LinearProblem", "reference_kind", "find_reference",
           "linearize"]

#: the reference motions, in the order of the pipeline's table above
KINDS = ("rest", "steady", "periodic")


class Reference(Protocol):
    """What every stage may read of a reference motion."""

    kind: str  #: "rest", "steady" or "periodic"
    residual: float  #: the residual it was solved to
    iterations: int  #: the Newton iterations it took


class LinearProblem(Protocol):
    """What every stage may read of a linear problem about a reference."""

    kind: str  #: the kind of its reference


def reference_kind(case) -> str:
    """The reference motion a case declares.

    Parameters
    ----------
    case : str, pathlib.Path or CaseSpec
        A case file or a read case (:func:`mbseig.read_case`).

    Returns
    -------
    str
        "rest" (no ``[motion]`` table), "steady" (``[motion]`` with ``speed`` or
        ``yaw_rate``) or "periodic" (``[motion]`` with ``period``).

    Examples
    --------
    >>> from mbseig.casefile import CaseSpec
    >>> reference_kind(CaseSpec({"motion": {"period": 1.0}}, "c", None, None))
    'periodic'
    """
    from .point import as_spec

    spec = as_spec(case)
    try:
        kind = motion_kind(spec.data)
    except CaseError as exc:
        raise exc.located(file=spec.source) from None
    return "rest" if kind is None else kind


def find_reference(case, *, config=None, params=None):
    """The model of a case and the reference motion it declares, solved.

    Parameters
    ----------
    case : str, pathlib.Path or CaseSpec
        A case file or a read case.
    config : str, optional
        The configuration (``[configurations.NAME]``).
    params : dict, optional
        Parameter overrides {name: value or expression}.

    Returns
    -------
    tuple
        ``(model, reference)``: a :class:`~mbseig.model.Model` and its
        :class:`~mbseig.statics.Equilibrium` at rest; the model and its
        :class:`~mbseig.studies.steady.SteadyState` in steady motion; the
        :class:`~mbseig.model.timed.TimedModel` and its
        :class:`~mbseig.studies.periodic_motion.ReferenceMotion` in periodic motion.

    Examples
    --------
    >>> from mbseig.casefile.examples import pendulum
    >>> model, ref = find_reference(pendulum())
    >>> ref.kind
    'rest'
    """
    from .point import as_spec, equilibrium_stage

    spec = as_spec(case)
    kind = reference_kind(spec)
    if kind == "periodic":
        from .periodic import timed_model
        from .periodic_motion import reference_motion

        timed, _ = timed_model(spec, config=config, params=params)
        try:
            return timed, reference_motion(timed)
        except MbseigError as exc:
            raise exc.located(file=spec.source) from None
    model = spec.build(config, **(params or {}))
    if kind == "steady":
        from ..casefile.motion_readers import read_motion
        from .steady import steady_state

        motion = read_motion(spec.data, dict(model.parameters), file=spec.source)
        try:
            return model, steady_state(model, motion)
        except MbseigError as exc:
            raise exc.located(file=spec.source) from None
    try:
        eq = equilibrium_stage(model)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
    return (eq.model if eq.model is not None else model), eq


def linearize(model, reference, /, **options):
    """The linear problem about any reference motion.

    Parameters
    ----------
    model : Model or TimedModel
        The model the reference belongs to (:func:`find_reference`).
    reference : Equilibrium, SteadyState or ReferenceMotion
        The reference motion.
    **options
        Passed to the linearization of that kind: :func:`mbseig.linear.linearize` at rest
        (``rank_tol``, ``constraint_stiffness``, ``sparse``),
        :func:`mbseig.studies.steady.linearize_steady` in steady motion (``naive``,
        ``rank_tol``), :func:`mbseig.studies.periodic.linearize_periodic` in periodic motion
        (``samples``, ``max_samples``).

    Returns
    -------
    LinearModel, SteadyLinearization or PeriodicLinearization
        The typed linear problem; its ``kind`` is the reference's.

    Examples
    --------
    >>> from mbseig.casefile.examples import pendulum
    >>> model, eq = find_reference(pendulum())
    >>> lin = linearize(model, eq)
    >>> lin.kind, lin.dof
    ('rest', 1)
    """
    from .periodic_motion import ReferenceMotion
    from .steady import SteadyState

    if isinstance(reference, SteadyState):
        from .steady import linearize_steady

        return linearize_steady(model, reference, **options)
    if isinstance(reference, ReferenceMotion):
        from .periodic import linearize_periodic

        return linearize_periodic(model, reference, **options)
    from ..linear import linearize as linearize_rest  # an Equilibrium; checks its arguments

    return linearize_rest(model, reference, **options)
