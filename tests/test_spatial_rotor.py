"""Spinning rotors: the heavy symmetric top (critical spin), the rigid rotor on anisotropic
bearings (Campbell diagram, whirl, critical speeds, log decrement) against closed forms.

References (closed forms, stated in the case files):
- sleeping top (Goldstein §5.7): Ω_c = 2√(m g l I_t)/I_p; above it s = iω±,
  ω± = (I_pΩ ± √(I_p²Ω² − 4 I_t m g l))/(2 I_t), both turning with the spin;
- rigid rotor (Genta 2005 §4): cylindrical √(2k/m), conical from
  (I_t s² + K_ty)(I_t s² + K_tz) + (J_pΩs)² = 0, critical speeds from
  (I_t² − J_p²)Ω⁴ − I_t(K_ty + K_tz)Ω² + K_ty K_tz = 0; damped cylindrical mode
  m s² + 2c s + 2k = 0: Λ = 2π δ/ω_d, δ = c/m.
Tolerance 1e-10 relative for eigenvalues and critical speeds (Brent to xtol 1e-13 × span);
Ω_c found by the sweep's boundary search: 1e-9 relative (the eigenvalues are defective at the
collision, so their error there is ~√ε; the boundary is the collision to O(tol²)).
"""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import mbseig
from mbseig.model.spatial_whirl import station_orbits, whirl
from mbseig.studies.campbell import campbell
from mbseig.studies.sweep import run_sweep

CASES = Path(__file__).resolve().parent.parent / "cases"
ROTOR, TOP = CASES / "rigid_rotor.toml", CASES / "heavy_top.toml"


def conical(p, Omega):
    Kty, Ktz = 2 * p["kz"] * p["a"] ** 2, 2 * p["ky"] * p["a"] ** 2
    b = p["It"] * (Kty + Ktz) + p["Jp"] ** 2 * Omega ** 2
    r = math.sqrt(b * b - 4 * p["It"] ** 2 * Kty * Ktz)
    return math.sqrt((b - r) / (2 * p["It"] ** 2)), math.sqrt((b + r) / (2 * p["It"] ** 2))


def top_omegas(p, Omega):
    It = p["ItG"] + p["m"] * p["l"] ** 2
    r = math.sqrt(p["Ip"] ** 2 * Omega ** 2 - 4 * It * p["m"] * p["g"] * p["l"])
    return (p["Ip"] * Omega - r) / (2 * It), (p["Ip"] * Omega + r) / (2 * It)


def whirls(a):
    return [whirl(a.model, a.eq.q, a.modes.shapes[:, k], a.modes.eigenvalues[k])
            for k in range(len(a.modes))]


@pytest.mark.parametrize("Omega", [150.0, 300.0, -300.0])
def test_rotor_modes_and_whirl(Omega):
    """Conical pair against the closed form; whirl relative to the spin: the lower conical mode
    backward, the upper forward (also for a negative speed), cylindrical orbits straight lines
    (mixed), axial and torsional modes none."""
    a = mbseig.analyze(ROTOR, params={"Omega": Omega})
    p = a.model.parameters
    w = a.modes.omega_n
    np.testing.assert_allclose(w[[4, 5]], conical(p, Omega), rtol=1e-10)
    assert whirls(a) == ["none", "none", "mixed", "mixed", "backward", "forward"]
    # the conical orbits are ellipses (|κ| strictly between 0 and 1), the cylindrical lines
    lower = station_orbits(a.model, a.eq.q, a.modes.shapes[:, 4], a.modes.eigenvalues[4])
    assert [o["station"] for o in lower] == ["centre of mass", "bearing 1",
                                             "bearing 2"]
    assert all(-1 < o["kappa"] < -1e-3 for o in lower[1:])
    cyl = station_orbits(a.model, a.eq.q, a.modes.shapes[:, 2], a.modes.eigenvalues[2])
    assert max(abs(o["kappa"]) for o in cyl) < 1e-12


