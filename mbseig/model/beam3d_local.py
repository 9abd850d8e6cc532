"""The standard local element of a spatial beam or shaft: its section and material
(:class:`BeamProperties3D`) and the 12×12 matrices M, K, G, K_g of one uniform element
(:func:`element_matrices`; Nelson 1980; Friswell et al. 2010 ch. 5), described in
:mod:`mbseig.model.beam3d`, which re-exports them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .beams import GAUSS_W, GAUSS_X, THEORIES, timoshenko_shape_functions

__all__ = ["BeamProperties3D", "ElementMatrices", "element_matrices"]

_FLIP = np.diag([1.0, -1.0, 1.0, -1.0])  # xz-plane: the planar rotation ψ is −θy
_XY = [1, 5, 7, 11]  # (v₁, θz₁, v₂, θz₂)
_XZ = [2, 4, 8, 10]  # (w₁, θy₁, w₂, θy₂)


@dataclass(frozen=True)
class BeamProperties3D:
    """Material and section of a spatial beam: E, G [Pa], ρ [kg/m³], A [m²], Iy, Iz [m⁴] (about
    the section's y and z axes), J [m⁴] (torsion constant), κ_y, κ_z (shear coefficients for
    shear along y and z), theory; ``rotary_inertia`` None follows the theory (Timoshenko: yes)."""

    E: float
    G: float
    rho: float
    A: float
    Iy: float
    Iz: float
    J: float
    kappa_y: float = 5.0 / 6.0
    kappa_z: float = 5.0 / 6.0
    theory: str = "timoshenko"
    rotary_inertia: bool | None = None

    def __getstate__(self):
        """Fields only: the evaluation cache its elements share (:mod:`mbseig.model.beam3d_batch`)
        is not part of the properties."""
        state = dict(self.__dict__)
        state.pop("_batch", None)
        state.pop("_elements", None)  # the element constants kept by mbseig.model.beam3d
        return state

    def __post_init__(self):
        if self.theory not in THEORIES:
            raise ValueError(f"theory must be one of {', '.join(THEORIES)}, got {self.theory!r}")

    @property
    def polar(self) -> float:
        """I_p = I_y + I_z, the polar second moment that carries the mass's torsional inertia."""
        return self.Iy + self.Iz

    @property
    def has_rotary_inertia(self) -> bool:
        if self.rotary_inertia is None:
            return self.theory == "timoshenko"
        return bool(self.rotary_inertia)

    def shear_parameters(self, L: float) -> tuple[float, float]:
        """(Φ_y, Φ_z) = (12 E I_z/(κ_y G A L²), 12 E I_y/(κ_z G A L²)); zeros for
        Euler–Bernoulli."""
        if self.theory == "euler-bernoulli":
            return 0.0, 0.0
        c = 12.0 * self.E / (self.G * self.A * L * L)
        return c * self.Iz / self.kappa_y, c * self.Iy / self.kappa_z


# ---------------------------------------------------------------------------------------------
# the linear local element
@dataclass(frozen=True)
class ElementMatrices:
    """Local 12×12 matrices of one element: M d̈ + Ω G ḋ + (K + N K_g) d = f (module docstring),
    d = [u, v, w, θx, θy, θz] at node 1 then node 2, x along the beam."""

    M: np.ndarray
    K: np.ndarray
    G: np.ndarray
    Kg: np.ndarray
    L: float
    Phi_y: float
    Phi_z: float


def _bending_stiffness(EI, L, Phi):
    """Closed-form Timoshenko bending stiffness on planar (w, ψ) (Przemieniecki; Friswell
    eq. 5.x)."""
    return EI / (L**3 * (1 + Phi)) * np.array([
        [12.0, 6 * L, -12, 6 * L],
        [6 * L, (4 + Phi) * L**2, -6 * L, (2 - Phi) * L**2],
        [-12, -6 * L, 12, -6 * L],
        [6 * L, (2 - Phi) * L**2, -6 * L, (4 + Phi) * L**2]])


def _plane_fields(L, Phi, dofs, flip):
    """(N, N′, N_ψ) of one bending plane as (ng, 12) arrays on d (rotation field as ψ of that
    plane: θz in xy, −θy in xz is returned as the rotation about y, i.e. sign restored)."""
    N, dN, Npsi = timoshenko_shape_functions(GAUSS_X, L, Phi)
    S = _FLIP if flip else np.eye(4)
    out = []
    for F in (N, dN, Npsi):
        full = np.zeros((GAUSS_X.size, 12))
        full[:, dofs] = F @ S
        out.append(full)
    if flip:  # the planar ψ is −θy: the rotation about y is −ψ
        out[2] = -out[2]
    return out


def element_matrices(props: BeamProperties3D, L: float) -> ElementMatrices:
    """The standard local matrices of one uniform element of length L (module docstring)."""
    p = props
    Phi_y, Phi_z = p.shear_parameters(L)
    M, K, Kg, G = (np.zeros((12, 12)) for _ in range(4))
    lin = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    spring = np.array([[1.0, -1.0], [-1.0, 1.0]])
    for dofs, k, m in (([0, 6], p.E * p.A / L, p.rho * p.A * L),
                       ([3, 9], p.G * p.J / L, p.rho * p.polar * L)):
        K[np.ix_(dofs, dofs)] += k * spring
        M[np.ix_(dofs, dofs)] += m * lin
    wq = GAUSS_W * L
    psi = {}
    for dofs, flip, I_bend, Phi in ((_XY, False, p.Iz, Phi_y), (_XZ, True, p.Iy, Phi_z)):
        S = _FLIP if flip else np.eye(4)
        K[np.ix_(dofs, dofs)] += S @ _bending_stiffness(p.E * I_bend, L, Phi) @ S
        N, dN, Npsi = _plane_fields(L, Phi, dofs, flip)
        M += p.rho * p.A * (N.T * wq) @ N
        if p.has_rotary_inertia:
            M += p.rho * I_bend * (Npsi.T * wq) @ Npsi
        Kg += (dN.T * wq) @ dN
        psi["z" if not flip else "y"] = Npsi
    Ny, Nz = psi["y"], psi["z"]
    G = p.rho * p.polar * ((Ny.T * wq) @ Nz - (Nz.T * wq) @ Ny)
    return ElementMatrices(M=M, K=K, G=G, Kg=Kg, L=L, Phi_y=Phi_y, Phi_z=Phi_z)
