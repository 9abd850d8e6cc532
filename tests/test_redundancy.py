"""Redundant constraints: same modes, reported redundancy, minimum-norm multipliers (DESIGN §3)."""

import numpy as np
import pytest
from conftest import CASES, write_case

from mbseig.studies import analyze


def with_duplicate_rod(tmp_path, source, rod_points):
    text = (CASES / source).read_text()
    extra = f'\n[[joints]]\ntype = "distance"\nname = "duplicate"\npoints = {rod_points}\n'
    i = text.index("[expected]")
    return write_case(tmp_path, text[:i] + extra + "\n" + text[i:], name=source)


@pytest.mark.parametrize("source, rod", [("pendulum.toml", '["O", "P"]'),
                                         ("double_pendulum.toml", '["P2", "P1"]')])
def test_duplicated_rod_same_modes(tmp_path, source, rod):
    ref = analyze(CASES / source)
    red = analyze(with_duplicate_rod(tmp_path, source, rod))
    assert red.eq.n_redundant == 1
    assert red.linear.dof == ref.linear.dof
    assert any("duplicate" in r or "rod" in r for r in red.eq.redundant)
    # same eigenvalues to rounding (the reference itself matches the closed form, test_cases.py)
    np.testing.assert_allclose(red.modes.omega_n, ref.modes.omega_n, rtol=1e-12)


def test_redundant_multipliers_are_minimum_norm(tmp_path):
    """Two identical rods share the load equally: λ = λ_single / 2 each (minimum norm).  Their
    self-stress (one rod in tension, the other in compression) changes no stiffness, so the
    statics accepts the minimum-norm choice and records no undetermined self-stress."""
    ref = analyze(CASES / "pendulum.toml")
    red = analyze(with_duplicate_rod(tmp_path, "pendulum.toml", '["O", "P"]'))
    np.testing.assert_allclose(red.eq.lam, [ref.eq.lam[0] / 2] * 2, rtol=1e-12)
    assert red.eq.self_stress == () and red.eq.static["verdict"] == "stable"


def test_redundancy_in_json(tmp_path, capsys):
    import json

    from mbseig.cli import main

    path = with_duplicate_rod(tmp_path, "pendulum.toml", '["O", "P"]')
    assert main(["modes", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["n_redundant"] == 1 and out["n_constraints"] == 2 and out["dof"] == 1
