"""Cases in Python: ``mbseig.CaseBuilder`` and ``mbseig.to_toml`` (docs/urdf.md, "Models in
Python").

References: tomllib is the reader of record, so a written case must read back to an equal dict
(every bundled case and format example; exact); a case built in Python must equal the bundled
file it copies (exact) and give identical eigenvalues from its dict and from its written TOML
(tolerance 0: the same model); the spatial double pendulum's frequencies against its closed form
(linearized compound double pendulum, the case's ``source``; relative 1e-10).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from conftest import CASES

import mbseig
from mbseig import CaseBuilder, to_toml
from mbseig.casefile.writer import point_ref
from mbseig.studies import analyze

# the format examples of DESIGN §8 (../shared/examples beside the checkout)
EXAMPLES = Path(__file__).resolve().parents[2] / "shared" / "examples"
TOMLS = sorted(CASES.glob("*.toml")) + sorted(EXAMPLES.glob("*.toml"))


@pytest.mark.parametrize("path", TOMLS, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_round_trip(path):
    """tomllib → to_toml → tomllib gives the same dict, floats bit for bit."""
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    text = to_toml(data)
    assert tomllib.loads(text) == data
    assert to_toml(tomllib.loads(text)) == text  # and the writer is stable


def test_round_trip_edge_values():
    """Strings needing escapes, keys needing quotes, floats at the ends of the double range,
    empty tables and arrays, nested arrays of tables, inline tables in arrays of tables."""
    case = {
        "title": 'a "quoted" \\ back\tslash\nnew line \x01 \x7f é ∞',
        "odd key": 1, "": "empty key",
        "floats": [0.1, 1e-300, 5e-324, 1.7976931348623157e308, -0.0, 1.0 / 3.0, 1e16,
                   math.inf, -math.inf],
        "ints": [0, -7, 2**62], "flags": [True, False],
        "mixed": [[1, 2], ["a"], [], [{}], [{"x": {"y": [1.5]}}]],
        "empty": {}, "none": [],
        "parameters": {"k": "2*pi*f", "nested": {"deep": {"x": 1}}},
        "forces": [{"type": "spring", "points": [point_ref("b", [0, 0.5, 1e-3]), "A"],
                    "table": {"parameter": "Omega", "at": [0.0, 1.0], "values": [[1, 2], [3, 4]]}},
                   {}],
        "report": {"sections": [{"name": "x", "sub": {"a": 1}}]},
    }
    back = tomllib.loads(to_toml(case))
    assert back == case
    assert all(repr(x) == repr(y)  # bit-exact
               for x, y in zip(back["floats"], case["floats"], strict=True))


def test_inline_point_reference_written_inline():
    text = to_toml({"forces": [{"type": "spring", "points": [point_ref("b", [1.0, 2.0, 3.0]),
                                                               "A"]}]})
    assert 'points = [{ body = "b", at = [1.0, 2.0, 3.0] }, "A"]' in text


def test_to_toml_rejects_what_toml_cannot_hold():
    with pytest.raises(TypeError, match="NoneType"):
        to_toml({"x": None})
    with pytest.raises(TypeError, match="keys must be strings"):
        to_toml({1: 2})


# ---------------------------------------------------------------------------------------------
# Notebook-sized models: the four-bar (2-D) and the spatial double pendulum (3-D) in Python
# ---------------------------------------------------------------------------------------------
def four_bar() -> CaseBuilder:
    """cases/four_bar.toml written with CaseBuilder (its numbers and expressions as in the file)."""
    c = CaseBuilder(
        dimension=2, title="Four-bar linkage, elbow-up, crank spring, gravity",
        description="Ground pivots A = (0, 0) and D = (1, 0) m. Uniform slender bars: "
                    "crank AB 0.3 m 1 kg, coupler BC 1.0 m 2 kg, rocker DC 0.8 m 1.5 kg "
                    "(I_G = m L^2 / 12), elbow-up. Torsional spring 50 N m/rad between ground "
                    "and crank, zero torque at crank angle 60 deg. Gravity g along -y.",
        source="independent check: tests/test_four_bar.py derives the 1-DOF reduction in the "
               "crank angle (potential energy and generalized mass from loop closure) and "
               "compares.",
        gravity=[0.0, "-g"])
    c.parameters(g=9.81, k_crank=50.0, theta0="deg(60)")
    c.point("A", [0.0, 0.0], fixed=True).point("D", [1.0, 0.0], fixed=True)
    c.point("B", [0.15, 0.2598]).point("C", [0.9916, 0.8000])
    c.body("crank", points=["A", "B"], length=0.3, mass=1.0, inertia="1.0*0.3**2/12")
    c.body("coupler", points=["B", "C"], length=1.0, mass=2.0, inertia="2.0*1.0**2/12")
    c.body("rocker", points=["D", "C"], length=0.8, mass=1.5, inertia="1.5*0.8**2/12")
    c.force("torsional", "crank spring", bodies=["ground", "crank"], stiffness="k_crank",
            angle0="theta0")
    c.expected(source="tests/test_four_bar.py (independent 1-DOF reduction)", verdict="critical")
    return c


def spatial_double_pendulum() -> CaseBuilder:
    """Two axisymmetric links sharing basic points (spherical joints), as in
    cases/spatial_double_pendulum.toml but with numbers instead of its expressions."""
    m1, m2, l1, c1, c2, J1, J2, Ja = 1.5, 0.9, 0.6, 0.25, 0.35, 0.04, 0.02, 0.003
    c = CaseBuilder(dimension=3, title="Spatial double pendulum", gravity=[0.0, 0.0, -9.81])
    c.point("O", [0.0, 0.0, 0.0], fixed=True).point("A", [0.0, 0.0, -l1])
    c.body("upper", mass=m1, com=[0.0, 0.0, -c1], inertia=[J1, J1, Ja], points=["O", "A"])
    c.body("lower", mass=m2, com=[0.0, 0.0, -l1 - c2], inertia=[J2, J2, Ja], points=["A"])
    return c


def double_pendulum_omega():
    """ω of the linearized compound double pendulum (cases/spatial_double_pendulum.toml,
    source: Meirovitch, Fundamentals of Vibrations §6), each twice (two vertical planes)."""
    g, m1, m2, l1, c1, c2, J1, J2 = 9.81, 1.5, 0.9, 0.6, 0.25, 0.35, 0.04, 0.02
    a, b, d = J1 + m1 * c1**2 + m2 * l1**2, m2 * l1 * c2, J2 + m2 * c2**2
    k1, k2 = g * (m1 * c1 + m2 * l1), g * m2 * c2
    S, D = a * k2 + d * k1, a * d - b**2
    r = math.sqrt(S**2 - 4 * D * k1 * k2)
    return np.array([math.sqrt((S - r) / (2 * D))] * 2 + [math.sqrt((S + r) / (2 * D))] * 2)


def test_notebook_four_bar_and_spatial_double_pendulum(tmp_path):
    """Build both in Python, run modes from the dict, write them with to_toml and run the files:
    identical eigenvalues (tolerance 0); the four-bar equals the bundled file's dict."""
    built = four_bar().to_dict()
    assert built == tomllib.loads((CASES / "four_bar.toml").read_text(encoding="utf-8"))
    for name, builder in (("four_bar", four_bar()), ("double", spatial_double_pendulum())):
        case = builder.to_dict()
        from_dict = analyze(mbseig.read_case(case))
        path = builder.write(tmp_path / f"{name}.toml")
        assert tomllib.loads(path.read_text(encoding="utf-8")) == case
        from_file = analyze(path)
        assert np.array_equal(from_dict.modes.eigenvalues, from_file.modes.eigenvalues)
        assert from_dict.modes.verdict == from_file.modes.verdict
        if name == "double":
            w = np.sort(from_dict.modes.omega_n)
            assert np.allclose(w[:2], 0.0, atol=1e-6)  # free spins about the vertical
            np.testing.assert_allclose(w[2:], double_pendulum_omega(), rtol=1e-10)


