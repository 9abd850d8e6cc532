"""The partial-spectrum path (mbseig.sparse) and the vectorized expansion of repeated elements.

References: closed forms of the chain cases (stated in cases/*.toml), and the dense solvers of
mbseig.qep as an independent method (all modes by LAPACK, then the same subset).
"""

import json

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import CASES, write_case

import mbseig
from mbseig.casefile import batch as case_batch
from mbseig.cli import main
from mbseig.eigen import solve_partial
from mbseig.errors import CaseError, SolverError


def chain(n, k=1000.0, m=1.0):
    K = sp.diags([-k * np.ones(n - 1), 2 * k * np.ones(n), -k * np.ones(n - 1)], [-1, 0, 1],
                 format="csr")
    return sp.identity(n, format="csr") * m, K


def closed_form_omega(n, k=1000.0, m=1.0):
    j = np.arange(1, n + 1)
    return 2 * np.sqrt(k / m) * np.sin(j * np.pi / (2 * (n + 1)))


def test_partial_eigh_matches_closed_form():
    """Lowest 10 modes of the fixed-fixed chain, n = 400: ω_j closed form, rtol 1e-10."""
    M, K = chain(400)
    md = mbseig.modes(M, None, K, n_modes=10)
    assert md.solver == "partial-eigh"
    np.testing.assert_allclose(md.omega_n, closed_form_omega(400)[:10], rtol=1e-10)
    assert md.verdict == "critical" and np.all(md.backward_error <= 1e-12)


def test_partial_proportional_from_case_file():
    """chain_damped.toml at n = 300 through the pipeline with sparse linearization: the case's
    closed-form eigenvalues (rtol 1e-10) for the 8 lowest modes."""
    model = mbseig.load_case(CASES / "chain_damped.toml", n=300)
    eq = mbseig.equilibrium(model)
    lin = mbseig.linearize(model, eq, sparse=True)
    assert sp.issparse(lin.M) and lin.dof == 300
    md = mbseig.modes(lin.M, lin.P, lin.Q, N=lin.N, n_modes=8)
    assert md.solver == "partial-proportional"
    w = closed_form_omega(300)[:8]
    c, k = 0.5, 1000.0
    s = -(c / (2 * k)) * w**2 + 1j * w * np.sqrt(1 - (c * w / (2 * k)) ** 2)
    np.testing.assert_allclose(md.eigenvalues, s, rtol=1e-10)


def _nonproportional(n):
    M, K = chain(n)
    C = sp.diags(np.r_[5.0, np.zeros(n - 2), 0.3]).tocsr()
    return M, C, K


def _dense_listing(M, C, K):
    d = mbseig.modes(M.toarray(), C.toarray(), K.toarray())
    return d


@pytest.mark.parametrize("solver, path", [("partial-companion", "partial-companion"),
                                          ("auto", "partial-projected")])
def test_partial_companion_against_dense(solver, path):
    """General damping: the 6 lowest modes agree with the dense companion path (rtol 1e-9),
    condition numbers too (symmetric matrices: y = x̄ on both paths, rtol 1e-6); ``auto``
    takes the projected path for the lowest modes of symmetric M, P, Q."""
    M, C, K = _nonproportional(150)
    md = mbseig.modes(M, C, K, n_modes=6, solver=solver)
    assert md.solver == path
    d = _dense_listing(M, C, K)
    np.testing.assert_allclose(md.eigenvalues, d.eigenvalues[:6], rtol=1e-9)
    np.testing.assert_allclose(md.condition, d.condition[:6], rtol=1e-6)
    assert md.stability == d.stability[:6]


def test_partial_companion_nonsymmetric_left_vectors():
    """A non-symmetric Q: κ from left vectors of the transposed problem equals the dense κ
    (LAPACK left vectors), rtol 1e-6; eigenvalues rtol 1e-9."""
    M, C, K = _nonproportional(120)
    R = sp.random(120, 120, density=0.03, random_state=3) * 30.0
    Q = (K + R).tocsr()
    md = mbseig.modes(M, C, Q, n_modes=5)
    d = _dense_listing(M, C, Q)
    for s, kap in zip(md.eigenvalues, md.condition, strict=True):
        i = np.argmin(np.abs(d.eigenvalues - s))
        assert abs(d.eigenvalues[i] - s) <= 1e-9 * abs(s)
        assert kap == pytest.approx(d.condition[i], rel=1e-6)


