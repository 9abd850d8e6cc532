"""The whole pipeline on one case and parameter point, and its JSON form (the fixed
`mbseig modes --json` interface).

Each mode of the JSON has ``freq_hz`` = ω_d/2π (damped, as fixed in DESIGN §8) and
``freq_n_hz`` = ω_n/2π = |s|/2π (natural), and, when the case names angles (report angles,
torsional elements, angle outputs), ``angles``: the mode shape in those angles [re, im] with
the normalization of the coordinate shape (largest coordinate component 1).

    case ─► Model ─► equilibrium ─► linearize ─► modes        (analyze)

``case`` is a path (read once here), a parsed :class:`~mbseig.casefile.CaseSpec` (a model
factory) or an already built model.
"""

from __future__ import annotations


from ..arguments import check
from ..errors import CaseError
from .point import Analysis, analyze_model, as_spec, modes_json
from .reference import reference_kind

__all__ = ["Analysis", "analyze", "analyze_model", "modes_json", "as_spec"]


def analyze(case=None, *, config=None, params=None, solver="auto", constraint_stiffness=True,
            modes_options=None, model=None, refine=None):
    """Run the whole pipeline on a case about the reference motion it declares.

    Parameters
    ----------
    case : str, pathlib.Path or CaseSpec, optional
        A case file or a read case (:func:`mbseig.read_case`); its ``[motion]`` table decides
        the reference (:func:`mbseig.studies.reference.reference_kind`).
    config : str, optional
        The configuration (``[configurations.NAME]``).
    params : dict, optional
        Parameter overrides {name: value or expression}.
    solver : str
        The eigensolver path (``mbseig.eigen.SOLVERS``; "auto" chooses by structure).  At rest
        only.
    constraint_stiffness : bool
        Keep the constraint forces' stiffness Σ λ ∇²Φ (False: the geometric stiffness left out,
        for comparison).  At rest only.
    modes_options : dict, optional
        Options of :func:`mbseig.modes` (``n_modes``, ``target``, ``band``, tolerances).  At
        rest only.
    model : Model, optional
        A built model instead of ``case`` (analysed at rest).
    refine : dict, optional
        {"modes", "f_max", "accuracy", "max_elements"} to refine the case's
        ``elements = "auto"`` beams for those modes (:mod:`mbseig.studies.refine`); a case's
        own ``[refinement]`` table does the same.  At rest only.

    Returns
    -------
    Analysis, SteadyAnalysis or PeriodicAnalysis
        The analysis of the case's reference: each has ``kind``, ``reference``, ``verdict`` and
        ``to_json()``.

    Examples
    --------
    >>> from mbseig.casefile.examples import damped_pendulum
    >>> a = analyze(damped_pendulum(c=0.2))
    >>> a.kind, str(a.verdict), len(a.to_json()["modes"])
    ('rest', 'stable', 1)
    """
    check("analyze", locals())
    opts = {"solver": solver, "constraint_stiffness": constraint_stiffness,
            "modes_options": modes_options}
    if model is not None:
        return analyze_model(model, **opts)
    spec = as_spec(case)
    kind = reference_kind(spec)
    if kind != "rest":  # the motion the case declares, never analysed as if at rest
        return _analyze_moving(spec, kind, config, params, refine=refine, **opts)
    model = spec.build(config, **(params or {}))
    if refine or (model.flexible or {}).get("refinement"):
        from .refine import refine_analysis  # cases with beams to refine only

        return refine_analysis(spec, config=config, params=params, request=refine, model=model,
                               **opts)
    return analyze_model(model, **opts)


def _analyze_moving(spec, kind, config, params, *, solver, constraint_stiffness, modes_options,
                    refine):
    """The analysis of a steady or periodic case; the options of a case at rest are refused,
    never ignored."""
    given = {"solver": solver != "auto", "constraint_stiffness": constraint_stiffness is not True,
             "modes_options": bool(modes_options), "refine": bool(refine)}
    bad = [k for k, v in given.items() if v]
    if bad:
        raise CaseError(f"{', '.join(bad)} does not apply to a {kind} motion (analyze takes "
                        f"the whole spectrum of its linearization)", element="motion",
                        file=spec.source)
    if kind == "steady":
        from .steady_modes import analyze_steady

        return analyze_steady(spec, config=config, params=params)
    from .periodic import periodic_analysis

    return periodic_analysis(spec, config=config, params=params)
