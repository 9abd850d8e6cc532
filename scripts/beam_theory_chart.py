"""Euler–Bernoulli versus Timoshenko: frequency ratio against slenderness (reports/beam_theory/).

    python scripts/beam_theory_chart.py

Lines: closed forms for a simply supported rectangular steel beam (ν = 0.3, κ = 5/6), ratio
ω_EB/ω_Timoshenko of modes 1–3 against L/h.  Markers: mbseig's Timoshenko beam
(cases/timoshenko_beam.toml with L varied, mesh refined to 1e-4; bending modes picked by their
shapes, as axial modes come lower in stubby beams) over its own Euler–Bernoulli beam, so the chart shows both the theory gap and that mbseig reproduces it.  Shaded: the
slenderness below which mbseig warns (L/d < 10 for Euler–Bernoulli, < 5 for either theory).
Writes beam_theory_ratio.png and beam_theory_ratio.csv.
"""

from __future__ import annotations

import csv
import math
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))


def closed_form_ratio(n, slenderness, nu=0.3, kappa=5.0 / 6.0):
    from test_beams import timoshenko_ss

    E, rho, b, h = 2.1e11, 7850.0, 0.02, 0.1
    L = slenderness * h
    A, I, G = b * h, b * h**3 / 12, E / (2 * (1 + nu))
    eb = (n * math.pi / L) ** 2 * math.sqrt(E * I / (rho * A))
    return eb / timoshenko_ss(n, E=E, G=G, kap=kappa, A=A, I=I, rho=rho, L=L)


def mbseig_ratio(slenderness):
    from mbseig.studies import analyze

    h = 0.1
    out = []
    for theory in ("euler-bernoulli", "timoshenko"):
        text = (ROOT / "cases" / "timoshenko_beam.toml").read_text()
        text = text.replace('theory = "timoshenko"', f'theory = "{theory}"')
        tmp = ROOT / "reports" / "beam_theory" / "_case.toml"
        tmp.write_text(text)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = analyze(tmp, params={"L": str(slenderness * h)},
                        refine={"modes": 3, "accuracy": 1e-4})
        tmp.unlink()
        # bending modes only: transverse (y) motion dominates axial (x) motion in the shape
        names = a.linear.coordinate_names
        ix = [k for k, nm in enumerate(names) if nm.endswith(".x")]
        iy = [k for k, nm in enumerate(names) if nm.endswith(".y")]
        sh = np.abs(a.modes.shapes)
        bending = [k for k in range(len(a.modes)) if sh[iy, k].max() > sh[ix, k].max()]
        out.append(np.sort(a.modes.omega_n[bending])[:3])
    return out[0] / out[1]


def main():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    outdir = ROOT / "reports" / "beam_theory"
    outdir.mkdir(parents=True, exist_ok=True)
    s = np.linspace(3, 50, 200)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.axvspan(3, 5, color="0.85", label="L/h < 5: no beam theory (warning)")
    ax.axvspan(5, 10, color="0.93", label="L/h < 10: Euler–Bernoulli warns")
    rows = []
    points = [4, 6, 8, 12, 20, 40]
    computed = {x: mbseig_ratio(x) for x in points}
    for n, color in zip((1, 2, 3), ("C0", "C1", "C2")):
        r = [closed_form_ratio(n, x) for x in s]
        ax.plot(s, r, color=color, label=f"mode {n}, closed forms")
        ax.plot(points, [computed[x][n - 1] for x in points], "o", color=color, mfc="none",
                label=f"mode {n}, mbseig" if n == 1 else None)
        for x in points:
            rows.append([n, x, closed_form_ratio(n, x), computed[x][n - 1]])
    ax.set_xlabel("slenderness L/h (simply supported, rectangular section, ν = 0.3, κ = 5/6)")
    ax.set_ylabel("ω Euler–Bernoulli / ω Timoshenko")
    ax.set_xlim(3, 50)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(outdir / "beam_theory_ratio.png", dpi=120)
    with open(outdir / "beam_theory_ratio.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["mode", "slenderness", "ratio_closed_form", "ratio_mbseig"])
        w.writerows(rows)
    print(f"wrote {outdir / 'beam_theory_ratio.png'} and .csv")


if __name__ == "__main__":
    main()
