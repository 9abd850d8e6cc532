"""``mbseig report CASE``: report.md and a self-contained report.html."""

from __future__ import annotations

from .common import case_command


def register(sub):
    p = sub.add_parser("report", help="write a stability report (Markdown and self-contained HTML)")
    p.add_argument("case", metavar="CASE", help="case file (TOML)")
    grp = p.add_mutually_exclusive_group()
    grp.add_argument("--config", action="append", default=None, metavar="NAME",
                     help="configuration(s) to report (repeatable; default: the base case)")
    grp.add_argument("--all-configs", action="store_true",
                     help="every configuration of the case, with the comparison table and the "
                          "studies of its [report] table")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default reports/CASE)")
    p.add_argument("--no-check", action="store_true", help="skip the time-domain check")
    p.add_argument("--no-studies", action="store_true", help="skip the [[report.studies]] sweeps")
    p.add_argument("--no-sensitivities", action="store_true",
                   help="leave out the eigenvalue sensitivities of the summary")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="local worker processes for the studies' sweeps (default: CPU count)")
    p.set_defaults(run=run)


@case_command("report")
def run(args, spec) -> int:
    from ..report import write_report

    md, page = write_report(args.case, out_dir=args.out, configs=args.config,
                            all_configs=args.all_configs, run_check=not args.no_check,
                            jobs=args.jobs, studies=not args.no_studies,
                            sensitivities=not args.no_sensitivities)
    print(f"wrote {md} and {page}")
    return 0
