"""Benchmark: a chain of N spatial rigid bodies joined by bushings (a rigid-segment model of a
clamped-clamped 2 m shaft), through the whole pipeline.

Each body (12 natural coordinates, 6 rigid-body conditions) is joined to the next by a 6×6
bushing; the ends are bushed to the ground.  Measured (wall time, one BLAS thread): reading and
assembling the case (``repeat`` tables, N bodies and N + 1 bushings), the first evaluation of
Φ, Φ_q, g and K, C (against a floor: tomllib alone, and M and Φ_q formed as CSR from their own
triplets), the equilibrium (sparse:
multipliers by LU of Φ_qΦ_qᵀ), the linearization (M, P, Q sparse in full coordinates, Φ_q kept
for the bordered pencil) and the lowest 20 modes by the partial path (shift-invert on one sparse
LU of the bordered pencil).  Accuracy: at a small N the partial path is compared with the dense
path on the same model (relative difference of the 20 lowest |s|).

    python benchmarks/spatial_chain.py [--n 10000] [--check-n 200]

The case and its reading are those of ``mbseig bench``'s spatial section
(:mod:`mbseig.bench.spatial_rows`).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

import mbseig
from mbseig.bench.spatial_rows import build_chain


def run(n, directory, n_modes=20, dense=False):
    model, times = build_chain(n, directory)
    t = time.perf_counter()
    eq = mbseig.equilibrium(model)
    times["equilibrium"] = time.perf_counter() - t
    t = time.perf_counter()
    lin = mbseig.linearize(model, eq, sparse=not dense)
    times["linearize"] = time.perf_counter() - t
    t = time.perf_counter()
    md = mbseig.modes(lin) if dense else mbseig.modes(lin, n_modes=n_modes)
    times["modes"] = time.perf_counter() - t
    return model, md, times


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10_000)
    ap.add_argument("--check-n", type=int, default=200)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as d:
        _, md_s, _ = run(args.check_n, d)
        _, md_d, _ = run(args.check_n, d, dense=True)
        a, b = np.sort(np.abs(md_s.eigenvalues))[:20], np.sort(np.abs(md_d.eigenvalues))[:20]
        print(f"accuracy at N = {args.check_n}: partial vs dense path, lowest 20 |s|: "
              f"max relative difference {np.max(np.abs(a - b) / b):.2e}")
        model, md, times = run(args.n, d)
    print(f"chain of {args.n} spatial bodies: {model.n} coordinates, {model.n_constraints} "
          f"constraints, {len(model.forces)} bushings")
    for k, v in times.items():
        print(f"  {k:<22} {v:8.2f} s")
    build = times["read + assemble"] + times["first Φ, Φ_q, g, K, C"]
    print(f"  read + first assembly {build:.2f} s = {build / times['floor']:.0f} x the floor")
    print(f"  solver {md.solver}; lowest frequencies [Hz]: "
          + ", ".join(f"{f:.4g}" for f in md.freq_hz[:6]) + ", ...")
    print(f"  largest backward error {md.backward_error.max():.1e}; verdict {md.verdict}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
