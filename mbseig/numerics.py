"""Small numerical helpers shared by every stage (the bottom layer, above :mod:`mbseig.errors`).

- sparse assembly: :func:`scatter` (dense local blocks) and :func:`coo_sum` (COO triplets);
- the rank of a constraint Jacobian and the orthonormal basis of its null space, one rule for
  the whole pipeline (docs/design.md, "Tolerances"): σ_k counts when σ_k > rank_tol · σ_max;
- column norms of real or complex blocks without complex temporaries;
- :func:`jsonable`, strict-JSON values (non-finite floats become null);
- stage boundaries (README, "Input rules"): :func:`require_finite` and :func:`watched` turn a
  non-finite result or an arithmetic overflow inside a stage into one
  :class:`~mbseig.errors.NumericalError` naming the stage and the likely cause.
"""

from __future__ import annotations

import ast
import contextlib
import math
import re
import warnings
from itertools import groupby

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .errors import MbseigError, NumericalError

__all__ = ["LazyModule", "min_norm_projection", "scatter", "coo_sum", "dense", "constraint_rank",
           "null_space_basis", "colnorm", "unit_columns", "jsonable", "nonfinite", "require_finite",
           "watched", "DOUBLE_RANGE", "blas_limit", "element_name", "user_names", "grow_columns"]


# an element's label as the reader makes it (casefile.fields.expand): ``forces[3] 'actuator'``,
# the name as repr() quotes it, possibly followed by a part (`` (rigid length)``)
_LABEL = re.compile(r"""\b[a-z_]+\[\d+\] ('(?:[^'\\]|\\.)*'|"(?:[^"\\]|\\.)*")""")


def element_name(label, *, part=True) -> str:
    """The name the user wrote for an element: ``forces[3] 'actuator'`` → ``actuator``;
    ``bodies[1] 'middle' (rigid length)`` → ``middle (rigid length)`` (``part=False``:
    ``middle``).  A label without a name is returned as it is."""
    text = str(label)
    m = _LABEL.search(text)
    if m is None or m.start() != len(text) - len(text.lstrip()):
        return text
    name = _unquote(m)
    return name + text[m.end():].rstrip() if part else name


def user_names(text):
    """Every element label in ``text`` replaced by the user's name (reports, tables)."""
    if not isinstance(text, str):
        return text
    return _LABEL.sub(_unquote, text)


def _unquote(match) -> str:
    """The name inside a label's repr() quotes (escapes undone exactly: the reader wrote it)."""
    return ast.literal_eval(match.group(1))


class LazyModule:
    """A module imported at its first attribute access: ``spla = LazyModule(
    "scipy.sparse.linalg")`` keeps the sparse solvers (≈ 80 ms of import) off the start-up of a
    command that never factorizes a sparse matrix."""

    def __init__(self, name):
        self._name = name

    def __getattr__(self, attr):
        import importlib

        return getattr(importlib.import_module(self._name), attr)


DOUBLE_RANGE = "the double-precision range (2.2e-308 to 1.8e308)"
# numpy's floating-point warnings (np.errstate "warn"): a number left the double range
_FLOAT_WARNING = re.compile(r"(overflow|divide by zero|invalid value) encountered")


DENSE_ASSEMBLY = 300  # coordinates + constraints up to which the statics and the continuation
# assemble a model's Jacobians as dense arrays (``dense=True``): at the size of a device (10
# coordinates, 7 constraints) one CSR construction or operation costs 20–150 µs of scipy's
# Python, the dense one ≈ 1 µs, and the Newton matrix of such a model is decomposed densely (by
# the SVD, mbseig.statics.linalg.SMALL = 300 unknowns) anyway


