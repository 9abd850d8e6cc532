"""The modes JSON of a periodic case (DESIGN §8, "Periodic motions"): the Floquet exponents
listed as modes with the stability their multipliers decide (:mod:`mbseig.modal.rules`: the
margin 1 − |μ| against its bound b), beside the ``floquet`` record and the frozen-time summary.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.linalg as la

from ..modal.rules import kind_of
from ..modal.rules import stability as rule  # (exponent_modes names its result stability)
from .periodic_motion import sample_linearization

__all__ = ["exponent_modes", "periodic_json", "partial_json", "largest_json", "frozen_time",
           "frozen_summary", "floquet_json", "reduced_exponents"]


def exponent_modes(fl, condition=None) -> list:
    """The Floquet exponents s = ln(μ)/T listed as modes (imaginary part reduced modulo 2π/T,
    a conjugate pair once with im > 0), each with the stability of its multiplier: stable when
    |μ| + b < 1, unstable when |μ| − b > 1, critical otherwise (b its error bound); the
    ``backward_error`` field holds b/|μ|, ``tolerance`` the band of δ = −ln|μ|/T that b
    decides, b/(|μ| T) to first order, and ``condition`` the condition number κ of μ where the
    method computes it (the full monodromy; ``condition`` aligned with the multipliers).
    A real negative μ (a response of twice the period) is one multiplier, not half of a
    conjugate pair: its exponent ln|μ|/T + iπ/T is listed once, and its ``multiplier`` has
    imaginary part 0.  Sorted by omega_n, then delta."""
    rows = []
    T = float(fl["period"])
    kappa = [None] * len(fl["multipliers"]) if condition is None else list(condition)
    for mu, ex, b, kap in zip(fl["multipliers"], fl["exponents"], fl["error_bounds"], kappa,
                              strict=True):
        re, im = ex
        if im < 0 or (im == 0 and mu[1] < 0):
            continue  # the conjugate of a listed pair
        m = abs(complex(*mu))
        stability = rule(1.0 - m, b)  # unstable: |μ| − b > 1, stable: |μ| + b < 1
        wn = math.hypot(re, im)
        # a real multiplier at 1 within its bound (and not past it) is a rigid-body motion
        kind = kind_of(stability, -re, im, 0.0,
                       rigid=im == 0 and re >= 0 and stability != "unstable")
        rows.append({"eigenvalue": [re, im], "delta": -re, "omega_n": wn, "omega_d": abs(im),
                     "freq_hz": abs(im) / (2 * math.pi), "zeta": -re / wn if wn else 0.0,
                     "stability": stability, "kind": kind, "multiplier": mu,
                     "backward_error": b / m if m else b, "tolerance": b / (m * T) if m else b,
                     **({} if kap is None else {"condition": float(kap)})})
    rows.sort(key=lambda r: (r["omega_n"], r["delta"]))
    for k, r in enumerate(rows, 1):
        r["index"] = k
    return rows


def periodic_json(a) -> dict:
    """The modes JSON of a periodic case: the §8 keys, ``floquet``, and ``modes`` listing the
    Floquet exponents (:func:`exponent_modes`)."""
    model = a.timed.base
    ref = a.reference
    fl = floquet_json(a)
    return {
        "case": model.name,
        "parameters": a.parameters,
        "n_coordinates": model.n,
        "n_constraints": model.n_constraints,
        "n_redundant": 0,
        "dof": a.dof,
        "solver": f"floquet: {a.floquet.method}",
        "equilibrium": {"residual": ref.residual, "iterations": ref.iterations},
        "verdict": a.floquet.verdict,
        "modes": exponent_modes(fl, a.floquet.condition),
        "floquet": fl,
        "frozen_time": frozen_summary(a),
    }


def partial_json(p) -> dict:
    """The modes JSON of ``--n-modes K``
    (:func:`mbseig.studies.periodic_partial.periodic_partial`)."""
    lin = p.linearization
    model, ref = lin.timed.base, lin.reference
    fl = p.to_dict()
    return {
        "case": model.name, "parameters": p.parameters, "n_coordinates": model.n,
        "n_constraints": model.n_constraints, "n_redundant": 0, "dof": lin.system.dof,
        "solver": f"floquet (partial): {p.method}",
        "equilibrium": {"residual": ref.residual, "iterations": ref.iterations},
        "verdict": p.verdict, "modes": exponent_modes(fl), "floquet": fl,
    }


def _largest(mu, k, decided):
    """Indices of the ``k`` multipliers of largest modulus (``mu`` sorted so already), each
    complex one with its conjugate, and the one that decides the verdict."""
    keep = list(range(min(k, mu.size)))
    for j in list(keep):
        m = mu[j]
        if abs(m.imag) > 1e-12 * abs(m):
            partner = int(np.argmin(np.abs(mu - m.conjugate())))
            if partner not in keep:
                keep.append(partner)
    if decided not in keep:
        keep.append(decided)
    return sorted(keep)


def largest_json(a, k, method) -> dict:
    """The modes JSON of ``--n-modes K`` answered by the full monodromy (``a``, a
    :func:`mbseig.studies.periodic.periodic_analysis`): its K multipliers of largest modulus
    (a complex one with its conjugate, and the multiplier that decides the verdict), the verdict
    over all of them; ``selected`` says how many of how many and, in ``method``, why this
    method."""
    fl = floquet_json(a)
    mu = np.array([complex(*m) for m in fl["multipliers"]])
    keep = _largest(mu, k, int(fl["decided_by"]["index"]))
    listed = dict(fl)
    for key in ("multipliers", "exponents", "error_bounds"):
        listed[key] = [fl[key][j] for j in keep]
    listed["decided_by"] = dict(fl["decided_by"], index=keep.index(fl["decided_by"]["index"]))
    listed["selected"] = {"count": len(keep), "of": int(mu.size), "method": method}
    condition = [a.floquet.condition[j] for j in keep] if a.floquet.condition is not None \
        else None
    model, ref = a.timed.base, a.reference
    return {
        "case": model.name, "parameters": a.parameters, "n_coordinates": model.n,
        "n_constraints": model.n_constraints, "n_redundant": 0, "dof": a.dof,
        "solver": f"floquet: {a.floquet.method}; the {len(keep)} largest |μ| of {mu.size}",
        "equilibrium": {"residual": ref.residual, "iterations": ref.iterations},
        "verdict": a.floquet.verdict, "modes": exponent_modes(listed, condition),
        "floquet": listed,
    }


def _frozen_pencils(analysis, instants):
    """(times, [(M_r, C_r, K_r)]) of the linearization frozen at ``instants`` instants of the
    period, on the null space at each instant, without the motion's Ṅ terms."""
    T = analysis.floquet.period
    C, K, J = sample_linearization(analysis.reference, 8, 0.0)
    M = analysis.reference.partition.M
    times = np.arange(instants) * T / instants
    out = []
    for t in times:
        Jt = J(t)
        N = la.null_space(Jt) if Jt.shape[0] else np.eye(M.shape[0])
        out.append((N.T @ M @ N, N.T @ C(t) @ N, N.T @ K(t) @ N))
    return times, out


