"""The start-up rows of ``mbseig bench``: ``mbseig modes`` on the hand device against
``python -c "import numpy, scipy.linalg"``, whole processes in pairs (:func:`bench_startup`
says how, and what it keeps out of the ratio), and their section of the report."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from .cases import case_path


def _f(x, fmt):
    return "–" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, fmt)


#: what the start-up rows are measured against (the floor) and how (README, "Start-up";
#: reports/benchmarks.md, "Start-up")
STARTUP_FLOOR = "import numpy, scipy.linalg (floor)"
#: set on some processors so that older OpenBLAS builds run a safe kernel; they slow a current
#: numpy's import, and would move both commands of a pair by a cost that is the machine's, not
#: mbseig's: dropped together for the timed runs (the kernel then run is recorded)
STARTUP_UNSET = ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE", "PYTHONDONTWRITEBYTECODE")


def startup_env(environ=None):
    """The environment of the timed start-up runs: the caller's, less :data:`STARTUP_UNSET`."""
    environ = os.environ if environ is None else environ
    return {k: v for k, v in environ.items() if k not in STARTUP_UNSET}


def timed_process(cmd, env):
    """(wall s, cpu s) of one whole process: wall from just before the start to the reaping,
    cpu the user + system seconds the OS accounts to it (os.wait4); output discarded."""
    t = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        raise subprocess.CalledProcessError(p.returncode, cmd)
    return wall, usage.ru_utime + usage.ru_stime


def bench_startup(repeats, log, case="hand_device"):
    """Whole-process wall time of ``mbseig modes CASE`` against ``python -c "import numpy,
    scipy.linalg"`` (the floor), measured so that what moves between runs and sessions is
    named rather than folded into the ratio:

    - one untimed round first: the page cache and the bytecode of every command warm (a
      ``PYTHONDONTWRITEBYTECODE`` in the environment is dropped, so that mbseig's modules load
      from cached bytecode as numpy's and scipy's do from the install);
    - ``OPENBLAS_CORETYPE`` and ``OPENBLAS_L2_SIZE`` dropped together for every command (the
      kernel then run is recorded from threadpoolctl in ``kernel``);
    - pairs: each repeat runs the floor and every command once, in an order that alternates
      between repeats; a row's ``ratio`` is the median over the repeats of its time / the
      floor's time in the same repeat (drift in load or clock cancels within a pair), with
      the smallest and largest pair ratio, and the median ``cpu`` seconds (user + system, the
      OS's accounting: what the process itself spent, which load moves far less than wall);
    - the floor exits as Python does, through its teardown (freeing numpy's and scipy's
      modules), which ``mbseig modes`` skips (mbseig.cli.console); the ``prompt exit`` floor
      row ends the same imports with ``os._exit(0)``, as ``mbseig modes`` ends, so the share
      of the teardown in the floor is read from the report, and the ``normal exit`` command
      row is mbseig's with the teardown.
    """
    exe = Path(sys.executable).with_name("mbseig")
    cli = [str(exe)] if exe.exists() else [sys.executable, "-m", "mbseig"]
    path = str(case_path(case))
    cmds = {STARTUP_FLOOR: [sys.executable, "-c", "import numpy, scipy.linalg"],
            "import numpy, scipy.linalg, prompt exit": [
                sys.executable, "-c", "import os, numpy, scipy.linalg; os._exit(0)"],
            "import mbseig": [sys.executable, "-c", "import mbseig"],
            f"mbseig modes {case}": [*cli, "modes", path],
            f"mbseig modes {case}, normal exit": [
                sys.executable, "-c", "import sys; from mbseig.cli import main; "
                f"sys.exit(main(['modes', {path!r}]))"]}
    env = startup_env()
    kernel = subprocess.run(
        [sys.executable, "-c", "import numpy; from threadpoolctl import threadpool_info as i; "
         "print(','.join(sorted({str(x.get('architecture')) for x in i()})))"],
        capture_output=True, text=True, env=env).stdout.strip() or None
    for c in cmds.values():
        timed_process(c, env)
    wall = {k: [] for k in cmds}
    cpu = {k: [] for k in cmds}
    names = list(cmds)
    load = [os.getloadavg()[0]] if hasattr(os, "getloadavg") else []
    for r in range(repeats):
        for k in (names if r % 2 == 0 else names[::-1]):
            w, c = timed_process(cmds[k], env)
            wall[k].append(w)
            cpu[k].append(c)
    if hasattr(os, "getloadavg"):
        load.append(os.getloadavg()[0])
    floor_w, floor_c = np.array(wall[STARTUP_FLOOR]), np.array(cpu[STARTUP_FLOOR])
    rows = []
    for k in names:
        pair = np.array(wall[k]) / floor_w
        rows.append({"section": "startup", "method": k, "n": 0, "time": float(np.median(wall[k])),
                     "ratio": float(np.median(pair)), "ratio_min": float(pair.min()),
                     "ratio_max": float(pair.max()), "cpu": float(np.median(cpu[k])),
                     "cpu_ratio": float(np.median(np.array(cpu[k]) / floor_c)),
                     "repeats": repeats, "kernel": kernel, "load": load,
                     "unset": list(STARTUP_UNSET)})
        log(f"startup {k:42s} {rows[-1]['time']:.3f} s  ({rows[-1]['ratio']:.2f}x floor, pairs "
            f"{pair.min():.2f}-{pair.max():.2f}; cpu {rows[-1]['cpu']:.3f} s, "
            f"{rows[-1]['cpu_ratio']:.2f}x)")
    return rows


def startup_lines(su):
    """The report's "Start-up" section (markdown lines) from the start-up rows."""
    L = []
    if not su:
        return L
    first = su[0]
    L += ["", "## Start-up", "",
          "Wall time of each command in a fresh process, after one untimed round (page cache "
          "and bytecode warm); every repeat runs the floor and each command once, in an order "
          "that alternates between repeats, and a row's ratio is the median over the repeats "
          "of its time / the floor's time in the same repeat (pairs: the smallest and largest "
          "of those); cpu is the process's user + system seconds (the OS's accounting), "
          "which load moves far less than wall time.  "
          + (f"`{'`, `'.join(first['unset'])}` dropped for every command; BLAS kernel "
             f"run: {first.get('kernel')}; load average (1 min) at the start and end: "
             f"{', '.join(f'{x:.2f}' for x in first.get('load', []))}."
             if "unset" in first else ""), "",
          "| command | time | / floor (median of pairs) | pairs | cpu | cpu / floor | runs |",
          "|---|---|---|---|---|---|---|"]
    for r in su:
        L.append(f"| `{r['method']}` | {r['time']:.3f} s | {r['ratio']:.2f}× | "
                 f"{_f(r.get('ratio_min'), '.2f')}–{_f(r.get('ratio_max'), '.2f')} | "
                 f"{_f(r.get('cpu'), '.3f')} s | {_f(r.get('cpu_ratio'), '.2f')}× | "
                 f"{r['repeats']} |")
    L += ["", "The floor exits through Python's teardown (freeing numpy's and scipy's "
          "modules); the executable ends `modes` once its output is flushed, without it. "
          "The `prompt exit` floor ends the same imports with `os._exit(0)`, as `modes` "
          "ends, and the `normal exit` row runs `modes` through `mbseig.cli.main()` with the "
          "teardown (README, start-up)."]
    return L
