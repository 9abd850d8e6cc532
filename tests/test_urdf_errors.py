"""A URDF that a case names but that cannot be read (missing, a directory): the one-line error
names the case file and its element (``urdf.file``) and the URDF path it names; exit 2 from
every command that reads the case, CaseError from the Python API, never a traceback."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import mbseig
from mbseig.cli import main
from mbseig.errors import CaseError

ARM = Path(__file__).resolve().parent / "data" / "urdf" / "arm"
CASE = ('schema_version = 1\ntitle = "robot"\ndimension = 3\n'
        '[urdf]\nfile = "{name}"\nstiffness = {{ default = 100.0 }}\n')


@pytest.mark.parametrize("kind", ["missing", "directory"])
def test_unreadable_urdf_names_case_and_urdf(kind, tmp_path, capsys):
    name = "robot.urdf"
    if kind == "directory":
        (tmp_path / name).mkdir()
    case = tmp_path / "arm_case.toml"
    case.write_text(CASE.format(name=name))
    with pytest.raises(CaseError) as exc:
        mbseig.load_case(case)
    e = exc.value
    assert e.file == str(case) and e.element == "urdf.file"
    assert str(tmp_path / name) in e.message and "\n" not in str(e)
    for command in (["modes", str(case)], ["check", str(case)], ["linearize", str(case)]):
        capsys.readouterr()
        assert main(command) == 2
        out, err = capsys.readouterr()
        assert out == "" and err.count("\n") == 1 and "Traceback" not in err
        assert err.startswith(f"mbseig: {case}: urdf.file: ")
        assert f"urdf.file: {tmp_path / name}: cannot read URDF file: " in err


def test_readable_urdf_beside_the_case_still_loads(tmp_path):
    """The same case with the URDF present (the two-link arm of tests/data) reads: the error
    above is about the file, not the table."""
    shutil.copy(ARM / "two_link_arm.urdf", tmp_path / "robot.urdf")
    case = tmp_path / "arm_case.toml"
    case.write_text(CASE.format(name="robot.urdf"))
    model = mbseig.load_case(case)
    assert set(model.bodies) >= {"upper", "fore"}


def test_import_urdf_missing_file_names_it(tmp_path, capsys):
    """Without a case, ``import-urdf`` names the URDF itself."""
    missing = tmp_path / "none.urdf"
    assert main(["import-urdf", str(missing), "--out", str(tmp_path / "o.toml")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"mbseig: {missing}: cannot read URDF file") and err.count("\n") == 1


def test_urdf_given_as_a_case_file_says_how_to_import_it(tmp_path, capsys):
    """A URDF where a case file is read (``mbseig modes robot.urdf``) is not called malformed
    TOML: the line says it is XML and names the command that writes its case."""
    urdf = tmp_path / "robot.urdf"
    urdf.write_text('<?xml version="1.0"?>\n<robot name="r"><link name="a"/></robot>\n')
    assert main(["modes", str(urdf)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"mbseig: {urdf}: not a case file but XML") and "import-urdf" in err
    assert "malformed TOML" not in err
