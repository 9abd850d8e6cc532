"""Sections of spatial beams (DESIGN §8, 3-D flexible bodies): ``circle``, ``tube``,
``rectangle`` properties with Cowper's shear coefficient, the Saint-Venant torsion constant of a
rectangle, and the section frame from an ``orientation`` (:mod:`mbseig.model.beam3d`)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import CaseError

__all__ = [
    "ORIENTATION_TOL",
    "SHAPES",
    "cowper_shear_coefficient",
    "rectangle_torsion_constant",
    "section_frame",
    "section_properties",
]

SHAPES = ("circle", "tube", "rectangle")
ORIENTATION_TOL = 1e-9  # |orientation ⟂ axis| / |orientation| below this: along the axis


def rectangle_torsion_constant(b: float, h: float, *, terms: int = 50) -> float:
    """Saint-Venant torsion constant of a solid b × h rectangle (Timoshenko & Goodier, *Theory of
    Elasticity*, 1970, §109; the series behind Roark's table 10.7 case 4), with a ≥ t the long
    and short sides:

        J = a t³ [1/3 − (64/π⁵)(t/a) Σ_{n = 1, 3, 5, …} tanh(nπa/(2t)) / n⁵]

    ``terms`` odd n are summed (the tail after 50 terms is below 1e-9 of the sum).
    """
    a, t = max(b, h), min(b, h)
    n = 2.0 * np.arange(terms) + 1.0
    s = np.sum(np.tanh(n * math.pi * a / (2.0 * t)) / n**5)
    return a * t**3 * (1.0 / 3.0 - 64.0 / math.pi**5 * (t / a) * s)


def cowper_shear_coefficient(shape: str, dims: dict, nu: float) -> float:
    """Cowper's shear coefficient (Cowper 1966, J. Appl. Mech. 33, table 1):
    circle 6(1+ν)/(7+6ν); tube 6(1+ν)(1+r²)²/((7+6ν)(1+r²)² + (20+12ν)r²), r = d_inner/d;
    rectangle 10(1+ν)/(12+11ν) (both directions)."""
    if shape == "circle":
        return 6.0 * (1 + nu) / (7 + 6 * nu)
    if shape == "tube":
        r2 = (dims["d_inner"] / dims["d"]) ** 2
        return 6 * (1 + nu) * (1 + r2) ** 2 / ((7 + 6 * nu) * (1 + r2) ** 2 + (20 + 12 * nu) * r2)
    if shape == "rectangle":
        return 10.0 * (1 + nu) / (12 + 11 * nu)
    raise ValueError(shape)


def section_properties(*, shape: str, dims: dict, nu: float, element: str = "") -> dict:
    """A, Iy, Iz, J, κ (Cowper, :func:`cowper_shear_coefficient`) and depth of a standard section.

    circle (d), tube (d, d_inner < d), rectangle (b along the section's y, h along its z):
    Iy = ∫z² dA = b h³/12, Iz = ∫y² dA = h b³/12, J by :func:`rectangle_torsion_constant`.
    Non-positive dimensions raise :class:`CaseError` naming ``element``.
    """
    need = {"circle": ("d",), "tube": ("d", "d_inner"), "rectangle": ("b", "h")}
    if shape not in need:
        raise CaseError(f"section shape must be one of {', '.join(SHAPES)}, got {shape!r}",
                        element=element)
    for k in need[shape]:
        if k not in dims:
            raise CaseError(f"a {shape} section needs {', '.join(need[shape])}", element=element)
        if not (math.isfinite(dims[k]) and dims[k] > 0):
            raise CaseError(f"section {k} must be positive, got {dims[k]:g}", element=element)
    if not (-1.0 < nu < 0.5):
        raise CaseError(f"nu must lie in (−1, 0.5), got {nu:g}", element=element)
    kappa = cowper_shear_coefficient(shape, dims, nu)
    if shape == "circle":
        d = dims["d"]
        Ib = math.pi * d**4 / 64.0
        return {"A": math.pi * d**2 / 4.0, "Iy": Ib, "Iz": Ib, "J": 2 * Ib, "kappa": kappa,
                "depth": d}
    if shape == "tube":
        d, di = dims["d"], dims["d_inner"]
        if di >= d:
            raise CaseError(f"tube d_inner = {di:g} must be less than d = {d:g}", element=element)
        Ib = math.pi * (d**4 - di**4) / 64.0
        return {"A": math.pi * (d**2 - di**2) / 4.0, "Iy": Ib, "Iz": Ib, "J": 2 * Ib,
                "kappa": kappa, "depth": d}
    b, h = dims["b"], dims["h"]
    return {"A": b * h, "Iy": b * h**3 / 12.0, "Iz": h * b**3 / 12.0,
            "J": rectangle_torsion_constant(b, h), "kappa": kappa, "depth": max(b, h)}


def section_frame(start, end, orientation=None, *, element: str = "") -> np.ndarray:
    """R₀ = [x₀ y₀ z₀] (columns): x₀ along start → end, y₀ the ``orientation`` projected normal
    to x₀, z₀ = x₀ × y₀.  Without ``orientation`` (axisymmetric sections) y₀ is the global axis
    least aligned with x₀, projected.  An orientation along the axis raises :class:`CaseError`."""
    x = np.asarray(end, float) - np.asarray(start, float)
    lx = math.sqrt(x @ x)
    if lx == 0.0:
        raise CaseError("the beam's end points coincide", element=element)
    x = x / lx
    if orientation is None:
        y = np.eye(3)[int(np.argmin(np.abs(x)))]
    else:
        y = np.asarray(orientation, float)
        if y.shape != (3,) or not np.all(np.isfinite(y)):
            raise CaseError("orientation must be three numbers [x, y, z]", element=element)
    y_n = y - (y @ x) * x
    ly = math.sqrt(y_n @ y_n)
    if ly <= ORIENTATION_TOL * max(math.sqrt(y @ y), np.finfo(float).tiny):
        raise CaseError(f"orientation {list(map(float, y))} is along the beam axis "
                        f"{[round(float(c), 12) for c in x]}: the section's y axis is undefined",
                        element=element)
    y_n = y_n / ly
    return np.column_stack([x, y_n, np.cross(x, y_n)])
