"""Rows of ``mbseig bench`` for stability under uncertainty (issue "Stability under
uncertainty"), one core (``jobs=1``, one BLAS thread), against the goals of the issue:

- 10⁵ Monte Carlo samples of the device in C4, inputs f ~ normal(1.2, 0.25) N,
  k_a ~ lognormal(1000, 0.1) N/m, damping_scale ~ uniform(0.5, 1.5), seed 0: at most 60 s,
  the whole study (sampling, every model, the interval, the drivers);
- subset simulation on cases/inverted_pendulum_springs.toml with k1 ~ normal(5.83, 0.3),
  k2 ~ normal(6, 0.3): P(unstable) = Φ(−β), β = (5.83 + 6 − 9.81)/√0.18 = 4.7612 (p = 9.62e-7,
  closed form), seeds 0–9, 3,000 samples a level: every seed within a factor 1.5 of p in at
  most 2·10⁴ model evaluations;
- FORM on the same plane boundary: β and the design point within 1e-3 of the closed form.

Each row records the time (the median of ``repeats`` runs where repeated), the machine's load
before and after, and whether the goal is met.
"""

from __future__ import annotations

import math
import statistics
import time
import warnings

from .cases import case_path, load_average

__all__ = ["bench_uncertainty", "DEVICE_INPUTS", "SUBSET_INPUTS"]

DEVICE_INPUTS = {"f": "normal(1.2, 0.25)", "k_a": "lognormal(1000, 0.1)",
                 "damping_scale": "uniform(0.5, 1.5)"}
SUBSET_INPUTS = {"k1": "normal(5.83, 0.3)", "k2": "normal(6, 0.3)"}
SUBSET_SAMPLES = 3000  # a level
SEEDS = range(10)
MG_L = 9.81  # m g / l of the pendulum case




def _closed_form(mu1, s1, mu2, s2):
    from scipy.special import ndtr

    s = math.hypot(s1, s2)
    beta = (mu1 + mu2 - MG_L) / s
    return beta, float(ndtr(-beta)), {"k1": mu1 - beta * s1 ** 2 / s,
                                       "k2": mu2 - beta * s2 ** 2 / s}


