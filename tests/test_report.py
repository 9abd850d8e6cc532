"""``mbseig report``: content, determinism, embedded images, and the committed device report.

The browser test needs Chromium and is skipped without it; the embedded-image checks do not.
"""

import sys

import pytest
from conftest import CASES, ROOT

from mbseig.cli import main
from mbseig.report import write_report

sys.path.insert(0, str(ROOT / "scripts"))
import check_report_html  # noqa: E402

COMMITTED = ROOT / "reports" / "hand_device" / "report.html"


def test_report_sections_and_time_domain_check(tmp_path):
    md, page = write_report(CASES / "hand_device.toml", out_dir=tmp_path, configs=["C1"],
                            studies=False)
    text = md.read_text()
    for heading in ("### Model", "### Equilibrium", "### Modes — verdict: stable",
                    "### Time-domain check"):
        assert heading in text
    assert "| MCP | 45 |" in text  # posture: the commanded angle (inverse statics)
    assert "all passed" in text  # every C1 mode confirmed by the nonlinear simulation
    problems, n = check_report_html.check_embedded(page.read_text())
    assert problems == [] and n == 2  # mode shapes and pole map


def test_report_is_deterministic(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["report", str(CASES / "four_bar.toml"), "--out", str(a), "--no-check"]) == 0
    assert main(["report", str(CASES / "four_bar.toml"), "--out", str(b), "--no-check"]) == 0
    assert (a / "report.html").read_bytes() == (b / "report.html").read_bytes()
    assert (a / "report.md").read_bytes() == (b / "report.md").read_bytes()


def test_committed_device_report_images_decode():
    html = COMMITTED.read_text()
    problems, n = check_report_html.check_embedded(html)
    assert problems == [] and n >= 13
    for needle in ("Comparison of the configurations", "critical c_a", "damping_scale = 0.01",
                   "leaves the range of motion", "constraint-force stiffness"):
        assert needle in html


@pytest.mark.skipif(check_report_html.find_chromium() is None, reason="chromium not installed")
def test_committed_report_in_headless_chromium(tmp_path):
    total, broken = check_report_html.check_in_browser(COMMITTED, tmp_path / "shot.png",
                                                       check_report_html.find_chromium(),
                                                       height=1200)
    assert total >= 13 and broken == 0
    assert (tmp_path / "shot.png").stat().st_size > 10_000


def test_report_on_a_linear_case(tmp_path):
    """A linear case has no mechanism: the report keeps the model, modes, pole map and check,
    and leaves out posture, reactions and the drawing (it used to fail on the missing fields)."""
    from conftest import CASES

    from mbseig.report import write_report

    md_path, html_path = write_report(CASES / "rotating_mass.toml", out_dir=tmp_path)
    text = md_path.read_text()
    assert "### Modes — verdict: critical" in text  # closed form: gyroscopically stable, δ = 0
    assert "### Equilibrium" not in text and "_shapes.png" not in text
    assert "_poles.png" in text and html_path.exists()
