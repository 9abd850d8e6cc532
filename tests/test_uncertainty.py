"""``mbseig uncertainty`` on models: the samples solved together give what ``mbseig modes``
gives one at a time, and the estimates on cases/inverted_pendulum_springs.toml match its
closed form.

The reference (the case file's header): m x'' + c x' + K x = 0 with K = k1 + k2 − m g / l, so
the pendulum is unstable exactly where k1 + k2 < m g / l.  With k1 ~ N(μ1, σ1²), k2 ~ N(μ2, σ2²)
independent, P(unstable) = Φ(−β), β = (μ1 + μ2 − m g / l) / √(σ1² + σ2²), and the design point
is the point of the plane k1 + k2 = m g / l nearest the mean in standard normal space:
kᵢ* = μᵢ − β σᵢ² / √(σ1² + σ2²).
"""

import csv
import json
import math

import numpy as np
import pytest
from conftest import ROOT
from scipy.special import ndtr

from mbseig.cli import main
from mbseig.studies.point import as_spec
from mbseig.studies.uncertainty import (
    least_damping,
    nominal_start,
    sample_task,
    uncertainty_study,
)
from mbseig.studies.uncertainty_methods import parse_input

CASES = ROOT / "cases"
PENDULUM = CASES / "inverted_pendulum_springs.toml"
MG_L = 1.0 * 9.81 / 1.0  # m g / l of the case
OPTS = {"safety": 10.0, "stability_rtol": 1e-12}


def closed_form(mu1, s1, mu2, s2):
    """(β, P(unstable), design point) of the plane boundary (module docstring)."""
    s = math.hypot(s1, s2)
    beta = (mu1 + mu2 - MG_L) / s
    return beta, float(ndtr(-beta)), {"k1": mu1 - beta * s1 ** 2 / s,
                                       "k2": mu2 - beta * s2 ** 2 / s}


def run_json(capsys, *argv):
    code = main(["uncertainty", *map(str, argv), "--json", "--no-progress"])
    out, err = capsys.readouterr()
    assert code == 0, err
    return json.loads(out)


def test_device_samples_together_equal_one_at_a_time():
    """The device in C4 (a follower load, a held position command, four dampers): every sample
    of the batch has the verdict and the least damping ``mbseig modes`` gives it alone, δ within
    the larger of the two error bounds (both are bounds of the same eigenvalue's error)."""
    spec = as_spec(CASES / "hand_device.toml")
    names = ["f", "k_a", "damping_scale"]
    rng = np.random.default_rng(1)
    n = 24
    X = np.column_stack([1.7 + 0.4 * rng.standard_normal(n), 1000 + 150 * rng.standard_normal(n),
                         np.exp(0.3 * rng.standard_normal(n))])
    q0 = nominal_start(spec, "C4", {}, names, [1.7, 1000.0, 1.0])
    d, b, c, e = sample_task(spec, "C4", {}, names, X, q0, "rest", OPTS)
    assert not any(e)
    from mbseig.statics import equilibrium
    from mbseig.studies.continuation import linear_point
    from mbseig.studies.spectra import point_spectra

    codes = {"stable": 0, "critical": 1, "unstable": 2}
    for i in range(n):
        model = spec.build("C4", **dict(zip(names, X[i], strict=True)))
        eq = equilibrium(model, offer_stable=False, self_stress="report")
        sp = point_spectra([linear_point(eq.model, eq)], **OPTS)[0]
        d1, b1 = least_damping(sp)
        assert codes[str.__str__(sp.verdict)] == c[i]
        assert abs(d1 - d[i]) <= max(b1, b[i])
    assert 0 < (c == 2).sum() < n  # both sides of the flutter boundary are sampled


