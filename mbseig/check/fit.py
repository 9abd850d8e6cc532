"""Reading a simulated mode: the amplitude that keeps it linear, the modal coordinate by the left
vector, the fit of its decay and frequency, and the probe of a rigid-body mode."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from ..errors import SimulationError


def judge(mc, s, delta_rtol, omega_rtol, zero_delta_tol, resolution_k, ode_rtol):
    """Pass/fail of a simulated mode against tolerances tied to the run's resolution (module
    docstring), and what the run could not resolve."""
    floor = ode_rtol * abs(s)
    u_d = max(resolution_k * mc.se_delta, floor, mc.amplitude_share_delta)
    u_w = max(resolution_k * mc.se_omega, floor, mc.amplitude_share_omega)
    w_p = mc.predicted_omega if mc.kind not in ("overdamped", "divergence") else 0.0
    w_scale = w_p if w_p > 0 else abs(s)
    tol_d = max(delta_rtol * abs(mc.predicted_delta), u_d)
    tol_w = max(omega_rtol * w_scale, u_w)
    err_d, err_w = abs(mc.measured_delta - mc.predicted_delta), abs(mc.measured_omega - w_p)
    notes = [mc.unresolved] if mc.unresolved else []
    if u_d > zero_delta_tol * abs(s):
        notes.append(f"δ resolved only to ±{u_d:.2g} (> zero_delta_tol·|s| = "
                     f"{zero_delta_tol * abs(s):.2g})")
    if u_w > omega_rtol * w_scale:
        notes.append(f"ω resolved only to ±{u_w:.2g} (> omega_rtol·ω = {omega_rtol * w_scale:.2g}; "
                     f"the run turns {abs(w_p) * mc.duration:.3g} rad)")
    return replace(mc, rel_error_delta=err_d / (tol_d / delta_rtol),
                   rel_error_omega=err_w / (tol_w / omega_rtol),
                   passed=bool(err_d <= tol_d and err_w <= tol_w), resolution_delta=u_d,
                   resolution_omega=u_w, tolerance_delta=tol_d, tolerance_omega=tol_w,
                   unresolved="; ".join(notes))


def amplification(Mr, Pr, s, x, yh):
    """How much a relative error of the state (x, ẋ ~ |s| x) grows in the modal coordinate:
    ‖y‖(‖sM + P‖ + |s|‖M‖)‖x‖ / |yᴴ(2sM + P)x| (≈ 1 for a well separated mode, ≈ ω_n/ω_d for
    a pair near critical damping, ∞ for a Jordan block)."""
    den = abs(yh @ ((2 * s * Mr + Pr) @ x))
    num = np.linalg.norm(yh) * (np.linalg.norm(s * Mr + Pr) + abs(s) * np.linalg.norm(Mr)) \
        * np.linalg.norm(x)
    return float(num / den) if den > 0 else math.inf


def smaller_amplitude(big, small):
    """The run at a tenth of the amplitude is the measurement; how far it moved from the full
    amplitude's is the amplitude-dependent share of the error (a bound of what remains in it
    for any error growing like aᵖ, p ≥ 1), counted into the resolution."""
    return replace(small, amplitude_share_delta=abs(big.measured_delta - small.measured_delta),
                   amplitude_share_omega=abs(big.measured_omega - small.measured_omega))


def left_row(modes, j, Mr, Pr, Qr, repeat_rtol=1e-8):
    """yᴴ of listed mode j, for the modal coordinate: the eigensolver's left vector
    (``Modes.left_vectors``) when s_j is a simple eigenvalue; for a repeated one (another
    eigenvalue within ``repeat_rtol``·max(|s|, 1)), the left null vector of s²M + sP + Q best
    aligned with (2sM + P)x, so that the modal coordinate of this shape is picked out."""
    s, x = complex(modes.eigenvalues[j]), modes.vectors[:, j]
    near = np.abs(modes.all_eigenvalues - s) <= repeat_rtol * max(abs(s), 1.0)
    if modes.left_vectors is not None and int(np.sum(near)) == 1:
        return np.asarray(modes.left_vectors[:, j])  # conjugated left vector: yᴴ = ȳᵀ
    return left_vector(Mr, Pr, Qr, s, x).conj()


def left_vector(Mr, Pr, Qr, s, x, rtol=1e-8):
    """y with yᴴ(s²M + sP + Q) = 0 and yᴴ(2sM + P)x real positive (largest over a repeated
    eigenvalue's left null space)."""
    T = s * s * Mr + s * Pr + Qr
    U, sv, _ = np.linalg.svd(T)
    k = max(1, int(np.sum(sv <= rtol * max(sv[0], 1e-300))))
    Y = U[:, -k:]
    b = Y.conj().T @ ((2 * s * Mr + Pr) @ x)
    if np.linalg.norm(b) == 0:
        raise SimulationError(f"eigenvalue {s:.6g} is defective (yᴴ(2sM + P)x = 0): its modal "
                              f"coordinate is undefined")
    return Y @ b


def probe_rigid(dyn, Mr, N, x, a, modes, eq, length, names):
    """(ω_eff, ω_ref) for a listed rigid-body mode: does the nonlinear model really offer no
    restoring force along it?

    The reduced accelerations at q₀ ± a N x̂ (projected onto the constraints, q̇ = 0) give by
    central differences k_eff = −x̂ᵀM_r(ẍ₊ − ẍ₋) / (2a x̂ᵀM_r x̂) and ω_eff = √|k_eff|; the
    O(a²) offset of the projected start from a curved rigid motion is even in a and cancels.
    ω_ref is the scale of the mode at hand (:func:`mode_scale`): the forces and stiffnesses on
    the points it moves, so a stiff element elsewhere in the model cannot hide a restoring
    force.  A linearization that drops a stiffness (the pendulum without Σλ∇²Φ) reports a
    rigid-body mode that fails this probe.
    """
    x = x.real if np.linalg.norm(x.real) >= np.linalg.norm(x.imag) else x.imag
    full = N @ x
    x = x / full[int(np.argmax(np.abs(full)))]
    acc = []
    for sign in (1.0, -1.0):
        u, _, _, _ = dyn.project(sign * a * (N @ x), np.zeros(dyn.n))
        qdd, _ = dyn.acceleration(dyn.q0 + u, np.zeros(dyn.n))
        acc.append(N.T @ qdd)
    k_eff = -(x @ Mr @ (acc[0] - acc[1])) / (2 * a * (x @ Mr @ x))
    w_eff = math.sqrt(abs(k_eff))
    w_ref = mode_scale(dyn, N @ x, eq, length, names)
    if w_ref == 0.0:  # nothing acts on these points: the model's other modes give the scale
        others = [abs(s) for s, kd in zip(modes.eigenvalues, modes.kind, strict=True)
                  if kd != "rigid-body"]
        w_ref = max(others, default=0.0)
    return w_eff, w_ref


def mode_scale(dyn, shape, eq, length, names, involved_tol=1e-3):
    """Frequency scale of the points a mode moves: ω_ref² = max(f/(L m), k/m) over those points'
    coordinates, with f the largest applied generalized force at equilibrium, k the largest
    row sum of |K + Σλ∇²Φ| (forces' and constraint forces' stiffness) and m the largest row
    sum of |M| of the coordinates that move (|shape| ≥ involved_tol·max)."""
    mag = np.abs(shape)
    moving = np.flatnonzero(mag >= involved_tol * mag.max()) if mag.size and mag.max() > 0 else []
    groups = {str(names[j]).rsplit(".", 1)[0] for j in moving}
    coords = [j for j, nm in enumerate(names) if str(nm).rsplit(".", 1)[0] in groups]
    if not coords:
        return 0.0
    Mabs = np.abs(dyn.M)
    m = float(np.max(Mabs[moving].sum(axis=1), initial=0.0))
    if m <= 0:
        return 0.0
    q0 = dyn.q0
    if dyn.linear:
        g = np.zeros(dyn.n)
        K = np.abs(np.asarray(dyn.Q))
    else:
        g = np.asarray(dyn.force(q0, np.zeros(dyn.n)))
        K = abs(dyn.model.force_jacobians(q0)[0])
        lam = getattr(eq, "lam", None)
        if dyn.m and lam is not None and len(lam):
            K = K + abs(dyn.model.constraint_hessian(q0, lam))
        K = K.toarray() if sp.issparse(K) else np.asarray(K)
    f = float(np.max(np.abs(g[coords]), initial=0.0))
    k = float(np.max(K[coords].sum(axis=1), initial=0.0))
    return math.sqrt(max(f / (length * m), k / m))


def fit_exponential(t, eta):
    """Least-squares fit of η(t) = η₀ e^{(−δ + iω) t}: log|η| and unwrapped arg η linear in t.

    Returns (δ, ω, rms residual of log η, fitted |η₀|, standard error of δ, of ω); the
    standard errors are those of the two slopes from the residuals (N − 2 degrees of freedom).
    """
    mag = np.abs(eta)
    if np.any(mag == 0) or not np.all(np.isfinite(mag)):
        raise SimulationError("the modal coordinate vanished or overflowed during the run")
    logm = np.log(mag)
    ph = np.unwrap(np.angle(eta))
    A = np.column_stack([np.ones_like(t), t])
    (c0, c1), *_ = np.linalg.lstsq(A, logm, rcond=None)
    (p0, p1), *_ = np.linalg.lstsq(A, ph, rcond=None)
    r_m, r_p = logm - c0 - c1 * t, ph - p0 - p1 * t
    res = np.sqrt(np.mean(r_m**2 + r_p**2))
    sxx = float(np.sum((t - t.mean()) ** 2))
    dof = max(t.size - 2, 1)
    se_d = math.sqrt(float(np.sum(r_m**2)) / dof / sxx) if sxx > 0 else math.inf
    se_w = math.sqrt(float(np.sum(r_p**2)) / dof / sxx) if sxx > 0 else math.inf
    return float(-c1), float(p1), float(res), float(np.exp(c0)), se_d, se_w
