"""Ctrl-C ends a sweep at once (issue 38): the first SIGINT stops the workers, keeps every
finished point, prints one line ``mbseig: interrupted after N of M points; rerun with --resume
DIR to finish`` and exits 130; a second SIGINT exits at once.  Never a worker traceback.

Each command runs as a user's would: ``mbseig`` in a process group of its own
(``start_new_session=True``), the SIGINT sent to the whole group (the parent and its workers,
as a terminal's Ctrl-C does).  To interrupt it in the middle without a timing guess, its tasks
are slowed by a wrapper (``slow_tasks``, written next to the case) that touches a marker file
when a task ends; the signal is sent once a marker exists.  No time is asserted: the timeouts
are generous bounds against a hang (the time to exit is measured in the report, not here).

Reference for "no point is lost": the uninterrupted in-process run of the same sweep; the
interrupted run resumed with the folder its line names writes every output byte for byte.
"""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mbseig.cli import main
from mbseig.studies.workers import pool_pays

from test_resume import MAP  # coupled oscillators: a two-parameter map, a boundary per line

# the tasks of each study kind, slowed by PAUSE seconds, each touching a marker file when done
SLOW = '''
import os, time
from pathlib import Path

import mbseig.studies.sweep as sweep
import mbseig.studies.periodic_sweep as periodic
import mbseig.studies.steady_sweep as steady

PAUSE = float(os.environ["SLOW_PAUSE"])
MARKS = Path(os.environ["SLOW_MARKS"])
REAL = {"line": sweep.sweep_line, "point": sweep.evaluate_point,
        "floquet": periodic._floquet_point, "steady": steady._steady_point,
        "chunk": steady._steady_chunk}


def _slowed(kind, args, kwargs):
    time.sleep(PAUSE)
    out = REAL[kind](*args, **kwargs)
    (MARKS / f"{os.getpid()}-{time.monotonic_ns()}").touch()
    return out


def line(*args, **kwargs):  # (module level: a pool's workers unpickle it by name)
    return _slowed("line", args, kwargs)


def point(*args, **kwargs):
    return _slowed("point", args, kwargs)


def floquet_point(*args, **kwargs):
    return _slowed("floquet", args, kwargs)


def steady_point(*args, **kwargs):
    return _slowed("steady", args, kwargs)


def steady_chunk(*args, **kwargs):
    return _slowed("chunk", args, kwargs)


sweep.sweep_line, sweep.evaluate_point = line, point
periodic._floquet_point, steady._steady_point = floquet_point, steady_point
steady._steady_chunk = steady_chunk
'''

LINE = re.compile(r"^mbseig: interrupted after (\d+) of (\d+) points; rerun with --resume (\S+) "
                  r"to finish( \(.*\))?$")


def _files(d: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir()) if p.is_file()}


