"""What a study's worker process runs, and whether a pool of them pays.

How many processes (``jobs=None``, the default of :class:`mbseig.studies.runners.Runner`).
Each stage (``map``) runs its first two tasks in-process and times them; the second one's time
t is the cost of a task once the process is warm (the first pays for imports, caches and the
statics that later lines share).  The R tasks
left go to a pool of W = min(free CPUs, R) processes only when it is predicted faster:

    start + ⌈R / W⌉ (t + x)  <  R t / (1 + MARGIN)

with ``start`` the pool's measured start-up (:data:`POOL_START`, per start method) and x the
measured transfer of one task (pickling its arguments and its result both ways).  The free
CPUs are those the 1-minute load average leaves beside this study's own processes
(:func:`free_cpus`): on a machine busy with other work a second process gets no second CPU.
Otherwise the whole stage runs in-process (:func:`pool_pays`, the rule; tests/test_interrupt.py).
A pool forked after the first tasks inherits what they left in memory, as the later tasks of an
in-process run do (the statics of a line shared by the lines that differ only in damping).
``jobs=1`` runs in-process, ``jobs=N`` on N processes from the first task.

A worker ignores SIGINT (:func:`worker_init`: the parent decides what an interruption
keeps); it receives the objects every task of a stage shares (the case) once per process
(:func:`interned`).
"""

from __future__ import annotations

import itertools
import math
import os
import pickle
import signal
import time

from ..eigen.dense import blas_held
from ..statics.linalg import blas_threads

__all__ = ["PROBE", "POOL_START", "MARGIN", "usable_cpus", "free_cpus", "pool_pays", "capped",
           "timed", "worker_init", "sigmask", "interned", "release", "start_method"]

#: tasks a stage runs in-process and times before it decides on a pool (jobs=None)
PROBE = 2
#: seconds from creating a pool to its workers' first results, by start method: measured on a
#: 2-core machine at load 5 (a ProcessPoolExecutor of 2 workers started from a process with
#: numpy, scipy and the sweep modules loaded, until both return a trivial task; 7 runs):
#: fork median 0.037 s (0.029–0.046); spawn 0.76 s (0.75–1.07) and forkserver 0.77 s
#: (0.72–1.23), which import numpy, scipy and mbseig in each worker.  Taken with a margin
#: (a larger parent forks more page tables; the first real task imports more modules).
POOL_START = {"fork": 0.1, "spawn": 1.5, "forkserver": 1.5}
#: the pool must be predicted this much faster than in-process: the estimate of one task from
#: one timed task and the start-up above are not exact, and a machine shared with other work
#: gives a pool less than its CPUs
MARGIN = 0.25


def usable_cpus() -> int:
    """The CPUs this process may run on (its affinity, else the machine's count)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def free_cpus(own: int = 1) -> tuple:
    """(free, load): the usable CPUs that other work leaves free, and the load it was read
    from.  free = usable CPUs − round(load − own), at least 1, with load the 1-minute load
    average and ``own`` this study's processes counted in it (the parent, and the workers of
    a pool that ran).  Measured on a 2-core machine at load 9–13: two processes did the work
    of one (two 30·10⁶-step Python loops took 2.05–2.23 s in one process, 1.98–2.13 s on two),
    and a pool of 2 was 1.14–1.30× slower than in-process on four studies."""
    cpus = usable_cpus()
    try:
        load = float(os.getloadavg()[0])
    except (AttributeError, OSError):  # (no load average on this platform: the CPUs alone)
        return cpus, None
    busy = max(0, int(round(load - own)))
    return max(1, cpus - busy), load


def pool_pays(remaining, per_task, transfer, workers, start, margin=MARGIN) -> bool:
    """Whether ``remaining`` tasks of ``per_task`` seconds each (``transfer`` seconds more each
    on a pool) finish sooner on ``workers`` processes that take ``start`` seconds to start than
    in-process, by the factor 1 + ``margin`` (module docstring)."""
    if workers < 2 or remaining < 2:
        return False
    pool = start + math.ceil(remaining / workers) * (per_task + transfer)
    return pool * (1.0 + margin) < remaining * per_task


# objects sent once per process: token -> object (in a worker: unpickled on first use, or
# inherited from the parent by fork), so that the tasks of a stage in one process receive the
# same object, as in-process (a line's statics are shared by identity of the case)
_INTERNED: dict = {}
_TOKENS = itertools.count()


class _Ref:
    """An object interned by token; ``blob`` (its pickle) for a worker that lacks it."""

    __slots__ = ("token", "blob")

    def __init__(self, token, blob):
        self.token, self.blob = token, blob

    def resolve(self):
        obj = _INTERNED.get(self.token)
        if obj is None:
            obj = _INTERNED[self.token] = pickle.loads(self.blob)
        return obj


def capped(fn, n, args, kwargs):
    """fn(*args, **kwargs) with BLAS capped (module docstring); module level, so picklable."""
    args = tuple(a.resolve() if isinstance(a, _Ref) else a for a in args)
    with blas_threads(n), blas_held(n):
        return fn(*args, **kwargs)


def worker_init():
    """A pool worker ignores SIGINT (it was started with it blocked; the parent decides)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    sigmask(signal.SIG_UNBLOCK if hasattr(signal, "SIG_UNBLOCK") else None, {signal.SIGINT})


def sigmask(how, signals):
    """signal.pthread_sigmask where the platform has it (POSIX), else nothing."""
    if how is None or not hasattr(signal, "pthread_sigmask"):
        return None
    return signal.pthread_sigmask(how, signals)


def timed(fn, n, args, kwargs):
    """(result, seconds, transfer seconds): fn's result, its time and the time to pickle and
    unpickle its arguments and result (what a pool would add)."""
    t0 = time.perf_counter()
    value = capped(fn, n, args, kwargs)
    t1 = time.perf_counter()
    try:
        pickle.loads(pickle.dumps((fn, args, kwargs, value), protocol=pickle.HIGHEST_PROTOCOL))
    except Exception:  # not picklable: no pool can run it
        return value, t1 - t0, math.inf
    return value, t1 - t0, time.perf_counter() - t1


def interned(calls, todo, tokens):
    """{i: args of call i} for the calls ``todo``, with every argument object that all of
    them share (the case) replaced by a :class:`_Ref` sent once per process; each token is
    appended to ``tokens`` (:func:`release` them when the study ends)."""
    if len(todo) < 2:
        return {i: calls[i][0] for i in todo}
    first = calls[todo[0]][0]
    shared = {id(a): a for a in first
              if not isinstance(a, (str, bytes, int, float, bool, type(None)))
              and all(any(b is a for b in calls[i][0]) for i in todo)}
    refs = {}
    for key, obj in shared.items():
        token = f"{os.getpid()}-{next(_TOKENS)}"
        _INTERNED[token] = obj  # (a worker forked after this inherits it)
        tokens.append(token)
        refs[key] = _Ref(token, pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))
    return {i: tuple(refs.get(id(a), a) for a in calls[i][0]) for i in todo}


def release(tokens):
    """Forget the interned objects of ``tokens`` (in this process)."""
    for token in tokens:
        _INTERNED.pop(token, None)


def start_method() -> str:
    """The start method a pool's processes use (fork, spawn or forkserver)."""
    import multiprocessing

    return multiprocessing.get_start_method(allow_none=False)
