"""Bad input: one line naming the file, the element and the problem; exit code 2; no traceback."""

import subprocess
import sys

import pytest
from conftest import CASES, write_case

from mbseig.cli import main

# the CLI contract: an accepted run prints no warning, a refusal one line (README, "Exit codes")
pytestmark = pytest.mark.filterwarnings("error")

PENDULUM = (CASES / "pendulum.toml").read_text()


def run_cli(capsys, path, *extra):
    code = main(["modes", str(path), *extra])
    err = capsys.readouterr().err
    return code, err


BAD = {
    "malformed TOML": (PENDULUM.replace("[parameters]", "[parameters"), "malformed TOML"),
    "unknown element type": (PENDULUM.replace('type = "distance"', 'type = "hinge"'),
                             "joints[0] 'rod': unknown joint type 'hinge'"),
    "unknown force type": (PENDULUM + '\n[[forces]]\ntype = "magnet"\n',
                           "forces[0]: unknown force type"),
    "missing point": (PENDULUM.replace('points = ["O", "P"]', 'points = ["O", "Q"]'),
                      "joints[0] 'rod': unknown point 'Q'"),
    "missing body": (PENDULUM + '\n[[joints]]\ntype = "attach"\npoint = "P"\nbody = "arm"\n',
                     "joints[1]: unknown body 'arm'"),
    "zero mass": (PENDULUM.replace('mass = "m"', "mass = 0"), "masses[0]: mass must be positive"),
    "negative mass": (PENDULUM.replace('mass = "m"', "mass = -1.0"),
                      "masses[0]: mass must be positive"),
    "unsafe expression": (PENDULUM.replace('mass = "m"',
                                           "mass = \"__import__('os').system('echo hi')\""),
                          "masses[0].mass: function not allowed"),
    "attribute access": (PENDULUM.replace('mass = "m"', 'mass = "m.__class__"'),
                         "masses[0].mass: not allowed"),
    "non-numeric": (PENDULUM.replace('mass = "m"', 'mass = "heavy"'),
                    "masses[0].mass: unknown name 'heavy'"),
    "typo in field": (PENDULUM.replace('mass = "m"', 'mass = "m"\nmas = 2'),
                      "masses[0]: unknown field 'mas'"),
    "wrong schema": (PENDULUM.replace("schema_version = 1", "schema_version = 7"),
                     "case: schema_version must be 1"),
    "inconsistent constraints": (
        PENDULUM + '\n[[points]]\nname = "F"\nposition = [5.0, 0.0]\nfixed = true\n'
                   '\n[[joints]]\ntype = "distance"\nname = "too short"\npoints = ["F", "P"]\n'
                   'length = 1.0\n',
        ("no equilibrium", "the constraints cannot be satisfied")),
    "free fall": (PENDULUM[:PENDULUM.index("[[joints]]")] + PENDULUM[PENDULUM.index("[expected]"):],
                  ("equilibrium: no equilibrium after", "equilibrium: no static equilibrium")),
}


@pytest.mark.parametrize("name", list(BAD))
def test_bad_case_one_line_exit_2(name, tmp_path, capsys):
    text, needle = BAD[name]
    path = write_case(tmp_path, text)
    code, err = run_cli(capsys, path)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"mbseig: {path}: ")
    # a tuple: the wordings of the statics' messages (issue 10 rewords them)
    assert any(n in lines[0] for n in (needle if isinstance(needle, tuple) else (needle,)))
    assert "Traceback" not in err


def test_unknown_param(capsys):
    code, err = run_cli(capsys, CASES / "pendulum.toml", "--param", "mass=3")
    assert code == 2 and "unknown parameter 'mass'" in err and str(CASES / "pendulum.toml") in err


def test_missing_file(capsys, tmp_path):
    code, err = run_cli(capsys, tmp_path / "nope.toml")
    assert code == 2 and "cannot read case file" in err


def test_bad_output_extension(capsys, tmp_path):
    code = main(["linearize", str(CASES / "pendulum.toml"), "--out", str(tmp_path / "x.txt")])
    assert code == 2 and "--out" in capsys.readouterr().err


def test_real_process_exit_code(tmp_path):
    """The installed entry point (python -m mbseig) exits 2 with one line and no traceback."""
    path = write_case(tmp_path, PENDULUM.replace('mass = "m"', "mass = 0"))
    r = subprocess.run([sys.executable, "-m", "mbseig", "modes", str(path)], capture_output=True,
                       text=True)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert r.stdout == ""
