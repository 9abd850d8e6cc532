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
sweeps     device sweeps: points a second in-process, by the lean path (the default) and the
           general path (``lean=False``) interleaved, speed-up on local processes and on a
           Dask LocalCluster (multi-process scheduler), 1 … cores.
peer       small models stage by stage (build, equilibrium, linearize, modes) against the eigen
           floor of the same run; EXUDYN's eigenvalues on a chain with non-proportional damping
           and on two spatial rigid-body models (damped spherical pendulum, spatial double
           pendulum) against closed forms (mbseig.bench.peer), when ``exudyn`` is installed.
jacobians  analytic K of a 2-D spring network against forward and central differences and the
           complex step.
constraint linearization with and without the constraint-force stiffness.
timedomain the time-domain check's integrator (mbseig.check) against loose settings.
failures   mbseig.bench.failcases: where naive methods give the wrong verdict.
nlevp      quadratic eigenproblems of the NLEVP collection (mbseig.bench.nlevp), each with its
           verdict, backward error or refusal.
lean       lean flexible models (mbseig.bench.lean_rows): a multi-span shaft of 10³ … 10⁵ DOF
           against an FE floor script (time and memory, fresh processes), Campbell sweeps
           against ROSS's run_campbell (MBSEIG_ROSS_PYTHON), FE bodies against LAPACK's error.
"""

from __future__ import annotations

import json
import os
import platform
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from .dense_rows import (
    bench_dense,
    bench_left_vectors,
    bench_pipeline,
    bench_structured,
    capped_threads,
    json_default,
)
from .cases import load_average
from .failcases import run_all
from .nlevp import bench_nlevp
from .peer import bench_peer
from .pipeline_rows import (
    bench_constraint_stiffness,
    bench_jacobians,
    bench_sweeps,
    bench_timedomain,
)
from .report import write_report
from .sparse_rows import bench_large, bench_partial
from .startup_rows import bench_startup

__all__ = ["run_bench"]


# ---------------------------------------------------------------------------------------------
def run_bench(*, quick=False, out_dir=None, repeats=None, threads=1, sections=None, log=print):
    """Run the benchmark and write the report; returns the result dict."""
    out_dir = Path(out_dir or "reports")
    out_dir.mkdir(parents=True, exist_ok=True)
    repeats = repeats or (1 if quick else 3)
    all_sections = ("dense", "structured", "partial", "large", "startup", "peer", "sweeps",
                    "jacobians", "constraint", "timedomain", "failures", "nlevp", "rotor", "beams",
                    "slepc", "spatial", "batch", "uncertainty", "lean")
    sections = sections or all_sections
    cfg = {
        "quick": quick, "repeats": repeats, "threads": threads,
        "dense_sizes": [10, 30, 100] if quick else [10, 30, 100, 300, 1000],
        "qz_max": 100 if quick else 300, "naive_max": 100 if quick else 1000,
        "general_max": 100 if quick else 3000,
        "structured_sizes": [100] if quick else [300, 1000, 3000],
        "pipeline_sizes": [100] if quick else [100, 300, 600, 1000],
        "partial_sizes": [1000, 3000] if quick else [10_000, 100_000, 1_000_000],
        "partial_general_max": 3000 if quick else 100_000,
        "jacobian_sizes": [10] if quick else [10, 100],
        "left_n": 100 if quick else 1000,
        "large_sizes": [2000] if quick else [10_000, 100_000, 1_000_000],
        "slepc_sizes": [2000] if quick else [10_000, 100_000, 1_000_000],
        "startup_repeats": max(repeats, 1 if quick else 15),
        "peer_sizes": [20] if quick else [50, 200, 500],
        "sweep_grid": (2, 5) if quick else (6, 20),
    }
    res = {"config": cfg, "rows": [], "machine": _machine(), "load": {"start": load_average()}}
    t_start = time.perf_counter()
    with capped_threads(threads), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        if "dense" in sections:
            res["rows"] += bench_dense(cfg["dense_sizes"], repeats, cfg["qz_max"], cfg["naive_max"],
                                       cfg["general_max"], log)
            res["left_vectors"] = bench_left_vectors(cfg["left_n"], repeats, log)
        if "structured" in sections:
            res["rows"] += bench_structured(cfg["structured_sizes"], repeats, cfg["general_max"],
                                            log)
            res["rows"] += bench_pipeline(cfg["pipeline_sizes"], repeats, log)
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
        if "rotor" in sections:  # ROSS only where MBSEIG_ROSS_PYTHON names a Python with it
            from .rotor_rows import bench_rotor

            res["rows"] += bench_rotor(log, repeats=repeats, n_speeds=9 if quick else 41)
        if "beams" in sections:
            from .beam_rows import bench_beams

            res["rows"] += bench_beams(log, repeats=repeats, beams=5 if quick else 50,
                                       elements=40 if quick else 334)
        if "spatial" in sections:
            from .spatial_rows import bench_spatial

            res["rows"] += bench_spatial(log, n=500 if quick else 10_000, repeats=repeats)
        if "batch" in sections:
            from .batch_rows import bench_batch

            res["rows"] += bench_batch(log, repeats=repeats, quick=quick)
        if "uncertainty" in sections:
            from .uncertainty_rows import bench_uncertainty

            res["rows"] += bench_uncertainty(log, repeats=repeats, quick=quick)
        if "lean" in sections:  # ROSS only where MBSEIG_ROSS_PYTHON names a Python with it
            from .lean_rows import bench_lean

            res["rows"] += bench_lean(log, repeats=repeats, quick=quick)
        if "failures" in sections:
            res["failures"] = [{k: getattr(c, k)
                                for k in ("name", "naive_method", "naive", "mbseig", "reference",
                                          "naive_wrong", "mbseig_right")}
                               for c in run_all()]
    if "partial" in sections:  # fresh processes: BLAS threads set through the environment
        res["rows"] += bench_partial(cfg["partial_sizes"], repeats, cfg["partial_general_max"],
                                     threads, log)
    if "large" in sections:  # SLEPc has its own section, against SLEPc itself
        res["rows"] += bench_large(cfg["large_sizes"], 1 if quick else repeats, threads, log,
                                   slepc=False)
    if "slepc" in sections:
        from .slepc_rows import bench_slepc

        res["rows"] += bench_slepc(cfg["slepc_sizes"], repeats, log, threads=threads)
    if "startup" in sections:
        res["rows"] += bench_startup(cfg["startup_repeats"], log)
    res["elapsed"] = time.perf_counter() - t_start
    res["load"]["end"] = load_average()
    (out_dir / "benchmarks.json").write_text(json.dumps(res, indent=1, default=json_default))
    write_report(res, out_dir)
    return res






def _machine():
    import scipy

    return {"python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "cpus": os.cpu_count(), "platform": platform.platform()}
