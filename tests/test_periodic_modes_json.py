"""The modes listing of a periodic case (``mbseig modes CASE --json``): each Floquet exponent
carries its multiplier's bound as a tolerance on δ and the multiplier's condition number, and a
real negative multiplier is listed once (not as half of a conjugate pair).

Reference: cases/pendulum_shaken_pivot.toml (hanging, A/l = 0.1, ω = 6.3) lies in the principal
Mathieu tongue (the case's source: scipy.special.mathieu_a / mathieu_b), where both multipliers
are real and negative, μ₁μ₂ = 1 (no damping: Liouville, det Φ = 1; rtol 1e-9 against the
multipliers' bounds of about 2e-12) and one of them is outside the unit circle."""

import json
import math

from conftest import CASES
from mbseig.cli import main


def test_flip_multipliers_listed_once_with_tolerance_and_condition(capsys):
    assert main(["modes", str(CASES / "pendulum_shaken_pivot.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    fl, modes = out["floquet"], out["modes"]
    assert len(fl["multipliers"]) == 2 and len(modes) == 2
    assert sorted(m["kind"] for m in modes) == ["flutter", "oscillatory"]  # DESIGN's kinds
    assert sorted(m["stability"] for m in modes) == ["stable", "unstable"]
    mus = [complex(*m["multiplier"]) for m in modes]
    assert all(mu.imag == 0 and mu.real < 0 for mu in mus)
    assert math.isclose(mus[0].real * mus[1].real, 1.0, rel_tol=1e-9)
    T = fl["period"]
    for m, mu in zip(modes, mus, strict=True):
        b = fl["error_bounds"][[complex(*x) for x in fl["multipliers"]].index(mu)]
        assert math.isclose(m["tolerance"], b / (abs(mu) * T), rel_tol=1e-15)
        assert math.isfinite(m["condition"]) and m["condition"] >= 1.0
        assert math.isclose(m["eigenvalue"][1], math.pi / T, rel_tol=1e-12)  # ln(μ)/T, μ < 0
