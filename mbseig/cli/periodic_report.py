"""``mbseig report CASE`` on a periodic case (DESIGN §8): report.md and a self-contained
report.html with the Floquet multipliers and their bounds, the verdict and what decided it, the
frozen-time eigenvalues beside them (not a criterion), the multipliers on the unit circle, the
time-domain check (unless ``--no-check``) and the ``[[report.studies]]`` sweeps (unless
``--no-studies``; a study with ``lines`` also draws the stability chart).  Computed by
:mod:`mbseig.studies.periodic_report`, formatted by :mod:`mbseig.report.periodic`."""

from __future__ import annotations

from pathlib import Path

from ..errors import CaseError

__all__ = ["run"]


def run(args, spec) -> int:
    from ..report.periodic import write_periodic_report
    from ..studies.periodic_report import periodic_report_data

    configs = getattr(args, "config", None) or [None]
    if len(configs) > 1 or getattr(args, "all_configs", False):
        raise CaseError("a periodic-motion report covers one configuration (one --config)",
                        element="command line", file=spec.source)
    rep = periodic_report_data(spec, config=configs[0],
                               run_check=not getattr(args, "no_check", False),
                               studies=not getattr(args, "no_studies", False))
    out = Path(args.out) if args.out else Path("reports") / spec.name
    md, page = write_periodic_report(rep, spec, out)
    print(f"wrote {md} and {page}")
    return 0
