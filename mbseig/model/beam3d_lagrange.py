"""The higher-order spatial shaft element: Lagrange interpolation of order p on p + 1 frame nodes,
co-rotational, with the shear integrated reduced (``element = "quartic"``: p = 4).

Why.  The standard element (:mod:`mbseig.model.beam3d`, ROSS's and Nelson's) interpolates the
Timoshenko fields interdependently: exact for end loads, but its shear strain is constant in an
element, so under the distributed inertia load of a mode the shear energy errs by O(h²) and the
frequencies converge only as h² once shear counts (docs/beams3d.md, "Convergence").  Here the
displacements u, v, w and the section rotations θx, θy, θz are independent Lagrange polynomials
of degree p on p + 1 equally spaced nodes, and the shear energy is integrated with p Gauss points
(the shear strain projected onto degree p − 1: free of shear locking for slender shafts, the
assumed-strain reading of reduced integration; Prathap, *The Finite Element Method in Structural
Mechanics*, 1993, ch. 5).  Every field is then approximated to O(h^p) in energy norm, so the
frequencies converge as h^(2p): h⁸ for the quartic element (measured: tests/
test_beams3d_quartic.py, docs/beams3d.md).

Local linear element (x along the beam, node k at x_k = k l₀ / p, DOFs per node
[u, v, w, θx, θy, θz] as the standard element's; :func:`lagrange_matrices`):

    U = ½ ∫ EA u′² + GJ θx′² + EI_z θz′² + EI_y θy′² dx                      (p + 1 Gauss points)
      + ½ ∫ κ_y GA (v′ − θz)² + κ_z GA (w′ + θy)² dx                         (p Gauss points)
    T = ½ ∫ ρA (u̇² + v̇² + ẇ²) + ρ I_p θ̇x² + ρ I_y θ̇y² + ρ I_z θ̇z² dx

Timoshenko only (``theory = "timoshenko"``, rotary inertia on): Euler–Bernoulli bending needs a
slope continuous between elements, which the standard element's cubic Hermite interpolation
has and independent Lagrange fields have not.

Nonlinear element (:class:`LagrangeBeam3DElement`).  The nodes are frames [r; u; v; w] as the
standard element's, mapped to the section axes z_k = [r_k; a_k; b_k; c_k].  The deformations
(6p of them, all invariant under rigid motions and zero at the reference):

    u_c = l − l₀,  l = |r_p − r₀|, e = (r_p − r₀)/l                 chord elongation
    a_k = π_k·a_k,  v_k = π_k·b_k,  w_k = π_k·c_k  (0 < k < p)      interior node offsets
        π_k = r_k − (1 − k/p) r₀ − (k/p) r_p                          from the chord
    t_k = ½ (c₀·b_k − b₀·c_k)  (0 < k ≤ p)                           twist relative to node 0
    φz_k = −e·b_k,  φy_k = e·c_k  (0 ≤ k ≤ p)                       rotations relative to chord

are, to first order at the reference, the local DOFs of the chord frame (node 0 at the origin,
node p on the x axis): u_k = (k/p) u_c + a_k, θx_k = t_k, v_k, w_k, θz_k = φz_k, θy_k = φy_k.
The interior transverse offsets enter in units of the chord's stretch λ = l/l₀, v̂_k = v_k/λ and
ŵ_k = w_k/λ, so that their slopes per reference length are the actual slopes of the axis.  The
strain energy is the linear element's on those, with the shear strains v̂′ − θz and ŵ′ + θy (the
angle between the section and the stretched axis), except the axial term, which keeps the
transverse slopes to second order as the stretched line element does,

    ε(x) = u′ + (v′² + w′²)/(2λ) = u′ + ½ λ (v̂′² + ŵ′²),

integrated with 2p − 1 Gauss points (exact): an axial force N adds N ∫ v̂′² + ŵ′² dx on the
interior offsets and, through the chord length's Hessian, N/l (I − eeᵀ) on the chord: the
consistent geometric stiffness of the extensible beam (columns buckle at the Euler load of the
mesh).  Without the stretch in the shear strain a compressed element would read the chord's
shortening as shear, an O(h²) error in the loaded frequencies (measured on the column at half
its Euler load, second bending pair: 2.2e-6 → 8.1e-9 from 4 to 8 elements with it, order 8;
2.3e-5 → 6.6e-6 without, order 2; tests/test_beams3d_quartic.py).

Mass.  The section at x is r(x) + y b(x) + z c(x) with r, b, c interpolated from the nodes (exact
for a rigid motion of the element), so T = ½ Σ_jk m_jk (ρA ṙ_j·ṙ_k + ρI_z ḃ_j·ḃ_k +
ρI_y ċ_j·ċ_k), m_jk = ∫ N_j N_k dx: a constant mass matrix on the nodes' coordinates (the
natural coordinates' property), equal to the local T above at the reference (|ḃ|² = θ̇x² + θ̇z²,
|ċ|² = θ̇x² + θ̇y²).  No velocity terms.

Spin Ω about the element's axis: the moment −ρI_pΩ ȧ per unit length (the law of the standard
element and of the rigid ``rotor``) does the virtual work ∫ m·(a × δa) dx with the interpolated
axis, so the force on a_k is ρI_pΩ Σ_j m_kj (a_k × ȧ_j) and C = −∂g/∂ȧ has the blocks
−ρI_pΩ m_kj [a_k]× (skew at the straight reference; its ∂/∂q, ∝ Ω q̇, is left out as in the
standard element: exact at rest).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.polynomial.legendre import leggauss

from ..errors import EquilibriumError
from .affine import Affine
from .base import Force
from .beam3d_local import BeamProperties3D

__all__ = ["ELEMENT_ORDERS", "LagrangeBeam3DElement", "LagrangeMatrices", "lagrange_matrices",
           "lagrange_shape", "load_weights", "nodes_to_sections"]

#: element name in case files → polynomial order p (p + 1 nodes an element)
ELEMENT_ORDERS = {"quartic": 4}


def lagrange_shape(p: int, xi: np.ndarray):
    """(N, N′) of the degree-p Lagrange basis on p + 1 equally spaced nodes of [0, 1] at the
    points ``xi`` (arrays (len(xi), p + 1); N′ per unit of ξ)."""
    nodes = np.linspace(0.0, 1.0, p + 1)
    xi = np.asarray(xi, float)
    N = np.ones((xi.size, p + 1))
    dN = np.zeros((xi.size, p + 1))
    for j in range(p + 1):
        others = [m for m in range(p + 1) if m != j]
        for m in others:
            N[:, j] *= (xi - nodes[m]) / (nodes[j] - nodes[m])
        for k in others:
            t = np.full(xi.size, 1.0 / (nodes[j] - nodes[k]))
            for m in others:
                if m != k:
                    t *= (xi - nodes[m]) / (nodes[j] - nodes[m])
            dN[:, j] += t
    return N, dN


def _gauss(n):
    """Gauss–Legendre points and weights on [0, 1]."""
    x, w = leggauss(n)
    return (x + 1.0) / 2.0, w / 2.0


def load_weights(p: int) -> np.ndarray:
    """∫₀¹ N_k dξ: a uniform load's consistent share per node (Newton–Cotes: 7, 32, 12, 32,
    7 over 90 for p = 4)."""
    x, w = _gauss(p + 1)
    return w @ lagrange_shape(p, x)[0]


# ---------------------------------------------------------------------------------------------
# the local linear element
@dataclass(frozen=True)
class LagrangeMatrices:
    """Local matrices of one element on d = [u, v, w, θx, θy, θz] per node (module docstring):
    M, K (the axial term included), G (the spin's, C = Ω G), and the deformation data of the
    nonlinear element: ``Lam`` (6(p+1) × 6p, d = Λ δ at the reference), ``K_rest`` (Λᵀ K Λ
    without the axial term), the axial Gauss rule (``axial_w``, ``axial_c``, ``axial_a``: ε_g =
    c_gᵀδ + ½ Σ (a_gᵀδ)² over the two transverse planes) and the nodes' mass m_jk."""

    p: int
    L: float
    M: np.ndarray
    K: np.ndarray
    G: np.ndarray
    Lam: np.ndarray
    K_rest: np.ndarray
    axial_w: np.ndarray
    axial_c: np.ndarray
    axial_a: np.ndarray
    m_nodes: np.ndarray


def _deformation_map(p):
    """Λ: local d (6(p+1)) from the deformations δ (6p) in the order of the module docstring,
    [u_c, a_1..a_{p−1}, t_1..t_p, v_1..v_{p−1}, φz_0..φz_p, w_1..w_{p−1}, φy_0..φy_p]."""
    n = p + 1
    Lam = np.zeros((6 * n, 6 * p))
    col = 0
    Lam[6 * p + 0, col] = 1.0  # u_p = u_c
    for k in range(1, p):
        Lam[6 * k + 0, col] = k / p
    col += 1
    for k in range(1, p):  # a_k
        Lam[6 * k + 0, col] = 1.0
        col += 1
    for k in range(1, p + 1):  # t_k = θx_k
        Lam[6 * k + 3, col] = 1.0
        col += 1
    for trans, rot in ((1, 5), (2, 4)):  # (v, θz), (w, θy)
        for k in range(1, p):
            Lam[6 * k + trans, col] = 1.0
            col += 1
        for k in range(n):
            Lam[6 * k + rot, col] = 1.0
            col += 1
    assert col == 6 * p
    return Lam


def _field(N, comp):
    """(ng, 6n) rows selecting component ``comp`` of d through the nodal basis N (ng, n)."""
    out = np.zeros((N.shape[0], 6 * N.shape[1]))
    out[:, comp::6] = N
    return out


@functools.lru_cache(maxsize=64)
def _matrices_cached(key, p, L):
    E, G, rho, A, Iy, Iz, J, ky, kz = key
    Ip = Iy + Iz
    xf, wf = _gauss(p + 1)
    xr, wr = _gauss(p)
    xa, wa = _gauss(2 * p - 1)
    N, dN = lagrange_shape(p, xf)
    dN = dN / L
    wf = wf * L
    Nr, dNr = lagrange_shape(p, xr)
    dNr = dNr / L
    wr = wr * L

    def quad(F, w):
        return (F.T * w) @ F

    K_axial = E * A * quad(_field(dN, 0), wf)
    K_rest = (G * J * quad(_field(dN, 3), wf) + E * Iz * quad(_field(dN, 5), wf)
              + E * Iy * quad(_field(dN, 4), wf)
              + ky * G * A * quad(_field(dNr, 1) - _field(Nr, 5), wr)
              + kz * G * A * quad(_field(dNr, 2) + _field(Nr, 4), wr))
    M = (rho * A * sum(quad(_field(N, c), wf) for c in (0, 1, 2))
         + rho * Ip * quad(_field(N, 3), wf) + rho * Iy * quad(_field(N, 4), wf)
         + rho * Iz * quad(_field(N, 5), wf))
    Py, Pz = _field(N, 4), _field(N, 5)
    Gm = rho * Ip * ((Py.T * wf) @ Pz - (Pz.T * wf) @ Py)
    Lam = _deformation_map(p)
    Na, dNa = lagrange_shape(p, xa)
    dNa = dNa / L
    out = LagrangeMatrices(
        p=p, L=L, M=M, K=K_axial + K_rest, G=Gm, Lam=Lam, K_rest=Lam.T @ K_rest @ Lam,
        axial_w=E * A * wa * L, axial_c=_field(dNa, 0) @ Lam,
        axial_a=np.stack([_field(dNa, 1) @ Lam, _field(dNa, 2) @ Lam]),
        m_nodes=quad(N, wf))
    for a in (out.M, out.K, out.G, out.Lam, out.K_rest, out.axial_w, out.axial_c, out.axial_a,
              out.m_nodes):
        a.setflags(write=False)
    return out


def lagrange_matrices(props: BeamProperties3D, L: float, p: int = 4) -> LagrangeMatrices:
    """The local matrices of one uniform element of length L and order p (module docstring)."""
    if props.theory != "timoshenko" or not props.has_rotary_inertia:
        raise ValueError("the Lagrange element needs the Timoshenko theory (shear and rotary "
                         "inertia): Euler-Bernoulli bending needs a continuous slope")
    pr = props
    key = (pr.E, pr.G, pr.rho, pr.A, pr.Iy, pr.Iz, pr.J, pr.kappa_y, pr.kappa_z)
    return _matrices_cached(key, int(p), float(L))


# ---------------------------------------------------------------------------------------------
# the co-rotational element on p + 1 frame nodes
def nodes_to_sections(R0: np.ndarray, n: int) -> np.ndarray:
    """S (12n × 12n): [r; a; b; c] per node (section axes) = S [r; u; v; w] per node (frame)."""
    node = np.zeros((12, 12))
    node[:3, :3] = np.eye(3)
    node[3:, 3:] = np.kron(np.asarray(R0, float).T, np.eye(3))
    return np.kron(np.eye(n), node)


def _selector(n, k, part):
    """3 × 12n selector of part (0 r, 1 a, 2 b, 3 c) of node k in z."""
    S = np.zeros((3, 12 * n))
    S[:, 12 * k + 3 * part:12 * k + 3 * part + 3] = np.eye(3)
    return S


@functools.lru_cache(maxsize=8)
def _layout(p):
    """Selectors and the constant Hessians of the bilinear deformations of an order-p element:
    (D, pairs, H_bilinear, dots) with D = r_p − r₀ (3 × 12n); pairs: (row, X, Y) for the rows
    δ_row = (X z)·(Y z); dots: (row, sign, X) for δ_row = sign e·(X z)."""
    n = p + 1
    R = [_selector(n, k, 0) for k in range(n)]
    A = [_selector(n, k, 1) for k in range(n)]
    B = [_selector(n, k, 2) for k in range(n)]
    C = [_selector(n, k, 3) for k in range(n)]
    D = R[p] - R[0]
    pi = {k: R[k] - (1 - k / p) * R[0] - (k / p) * R[p] for k in range(1, p)}
    pairs, dots = [], []
    row = 1
    for k in range(1, p):
        pairs.append((row, pi[k], A[k], 1.0))
        row += 1
    for k in range(1, p + 1):  # t_k = ½ (c₀·b_k − b₀·c_k)
        pairs.append((row, C[0], B[k], 0.5))
        pairs.append((row, B[0], C[k], -0.5))
        row += 1
    for X, sign in ((B, -1.0), (C, 1.0)):
        off = 2 if sign < 0 else 3
        for k in range(1, p):
            pairs.append((row, pi[k], (B if off == 2 else C)[k], 1.0))
            row += 1
        for k in range(n):
            dots.append((row, sign, X[k]))
            row += 1
    assert row == 6 * p
    H = np.zeros((6 * p, 12 * n, 12 * n))
    for r, X, Y, c in pairs:
        H[r] += c * (X.T @ Y + Y.T @ X)
    for a in (D, H):
        a.setflags(write=False)
    return D, H, tuple(dots)


@functools.lru_cache(maxsize=8)
def _transverse_rows(p):
    """Rows of the interior transverse offsets v_k, w_k in δ (module docstring's order)."""
    v0 = 2 * p
    w0 = v0 + (p - 1) + (p + 1)
    return np.array(list(range(v0, v0 + p - 1)) + list(range(w0, w0 + p - 1)))


@dataclass(frozen=True, eq=False)
class LagrangeBeam3DElement(Force):
    """One co-rotational element of order p between p + 1 frame nodes (module docstring).

    ``frames`` maps q to the node frames [r₀; u₀; v₀; w₀; …; r_p; …] (12(p + 1) rows; triads
    equal to the global axes at the reference); ``R0`` the reference section frame; ``spin`` Ω
    about the element axis (rad/s).  Its mass is constant: :meth:`mass_matrix`.
    """

    name: str
    frames: Affine
    props: BeamProperties3D
    l0: float
    R0: np.ndarray
    order: int = 4
    spin: float = 0.0
    affine_field = "frames"
    stiff_structure = True

    def __post_init__(self):
        p = int(self.order)
        n = p + 1
        if self.frames.C.shape[0] != 12 * n:
            raise ValueError(f"an order-{p} element needs {n} frames (12 rows each)")
        em = lagrange_matrices(self.props, float(self.l0), p)
        S = nodes_to_sections(self.R0, n)
        nodes = Affine(self.frames.idx, S @ self.frames.C, S @ self.frames.d)
        pr = self.props
        per_node = np.diag(np.concatenate([np.full(3, pr.rho * pr.A), np.zeros(3),
                                           np.full(3, pr.rho * pr.Iz), np.full(3, pr.rho * pr.Iy)]))
        Mz = np.kron(em.m_nodes, per_node)
        Cn = nodes.C
        mass = Cn.T @ Mz @ Cn
        mass.setflags(write=False)
        object.__setattr__(self, "_nodes", nodes)
        object.__setattr__(self, "_em", em)
        object.__setattr__(self, "_mass", mass)

    @property
    def matrices(self) -> LagrangeMatrices:
        return self._em

    @property
    def n_nodes(self) -> int:
        return int(self.order) + 1

    # -- deformations ------------------------------------------------------------------------
    def _measures(self, z, hessians=True):
        """δ (6p,), B = ∂δ/∂z (6p, 12n) and the Hessians (6p, 12n, 12n) (None without
        ``hessians``)."""
        p = int(self.order)
        D, H_bil, dots = _layout(p)
        d = D @ z
        length = np.sqrt(d @ d)
        if length.real == 0.0:
            raise EquilibriumError("beam element collapsed to zero length", element=self.name)
        e = d / length
        P = np.eye(3) - np.outer(e, e)
        B = H_bil @ z  # (6p, 12n): the bilinear rows' gradients; δ_row = ½ zᵀ H z
        delta = 0.5 * (B @ z)
        delta[0] = length - self.l0
        B[0] = e @ D
        H = np.array(H_bil, dtype=z.dtype) if hessians else None
        if hessians:
            H[0] = D.T @ (P / length) @ D
        for row, sgn, X in dots:
            x = X @ z
            ex = e @ x
            delta[row] = sgn * ex
            B[row] = sgn * ((x - ex * e) / length @ D + e @ X)
            if hessians:
                Hdd = -(np.outer(x, e) + np.outer(e, x)
                        + ex * (np.eye(3) - 3 * np.outer(e, e))) / (length * length)
                Hdx = D.T @ (P / length) @ X
                H[row] = sgn * (D.T @ Hdd @ D + Hdx + Hdx.T)
        return delta, B, H

    def local_deformation(self, q):
        """δ: the deformations in the order of the module docstring."""
        return self._measures(self._nodes(q), hessians=False)[0]

    def _strains(self, dh):
        """(ε_g, ∇ε_g, the slopes (2, ng), s_g) at the axial Gauss points on the scaled
        deformations δ̂: ε_g = c_gᵀδ̂ + λ s_g, s_g = ½ Σ (a_gᵀδ̂)², λ = l/l₀ (module docstring)."""
        em = self._em
        a = np.einsum("pgi,i->pg", em.axial_a, dh)
        s = 0.5 * (a * a).sum(axis=0)
        stretch = 1.0 + dh[0] / self.l0
        eps = em.axial_c @ dh + stretch * s
        grad = em.axial_c + stretch * np.einsum("pg,pgi->gi", a, em.axial_a)
        grad[:, 0] += s / self.l0
        return eps, grad, a, s

    def _scaled(self, delta):
        """(δ̂, the transverse rows, β = l₀/l): δ with the interior transverse offsets times β."""
        rows = _transverse_rows(int(self.order))
        beta = self.l0 / (self.l0 + delta[0])
        dh = delta.copy()
        dh[rows] = beta * delta[rows]
        return dh, rows, beta

    def _energy_derivatives(self, delta):
        """(U, U_δ, U_δδ): the energy of δ̂ (:meth:`_energy_scaled`) through the scaling."""
        dh, rows, beta = self._scaled(delta)
        U, Uh, Uhh = self._energy_scaled(dh)
        length = self.l0 + delta[0]
        db = -beta / length  # ∂β/∂δ₀
        J = np.eye(delta.size, dtype=dh.dtype)
        J[rows, rows] = beta
        J[rows, 0] = db * delta[rows]
        Up = J.T @ Uh
        Upp = J.T @ Uhh @ J
        g = Uh[rows]
        Upp[0, rows] += db * g
        Upp[rows, 0] += db * g
        Upp[0, 0] += (-2.0 * db / length) * np.sum(g * delta[rows])  # ∂²β/∂δ₀² = −2 (∂β/∂δ₀)/l
        return U, Up, Upp

    def _energy_scaled(self, dh):
        """(U, U_δ̂, U_δ̂δ̂) on the scaled deformations (module docstring)."""
        em = self._em
        eps, grad, a, s = self._strains(dh)
        w = em.axial_w
        we = w * eps
        U = 0.5 * dh @ em.K_rest @ dh + 0.5 * np.sum(we * eps)
        Up = em.K_rest @ dh + grad.T @ we
        stretch = 1.0 + dh[0] / self.l0
        Upp = em.K_rest + (grad.T * w) @ grad \
            + stretch * np.einsum("g,pgi,pgj->ij", we, em.axial_a, em.axial_a)
        ds = np.einsum("g,pg,pgi->i", we, a, em.axial_a) / self.l0  # Σ w ε ∂λ/∂δ₀ ∇s
        Upp[0, :] += ds
        Upp[:, 0] += ds
        return U, Up, Upp

    def strain_energy(self, q):
        return self._energy_derivatives(self.local_deformation(q))[0]

    def axial_force(self, q) -> float:
        """The element's mean axial force EA ε̄ (tension positive)."""
        eps = self._strains(self._scaled(self.local_deformation(q))[0])[0]
        return float(np.real(np.sum(self._em.axial_w * eps) / self.l0))

    # -- force element interface ------------------------------------------------------------
    def mass_matrix(self) -> np.ndarray:
        """The constant mass on idx (module docstring; read-only)."""
        return self._mass

    def _spin_force(self, z, zd):
        """The gyroscopic force on z: ρI_pΩ Σ_j m_kj (a_k × ȧ_j) on each a_k."""
        n = self.n_nodes
        a = z.reshape(n, 12)[:, 3:6]
        ad = self._em.m_nodes @ zd.reshape(n, 12)[:, 3:6]
        g = np.zeros((n, 12), dtype=np.result_type(z, zd))
        g[:, 3:6] = np.cross(a, ad)
        return (self.props.rho * self.props.polar * self.spin) * g.ravel()

    def _spin_damping(self, z):
        """C on z of the gyroscopic force: blocks −ρI_pΩ m_kj [a_k]×."""
        n = self.n_nodes
        C = np.zeros((12 * n, 12 * n), dtype=z.dtype)
        c = self.props.rho * self.props.polar * self.spin
        for k in range(n):
            ax, ay, az = z[12 * k + 3:12 * k + 6]
            skew = np.array([[0, -az, ay], [az, 0, -ax], [-ay, ax, 0]])
            for j in range(n):
                C[12 * k + 3:12 * k + 6, 12 * j + 3:12 * j + 6] = -c * self._em.m_nodes[k, j] * skew
        return C

    def force(self, q, qd):
        nodes = self._nodes
        z = nodes(q)
        delta, B, _ = self._measures(z, hessians=False)
        Up = self._energy_derivatives(delta)[1]
        gz = -(B.T @ Up)
        if self.spin:
            gz = gz + self._spin_force(z, nodes.C @ qd[self.idx])
        return nodes.C.T @ gz

    def jacobians(self, q, qd):
        """(K, C): K exact for the elastic part; the gyroscopic force's ∂/∂q (∝ Ω q̇) is left
        out, so K is exact at rest (where the linearization evaluates it)."""
        nodes = self._nodes
        z = nodes(q)
        delta, B, H = self._measures(z)
        _, Up, Upp = self._energy_derivatives(delta)
        Kz = B.T @ Upp @ B + np.tensordot(Up, H, axes=1)
        Cn = nodes.C
        K = Cn.T @ Kz @ Cn
        C = Cn.T @ self._spin_damping(z) @ Cn if self.spin else np.zeros_like(K)
        return K, C
