"""Wall time and agreement of `mbseig check` on the bundled 3-D beam cases at their own meshes.

Per case and mode: the median wall time of REPEAT runs of `mbseig.check_modes`, the force
evaluations, predicted and measured δ and ω, the verdict.  Not a test (the unit tests,
tests/test_check_beams3d.py, run small meshes); run by hand, one thread:

    OPENBLAS_NUM_THREADS=1 python benchmarks/check_beams3d.py [REPEAT]
    OPENBLAS_NUM_THREADS=1 python benchmarks/check_beams3d.py --rhs [REPEAT]

``--rhs``: the cost of one right-hand side of the check (tangent coordinates, fresh states) and
of its parts (lift: q and q̇ on the constraints; accel: the index-1 solve with force, velocity
terms, M(q), Φ_q and γ; and those beam parts alone), with the beams evaluated in batches
(mbseig.model.beam3d_batch) and element by element (``beam3d.BATCHED = False``, the reference
path), paired in one process: medians of REPEAT rounds (default 5) of 30 states each.
"""

import statistics
import sys
import time
from pathlib import Path

import numpy as np

from mbseig.check import check_modes
from mbseig.check.dynamics import ForwardDynamics
from mbseig.check.tangent import TangentCoordinates
from mbseig.model import beam3d
from mbseig.studies import analyze

ROOT = Path(__file__).resolve().parent.parent
# (case, checked modes): the lowest bending mode of each; the overhung rotor's first two modes
# are its free axial translation and spin (rigid-body: probed statically, not fitted)
CASES = [("cantilever_3d_oblique.toml", [1]), ("column_buckling_3d.toml", [1]),
         ("spinning_shaft_rayleigh.toml", [1]), ("overhung_rotor_friswell.toml", [1, 2, 3])]


def main(repeat=1):
    print(f"{'case':<30} {'mode':>4} {'time [s]':>9} {'nfev':>6} {'delta pred':>11} "
          f"{'delta meas':>11} {'omega pred':>12} {'omega rel err':>13}  result")
    for name, indices in CASES:
        path = ROOT / "cases" / name
        if not path.exists():
            continue
        a = analyze(path)
        times, res = [], None
        for _ in range(repeat):
            t = time.perf_counter()
            res = check_modes(a.model, a.eq, a.linear, a.modes, indices=indices)
            times.append(time.perf_counter() - t)
        for m in res.modes:
            if m.skipped:
                print(f"{name:<30} {m.index:>4} {'':>9} {'':>6} {'':>11} {'':>11} "
                      f"{m.predicted_omega:>12.6g} {'':>13}  "
                      f"{'pass' if m.passed else 'FAIL'} ({m.skipped})")
                continue
            err = abs(m.measured_omega / m.predicted_omega - 1)
            print(f"{name:<30} {m.index:>4} {statistics.median(times):>9.1f} {m.nfev:>6} "
                  f"{m.predicted_delta:>11.3g} {m.measured_delta:>11.3g} "
                  f"{m.predicted_omega:>12.6g} {err:>13.2e}  {'pass' if m.passed else 'FAIL'}")


def _parts(path, calls):
    """{part: run()} of one case: the check's right-hand side and its beam parts at ``calls``
    fresh states near the equilibrium."""
    a = analyze(path)
    m, q0 = a.model, a.eq.q
    dyn = ForwardDynamics(m, q0)
    tc = TangentCoordinates(dyn)
    k = tc.k
    rng = np.random.default_rng(1)
    ys = [np.concatenate([1e-4 * m.length_scale * rng.standard_normal(k) / np.sqrt(k),
                          1e-2 * rng.standard_normal(k) / np.sqrt(k)]) for _ in range(calls)]
    states = [(q0 + u, v) for u, v, _, _ in (tc.lift(y[:k], y[k:]) for y in ys)]
    return {"rhs": lambda: [tc.rhs(0.0, y) for y in ys],
            "lift": lambda: [tc.lift(y[:k], y[k:]) for y in ys],
            "accel": lambda: [dyn.acceleration(q, v) for q, v in states],
            "force": lambda: [m.generalized_force(q, v) for q, v in states],
            "h": lambda: [dyn.velocity_terms(q, v) for q, v in states],
            "mass": lambda: [m.mass_matrix(q) for q, _ in states],
            "phi_q": lambda: [m.phi_q(q) for q, _ in states]}


def rhs_costs(repeat=5, calls=30):
    """Per-evaluation milliseconds, batched against element by element (module docstring)."""
    print(f"{'case':<30} {'part':<6} {'element [ms]':>13} {'batched [ms]':>13} {'ratio':>6}")
    for name, _ in CASES:
        path = ROOT / "cases" / name
        if not path.exists():
            continue
        parts = _parts(path, calls)
        times = {}
        for _ in range(repeat):
            for batched in (False, True):
                beam3d.BATCHED = batched
                for part, run in parts.items():
                    t = time.perf_counter()
                    run()
                    times.setdefault((part, batched), []).append(
                        (time.perf_counter() - t) / calls * 1e3)
        beam3d.BATCHED = True
        for part in parts:
            ref, new = (statistics.median(times[(part, b)]) for b in (False, True))
            print(f"{name:<30} {part:<6} {ref:>13.3f} {new:>13.3f} {ref / new:>6.1f}")


if __name__ == "__main__":
    if "--rhs" in sys.argv:
        args = [x for x in sys.argv[1:] if x != "--rhs"]
        rhs_costs(int(args[0]) if args else 5)
    else:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
