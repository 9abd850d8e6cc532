"""Rows of the ``mbseig bench`` report against SLEPc (where slepc4py is installed: docs/scaling.md
§5): the lowest 20 modes of the large damped chain, mbseig against SLEPc's polynomial eigensolver
on the same problem, time and peak memory, each solve in a fresh process, interleaved.

Model: the bench's large chain (:func:`mbseig.bench.sparse_rows.large_chain`: n masses
m_i = 1 + 0.5 sin i, springs k = 1000, grounded dashpots on every 7th mass plus βK:
non-proportional damping), with every 10th spring a rigid link ("constrained", n/10 rows) or
without links ("unconstrained").  Kinds:

- ``slepc``: SLEPc's PEP (TOAR, shift-and-invert at 0, PETSc's own LU, ``preonly``) on the
  reduced problem NᵀMN s² + NᵀPN s + NᵀQN (N the chain's sparse null basis: one coordinate of
  each link eliminated; N = I without links), asked for the eigenvalues mbseig returns for 20
  modes: 41 nearest 0, tolerance 1e-14 (the backward error mbseig reaches).  Its time is its own
  (the worker's imports, numpy's included, matrix assembly and PEPSolve), without the process
  start and the file transfer; its memory is the worker's peak.
- ``mbseig``: ``mbseig.eigen.solve(Problem(M, P, Q, G=G), Request("auto", n_modes=20))`` on the
  model as it is (constraints in the bordered pencil), with every check it makes.
- ``pslepc`` and ``bslepc``: mbseig's ``partial-slepc`` path (worker, transfer and checks
  included) against a direct SLEPc solve of the very matrices that path gives SLEPc (the
  bordered pencil, UMFPACK LU, 41 eigenvalues at 1e-14, the worker's own time): the cost of
  mbseig around SLEPc.

Row keys: ``section`` "slepc", ``method`` (kind), ``model`` ("constrained" or
"unconstrained"), ``n``, ``time`` and ``rss_mb`` (medians), ``spread`` (min, max seconds),
``repeats``, ``ratio`` and ``mem_ratio`` against the kind's reference (slepc for mbseig,
bslepc for pslepc), ``eta`` (mbseig kinds), ``load`` (1-minute load average at the start).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

__all__ = ["GOALS", "bench_slepc", "reduced", "slepc_targets", "slepc_worker"]

#: kind → (reference kind, time goal, memory goal) of issue "Fast at every size"
GOALS = {"mbseig": ("slepc", 2.0, 1.5), "pslepc": ("bslepc", 1.2, None)}


def reduced(M, C, K, G):
    """(Mr, Pr, Qr) = Nᵀ(M, C, K)N with N the sparse null basis of the chain's links."""
    import scipy.sparse as sp

    n = M.shape[0]
    G = G.tocsr()
    dep = G.indices[G.data > 0]  # x_{a+1}: eliminated
    partner = G.indices[G.data < 0]  # x_a: kept
    keep = np.ones(n, bool)
    keep[dep] = False
    col = np.cumsum(keep) - 1
    col[dep] = col[partner]
    N = sp.csr_matrix((np.ones(n), (np.arange(n), col)), shape=(n, int(keep.sum())))
    if G.shape[0] and abs(G @ N).max() != 0:
        raise RuntimeError("the reduction basis does not span the links' null space")
    return tuple((N.T @ A @ N).tocsr() for A in (M, C, K))


def slepc_worker(kind, n, constrained=True):
    """Run in a fresh process: one solve of ``kind`` (module docstring), JSON on stdout."""
    from .sparse_rows import large_chain, peak_rss_mb

    M, C, K, G = large_chain(n, every=10 if constrained else n + 1)
    t0 = time.perf_counter()
    if kind in ("mbseig", "pslepc"):
        from ..eigen import Problem, Request, solve

        path = "auto" if kind == "mbseig" else "partial-slepc"
        sol = solve(Problem(M, C, K, G=G if G.shape[0] else None), Request(path, n_modes=20))
        out = {"seconds": time.perf_counter() - t0, "rss_mb": peak_rss_mb(),
               "solver": sol.solver, "eta": float(np.max(sol.backward_error)),
               "lowest": float(np.min(np.abs(sol.eigenvalues)))}
    else:
        from ..eigen.slepc import slepc_solve

        if kind == "bslepc":  # the bordered pencil partial-slepc hands to SLEPc, its options
            from ..eigen.shift_invert import bordered

            Mr, Pr, Qr, _ = bordered(M, C, K, G)
            factor = "umfpack"
        else:
            Mr, Pr, Qr = reduced(M, C, K, G)
            factor = "petsc"
        del M, C, K, G
        t0 = time.perf_counter()
        # slepc20 (benchmarks/slepc_reduced.py only): 20 eigenvalues at SLEPc's usual 1e-8, a
        # figure sometimes quoted for "SLEPc on this problem" that is not the same work
        nev, tol = (20, 1e-8) if kind == "slepc20" else (41, 1e-14)
        s, _, info = slepc_solve(Mr, Pr, Qr, nev, tol=tol, factor=factor, upper_tol=1e-9)
        out = {"seconds": info["setup"] + info["solve"], "wall": time.perf_counter() - t0,
               "rss_mb": info["peak_rss_mb"][0], "nconv": info["nconv"],
               "lowest": float(np.min(np.abs(s)))}
    out.update(kind=kind, n=n, model="constrained" if constrained else "unconstrained")
    print(json.dumps(out))