def test_monte_carlo_matches_the_closed_form(capsys, tmp_path):
    """P(unstable) within 4 standard errors of Φ(−β); the interval is the exact binomial one
    (Clopper–Pearson) and holds the true value; the outputs hold every evaluation."""
    from scipy.stats import binomtest

    beta, p, _ = closed_form(6.0, 1.0, 6.0, 0.8)
    n = 4000
    out = run_json(capsys, PENDULUM, "--param", "k1=normal(6, 1)", "--param",
                   "k2=normal(6, 0.8)", "--samples", n, "--method", "monte-carlo",
                   "--out", tmp_path)
    assert out["method"] == "monte-carlo" and out["evaluations"] == n
    assert abs(out["p_unstable"] - p) <= 4 * math.sqrt(p * (1 - p) / n)
    k = out["verdicts"]["unstable"]
    assert out["verdicts"]["failed"] == 0 and sum(out["verdicts"].values()) == n
    lo, hi = binomtest(k, n).proportion_ci(0.95, method="exact")
    assert out["ci95"] == pytest.approx([lo, hi], rel=1e-12)
    # the least damping: δ = (c − √(c² − 4 m K))/(2m) at K = k1 + k2 − m g / l, so its median is
    # that at the median K (δ is monotone in K)
    K50 = 12.0 - MG_L
    d50 = (10.0 - math.sqrt(100.0 - 4 * K50)) / 2
    assert out["least_damping"]["quantiles"]["0.5"] == pytest.approx(d50, rel=0.05)
    # drivers: δ ≈ K/c near the mean, so the shares are near σᵢ²/(σ1² + σ2²) = 0.61, 0.39
    shares = {d["name"]: d["share"] for d in out["drivers"]}
    assert shares["k1"] > shares["k2"] > 0.2 and sum(shares.values()) <= 1.0 + 1e-12
    rows = list(csv.DictReader(open(tmp_path / "samples.csv")))
    assert len(rows) == n
    assert sum(r["verdict"] == "unstable" for r in rows) == k
    for r in rows[:50]:  # each row's verdict is its own least damping's sign
        K = float(r["k1"]) + float(r["k2"]) - MG_L
        assert (r["verdict"] == "unstable") == (K < 0)
    for name in ("histogram.png", "scatter.png", "uncertainty.json"):
        assert (tmp_path / name).stat().st_size > 0


def test_zero_unstable_samples_give_an_honest_interval(capsys, tmp_path):
    """No unstable sample in n: the interval is [0, 1 − 0.025^(1/n)], never [0, 0]."""
    n = 200
    out = run_json(capsys, PENDULUM, "--param", "k1=normal(9, 0.2)", "--param",
                   "k2=normal(9, 0.2)", "--samples", n, "--method", "monte-carlo",
                   "--out", tmp_path)
    assert out["verdicts"]["unstable"] == 0 and out["p_unstable"] == 0.0
    assert out["ci95"][0] == 0.0
    assert out["ci95"][1] == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-9)


def test_form_is_exact_on_the_plane(capsys, tmp_path):
    """FORM on a plane boundary in normal inputs is exact: β and the design point to 1e-3."""
    beta, p, point = closed_form(6.0, 1.0, 6.0, 0.8)
    out = run_json(capsys, PENDULUM, "--param", "k1=normal(6, 1)", "--param",
                   "k2=normal(6, 0.8)", "--method", "form", "--out", tmp_path)
    assert out["reliability_index"] == pytest.approx(beta, rel=1e-3)
    assert out["p_unstable"] == pytest.approx(p, rel=1e-3 * beta ** 2)  # dΦ/Φ ≈ β dβ
    for k, v in point.items():
        assert out["design_point"][k] == pytest.approx(v, rel=1e-3)


def test_form_beta_is_negative_where_the_mean_is_unstable(capsys, tmp_path):
    beta, _, point = closed_form(4.0, 1.0, 4.0, 0.8)
    assert beta < 0
    out = run_json(capsys, PENDULUM, "--param", "k1=normal(4, 1)", "--param",
                   "k2=normal(4, 0.8)", "--method", "form", "--out", tmp_path)
    assert out["reliability_index"] == pytest.approx(beta, rel=1e-3)
    for k, v in point.items():
        assert out["design_point"][k] == pytest.approx(v, rel=1e-3)


