"""How many digits a beam mesh keeps against the rounding of its assembled matrices
(docs/beams3d.md, "Not yet").

The stiffness of a beam mesh has cond ∝ elements⁴: refined far enough, the rounding of its
assembled matrices, not the element, limits the lowest frequencies.  For a computed mode
(λ = ω², x) of the reduced symmetric pencil (Q, M) of an undamped model, rounding every stored
entry of Q and M by at most u (relative) moves λ, to first order, by at most

    |δλ| ≤ u (|x|ᵀ|Q||x| + λ |x|ᵀ|M||x|) / (xᵀMx)

(δλ = xᵀ(δQ − λ δM)x / xᵀMx for a simple eigenvalue, each term bounded by its absolute
value: the componentwise condition of the eigenvalue), so ω moves by at most half that,
relatively: e = |δλ| / (2λ).  It is a first-order estimate, not a bound on the computed value:
the solver's own error is normwise (the listed bounds, which at 600 elements of the oblique
cantilever overstate the error by 10³–10⁴), while e follows the mode's own cancellation (there
7–70× the error measured against the closed form at 200–2,000 elements).  e grows with the mesh
as elements^3.3–4 (measured on that cantilever), so the mesh that keeps ``DIGITS`` digits
against rounding is the present one scaled by (10^−DIGITS / e)^(1/3): the slower law, so that
the scaled mesh keeps them under either.

The statement is made for models with beams whose listing is of an undamped symmetric pencil
(P = 0), on the lowest ``LOWEST`` listed modes with ω > 0, and printed only where they keep
fewer than ``DIGITS`` digits."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["DIGITS", "LOWEST", "MeshRounding", "mesh_rounding", "rounding_estimate"]

DIGITS = 8  # the statement is printed where the lowest modes keep fewer digits than this
LOWEST = 4  # the lowest listed modes the statement covers
U = np.finfo(float).eps / 2  # unit roundoff


@dataclass(frozen=True)
class MeshRounding:
    """``relative`` (e per listed mode, NaN where not estimated), ``worst`` (the largest e of the
    lowest modes), ``digits`` kept (−log10 worst), ``beams`` {name: elements now} and
    ``keeps`` {name: elements that keep DIGITS digits against rounding}."""

    relative: np.ndarray
    worst: float
    digits: float
    beams: dict
    keeps: dict

    @property
    def resolved(self) -> bool:
        """Whether the lowest modes keep at least ``DIGITS`` digits."""
        return self.worst <= 10.0**-DIGITS

    def line(self) -> str:
        """The one-line statement (module docstring)."""
        mesh = ", ".join(f"beam {nm} at {self.keeps[nm]:,} elements (now {n:,})"
                         for nm, n in self.beams.items())
        return (f"mesh: finer than double precision resolves to {DIGITS} digits: rounding of the "
                f"assembled matrices leaves the lowest modes at least about {self.digits:.0f} "
                f"(first-order estimate: ω within {self.worst:.1e}, relative; it grows as "
                f"elements^3.3–4); {mesh} keeps {DIGITS} against rounding")

    def record(self) -> dict:
        return {"relative": [None if not np.isfinite(e) else float(e) for e in self.relative],
                "worst": float(self.worst), "digits": float(self.digits),
                "resolved_digits": DIGITS, "resolved": self.resolved,
                "elements": dict(self.beams), "elements_keeping": dict(self.keeps),
                "estimate": "u (|x|ᵀ|Q||x| + λ|x|ᵀ|M||x|) / (2 λ xᵀMx), first order"}


def mesh_rounding(model, lin, modes) -> MeshRounding | None:
    """The :class:`MeshRounding` of a model with beams listed from an undamped symmetric pencil,
    or None (no beams, damping or gyroscopic terms, complex vectors, no mode with ω > 0)."""
    beams = {nm: int(r["elements"]) for nm, r in ((model.flexible or {}).get("bodies") or {})
             .items() if r.get("type") == "beam"}
    if not beams or len(modes) == 0:
        return None
    P = lin.P
    if P is not None and (P.count_nonzero() if sp.issparse(P) else np.count_nonzero(P)):
        return None
    X = modes.vectors
    if X.shape[0] != lin.M.shape[0]:
        return None
    if np.iscomplexobj(X):
        if np.any(X.imag):
            return None
        X = X.real
    w = np.abs(np.asarray(modes.eigenvalues))
    rel = rounding_estimate(lin.M, lin.Q, w, X)
    low = np.argsort(np.where(np.isfinite(rel), w, np.inf), kind="stable")[:LOWEST]
    low = low[np.isfinite(rel[low])]
    if not low.size:
        return None
    worst = float(np.max(rel[low]))
    scale = min(1.0, (10.0**-DIGITS / worst) ** (1.0 / 3.0)) if worst > 0 else 1.0
    keeps = {nm: max(1, math.floor(n * scale)) for nm, n in beams.items()}
    digits = -math.log10(worst) if worst > 0 else float(-math.log10(U))
    return MeshRounding(rel, worst, digits, beams, keeps)


def rounding_estimate(M, Q, omega, X):
    """e_k = u (|x|ᵀ|Q||x| + λ|x|ᵀ|M||x|) / (2 λ xᵀMx), λ = ω_k², x = X[:, k], for every column
    with ω_k > 0 and xᵀMx > 0 (NaN elsewhere): the first-order relative change of ω_k when every
    stored entry of Q and M is rounded by at most u (module docstring)."""
    M, Q = _csr(M), _csr(Q)
    Ma, Qa = abs(M), abs(Q)
    rel = np.full(len(omega), np.nan)
    for k in np.flatnonzero(np.asarray(omega) > 0):
        x = X[:, k]
        ax = np.abs(x)
        mx = float(x @ (M @ x))
        lam = float(omega[k]) ** 2
        if mx > 0:
            rel[k] = U * (float(ax @ (Qa @ ax)) + lam * float(ax @ (Ma @ ax))) / mx / (2.0 * lam)
    return rel


def _csr(A):
    return A.tocsr() if sp.issparse(A) else sp.csr_matrix(np.asarray(A))
