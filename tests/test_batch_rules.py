"""The batched forms of one-point rules against those rules, problem by problem.

- :func:`mbseig.modal.bounds.numerical_ranks` (Gram–Schmidt with column pivoting, stacked)
  against :func:`mbseig.modal.bounds.numerical_rank` (LAPACK ``geqp3``): the same rank on blocks
  whose pivots |R_jj| lie far from the threshold (a factor 10² and more on either side, where
  rounding of order ε cannot move a pivot across it).
- :func:`mbseig.modal.bounds.nullities` against :func:`mbseig.modal.bounds.nullity`: the same
  singular values of T(s̄) (one LAPACK routine on the same matrix), the same count.
- :func:`mbseig.statics.batch._bordered` against the pseudo-inverse: both are the minimum-norm
  least-squares solution S⁺R; for S with the kept singular values in [1, 10³] the two differ by
  rounding, at most c·cond·ε with cond = 10³ (c = 100 for the two algorithms' constants).
- :func:`mbseig.modal.scope.spectrum_verdicts` on spectra built so that the verdict and the
  directions left out are known (DESIGN §6's rule), together, one at a time and with sparse N.
- the zero-pair floor, one-point and batched, where it overflows: it decides nothing.
"""

import numpy as np
import pytest

from mbseig.eigen.base import QEPSolution
from mbseig.modal.bounds import nullities, nullity, numerical_rank, numerical_ranks
from mbseig.modal.result import STABILITY_ORDER
from mbseig.modal.scope import spectrum_verdict, spectrum_verdicts
from mbseig.model.symmetry import RigidDirections
from mbseig.statics.batch import SINGULAR, _bordered, _null_border

EPS = np.finfo(float).eps


def _blocks(rng, G, n, k, deficient):
    X = rng.standard_normal((G, n, k)) + 1j * rng.standard_normal((G, n, k))
    if deficient:  # the last column a combination of the others, up to 1e-10 (below 1e-6)
        c = rng.standard_normal((G, k - 1))
        X[:, :, -1] = np.einsum("gnk,gk->gn", X[:, :, :-1], c) \
            + 1e-10 * rng.standard_normal((G, n))
    return X


@pytest.mark.parametrize("k", [2, 3, 4])
@pytest.mark.parametrize("deficient", [False, True])
def test_numerical_ranks_equal_the_pivoted_qr_rank(k, deficient):
    rng = np.random.default_rng(7 + k)
    X = _blocks(rng, 50, 12, k, deficient)
    got = numerical_ranks(X, 1e-6)
    want = np.array([numerical_rank(x, 1e-6) for x in X])
    assert np.array_equal(got, want)
    assert np.all(got == (k - 1 if deficient else k))


def test_numerical_ranks_of_repeated_vectors():
    """Eigenvectors of a defective eigenvalue: one vector twice (rank 1), and a zero column."""
    rng = np.random.default_rng(3)
    x = rng.standard_normal((20, 8, 1)) + 0j
    X = np.concatenate([x, x * (1 + 1e-12), np.zeros_like(x)], axis=2)
    assert np.all(numerical_ranks(X, 1e-6) == 1)
    assert all(numerical_rank(b, 1e-6) == 1 for b in X)


def _solution(M, P, Q):
    k = 2 * M.shape[0]
    return QEPSolution(np.zeros(k, complex), np.zeros((M.shape[0], k), complex), np.zeros(k),
                       np.zeros(k), "test", "test", 0, (1.0, 1.0, 1.0), {}, None,
                       n_dof=M.shape[0], complex_problem=False, problem=(M, P, Q, 1.0))


