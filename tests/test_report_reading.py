"""What a person reads in a report and its figures (DESIGN §6, issue 40): the zero rule in the
report's tables, summaries and figure titles; one page style for rest, steady and periodic
motion; the bicycle's report with figures and units; no internal coordinate names; figures
whose text is never clipped; GIFs legible at their own pixel size.

References: the raw values and their bounds come from ``mbseig modes --json`` of the same case
(the report must print 0 exactly where the JSON's value lies within its bound, and the value
otherwise); rounding residue is 1e-13 and below (as tests/test_zero_rule.py). The figures'
text boxes are measured by matplotlib's renderer against the figure's own box (1 px of
anti-aliasing allowed); a GIF's text height in pixels is its point size × dpi / 72.
"""

import json
import re

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig.cli import main

TINY = re.compile(r"[-+]?\d\.?\d*e-(?:1[3-9]|[2-9]\d|\d{3})\b")  # 1e-13 and below
INTERNAL = re.compile(r"\.[uvw]\.|\.n\d+\b")  # a unit-vector coordinate, a beam node index


#: columns and sentences that hold error measures, not values (a residual, a bound, a backward
#: error, a margin δ − tol): their small numbers are data about the computation
MEASURES = re.compile(r"residual|bound|err|η|margin|correction|tol|differ", re.I)


def values_text(md):
    """The report's text without its error measures (:data:`MEASURES`): table cells under such
    a header or in a row named so, sentences that state them."""
    out, header = [], None
    for ln in md.splitlines():
        if ln.startswith("|"):
            cells = [c.strip() for c in re.split(r"(?<!\\)\|", ln)[1:-1]]
            if header is None:
                header = cells
                continue
            if set(ln) <= set("|-"):
                continue
            if MEASURES.search(cells[0]):
                continue
            out += [c for h, c in zip(header, cells, strict=True) if not MEASURES.search(h)]
        else:
            header = None
            out += [t for t in re.split(r"(?<=[.;])\s", ln) if not MEASURES.search(t)]
    return "\n".join(out)


