"""Figures that show numbers, not rounding; readable 3-D mode shapes; the report's first page.

References: values within their error band (|Re s| ≤ tol, the eigenvalue's stability tolerance)
are drawn exactly as 0 and the axes span at least ±5 % of max |s| (the documented physical
scale, mbseig.plots.sweeps.physical_limits); the log decrement's band is 2π tol/ω_d. The rotor
disc radius is the closed form of a uniform disc, r = √(2 J_p/m). The margin text's numbers are
the arithmetic of the case's values (d = p* − p, 100 |d|/|p| %).
"""

import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig.plots import spatial
from mbseig.plots.sweeps import banded_real, root_locus


class Sweep(SimpleNamespace):
    """The attributes root_locus reads from a sweep result (duck typing)."""

    def listed_tracks(self, S):
        return range(S.shape[1])


def undamped_sweep(noise):
    x = np.linspace(0.0, 800.0, 9)
    rng = np.random.default_rng(1)
    w = np.stack([100 + 0 * x, 300 + 0.1 * x], axis=1)
    tracks = rng.uniform(-noise, noise, w.shape) + 1j * w
    return Sweep(case="rotor.toml", config=None, axes=[("Omega", x)], axis="Omega", values=x,
                 tracks=[tracks], tolerances_track=[1e-12 * np.abs(tracks) + 1e-10],
                 boundaries=[], lines=[{}], units={"Omega": "rad/s"})


def test_banded_real_is_zero_inside_the_band_only():
    col = np.array([1e-13 + 5j, -2e-13 + 5j, -3.0 + 4j])
    tol = np.array([1e-10, 1e-10, 1e-10])
    assert list(banded_real(col, tol)) == [0.0, 0.0, -3.0]
    assert list(banded_real(col, None)) == list(col.real)  # no tolerance: drawn as computed


def test_root_locus_draws_noise_as_zero_on_a_physical_axis():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = root_locus(undamped_sweep(1.5e-13))
    ax = fig.axes[0]
    xs = np.concatenate([ln.get_xdata() for ln in ax.lines if len(ln.get_xdata()) > 2])
    assert np.all(xs == 0.0)  # every Re s within its band: on the axis
    lo, hi = ax.get_xlim()
    assert hi - lo >= 0.1 * 380  # at least ±5 % of max |s| (= 380 rad/s), not ±1e-13
    assert "rad/s" in ax.get_title() and "[1/s]" in ax.get_xlabel()
    assert "[rad/s]" in ax.get_ylabel()


def campbell_result(noise, *, rpm=False):
    x = np.linspace(0.0, 800.0, 9)
    speeds = x * 2 * math.pi / 60 if rpm else x
    rng = np.random.default_rng(2)
    tracks = rng.uniform(-noise, noise, (9, 2)) + 1j * np.stack([100 + 0 * x, 300 + 0 * x], 1)
    return SimpleNamespace(case="rotor", parameter="speed" if rpm else "Omega", values=x,
                           speeds=speeds, harmonic=1.0, tracks=tracks,
                           frequency=np.abs(tracks.imag),
                           log_decrement=2 * math.pi * (-tracks.real) / np.abs(tracks.imag),
                           whirl=[["forward", "backward"]] * 9, critical_speeds=[])


@pytest.mark.parametrize("rpm", [False, True])
def test_campbell_log_decrement_noise_is_zero_and_units_are_named(rpm):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = spatial.campbell_diagram(campbell_result(1e-13, rpm=rpm))
    a2 = fig.axes[1]
    ys = np.concatenate([ln.get_ydata() for ln in a2.lines])
    assert np.all(ys == 0.0)  # Λ ~ 1e-15 is inside 2π·1e-12|s|/ω_d
    lo, hi = a2.get_ylim()
    assert lo <= -0.05 and hi >= 0.05
    assert a2.get_xlabel().endswith("[rpm]" if rpm else "[rad/s]")
    assert "[–]" in a2.get_ylabel() and "[Hz]" in fig.axes[0].get_ylabel()


