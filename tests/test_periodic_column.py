"""A column under a pulsating axial load (Bolotin's principal parametric resonance), bundled as
cases/column_pulsating_load.toml (the partial Floquet method is compared with the full one on it
in test_periodic_partial.py).

Reference (closed form, derivation in the case's description): about the straight state the
chain's lateral motion decouples exactly in sine modes; mode 1 obeys Mathieu's equation
y'' + Ω²(1 − P0/Pcr − (Pt/Pcr) cos Wt) y = 0, whose principal-region edges are where
a = 4Ω²(1 − P0/Pcr)/W² equals mathieu_a(1, q) or mathieu_b(1, q), q = 2Ω²(Pt/Pcr)/W²
(scipy.special, DLMF 28.2), solved for W by brentq.
"""

import json
import math

import numpy as np
import pytest
from conftest import CASES
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import mathieu_a, mathieu_b

from mbseig.casefile import read_case
from mbseig.cli import main
from mbseig.studies.floquet import monodromy

CASE = CASES / "column_pulsating_load.toml"
N, L, MB, K = 4, 1.0, 0.25, 100.0  # the case's parameters
H = L / N
D1 = -4 * math.sin(math.pi / (2 * N)) ** 2  # eigenvalue of the second difference, mode 1
PCR = K * abs(D1) / H  # buckling load of the chain
M1 = (MB / 6) * (6 + D1)  # modal mass of mode 1 (uniform rigid bars)
OM2 = (abs(D1) / H) * PCR / M1  # Ω², mode 1 at P = 0
P0, PT = 0.3 * PCR, 0.2 * PCR
W1 = math.sqrt(OM2 * (1 - P0 / PCR))


def edges():
    """(lower, upper) W of the principal region from scipy's characteristic values."""
    def g(W, char):
        return char(1, 2 * OM2 * (PT / PCR) / W ** 2) - 4 * OM2 * (1 - P0 / PCR) / W ** 2
    return (brentq(lambda W: g(W, mathieu_a), 1.6 * W1, 2 * W1, xtol=1e-13, rtol=1e-15),
            brentq(lambda W: g(W, mathieu_b), 2 * W1, 2.4 * W1, xtol=1e-13, rtol=1e-15))


def mode1_multiplier(W):
    """Dominant multiplier of the scalar mode-1 Mathieu equation, integrated on its own
    (independent of mbseig's constrained path): the monodromy of y'' + Ω²(…) y = 0."""
    def f(t, x):
        X = x.reshape(2, 2)
        A = np.array([[0.0, 1.0], [-OM2 * (1 - (P0 + PT * math.cos(W * t)) / PCR), 0.0]])
        return (A @ X).ravel()
    sol = solve_ivp(f, (0, 2 * math.pi / W), np.eye(2).ravel(), method="DOP853", rtol=1e-12,
                    atol=1e-14)
    mu = np.linalg.eigvals(sol.y[:, -1].reshape(2, 2))
    return mu[np.argmax(np.abs(mu))]


@pytest.fixture(scope="module")
def modes_json():
    import io
    from contextlib import redirect_stdout

    buf = io.StringIO()
    with redirect_stdout(buf):
        assert main(["modes", str(CASE), "--json"]) == 0
    return json.loads(buf.getvalue())


def test_case_states_closed_form_values():
    """The case's stated edges, Bolotin's approximation and the centre frequency 2ω₁ are those
    of the closed form (1e-10); Bolotin's first approximation 2ω₁√(1 ∓ β) is within β² of the
    exact edges (its error is O(β²), Bolotin 1964 §2)."""
    exp = read_case(CASE).data["expected"]
    lo, hi = edges()
    np.testing.assert_allclose(exp["flip_boundaries"], [lo, hi], rtol=1e-10)
    beta = PT / (2 * (PCR - P0))
    bolotin = [2 * W1 * math.sqrt(1 - beta), 2 * W1 * math.sqrt(1 + beta)]
    np.testing.assert_allclose(exp["bolotin_boundaries"], bolotin, rtol=1e-10)
    assert max(abs(b / e - 1) for b, e in zip(bolotin, (lo, hi), strict=True)) < beta ** 2


def test_column_modes_against_mathieu(modes_json):
    """At W = 2ω₁: 8 coordinates − 5 constraints = 3 DOF (6 multipliers, none spurious); the
    dominant multiplier equals the scalar Mathieu equation's (independent integration, 1e-7
    relative, the case's rtol); modes 2 and 3 are on the unit circle (undamped, outside their
    own regions) within their bounds; verdict unstable with the bound far below the margin."""
    out = modes_json
    fl = out["floquet"]
    exp = read_case(CASE).data["expected"]
    assert out["n_coordinates"] == 8 and out["dof"] == 3 and len(fl["multipliers"]) == 6
    assert fl["verdict"] == exp["verdict"] == out["verdict"]
    mu = complex(*fl["multipliers"][0])
    ref = mode1_multiplier(2 * W1)
    assert abs(mu - ref) <= exp["rtol"] * abs(ref)
    assert fl["error_bound"] < 1e-3 * fl["decided_by"]["margin"]
    others = [abs(complex(*m)) for m in fl["multipliers"][1:5]]
    bounds = fl["error_bounds"][1:5]
    assert all(abs(m - 1) <= b for m, b in zip(others, bounds, strict=True))
    # the pair μ, 1/μ of an undamped Mathieu mode (Liouville: det = 1)
    assert abs(complex(*fl["multipliers"][5]) * mu - 1) < 1e-7


@pytest.mark.parametrize("side", [0, 1])
def test_column_region_edges_against_mathieu(side):
    """The verdict changes at the closed-form edge: det(I + Φ) (Φ the case's projected
    monodromy, integrated on the Chebyshev interpolants of A(t) as the analysis does) changes
    sign between W_edge (1 − 1e-6) and W_edge (1 + 1e-6) (flip, μ = −1)."""
    from mbseig.studies.floquet_chebyshev import chebyshev_system
    from mbseig.studies.periodic import periodic_linearization

    spec = read_case(CASE)
    W = edges()[side]
    signs = []
    for f in (1 - 1e-6, 1 + 1e-6):
        lin = periodic_linearization(spec, params={"W": repr(W * f)})
        Phi = monodromy(chebyshev_system(lin.system.system)[0], rtol=1e-10)
        signs.append(np.sign(np.linalg.det(np.eye(Phi.shape[0]) + Phi)))
    assert signs[0] == -signs[1] != 0
