"""``mbseig bench``: speed against accuracy, measured side by side in one run.

Writes ``reports/benchmarks.md`` and ``reports/speed_accuracy.png`` (error against wall time,
one point per method and size).  Every time is the median of ``repeats`` runs; methods that are
compared run interleaved (floor, method, floor, method, ...) so that the ratios stated in the
report come from the same moments of a shared, noisy machine.  BLAS is capped to ``threads``
threads (threadpoolctl) unless ``threads = 0``.

Sections
--------
dense      chain_damped family (closed-form eigenvalues) n = 10 … 3000 reduced DOF: naive
           companion (explicit M⁻¹, unscaled), QZ unscaled, QZ scaled, mbseig's companion path
           (the dense general path), mbseig's default (structured), and LAPACK's geev on the
           same 2n companion with vectors (the floor).
structured undamped / proportionally damped chains: eigh and proportional paths against the
           dense general path on the same matrices.
partial    lowest 20 modes of the damped chain, 10⁴ … 10⁶ coordinates, whole pipeline (load,
           equilibrium, linearization, modes) in a fresh process each (peak memory), and the
           general (non-proportional) partial path.
large      lowest 20 modes of a 1-D chain with n/10 rigid links (bordered pencil) and
           non-proportional damping, 10⁴ … 10⁶ coordinates: the general partial path (and the
           optional SLEPc backend) against the undamped eigsh shift-invert floor, fresh processes.
startup    ``mbseig modes`` on the hand device against ``import numpy, scipy.linalg``.
sweeps     device sweeps: points a second in-process, speed-up on local processes and on a
           Dask LocalCluster (multi-process scheduler), 1 … cores.
peer       EXUDYN's eigenvalues on a chain with non-proportional damping and on two spatial
           rigid-body models (damped spherical pendulum, spatial double pendulum) against closed
           forms (mbseig.bench.peer), when ``exudyn`` is installed.
jacobians  analytic K of a 2-D spring network against forward and central differences and the
           complex step.
constraint linearization with and without the constraint-force stiffness.
timedomain the time-domain check's integrator (mbseig.check) against loose settings.
failures   mbseig.bench.failcases: where naive methods give the wrong verdict.
nlevp      quadratic eigenproblems of the NLEVP collection (mbseig.bench.nlevp), each with its
           verdict, backward error or refusal.
"""

from __future__ import annotations

import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
import warnings
from contextlib import nullcontext
from pathlib import Path

import numpy as np
import scipy.linalg as sla

from ..casefile import load_case
from ..check import check_modes
from ..eigen import solve_qep
from ..linear import linearize
from ..modal import modes
from ..model.batched import spring_forces
from ..statics import equilibrium
from .cases import case_path
from .failcases import run_all
from .nlevp import bench_nlevp
from .peer import bench_peer
from .report import write_report

__all__ = ["run_bench"]


# ---------------------------------------------------------------------------------------------
def _threads(n):
    if not n:
        return nullcontext()
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - optional
        warnings.warn("threadpoolctl not installed: BLAS threads not capped", RuntimeWarning)
        return nullcontext()
    return threadpool_limits(limits=n)


def _median_times(fns, repeats):
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
    pos = np.clip(np.searchsorted(ex.imag, s.imag), 1, ex.size - 1) if ex.size > 1 else np.zeros(s.size, int)
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
            fns["LAPACK geev (floor)"] = lambda: g * sla.eig(A, check_finite=False)[0]
            fns["mbseig companion"] = lambda: solve_qep(M, C, K, solver="companion")
        if n <= naive_max:
            fns["naive companion"] = lambda: _naive_with_vectors(M, C, K)
        if n <= qz_max:
            fns["QZ unscaled"] = lambda: solve_qep(M, C, K, solver="qz", scale=False)
            fns["QZ scaled"] = lambda: solve_qep(M, C, K, solver="qz")
        fns["mbseig default"] = lambda: solve_qep(M, C, K)
        t, out = _median_times(fns, reps)
        for name, res in out.items():
            s = res if isinstance(res, np.ndarray) else res.eigenvalues
            eta = math.nan if isinstance(res, np.ndarray) else float(np.max(res.backward_error))
            solver = name if isinstance(res, np.ndarray) else res.solver
            rows.append({"section": "dense", "method": name, "n": n, "time": t[name], "repeats": reps,
                         "error": rel_error(s, exact), "eta": eta, "solver": solver})
            log(f"dense n={n:5d} {name:22s} {t[name]:9.4f} s  err {rows[-1]['error']:.1e}  η {eta:.1e}")
    return rows


