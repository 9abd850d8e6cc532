"""The modes as every report page shows them, whatever the motion (rest, steady, periodic): the
mode table with units, the verdict and what it leaves out, the least-damped mode, the panel
label of a mode and the time-domain check's table.

Every number a person reads goes through the zero rule (DESIGN §6, :mod:`mbseig.display`): a
value within its error bound of 0 is printed as 0.  The bounds come with the listing
(:class:`mbseig.studies.report_studies.ModeListing`: of Re s and δ, of Im s and |s|); ζ is δ/|s|
of the values as read, a frequency |s|/2π or |Im s|/2π carries the bound of its part / 2π.
"""

from __future__ import annotations

import math

import numpy as np

from ..display import fmt, shown
from .text import fmt as text_fmt

__all__ = ["read", "mode_table", "mode_label", "scope_blocks", "least_text", "check_table",
           "ZERO_NOTE"]

ZERO_NOTE = ("Values within their error bound of 0 are printed as 0 (the bounds: Re s and δ "
             "the tolerance that decided the stability, Im s and |s| the eigenvalue's error "
             "bound; `mbseig modes --json` keeps the computed values).")


def read(listing, k):
    """Mode k as a person reads it: a dict of re, im, delta, wn, zeta, fn, fd (zero rule)."""
    s = complex(listing.eigenvalues[k])
    bre, bim = float(listing.bound_re[k]), float(listing.bound_im[k])
    re, im = shown(s.real, bre), shown(s.imag, bim)
    delta = shown(float(listing.delta[k]), bre)
    wn = shown(abs(s), bim)
    zeta = delta / wn + 0.0 if wn > 0 else 0.0
    return {"re": re, "im": im, "delta": delta, "wn": wn, "zeta": zeta,
            "fn": wn / (2 * math.pi), "fd": abs(im) / (2 * math.pi)}


def mode_table(listing):
    """("table", head, rows) of the listing: eigenvalue parts, both frequencies, ζ, δ, the
    margin δ − tol (δ as read; "–" for a mode not counted), stability, kind and the coordinates
    that move most (the declared direction of a rigid-body mode by construction)."""
    rows = []
    for k in range(len(listing)):
        s = complex(listing.eigenvalues[k])
        bre, bim = float(listing.bound_re[k]), float(listing.bound_im[k])
        v = read(listing, k)
        rb = listing.rigid_body[k]
        rows.append([str(k + 1), fmt(s.real, bre), fmt(s.imag, bim),
                     fmt(abs(s) / (2 * math.pi), bim / (2 * math.pi)),
                     fmt(abs(s.imag) / (2 * math.pi), bim / (2 * math.pi)),
                     format(v["zeta"], ".4g"), fmt(float(listing.delta[k]), bre, ".5g"),
                     "–" if rb else format(v["delta"] - float(listing.tolerance[k]), ".4g"),
                     listing.stability[k] + (" (not counted)" if rb else ""),
                     listing.kind[k] + (" by construction" if rb else ""),
                     rb or ", ".join(listing.dominant[k][:3]) or "–"])
    return ("table", ["mode", "Re s [1/s]", "Im s [rad/s]", "ω_n/2π [Hz] (undamped)",
                      "ω_d/2π [Hz] (damped)", "ζ [–]", "δ [1/s]", "margin δ − tol [1/s]",
                      "stability", "kind", "dominant coordinates"], rows)


def scope_blocks(listing):
    """The verdict's scope in words (which modes it leaves out), and the zero rule's note."""
    scope = getattr(listing.verdict, "full_scope", "")
    out = []
    if scope:
        out.append(("p", f"Verdict scope: {scope}. A mode left out is rigid-body by the model's "
                         "construction (its structure or its motion has it whatever the "
                         "parameters); any other eigenvalue within its bound of 0 counts as "
                         "critical."))
    out.append(("p", ZERO_NOTE))
    return out


def least_text(listing, k):
    """The stability margin of the least-damped counted mode k (None: no counted mode)."""
    if k is None:
        return ("Stability margin: no mode is counted (every mode is rigid-body by "
                "construction): the verdict is critical.")
    v = read(listing, k)
    counted = [j for j in range(len(listing)) if listing.rigid_body[j] is None]
    margin = min(shown(float(listing.delta[j]), float(listing.bound_re[j]))
                 - float(listing.tolerance[j]) for j in counted)
    text = (f"Stability margin: the least-damped mode is mode {k + 1} with δ = "
            f"{text_fmt(v['delta'], 5)} 1/s (ζ = {text_fmt(v['zeta'], 4)}); min δ − tol = "
            f"{margin:.4g} 1/s over the counted modes")
    return text + (f" (tol per mode: {listing.rule})." if listing.rule else ".")


def mode_label(k, listing):
    """Panel title of mode k by its kind: damped frequency and ζ, the time constant of a real
    mode, or rigid-body; numbers as read (zero rule)."""
    v = read(listing, k)
    kind = listing.kind[k]
    if listing.rigid_body[k]:  # (the table names its direction)
        return f"mode {k + 1}: rigid-body by construction, not counted"
    if kind in ("overdamped", "divergence") and v["re"] != 0:
        what = "overdamped, decays" if kind == "overdamped" else "DIVERGENCE, grows"
        return f"mode {k + 1}: {what}, τ = 1/|s| = {1e3 / abs(v['re']):.4g} ms"
    if kind == "rigid-body":
        return f"mode {k + 1}: rigid-body (s = 0 within its bound)"
    return (f"mode {k + 1}: ω_d/2π = {v['fd']:.4g} Hz, ζ = {text_fmt(v['zeta'], 3)}"
            + (" (FLUTTER)" if kind == "flutter" else ""))


def check_table(res, listing):
    """("table", head, rows) of a time-domain check (:class:`mbseig.check.ModeCheck` per
    mode): predicted values with their bounds (the check's own, else the listing's), measured
    values with what the run resolves of them (``resolution_delta`` / ``resolution_omega``, when
    the check gives it)."""
    rows = []
    for m in res.modes:
        k = m.index - 1
        inside = listing is not None and 0 <= k < len(listing)
        bre = _finite(getattr(m, "bound_delta", math.nan)) or (
            float(listing.bound_re[k]) if inside else None)
        bim = _finite(getattr(m, "bound_omega", math.nan)) or (
            float(listing.bound_im[k]) if inside else None)
        pd, pw = fmt(m.predicted_delta, bre), fmt(m.predicted_omega, bim, ".8g")
        if m.skipped:
            rows.append([str(m.index), m.kind, pd, "–", "–", pw, "–", "–",
                         f"skipped ({m.skipped})" + ("" if m.passed is None else
                                                     "; static probe passed" if m.passed
                                                     else "; static probe FAILED")])
            continue
        rd = _finite(getattr(m, "resolution_delta", math.nan))
        rw = _finite(getattr(m, "resolution_omega", math.nan))
        rows.append([str(m.index), m.kind, pd, fmt(m.measured_delta, rd),
                     _rel(m.rel_error_delta), pw, fmt(m.measured_omega, rw, ".8g"),
                     _rel(m.rel_error_omega), "pass" if m.passed else "**FAIL**"])
    return ("table", ["mode", "kind", "δ predicted [1/s]", "δ measured [1/s]",
                      "δ rel. err. [–]", "ω predicted [rad/s]", "ω measured [rad/s]",
                      "ω rel. err. [–]", "result"], rows)


def _finite(x):
    x = float(x)
    return x if np.isfinite(x) else None


def _rel(x):
    return "–" if not np.isfinite(x) else f"{x:.1e}"
