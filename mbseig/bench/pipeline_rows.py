"""Whole-pipeline rows of the benchmark: sweeps in points a second, assembly of Jacobians, the
constraint-force stiffness and the time-domain check."""

from __future__ import annotations

import math
import os
import time
import warnings
from pathlib import Path

import numpy as np

from ..casefile import load_case
from ..check import check_modes
from ..linear import linearize
from ..modal import modes
from ..model.base import BatchForce
from ..model.batched import spring_forces
from ..statics import equilibrium
from .cases import case_path
from .dense_rows import (
    median_times,
)


def bench_sweeps(lines, points, log, case="hand_device"):
    """Device sweeps: points a second in-process (after the first line), and the speed-up of
    ``lines`` lines of ``points`` points each (a 2-D sweep, one task per line) on local
    processes and on a Dask ``LocalCluster`` (multi-process, a real scheduler), 1 … cores."""
    from ..casefile import read_case
    from ..studies import run_sweep

    spec = read_case(case_path(case))
    axes = [("k_a", np.linspace(800.0, 1200.0, points)), ("c_a", np.linspace(5.0, 9.0, lines))]
    cores = os.cpu_count() or 1

    def timed(sweep_axes=axes, **kw):
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            run_sweep(spec, sweep_axes, progress=False, curves=False, **kw)
        return time.perf_counter() - t

    rows = []
    timed(jobs=1)  # warm: imports and caches, as "after the first" in the goal
    # the in-process sweeps, lean (the default) and general (lean=False: the case built and the
    # command resolved at every value), medians of five interleaved runs (one run of ≈ 1 s
    # moved by ±20 % on this shared machine): the general path is the floor of the same run
    load_axes = [("f", np.linspace(0.0, 1.5, points)), ("c_a", np.linspace(5.0, 9.0, lines))]
    runs = {k: [] for k in ("k_a", "load", "k_a general", "load general")}
    for _ in range(5):
        for lean, tag in ((True, ""), (False, " general")):
            runs["k_a" + tag].append(timed(jobs=1, lean=lean))
            runs["load" + tag].append(timed(load_axes, config="C4", jobs=1, lean=lean))
    med = {k: float(np.median(v)) for k, v in runs.items()}
    base = med["k_a"]
    total = lines * points
    for key, method in (("k_a", "in-process"),
                        ("k_a general",
                         "in-process, general path (built and resolved at every k_a)"),
                        ("load", "in-process, C4 load f × c_a (command reused)"),
                        ("load general", "in-process, C4 load, general path (built at every f)")):
        t = med[key]
        general = med[key if key.endswith("general") else key + " general"]
        rows.append({"section": "sweeps", "method": method, "n": total, "workers": 1, "time": t,
                     "rate": total / t, "speedup": base / t, "vs_general": general / t,
                     "spread": (min(runs[key]) / t, max(runs[key]) / t)})
        log(f"sweeps {total} points, {method}: {t:.2f} s ({total / t:.1f} points/s, "
            f"{general / t:.2f}x the general path)")
    for w in range(2, cores + 1):
        t = timed(jobs=w)
        rows.append({"section": "sweeps", "method": "local processes", "n": total, "workers": w,
                     "time": t, "rate": total / t, "speedup": base / t})
        log(f"sweeps {total} points on {w} processes: {t:.2f} s (×{base / t:.2f})")
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        log("sweeps: dask.distributed not installed: Dask rows skipped")
        return rows
    for w in range(1, cores + 1):
        with LocalCluster(n_workers=w, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cl, \
                Client(cl) as client:
            timed(scheduler=client)  # workers import mbseig once
            t = timed(scheduler=client)
        rows.append({"section": "sweeps", "method": "Dask LocalCluster", "n": total, "workers": w,
                     "time": t, "rate": total / t, "speedup": base / t})
        log(f"sweeps {total} points on a Dask LocalCluster of {w}: {t:.2f} s (×{base / t:.2f})")
    return rows


SMALL_CASES = ("spatial_double_pendulum", "spherical_pendulum", "hand_device")


def bench_small_stages(repeats, log, cases=SMALL_CASES):
    """Small models stage by stage, from the parsed case to the eigenvalues (build, equilibrium,
    linearize, modes with every measure they report), medians of ``repeats`` runs interleaved
    with the eigen floor of the same run: LAPACK ``geev`` (``scipy.linalg.eig``, right vectors)
    of the model's 2d first companion matrix, the call a compiled peer's eigen step makes."""
    import scipy.linalg as sla

    from ..casefile import read_case
    from ..studies.point import eigen_stage, equilibrium_stage

    rows = []
    for name in cases:
        spec = read_case(case_path(name))
        stages = {k: [] for k in ("build", "equilibrium", "linearize", "modes", "floor")}
        for _ in range(repeats):
            t0 = time.perf_counter()
            model = spec.build()
            t1 = time.perf_counter()
            eq = equilibrium_stage(model)
            t2 = time.perf_counter()
            lin = linearize(model, eq)
            t3 = time.perf_counter()
            md = eigen_stage(lin)
            t4 = time.perf_counter()
            M, P, Q = (np.asarray(A.toarray() if hasattr(A, "toarray") else A) for A in
                       (lin.M, lin.P, lin.Q))
            d = M.shape[0]
            t5 = time.perf_counter()
            Minv = np.linalg.inv(M)
            sla.eig(np.block([[np.zeros((d, d)), np.eye(d)], [-Minv @ Q, -Minv @ P]]))
            t6 = time.perf_counter()
            for k, v in zip(stages, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t6 - t5), strict=True):
                stages[k].append(v)
        med = {k: float(np.median(v)) for k, v in stages.items()}
        total = med["build"] + med["equilibrium"] + med["linearize"] + med["modes"]
        rows.append({"section": "small", "method": name, "n": int(lin.dof), "time": total,
                     **med, "ratio": total / med["floor"], "solver": md.solver,
                     "repeats": repeats})
        log(f"small {name}: build {med['build'] * 1e3:.2f} + equilibrium "
            f"{med['equilibrium'] * 1e3:.2f} + linearize {med['linearize'] * 1e3:.2f} + modes "
            f"{med['modes'] * 1e3:.2f} = {total * 1e3:.2f} ms; eig floor "
            f"{med['floor'] * 1e3:.3f} ms ({total / med['floor']:.0f}x)")
    return rows


