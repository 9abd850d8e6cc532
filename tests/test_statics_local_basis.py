"""The statics' Newton on the local basis of a model with frames
(mbseig.statics.newton.LocalNewtonMatrix), against the augmented matrix it replaces.

- A solve equals the augmented matrix's, Δq and Δλ, within the two solves' rounding: ε times
  the condition numbers of the matrices each factorizes (the reduced Nᵀ(K + H)N, Φ_q Φ_qᵀ and
  the equilibrated augmented matrix), times a small constant (a backward stable solve's error
  is a modest multiple of κ ε: Higham, Accuracy and Stability, §7.1).
- A start that has converged is judged so, with the q and λ the augmented test gives (bitwise:
  q is the start in both, λ its least-squares multipliers).
- A start that has not converged reaches the augmented Newton's equilibrium within the
  convergence tolerances (xtol in the model's scales, its correction being the same to
  rounding)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import CASES

from mbseig.bench.lean_rows import shaft_case
from mbseig.casefile import load_case, read_case
from mbseig.numerics import dense, equilibration
from mbseig.statics import newton as newton_module
from mbseig.statics.cache import Memo
from mbseig.statics.linalg import NewtonMatrix, augmented
from mbseig.statics.newton import local_newton, newton, settings_for

EPS = np.finfo(float).eps


def _settings(memo, q):
    return settings_for(memo, q, tol=1e-12, xtol=None, floor_tol=1e-8, max_iter=50,
                        rank_tol=1e-10)


def _column():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_case(CASES / "column_buckling_3d.toml").build()


def test_solve_equals_the_augmented_solve():
    """The loaded 3-D column (25 node triads, a sliding end): a random right-hand side, both
    force and constraint rows, solved both ways at the case's start."""
    model = _column()
    memo = Memo(model)
    q = np.asarray(model.q_init, float)
    s = _settings(memo, q)
    lam = newton_module.static_multipliers(memo, q, s)
    n, m = model.n, model.n_constraints
    rng = np.random.default_rng(2)
    rhs = np.concatenate([rng.standard_normal(n) * s.force_scale, rng.standard_normal(m) * 1e-3])
    NM = local_newton(memo, q, lam, s)
    assert NM is not None and n + m > 300
    x, e = NM.solve(rhs)
    A, Phi_q = augmented(memo, q, lam)
    ref = NewtonMatrix(A).solve(rhs)[0]
    d = equilibration(A)
    kappa = (np.linalg.cond(d[:, None] * dense(A) * d[None, :])
             + np.linalg.cond(dense(NM.reduced.A)) + np.linalg.cond(dense(Phi_q @ Phi_q.T)))
    for part in (slice(0, n), slice(n, n + m)):  # Δq, then Δλ
        assert np.linalg.norm(x[part] - ref[part]) <= 10 * kappa * EPS * np.linalg.norm(ref[part])
    assert not np.any(e)  # a nonsingular reduced matrix balances every force


@pytest.fixture(scope="module")
def shaft_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("shaft") / "shaft.toml"
    path.write_text(shaft_case(2, per=10))
    return path


def _solve(model, q0):
    memo = Memo(model)
    s = _settings(memo, q0)
    return newton(memo, q0, s), s


def _with_and_without(model, q0, monkeypatch):
    """(Newton with the local matrix, the same with it switched off, settings, the kinds of
    Newton matrix the first used)."""
    kinds = []
    make = newton_module.local_newton
    monkeypatch.setattr(newton_module, "local_newton",
                        lambda *a: kinds.append(getattr(make(*a), "kind", None)) or make(*a))
    fast, s = _solve(model, q0)
    monkeypatch.setattr(newton_module, "local_newton", lambda *a, **k: None)
    ref, _ = _solve(model, q0)
    return fast, ref, s, kinds


def test_converged_start_is_judged_on_the_local_basis(shaft_file, monkeypatch):
    """A shaft at rest on its supports (its start is its equilibrium): judged converged on the
    local basis, with the augmented test's result (same q, λ bitwise; 0 iterations; both
    corrections within xtol)."""
    model = load_case(shaft_file)
    fast, ref, s, kinds = _with_and_without(model, np.asarray(model.q_init, float), monkeypatch)
    assert kinds == ["local"]
    assert np.array_equal(fast.q, ref.q) and np.array_equal(fast.lam, ref.lam)
    assert fast.iterations == ref.iterations == 0
    assert fast.correction <= s.xtol and ref.correction <= s.xtol


def test_start_away_from_equilibrium_reaches_the_augmented_equilibrium(monkeypatch):
    """The loaded column shortens under its load: Newton on the local basis takes steps and
    ends where the augmented Newton ends, within the convergence test's own tolerance: both
    stop with a correction below xtol in the model's scales, so their q differ by at most
    twice that (scales.size); their constraint forces Φ_qᵀλ, each the least-squares balance of
    g at its q, then differ by about K Δq, at most ‖K‖∞ · 2 xtol ℓ ≤ 2 xtol · force_scale
    (force_scale ≥ ‖K‖∞ ℓ), doubled for the first-order neglect."""
    model = _column()
    fast, ref, s, kinds = _with_and_without(model, np.asarray(model.q_init, float), monkeypatch)
    assert fast.iterations > 0 and set(kinds) == {"local"}
    assert fast.correction <= s.xtol and ref.correction <= s.xtol
    assert s.scales.size(fast.q - ref.q) <= 2 * s.xtol
    Phi_q = Memo(model).phi_q(ref.q)
    assert np.max(np.abs(Phi_q.T @ (fast.lam - ref.lam))) <= 4 * s.xtol * s.force_scale
