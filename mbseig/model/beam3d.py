"""Spatial beams and shafts: the 3-D Timoshenko / Euler–Bernoulli element, linear and
co-rotational.

Two layers.

1. The standard local element (:func:`element_matrices`): 12×12 matrices on the local DOFs

       d = [u₁, v₁, w₁, θx₁, θy₁, θz₁, u₂, v₂, w₂, θx₂, θy₂, θz₂]      (x along the beam)

   of a uniform shaft element (Nelson 1980; Friswell et al., *Dynamics of Rotating Machines*,
   2010, ch. 5; the element ROSS uses), with

       M d̈ + Ω G d̈ + (K + N K_g) d = f          (G skew: spin Ω about +x; N axial force,
                                                  tension > 0)

   Bending in the xy-plane acts on (v, θz) with v′ ≈ θz, in the xz-plane on (w, θy) with
   w′ ≈ −θy; each plane uses the interdependent Timoshenko interpolation (Friedman & Kosmatka
   1993, :func:`mbseig.model.beams.timoshenko_shape_functions`) with its own shear parameter

       Φ_y = 12 E I_z / (κ_y G A L²)   (shear along y, bending about z)
       Φ_z = 12 E I_y / (κ_z G A L²)   (shear along z, bending about y)

   M = ∫ ρA NᵀN + ρI_z N_ψzᵀN_ψz + ρI_y N_ψyᵀN_ψy dx (rotary inertia in the Timoshenko theory or
   with ``rotary_inertia=True``: a Rayleigh beam), axial and torsion linear (ρA, ρI_p,
   I_p = I_y + I_z the polar second moment of the mass), K the closed-form Timoshenko stiffness,
   torsion GJ/L, axial EA/L.  The gyroscopic matrix of the spinning shaft's polar inertia is

       G = ρ I_p ∫ (N_ψyᵀ N_ψz − N_ψzᵀ N_ψy) dx,

   from the moment −ρI_pΩ ȧ per unit length on a section whose axis a tilts by ψ (the same law
   as the rigid ``rotor`` element: T = −J_pΩ ȧ).  K_g = ∫ N′ᵀN′ dx in both planes is the
   consistent geometric stiffness per unit axial force.

2. The nonlinear element for mbseig (:class:`Beam3DElement`): co-rotational, on nodes that are
   *frames* [r; u; v; w] exactly like spatial rigid bodies (:mod:`mbseig.model.spatial_body`): a
   basic point and three unit vectors equal to the global x, y, z axes at the reference, with
   the six quadratic conditions of :func:`mbseig.model.spatial_joints.triad_constraint` per free
   node.  The section axes of node i, a_i (beam axis), b_i (section y), c_i (section z), are
   fixed combinations of u, v, w (the reference section frame R₀ = [x₀ y₀ z₀]), so they are
   linear in q.  With d = r₂ − r₁, l = |d|, e = d/l the element's deformations are

       u  = l − l₀                                  elongation
       θ  = ½ (c₁·b₂ − b₁·c₂)                       twist (sin of the relative rotation about x)
       φz_i = −e·b_i,  φy_i = e·c_i                 end rotations about z and y relative to
                                                    the chord

   all invariant under rigid motions and zero at the reference (dot products of co-rotated
   vectors), smooth, with gradients and Hessians in closed form.  The strain energy is the
   planar beams' in each bending plane plus torsion:

       ε̄ = u/l₀ + ½ φzᵀ G_z φz + ½ φyᵀ G_y φy,     N = EA ε̄
       U = ½ EA l₀ ε̄² + ½ φzᵀ Kb_z φz + ½ φyᵀ Kb_y φy + ½ (GJ/l₀) θ²
       Kb = EI/(l₀(1 + Φ)) [[4 + Φ, 2 − Φ], [2 − Φ, 4 + Φ]],   G = (1/l₀) ∫ N_φ′ N_φ′ᵀ dx

   g = −Bᵀ U_p, K = −∂g/∂q = Bᵀ U_pp B + Σ_k U_p,k ∇²p_k (exact).  At the straight reference the
   tangent on the rigid-motion-free directions is the standard K, and under an axial force N it
   adds N K_g exactly (the chord term N/l (I − eeᵀ) plus N l₀ G), so columns buckle at the Euler
   load of the mesh.

   Mass and spin act on the nodal velocities in the current element frame R_e (e, and the mean
   section y axis of the two nodes made normal to e):  ḋ = T(q) q̇ with translations R_eᵀ ṙ_i and
   rotation rates R_eᵀ ω_i, ω_i = ½ (a_i × ȧ_i + b_i × ḃ_i + c_i × ċ_i); M(q) = Tᵀ M_loc T (as
   the planar co-rotational beams: configuration-dependent, evaluated at q₀ by the
   linearization) and the gyroscopic force g = −Ω Tᵀ G T q̇, so C = −∂g/∂q̇ = Ω Tᵀ G T.

3. Evaluation.  ``force``, ``jacobians``, ``mass`` and ``velocity_terms`` of real states are
   served by the beam's batch (:mod:`mbseig.model.beam3d_batch`: all elements of the beam at
   once, :mod:`mbseig.model.beam3d_kernel`; the force forms no Hessians); the ``*_reference``
   methods evaluate one element alone with the formulas above (complex states, ``BATCHED =
   False``), and the batch equals them to rounding (tests/test_beam3d_kernel.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import EquilibriumError
from .affine import Affine, identity_of
from .base import ConfigurationMass, Force
from .beam3d_batch import group_of
from .beam3d_local import BeamProperties3D, ElementMatrices, element_matrices
from .beam_sections import (
    SHAPES,
    cowper_shear_coefficient,
    rectangle_torsion_constant,
    section_frame,
    section_properties,
)
from .beam_whirl import SpinningShaft, velocity_map_z, velocity_terms_z
from .beams import GAUSS_W, GAUSS_X, THEORIES, timoshenko_shape_functions

__all__ = [
    "SHAPES",
    "THEORIES",
    "Beam3DElement",
    "BeamProperties3D",
    "ElementMatrices",
    "SpinningShaft",
    "cowper_shear_coefficient",
    "element_matrices",
    "frames_to_local",
    "rectangle_torsion_constant",
    "section_frame",
    "section_properties",
]

#: evaluate float states through the beam's batch (mbseig.model.beam3d_batch); False: each
#: element alone (the reference path, also taken for complex states: complex-step tests)
BATCHED = True


# ---------------------------------------------------------------------------------------------
# the co-rotational element on frame nodes
def frames_to_local(R0: np.ndarray) -> np.ndarray:
    """S (24×24): [r; a; b; c] per node (section axes) = S [r; u; v; w] per node (frame)."""
    node = np.zeros((12, 12))
    node[:3, :3] = np.eye(3)
    node[3:, 3:] = np.kron(np.asarray(R0, float).T, np.eye(3))
    return np.kron(np.eye(2), node)


_S_KEPT = 16  # section frames whose S is kept (a model's beams: one frame each, mostly)
_S_CACHE: dict = {}


def _in_own_order(frames):
    """The frames map with its coordinates reordered where it only selects them (a permutation
    matrix: a node's coordinates allocated before the element's other node's), so that its
    matrix is the shared identity (the same map, exactly: C q[idx] = q[idx[perm]])."""
    C = frames.C
    if C.shape != (24, 24) or C is identity_of(24):
        return frames
    nz = C != 0
    if not (np.all(nz.sum(axis=1) == 1) and np.all(nz.sum(axis=0) == 1)):
        return frames
    perm = np.argmax(nz, axis=1)
    if not np.all(C[np.arange(24), perm] == 1.0):
        return frames
    return Affine(np.asarray(frames.idx)[perm], identity_of(24), frames.d)


def _node_map(R0, C):
    """S C of an element (the frames map C to the section axes): S made once per section
    frame R0 and kept (read-only); where C is the identity (the element's coordinates are its
    two nodes' own, in order) S itself, shared, since S I = S exactly."""
    R0 = np.asarray(R0, float)
    key = R0.tobytes()
    S = _S_CACHE.get(key)
    if S is None:
        S = frames_to_local(R0)
        S.setflags(write=False)
        if len(_S_CACHE) >= _S_KEPT:
            _S_CACHE.pop(next(iter(_S_CACHE)))
        _S_CACHE[key] = S
    eye = identity_of(24)
    if C is eye or (C.shape == (24, 24) and np.array_equal(C, eye)):
        return S, S
    return S, S @ C


_D = np.zeros((3, 24))
_D[:, 12:15] = np.eye(3)
_D[:, 0:3] = -np.eye(3)


def _sel(k):
    """3×24 selector of block k of z = [r₁, a₁, b₁, c₁, r₂, a₂, b₂, c₂]."""
    S = np.zeros((3, 24))
    S[:, 3 * k:3 * k + 3] = np.eye(3)
    return S


_B1, _C1, _B2, _C2 = _sel(2), _sel(3), _sel(6), _sel(7)
# twist θ = ½ (c₁·b₂ − b₁·c₂): constant Hessian
_H_TWIST = 0.5 * (_C1.T @ _B2 + _B2.T @ _C1 - _B1.T @ _C2 - _C2.T @ _B1)
# rows of p = [u, θ, φz₁, φz₂, φy₁, φy₂]: (sign, selector) of the dot measures
_DOTS = ((-1.0, _B1), (-1.0, _B2), (1.0, _C1), (1.0, _C2))


@dataclass(frozen=True, eq=False)
class Beam3DElement(Force, ConfigurationMass):
    """One co-rotational spatial beam element between two frame nodes (module docstring).

    ``frames`` maps q to the two node frames [r₁; u₁; v₁; w₁; r₂; u₂; v₂; w₂] (24 rows; triads
    equal to the global axes at the reference); ``R0`` the reference section frame; ``spin`` Ω
    about the element axis (rad/s).
    """

    name: str
    frames: Affine
    props: BeamProperties3D
    l0: float
    R0: np.ndarray
    spin: float = 0.0
    affine_field = "frames"

    def __post_init__(self):
        em, planes = _constants(self.props, float(self.l0))
        frames = _in_own_order(self.frames)
        if frames is not self.frames:
            object.__setattr__(self, "frames", frames)
        S, SC = _node_map(self.R0, self.frames.C)
        nodes = Affine(self.frames.idx, SC, S @ self.frames.d)
        object.__setattr__(self, "_nodes", nodes)
        object.__setattr__(self, "_em", em)
        object.__setattr__(self, "_planes", tuple(planes))

    @property
    def matrices(self) -> ElementMatrices:
        return self._em

    # -- deformations ------------------------------------------------------------------------
    def _measures(self, z, hessians=True):
        """p (6,), B = ∂p/∂z (6, 24) and the Hessians ∇²p_k (6, 24, 24) on the section axes z
        (None without ``hessians``)."""
        d = _D @ z
        length = np.sqrt(d @ d)
        if length.real == 0.0:
            raise EquilibriumError("beam element collapsed to zero length", element=self.name)
        e = d / length
        P = np.eye(3) - np.outer(e, e)
        dt = z.dtype
        p = np.zeros(6, dtype=dt)
        B = np.zeros((6, 24), dtype=dt)
        H = np.zeros((6, 24, 24), dtype=dt) if hessians else None
        p[0] = length - self.l0
        B[0] = e @ _D
        p[1] = 0.5 * ((_C1 @ z) @ (_B2 @ z) - (_B1 @ z) @ (_C2 @ z))
        B[1] = _H_TWIST @ z
        if hessians:
            H[0] = _D.T @ (P / length) @ _D
            H[1] = _H_TWIST
        for k, (sgn, X) in enumerate(_DOTS, start=2):
            x = X @ z
            ex = e @ x
            p[k] = sgn * ex
            B[k] = sgn * ((x - ex * e) / length @ _D + e @ X)
            if not hessians:
                continue
            Hdd = -(np.outer(x, e) + np.outer(e, x)
                    + ex * (np.eye(3) - 3 * np.outer(e, e))) / (length * length)
            Hdx = _D.T @ (P / length) @ X
            H[k] = sgn * (_D.T @ Hdd @ _D + Hdx + Hdx.T)
        return p, B, H

    def local_deformation(self, q):
        """(u, θ, φz₁, φz₂, φy₁, φy₂): elongation, twist, end rotations about z and y (module
        docstring)."""
        return self._measures(self._nodes(q), hessians=False)[0]

    def _energy_derivatives(self, p):
        EA, l0 = self.props.E * self.props.A, self.l0
        (Gz, Kbz), (Gy, Kby) = self._planes
        phz, phy = p[2:4], p[4:6]
        az, ay = Gz @ phz, Gy @ phy
        eps = p[0] / l0 + 0.5 * phz @ az + 0.5 * phy @ ay
        N = EA * eps
        GJ = self.props.G * self.props.J / l0
        Up = np.concatenate([[N, GJ * p[1]], N * l0 * az + Kbz @ phz, N * l0 * ay + Kby @ phy])
        c = np.concatenate([[1.0 / l0, 0.0], az, ay])
        Upp = EA * l0 * np.outer(c, c)
        Upp[1, 1] += GJ
        Upp[2:4, 2:4] += N * l0 * Gz + Kbz
        Upp[4:6, 4:6] += N * l0 * Gy + Kby
        U = 0.5 * EA * l0 * eps**2 + 0.5 * phz @ Kbz @ phz + 0.5 * phy @ Kby @ phy \
            + 0.5 * GJ * p[1] ** 2
        return U, Up, Upp, N

    def strain_energy(self, q):
        return self._energy_derivatives(self.local_deformation(q))[0]

    def axial_force(self, q) -> float:
        """N = EA ε̄ (tension positive)."""
        return float(np.real(self._energy_derivatives(self.local_deformation(q))[3]))

    # -- velocity map ------------------------------------------------------------------------
    def velocity_map(self, q) -> np.ndarray:
        """T (12 × |idx|): local nodal velocities ḋ = T q̇[idx] in the current element frame."""
        return velocity_map_z(self._nodes(q)) @ self._nodes.C

    def velocity_terms(self, q, qd) -> np.ndarray:
        """h = Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q on idx, in closed form (batched: :meth:`_batched`)."""
        if self._batched(q, qd):
            return group_of(self.props).evaluate("velocity_terms", self, q, qd)
        return self.velocity_terms_reference(q, qd)

    def velocity_terms_reference(self, q, qd) -> np.ndarray:
        """:meth:`velocity_terms` of this element alone (:mod:`mbseig.model.beam_whirl`)."""
        C = self._nodes.C
        return C.T @ velocity_terms_z(self._nodes(q), C @ qd[self.idx], self._em.M)

    # -- force element interface ------------------------------------------------------------
    def _batched(self, q, qd=None) -> bool:
        """Whether (q, q̇) is served by the beam's batch (:mod:`mbseig.model.beam3d_batch`):
        real vectors; anything else (complex steps) is evaluated here alone."""
        return BATCHED and _real(q) and (qd is None or _real(qd))

    def batch_group(self, q, qd=None):
        """The batch that serves this element at (q, q̇) (:meth:`_batched`), or None."""
        return group_of(self.props) if self._batched(q, qd) else None

    def kernel_record(self) -> dict:
        """This element's constant data for :class:`mbseig.model.beam3d_kernel.Stack`."""
        p, (Gz, Kbz), (Gy, Kby) = self.props, *self._planes
        return {"idx": self._nodes.idx, "C": self._nodes.C, "d": self._nodes.d, "l0": self.l0,
                "EA": p.E * p.A, "GJ": p.G * p.J / self.l0, "spin": self.spin, "Gz": Gz,
                "Kbz": Kbz, "Gy": Gy, "Kby": Kby, "M": self._em.M, "G": self._em.G}

    def force(self, q, qd):
        if self._batched(q, qd):
            return group_of(self.props).evaluate("force", self, q, qd)
        return self.force_reference(q, qd)

    def force_reference(self, q, qd):
        """:meth:`force` of this element alone, through the Hessian-free part of
        :meth:`_measures`."""
        z = self._nodes(q)
        p, B, _ = self._measures(z, hessians=False)
        Up = self._energy_derivatives(p)[1]
        g = -(self._nodes.C.T @ (B.T @ Up))
        if self.spin:
            T = self.velocity_map(q)
            g = g - self.spin * (T.T @ (self._em.G @ (T @ qd[self.idx])))
        return g

    def jacobians(self, q, qd):
        """(K, C): K exact for the elastic part; the gyroscopic force's ∂/∂q (∝ Ω q̇) is left
        out, so K is exact at rest (q̇ = 0, where the linearization evaluates it)."""
        if self._batched(q, qd):
            return group_of(self.props).evaluate("jacobians", self, q, qd)
        return self.jacobians_reference(q, qd)

    def jacobians_reference(self, q, qd):
        """:meth:`jacobians` of this element alone."""
        z = self._nodes(q)
        p, B, H = self._measures(z)
        _, Up, Upp, _ = self._energy_derivatives(p)
        Kz = B.T @ Upp @ B + np.tensordot(Up, H, axes=1)
        Cn = self._nodes.C
        K = Cn.T @ Kz @ Cn
        if self.spin:
            T = self.velocity_map(q)
            C = self.spin * (T.T @ self._em.G @ T)
        else:
            C = np.zeros_like(K)
        return K, C

    # -- inertia -----------------------------------------------------------------------------
    def mass(self, q):
        """Consistent mass on idx in the current element frame: Tᵀ M_loc T."""
        if self._batched(q):
            return group_of(self.props).evaluate("mass", self, q, None)
        return self.mass_reference(q)

    def mass_reference(self, q):
        """:meth:`mass` of this element alone."""
        T = self.velocity_map(q)
        return T.T @ self._em.M @ T


def _constants(p, l0):
    """(element matrices, bending planes' (G, K_b)) of an element of length l0: the same for
    every element of a beam with that length, so made once per (properties, length) and kept
    on the properties (read-only, shared)."""
    kept = p.__dict__.get("_elements")
    if kept is None:
        kept = {}
        object.__setattr__(p, "_elements", kept)
    hit = kept.get(l0)
    if hit is None:
        em = element_matrices(p, l0)
        planes = []
        for Phi, I_bend in ((em.Phi_y, p.Iz), (em.Phi_z, p.Iy)):
            _, dN, _ = timoshenko_shape_functions(GAUSS_X, l0, Phi)
            dphi = dN[:, [1, 3]]
            Gm = (dphi.T * (GAUSS_W * l0)) @ dphi / l0
            Kb = p.E * I_bend / (l0 * (1 + Phi)) * np.array([[4 + Phi, 2 - Phi],
                                                              [2 - Phi, 4 + Phi]])
            planes.append((Gm, Kb))
        for A in (em.M, em.K, em.G, em.Kg, *(x for pl in planes for x in pl)):
            A.setflags(write=False)
        hit = kept[l0] = (em, tuple(planes))
    return hit


def _real(v) -> bool:
    return isinstance(v, np.ndarray) and v.dtype == np.float64 and v.ndim == 1
