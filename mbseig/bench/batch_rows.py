"""Rows of ``mbseig bench`` for many points at once (issue "Many points at once"): sweeps in
points a second, one core (``jobs=1``, one BLAS thread), against the goals of the issue:

- the spatial double pendulum over its masses and lengths (a 2-D grid, m1 along each line, l1
  across: the geometry moves), per point at most EXUDYN's eigen call on the same kind of model
  (the floor, timed in the same run where EXUDYN is installed: the ``bench`` extra);
- the device's C4 load sweep over f (the equilibrium moves with the load, the flutter boundary
  located) and its k_a sweep: at least 3,000 points a second each;
- the bicycle from its bodies over its speed, boundaries located: at least 2,000 points a second.

Each row: the median of ``repeats`` runs after one warm-up run (imports and caches, as "after
the first" in the goals), the spread (fastest and slowest over the median), the machine's load
before and after, the points, the boundaries found, and whether the goal is met.
"""

from __future__ import annotations

import statistics
import time
import warnings

import numpy as np

from .cases import case_path, load_average

__all__ = ["bench_batch", "GOALS"]

GOALS = {"device C4 over f": 3000.0, "device over k_a": 3000.0, "bicycle over v": 2000.0}




def _timed(run, repeats):
    run()  # warm: imports and caches
    times, out = [], None
    for _ in range(repeats):
        t = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - t)
    return times, out


def _row(label, n, times, boundaries, goal_rate=None, floor=None, **extra):
    t = statistics.median(times)
    row = {"section": "batch", "method": label, "n": int(n), "time": t, "rate": n / t,
           "per_point": t / n, "spread": (min(times) / t, max(times) / t),
           "repeats": len(times), "boundaries": boundaries, **extra}
    if goal_rate is not None:
        row["goal"] = f"≥ {goal_rate:,.0f} points/s"
        row["met"] = bool(n / t >= goal_rate)
    if floor is not None:
        row["floor_per_point"] = floor
        row["goal"] = "per point ≤ EXUDYN's eigen call (1.0×)"
        row["ratio"] = (t / n) / floor
        row["met"] = bool(row["ratio"] <= 1.0)
    return row


def _exudyn_floor(repeats):
    """EXUDYN's eigen call on its spatial double pendulum (seconds, median), or None."""
    from .peer import SPATIAL_MODELS, _exudyn_eigenvalues, _exudyn_spatial, exudyn_available

    if not exudyn_available():
        return None
    _, p, _, _ = SPATIAL_MODELS["double"]
    sc, mbs = _exudyn_spatial("double", p)
    _exudyn_eigenvalues(mbs)
    times = []
    for _ in range(max(repeats, 5)):
        t = time.perf_counter()
        _exudyn_eigenvalues(mbs)
        times.append(time.perf_counter() - t)
    del sc, mbs
    return statistics.median(times)


def bench_batch(log, *, repeats=3, quick=False):
    """The rows (module docstring)."""
    from ..casefile import read_case
    from ..studies import run_sweep
    from ..studies.steady_sweep import steady_sweep

    rows = []
    load0 = load_average()
    n_dev = 400 if quick else 2000
    device = read_case(case_path("hand_device"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for label, config, axis, lo, hi in (("device C4 over f", "C4", "f", 0.0, 2.5),
                                            ("device over k_a", None, "k_a", 200.0, 2000.0)):
            axes = [(axis, np.linspace(lo, hi, n_dev))]

            def run(axes=axes, config=config):
                return run_sweep(device, axes, config=config, jobs=1, progress=False,
                                 curves=False)

            times, res = _timed(run, repeats)
            statics = sorted({p.get("statics") for p in res.points[0]})
            rows.append(_row(label, n_dev, times, len(res.boundaries), GOALS[label],
                             statics=statics, grid=f"{axis} {lo:g}..{hi:g}, {n_dev} points"))
            log(f"batch {label}: {n_dev} points {statistics.median(times):.2f} s "
                f"({rows[-1]['rate']:.0f} points/s; goal {GOALS[label]:.0f}), "
                f"{len(res.boundaries)} boundaries, statics {statics}")
        # the spatial double pendulum over its masses (along each line) and lengths (across)
        n1, n2 = (40, 10) if quick else (200, 100)
        pend = read_case(case_path("spatial_double_pendulum"))
        axes = [("m1", np.linspace(0.5, 3.0, n1)), ("l1", np.linspace(0.4, 0.9, n2))]

        def run_pendulum():
            return run_sweep(pend, axes, jobs=1, progress=False, curves=False)

        times, res = _timed(run_pendulum, 1 if not quick else repeats)
        floor = _exudyn_floor(repeats)
        statics = sorted({p.get("statics") for line in res.points for p in line})
        rows.append(_row("spatial double pendulum over m1 × l1", n1 * n2, times,
                         len(res.boundaries), floor=floor, statics=statics,
                         grid=f"m1 0.5..3 ({n1}) × l1 0.4..0.9 ({n2})"))
        log(f"batch spatial double pendulum: {n1 * n2} points {statistics.median(times):.2f} s "
            f"({rows[-1]['per_point'] * 1e3:.3f} ms a point; EXUDYN's eigen call "
            f"{'not installed' if floor is None else f'{floor * 1e3:.3f} ms'})")
        # the bicycle over its speed (a steady motion), boundaries located
        n_b = 40 if quick else 200
        bike = read_case(case_path("whipple_bicycle"))
        values = np.linspace(0.5, 10.0, n_b)

        def run_bike():
            return steady_sweep(bike, "v", values, jobs=1, progress=False)

        times, res = _timed(run_bike, repeats)
        nb = len(res.boundaries)
        rows.append(_row("bicycle over v", n_b, times, nb, GOALS["bicycle over v"],
                         grid=f"v 0.5..10, {n_b} points",
                         statics=["batch" if res.batch is None else
                                  f"one at a time ({res.batch})"]))
        log(f"batch bicycle over v: {n_b} points {statistics.median(times):.2f} s "
            f"({rows[-1]['rate']:.0f} points/s; goal 2000), {nb} boundaries")
    load1 = load_average()
    for r in rows:
        r["load"] = {"start": load0, "end": load1}
    return rows
