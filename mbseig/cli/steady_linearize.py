"""``mbseig linearize CASE`` on a steady motion (DESIGN §8): the first-order descriptor system
E Ẋ = A X about the motion, X = [x; z] (d positions on the holonomic manifold, k independent
velocities; :func:`mbseig.studies.steady.linearize_steady`), with the maps back to the full
coordinates, q = q₀(t) + N x and [q̇ − q̇₀; Ω − Ω₀] = [N 0; 0 I](T z − S x).

The pencil is also written in mbseig's quadratic convention, (M s² + P s + Q) X = 0 with M = 0,
P = E, Q = −A (``dof`` = d + k, the size of X), and E is invertible, so ``A_state`` = E⁻¹A is the
state matrix.  ``--out FILE`` writes .npz, .mat or .json."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import CaseError
from ..numerics import jsonable
from .common import case_kwargs, print_json

__all__ = ["run"]

FORMATS = (".npz", ".mat", ".json")


def _arrays(a) -> dict:
    lin, st = a.linear, a.state
    n = lin.E.shape[0]
    return {"E": lin.E, "A": np.linalg.solve(lin.E, lin.A), "A_descriptor": lin.A,
            "M": np.zeros((n, n)), "P": lin.E, "Q": -lin.A, "N": lin.N, "T": lin.T, "S": lin.S,
            "q0": st.q, "qd0": st.qd, "spin0": st.spin, "lam0": st.lam, "mu0": st.mu}


def run(args, spec) -> int:
    from ..studies.steady_modes import analyze_steady

    out_path = getattr(args, "out", None)
    if out_path is not None and Path(out_path).suffix not in FORMATS:
        raise CaseError(f"--out must end in {', '.join(FORMATS)}, got {out_path!r}",
                        element="command line")
    kw = case_kwargs(args)
    a = analyze_steady(spec, config=kw["config"], params=kw["params"])
    arrays = _arrays(a)
    lin = a.linear
    info = {"case": a.model.name, "parameters": dict(a.model.parameters),
            "form": "descriptor: E X' = A_descriptor X, X = [positions; independent velocities]; "
                    "also M = 0, P = E, Q = -A_descriptor; A = E^-1 A_descriptor",
            "dof": int(lin.E.shape[0]), "n_positions": int(lin.dof),
            "n_velocities": int(lin.n_velocities),
            "motion": {"speed": a.motion.speed, "direction": list(a.motion.direction),
                       "yaw_rate": a.motion.yaw_rate},
            "contacts": [dict(c) for c in a.state.contacts]}
    if out_path is not None:
        p = Path(out_path)
        if p.suffix == ".npz":
            np.savez(p, **arrays)
        elif p.suffix == ".mat":
            from scipy.io import savemat

            savemat(p, arrays)
        else:
            p.write_text(json.dumps(jsonable({**info, **{k: v.tolist() for k, v in arrays.items()}}),
                                    allow_nan=False))
    if args.json:
        print_json({**info, **{k: v.tolist() for k, v in arrays.items()}})
        return 0
    print(f"case {info['case']}: steady motion, descriptor system E X' = A X of size "
          f"{info['dof']} ({info['n_positions']} positions, {info['n_velocities']} independent "
          f"velocities)")
    if out_path is not None:
        print(f"written: {out_path}")
    return 0
