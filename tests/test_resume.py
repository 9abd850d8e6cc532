"""Sweeps that survive faults (issue 28): ``mbseig sweep --resume DIR`` keeps every completed
line as it completes, a rerun computes only the missing ones and writes the same files byte for
byte as an uninterrupted sweep; a Dask worker killed during a sweep loses no point and writes
none twice.

References: the uninterrupted run of the same sweep (every output file compared byte for byte),
and the in-process run of the same points (the JSON compared exactly) for the Dask run.
"""

import json
import os
import pickle
import signal
from pathlib import Path

import numpy as np
import pytest

import mbseig.studies.sweep as sweep_module
from mbseig.cli import main
from mbseig.studies.sweep import run_sweep

# two coupled oscillators, a damper c on the first coordinate (stability lost at c = 0) and
# a second stiffness k2: a two-parameter map with a boundary on every line
MAP = """
schema_version = 1
kind = "linear"
description = "coupled 2-DOF with a swept damper c and a second stiffness k2"
[parameters]
c = 1.0
k2 = 9.0
[matrices]
M = [[1.0, 0.0], [0.0, 2.0]]
P = [["c", 0.0], [0.0, 0.3]]
Q = [[4.0, 1.0], [1.0, "k2"]]
[expected]
source = "state-matrix abscissa"
"""

SWEEP = ["--param", "c=1:-1:4", "--param", "k2=8:10:3", "--jobs", "1", "--no-progress",
         "--no-curves"]


def _files(d: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir()) if p.is_file()}


def test_interrupted_sweep_resumes_to_identical_outputs(tmp_path, monkeypatch):
    case = tmp_path / "map.toml"
    case.write_text(MAP)
    whole = tmp_path / "whole"
    assert main(["sweep", str(case), *SWEEP, "--out", str(whole)]) == 0

    real = sweep_module.sweep_line
    calls = []

    def failing(*a, **kw):  # the second line fails: a fault in the middle of the sweep
        calls.append(a[2])
        if len(calls) == 2:
            raise RuntimeError("simulated fault")
        return real(*a, **kw)

    ckpt, out = tmp_path / "ckpt", tmp_path / "resumed"
    monkeypatch.setattr(sweep_module, "sweep_line", failing)
    with pytest.raises(RuntimeError, match="simulated fault"):
        main(["sweep", str(case), *SWEEP, "--out", str(out), "--resume", str(ckpt)])
    kept = sorted(p.name for p in ckpt.glob("lines-*.pkl"))
    assert kept == ["lines-000000.pkl"]  # the line completed before the fault
    assert not list(ckpt.glob(".*.tmp"))  # no partial file left behind

    calls.clear()
    monkeypatch.setattr(sweep_module, "sweep_line",
                        lambda *a, **kw: calls.append(a[2]) or real(*a, **kw))
    assert main(["sweep", str(case), *SWEEP, "--out", str(out), "--resume", str(ckpt)]) == 0
    assert [c["k2"] for c in calls] == [9.0, 10.0]  # the missing two lines only
    assert _files(out) == _files(whole)

    calls.clear()  # everything held: nothing is computed again, the same result again
    axes = [("c", np.linspace(1.0, -1.0, 4)), ("k2", np.linspace(8.0, 10.0, 3))]
    again = run_sweep(case, axes, jobs=1, curves=False, resume=ckpt)
    assert calls == []
    fresh = run_sweep(case, axes, jobs=1, curves=False)
    assert json.dumps(again.to_json()) == json.dumps(fresh.to_json())


def test_resume_refuses_another_sweeps_directory(tmp_path, capsys):
    case = tmp_path / "map.toml"
    case.write_text(MAP)
    ckpt = tmp_path / "ckpt"
    args = ["--jobs", "1", "--no-progress", "--resume", str(ckpt)]
    assert main(["sweep", str(case), "--param", "c=1:-1:3", "--out", str(tmp_path / "a"),
                 *args]) == 0
    capsys.readouterr()
    rc = main(["sweep", str(case), "--param", "c=1:-1:4", "--out", str(tmp_path / "b"), *args])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--resume" in err[0] and "different study" in err[0]


def test_killed_dask_worker_loses_no_point(tmp_path):
    """A worker process of a LocalCluster is killed (SIGKILL) while the points run: the
    scheduler runs its points again on the other worker; every point arrives once, equal to the
    in-process run."""
    distributed = pytest.importorskip("distributed")
    case = tmp_path / "map.toml"
    case.write_text(MAP)
    axes = [("c", np.linspace(1.0, -1.0, 8)), ("k2", np.linspace(8.0, 10.0, 2))]
    serial = json.dumps(run_sweep(case, axes, jobs=1, continuation=False, curves=False).to_json())
    killed = {}
    ckpt = tmp_path / "ckpt"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        pids = client.run(os.getpid)

        def progress(label, done, total):
            if label == "points" and done >= 4 and not killed:
                addr, pid = min(pids.items())
                os.kill(pid, signal.SIGKILL)  # a worker this test started
                killed[addr] = pid

        res = run_sweep(case, axes, scheduler=client, continuation=False, curves=False,
                        progress=progress, resume=ckpt)
    assert killed and res.runner == "dask"
    assert json.dumps(res.to_json()) == serial
    n = 8 * 2
    assert sorted(ckpt.glob("points-*.pkl")) == [ckpt / f"points-{i:06d}.pkl" for i in range(n)]


class _Runs:
    """A pickle that would run ``os.system`` (or another callable) when read."""

    def __init__(self, fn, *args):
        self.fn, self.args = fn, args

    def __reduce__(self):
        return self.fn, self.args


@pytest.mark.parametrize("fn", [os.system, eval, np.save], ids=["os.system", "eval", "np.save"])
def test_resume_folder_cannot_run_code(tmp_path, capsys, fn):
    """A result file replaced by one that names a callable mbseig never writes is refused in one
    line naming the file and the callable, and the callable does not run (its witness file is
    not created); the folder's genuine results still read as before."""
    case = tmp_path / "map.toml"
    case.write_text(MAP)
    ckpt, witness = tmp_path / "ckpt", tmp_path / "ran"
    args = ["sweep", str(case), "--param", "c=1:-1:3", "--jobs", "1", "--no-progress",
            "--resume", str(ckpt)]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    [first, *_] = sorted(ckpt.glob("*.pkl"))
    payload = {os.system: (f"touch {witness}",), eval: (f"open({str(witness)!r}, 'w')",),
               np.save: (str(witness), np.zeros(1))}[fn]
    first.write_bytes(pickle.dumps(_Runs(fn, *payload)))
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and first.name in err[0] and "--resume" in err[0], err
    assert "mbseig never writes" in err[0] and not witness.exists()
    assert not list(tmp_path.glob("ran*"))