def scatter(n_rows, n_cols, blocks, *, dense=False, nonzero=False):
    """Sum of dense local blocks (row indices, column indices, values) into a CSR matrix, or a
    dense array when ``dense`` (duplicates summed in both); ``nonzero``: of the blocks' nonzero
    entries only (:func:`nonzero_sum`)."""
    if nonzero and not dense:
        return nonzero_sum(n_rows, n_cols, list(blocks))  # (the caller's list left as it is)
    if dense:
        keys, vals = [], []
        for r, c, v in blocks:
            if np.size(v):
                r, c = np.asarray(r).ravel(), np.asarray(c).ravel()
                keys.append((r[:, None] * n_cols + c[None, :]).ravel())  # row-major, as v
                vals.append(np.asarray(v, dtype=float).ravel())
        return _dense_sum(n_rows, n_cols, keys, vals)
    triplets = []
    # 32-bit indices where they fit, as scipy keeps them (64-bit ones it copies down: 8 bytes an
    # entry more at the peak, 80 MB for a 10⁵-DOF beam model's mass)
    kind = np.int32 if max(n_rows, n_cols) < 2**31 - 1 else np.int64
    for r, c, v in blocks:
        if np.size(v) == 0:
            continue
        r = np.asarray(r).ravel().astype(kind, copy=False)
        c = np.asarray(c).ravel().astype(kind, copy=False)
        # row-major (i, j) pairs of the block, as meshgrid(r, c, indexing="ij") gives them
        triplets.append((np.repeat(r, c.size), np.tile(c, r.size),
                         np.asarray(v, dtype=float).ravel()))
    return coo_sum(n_rows, n_cols, triplets)


SUM_CHUNK = 1024  # blocks read at a time by nonzero_sum


def equilibration(A):
    """d with d_i = 1/√max_j |A_ij| (1 for empty rows), for the symmetric scaling D A D (dense
    or sparse A)."""
    if not sp.issparse(A):
        mx = np.max(np.abs(A), axis=1, initial=0.0)
        mx[~(mx > 0)] = 1.0
        return 1.0 / np.sqrt(mx)
    A = sp.csr_matrix(A)
    mx = np.zeros(A.shape[0])
    nz = np.diff(A.indptr) > 0
    if A.nnz:
        mx[nz] = np.maximum.reduceat(np.abs(A.data), A.indptr[:-1][nz])
    mx[mx <= 0] = 1.0
    return 1.0 / np.sqrt(mx)


def nonzero_sum(n_rows, n_cols, blocks):
    """The CSR sum of the blocks' nonzero entries: the terms of :func:`scatter`'s sum without
    its zeros (a structural zero adds nothing), in block order, and no stored zero; an entry of
    three or more terms may differ from scatter's in its last bits where either sum passes
    FAST_CSR triplets (scipy does not fix the order in which it adds duplicates).  Read
    ``SUM_CHUNK`` blocks at a time.  A list of blocks is emptied as it is read
    (each block let go once its nonzeros are taken), so that the peak holds one chunk of the
    blocks and the nonzero triplets, not every block and every triplet: a 3-D beam's K, C and
    mass in natural coordinates at rest (a straight beam along an axis) are 85-95 % zeros."""
    kind = np.int32 if max(n_rows, n_cols) < 2**31 - 1 else np.int64
    parts = []
    for a in range(0, len(blocks), SUM_CHUNK):
        chunk = blocks[a:a + SUM_CHUNK]
        if isinstance(blocks, list):
            blocks[a:a + SUM_CHUNK] = [None] * len(chunk)
        rs, cs, vs = [], [], []
        for (nr, nc), run in groupby(((np.asarray(r).ravel(), np.asarray(c).ravel(), v)
                                      for r, c, v in chunk), key=lambda t: (t[0].size, t[1].size)):
            R, C, V = zip(*run, strict=True)
            V = [np.asarray(v, dtype=float).ravel() for v in V]
            if any(v.size != nr * nc for v in V):
                raise ValueError(f"a block on {nr} rows and {nc} columns without "
                                 f"{nr * nc} values")
            R, C = np.array(R, dtype=kind), np.array(C, dtype=kind)  # (blocks, nr), (blocks, nc)
            shape = (R.shape[0], nr, nc)  # row-major (i, j) of each block, as its values
            rs.append(np.broadcast_to(R[:, :, None], shape).ravel())
            cs.append(np.broadcast_to(C[:, None, :], shape).ravel())
            vs.extend(V)
        del chunk
        if vs:
            v = np.concatenate(vs)
            keep = np.flatnonzero(v)
            parts.append((np.concatenate(rs)[keep], np.concatenate(cs)[keep], v[keep]))
    if isinstance(blocks, list):
        blocks.clear()
    A = coo_sum(n_rows, n_cols, parts)
    if A.data.size > A.nnz:  # (scipy keeps the triplets' length after summing duplicates)
        A = sp.csr_matrix((A.data[:A.nnz].copy(), A.indices[:A.nnz].copy(), A.indptr),
                          shape=A.shape)
    return A


