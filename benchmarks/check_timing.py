"""Wall time of the time-domain check (`mbseig.check_modes`) on small cases.

Median of REPEAT runs per case, next to the median time of the modal analysis of the same case
(load, equilibrium, linearization, modes) as the in-run baseline: the ratio says how much the
cross-check costs relative to the prediction it checks.  Not a test; run by hand:

    python benchmarks/check_timing.py
"""

import statistics
import time
from pathlib import Path

from mbseig.studies import analyze
from mbseig.check import check_modes

ROOT = Path(__file__).resolve().parent.parent
CASES = [("hand_device.toml", {}, None), ("chain_damped.toml", {"n": 3}, None),
         ("double_pendulum.toml", {}, None), ("ziegler_pendulum.toml", {}, "flutter")]
REPEAT = 5


def median_time(fn):
    times = []
    for _ in range(REPEAT):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def main():
    print(f"{'case':<28} {'dof':>4} {'modes':>5} {'analysis [s]':>13} {'check [s]':>10} "
          f"{'ratio':>7} {'force evals':>11}")
    for name, params, config in CASES:
        path = ROOT / "cases" / name
        if not path.exists():
            continue
        t_a, a = median_time(lambda: analyze(path, params=params, config=config))
        t_c, r = median_time(lambda: check_modes(a.model, a.eq, a.linear, a.modes))
        nfev = sum(m.nfev for m in r.modes)
        label = name.removesuffix(".toml") + (f" n={params['n']}" if params else "") + (
            f" ({config})" if config else "")
        print(f"{label:<28} {a.linear.dof:>4} {len(r.modes):>5} {t_a:>13.3f} {t_c:>10.3f} "
              f"{t_c / t_a:>7.0f} {nfev:>11}")


if __name__ == "__main__":
    main()
