"""Exponential Adams integration of a stiff, nearly linear system y′ = f(t, y) whose Jacobian J
at the start is known and diagonalizable: the time-domain check of flexible models.

With J = V Λ V⁻¹ (Λ diagonal, complex) and z = V⁻¹ y the system is

    z′ = Λ z + F(t, z),        F = V⁻¹ f(t, V z) − Λ z          (the nonlinear remainder),

and over a step from t_n, with F replaced by the polynomial P(σ) through its values at the
nodes σ_i (in units of the step h, σ = 0 at t_n),

    z(t_n + θh) = e^{θhΛ} z_n + Σ_i β_i(θ) F_i,
    β_i(θ) = h Σ_k a_ik k! θ^{k+1} φ_{k+1}(θhΛ),      P(σ) = Σ_i F_i Σ_k a_ik σ^k,

φ_0 = exp, φ_{k+1}(x) = (φ_k(x) − 1/k!)/x (:func:`phi_functions`).  The linear part, the stiff
and fast modes of a structure among it, is integrated exactly for any h; only the remainder F,
which is of second order in the motion's amplitude for a model displaced from its equilibrium,
is approximated.  So the step is set by how F varies, not by the fastest mode.

One step (PEC, uniform h): predict with the ORDER nodes σ = 0, −1, …, −(ORDER − 1)
(exponential Adams–Bashforth), evaluate F there, correct with the nodes σ = 1, 0, …,
−(ORDER − 2) (exponential Adams–Moulton, the same order); the history keeps F at the predicted
state, so a step costs one evaluation.  Milne's device turns the difference between predictor
and corrector into the corrector's error estimate (``MILNE``), measured as the RMS of
err_i / (atol_i + rtol |y_i|) over the held components and, apart, over the ``loose`` ones (the
unresolved fast modes of the check, held to a loose tolerance), the larger of the two ≤ 1.
One RMS over all components, as scipy's solvers take it, lets the held modes' error grow with
the square root of the number of loose ones: on cases/column_buckling_3d.toml the undamped
modes then measured δ up to 2.0e-4 rad/s, above the 1.8e-4 that rtol·|s| allows (a failed check
with two BLAS threads), against 1e-5 held apart; the max over the components held them as well
but took twice the steps and sent the cantilevers' repeated pairs past the budget.  A
rejected step halves h and restarts from the last accepted state; ``GROW_AFTER`` steps in a row
with an error below ``GROW_BELOW`` double it (also a restart).  A restart takes ORDER steps at
once, solving for their F values by fixed-point iteration (collocation on the nodes 0 … ORDER):
F varies by ‖∂F/∂z‖ h ≪ 1 per step, so the iteration contracts fast; when it does not, h is
halved (an iteration that stalls within the tolerance stops there: F's rounding noise, not the
iteration, sets that floor).  Its error estimate is its end state against the one without the
last node.  Dense output between steps is the same formula at intermediate θ (the corrector's
polynomial), exact in the linear part.

The remainder F carries every error of J: J is only where the integration starts from, not what
it integrates (the run solves y′ = f exactly as far as the error control sees), and a J that is
off makes F larger and the steps shorter, not the result different
(tests/test_check_exponential.py runs the integrator from a deliberately wrong J).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ORDER", "COND_MAX", "ExponentialAdams", "phi_functions", "ExponentialUnusable"]

ORDER = 6  # nodes of the predictor and of the corrector (one new node), the order of both
COND_MAX = 1e6  # largest condition number of V (J's eigenvectors) the method accepts
#: error constants of the order-p Adams–Bashforth and Adams–Moulton methods, γ_p and |γ*_p|
#: (Hairer, Nørsett & Wanner, Solving ODEs I, §III.1, Tables 1.1 and 1.2)
ERROR_CONSTANTS = {5: (95 / 288, 3 / 160), 6: (19087 / 60480, 863 / 60480),
                   7: (5257 / 17280, 275 / 24192)}
#: Milne's estimate of the corrector's local error from the difference between predictor and
#: corrector, |γ*_p| / (γ_p + |γ*_p|).  The exponential weights φ_k(x) are bounded by the
#: classical 1/k! for Re x ≤ 0, so are their error terms.  Order 6 rather than 5: on
#: cases/ross_example_rotor.toml's mode 3 a third of the steps (2.7 s against 9.0 s), on the
#: oblique cantilever's mode 1 the same within the noise; order 7 took twice as long there.
MILNE = ERROR_CONSTANTS[ORDER][1] / sum(ERROR_CONSTANTS[ORDER])
GROW_AFTER = 8
GROW_BELOW = 0.5 ** (ORDER + 2)
MAX_ITER = 12  # fixed-point iterations of a restart
MAX_HALVINGS = 40
_TAYLOR = 2.0  # |x| below which φ_k is summed as its Taylor series
_TERMS = 40


class ExponentialUnusable(Exception):
    """J cannot carry the method (eigenvectors too ill-conditioned): integrate otherwise."""


def phi_functions(x, kmax):
    """φ_0 … φ_kmax at the complex array x: φ_k(x) = Σ_j x^j / (j + k)!, by the recurrence
    φ_{k+1} = (φ_k − 1/k!)/x where |x| ≥ 2 (its error grows at most as (k+1)!/2^k ≤ 315 for k ≤ 7)
    and by 40 terms of the series below (their remainder is below 2^40/40! ≈ 1e-36)."""
    x = np.asarray(x, complex)
    out = np.empty((kmax + 1,) + x.shape, complex)
    big = np.abs(x) >= _TAYLOR
    xb = x[big]
    phi = np.exp(xb)
    out[0][big] = phi
    for k in range(kmax):
        phi = (phi - 1.0 / math.factorial(k)) / xb
        out[k + 1][big] = phi
    xs = x[~big]
    for k in range(kmax + 1):
        term = np.full(xs.shape, 1.0 / math.factorial(k), complex)
        acc = term.copy()
        for j in range(1, _TERMS):
            term = term * xs / (j + k)
            acc = acc + term
        out[k][~big] = acc
    return out


def _lagrange_monomials(nodes):
    """a (m × m): ℓ_i(σ) = Σ_k a_ik σ^k, the Lagrange basis of the nodes."""
    s = np.asarray(nodes, float)
    V = np.vander(s, increasing=True)  # V[j, k] = s_j^k
    return np.linalg.inv(V).T


class ExponentialAdams:
    """The integrator of the module docstring for y′ = fun(t, y), y real of size d, with the
    Jacobian ``J`` (d × d) at the start; ``atol`` (d,) and ``rtol`` as scipy's.  ``scale``
    (d,): the state's natural units (a velocity of a mode of frequency ω in units of ω), in
    which J's eigenvectors are judged: an oscillator's pair (1, ±iω) is parallel in the raw
    state for large ω, orthogonal in units of ω."""

    def __init__(self, fun, J, *, rtol, atol, scale=None, loose=None):
        S = np.ones(len(J)) if scale is None else np.asarray(scale, float)
        lam, V = np.linalg.eig(np.asarray(J, float) * S[None, :] / S[:, None])
        V = V / np.linalg.norm(V, axis=0)
        cond = np.linalg.cond(V)
        if not np.isfinite(cond) or cond > COND_MAX:
            raise ExponentialUnusable(f"the eigenvectors of J have condition {cond:.2g} "
                                      f"(above {COND_MAX:.0e}: J is nearly defective)")
        Vi = np.linalg.inv(V)
        self.fun, self.lam, self.V, self.Vi = fun, lam, S[:, None] * V, Vi / S[None, :]
        self.rtol, self.atol = float(rtol), np.asarray(atol, float)
        self.loose = (np.zeros(len(J), bool) if loose is None
                      else np.asarray(loose, bool).reshape(len(J)))
        self.nfev = 0
        self._weights = {}
        self.rejected = self.restarts = self.steps = 0

    # -- pieces ------------------------------------------------------------------------------
    def F(self, t, z):
        """(F, y) at z; F through y = Re(V z) alone, so that a part of z outside the real
        states (rounding: z of a real y pairs its conjugate modes) cannot feed back."""
        self.nfev += 1
        y = (self.V @ z).real
        return self.Vi @ self.fun(t, y) - self.lam * (self.Vi @ y), y

    def real(self, z):
        """z of the real state Re(V z)."""
        return self.Vi @ (self.V @ z).real

    def weights(self, h, nodes, theta):
        """(e^{θhΛ}, β (m × d)) for the nodes (units of h) at θ, cached per (h, nodes, θ)."""
        key = (h, tuple(nodes), round(float(theta), 12))
        w = self._weights.get(key)
        if w is None:
            a = _lagrange_monomials(nodes)
            m = len(nodes)
            x = theta * h * self.lam
            phis = phi_functions(x, m)
            # β_i = h Σ_k a_ik k! θ^{k+1} φ_{k+1}
            scal = np.array([math.factorial(k) * theta ** (k + 1) for k in range(m)])
            beta = h * (a * scal) @ phis[1:]
            w = (phis[0], beta)
            if len(self._weights) > 4096:
                self._weights.clear()
            self._weights[key] = w
        return w

    def _at(self, z0, Fs, h, nodes, theta):
        E, beta = self.weights(h, nodes, theta)
        return E * z0 + np.sum(beta * np.asarray(Fs), axis=0)

    def _norm(self, err_z, y):
        """The larger of the RMS of |e_i| / (atol_i + rtol |y_i|) over the held components
        and over the ``loose`` ones (module docstring)."""
        e = (self.V @ err_z).real
        w = (e / (self.atol + self.rtol * np.abs(y))) ** 2
        held = float(np.mean(w[~self.loose])) if (~self.loose).any() else 0.0
        loose = float(np.mean(w[self.loose])) if self.loose.any() else 0.0
        return float(np.sqrt(max(held, loose)))

    # -- restart: ORDER steps at once ------------------------------------------------------
    def _restart(self, t0, z0, F0, h, nodes):
        """(F at the ``nodes`` 0 … p, y at the last) over t0 … t0 + p h by fixed-point
        collocation; None when the iteration does not contract."""
        p = ORDER
        Fs = [F0] * (p + 1)
        zs = None
        last = np.inf
        for _ in range(MAX_ITER):
            new = [self._at(z0, Fs, h, nodes, j) for j in range(1, p + 1)]
            if zs is not None:
                change = max(self._norm(a - b, (self.V @ a).real)
                             for a, b in zip(new, zs, strict=True))
                # converged: a change of 1e-2 of the tolerance; or stalled within the
                # tolerance (the rounding noise of F, not the iteration, sets the floor)
                if change <= 1e-2 or (change <= 1.0 and change > 0.5 * last):
                    zs = new
                    break
                if change > 0.5 * last:
                    return None
                last = change
            zs = new
            out = [self.F(t0 + j * h, z) for j, z in zip(range(1, p + 1), zs, strict=True)]
            Fs = [F0] + [o[0] for o in out]
        else:
            return None
        out = [self.F(t0 + j * h, z) for j, z in zip(range(1, p + 1), zs, strict=True)]
        return [F0] + [o[0] for o in out], out[-1][1]

    # -- the run -----------------------------------------------------------------------------
    def run(self, y0, t_eval, h0, *, fixed_step=False, budget=None):
        """y at the times t_eval (t_eval[0] = 0, increasing), starting with the step h0;
        ``fixed_step``: keep h0, no error control (to measure the order).  ``budget``: the most
        right-hand sides a sample (counted from the start, with one period's worth of samples
        as allowance); beyond it the run stops with :class:`ExponentialUnusable` (the step
        follows a fast motion of the remainder, which an L-stable method would damp)."""
        t_eval = np.asarray(t_eval, float)
        d = self.V.shape[0]
        Y = np.empty((d, t_eval.size))
        Y[:, 0] = y0
        T = t_eval[-1]
        t, z = 0.0, self.Vi @ np.asarray(y0, float)
        Fz, _ = self.F(t, z)
        h = float(h0)
        nxt = 1  # next sample to fill
        halvings = 0
        p = ORDER
        nodes = list(range(p + 1))  # a restart's
        pred_nodes = [-i for i in range(p)]
        corr_nodes = [1] + pred_nodes[:-1]

        def over():
            return budget is not None and self.nfev > budget * (nxt + 40)

        while nxt < t_eval.size:
            if over():
                raise ExponentialUnusable(
                    f"the remainder varies faster than the sampling ({self.nfev} right-hand "
                    f"sides by sample {nxt} of {t_eval.size - 1}, budget {budget} a sample): "
                    "fast modes ring into the checked one")
            self.restarts += 1
            got = self._restart(t, z, Fz, h, nodes)
            if got is None:
                h, halvings = self._halve(h, halvings)
                continue
            Fall, y_end = got
            # the restart's error: its end state against the one that leaves out the last node
            # (whose last interval is the predictor's extrapolation: Milne's factor as there)
            z_end = self._at(z, Fall, h, nodes, p)
            err = MILNE * self._norm(z_end - self._at(z, Fall[:-1], h, nodes[:-1], p), y_end)
            if not fixed_step and (not np.isfinite(err) or err > 1.0):
                self.rejected += 1
                h, halvings = self._halve(h, halvings)
                continue
            # samples inside the restart's span
            nxt = self._fill(Y, t_eval, nxt, t, p, (z, Fall, h, nodes))
            t, z = t + p * h, self.real(z_end)
            hist = Fall[:0:-1]  # F_n, F_{n-1}, …: the restart's nodes p … 1
            good = 0
            while nxt < t_eval.size and not over():
                zp = self._at(z, hist, h, pred_nodes, 1.0)
                Fp, yp = self.F(t + h, zp)
                Fc = [Fp] + hist[:-1]
                zc = self._at(z, Fc, h, corr_nodes, 1.0)
                err = MILNE * self._norm(zc - zp, yp)
                if not fixed_step and (not np.isfinite(err) or err > 1.0):
                    self.rejected += 1
                    h, halvings = self._halve(h, halvings)
                    Fz = hist[0]
                    break
                self.steps += 1
                halvings = 0
                nxt = self._fill(Y, t_eval, nxt, t, 1, (z, Fc, h, corr_nodes))
                zc = self.real(zc)
                # PEC: the history keeps F at the predicted state (one evaluation a step; it
                # differs from F at the corrected one by ‖∂F/∂z‖ |z_C − z_P|, far below the
                # step's error where ‖∂F/∂z‖ h ≪ 1, as the restarts' contraction shows)
                Fn = Fp
                t, z = t + h, zc
                hist = [Fn] + hist[:p - 1]
                good = good + 1 if err < GROW_BELOW else 0
                if not fixed_step and good >= GROW_AFTER and t + 2 * h * p < T:
                    h, Fz = 2.0 * h, Fn
                    break
            else:
                if not over():
                    break  # every sample filled
        return Y

    def _halve(self, h, halvings):
        halvings += 1
        if halvings > MAX_HALVINGS:
            raise ArithmeticError(f"exponential integration: the step fell to {h:.3g} after "
                                  f"{MAX_HALVINGS} halvings")
        return 0.5 * h, halvings

    def _fill(self, Y, t_eval, nxt, t0, span, poly):
        """The samples in (t0, t0 + span·h] from the step's polynomial ``poly`` = (z0, F
        values, h, nodes); the index of the next sample."""
        z0, Fs, h, nodes = poly
        t1 = t0 + span * h
        while nxt < t_eval.size and t_eval[nxt] <= t1 * (1 + 1e-14):
            Y[:, nxt] = (self.V @ self._at(z0, Fs, h, nodes, (t_eval[nxt] - t0) / h)).real
            nxt += 1
        return nxt
