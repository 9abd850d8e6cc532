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
    if not args.stiffness:
        print(rest_note(args.out, gravity=not args.no_gravity))
    return 0


HOLD = ("for the robot held at its reference posture (servos as joint springs) give "
        "--stiffness default=K (N m/rad; N/m on prismatic joints) and --damping default=C "
        "(or --damping urdf)")


def rest_note(path, *, gravity=True) -> str:
    """What the equilibrium of an imported case without joint springs is (solved from its
    reference posture) and how to get a stable rest position: springs, or the stable rest
    position that :func:`mbseig.equilibrium` offers as ``eq.stable_alternative``."""
    import warnings

    from ..casefile import load_case
    from ..errors import MbseigError
    from ..statics import StaticInstabilityWarning, equilibrium

    head = "note: no joint springs (--stiffness): nothing holds the joints"
    if not gravity:
        return (f"{head} and there is no gravity, so every posture is at rest and every mode "
                f"is a rigid-body one; {HOLD}")
    try:
        with warnings.catch_warnings():  # its text is eq.notes, said below
            warnings.simplefilter("ignore", StaticInstabilityWarning)
            eq = equilibrium(load_case(path))
    except MbseigError as exc:
        return (f"{head}, so gravity alone sets the rest position, and from the reference "
                f"posture none was found ({exc.message}); {HOLD}")
    static = eq.static or {}
    verdict = static.get("verdict", "not examined")
    found = f"statically {verdict} ({eq.iterations} Newton iterations from the reference posture)"
    if verdict == "unstable":
        found = (f"statically unstable, {static.get('index')} direction(s) of negative "
                 f"stiffness ({eq.iterations} Newton iterations from the reference posture)")
        alt = eq.stable_alternative
        found += (f"; a stable rest position exists ({alt.method}), offered in Python as "
                  f"mbseig.equilibrium(model).stable_alternative" if alt is not None else
                  "; the statics' search for a stable rest position from there (load "
                  "continuation, descent along the unstable direction; "
                  "eq.stable_alternative) found none: --position JOINT=VALUE starts it from "
                  "another posture")
    elif verdict == "neutral":
        found += (": a direction of zero stiffness remains (a joint that gravity does not "
                  "load, such as one about the vertical), so no rest position is strictly stable")
    return (f"{head}, so gravity alone sets the rest position; the equilibrium found is "
            f"{found}; {HOLD}")
