"""Figures of rotors: the Campbell diagram of a speed sweep (:mod:`mbseig.studies.campbell`)
and the unbalance response (:mod:`mbseig.studies.unbalance`): the Bode diagram (amplitude and
phase against the speed) and the polar diagram (the complex amplitude traced over the speed).

Results are read by their attributes (duck typing).  A Campbell result: ``values``,
``parameter``, ``speeds``, ``harmonic``, ``frequency``, ``log_decrement``, ``whirl`` (per point,
per track), ``critical_speeds`` and, when it has them, ``tolerance`` (per point, per track: each
eigenvalue's stability tolerance) and ``units``.  An unbalance response: ``values`` of
``parameter``, ``speeds`` [rad/s], ``stations``, ``X1``, ``X2`` (complex lateral amplitudes along
e₁, e₂ [m]), ``major`` (orbit major semi-axis [m]), ``outputs``, ``output_units``, ``Y``,
``unbalance`` [kg m], ``at`` and ``case``.  A station's amplitude is its orbit's major
semi-axis, its phase that of X₁ (x₁(t) = |X₁| cos(Ωt + ∠X₁)), unwrapped along the speed; an
output is drawn when its unit is m.  At Ω = 0 there is no unbalance force and no phase: those
points are left out.  A resonance (``res.resonance_values()``: the unbalance drives an undamped
mode at its own frequency, no steady response) breaks the curves and is marked: a red dashed
line in the Bode diagram, a legend entry in the polar diagram.
"""

from __future__ import annotations

import math
import re

import numpy as np

from .common import SPATIAL_STYLE, colormap, figure, styled

__all__ = ["default_stations", "unbalance_bode", "unbalance_polar", "MAX_CURVES",
           "WHIRL_COLOURS", "campbell_diagram", "campbell_range", "speed_unit"]

WHIRL_COLOURS = {"forward": "tab:blue", "backward": "tab:red", "mixed": "tab:gray",
                 "none": "tab:green", None: "k"}

MAX_CURVES = 10  # curves a figure shows (the table and JSON have every station)


def default_stations(res, stations=None):
    """The (name, complex amplitude per speed, amplitude per speed) drawn: ``stations`` (names)
    when given, else the named stations that move (not the beam's automatic nodes ``BEAM.nK``)
    and the outputs in m — or, when none is named, the moving nodes evenly spread —, at most
    ``MAX_CURVES``."""
    items = [(s, res.X1[:, j], res.major[:, j]) for j, s in enumerate(res.stations)]
    items += [(n, res.Y[:, j], np.abs(res.Y[:, j]))
              for j, (n, u) in enumerate(zip(res.outputs, res.output_units, strict=True))
              if u == "m"]
    if stations:
        return [it for it in items if it[0] in set(stations)][:MAX_CURVES]
    moving = [it for it in items if np.nanmax(np.abs(it[2]), initial=0.0) > 0]
    chosen = [it for it in moving if not re.search(r"\.n\d+$", it[0])]
    if not chosen:  # a bare shaft: its nodes, evenly spread
        step = max(1, -(-len(moving) // MAX_CURVES))
        chosen = moving[::step]
    return chosen[:MAX_CURVES]


def _x_label(res, unit):
    u = f" [{unit}]" if unit and unit != "1" else ""
    return f"{res.parameter}{u}"


def _critical_lines(ax, critical):
    for k, c in enumerate(critical or ()):
        ax.axvline(c, color="0.4", lw=0.8, ls=":", label="critical speed" if k == 0 else None)


def _resonances(res):
    """The swept values where the response is a resonance (no steady response)."""
    return res.resonance_values()


RESONANCE_LABEL = "resonance: no steady response"


def _resonance_lines(ax, values, label=True):
    for k, v in enumerate(values):
        ax.axvline(v, color="tab:red", lw=1.0, ls="--",
                   label=RESONANCE_LABEL if label and k == 0 else None)


@styled
def unbalance_bode(res, *, unit=None, stations=None, critical=()):
    """Amplitude (log scale when it spans two decades) and phase of every drawn station and
    output against the swept parameter; ``critical``: parameter values drawn as dotted lines."""
    fig = figure(figsize=(8.8, 6.4))
    a1, a2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [1.6, 1]})
    x = np.asarray(res.values, float)
    cmap = colormap("tab10")
    amps = []
    for i, (name, z, amp) in enumerate(default_stations(res, stations)):
        amp = np.where(np.asarray(amp) > 0, amp, np.nan)
        ok = np.isfinite(amp)
        amps.append(amp[ok])
        a1.plot(x, amp, "-", color=cmap(i % 10), lw=1.3, label=name)
        ph = np.full(len(x), np.nan)
        if ok.any():
            ph[ok] = np.degrees(np.unwrap(np.angle(np.asarray(z)[ok])))
        a2.plot(x, ph, "-", color=cmap(i % 10), lw=1.1)
    allv = np.concatenate(amps) if amps else np.array([])
    if allv.size and allv.max() / allv.min() >= 100:
        a1.set_yscale("log")
    _critical_lines(a1, critical)
    _critical_lines(a2, critical)
    _resonance_lines(a1, _resonances(res))
    _resonance_lines(a2, _resonances(res), label=False)
    a1.set_ylabel("amplitude (orbit major semi-axis) [m]")
    a2.set_ylabel("phase of x₁ [deg]")
    a2.set_xlabel(_x_label(res, unit))
    a1.set_title(f"unbalance response of {res.case}: m·e = {res.unbalance:g} kg m at {res.at}")
    a1.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    a1.grid(True, lw=0.3, which="both")
    a2.grid(True, lw=0.3)
    fig.tight_layout()
    return fig


