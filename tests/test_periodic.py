"""Periodic motions (DESIGN §8): Floquet multipliers of driven cases through the pipeline.

References: Mathieu characteristic values from scipy.special.mathieu_a / mathieu_b (DLMF §28.2
standard form w'' + (a − 2q cos 2z) w = 0); the pendulum on a vertically driven pivot maps onto
it with a = ±4g/(l ω²), q = 2A/l (hanging / inverted; derivation in the cases' descriptions).
"""

import json
import math

import numpy as np
import pytest
from pathlib import Path
from conftest import CASES
from scipy.special import mathieu_a, mathieu_b

from mbseig.casefile import read_case
from mbseig.cli import main
from mbseig.studies.periodic import periodic_analysis, timed_model
from mbseig.studies.periodic_check import check_floquet
from mbseig.studies.periodic_sweep import periodic_sweep

# the format examples of DESIGN §8 (../shared/examples beside the checkout)
EXAMPLE = str(Path(__file__).resolve().parents[2] / "shared" / "examples"
              / "driven_slider_crank.toml")
HANGING = CASES / "pendulum_shaken_pivot.toml"
INVERTED = CASES / "inverted_pendulum_shaken_pivot.toml"
G, L, A = 9.81, 1.0, 0.1
Q = 2 * A / L


@pytest.fixture(scope="module")
def hanging():
    return periodic_analysis(read_case(HANGING))  # w = 6.3, inside the principal tongue


@pytest.fixture(scope="module")
def inverted():
    return periodic_analysis(read_case(INVERTED))  # w = 50 > w* = 44.39


@pytest.mark.skipif(not Path(EXAMPLE).exists(),
                    reason="the format examples are not beside this checkout")
