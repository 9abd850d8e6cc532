"""The report's first page: the figure of every configuration's least-damped pole with the
boundaries found, the summary per configuration (verdict, least-damped mode, range of motion,
margins to every boundary the studies found: on which side the present value lies and how far),
the table and tornado chart of the parameters that move the least-damped mode most, and the
comparison of the configurations with what the studies found."""

from __future__ import annotations

import math
from pathlib import Path

from .. import plots
from ..display import shown
from .modes import read
from .text import fmt
from .units import with_unit

__all__ = ["summary_blocks", "comparison_blocks", "margin_text", "findings",
           "sensitivity_blocks", "least_mode_text", "verdict_cell", "scope_sentences"]


def margin_text(name, current, crit, unit, kind, *, verdict="stable"):
    """Where the present value lies and how far the boundary is: ``f = 1 N (stable): flutter
    if f rises by 0.7864 N (+79 % of its present value) to f* = 1.78639 N``.  The boundary is
    the first loss of stability the study found; the present configuration's verdict says on
    which side of it the present value lies."""
    d = crit - current
    way = "rises" if d > 0 else "falls"
    rel = f", {100 * abs(d) / abs(current):.0f} % of its present value" if current else ""
    side = "stable side" if verdict == "stable" else f"{verdict} at present"
    return (f"{name} = {with_unit(fmt(current, 5), unit)} ({side}): {kind} if {name} {way} by "
            f"{with_unit(f'{abs(d):.4g}', unit)}{rel}, to {name}* = "
            f"{with_unit(fmt(crit, 6), unit)}")


def summary_blocks(summaries, study_sums, units, sensitivities=None, *, out_dir=None,
                   stem="case"):
    """The summary first: the figure of every configuration's least-damped pole with the
    boundaries found (when ``out_dir`` is given), then per configuration the verdict, the
    least-damped mode, the margins to every boundary the studies found (with units) and, when
    :mod:`mbseig.studies.design` is there, the table and tornado chart of the parameters that
    move the least-damped mode."""
    rows = []
    for s in summaries:
        least = least_mode_text(s["least_mode"])
        margins = []
        for st in study_sums:
            if st.get("config") != s["config"] or "critical" not in st:
                continue
            name = st["parameter"]
            unit = units.get(name)
            current = s["parameters"].get(name)
            own = _own_lines(s, st)
            for c in own:
                where = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k))
                                  for k, v in c["line"].items())
                if c["critical"] is None:
                    margins.append(f"{name}: no boundary in the swept range"
                                   + (f" ({where})" if where else ""))
                elif current is not None and isinstance(current, (int, float)):
                    margins.append(margin_text(name, float(current), c["critical"], unit, c["kind"],
                                               verdict=s["verdict"])
                                   + (f" at {where}" if where and len(own) > 1 else ""))
                else:
                    margins.append(f"{name}* = {with_unit(fmt(c['critical'], 6), unit)} "
                                   f"({c['kind']})")
                if c.get("rom"):
                    margins.append(f"{c['rom']['joint']} leaves its range of motion at {name} = "
                                   + with_unit(fmt(c["rom"]["value"], 6), unit))
        rom = ("inside" if not s["out_of_range"] else "OUTSIDE for " + ", ".join(s["out_of_range"]))
        rows.append([s["config"], verdict_cell(s["verdict"]), least, rom,
                     "; ".join(margins) or "no boundary study"])
    blocks = [("h2", "Summary")]
    if out_dir is not None:
        blocks += _summary_figure(summaries, study_sums, units, out_dir, stem)
    blocks.append(("table", ["configuration", "verdict", "least-damped mode", "range of motion",
                             "margins to the boundaries found (where the present value lies, how "
                             "far the boundary is)"], rows))
    blocks += scope_sentences([(s["config"], s["verdict"]) for s in summaries])
    if sensitivities is not None:  # one ranking a configuration (mbseig.studies.report_data)
        blocks += sensitivity_blocks(summaries, sensitivities, units, out_dir=out_dir, stem=stem)
    else:
        blocks.append(("p", "Eigenvalue sensitivities not computed (--no-sensitivities)."))
    return blocks


def verdict_cell(verdict):
    """The verdict word of a summary table, bold unless stable."""
    word = getattr(verdict, "word", str(verdict))
    return word if word == "stable" else f"**{word}**"


def scope_sentences(pairs):
    """'Verdict of CONFIG: what it leaves out' for every (configuration, Verdict) with a scope."""
    out = []
    for config, v in pairs:
        scope = getattr(v, "full_scope", "")
        if scope:
            out.append(("p", f"Verdict of {config}: {getattr(v, 'word', v)}; {scope}."))
    return out


