"""Partial-spectrum rows of the benchmark: large chains with and without constraints, each path
in a fresh process (time and peak memory) against the eigsh floor."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ..casefile import load_case
from ..linear import linearize
from ..modal import modes
from ..statics import equilibrium
from .cases import case_path
from .dense_rows import (
    chain_exact,
    json_default,
    rel_error,
)


# ---------------------------------------------------------------------------------------------
def partial_worker(kind, n, n_modes):
    """Run in a fresh process: whole pipeline for the damped chain, JSON on stdout."""
    import scipy.sparse as sp

    t0 = time.perf_counter()
    model = load_case(case_path("chain_damped"), n=n)
    t1 = time.perf_counter()
    eq = equilibrium(model)
    t2 = time.perf_counter()
    lin = linearize(model, eq, sparse=True)
    t3 = time.perf_counter()
    P = lin.P
    if kind == "general":  # one extra dashpot at the first mass: not proportional any more
        P = (P + sp.csr_matrix(([2.0], ([0], [0])), shape=P.shape)).tocsr()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        md = modes(lin.M, P, lin.Q, N=lin.N, coordinate_names=lin.coordinate_names, n_modes=n_modes)
    t4 = time.perf_counter()
    err = (rel_error(md.eigenvalues, chain_exact(n)[: n_modes + 5]) if kind == "proportional"
           else math.nan)
    rss = peak_rss_mb()
    print(json.dumps({"kind": kind, "n": n, "load": t1 - t0, "equilibrium": t2 - t1,
                      "linearize": t3 - t2, "modes": t4 - t3, "total": t4 - t0, "rss_mb": rss,
                      "error": err, "eta": float(md.backward_error.max()), "solver": md.solver,
                      "n_listed": len(md), "verdict": md.verdict}))


def peak_rss_mb():
    """Peak resident memory of this process (VmHWM: ru_maxrss would inherit the parent's peak)."""
    import resource

    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bench_partial(sizes, repeats, general_max, threads, log, n_modes=20):
    rows = []
    env = dict(os.environ)
    if threads:
        env.update({k: str(threads)
                    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")})
    for kind in ("proportional", "general"):
        for n in sizes:
            if kind == "general" and n > general_max:
                continue
            runs = []
            for _ in range(repeats):  # medians at every size, 10⁶ included (≈20 s a run)
                code = ("from mbseig.bench.sparse_rows import partial_worker; "
                        f"partial_worker({kind!r}, {n}, {n_modes})")
                p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                   env=env)
                if p.returncode != 0:
                    log(f"partial {kind} n={n} failed: {p.stderr.strip().splitlines()[-1:]}")
                    break
                runs.append(json.loads(p.stdout.strip().splitlines()[-1]))
            if not runs:
                continue
            med = {k: float(np.median([r[k] for r in runs])) for k in
                   ("load", "equilibrium", "linearize", "modes", "total", "rss_mb")}
            row = {"section": "partial", "method": f"partial {kind}", "n": n, "time": med["total"],
                   "repeats": len(runs), **med, "error": runs[-1]["error"], "eta": runs[-1]["eta"],
                   "solver": runs[-1]["solver"], "n_listed": runs[-1]["n_listed"]}
            rows.append(row)
            log(f"partial {kind:12s} n={n:8d} total {med['total']:.2f} s "
                f"(modes {med['modes']:.2f}) "
                f"rss {med['rss_mb']:.0f} MB err {row['error']:.1e} η {row['eta']:.1e}")
    return rows


# ---------------------------------------------------------------------------------------------
def large_chain(n, every=10, k=1000.0, c_ground=1e-5, beta=2e-4):
    """(M, P, Q, G) of the large constrained benchmark model: a 1-D chain of n masses
    m_i = 1 + 0.5 sin i between walls, springs k, every ``every``-th spring a rigid link
    (n/every constraint rows x_{i+1} − x_i = 0), grounded dashpots c on every 7th mass plus
    stiffness-proportional damping βK: non-proportional, so the general path runs."""
    import scipy.sparse as sp

    i = np.arange(n)
    K = sp.diags([2 * k * np.ones(n), -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1],
                 format="csr")
    cd = np.zeros(n)
    cd[::7] = c_ground
    C = (sp.diags(cd) + beta * K).tocsr()
    M = sp.diags(1 + 0.5 * np.sin(i), format="csr")
    a = np.arange(every - 1, n - 1, every)
    r = np.arange(a.size)
    G = sp.csr_matrix((np.r_[-np.ones(a.size), np.ones(a.size)], (np.r_[r, r], np.r_[a, a + 1])),
                      shape=(a.size, n))
    return M, C, K, G


def large_worker(kind, n, n_modes):
    """Fresh process: one solve of the large constrained model, JSON on stdout (peak RSS)."""
    import scipy.sparse.linalg as spla

    from ..eigen import Problem, Request, solve
    from ..eigen.shift_invert import bordered as _bordered

    t0 = time.perf_counter()
    M, C, K, G = large_chain(n)
    t1 = time.perf_counter()
    out = {"kind": kind, "n": n, "m": G.shape[0], "build": t1 - t0}
    if kind == "floor":  # undamped eigsh shift-invert at 0 on the same bordered pencil
        Mb, _, Qb, _ = _bordered(M, C, K, G)
        lu = spla.splu(Qb.tocsc())
        op = spla.LinearOperator(Qb.shape, matvec=lu.solve, dtype=float)
        w, _ = spla.eigsh(Qb, k=n_modes, M=Mb, sigma=0.0, OPinv=op)  # with vectors, as mbseig
        out.update(eta=math.nan, omega_1=float(np.sqrt(np.min(np.abs(w)))))
    else:
        sol = solve(Problem(M, C, K, G=G), Request(kind, n_modes=n_modes))
        out.update(eta=float(np.max(sol.backward_error)), verified=bool(sol.coverage["verified"]),
                   omega_1=float(np.min(np.abs(sol.eigenvalues))), slepc=sol.details.get("slepc"),
                   solver=sol.solver, arpack_k=sol.details.get("arpack_k"))
        pj = sol.details.get("projected")
        if pj:  # the projected path's figures: Lanczos size, refinement rounds, LU solves
            out["projected"] = {k: pj[k] for k in ("k_u", "iterations", "basis_size", "lu_solves",
                                                   "eta_history", "seconds")}
            out["projected"]["certificate"] = {k: pj["certificate"].get(k) for k in
                                               ("R", "tau", "rho", "Omega", "n_inside", "why")}
    out.update(solve=time.perf_counter() - t1, rss_mb=peak_rss_mb())
    print(json.dumps(out, default=json_default))


def bench_large(sizes, repeats, threads, log, n_modes=20, slepc=True):
    """Lowest 20 modes of the large constrained model with non-proportional damping: the
    projected path (undamped Lanczos + refinement, certified), the scipy companion path and the
    SLEPc backend (when installed) against the undamped eigsh floor, each in a fresh process,
    interleaved per repeat (the ratio is of medians of the same run)."""
    from ..eigen.slepc import slepc_available

    kinds = (["floor", "partial-projected", "partial-companion"]
             + (["partial-slepc"] if slepc and slepc_available() else []))
    env = dict(os.environ)
    if threads:
        env.update({k: str(threads)
                    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")})
    rows = []
    for n in sizes:
        runs = {k: [] for k in kinds}
        for rep in range(repeats):
            for kind in kinds:
                if n >= 1_000_000 and rep and kind in ("partial-companion", "partial-slepc"):
                    # 10⁶: the slow paths once (minutes a run), floor and projected medians
                    continue
                code = ("from mbseig.bench.sparse_rows import large_worker; "
                        f"large_worker({kind!r}, {n}, {n_modes})")
                p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                   env=env)
                if p.returncode != 0:
                    log(f"large {kind} n={n} failed: {p.stderr.strip().splitlines()[-1:]}")
                    continue
                runs[kind].append(json.loads(p.stdout.strip().splitlines()[-1]))
        if not runs["floor"]:
            continue
        floor = float(np.median([r["solve"] for r in runs["floor"]]))
        for kind, rr in runs.items():
            if not rr:
                continue
            t = float(np.median([r["solve"] for r in rr]))
            row = {"section": "large", "method": kind, "n": n, "m": rr[-1]["m"], "time": t,
                   "ratio": t / floor, "rss_mb": float(np.median([r["rss_mb"] for r in rr])),
                   "eta": rr[-1]["eta"], "omega_1": rr[-1]["omega_1"], "repeats": len(rr),
                   "verified": rr[-1].get("verified"), "solver": rr[-1].get("solver"),
                   "projected": rr[-1].get("projected")}
            rows.append(row)
            log(f"large {kind:18s} n={n:8d} {t:8.2f} s  ({row['ratio']:.2f}x floor) "
                f"rss {row['rss_mb']:.0f} MB "
                f"η {row['eta']:.1e}" + ("" if kind == "floor" else f" verified {row['verified']}"))
    return rows
