"""The statics' Newton correction on the local basis of a model with frames
(mbseig.statics.newton.basis_correction), against the augmented matrix it replaces.

- The correction for a right-hand side equals the augmented solve's, within the two solves'
  rounding: ε times the condition numbers of the matrices each factorizes (the reduced
  Nᵀ(K + H)N and the equilibrated augmented matrix), times a small constant (a backward
  stable solve's error is a modest multiple of κ ε: Higham, Accuracy and Stability, §7.1).
- A start that has converged is judged so on the local basis, with the q and λ the augmented
  test gives (bitwise: q is the start in both).
- A start that has not converged leaves the Newton as it was (bitwise)."""

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
from mbseig.statics.newton import basis_correction, newton, settings_for

EPS = np.finfo(float).eps


def _settings(memo, q):
    return settings_for(memo, q, tol=1e-12, xtol=None, floor_tol=1e-8, max_iter=50,
                        rank_tol=1e-10)


def test_correction_equals_the_augmented_solve():
    """The loaded 3-D column (25 node triads, a sliding end): a random right-hand side, both
    force and constraint rows, solved both ways at the case's start."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = read_case(CASES / "column_buckling_3d.toml").build()
    memo = Memo(model)
    q = np.asarray(model.q_init, float)
    s = _settings(memo, q)
    lam = newton_module.static_multipliers(memo, q, s)
    n, m = model.n, model.n_constraints
    rng = np.random.default_rng(2)
    rhs = np.concatenate([rng.standard_normal(n) * s.force_scale, rng.standard_normal(m) * 1e-3])
    got = basis_correction(memo, q, lam, rhs, s)
    assert got is not None
    dq, free, NM = got
    A, _ = augmented(memo, q, lam)
    ref = NewtonMatrix(A).solve(rhs)[0][:n]
    d = equilibration(A)
    kappa_aug = np.linalg.cond(d[:, None] * dense(A) * d[None, :])
    kappa_red = np.linalg.cond(dense(NM.A))
    bound = 10 * (kappa_aug + kappa_red) * EPS * np.linalg.norm(ref)
    assert np.linalg.norm(dq - ref) <= bound
    assert free == 0.0  # a nonsingular reduced matrix balances every force


@pytest.fixture(scope="module")
def shaft_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("shaft") / "shaft.toml"
    path.write_text(shaft_case(2, per=10))
    return path


def _solve(model, q0):
    memo = Memo(model)
    s = _settings(memo, q0)
    return newton(memo, q0, s), s


def test_converged_start_is_judged_on_the_local_basis(shaft_file, monkeypatch):
    """A shaft at rest on its supports (its start is its equilibrium): the local basis judges
    it converged, and the result is the augmented test's (same q, λ bitwise; 0 iterations;
    both corrections within half xtol)."""
    model = load_case(shaft_file)
    q0 = np.asarray(model.q_init, float)
    taken = []
    judge = newton_module._converged_on_basis
    monkeypatch.setattr(newton_module, "_converged_on_basis",
                        lambda *a: taken.append(judge(*a)) or taken[-1])
    fast, s = _solve(model, q0)
    assert taken and taken[0] is not None and model.n + model.n_constraints > 300
    monkeypatch.setattr(newton_module, "_converged_on_basis", lambda *a, **k: None)
    ref, _ = _solve(model, q0)
    assert np.array_equal(fast.q, ref.q) and np.array_equal(fast.lam, ref.lam)
    assert fast.iterations == ref.iterations == 0
    assert fast.correction <= 0.5 * s.xtol and ref.correction <= s.xtol


def test_start_away_from_equilibrium_leaves_the_newton_as_it_was(monkeypatch):
    """The loaded column shortens under its load: its start has not converged, the local
    basis says so, and the Newton is the one without the local test (bitwise)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = read_case(CASES / "column_buckling_3d.toml").build()
    q0 = np.asarray(model.q_init, float)
    taken = []
    judge = newton_module._converged_on_basis
    monkeypatch.setattr(newton_module, "_converged_on_basis",
                        lambda *a: taken.append(judge(*a)) or taken[-1])
    fast, _ = _solve(model, q0)
    assert taken == [None] and fast.iterations > 0
    monkeypatch.setattr(newton_module, "_converged_on_basis", lambda *a, **k: None)
    ref, _ = _solve(model, q0)
    assert fast.iterations == ref.iterations
    assert np.array_equal(fast.q, ref.q) and np.array_equal(fast.lam, ref.lam)