def test_nullities_equal_nullity():
    """Problems with a double eigenvalue s₀ of geometric multiplicity 1 (a Jordan block) or 2
    (two equal diagonal entries), at means near s₀ and far from it. Reference: the multiplicity
    built in, where the mean is within 1e-9 of s₀ (σ of T there: the distance, or its square
    for the Jordan block, below the rule's 10·(spread + √ε·scale)‖T′‖); and one-at-a-time
    nullity at every mean (nullity runs the same counting on a batch of one)."""
    rng = np.random.default_rng(11)
    Ms, Ps, Qs, means, spreads, scales, want, built = [], [], [], [], [], [], [], []
    for j in range(24):
        n = 5
        s0 = complex(rng.uniform(-1, 1), rng.uniform(0, 3)) * (1 if j % 3 else 40.0)
        # first-order system x' = A x written as M s² + P s + Q with M = 0 (s I − A)
        A = np.diag(rng.uniform(-3, 3, n)).astype(complex)
        A[0, 0] = A[1, 1] = s0.real
        if j % 2:
            A[0, 1] = 1.0
        S = rng.standard_normal((n, n))
        Ar = (S @ A.real @ np.linalg.inv(S))
        M, P, Q = np.zeros((n, n)), np.eye(n), -Ar
        mean = complex(s0.real, 0.0) + (1e-9 if j % 4 == 0 else (0.3 if j % 5 == 0 else 0.0))
        spread, scale = 1e-9, max(abs(mean), 1.0)
        Ms.append(M), Ps.append(P), Qs.append(Q), means.append(mean), spreads.append(spread)
        scales.append(scale)
        want.append(nullity(_solution(M, P, Q), mean, spread, scale))
        built.append(None if abs(mean - s0.real) > 1e-9 else (1 if j % 2 else 2))
    got = nullities(np.array(Ms), np.array(Ps), np.array(Qs), means, spreads, scales)
    assert np.array_equal(got, np.array(want))
    near = [(g, m) for g, m in zip(got, built, strict=True) if m is not None]
    assert len(near) >= 12 and all(g == m for g, m in near), near


def test_bordered_steps_equal_the_pseudo_inverse():
    rng = np.random.default_rng(5)
    B, N, k = 30, 9, 2
    V, _ = np.linalg.qr(rng.standard_normal((N, N)))
    U, _ = np.linalg.qr(rng.standard_normal((N, N)))
    S = np.empty((B, N, N))
    for b in range(B):  # the same null spaces, other kept singular values and vectors
        W, _ = np.linalg.qr(rng.standard_normal((N - k, N - k)))
        sv = np.diag(np.logspace(0, 3, N - k) * rng.uniform(1, 2))
        S[b] = U[:, :N - k] @ W @ sv @ V[:, :N - k].T
    other = 7  # a point whose null space differs: it must be left to the pseudo-inverse
    S[other] = S[other] + 1e-3 * np.outer(U[:, -1], V[:, -1])
    cut = 11  # a point with one more singular value below the cut: the pseudo-inverse too
    w, sv_, vt = np.linalg.svd(S[cut])
    sv_[N - k - 1] = 1e-3 * SINGULAR * sv_[0]
    S[cut] = (w * sv_) @ vt
    R = rng.standard_normal((B, N))
    border = _null_border(S)
    assert border is not None and border[0].shape == (N, k)
    z = _bordered(S, R, border)
    want = np.einsum("bij,bj->bi", np.linalg.pinv(S, rcond=SINGULAR), R)
    mask = np.ones(B, bool)
    mask[[other, cut]] = False
    assert np.all(np.isnan(z[other])) and np.all(np.isnan(z[cut]))
    err = np.abs(z[mask] - want[mask]).max(axis=1) / np.abs(want[mask]).max(axis=1)
    assert err.max() <= 100 * 1e3 * EPS


def _rigid(names, vectors):
    return lambda: RigidDirections(tuple(names), vectors)


