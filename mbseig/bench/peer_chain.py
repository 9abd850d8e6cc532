"""The chain rows of the peer comparison: the same chain model in mbseig and in EXUDYN, the
eigenvalues of both against the closed form, times in one run; the helpers both peer sections
share (is EXUDYN there, the backward error of an eigenvalue of EXUDYN's)."""

from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path

import numpy as np


def exudyn_available():
    try:
        import exudyn  # noqa: F401
    except ImportError:
        return False
    return True


def interleaved(repeats, ours, theirs):
    """Times of ``ours()`` and ``theirs()`` run alternately ``repeats`` times (a shared machine's
    load falls on both alike), and the last result of each."""
    t_m, t_e = [], []
    for _ in range(repeats):
        t = time.perf_counter()
        a = ours()
        t_m.append(time.perf_counter() - t)
        t = time.perf_counter()
        b = theirs()
        t_e.append(time.perf_counter() - t)
    return t_m, t_e, a, b


def linearized_modes(model, eq, linearize, modes):
    """mbseig's timed part of a peer row: linearize and modes (the equilibrium is shared)."""
    lin = linearize(model, eq)
    return lin, modes(lin.M, lin.P, lin.Q)


def _case(n, k=1000.0, c=0.5, c0=2.0):
    """The chain as a case file: n unit masses between two walls, springs k with dampers c, one
    extra dashpot c0 to the left wall."""
    from ..casefile.writer import CaseBuilder

    chain = CaseBuilder(dimension=1, source="bench: damped chain with one extra dashpot to the "
                        "wall (non-proportional)")
    every = {"i": [1, "n"]}
    chain.parameter("n", n)
    chain.point("wall_left", [0.0], fixed=True)
    chain.point("m{i}", ["0.1*i"], repeat=every)
    chain.point("wall_right", ["(n + 1)*0.1"], fixed=True)
    chain.mass("m{i}", 1.0, repeat=every)
    for ends, repeat, gains in ((["wall_left", "m1"], None, (k, c)),
                                (["m{i}", "m{i + 1}"], {"i": [1, "n - 1"]}, (k, c)),
                                (["m{n}", "wall_right"], None, (k, c)),
                                (["wall_left", "m1"], None, (0.0, c0))):
        chain.force("spring_damper", repeat=repeat, points=ends, stiffness=gains[0],
                    damping=gains[1])
    return chain.to_toml()


def _exudyn_model(n, k=1000.0, c=0.5, c0=2.0):
    import exudyn as exu
    from exudyn.itemInterface import (
        CoordinateSpringDamper,
        MarkerNodeCoordinate,
        Mass1D,
        Node1D,
        NodePointGround,
    )

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
        mbs.AddObject(CoordinateSpringDamper(markerNumbers=[chain[i], chain[i + 1]], stiffness=k,
                                             damping=c))
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mg, markers[0]], stiffness=0.0, damping=c0))
    mbs.Assemble()
    return SC, mbs


def eigenvalue_backward_error(M, C, K, s):
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


def chain_rows(sizes, repeats, log, n_check=20):
    """The chain rows of the peer section (EXUDYN installed): one row a size."""
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
            t_m, t_e, (lin, md), ev = interleaved(
                repeats, lambda model=model, eq=eq: linearized_modes(model, eq, linearize, modes),
                lambda m=mbs: exu.solver.ComputeODE2Eigenvalues(m, computeComplexEigenvalues=True,
                                                                useAbsoluteValues=False))
            M, C, K = (np.asarray(A.toarray() if hasattr(A, "toarray") else A)
                       for A in (lin.M, lin.P, lin.Q))
            s_m = np.asarray(md.eigenvalues)
            s_m = np.concatenate([s_m, np.conj(s_m[np.abs(s_m.imag) > 0])])  # listed once per pair
            s_e = np.asarray(ev[0], complex)
            lo_m = s_m[np.argsort(np.abs(s_m))[:n_check]]
            lo_e = s_e[np.argsort(np.abs(s_e))[:n_check]]
            eta_m = float(np.max(eigenvalue_backward_error(M, C, K, lo_m)))
            eta_e = float(np.max(eigenvalue_backward_error(M, C, K, lo_e)))
            tm, te = float(np.median(t_m)), float(np.median(t_e))
            row = {"section": "peer", "method": "EXUDYN vs mbseig (general damping)", "n": n,
                   "time": tm, "mbseig_time": tm, "exudyn_time": te, "ratio": tm / te,
                   "mbseig_eta": eta_m, "exudyn_eta": eta_e,
                   "set_distance": _set_distance(s_m, s_e),
                   "mbseig_solver": md.solver, "exudyn_count": int(s_e.size), "repeats": repeats,
                   "exudyn_version": getattr(exu, "__version__", "?")}
            rows.append(row)
            log(f"peer n={n:5d} mbseig {tm:.3f} s ({md.solver}) η(s) {eta_m:.1e} | "
                f"EXUDYN {te:.3f} s η(s) {eta_e:.1e} | ratio {tm / te:.2f} | "
                f"sets differ by {row['set_distance']:.1e}")
            del SC, mbs
    return rows
