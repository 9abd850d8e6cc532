"""Dense rows of the benchmark: the chain family, eigenvalue errors against its closed form,
the companion and QZ paths against LAPACK's geev floor, left vectors, the structured paths
against eigh(Q, M)."""

from __future__ import annotations

import math
import time
import warnings
from contextlib import nullcontext

import numpy as np
import scipy.linalg as sla

from ..eigen import Problem, Request, solve


# ---------------------------------------------------------------------------------------------
def capped_threads(n):
    if not n:
        return nullcontext()
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - optional
        warnings.warn("threadpoolctl not installed: BLAS threads not capped", RuntimeWarning,
                      stacklevel=2)
        return nullcontext()
    return threadpool_limits(limits=n)


def median_times(fns, repeats):
    """Interleaved runs of several callables: medians and the last result of each."""
    times = {k: [] for k in fns}
    out = {}
    for _ in range(repeats):
        for k, fn in fns.items():
            t = time.perf_counter()
            out[k] = fn()
            times[k].append(time.perf_counter() - t)
    return {k: float(np.median(v)) for k, v in times.items()}, out


def chain_matrices(n, k=1000.0, m=1.0, c=0.5, damped=True):
    K = 2 * k * np.eye(n) - k * (np.eye(n, k=1) + np.eye(n, k=-1))
    M = m * np.eye(n)
    C = (c / k) * K if damped else np.zeros((n, n))
    return M, C, K


def chain_exact(n, k=1000.0, m=1.0, c=0.5, damped=True):
    w = 2 * np.sqrt(k / m) * np.sin(np.arange(1, n + 1) * np.pi / (2 * (n + 1)))
    if not damped:
        return 1j * w
    return -(c / (2 * k)) * w**2 + 1j * w * np.sqrt(1 - (c * w / (2 * k)) ** 2)


def rel_error(s, exact):
    """max_k min_j |s_k − s_j| / |s_j| over the computed eigenvalues (upper half-plane)."""
    s = np.asarray(s)
    s = np.where(s.imag < 0, np.conj(s), s)
    ex = np.sort_complex(exact)
    order = np.argsort(ex.imag)
    ex = ex[order]
    pos = (np.clip(np.searchsorted(ex.imag, s.imag), 1, ex.size - 1) if ex.size > 1
           else np.zeros(s.size, int))
    cand = np.stack([ex[np.maximum(pos - 1, 0)], ex[pos]])
    d = np.abs(cand - s[None, :]) / np.abs(cand)
    return float(np.max(np.min(d, axis=0))) if s.size else math.nan


def _floor_companion(M, C, K):
    n = M.shape[0]
    L = np.sqrt(np.diag(M))  # chains: diagonal M, as mbseig's mass normalization
    Qt = K / np.outer(L, L)
    Pt = C / np.outer(L, L)
    g = np.sqrt(np.linalg.norm(Qt) / np.sqrt(n))
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Qt / g**2, -Pt / g]]), g


# ---------------------------------------------------------------------------------------------
def bench_dense(sizes, repeats, qz_max, naive_max, general_max, log):
    rows = []
    for n in sizes:
        M, C, K = chain_matrices(n)
        exact = chain_exact(n)
        reps = repeats if n <= 1000 else 1
        A, g = _floor_companion(M, C, K)
        fns = {}
        if n <= general_max:
            fns["LAPACK geev (floor)"] = lambda g=g, A=A: g * sla.eig(A, check_finite=False)[0]
            fns["mbseig companion"] = lambda M=M, C=C, K=K: solve(Problem(M, C, K),
                                                                  Request("companion"))
        if n <= naive_max:
            fns["naive companion"] = lambda M=M, C=C, K=K: _naive_with_vectors(M, C, K)
        if n <= qz_max:
            fns["QZ unscaled"] = lambda M=M, C=C, K=K: solve(
                Problem(M, C, K), Request("qz", options={"scale": False}))
            fns["QZ scaled"] = lambda M=M, C=C, K=K: solve(Problem(M, C, K), Request("qz"))
        fns["mbseig default"] = lambda M=M, C=C, K=K: solve(Problem(M, C, K), Request())
        t, out = median_times(fns, reps)
        for name, res in out.items():
            s = res if isinstance(res, np.ndarray) else res.eigenvalues
            eta = math.nan if isinstance(res, np.ndarray) else float(np.max(res.backward_error))
            solver = name if isinstance(res, np.ndarray) else res.solver
            rows.append({"section": "dense", "method": name, "n": n, "time": t[name],
                         "repeats": reps, "error": rel_error(s, exact), "eta": eta,
                         "solver": solver})
            log(f"dense n={n:5d} {name:22s} {t[name]:9.4f} s  err {rows[-1]['error']:.1e}  "
                f"η {eta:.1e}")
    return rows