# ---------------------------------------------------------------------------------------------
def _spring_net_case(n):
    """A 2-D chain of n unit masses on springs (stiffness growing along it), under its own
    free lengths' preload."""
    from ..casefile.writer import CaseBuilder

    net = CaseBuilder(dimension=2, source="bench: 2-D chain of springs under a tip load")
    net.parameter("n", n)
    net.point("a", [0.0, 0.0], fixed=True)
    net.point("p{i}", ["0.4*i", "0.05*i**1.5"], repeat={"i": [1, "n"]})
    net.mass("p{i}", 1.0, repeat={"i": [1, "n"]})
    net.force("spring_damper", points=["a", "p1"], stiffness=800.0, damping=1.0,
              free_length=0.35)
    net.force("spring_damper", repeat={"i": [1, "n - 1"]}, points=["p{i}", "p{i + 1}"],
              stiffness="500 + 10*i", damping=0.2, free_length=0.35)
    return net.to_toml()


def _complex_g(model):
    """g(q) of the model's springs for complex q: mbseig's own spring law
    (:func:`mbseig.model.batched.spring_forces`, complex-step safe: l = √(d·d)) on q + ih."""
    singles = [f for f in model.forces if not isinstance(f, BatchForce)]
    batches = [f for f in model.forces if isinstance(f, BatchForce)]

    def g(q):
        out = np.zeros(q.shape[0], dtype=q.dtype)
        zero = np.zeros_like(q)
        for f in singles:  # SpringDamper on an affine difference map
            np.add.at(out, f.idx, -(f.diff.C.T @ spring_forces(*f.members(q, zero))[0]))
        for b in batches:
            fm = spring_forces(*b.members(q, zero))
            for idx, sign in ((b.ia, 1.0), (b.ib, -1.0)):
                ok = idx >= 0
                np.add.at(out, idx[ok], sign * fm[ok])
        return out

    return g


