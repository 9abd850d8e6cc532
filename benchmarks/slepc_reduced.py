"""Benchmark: mbseig's lowest 20 modes of a large damped constrained model against SLEPc's PEP
solve of the same model's reduced problem, time and peak memory, each in a fresh process.

The kinds and the model are those of ``mbseig bench``'s slepc section
(:mod:`mbseig.bench.slepc_rows`, which also runs the chain without its links); this script runs
any of them at any size.  Model: the bench's large chain (:func:`mbseig.bench.sparse_rows.large_chain`: n masses
m_i = 1 + 0.5 sin i, springs k = 1000, every 10th spring a rigid link, grounded dashpots on every
7th mass plus βK: non-proportional damping).  Its constraints x_{a+1} = x_a have a sparse null
basis N (one coordinate of each link eliminated), so the reduced problem
(NᵀMN s² + NᵀPN s + NᵀQN) y = 0 is a sparse PEP without constraints: what SLEPc is given here.

- ``slepc``: SLEPc's PEP (TOAR, shift-and-invert at 0, PETSc's own LU, ``preonly``) on the reduced
  matrices, asked for the same eigenvalues mbseig returns for 20 modes: 41 nearest 0 (20
  conjugate pairs and a margin), tolerance 1e-14 (the backward error mbseig reaches); the
  worker of ``partial-slepc`` (:mod:`mbseig.eigen.slepc_worker`) runs it and reports its own
  peak memory; its time is the worker's own (assembling the matrices and PEPSolve), without the
  worker's start and the file transfer.
- ``mbseig``: ``mbseig.eigen.solve(Problem(M, P, Q, G=G), Request("auto", n_modes=20))`` on the
  constrained model (the path ``auto`` picks, with every check it makes).
- ``slepc20``: for reference, SLEPc asked for 20 eigenvalues (10 modes) at its default-like
  tolerance 1e-8: a figure sometimes quoted for "SLEPc on this problem" that is not the same work.
- ``pslepc`` and ``bslepc``: mbseig's ``partial-slepc`` path (with its checks) against a direct
  SLEPc solve of the very matrices that path gives SLEPc (the bordered pencil, UMFPACK LU, 41
  eigenvalues at 1e-14, the worker's own time): the cost of mbseig around SLEPc.

    python benchmarks/slepc_reduced.py [--sizes 10000 100000 1000000] [--repeats 3]

Prints one JSON line per run and a table of medians (time, peak RSS, ratio mbseig / slepc).
Needs slepc4py (docs/scaling.md); one BLAS thread.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from mbseig.bench.slepc_rows import slepc_worker  # noqa: E402


def worker(kind, n):
    slepc_worker(kind, n, constrained=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--kinds", nargs="+", default=["slepc", "mbseig", "slepc20"],
                    choices=["slepc", "mbseig", "slepc20", "pslepc", "bslepc"])
    ap.add_argument("--worker", nargs=2, metavar=("KIND", "N"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        return worker(a.worker[0], int(a.worker[1]))
    rows = {}
    for n in a.sizes:
        for _ in range(a.repeats):
            for kind in a.kinds:  # interleaved, so that the machine's load falls on every kind
                p = subprocess.run([sys.executable, __file__, "--worker", kind, str(n)],
                                   capture_output=True, text=True, check=True)
                r = json.loads(p.stdout.strip().splitlines()[-1])
                print(json.dumps(r), flush=True)
                rows.setdefault((n, kind), []).append(r)
    print(f"\n{'n':>9} {'kind':>8} {'median s':>9} {'spread s':>15} {'peak MB':>8} {'/ ref':>8} "
          f"{'mem / ref':>11}   (ref: slepc, or bslepc for pslepc)")
    for n in a.sizes:
        for kind in a.kinds:
            ref = rows.get((n, "bslepc" if kind == "pslepc" else "slepc"))
            rs = rows[(n, kind)]
            t = statistics.median(r["seconds"] for r in rs)
            m = statistics.median(r["rss_mb"] for r in rs)
            lo, hi = min(r["seconds"] for r in rs), max(r["seconds"] for r in rs)
            ratio = mem = ""
            if ref:
                ratio = f"{t / statistics.median(r['seconds'] for r in ref):.2f}x"
                mem = f"{m / statistics.median(r['rss_mb'] for r in ref):.2f}x"
            print(f"{n:>9} {kind:>8} {t:>9.2f} {lo:>7.2f}–{hi:<7.2f} {m:>8.0f} {ratio:>8} {mem:>11}")


if __name__ == "__main__":
    main()