def _dense_sum(n_rows, n_cols, keys, vals):
    """The dense n_rows × n_cols array with vals summed at the flat indices keys (one
    bincount: duplicates summed in their given order)."""
    if not keys:
        return np.zeros((n_rows, n_cols))
    k = np.concatenate(keys)
    if k.size and (k.min() < 0 or k.max() >= n_rows * n_cols):
        raise IndexError(f"index outside a {n_rows} × {n_cols} matrix")
    return np.bincount(k, weights=np.concatenate(vals),
                       minlength=n_rows * n_cols).reshape(n_rows, n_cols)


FAST_CSR = 20000  # triplets up to which CSR is assembled by numpy (scipy's COO path costs
# ≈ 0.3 ms of Python per matrix, which dominates the statics of a small model)


def coo_sum(n_rows, n_cols, triplets, *, dense=False):
    """Sum of (rows, cols, values) triplets as CSR (duplicates summed, sorted indices), or as a
    dense array when ``dense``."""
    triplets = [t for t in triplets if t[0].size]
    if dense:
        return _dense_sum(n_rows, n_cols,
                          [np.asarray(r) * n_cols + np.asarray(c) for r, c, _ in triplets],
                          [np.asarray(v, dtype=float) for _, _, v in triplets])
    if not triplets:
        return sp.csr_matrix((n_rows, n_cols))
    if len(triplets) == 1:  # (one triplet: its arrays as they are, no copies)
        r, c, v = (np.asarray(x).ravel() for x in triplets[0])
    else:
        r, c, v = (np.concatenate(x) for x in zip(*triplets, strict=True))
    if r.size > FAST_CSR:
        return sp.coo_matrix((v, (r, c)), shape=(n_rows, n_cols)).tocsr()
    return csr_from_triplets(n_rows, n_cols, r, c, v)


def csr_from_triplets(n_rows, n_cols, r, c, v):
    """CSR of the triplets with duplicates summed in their given order, built by numpy (no
    COO conversion); for small matrices."""
    r = np.asarray(r, dtype=np.int64)
    c = np.asarray(c, dtype=np.int64)
    if not r.size:
        return sp.csr_matrix((n_rows, n_cols))
    if (r.min() < 0 or r.max() >= n_rows or c.min() < 0 or c.max() >= n_cols):
        raise IndexError(f"triplet index outside a {n_rows} × {n_cols} matrix")
    key = r * n_cols + c
    order = np.argsort(key, kind="stable")
    key = key[order]
    first = np.flatnonzero(np.concatenate(([True], key[1:] != key[:-1])))
    data = np.add.reduceat(np.asarray(v, dtype=float)[order], first)
    key = key[first]
    rows = key // n_cols
    indptr = np.zeros(n_rows + 1, dtype=np.int32)
    np.cumsum(np.bincount(rows, minlength=n_rows), out=indptr[1:])
    return sp.csr_matrix((data, (key - rows * n_cols).astype(np.int32), indptr),
                         shape=(n_rows, n_cols))


def csr_of_dense(D):
    """CSR of a dense array (its nonzeros), built by numpy; for small matrices."""
    D = np.asarray(D, dtype=float)
    r, c = np.nonzero(D)
    indptr = np.zeros(D.shape[0] + 1, dtype=np.int32)
    np.cumsum(np.bincount(r, minlength=D.shape[0]), out=indptr[1:])
    return sp.csr_matrix((D[r, c], c.astype(np.int32), indptr), shape=D.shape)


def saddle(A, G):
    """[[A, Gᵀ], [G, 0]] as CSR (the augmented matrix of a constrained model); assembled
    densely when small, and returned dense when A and G are both dense arrays."""
    n, m = A.shape[0], G.shape[0]
    if n + m > 400:
        return sp.bmat([[A, G.T], [G, None]], format="csr")
    D = np.zeros((n + m, n + m))
    D[:n, :n] = A.toarray() if sp.issparse(A) else A
    Gd = G.toarray() if sp.issparse(G) else np.asarray(G, float)
    D[n:, :n] = Gd
    D[:n, n:] = Gd.T
    return D if not (sp.issparse(A) or sp.issparse(G)) else csr_of_dense(D)


