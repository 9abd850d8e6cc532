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
    kept = sorted(p.name for p in ckpt.glob("lines-*.npz"))
    assert kept == ["lines-000000.npz"]  # the line completed before the fault
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
    assert sorted(ckpt.glob("points-*.npz")) == [ckpt / f"points-{i:06d}.npz" for i in range(n)]


class _Runs:
    """A pickle that would run ``os.system`` (or another callable) when read."""

    def __init__(self, fn, *args):
        self.fn, self.args = fn, args

    def __reduce__(self):
        return self.fn, self.args


def _swept(tmp_path, out):
    case = tmp_path / "map.toml"
    case.write_text(MAP)
    ckpt = tmp_path / "ckpt"
    args = ["sweep", str(case), "--param", "c=1:-1:3", "--jobs", "1", "--no-progress",
            "--resume", str(ckpt)]
    assert main([*args, "--out", str(tmp_path / out)]) == 0
    return ckpt, args


def test_resume_folder_holds_no_pickle(tmp_path):
    """A resume folder holds its manifest and one .npz a task: each a JSON document and arrays,
    read with numpy's allow_pickle=False (a pickled entry would raise there)."""
    ckpt, _ = _swept(tmp_path, "a")
    files = sorted(p.name for p in ckpt.iterdir() if p.name != "manifest.json")
    assert (ckpt / "manifest.json").exists() and files, files
    assert all(name.endswith(".npz") for name in files), files
    for name in files:
        with np.load(ckpt / name, allow_pickle=False) as npz:
            for key in npz.files:
                assert npz[key].dtype != object


@pytest.mark.parametrize("fn", [os.system, eval, np.save], ids=["os.system", "eval", "np.save"])
def test_an_old_pickle_folder_is_refused_unopened(tmp_path, capsys, fn):
    """A folder of an earlier mbseig that pickled its results is refused in one line, and none
    of its files is opened: a pickle that would run a callable (its witness file) does not."""
    ckpt, args = _swept(tmp_path, "a")
    witness = tmp_path / "ran"
    payload = {os.system: (f"touch {witness}",), eval: (f"open({str(witness)!r}, 'w')",),
               np.save: (str(witness), np.zeros(1))}[fn]
    (ckpt / "points-000000.pkl").write_bytes(pickle.dumps(_Runs(fn, *payload)))
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--resume" in err[0] and "pickled" in err[0], err
    assert not witness.exists() and not list(tmp_path.glob("ran*"))


@pytest.mark.parametrize("name", ["os:system", "builtins:eval", "mbseig.studies.workers:Pool",
                                  "numpy:save"])
def test_a_record_naming_another_class_is_refused(tmp_path, capsys, name):
    """A result file whose JSON names a class outside mbseig's data modules is refused in one
    line naming the file; the genuine results of the folder still read."""
    import json
    import zipfile

    ckpt, args = _swept(tmp_path, "a")
    first = sorted(ckpt.glob("*.npz"))[0]
    with np.load(first, allow_pickle=False) as npz:
        arrays = {k: npz[k] for k in npz.files}
    arrays["__record__"] = np.frombuffer(json.dumps({"r": name, "f": []}).encode(), np.uint8)
    np.savez(first, **arrays)
    assert zipfile.is_zipfile(first)
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and first.name in err[0] and "--resume" in err[0], err
    assert "mbseig never writes" in err[0] or "not a class of mbseig" in err[0]


def test_records_come_back_bit_for_bit():
    """encode/decode (mbseig.records) keep every value and type: floats of every kind (−0, NaN,
    ±inf, subnormals), complex, tuple against list, dict keys of any type in order, numpy
    arrays and scalars with their dtypes, sparse matrices, a Verdict with its scope, a record."""
    import scipy.sparse as sp

    from mbseig.modal.result import Verdict
    from mbseig.records import decode, encode
    from mbseig.studies.records import SweepPoint

    vals = [0.0, -0.0, float("nan"), float("inf"), -float("inf"), 5e-324, 0.1 + 0.2]
    obj = {"floats": vals, 3: (1 + 2j, complex(-0.0, float("nan"))), (1, "a"): [None, True],
           "arr": np.arange(6, dtype=np.int32).reshape(2, 3), "c": np.array([1j, -0.0]),
           "scalar": np.float32(1.5), "flag": np.bool_(True), "word": np.str_("x"),
           "sparse": sp.csr_matrix(np.array([[0.0, 2.0], [3.0, 0.0]])),
           "verdict": Verdict("stable", "of the 4 modes computed", "rigid-body left out"),
           "set": frozenset({1, 2}), "bytes": b"\x00\xff"}
    fields = {f.name: None for f in __import__("dataclasses").fields(SweepPoint)}
    obj["record"] = SweepPoint(**fields)
    data, arrays = encode(obj)
    back = decode(json.loads(json.dumps(data)), arrays)
    assert list(back) == list(obj)
    for a, b in zip(vals, back["floats"], strict=True):
        assert type(b) is float and np.array(a).tobytes() == np.array(b).tobytes()
    assert type(back[3]) is tuple and back[3][0] == 1 + 2j
    assert np.signbit(back[3][1].real) and np.isnan(back[3][1].imag)
    assert back[(1, "a")] == [None, True]
    for k in ("arr", "c"):
        assert back[k].dtype == obj[k].dtype and back[k].tobytes() == obj[k].tobytes()
    assert type(back["scalar"]) is np.float32 and back["scalar"] == 1.5
    assert type(back["flag"]) is np.bool_ and type(back["word"]) is np.str_
    assert back["sparse"].format == "csr" and (back["sparse"] != obj["sparse"]).nnz == 0
    v = back["verdict"]
    assert type(v) is Verdict and v == "stable" and v.full_scope == obj["verdict"].full_scope
    assert back["set"] == frozenset({1, 2}) and back["bytes"] == b"\x00\xff"
    assert type(back["record"]) is SweepPoint and vars(back["record"]) == vars(obj["record"])