def test_spectrum_verdicts_by_construction():
    """Spectra of 6 reduced coordinates (N: 8 × 6) with 2 declared directions, built so that the
    answer is known (DESIGN §6): both directions found at the two rigid eigenvalues (left out);
    one found and the other rigid vector elsewhere (one left out, the other counted critical);
    a defective zero, one vector twice (both found); none rigid (every mode counts). Checked
    against that, together and one spectrum at a time (spectrum_verdict: a batch of one), and
    with N sparse (each spectrum's directions reduced on their own)."""
    import scipy.sparse as sps

    rng = np.random.default_rng(2)
    B, nf, n, k = 40, 8, 6, 12
    N, _ = np.linalg.qr(rng.standard_normal((nf, n)))
    D, _ = np.linalg.qr(N @ rng.standard_normal((n, 2)))
    Dr = N.T @ D
    codes = rng.integers(0, 3, (B, k))
    rigid = np.zeros((B, k), bool)
    vectors = rng.standard_normal((B, n, k)) + 1j * rng.standard_normal((B, n, k))
    found = {0: ["spin a", "spin b"], 1: ["spin b"], 2: ["spin a", "spin b"], 3: []}
    for b in range(B):
        case = b % 4
        if case == 0:
            rigid[b, [0, 1]] = True
            vectors[b][:, 0], vectors[b][:, 1] = Dr[:, 0] + Dr[:, 1], Dr[:, 0] - Dr[:, 1]
        elif case == 1:
            rigid[b, [2, 5]] = True
            vectors[b][:, 2] = Dr[:, 1]
        elif case == 2:
            rigid[b, [0, 1, 3]] = True
            vectors[b][:, 0] = vectors[b][:, 1] = Dr[:, 0]
            vectors[b][:, 3] = Dr[:, 1]
            codes[b] = 0
            codes[b, [0, 1, 3]] = 1
        codes[b, rigid[b]] = STABILITY_ORDER["critical"]
    words = ("stable", "critical", "unstable")
    dirs = [_rigid(["spin a", "spin b"], D) for _ in range(B)]
    together = spectrum_verdicts(codes, rigid, vectors, dirs, [N] * B)
    sparse = spectrum_verdicts(codes, rigid, vectors, dirs, [sps.csr_matrix(N)] * B)
    for b in range(B):
        case = b % 4
        counted = [words[c] for c, r in zip(codes[b], rigid[b], strict=True) if not r]
        if case == 1:
            counted.append("critical")  # the rigid vector along no declared direction
        want = max(counted, key=STABILITY_ORDER.get) if counted else "critical"
        names = found[case]
        one = spectrum_verdict([words[c] for c in codes[b]], rigid[b], vectors[b], dirs[b], N)
        for v in (together[b], sparse[b], one):
            assert str(v) == want and v.scope == "", b
            if names:
                k_ = len(names)
                assert v.rigid_scope.startswith(
                    f"{k_} rigid-body mode{'s' if k_ > 1 else ''} (s = 0) by construction not "
                    f"counted: {'; '.join(names)}"), (b, v.rigid_scope)
            else:
                assert v.rigid_scope == "", b


def test_zero_pair_floor_beyond_the_range_of_doubles_decides_nothing():
    """A mode near s = 0 whose floor h = √(η‖Q‖‖x‖²/|xᴴMx|) overflows (a modal mass of 1e-300
    against ‖Q‖ = 1e300: a fuzzed matrix file) is left as it was: no overflow warning, no
    infinite tolerance, not made rigid-body (the one-point rule and the batched one)."""
    import warnings

    from mbseig.eigen.batch import BatchSolution
    from mbseig.modal.batch import batch_tolerances
    from mbseig.modal.bounds import Bounds, zero_pair_floor

    s = np.array([1e-9 + 0j, 2.0j])
    X = np.eye(2, dtype=complex)
    M, P, Q = np.diag([1e-300, 1.0]), np.zeros((2, 2)), np.diag([1e300, 1.0])
    sol = QEPSolution(s, X, np.full(2, 1e-16), np.ones(2), "test", "test", 0,
                      (1.0, 0.0, 1e300), {}, None, n_dof=2, complex_problem=False,
                      problem=(M, P, Q, 1.0))
    b = Bounds(np.full(2, 1e-12), np.full(2, 1e-11), np.full(2, 1e-11), np.zeros(2, bool),
               np.arange(2), np.ones(2, int), np.ones(2, int))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = zero_pair_floor(b, sol, M, P, 10.0)
    assert not got.rigid[0] and np.isfinite(got.tol).all()
    batch = BatchSolution(eigenvalues=s[None], vectors=X[None], left=X[None],
                          backward_error=np.full((1, 2), 1e-16), condition=np.ones((1, 2)),
                          norms=np.array([[1.0, 0.0, 1e300]]), covered=np.array([True]),
                          solver=np.array(["test"]), reason=np.array([""]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bb = batch_tolerances(batch, M[None], P[None], Q[None])
    assert not bb.rigid[0, 0] and np.isfinite(bb.tol[0]).all()


def test_nullities_at_a_huge_mean_form_only_the_reversed_problem():
    """A cluster's mean of 1e200: T is formed reversed, T(μ)/μ² = M + P/μ + Q/μ² (finite); the
    unreversed μ²M would overflow. No warning, and the count equals nullity's (the same rule)."""
    import warnings

    M, P, Q = np.eye(2)[None], np.zeros((1, 2, 2)), np.diag([1.0, 2.0])[None]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = nullities(M, P, Q, [1e200 + 0j], [0.0], [1e200])
        want = nullity(_solution(M[0], P[0], Q[0]), 1e200 + 0j, 0.0, 1e200)
    assert got[0] == want
