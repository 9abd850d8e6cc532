"""Studies: the pipeline run over many points of one parsed case.

- :mod:`~mbseig.studies.point`: one point (Model → equilibrium → linearize → modes);
- :mod:`~mbseig.studies.pipeline`: :func:`analyze` on a case (path, spec or model) and the
  ``mbseig modes --json`` object;
- :mod:`~mbseig.studies.refine`: mesh refinement driven by the modes of interest;
- :mod:`~mbseig.studies.sweep`: parameter sweeps, MAC tracking, stability boundaries;
- :mod:`~mbseig.studies.runners`: in-process, local processes or Dask.

A study reads its case once (:func:`mbseig.casefile.read_case`) and passes the parsed
:class:`~mbseig.casefile.CaseSpec`, a picklable model factory, to its points.
"""

from .pipeline import Analysis, analyze, analyze_model, modes_json
from .refine import Refinement, refine_analysis
from .sweep import SweepResult, parse_range, run_sweep, write_outputs

__all__ = ["Analysis", "analyze", "analyze_model", "modes_json", "Refinement",
           "refine_analysis", "SweepResult", "parse_range", "run_sweep", "write_outputs"]