def test_target_and_band():
    """target: the modes nearest ω = 20 rad/s; band: every mode with 10 ≤ ω_n ≤ 20 (closed form)."""
    M, K = chain(300)
    w = closed_form_omega(300)
    md = mbseig.modes(M, None, K, n_modes=4, target=20.0)
    expect = np.sort(w[np.argsort(np.abs(w - 20.0))[:4]])
    np.testing.assert_allclose(md.omega_n, expect, rtol=1e-10)
    for P in (None, _nonproportional(300)[1]):
        md = mbseig.modes(M, P, K, band=(10.0, 20.0))
        inside = w[(w >= 10) & (w <= 20)]
        assert len(md) == inside.size
        if P is None:
            np.testing.assert_allclose(md.omega_n, inside, rtol=1e-10)


def test_free_free_rigid_mode_partial():
    """Free-free chain: the singular Q moves the shift off 0; one rigid-body mode, then the
    closed form ω_j = 2√(k/m) sin(jπ/2n) (rtol 1e-9)."""
    model = mbseig.load_case(CASES / "chain_free_free.toml", n=200)
    lin = mbseig.linearize(model, mbseig.equilibrium(model), sparse=True)
    md = mbseig.modes(lin.M, lin.P, lin.Q, n_modes=4)
    assert md.kind[0] == "rigid-body" and md.kind.count("rigid-body") == 1
    j = np.arange(1, 4)
    np.testing.assert_allclose(md.omega_n[1:], 2 * np.sqrt(1000.0) * np.sin(j * np.pi / 400),
                               rtol=1e-9)


LINK_CHAIN = """
schema_version = 1
dimension = 2
gravity = [0.0, -9.81]
source = "test: hanging chain of point masses on massless rods"
[parameters]
n = 12
[[points]]
name = "pivot"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "p{i}"
repeat = { i = [1, "n"] }
position = ["0.05*i", "-i"]
[[masses]]
repeat = { i = [1, "n"] }
point = "p{i}"
mass = "1 + 0.1*i"
[[joints]]
type = "distance"
points = ["pivot", "p1"]
[[joints]]
type = "distance"
repeat = { i = [1, "n - 1"] }
points = ["p{i}", "p{i + 1}"]
[[forces]]
type = "damper"
repeat = { i = [1, "n"] }
points = ["pivot", "p{i}"]
damping = 0.01
"""


def test_bordered_pencil_equals_null_space_reduction(tmp_path):
    """Constraint rows kept in the pencil (no null-space basis): the 5 lowest modes of a hanging
    12-link chain agree with the dense reduction Nᵀ(·)N (rtol 1e-8), constraint stiffness
    included."""
    path = write_case(tmp_path, LINK_CHAIN)
    model = mbseig.load_case(path)
    eq = mbseig.equilibrium(model)
    dense = mbseig.linearize(model, eq)
    d = mbseig.modes(dense.M, dense.P, dense.Q)
    lin = mbseig.linearize(model, eq, sparse=True)
    assert lin.N is None and lin.constraint_jacobian is not None and lin.dof == dense.dof
    md = mbseig.modes(lin.M, lin.P, lin.Q, constraints=lin.constraint_jacobian, n_modes=5)
    np.testing.assert_allclose(md.eigenvalues, d.eigenvalues[:5], rtol=1e-8)
    # the shapes are in full coordinates and satisfy Φ_q q = 0
    G = lin.constraint_jacobian
    assert np.abs(G @ md.vectors).max() <= 1e-8 * np.abs(G).max()


def test_no_convergence_is_an_error():
    M, C, K = _nonproportional(400)
    with pytest.raises(SolverError, match="did not converge"):
        mbseig.modes(M, C, K, n_modes=10, maxiter=2, solver="partial-companion")


def test_bad_requests():
    M, K = chain(50)
    with pytest.raises(SolverError, match="n_modes"):
        solve_partial(M, None, K, n_modes=0)
    with pytest.raises(SolverError, match="dense path"):
        solve_partial(M, None, K, n_modes=60)
    big = sp.identity(30000, format="csr")
    with pytest.raises(SolverError, match="partial spectrum"):
        mbseig.modes(big, None, big)