def test_slider_crank_example_gives_the_floquet_object(capsys):
    """The §8 example runs unchanged; its JSON has the §8 keys; 6 coordinates − 5 constraints
    leave 1 DOF, hence 2 multipliers (none spurious from the constraints); period 2π/w (closed
    form); Liouville's identity det Φ = exp ∫ tr A holds to 1e-10; the bound is below the
    margin that decides the verdict."""
    assert main(["modes", EXAMPLE, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    fl = out["floquet"]
    assert {"period", "multipliers", "exponents", "error_bound", "verdict"} <= set(fl)
    assert out["dof"] == 1 and len(fl["multipliers"]) == 2
    assert fl["period"] == pytest.approx(2 * math.pi / 20.0, rel=1e-15)
    assert fl["det_check"] < 1e-10
    assert fl["error_bound"] < fl["decided_by"]["margin"]
    assert out["verdict"] == fl["verdict"]
    # the bundled case is this example with its source and expected values (a 30-period
    # nonlinear simulation along the Floquet vector, stated in the case)
    exp = read_case(CASES / "driven_slider_crank_spring_mass.toml").data["expected"]
    assert fl["verdict"] == exp["verdict"]
    np.testing.assert_allclose([abs(complex(*m)) for m in fl["multipliers"]],
                               exp["multiplier_modulus"], rtol=exp["rtol"])
    # exponents: ln(mu)/T with the imaginary part in (-pi/T, pi/T]
    for mu, ex in zip(fl["multipliers"], fl["exponents"], strict=True):
        assert ex[0] == pytest.approx(math.log(abs(complex(*mu))) / fl["period"], rel=1e-12)
        assert abs(ex[1]) <= math.pi / fl["period"] * (1 + 1e-12)


def test_hanging_pendulum_principal_tongue_edge_against_mathieu():
    """Lower edge of the principal tongue (flip, μ = −1): ω = 2 sqrt(g/(l a_1(q))) with a_1 from
    scipy.special.mathieu_a(1, q); located by the sweep to 1e-8 relative."""
    sweep = periodic_sweep(read_case(HANGING), "w", [5.70, 5.76])
    (b,) = sweep.boundaries
    exact = 2 * math.sqrt(G / (L * mathieu_a(1, Q)))
    assert b.kind == "flip" and b.stability == "loss"
    assert b.value == pytest.approx(exact, rel=1e-8)


def test_kapitza_inverted_pendulum_boundary_against_mathieu():
    """Inverted: held above ω* = sqrt(−4g/(l a_0(q))) (scipy.special.mathieu_a(0, q)), a fold
    (μ = +1); located to 1e-8 relative.  Kapitza's sqrt(2gl)/A is the leading term of the
    series of a_0 (DLMF 28.6.1): within 0.3 %."""
    sweep = periodic_sweep(read_case(INVERTED), "w", [44.2, 44.6])
    (b,) = sweep.boundaries
    exact = math.sqrt(-4 * G / (L * mathieu_a(0, Q)))
    assert b.kind == "fold" and b.stability == "recovery"
    assert b.value == pytest.approx(exact, rel=1e-8)
    assert b.value == pytest.approx(math.sqrt(2 * G * L) / A, rel=3e-3)


def test_frozen_time_is_wrong_and_floquet_is_right(hanging, inverted, capsys):
    """Hanging at w = 6.3 (inside the tongue): no frozen instant has Re s > 0, Floquet says
    unstable with a margin far above its bound.  Inverted at w = 50 (above ω*): every instant
    with A w² cos(wt) > g has a real s > 0 (frozen: unstable), Floquet: |μ| = 1 within the
    bound (undamped: critical, not unstable)."""
    from mbseig.studies.periodic_listing import frozen_summary

    fh, fi = hanging.floquet, inverted.floquet
    assert fh.verdict == "unstable" and frozen_summary(hanging)["verdict"] != "unstable"
    assert fh.decided_by[3] > 1e3 * fh.error_bound  # margin ≫ bound
    assert fi.verdict == "critical" and frozen_summary(inverted)["verdict"] == "unstable"
    assert np.all(np.abs(np.abs(fi.multipliers) - 1) <= fi.error_bounds)
    assert fi.error_bound < 1e-8


def test_pendulum_cases_expected(hanging, inverted):
    """The bundled pendulum cases' [expected] verdicts (Floquet and frozen-time), and their
    stated boundaries against scipy's characteristic values (the cases' sources), 1e-9."""
    from mbseig.studies.periodic_listing import frozen_summary

    for a, path in ((hanging, HANGING), (inverted, INVERTED)):
        exp = read_case(path).data["expected"]
        assert exp["source"]
        assert a.floquet.verdict == exp["verdict"]
        assert frozen_summary(a)["verdict"] == exp["frozen_verdict"]
    flips = read_case(HANGING).data["expected"]["flip_boundaries"]
    np.testing.assert_allclose(flips, [2 * math.sqrt(G / (L * mathieu_a(1, Q))),
                                       2 * math.sqrt(G / (L * mathieu_b(1, Q)))], rtol=1e-9)
    (fold,) = read_case(INVERTED).data["expected"]["fold_boundaries"]
    assert fold == pytest.approx(math.sqrt(-4 * G / (L * mathieu_a(0, Q))), rel=1e-9)


def test_error_bounds_from_two_estimates_and_liouville(hanging):
    """Bounds are at least the two estimates' difference and the Liouville mismatch (both
    measured), and each is far below the distance |μ| − 1 that decides the verdict."""
    f = hanging.floquet
    assert f.det_check < 1e-10
    assert np.all(f.error_bounds >= np.abs(f.multipliers) * f.det_check)
    assert f.error_bounds[0] < 1e-3 * (abs(f.multipliers[0]) - 1)


def test_check_growth_along_floquet_vector(hanging):
    """Nonlinear simulation from the reference perturbed along the dominant Floquet vector:
    growth per period equals |μ| (linear limit; amplitude 1e-5 l, tolerance 1e-4)."""
    res = check_floquet(hanging, amplitude=1e-5, periods=6, rtol=1e-4)
    assert res.passed, res
    assert res.growth == pytest.approx(abs(hanging.floquet.multipliers[0]), rel=1e-4)


def test_pivot_rheonomic_terms_exact():
    """The moving pivot's constraint Φ = r_O − p(t): Φ_t = −ṗ, Φ_tt = −p̈ with p = (0, A cos wt)
    (closed form), to 1e-12 relative."""
    timed, params = timed_model(read_case(HANGING))
    w, t = params["w"], 0.3
    q = timed.base.q_init
    _, dt, dtt = timed.phi_time(q, t)
    assert dt[:2] == pytest.approx([0.0, A * w * math.sin(w * t)], abs=1e-12 * A * w)
    assert dtt[:2] == pytest.approx([0.0, A * w * w * math.cos(w * t)], abs=1e-12 * A * w * w)


@pytest.mark.parametrize("old, new, element, words", [
    ('period = "2*pi/w"', 'period = "-1"', "motion.period", "must be positive"),
    ('period = "2*pi/w"', 'period = "0*w"', "motion.period", "must be positive"),
    ('mass = "m"', 'mass = "m*(1 + 0.1*sin(w*t))"', "masses[0]", "cannot depend on time"),
    ("m = 1.0 ", 'm = "1 + t" ', "parameters.m", "cannot depend on time"),
    ('"A*cos(w*t)"', '"A*cos(1.5*w*t)"', "points[0] 'O'", "does not repeat with period"),
])
def test_bad_periodic_input_one_line(tmp_path, capsys, old, new, element, words):
    """A period that is not positive, t where a field cannot depend on time, a motion that
    does not repeat with the stated period: one line naming the file and element, exit 2."""
    text = HANGING.read_text()
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    assert main(["modes", str(path), "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith(f"mbseig: {path}: {element}: ") and words in err, err
