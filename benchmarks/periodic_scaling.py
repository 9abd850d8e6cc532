"""Benchmark: how the cost of Floquet analysis grows with the model, full monodromy against the
partial (Arnoldi) method, on a chain of N pendulums whose pivots are shaken vertically.

The chain (cases/pendulum_chain_shaken.toml with n = N): N pendulums (point mass m on a rigid rod
l, distance constraints), side by side at spacing a, each pivot moved as y = A cos(w t) (the rod's
constraint is rheonomic), neighbours coupled by weak springs kc between the masses. 2N coordinates
(the masses; the reader keeps these repeated pivots out of the coordinates), N constraints, N
degrees of freedom, 2N multipliers. The hanging chain is an exact periodic motion (shooting
converges at once), so the timings are those of the linearization along it and of the monodromy.
Linearized, the chain's modes decouple into Mathieu equations θ'' + (g/l + (kc/m) λ_j − (A w²/l)
cos wt) θ = 0, λ_j = 2 − 2 cos(jπ/N) (free ends): mode 0 (λ = 0) is the single pendulum, and w =
6.3 puts it in the principal tongue (cases/pendulum_shaken_pivot.toml), so the dominant multiplier
is that of the single pendulum, μ = −1.36824 (checked against the full method at every N). With kc
= 0.05 every mode j stays in the tongue (g/l + 4 kc/m < (w/2)² a₁(0.2)), so all N modes grow (at N
= 6 within 0.2 % of it): the dominant multiplier is the top of a cluster.

Measured for each N (wall time and the process's CPU time, one BLAS thread, median of --repeat
cold runs): the linearization (timed model, reference motion, sampled linearization), the full
monodromy on that linearization (two estimates, every multiplier, ``periodic_analysis``), and
the K largest multipliers by the partial method (``periodic_partial``, two estimates).  On a
shared machine the CPU time is the steadier figure.  Growth exponents are fitted on log(time)
against log(N).

The detuned chain (``--chain detuned``: l2 = 0.5, pendulums 2 to N out of the tongue, stable
on their own) keeps pendulum 1 alone in resonance: its multiplier (−1.36811) stands apart from
the rest, on the unit circle, and ARPACK converges in about one basis at every N.  Its
reference is the full method (no closed form: the modes do not decouple); the single
pendulum's multiplier printed beside it differs by the coupling (≈ 1.3e-4).

    python benchmarks/periodic_scaling.py [--sizes 15 50 100 150] [--partial-max N] [--k 1]
        [--repeat 5] [--chain uniform|detuned]

docs/periodic.md, "Floquet at scale", has the runs of
``--sizes 15 25 50 100 150 500 --k 1`` on both chains.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
#: the bundled chain (n = 6 there), its size replaced per run
CASE = (ROOT / "cases" / "pendulum_chain_shaken.toml").read_text()
assert "\nn = 6 " in CASE and "\nl2 = 1.0 " in CASE
#: the chains: uniform (l2 = l, every mode in the tongue, the growing multipliers clustered) and
#: detuned (l2 = 0.5: pendulums 2 to n out of the tongue, pendulum 1's multiplier apart)
CHAINS = {"uniform": "1.0", "detuned": "0.5"}


def single_pendulum_multiplier(g=9.81, l=1.0, A=0.1, w=6.3):
    """Dominant multiplier of θ'' + (g/l − (A w²/l) cos wt) θ = 0 (the chain's mode 0), by its
    own integration (scipy solve_ivp, DOP853, rtol 1e-12): the reference of every N."""
    from scipy.integrate import solve_ivp

    def f(t, x):
        k = g / l - A * w * w / l * np.cos(w * t)
        X = x.reshape(2, 2)
        return np.array([X[1], -k * X[0]]).ravel()
    sol = solve_ivp(f, (0.0, 2 * np.pi / w), np.eye(2).ravel(), method="DOP853", rtol=1e-12,
                    atol=1e-14)
    mu = np.linalg.eigvals(sol.y[:, -1].reshape(2, 2))
    return mu[np.argmax(np.abs(mu))]


def cold_runs(spec, repeat, k=None):
    """Median wall times of cold runs (nothing kept between runs): the linearization, then the
    full monodromy on that linearization (two estimates, bounds, verdict), then, with ``k``,
    the partial method on it; the last run's results."""
    from mbseig.studies.periodic import (
        forget_kept,
        periodic_analysis,
        periodic_linearization,
    )
    from mbseig.studies.periodic_partial import periodic_partial

    times = {key: [] for key in ("linearization", "full", "partial", "linearization_cpu",
                                 "full_cpu")}
    out = None
    for _ in range(repeat):
        forget_kept()
        t0, c0 = time.perf_counter(), time.process_time()
        lin = periodic_linearization(spec)
        t1, c1 = time.perf_counter(), time.process_time()
        a = periodic_analysis(spec)  # reuses the linearization just made
        t2, c2 = time.perf_counter(), time.process_time()
        times["linearization"].append(t1 - t0)
        times["full"].append(t2 - t1)
        times["linearization_cpu"].append(c1 - c0)
        times["full_cpu"].append(c2 - c1)
        p = None
        if k:
            p = periodic_partial(spec, k=k)
            times["partial"].append(time.perf_counter() - t2)
        out = (lin, a, p)
    return {key: statistics.median(v) for key, v in times.items() if v}, out


def run(n, directory, *, k, partial, repeat, chain="uniform"):
    from mbseig.casefile import read_case

    path = Path(directory) / f"chain{n}_{chain}.toml"
    path.write_text(CASE.replace("\nn = 6 ", f"\nn = {n} ", 1)
                    .replace("\nl2 = 1.0 ", f"\nl2 = {CHAINS[chain]} ", 1))
    spec = read_case(path)
    row = {"n": n}
    medians, (lin, a, p) = cold_runs(spec, repeat, k if partial else None)
    row.update(medians)
    row["coordinates"], row["dof"] = lin.timed.base.n, lin.system.dof
    row["mu_full"] = complex(a.floquet.multipliers[0])
    row["bound_full"] = float(a.floquet.error_bounds[0])
    if p is not None:
        row["mu_partial"] = complex(p.multipliers[0])
        row["bound_partial"] = float(p.error_bounds[0])
        row["products"] = p.products
    return row


def fit(rows, key):
    pts = [(r["dof"], r[key]) for r in rows if key in r and r[key] > 0]
    if len(pts) < 2:
        return float("nan")
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[15, 50, 100, 150])
    ap.add_argument("--partial-max", type=int, default=10**6,
                    help="run the partial method up to this N (default: every size)")
    ap.add_argument("--k", type=int, default=1, help="multipliers of the partial method (K = 2 "
                    "asks into the cluster of the chain's growing multipliers: many more "
                    "products)")
    ap.add_argument("--repeat", type=int, default=1, help="runs per size (median)")
    ap.add_argument("--chain", choices=sorted(CHAINS), default="uniform",
                    help="uniform (clustered multipliers; the reference is the single pendulum's "
                         "multiplier) or detuned (l2 = 0.5; pendulum 1's multiplier apart, "
                         "checked against the full method only)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    rows = []
    ref = single_pendulum_multiplier()
    print(f"chain: {args.chain} (l2 = {CHAINS[args.chain]})")
    with tempfile.TemporaryDirectory() as d:
        for n in args.sizes:
            row = run(n, d, k=args.k, partial=n <= args.partial_max, repeat=args.repeat,
                      chain=args.chain)
            rows.append(row)
            line = (f"N = {n:4d}: {row['coordinates']:4d} coordinates, {row['dof']:4d} DOF; "
                    f"linearization {row['linearization']:7.2f} s "
                    f"({row['linearization_cpu']:.2f} s CPU), full monodromy "
                    f"{row['full']:8.2f} s ({row['full_cpu']:.2f} s CPU) (|mu| = "
                    f"{abs(row['mu_full']):.10f} "
                    f"± {row['bound_full']:.1e}, {abs(row['mu_full'] - ref):.1e} from the single "
                    "pendulum)")
            if "partial" in row:
                line += (f", partial (K = {args.k}) {row['partial']:8.2f} s, {row['products']} "
                         f"products, |mu| differs by {abs(row['mu_partial'] - row['mu_full']):.1e}"
                         f" (its bound {row['bound_partial']:.1e})"
                         f"; linearization + partial {row['linearization'] + row['partial']:.2f} s"
                         f", + full {row['linearization'] + row['full']:.2f} s")
            print(line, flush=True)
    print(f"growth with the DOF r (time ~ r^p): linearization p = {fit(rows, 'linearization'):.2f},"
          f" full monodromy p = {fit(rows, 'full'):.2f}, partial p = {fit(rows, 'partial'):.2f}; "
          f"CPU: linearization p = {fit(rows, 'linearization_cpu'):.2f}, full monodromy "
          f"p = {fit(rows, 'full_cpu'):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
