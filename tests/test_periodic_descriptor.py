"""The monodromy in the model's own coordinates (mbseig.studies.floquet_descriptor): the
partial method's products, the full monodromy of large models, and what ``--floquet`` says.

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
from mbseig.studies import periodic as P
from mbseig.studies import periodic_partial as PP
from mbseig.studies.floquet import FloquetError
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
        def rate(k, x, out, at=times):
            out[:] = A(at[k]) @ x

        x = rk_fixed(rate, np.array([1.0, 0.3]), h, steps)
        err.append(np.linalg.norm(x - ref))
    assert 2**5.5 <= err[0] / err[1] <= 2**6.5


def test_descriptor_products_give_the_full_monodromys_multipliers():
    """On the 3-pendulum chain (6 coordinates, 3 rheonomic constraints, 6 multipliers), the
    largest multiplier by ARPACK on the descriptor products equals the full monodromy's within
    the sum of the two bounds (the full one's and the two estimates' difference plus residual of
    the partial one), the verdict is the same (unstable), and the product maps the constraint
    directions the projection removes to 0 (to the rounding of one projection)."""
    spec = read_case(CHAIN)
    p = PP.periodic_partial(spec, k=1, params={"n": 3})
    full = periodic_analysis(spec, params={"n": 3}).floquet
    assert abs(p.multipliers[0] - full.multipliers[0]) <= (p.error_bounds[0]
                                                           + full.error_bounds[0])
    assert p.error_bounds[0] < 1e-8 and p.verdict == full.verdict == "unstable"
    lin = periodic_linearization(spec, params={"n": 3})
    flow, rec = descriptor_flow(lin.reference.partition.M, lin.fits[0], lin.timed.period,
                                rtol=1e-9)
    J0 = flow._J0.toarray()
    x = np.concatenate([J0.T @ np.arange(1.0, 4.0), np.zeros(6)])
    assert np.linalg.norm(flow(x)) <= 1e-12 * np.linalg.norm(x)  # rounding of one projection
    assert rec["steps"] >= 64 and rec["history"][-1][1] <= 63 * 1e-9


def test_a_stiff_model_is_handed_to_the_projected_integration(monkeypatch):
    """The pulsating column (a beam: its fastest mode needs 1,024 fixed steps a period for
    1e-10) does not settle within a small step cap (StepsNotSettled); made to try the full
    monodromy in its own coordinates (from 1 DOF, within 128 steps here: FULL_MAX_STEPS is 512),
    it does not settle either, and the analysis integrates the projected system instead, saying
    so in its method; ``--floquet auto`` tries the partial method within that cap, and the full
    monodromy answers, saying why."""
    spec = read_case(CASES / "column_pulsating_load.toml")
    lin = periodic_linearization(spec)
    monkeypatch.setattr("mbseig.studies.floquet_descriptor.MAX_STEPS", 64)
    with pytest.raises(StepsNotSettled, match="too stiff"):
        descriptor_partial(lin.reference.partition.M, lin.fits[0], lin.timed.period, k=1,
                           rtol=1e-9, tol=1e-9)
    monkeypatch.setattr(P, "DESCRIPTOR_FROM_DOF", 1)
    monkeypatch.setattr(PP, "TRY_PRODUCTS_PER_DOF", 100.0)  # a try at 3 DOF
    monkeypatch.setattr("mbseig.studies.floquet_descriptor.FULL_MAX_STEPS", 128)
    P.forget_kept()
    method = P.periodic_analysis(spec).floquet.method
    # --floquet auto (from 1 DOF here) tries the partial method within the same step cap first
    how = PP.largest_multipliers(spec, k=1)["floquet"]["selected"]["method"]
    P.forget_kept()
    assert method.startswith("variational equations projected on the constraints")
    assert "did not settle within 128 steps" in method
    assert how.startswith("full monodromy")
    assert "could not run: its explicit steps did not settle within 128 a period" in how


def test_full_monodromy_in_the_models_coordinates_equals_the_projected_one(monkeypatch):
    """The 6-pendulum chain's full monodromy integrated in the model's own coordinates (every
    column at once; taken from 100 DOF on, from 1 DOF here) and on the projected system's
    Chebyshev interpolants (the default at 6 DOF): every one of the 12 multipliers agrees within
    the sum of the two bounds, and each method names itself."""
    spec = read_case(CHAIN)
    P.forget_kept()
    projected = P.periodic_analysis(spec).floquet
    monkeypatch.setattr(P, "DESCRIPTOR_FROM_DOF", 1)
    P.forget_kept()
    sparse = P.periodic_analysis(spec).floquet
    P.forget_kept()
    assert projected.method.startswith("variational equations projected")
    assert sparse.method.startswith("variational equations in the model's coordinates")
    assert sparse.multipliers.size == projected.multipliers.size == 12
    for mu, b in zip(sparse.multipliers, sparse.error_bounds, strict=True):
        j = int(np.argmin(np.abs(projected.multipliers - mu)))
        assert abs(mu - projected.multipliers[j]) <= b + projected.error_bounds[j]
    assert sparse.verdict == projected.verdict == "unstable"


def test_partial_on_request_says_so(capsys):
    """``--floquet partial`` answers from the partial method and says it was asked; ``auto``
    answers from the full monodromy and says why (the 3-pendulum chain)."""
    for option, start in (("partial", "partial (Arnoldi) method, as asked"),
                          ("auto", "full monodromy, then the largest |μ|")):
        assert main(["modes", str(CHAIN), "--param", "n=3", "--n-modes", "1", "--floquet",
                     option, "--json"]) == 0
        fl = json.loads(capsys.readouterr().out)["floquet"]
        assert fl["selected"]["method"].startswith(start)
        assert ("partial" in fl) == (option == "partial")


def test_auto_tries_the_partial_method_then_the_full_monodromy(monkeypatch, capsys):
    """``--floquet auto`` from ``DESCRIPTOR_FROM_DOF`` on (1 here, so that 3 pendulums are
    enough): on the detuned chain (l2 = 0.5: pendulum 1 alone in the tongue, its multiplier
    apart from the rest on the unit circle) the partial method converges within its budget and
    answers, agreeing with ``--floquet full`` within the sum of the two bounds; given a budget
    of 5 products (below ARPACK's first basis of 20), the uniform chain's attempt stops with
    BudgetSpent and the full monodromy answers, equal to the last bit to ``--floquet full``'s,
    each saying what ran and why; any other refusal of the partial method (stubbed here) is
    answered by the full monodromy too, its message quoted; a budget above
    ``TRY_PRODUCTS_PER_DOF`` a DOF is not tried at all."""
    monkeypatch.setattr(P, "DESCRIPTOR_FROM_DOF", 1)
    monkeypatch.setattr(PP, "TRY_PRODUCTS_PER_DOF", 100.0)  # 60 products at 3 DOF
    P.forget_kept()

    def run(*argv):
        assert main(["modes", str(CHAIN), "--param", "n=3", *argv, "--n-modes", "1",
                     "--json"]) == 0
        return json.loads(capsys.readouterr().out)["floquet"]

    auto, full = run("--param", "l2=0.5"), run("--param", "l2=0.5", "--floquet", "full")
    assert auto["selected"]["method"].startswith("partial (Arnoldi) method: from 1 DOF on")
    assert auto["partial"]["products"] <= 2 * PP.partial_budget(1) + 8  # + probes, residuals
    mu_a, mu_f = complex(*auto["multipliers"][0]), complex(*full["multipliers"][0])
    assert abs(mu_a - mu_f) <= auto["error_bounds"][0] + full["error_bounds"][0]
    assert auto["verdict"] == full["verdict"] == "unstable"
    monkeypatch.setattr(PP, "partial_budget", lambda k: 5)
    auto, full = run(), run("--floquet", "full")
    assert "did not converge within its budget of 5 products" in auto["selected"]["method"]
    assert "partial" not in auto
    assert auto["multipliers"] == full["multipliers"]
    assert auto["error_bounds"] == full["error_bounds"]

    def refuse(*args, **kw):
        raise FloquetError("a refusal of the partial method", element="monodromy")

    monkeypatch.setattr(PP, "descriptor_partial", refuse)  # any other refusal: the full answers
    auto = run()
    assert "stopped: a refusal of the partial method" in auto["selected"]["method"]
    assert auto["multipliers"] == full["multipliers"]
    monkeypatch.setattr(PP, "TRY_PRODUCTS_PER_DOF", 0.6)  # 5 products > 0.6 × 3 DOF: no try
    auto = run()
    P.forget_kept()
    assert "would give the partial method's try 5 products, more than 0.6 a DOF (3 DOF" in \
        auto["selected"]["method"]
    assert auto["multipliers"] == full["multipliers"]


def test_start_vector_keeps_the_constraints_where_all_ones_does_not():
    """On the spatial pendulum on a shaken pivot (9 constraints on 12 coordinates, unit-vector
    conditions among them) the all-ones state lies wholly in the constraint directions, so a
    start or probe built from it projected to 0 (and the step probe settled vacuously); the
    seeded random start projects to a unit consistent state, the steps are chosen on it, and
    the dominant multiplier agrees with the full monodromy's within the two bounds (partial
    method at rtol 1e-9 to keep the suite fast)."""
    spec = read_case(CASES / "spatial_pendulum_shaken_pivot.toml")
    lin = periodic_linearization(spec)
    flow, rec = descriptor_flow(lin.reference.partition.M, lin.fits[0], lin.timed.period,
                                rtol=1e-9)
    assert np.linalg.norm(flow.project(np.ones(2 * flow.n))) <= 1e-12
    # a real probe: its 32- and 64-step products differ (the all-ones one gave 0 and 0)
    assert rec["history"][0][1] > 1e-12
    p = PP.periodic_partial(spec, k=1, rtol=1e-9)
    full = periodic_analysis(spec).floquet
    assert abs(p.multipliers[0] - full.multipliers[0]) <= (p.error_bounds[0]
                                                           + full.error_bounds[0])
