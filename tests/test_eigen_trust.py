"""Eigen-solver trust (issue 13; issue 17's eigen items): no verdict may hide an instability.

References, named per test: closed forms (1-DOF roots, chain ω_j, the NLEVP problems' published
eigenvalues and determinants, mbseig/bench/nlevp.py), and 50-digit solves with mpmath of the
very matrices given (all 2n eigenvalues through s = σ + 1/t, so a singular M is no obstacle).
Every listed eigenvalue is also held to its own recorded tolerance: |s − s_ref| ≤ tolerance (the
bound is valid), and a verdict is compared with the reference's.
"""

import math
import warnings

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import write_case
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mbseig
from mbseig.bench import nlevp
from mbseig.errors import SolverError

mp = pytest.importorskip("mpmath")


# ---------------------------------------------------------------------------------------------
# references
# ---------------------------------------------------------------------------------------------
def reference_eigenvalues(M, P, Q, dps=50, sigma="0.3718"):
    """All finite eigenvalues of s²M + sP + Q at ``dps`` digits, and the number of infinite ones.

    Möbius shift s = σ + 1/t: t²·Q(σ + 1/t) = (σ²M + σP + Q)t² + (2σM + P)t + M, whose leading
    coefficient is nonsingular for a regular pencil and a generic σ; t = 0 ⇔ s = ∞."""
    mp.mp.dps = dps
    n = M.shape[0]

    def conv(A):
        return mp.matrix([[mp.mpc(complex(v)) for v in row] for row in np.asarray(A)])

    Mm, Pm, Qm = conv(M), conv(P), conv(Q)
    sg = mp.mpf(sigma)
    A2, A1 = sg * sg * Mm + sg * Pm + Qm, 2 * sg * Mm + Pm
    inv = A2 ** -1
    C = mp.zeros(2 * n, 2 * n)
    X, Y = -inv * Mm, -inv * A1
    for i in range(n):
        C[i, n + i] = 1
        for j in range(n):
            C[n + i, j], C[n + i, n + j] = X[i, j], Y[i, j]
    t = mp.eig(C, left=False, right=False)
    tiny = mp.mpf(10) ** (-(dps // 2))
    finite = [sg + 1 / ti for ti in t if abs(ti) > tiny]
    return np.array([complex(z) for z in finite]), 2 * n - len(finite)


def reference_verdict(ev, atol=0.0):
    re = np.real(ev)
    return "unstable" if np.any(re > atol) else "critical" if np.any(re >= -atol) else "stable"


def assert_within_tolerance(md, ref, *, complex_problem=False):
    """Every listed eigenvalue is within its recorded bound of a reference eigenvalue (or of its
    conjugate, for a real problem listed once per pair): |s − s_ref| ≤ safety · error_estimate,
    and |Re s − Re s_ref| ≤ tolerance (the δ tolerance, which the structured paths sharpen)."""
    safety = md.tolerances["safety"]
    cand = ref if complex_problem else np.concatenate([ref, np.conj(ref)])
    for s, err, tol in zip(md.eigenvalues, md.error_estimate, md.tolerance, strict=True):
        d = np.abs(cand - s)
        j = int(np.argmin(d))
        assert d[j] <= max(safety * err, 1e-300), (s, d[j], safety * err)
        near = d <= max(safety * err, 1e-300)  # of the candidates within the bound, the best Re
        assert float(np.min(np.abs(cand[near].real - s.real))) <= max(tol, 1e-300), (s, tol)


def oscillators(c, k=1.0):
    """Decoupled 1-DOF oscillators m = 1 with dampings c and stiffnesses k."""
    c, k = np.broadcast_arrays(np.asarray(c, float), np.asarray(k, float))
    return np.eye(c.size), np.diag(c), np.diag(k)


# ---------------------------------------------------------------------------------------------
# 1. defective eigenvalues: a bound valid for Jordan blocks
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("solver", ["auto", "companion", "qz"])
def test_critically_anti_damped_oscillator_is_unstable(solver):
    """m = k = 1, c = −2: s² − 2s + 1 = (s − 1)², the response t·eᵗ (closed form): a double
    root at +1, listed twice as a divergence, verdict unstable; c = +2: stable.  The second
    oscillator (c = 0.3) is a simple pair −0.15 ± i√(1 − 0.0225)."""
    for c, verdict, kind in ((-2.0, "unstable", "divergence"), (2.0, "stable", "overdamped")):
        md = mbseig.modes(*oscillators([c, 0.3]), solver=solver)
        assert md.verdict == verdict
        assert md.kind.count(kind) == 2 and "rigid-body" not in md.kind
        double = md.eigenvalues[[k for k, kd in enumerate(md.kind) if kd == kind]]
        np.testing.assert_allclose(double, -c / 2, atol=1e-6)  # √ε-accurate (defective)
        assert np.all(double.imag == 0)  # not twice the same +Im
        assert np.all(np.isfinite(md.tolerance)) and np.all(md.tolerance < 1e-5)
        assert_within_tolerance(md, np.array([-c / 2, -c / 2, -0.15 + 1j * math.sqrt(1 - 0.0225)]))


def test_nlevp_qep2_triple_root_at_one():
    """NLEVP qep2: det = (s − 1)³(s + 1)(s² + 1) (closed form): the triple root s = 1 (Jordan
    blocks 2 + 1) is listed three times as a divergence, never as a rigid-body mode."""
    M, P, Q, ref = nlevp.qep2()
    for solver in ("auto", "qz"):
        md = mbseig.modes(M, P, Q, solver=solver)
        assert md.verdict == "unstable"
        assert md.kind.count("divergence") == 3 and "rigid-body" not in md.kind
        assert_within_tolerance(md, np.array(ref["eigenvalues"], complex))
        assert md.accounting["finite"] + md.accounting["infinite"] == 6


def test_nlevp_qep3_tiny_eigenvalue_not_merged():
    """NLEVP qep3 (exact eigenvalues 0, 1, 1 + E, 2, 3, ∞ with E = −1 + √(ε/2), so 1 + E =
    1.0537e-8 exactly in floating point): 0 is the only rigid-body mode, 1.05e-8 is listed on its
    own as a divergence, to 1e-22 absolute (the componentwise bound separates it)."""
    M, P, Q, ref = nlevp.qep3()
    md = mbseig.modes(M, P, Q)
    assert md.kind.count("rigid-body") == 1 and md.n_infinite == 1 and len(md) == 5
    tiny = md.eigenvalues[(np.abs(md.eigenvalues) > 0) & (np.abs(md.eigenvalues) < 1e-6)]
    assert tiny.size == 1 and abs(tiny[0] - ref["eigenvalues"][2]) <= 1e-22
    assert md.verdict == "unstable"
    assert_within_tolerance(md, np.array(ref["eigenvalues"], complex))


def test_nlevp_qep1_singular_mass():
    """NLEVP qep1: eigenvalues 1/3, 1/2, 1, ±i, ∞ (published); M singular → scaled QZ."""
    M, P, Q, ref = nlevp.qep1()
    md = mbseig.modes(M, P, Q)
    assert md.solver == "qz" and md.n_infinite == 1 and md.verdict == "unstable"
    assert_within_tolerance(md, np.array(ref["eigenvalues"], complex))
    np.testing.assert_allclose(np.sort(md.eigenvalues.real[md.eigenvalues.imag == 0]),
                               [1 / 3, 1 / 2, 1.0], rtol=1e-12)


# ---------------------------------------------------------------------------------------------
# 3. complex M, P, Q (hysteretic damping): every eigenvalue listed
# ---------------------------------------------------------------------------------------------
def test_power_plant_complex_listed_in_full():
    """NLEVP power_plant, K = (1 + 0.2i)K₀: 16 eigenvalues, no conjugate pairs; against a
    50-digit solve: each listed eigenvalue within its tolerance, the same 4 with Re s > 0,
    verdict unstable; no ComplexWarning (nothing is cast)."""
    M, P, Q, ref = nlevp.power_plant()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        md = mbseig.modes(M, P, Q)
    exact, n_inf = reference_eigenvalues(M, P, Q, dps=40)
    assert md.complex_problem and len(md) == 16 and n_inf == 0
    assert int(np.sum(exact.real > 0)) == ref["n_unstable"] == int(np.sum(md.delta < -md.tolerance))
    assert md.verdict == "unstable"
    assert_within_tolerance(md, exact, complex_problem=True)
    assert md.accounting["finite"] == 16


# ---------------------------------------------------------------------------------------------
# 4. partial spectrum with a target: shift-invert where it ranks
# ---------------------------------------------------------------------------------------------
def _chain_with_divergence(n=150):
    K = sp.diags([-1000.0 * np.ones(n - 1), 2000.0 * np.ones(n), -1000.0 * np.ones(n - 1)],
                 [-1, 0, 1])
    Kd = sp.block_diag([K, sp.csr_matrix([[-400.0]])]).tocsr()  # ẍ − 400x = 0: s = ±20
    C = sp.block_diag([sp.diags(np.r_[5.0, np.zeros(n - 2), 0.3]), sp.csr_matrix([[0.0]])]).tocsr()
    return sp.identity(n + 1, format="csr"), C, Kd


@pytest.mark.parametrize("damped", [True, False])
def test_target_finds_divergence_at_plus_20(damped):
    """A decoupled coordinate with ẍ = 400x (closed form s = ±20) beside a chain with modes near
    20 rad/s: n_modes = 3 nearest 20 rad/s must include s = +20, verdict unstable; the verdict
    says it is of the modes computed, and the listing says which range it covers."""
    M, C, K = _chain_with_divergence()
    md = mbseig.modes(M, C if damped else None, K, n_modes=3, target=20.0)
    assert md.solver == ("partial-companion" if damped else "partial-eigh")
    assert np.min(np.abs(md.eigenvalues - 20.0)) <= 1e-9 * 20
    assert md.verdict == "unstable" and "of the modes computed" in str(md.verdict)
    assert md.partial and "found" in md.coverage and "not computed" in md.coverage


def test_partial_double_eigenvalue_said():
    """Two identical oscillators ω = 2 (closed form) and two others: n_modes = 1 returns both
    members of the double eigenvalue and says so."""
    M = sp.identity(6, format="csr")
    K = sp.diags([4.0, 4.0, 9.0, 16.0, 25.0, 36.0]).tocsr()
    md = mbseig.modes(M, None, K, n_modes=1)
    np.testing.assert_allclose(md.omega_n, [2.0, 2.0], rtol=1e-12)
    assert "repeated" in md.coverage


# ---------------------------------------------------------------------------------------------
# 5. bordered paths: β ≠ 0, purified vectors, a Jordan block at s = 0
# ---------------------------------------------------------------------------------------------
INCLINED = """
schema_version = 1
dimension = 2
source = "closed form of the 1-D fixed-fixed chain along the incline, C = beta K"
[parameters]
n = 120
k = 1000.0
beta = 0.01
[[points]]
name = "w0"
position = [0.0, 0.0]
fixed = true
[[points]]
name = "m{i}"
repeat = { i = [1, "n"] }
position = ["0.06*i", "0.08*i"]
[[points]]
name = "w1"
position = ["0.06*(n + 1)", "0.08*(n + 1)"]
fixed = true
[[masses]]
repeat = { i = [1, "n"] }
point = "m{i}"
mass = 1.0
[[joints]]
type = "slider"
repeat = { i = [1, "n"] }
point = "m{i}"
direction = [0.6, 0.8]
[[forces]]
type = "spring_damper"
points = ["w0", "m1"]
stiffness = "k"
damping = "beta*k"
[[forces]]
type = "spring_damper"
repeat = { i = [1, "n - 1"] }
points = ["m{i}", "m{i + 1}"]
stiffness = "k"
damping = "beta*k"
[[forces]]
type = "spring_damper"
points = ["m{n}", "w1"]
stiffness = "k"
damping = "beta*k"
"""


def test_bordered_proportional_with_stiffness_damping(tmp_path):
    """Masses on inclined sliders, C = βK with β = 0.01: the bordered partial-proportional path
    (multipliers scaled by 1 + βs) against the closed form ω_j = 2√(k/m) sin(jπ/(2(n+1))),
    s² + βω²s + ω² = 0 (rtol 1e-9); every pair η ≤ 1e-12 (was 6.5e-6, then SolverError)."""
    model = mbseig.load_case(write_case(tmp_path, INCLINED))
    lin = mbseig.linearize(model, mbseig.equilibrium(model), sparse=True)
    md = mbseig.modes(lin.M, lin.P, lin.Q, constraints=lin.constraint_jacobian, n_modes=6)
    assert md.solver == "partial-proportional"
    n = 120  # the masses of INCLINED
    w = 2 * np.sqrt(1000.0) * np.sin(np.arange(1, 7) * np.pi / (2 * (n + 1)))
    s = (-0.01 * w**2 + 1j * w * np.sqrt(4 - (0.01 * w) ** 2)) / 2
    np.testing.assert_allclose(md.eigenvalues, s, rtol=1e-9)
    assert np.all(md.backward_error <= 1e-12) and md.verdict == "stable"


def test_bordered_hanging_chain_vectors_purified(tmp_path):
    """The 12-link hanging chain (tests/test_sparse.py) through the bordered eigh path: 10 modes,
    every η ≤ 1e-12 (polluted vectors gave up to 2e-2); eigenvalues as the dense null-space
    reduction (rtol 1e-8)."""
    from test_sparse import LINK_CHAIN

    model = mbseig.load_case(write_case(tmp_path,
                                        LINK_CHAIN.replace('damping = 0.01', 'damping = 0.0')))
    eq = mbseig.equilibrium(model)
    dense = mbseig.linearize(model, eq)
    d = mbseig.modes(dense.M, dense.P, dense.Q)
    lin = mbseig.linearize(model, eq, sparse=True)
    md = mbseig.modes(lin.M, lin.P, lin.Q, constraints=lin.constraint_jacobian, n_modes=10)
    assert md.solver == "partial-eigh"
    assert np.all(md.backward_error <= 1e-12), md.backward_error
    np.testing.assert_allclose(md.omega_n, d.omega_n[:10], rtol=1e-8)


def test_free_free_nonproportional_jordan_block_at_zero():
    """A free-free chain with dampers between the masses only: s = 0 is a Jordan block (rigid
    translation, P x = 0).  n_modes = 3 neither raises nor loses accuracy: one rigid-body mode,
    then the two lowest against the dense path (rtol 1e-9), η ≤ 1e-12."""
    n = 100
    K = sp.diags([-1000.0 * np.ones(n - 1), np.r_[1000.0, 2000.0 * np.ones(n - 2), 1000.0],
                  -1000.0 * np.ones(n - 1)], [-1, 0, 1]).tocsr()
    cd = np.linspace(0.1, 2.0, n - 1)
    C = sp.diags([-cd, np.r_[cd, 0] + np.r_[0, cd], -cd], [-1, 0, 1]).tocsr()
    md = mbseig.modes(sp.identity(n, format="csr"), C, K, n_modes=3)
    d = mbseig.modes(np.eye(n), C.toarray(), K.toarray())
    assert md.kind[0] == "rigid-body" and md.kind.count("rigid-body") == 1 and len(md) == 3
    np.testing.assert_allclose(md.eigenvalues[1:], d.eigenvalues[1:3], rtol=1e-9)
    assert np.all(md.backward_error <= 1e-12) and md.zeta[0] == 0.0


# ---------------------------------------------------------------------------------------------
# 6. singular pencils are refused, naming the coordinates
# ---------------------------------------------------------------------------------------------
def test_singular_pencil_refused_with_coordinates():
    """x2 has no mass, damping or stiffness: det ≡ 0, refused naming x2; rotated by an
    orthogonal R, the message names the combination."""
    M, C, K = np.diag([1.0, 0, 1]), np.zeros((3, 3)), np.diag([2.0, 0, 3])
    with pytest.raises(SolverError, match=r"singular pencil: x2 has no mass"):
        mbseig.modes(M, C, K)
    R = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    with pytest.raises(SolverError, match=r"singular pencil: .*combination") as exc:
        mbseig.modes(R.T @ M @ R, R.T @ C @ R, R.T @ K @ R, coordinate_names=["a", "b", "c"])
    assert "\n" not in str(exc.value)


# ---------------------------------------------------------------------------------------------
# 7. badly scaled models: path by conditioning, sharper bound
# ---------------------------------------------------------------------------------------------
def _badly_scaled(seed=1, n=10):
    rng = np.random.default_rng(seed)
    m = np.logspace(-6, 3, n)[rng.permutation(n)]
    k = np.logspace(3, 9, n + 1)[rng.permutation(n + 1)]
    c = np.abs(rng.normal(size=n + 1)) * 1e-2

    def chain(v):
        return np.diag(v[:-1] + v[1:]) - np.diag(v[1:-1], 1) - np.diag(v[1:-1], -1)

    return np.diag(m), chain(c), chain(k)


def test_badly_scaled_chain_path_and_bound():
    """Masses 1e-6…1e3 kg, springs 1e3…1e9 N/m, light non-proportional dampers (M, K, C
    positive definite: stable by the dissipation theorem).  auto takes scaled QZ (cond(M) = 1e9
    > 1e5); against a 40-digit solve every eigenvalue is within its tolerance, the largest
    relative error of Re s is below 1e-5 (the companion path: 1e-4), and the verdict is stable
    with the least δ ≥ 100 × its tolerance (measured: δ 2.7e-6, tolerance 3.9e-9)."""
    M, C, K = _badly_scaled()
    md = mbseig.modes(M, C, K)
    assert md.solver == "qz" and "cond(M)" in md.solver_reason
    exact, _ = reference_eigenvalues(M, C, K, dps=40)
    assert_within_tolerance(md, exact)
    rel = [np.min(np.abs(exact - s)) / abs(exact[np.argmin(np.abs(exact - s))].real)
           for s in md.eigenvalues]
    assert max(rel) <= 1e-5
    i = int(np.argmin(md.delta))
    assert md.verdict == "stable" and md.delta[i] >= 100 * md.tolerance[i]


# ---------------------------------------------------------------------------------------------
# 8. listing noise
# ---------------------------------------------------------------------------------------------
def test_bicycle_below_weave_speed_no_warning():
    """The Whipple bicycle at 2 m/s (below the weave speed 4.29 m/s, Meijaard et al. 2007):
    unstable, and nothing on stderr (warnings as errors); at 5 m/s: stable."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for v, verdict in ((2.0, "unstable"), (5.0, "stable")):
            M, P, Q, ref = nlevp.bicycle(v)
            md = mbseig.modes(M, P, Q)
            assert md.verdict == verdict == ref["verdict"]
            exact, _ = reference_eigenvalues(M, P, Q, dps=30)
            assert_within_tolerance(md, exact)


def test_rigid_body_member_and_zeta():
    """A free-free chain on the companion path: the double zero is split into a ±√ε pair; the
    listed rigid-body mode is its member of largest Re s, with ζ = 0 (not 1)."""
    n = 40
    K = 1000.0 * (np.diag(np.r_[1.0, 2 * np.ones(n - 2), 1.0]) - np.eye(n, k=1) - np.eye(n, k=-1))
    md = mbseig.modes(np.eye(n), np.zeros((n, n)), K, solver="companion")
    r = md.kind.index("rigid-body")
    cluster = md.all_eigenvalues[np.abs(md.all_eigenvalues) <= md.tolerance[r]]
    assert md.eigenvalues[r].real == pytest.approx(np.max(cluster.real), abs=0.0)
    assert md.zeta[r] == 0.0 and md.stability[r] == "critical"


# ---------------------------------------------------------------------------------------------
# issue 17: every DOF accounted for; extreme magnitudes listed right or refused
# ---------------------------------------------------------------------------------------------
def test_secular_growth_at_zero_refused():
    """T(s) = [[s², s + 1], [0, s²]]: det = s⁴ but one eigenvector at s = 0 (a Jordan chain of
    length 4, response ~ t³): no listing can account for it; refused in one line."""
    M, P, Q = np.eye(2), np.array([[0.0, 1], [0, 0]]), np.array([[0.0, 1], [0, 0]])
    with pytest.raises(SolverError, match="independent rigid-body vectors"):
        mbseig.modes(M, P, Q)


@pytest.mark.parametrize("name", ["qep2", "rotating"])
def test_huge_stiffness_listed_by_scaling(name):
    """qep2 with Q = diag(1, −1, 1)·1e300: roots ±1e150 (a divergence), ±1e150 i, 1 ± i√(1e300 − 1)
    (closed form); the rotating mass with Q = −1e300 I: s ≈ ±1e150 − 3i.  Listed by scaling
    (s = γμ), every DOF accounted, verdict unstable, no NaN."""
    if name == "qep2":
        M, P, Q, ref = nlevp.qep2(1e300)
        exact = np.array(ref["eigenvalues"], complex)
    else:
        M, P, Q, ref = nlevp.rotating_mass(q=-1e300)
        exact = np.array([1e150 - 3j, -1e150 - 3j, 1e150 + 3j, -1e150 + 3j])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        md = mbseig.modes(M, P, Q)
    assert md.verdict == "unstable" and "divergence" in md.kind
    assert np.all(np.isfinite(md.eigenvalues)) and np.all(np.isfinite(md.backward_error))
    assert md.accounting["finite"] + md.accounting["infinite"] == 2 * M.shape[0]
    assert_within_tolerance(md, exact)
    assert np.min(np.abs(md.eigenvalues - 1e150)) <= 1e-12 * 1e150


@pytest.mark.parametrize("entry", [(0, 0), (0, 1), (1, 0)])
def test_huge_damping_entry_refused_not_nan(entry):
    """One P entry of 1e300 on the rotating mass: eigenvalues spread over 1e−150…1e300, beyond
    one double-precision solve.  Refused with a one-line reason, never NaN or η = 0."""
    M, P, Q, _ = nlevp.rotating_mass(p_entry=(entry, 1e300))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SolverError, match="double precision") as exc:
            mbseig.modes(M, P, Q)
    assert "\n" not in str(exc.value)


def test_subnormal_mass_never_reaches_lapack_as_illegal():
    """A mass entry 5e-324 (subnormal): cond(M) = ∞ takes scaled QZ; the massless coordinate's
    two eigenvalues are infinite (dropped, counted), the other pair ±i√(k/m) of the remaining
    1-DOF block: x₂'' + 6·0 ... = the pencil's finite pair, all accounted."""
    M, P, Q, _ = nlevp.rotating_mass()
    M = np.diag([5e-324, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        md = mbseig.modes(M, P, Q)
    assert md.solver == "qz" and md.n_infinite == 2
    assert md.accounting["finite"] + md.accounting["infinite"] == 4
    exact, n_inf = reference_eigenvalues(np.diag([0.0, 1.0]), P, Q, dps=30)
    assert n_inf == 2
    assert_within_tolerance(md, exact)


# ---------------------------------------------------------------------------------------------
# property: planted defective, near-zero and near-critical eigenvalues, 50-digit references
# ---------------------------------------------------------------------------------------------
def _block(kind, d):
    """(m, c, k) of a 1-DOF block and its two exact roots (dyadic values: no rounding)."""
    if kind == "defective":  # (s − d)²
        return (1.0, -2 * d, d * d), [d, d]
    if kind == "divergence-pair":  # s² − d²: ±d
        return (1.0, 0.0, -d * d), [d, -d]
    if kind == "critical-pair":  # s² + d²: ±i d
        return (1.0, 0.0, d * d), [1j * d, -1j * d]
    if kind == "rigid-and-rate":  # s(s + d): 0 and −d (d of either sign)
        return (1.0, d, 0.0), [0.0, -d]
    if kind == "light":  # s² + d s + 1, δ = d/2 (near-critical: d tiny of either sign)
        disc = complex(d * d - 4)
        r = np.sqrt(disc)
        return (1.0, d, 1.0), [(-d + r) / 2, (-d - r) / 2]
    raise ValueError(kind)


KINDS = ["defective", "divergence-pair", "critical-pair", "rigid-and-rate", "light"]
# d = ±2^e, e ≥ −20: d² and sums of the transformed entries (integers up to ~10 times the
# block values) stay exact in double precision, so the matrices are exactly the planted ones
DYADIC = st.builds(lambda sgn, e: sgn * 2.0**e, st.sampled_from([-1.0, 1.0]),
                   st.integers(min_value=-20, max_value=2))
UNIMODULAR = st.lists(st.integers(min_value=-1, max_value=1), min_size=3, max_size=3)


def _unimodular(n, coeffs):
    """An integer matrix of determinant 1 (upper unit-triangular times lower), exact in floats."""
    U = np.eye(n)
    L = np.eye(n)
    it = iter(coeffs * n)
    for i in range(n):
        for j in range(i + 1, n):
            U[i, j] = next(it)
            L[j, i] = next(it)
    return U @ L


@settings(max_examples=int(__import__("os").environ.get("MBSEIG_PROPERTY_EXAMPLES", 60)),
          deadline=None, suppress_health_check=[HealthCheck.too_slow],
          derandomize=not __import__("os").environ.get("MBSEIG_PROPERTY_EXAMPLES"))
@given(kinds=st.lists(st.sampled_from(KINDS), min_size=2, max_size=3),
       ds=st.lists(DYADIC, min_size=3, max_size=3), cu=UNIMODULAR, cv=UNIMODULAR,
       solver=st.sampled_from(["auto", "qz"]))
def test_verdicts_against_50_digit_references(kinds, ds, cu, cv, solver):
    """Random small systems: planted 1-DOF blocks (a defective double root, a ±d divergence pair,
    ±id, a zero with a rate −d, light (anti)damping δ = d/2, with d = ±2^e, e in −34…2) coupled
    by integer unimodular transforms U Q(s) V (same determinant, same Jordan structure, exact in
    floating point).  The 50-digit eigenvalues of the transformed matrices match the planted ones;
    mbseig's listing must (a) put every listed eigenvalue within its recorded tolerance of an
    exact one, (b) never call a system stable with an exact Re s ≥ 0, nor unstable without an
    exact Re s > 0, and (c) never classify an exact Re s > tolerance as critical or rigid-body."""
    n = len(kinds)
    # ds always draws 3 values, kinds 2 or 3: the blocks use the first len(kinds) of ds
    blocks = [_block(k, d) for k, d in zip(kinds, ds, strict=False)]
    M0 = np.diag([b[0][0] for b in blocks])
    P0 = np.diag([b[0][1] for b in blocks])
    Q0 = np.diag([b[0][2] for b in blocks])
    planted = np.array([r for b in blocks for r in b[1]], complex)
    U, V = _unimodular(n, cu), _unimodular(n, cv)
    M, P, Q = U @ M0 @ V, U @ P0 @ V, U @ Q0 @ V
    exact, n_inf = reference_eigenvalues(M, P, Q, dps=50)
    assert n_inf == 0  # the 50-digit solve agrees with the planted roots (√ of 1e-50: defective)
    assert np.max(np.min(np.abs(exact[:, None] - planted[None, :]), axis=1)) <= 1e-12
    # parts below 1e-30 are the 50-digit solve's noise around exact zeros
    exact = np.where(np.abs(exact.real) <= 1e-30, 0.0, exact.real) \
        + 1j * np.where(np.abs(exact.imag) <= 1e-30, 0.0, exact.imag)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy/scipy warning leaks from valid real input;
        # mbseig's own flag of a pair above eta_warn (also in md.flags) is a signal, not a leak
        warnings.filterwarnings("ignore", message=".*backward-error target",
                                category=RuntimeWarning)
        md = mbseig.modes(M, P, Q, solver=solver)
    assert np.all(np.isfinite(md.tolerance))
    assert_within_tolerance(md, exact)
    truth = reference_verdict(exact)
    if md.verdict == "stable":
        assert truth == "stable", (planted, md.eigenvalues)
    if md.verdict == "unstable":
        assert truth == "unstable", (planted, md.eigenvalues)
    for lam in exact[exact.real > 0]:
        k = int(np.argmin(np.abs(np.where(md.eigenvalues.imag >= 0, md.eigenvalues,
                                          np.conj(md.eigenvalues))
                                 - (lam if lam.imag >= 0 else np.conj(lam)))))
        if lam.real > md.tolerance[k]:
            assert md.stability[k] == "unstable" and md.kind[k] != "rigid-body", (lam, md.table())
