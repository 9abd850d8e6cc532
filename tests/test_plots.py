"""Figures: no backend switch, rigid bodies kept rigid in mode-shape drawings, every element
drawn, real modes drawn as decays, legends outside the data, log scales where values span
decades.

References: rigid lengths from the case file (hand_device.md: phalanx lengths 0.245/0.143/0.097
of 190 mm, rod 40 mm), checked to 1e-9 relative (the projection's own tolerance is 1e-12 of L²).
"""

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from conftest import CASES

from mbseig import plots


def test_plots_do_not_switch_the_backend():
    """A notebook's backend survives mbseig's figures: run in a fresh interpreter with a
    non-Agg backend chosen first, draw every kind of figure, and check the backend and pyplot's
    figure list are unchanged (an earlier version switched to Agg and later figures vanished)."""
    code = textwrap.dedent(f"""
        import matplotlib
        matplotlib.use("svg")
        import matplotlib.pyplot as plt
        import numpy as np
        from matplotlib.figure import Figure
        import mbseig
        from mbseig import plots
        before = matplotlib.get_backend()
        fig0 = plt.figure()  # the user's own figure
        a = mbseig.analyze({str(CASES / "hand_device.toml")!r}, config="C1")
        figs = [plots.pole_map(a.modes.eigenvalues, stability=a.modes.stability),
                plots.mechanism_modes(a.eq.model, a.eq.q, a.modes.shapes, ["1", "2", "3"],
                                      eigenvalues=a.modes.eigenvalues)]
        assert all(isinstance(f, Figure) for f in figs)
        assert matplotlib.get_backend() == before, (before, matplotlib.get_backend())
        assert plt.get_fignums() == [fig0.number], plt.get_fignums()
        print("OK", before)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "OK svg"


@pytest.fixture(scope="module")
def c3():
    import mbseig

    return mbseig.analyze(CASES / "hand_device.toml", config="C3")


def _lengths(model, q):
    out = {}
    for name, b in model.bodies.items():
        i, j = b["points"]
        out[name] = float(np.linalg.norm(model.points[j](q) - model.points[i](q)))
    return out


def test_projection_keeps_bodies_rigid(c3):
    """A linear displacement q0 + a·v stretches the bodies; the projection onto Φ = 0 restores
    every rigid length (the distal phalanx used to be drawn 53 mm long instead of 18.43 mm)."""
    model, q0 = c3.eq.model, c3.eq.q
    v = np.real(c3.modes.shapes[:, 2])
    v = v / np.max(np.abs(v))
    q_lin = q0 + 0.12 * model.length_scale * v
    expected = {"proximal": 0.04655, "middle": 0.02717, "distal": 0.01843, "rod": 0.040}
    stretched = _lengths(model, q_lin)
    assert max(abs(stretched[k] / L - 1) for k, L in expected.items()) > 0.01  # visibly wrong
    q_proj, res = plots.project_constraints(model, q_lin)
    assert res <= 1e-12
    got = _lengths(model, q_proj)
    for k, L in expected.items():
        assert got[k] == pytest.approx(L, rel=1e-9), k
    # the slider stays on its guide x = 15 mm
    assert model.points["S"](q_proj)[0] == pytest.approx(0.015, abs=1e-12)


def test_every_element_is_found_for_the_drawing(c3):
    lay = plots.mechanism_layout(c3.eq.model, c3.eq.q)
    assert [s["name"] for s in lay["springs"]] == ["actuator"]
    assert lay["springs"][0]["ends"] == ("G", "S")
    assert [g["name"] for g in lay["guides"]] == ["guide"]
    assert {t["name"]: t["at"] for t in lay["torsional"]} == {"MCP": "A", "PIP": "B", "DIP": "C"}
    assert [ld["name"] for ld in lay["loads"]] == ["tendon load"]
    assert sorted(lay["fixed"]) == ["A", "G"]


def test_real_modes_are_drawn_as_decays(c3):
    """C3 has two overdamped modes (real s): their panels hold four fading configurations
    (t = 0, τ, 2τ, 3τ), not a ± pair, and the legend says so."""
    md = c3.modes
    real = [k for k in range(len(md)) if md.eigenvalues[k].imag == 0]
    assert real  # C3: spastic finger, damping ×10
    fig = plots.mechanism_modes(c3.eq.model, c3.eq.q, md.shapes,
                                [f"m{k}" for k in range(len(md))], eigenvalues=md.eigenvalues)
    ax_real = fig.axes[real[0]]
    purple = [ln for ln in ax_real.lines if ln.get_color() == "tab:purple"]
    red = [ln for ln in ax_real.lines if ln.get_color() == "tab:red"]
    assert purple and not red
    ax_osc = fig.axes[next(k for k in range(len(md)) if md.eigenvalues[k].imag != 0)]
    assert any(ln.get_color() == "tab:red" for ln in ax_osc.lines)
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any("real mode" in t for t in texts)


def test_pole_map_grid_and_legend_outside():
    s = np.array([-1 + 10j, -0.5 + 100j, -30 + 0j])
    fig = plots.pole_map(s, stability=["stable"] * 3)
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.texts]
    assert any(t.startswith("ζ=") for t in texts) and any(t.startswith("ωn=") for t in texts)
    leg = ax.get_legend()
    assert leg is not None
    fig.canvas.draw()
    lb = leg.get_window_extent()
    axb = ax.get_window_extent()
    assert lb.x0 >= axb.x1 - 1  # legend right of the axes, not over the data


def test_decade_scale():
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    assert plots.decade_scale(ax, "y", [1, 0.1, 0.01, 0]) == "symlog"
    assert plots.decade_scale(ax, "x", [1e3, 1e4, 1e5]) == "log"
    assert plots.decade_scale(ax, "x", [1, 2, 3]) == "linear"
