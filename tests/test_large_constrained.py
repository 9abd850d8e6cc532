"""A large constrained model through the whole pipeline, with no dense Φ_q factorization.

n masses in the plane joined by springs along x, every mass on a slider along y = 0, walls at
both ends: 2n coordinates, n constraints, n DOF.  The sliders remove the transverse motion, so the
modes are those of the 1-D fixed-fixed chain, closed form ω_j = 2√(k/m) sin(jπ/(2(n+1))).
At n = 3000 (6000 coordinates) the equilibrium takes its sparse path (multipliers from the
normal equations by sparse LU, independence of the constraints checked by the pivots) and the
modes the bordered partial path (constraint rows kept in the pencil, no null-space basis).
Tolerance 1e-9 relative on the lowest 10 modes (the partial path's residual check is 1e-12 in
backward error; the lowest modes are well separated).
"""

import numpy as np
import pytest
from conftest import write_case

from mbseig.errors import EquilibriumError
from mbseig.studies import analyze

CASE = """
schema_version = 1
title = "Planar spring chain on sliders"
source = "closed form of the 1-D fixed-fixed chain (the sliders remove the transverse motion)"
dimension = 2
[parameters]
n = 3000
k = 1000.0
m = 1.0
[[points]]
name = "wall_left"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "m{i}"
repeat = { i = [1, "n"] }
position = ["i*0.1", 0.0]
[[points]]
name = "wall_right"
position = ["(n + 1)*0.1", 0.0]
fixed = true
[[masses]]
repeat = { i = [1, "n"] }
point = "m{i}"
mass = "m"
[[joints]]
type = "slider"
repeat = { i = [1, "n"] }
point = "m{i}"
direction = [1.0, 0.0]
[[forces]]
type = "spring"
points = ["wall_left", "m1"]
stiffness = "k"
[[forces]]
type = "spring"
repeat = { i = [1, "n - 1"] }
points = ["m{i}", "m{i + 1}"]
stiffness = "k"
[[forces]]
type = "spring"
points = ["m{n}", "wall_right"]
stiffness = "k"
[expected]
source = "closed form (see source)"
"""


def test_large_constrained_chain_sparse_pipeline(tmp_path):
    n = 3000
    a = analyze(write_case(tmp_path, CASE), modes_options={"n_modes": 10})
    assert a.model.n == 2 * n and a.model.n_constraints == n
    assert "sparse LU" in a.eq.tolerances["rank_method"] and a.eq.n_redundant == 0
    assert a.linear.N is None and a.linear.constraint_jacobian is not None  # bordered pencil
    assert a.modes.solver.startswith("partial")
    j = np.arange(1, 11)
    exact = 2 * np.sqrt(1000.0) * np.sin(j * np.pi / (2 * (n + 1)))
    np.testing.assert_allclose(a.modes.omega_n, exact, rtol=1e-9)
    assert a.modes.verdict == "critical"


def test_large_model_with_redundant_constraints_is_refused(tmp_path):
    """Above the dense limit redundancy cannot be resolved by SVD: a clear error, not a guess."""
    text = CASE.replace("n = 3000", "n = 2100") + """
[[joints]]
type = "slider"
name = "duplicate"
point = "m5"
direction = [1.0, 0.0]
"""
    with pytest.raises(EquilibriumError, match="redundant constraints .* must be independent"):
        analyze(write_case(tmp_path, text), modes_options={"n_modes": 5})
