"""Eigenvalues and error measures of the structured paths (eigh, proportional): the roots of
s² + (α + βω²) s + ω² = 0 per undamped mode, their η and κ from the one real residual of each
mode, and the sharper error bound of Re s under Rayleigh damping.

Undamped and proportional pairs (:func:`undamped_pairs`).  With a real unit v and ω² = w from the
undamped problem, its residual r = Qv − wMv, and P = αM + βQ + E (E the deviation of the
Rayleigh fit; E = 0 and α = β = 0 when P = 0), every root s of s² + (α + βw)s + w = 0 has,
exactly::

    (s²M + sP + Q)v = ρ(s) Mv + (1 + βs) r + s Ev,    ρ(s) = s² + (α + βw)s + w

so that, with ‖Ev‖ ≤ ‖E‖_F,

    η ≤ (|ρ(s)| ‖Mv‖ + |1 + βs| ‖r‖ + |s| ‖E‖_F) / w(s)

and, as vᵀPv = (α + βw)vᵀMv + β vᵀr + vᵀEv,

    κ ≤ w(s) / (|(2s + α + βw) vᵀMv + β vᵀr| − ‖E‖_F).

|ρ(s)| of the computed s is evaluated in extended precision and increased by the rounding bound
of that evaluation; r, Mv, vᵀMv, vᵀr are the only quantities that involve the matrices: one
real residual per mode, for both roots, no complex n-vector.  ρ is at the rounding level of s,
so η is |1 + βs|‖r‖/w(s) plus terms of order ε and ‖E‖/‖P‖: the directly evaluated η of the
same pair (tests/test_proportional_fast.py) up to the rounding of either evaluation.
"""

from __future__ import annotations

import numpy as np

from .measures import EPS, EPS_LD, LD, reversal, weights


def undamped_roots(w, alpha, beta):
    """Both roots of s² + (α + βω²)s + ω² = 0 per undamped mode ω² = w, [s₊; s₋] (stable form).

    Solved as u² + (c/r)u + w/r² = 0 with s = r u, r = max(|c|, √|w|), so that no c² or
    c·c − 4w overflows whatever the magnitudes."""
    w = np.asarray(w, float)
    with np.errstate(over="ignore", invalid="ignore"):
        c = alpha + beta * w
    r = np.maximum(np.abs(c), np.sqrt(np.abs(w)))
    r = np.where((r > 0) & np.isfinite(r), r, 1.0)
    cu, wu = c / r, (w / r) / r
    disc = cu * cu - 4.0 * wu
    s1 = np.empty(w.size, complex)
    s2 = np.empty(w.size, complex)
    osc = disc < 0
    s1[osc] = r[osc] * (-cu[osc] / 2 + 0.5j * np.sqrt(-disc[osc]))
    s2[osc] = np.conj(s1[osc])
    re = ~osc
    root = np.sqrt(disc[re])
    cr = cu[re]
    big = -(cr + np.copysign(root, cr)) / 2  # the root of larger magnitude, no cancellation
    small = np.divide(wu[re], big, out=np.zeros_like(big), where=big != 0)
    s1[re], s2[re] = r[re] * big, r[re] * small
    return np.concatenate([s1, s2])


def undamped_pairs(w, mv_norm, r_norm, a, vr, alpha, beta, fit_residual, norms):
    """s₊, s₋ of each undamped mode (ω² = w, unit real v) with s² + (α + βω²)s + ω² = 0, and
    η and κ of both, from the real residual r = Qv − ω²Mv of the undamped pair (module doc,
    "Undamped and proportional pairs"): no complex T(s)v is formed.

    mv_norm, r_norm : ‖Mv‖, ‖r‖ per mode; a : vᵀMv; vr : vᵀr; fit_residual : ‖E‖_F of
    E = P − αM − βQ (0 for P = 0).  Returns (s, η, κ), s = [s₊, s₋], y = x = v for κ.
    The scalar algebra runs in extended precision (np.longdouble where the platform has it),
    which also keeps |s|² w(s) free of overflow.
    """
    s = undamped_roots(w, alpha, beta)
    def twice(x):
        return np.tile(np.asarray(x, dtype=LD), 2)  # s₊ and s₋ share v

    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        S = s.astype(np.clongdouble)
        W = twice(w)
        al, be, fit = LD(alpha), LD(beta), LD(fit_residual)
        c = al + be * W
        rho = (S * S + c * S) + W  # s's own residual in its quadratic: rounding level
        A = np.abs(S)
        rho_bound = np.abs(rho) + 8 * EPS_LD * (A * A + (abs(al) + abs(be) * np.abs(W)) * A
                                                 + np.abs(W))  # + the rounding of ρ itself
        num = rho_bound * twice(mv_norm) + np.abs(1 + be * S) * twice(r_norm) + A * fit
        nM, nP, nQ = (LD(x) for x in norms)
        weight = A * A * nM + A * nP + nQ
        eta = np.where(weight > 0, num / np.where(weight > 0, weight, 1),
                       np.where(num == 0, 0, np.inf))
        # vᵀ(2sM + P)v = (2s + α + βω²) vᵀMv + β vᵀr + vᵀEv, |vᵀEv| ≤ ‖E‖_F: the smallest it
        # can be, so that κ is never understated by the fit
        den = np.abs((2 * S + c) * twice(a) + be * twice(vr)) - fit
        kappa = np.where(den > 0, weight / np.where(den > 0, den, 1), np.inf)
        kappa = np.where(weight == 0, 0, kappa)  # s = 0 with Q = 0: fixed (measures.fixed_zero)
        return s, eta.astype(float), kappa.astype(float)


def proportional_real_error(s, kappa, eta, norms, alpha, beta, fit_residual):
    """Error bound of Re s on the proportional path, oscillatory roots (Re s = −(α + βω²)/2).

    ω² = −s s̄ for the pair; its error is at most 2|s|·κη (first order, undamped pencil), so
    |Δ Re s| ≤ |β| |s| κη + κ |s| ‖P − αM − βQ‖ / w(s) + ε |α + βω²|, w(s) the η weight.
    Real (overdamped) roots get no bound here (κη applies).
    """
    a = np.abs(s)
    _, big = reversal(s)
    weight = weights(s, norms)  # w(s), or w(s)/|s|² where |s| > 1
    ke = kappa * np.maximum(eta, EPS)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        scale = np.where(big, 1.0 / a, a)  # κ|s|·fit/w(s) in either form
        fit = np.where(weight > 0, kappa * scale * fit_residual / weight, np.inf)
        err = np.abs(beta) * a * ke + fit + EPS * 2 * np.abs(s.real)
    return np.where(np.abs(s.imag) > 0, err, np.inf)
