"""Continuation against cold starts: Newton iterations and time per sweep point (issue 10).

Two sweeps, each solved twice:

- **cold**: every point on its own from the case's positions (``solve_statics``: position solve,
  trust-region Newton, load continuation when needed), as a sweep did before continuation;
- **continuation**: the branch followed through the grid (``mbseig.statics.continuation.follow``:
  tangent predictor from the previous equilibrium, pseudo-arclength correctors; the Newton
  iterations are those of all its correctors, divided by the number of grid points).

Models:

- the finger device, C4, follower force f = 0 … 2.4 N (25 points; the actuator's held command is
  resolved once, outside the timings, for both);
- a 10⁴-coordinate model: a taut cable of 5000 point masses on 5001 stiff springs between two
  supports (10 000 coordinates; the springs are one vectorized batch), started on a circular arc
  with the springs 0.1 % longer than their free length (1 N of pretension), under gravity and a
  horizontal load w per unit mass swept 0 … 5 m/s² (11 points).  Its family changes the constant load vector of one built model (the
  reader is not what is measured).  (A chain of rods instead of springs is limited by the
  assembly of 5000 separate constraint elements, ≈ 0.1–0.5 s per Jacobian, not by the solver.)

Times are wall-clock medians of ``--repeats`` interleaved runs with BLAS capped to one thread;
iterations are deterministic.  The machine is shared and noisy: compare the ratios measured in
the same run.  Usage: ``python benchmarks/continuation_bench.py [--repeats 3] [--quick]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import mbseig
from mbseig.statics import resolve
from mbseig.statics.continuation import Family, follow
from mbseig.statics.inverse import reuse_commands
from mbseig.statics.linalg import blas_threads
from mbseig.statics.solve import solve_statics

ROOT = Path(__file__).resolve().parent.parent


def device_family():
    spec = mbseig.read_case(ROOT / "cases" / "hand_device.toml")
    resolved = resolve(spec.build("C4", f=0.0))

    def make(f):
        return reuse_commands(spec.build("C4", f=float(f)), resolved)

    return make


def chain_case(n=5000, span=3.5, length=5.0, stiffness=1e6, pretension=1e-3):
    """A case file text: n masses on n + 1 equal springs on the circular arc through both
    supports, each ``pretension`` (relative) longer than its free length, gravity, a horizontal
    load w·m."""
    a = length / (n + 1)
    # half-angle θ of the arc: R = a / (2 sin(θ/(n+1))), span = 2 R sin θ
    from scipy.optimize import brentq

    theta = brentq(lambda t: a * math.sin(t) / math.sin(t / (n + 1)) - span, 1e-6, math.pi - 1e-9)
    R = a / (2 * math.sin(theta / (n + 1)))
    cy = R * math.cos(theta)  # the centre above the supports' line
    pts = []
    for i in range(1, n + 1):
        ang = -theta + 2 * theta * i / (n + 1)
        pts.append((span / 2 + R * math.sin(ang), cy - R * math.cos(ang)))
    lines = ['schema_version = 1', 'title = "catenary of point masses on rods"', "dimension = 2",
             'gravity = [0.0, -9.81]', "[parameters]", "w = 0.0",
             '[[points]]\nname = "A"\nposition = [0.0, 0.0]\nfixed = true',
             f'[[points]]\nname = "B"\nposition = [{span!r}, 0.0]\nfixed = true']
    for i, (x, y) in enumerate(pts, 1):
        lines.append(f'[[points]]\nname = "m{i}"\nposition = [{x!r}, {y!r}]')
    lines.append(f'[[masses]]\nrepeat = {{ i = [1, {n}] }}\npoint = "m{{i}}"\nmass = 0.001')
    spring = (f'type = "spring"\nstiffness = {stiffness!r}\n'
              f'free_length = {a * (1 - pretension)!r}')
    lines.append(f'[[forces]]\n{spring}\npoints = ["A", "m1"]')
    lines.append(f'[[forces]]\n{spring}\nrepeat = {{ i = [1, {n - 1}] }}\n'
                 f'points = ["m{{i}}", "m{{i + 1}}"]')
    lines.append(f'[[forces]]\n{spring}\npoints = ["m{n}", "B"]')
    return "\n".join(lines) + "\n"


def chain_family(n):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "chain.toml"
        path.write_text(chain_case(n))
        model = mbseig.load_case(path)
    wind = np.zeros(model.n)
    wind[0::2] = 0.001  # m per mass along x: the load w·m
    g0 = model.g_const.copy()

    def make(w):
        return dataclasses.replace(model, g_const=g0 + float(w) * wind)

    return make


def cold(make, values):
    iters, t0 = 0, time.perf_counter()
    for v in values:
        m = make(v)
        eq = solve_statics(m, q_init=m.q_init)
        iters += eq.iterations + eq.path.get("position_iterations", 0)
        if eq.path.get("total_iterations"):
            iters += eq.path["total_iterations"] - eq.iterations
    return iters / len(values), (time.perf_counter() - t0) / len(values)


def continued(make, values):
    t0 = time.perf_counter()
    m0 = make(values[0])
    eq0 = solve_statics(m0, q_init=m0.q_init)
    fam = Family(make, abs(values[-1] - values[0]), m0, eq0.q)
    br = follow(fam, values, fam.start(eq0.q, values[0]))
    elapsed = time.perf_counter() - t0
    assert all(g is not None for g in br.grid), "a grid point was not reached"
    iters = eq0.iterations + sum(p.iterations for p in br.points)
    return iters / len(values), elapsed / len(values)


def measure(name, make, values, repeats):
    rows = {"cold": [], "continuation": []}
    its = {}
    for _ in range(repeats):  # interleaved, so that both see the same machine
        for label, fn in (("cold", cold), ("continuation", continued)):
            it, dt = fn(make, values)
            rows[label].append(dt)
            its[label] = it
    med = {k: statistics.median(v) for k, v in rows.items()}
    print(f"\n{name}: {len(values)} points, {repeats} runs (medians)")
    print(f"{'':14}{'Newton its/point':>18}{'time/point [s]':>16}")
    for k in ("cold", "continuation"):
        print(f"{k:14}{its[k]:>18.2f}{med[k]:>16.4f}")
    print(f"{'ratio cold/cont.':14}{its['cold'] / its['continuation']:>18.2f}"
          f"{med['cold'] / med['continuation']:>16.2f}")
    return {"iterations": its, "time": med}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="a 2000-coordinate cable, 1 run")
    args = ap.parse_args(argv)
    repeats = 1 if args.quick else args.repeats
    with blas_threads(1):
        measure("finger device C4, f = 0 … 2.4 N", device_family(), np.linspace(0.0, 2.4, 25),
                repeats)
        n = 1000 if args.quick else 5000
        measure(f"cable of {n} masses on springs ({2 * n} coordinates), w = 0 … 5 m/s²",
                chain_family(n), np.linspace(0.0, 5.0, 11), repeats)


if __name__ == "__main__":
    main()
