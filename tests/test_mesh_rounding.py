"""The digits a beam mesh keeps against the rounding of its assembled matrices
(mbseig.studies.mesh_rounding)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import CASES

from mbseig.casefile import load_case
from mbseig.studies.mesh_rounding import DIGITS, U, mesh_rounding, rounding_estimate
from mbseig.studies.point import analyze_model, modes_json

BETA1 = 1.8751040687  # cantilever, first root of cos x cosh x = -1 (Blevins, table 8-1)


def test_estimate_is_the_first_order_change_under_the_worst_rounding():
    """A random symmetric definite pencil: moving every entry by t·|entry| with the sign that
    raises λ (δQ_ij = t|Q_ij| sgn(x_i x_j), δM_ij = −t|M_ij| sgn(x_i x_j)) changes λ by
    t (|x|ᵀ|Q||x| + λ|x|ᵀ|M||x|)/xᵀMx to first order (δλ = xᵀ(δQ − λδM)x / xᵀMx, closed form for a
    simple eigenvalue); the central difference at t = 1e-6 agrees within its truncation, O(t²)
    relative (bounded here by 1e-8), and the rounding of λ(±t), ε/t ≈ 2e-10."""
    rng = np.random.default_rng(4)
    A, B = rng.standard_normal((2, 7, 7))
    Q, M = A @ A.T + 7 * np.eye(7), B @ B.T + 7 * np.eye(7)
    lam, X = sla.eigh(Q, M)
    omega = np.sqrt(lam)
    e = rounding_estimate(M, Q, omega, X)
    t = 1e-6
    for k in range(7):
        x = X[:, k]
        S = np.sign(np.outer(x, x))
        lp = sla.eigh(Q + t * np.abs(Q) * S, M - t * np.abs(M) * S, eigvals_only=True)[k]
        lm = sla.eigh(Q - t * np.abs(Q) * S, M + t * np.abs(M) * S, eigvals_only=True)[k]
        slope = (lp - lm) / (2 * t)  # dλ/dt
        predicted = e[k] * 2 * lam[k] / U  # e = u · (dλ/dt) / (2λ)
        assert abs(slope / predicted - 1) <= 1e-8 + 4 * np.finfo(float).eps / t


@pytest.mark.parametrize("elements", [600])  # (200 holds too: e 3.6e-7, error 3.6e-8; 1.9 s)
def test_a_fine_cantilever_says_so_and_its_frequencies_lie_within_the_statement(elements):
    """The oblique cantilever (closed form: ω = (β₁L)² √(E I/(ρ A L⁴)) in each bending plane,
    Blevins table 8-1) meshed finer than double precision resolves to 8 digits: the statement
    is made, and the two lowest listed frequencies lie within its estimate of the closed form
    (plus the element's own error, 2.7e-8 · (24/elements)⁴ by the case's source: h⁴); the mesh
    it names keeps 8 digits by the same estimate."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = analyze_model(load_case(CASES / "cantilever_3d_oblique.toml", n=elements),
                          modes_options={"n_modes": 6})
    r = mesh_rounding(a.model, a.linear, a.modes)
    assert r is not None and not r.resolved and r.digits < DIGITS
    assert f"at {r.keeps['bar']:,} elements (now {elements:,})" in r.line()
    E, rho, b, h, L = 2.1e11, 7850.0, 0.02, 0.03, 1.0
    closed = sorted(BETA1**2 * np.sqrt(E * inertia / (rho * b * h * L**4))
                    for inertia in (h * b**3 / 12, b * h**3 / 12))
    order = np.argsort(a.modes.omega_n)[:2]
    for k, ref in zip(order, closed, strict=True):
        tol = r.relative[k] + 2.7e-8 * (24 / elements) ** 4
        assert abs(a.modes.omega_n[k] / ref - 1) <= tol
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        coarse = analyze_model(load_case(CASES / "cantilever_3d_oblique.toml",
                                         n=r.keeps["bar"]))
    kept = mesh_rounding(coarse.model, coarse.linear, coarse.modes)
    assert kept.resolved and kept.worst <= 10.0**-DIGITS


def test_the_bundled_mesh_is_resolved_and_its_json_says_so():
    """At its bundled 24 elements the cantilever keeps more than 8 digits: no statement, and
    the JSON records the estimate (an extension key)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = analyze_model(load_case(CASES / "cantilever_3d_oblique.toml"))
    out = modes_json(a)["mesh_rounding"]
    assert out["resolved"] and out["worst"] <= 10.0**-DIGITS
    assert out["elements"] == out["elements_keeping"] == {"bar": 24}