def test_dict_case_errors_are_the_file_messages(tmp_path):
    """A dict is validated like a file: the same CaseError, an exception instead of exit 2."""
    case = spatial_double_pendulum().to_dict()
    case["bodies"][1]["mass"] = -1.0
    path = tmp_path / "bad.toml"
    path.write_text(to_toml(case))
    with pytest.raises(mbseig.CaseError) as from_dict:
        mbseig.load_case(case)
    with pytest.raises(mbseig.CaseError) as from_file:
        mbseig.load_case(path)
    assert str(from_dict.value).replace("<dict>", "") == str(from_file.value).replace(str(path), "")


def test_case_builder_3d_and_checks():
    import numpy as np

    c = CaseBuilder(dimension=3, gravity=np.array([0.0, 0.0, -9.81]))
    c.body("b", mass=1.0, com=np.array([0.0, 0.0, 1.0]), inertia=np.eye(3) * 0.1)
    c.joint("spherical", "s", bodies=["ground", "b"], at=[0.0, 0.0, 0.0])
    c.force("spring", "k", points=[point_ref("ground", [1, 0, 1]), point_ref("b", [0, 0, 1])],
            stiffness=10.0)
    d = c.to_dict()
    assert d["bodies"][0]["inertia"] == [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
    assert tomllib.loads(c.to_toml()) == d
    with pytest.raises(ValueError, match="used already"):
        c.joint("weld", "s", bodies=["ground", "b"], at=[0, 0, 0])
    with pytest.raises(ValueError, match="3 components"):
        c.point("P", [0.0, 0.0])


def test_guide_examples_run(tmp_path, monkeypatch, capsys):
    """Every ```python block of docs/urdf.md runs (in a fresh folder that sees tests/data), and
    its complete ```toml case runs next to the arm's URDF; the guide cannot rot."""
    import re
    import shutil

    text = (Path(__file__).resolve().parent.parent / "docs" / "urdf.md").read_text()
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tests" / "data").mkdir(parents=True)
    (tmp_path / "tests" / "data" / "urdf").symlink_to(
        Path(__file__).resolve().parent / "data" / "urdf")
    shutil.copy(Path(__file__).resolve().parent / "data" / "urdf" / "arm" / "two_link_arm.urdf",
                tmp_path)
    blocks = re.findall(r"```python\n(.*?)```", text, re.DOTALL)
    assert len(blocks) == 2
    for block in blocks:
        exec(compile(block, "docs/urdf.md", "exec"), {})  # noqa: S102 (the guide's own code)
    cases = [tomllib.loads(b) for b in re.findall(r"```toml\n(.*?)```", text, re.DOTALL)]
    full = [c for c in cases if "schema_version" in c]
    assert len(full) == 1
    path = tmp_path / "arm.toml"
    path.write_text(to_toml(full[0]))
    assert analyze(path).modes.verdict == "stable"