def frozen_time(analysis, *, instants=64):
    """(times, eigenvalues) of the linearization frozen at instants of the period: what a
    frozen-time analysis would report (M_r s² + C_r s + K_r on the null space at each instant,
    without the motion's Ṅ terms).  Not a stability criterion of a periodic motion."""
    times, pencils = _frozen_pencils(analysis, instants)
    out = []
    for Mr, Cr, Kr in pencils:
        r = Mr.shape[0]
        A = np.block([[np.zeros((r, r)), np.eye(r)],
                      [-np.linalg.solve(Mr, Kr), -np.linalg.solve(Mr, Cr)]])
        out.append(np.linalg.eigvals(A))
    return times, np.array(out)


def frozen_summary(a, *, instants=64) -> dict:
    """The frozen-time verdict (not a stability criterion of a periodic motion): every frozen
    instant's modes by :func:`mbseig.modes`, each eigenvalue judged against its own bound
    (DESIGN §6: a real part within its bound of 0 is 0), the worst of their verdicts, and the
    largest real part as so read.  ``bound``: the largest of those bounds, for a table of the
    frozen eigenvalues."""
    from ..modal import modes
    from ..modal.bounds import worst as worst_of

    _, pencils = _frozen_pencils(a, instants)
    verdicts, largest, bound = [], -math.inf, 0.0
    for Mr, Cr, Kr in pencils:
        with warnings.catch_warnings():  # (a frozen instant is not a criterion: its solver's
            warnings.simplefilter("ignore", RuntimeWarning)  # notes are not the listing's)
            md = modes(Mr, Cr, Kr)
        verdicts.append(md.verdict.word)
        re = md.eigenvalues.real  # as a person reads them: 0 within the bound (DESIGN §6)
        if re.size:
            largest = max(largest, float(np.max(np.where(np.abs(re) > md.tolerance, re, 0.0))))
        bound = max(bound, float(np.max(md.tolerance, initial=0.0)))
    if not math.isfinite(largest):  # (no eigenvalue at all)
        largest = 0.0
    return {"instants": len(pencils), "max_real_part": largest + 0.0,
            "verdict": worst_of(verdicts) if verdicts else "critical", "bound": bound,
            "note": "eigenvalues at frozen instants, each judged against its own error bound: "
                    "not a stability criterion of a periodic motion"}


def floquet_json(analysis) -> dict:
    """The §8 ``"floquet"`` object (and its extras: per-multiplier bounds, the deciding
    multiplier and margin, Liouville's check, the method, tolerances and samples)."""
    out = analysis.floquet.to_dict()
    out["exponents"] = reduced_exponents(analysis.floquet.multipliers, analysis.floquet.period)
    out["samples"] = analysis.samples
    out["sampling_difference"] = analysis.sampling_difference
    ref = analysis.reference
    out["reference"] = {"method": ref.method, "residual": ref.residual,
                        "iterations": ref.iterations}
    out["time_dependent"] = list(analysis.timed.time_dependent)
    return out


def reduced_exponents(multipliers, period) -> list:
    """[re, im] of the exponents ln(μ)/T, imaginary parts reduced modulo 2π/T into
    (−π/T, π/T]."""
    T = float(period)
    w = 2 * math.pi / T
    out = []
    for mu in multipliers:
        with np.errstate(divide="ignore"):
            e = np.log(complex(mu)) / T
        im = e.imag - w * math.floor((e.imag + math.pi / T) / w)
        if im <= -math.pi / T:
            im += w
        out.append([float(e.real), float(im)])
    return out
