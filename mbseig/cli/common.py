"""Options shared by the subcommands."""

from __future__ import annotations

import functools
import json
import sys

from ..casefile import parse_param_overrides
from ..casefile.fields import RANGE_RULE, in_range
from ..errors import CaseError
from ..numerics import jsonable

__all__ = ["add_case_arguments", "case_kwargs", "print_json", "print_reactions", "number_option",
           "output_notes", "equilibrium_notes", "moving_case", "case_command",
           "analyzed"]


def add_case_arguments(parser):
    parser.add_argument("case", metavar="CASE", help="case file (TOML)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a case parameter (repeatable); VALUE may be an expression")
    parser.add_argument("--config", default=None, metavar="NAME",
                        help="a named configuration of the case's [configurations] table")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def case_kwargs(args) -> dict:
    return {"config": args.config, "params": parse_param_overrides(args.param)}


def print_json(obj) -> int:
    """Print ``obj`` as one JSON object; returns the command's exit code 0."""
    json.dump(jsonable(obj), sys.stdout, indent=1, allow_nan=False)
    sys.stdout.write("\n")
    return 0


def analyzed(args, spec, analyze):
    """``analyze(spec, config=..., params=...)`` with the command line's configuration and
    parameter overrides (the moving-case analyses take the case as read once)."""
    kw = case_kwargs(args)
    return analyze(spec, config=kw["config"], params=kw["params"])


def print_reactions(rows):
    """The reaction table of :func:`mbseig.statics.reactions.reaction_forces`, one line a
    constraint: multipliers, what they carry (the element's own label and unit), point forces."""
    if not rows:
        return
    print("reactions at equilibrium (multipliers λ; force on each point = −Φ_qᵀλ):")
    for r in rows:
        lam = ", ".join(f"{x:.6g}" for x in r["multipliers"])
        c = r["reaction"]
        value = c["value"] if isinstance(c["value"], list) else [c["value"]]
        carried = f"{c['label']} {', '.join(f'{v:.6g}' for v in value)} {c['unit']}".rstrip()
        forces = "; ".join(f"{p} ({', '.join(f'{v:.6g}' for v in f)})" for p, f in r["forces"].items())
        print(f"  {r['element']}: λ = {lam}; {carried}; on {forces}")


def number_option(name, value, *, positive=False, nonnegative=False, minimum=None):
    """A numeric command-line option checked like a case number (finite, 0 or of magnitude
    1e-100 to 1e100), and positive, non-negative or at least ``minimum`` where the option says
    so (None passes through)."""
    if value is None:
        return None
    rule = ("a positive number" if positive else "a non-negative number" if nonnegative
            else f"a number >= {minimum:g}" if minimum is not None else "a number")
    ok = in_range(value) and (not positive or value > 0) and (
        not nonnegative or value >= 0) and (minimum is None or value >= minimum)
    if not ok:
        raise CaseError(f"{name} must be {rule} ({RANGE_RULE}), got {value!r}",
                        element="command line")
    return value


def output_notes(model, eq):
    """What the reported warnings said (mbseig.errors.ReportedWarning), for the output: the
    beam-theory guidance of every beam and the equilibrium's notes."""
    bodies = (getattr(model, "flexible", None) or {}).get("bodies") or {}
    return ([f"beam {nm}: {w}" for nm, r in bodies.items() for w in r.get("warnings", ())]
            + [f"equilibrium: {n}" for n in equilibrium_notes(eq)])


def equilibrium_notes(eq):
    """The equilibrium's notes (static stability, self-stress), as strings."""
    return [str(n) for n in (getattr(eq, "notes", None) or ())]


def moving_case(command, spec):
    """The module that runs ``command`` on a case with a ``[motion]`` table (DESIGN §8), or None
    for a static case: ``mbseig.cli.{kind}_{command}`` with kind ``steady`` or ``periodic``
    (:func:`mbseig.casefile.motion_kind`).  A command that has none for that kind is refused in
    one line, never run as if the case were at rest."""
    import importlib

    from ..casefile import motion_kind

    try:
        kind = motion_kind(spec.data)
    except CaseError as exc:
        raise exc.located(file=spec.source) from None
    if kind is None:
        return None
    try:
        return importlib.import_module(f".{kind}_{command}", __package__)
    except ModuleNotFoundError as exc:
        if exc.name != f"{__package__}.{kind}_{command}":
            raise
        raise CaseError(f"mbseig {command} does not analyse {kind} motions ([motion] with "
                        f"{'period' if kind == 'periodic' else 'speed'})", element="motion",
                        file=spec.source) from None


def case_command(command):
    """Decorate ``run(args, spec)`` of ``mbseig COMMAND`` for a case at rest: the case is read
    once; a case with a ``[motion]`` table goes to its own module instead (:func:`moving_case`),
    or is refused in one line."""
    def wrap(run_static):
        @functools.wraps(run_static)
        def run(args) -> int:
            from ..studies.point import as_spec

            spec = as_spec(args.case)
            moving = moving_case(command, spec)
            if moving is not None:
                return moving.run(args, spec)
            return run_static(args, spec)
        return run
    return wrap
