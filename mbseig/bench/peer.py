"""Peer comparison in the same run: EXUDYN's eigenvalue computation against mbseig's (optional:
``pip install exudyn``, the ``bench`` extra).

Model: a 1-D chain of n unit masses between walls, springs k = 1000 with dashpots c = 0.5 in
parallel, plus one dashpot c₀ = 2 from the first mass to the wall: the damping is not
proportional, so each side takes its general path (EXUDYN ``ComputeODE2Eigenvalues`` with
``computeComplexEigenvalues=True``: M, K, D from its model, then the first-order system; mbseig:
linearization, then its dense general path).  Built the same in both: EXUDYN ``Node1D`` /
``Mass1D`` / ``CoordinateSpringDamper``, mbseig a case file with the same elements.

Accuracy of each side, against a reference independent of both: the backward error of each
computed eigenvalue alone (no eigenvector needed), η(s) = σ_min(s²M + sC + K) / (|s|²‖M‖ +
|s|‖C‖ + ‖K‖) (Tisseur 2000), from an SVD of the n × n matrix, for the ``n_check`` eigenvalues
of smallest |s| (the slow modes, whose relative accuracy a first-order form loses first); and
the largest distance between the two sides' eigenvalue sets, relative to |s|.
"""

from __future__ import annotations

import math
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

__all__ = ["exudyn_available", "bench_peer"]


def exudyn_available():
    try:
        import exudyn  # noqa: F401
    except ImportError:
        return False
    return True


def _case(n, k=1000.0, c=0.5, c0=2.0):
    return f"""
schema_version = 1
dimension = 1
source = "bench: damped chain with one extra dashpot to the wall (non-proportional)"
[parameters]
n = {n}
[[points]]
name = "wall_left"
position = [0.0]
fixed = true
[[points]]
name = "m{{i}}"
repeat = {{ i = [1, "n"] }}
position = ["0.1*i"]
[[points]]
name = "wall_right"
position = ["(n + 1)*0.1"]
fixed = true
[[masses]]
repeat = {{ i = [1, "n"] }}
point = "m{{i}}"
mass = 1.0
[[forces]]
type = "spring_damper"
points = ["wall_left", "m1"]
stiffness = {k}
damping = {c}
[[forces]]
type = "spring_damper"
repeat = {{ i = [1, "n - 1"] }}
points = ["m{{i}}", "m{{i + 1}}"]
stiffness = {k}
damping = {c}
[[forces]]
type = "spring_damper"
points = ["m{{n}}", "wall_right"]
stiffness = {k}
damping = {c}
[[forces]]
type = "spring_damper"
points = ["wall_left", "m1"]
stiffness = 0.0
damping = {c0}
"""


def _exudyn_model(n, k=1000.0, c=0.5, c0=2.0):
    import exudyn as exu
    from exudyn.itemInterface import CoordinateSpringDamper, MarkerNodeCoordinate, Mass1D, Node1D
    from exudyn.itemInterface import NodePointGround

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    markers = []
    for i in range(n):
        nd = mbs.AddNode(Node1D(referenceCoordinates=[0.1 * (i + 1)], initialCoordinates=[0.0],
                                initialVelocities=[0.0]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)  # physicsMass → mass renaming
            try:
                mbs.AddObject(Mass1D(nodeNumber=nd, mass=1.0))
            except TypeError:
                mbs.AddObject(Mass1D(nodeNumber=nd, physicsMass=1.0))
        markers.append(mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nd, coordinate=0)))
    chain = [mg] + markers + [mg]
    for i in range(n + 1):
        mbs.AddObject(CoordinateSpringDamper(markerNumbers=[chain[i], chain[i + 1]], stiffness=k, damping=c))
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mg, markers[0]], stiffness=0.0, damping=c0))
    mbs.Assemble()
    return SC, mbs


def _eigenvalue_backward_error(M, C, K, s):
    nM, nC, nK = (np.linalg.norm(A) for A in (M, C, K))
    out = np.empty(s.size)
    for j, z in enumerate(s):
        smin = np.linalg.svd(z * z * M + z * C + K, compute_uv=False)[-1]
        out[j] = smin / (abs(z) ** 2 * nM + abs(z) * nC + nK)
    return out


def _set_distance(a, b):
    """max over a of min over b of |a − b| / |a| (both sets: the larger of the two ways)."""
    d1 = np.max(np.min(np.abs(a[:, None] - b[None, :]), axis=1) / np.abs(a))
    d2 = np.max(np.min(np.abs(b[:, None] - a[None, :]), axis=1) / np.abs(b))
    return float(max(d1, d2))


