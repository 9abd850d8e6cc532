"""Benchmark: a large 3-D beam model through the whole pipeline, lowest 20 modes by the partial
path, and the meshes the closed forms need for 1e-8 (docs/beams3d.md, "Convergence").

    python benchmarks/beam3d_large.py                   # 50 × 334 elements: 100 200 DOF
    python benchmarks/beam3d_large.py --beams 5 --elements 400 --runs 3
    python benchmarks/beam3d_large.py --convergence     # error against the closed forms per mesh

The model (:mod:`mbseig.bench.beam_rows`, which ``mbseig bench`` runs at the default size):
``--beams`` (50) copies of the bar of cases/cantilever_3d_oblique.toml (rectangle 20 × 30 mm
along the oblique axis (1, 2, 2)/3, clamped at one end) of lengths 1, 1.1, 1.2, … m, each with
``--elements`` (334) elements; 6 DOF per node, every node a frame of 12 coordinates with 6 triad
conditions, so DOF = 6 × beams × elements.  Times
are wall seconds of load_case, equilibrium, linearize (sparse above 5000 coordinates: the
constraints stay in the bordered pencil) and modes(n_modes=20); each figure is the median of
``--runs`` runs, BLAS on one thread; the machine's load average is printed beside them.  The
20 frequencies are compared with the closed forms (Blevins table 8-1, both bending planes of
every bar); at this mesh the remaining error is the eigenvalue's conditioning, not the mesh.
Five bars of 3 334 elements each would also be 10⁵ DOF, but past about 1 500 elements a bar the
lowest bending eigenvalue is not separated from zero in double precision (docs/beams3d.md).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

import mbseig
from mbseig.bench.beam_rows import BETA_L, run_comb, timed_pipeline
from mbseig.numerics import blas_limit

CASE = Path(__file__).resolve().parent.parent / "cases" / "cantilever_3d_oblique.toml"
BL = BETA_L[:2]


def closed_forms(p):
    E, rho, A, L = p["E"], p["rho"], p["A"], p["L"]
    return np.sort([b**2 * np.sqrt(E * inertia / (rho * A * L**4))
                    for b in BL for inertia in (p["Iy"], p["Iz"])])


def run_once(n, n_modes=20):
    m, md, times = timed_pipeline(CASE, n_modes, n=n)
    dof = m.n - m.n_constraints
    w = np.sort(md.omega_n)
    err = w[:4] / closed_forms(m.parameters) - 1
    return dof, times, err, md.solver


def bench(beams, n, runs):
    import tempfile

    rows = []
    with blas_limit(1), tempfile.TemporaryDirectory() as tmp:
        for k in range(runs):
            rows.append(run_comb(beams, n, Path(tmp) / "comb.toml", log=print))
            print(f"  run {k + 1}: " + ", ".join(f"{a} {b:.2f}" for a, b in rows[-1][1].items())
                  + f" (load {os.getloadavg()[0]:.1f})", flush=True)
    dof, _, err, solver = rows[-1]
    med = {k: statistics.median(r[1][k] for r in rows) for k in rows[0][1]}
    total = statistics.median(sum(r[1].values()) for r in rows)
    print(f"{beams} beams x {n} elements, {dof} DOF, path {solver}, {runs} run(s), load "
          f"average {os.getloadavg()[0]:.1f}")
    print("  median wall s: " + ", ".join(f"{k} {v:.2f}" for k, v in med.items())
          + f", total {total:.2f}")
    print(f"  20 modes vs closed forms: largest |error| {np.max(np.abs(err)):.1e} "
          f"(lowest {err[0]:+.1e})")


def convergence(meshes):
    """Relative errors of the first two bending modes of each plane per mesh (order 4)."""
    with blas_limit(1):
        for n in meshes:
            _, times, err, _ = run_once(n, n_modes=8)
            print(f"{n:6d} elements: " + ", ".join(f"{e:+.2e}" for e in err)
                  + f"  ({sum(times.values()):.1f} s)")


def timoshenko_shaft(n):
    """Relative errors of the spinning Timoshenko shaft's first two whirl pairs at n elements
    (cases/spinning_shaft_rayleigh.toml with Cowper's κ; the characteristic equation of
    tests/test_beams3d_convergence.py): the direct mesh for 1e-8 (order 2)."""
    import tempfile

    text = (CASE.parent / "spinning_shaft_rayleigh.toml").read_text().replace(
        "shear_coefficient = 1e12\n", "")
    with blas_limit(1), tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "shaft.toml"
        path.write_text(text)
        t = time.perf_counter()
        m = mbseig.load_case(path, n=n)
        md = mbseig.modes(mbseig.linearize(m, mbseig.equilibrium(m), sparse=True), n_modes=4)
        sec = time.perf_counter() - t
    p = m.parameters
    A, I = np.pi * (p["d"] ** 2 - p["di"] ** 2) / 4, np.pi * (p["d"] ** 4 - p["di"] ** 4) / 64
    nu, r2 = p["E"] / (2 * p["G"]) - 1, (p["di"] / p["d"]) ** 2
    kap = 6 * (1 + nu) * (1 + r2) ** 2 / ((7 + 6 * nu) * (1 + r2) ** 2 + (20 + 12 * nu) * r2)
    ref = []
    for j in (1, 2):
        k, s = j * np.pi / p["L"], kap * p["G"] * A
        poly = np.polymul([-p["rho"] * A, 0, s * k * k],
                          [-p["rho"] * I, 2 * p["rho"] * I * p["Omega"], p["E"] * I * k * k + s])
        poly[-1] -= (s * k) ** 2
        r = np.roots(poly).real
        ref += [-max(x for x in r if x < 0), min(x for x in r if x > 0)]
    err = np.sort(md.omega_n)[:4] / np.array(ref) - 1
    print(f"Timoshenko shaft, {n} elements: " + ", ".join(f"{e:+.2e}" for e in err)
          + f"  ({sec:.1f} s)")


def axial_direct(n):
    """The cantilever's first torsion and axial modes at n elements against the closed forms
    (linear elements: error (kh)²/24, 1e-8 at 3206 elements)."""
    with blas_limit(1):
        t = time.perf_counter()
        m = mbseig.load_case(CASE, n=n)
        lin = mbseig.linearize(m, mbseig.equilibrium(m), sparse=True)
        p = m.parameters
        props = next(f for f in m.forces if hasattr(f, "props")).props
        k = np.pi / (2 * p["L"])
        refs = (k * np.sqrt(props.G * props.J / (p["rho"] * props.polar)),
                k * np.sqrt(p["E"] / p["rho"]))
        errs = [mbseig.modes(lin, n_modes=2, target=r).omega_n for r in refs]
        sec = time.perf_counter() - t
    out = [np.min(np.abs(w - r)) / r for w, r in zip(errs, refs)]
    print(f"cantilever torsion / axial, {n} elements: {out[0]:.2e} / {out[1]:.2e}  ({sec:.1f} s)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--beams", type=int, default=50)
    ap.add_argument("--elements", type=int, default=334)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--convergence", action="store_true")
    a = ap.parse_args(argv)
    if a.convergence:
        convergence([24, 48, 96, 128, 192])
        timoshenko_shaft(2448)
        axial_direct(3216)
    else:
        bench(a.beams, a.elements, a.runs)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
