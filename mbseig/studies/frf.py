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
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import CaseError
from ..numerics import jsonable

__all__ = ["FRF", "frf", "frf_json", "write_frf", "bode_figure", "zeros", "dc_gain",
           "default_band"]

ZERO_TOL = 1e-9


class FRF:
    """One input → one output: frequencies (Hz), complex response, poles, zeros, DC gain."""

    def __init__(self, input_name, output_name, freq_hz, response, poles, zeros_, dc, units):
        self.input, self.output = input_name, output_name
        self.freq_hz, self.response = np.asarray(freq_hz, float), np.asarray(response, complex)
        self.poles, self.zeros, self.dc_gain, self.units = poles, zeros_, dc, units


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
    from ..eigen import Problem, Request, solve

    s = np.asarray(solve(Problem(lin.M, lin.P, lin.Q), Request()).eigenvalues, complex)
    return s[np.lexsort((s.imag, s.real, np.abs(s)))]


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
    p = poles(lin)
    if freq_hz is None:
        lo, hi = default_band(p)
        freq_hz = np.geomspace(lo, hi, 500)
    freq_hz = np.asarray(freq_hz, float)
    b, cq, cv, d = _io(lin, input_name, output_name)
    M, P, Q = (np.asarray(X, float) for X in (lin.M, lin.P, lin.Q))
    resp = np.empty(freq_hz.size, complex)
    for k, f in enumerate(freq_hz):
        s = 2j * np.pi * f
        try:
            x = np.linalg.solve(M * s * s + P * s + Q, b)
        except np.linalg.LinAlgError:
            raise CaseError(f"{f:g} Hz is a pole of the system (M s² + P s + Q singular): "
                            f"choose other frequencies", element="--hz") from None
        resp[k] = (cq + s * cv) @ x + d
    j = list(lin.output_names).index(output_name)
    i = list(lin.input_names).index(input_name)
    units = (lin.output_units[j] if lin.output_units else "",
             lin.input_units[i] if lin.input_units else "")
    return FRF(input_name, output_name, freq_hz, resp, p, zeros(lin, input_name, output_name),
               dc_gain(lin, input_name, output_name), units)


def frf_json(r: FRF) -> dict:
    """The fixed ``mbseig frf --json`` object (DESIGN §8)."""
    return jsonable({
        "input": r.input, "output": r.output,
        "freq_hz": [float(f) for f in r.freq_hz],
        "response": [[float(z.real), float(z.imag)] for z in r.response],
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
    (ax2.semilogx if np.all(f > 0) else ax2.plot)(f, np.degrees(np.unwrap(np.angle(r.response))))
    ax2.set_ylabel("phase [deg]")
    ax2.set_xlabel("frequency [Hz]")
    ax2.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{r.input} → {r.output}")
    return fig


def write_frf(r: FRF, out_dir):
    """``frf.csv`` (freq_hz, re, im, magnitude, phase_deg) and ``bode.png`` in ``out_dir``."""
    from pathlib import Path

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        phase = np.degrees(np.angle(r.response))
        lines = ["freq_hz,re,im,magnitude,phase_deg"]
        lines += [f"{f:.12g},{z.real:.12g},{z.imag:.12g},{abs(z):.12g},{ph:.12g}"
                  for f, z, ph in zip(r.freq_hz, r.response, phase)]
        (out / "frf.csv").write_text("\n".join(lines) + "\n")
        bode_figure(r).savefig(out / "bode.png", dpi=100, metadata={"Software": None})
    except OSError as exc:
        raise CaseError(f"cannot write: {exc.strerror or exc}", file=str(out),
                        element="--out") from None
    return out
