"""``mbseig unbalance CASE --param Omega=LO:HI:N --at STATION --me M_E``: the synchronous
response of a spinning rotor to an unbalance (mbseig.studies.unbalance), as a table, JSON, CSV
and Bode and polar figures."""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..casefile import parse_param_overrides
from ..errors import CaseError
from .common import (
    add_case_arguments,
    case_command,
    number_option,
    parameter_units_of,
    print_json,
)


def register(sub):
    p = sub.add_parser(
        "unbalance", help="synchronous response of a spinning rotor to an unbalance m·e",
        description="Steady response to the rotating force m·e·Ω² of an unbalance at a station, "
                    "over a swept parameter: --param NAME=START:STOP:COUNT (exactly one: the "
                    "rotor speed, or any parameter it depends on; --param NAME=VALUE fixes "
                    "others). Prints the amplitude and phase at every rotor station and named "
                    "output, x(t) = |X| cos(Omega t + phase), for the two lateral directions "
                    "e1, e2 normal to the spin axis, and the orbit's major semi-axis.")
    add_case_arguments(p)
    p.add_argument("--at", required=True, metavar="STATION",
                   help="where the unbalance sits: a beam station BEAM.NAME, a body (its centre "
                        "of mass) or a point of the case")
    p.add_argument("--me", required=True, type=float, metavar="M_E",
                   help="the unbalance m·e [kg m] (the response is proportional to it)")
    p.add_argument("--angle", type=float, default=0.0, metavar="DEG",
                   help="angle of the unbalance at t = 0 from e1 about the spin axis [deg] "
                        "(default 0; e1, e2 as printed)")
    p.add_argument("--station", action="append", default=None, metavar="NAME",
                   help="a station or output drawn in the figures (repeatable; default: the "
                        "named stations and the outputs in m, at most 10); the table and JSON "
                        "list every one")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="write unbalance.csv, unbalance.json, unbalance_bode.png and "
                        "unbalance_polar.png to DIR")
    p.set_defaults(run=run)


@case_command("unbalance")
def run(args, spec) -> int:
    from ..studies.sweep import parse_range
    from ..studies.unbalance import unbalance_response

    ranges = [parse_range(item) for item in args.param if ":" in item]
    fixed = parse_param_overrides([item for item in args.param if ":" not in item])
    if len(ranges) != 1:
        raise CaseError("give one --param NAME=START:STOP:COUNT (the speed or a parameter it "
                        f"depends on), got {len(ranges)}", element="--param", file=spec.source)
    number_option("--me", args.me, positive=True)
    number_option("--angle", args.angle)
    name, values = ranges[0]
    res = unbalance_response(spec, name, values, at=args.at, unbalance=args.me,
                             phase=math.radians(args.angle), config=args.config, fixed=fixed)
    known = set(res.stations) | set(res.outputs)
    unknown = [st for st in args.station or () if st not in known]
    if unknown:
        raise CaseError(f"unknown station or output {unknown[0]!r} (known: "
                        f"{', '.join(sorted(known))})", element="--station", file=spec.source)
    unit = parameter_units_of(spec).get(name)
    paths = write_unbalance(res, args.out, unit=unit, stations=args.station) if args.out else []
    if args.json:
        return print_json(res.to_json())
    d = res.directions or {}
    vec = ", ".join
    print(f"unbalance {res.unbalance:g} kg m at {res.at}, angle {args.angle:g} deg, over "
          f"{name} = {values[0]:g} … {values[-1]:g}" + (f" {unit}" if unit and unit != "1" else "")
          + f" ({len(values)} values)")
    print(f"spin axis ({vec(f'{x:.4g}' for x in d.get('axis', ()))}); lateral components "
          f"x1 along e1 = ({vec(f'{x:.4g}' for x in d.get('e1', ()))}), x2 along e2 = "
          f"({vec(f'{x:.4g}' for x in d.get('e2', ()))}); x(t) = |X| cos(Omega t + phase)")
    print(res.listing(unit))
    hits = res.resonance_values()
    if hits:
        print(f"resonance at {name} = {', '.join(f'{v:g}' for v in hits)}: the unbalance drives "
              f"an undamped mode at its own frequency, no steady response (null in the JSON)")
    if paths:
        print("wrote " + ", ".join(str(p) for p in paths))
    return 0


def write_unbalance(res, out_dir, *, unit=None, stations=None, critical=()):
    """unbalance.csv, unbalance.json and the Bode and polar figures in ``out_dir``."""
    from ..plots import rotor, save

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CaseError(f"cannot create the directory: {exc.strerror or exc}", file=str(out),
                        element="--out") from None
    paths = [res.write_csv(out / "unbalance.csv")]
    path = out / "unbalance.json"
    path.write_text(json.dumps(res.to_json(), indent=1, allow_nan=False) + "\n")
    paths.append(path)
    paths.append(save(rotor.unbalance_bode(res, unit=unit, stations=stations,
                                           critical=critical), out / "unbalance_bode.png"))
    paths.append(save(rotor.unbalance_polar(res, unit=unit, stations=stations),
                      out / "unbalance_polar.png"))
    return paths
