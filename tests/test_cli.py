"""The command line on every case, the fixed JSON schema (DESIGN §8) and exit codes."""

import json
import re

import numpy as np
import pytest
from conftest import CASES

from mbseig.cli import main

# the CLI contract: an accepted run prints no warning, a refusal one line (README, "Exit codes")
pytestmark = pytest.mark.filterwarnings("error")

CASE_FILES = sorted(CASES.glob("*.toml"))
FORMAT_CASES = {"four_bar", "hand_device", "spatial_double_pendulum", "cantilever_3d_oblique",
                "whipple_bicycle", "pendulum_shaken_pivot", "box_on_contacts_liftoff"}
INTERNAL = re.compile(r"\.[uvw]\.[xyz]\b|\.n\d+\b")  # an internal unit vector or node index
MODE_KEYS = {"index", "eigenvalue", "delta", "omega_n", "omega_d", "freq_hz", "zeta", "stability",
             "kind", "backward_error"}
TOP_KEYS = {"case", "parameters", "n_coordinates", "n_constraints", "n_redundant", "dof", "solver",
            "equilibrium", "verdict", "modes"}


@pytest.mark.parametrize("path", CASE_FILES, ids=lambda p: p.stem)
def test_modes_json_schema(path, capsys):
    assert main(["modes", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert TOP_KEYS <= set(out)
    assert set(out["equilibrium"]) >= {"residual", "iterations"}
    assert out["verdict"] in ("stable", "critical", "unstable")
    # DESIGN §6: the worst over the modes that are not rigid-body by construction, critical when
    # no other mode is left
    counted = [m["stability"] for m in out["modes"] if not m.get("rigid_body")]
    worst = max(counted, key=["stable", "critical", "unstable"].index, default="critical")
    assert out["verdict"] == worst
    keys = [(m["omega_n"], m["delta"]) for m in out["modes"]]
    assert keys == sorted(keys)
    for i, m in enumerate(out["modes"], 1):
        assert MODE_KEYS <= set(m)
        assert m["index"] == i
        re, im = m["eigenvalue"]
        assert im >= 0
        assert m["delta"] == pytest.approx(-re, abs=0.0)
        assert m["omega_n"] == pytest.approx(np.hypot(re, im), rel=1e-12)
        assert m["stability"] in ("stable", "critical", "unstable")
        assert m["kind"] in ("oscillatory", "overdamped", "rigid-body", "divergence", "flutter")
        # DESIGN §6: dominant coordinates named as the user wrote them, never by an internal
        # unit vector (B.u.x) or node index (BEAM.n3)
        for name, _ in m.get("dominant") or []:
            assert not INTERNAL.search(name), name
        assert not INTERNAL.search(m.get("rigid_body") or ""), m["rigid_body"]


@pytest.mark.parametrize("path", CASE_FILES, ids=lambda p: p.stem)
def test_modes_table_and_linearize(path, capsys, tmp_path):
    assert main(["modes", str(path)]) == 0
    text = capsys.readouterr().out
    assert "verdict:" in text
    assert not INTERNAL.search(text), INTERNAL.search(text)
    # the three file formats on one case of each kind of model (the writers see only the
    # matrices: dense or sparse, planar or spatial, at rest, steady or periodic)
    suffixes = (".npz", ".mat", ".json") if path.stem in FORMAT_CASES else ()
    for suffix in suffixes:
        out = tmp_path / f"lin{suffix}"
        assert main(["linearize", str(path), "--out", str(out)]) == 0
        assert out.stat().st_size > 0
    capsys.readouterr()
    assert main(["linearize", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    M, Q = np.array(data["M"]), np.array(data["Q"])
    assert M.shape == Q.shape == (data["dof"], data["dof"])
    for key in ("M", "P", "Q", "A"):  # never inf or NaN (null in JSON) with exit 0
        if key in data:
            assert np.all(np.isfinite(np.array(data[key], dtype=float))), key


def test_linearize_npz_round_trip(tmp_path):
    """Matrices written by --out give the same modes as the direct pipeline (same arrays)."""
    import mbseig
    from mbseig.studies import analyze

    path = CASES / "four_bar.toml"
    out = tmp_path / "fb.npz"
    assert main(["linearize", str(path), "--out", str(out)]) == 0
    z = np.load(out)
    a = analyze(path)
    np.testing.assert_array_equal(z["M"], a.linear.M)
    np.testing.assert_array_equal(z["Q"], a.linear.Q)
    md = mbseig.modes(z["M"], z["P"], z["Q"])
    np.testing.assert_allclose(md.eigenvalues, a.modes.eigenvalues, rtol=1e-14)


def test_param_override(capsys):
    assert main(["modes", str(CASES / "chain_fixed_fixed.toml"), "--param", "n=3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["dof"] == 3 and out["parameters"]["n"] == 3
    # closed form, n = 3: omega_1 = 2 sqrt(1000) sin(pi/8)
    assert out["modes"][0]["omega_n"] == pytest.approx(2 * np.sqrt(1000) * np.sin(np.pi / 8),
                                                       rel=1e-12)


def test_executable_prompt_exit_delivers_the_whole_output(tmp_path):
    """``python -m mbseig`` ends modes and linearize without the interpreter's teardown
    (mbseig.cli.console): the output must be complete. Reference: main() in this process
    prints the same text; the --out file is written and readable; a refusal keeps exit code 2
    and its one line on stderr."""
    import contextlib
    import io
    import subprocess
    import sys

    case = str(CASES / "chain_damped.toml")
    r = subprocess.run([sys.executable, "-m", "mbseig", "modes", case, "--json"],
                       capture_output=True, text=True)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["modes", case, "--json"]) == 0
    assert r.returncode == 0 and r.stderr == ""
    assert json.loads(r.stdout) == json.loads(buf.getvalue())
    out = tmp_path / "lin.npz"
    r = subprocess.run([sys.executable, "-m", "mbseig", "linearize", case, "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0
    with np.load(out) as d:
        assert d["M"].shape[0] == d["M"].shape[1] > 0
    r = subprocess.run([sys.executable, "-m", "mbseig", "modes", str(tmp_path / "missing.toml")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and r.stdout == "" and len(r.stderr.strip().splitlines()) == 1


def test_help_of_every_command_prints_and_exits_zero(capsys):
    """``mbseig --help`` and ``mbseig COMMAND --help`` print their usage and exit 0: argparse
    expands ``%`` in help texts, so an unescaped percent sign in one command's help is a
    traceback in the top-level help (95 % once was). Reference: argparse's documented exit
    status 0 for --help."""
    from mbseig.cli import SUBCOMMANDS

    for argv in (["--help"], *([name, "--help"] for name in SUBCOMMANDS)):
        with pytest.raises(SystemExit) as stop:
            main(argv)
        assert stop.value.code == 0, argv
        out = capsys.readouterr().out
        assert out.startswith("usage: mbseig"), argv
