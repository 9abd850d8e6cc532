"""The steady harmonic response x̂ of Z x̂ = f through a dynamic stiffness that may be singular:
Z = Q − Ω²M + iΩP (an unbalance at the speed Ω, :mod:`mbseig.studies.unbalance`) or
Z = M s² + P s + Q at s = iω (a frequency response, :mod:`mbseig.studies.frf`).

Where the excitation frequency meets an undamped eigenvalue, Z is singular and the response is
unbounded (a resonance) if the force drives the singular direction, and finite otherwise.  Both
questions are decided here from numbers with a stated bound, not from whether an LU
factorization happened to meet an exact zero pivot (which depends on the BLAS kernel: the same Z
gives ``LinAlgError`` on one machine and an amplitude of 1e26 m on another).

The accuracy of Z.  Z is formed from M, P, Q, which the linearization computed in floating
point, so the computed Z differs from the model's by ΔZ with ‖ΔZ‖ ≲ δ·w,

    w = ‖Q‖_F + Ω²‖M‖_F + |Ω|‖P‖_F      (w(s) = |s|²‖M‖_F + |s|‖P‖_F + ‖Q‖_F: the weight of
                                          the eigenpairs' backward error η, mbseig.eigen.measures)
    δ = SAFETY · n · ε                    (n the model's coordinates, ε the unit roundoff)

n·ε is the standard bound of the rounding in a sum of n products (each entry of M, P, Q is such
a sum, projected on the null-space basis N, then combined into Z) and of the backward error of
the SVD of an n×n matrix; SAFETY = 10 covers the few roundings per entry on top of those
sums.  (Measured on the bundled rigid rotor, natively and under the Haswell and Sandybridge
kernels of OpenBLAS, where δ = 2.7e-14: σ_min/w ≤ 3e-18 at Ω = 100 and 400 rad/s, ≤ 5e-17 at
the double nearest √(2ky/m); the smallest σ_min/w of a regular speed of Omega=0:800:41 is
2.1e-5, at 20 rad/s.)

Singular.  Z counts as singular along the right singular vectors V_K whose singular values
σ_k ≤ δ·w: within the accuracy of Z, a perturbation no larger than its own rounding makes it
exactly singular (the excitation frequency is then an eigenvalue of a QEP within backward error
δ, the definition used for the eigenpairs).  Where σ_min > δ·w the response is determined, to
the relative error κ·δ/(1 − κ·δ) with κ = w/σ_min (first order: ‖Δx‖/‖x‖ ≤ κ‖ΔZ‖/w).

Excited.  The minimum-norm solution in the complement, x_c = Σ_{σ_k > δw} v_k (u_kᴴ f)/σ_k, is
checked by its residual: its normwise backward error (Rigal & Gaches 1967)

    η = ‖Z x_c − f‖ / (w ‖x_c‖ + ‖f‖)

is, up to rounding, ‖U_Kᴴ f‖/(w‖x_c‖ + ‖f‖): the force's component along the near-null left
vectors U_K against the largest value that the accuracy of Z gives it for a force that does not
drive them (a perturbation ΔZ turns U_K towards each retained u_j by ‖ΔZ‖/σ_j to first order,
which puts at most ‖ΔZ‖·‖Σ_j u_j (u_jᴴ f)/σ_j‖ = ‖ΔZ‖‖x_c‖ ≤ δw‖x_c‖ of f on the computed U_K;
the rounding of f adds δ‖f‖).  η ≤ δ: x_c solves exactly a model within the accuracy of this
one, the force does not drive the singular directions, and x_c is the response (status
``"singular"``).  η > δ: a resonance (status ``"resonance"``): a model within the accuracy of Z
is exactly singular with f outside its range, so no steady response exists (an undamped mode
driven at its own frequency grows linearly in time); the amplitude a solver would print,
‖U_Kᴴ f‖/σ_K, is set by rounding alone.

At a singular, unexcited frequency the steady response is not unique: any amount of the free
mode V_K can be added.  x_c carries none of it (minimum norm in the coordinates of Z); where the
free mode is decoupled from the loaded ones (the axial and torsional modes of an axisymmetric
rotor under an unbalance) that is also the limit of the response at the neighbouring speeds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SolverError

__all__ = ["SAFETY", "EPS", "Harmonic", "accuracy", "solve_harmonic", "weight"]

EPS = float(np.finfo(float).eps)
SAFETY = 10.0


def accuracy(n) -> float:
    """δ = SAFETY · n · ε, the relative accuracy of a dynamic stiffness of n coordinates."""
    return SAFETY * max(int(n), 1) * EPS


def weight(norms, s) -> float:
    """w = |s|²‖M‖ + |s|‖P‖ + ‖Q‖ from (‖M‖, ‖P‖, ‖Q‖) at the (complex) frequency s."""
    nM, nP, nQ = norms
    a = abs(s)
    return float(a * a * nM + a * nP + nQ)


@dataclass(frozen=True, eq=False)
class Harmonic:
    """One solve of Z x = f.

    x : the response (None at a resonance).
    status : ``"regular"`` (σ_min > δw), ``"singular"`` (singular, not excited: x is the
        minimum-norm solution x_c) or ``"resonance"``.
    sigma_min : σ_min(Z)/w.
    tolerance : δ.
    backward_error : η of x (of x_c at a resonance, where it measures the excitation).
    free : the number of singular directions (σ_k ≤ δw).
    error : a first-order bound of ‖Δx‖/‖x‖, κδ with κ = w/σ_r (σ_r the smallest singular
        value kept), or None at a resonance.
    """

    x: object
    status: str
    sigma_min: float
    tolerance: float
    backward_error: float
    free: int
    error: object

    @property
    def resonance(self) -> bool:
        return self.status == "resonance"

    def to_json(self) -> dict:
        return {"status": self.status, "sigma_min": self.sigma_min, "tolerance": self.tolerance,
                "backward_error": self.backward_error, "free_directions": self.free,
                "error_bound": self.error}


def _svd(Z):
    try:
        return np.linalg.svd(Z)
    except np.linalg.LinAlgError:  # gesdd did not converge: the same factorization by gesvd
        import scipy.linalg as sla

        try:
            return sla.svd(Z, lapack_driver="gesvd")
        except np.linalg.LinAlgError:
            raise SolverError("the singular value decomposition of the dynamic stiffness did "
                              "not converge", element="harmonic response") from None


def solve_harmonic(Z, f, w, *, n) -> Harmonic:
    """Z x = f for the dynamic stiffness Z (weight ``w``, module docstring) of a model of ``n``
    coordinates: regular, singular and not excited (minimum norm), or a resonance."""
    Z = np.asarray(Z, complex)
    f = np.asarray(f, complex)
    delta = accuracy(n)
    if not (np.all(np.isfinite(Z)) and np.all(np.isfinite(f))):
        raise SolverError("the dynamic stiffness or the force is not finite",
                          element="harmonic response")
    U, s, Vh = _svd(Z)
    w = max(float(w), float(s[0]) if s.size else 0.0)
    keep = s > delta * w
    c = U.conj().T @ f
    y = np.zeros_like(c)
    y[keep] = c[keep] / s[keep]
    x = Vh.conj().T @ y
    fn = float(np.linalg.norm(f))
    xn = float(np.linalg.norm(x))
    den = w * xn + fn
    eta = float(np.linalg.norm(Z @ x - f)) / den if den > 0 else 0.0
    sigma = float(s[-1]) / w if w > 0 else 0.0
    free = int(np.count_nonzero(~keep))
    kappa = w / float(s[keep][-1]) if keep.any() else np.inf
    error = float(kappa * delta / (1 - kappa * delta)) if kappa * delta < 1 else np.inf
    if free == 0:
        if eta > delta:  # the SVD solve is backward stable: this would be a broken LAPACK
            raise SolverError(f"the solve of the dynamic stiffness missed its accuracy "
                              f"(backward error {eta:.2g} > {delta:.2g})",
                              element="harmonic response")
        return Harmonic(x, "regular", sigma, delta, eta, 0, error)
    if eta <= delta:
        return Harmonic(x, "singular", sigma, delta, eta, free, error)
    return Harmonic(None, "resonance", sigma, delta, eta, free, None)
