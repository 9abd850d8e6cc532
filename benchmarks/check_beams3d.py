"""Wall time and agreement of `mbseig check` on the bundled 3-D flexible cases at their own meshes.

Per case: its lowest five modes that are not rigid-body, each checked alone by
`mbseig.check_modes` (the median wall time of REPEAT runs), the force evaluations, predicted and
measured δ and ω, the verdict and the integrator.  Not a test (the unit tests,
tests/test_check_beams3d.py, run small meshes); run by hand, one thread:

    OPENBLAS_NUM_THREADS=1 python benchmarks/check_beams3d.py [REPEAT] [--method Radau]
    OPENBLAS_NUM_THREADS=1 python benchmarks/check_beams3d.py --rhs [REPEAT]

``--method Radau``: the implicit integrator instead of the default (exponential Adams where
it applies), for the A/B of docs/beams3d.md.
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
# the bundled 3-D flexible cases; each is checked on its lowest five modes that are not
# rigid-body (the rotors' free axial translation and spin are probed statically, not fitted)
CASES = ["cantilever_3d_oblique.toml", "column_buckling_3d.toml", "spinning_shaft_rayleigh.toml",
         "overhung_rotor_friswell.toml", "ross_example_rotor.toml"]
LOWEST = 5


def main(repeat=1, method="DOP853"):
    print(f"{'case':<30} {'mode':>4} {'time [s]':>9} {'nfev':>6} {'delta pred':>11} "
          f"{'delta meas':>11} {'omega pred':>12} {'omega rel err':>13}  result  integrator")
    for name in CASES:
        path = ROOT / "cases" / name
        a = analyze(path)
        indices = [j + 1 for j, kind in enumerate(a.modes.kind) if kind != "rigid-body"][:LOWEST]
        total = 0.0
        for k in indices:
            times, res = [], None
            for _ in range(repeat):
                t = time.perf_counter()
                res = check_modes(a.model, a.eq, a.linear, a.modes, indices=[k], method=method)
                times.append(time.perf_counter() - t)
            m = res.modes[0]
            err = abs(m.measured_omega / m.predicted_omega - 1)
            total += statistics.median(times)
            print(f"{name:<30} {m.index:>4} {statistics.median(times):>9.1f} {m.nfev:>6} "
                  f"{m.predicted_delta:>11.3g} {m.measured_delta:>11.3g} "
                  f"{m.predicted_omega:>12.6g} {err:>13.2e}  {'pass' if m.passed else 'FAIL'}"
                  f"  {res.integrator}", flush=True)
        print(f"{name:<30} {len(indices)} modes in {total:.1f} s: {total / len(indices):.1f} s a "
              "mode", flush=True)


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
    for name in CASES[:4]:
        path = ROOT / "cases" / name
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
    argv = sys.argv[1:]
    chosen = "DOP853"
    if "--method" in argv:
        i = argv.index("--method")
        chosen = argv[i + 1]
        del argv[i:i + 2]
    if "--rhs" in argv:
        args = [x for x in argv if x != "--rhs"]
        rhs_costs(int(args[0]) if args else 5)
    else:
        main(int(argv[0]) if argv else 1, chosen)
