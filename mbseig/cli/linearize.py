"""``mbseig linearize CASE``: M, P, Q, the null-space basis, q₀, λ₀ and the state matrix.

With named ``[[inputs]]`` / ``[[outputs]]`` also B_r (M ẍ + P ẋ + Q x = B_r u), the first-order
B = [0; M⁻¹ B_r], C, D (y = C [x; ẋ] + D u) and ``input_names``, ``output_names`` (npz: string
arrays; mat: cell arrays; json: lists)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..casefile import load_case
from ..errors import CaseError, MbseigError
from ..numerics import jsonable, require_finite
from ..statics import solved
from ..studies.point import linear_stage
from .common import (
    add_case_arguments,
    case_kwargs,
    case_command,
    output_notes,
    print_json,
)

STATE_CAUSE = ("M is nearly singular against P and Q (a negligible mass or inertia): "
               "A = [0 I; -M^-1 Q  -M^-1 P] overflows")

FORMATS = (".npz", ".mat", ".json")


def register(sub):
    p = sub.add_parser("linearize", help="equilibrium and reduced linear model M, P, Q")
    add_case_arguments(p)
    p.add_argument("--out", default=None, metavar="FILE",
                   help="write the matrices to FILE (.npz, .mat or .json)")
    p.set_defaults(run=run)


def _arrays(model, eq, lin):
    arrays = {"M": lin.M, "P": lin.P, "Q": lin.Q, "N": lin.N, "q0": lin.q0, "lam0": lin.lam0}
    if getattr(lin, "constraint_jacobian", None) is not None:  # large constrained model: Φ_q, no N
        arrays["G"] = lin.constraint_jacobian
    arrays = {k: v for k, v in arrays.items() if v is not None}
    if sp.issparse(lin.M):
        return arrays  # large model kept sparse (mbseig.linear.SPARSE_MIN): no dense state matrix
    if lin.B is not None and (lin.input_names or lin.output_names):
        # named signals: M ẍ + P ẋ + Q x = B_r u; y = C [x; ẋ] + D u
        arrays.update({"B_r": lin.B, "C": lin.C, "D": lin.D})
    try:
        with np.errstate(all="ignore"):  # judged by the finiteness check below
            arrays["A"] = lin.state_matrix()
            if "B_r" in arrays:  # the first-order quadruple (A, B, C, D), z = [x; ẋ]
                arrays["B"] = lin.state_space()[1]
    except np.linalg.LinAlgError:
        pass  # singular M: no first-order state matrix (descriptor form only)
    else:
        require_finite("linearization", STATE_CAUSE, A=arrays["A"], B=arrays.get("B"))
    return arrays


def json_value(v):
    """A dense array as nested lists; a sparse one as its CSR parts."""
    if sp.issparse(v):
        v = v.tocsr()
        return {"format": "csr", "shape": list(v.shape), "data": v.data.tolist(),
                "indices": v.indices.tolist(), "indptr": v.indptr.tolist()}
    return v.tolist()


def _npz_arrays(arrays):
    """Sparse matrices as ``K_data, K_indices, K_indptr, K_shape`` (CSR parts)."""
    out = {}
    for k, v in arrays.items():
        if sp.issparse(v):
            v = v.tocsr()
            out.update({f"{k}_data": v.data, f"{k}_indices": v.indices, f"{k}_indptr": v.indptr,
                        f"{k}_shape": np.array(v.shape)})
        else:
            out[k] = v
    return out


def run_rest(args, spec) -> int:
    kwargs = case_kwargs(args)
    model = load_case(args.case, config=kwargs["config"], **kwargs["params"])
    try:
        eq, lin = linear_stage(model)
        model = solved(model, eq)
        arrays = _arrays(model, eq, lin)
    except MbseigError as exc:
        raise exc.located(file=model.source) from None
    meta = {
        "case": model.name, "parameters": dict(model.parameters),
        "n_coordinates": int(model.n), "n_constraints": int(lin.n_constraints),
        "n_redundant": int(eq.n_redundant), "dof": int(lin.dof),
        "equilibrium": {"residual": float(eq.residual), "iterations": int(eq.iterations)},
        "coordinate_names": list(model.coordinate_names),
        "rank_tol": lin.tolerances.get("rank_tol"),
        "notes": output_notes(model, eq),
        "input_names": list(lin.input_names), "output_names": list(lin.output_names),
        "output_units": list(lin.output_units),
        "input_units": list(lin.input_units),
    }
    if args.out:
        write_arrays(Path(args.out), arrays, meta)
    if args.json:
        print_json({**meta, **{k: json_value(v) for k, v in arrays.items()}})
    else:
        print(f"case {model.name}: {model.n} coordinates, {lin.n_constraints} constraints "
              f"({eq.n_redundant} redundant), {lin.dof} DOF; equilibrium residual "
              f"{eq.residual:.2e} after {eq.iterations} iterations")
        for note in meta["notes"]:
            print(f"note: {note}")
        if args.out:
            print(f"wrote {args.out}: {', '.join(arrays)}")
        elif lin.dof <= 8:
            with np.printoptions(precision=6, suppress=False, linewidth=120):
                for k in ("M", "P", "Q", "B_r", "C", "D"):
                    if k in arrays:
                        print(f"{k} =\n{arrays[k]}")
                if meta["input_names"] or meta["output_names"]:
                    print(f"inputs: {', '.join(meta['input_names']) or 'none'}; outputs: "
                          f"{', '.join(meta['output_names']) or 'none'} "
                          f"(y = C [x; xdot] + D u, M x'' + P x' + Q x = B_r u)")
    return 0


def write_arrays(path, arrays, meta):
    if path.suffix not in FORMATS:
        raise CaseError(f"output must end in {', '.join(FORMATS)}", file=str(path), element="--out")
    try:
        if path.suffix == ".npz":
            np.savez(path, coordinate_names=np.array(meta["coordinate_names"]),
                     input_names=np.array(meta["input_names"], dtype=str),
                     output_names=np.array(meta["output_names"], dtype=str),
                     **_npz_arrays(arrays))
        elif path.suffix == ".mat":
            import scipy.io

            names = {k: np.array(meta[k], dtype=object) for k in ("input_names", "output_names")}
            scipy.io.savemat(str(path), {**arrays, "coordinate_names": meta["coordinate_names"],
                                         **names})
        else:
            path.write_text(json.dumps(jsonable({**meta, **{k: json_value(v)
                                                            for k, v in arrays.items()}})))
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(path),
                        element="--out") from None


# ---- steady motion (steady reference: [motion] with speed)
# ``mbseig linearize CASE`` on a steady motion (DESIGN §8): the first-order descriptor system
# E Ẋ = A X about the motion, X = [x; z] (d positions on the holonomic manifold, k independent
# velocities; :func:`mbseig.studies.steady.linearize_steady`), with the maps back to the full
# coordinates, q = q₀(t) + N x and [q̇ − q̇₀; Ω − Ω₀] = [N 0; 0 I](T z − S x).
#
# The pencil is also written in mbseig's quadratic convention, (M s² + P s + Q) X = 0 with M = 0,
# P = E, Q = −A (``dof`` = d + k, the size of X), and E is invertible, so ``A_state`` = E⁻¹A is the
# state matrix.  ``--out FILE`` writes .npz, .mat or .json.
STEADY_FORMATS = (".npz", ".mat", ".json")


def _steady_arrays(a) -> dict:
    lin, st = a.linear, a.state
    n = lin.E.shape[0]
    return {"E": lin.E, "A": np.linalg.solve(lin.E, lin.A), "A_descriptor": lin.A,
            "M": np.zeros((n, n)), "P": lin.E, "Q": -lin.A, "N": lin.N, "T": lin.T, "S": lin.S,
            "q0": st.q, "qd0": st.qd, "spin0": st.spin, "lam0": st.lam, "mu0": st.mu}


def run_steady(args, spec) -> int:
    from ..studies.steady_modes import analyze_steady

    out_path = getattr(args, "out", None)
    if out_path is not None and Path(out_path).suffix not in STEADY_FORMATS:
        raise CaseError(f"--out must end in {', '.join(STEADY_FORMATS)}, got {out_path!r}",
                        element="command line")
    kw = case_kwargs(args)
    a = analyze_steady(spec, config=kw["config"], params=kw["params"])
    arrays = _steady_arrays(a)
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
            p.write_text(json.dumps(jsonable({**info,
                                              **{k: v.tolist() for k, v in arrays.items()}}),
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


# ---- periodic motion (periodic reference: [motion] with period)
# ``mbseig linearize CASE`` on a periodic case: the linearization along the periodic
# reference motion, projected on the constraints.
#
#     x = (y, p),   δq = N(t) y,   p = Nᵀ M δq̇,   ẋ = A(t) x,   A(t + T) = A(t)
#
# ``A`` holds A(t_k) at the ``times`` t_k = kT/S of one period (S × 2r × 2r; the first-order
# periodic system whose monodromy gives the Floquet multipliers, mbseig.studies.floquet_paths),
# and ``M``, ``P``, ``Q`` are the reduced matrices NᵀMN, NᵀCN, NᵀKN at t = 0 (frozen at that
# instant: they omit the motion's Ṅ terms and are not a stability criterion).
SAMPLES = 16  # instants of A(t) written


def run_periodic(args, spec) -> int:
    from ..studies.periodic import periodic_linearization
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


#: the command on every reference the case declares (its [motion] table)
run = case_command("linearize", rest=run_rest, steady=run_steady, periodic=run_periodic)