def _naive_with_vectors(M, C, K):
    n = M.shape[0]
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ C]])
    return np.linalg.eig(A)[0]


def bench_left_vectors(n, repeats, log):
    """Cost of LAPACK's left eigenvectors on the dense companion path (non-symmetric P)."""
    M, C, K = chain_matrices(n)
    fns = {"right only": lambda: solve_qep(M, C, K, solver="companion", left=False),
           "left and right": lambda: solve_qep(M, C, K, solver="companion", left=True)}
    t, _ = _median_times(fns, repeats)
    log(f"left vectors n={n}: {t}")
    return {"n": n, **t}


def bench_structured(sizes, repeats, general_max, log):
    rows = []
    for n in sizes:
        for damped, label in ((False, "eigh"), (True, "proportional")):
            M, C, K = chain_matrices(n, damped=damped)
            exact = chain_exact(n, damped=damped)
            fns = {"floor": lambda: sla.eigh(K, M, check_finite=False), label: lambda: solve_qep(M, C, K)}
            if n <= general_max:
                fns["general"] = lambda: solve_qep(M, C, K, solver="companion")
            t, out = _median_times(fns, repeats if n <= 1000 else 1)
            row = {"section": "structured", "method": f"mbseig {label}", "n": n, "time": t[label],
                   "error": rel_error(out[label].eigenvalues, exact),
                   "eta": float(out[label].backward_error.max()), "solver": out[label].solver}
            row["floor_time"] = t["floor"]  # eigh(Q, M) with vectors, interleaved
            row["floor_ratio"] = t[label] / t["floor"]
            if "general" in t:
                row["general_time"] = t["general"]
                row["speedup"] = t["general"] / t[label]
            rows.append(row)
            log(f"structured n={n:5d} {label:13s} {t[label]:.4f} s  general {t.get('general', math.nan):.3f} s")
    return rows


# ---------------------------------------------------------------------------------------------
def _partial_worker(kind, n, n_modes):
    """Run in a fresh process: whole pipeline for the damped chain, JSON on stdout."""
    import resource

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
    err = rel_error(md.eigenvalues, chain_exact(n)[: n_modes + 5]) if kind == "proportional" else math.nan
    rss = _peak_rss_mb(resource)
    print(json.dumps({"kind": kind, "n": n, "load": t1 - t0, "equilibrium": t2 - t1, "linearize": t3 - t2,
                      "modes": t4 - t3, "total": t4 - t0, "rss_mb": rss, "error": err,
                      "eta": float(md.backward_error.max()), "solver": md.solver,
                      "n_listed": len(md), "verdict": md.verdict}))


