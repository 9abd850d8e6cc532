"""The report's study sections (``[[report.studies]]``): a sweep's table of first losses of
stability, range-of-motion exits and boundary curves with its figures, and the comparison with
and without the constraint-force stiffness; computed by :mod:`mbseig.studies.report_studies`.
A sweep over a rotor's speed also shows the rotor (:func:`rotor_blocks`: the Campbell diagram,
the critical speeds and the unbalance response, computed by
:func:`mbseig.studies.campbell.rotor_study`)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import plots
from ..display import fmt_complex
from ..plots import rotor as rotor_plots
from .text import fmt
from .units import with_unit

__all__ = ["study_section", "compare_blocks", "rotor_blocks", "rotor_section"]

# what they format is computed by mbseig.studies.report_data (StudyData, RotorData)


def study_section(data, units):
    """Blocks of one ``[[report.studies]]`` entry and its summary, from its computed
    :class:`~mbseig.studies.report_data.StudyData`."""
    study, title = data.study, data.title
    config = study.get("config")
    blocks = [("h2", title)]
    if data.kind == "compare":
        return blocks + compare_blocks(data.compare), {"title": title}
    sw = data.sweep
    res, values, name = sw.result, sw.values, sw.parameter
    sdir, paths = data.folder, data.paths
    xtol = res.tolerances["xtol"]
    unit = units.get(name)
    rows = []
    for c in sw.critical:
        first, rom, line = c["first"], c["rom"], c["line"]
        label = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k))
                          for k, v in line.items()) or "–"
        freq = "–" if first is None else f"{abs(first['eigenvalue'][1]) / (2 * math.pi):.5g}"
        band = ("–" if first is None or first["band"][0] == first["band"][1] else
                f"{first['band'][0]:.10g} … {first['band'][1]:.10g}")
        rows.append([label,
                     "stable over the range" if first is None
                     else with_unit(f"{first['value']:.10g}", unit),
                     "–" if first is None else first["kind"] + (
                         "" if first.get("event") == "crossing" else f" ({first['event']})"),
                     freq, band,
                     "inside over the range" if rom is None else
                     with_unit(f"{rom['value']:.8g}", unit) + f" ({rom['joint']})",
                     str(c["failed"])])
    # the crossing eigenvalue at each boundary, for the summary figure
    crit = [{**{k: v for k, v in c.items() if k != "first"},
             "eigenvalue": None if c["first"] is None else list(c["first"]["eigenvalue"])}
            for c in sw.critical]
    n_fold = sum(1 for f in res.folds if f["type"] == "fold")
    blocks.append(("p", f"{name} from {values[0]:g} to {with_unit(f'{values[-1]:g}', unit)} "
                        f"({len(values)} points per line) on "
                        f"{config}, each line followed by continuation from its first equilibrium "
                        f"(tangent predictor, pseudo-arclength through folds; {n_fold} fold(s) "
                        f"found); modes tracked by MAC; each boundary located where Re s = 0 of "
                        f"the crossing mode (or where the two eigenvalues of an undamped pair "
                        f"collide) by Brent's method to xtol = {xtol:.3g}, with the band where "
                        f"the mode is critical within its tolerance beside it; range-of-motion "
                        f"exit by Brent's method on the smallest joint margin to the same xtol."))
    u = f" [{unit}]" if unit and unit != "1" else ""
    blocks.append(("table", ["line", f"critical {name}", "instability",
                             "ω_d/2π at onset [Hz]", f"critical band{u}",
                             f"{name} where the posture leaves the range of motion",
                             "failed points"], rows))
    for c in res.curves:
        pts = [p for p in c["points"] if p["value"] is not None]
        blocks.append(("p", f"The {c['kind']} boundary of the first line, followed across "
                            f"{c['along']} (two-parameter continuation: each point located again "
                            f"from the secant prediction of the last two; "
                            f"{len(pts)} of {len(c['points'])} points found):"))
        ua = units.get(c["along"])
        blocks.append(("table", [c["along"] + (f" [{ua}]" if ua and ua != "1"
                                               else " [–]" if ua else ""),
                                 f"critical {name}{u}", "test function"],
                       [[f"{p['p2']:.6g}", f"{p['value']:.10g}", p.get("test") or "–"]
                        for p in pts]))
    captions = {"root_locus": "root locus (one colour a mode, numbered as the mode tables at the "
                              "first value; one line style a line)",
                "modes_vs_parameter": "damped frequency ω_d/2π and damping δ of each mode",
                "bifurcation": "bifurcation diagram (dashed where unstable)",
                "stability_map": "stability map: spectral abscissa on the grid",
                "stability_chart": "stability chart from the followed boundaries"}
    for p in paths:
        if p.suffix == ".png":
            blocks.append(("img", p, f"{title}: {captions.get(p.stem, p.stem.replace('_', ' '))}"))
    if data.rotor is not None:
        blocks += rotor_blocks(data.rotor, sdir, title, units)
    return blocks, {"title": title, "parameter": name, "config": config, "critical": crit,
                    "curves": sw.curves}


def compare_blocks(cmp):
    pairs = cmp.pairs
    bounds = cmp.bounds or [((None, None), (None, None))] * len(pairs)
    rows = []
    for k, ((a, b), (ba, bb)) in enumerate(zip(pairs, bounds, strict=True)):
        rel = abs(a - b) / abs(a) if a is not None and b is not None and abs(a) > 0 else None
        rows.append([str(k + 1), "–" if a is None else fmt_complex(a, *ba),
                     "–" if b is None else fmt_complex(b, *bb),
                     "–" if rel is None else f"{rel:.3g}"])
    return [("p", f"Eigenvalues of {cmp.config} with the constraint-force stiffness Σ λ ∇²Φ "
                  f"(correct) and without it (the common omission); largest multiplier |λ| = "
                  f"{cmp.lam_max:.4g}. "
                  f"Verdict with: {cmp.verdict_with}; without: {cmp.verdict_without}."),
            ("table", ["#", "s with Σλ∇²Φ", "s without", "|Δs|/|s|"], rows)]


def rotor_section(data, units):
    """A report section of a rotor over the speeds asked for by the caller (not a
    ``[[report.studies]]`` entry), from its :class:`~mbseig.studies.report_data.RotorData`:
    :func:`rotor_blocks`, or a sentence when the parameter does not set a rotor's speed."""
    name, config = data.parameter, data.config
    title = f"Rotor over {name}" + (f" ({config})" if config else "")
    if data.rotor is None:
        return [("h2", title), ("p", f"{name} does not set the speed of a rotor of the case: "
                                     f"no Campbell diagram or unbalance response.")]
    return [("h2", title)] + rotor_blocks(data.rotor, data.folder, title, units)


