"""``mbseig report CASE``: report.md and a self-contained report.html."""

from __future__ import annotations

from ..errors import CaseError

from pathlib import Path
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
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (default reports/CASE)")
    p.add_argument("--no-check", action="store_true", help="skip the time-domain check")
    p.add_argument("--no-studies", action="store_true", help="skip the [[report.studies]] sweeps")
    p.add_argument("--no-sensitivities", action="store_true",
                   help="leave out the eigenvalue sensitivities of the summary")
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
    from ..errors import CaseError
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


def run_rest(args, spec) -> int:
    from ..report import write_report

    speeds, unbalance = _rotor_options(args, spec)
    md, page = write_report(args.case, out_dir=args.out, configs=args.config,
                            all_configs=args.all_configs, run_check=not args.no_check,
                            jobs=args.jobs, studies=not args.no_studies,
                            sensitivities=not args.no_sensitivities, speeds=speeds,
                            unbalance=unbalance)
    print(f"wrote {md} and {page}")
    return 0


# ---- steady motion (steady reference: [motion] with speed)
# ``mbseig report CASE`` on a steady motion (DESIGN §8): report.md and a self-contained
# report.html on the page every motion shares, with the motion, the steady state (residual,
# spins, each wheel's normal force and state), the modes with their verdict, shapes and pole map,
# and the time-domain check (unless ``--no-check``).  Computed by
# :mod:`mbseig.studies.steady_report`, formatted by :mod:`mbseig.report.steady`.
def run_steady(args, spec) -> int:
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


# ---- periodic motion (periodic reference: [motion] with period)
# ``mbseig report CASE`` on a periodic case (DESIGN §8): report.md and a self-contained
# report.html with the Floquet multipliers and their bounds, the verdict and what decided it, the
# frozen-time eigenvalues beside them (not a criterion), the multipliers on the unit circle, the
# time-domain check (unless ``--no-check``) and the ``[[report.studies]]`` sweeps (unless
# ``--no-studies``; a study with ``lines`` also draws the stability chart).  Computed by
# :mod:`mbseig.studies.periodic_report`, formatted by :mod:`mbseig.report.periodic`.
def run_periodic(args, spec) -> int:
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


#: the command on every reference the case declares (its [motion] table)
run = case_command("report", rest=run_rest, steady=run_steady, periodic=run_periodic)