def dense(A) -> np.ndarray:
    """A dense float array of a dense or sparse matrix."""
    return A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)


def constraint_rank(Phi_q, rank_tol):
    """(rank, singular values) of Φ_q with the relative tolerance rank_tol · σ_max."""
    if Phi_q.shape[0] == 0:
        return 0, np.zeros(0)
    s = sla.svd(dense(Phi_q), compute_uv=False)
    return rank_of(s, rank_tol), s


def rank_of(s, rank_tol):
    return int(np.sum(s > rank_tol * s[0])) if s.size and s[0] > 0 else 0


def null_space_basis(Phi_q, n, rank_tol):
    """(N, rank): orthonormal basis of null(Φ_q) from the SVD, rank as :func:`constraint_rank`."""
    if Phi_q.shape[0] == 0:
        return np.eye(n), 0
    _, s, vt = sla.svd(dense(Phi_q), full_matrices=True)
    rank = rank_of(s, rank_tol)
    return vt[rank:].T.copy(), rank


def closest_basis(Z, sel=None):
    """(N, selection, cosine): among the orthonormal bases of span Z (Z orthonormal, n × d),
    the one closest to the coordinate directions E = I[:, sel] (the polar factor of Π E,
    Π = Z Zᵀ: N = Z U Vᵀ with Zᵀ E = U Σ Vᵀ).  ``sel`` defaults to the d coordinates chosen by
    column-pivoted QR of Zᵀ (sorted); ``cosine`` is σ_min(Zᵀ E), how well E fixes N.  It
    depends on span Z alone, not on the basis Z an SVD returned (docs/design.md, "Null-space
    basis")."""
    d = Z.shape[1]
    if sel is None:
        _, _, piv = sla.qr(Z.T, mode="economic", pivoting=True)
        sel = np.sort(piv[:d])
    U, sv, Vt = np.linalg.svd(Z[sel, :].T)
    return Z @ (U @ Vt), sel, float(sv[-1]) if sv.size else 1.0


def colnorm(X):
    """Column 2-norms of a real or complex block without complex temporaries."""
    if np.iscomplexobj(X):
        return np.sqrt(np.einsum("ij,ij->j", X.real, X.real)
                       + np.einsum("ij,ij->j", X.imag, X.imag))
    return np.sqrt(np.einsum("ij,ij->j", X, X))


def unit_columns(X):
    """X with unit columns (zero columns left as they are)."""
    nrm = colnorm(X)
    nrm[nrm == 0] = 1.0
    return X / nrm


