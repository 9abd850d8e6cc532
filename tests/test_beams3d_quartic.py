"""The higher-order shaft element (``element = "quartic"``, mbseig.model.beam3d_lagrange) against
closed forms, its own local matrices, complex-step derivatives and the standard element.

References:
- the pinned spinning Timoshenko shaft's characteristic equation per mode (Friswell et al. 2010
  §5.4; ``_shaft_roots`` of tests/test_beams3d_convergence.py), Cowper's κ for the tube;
- the cantilever's tip deflection under a uniform load, wL⁴/(8EI) + wL²/(2κGA) (Timoshenko
  beam theory, e.g. Wang, Reddy & Lee, *Shear Deformable Beams and Plates*, 2000, ch. 4): a
  quartic w and a cubic rotation, which the quartic element holds exactly;
- the local matrices by direct Gauss integration of the fields (``lagrange_matrices``) against
  the co-rotational element's tangent at the reference;
- complex-step derivatives (exact to rounding) of the element's force for its K and C.
"""

import numpy as np
import pytest
from conftest import CASES, write_case
from test_beams3d_convergence import _shaft_roots

from mbseig import equilibrium, linearize, load_case, modes
from mbseig.casefile import read_case
from mbseig.errors import CaseError
from mbseig.model.beam3d_lagrange import (
    LagrangeBeam3DElement,
    lagrange_matrices,
    lagrange_shape,
    load_weights,
)
from mbseig.numerics import blas_limit
from mbseig.studies import campbell as C

SHAFT = (CASES / "spinning_shaft_rayleigh.toml").read_text().replace(
    "shear_coefficient = 1e12\n", "")


def _quartic_shaft(tmp_path, n, element="quartic"):
    text = SHAFT.replace('elements = "n"', f'elements = "n"\nelement = "{element}"')
    with blas_limit(1):
        m = load_case(write_case(tmp_path, text, f"shaft_{element}{n}.toml"), n=n)
        eq = equilibrium(m)
        md = modes(linearize(m, eq, sparse=True), n_modes=4)
    return m, eq, np.sort(md.omega_n)[:4]


def _kappa(p):
    nu = p["E"] / (2 * p["G"]) - 1
    r2 = (p["di"] / p["d"]) ** 2  # Cowper 1966, table 1 (tube)
    return 6 * (1 + nu) * (1 + r2) ** 2 / ((7 + 6 * nu) * (1 + r2) ** 2 + (20 + 12 * nu) * r2)


def _errors(m, w):
    p = m.parameters
    ref = []
    for n_mode in (1, 2):
        ref += list(_shaft_roots(p, n_mode, _kappa(p)))
    return np.abs(w / np.array(ref) - 1)


def test_quartic_shaft_meets_1e8_with_a_quarter_of_the_standard_elements_nodes(tmp_path):
    """The spinning Timoshenko shaft (Ω = 500 rad/s, shear with Cowper's κ): the backward and
    forward whirl of n = 1, 2 converge as h⁸ with the quartic element (the second pair's error
    falls by 2⁸ = 256 per halving: measured 244 from 4 to 8 elements; asserted between 2⁷ and
    2⁹, the order ±1 outside the asymptotic range) and meet the closed form to 1e-8 at 10
    elements, 41 nodes (reached 1.4e-9).  The standard element with four times those nodes (164
    elements) is still above 1e-8 (about 1.5e-7: it converges as h², and needs ≈ 2400 elements
    for 1e-8, docs/beams3d.md)."""
    m, _, w4 = _quartic_shaft(tmp_path, 4)
    e4 = _errors(m, w4)
    _, _, w8 = _quartic_shaft(tmp_path, 8)
    e8 = _errors(m, w8)
    ratio = e4[2:] / e8[2:]
    assert np.all((ratio >= 2.0**7) & (ratio <= 2.0**9)), ratio
    m10, _, w10 = _quartic_shaft(tmp_path, 10)
    assert np.all(_errors(m10, w10) <= 1e-8)
    nodes = len(m10.flexible["bodies"]["shaft"]["nodes"])
    assert nodes == 41 and m10.flexible["bodies"]["shaft"]["element"] == "quartic"
    ms, _, ws = _quartic_shaft(tmp_path, 4 * (nodes - 1), "ross")
    assert len(ms.flexible["bodies"]["shaft"]["nodes"]) == 4 * (nodes - 1) + 1
    assert np.all(_errors(ms, ws)[2:] > 1e-8)