def critical_speeds(p):
    """(Ω, whirl) of every crossing of the 1x line, sorted: the closed forms of the case."""
    Kty, Ktz = 2 * p["kz"] * p["a"] ** 2, 2 * p["ky"] * p["a"] ** 2
    A, B, C = p["It"] ** 2 - p["Jp"] ** 2, p["It"] * (Kty + Ktz), Kty * Ktz
    r = math.sqrt(B * B - 4 * A * C)
    return sorted([(math.sqrt(2 * p["ky"] / p["m"]), "mixed"),
                   (math.sqrt(2 * p["kz"] / p["m"]), "mixed"),
                   (math.sqrt((B - r) / (2 * A)), "backward"),
                   (math.sqrt((B + r) / (2 * A)), "forward")])


def test_campbell_critical_speeds_against_closed_form():
    p = mbseig.load_case(ROTOR).parameters
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = campbell(ROTOR, "Omega", np.linspace(0.0, 800.0, 17), xtol_rel=1e-13)
    expected = critical_speeds(p)
    got = [(c["value"], c["whirl"]) for c in res.critical_speeds]
    assert [w for _, w in got] == [w for _, w in expected]
    np.testing.assert_allclose([v for v, _ in got], [v for v, _ in expected], rtol=1e-10)
    # tracked conical frequencies along the whole grid, and the excitation line
    for k, Om in enumerate(res.values):
        ref = sorted([math.sqrt(p["kx"] / p["m"]), math.sqrt(2 * p["ky"] / p["m"]),
                      math.sqrt(2 * p["kz"] / p["m"]), *conical(p, Om)])
        np.testing.assert_allclose(np.sort(res.frequency[k])[1:], ref, rtol=1e-10)
    js = res.to_json()
    assert js["excitation"][-1] == pytest.approx(800.0)
    assert {c["whirl"] for c in js["critical_speeds"]} == {"mixed", "backward", "forward"}


def test_log_decrement_of_damped_cylindrical_modes():
    a = mbseig.analyze(ROTOR, config="damped", params={"Omega": 200.0})
    p = a.model.parameters
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = campbell(ROTOR, "Omega", [0.0, 200.0], config="damped")
    for c_, k_ in (("cy", "ky"), ("cz", "kz")):
        delta = p[c_] / p["m"]
        wd = math.sqrt(2 * p[k_] / p["m"] - delta ** 2)
        lam = 2 * math.pi * delta / wd
        j = int(np.nanargmin(np.abs(res.frequency[1] - wd)))
        assert res.frequency[1, j] == pytest.approx(wd, rel=1e-10)
        assert res.log_decrement[1, j] == pytest.approx(lam, rel=1e-10)
    assert a.modes.verdict == "stable" or "rigid-body" in a.modes.kind


def test_top_precession_modes_turn_with_the_spin():
    a = mbseig.analyze(TOP)
    p = a.model.parameters
    np.testing.assert_allclose(a.modes.omega_n[1:], top_omegas(p, p["Omega"]), rtol=1e-10)
    assert whirls(a)[1:] == ["forward", "forward"]


def test_sweep_finds_the_critical_spin_of_the_top():
    spec = mbseig.read_case(TOP)
    p = spec.build().parameters
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = run_sweep(spec, [("Omega", np.linspace(40.0, 120.0, 5))], jobs=1)
    (b,) = res.boundaries
    assert b["kind"] == "flutter" and b["stability"] == "recovery"
    assert b["value"] == pytest.approx(p["Omega_c"], rel=1e-9)


def test_rotor_time_domain_check():
    """The nonlinear gyroscopic moment agrees with its linearization: the conical modes of the
    spinning rotor pass the check (undamped: |δ_m| ≤ 1e-5 |s|, ω to 1e-3)."""
    a = mbseig.analyze(ROTOR)
    res = mbseig.check_modes(a.model, a.eq, a.linear, a.modes, indices=[5, 6], periods=5)
    assert res.passed
    assert max(m.rel_error_omega for m in res.modes) < 1e-6
