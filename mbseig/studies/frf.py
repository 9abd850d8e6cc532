"""Frequency response, poles, zeros and DC gain of one input → one output of a linear model
(``mbseig frf``; DESIGN §8, docs/design.md "Inputs and outputs").

With M ẍ + P ẋ + Q x = B u and y = C_q x + C_v ẋ + D u (C = [C_q, C_v]):

    G(s) = (C_q + s C_v)(M s² + P s + Q)⁻¹ b + d          (no M⁻¹ formed)
    G(0) = C_q Q⁻¹ b + d                                   (None when Q is singular)

Poles: every finite eigenvalue of M s² + P s + Q (the dense eigensolver of :mod:`mbseig.eigen`,
each listed, conjugates included).  Zeros: the finite generalized eigenvalues of the Rosenbrock
pencil of the descriptor form E ż = A z + B u, z = [x; ẋ]:

    ┌ A  b ┐       ┌ E  0 ┐        A = ┌  0   I ┐,  E = ┌ I  0 ┐
    └ c  d ┘ −  s  └ 0  0 ┘            └ −Q  −P ┘       └ 0  M ┘

(QZ, :func:`scipy.linalg.eig`; an eigenvalue α/β counts as finite when |β| > ZERO_TOL·|α|
after the pencil's rows are balanced), so a zero is where the output can stay at rest while the
input moves the system: the poles of the zero dynamics.

A pole on the frequency grid.  Z(s) = M s² + P s + Q is solved by LU with its backward error
checked (≤ δ, :mod:`mbseig.studies.harmonic`); near a pole (within 100 times the first-order
distance κ_p(δ + η_p) of a pole p whose s = iω would make Z singular within the accuracy δ,
plus 100 √(δ + η_p)·max(|p|, γ) for a double defective one, γ = √(‖Q‖/‖M‖)), or where that check
fails, by the SVD of :func:`~mbseig.studies.harmonic.solve_harmonic`, which decides whether Z is
singular.  Where it is, G is a rational function with an isolated singularity at s₀, and its
Laurent coefficients come from N_CONTOUR values on a circle s₀ + r e^{iθ} that holds the poles
within √δ·max(|s₀|, γ) of s₀ and no other (r a quarter of the distance to the next pole, at
least 4 times that radius, so both ratios are ≤ 1/4):

    ĝ_m = (1/N) Σ_k G(s₀ + r e^{iθ_k}) e^{−imθ_k} ≈ a_m r^m     (trapezoid rule, exact to
                                                                 4^{−(N−8)} for |m| ≤ 8)

The principal part a_{−1} … a_{−8} against the error of the sampled values (each G_k to
κ_k δ of ‖c‖‖x_k‖, κ_k = w/σ_min at that point) decides: zero within it, the singularity is
removable (the pole is not excited by the input or not seen by the output) and G(s₀) = ĝ₀, the
transfer function's limit; otherwise a pole on the grid, a resonance (``response`` null,
``resonance`` true).  A pole of order above 8 at s₀ would need a Jordan chain longer than 8.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import CaseError, SolverError
from ..numerics import jsonable
from .harmonic import accuracy, solve_harmonic, weight

__all__ = ["FRF", "frf", "frf_json", "write_frf", "bode_figure", "zeros", "dc_gain",
           "default_band"]

ZERO_TOL = 1e-9
N_CONTOUR = 64    # points on the circle around a pole on the grid
MAX_ORDER = 8     # Laurent coefficients a_{-1} ... a_{-MAX_ORDER} tested
GATE = 100.0      # margin of the distance to a pole inside which the SVD decides


class FRF:
    """One input → one output: frequencies (Hz), complex response (NaN at a resonance), poles,
    zeros, DC gain; ``singular``: per grid frequency where Z was singular, a dict (``freq_hz``,
    ``status`` "pole" or "limit", ``principal`` the largest |ĝ_{−m}|, ``error`` its bound)."""

    def __init__(self, input_name, output_name, freq_hz, response, poles, zeros_, dc, units,
                 singular=()):
        self.input, self.output = input_name, output_name
        self.freq_hz, self.response = np.asarray(freq_hz, float), np.asarray(response, complex)
        self.poles, self.zeros, self.dc_gain, self.units = poles, zeros_, dc, units
        self.singular = list(singular)

    @property
    def resonance(self) -> np.ndarray:
        """Per frequency: a pole on the grid that the input drives and the output sees."""
        return ~np.isfinite(self.response)


def _io(lin, input_name, output_name):
    if lin.B is None:
        raise CaseError("the model was kept sparse: no input and output matrices",
                        element="frf")
    if not lin.input_names:
        raise CaseError("the case has no [[inputs]]", element="--input")
    if not lin.output_names:
        raise CaseError("the case has no [[outputs]]", element="--output")
    names_i, names_o = list(lin.input_names), list(lin.output_names)
    if input_name not in names_i:
        raise CaseError(f"unknown input {input_name!r} (known: {', '.join(names_i)})",
                        element="--input")
    if output_name not in names_o:
        raise CaseError(f"unknown output {output_name!r} (known: {', '.join(names_o)})",
                        element="--output")
    i, j = names_i.index(input_name), names_o.index(output_name)
    n = lin.dof
    return lin.B[:, i], lin.C[j, :n], lin.C[j, n:], float(lin.D[j, i])


def dc_gain(lin, input_name, output_name):
    """G(0) = C_q Q⁻¹ b + d, or None when Q is singular (a rigid-body mode: no static gain)."""
    b, cq, _, d = _io(lin, input_name, output_name)
    Q = np.asarray(lin.Q, float)
    if np.linalg.cond(Q) > 1e14:
        return None
    return float(cq @ np.linalg.solve(Q, b) + d)


def poles(lin):
    """Every finite eigenvalue of M s² + P s + Q (conjugates included), sorted by |s|, Re s."""
    return _poles(lin)[0]


def _poles(lin):
    """(poles sorted as :func:`poles`, their η, their κ)."""
    from ..eigen import Problem, Request, solve

    sol = solve(Problem(lin.M, lin.P, lin.Q), Request())
    s = np.asarray(sol.eigenvalues, complex)
    order = np.lexsort((s.imag, s.real, np.abs(s)))
    return s[order], np.asarray(sol.backward_error, float)[order], \
        np.asarray(sol.condition, float)[order]


def zeros(lin, input_name, output_name):
    """Finite invariant zeros of the Rosenbrock pencil (module docstring), sorted by |s|."""
    b, cq, cv, d = _io(lin, input_name, output_name)
    n = lin.dof
    M, P, Q = (np.asarray(X, float) for X in (lin.M, lin.P, lin.Q))
    A = np.zeros((2 * n + 1, 2 * n + 1))
    E = np.zeros_like(A)
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n], A[n:2 * n, n:2 * n], A[n:2 * n, 2 * n] = -Q, -P, b
    A[2 * n, :n], A[2 * n, n:2 * n], A[2 * n, 2 * n] = cq, cv, d
    E[:n, :n], E[n:2 * n, n:2 * n] = np.eye(n), M
    # balance the rows (the dynamic rows by their size, the output row by its own)
    r = np.maximum(np.abs(np.hstack([A, E])).max(axis=1), np.finfo(float).tiny)
    A, E = A / r[:, None], E / r[:, None]
    w = sla.eig(A, E, right=False, homogeneous_eigvals=True)
    alpha, beta = w
    finite = np.abs(beta) > ZERO_TOL * np.abs(alpha)
    z = alpha[finite] / beta[finite]
    z = np.where(np.abs(z.imag) <= 1e-12 * np.maximum(np.abs(z), 1e-300), z.real + 0j, z)
    return z[np.lexsort((z.imag, z.real, np.abs(z)))]


def default_band(p):
    """(f_lo, f_hi) Hz around the poles: a decade below the smallest nonzero |s| to a decade
    above the largest."""
    w = np.abs(p)
    w = w[w > 0]
    if not w.size:
        return 0.01, 100.0
    return float(w.min() / (2 * np.pi) / 10), float(w.max() / (2 * np.pi) * 10)


def frf(lin, input_name, output_name, freq_hz=None) -> FRF:
    """The frequency response of ``output_name`` to ``input_name`` at ``freq_hz`` (default:
    500 log-spaced frequencies of :func:`default_band`), with poles, zeros and DC gain."""
    p, eta, kappa = _poles(lin)
    if freq_hz is None:
        lo, hi = default_band(p)
        freq_hz = np.geomspace(lo, hi, 500)
    freq_hz = np.asarray(freq_hz, float)
    b, cq, cv, d = _io(lin, input_name, output_name)
    sys = _System(lin, b, cq, cv, d, p, eta, kappa)
    resp = np.empty(freq_hz.size, complex)
    singular = []
    for k, f in enumerate(freq_hz):
        resp[k], info = sys.at(2j * np.pi * f)
        if info is not None:
            singular.append({"freq_hz": float(f), **info})
    j = list(lin.output_names).index(output_name)
    i = list(lin.input_names).index(input_name)
    units = (lin.output_units[j] if lin.output_units else "",
             lin.input_units[i] if lin.input_units else "")
    return FRF(input_name, output_name, freq_hz, resp, p, zeros(lin, input_name, output_name),
               dc_gain(lin, input_name, output_name), units, singular)


class _System:
    """G(s) = (c_q + s c_v) Z(s)⁻¹ b + d at grid frequencies, poles on the grid included
    (module docstring)."""

    def __init__(self, lin, b, cq, cv, d, p, eta, kappa):
        self.M, self.P, self.Q = (np.asarray(X, float) for X in (lin.M, lin.P, lin.Q))
        self.b, self.cq, self.cv, self.d = b, cq, cv, d
        self.norms = tuple(float(np.linalg.norm(X)) for X in (self.M, self.P, self.Q))
        self.n = max(lin.N.shape[0] if getattr(lin, "N", None) is not None else 0, lin.dof)
        self.delta = accuracy(self.n)
        nM, _, nQ = self.norms
        self.gamma = float(np.sqrt(nQ / nM)) if nM > 0 else 0.0
        self.p = p
        e = self.delta + np.nan_to_num(eta, nan=np.inf)
        k = np.where(np.isfinite(kappa), kappa, 0.0)
        self.gate = GATE * (k * e + np.sqrt(e) * np.maximum(np.abs(p), self.gamma))

    def _z(self, s):
        return self.M * (s * s) + self.P * s + self.Q

    def _value(self, s, x):
        return (self.cq + s * self.cv) @ x + self.d

    def at(self, s):
        """(G(s), None) at a regular point; (G(s₀) or NaN, info) where Z(s₀) is singular."""
        Z, w = self._z(s), weight(self.norms, s)
        if not np.any(np.abs(self.p - s) <= self.gate):
            try:
                x = np.linalg.solve(Z, self.b)
                den = w * np.linalg.norm(x) + np.linalg.norm(self.b)
                if np.all(np.isfinite(x)) and np.linalg.norm(Z @ x - self.b) <= self.delta * den:
                    return self._value(s, x), None
            except np.linalg.LinAlgError:
                pass
        h = solve_harmonic(Z, self.b, w, n=self.n)
        if h.status == "regular":
            return self._value(s, h.x), None
        return self._limit(s)

    def _limit(self, s0):
        """The Laurent coefficients of G about s₀ from a circle (module docstring)."""
        dist = np.abs(self.p - s0)
        rho = np.sqrt(self.delta) * max(abs(s0), self.gamma)
        if not np.any(dist <= rho) and dist.size:
            rho = float(dist.min())
        out = dist[dist > rho]
        d_out = float(out.min()) if out.size else np.inf
        if d_out < 16 * rho:  # another pole too close to hold the circle between them
            return np.nan + 0j, {"status": "pole", "principal": None, "error": None,
                                 "reason": f"another pole within {d_out:.3g} of s"}
        # as far from the singularity as the next pole allows: the samples are then moderate
        # (a small circle would sample G where it is huge and cancels in c·x)
        r = d_out / 4 if np.isfinite(d_out) else max(4 * rho, abs(s0), self.gamma)
        theta = 2 * np.pi * (np.arange(N_CONTOUR) + 0.5) / N_CONTOUR
        G = np.empty(N_CONTOUR, complex)
        err = 0.0
        for k, th in enumerate(theta):
            s = s0 + r * np.exp(1j * th)
            h = solve_harmonic(self._z(s), self.b, weight(self.norms, s), n=self.n)
            if h.status != "regular":
                raise SolverError(f"a pole on the circle of radius {r:.3g} around s = {s0:.6g}",
                                  element="frf")
            c = self.cq + s * self.cv
            G[k] = c @ h.x + self.d
            err = max(err, (h.error + self.delta) * np.linalg.norm(c) * np.linalg.norm(h.x))
        coef = lambda m: np.mean(G * np.exp(-1j * m * theta))  # noqa: E731
        principal = max(abs(coef(-m)) for m in range(1, MAX_ORDER + 1))
        info = {"principal": float(principal), "error": float(err)}
        if principal <= err:
            return coef(0), {"status": "limit", **info}
        return np.nan + 0j, {"status": "pole", **info}


def frf_json(r: FRF) -> dict:
    """The fixed ``mbseig frf --json`` object (DESIGN §8)."""
    return jsonable({
        "input": r.input, "output": r.output,
        "freq_hz": [float(f) for f in r.freq_hz],
        "response": [[float(z.real), float(z.imag)] if np.isfinite(z) else None
                     for z in r.response],
        "resonance": [bool(x) for x in r.resonance],
        "singular": r.singular,
        "dc_gain": r.dc_gain,
        "poles": [[float(z.real), float(z.imag)] for z in r.poles],
        "zeros": [[float(z.real), float(z.imag)] for z in r.zeros],
    })


def bode_figure(r: FRF):
    """Magnitude and phase against frequency (a matplotlib Figure; no pyplot)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 6))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    mag = np.abs(r.response)
    f = r.freq_hz
    plot = ax1.loglog if np.all(f > 0) else ax1.semilogy
    plot(f, np.where(mag > 0, mag, np.nan))
    yu, uu = r.units
    ax1.set_ylabel(f"|{r.output} / {r.input}|" + (f" [{yu}/{uu}]" if yu and uu else ""))
    ax1.grid(True, which="both", alpha=0.3)
    ok = np.isfinite(r.response)
    phase = np.full(f.size, np.nan)
    if ok.any():  # unwrapped over the finite values: a pole on the grid breaks the curve
        phase[ok] = np.degrees(np.unwrap(np.angle(r.response[ok])))
    (ax2.semilogx if np.all(f > 0) else ax2.plot)(f, phase)
    for k, fk in enumerate(f[~ok]):
        for ax in (ax1, ax2):
            ax.axvline(fk, color="tab:red", lw=1.0, ls="--",
                       label="pole on the grid: unbounded" if k == 0 and ax is ax1 else None)
    if not ok.all():
        ax1.legend(fontsize=7)
    ax2.set_ylabel("phase [deg]")
    ax2.set_xlabel("frequency [Hz]")
    ax2.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{r.input} → {r.output}")
    return fig


def write_frf(r: FRF, out_dir):
    """``frf.csv`` (freq_hz, re, im, magnitude, phase_deg, resonance: the values blank at a pole
    on the grid) and ``bode.png`` in ``out_dir``."""
    from pathlib import Path

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        phase = np.degrees(np.angle(r.response))
        lines = ["freq_hz,re,im,magnitude,phase_deg,resonance"]
        lines += [f"{f:.12g},{z.real:.12g},{z.imag:.12g},{abs(z):.12g},{ph:.12g},false"
                  if np.isfinite(z) else f"{f:.12g},,,,,true"
                  for f, z, ph in zip(r.freq_hz, r.response, phase, strict=True)]
        (out / "frf.csv").write_text("\n".join(lines) + "\n")
        bode_figure(r).savefig(out / "bode.png", dpi=100, metadata={"Software": None})
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(out),
                        element="--out") from None
    return out