def _element(tmp_path):
    """(model, reference q, element) of the free spinning shaft at 2 quartic elements (every
    node free, so the element acts on all its frames' coordinates)."""
    text = SHAFT.replace("fixed = true", "fixed = false").replace(
        'elements = "n"', 'elements = "n"\nelement = "quartic"')
    m = load_case(write_case(tmp_path, text, "free.toml"), n=2)
    el = next(f for f in m.forces if isinstance(f, LagrangeBeam3DElement))
    assert el.idx.size == 12 * el.n_nodes
    return m, np.array(m.q_init, float), el


def _local_to_q(el, q0):
    """T: q[idx] = q0[idx] + T d for small local DOFs d of the element's nodes (translations
    R0 (u, v, w), rotations R0 (θx, θy, θz) applied to each node's triad)."""
    R0 = el.R0
    n = el.n_nodes
    T = np.zeros((12 * n, 6 * n))
    for k in range(n):
        T[12 * k:12 * k + 3, 6 * k:6 * k + 3] = R0
        for j in range(3):  # triad vector e_j moves by (R0 θ) × e_j = −[e_j]× R0 θ
            e = np.eye(3)[j]
            skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
            T[12 * k + 3 + 3 * j:12 * k + 6 + 3 * j, 6 * k + 3:6 * k + 6] = -skew @ R0
    # frames rows → the element's coordinates (the frames map is a selection here)
    Cf = el.frames.C
    return np.linalg.lstsq(Cf, T, rcond=None)[0]


def test_tangent_at_the_reference_is_the_local_element(tmp_path):
    """At the straight reference the co-rotational element's K, mass and C, mapped to the local
    DOFs, equal the local matrices integrated directly from the fields (to rounding: 1e-9 of
    each matrix's largest entry, a bound on the sums' rounding with condition ~1e6 of K)."""
    m, q0, el = _element(tmp_path)
    T = _local_to_q(el, q0)
    K, Cm = el.jacobians(q0, np.zeros_like(q0))
    em = lagrange_matrices(el.props, el.l0, el.order)
    for got, ref in ((T.T @ K @ T, em.K), (T.T @ el.mass_matrix() @ T, em.M),
                     (T.T @ Cm @ T, el.spin * em.G)):
        assert np.max(np.abs(got - ref)) <= 1e-9 * np.max(np.abs(ref))


def test_force_and_tangent_agree_with_complex_steps(tmp_path):
    """At a deformed state (every coordinate moved by up to 2e-2 of the length scale), K =
    −∂g/∂q (at q̇ = 0, where the spin's ∂/∂q vanishes) and C = −∂g/∂q̇ equal complex-step
    derivatives of the force (exact to rounding; 1e-10 of the largest entry)."""
    m, q0, el = _element(tmp_path)
    rng = np.random.default_rng(3)
    q = q0 + 2e-2 * rng.standard_normal(q0.size)
    qd = rng.standard_normal(q0.size)
    idx = el.idx
    zero = np.zeros_like(q)
    K, _ = el.jacobians(q, zero)
    _, Cm = el.jacobians(q, qd)
    h = 1e-30
    K_cs = np.empty_like(K)
    C_cs = np.empty_like(K)
    for j, i in enumerate(idx):
        dq = np.zeros(q.size, complex)
        dq[i] = 1j * h
        K_cs[:, j] = -el.force(q + dq, zero.astype(complex)).imag / h
        C_cs[:, j] = -el.force(q.astype(complex), qd + dq).imag / h
    assert np.max(np.abs(K - K_cs)) <= 1e-10 * np.max(np.abs(K))
    assert np.max(np.abs(Cm - C_cs)) <= 1e-10 * np.max(np.abs(Cm))