def test_campbell_keeps_real_damping():
    res = campbell_result(0.0)
    res.tracks = res.tracks - 2.0  # δ = 2 1/s: Λ = 2π·2/ω_d
    res.log_decrement = 2 * math.pi * 2.0 / np.abs(res.tracks.imag)
    fig = spatial.campbell_diagram(res)
    ys = np.concatenate([ln.get_ydata() for ln in fig.axes[1].lines])
    assert np.isclose(ys.max(), 2 * math.pi * 2 / 100, rtol=1e-12)


def test_spatial_three_view_draws_bodies_joints_and_no_warning():
    a = mbseig.analyze(CASES / "spatial_double_pendulum.toml")
    layout = spatial.spatial_layout(a.model)
    assert layout["fixed"] == ["O"] and "A" in layout["joints"]  # pivot and shared point
    # each link is drawn through its carried points, not as a dot at its centre of mass
    assert [len(b["points"]) for b in layout["bodies"]] == [3, 2]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "Ignoring fixed y limits ..." would fail here
        fig = spatial.spatial_modes(a.model, a.eq.q, a.modes.shapes[:, 2:4], ["m3", "m4"])
    assert sum(ax.name == "3d" for ax in fig.axes) == 2 and len(fig.axes) == 8
    for ax in fig.axes:  # true aspect: every view as wide as it is high
        if ax.name != "3d":
            (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
            assert math.isclose(x1 - x0, y1 - y0, rel_tol=1e-12)


def test_rotor_disc_is_the_uniform_disc_of_the_body():
    a = mbseig.analyze(CASES / "rigid_rotor.toml")
    layout = spatial.spatial_layout(a.model)
    (disc,) = layout["discs"]
    p = a.model.parameters
    assert math.isclose(disc["radius"], math.sqrt(2 * p["Jp"] / p["m"]), rel_tol=1e-14)
    assert [s["name"] for s in layout["stations"]] == ["bearing 1",
                                                       "bearing 2"]


def test_margin_text_says_the_side_and_the_distance():
    from mbseig.report.summary import margin_text

    t = margin_text("c_a", 1.0, -6.95123, "N s/m", "flutter")
    assert t == ("c_a = 1 N s/m (stable side): flutter if c_a falls by 7.951 N s/m, 795 % of "
                 "its present value, to c_a* = -6.95123 N s/m")
    t = margin_text("f", 1.0, 1.78639, "N", "flutter")
    assert "f rises by 0.7864 N, 79 % of its present value" in t


def test_reactions_below_their_error_bound_are_zero():
    from mbseig.studies.report_studies import _reaction_zero

    eq = SimpleNamespace(tolerances={"tol": 1e-12})
    rep = {"pins": [{"force": [12.0, 1.77636e-15]}],
           "constraints": [{"reaction": {"value": [6.3e-22, -30.0]}}, {"reaction": {"value": 4.0}}]}
    assert _reaction_zero(eq, rep) == pytest.approx(30.0e-12, rel=1e-15)


def test_summary_figures():
    from mbseig import plots

    fig = plots.summary_poles([{"label": "C1", "s": -12.4 + 56.2j, "stable": True},
                               {"label": "C2", "s": -15.0 + 63.0j, "stable": True}],
                              [{"label": "C2: c_a* = -6.95 N s/m", "s": 430j}])
    ax = fig.axes[0]
    assert ax.get_xlim()[1] > 0 and ax.get_ylim()[1] >= 430  # the boundary is in view
    fig = plots.tornado([{"title": "C1", "rows": [("hand_length", -0.613), ("c_a", 0.0279)]}])
    widths = sorted(round(p.get_width(), 12) for p in fig.axes[0].patches)
    assert widths == sorted(round(w, 12) for w in (-6.13, 6.13, 0.279, -0.279))  # ±10 %
