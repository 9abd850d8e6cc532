"""The partial Floquet method's products in the model's own coordinates
(mbseig.studies.floquet_descriptor) and ``--floquet auto``'s choice.

References: the full monodromy of the same case (an independent computation: the projected
system on a dense null-space basis, every multiplier from the dense monodromy matrix); the
order of Butcher's Runge–Kutta method (6: the error falls 2⁶ per halved step on a smooth
problem); the projection's null space (exact: the constraint directions it removes)."""

import json

import numpy as np
import pytest
from conftest import CASES
from scipy.integrate import solve_ivp

from mbseig.casefile import read_case
from mbseig.cli import main
from mbseig.studies import periodic_partial as PP
from mbseig.studies.floquet_descriptor import (
    StepsNotSettled,
    descriptor_flow,
    descriptor_partial,
    rk_fixed,
)
from mbseig.studies.periodic import periodic_analysis, periodic_linearization

CHAIN = CASES / "pendulum_chain_shaken.toml"


def test_butcher_method_has_order_6():
    """Fixed steps on x′ = A(t) x with A smooth and time-dependent: the error against DOP853 at
    rtol 1e-13 falls by 2⁶ per halving (asserted within [2^5.5, 2^6.5]: the asymptotic range at
    40 → 80 steps, errors 6e-9 → 9e-11, far above the reference's 1e-13)."""
    def A(t):
        return np.array([[0.0, 1.0], [-(4 + np.cos(3 * t)), -0.1 * np.sin(t)]])

    ref = solve_ivp(lambda t, x: A(t) @ x, (0, 2), [1.0, 0.3], method="DOP853", rtol=1e-13,
                    atol=1e-15).y[:, -1]
    err = []
    for steps in (40, 80):
        h = 2.0 / steps
        times = [s * h + c * h for s in range(steps) for c in (0, 1 / 3, 1 / 2, 2 / 3)]
        times.append(2.0)
        x = rk_fixed(lambda k, x, at=times: A(at[k]) @ x, np.array([1.0, 0.3]), h, steps)
        err.append(np.linalg.norm(x - ref))
    assert 2**5.5 <= err[0] / err[1] <= 2**6.5


def test_descriptor_products_give_the_full_monodromys_multipliers():
    """On the 6-pendulum chain (12 coordinates, 6 rheonomic constraints, 12 multipliers), the
    largest multipliers by ARPACK on the descriptor products equal the full monodromy's within
    the sum of the two bounds (the full one's and the two estimates' difference plus residual of
    the partial one), the verdict is the same (unstable), and the product maps the constraint
    directions the projection removes to 0 exactly."""
    spec = read_case(CHAIN)
    p = PP.periodic_partial(spec, k=2)
    full = periodic_analysis(spec).floquet
    for j in range(2):
        assert abs(p.multipliers[j] - full.multipliers[j]) <= (p.error_bounds[j]
                                                               + full.error_bounds[j])
    assert p.error_bounds[0] < 1e-8 and p.verdict == full.verdict == "unstable"
    lin = periodic_linearization(spec)
    flow, rec = descriptor_flow(lin.reference.partition.M, lin.fits[0], lin.timed.period,
                                rtol=1e-9)
    J0 = flow._J0.toarray()
    x = np.concatenate([J0.T @ np.arange(1.0, 7.0), np.zeros(12)])
    assert np.linalg.norm(flow(x)) <= 1e-12 * np.linalg.norm(x)  # rounding of one projection
    assert rec["steps"] >= 64 and rec["history"][-1][1] <= 63 * 1e-9


def test_too_many_multipliers_and_a_stiff_model_are_refused_or_handed_over(monkeypatch,
                                                                            capsys):
    """Asking for more multipliers than the model has beyond the projection's zeros is
    refused; a model whose fixed steps do not settle raises StepsNotSettled, and ``--floquet
    auto`` (made to choose the partial method here) then answers from the full monodromy and
    says why."""
    spec = read_case(CASES / "column_pulsating_load.toml")
    lin = periodic_linearization(spec)
    monkeypatch.setattr("mbseig.studies.floquet_descriptor.MAX_STEPS", 64)
    with pytest.raises(StepsNotSettled, match="too stiff"):
        descriptor_partial(lin.reference.partition.M, lin.fits[0], lin.timed.period, k=1,
                           rtol=1e-9, tol=1e-9)
    monkeypatch.setattr(PP, "PARTIAL_FROM_DOF", 1)
    assert main(["modes", str(CASES / "column_pulsating_load.toml"), "--n-modes", "1",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    method = out["floquet"]["selected"]["method"]
    assert method.startswith("full monodromy: the partial method") and "did not settle" in method


def test_auto_chooses_by_the_degrees_of_freedom(monkeypatch, capsys):
    """``--floquet auto`` answers from the partial method from PARTIAL_FROM_DOF degrees of
    freedom on (lowered here to the 6-DOF chain) and from the full monodromy below; both name
    their choice, and their dominant multipliers agree within their bounds."""
    out = {}
    for threshold in (6, 7):
        monkeypatch.setattr(PP, "PARTIAL_FROM_DOF", threshold)
        assert main(["modes", str(CHAIN), "--n-modes", "1", "--json"]) == 0
        out[threshold] = json.loads(capsys.readouterr().out)["floquet"]
    part, full = out[6], out[7]
    assert part["selected"]["method"].startswith("partial (Arnoldi) method: 6 DOF")
    assert "partial" in part and part["selected"]["of"] == 12
    assert full["selected"]["method"].startswith("full monodromy") and "6 DOF < 7" in \
        full["selected"]["method"]
    mu_p, mu_f = complex(*part["multipliers"][0]), complex(*full["multipliers"][0])
    assert abs(mu_p - mu_f) <= part["error_bounds"][0] + full["error_bounds"][0]