def _naive_with_vectors(M, C, K):
    n = M.shape[0]
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ C]])
    return np.linalg.eig(A)[0]


def bench_left_vectors(n, repeats, log):
    """Cost of LAPACK's left eigenvectors on the dense companion path (non-symmetric P)."""
    M, C, K = chain_matrices(n)
    fns = {"right only": lambda: solve(Problem(M, C, K),
                                       Request("companion", options={"left": False})),
           "left and right": lambda: solve(Problem(M, C, K),
                                           Request("companion", options={"left": True}))}
    t, _ = median_times(fns, repeats)
    log(f"left vectors n={n}: {t}")
    return {"n": n, **t}


def bench_structured(sizes, repeats, general_max, log):
    rows = []
    for n in sizes:
        for damped, label in ((False, "eigh"), (True, "proportional")):
            M, C, K = chain_matrices(n, damped=damped)
            exact = chain_exact(n, damped=damped)
            fns = {"floor": lambda K=K, M=M: sla.eigh(K, M, check_finite=False),
                   label: lambda M=M, C=C, K=K: solve(Problem(M, C, K), Request())}
            if n <= general_max:
                fns["general"] = lambda M=M, C=C, K=K: solve(Problem(M, C, K),
                                                             Request("companion"))
            t, out = median_times(fns, repeats if n <= 1000 else 1)
            row = {"section": "structured", "method": f"mbseig {label}", "n": n, "time": t[label],
                   "error": rel_error(out[label].eigenvalues, exact),
                   "eta": float(out[label].backward_error.max()), "solver": out[label].solver}
            row["floor_time"] = t["floor"]  # eigh(Q, M) with vectors, interleaved
            row["floor_ratio"] = t[label] / t["floor"]
            if "general" in t:
                row["general_time"] = t["general"]
                row["speedup"] = t["general"] / t[label]
            rows.append(row)
            log(f"structured n={n:5d} {label:13s} {t[label]:.4f} s  "
                f"general {t.get('general', math.nan):.3f} s")
    return rows


def bench_pipeline(sizes, repeats, log, case="chain_damped"):
    """The whole pipeline (build, equilibrium with its static-stability check, linearization,
    modes) on the bundled damped chain of n masses against its eigen floor, ``eigh(K, M)`` on
    the same matrices, interleaved in one process (the median of ``repeats`` of each)."""
    from ..casefile import read_case
    from ..studies.pipeline import analyze
    from .cases import case_path

    spec = read_case(case_path(case))
    rows = []
    for n in sizes:
        a = analyze(spec, params={"n": n})
        M, K = (A.toarray() if hasattr(A, "toarray") else np.asarray(A)
                for A in (a.linear.M, a.linear.Q))
        t, _ = median_times({"floor": lambda K=K, M=M: sla.eigh(K, M, check_finite=False),
                             "pipeline": lambda n=n: analyze(spec, params={"n": n})},
                            max(repeats, 5))
        ratio = t["pipeline"] / t["floor"]
        rows.append({"section": "structured", "method": "mbseig whole pipeline", "n": n,
                     "time": t["pipeline"], "floor_time": t["floor"], "pipeline_ratio": ratio,
                     "solver": a.modes.solver,
                     "eta": float(np.max(a.modes.backward_error, initial=0.0))})
        log(f"pipeline  n={n:5d} {t['pipeline']:.4f} s  floor {t['floor']:.4f} s  ({ratio:.2f}x)")
    return rows


def json_default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    return str(x)