def bench_uncertainty(log, *, repeats=3, quick=False):
    """The rows (module docstring)."""
    from ..casefile import read_case
    from ..studies.uncertainty import uncertainty_study
    from ..studies.uncertainty_methods import parse_input

    rows = []
    load0 = load_average()
    device = read_case(case_path("hand_device"))
    pend = read_case(case_path("inverted_pendulum_springs"))
    n = 10_000 if quick else 100_000
    inputs = [parse_input(k, v) for k, v in DEVICE_INPUTS.items()]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        uncertainty_study(device, inputs, config="C4", samples=500, method="monte-carlo",
                          jobs=1, grid=False)  # (warm: imports and caches)
        times, study = [], None
        for _ in range(1 if not quick else repeats):
            t = time.perf_counter()
            study = uncertainty_study(device, inputs, config="C4", samples=n,
                                      method="monte-carlo", jobs=1, grid=False)
            times.append(time.perf_counter() - t)
        r = study.result
        t = statistics.median(times)
        goal = 60.0 * n / 100_000
        rows.append({"section": "uncertainty", "method": f"device C4, {n:,} Monte Carlo samples",
                     "n": n, "time": t, "per_point": t / n, "evaluations": r.evaluations,
                     "p_unstable": r.p_unstable, "ci95": list(r.ci95), "verdicts": r.verdicts,
                     "drivers": r.drivers, "inputs": DEVICE_INPUTS, "seed": 0,
                     "goal": f"≤ {goal:.0f} s", "met": bool(t <= goal), "runs": len(times)})
        log(f"uncertainty device C4: {n} samples {t:.1f} s ({t / n * 1e3:.3f} ms a sample), "
            f"P(unstable) {r.p_unstable:.4g} [{r.ci95[0]:.4g}, {r.ci95[1]:.4g}]")
        # subset simulation near 1e-6 against the closed form, ten seeds
        beta, p, point = _closed_form(5.83, 0.3, 6.0, 0.3)
        sub = [parse_input(k, v) for k, v in SUBSET_INPUTS.items()]
        seeds = list(SEEDS)[:3] if quick else list(SEEDS)
        per = []
        t0 = time.perf_counter()
        for seed in seeds:
            res = uncertainty_study(pend, sub, samples=SUBSET_SAMPLES, seed=seed,
                                    method="subset", jobs=1, grid=False).result
            per.append({"seed": seed, "p": res.p_unstable, "ratio": res.p_unstable / p,
                        "evaluations": res.evaluations, "ci95": list(res.ci95)})
        t_sub = time.perf_counter() - t0
        ratios = [x["ratio"] for x in per]
        worst = max(max(ratios), 1 / min(ratios))
        logs = [math.log(x) for x in ratios]
        within = sum(abs(v) <= math.log(1.5) for v in logs)
        covered = sum(x["ci95"][0] <= p <= x["ci95"][1] for x in per)
        most = max(x["evaluations"] for x in per)
        rows.append({"section": "uncertainty",
                     "method": "subset simulation, pendulum p = 9.62e-7 (closed form)",
                     "n": len(seeds), "time": t_sub, "per_point": t_sub / max(1, sum(
                         x["evaluations"] for x in per)), "p_exact": p, "beta_exact": beta,
                     "seeds": per, "worst_factor": worst, "median_ratio":
                         statistics.median(ratios), "evaluations": most,
                     "within_1_5": within, "interval_covers": covered,
                     "geometric_mean_ratio": math.exp(statistics.fmean(logs)),
                     "sd_log_ratio": statistics.stdev(logs) if len(logs) > 1 else 0.0,
                     "samples_per_level": SUBSET_SAMPLES, "inputs": SUBSET_INPUTS,
                     "goal": "every seed within 1.5× in ≤ 2·10⁴ evaluations",
                     "met": bool(worst <= 1.5 and most <= 20_000)})
        log(f"uncertainty subset: seeds {seeds[0]}..{seeds[-1]}, ratios "
            f"{min(ratios):.3f}..{max(ratios):.3f} of p = {p:.4g}, at most {most} evaluations")
        # FORM on the plane
        t0 = time.perf_counter()
        res = uncertainty_study(pend, sub, method="form", jobs=1, grid=False).result
        t_form = time.perf_counter() - t0
        err_beta = abs(res.reliability_index - beta) / abs(beta)
        err_point = max(abs(res.design_point[k] - v) / abs(v) for k, v in point.items())
        rows.append({"section": "uncertainty", "method": "FORM, pendulum plane boundary",
                     "n": 1, "time": t_form, "per_point": t_form, "beta": res.reliability_index,
                     "beta_exact": beta, "error_beta": err_beta, "error_point": err_point,
                     "evaluations": res.evaluations, "inputs": SUBSET_INPUTS,
                     "goal": "β and design point within 1e-3",
                     "met": bool(err_beta <= 1e-3 and err_point <= 1e-3)})
        log(f"uncertainty FORM: beta {res.reliability_index:.7g} (exact {beta:.7g}, "
            f"error {err_beta:.1e}), design point error {err_point:.1e}, "
            f"{res.evaluations} evaluations")
    load1 = load_average()
    for r in rows:
        r["load"] = {"start": load0, "end": load1}
    return rows


def report_lines(rows) -> list:
    """The Markdown section of the rows."""
    if not rows:
        return []
    r0 = rows[0]
    L = ["", "## Stability under uncertainty", "",
         "`mbseig uncertainty` in-process on one core (`jobs=1`, one BLAS thread). Load average "
         f"before and after: {r0['load']['start']} → {r0['load']['end']}.", "",
         "| study | inputs | evaluations | time | result | goal | met |",
         "|---|---|---|---|---|---|---|"]
    for r in rows:
        ins = ", ".join(f"{k} ~ {v}" for k, v in r["inputs"].items())
        if "p_unstable" in r:
            res = (f"P(unstable) {r['p_unstable']:.4g}, 95 % [{r['ci95'][0]:.4g}, "
                   f"{r['ci95'][1]:.4g}]; {r['per_point'] * 1e3:.3f} ms a sample")
        elif "seeds" in r:
            res = (f"p̂/p over seeds {r['seeds'][0]['seed']}–{r['seeds'][-1]['seed']}: "
                   + ", ".join(f"{x['ratio']:.3f}" for x in r["seeds"])
                   + f" ({r['samples_per_level']} a level): {r['within_1_5']} of "
                   f"{len(r['seeds'])} within 1.5×, worst factor {r['worst_factor']:.3f}, "
                   f"geometric mean {r['geometric_mean_ratio']:.3f}, sd of ln(p̂/p) "
                   f"{r['sd_log_ratio']:.3f}; each run's 95 % interval holds p in "
                   f"{r['interval_covers']} of {len(r['seeds'])}")
        else:
            res = (f"β {r['beta']:.7g} (closed form {r['beta_exact']:.7g}: error "
                   f"{r['error_beta']:.1e}); design point error {r['error_point']:.1e}")
        met = "yes" if r["met"] else "**no**"
        L.append(f"| {r['method']} | {ins} | {r['evaluations']} | {r['time']:.1f} s | {res} | "
                 f"{r['goal']} | {met} |")
    return L
