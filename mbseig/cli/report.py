"""``mbseig report CASE``: report.md and a self-contained report.html."""

from __future__ import annotations

from ..errors import CaseError

import math

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
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default reports/CASE)")
    p.add_argument("--no-check", action="store_true", help="skip the time-domain check")
    p.add_argument("--no-studies", action="store_true", help="skip the [[report.studies]] sweeps")
    p.add_argument("--no-sensitivities", action="store_true",
                   help="leave out the eigenvalue sensitivities of the summary")
    p.add_argument("--no-animations", action="store_true",
                   help="leave out the animated mode shapes (one looping GIF a mode)")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="local worker processes for the studies' sweeps (default: CPU count)")
    p.add_argument("--speeds", default=None, metavar="NAME=START:STOP:COUNT",
                   help="a rotor section over this speed range (or a parameter the speed "
                        "depends on): Campbell diagram, critical speeds, unbalance response")
    p.add_argument("--unbalance", default=None, metavar="AT:M_E",
                   help="the unbalance of the rotor section: station, body or point, and m·e "
                        "[kg m] (default: 1 kg m at the first disk, per unit)")
    p.set_defaults(run=run)


def _rotor_options(args, spec):
    """(speeds, unbalance) of the command line, checked: one line naming the option if bad."""
    from ..studies.sweep import parse_range

    speeds = unbalance = None
    if args.speeds is not None:
        if ":" not in args.speeds:
            raise CaseError(f"--speeds must be NAME=START:STOP:COUNT, got {args.speeds!r}",
                            element="--speeds", file=spec.source)
        try:
            speeds = parse_range(args.speeds)
        except CaseError as exc:  # (its text speaks of --param, the sweep's option)
            raise CaseError(exc.message.replace("--param expects", "expects"),
                            element="--speeds", file=spec.source) from None
    if args.unbalance is not None:
        at, _, me = args.unbalance.rpartition(":")
        try:
            value = float(me)
        except ValueError:
            value = math.nan
        if not at or not (math.isfinite(value) and value > 0):
            raise CaseError(f"--unbalance must be AT:M_E with m·e > 0 [kg m], got "
                            f"{args.unbalance!r}", element="--unbalance", file=spec.source)
        unbalance = (at, value)
    return speeds, unbalance


def run_any(args, spec) -> int:
    """The report of a case about the reference motion it declares (rest, steady or periodic:
    :func:`mbseig.studies.report_data.write_report`, one path for all three)."""
    from ..studies.report_data import write_report

    speeds, unbalance = _rotor_options(args, spec)
    md, page = write_report(spec, out_dir=args.out, configs=args.config,
                            all_configs=args.all_configs, run_check=not args.no_check,
                            jobs=args.jobs, studies=not args.no_studies,
                            sensitivities=not args.no_sensitivities,
                            animations=not args.no_animations, speeds=speeds,
                            unbalance=unbalance)
    print(f"wrote {md} and {page}")
    return 0


#: the command on every reference the case declares (its [motion] table)
run = case_command("report", rest=run_any, steady=run_any, periodic=run_any)
