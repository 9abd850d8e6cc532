"""The report's first page: the summary per configuration (verdict, least-damped mode, range of
motion, margins to every boundary the studies found, the parameters that move the least-damped
mode most) and the comparison of the configurations with what the studies found."""

from __future__ import annotations

from ..studies.report_studies import least_mode_sensitivities
from .text import fmt
from .units import with_unit

__all__ = ["summary_blocks", "comparison_blocks", "margin_text", "findings"]


def margin_text(name, current, crit, unit, kind):
    """``f: 0.786 N to flutter (f* = 1.786 N, +79 %)``."""
    d = crit - current
    rel = f", {100 * d / abs(current):+.0f} % of the present value" if current else ""
    return (f"{name} = {with_unit(fmt(current, 5), unit)} → {name}* = "
            f"{with_unit(fmt(crit, 6), unit)} ({kind}): margin {with_unit(f'{d:+.4g}', unit)}{rel}")


def summary_blocks(case, summaries, study_sums, units, sensitivities=True):
    """The summary first: per configuration the verdict, the least-damped mode, the margins to
    every boundary the studies found (with units) and, when :mod:`mbseig.studies.design` is
    there, the parameter that moves the least stable mode most."""
    rows = []
    notes = []
    for s in summaries:
        lm = s["least_mode"]
        if lm is None:
            least = "–"
        elif lm["fd"] > 0:
            least = (f"mode {lm['mode']} ({lm['kind']}): ω_n/2π = {lm['fn']:.4g} Hz, "
                     f"ω_d/2π = {lm['fd']:.4g} Hz, ζ = {lm['zeta']:.3g}, δ = {lm['delta']:.4g} 1/s")
        else:
            least = (f"mode {lm['mode']} ({lm['kind']}): ω_n/2π = {lm['fn']:.4g} Hz, "
                     f"δ = {lm['delta']:.4g} 1/s")
        margins = []
        for st in study_sums:
            if st.get("config") != s["config"] or "critical" not in st:
                continue
            name = st["parameter"]
            unit = units.get(name)
            current = s["parameters"].get(name)
            own = [c for c in st["critical"]
                   if all(s["parameters"].get(k) is not None and
                          abs(float(s["parameters"][k]) - float(v)) <= 1e-12 * (1 + abs(float(v)))
                          for k, v in c["line"].items())] or st["critical"]
            for c in own:
                where = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k))
                                  for k, v in c["line"].items())
                if c["critical"] is None:
                    margins.append(f"{name}: no boundary in the swept range" + (f" ({where})" if where else ""))
                elif current is not None and isinstance(current, (int, float)):
                    margins.append(margin_text(name, float(current), c["critical"], unit, c["kind"])
                                   + (f" at {where}" if where and len(own) > 1 else ""))
                else:
                    margins.append(f"{name}* = {with_unit(fmt(c['critical'], 6), unit)} ({c['kind']})")
                if c.get("rom"):
                    margins.append(f"{c['rom']['joint']} leaves its range of motion at {name} = "
                                   + with_unit(fmt(c["rom"]["value"], 6), unit))
        rom = ("inside" if not s["out_of_range"] else "OUTSIDE for " + ", ".join(s["out_of_range"]))
        rows.append([s["config"], f"**{s['verdict']}**" if s["verdict"] != "stable" else s["verdict"],
                     least, rom, "; ".join(margins) or "no boundary study"])
        sens = sensitivity_sentence(case, s, units) if sensitivities else None
        if sens:
            notes.append(sens)
    blocks = [("h2", "Summary"),
              ("table", ["configuration", "verdict", "least-damped mode", "range of motion",
                         "margins to the boundaries found (present value → critical value)"], rows)]
    if notes:
        blocks += [("p", n) for n in notes]
    elif not sensitivities:
        blocks.append(("p", "Eigenvalue sensitivities not computed (--no-sensitivities)."))
    return blocks


def sensitivity_sentence(case, s, units):
    """The parameters that move the least-damped mode most per relative change, with units
    (:func:`mbseig.studies.report_studies.least_mode_sensitivities`)."""
    ranked = least_mode_sensitivities(case, s)
    if isinstance(ranked, str):
        return f"{s['config']}: sensitivities not computed ({ranked})."
    if not ranked:
        return None
    k = s["least"]
    parts = []
    for p, d, value, per_pct in ranked:
        unit = units.get(p)
        per = f"1/s per {unit}" if unit and unit != "1" else "1/s"
        effect = "destabilizes" if d.real > 0 else "stabilizes"
        step = f"+1 % moves Re s by {per_pct:+.3g} 1/s"
        parts.append(f"{p} (= {with_unit(fmt(value, 5), unit)}; ∂Re s/∂{p} = {d.real:.4g} {per}; "
                     f"{step}; increasing it {effect} the mode)")
    return (f"{s['config']}: the parameters that move the least-damped mode (mode {k + 1}, "
            f"Re s = {-s['least_mode']['delta']:.4g} 1/s) most, per relative change: "
            + "; ".join(parts) + " (parameters at 0 left out).")


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
        rows.append([s["config"], str(s["dof"]), s["verdict"], fmt(s["least_delta"], 5),
                     fmt(s["least_zeta"], 4), ", ".join(f"{f:.4g}" for f in s["freqs"]),
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
            lim = min(small, key=lambda c: c["line"]["damping_scale"])["critical"] if small else None
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
