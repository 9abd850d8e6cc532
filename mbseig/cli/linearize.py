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


@case_command("linearize")
def run(args, spec) -> int:
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
            path.write_text(json.dumps(jsonable({**meta, **{k: json_value(v) for k, v in arrays.items()}})))
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(path), element="--out") from None
