"""A case's [motion] table decides which analysis runs (DESIGN §8): a table that asks for
neither a periodic nor a steady motion is refused in one line naming the file and the table,
exit 2, by every command (README, "Exit codes")."""

import pytest

from mbseig.cli import main

CASE = """schema_version = 1
dimension = 3
[motion]
foo = 1.0
[[bodies]]
name = "b"
mass = 1.0
com = [0.0, 0.0, 0.0]
inertia = [1.0, 1.0, 1.0]
"""


@pytest.mark.parametrize("argv", [["modes"], ["linearize"], ["check"],
                                  ["sweep", "--param", "x=0:1:3"]])
def test_motion_without_period_or_speed_is_refused(tmp_path, capsys, argv):
    path = tmp_path / "bad.toml"
    path.write_text(CASE)
    assert main([argv[0], str(path), *argv[1:]]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert err.startswith(f"mbseig: {path}: motion: ") and "period" in err and "speed" in err