def least_mode_text(lm):
    """The least-damped counted mode of a summary (:func:`mbseig.studies.report_studies.
    least_mode_record`) as read: the zero rule on δ, ζ and the frequencies."""
    if lm is None:
        return "– (no counted mode: every mode is rigid-body by construction)"
    bre, bim = lm.get("bound_re"), lm.get("bound_im")
    fb = None if bim is None else bim / (2 * math.pi)
    delta = shown(lm["delta"], bre)
    fn = shown(lm["fn"], fb)
    zeta = delta / (2 * math.pi * fn) + 0.0 if fn > 0 else 0.0
    head = f"mode {lm['mode']} ({lm['kind']}): ω_n/2π = {fmt(lm['fn'], 4, fb)} Hz, "
    if shown(lm["fd"], fb) > 0:
        head += f"ω_d/2π = {fmt(lm['fd'], 4, fb)} Hz, ζ = {fmt(zeta, 3)}, "
    return head + f"δ = {fmt(lm['delta'], 4, bre)} 1/s"


def _own_lines(s, st):
    """The study's lines at this configuration's own values of the other axes (all lines when
    none matches)."""
    return [c for c in st["critical"]
            if all(s["parameters"].get(k) is not None and
                   abs(float(s["parameters"][k]) - float(v)) <= 1e-12 * (1 + abs(float(v)))
                   for k, v in c["line"].items())] or st["critical"]


def _summary_figure(summaries, study_sums, units, out_dir, stem):
    """The least-damped pole of every configuration and the crossing eigenvalue of every
    boundary found at the configuration's own line, on one ζ/ω_n grid."""
    poles = [{"label": f"{s['config']}: mode {s['least_mode']['mode']} ({s['verdict']})",
              "s": _shown_pole(s["least_mode"]), "stable": s["verdict"] == "stable"}
             for s in summaries if s["least_mode"] is not None and "eigenvalue" in s["least_mode"]]
    if not poles:
        return []
    bounds = []
    for s in summaries:
        for st in study_sums:
            if st.get("config") != s["config"] or "critical" not in st:
                continue
            for c in _own_lines(s, st):
                if c["critical"] is None or c.get("eigenvalue") is None:
                    continue
                name = st["parameter"]
                bounds.append({"s": complex(*c["eigenvalue"]),
                               "label": f"{s['config']}: {name}* = "
                                        + with_unit(fmt(c["critical"], 4), units.get(name))})
    fig = plots.summary_poles(poles, bounds, title="least-damped mode of every configuration, "
                                                   "and the boundaries found")
    img = plots.save(fig, Path(out_dir) / f"{stem}_summary_poles.png")
    return [("img", img, "the least-damped pole of every configuration (circles, with its "
                         "conjugate) over lines of constant ζ and circles of constant ω_n; "
                         "crosses: the crossing eigenvalue at each stability boundary the studies "
                         "found, labelled with the critical value")]


def _shown_pole(lm):
    re, im = lm["eigenvalue"]
    return complex(shown(re, lm.get("bound_re")), shown(im, lm.get("bound_im")))


def sensitivity_blocks(summaries, rankings, units, *, out_dir=None, stem="case"):
    """The table of the parameters that move the least-damped mode most per relative change
    (:func:`mbseig.studies.report_studies.least_mode_sensitivities`), with units, and their
    tornado chart (when ``out_dir`` is given)."""
    rows, panels, notes = [], [], []
    unbounded = False
    for s, ranked in zip(summaries, rankings, strict=True):
        if isinstance(ranked, str):
            notes.append(f"{s['config']}: sensitivities not computed ({ranked}).")
            continue
        if not ranked:
            continue
        k = s["least"]
        bars = []
        for r in ranked:
            p, d, b = r["parameter"], r["derivative"], r["bound"]
            unbounded |= not math.isfinite(b)
            unit = units.get(p)
            per = f"1/s per {unit}" if unit and unit != "1" else "1/s"
            change = -shown(r["per_pct"], r["per_pct_bound"])  # of δ = −Re s, for +1 %
            effect = ("no change beyond its error bound" if change == 0 else
                      "adds damping" if change > 0 else "takes damping away")
            rows.append([s["config"], f"{k + 1}", p, with_unit(fmt(r["value"], 5), unit),
                         f"{fmt(d.real, 4, b)} {per}", "0" if change == 0 else f"{change:+.3g}",
                         effect])
            bars.append((p, change))
        lm = s["least_mode"]
        title = f"{s['config']}: mode {k + 1}, δ = {fmt(lm['delta'], 4, lm.get('bound_re'))} 1/s"
        if any(c != 0 for _, c in bars):
            panels.append({"title": title, "rows": bars})
        else:
            notes.append(f"{s['config']}: no parameter moves δ of mode {k + 1} beyond the error "
                         f"bound of its sensitivity (every ∂Re s/∂p is 0 as read); no chart.")
    blocks = []
    if rows:
        blocks.append(("p", "The parameters that move the least-damped mode most, per relative "
                            "change (first-order eigenvalue sensitivities; parameters at 0 left "
                            "out), largest first; a derivative within its error bound (propagated "
                            "from the eigenvalue's) is 0:"))
        blocks.append(("table", ["configuration", "mode", "parameter", "present value",
                                 "∂Re s/∂p", "change of δ for +1 % [1/s]", "increasing it"], rows))
        if unbounded:
            blocks.append(("p", "These sensitivities come without an error bound: they are "
                                "printed as computed."))
        if out_dir is not None and panels:
            img = plots.save(plots.tornado(panels),
                             Path(out_dir) / f"{stem}_sensitivity_tornado.png")
            blocks.append(("img", img, "tornado chart: first-order change of the least-damped "
                                       "mode's damping δ for ±10 % of each parameter (blue adds "
                                       "damping, red takes it away), largest first"))
    blocks += [("p", n) for n in notes]
    return blocks


