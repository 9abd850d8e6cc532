"""The constraint-force stiffness Σ λ₀ₖ ∇²Φₖ (DESIGN §4) is what makes preloaded systems right.

Dropping it (``linearize(..., constraint_stiffness=False)``) is the error one widely used code
makes: the pendulum in natural coordinates then has no restoring stiffness at all (ω = 0,
reported as a rigid-body mode), and the gravity-loaded four-bar's frequency moves away from the
independent 1-DOF reference of tests/test_four_bar.py.
"""

import numpy as np
import pytest
from conftest import CASES
from test_four_bar import reference

import mbseig


def _modes(path, constraint_stiffness, **params):
    model = mbseig.load_case(path, **params)
    eq = mbseig.equilibrium(model)
    lin = mbseig.linearize(model, eq, constraint_stiffness=constraint_stiffness)
    return lin, mbseig.modes(lin.M, lin.P, lin.Q)


def test_pendulum_without_constraint_stiffness_has_zero_frequency():
    lin, md = _modes(CASES / "pendulum.toml", True)
    assert md.omega_n[0] == pytest.approx(np.sqrt(9.81), rel=1e-12)  # closed form √(g/l)
    lin0, md0 = _modes(CASES / "pendulum.toml", False)
    assert np.all(lin0.Q == 0)
    assert md0.omega_n[0] == 0.0 and md0.kind[0] == "rigid-body"


def test_loaded_four_bar_shifts_without_constraint_stiffness():
    _, omega_ref = reference(9.81)
    _, md = _modes(CASES / "four_bar.toml", True)
    _, md0 = _modes(CASES / "four_bar.toml", False)
    assert md.omega_n[0] == pytest.approx(omega_ref, rel=1e-10)
    shift = abs(md0.omega_n[0] / omega_ref - 1)
    assert shift > 0.01, f"dropping Σλ∇²Φ should move the loaded four-bar, moved {shift:.2%}"