def _run(kind, n, constrained, env):
    code = (f"from mbseig.bench.slepc_rows import slepc_worker; "
            f"slepc_worker({kind!r}, {n}, {constrained})")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    if p.returncode != 0:
        return None, (p.stderr.strip().splitlines() or ["no output"])[-1][:160]
    return json.loads(p.stdout.strip().splitlines()[-1]), ""


def bench_slepc(sizes, repeats, log=print, *, threads=1):
    """The slepc section (module docstring); at 10⁶ at most two runs of each kind."""
    from ..eigen.slepc import slepc_available

    if not slepc_available():
        log("slepc: slepc4py not importable: SLEPc rows skipped (docs/scaling.md §5)")
        return []
    env = dict(os.environ)
    if threads:
        env.update({k: str(threads) for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")})
    plan = [(True, ("slepc", "mbseig", "pslepc", "bslepc")), (False, ("slepc", "mbseig"))]
    rows = []
    for n in sizes:
        load = os.getloadavg()[0]
        runs = {}
        for _ in range(min(repeats, 2) if n >= 1_000_000 else repeats):
            for constrained, kinds in plan:
                for kind in kinds:  # interleaved: the machine's load falls on every kind
                    r, why = _run(kind, n, constrained, env)
                    if r is None:
                        log(f"slepc {kind} n={n} failed: {why}")
                        continue
                    runs.setdefault((r["model"], kind), []).append(r)
        for (model, kind), rr in runs.items():
            t = statistics.median(r["seconds"] for r in rr)
            row = {"section": "slepc", "method": kind, "model": model, "n": n, "time": t,
                   "rss_mb": statistics.median(r["rss_mb"] for r in rr),
                   "spread": (min(r["seconds"] for r in rr), max(r["seconds"] for r in rr)),
                   "repeats": len(rr), "eta": rr[-1].get("eta"), "load": load}
            ref = runs.get((model, GOALS[kind][0])) if kind in GOALS else None
            if ref:
                row["ratio"] = t / statistics.median(r["seconds"] for r in ref)
                row["mem_ratio"] = row["rss_mb"] / statistics.median(r["rss_mb"] for r in ref)
            rows.append(row)
            log(f"slepc {model:13s} {kind:7s} n={n:8d} {t:7.2f} s {row['rss_mb']:7.0f} MB"
                + (f"  {row['ratio']:.2f}x time, {row['mem_ratio']:.2f}x memory of "
                   f"{GOALS[kind][0]}" if "ratio" in row else ""))
    return rows


def slepc_targets(rows):
    """Target rows (name, measured, goal, met) of the slepc section."""
    out = []
    for r in rows:
        if "ratio" not in r:
            continue
        ref, tgoal, mgoal = GOALS[r["method"]]
        what = ("mbseig (auto, every check) / SLEPc PEP on the reduced problem"
                if r["method"] == "mbseig" else
                "partial-slepc (worker, transfer, checks) / SLEPc PEP on the same bordered pencil")
        ok = r["ratio"] <= tgoal and (mgoal is None or r["mem_ratio"] <= mgoal)
        goal = f"≤ {tgoal}× time" + (f", ≤ {mgoal}× memory" if mgoal else "")
        out.append((f"lowest 20 modes, general damping, {r['model']} chain n = {r['n']:.0e}: "
                    f"{what}", f"{r['ratio']:.2f}× time, {r['mem_ratio']:.2f}× memory "
                    f"({r['time']:.2f} s / {r['time'] / r['ratio']:.2f} s)", goal, ok))
    return out
