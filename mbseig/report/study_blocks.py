"""The report's study sections (``[[report.studies]]``): a sweep's table of first losses of
stability, range-of-motion exits and boundary curves with its figures, and the comparison with
and without the constraint-force stiffness; computed by :mod:`mbseig.studies.report_studies`."""

from __future__ import annotations

import math

from ..studies import write_outputs
from ..studies.report_studies import compare_study, sweep_study
from .units import with_unit

__all__ = ["study_section", "compare_blocks"]


def study_section(case, study, out_dir, stem, jobs, units):
    kind = "compare" if "compare" in study else "sweep"
    config = study.get("config")
    title = study.get("title", f"{kind} on {config}")
    blocks = [("h2", title)]
    if kind == "compare":
        return blocks + compare_blocks(compare_study(case, config)), {"title": title}
    sw = sweep_study(case, study, jobs=jobs)
    res, values, name = sw.result, sw.values, sw.parameter
    sdir = out_dir / f"{stem}_{config}_{name}"
    paths = write_outputs(res, sdir, units=units)
    xtol = res.tolerances["xtol"]
    unit = units.get(name)
    rows = []
    for c in sw.critical:
        first, rom, line = c["first"], c["rom"], c["line"]
        label = ", ".join(f"{k} = " + with_unit(f"{v:g}", units.get(k)) for k, v in line.items()) or "–"
        freq = "–" if first is None else f"{abs(first['eigenvalue'][1]) / (2 * math.pi):.5g}"
        band = ("–" if first is None or first["band"][0] == first["band"][1] else
                f"{first['band'][0]:.10g} … {first['band'][1]:.10g}")
        rows.append([label,
                     "stable over the range" if first is None else with_unit(f"{first['value']:.10g}", unit),
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
                        f"the mode is critical within its tolerance beside it; range-of-motion exit "
                        f"by Brent's method on the smallest joint margin to the same xtol."))
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
        blocks.append(("table", [c["along"] + (f" [{ua}]" if ua and ua != "1" else " [–]" if ua else ""),
                                 f"critical {name}{u}", "test function"],
                       [[f"{p['p2']:.6g}", f"{p['value']:.10g}", p.get("test") or "–"] for p in pts]))
    captions = {"root_locus": "root locus (one colour a mode, numbered as the mode tables at the "
                              "first value; one line style a line)",
                "modes_vs_parameter": "damped frequency ω_d/2π and damping δ of each mode",
                "bifurcation": "bifurcation diagram (dashed where unstable)",
                "stability_map": "stability map: spectral abscissa on the grid",
                "stability_chart": "stability chart from the followed boundaries"}
    for p in paths:
        if p.suffix == ".png":
            blocks.append(("img", p, f"{title}: {captions.get(p.stem, p.stem.replace('_', ' '))}"))
    return blocks, {"title": title, "parameter": name, "config": config, "critical": crit,
                    "curves": sw.curves}


def compare_blocks(cmp):
    pairs = cmp.pairs
    rows = []
    for k, (a, b) in enumerate(pairs):
        rel = abs(a - b) / abs(a) if a is not None and b is not None and abs(a) > 0 else None
        rows.append([str(k + 1), "–" if a is None else f"{a.real:.6g} {a.imag:+.6g}i",
                     "–" if b is None else f"{b.real:.6g} {b.imag:+.6g}i",
                     "–" if rel is None else f"{rel:.3g}"])
    return [("p", f"Eigenvalues of {cmp.config} with the constraint-force stiffness Σ λ ∇²Φ (correct) "
                  f"and without it (the common omission); largest multiplier |λ| = {cmp.lam_max:.4g}. "
                  f"Verdict with: {cmp.verdict_with}; without: {cmp.verdict_without}."),
            ("table", ["#", "s with Σλ∇²Φ", "s without", "|Δs|/|s|"], rows)]
