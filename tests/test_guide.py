"""docs/guide.md cannot rot: every code block of the guide is run here, in order, in a fresh
directory where ``cases/`` is the bundled cases folder.

- ```toml blocks preceded by ``<!-- file: NAME -->`` are written to NAME;
- ```sh blocks: every line is an ``mbseig`` command, run through :func:`mbseig.cli.main` (the
  executable's own entry point) and required to exit 0;
- ```python blocks are executed in one namespace, in order; their asserts state the closed
  forms the guide quotes (√(g/l), Ziegler's 7/2 − √2, ...);
- the ```sh-install block is the installation command: checked against the installed
  distribution (its name and the ``mbseig`` entry point), not re-run.
"""

import os
import re
import shlex
from importlib.metadata import distribution

import pytest
from conftest import ROOT

from mbseig.cli import main

GUIDE = ROOT / "docs" / "guide.md"
BLOCK = re.compile(r"(?:<!-- file: (?P<file>[^ ]+) -->\n)?```(?P<lang>[\w-]+)\n(?P<body>.*?)```",
                   re.DOTALL)


def blocks():
    return [(m["lang"], m["file"], m["body"]) for m in BLOCK.finditer(GUIDE.read_text())]


def test_guide_has_every_topic():
    text = GUIDE.read_text()
    for heading in ("## Installation", "## A planar mechanism", "## A spatial mechanism",
                    "## A rotor", "## A sweep with a stability boundary", "## A report",
                    "## Linear models for control design", "## Mode shapes you can watch",
                    "## Stability under uncertainty"):
        assert heading in text
    langs = {lang for lang, _, _ in blocks()}
    assert langs <= {"sh", "sh-install", "toml", "python"}  # every block is of a kind run below


def test_installation_block_names_this_distribution():
    install = [body for lang, _, body in blocks() if lang == "sh-install"]
    assert len(install) == 1 and "pip install ." in install[0]
    dist = distribution("mbseig")
    assert dist.metadata["Name"] == "mbseig"
    # the Python version the guide states is the one the distribution requires
    assert f"Python {dist.metadata['Requires-Python'].lstrip('>=')} or newer" in GUIDE.read_text()
    assert any(ep.name == "mbseig" for ep in dist.entry_points if ep.group == "console_scripts")


def test_every_block_of_the_guide_runs(tmp_path, monkeypatch, capsys):
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "guide"}
    ran = {"sh": 0, "python": 0, "toml": 0}
    for lang, fname, body in blocks():
        if lang == "toml":
            assert fname, "a TOML block of the guide must name its file"
            (tmp_path / fname).write_text(body)
        elif lang == "sh":
            for line in body.splitlines():
                line = line.strip()
                if not line or line.startswith("#"):
                    continue
                argv = shlex.split(line)
                assert argv[0] == "mbseig", f"not an mbseig command: {line}"
                code = main(argv[1:])
                err = capsys.readouterr().err
                assert code == 0, f"{line}: exit {code}: {err}"
        elif lang == "python":
            exec(compile(body, f"{GUIDE.name} python block {ran['python'] + 1}", "exec"),
                 namespace)
        else:
            continue
        ran[lang] += 1
    assert ran["sh"] >= 8 and ran["python"] >= 5 and ran["toml"] == 1
    # what the commands wrote
    for path in ("four_bar_mode1.gif", "swing.gif", "rotor_sweep/campbell.png",
                 "ziegler/sweep.json", "pendulum_report/report.html", "hand_C1.npz",
                 "pendulum_mc/samples.csv", "pendulum_mc/scatter.png"):
        assert (tmp_path / path).stat().st_size > 0, path
    assert os.path.samefile(tmp_path / "cases", ROOT / "cases")


@pytest.mark.parametrize("line", ["mbseig animate cases/four_bar.toml --mode 9 --out x.gif"])
def test_refusal_quoted_in_the_guide(line, capsys):
    """The guide quotes the one-line refusal of an unknown mode number."""
    assert main(shlex.split(line)[1:]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--mode: mode 9 does not exist" in err
    assert "--mode: mode 9 does not exist" in GUIDE.read_text()