def test_energy_is_invariant_under_rigid_motion(tmp_path):
    """The deformations (and so the energy and the mean axial force) of a deformed element do
    not change under a rigid rotation and translation of all its nodes (1e-12 relative)."""
    m, q0, el = _element(tmp_path)
    rng = np.random.default_rng(5)
    delta0 = el.local_deformation(q0)
    assert np.max(np.abs(delta0)) <= 1e-14
    # a deformed state with orthonormal triads: each node rotated a little, moved a little
    q = q0.copy()
    z = el.frames(q)
    n = el.n_nodes

    def rot(v):
        t = np.linalg.norm(v)
        k = v / t
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K

    frames = z.reshape(n, 4, 3)
    deformed = np.array([np.vstack([f[0] + 1e-3 * rng.standard_normal(3),
                                    (rot(1e-2 * rng.standard_normal(3)) @ f[1:].T).T])
                         for f in frames])
    Q, c = rot(np.array([0.3, -1.1, 0.7])), np.array([0.2, -0.5, 1.0])
    moved = np.array([np.vstack([Q @ f[0] + c, (Q @ f[1:].T).T]) for f in deformed])
    Cf = el.frames.C
    q1, q2 = q.copy(), q.copy()
    q1[el.idx] = np.linalg.lstsq(Cf, deformed.ravel() - el.frames.d, rcond=None)[0]
    q2[el.idx] = np.linalg.lstsq(Cf, moved.ravel() - el.frames.d, rcond=None)[0]
    d1, d2 = el.local_deformation(q1), el.local_deformation(q2)
    assert np.max(np.abs(d1)) > 1e-4
    assert np.max(np.abs(d1 - d2)) <= 1e-12 * np.max(np.abs(d1))
    assert abs(el.strain_energy(q1) - el.strain_energy(q2)) <= 1e-12 * el.strain_energy(q1)


def test_shape_functions_and_load_weights():
    """The Lagrange basis is a partition of unity that interpolates its nodes, its derivative
    sums to zero, and its integrals are the Newton–Cotes weights 7, 32, 12, 32, 7 over 90."""
    xi = np.linspace(0.0, 1.0, 5)
    N, dN = lagrange_shape(4, xi)
    np.testing.assert_allclose(N, np.eye(5), atol=1e-14)
    x = np.linspace(0.0, 1.0, 13)
    N, dN = lagrange_shape(4, x)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(dN.sum(axis=1), 0.0, atol=1e-12)
    np.testing.assert_allclose(load_weights(4), np.array([7, 32, 12, 32, 7]) / 90, atol=1e-15)


CANTILEVER = """schema_version = 1
dimension = 3
gravity = [0.0, 0.0, "-g"]
[parameters]
g = 1e-3
L = 0.8
d = 0.06
[[points]]
name = "A"
position = [0.0, 0.0, 0.0]
fixed = true
[[points]]
name = "B"
position = ["L", 0.0, 0.0]
[[beams]]
name = "rod"
points = ["A", "B"]
E = 2.0e11
G = 7.7e10
rho = 7800.0
section = { shape = "circle", d = "d" }
theory = "timoshenko"
element = "quartic"
elements = 2
ends = ["clamped", "free"]
"""


def test_quartic_cantilever_holds_the_exact_deflection_under_its_weight(tmp_path):
    """A Timoshenko cantilever under its own weight w = ρAg: the exact deflection is a quartic
    with a cubic rotation, so two quartic elements (consistent loads) give the tip deflection
    wL⁴/(8EI) + wL²/(2κGA) to rounding and to the model's geometric nonlinearity (the tip moves
    ~1e-8 L: relative effects ~1e-16); asserted 1e-9 relative, the equilibrium's residual
    tolerance times the stiffness's condition."""
    m = load_case(write_case(tmp_path, CANTILEVER))
    eq = equilibrium(m)
    p = m.flexible["bodies"]["rod"]
    w = p["rho"] * p["A"] * 1e-3
    L, EI, kGA = 0.8, p["E"] * p["Iy"], p["shear_coefficient"] * p["G"] * p["A"]
    exact = w * L**4 / (8 * EI) + w * L**2 / (2 * kGA)
    tip = m.coordinate_names.index("B.z")
    assert abs(-eq.q[tip] / exact - 1) <= 1e-9