def bench_jacobians(sizes, repeats, log, tmpdir):
    rows = []
    for npts in sizes:
        path = Path(tmpdir) / f"spring_net_{npts}.toml"
        path.write_text(_spring_net_case(npts))
        model = load_case(path)
        rng = np.random.default_rng(0)
        q = model.q_init + 0.02 * rng.normal(size=model.n)
        n = model.n

        def g(x, model=model):
            return model.generalized_force(x)

        gc = _complex_g(model)
        E = np.eye(n)
        fd_h, cd_h, cs_h = (1e-7 * max(1.0, np.abs(q).max()), 1e-5 * max(1.0, np.abs(q).max()),
                            1e-30)
        g0 = g(q)
        fns = {
            "analytic": lambda model=model, q=q: model.force_jacobians(q)[0].toarray(),
            "forward differences": lambda g=g, q=q, fd_h=fd_h, g0=g0, E=E: -np.column_stack(
                [(g(q + fd_h * e) - g0) / fd_h for e in E]),
            "central differences": lambda g=g, q=q, cd_h=cd_h, E=E: -np.column_stack(
                [(g(q + cd_h * e) - g(q - cd_h * e)) / (2 * cd_h) for e in E]),
            "complex step": lambda gc=gc, q=q, cs_h=cs_h, E=E: -np.column_stack(
                [gc(q + 1j * cs_h * e).imag / cs_h for e in E]),
        }
        t, out = median_times(fns, repeats)
        ref = out["complex step"]
        scale = np.abs(ref).max()
        for name in fns:
            err = float(np.abs(out[name] - ref).max() / scale) if name != "complex step" else \
                float(np.abs(out[name] - out["analytic"]).max() / scale)
            rows.append({"section": "jacobians", "method": name, "n": n, "time": t[name],
                         "error": err})
            log(f"jacobian n={n:5d} {name:20s} {t[name]:.5f} s  rel err {err:.1e}")
    return rows


def bench_constraint_stiffness(repeats, log):
    rows = []
    for case, exact in (("pendulum", math.sqrt(9.81)), ("four_bar", None)):
        model = load_case(case_path(case))
        eq = equilibrium(model)
        fns = {"with Σλ∇²Φ": lambda model=model, eq=eq: linearize(model, eq),
               "without Σλ∇²Φ": lambda model=model, eq=eq: linearize(model, eq,
                                                                    constraint_stiffness=False)}
        t, out = median_times(fns, repeats)
        w = {k: float(modes(v.M, v.P, v.Q).omega_n[0]) for k, v in out.items()}
        ref = exact if exact is not None else w["with Σλ∇²Φ"]
        for k in fns:
            rows.append({"section": "constraint", "method": f"{case} {k}", "n": model.n,
                         "time": t[k], "omega": w[k], "error": abs(w[k] - ref) / ref,
                         "reference": "√(g/l)" if exact
                         else "mbseig with Σλ∇²Φ (independent reduction in tests)"})
            log(f"constraint {case:9s} {k:15s} ω = {w[k]:.6g}  rel err {rows[-1]['error']:.1e}  "
                f"{t[k]:.5f} s")
    return rows


def bench_timedomain(log):
    """δ error of the time-domain check against cost, for three integrator settings."""
    rows = []
    model = load_case(case_path("ziegler_pendulum"), config="flutter")
    eq = equilibrium(model)
    lin = linearize(model, eq)
    md = modes(lin.M, lin.P, lin.Q, N=lin.N, coordinate_names=lin.coordinate_names)
    settings = [("DOP853 rtol 1e-10 (default)", "DOP853", 1e-10),
                ("DOP853 rtol 1e-4 (loose explicit)", "DOP853", 1e-4),
                ("Radau rtol 1e-3 (loose implicit)", "Radau", 1e-3),
                ("BDF rtol 1e-3 (low-order implicit)", "BDF", 1e-3)]
    for label, method, rtol in settings:
        try:
            res = check_modes(model, eq, lin, md, method=method, ode_rtol=rtol)
        except Exception as exc:  # noqa: BLE001 - a failed setting is a result to report
            log(f"timedomain {label}: {exc}")
            continue
        for mc in res.modes:
            if mc.skipped:
                continue
            rows.append({"section": "timedomain", "method": label, "n": int(mc.index),
                         "time": res.elapsed, "error": float(mc.rel_error_delta),
                         "predicted_delta": float(mc.predicted_delta),
                         "measured_delta": float(mc.measured_delta), "passed": bool(mc.passed),
                         "nfev": int(mc.nfev)})
            log(f"timedomain {label:34s} mode {mc.index}: δ pred {mc.predicted_delta:+.4g} meas "
                f"{mc.measured_delta:+.4g} rel err {mc.rel_error_delta:.1e} ({res.elapsed:.2f} s)")
    return rows, ""
