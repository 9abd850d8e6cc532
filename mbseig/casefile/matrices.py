"""Linear cases: ``kind = "linear"`` with a ``[matrices]`` table of M, P, Q (lists of rows,
``.npz``/``.mtx`` files, or parameter-weighted sums of such terms).

The matrix rule (every loader, inline rows and files alike): a matrix is real, square, non-empty,
of at most ``MAX_ORDER`` rows, with finite entries, and a sum of terms stays finite.  Anything
else is refused with one line naming the file and the element (``matrices.Q``), never cast: a
complex matrix (e.g. hysteretic damping (1 + iμ)K) is refused the same way by the .npz and .mtx
loaders (its imaginary part has no time-domain model in the check, the linearization outputs
and the reports; :func:`mbseig.modes` takes complex M, P, Q directly), a complex array whose
imaginary part is exactly zero is real.  Integer files are read as floats when every entry is
exactly representable (|k| ≤ 2⁵³), and refused otherwise; object arrays, truncated or empty
files and missing keys are refused.  Very large or subnormal entries are accepted: the
eigensolver scales M, P, Q (mbseig.eigen.dense).
"""

from __future__ import annotations

import zipfile

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError, MbseigError
from ..model.linear_case import LinearCase
from .expr import evaluate
from .fields import Fields

__all__ = ["linear_case", "matrix_value", "matrix_file", "MAX_ORDER"]

MAX_ORDER = 5000  # rows of one matrix of a linear case: stored dense (the dense eigen limit)
_EXACT_INT = 2**53


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
            if total is not None and total.shape != A.shape:
                raise CaseError(f"terms have different shapes ({total.shape[0]}×{total.shape[1]} "
                                f"and {A.shape[0]}×{A.shape[1]})", element=label)
            with np.errstate(over="ignore", invalid="ignore"):  # judged just below
                total = factor * A if total is None else total + factor * A
            if not np.all(np.isfinite(total)):
                raise CaseError(f"the sum of terms overflows at term {k} (factor {factor:g}): "
                                f"a matrix must stay finite", element=label)
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
    """The real square matrix stored under ``key`` of an .npz file, or in an .mtx file; every
    problem is one CaseError naming the file and ``label`` (module docstring)."""
    name = path.name
    if path.suffix not in (".npz", ".mtx"):
        raise CaseError(f"matrix files must be .npz or .mtx, got {name!r}", element=label)
    try:
        A = _read_npz(path, key, label) if path.suffix == ".npz" else _read_mtx(path, label)
    except CaseError:
        raise
    except (OSError, EOFError, ValueError, TypeError, OverflowError, IndexError, KeyError,
            MemoryError, zipfile.BadZipFile, zipfile.LargeZipFile) as exc:
        why = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise CaseError(f"{name}: cannot be read as a {path.suffix[1:]} matrix file "
                        f"({type(exc).__name__}: {why})", element=label) from None
    return _checked(A, name, label)


def _read_npz(path, key, label):
    name = path.name
    if path.stat().st_size == 0:
        raise CaseError(f"{name}: the file is empty", element=label)
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:  # fh: closed even
        keys = list(z.keys())  # when np.load fails on a truncated archive
        if key is None or key not in keys:
            have = ", ".join(keys) if keys else "no arrays"
            asked = "no key given" if key is None else f"no array {key!r}"
            raise CaseError(f"{name}: {asked} (it has {have})", element=label)
        return z[key]


def _read_mtx(path, label):
    import scipy.io

    name = path.name
    if path.stat().st_size == 0:
        raise CaseError(f"{name}: the file is empty", element=label)
    rows, cols, entries, fmt, field, symmetry = scipy.io.mminfo(str(path))
    if rows != cols or rows == 0:
        raise CaseError(f"{name}: matrix must be square and non-empty, the header says "
                        f"{rows}×{cols}", element=label)
    if rows > MAX_ORDER:
        raise CaseError(f"{name}: {rows} rows is beyond the {MAX_ORDER} of a linear case "
                        f"(matrices are stored dense)", element=label)
    A = scipy.io.mmread(str(path))
    return A.toarray() if sp.issparse(A) else np.asarray(A)


def _checked(A, name, label):
    A = np.asarray(A)
    if A.dtype.kind not in "biufc":
        raise CaseError(f"{name}: entries of type {A.dtype} are not numbers", element=label)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.size == 0:
        raise CaseError(f"{name}: matrix must be square and non-empty, got shape "
                        f"{'×'.join(str(d) for d in A.shape) or 'scalar'}", element=label)
    if A.shape[0] > MAX_ORDER:
        raise CaseError(f"{name}: {A.shape[0]} rows is beyond the {MAX_ORDER} of a linear case "
                        f"(matrices are stored dense)", element=label)
    if A.dtype.kind == "c":
        if np.any(A.imag):
            i, j = np.argwhere(A.imag != 0)[0]
            raise CaseError(f"{name}: complex entry ({i}, {j}) = {complex(A[i, j])!r}: "
                            f"linear cases take real M, P, Q (a complex stiffness has no "
                            f"time-domain model); mbseig.modes() solves complex matrices",
                            element=label)
        A = A.real
    if A.dtype.kind in "iu":
        if np.any(np.abs(A.astype(float)) > _EXACT_INT):
            i, j = np.argwhere(np.abs(A.astype(float)) > _EXACT_INT)[0]
            raise CaseError(f"{name}: integer entry ({i}, {j}) = {int(A[i, j])} is not exactly a "
                            f"double (|k| > 2^53): store the matrix as floats", element=label)
    A = np.asarray(A, dtype=float)
    if not np.all(np.isfinite(A)):
        i, j = np.argwhere(~np.isfinite(A))[0]
        raise CaseError(f"{name}: entry ({i}, {j}) = {float(A[i, j])!r} is not finite",
                        element=label)
    return A
