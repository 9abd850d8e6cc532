"""The time-domain check of a steady motion (DESIGN §7 for moving systems): the nonlinear model,
non-holonomic rows included, simulated from the reference motion perturbed along a mode, and the
decay rate δ and frequency ω of the response measured and compared with the prediction.

Nonlinear model (inertial coordinates; q, q̇ and the wheels' axial rates Ω are the state)::

    ┌ M    0    Φ_qᵀ  Aᵀ ┐ ┌ q̈ ┐   ┌ f(q, q̇, Ω) ┐
    │ 0    J    0     Bᵀ │ │ Ω̇ │ = │ 0          │          f: forces + the spins' gyroscopic
    │ Φ_q  0    0     0  │ │ λ │   │ γ(q, q̇)    │             moments on the wheel frames
    └ A    B    0     0  ┘ └ μ ┘   └ −Ã(q, q̇) q̇ ┘          Ã = ∂(A q̇)/∂q (the rows' derivative)

integrated by DOP853 (explicit, no numerical damping).  The reference moves as q = 𝓡(t) q̄ + b(t)
(:func:`mbseig.studies.steady.generator`: q̇ = L q + l; 𝓡 = e^{Lt}); the deviation is read in
the moving coordinates, q̄ = 𝓡ᵀ(q − b), p = 𝓡ᵀq̇ − ξ(q̄), and projected onto the reduced state of
the linearization under test, X = [x; z] with x = Nᵀ(q̄ − q₀), z = Tᵀ([Nᵀp; Ω − Ω₀] + S x).  The
modal coordinate is η(t) = yᴴ E X(t) / (yᴴ E X_mode) with y the left vector of the pencil
(s E − A); log|η| and arg η are fitted by straight lines (:func:`mbseig.check.fit.fit_exponential`).

A mode passes when |δ_meas − δ| ≤ max(delta_rtol |δ|, zero_delta_tol |s|) and
|ω_meas − ω| ≤ omega_rtol · max(ω, |s|).  The linearization that drops Ã (``naive=True``) predicts
eigenvalues the nonlinear model does not have: the check fails it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.integrate import solve_ivp

from ..check import ModeCheck

__all__ = ["SteadyCheck", "check_steady", "mode_dict"]


#: the per-mode record of a steady-motion check is the time-domain check's own
#: (:class:`mbseig.check.ModeCheck`); these are the fields it fills and its JSON lists
MODE_FIELDS = ("index", "kind", "eigenvalue", "predicted_delta", "predicted_omega",
               "measured_delta", "measured_omega", "tolerance_delta", "tolerance_omega", "passed",
               "skipped", "duration", "fit_residual", "constraint_drift", "velocity_drift", "nfev")


def mode_dict(m: ModeCheck) -> dict:
    """One mode of a steady-motion check as JSON values."""
    d = {k: getattr(m, k) for k in MODE_FIELDS}
    d["eigenvalue"] = [float(m.eigenvalue.real), float(m.eigenvalue.imag)]
    return d


@dataclass(frozen=True)
class SteadyCheck:
    name: str
    naive: bool
    modes: tuple
    tolerances: dict
    elapsed: float

    @property
    def passed(self) -> bool:
        return all(m.passed is not False for m in self.modes)

    @property
    def failed(self) -> list:
        return [m.index for m in self.modes if m.passed is False]

    def as_dict(self) -> dict:
        return {"case": self.name, "linearization": "naive" if self.naive else "exact",
                "passed": self.passed, "failed": self.failed, "tolerances": dict(self.tolerances),
                "elapsed": self.elapsed, "modes": [mode_dict(m) for m in self.modes]}


class _Dynamics:
    """The nonlinear equations (module docstring) of a model with rolling wheels."""

    def __init__(self, model):
        from .steady import SteadyAssembly

        self.model, self.asm = model, SteadyAssembly(model)
        self.n, self.nw = model.n, len(self.asm.wheels)
        self.nfev = 0

    def split(self, y):
        n = self.n
        return y[:n], y[n:2 * n], y[2 * n:]

    def rhs(self, t, y):
        self.nfev += 1
        asm, n, nw = self.asm, self.n, self.nw
        q, qd, spin = self.split(y)
        f = np.array(self.model.generalized_force(q, qd), float)
        for k, w in enumerate(asm.wheels):
            f[w.idx] += w.gyroscopic(q, qd, spin[k])[0]
        Pq = asm.phi_q(q)
        A, At = asm.velocity(q, qd)
        m, mv = Pq.shape[0], A.shape[0]
        K = np.zeros((n + nw + m + mv,) * 2)
        K[:n, :n] = asm.M
        K[n:n + nw, n:n + nw] = asm.J
        K[:n, n + nw:n + nw + m] = Pq.T
        K[:n, n + nw + m:] = A.T
        K[n:n + nw, n + nw + m:] = asm.B.T
        K[n + nw:n + nw + m, :n] = Pq
        K[n + nw + m:, :n] = A
        K[n + nw + m:, n:n + nw] = asm.B
        rhs = np.concatenate([f, np.zeros(nw), self.model.gamma(q, qd), -At @ qd])
        try:  # nonsingular without redundant rows; else the minimum-norm solution
            sol = np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:
            sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
        return np.concatenate([qd, sol[:n], sol[n:n + nw]])

    def drift(self, y):
        q, qd, spin = self.split(y)
        A, _ = self.asm.velocity(q, qd)
        scale = self.model.constraint_scales()
        return (float(np.max(np.abs(self.model.phi(q) / scale), initial=0.0)),
                float(np.max(np.abs(A @ qd + self.asm.B @ spin), initial=0.0)))


def _frame(L, ell, t):
    """(𝓡 = e^{Lt}, b(t) = ∫₀ᵗ e^{Lτ} l dτ) of the reference motion."""
    n = L.shape[0]
    if not np.any(L):
        return np.eye(n), ell * t
    G = np.zeros((n + 1, n + 1))
    G[:n, :n], G[:n, n] = L, ell
    E = sla.expm(G * t)
    return E[:n, :n], E[:n, n]


def _project(dyn, q, qd, spin, *, tol=1e-14, max_iter=20):
    """q onto Φ = 0 (minimum-norm Newton), then (q̇, Ω) onto the velocity rows (minimum norm)."""
    for _ in range(max_iter):
        r = dyn.model.phi(q)
        if np.max(np.abs(r), initial=0.0) < tol:
            break
        q = q - np.linalg.lstsq(dyn.asm.phi_q(q), r, rcond=None)[0]
    A, _ = dyn.asm.velocity(q, qd)
    W = np.vstack([np.hstack([dyn.asm.phi_q(q), np.zeros((dyn.model.n_constraints, dyn.nw))]),
                   np.hstack([A, dyn.asm.B])])
    v = np.concatenate([qd, spin])
    v = v - np.linalg.lstsq(W, W @ v, rcond=None)[0]
    return q, v[:dyn.n], v[dyn.n:]


def check_steady(spec, *, config=None, params=None, indices=None, naive=False, amplitude=1e-4,
                 periods=20.0, efolds=3.0, delta_rtol=1e-2, omega_rtol=1e-3,
                 zero_delta_tol=1e-5, ode_rtol=1e-10, samples_per_period=40, min_samples=400):
    """Check the listed modes of the steady motion of ``spec`` (module docstring); ``indices``
    are 1-based mode numbers as ``modes`` lists them (default: every one that is not rigid-body).
    ``naive=True`` checks the linearization that drops Ã instead of the exact one."""
    from ..check.fit import fit_exponential
    from ..eigen import Request, descriptor_problem, solve
    from .steady import generator
    from .steady_modes import analyze_steady

    t0 = time.perf_counter()
    a = analyze_steady(spec, config=config, params=params, naive=naive)
    model, st, lin = a.model, a.state, a.linear
    # vectors in the coordinates X = [x; z] (no deflation)
    full = solve(descriptor_problem(lin.E, lin.A), Request(solver="descriptor-qz"))
    L, ell = generator(model, a.motion)
    dyn = _Dynamics(model)
    length = model.length_scale
    d = lin.dof
    out = []
    for row in a.modes:
        if indices is not None and row["index"] not in indices:
            continue
        s = complex(*row["eigenvalue"])
        base = {"index": row["index"], "kind": row["kind"], "eigenvalue": s,
                "predicted_delta": -s.real, "predicted_omega": abs(s.imag),
                "bound_delta": float(row["tolerance"]), "bound_omega": float(row["tolerance"])}
        if row["kind"] == "rigid-body":
            out.append(ModeCheck(**base, skipped="rigid-body (s = 0): not simulated"))
            continue
        j = int(np.argmin(np.abs(full.eigenvalues - s)))
        X, yc = full.vectors[:, j], full.left_vectors[:, j]
        real_mode = row["omega_d"] == 0.0
        if real_mode:
            s = complex(s.real, 0.0)
            X = X.real if np.linalg.norm(X.real) >= np.linalg.norm(X.imag) else X.imag
            X = X.astype(complex)
            T = efolds / abs(s)
            n_samples = min_samples
        else:
            T = periods * 2 * math.pi / abs(s.imag)
            if s.real != 0:
                T = min(T, efolds / abs(s.real))
            n_samples = max(min_samples, int(samples_per_period * T * abs(s.imag) / (2 * math.pi)))
        shape = lin.N @ X[:d]
        k = int(np.argmax(np.abs(shape)))
        X = X / (shape[k] if abs(shape[k]) > 0 else np.max(np.abs(X)))
        amp = amplitude * length * math.exp(-max(0.0, s.real) * T)
        X0 = amp * X.real
        x0, z0 = X0[:d], X0[d:]
        w0 = lin.T @ z0 - lin.S @ x0
        qbar = st.q + lin.N @ x0
        p = lin.N @ w0[:d]
        q, qd, spin = _project(dyn, qbar, p + L @ qbar + ell, st.spin + w0[d:])
        t_eval = np.linspace(0.0, T, n_samples + 1)
        dyn.nfev = 0
        sol = solve_ivp(dyn.rhs, (0.0, T), np.concatenate([q, qd, spin]), method="DOP853",
                        t_eval=t_eval, rtol=ode_rtol, atol=ode_rtol * amp)
        if not sol.success:
            out.append(ModeCheck(**base, skipped=f"integration failed: {sol.message}",
                                       passed=False))
            continue
        den = yc @ (lin.E @ X)
        eta = np.empty(sol.t.size, complex)
        drift_c = drift_v = 0.0
        for i, t in enumerate(sol.t):
            q, qd, spin = dyn.split(sol.y[:, i])
            R, b = _frame(L, ell, t)
            qb = R.T @ (q - b)
            pb = R.T @ qd - (L @ qb + ell)
            x = lin.N.T @ (qb - st.q)
            z = lin.T.T @ (np.concatenate([lin.N.T @ pb, spin - st.spin]) + lin.S @ x)
            eta[i] = yc @ (lin.E @ np.concatenate([x, z])) / den
            c, v = dyn.drift(sol.y[:, i])
            drift_c, drift_v = max(drift_c, c), max(drift_v, v)
        if real_mode:
            eta = eta.real.astype(complex)
        md, mw, res, _, _, _ = fit_exponential(sol.t, eta)
        mw = abs(mw) if real_mode else mw
        tol_d = max(delta_rtol * abs(s.real), zero_delta_tol * abs(s))
        tol_w = omega_rtol * max(abs(s.imag), abs(s))
        ok = abs(md - (-s.real)) <= tol_d and abs(mw - abs(s.imag)) <= tol_w
        out.append(ModeCheck(**base, measured_delta=md, measured_omega=mw,
                                   tolerance_delta=tol_d, tolerance_omega=tol_w, passed=bool(ok),
                                   duration=T, fit_residual=res, constraint_drift=drift_c,
                                   velocity_drift=drift_v, nfev=dyn.nfev))
    tol = {"amplitude": amplitude, "length_scale": length, "periods": periods, "efolds": efolds,
           "delta_rtol": delta_rtol, "omega_rtol": omega_rtol, "zero_delta_tol": zero_delta_tol,
           "ode_rtol": ode_rtol}
    return SteadyCheck(model.name, naive, tuple(out), tol, time.perf_counter() - t0)