def test_subset_simulation_reaches_a_small_probability(capsys, tmp_path):
    """p = Φ(−β) ≈ 2.9e-4 with 1,000 samples a level: within the 95 % interval the estimator's
    coefficient of variation gives, widened to 3 standard deviations (the CoV is itself an
    estimate)."""
    beta, p, point = closed_form(6.0, 0.45, 6.0, 0.45)
    out = run_json(capsys, PENDULUM, "--param", "k1=normal(6, 0.45)", "--param",
                   "k2=normal(6, 0.45)", "--method", "subset", "--samples", 1000,
                   "--out", tmp_path)
    cov = out["details"]["subset"]["per_level"][-1]["coefficient_of_variation"]
    assert abs(math.log(out["p_unstable"] / p)) <= 3 * cov
    assert out["evaluations"] <= 6000
    assert out["design_point"] is not None and out["reliability_index"] >= beta - 1e-9


def test_resume_gives_the_same_output(capsys, tmp_path):
    args = [PENDULUM, "--param", "k1=normal(6, 1)", "--param", "k2=normal(6, 0.8)",
            "--samples", 600, "--method", "monte-carlo", "--resume", tmp_path / "kept"]
    first = run_json(capsys, *args, "--out", tmp_path / "a")
    second = run_json(capsys, *args, "--out", tmp_path / "b")
    for out in (first, second):
        out.pop("outputs")
    assert first == second
    assert any((tmp_path / "kept").iterdir())


