"""Wall time and agreement of `mbseig check` on the bundled 3-D beam cases at their own meshes.

Per case and mode: the median wall time of REPEAT runs of `mbseig.check_modes`, the force
evaluations, predicted and measured δ and ω, the verdict.  Not a test (the unit tests,
tests/test_check_beams3d.py, run small meshes); run by hand, one thread:

    OPENBLAS_NUM_THREADS=1 python benchmarks/check_beams3d.py [REPEAT]
"""

import statistics
import sys
import time
from pathlib import Path

from mbseig.check import check_modes
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


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
