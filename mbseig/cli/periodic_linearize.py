"""``mbseig linearize CASE`` on a periodic case: the linearization along the periodic
reference motion, projected on the constraints.

    x = (y, p),   δq = N(t) y,   p = Nᵀ M δq̇,   ẋ = A(t) x,   A(t + T) = A(t)

``A`` holds A(t_k) at the ``times`` t_k = kT/S of one period (S × 2r × 2r; the first-order
periodic system whose monodromy gives the Floquet multipliers, mbseig.studies.floquet_paths),
and ``M``, ``P``, ``Q`` are the reduced matrices NᵀMN, NᵀCN, NᵀKN at t = 0 (frozen at that
instant: they omit the motion's Ṅ terms and are not a stability criterion)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..studies.periodic import periodic_linearization
from .common import case_kwargs, print_json
from .linearize import json_value, write_arrays

SAMPLES = 16  # instants of A(t) written


def run(args, spec) -> int:
    kw = case_kwargs(args)
    lin = periodic_linearization(spec, config=kw["config"], params=kw["params"])
    model, ref, sys1 = lin.timed.base, lin.reference, lin.system
    T = lin.timed.period
    times = np.arange(SAMPLES) * T / SAMPLES
    A = np.array([sys1.system.segments[sys1.path.segment(t)][2](t) for t in times])
    N0 = sys1.path.bases[0]
    q, qd, _, lam = ref.at(0.0)
    m0 = lin.timed.at(0.0)
    K, C = m0.force_jacobians(q, qd, dense=True)
    K = np.asarray(K) + (np.asarray(m0.constraint_hessian(q, lam, dense=True))
                         if m0.n_constraints else 0.0)
    M = ref.partition.M
    arrays = {"M": N0.T @ M @ N0, "P": N0.T @ np.asarray(C) @ N0, "Q": N0.T @ K @ N0,
              "A": A, "times": times, "N": N0}
    meta = {
        "case": model.name, "parameters": lin.parameters, "n_coordinates": int(model.n),
        "n_constraints": int(model.n_constraints), "n_redundant": 0, "dof": int(sys1.dof),
        "period": T,
        "equilibrium": {"residual": float(ref.residual), "iterations": int(ref.iterations)},
        "reference": ref.method, "coordinate_names": list(model.coordinate_names),
        "notes": ["M, P, Q: reduced at t = 0, frozen (not a stability criterion of a periodic "
                  "motion); A: the projected first-order periodic system at the times"],
        "input_names": [], "output_names": [],
    }
    if args.out:
        write_arrays(Path(args.out), arrays, meta)
    if args.json:
        print_json({**meta, **{k: json_value(v) for k, v in arrays.items()}})
        return 0
    print(f"case {model.name}: periodic, T = {T:.6g} s, {model.n} coordinates, "
          f"{model.n_constraints} constraints, {sys1.dof} DOF; reference: {ref.method}, "
          f"residual {ref.residual:.2e}")
    if args.out:
        print(f"wrote {args.out}: {', '.join(arrays)}")
    elif sys1.dof <= 4:
        with np.printoptions(precision=6, linewidth=120):
            for k in ("M", "P", "Q"):
                print(f"{k} (t = 0, frozen) =\n{arrays[k]}")
            print(f"A(0) (projected first-order periodic system) =\n{A[0]}")
    return 0