def test_cli_n_modes_json(capsys):
    assert main(["modes", str(CASES / "chain_damped.toml"), "--param", "n=6000",
                 "--n-modes", "5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["solver"] == "partial-proportional" and len(out["modes"]) == 5
    assert out["n_coordinates"] == 6000 and out["dof"] == 6000
    w = closed_form_omega(6000)[:5]
    np.testing.assert_allclose([m["omega_n"] for m in out["modes"]], w, rtol=1e-9)


# ---- vectorized expansion of repeated elements ---------------------------------------------
SPRING_NET = """
schema_version = 1
dimension = 2
gravity = [0.0, -9.81]
source = "test: 2-D chain of springs with gravity"
[parameters]
n = 7
[[points]]
name = "a"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "p{i}"
repeat = { i = [1, "n"] }
position = ["0.4*i", "-0.1*i**2"]
[[masses]]
repeat = { i = [1, "n"] }
point = "p{i}"
mass = "0.5 + i/10"
[[forces]]
type = "spring_damper"
points = ["a", "p1"]
stiffness = 800.0
damping = 1.0
[[forces]]
type = "spring_damper"
repeat = { i = [1, "n - 1"] }
points = ["p{i}", "p{i + 1}"]
stiffness = "500 + 10*i"
damping = "0.2*i"
free_length = "0.3 + 0.01*i"
"""


def _per_element(monkeypatch):
    monkeypatch.setattr(case_batch.Batcher, "__call__", lambda self, *a: False)


@pytest.mark.parametrize("text,params", [(SPRING_NET, {}), (None, {"n": 9})])
def test_batch_equals_per_element(tmp_path, monkeypatch, text, params):
    """The batch path assembles the same M, g, K, C (to rounding, rtol 1e-14) as one element at
    a time, on a 2-D spring network with gravity and on chain_damped."""
    path = write_case(tmp_path, text) if text else CASES / "chain_damped.toml"
    fast = mbseig.load_case(path, **params)
    rng = np.random.default_rng(0)
    q = fast.q_init + 0.01 * rng.normal(size=fast.n)
    qd = rng.normal(size=fast.n)
    Kf, Cf = fast.force_jacobians(q, qd)
    with monkeypatch.context() as mp:
        _per_element(mp)
        slow = mbseig.load_case(path, **params)
    assert fast.coordinate_names == slow.coordinate_names
    assert any(hasattr(f, "jacobian_coo") for f in fast.forces)
    assert not any(hasattr(f, "jacobian_coo") for f in slow.forces)
    Ks, Cs = slow.force_jacobians(q, qd)
    for a, b in ((fast.mass, slow.mass), (Kf, Ks), (Cf, Cs)):
        np.testing.assert_allclose(a.toarray(), b.toarray(), rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(fast.generalized_force(q, qd), slow.generalized_force(q, qd),
                               rtol=1e-13)
    np.testing.assert_allclose(fast.q_init, slow.q_init)
    assert set(fast.points) == set(slow.points)
    name = fast.coordinate_names[2].split(".")[0]
    np.testing.assert_allclose(fast.points[name](q), slow.points[name](q))


def test_batch_jacobians_central_differences(tmp_path):
    """Batch kernel Jacobians against central differences of its own g (step 1e-6, rtol 1e-6)."""
    model = mbseig.load_case(write_case(tmp_path, SPRING_NET))
    rng = np.random.default_rng(1)
    q = model.q_init + 0.01 * rng.normal(size=model.n)
    qd = rng.normal(size=model.n)
    K, C = model.force_jacobians(q, qd)
    h = 1e-6
    Kn = np.column_stack([-(model.generalized_force(q + h * e, qd)
                            - model.generalized_force(q - h * e, qd)) / (2 * h)
                          for e in np.eye(model.n)])
    Cn = np.column_stack([-(model.generalized_force(q, qd + h * e)
                            - model.generalized_force(q, qd - h * e)) / (2 * h)
                          for e in np.eye(model.n)])
    np.testing.assert_allclose(K.toarray(), Kn, rtol=1e-6, atol=1e-6 * np.abs(Kn).max())
    np.testing.assert_allclose(C.toarray(), Cn, rtol=1e-6, atol=1e-6 * np.abs(Cn).max())


def test_batch_declines_and_keeps_messages(tmp_path, monkeypatch):
    """A bad repeated element gives the per-element message (the batch declines)."""
    bad = SPRING_NET.replace('points = ["p{i}", "p{i + 1}"]', 'points = ["p{i}", "q{i + 1}"]')
    path = write_case(tmp_path, bad)
    with pytest.raises(CaseError) as fast:
        mbseig.load_case(path)
    _per_element(monkeypatch)
    with pytest.raises(CaseError) as slow:
        mbseig.load_case(path)
    assert str(fast.value) == str(slow.value) and "unknown point 'q2'" in str(fast.value)


def test_lightly_damped_large_chain_is_stable():
    """chain_damped, n = 20000: δ₁ = (c/2k) ω₁² ≈ 6e-9 (closed form) is below the normwise bound
    κη ≈ 8e-9 of s₁ but far above the proportional path's bound on Re s (≈ 1e-13):
    verdict stable, as the case file states.

    δ = −Re s = (α + βω²)/2 with α, β fitted to P = αM + βQ in floating point: the fit's α is
    up to ~10 ε|β|‖Q‖₂/‖M‖₂ ≈ 4e-15 (sign and size set by the BLAS kernel's summation order:
    from −5.9e-15 to +2.0e-15 over five OpenBLAS kernels and one or two threads), which moves
    every δ by α/2, up to 4.8e-7 of δ₁: no relative tolerance on δ₁ holds that a priori (the
    former rtol 1e-7 held on one kernel only).  The bound that does is the path's own bound on
    Re s (proportional_real_error): |β||s|κη + κ|s|‖E‖_F/w(s) + ε|α + βω²|, E = P − αM − βQ,
    whose fit term is ≈ ‖E‖_F/2 here (κ ≈ w(s)/2|s|) and so covers the fitted α (M = I puts
    |α|√n into ‖E‖_F).  The verdict's tolerance is ``safety`` times that bound (the 1e-12|s|
    floor is far below it), so the closed form must lie within tolerance/safety; measured
    95–1100× inside on those kernels."""
    model = mbseig.load_case(CASES / "chain_damped.toml", n=20000)
    lin = mbseig.linearize(model, mbseig.equilibrium(model))
    md = mbseig.modes(lin.M, lin.P, lin.Q, n_modes=5)
    assert md.solver == "partial-proportional"
    w = closed_form_omega(20000)[:5]
    assert np.all(md.tolerance > 10 * md.tolerances["stability_rtol"] * md.omega_n)  # not the floor
    bound = md.tolerance / md.tolerances["safety"]
    assert np.all(np.abs(md.delta - (0.5 / 2000.0) * w**2) <= bound)
    assert md.verdict == "stable" and np.all(md.tolerance < 1e-3 * md.delta)
    # the normwise bound κ·max(η, ε) alone could not decide; the componentwise one (κ_c η_c,
    # mbseig.eigen.measures) and the proportional path's Re s bound both do
    assert md.condition[0] * max(md.backward_error[0], np.finfo(float).eps) > md.delta[0]
    assert md.error_estimate[0] < md.delta[0]


def test_linearize_cli_large_model_sparse_output(tmp_path, capsys):
    """Above SPARSE_MIN coordinates `mbseig linearize` writes CSR parts (npz, JSON) instead of
    dense matrices; they rebuild the stiffness of the chain (2k on the diagonal, −k beside)."""
    out = tmp_path / "lin.npz"
    args = ["linearize", str(CASES / "chain_damped.toml"), "--param", "n=6000"]
    assert main([*args, "--out", str(out)]) == 0
    with np.load(out) as z:
        Q = sp.csr_matrix((z["Q_data"], z["Q_indices"], z["Q_indptr"]), shape=tuple(z["Q_shape"]))
    assert Q.shape == (6000, 6000) and Q.nnz == 3 * 6000 - 2
    np.testing.assert_allclose(Q.diagonal(), 2000.0)
    capsys.readouterr()
    assert main([*args, "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    assert js["M"]["format"] == "csr" and js["dof"] == 6000 and "A" not in js