def bench_peer(sizes, repeats, log, n_check=20):
    """Rows of the peer section (empty with a note when EXUDYN is not installed)."""
    if not exudyn_available():
        log("peer: exudyn not installed (pip install exudyn): section skipped")
        return [], "EXUDYN not installed (`pip install exudyn`, part of the `bench` extra): not run"
    import exudyn as exu

    from ..casefile import load_case
    from ..linear import linearize
    from ..modal import modes
    from ..statics import equilibrium

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            path = Path(tmp) / f"chain_{n}.toml"
            path.write_text(_case(n))
            model = load_case(path)
            eq = equilibrium(model)
            SC, mbs = _exudyn_model(n)
            t_m, t_e = [], []
            for _ in range(repeats):  # interleaved
                t = time.perf_counter()
                lin = linearize(model, eq)
                md = modes(lin.M, lin.P, lin.Q)
                t_m.append(time.perf_counter() - t)
                t = time.perf_counter()
                ev = exu.solver.ComputeODE2Eigenvalues(mbs, computeComplexEigenvalues=True,
                                                       useAbsoluteValues=False)
                t_e.append(time.perf_counter() - t)
            M, C, K = (np.asarray(A.toarray() if hasattr(A, "toarray") else A) for A in (lin.M, lin.P, lin.Q))
            s_m = np.asarray(md.eigenvalues)
            s_m = np.concatenate([s_m, np.conj(s_m[np.abs(s_m.imag) > 0])])  # listed once per pair
            s_e = np.asarray(ev[0], complex)
            lo_m = s_m[np.argsort(np.abs(s_m))[:n_check]]
            lo_e = s_e[np.argsort(np.abs(s_e))[:n_check]]
            eta_m = float(np.max(_eigenvalue_backward_error(M, C, K, lo_m)))
            eta_e = float(np.max(_eigenvalue_backward_error(M, C, K, lo_e)))
            tm, te = float(np.median(t_m)), float(np.median(t_e))
            row = {"section": "peer", "method": "EXUDYN vs mbseig (general damping)", "n": n,
                   "time": tm, "mbseig_time": tm, "exudyn_time": te, "ratio": tm / te,
                   "mbseig_eta": eta_m, "exudyn_eta": eta_e, "set_distance": _set_distance(s_m, s_e),
                   "mbseig_solver": md.solver, "exudyn_count": int(s_e.size), "repeats": repeats,
                   "exudyn_version": getattr(exu, "__version__", "?")}
            rows.append(row)
            log(f"peer n={n:5d} mbseig {tm:.3f} s ({md.solver}) η(s) {eta_m:.1e} | EXUDYN {te:.3f} s "
                f"η(s) {eta_e:.1e} | ratio {tm / te:.2f} | sets differ by {row['set_distance']:.1e}")
            del SC, mbs
    return rows, ""


def peer_lines(rows, note):
    L = ["", "## Peer: EXUDYN on a chain with non-proportional damping (same run)", ""]
    if not rows:
        return L + [note or "not run"]
    L += ["Each side from its own model of the same chain (n unit masses, k = 1000, c = 0.5 per "
          "spring, one extra dashpot c₀ = 2 to the wall), general path on both sides: mbseig "
          "`linearize` + `modes` (its dense general path), EXUDYN `ComputeODE2Eigenvalues(... "
          "computeComplexEigenvalues=True)` (matrices from its model, then the first-order "
          "system). η(s): backward error of each eigenvalue alone, σ_min(T(s)) / (|s|²‖M‖ + "
          "|s|‖C‖ + ‖K‖) by SVD, worst of the 20 smallest |s| — a reference independent of both "
          "solvers. Times: medians of interleaved runs.", "",
          "| n | mbseig | EXUDYN | mbseig / EXUDYN | mbseig η(s) | EXUDYN η(s) | sets differ by | runs |",
          "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        L.append(f"| {r['n']} | {r['mbseig_time']:.3f} s ({r['mbseig_solver']}) | {r['exudyn_time']:.3f} s | "
                 f"{r['ratio']:.2f} | {r['mbseig_eta']:.0e} | {r['exudyn_eta']:.0e} | "
                 f"{r['set_distance']:.0e} | {r['repeats']} |")
    L += ["", f"EXUDYN {rows[0]['exudyn_version']}. Spatial models were not compared in this run."]
    return L
