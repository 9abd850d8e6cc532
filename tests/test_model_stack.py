"""B models of one structure evaluated at once (mbseig.model.stacked) and their equilibria and
static verdicts (mbseig.statics.batch) against each model's own evaluations and statics.

Reference: the models' own methods (Model.generalized_force, force_jacobians, phi, phi_q,
constraint_hessian, mass) and mbseig.statics.stiffness.static_stability, one model at a time.
Tolerance: each entry is a sum of a few products formed in another order, so it differs by a
few ulps of the largest term it sums: 1e-12 of the largest entry of the matrix allowed
(measured ≤ 2e-14).  Verdicts and inertia counts must be equal.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mbseig.casefile import read_case
from mbseig.model.stacked import ModelStack, stackable
from mbseig.statics import equilibrium
from mbseig.statics.batch import newton_batch, null_bases, residual, singular, static_verdicts
from mbseig.statics.family import Family
from mbseig.statics.stiffness import static_stability
from mbseig.studies.continuation import family_maker

from conftest import CASES

FAMILIES = [("hand_device", "C4", "f", [0.2, 0.4, 0.6, 0.8]),
            ("hand_device", None, "k_a", [500.0, 900.0, 1500.0]),
            ("spatial_double_pendulum", None, "m1", [1.0, 1.5, 2.5]),
            ("ziegler_pendulum", None, "p", [1.0, 2.0, 2.2]),
            ("four_bar", None, "k_crank", [10.0, 50.0, 90.0])]


def _models(case, config, axis, values):
    spec = read_case(CASES / f"{case}.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        make, _ = family_maker(spec, config, {}, axis)
        return [equilibrium(make(v), offer_stable=False, self_stress="report") for v in values]


def _close(x, y):
    y = np.asarray(y.toarray() if hasattr(y, "toarray") else y)
    scale = max(float(np.max(np.abs(y), initial=0.0)), 1e-300)
    return float(np.max(np.abs(x - y), initial=0.0)) <= 1e-12 * scale


@pytest.mark.parametrize("case,config,axis,values", FAMILIES, ids=[f[0] + "-" + f[2]
                                                                   for f in FAMILIES])
def test_stacked_evaluations_equal_each_model(case, config, axis, values):
    eqs = _models(case, config, axis, values)
    models = [e.model for e in eqs]
    assert stackable(models) is None
    st = ModelStack(models)
    rng = np.random.default_rng(3)
    Q = np.stack([e.q + 1e-2 * rng.standard_normal(e.q.size) for e in eqs])
    L = rng.standard_normal((len(models), st.m))
    G, (K, C), P, J, H = st.g(Q), st.jacobians(Q), st.phi(Q), st.phi_q(Q), st.hessian(Q, L)
    for b, m in enumerate(models):
        q = Q[b]
        K1, C1 = m.force_jacobians(q, np.zeros(m.n), dense=True)
        assert _close(G[b], m.generalized_force(q))
        assert _close(K[b], K1) and _close(C[b], C1)
        assert _close(P[b], m.phi(q)) and _close(J[b], m.phi_q(q, dense=True))
        assert _close(H[b], m.constraint_hessian(q, L[b], dense=True))
        assert _close(st.M[min(b, st.M.shape[0] - 1)], m.mass)


@pytest.mark.parametrize("case,config,axis,values", FAMILIES, ids=[f[0] + "-" + f[2]
                                                                   for f in FAMILIES])
def test_batched_newton_and_static_verdicts_equal_each_point(case, config, axis, values):
    """From the first point's equilibrium, Newton on all points converges to each point's own
    equilibrium (the statics' solve of that model alone: both to a correction of CTOL = 1e-11
    in the model's scales, 1e-8 allowed), and the static verdicts equal static_stability's."""
    eqs = _models(case, config, axis, values)
    models = [e.model for e in eqs]
    by_value = dict(zip(values, models, strict=True))
    fam = Family(lambda p: by_value[p], 1.0, models[0], eqs[0].q)
    st = ModelStack(models)
    y0 = fam.start(eqs[0].q, values[0])
    Y = np.tile(y0, (len(models), 1))
    Y, its, done, _ = newton_batch(st, Y, fam.rows, fam.scales,
                                   min_norm=singular(residual(st, Y, fam.rows)[1][:1]))
    assert done.all()
    n = st.n
    for b, e in enumerate(eqs):
        assert np.max(np.abs(Y[b, :n] - e.q) / fam.scales.ell) <= 1e-8
    Lf = np.zeros((len(models), st.m))
    Lf[:, fam.rows] = Y[:, n:]
    N, _ = null_bases(st.phi_q(Y[:, :n]))
    K, _ = st.jacobians(Y[:, :n])
    Kr = np.swapaxes(N, 1, 2) @ (K + st.hessian(Y[:, :n], Lf)) @ N
    for b, (m, rec) in enumerate(zip(models, static_verdicts(Kr, N), strict=True)):
        ref = static_stability(m, Y[b, :n], Lf[b])
        assert rec["verdict"] == ref["verdict"]
        if "index" in ref and ref.get("index") is not None:
            assert rec["index"] == ref["index"]


def test_models_of_different_structure_are_not_stacked():
    eqs = _models("hand_device", "C4", "f", [0.2])
    other = _models("four_bar", None, "k_crank", [10.0])
    assert stackable([eqs[0].model, other[0].model]) == "models of different structure"


def test_a_subset_of_the_stack_evaluates_its_rows():
    """ModelStack.take(idx): the rows idx of every evaluation of the whole stack (the same
    kernels on a slice of their arrays; BLAS may take another code path on a slice's alignment,
    so equal to a few ulps: 1e-12 of the largest entry, as above)."""
    eqs = _models("hand_device", "C4", "f", [0.2, 0.4, 0.6, 0.8])
    st = ModelStack([e.model for e in eqs])
    Q = np.stack([e.q for e in eqs])
    L = np.ones((len(eqs), st.m))
    idx = np.array([3, 1])
    sub = st.take(idx)
    assert _close(sub.g(Q[idx]), st.g(Q)[idx])
    assert _close(sub.jacobians(Q[idx])[0], st.jacobians(Q)[0][idx])
    assert _close(sub.phi_q(Q[idx]), st.phi_q(Q)[idx])
    assert _close(sub.hessian(Q[idx], L[idx]), st.hessian(Q, L)[idx])
