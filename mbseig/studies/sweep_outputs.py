"""What a sweep writes: sweep.json, tracks.csv, boundaries.csv, branch.csv and curves.csv, and
the figures (root locus, modes against the parameter, bifurcation diagram, stability map and
chart)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from .. import plots
from .sweep_result import SweepResult


# ---------------------------------------------------------------------------------------------
def write_outputs(res: SweepResult, out_dir, *, units=None) -> list[Path]:
    """sweep.json, tracks.csv, boundaries.csv, root_locus.png, modes_vs_parameter.png,
    bifurcation.png (and branch.csv) when branches were followed, and, for two swept
    parameters, stability_map.png, with curves.csv and stability_chart.png when boundaries were
    followed across the second.  ``units`` ({parameter: unit}) labels the plots' axes.
    Returns the written paths."""
    if units:
        import dataclasses

        res = dataclasses.replace(res, units={**res.units, **units})
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    p = out / "sweep.json"
    p.write_text(json.dumps(res.to_json(), indent=1, allow_nan=False) + "\n")
    paths.append(p)
    others = [n for n, _ in res.axes[1:]]
    p = out / "tracks.csv"
    with p.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(others + [res.axis, "track", "re", "im", "delta", "omega_n", "freq_hz", "zeta",
                             "mode"])
        for li, line in enumerate(res.lines):
            S = res.tracks[li]
            numbers = res.mode_numbers(li)
            for j in res.listed_tracks(S):
                for k, v in enumerate(res.values):
                    s = S[k, j]
                    if np.isnan(s):
                        continue
                    wn = abs(s)
                    w.writerow([repr(float(line[n])) for n in others] + [
                        repr(float(v)), j, repr(float(s.real)), repr(float(s.imag)),
                        repr(float(-s.real)), repr(float(wn)),
                        repr(float(abs(s.imag) / (2 * math.pi))),
                        repr(float(-s.real / wn)) if wn > 0 else "0.0", numbers.get(j, "")])
    paths.append(p)
    p = out / "boundaries.csv"
    with p.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(others + ["parameter", "value", "track", "re", "im", "kind", "stability", "xtol",
                             "event", "band_lo", "band_hi", "method"])
        for b in res.boundaries:
            w.writerow([repr(b["fixed"][n]) for n in others] + [
                b["parameter"], repr(b["value"]), "" if b["track"] is None else b["track"],
                repr(b["eigenvalue"][0]), repr(b["eigenvalue"][1]), b["kind"], b["stability"],
                repr(b["xtol"]), b.get("event", ""), repr(b["band"][0]), repr(b["band"][1]),
                b.get("method", "")])
    paths.append(p)
    paths.append(plots.save(plots.root_locus(res), out / "root_locus.png"))
    paths.append(plots.save(plots.modes_vs_parameter(res), out / "modes_vs_parameter.png"))
    if res.diagram:
        p = out / "branch.csv"
        with p.open("w", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(others + [res.axis, res.diagram["variable"], "kind", "segment", "static",
                                 "verdict"])
            for li, line in enumerate(res.lines):
                for b in res.branches[li]:
                    w.writerow([repr(float(line[n])) for n in others] + [
                        repr(float(b["p"])),
                        "" if b.get("value") is None else repr(float(b["value"])),
                        b["kind"], b["segment"], b.get("static") or "", b.get("verdict") or ""])
        paths.append(p)
        paths.append(plots.save(plots.bifurcation_diagram(res), out / "bifurcation.png"))
    if len(res.axes) == 2:
        paths.append(plots.save(plots.stability_map(res), out / "stability_map.png"))
        if res.curves:
            p = out / "curves.csv"
            with p.open("w", newline="") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(["curve", res.curves[0]["along"], res.axis, "stability", "test",
                            "band_lo", "band_hi"])
                for i, c in enumerate(res.curves):
                    for pt in c["points"]:
                        band = pt.get("band") or [None, None]
                        w.writerow([i, repr(pt["p2"]),
                                    "" if pt["value"] is None else repr(pt["value"]),
                                    c["stability"], pt.get("test") or "",
                                    "" if band[0] is None else repr(band[0]),
                                    "" if band[1] is None else repr(band[1])])
            paths.append(p)
            paths.append(plots.save(plots.stability_chart(res), out / "stability_chart.png"))
    return paths
