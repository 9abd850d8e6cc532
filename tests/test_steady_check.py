"""``mbseig check`` on a steady motion: the nonlinear model with its rolling constraints,
simulated from the reference perturbed along a mode, confirms the exact linearization and fails
the naive one (velocity rows' position derivative dropped), and the bench row says so.

References: the rolling disk's closed form (cases/rolling_disk.toml, source): at m = r = g = 1,
v = 1 the lean pair is s = ±i √(4(3v² − g r)/5) = ±1.26491106406735i; at v² = g r/3 only s = 0,
where the naive linearization predicts the real pair ±√(8/15) = ±0.730297."""

import json

import pytest
from conftest import CASES

from mbseig.cli import main
from mbseig.studies.pipeline import as_spec
from mbseig.studies.steady_check import check_steady

DISK = CASES / "rolling_disk.toml"
UNIT = {"g": "1", "m": "1", "r": "1"}


def test_check_passes_the_exact_linearization(capsys):
    """v = 1: the undamped lean pair; measured |δ| ≤ 1e-5 |s| and ω to 1e-3 (the check's
    default tolerances), constraint drift below 1e-10."""
    args = ["check", str(DISK), "--json", "--periods", "3"]
    for k, v in {**UNIT, "v": "1"}.items():
        args += ["--param", f"{k}={v}"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    (sim,) = [m for m in out["modes"] if not m["skipped"]]
    assert sim["passed"] and sim["eigenvalue"][1] == pytest.approx(1.26491106406735, abs=1e-10)
    assert abs(sim["measured_omega"] - 1.26491106406735) < 1e-3 * 1.26491106406735
    assert abs(sim["measured_delta"]) < 1e-5 * 1.26491106406735
    assert sim["constraint_drift"] < 1e-10 and sim["velocity_drift"] < 1e-10


def test_check_fails_the_naive_linearization():
    """v² = g r/3: the naive pair ±0.730297 is not in the nonlinear model (its true eigenvalues
    are 0): both simulated modes fail, the measured δ far from the predicted one."""
    res = check_steady(as_spec(DISK), params={**UNIT, "v": "sqrt(1/3)"}, naive=True, efolds=1.0)
    sim = [m for m in res.modes if not m.skipped]
    assert len(sim) == 2 and not res.passed
    for m in sim:
        assert abs(abs(m.predicted_delta) - (8 / 15) ** 0.5) < 1e-10
        assert not m.passed
        assert abs(m.measured_delta - m.predicted_delta) > 0.1 * abs(m.predicted_delta)


def test_bench_row():
    """The "Stability where methods fail" row: the naive answer wrong (±√(8/15), check failed),
    mbseig right (only s = 0 at the critical speed)."""
    from mbseig.bench.failcases_steady import rolling_disk_naive

    row = rolling_disk_naive(efolds=0.5)
    assert row.naive_wrong and row.mbseig_right
    assert row.data["check_passed"] is False