def comparison_blocks(summaries, study_sums, units):
    rows = []
    for s in summaries:
        crit = []
        for st in study_sums:
            if st.get("config") == s["config"] and "critical" in st:
                for c in st["critical"]:
                    where = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k))
                                      for k, v in c["line"].items())
                    val = ("none in range" if c["critical"] is None else
                           with_unit(f"{c['critical']:.6g}", units.get(st["parameter"])))
                    crit.append(f"{st['parameter']}* = {val}" + (f" ({where})" if where else ""))
        lm = s["least_mode"] or {}
        listing = s.get("listing")
        freqs = ([read(listing, k)["fd"] for k in range(len(listing))] if listing is not None
                 else s["freqs"])
        delta = shown(s["least_delta"], lm.get("bound_re")) if lm else s["least_delta"]
        zeta = delta / (2 * math.pi * lm["fn"]) if lm and lm["fn"] > 0 else s["least_zeta"]
        rows.append([s["config"], str(s["dof"]), str(s["verdict"]), fmt(delta, 5),
                     fmt(zeta, 4), ", ".join(fmt(f, 4) for f in freqs),
                     ", ".join(f"{k} {v:.2f}" for k, v in s["posture"].items()),
                     ", ".join(s["out_of_range"]) or "none",
                     ", ".join(f"{t:.4g}" for t in s["actuator"]) or "–",
                     "; ".join(crit) or "–"])
    blocks = [("h2", "Comparison of the configurations"),
              ("table", ["config", "DOF", "verdict", "least δ [1/s]", "its ζ [–]",
                         "ω_d/2π of the modes [Hz]", "posture [deg]", "outside ROM",
                         "actuator tension [N]", "critical parameters"], rows)]
    blocks += findings(study_sums, units)
    return blocks


def findings(study_sums, units):
    """What the follower-load study says about damping (the destabilizing-damping paradox)."""
    out = []
    for st in study_sums:
        crit = st.get("critical") or []
        lines = [c for c in crit if "damping_scale" in c["line"] and c["critical"] is not None]
        if len(lines) < 2:
            continue
        by = sorted(lines, key=lambda c: -c["line"]["damping_scale"])
        u = units.get(st["parameter"])
        def val(x, u=u):
            return with_unit(f"{x:.6g}", u)
        text = [f"{st['parameter']}* = {val(c['critical'])} at damping scale "
                f"{c['line']['damping_scale']:g}" for c in by]
        msg = "Critical load against the damping scale: " + "; ".join(text) + ". "
        zero = next((c for c in by if c["line"]["damping_scale"] == 0), None)
        curve = next((c for c in st.get("curves", []) if c["along"] == "damping_scale"), None)
        small = [c for c in by if c["line"]["damping_scale"] > 0]
        if curve and curve["points"]:
            pos = [p for p in curve["points"] if p[0] > 0]
            if pos:
                s_min, f_min = min(pos)
                msg += (f"Followed continuously in the damping scale, the critical load is "
                        f"{val(f_min)} at the smallest scale {s_min:g}. ")
                small = small + [{"critical": f_min, "line": {"damping_scale": s_min}}]
        if zero is not None:
            msg += f"The undamped flutter load (damping scale 0) is {val(zero['critical'])}. "
            lim = (min(small, key=lambda c: c["line"]["damping_scale"])["critical"] if small
                   else None)
            if lim is not None and lim < zero["critical"] * (1 - 1e-6):
                msg += (f"As the damping tends to zero the critical load tends to about "
                        f"{with_unit(f'{lim:.5g}', u)}, "
                        f"below the undamped value: the destabilizing effect of small damping on "
                        f"a follower-loaded (circulatory) system. A design that relies on the "
                        f"dampers for its margin loses it when they are small.")
            elif lim is not None:
                msg += ("As the damping tends to zero the critical load does not fall below the "
                        "undamped value here.")
        out.append(("p", msg))
    return out