def _peak_rss_mb(resource):
    """Peak resident memory of this process (VmHWM: ru_maxrss would inherit the parent's peak)."""
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
        env.update({k: str(threads) for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")})
    for kind in ("proportional", "general"):
        for n in sizes:
            if kind == "general" and n > general_max:
                continue
            runs = []
            for _ in range(repeats):  # medians at every size, 10⁶ included (≈20 s a run)
                code = f"from mbseig.bench.run import _partial_worker; _partial_worker({kind!r}, {n}, {n_modes})"
                p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
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
            log(f"partial {kind:12s} n={n:8d} total {med['total']:.2f} s (modes {med['modes']:.2f}) "
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
    K = sp.diags([2 * k * np.ones(n), -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1], format="csr")
    cd = np.zeros(n)
    cd[::7] = c_ground
    C = (sp.diags(cd) + beta * K).tocsr()
    M = sp.diags(1 + 0.5 * np.sin(i), format="csr")
    a = np.arange(every - 1, n - 1, every)
    r = np.arange(a.size)
    G = sp.csr_matrix((np.r_[-np.ones(a.size), np.ones(a.size)], (np.r_[r, r], np.r_[a, a + 1])),
                      shape=(a.size, n))
    return M, C, K, G


def _large_worker(kind, n, n_modes):
    """Fresh process: one solve of the large constrained model, JSON on stdout (peak RSS)."""
    import resource

    import scipy.sparse.linalg as spla

    from ..eigen import solve_partial
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
        sol = solve_partial(M, C, K, G=G, n_modes=n_modes, solver=kind)
        out.update(eta=float(np.max(sol.backward_error)), verified=bool(sol.coverage["verified"]),
                   omega_1=float(np.min(np.abs(sol.eigenvalues))), slepc=sol.details.get("slepc"),
                   solver=sol.solver, arpack_k=sol.details.get("arpack_k"))
        pj = sol.details.get("projected")
        if pj:  # the projected path's figures: Lanczos size, refinement rounds, LU solves
            out["projected"] = {k: pj[k] for k in ("k_u", "iterations", "basis_size", "lu_solves",
                                                   "eta_history", "seconds")}
            out["projected"]["certificate"] = {k: pj["certificate"].get(k) for k in
                                               ("R", "tau", "rho", "Omega", "n_inside", "why")}
    out.update(solve=time.perf_counter() - t1, rss_mb=_peak_rss_mb(resource))
    print(json.dumps(out, default=_json_default))


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
        env.update({k: str(threads) for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")})
    rows = []
    for n in sizes:
        runs = {k: [] for k in kinds}
        for rep in range(repeats):
            for kind in kinds:
                if n >= 1_000_000 and rep and kind in ("partial-companion", "partial-slepc"):
                    continue  # 10⁶: the slow paths once (minutes a run), floor and projected medians
                code = f"from mbseig.bench.run import _large_worker; _large_worker({kind!r}, {n}, {n_modes})"
                p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
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
            log(f"large {kind:18s} n={n:8d} {t:8.2f} s  ({row['ratio']:.2f}x floor) rss {row['rss_mb']:.0f} MB "
                f"η {row['eta']:.1e}" + ("" if kind == "floor" else f" verified {row['verified']}"))
    return rows


def bench_startup(repeats, log, case="hand_device"):
    """Wall time of ``mbseig modes CASE`` against ``python -c "import numpy, scipy.linalg"``,
    interleaved, medians (the start-up goal's ratio)."""
    exe = Path(sys.executable).with_name("mbseig")
    cli = [str(exe)] if exe.exists() else [sys.executable, "-m", "mbseig"]
    cmds = {"import numpy, scipy.linalg (floor)": [sys.executable, "-c", "import numpy, scipy.linalg"],
            "import mbseig": [sys.executable, "-c", "import mbseig"],
            f"mbseig modes {case}": [*cli, "modes", str(case_path(case))],
            # the same command through main() with Python's normal exit (teardown included):
            # what the executable's prompt exit saves (mbseig.cli.console)
            f"mbseig modes {case}, normal exit": [
                sys.executable, "-c", "import sys; from mbseig.cli import main; "
                f"sys.exit(main(['modes', {str(case_path(case))!r}]))"]}
    # as Python runs by default, from cached bytecode: a PYTHONDONTWRITEBYTECODE in the
    # environment (set on some CI machines) would make every run compile mbseig's modules
    # anew (≈ 60 ms here) while numpy and scipy load theirs from the install; one untimed
    # round writes the cache, as the first run after `pip install -e .` does (a plain
    # `pip install .` compiles at install time)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    for c in cmds.values():
        subprocess.run(c, capture_output=True, check=True, env=env)
    times = {k: [] for k in cmds}
    for _ in range(repeats):
        for k, c in cmds.items():
            t = time.perf_counter()
            subprocess.run(c, capture_output=True, check=True, env=env)
            times[k].append(time.perf_counter() - t)
    floor = float(np.median(times["import numpy, scipy.linalg (floor)"]))
    rows = []
    for k, v in times.items():
        t = float(np.median(v))
        rows.append({"section": "startup", "method": k, "n": 0, "time": t, "ratio": t / floor,
                     "repeats": repeats})
        log(f"startup {k:38s} {t:.3f} s  ({t / floor:.2f}x floor)")
    return rows


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
    # the two in-process sweeps: medians of three interleaved runs (one run of ≈ 2 s moved by
    # ±20 % on this shared machine)
    load_axes = [("f", np.linspace(0.0, 1.5, points)), ("c_a", np.linspace(5.0, 9.0, lines))]
    runs = {"k_a": [], "load": []}
    for _ in range(3):
        runs["k_a"].append(timed(jobs=1))
        runs["load"].append(timed(load_axes, config="C4", jobs=1))
    base = float(np.median(runs["k_a"]))
    total = lines * points
    rows.append({"section": "sweeps", "method": "in-process", "n": total, "workers": 1, "time": base,
                 "rate": total / base, "speedup": 1.0})
    log(f"sweeps {total} points in-process: {base:.2f} s ({total / base:.1f} points/s)")
    # the device's load study (C4: tendon load f × damping), whose inverse-statics command
    # the swept parameters do not enter (settings reused): the rate without re-solving it
    t = float(np.median(runs["load"]))
    rows.append({"section": "sweeps", "method": "in-process, C4 load f × c_a (command reused)",
                 "n": total, "workers": 1, "time": t, "rate": total / t, "speedup": base / t})
    log(f"sweeps {total} points in-process, C4 load sweep: {t:.2f} s ({total / t:.1f} points/s)")
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
        with LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
                Client(cl) as client:
            timed(scheduler=client)  # workers import mbseig once
            t = timed(scheduler=client)
        rows.append({"section": "sweeps", "method": "Dask LocalCluster", "n": total, "workers": w,
                     "time": t, "rate": total / t, "speedup": base / t})
        log(f"sweeps {total} points on a Dask LocalCluster of {w}: {t:.2f} s (×{base / t:.2f})")
    return rows

# ---------------------------------------------------------------------------------------------
def _spring_net_case(n):
    return f"""
schema_version = 1
dimension = 2
source = "bench: 2-D chain of springs under a tip load"
[parameters]
n = {n}
[[points]]
name = "a"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "p{{i}}"
repeat = {{ i = [1, "n"] }}
position = ["0.4*i", "0.05*i**1.5"]
[[masses]]
repeat = {{ i = [1, "n"] }}
point = "p{{i}}"
mass = 1.0
[[forces]]
type = "spring_damper"
points = ["a", "p1"]
stiffness = 800.0
damping = 1.0
free_length = 0.35
[[forces]]
type = "spring_damper"
repeat = {{ i = [1, "n - 1"] }}
points = ["p{{i}}", "p{{i + 1}}"]
stiffness = "500 + 10*i"
damping = 0.2
free_length = 0.35
"""


def _complex_g(model):
    """g(q) of the model's springs for complex q: mbseig's own spring law
    (:func:`mbseig.model.batched.spring_forces`, complex-step safe: l = √(d·d)) on q + ih."""
    singles = [f for f in model.forces if not hasattr(f, "member_forces")]
    batches = [f for f in model.forces if hasattr(f, "member_forces")]

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
        g = lambda x: model.generalized_force(x)
        gc = _complex_g(model)
        E = np.eye(n)
        fd_h, cd_h, cs_h = 1e-7 * max(1.0, np.abs(q).max()), 1e-5 * max(1.0, np.abs(q).max()), 1e-30
        fns = {
            "analytic": lambda: model.force_jacobians(q)[0].toarray(),
            "forward differences": lambda: -np.column_stack([(g(q + fd_h * e) - g0) / fd_h for e in E]),
            "central differences": lambda: -np.column_stack([(g(q + cd_h * e) - g(q - cd_h * e)) / (2 * cd_h) for e in E]),
            "complex step": lambda: -np.column_stack([gc(q + 1j * cs_h * e).imag / cs_h for e in E]),
        }
        g0 = g(q)
        t, out = _median_times(fns, repeats)
        ref = out["complex step"]
        scale = np.abs(ref).max()
        for name in fns:
            err = float(np.abs(out[name] - ref).max() / scale) if name != "complex step" else \
                float(np.abs(out[name] - out["analytic"]).max() / scale)
            rows.append({"section": "jacobians", "method": name, "n": n, "time": t[name], "error": err})
            log(f"jacobian n={n:5d} {name:20s} {t[name]:.5f} s  rel err {err:.1e}")
    return rows


def bench_constraint_stiffness(repeats, log):
    rows = []
    for case, exact in (("pendulum", math.sqrt(9.81)), ("four_bar", None)):
        model = load_case(case_path(case))
        eq = equilibrium(model)
        fns = {"with Σλ∇²Φ": lambda: linearize(model, eq),
               "without Σλ∇²Φ": lambda: linearize(model, eq, constraint_stiffness=False)}
        t, out = _median_times(fns, repeats)
        w = {k: float(modes(v.M, v.P, v.Q).omega_n[0]) for k, v in out.items()}
        ref = exact if exact is not None else w["with Σλ∇²Φ"]
        for k in fns:
            rows.append({"section": "constraint", "method": f"{case} {k}", "n": model.n, "time": t[k],
                         "omega": w[k], "error": abs(w[k] - ref) / ref,
                         "reference": "√(g/l)" if exact else "mbseig with Σλ∇²Φ (independent reduction in tests)"})
            log(f"constraint {case:9s} {k:15s} ω = {w[k]:.6g}  rel err {rows[-1]['error']:.1e}  {t[k]:.5f} s")
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
            rows.append({"section": "timedomain", "method": label, "n": int(mc.index), "time": res.elapsed,
                         "error": float(mc.rel_error_delta), "predicted_delta": float(mc.predicted_delta),
                         "measured_delta": float(mc.measured_delta), "passed": bool(mc.passed),
                         "nfev": int(mc.nfev)})
            log(f"timedomain {label:34s} mode {mc.index}: δ pred {mc.predicted_delta:+.4g} meas "
                f"{mc.measured_delta:+.4g} rel err {mc.rel_error_delta:.1e} ({res.elapsed:.2f} s)")
    return rows, ""


# ---------------------------------------------------------------------------------------------
def run_bench(*, quick=False, out_dir=None, repeats=None, threads=1, sections=None, log=print):
    """Run the benchmark and write the report; returns the result dict."""
    out_dir = Path(out_dir or "reports")
    out_dir.mkdir(parents=True, exist_ok=True)
    repeats = repeats or (1 if quick else 3)
    all_sections = ("dense", "structured", "partial", "large", "startup", "peer", "sweeps",
                    "jacobians", "constraint", "timedomain", "failures", "nlevp")
    sections = sections or all_sections
    cfg = {
        "quick": quick, "repeats": repeats, "threads": threads,
        "dense_sizes": [10, 30, 100] if quick else [10, 30, 100, 300, 1000],
        "qz_max": 100 if quick else 300, "naive_max": 100 if quick else 1000,
        "general_max": 100 if quick else 3000,
        "structured_sizes": [100] if quick else [300, 1000, 3000],
        "partial_sizes": [1000, 3000] if quick else [10_000, 100_000, 1_000_000],
        "partial_general_max": 3000 if quick else 100_000,
        "jacobian_sizes": [10] if quick else [10, 100],
        "left_n": 100 if quick else 1000,
        "large_sizes": [2000] if quick else [10_000, 100_000, 1_000_000],
        "startup_repeats": 1 if quick else 15,
        "peer_sizes": [20] if quick else [50, 200, 500],
        "sweep_grid": (2, 5) if quick else (6, 20),
    }
    res = {"config": cfg, "rows": [], "machine": _machine()}
    t_start = time.perf_counter()
    with _threads(threads), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        if "dense" in sections:
            res["rows"] += bench_dense(cfg["dense_sizes"], repeats, cfg["qz_max"], cfg["naive_max"],
                                       cfg["general_max"], log)
            res["left_vectors"] = bench_left_vectors(cfg["left_n"], repeats, log)
        if "structured" in sections:
            res["rows"] += bench_structured(cfg["structured_sizes"], repeats, cfg["general_max"], log)
        if "peer" in sections:
            rows, note = bench_peer(cfg["peer_sizes"], repeats, log)
            res["rows"] += rows
            res["peer_note"] = note
        if "sweeps" in sections:
            res["rows"] += bench_sweeps(*cfg["sweep_grid"], log)
        if "jacobians" in sections:
            with tempfile.TemporaryDirectory() as tmp:
                res["rows"] += bench_jacobians(cfg["jacobian_sizes"], repeats, log, tmp)
        if "constraint" in sections:
            res["rows"] += bench_constraint_stiffness(repeats, log)
        if "timedomain" in sections:
            rows, why = bench_timedomain(log)
            res["rows"] += rows
            res["timedomain_note"] = why
        if "nlevp" in sections:
            res["rows"] += bench_nlevp(log)
        if "failures" in sections:
            res["failures"] = [{k: getattr(c, k) for k in ("name", "naive_method", "naive", "mbseig",
                                                           "reference", "naive_wrong", "mbseig_right")}
                               for c in run_all()]
    if "partial" in sections:  # fresh processes: BLAS threads set through the environment
        res["rows"] += bench_partial(cfg["partial_sizes"], repeats, cfg["partial_general_max"], threads, log)
    if "large" in sections:
        res["rows"] += bench_large(cfg["large_sizes"], 1 if quick else repeats, threads, log,
                                   slepc=not quick)
    if "startup" in sections:
        res["rows"] += bench_startup(cfg["startup_repeats"], log)
    res["elapsed"] = time.perf_counter() - t_start
    (out_dir / "benchmarks.json").write_text(json.dumps(res, indent=1, default=_json_default))
    write_report(res, out_dir)
    return res


def _json_default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    return str(x)


def _machine():
    import scipy

    return {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "cpus": os.cpu_count(), "platform": platform.platform()}
