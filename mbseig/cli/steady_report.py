"""``mbseig report CASE`` on a steady motion (DESIGN §8): report.md and a self-contained
report.html on the page every motion shares, with the motion, the steady state (residual,
spins, each wheel's normal force and state), the modes with their verdict, shapes and pole map,
and the time-domain check (unless ``--no-check``).  Computed by
:mod:`mbseig.studies.steady_report`, formatted by :mod:`mbseig.report.steady`."""

from __future__ import annotations

from pathlib import Path

from ..errors import CaseError

__all__ = ["run"]


def run(args, spec) -> int:
    from ..report.steady import write_steady_report
    from ..studies.steady_report import steady_report_data

    configs = getattr(args, "config", None) or [None]
    if len(configs) > 1 or getattr(args, "all_configs", False):
        raise CaseError("a steady-motion report covers one configuration (one --config)",
                        element="command line", file=spec.source)
    rep = steady_report_data(spec, config=configs[0],
                             run_check=not getattr(args, "no_check", False))
    out = Path(args.out) if args.out else Path("reports") / spec.name
    md, page = write_steady_report(rep, spec, out)
    print(f"wrote {md} and {page}")
    return 0