def rotor_blocks(rs, out_dir, title, units):
    """The Campbell diagram with its critical-speed table, then the unbalance response (a
    table of each station's peak, the Bode and polar figures, the full table as CSV) of a
    :class:`~mbseig.studies.campbell.RotorStudy`."""
    out_dir.mkdir(parents=True, exist_ok=True)
    name, camp = rs.parameter, rs.campbell
    unit = units.get(name)
    camp = dataclasses.replace(camp, units={k: v for k, v in units.items() if v})
    blocks = [("h3", f"{title}: Campbell diagram and critical speeds")]
    img = plots.save(rotor_plots.campbell_diagram(camp), out_dir / "campbell.png")
    blocks.append(("img", img, f"{title}: Campbell diagram (frequency of each mode against "
                               f"{name}, coloured by whirl; dashed: the {camp.harmonic:g}x "
                               f"excitation; circles: critical speeds) and log decrements "
                               f"(within their error bound 2π tol/ω_d: drawn as 0)"))
    rows = [[str(k + 1), with_unit(f"{c['value']:.8g}", unit), f"{c['speed']:.8g}",
             f"{c['speed'] * 30 / math.pi:.6g}", f"{c['frequency'] / (2 * math.pi):.6g}",
             c["whirl"] or "–", str(c["mode"])] for k, c in enumerate(camp.critical_speeds)]
    xtol = camp.tolerances.get("xtol", 0.0)
    if rows:
        blocks.append(("p", f"Critical speeds: where a lateral mode's frequency meets the "
                            f"{camp.harmonic:g}x excitation line, each located by Brent's method "
                            f"to xtol = {xtol:.3g} along the track followed by MAC."))
        blocks.append(("table", ["#", f"critical {name}", "Ω [rad/s]", "Ω [rpm]",
                                 "ω_d/2π [Hz]", "whirl", "track"], rows))
    else:
        blocks.append(("p", f"No critical speed in the swept range (no lateral mode meets the "
                            f"{camp.harmonic:g}x excitation line)."))
    blocks += _unbalance_blocks(rs, out_dir, title, unit,
                                [c["value"] for c in camp.critical_speeds])
    return blocks


def _unbalance_blocks(rs, out_dir, title, unit, critical):
    ub = rs.unbalance
    csv = ub.write_csv(out_dir / "unbalance.csv")
    how = ("m·e = 1 kg m (the case names no unbalance; the response is proportional to m·e: "
           "multiply by the rotor's own)" if rs.default_unbalance else f"m·e = {rs.me:g} kg m")
    blocks = [("h3", f"{title}: unbalance response"),
              ("p", f"Synchronous response to an unbalance {how} at {rs.at}, angle 0 from e₁ "
                    f"= ({', '.join(f'{x:.3g}' for x in ub.directions['e1'])}), at each "
                    f"{rs.parameter} of the sweep: the orbit's major semi-axis and the phase of "
                    f"x₁ (x₁(t) = |X₁| cos(Ωt + phase)) at every rotor station and output; the "
                    f"whole table (every speed) is in `{out_dir.name}/{csv.name}`.")]
    rows = []
    for v, om, st, a, _b, big, u in ub.peaks():
        rows.append([st, with_unit(fmt(v, 6), unit), fmt(om, 6), f"{big:.4e} {u or ''}".strip(),
                     "–" if a == 0 else f"{np.degrees(np.angle(a)):.1f}"])
    hits = ub.resonance_values()
    if hits:
        at = ", ".join(with_unit(f"{v:.8g}", unit) for v in hits)
        blocks.append(("p", f"Resonance at {rs.parameter} = {at}: the unbalance drives an "
                            f"undamped mode at its own frequency, so no steady response exists "
                            f"there (it grows without bound): blank in the CSV (column "
                            f"`resonance`), red dashed lines in the Bode diagram, named in the "
                            f"polar diagram's legend; the peaks below are over the other "
                            f"speeds."))
    peak = "peak amplitude per kg m of m·e" if rs.default_unbalance else "peak amplitude"
    blocks.append(("table", ["station / output", f"{rs.parameter} at the peak",
                             "Ω at the peak [rad/s]", peak, "phase of x₁ [deg]"], rows))
    for fig, stem, cap in ((rotor_plots.unbalance_bode(ub, unit=unit, critical=critical),
                            "unbalance_bode", "Bode diagram: amplitude and phase against "
                            + rs.parameter + " (dotted: critical speeds"
                            + ("; red dashed: resonances)" if hits else ")")),
                           (rotor_plots.unbalance_polar(ub, unit=unit), "unbalance_polar",
                            "polar diagram of x₁")):
        blocks.append(("img", plots.save(fig, out_dir / f"{stem}.png"), f"{title}: {cap}"))
    return blocks

