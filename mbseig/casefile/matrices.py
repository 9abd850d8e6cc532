"""Linear cases: ``kind = "linear"`` with a ``[matrices]`` table of M, P, Q (lists of rows,
``.npz``/``.mtx`` files, or parameter-weighted sums of such terms)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError, MbseigError
from ..model.linear_case import LinearCase
from .expr import evaluate
from .fields import Fields

__all__ = ["linear_case", "matrix_value", "matrix_file"]


def linear_case(data, name, source, files, params, description, expected):
    mats = data.get("matrices")
    if not isinstance(mats, dict):
        raise CaseError("a linear case needs a [matrices] table with M, P (optional) and Q",
                        element="matrices")
    unknown = sorted(set(mats) - {"M", "P", "Q"})
    if unknown:
        raise CaseError(f"unknown matrix {unknown[0]!r} (M, P, Q)", element="matrices")
    out = {}
    for key in ("M", "Q", "P"):
        if key not in mats:
            if key == "P":
                continue
            raise CaseError(f"missing matrix {key}", element="matrices")
        out[key] = matrix_value(mats[key], f"matrices.{key}", params, files)
    n = out["M"].shape[0]
    out.setdefault("P", np.zeros((n, n)))
    for key, A in out.items():
        if A.shape != (n, n):
            raise CaseError(f"must be {n}×{n} like M, got {A.shape[0]}×{A.shape[1]}",
                            element=f"matrices.{key}")
    return LinearCase(name=name, source=source, parameters=dict(params), M=out["M"], P=out["P"],
                      Q=out["Q"], description=description, expected=expected)


def matrix_value(value, label, params, files):
    """A matrix, a {file = ...} reference, or a list of {factor, matrix|file} terms.

    files(name, key, label) returns the array stored in a matrix file next to the case (read
    once per case: :class:`mbseig.casefile.CaseSpec`)."""
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        total = None
        for k, term in enumerate(value):
            f = Fields(term, f"{label}[{k}]", params)
            factor = f.num("factor", 1.0)
            A = matrix_value(f.raw("matrix"), f"{label}[{k}].matrix", params, files)
            f.done()
            total = factor * A if total is None else total + factor * A
            if total.shape != A.shape:
                raise CaseError("terms have different shapes", element=label)
        return total
    if isinstance(value, dict):
        f = Fields(value, label, params)
        fname = f.text("file")
        key = f.text("key", None)
        f.done()
        return files(fname, key, label)
    if isinstance(value, list) and value and all(isinstance(r, list) for r in value):
        width = len(value[0])
        if width == 0 or any(len(r) != width for r in value) or width != len(value):
            raise CaseError("a matrix must be a non-empty square list of rows", element=label)
        try:
            return np.array([[evaluate(x, params) for x in row] for row in value])
        except MbseigError as exc:
            raise exc.located(element=label) from None
    raise CaseError("expected a matrix (list of rows), {file = ...} or a list of terms",
                    element=label)


def matrix_file(path, key, label):
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as z:
                if key is None or key not in z:
                    raise CaseError(f"{path.name} has no array {key!r} (has {', '.join(z)})",
                                    element=label)
                A = np.asarray(z[key], dtype=float)
        elif path.suffix == ".mtx":
            import scipy.io

            A = scipy.io.mmread(str(path))
            A = A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)
        else:
            raise CaseError(f"matrix files must be .npz or .mtx, got {path.name!r}", element=label)
    except OSError as exc:
        raise CaseError(f"cannot read {path}: {exc}", element=label) from None
    except ValueError as exc:
        raise CaseError(f"cannot read {path}: {exc}", element=label) from None
    if A.ndim != 2 or A.shape[0] != A.shape[1] or not np.all(np.isfinite(A)):
        raise CaseError(f"{path.name}: matrix must be square and finite", element=label)
    return A
