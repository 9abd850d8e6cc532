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

from ..lazy import lazy_names

# PEP 562: `from ..studies import analyze` does not import the sweep machinery (plots,
# boundaries, continuation) that `mbseig modes` never uses
_LAZY = {"Analysis": "pipeline", "analyze": "pipeline", "analyze_model": "pipeline",
         "modes_json": "pipeline", "Refinement": "refine", "refine_analysis": "refine",
         "SweepResult": "sweep", "parse_range": "sweep", "run_sweep": "sweep",
         "write_outputs": "sweep"}

__all__ = list(_LAZY)


__getattr__, __dir__ = lazy_names(__name__, globals(), _LAZY)