@pytest.mark.parametrize("case, name, dist", [
    ("whipple_bicycle.toml", "v", "uniform(2.0, 9.0)"),  # weave 4.29, capsize 6.02 (m/s)
    ("pendulum_shaken_pivot.toml", "w", "uniform(5.0, 6.5)"),  # the principal tongue's edge
])
def test_moving_references_take_the_verdict_of_modes(capsys, case, name, dist):
    """Steady and periodic samples: each sample's verdict is the one ``mbseig modes --json``
    prints at that point (the definition, DESIGN §8), and its least damping is read from that
    JSON (steady: the least δ of the rows not declared rigid-body; periodic: −ln max|μ| / T)
    within the sample's bound."""
    spec = as_spec(CASES / case)
    study = uncertainty_study(spec, [parse_input(name, dist)], samples=4, method="monte-carlo",
                              jobs=1, grid=False)
    r = study.result
    assert r.evaluations == 4 and study.kind in ("steady", "periodic")
    words = set()
    for x, d, b, code in zip(r.evaluated.x[:, 0], r.evaluated.delta, r.evaluated.bound,
                             r.evaluated.code, strict=True):
        assert main(["modes", str(CASES / case), "--param", f"{name}={float(x)!r}", "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert ["stable", "critical", "unstable"][code] == out["verdict"]
        words.add(out["verdict"])
        if study.kind == "steady":
            ref = min(m["delta"] for m in out["modes"] if not m.get("rigid_body"))
        else:
            fl = out["floquet"]
            ref = -math.log(max(abs(complex(*m)) for m in fl["multipliers"])) / fl["period"]
        assert abs(d - ref) <= b
    assert len(words) > 1  # the samples lie on both sides of a boundary


@pytest.mark.parametrize("param, message", [
    ("nope=normal(1, 2)", "is not a parameter of the case"),
    ("K=normal(1, 2)", "is computed from others"),
    ("k1=normal(1, -2)", "k1"),
    ("k1=gamma(1, 2)", "k1"),
])
def test_bad_inputs_are_refused_in_one_line(capsys, param, message):
    code = main(["uncertainty", str(PENDULUM), "--param", param, "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and message in err


def test_readme_worked_example(capsys, tmp_path):
    """The README's worked example prints the numbers the README quotes, and they agree with
    the closed form (within 4 standard errors; the interval holds it)."""
    import re

    text = (ROOT / "README.md").read_text()
    command = re.search(r"\n(mbseig uncertainty cases/inverted_pendulum_springs\.toml [^\n]*)\n",
                        text).group(1)
    import shlex

    argv = shlex.split(command)[1:]
    argv[1] = str(CASES / "inverted_pendulum_springs.toml")
    assert main([*argv, "--no-progress", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    got = re.search(r"P\(unstable\) = ([0-9.]+), 95 % interval \[([0-9.]+), ([0-9.]+)\]", out)
    quoted = re.search(r"gives P\(unstable\) = ([0-9.]+) with 95 % interval \[([0-9.]+), "
                       r"([0-9.]+)\]", text)
    assert got and quoted
    for a, b in zip(got.groups(), quoted.groups(), strict=True):
        assert float(a) == pytest.approx(float(b), rel=2e-3)  # (the README rounds to 3 digits)
    beta, p, _ = closed_form(6.0, 1.0, 6.0, 0.8)
    assert abs(float(got.group(1)) - p) <= 4 * math.sqrt(p * (1 - p) / 10_000)
    assert float(got.group(2)) <= p <= float(got.group(3))
    assert f"β = {beta:.4f}" in text


def test_samples_without_a_model_are_counted_failed(capsys, tmp_path):
    """A normal mass draws negative values (m ~ N(1, 0.6²): P(m ≤ 0) = Φ(−1/0.6) = 0.048):
    those samples are refused by the case's own check, counted ``failed`` with that message,
    never stable, and they widen the interval's upper end (Clopper–Pearson of unstable +
    failed)."""
    from scipy.stats import binomtest

    n = 500
    out = run_json(capsys, PENDULUM, "--param", "m=normal(1, 0.6)", "--param", "k1=normal(6, 1)",
                   "--samples", n, "--method", "monte-carlo", "--out", tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "samples.csv")))
    failed = [r for r in rows if r["verdict"] == "failed"]
    assert len(failed) == out["verdicts"]["failed"] > 0
    assert all(float(r["m"]) <= 0 and "mass must be positive" in r["error"] for r in failed)
    assert all(float(r["m"]) > 0 for r in rows if r["verdict"] != "failed")
    k, f = out["verdicts"]["unstable"], out["verdicts"]["failed"]
    assert out["ci95"][0] == pytest.approx(binomtest(k, n).proportion_ci(0.95, "exact").low)
    assert out["ci95"][1] == pytest.approx(binomtest(k + f, n).proportion_ci(0.95, "exact").high)
    assert out["p_not_stable"] == pytest.approx((n - out["verdicts"]["stable"]) / n)


def test_flutter_of_the_damped_ziegler_pendulum(capsys, tmp_path):
    """A flutter reference: Ziegler's pendulum with joint damping c = 0.1 loses stability by
    flutter at p = 41/28 + c²/2 (its Hurwitz determinant; the case file's source), so with
    p ~ N(1.3, 0.1²) P(unstable) = Φ(−β), β = (41/28 + 0.005 − 1.3)/0.1 = 1.69286, exactly;
    FORM finds that point of the one-dimensional boundary to its tolerance (1e-3 asked), and
    Monte Carlo lies within 4 standard errors."""
    beta = (41 / 28 + 0.1 ** 2 / 2 - 1.3) / 0.1
    p = float(ndtr(-beta))
    args = [CASES / "ziegler_pendulum.toml", "--param", "c=0.1", "--param", "p=normal(1.3, 0.1)"]
    form = run_json(capsys, *args, "--method", "form", "--out", tmp_path / "form")
    assert form["reliability_index"] == pytest.approx(beta, rel=1e-3)
    assert form["design_point"]["p"] == pytest.approx(41 / 28 + 0.005, rel=1e-3)
    n = 1000
    mc = run_json(capsys, *args, "--method", "monte-carlo", "--samples", n,
                  "--out", tmp_path / "mc")
    assert abs(mc["p_unstable"] - p) <= 4 * math.sqrt(p * (1 - p) / n)