def test_column_geometric_stiffness_agrees_with_the_standard_element(tmp_path):
    """The compressed column (cases/column_buckling_3d.toml at half its Euler load, shortened
    by P/EA = 1.2e-4) as a Timoshenko beam: the quartic element's lowest two bending pairs at 8
    elements equal the standard element's Richardson limit (h² then h⁴ over 24, 48, 96
    elements, an independent discretization; the two agree to 7e-11 on the first pair, so the
    limit's own error is below the 1e-8 asserted) to 1e-8, and the second
    pair converges as h⁸ (error ratio from 4 to 8 elements within [2⁷, 2⁹]; measured 277): the
    geometric stiffness and the stretched shear strain are consistent (with the shear read on
    the unstretched offsets the order was 2)."""
    text = (CASES / "column_buckling_3d.toml").read_text().replace(
        'theory = "euler-bernoulli"', 'theory = "timoshenko"')

    def lowest(element, n):
        t = text.replace('elements = "n"', f'elements = "n"\nelement = "{element}"')
        with blas_limit(1):
            mm = load_case(write_case(tmp_path, t, f"col_{element}{n}.toml"), n=n)
            md = modes(linearize(mm, equilibrium(mm), sparse=True), n_modes=6)
        return np.sort(md.omega_n)[[0, 2]]  # one of each equal pair

    e = {n: lowest("ross", n) for n in (24, 48, 96)}
    r1, r2 = (4 * e[48] - e[24]) / 3, (4 * e[96] - e[48]) / 3
    ref = (16 * r2 - r1) / 15
    e4, e8 = (np.abs(lowest("quartic", n) / ref - 1) for n in (4, 8))
    assert np.all(e8 <= 1e-8)
    assert 2.0**7 <= e4[1] / e8[1] <= 2.0**9


@pytest.mark.parametrize("edit, message", [
    ('element = "quartic"', None),
    ('element = "cubic"', "element must be one of ross, quartic"),
])
def test_element_field(tmp_path, edit, message):
    """``element``: a known name is used (the record says which), an unknown one is refused in
    one line naming the beam; the quartic element on an Euler–Bernoulli beam is refused."""
    text = SHAFT.replace('elements = "n"', f'elements = "n"\n{edit}')
    path = write_case(tmp_path, text)
    if message is None:
        m = load_case(path, n=3)
        assert m.flexible["bodies"]["shaft"]["element"] == "quartic"
        assert len(m.flexible["bodies"]["shaft"]["nodes"]) == 13
        return
    with pytest.raises(CaseError, match=message) as e:
        load_case(path)
    assert "beams[0]" in str(e.value) or "shaft" in str(e.value)


def test_euler_bernoulli_quartic_refused_and_auto_defaults(tmp_path):
    """``element = "quartic"`` needs the Timoshenko theory (refused otherwise, naming the
    theory); ``elements = "auto"`` on a Timoshenko beam takes the quartic element, a count the
    standard one."""
    eb = SHAFT.replace('theory = "timoshenko"', 'theory = "euler-bernoulli"').replace(
        'elements = "n"', 'elements = "n"\nelement = "quartic"')
    with pytest.raises(CaseError, match="needs theory"):
        load_case(write_case(tmp_path, eb, "eb.toml"))
    auto = load_case(write_case(tmp_path, SHAFT.replace('elements = "n"', 'elements = "auto"'),
                                "auto.toml"))
    assert auto.flexible["bodies"]["shaft"]["element"] == "quartic"
    count = load_case(write_case(tmp_path, SHAFT, "count.toml"), n=4)
    assert count.flexible["bodies"]["shaft"]["element"] == "ross"


def test_campbell_one_build_equals_builds_per_point_with_quartic_shafts(tmp_path, monkeypatch):
    """A speed sweep of the spinning shaft meshed with 2 quartic elements: the one-build path
    (the spin replaced element by element) gives exactly the numbers of a build per point."""
    text = SHAFT.replace('elements = "n"', 'elements = 2\nelement = "quartic"')
    spec = read_case(write_case(tmp_path, text))
    speeds = np.linspace(0.0, 500.0, 3)
    a = C.campbell(spec, "Omega", speeds)
    assert a.reuse.startswith("one build")
    orig = C.SpeedLine.__init__

    def declined(self, *args, **kw):
        orig(self, *args, **kw)
        self.reason = "declined by the test"

    monkeypatch.setattr(C.SpeedLine, "__init__", declined)
    b = C.campbell(spec, "Omega", speeds)
    assert b.reuse == "built at every point"
    np.testing.assert_array_equal(a.tracks, b.tracks)
    assert a.whirl == b.whirl