def _interrupt(tmp_path, argv, *, signals=1, pause=0.4, after=3, gap=0.05):
    """Run ``mbseig ARGV`` with slowed tasks in a new session; once ``after`` tasks have ended,
    SIGINT its process group ``signals`` times ``gap`` s apart.  (returncode, stdout, stderr
    lines).  A task's marker is touched as it returns, before its result reaches the parent:
    with two workers, the third marker means one worker has ended two tasks, the first of
    them ``pause`` seconds before, so at least one result has arrived."""
    (tmp_path / "slow_tasks.py").write_text(SLOW)
    marks = tmp_path / f"marks-{len(list(tmp_path.glob('marks-*')))}"
    marks.mkdir()
    env = {**os.environ, "SLOW_PAUSE": str(pause), "SLOW_MARKS": str(marks),
           "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    code = "import slow_tasks; from mbseig.cli import console; console()"
    proc = subprocess.Popen([sys.executable, "-c", code, *argv], cwd=tmp_path, env=env,
                            start_new_session=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while len(list(marks.iterdir())) < after:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "no task ended within 120 s"
            time.sleep(0.02)
        for k in range(signals):
            if k:
                time.sleep(gap)
            try:
                os.killpg(proc.pid, signal.SIGINT)  # the group: the parent and its workers
            except ProcessLookupError:
                break  # (already gone after the first)
        out, err = proc.communicate(timeout=60)  # a hang fails here
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    return proc.returncode, out.decode(), err.decode().splitlines()


def _one_line(err):
    """The interrupt line, after checking it is the only one and nothing else was said."""
    assert not any("Traceback" in e or "KeyboardInterrupt" in e for e in err), err
    assert len(err) == 1, err
    found = LINE.match(err[0])
    assert found, err[0]
    return int(found[1]), int(found[2]), found[3]


SWEEP = ["--param", "c=1:-1:5", "--param", "k2=8:10:10", "--no-progress", "--no-curves"]


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """(case, outputs) of the uninterrupted in-process sweep: the reference."""
    d = tmp_path_factory.mktemp("whole")
    case = d / "map.toml"
    case.write_text(MAP)
    assert main(["sweep", str(case), *SWEEP, "--jobs", "1", "--out", str(d / "out")]) == 0
    return case, _files(d / "out")


@pytest.mark.parametrize("jobs,resume", [(["--jobs", "1"], True), (["--jobs", "2"], False),
                                          ([], True)],
                         ids=["serial-resume", "pool-default-folder", "default-jobs-resume"])
def test_one_sigint_keeps_every_finished_point(tmp_path, whole, jobs, resume):
    case, reference = whole
    out = tmp_path / "out"
    keep = ["--resume", str(tmp_path / "ckpt")] if resume else []
    rc, stdout, err = _interrupt(tmp_path, ["sweep", str(case), *SWEEP, *jobs, "--out", str(out),
                                            *keep])
    assert rc == 130 and stdout == ""
    done, total, folder = _one_line(err)
    assert total == 5 * 10 and 0 < done < total and done % 5 == 0  # whole lines of 5 points
    expected = tmp_path / "ckpt" if resume else tmp_path / "out-resume"
    assert Path(folder) == expected and not out.exists()

    assert main(["sweep", str(case), *SWEEP, "--jobs", "1", "--out", str(out),
                 "--resume", folder]) == 0
    assert _files(out) == reference


def test_second_sigint_exits_at_once_and_loses_nothing(tmp_path, whole):
    """Two SIGINTs 50 ms apart on a pool: exit 130, no hang, no traceback; the line (said by
    whichever handler ran) names a folder from which the sweep resumes to the same outputs."""
    case, reference = whole
    out = tmp_path / "out"
    rc, stdout, err = _interrupt(tmp_path, ["sweep", str(case), *SWEEP, "--jobs", "2",
                                            "--out", str(out)], signals=2)
    assert rc == 130 and stdout == ""
    done, total, folder = _one_line(err)
    assert 0 < done < total == 50
    assert main(["sweep", str(case), *SWEEP, "--jobs", "1", "--out", str(out),
                 "--resume", folder]) == 0
    assert _files(out) == reference


def test_periodic_and_steady_sweeps_stop_the_same_way(tmp_path, cases_dir):
    """The Floquet sweep of the shaken pendulum and the bicycle's speed sweep run their grid on
    the same runner: one SIGINT, exit 130, the line, and the resumed JSON equals the
    uninterrupted one.  (The bicycle's points are analysed together, CHUNK to a task: 400
    points are 7 tasks.)"""
    for case, param, n in ((cases_dir / "pendulum_shaken_pivot.toml", "m=0.2:1:6", 6),
                           (cases_dir / "whipple_bicycle.toml", "v=2:8:400", 400)):
        whole, out = tmp_path / f"whole-{case.stem}", tmp_path / f"out-{case.stem}"
        args = ["sweep", str(case), "--param", param, "--no-progress", "--json"]
        assert main([*args, "--jobs", "1", "--out", str(whole)]) == 0
        rc, stdout, err = _interrupt(tmp_path, [*args, "--out", str(out)], pause=0.3)
        assert rc == 130 and stdout == ""
        done, total, folder = _one_line(err)
        assert total == n and 0 < done < n
        assert Path(folder) == tmp_path / f"out-{case.stem}-resume"
        assert main([*args, "--jobs", "1", "--out", str(out), "--resume", folder]) == 0
        assert (out / "sweep.json").read_bytes() == (whole / "sweep.json").read_bytes()


def test_the_pool_rule():
    """:func:`pool_pays`, the rule of the default --jobs (mbseig.studies.workers): a pool of W
    workers takes start + ⌈R/W⌉ (t + x) for R tasks of t seconds (x to transfer each) and must
    beat R t by the margin 1.25."""
    # the device sweep's lines (16 lines, 2 timed in-process): t = 0.50 s, x = 0.01 s, fork
    assert pool_pays(14, 0.50, 0.01, 2, 0.1)          # 0.1 + 7·0.51 = 3.67 s vs 7.0 s
    # the bicycle's 41 points of 22 ms, 0.2 MB each to send back: x ≈ 2 ms
    assert pool_pays(39, 0.022, 0.002, 2, 0.1)        # 0.1 + 20·0.024 = 0.58 s vs 0.86 s
    assert not pool_pays(39, 0.022, 0.002, 2, 1.5)    # spawned workers: 1.98 s vs 0.86 s
    # tiny tasks: the start-up alone costs more than they take
    assert not pool_pays(30, 0.001, 0.0005, 2, 0.1)   # 0.1225 s vs 0.03 s
    # the margin: a pool predicted only 10 % faster is not taken
    assert not pool_pays(10, 1.0, 0.0, 2, 4.0)        # 9.0 s vs 10.0 s
    assert pool_pays(10, 1.0, 0.0, 2, 2.0)            # 7.0 s · 1.25 = 8.75 s < 10.0 s
    # one CPU, or fewer than two tasks left: never a pool
    assert not pool_pays(100, 10.0, 0.0, 1, 0.0)
    assert not pool_pays(1, 10.0, 0.0, 2, 0.0)


def test_default_jobs_decides_from_the_first_tasks(monkeypatch):
    """Runner(jobs=None) times its first two tasks in-process: 30 tasks of ~0 s stay
    in-process; 6 tasks that each sleep 0.3 s go to a pool when two CPUs are free, stay
    in-process when one is (the decision is asserted, not a time: a sleep takes its time on
    any machine; the free CPUs are set here, as the load average would give them)."""
    import multiprocessing

    import mbseig.studies.runners as runners
    from mbseig.studies.runners import Runner

    with Runner() as runner:
        assert runner.map(abs, [((-k,), {}) for k in range(30)], "tiny") == list(range(30))
    assert runner.decisions[0][2] == "serial" and runner.kind == "serial"
    slept = [((0.3,), {}) for _ in range(6)]
    monkeypatch.setattr(runners, "free_cpus", lambda own=1: (1, 9.0))
    with Runner() as runner:
        assert runner.map(time.sleep, slept, "slept") == [None] * 6
    assert runner.decisions[0][2] == "serial" and runner.decisions[0][3]["workers"] == 1
    if multiprocessing.get_start_method() != "fork":
        pytest.skip("the slept tasks are timed for fork's start-up")
    monkeypatch.setattr(runners, "free_cpus", lambda own=1: (2, 0.0))
    with Runner() as runner:
        assert runner.map(time.sleep, slept, "slept") == [None] * 6
    assert runner.decisions[0][2] == "processes" and runner.kind == "processes"
    assert runner.decisions[0][3]["remaining"] == 4


def test_free_cpus_leave_out_other_work(monkeypatch):
    """free = usable CPUs − round(load − own), at least 1 (mbseig.studies.workers)."""
    import mbseig.studies.workers as workers

    monkeypatch.setattr(workers, "usable_cpus", lambda: 2)
    for load, own, free in ((0.2, 1, 2), (1.1, 1, 2), (1.8, 1, 1), (3.2, 3, 2), (11.7, 1, 1)):
        monkeypatch.setattr(workers.os, "getloadavg", lambda load=load: (load, load, load))
        assert workers.free_cpus(own) == (free, load)
