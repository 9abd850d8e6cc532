"""Benchmark: the standard shaft element (``element = "ross"``) against the quartic one
(``element = "quartic"``) on the spinning simply supported Timoshenko shaft (docs/beams3d.md,
"The quartic shaft element").

    python benchmarks/shaft_element.py                  # both elements over their meshes
    python benchmarks/shaft_element.py --ross 24 96 384 --quartic 4 8 --runs 3

The shaft is cases/spinning_shaft_rayleigh.toml with shear (Cowper's κ for the tube, no
``shear_coefficient``), at Ω = 500 rad/s; the reference is the characteristic equation of the
pinned Timoshenko shaft per mode (Friswell et al. 2010 §5.4, tests/test_beams3d_convergence.py).
For each mesh: elements, nodes, degrees of freedom (coordinates less constraints), the largest
relative error of the lowest four lateral modes (backward and forward whirl of n = 1, 2) and the
wall time of load_case + equilibrium + linearize (sparse) + modes(n_modes=4), median of
``--runs`` runs (meshes above 1,000 elements: one run), BLAS on one thread.  The last lines give
the smallest mesh of each element that meets 1e-8 and the ratio of their degrees of freedom.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from test_beams3d_convergence import _shaft_roots  # noqa: E402 (the closed form, shared)

from mbseig import equilibrium, linearize, load_case, modes  # noqa: E402
from mbseig.numerics import blas_limit  # noqa: E402

SHAFT = (ROOT / "cases" / "spinning_shaft_rayleigh.toml").read_text().replace(
    "shear_coefficient = 1e12\n", "")
GOAL = 1e-8


def _kappa(p):
    nu = p["E"] / (2 * p["G"]) - 1
    r2 = (p["di"] / p["d"]) ** 2  # Cowper 1966, table 1 (tube)
    return 6 * (1 + nu) * (1 + r2) ** 2 / ((7 + 6 * nu) * (1 + r2) ** 2 + (20 + 12 * nu) * r2)


def run(path, n):
    t0 = time.perf_counter()
    m = load_case(path, n=n)
    eq = equilibrium(m)
    md = modes(linearize(m, eq, sparse=True), n_modes=4)
    elapsed = time.perf_counter() - t0
    w = np.sort(md.omega_n)[:4]
    p = m.parameters
    ref = [r for k in (1, 2) for r in _shaft_roots(p, k, _kappa(p))]
    err = np.abs(w / np.array(ref) - 1)
    nodes = len(m.flexible["bodies"]["shaft"]["nodes"])
    return nodes, m.n - m.n_constraints, err, elapsed


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ross", type=int, nargs="*",
                    default=[24, 48, 96, 192, 384, 768, 1536, 2448])
    ap.add_argument("--quartic", type=int, nargs="*", default=[2, 4, 6, 8, 10, 12, 16])
    ap.add_argument("--runs", type=int, default=3)
    a = ap.parse_args()
    print(f"# spinning Timoshenko shaft, lowest four whirl modes; load average "
          f"{os.getloadavg()[0]:.2f}; BLAS one thread")
    print(f"{'element':>8} {'elements':>8} {'nodes':>6} {'DOF':>7} {'max error':>10} "
          f"{'errors (B1, F1, B2, F2)':>40} {'time s':>8}")
    best = {}
    with blas_limit(1), tempfile.TemporaryDirectory() as tmp:
        for element, meshes in (("ross", a.ross), ("quartic", a.quartic)):
            path = Path(tmp) / f"{element}.toml"
            path.write_text(SHAFT.replace('elements = "n"',
                                          f'elements = "n"\nelement = "{element}"'))
            for n in meshes:
                times = []
                for _ in range(1 if n > 1000 else a.runs):
                    nodes, dof, err, t = run(path, n)
                    times.append(t)
                worst = float(err.max())
                errs = " ".join(f"{e:.2e}" for e in err)
                print(f"{element:>8} {n:>8} {nodes:>6} {dof:>7} {worst:>10.2e} {errs:>40} "
                      f"{statistics.median(times):>8.2f}", flush=True)
                if worst <= GOAL and element not in best:
                    best[element] = (n, nodes, dof)
    for element, (n, nodes, dof) in best.items():
        print(f"# {element}: 1e-8 first met at {n} elements, {nodes} nodes, {dof} DOF")
    if len(best) == 2:
        print(f"# DOF ratio quartic / ross: {best['quartic'][2] / best['ross'][2]:.4f} "
              f"(goal <= 0.25)")


if __name__ == "__main__":
    main()
