"""Everything a stability report shows, computed: :func:`report_data`; the report package only
formats it (:func:`mbseig.report.build.render_report`, and the steady and periodic pages).

    write_report(case) = render(report_data(case))

Rest, steady and periodic cases come through the same :func:`report_data`: the reference the
case declares (:func:`mbseig.studies.reference.reference_kind`) picks what is computed, and the
data record carries its ``kind`` for the renderer.

For a case at rest: per configuration its study (:func:`~.report_studies.study_configuration`:
equilibrium, modes, reactions, the time-domain check), the ``[[report.studies]]`` entries (a
sweep with its outputs written under the report's folder, its critical values and the rotor's
Campbell diagram and unbalance response when it sweeps a rotor's speed; or the comparison with
and without the constraint-force stiffness), the rotor over ``speeds`` asked for by the caller,
and the least-damped mode's parameter sensitivities.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CaseError
from .campbell import is_rotor, rotor_study
from .point import as_spec
from .reference import reference_kind
from .report_studies import (
    compare_study,
    least_mode_sensitivities,
    study_configuration,
    sweep_study,
)
from .sweep_outputs import write_outputs

__all__ = ["ReportData", "StudyData", "RotorData", "report_data", "write_report",
           "check_study_unbalance"]


@dataclass(frozen=True, eq=False)
class StudyData:
    """One ``[[report.studies]]`` entry computed: ``kind`` "sweep" or "compare", its title, the
    entry, the comparison or the sweep (:class:`~.report_studies.SweepStudy`) with the paths of
    its written outputs and their folder, and the rotor study of a sweep over a rotor's speed."""

    kind: str
    title: str
    study: dict
    compare: object = None
    sweep: object = None
    paths: tuple = ()
    folder: Path = None
    rotor: object = None


@dataclass(frozen=True, eq=False)
class RotorData:
    """The rotor over ``speeds`` asked for by the caller: parameter, values, configuration and
    the rotor study (None when the parameter does not set a rotor's speed)."""

    parameter: str
    values: list
    config: object
    rotor: object
    folder: Path


@dataclass(frozen=True, eq=False)
class ReportData:
    """What one report shows (module docstring).  ``kind``: the case's reference; for a steady
    or periodic case ``moving`` holds its report record and the other fields are empty."""

    kind: str
    case: object
    configs: list
    units: dict
    summaries: list = field(default_factory=list)
    description: str = ""
    studies: list = field(default_factory=list)
    rotor: RotorData = None
    rotor_note: bool = False
    sensitivities: list = None
    run_check: bool = True
    moving: object = None


def check_study_unbalance(case, study, label):
    """Refuse, before any work, a ``[[report.studies]]`` entry's own ``unbalance`` that its
    study could not honour: a sweep that does not set a rotor's speed, or ``at`` naming no point,
    station or body of the model."""
    from .campbell import speed_parameter
    from .unbalance import unbalance_point

    own = study.get("unbalance")
    if not own or "compare" in study:
        return
    where = f"{label}.unbalance"
    name, config = study["sweep"], study.get("config")
    lo, hi = (float(v) for v in study["range"])
    if not speed_parameter(case, name, [lo, hi], config=config):
        raise CaseError(f"an unbalance response needs a sweep over a rotor's speed; {name} does "
                        f"not set the speed of a rotor", element=where,
                        file=getattr(case, "source", None))
    try:
        unbalance_point(case.build(config, **{name: lo}), own["at"])
    except CaseError as exc:
        raise CaseError(exc.message, file=getattr(case, "source", None), element=where) from None


def study_data(case, study, out_dir, stem, jobs, units, *, unbalance=None, label=None):
    """One ``[[report.studies]]`` entry computed (``label`` names it in errors); the rotor's
    unbalance response takes the entry's own ``unbalance = {at, me}``, else ``unbalance`` =
    (point, m·e) of the command line, else m·e = 1 kg m at the first disk."""
    kind = "compare" if "compare" in study else "sweep"
    config = study.get("config")
    title = study.get("title", f"{kind} on {config}")
    if kind == "compare":
        return StudyData(kind, title, study, compare=compare_study(case, config))
    check_study_unbalance(case, study, label or "report.studies")  # before the sweep runs
    sw = sweep_study(case, study, jobs=jobs)
    folder = Path(out_dir) / f"{stem}_{config}_{sw.parameter}"
    paths = write_outputs(sw.result, folder, units=units)
    own = study.get("unbalance")  # checked by check_study_unbalance
    rs = rotor_study(case, sw.parameter, sw.values, config=config, jobs=jobs,
                     unbalance=(own["at"], float(own["me"])) if own else unbalance,
                     xtol_rel=float(study.get("xtol_rel", 1e-10)))
    return StudyData(kind, title, study, sweep=sw, paths=tuple(paths), folder=folder, rotor=rs)