@styled
def unbalance_polar(res, *, unit=None, stations=None):
    """The complex amplitude X₁ (Re, Im) of every drawn station and output traced over the
    speed, the first speed (circle) and the last (square) marked, the largest amplitude of the
    first curve labelled with its speed; true aspect."""
    fig = figure(figsize=(7.6, 6.4))
    ax = fig.subplots()
    cmap = colormap("tab10")
    x = np.asarray(res.values, float)
    u = f" {unit}" if unit and unit != "1" else ""
    for i, (name, z, _amp) in enumerate(default_stations(res, stations)):
        z = np.asarray(z)
        c = cmap(i % 10)
        ax.plot(z.real, z.imag, "-", color=c, lw=1.2, label=name)
        ax.plot(z.real[0], z.imag[0], "o", color=c, ms=4)
        ax.plot(z.real[-1], z.imag[-1], "s", color=c, ms=4)
        if i:  # the largest amplitude's speed, labelled on the first curve only
            continue
        k = int(np.nanargmax(np.abs(z))) if np.isfinite(np.abs(z)).any() else 0
        ax.annotate(f"{res.parameter} = {x[k]:.4g}{u}", (z.real[k], z.imag[k]), fontsize=6,
                    xytext=(4, 4), textcoords="offset points", color=c)
    for v in _resonances(res):  # the curve is broken there: say where and why
        ax.plot([], [], color="tab:red", ls="--", lw=1.0,
                label=f"{res.parameter} = {v:.4g}{u}: {RESONANCE_LABEL} "
                      f"(curve broken)")
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("Re X₁ [m]")
    ax.set_ylabel("Im X₁ [m]")
    ax.set_title(f"polar diagram: {res.parameter} from {x[0]:g} (circle) to {x[-1]:g}{u} "
                 f"(square)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    return fig


def speed_unit(res):
    """The unit of a Campbell diagram's parameter: its unit from the case (``res.units``) when
    known; else rad/s when the parameter is the rotor speed Ω itself, rpm when it is Ω·60/2π
    (both to 1e-9), else None."""
    unit = (getattr(res, "units", None) or {}).get(res.parameter)
    if unit:
        return unit
    x, w = np.asarray(res.values, float), np.asarray(res.speeds, float)
    scale = max(float(np.max(np.abs(w), initial=0.0)), 1e-300)
    if np.allclose(x, w, rtol=0, atol=1e-9 * scale):
        return "rad/s"
    if np.allclose(x * 2 * math.pi / 60, w, rtol=0, atol=1e-9 * scale):
        return "rpm"
    return None


def _with_units(res, units):
    import dataclasses

    try:
        return dataclasses.replace(res, units=dict(units))
    except (TypeError, ValueError):
        return res


def _log_dec_band(res, rtol):
    """Per point and track, the log decrement's error band 2π tol/ω: ``res.tolerance`` when
    the result carries the eigenvalues' stability tolerances, else rtol |s| (the floor of
    mbseig.modal's tolerance rule)."""
    s = np.asarray(res.tracks)
    tol = getattr(res, "tolerance", None)
    tol = np.asarray(tol, float) if tol is not None else rtol * np.abs(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(s.imag) > 0, 2 * math.pi * tol / np.abs(s.imag), np.nan)


def campbell_range(res, *, margin=1.3, min_tracks=4):
    """(top frequency [Hz], tracks drawn): the frequency axis reaches ``margin`` times the
    highest of the excitation line and the critical speeds, and at least the ``min_tracks``
    lowest tracks; a track starting above it (a flexible shaft's higher modes, up to the
    mesh's) is not drawn."""
    F = np.asarray(res.frequency, float) / (2 * math.pi)
    exc = float(np.nanmax(res.harmonic * np.abs(np.asarray(res.speeds, float)), initial=0.0))
    crit = max((c["frequency"] for c in res.critical_speeds), default=0.0)
    top = margin * max(exc, crit) / (2 * math.pi)
    lows = np.sort(np.nan_to_num(np.nanmin(F, axis=0), nan=np.inf)) if F.size else np.array([])
    lows = lows[np.isfinite(lows)]
    if lows.size:
        k = min(min_tracks, lows.size) - 1
        highs = [float(np.nanmax(F[:, j])) for j in range(F.shape[1])
                 if np.nanmin(F[:, j]) <= lows[k]]
        top = max(top, 1.1 * max(highs))
    top = top if top > 0 else 1.0
    drawn = [j for j in range(F.shape[1]) if np.isfinite(F[:, j]).any()
             and np.nanmin(F[:, j]) <= top]
    return top, drawn


def _rigid_points(res, shape):
    """(points, tracks) mask of the rigid-body eigenvalues (s ≈ 0 within the tolerance: no log
    decrement to show)."""
    kind = getattr(res, "kind", None)
    if not kind:
        return np.zeros(shape, bool)
    return np.array([[row[j] == "rigid-body" for j in range(shape[1])] for row in kind], bool)


def campbell_diagram(res, *, rtol=1e-12, min_log_dec_span=0.05, units=None):
    """Frequency against the swept parameter, coloured by whirl, with the excitation line
    h·|Ω| (dashed) and the critical speeds (circles); below, the logarithmic decrement.
    The frequency axis is limited by :func:`campbell_range` (the tracks above it are counted
    in the legend); ``units`` (parameter → unit, the case's) names the speed's unit.

    A log decrement within its error band (2π tol/ω, the eigenvalue's stability tolerance;
    ``rtol``·|s| when the result does not carry it) is drawn as 0, on the grey band, so the
    panel shows the physics and not the rounding; its axis spans at least ±
    ``min_log_dec_span``."""
    import matplotlib
    from matplotlib.lines import Line2D

    with matplotlib.rc_context(SPATIAL_STYLE):
        fig = figure(figsize=(8.8, 7))
        a1, a2 = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
        x = np.asarray(res.values, float)
        F = np.asarray(res.frequency) / (2 * math.pi)
        LD = np.asarray(res.log_decrement)
        band = _log_dec_band(res, rtol)
        LDp = np.where(np.abs(LD) <= band, 0.0, LD)
        top, drawn = campbell_range(res)
        hidden = F.shape[1] - len(drawn)
        rigid = _rigid_points(res, F.shape)[:, drawn]
        LDp = np.where(rigid, np.nan, LDp[:, drawn])
        band = np.where(rigid, np.nan, band[:, drawn])
        for i, j in enumerate(drawn):
            for k in range(len(x) - 1):
                # a segment takes its first point's whirl; at rest a spinning beam has none
                # (None), and the segment takes the next point's
                w = res.whirl[k][j] if res.whirl[k][j] is not None else res.whirl[k + 1][j]
                colour = WHIRL_COLOURS.get(w, "k")
                a1.plot(x[k:k + 2], F[k:k + 2, j], "-", color=colour, lw=1.5)
                a2.plot(x[k:k + 2], LDp[k:k + 2, i], "-", color=colour, lw=1.2)
        a1.plot(x, res.harmonic * np.abs(res.speeds) / (2 * math.pi), "k--", lw=1)
        for c in res.critical_speeds:
            a1.plot(c["value"], c["frequency"] / (2 * math.pi), "o", mfc="none",
                    color=WHIRL_COLOURS.get(c["whirl"], "k"), ms=7)
        handles = [Line2D([], [], color=WHIRL_COLOURS[w], label=w) for w in
                   ("forward", "backward", "mixed", "none")]
        handles.append(Line2D([], [], color="k", ls="--", label=f"{res.harmonic:g}x excitation"))
        if hidden:
            handles.append(Line2D([], [], ls="none", label=f"{hidden} modes above "
                                                          f"{top:.4g} Hz not drawn"))
        a1.set_ylim(0.0, top)
        a1.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0),
                  borderaxespad=0.0)  # outside the axes, never over the curves
        a1.set_ylabel("frequency ω_d/2π [Hz]")
        a1.set_title(f"Campbell diagram of {res.case}: circles = critical speeds")
        finite = np.abs(LDp[np.isfinite(LDp)])
        top = max(float(finite.max()) * 1.15 if finite.size else 0.0, min_log_dec_span)
        lo = min(float(np.nanmin(LDp)) * 1.15 if finite.size else 0.0, -min_log_dec_span)
        a2.set_ylim(lo, top)
        bmax = float(np.nanmax(band)) if np.isfinite(band).any() else 0.0
        a2.axhspan(-bmax, bmax, color="0.8", lw=0, zorder=0)
        a2.axhline(0.0, color="0.5", lw=0.6, zorder=0)
        a2.set_ylabel("log decrement Λ = 2πδ/ω_d [–]")
        a2.legend(handles=[Line2D([], [], color="0.6", lw=4,
                                  label=f"|Λ| ≤ 2π tol/ω_d (≤ {bmax:.1g}): drawn as 0")],
                  fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
        unit = speed_unit(res if units is None else _with_units(res, units))
        a2.set_xlabel(res.parameter + (f" [{unit}]" if unit else ""))
        a1.grid(True, lw=0.3)
        a2.grid(True, lw=0.3)
        fig.tight_layout()
        return fig