def modes_json(case, capsys, *extra):
    assert main(["modes", str(CASES / f"{case}.toml"), "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)


def table_after(md, heading):
    """(header, rows) of the first Markdown table after the line ``heading``."""
    lines = md[md.index(heading):].splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("| "))
    rows = []
    for ln in lines[start:]:
        if not ln.startswith("|"):
            break
        rows.append([c.strip() for c in re.split(r"(?<!\\)\|", ln)[1:-1]])
    return rows[0], rows[2:]


@pytest.fixture(scope="module")
def rigid_rotor_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("rigid_rotor")
    md, page = mbseig.write_report(CASES / "rigid_rotor.toml", out_dir=out, animations=False)
    return md.read_text(), page.read_text(), out


def test_rigid_rotor_report_prints_no_number_below_its_bound(rigid_rotor_report, capsys):
    """Every Re s, Im s, δ, ζ, frequency of the mode table reads 0 exactly where the JSON's
    value lies within its bound (Re s, δ: the mode's tolerance); no rounding residue anywhere
    (tables, summary, sensitivities, check); the least-damped mode is not the rotor's spin."""
    md, _, _ = rigid_rotor_report
    raw = modes_json("rigid_rotor", capsys)
    head, rows = table_after(md, "### Modes — verdict: critical")
    assert len(rows) == len(raw["modes"])
    col = {h: i for i, h in enumerate(head)}
    for row, m in zip(rows, raw["modes"], strict=True):
        re_s, tol = m["eigenvalue"][0], m["tolerance"]
        zero = abs(re_s) <= tol
        assert zero  # an undamped rotor: every δ is rounding residue (cy = cz = 0)
        assert row[col["Re s [1/s]"]] == "0" and row[col["δ [1/s]"]] == "0"
        assert row[col["ζ [–]"]] == "0"
        assert float(row[col["Im s [rad/s]"]]) == pytest.approx(m["eigenvalue"][1], rel=1e-5)
    assert rows[0][col["dominant coordinates"]] == raw["modes"][0]["rigid_body"]
    assert "not counted" in rows[0][col["stability"]]
    assert not TINY.findall(values_text(md)), TINY.findall(values_text(md))
    assert not INTERNAL.findall(md)
    summary = md.split("## Summary")[1].split("## Configuration")[0]
    # the least-damped counted mode: mode 1 (the declared spin) is left out, the others all
    # have δ = 0 as read, and the first listed of them is taken
    assert "| base | **critical** | mode 2 (oscillatory)" in summary and "δ = 0 1/s" in summary
    assert raw["verdict_scope"] in md
    # the sensitivities of an undamped (gyroscopic, conservative) rotor's δ are 0 as read:
    # Re s stays 0 whatever the parameters, the computed ∂Re s/∂p are residue within bounds
    _, srows = table_after(summary, "The parameters that move")
    assert srows and all(r[5] == "0" and r[6] == "no change beyond its error bound"
                         for r in srows)
    assert "adds damping" not in summary and "sensitivity_tornado" not in summary


def test_figure_titles_and_gif_frames_read_zero(capsys):
    """The panel titles (still figures and GIF frames) of the rigid rotor's modes say ζ = 0,
    not 6.25e-17."""
    from mbseig.report.modes import mode_label
    from mbseig.studies.report_studies import listing_of_modes

    a = mbseig.analyze(CASES / "rigid_rotor.toml")
    listing = listing_of_modes(a.modes)
    labels = [mode_label(k, listing) for k in range(len(listing))]
    assert labels[0] == "mode 1: rigid-body by construction, not counted"
    assert all(lab.endswith("ζ = 0") for lab in labels[1:]), labels
    assert not any(TINY.search(lab) for lab in labels)


def test_least_damped_mode_skips_the_rigid_spin(tmp_path, capsys):
    """rssr_four_bar: mode 1 is the coupler's spin about its own line (rigid-body by
    construction, ``rigid_body`` in the JSON); the summary's least-damped mode is mode 2."""
    raw = modes_json("rssr_four_bar", capsys)
    assert raw["modes"][0]["rigid_body"] and raw["modes"][1]["rigid_body"] is None
    md, _ = mbseig.write_report(CASES / "rssr_four_bar.toml", out_dir=tmp_path, run_check=False,
                                animations=False, sensitivities=False)
    text = md.read_text()
    assert "| base | **critical** | mode 2 (oscillatory): ω_n/2π = 11.33 Hz" in text
    assert not TINY.findall(values_text(text)), TINY.findall(values_text(text))


@pytest.fixture(scope="module")
def three_pages(tmp_path_factory):
    """The pages of a rest, a steady and a periodic case, as the command writes them."""
    out = tmp_path_factory.mktemp("pages")
    pages = {}
    for kind, case, extra in (("rest", "pendulum", ["--no-check"]),
                              ("steady", "whipple_bicycle", []),
                              ("periodic", "pendulum_shaken_pivot", ["--no-check"])):
        d = out / kind
        assert main(["report", str(CASES / f"{case}.toml"), "--out", str(d), *extra]) == 0
        pages[kind] = (d, (d / "report.md").read_text(), (d / "report.html").read_text())
    return pages


def test_one_page_style_for_every_motion(three_pages):
    """Rest, steady and periodic reports: the same CSS, the same head, the same sections in
    the same order (the reference state named for its motion)."""
    styles = {k: re.search(r"<style>(.*?)</style>", html, re.S).group(1)
              for k, (_, _, html) in three_pages.items()}
    assert styles["rest"] == styles["steady"] == styles["periodic"]
    assert "@media print" in styles["rest"]
    reference = {"rest": "Equilibrium", "steady": "Steady motion", "periodic": "Reference motion"}
    for kind, (_, md, html) in three_pages.items():
        heads = re.findall(r"^(##+) (.*)$", md, flags=re.M)
        skeleton = [(h, t.split(" — ")[0]) for h, t in heads]
        assert skeleton == [("##", "Contents"), ("##", "Summary"), ("##", "Configuration base"),
                            ("###", "Model"), ("###", reference[kind]), ("###", "Modes"),
                            ("###", "Time-domain check")], (kind, skeleton)
        assert "Generated by mbseig" in md and '<nav class="toc">' in html
        assert re.search(r"\| base \| \**(stable|critical|unstable)\** \|", md)  # summary row
        assert "data:image/png;base64," in html and 'src="data:' in html


def test_bicycle_report_has_figures_and_units(three_pages):
    out, md, html = three_pages["steady"]
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", md)
    assert any("shapes" in f for f in figures) and any("poles" in f for f in figures)
    assert all((out / f).stat().st_size > 10_000 for f in figures)
    assert html.count("data:image/png;base64,") == len(figures)
    assert "Speed 5 m/s along x" in md and "along [1.0" not in md
    assert "| v | 5 | m/s |" in md and "| mR | 2 | kg |" in md and "| rR | 0.3 | m |" in md
    for unit in ("Re s [1/s]", "Im s [rad/s]", "ω_n/2π [Hz]", "δ [1/s]", "normal force [N]"):
        assert unit in md
    # the benchmark's modes at 5 m/s (Meijaard et al. 2007, Table 2): the four rigid-body
    # modes by construction named, then capsize, weave, castering; verdict stable
    assert "### Modes — verdict: stable" in md
    for name in ("position along the motion", "lateral position", "heading",
                 "speed along the motion"):
        assert f"| {name} |" in md
    assert "| -0.775342 | 4.46487 |" in md
    assert "The 4 rigid-body modes by construction (named in the table) are not drawn." in md


@pytest.mark.parametrize("case", ["overhung_rotor_friswell", "rolling_disk"])
def test_no_report_names_an_internal_coordinate(case, tmp_path):
    """A beam's nodes and a body's unit vectors are coordinates of mbseig's, never named in a
    report (the rigid rotor's report is checked in its own test above)."""
    if case == "rolling_disk":  # a steady motion: its own page, written by the command
        assert main(["report", str(CASES / f"{case}.toml"), "--out", str(tmp_path),
                     "--no-check"]) == 0
        md = (tmp_path / "report.md").read_text()
    else:
        md = mbseig.write_report(CASES / f"{case}.toml", out_dir=tmp_path, run_check=False,
                                 studies=False, sensitivities=False,
                                 animations=False)[0].read_text()
    assert not INTERNAL.findall(md), INTERNAL.findall(md)
    assert not TINY.findall(values_text(md)), TINY.findall(values_text(md))


# ---------------------------------------------------------------------------------------------
# figures
def outside_texts(fig):
    """The texts drawn on ``fig`` (recorded as matplotlib draws them: a tick label outside the
    view or an annotation clipped away is not drawn) whose box leaves the figure (1 px of
    anti-aliasing allowed)."""
    from unittest import mock

    from matplotlib.text import Text

    from mbseig.plots.common import renderer

    drawn, original = [], Text.draw

    def record(self, r):
        if self.get_visible() and self.get_text().strip():
            drawn.append(self)
        return original(self, r)

    r = renderer(fig)
    with mock.patch.object(Text, "draw", record):
        fig.canvas.draw()
    box = fig.bbox
    out = []
    for t in drawn:
        bb = t.get_window_extent(r)
        if t.get_clip_on() and t.get_clip_box() is not None:
            bb = bb.intersection(bb, t.get_clip_box()) or bb
        if (bb.x0 < box.x0 - 1 or bb.y0 < box.y0 - 1 or bb.x1 > box.x1 + 1
                or bb.y1 > box.y1 + 1):
            out.append(t.get_text())
    return out


def some_figures():
    from mbseig import plots
    from mbseig.plots.spatial import spatial_modes

    pend = mbseig.analyze(CASES / "pendulum.toml")
    rotor = mbseig.analyze(CASES / "rigid_rotor.toml")
    yield "pendulum shapes", lambda: plots.mechanism_modes(
        pend.model, pend.eq.q, pend.modes.shapes, ["mode 1: ω_d/2π = 0.4985 Hz, ζ = 0"],
        title="base: equilibrium (black) and mode shapes, rigid bodies kept rigid")
    yield "pole map", lambda: plots.pole_map(rotor.modes.eigenvalues, title="base: pole map",
                                             stability=rotor.modes.stability)
    yield "tornado", lambda: plots.tornado([{"title": "C1: mode 1, δ = 12.4 1/s", "rows": [
        ("hand_length", -0.613), ("a parameter with a long name", 0.0279)]}])
    yield "spatial shapes", lambda: spatial_modes(
        rotor.model, rotor.eq.q, rotor.modes.shapes,
        ["mode 1: rigid-body by construction, not counted"]
        + [f"mode {k}: ω_d/2π = 63.98 Hz, ζ = 0" for k in range(2, 7)],
        title="base: equilibrium (black) and mode shapes (±, red/blue)")


@pytest.mark.parametrize("name", ["pendulum shapes", "pole map", "tornado", "spatial shapes"])
def test_no_text_is_clipped(name, tmp_path):
    """As saved (plots.save fits the figure first), no text leaves the figure; the pendulum's
    shapes figure, one narrow panel under a long title, did before the fit (the check can
    fail: it finds the clipped title and legend of the figure as drawn without it)."""
    from mbseig import plots

    make = dict(some_figures())[name]
    if name == "pendulum shapes":
        raw = make()
        raw.set_layout_engine("none")  # as before: the layout leaves the title wider than it
        raw.set_size_inches(3.4, 5.1)
        assert outside_texts(raw)
    fig = make()
    plots.save(fig, tmp_path / "f.png")
    assert outside_texts(fig) == []


def test_periodic_multiplier_figure_is_not_clipped(tmp_path):
    from mbseig.plots import save
    from mbseig.report.periodic import multiplier_figure
    from mbseig.studies.periodic_report import periodic_report_data
    from mbseig.studies.point import as_spec

    rep = periodic_report_data(as_spec(CASES / "pendulum_shaken_pivot.toml"), run_check=False,
                               studies=False)
    fig = multiplier_figure(rep)
    save(fig, tmp_path / "m.png")
    assert outside_texts(fig) == []


@pytest.mark.parametrize("case", ["rigid_rotor", "four_bar"])
def test_gif_text_is_legible_and_a_rotor_shows_both_lateral_directions(case):
    """Every text of a GIF frame is at least MIN_TEXT_PX pixels high at the GIF's dpi (point
    size × dpi / 72), nothing is clipped, and a rotor spinning about x is seen in its end view
    (y, z: both lateral directions) beside the 3-D view."""
    import matplotlib
    from matplotlib.text import Text

    from mbseig.plots.animation import GIF_DPI, MIN_TEXT_PX, mode_figure, mode_frames
    from mbseig.plots.common import STYLE, fit

    a = mbseig.analyze(CASES / f"{case}.toml")
    k = 2 if case == "rigid_rotor" else 0  # the rotor's mode 3 moves along y (its "rotor y")
    qs = mode_frames(a.model, a.eq.q, a.modes.shapes[:, k], frames=4)
    with matplotlib.rc_context({**STYLE, "font.size": 9}):
        fig, axes, _ = mode_figure(a.model, a.eq.q, qs, title="mode 2: ω_d/2π = 15.92 Hz, ζ = 0")
        fig.set_dpi(GIF_DPI)
        fit(fig)
        sizes = [t.get_fontsize() * GIF_DPI / 72 for t in fig.findobj(Text)
                 if t.get_visible() and t.get_text().strip()]
        assert sizes and min(sizes) >= MIN_TEXT_PX
        assert outside_texts(fig) == []
    if case == "rigid_rotor":
        views = [(ax.get_xlabel(), ax.get_ylabel()) for ax in axes[1:]]
        assert views[0] == ("y [m]", "z [m]") and views[1][0] == "x [m]"


def test_check_figure_reads_zero_and_names_no_internal_coordinate(tmp_path, monkeypatch):
    """mbseig check --plot: a predicted δ within its bound and a measured one within what the
    run resolves read 0 in the legend; a unit-vector component is not named on the axis."""
    from types import SimpleNamespace

    import mbseig.plots.poles as poles
    from mbseig.check import ModeCheck

    figs = []
    real_save = poles.save
    monkeypatch.setattr(poles, "save", lambda fig, path, **kw: figs.append(fig)
                        or real_save(fig, path, **kw))
    t = np.linspace(0.0, 1.0, 200)
    m = ModeCheck(index=3, kind="oscillatory", eigenvalue=complex(-2e-14, 316.2),
                  predicted_delta=2e-14, predicted_omega=316.2, measured_delta=8.7e-10,
                  measured_omega=316.2, rel_error_delta=8.7e-4, rel_error_omega=5.8e-11,
                  passed=True, fit_amplitude=1e-4, coordinate="rotor.u.y", t=t,
                  eta=1e-4 * np.exp(316.2j * t), response=1e-4 * np.cos(316.2 * t),
                  bound_delta=3.2e-10, bound_omega=3.2e-9, resolution_delta=2e-9,
                  resolution_omega=1e-8)
    (path,) = poles.plot_check(SimpleNamespace(name="rotor", modes=[m]), tmp_path)
    assert path.stat().st_size > 1000 and len(figs) == 1
    ax1, ax2 = figs[0].axes
    legend = [tx.get_text() for tx in ax1.get_legend().get_texts()]
    assert "fitted envelope, δ = 0 1/s" in legend and "predicted envelope, δ = 0 1/s" in legend
    assert not INTERNAL.search(ax2.get_ylabel()) and not TINY.search(ax1.get_title())
    # and a name the user wrote stays (a body's point)
    m2 = ModeCheck(**{**{f: getattr(m, f) for f in ("index", "kind", "eigenvalue",
                                                     "predicted_delta", "predicted_omega",
                                                     "measured_delta", "measured_omega",
                                                     "passed", "fit_amplitude", "t", "eta",
                                                     "response")}, "coordinate": "rotor.y"})
    poles.plot_check(SimpleNamespace(name="rotor", modes=[m2]), tmp_path)
    assert figs[1].axes[1].get_ylabel() == "rotor.y − equilibrium"
