"""The co-rotational element on frame nodes: exact tangent, rigid-motion invariance, and its
linearization about the straight reference equal to the standard local element.

References: complex-step derivatives (Squire & Trapp 1998; error ~1e-16, tolerance 1e-9
relative), the local matrices of :func:`mbseig.model.beam3d.element_matrices` (themselves
equal to ROSS, tests/test_beams3d_element.py), exact identities for rigid motions.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mbseig.model.affine import Affine
from mbseig.model.beam3d import (
    Beam3DElement,
    BeamProperties3D,
    section_frame,
    section_properties,
)


def _props(theory="timoshenko"):
    sp = section_properties(shape="rectangle", dims={"b": 0.02, "h": 0.05}, nu=0.3)
    return BeamProperties3D(E=2.1e11, G=2.1e11 / 2.6, rho=7800.0, A=sp["A"], Iy=sp["Iy"],
                            Iz=sp["Iz"], J=sp["J"], kappa_y=sp["kappa"], kappa_z=sp["kappa"],
                            theory=theory)


START, END, ORIENT = np.array([0.1, -0.2, 0.3]), np.array([0.5, 0.1, 0.6]), [0.0, 0.0, 1.0]


def _element(theory="timoshenko", spin=0.0):
    R0 = section_frame(START, END, ORIENT)
    frames = Affine(np.arange(24), np.eye(24), np.zeros(24))
    return Beam3DElement("e", frames, _props(theory), float(np.linalg.norm(END - START)), R0,
                         spin)


def _reference():
    return np.concatenate([START, np.eye(3).ravel(), END, np.eye(3).ravel()])


def _deformed(rng, scale=0.05):
    """A configuration with large rigid motion and a moderate deformation (triads rotated by
    different rotations; points moved)."""
    q = _reference()
    Rr = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
    out = []
    for k in range(2):
        r = Rr @ q[12 * k:12 * k + 3] + rng.normal(size=3) * scale * 0.1
        Rk = Rr @ Rotation.from_rotvec(rng.normal(size=3) * scale).as_matrix()
        out.append(np.concatenate([r, Rk.T.ravel()]))  # rows of Rkᵀ are the rotated u, v, w
    return np.concatenate(out)


@pytest.mark.parametrize("theory", ["timoshenko", "euler-bernoulli"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tangent_against_complex_step(theory, seed):
    """K = −∂g/∂q and g = −∂U/∂q at deformed states, also off the triad manifold (the Hessians
    are exact everywhere): complex step, 1e-9 of the largest entry."""
    rng = np.random.default_rng(seed)
    el = _element(theory)
    q = _deformed(rng) + (rng.normal(size=24) * 1e-3 if seed == 2 else 0.0)
    qd = np.zeros(24)
    K, _ = el.jacobians(q, qd)
    h = 1e-30
    Kcs = np.empty((24, 24))
    gU = np.empty(24)
    for j in range(24):
        qc = q.astype(complex)
        qc[j] += 1j * h
        Kcs[:, j] = -el.force(qc, qd).imag / h
        gU[j] = -el.strain_energy(qc).imag / h
    assert np.max(np.abs(K - Kcs)) <= 1e-9 * np.max(np.abs(K))
    g = el.force(q, qd)
    assert np.max(np.abs(g - gU)) <= 1e-9 * np.max(np.abs(g))
    assert np.max(np.abs(K - K.T)) <= 1e-9 * np.max(np.abs(K))  # conservative


def test_rigid_motion_is_strain_free():
    """Any rigid motion of the reference leaves p = 0 and g = 0; of a deformed state it leaves
    the deformations unchanged (dot products of co-rotated vectors): exact to 1e-12."""
    rng = np.random.default_rng(5)
    el = _element()
    R = Rotation.from_rotvec([2.0, -1.0, 0.7]).as_matrix()
    t = rng.normal(size=3)

    def moved(q):
        out = []
        for k in range(2):
            r = R @ q[12 * k:12 * k + 3] + t
            tri = (R @ q[12 * k + 3:12 * k + 12].reshape(3, 3).T).T
            out.append(np.concatenate([r, tri.ravel()]))
        return np.concatenate(out)

    q0 = _reference()
    assert np.max(np.abs(el.local_deformation(moved(q0)))) <= 1e-12
    assert np.max(np.abs(el.force(moved(q0), np.zeros(24)))) <= 1e-12 * el.props.E * 1e-6
    qd = _deformed(rng)
    assert np.allclose(el.local_deformation(moved(qd)), el.local_deformation(qd), rtol=0,
                       atol=1e-12)


def _tangent_basis(q0, R0):
    """T₀ (24×12): frame-coordinate velocities of the local DOFs [u, v, w, θx, θy, θz] per node
    (translations R₀ δ, triad vectors δe = (R₀ θ) × e)."""
    T0 = np.zeros((24, 12))
    for k in range(2):
        o, c = 12 * k, 6 * k
        T0[o:o + 3, c:c + 3] = R0
        for a in range(3):
            omega = R0[:, a]
            for j in range(3):
                e = q0[o + 3 + 3 * j:o + 6 + 3 * j]
                T0[o + 3 + 3 * j:o + 6 + 3 * j, c + 3 + a] = np.cross(omega, e)
    return T0


@pytest.mark.parametrize("theory", ["timoshenko", "euler-bernoulli"])
def test_linearization_is_the_standard_element(theory):
    """At the straight, unstressed reference: T₀ᵀ K T₀ = K_loc, T₀ᵀ M T₀ = M_loc and
    T₀ᵀ C T₀ = Ω G_loc for an oblique element with a rectangular section (1e-12 relative)."""
    Omega = 250.0
    el = _element(theory, spin=Omega)
    q0 = _reference()
    T0 = _tangent_basis(q0, el.R0)
    K, C = el.jacobians(q0, np.zeros(24))
    M = el.mass(q0)
    em = el.matrices
    for ours, ref in ((T0.T @ K @ T0, em.K), (T0.T @ M @ T0, em.M), (T0.T @ C @ T0, Omega * em.G)):
        assert np.max(np.abs(ours - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_axial_preload_adds_consistent_geometric_stiffness():
    """Stretched uniformly by ε (triads unchanged), the lateral tangent is K_loc + N K_g, N = EA ε,
    up to the change of length in the bending terms, O(ε K_bend); a section with
    EI/(EA L²) = 6e-10 makes that 1e-8 of N K_g (asserted 1e-6)."""
    props = BeamProperties3D(E=2.1e11, G=8e10, rho=7800.0, A=1e-2, Iy=1e-12, Iz=2e-12,
                             J=3e-12, theory="euler-bernoulli")
    R0 = section_frame(START, END, ORIENT)
    l0 = float(np.linalg.norm(END - START))
    el = Beam3DElement("e", Affine(np.arange(24), np.eye(24), np.zeros(24)), props, l0, R0)
    eps = 1e-8  # the O(ε) change of the chord terms (N/l vs N/l₀) is then 1e-8 of N K_g
    q = _reference()
    q[12:15] = START + (1 + eps) * l0 * R0[:, 0]
    N = el.axial_force(q)
    assert N == pytest.approx(props.E * props.A * eps, rel=1e-6)  # rounding of l − l₀: 1e-16/ε
    T0 = _tangent_basis(q, R0)
    K, _ = el.jacobians(q, np.zeros(24))
    em = el.matrices
    lat = [1, 2, 4, 5, 7, 8, 10, 11]
    Kt = (T0.T @ K @ T0)[np.ix_(lat, lat)]
    ref = (em.K + N * em.Kg)[np.ix_(lat, lat)]
    geo = N * em.Kg[np.ix_(lat, lat)]
    assert np.max(np.abs(Kt - ref)) <= 1e-6 * np.max(np.abs(geo))


def test_gyroscopic_force_is_linear_in_rates():
    """g_gyro = −Ω Tᵀ G T q̇ equals −C q̇ (C from jacobians) and does no work (q̇ᵀ g = 0)."""
    rng = np.random.default_rng(3)
    el = _element(spin=300.0)
    el0 = _element(spin=0.0)
    q = _deformed(rng)
    qd = rng.normal(size=24)
    g_el = el0.force(q, qd)
    g = el.force(q, qd) - g_el  # the elastic part cancels to its rounding, 1e-16 of g_el
    _, C = el.jacobians(q, qd)
    assert np.allclose(g, -C @ qd, rtol=0, atol=1e-14 * np.max(np.abs(g_el)))
    assert abs(qd @ (C @ qd)) <= 1e-12 * np.linalg.norm(qd) * np.linalg.norm(C @ qd)
