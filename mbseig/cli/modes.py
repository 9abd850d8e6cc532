"""``mbseig modes CASE``: the modes, their stability and the verdict."""

from __future__ import annotations

from ..analysis import analyze, modes_json
from ..qep import SOLVERS
from .common import add_case_arguments, case_kwargs, print_json


def register(sub):
    p = sub.add_parser("modes", help="solve the modes and classify their stability")
    add_case_arguments(p)
    p.add_argument("--solver", default="auto", choices=["auto", *SOLVERS],
                   help="eigensolver path (default: chosen by structure)")
    p.add_argument("--reactions", action="store_true",
                   help="also print the constraint multipliers (joint reactions) at equilibrium")
    p.set_defaults(run=run)


def run(args) -> int:
    a = analyze(args.case, solver=args.solver, **case_kwargs(args))
    if args.json:
        out = modes_json(a)
        if args.reactions:
            out["reactions"] = [{"element": nm, "multipliers": [float(x) for x in lam]}
                                for nm, lam in a.eq.reactions]
        print_json(out)
        return 0
    m, eq, lin = a.model, a.eq, a.linear
    n_c = getattr(m, "n_constraints", 0)
    print(f"case {m.name}: {m.n} coordinates, {n_c} constraints ({eq.n_redundant} redundant), "
          f"{lin.dof} DOF")
    if eq.redundant:
        print("redundant: " + "; ".join(eq.redundant))
    print(f"equilibrium: residual {eq.residual:.2e} after {eq.iterations} Newton iterations")
    print(f"solver: {a.modes.solver} ({a.modes.solver_reason})")
    print(a.modes.table())
    print(f"verdict: {a.modes.verdict}")
    if args.reactions:
        print("reactions (constraint multipliers λ; force = −Φ_qᵀλ):")
        for nm, lam in eq.reactions:
            print(f"  {nm}: " + ", ".join(f"{x:.6g}" for x in lam))
    return 0
