"""Options shared by the subcommands."""

from __future__ import annotations

import json
import sys

from ..casefile import parse_param_overrides
from ..numerics import jsonable

__all__ = ["add_case_arguments", "case_kwargs", "print_json", "print_reactions"]


def add_case_arguments(parser):
    parser.add_argument("case", metavar="CASE", help="case file (TOML)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a case parameter (repeatable); VALUE may be an expression")
    parser.add_argument("--config", default=None, metavar="NAME",
                        help="a named configuration of the case's [configurations] table")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def case_kwargs(args) -> dict:
    return {"config": args.config, "params": parse_param_overrides(args.param)}


def print_json(obj):
    json.dump(jsonable(obj), sys.stdout, indent=1, allow_nan=False)
    sys.stdout.write("\n")


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
