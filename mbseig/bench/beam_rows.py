"""Rows of the ``mbseig bench`` report for a large 3-D beam model: a comb of ``beams`` oblique
cantilevers, 10⁵ degrees of freedom at the default size, through the whole pipeline (read and
build, equilibrium, sparse linearization, lowest 20 modes by the partial path), timed, and its
20 frequencies against the closed forms.

The model: ``beams`` copies of the bar of cases/cantilever_3d_oblique.toml (steel, rectangle
20 × 30 mm, axis (1, 2, 2)/3, orientation (0, 1, −1), Euler–Bernoulli, clamped at one end) of
lengths 1 + 0.1 k m, side by side, each of ``elements`` elements; 6 DOF per node (a node is a
frame of 12 coordinates with 6 triad conditions), so DOF = 6 × beams × elements.  Reference:
the cantilever's closed form ω = (β L)² √(EI / ρA) / L² (Blevins, Formulas for Natural Frequency
and Mode Shape, table 8-1: βL = 1.8751, 4.6941, 7.8548, 10.9955), in both bending planes of
every bar, sorted.

Why a comb of many bars rather than five bars of 3 334 elements each: the lowest eigenvalues of
an Euler–Bernoulli mesh are conditioned by (elements a bar)⁴ (cond(Q) ≈ 6e11 at 300 elements,
4.5e14 at 1 500, ≈ 1e16 at 3 334), so past about 1 500 elements a bar the lowest bending mode is
not separated from zero in double precision in any coordinates: docs/beams3d.md, "Large
models".  At 334 elements a bar the mesh error is below 1e-12 and the measured error is that
conditioning (the same bar alone by the dense eigensolver: 2.4e-6; by the partial path: 7e-8).
ROSS builds rotors along one axis (shaft elements, disks, bearings); this comb is not a rotor,
so it has no ROSS row.

Row keys: ``section`` "beams", ``method``, ``n`` (DOF), ``beams``, ``elements``, ``time``
(median wall seconds of the whole pipeline over ``repeats`` runs), ``stages`` (median seconds
per stage), ``error`` (largest relative error of the 20 frequencies), ``solver``, ``repeats``,
``load`` (1-minute load average at the start).
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

__all__ = ["bench_beams", "comb_case", "run_comb", "timed_pipeline"]

#: βL of a clamped-free Euler–Bernoulli beam, first four modes (Blevins table 8-1)
BETA_L = (1.8751040687119611, 4.694091132974175, 7.854757438237613, 10.995540734875467)


def comb_case(beams, n, path):
    """Write the comb of ``beams`` oblique cantilevers of ``n`` elements each (module
    docstring) to ``path``; return the closed-form bending frequencies [rad/s], sorted."""
    text = ["schema_version = 1", "dimension = 3", "[parameters]", "E = 2.1e11", "nu = 0.3",
            "rho = 7850.0", "b = 0.02", "h = 0.03", f"n = {n}"]
    u = np.array([1.0, 2.0, 2.0]) / 3
    for k in range(beams):
        L = 1 + 0.1 * k
        root = np.array([0.0, 0.1 * k, 0.0])
        tip = root + L * u
        text += ["[[points]]", f'name = "A{k}"', f"position = {root.tolist()}", "fixed = true",
                 "[[points]]", f'name = "B{k}"', f"position = {tip.tolist()}",
                 "[[beams]]", f'name = "bar{k}"', f'points = ["A{k}", "B{k}"]', 'E = "E"',
                 'nu = "nu"', 'rho = "rho"', 'section = { shape = "rectangle", b = "b", h = "h" }',
                 "orientation = [0.0, 1.0, -1.0]", 'theory = "euler-bernoulli"',
                 'elements = "n"', 'ends = ["clamped", "free"]']
    Path(path).write_text("\n".join(text) + "\n")
    E, rho, b, h = 2.1e11, 7850.0, 0.02, 0.03
    A = b * h
    w = [bl**2 * np.sqrt(E * inertia / (rho * A * (1 + 0.1 * k) ** 4)) for k in range(beams)
         for bl in BETA_L for inertia in (b * h**3 / 12, h * b**3 / 12)]
    return np.sort(w)


def timed_pipeline(path, n_modes=20, log=None, **params):
    """(model, modes, {stage: seconds}) of one run of read, equilibrium, linearize (sparse above
    5000 coordinates) and the lowest ``n_modes`` modes of the case at ``path``."""
    from ..casefile import load_case
    from ..linear import linearize
    from ..modal import modes
    from ..statics import equilibrium

    times, t = {}, time.perf_counter()
    m = load_case(path, **params)
    times["load"] = time.perf_counter() - t
    t = time.perf_counter()
    eq = equilibrium(m)
    times["equilibrium"] = time.perf_counter() - t
    t = time.perf_counter()
    lin = linearize(m, eq)
    times["linearize"] = time.perf_counter() - t
    t = time.perf_counter()
    md = modes(lin, n_modes=n_modes)
    times["modes"] = time.perf_counter() - t
    if log:
        log("    " + ", ".join(f"{k} {v:.2f} s" for k, v in times.items()))
    return m, md, times


def run_comb(beams, n, path, n_modes=20, log=None):
    """One run of the pipeline on the comb: (DOF, {stage: seconds}, relative errors of the lowest
    ``n_modes`` frequencies, solver path)."""
    ref = comb_case(beams, n, path)
    m, md, times = timed_pipeline(path, n_modes, log)
    w = np.sort(md.omega_n)
    return m.n - m.n_constraints, times, w[:n_modes] / ref[:n_modes] - 1, md.solver


def bench_beams(log=print, *, beams=50, elements=334, repeats=3, n_modes=20):
    """The beams section (module docstring): medians of ``repeats`` runs, BLAS as the caller set
    it (one thread in ``mbseig bench``)."""
    load = os.getloadavg()[0]
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):
            runs.append(run_comb(beams, elements, Path(tmp) / "comb.toml", n_modes, log))
    dof, _, err, solver = runs[-1]
    stages = {k: statistics.median(r[1][k] for r in runs) for k in runs[0][1]}
    total = statistics.median(sum(r[1].values()) for r in runs)
    worst = float(max(np.max(np.abs(r[2])) for r in runs))
    log(f"beams: {beams} x {elements} elements, {dof} DOF, {solver}: {total:.1f} s "
        f"(median of {repeats}, load {load:.1f}); {n_modes} modes vs closed forms <= {worst:.1e}")
    return [{"section": "beams", "method": f"comb of {beams} oblique cantilevers, lowest "
             f"{n_modes} modes", "n": int(dof), "beams": beams, "elements": elements,
             "time": total, "stages": stages, "error": worst, "solver": solver,
             "repeats": repeats, "load": load}]
