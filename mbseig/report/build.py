"""Stability reports: ``report.md`` and a self-contained ``report.html`` per case, rendered
from what :func:`mbseig.studies.report_data.report_data` computed (this package computes
nothing: the layer contract "the report computes nothing" holds without indirect imports).

First the summary (:mod:`mbseig.report.summary`).  For each configuration (all of the case's
``[configurations]`` with ``all_configs``): the model summary, the equilibrium (posture,
range-of-motion flags, pin reactions, constraint forces, actuator effort), the mode table with
verdict and margins, the mechanism at equilibrium with each mode shape superposed, one looping
GIF a mode (embedded in the HTML), the pole map and the time-domain check of every mode
(:mod:`mbseig.check`).  Then the studies declared in ``[[report.studies]]``:

- ``sweep``: a parameter swept over ``range`` with ``count`` points on ``config`` (optionally
  one line per value of ``lines = {name = [values]}``); its stability boundaries
  (:func:`mbseig.studies.run_sweep`) and the parameter value at which the equilibrium leaves the
  range of motion (Brent's method on the smallest joint margin, same ``xtol``).
- ``compare = "constraint_stiffness"``: the eigenvalues of ``config`` with and without the
  constraint-force stiffness Σ λ ∇²Φ.

A sweep over a parameter that sets a rotor's speed (a ``rotor`` element, a beam's ``spin``)
also gives the rotor's Campbell diagram, its critical speeds and the unbalance response
(:mod:`mbseig.report.study_blocks`); ``speeds`` = (parameter, values) asks for that section
without a ``[[report.studies]]`` entry, and ``unbalance`` = (point, m·e [kg m]) places the
unbalance (default m·e = 1 kg m at the first disk).

Output is deterministic: no dates or timings; figures are PNGs without metadata, animations
GIFs of the same frames; numbers are formatted at fixed precision.  The HTML embeds every
figure and animation as a base64 data URI; the files are also written next to report.md, which
links them.
"""

from __future__ import annotations

from pathlib import Path

from .page import head_blocks, page_blocks, write_page
from .provenance import provenance
from .sections import configuration_blocks
from .study_blocks import rotor_section, study_section
from .summary import comparison_blocks, summary_blocks

__all__ = ["build_report", "render_report", "provenance"]


def build_report(data, out_dir, *, animations=True):
    """Blocks of the report of a case at rest from its computed
    :class:`~mbseig.studies.report_data.ReportData`: title, provenance, table of contents,
    summary, comparison, one section a configuration, the studies (and the rotor over the
    speeds asked for, module docstring)."""
    case, configs, units = data.case, data.configs, data.units
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = case.name
    head = head_blocks(stem, data.description, provenance(case), configs)
    cfg_blocks = []
    for s in data.summaries:
        cfg_blocks += configuration_blocks(case, s, out_dir, run_check=data.run_check, stem=stem,
                                           units=units, animations=animations)
    study_blocks, study_sums = [], []
    for d in data.studies:
        b, s = study_section(d, units)
        study_blocks += b
        study_sums.append(s)
    if data.rotor is not None:
        study_blocks += rotor_section(data.rotor, units)
    elif data.rotor_note and not any(b[0] == "h3" and "Campbell" in b[1] for b in study_blocks):
        study_blocks += [("h2", "Rotor"), ("p", "The case has a spinning rotor: a "
                          "[[report.studies]] sweep over its speed (or a speed range asked of "
                          "the report) adds its Campbell diagram, critical speeds and unbalance "
                          "response.")]
    body = summary_blocks(data.summaries, study_sums, units, data.sensitivities,
                          out_dir=out_dir, stem=stem)
    if len(configs) > 1:
        body += comparison_blocks(data.summaries, study_sums, units)
    body += cfg_blocks + study_blocks
    return page_blocks(head, body)


def render_report(data, out_dir, *, animations=True):
    """Write report.md and report.html of computed report data
    (:func:`mbseig.studies.report_data.report_data`) into ``out_dir``; returns their paths.

    Parameters
    ----------
    data : ReportData
        What the report shows; its ``kind`` (rest, steady, periodic) picks the page.
    out_dir : str or pathlib.Path
        The report's folder.
    animations : bool
        One looping GIF a mode (rest; False leaves them out).

    Returns
    -------
    tuple of pathlib.Path
        (report.md, report.html).
    """
    out = Path(out_dir)
    if data.kind == "steady":
        from .steady import write_steady_report

        return write_steady_report(data.moving, data.case, out)
    if data.kind == "periodic":
        from .periodic import write_periodic_report

        return write_periodic_report(data.moving, data.case, out)
    blocks = build_report(data, out, animations=animations)
    return write_page(blocks, out, f"Stability report: {data.case.name}")