def report_data(case, *, configs=None, out_dir, run_check=True, jobs=None, studies=True,
                sensitivities=True, speeds=None, unbalance=None) -> ReportData:
    """Everything the report of ``case`` shows, computed (module docstring).

    Parameters
    ----------
    case : str, pathlib.Path or CaseSpec
        A case file or a read case; read once.
    configs : list, optional
        Configuration names ([None] for the case as written, the default).
    out_dir : str or pathlib.Path
        The report's folder (a sweep's outputs are written under it).
    run_check : bool
        Run the time-domain check of every mode.
    jobs : int, optional
        Worker processes of the sweeps.
    studies : bool
        Run the case's ``[[report.studies]]``.
    sensitivities : bool
        Compute the least-damped mode's parameter sensitivities.
    speeds : tuple, optional
        (parameter, values): the rotor over these speeds.
    unbalance : tuple, optional
        (point, m·e [kg m]) of the rotor's unbalance.

    Returns
    -------
    ReportData
        The record :func:`mbseig.report.build.render_report` formats.

    Examples
    --------
    >>> import tempfile
    >>> from mbseig.casefile.examples import pendulum
    >>> data = report_data(pendulum(), out_dir=tempfile.mkdtemp(), run_check=False,
    ...                    sensitivities=False)
    >>> data.kind, [str(s.verdict) for s in data.summaries]
    ('rest', ['critical'])
    """
    case = as_spec(case)
    configs = configs or [None]
    kind = reference_kind(case)
    from ..report.units import parameter_units

    units = parameter_units(case)
    if kind != "rest":
        if len(configs) > 1:
            raise CaseError(f"a {kind}-motion report covers one configuration (one --config)",
                            element="command line", file=case.source)
        if speeds is not None or unbalance is not None:
            raise CaseError(f"the rotor's speeds and unbalance apply to a case at rest, not to a "
                            f"{kind} motion", element="command line", file=case.source)
        if kind == "steady":
            from .steady_report import steady_report_data

            rep = steady_report_data(case, config=configs[0], run_check=run_check)
        else:
            from .periodic_report import periodic_report_data

            rep = periodic_report_data(case, config=configs[0], run_check=run_check,
                                       studies=studies)
        return ReportData(kind, case, configs, units, run_check=run_check, moving=rep)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = case.name
    base = case.build(configs[0])
    chosen = []
    if studies:  # the studies that will run, their own unbalance checked before any work
        # (a linear case has no [report])
        for k, st in enumerate(getattr(base, "report", {}).get("studies", [])):
            if st.get("config") in configs or len(configs) > 1:
                check_study_unbalance(case, st, f"report.studies[{k}]")
                chosen.append((k, st))
    summaries = [study_configuration(case, c, run_check=run_check) for c in configs]
    done = [study_data(case, st, out_dir, stem, jobs, units, unbalance=unbalance,
                       label=f"report.studies[{k}]") for k, st in chosen]
    rotor, note = None, False
    if speeds is not None:
        name, values = speeds
        rotor = RotorData(name, list(values), configs[0],
                          rotor_study(case, name, values, config=configs[0], jobs=jobs,
                                      unbalance=unbalance),
                          out_dir / f"{stem}_rotor_{name}")
    elif is_rotor(case, base):
        note = True
    sens = ([least_mode_sensitivities(case, s, top=6) for s in summaries] if sensitivities
            else None)
    return ReportData(kind, case, configs, units, summaries, base.description or "", done, rotor,
                      note, sens, run_check)


def write_report(case, *, out_dir=None, configs=None, all_configs=False, run_check=True,
                 jobs=None, studies=True, sensitivities=True, animations=True, speeds=None,
                 unbalance=None):
    """Write a case's stability report: report.md and a self-contained report.html.

    Parameters
    ----------
    case : str, pathlib.Path or CaseSpec
        A case file or a read case; read once.  Its reference motion (rest, steady or
        periodic) decides the report's sections.
    out_dir : str or pathlib.Path, optional
        The folder (default reports/<case>).
    configs : list, optional
        Configuration names (default: the case as written).
    all_configs : bool
        The case as written, then every named configuration.
    run_check : bool
        Run the time-domain check of every mode.
    jobs : int, optional
        Worker processes of the sweeps.
    studies : bool
        Run the case's ``[[report.studies]]``.
    sensitivities : bool
        The least-damped mode's parameter sensitivities.
    animations : bool
        One looping GIF a mode (False leaves them out).
    speeds : tuple, optional
        (parameter, values): the rotor's Campbell diagram and unbalance response over them.
    unbalance : tuple, optional
        (point, m·e [kg m]) of the rotor's unbalance (default m·e = 1 kg m at the first disk).

    Returns
    -------
    tuple of pathlib.Path
        (report.md, report.html).

    Examples
    --------
    >>> import tempfile
    >>> from mbseig.casefile.examples import pendulum
    >>> md, page = write_report(pendulum(), out_dir=tempfile.mkdtemp(), run_check=False,
    ...                         animations=False, sensitivities=False)
    >>> md.name, page.name
    ('report.md', 'report.html')
    """
    from ..report.build import render_report

    case = as_spec(case)
    if all_configs:  # the base case first, then every named configuration
        if reference_kind(case) != "rest":
            raise CaseError(f"a {reference_kind(case)}-motion report covers one configuration "
                            f"(one --config)", element="command line", file=case.source)
        configs = [None] + sorted(case.configurations)
    out = Path(out_dir) if out_dir else Path("reports") / case.name
    data = report_data(case, configs=configs, out_dir=out, run_check=run_check, jobs=jobs,
                       studies=studies, sensitivities=sensitivities, speeds=speeds,
                       unbalance=unbalance)
    return render_report(data, out, animations=animations)
