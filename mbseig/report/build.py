"""Stability reports: ``report.md`` and a self-contained ``report.html`` per case.

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

import hashlib
import os
import time
from pathlib import Path

from ..studies.campbell import is_rotor
from ..studies.point import as_spec
from ..studies.report_studies import study_configuration
from .page import head_blocks, page_blocks, write_page
from .sections import configuration_blocks
from .study_blocks import check_study_unbalance, rotor_section, study_section
from .summary import comparison_blocks, summary_blocks
from .units import parameter_units

__all__ = ["build_report", "write_report", "provenance"]


def provenance(case) -> dict:
    """mbseig version, date (UTC; ``SOURCE_DATE_EPOCH`` when set, for reproducible builds) and
    the SHA-256 of the case file: what a reader needs to know which inputs made the report."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        ver = version("mbseig")
    except PackageNotFoundError:  # not installed as a distribution (a source tree)
        ver = "unknown"
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    try:
        stamp = float(epoch) if epoch else time.time()
    except ValueError:
        stamp = time.time()
    date = time.strftime("%Y-%m-%d", time.gmtime(stamp))
    try:
        digest = hashlib.sha256(Path(case.source).read_bytes()).hexdigest()
    except (OSError, TypeError):
        digest = "unavailable"
    import numpy
    import scipy

    return {"mbseig": ver, "date": date, "case": Path(str(case.source)).name,
            "sha256": digest, "numpy": numpy.__version__, "scipy": scipy.__version__}


def build_report(case, *, configs=None, out_dir, run_check=True, jobs=None, studies=True,
                 sensitivities=True, animations=True, speeds=None, unbalance=None):
    """Blocks of the report of ``case`` (a path or a parsed :class:`~mbseig.casefile.CaseSpec`,
    read once) for ``configs`` (list of names; [None] for the base): title, provenance, table
    of contents, summary, comparison, one section a configuration, the studies (and the rotor
    over ``speeds``, module docstring)."""
    case = as_spec(case)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    stem = case.name
    configs = configs or [None]
    units = parameter_units(case)
    base = case.build(configs[0])
    head = head_blocks(stem, base.description or "", provenance(case), configs)
    chosen = []
    if studies:  # the studies that will run, their own unbalance checked before any work
        for k, st in enumerate(getattr(base, "report", {}).get("studies", [])):  # a linear case has no [report]
            if st.get("config") in configs or len(configs) > 1:
                check_study_unbalance(case, st, f"report.studies[{k}]")
                chosen.append((k, st))
    summaries, cfg_blocks = [], []
    for c in configs:
        s = study_configuration(case, c, run_check=run_check)
        cfg_blocks += configuration_blocks(case, s, out_dir, run_check=run_check, stem=stem,
                                           units=units, animations=animations)
        summaries.append(s)
    study_blocks, study_sums = [], []
    for k, st in chosen:
        b, s = study_section(case, st, out_dir, stem, jobs, units, unbalance=unbalance,
                             label=f"report.studies[{k}]")
        study_blocks += b
        study_sums.append(s)
    if speeds is not None:
        study_blocks += rotor_section(case, speeds, out_dir, stem, jobs, units,
                                      config=configs[0], unbalance=unbalance)
    elif is_rotor(case, base) and not any(b[0] == "h3" and "Campbell" in b[1]
                                          for b in study_blocks):
        study_blocks += [("h2", "Rotor"), ("p", "The case has a spinning rotor: a "
                          "[[report.studies]] sweep over its speed (or a speed range asked of "
                          "the report) adds its Campbell diagram, critical speeds and unbalance "
                          "response.")]
    body = summary_blocks(case, summaries, study_sums, units, sensitivities, out_dir=out_dir,
                          stem=stem)
    if len(configs) > 1:
        body += comparison_blocks(summaries, study_sums, units)
    body += cfg_blocks + study_blocks
    return page_blocks(head, body)


def write_report(case, *, out_dir=None, configs=None, all_configs=False, run_check=True,
                 jobs=None, studies=True, sensitivities=True, animations=True, speeds=None,
                 unbalance=None):
    """Write report.md and report.html (default directory reports/<case>); returns their paths.
    ``animations=False`` leaves out the animated mode shapes (one GIF a mode); ``speeds`` and
    ``unbalance``: the rotor section (module docstring).

    ``case`` is a path or a parsed :class:`~mbseig.casefile.CaseSpec`; it is read once."""
    case = as_spec(case)
    if all_configs:  # the base case first, then every named configuration
        configs = [None] + sorted(case.configurations)
    out = Path(out_dir) if out_dir else Path("reports") / case.name
    blocks = build_report(case, configs=configs, out_dir=out, run_check=run_check, jobs=jobs,
                          studies=studies, sensitivities=sensitivities, animations=animations,
                          speeds=speeds, unbalance=unbalance)
    return write_page(blocks, out, f"Stability report: {case.name}")
