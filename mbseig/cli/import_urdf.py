"""``mbseig import-urdf ROBOT.urdf --out CASE.toml``: write the plain 3-D case of a URDF robot
(:func:`mbseig.casefile.urdf.import_urdf`).

    mbseig import-urdf arm.urdf --out arm.toml --position shoulder=0.4 --position elbow=-0.8 \\
        --stiffness default=400 --stiffness shoulder=1500 --damping urdf [--floating]
"""

from __future__ import annotations

import math

from ..errors import CaseError

__all__ = ["register"]


def register(sub):
    p = sub.add_parser("import-urdf", help="write the plain 3-D case of a URDF robot")
    p.add_argument("urdf", metavar="ROBOT.urdf")
    p.add_argument("--out", required=True, metavar="CASE.toml")
    p.add_argument("--position", action="append", default=[], metavar="JOINT=VALUE",
                   help="reference joint value, rad or m (repeatable; others 0)")
    p.add_argument("--stiffness", action="append", default=[], metavar="JOINT=K",
                   help="joint spring, N m/rad or N/m; JOINT may be 'default' (repeatable)")
    p.add_argument("--damping", action="append", default=[], metavar="JOINT=C",
                   help="joint damper as --stiffness, or 'urdf' for each <dynamics damping>")
    p.add_argument("--floating", action="store_true", help="free base (default: welded root)")
    p.add_argument("--no-gravity", action="store_true", help="leave gravity out of the case")
    p.set_defaults(run=run)


def _pairs(items, option):
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name.strip() or not math.isfinite(number):
            raise CaseError(f"expects JOINT=NUMBER, got {item!r}", element=option)
        out[name.strip()] = number
    return out


def run(args):
    from ..casefile.urdf import import_urdf

    damping = "urdf" if args.damping == ["urdf"] else _pairs(args.damping, "--damping")
    case = import_urdf(args.urdf, args.out, positions=_pairs(args.position, "--position"),
                       stiffness=_pairs(args.stiffness, "--stiffness") or None,
                       damping=damping or None, floating=args.floating,
                       gravity=None if args.no_gravity else (0.0, 0.0, -9.81))
    print(f"{args.out}: {len(case.get('bodies', []))} bodies, {len(case.get('joints', []))} "
          f"joints, {len(case.get('forces', []))} forces")
    return 0
