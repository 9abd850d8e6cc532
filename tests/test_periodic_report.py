"""``mbseig report`` on a periodic case: report.md and a self-contained report.html with the
multipliers and their bounds, the verdict and what decided it, the frozen-time eigenvalues beside
them (marked as not a criterion), the multiplier figure, the time-domain check and the
``[[report.studies]]`` sweeps (a study with lines draws the stability chart).

References: the verdict and multipliers come from the same analysis as ``mbseig modes --json``
(the report must print what the analysis found); the located edge of the principal tongue is
2√(g/(l a_1(q))), q = 2A/l (scipy.special.mathieu_a, DLMF 28.2), to 1e-8 relative (the study's
location tolerance).
"""

import json
import math
import re

from conftest import CASES
from scipy.special import mathieu_a

from mbseig.cli import main

CASE = CASES / "pendulum_shaken_pivot.toml"
STUDIES = """

[[report.studies]]
title = "lower edge of the principal tongue"
sweep = "w"
range = [5.70, 5.76]
count = 2

[[report.studies]]
title = "inside the tongue at two amplitudes"
sweep = "w"
range = [6.2, 6.6]
count = 2
lines = { A = [0.1, 0.15] }

[[report.studies]]
title = "constraint stiffness"
compare = "constraint_stiffness"
"""


def test_periodic_report(tmp_path, capsys):
    case = tmp_path / "pendulum_report.toml"
    case.write_text(CASE.read_text() + STUDIES)
    assert main(["modes", str(case), "--json"]) == 0
    fl = json.loads(capsys.readouterr().out)["floquet"]
    out = tmp_path / "rep"
    assert main(["report", str(case), "--out", str(out)]) == 0
    md = (out / "report.md").read_text()
    page = (out / "report.html").read_text()
    # the verdict, the deciding multiplier with its bound and margin, as the analysis found
    d = fl["decided_by"]
    assert f"**Verdict: {fl['verdict']}**" in md and fl["verdict"] == "unstable"
    assert f"|μ| = {d['modulus']:.10f} ± {d['bound']:.1e}" in md
    # every multiplier with its bound in the table; a part within its bound of 0 reads 0 (the
    # zero rule: here Im μ of the two real multipliers of the flip tongue)
    for m, b in zip(fl["multipliers"], fl["error_bounds"], strict=True):
        parts = ["0" if abs(x) <= b else f"{x:+.10f}" for x in m]
        assert f"| {parts[0]} | {parts[1]} | {abs(complex(*m)):.10f} | {b:.1e} |" in md
    assert "+0.0000000000" not in md
    # the frozen-time eigenvalues beside them, marked as not a criterion (here: wrong)
    assert "Frozen-time eigenvalues (not a criterion)" in md
    assert "which would say critical" in md and "Not a stability criterion" in md
    # the time-domain check ran and passed
    assert "**passed**" in md
    # the studies: located edge against Mathieu, lines without a change, compare not run
    edge = 2 * math.sqrt(9.81 / mathieu_a(1, 0.2))
    row = re.search(r"\| – \| ([0-9.]+) \| flip \| loss \|", md)
    assert row and abs(float(row.group(1)) / edge - 1) < 1e-8
    assert md.count("unstable over the range") == 2
    assert "has no counterpart (not run)" in md
    # figures: linked in the Markdown, embedded in the HTML (self-contained: no file links)
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", md)
    assert len(figures) == 4 and all((out / f).is_file() for f in figures)
    assert any("chart" in f for f in figures) and any("multipliers" in f for f in figures)
    assert page.count("data:image/png;base64,") == 4 and ".png\"" not in page


def test_periodic_report_no_check_no_studies(tmp_path, capsys):
    """--no-check and --no-studies leave those sections out; two configurations are refused in
    one line."""
    out = tmp_path / "rep"
    assert main(["report", str(CASE), "--out", str(out), "--no-check", "--no-studies"]) == 0
    md = (out / "report.md").read_text()
    # the same page as every motion: the section stays, saying the check was not run
    assert "Time-domain check not run (report built with --no-check)." in md
    assert "**passed**" not in md and "## Study" not in md
    assert "Floquet multipliers" in md
    capsys.readouterr()
    assert main(["report", str(CASE), "--all-configs", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "one configuration" in err