def jsonable(x):
    """Floats with non-finite values as None, so that the output is strict JSON."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    return x


# ---------------------------------------------------------------------------------------------
# stage boundaries
# ---------------------------------------------------------------------------------------------
def nonfinite(arrays: dict):
    """The name of the first array (dense or sparse, real or complex; None skipped) holding a
    NaN or an infinity, or None."""
    for name, A in arrays.items():
        if A is None:
            continue
        data = A.data if sp.issparse(A) else np.asarray(A)
        if data.dtype.kind in "fc" and data.size and not np.all(np.isfinite(data)):
            return name
    return None


def require_finite(stage: str, cause: str, **arrays):
    """Raise :class:`NumericalError` (element = the stage) when one of ``arrays`` is not finite."""
    bad = nonfinite(arrays)
    if bad is not None:
        raise NumericalError(f"{bad} is not finite (inf or NaN entries); likely cause: {cause}",
                             element=stage)


@contextlib.contextmanager
def watched(stage: str, cause: str, *, float_warnings: bool = True):
    """Run one stage of the pipeline with its floating-point arithmetic watched.

    numpy reports a number leaving the double range by a RuntimeWarning ("overflow / invalid
    value / divide by zero encountered"); after such an event the stage's result cannot be
    trusted (an infinity divided away leaves a finite, wrong number), so the warning becomes a
    :class:`NumericalError` naming the stage and the likely cause instead of a warning followed
    by an answer.  An arithmetic exception (OverflowError, ZeroDivisionError,
    FloatingPointError) or SciPy's refusal of non-finite input ("array must not contain infs or
    NaNs") inside the stage becomes the same error.  Other warnings pass through unchanged.
    ``float_warnings=False`` leaves every warning to the stage (the eigensolvers judge their
    own) and converts only the exceptions.
    """
    if not float_warnings:
        with _arithmetic_errors(stage, cause):
            yield
        return
    with warnings.catch_warnings(record=True) as caught, \
            np.errstate(over="warn", invalid="warn", divide="warn"):
        warnings.simplefilter("always")
        with _arithmetic_errors(stage, cause):
            yield
    floats = [w for w in caught if issubclass(w.category, RuntimeWarning)
              and _FLOAT_WARNING.search(str(w.message))]
    for w in caught:
        if w not in floats:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if floats:
        raise NumericalError(f"floating-point {floats[0].message} (numpy); likely cause: {cause}",
                             element=stage)


@contextlib.contextmanager
def _arithmetic_errors(stage, cause):
    try:
        yield
    except MbseigError:
        raise
    except ArithmeticError as exc:
        raise NumericalError(f"arithmetic failed ({exc}); likely cause: {cause}",
                             element=stage) from None
    except ValueError as exc:
        if "infs or NaNs" not in str(exc):
            raise
        raise NumericalError(f"a non-finite intermediate result (inf or NaN); likely cause: "
                             f"{cause}", element=stage) from None


_BLAS_CONTROLLER = []  # one threadpoolctl controller per process, made on first use


def blas_limit(n):
    """A context capping BLAS at ``n`` threads while it is open (threadpoolctl, when installed;
    nothing when n is None).  The controller that finds the BLAS libraries is made once per
    process, so entering the context costs ≈ 0.2 ms instead of the 1–5 ms of a fresh
    ``threadpool_limits``: cheap enough around every small dense solve, where a second BLAS
    thread only adds synchronization (a 3 × 3 triangular solve measured 5–8 ms with two OpenBLAS
    threads on a loaded 2-core machine, 0.2 ms with one)."""
    if n is None:
        return contextlib.nullcontext()
    if not _BLAS_CONTROLLER:
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:
            _BLAS_CONTROLLER.append(None)
        else:
            _BLAS_CONTROLLER.append(ThreadpoolController())
    controller = _BLAS_CONTROLLER[0]
    if controller is None:
        return contextlib.nullcontext()
    try:  # already capped (OPENBLAS_NUM_THREADS=1, an enclosing limit): nothing to do (≈ 1 µs)
        if all(lc.get_num_threads() <= n for lc in controller.lib_controllers):
            return contextlib.nullcontext()
    except Exception:  # noqa: BLE001 (a library that cannot say: limit it as before)
        pass
    return controller.limit(limits=n)


def min_norm_projection(residual, jacobian, x, scales, *, tol, max_iter):
    """x moved onto residual(x) = 0 by Gauss–Newton with minimum-norm steps
    (x ← x − J⁺ r, J = jacobian(x)), the one projector onto the constraints (mode-shape drawings,
    the time-domain check).  Returns (x, max |r_k|/scale_k before the last step taken, converged,
    the sum of the steps)."""
    x = np.array(x, dtype=float)
    total = np.zeros_like(x)
    res = math.inf
    for _ in range(max_iter):
        r = np.asarray(residual(x), float)
        res = float(np.max(np.abs(r) / scales, initial=0.0))
        if res <= tol:
            return x, res, True, total
        J = jacobian(x)
        J = J.toarray() if sp.issparse(J) else np.asarray(J)
        step = -np.linalg.lstsq(J, r, rcond=None)[0]
        x += step
        total += step
    return x, res, False, total


def grow_columns(owner, name, cols):
    """``owner.<name>``, a column-major array, widened to ``cols`` columns (the new ones zero) and
    stored back: in place where nothing else references it (``ndarray.resize``; a large array's
    pages are remapped by realloc, not copied, so the old and the new never coexist), else a
    copy.  The first columns keep their values bit for bit either way."""
    X = getattr(owner, name)
    setattr(owner, name, None)  # (the attribute's reference would block the in-place growth)
    try:
        X.resize((X.shape[0], cols), refcheck=True)
    except ValueError:  # a view or another name holds it
        Y = np.zeros((X.shape[0], cols), order="F")
        Y[:, :X.shape[1]] = X
        X = Y
    finally:  # (on any failure, out of memory included, the owner keeps its array)
        setattr(owner, name, X)
    return X
