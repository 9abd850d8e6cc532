"""Runners for studies: one pure function over many argument tuples, in-process, on local
processes or on a Dask cluster, with the same results on each (tests/test_sweep.py).

Each call runs with BLAS capped to ``blas_threads`` threads (default 1, through threadpoolctl
when it is installed): a study's points are small dense problems, for which a second BLAS thread
only adds synchronization, and with several workers on few cores it costs far more (a 6×6
triangular solve measured 13 ms with two OpenBLAS threads on a busy 2-core machine, 30 µs with
one).

How many processes (``jobs=None``, the default): each stage runs its first tasks in-process,
timed, and the rest on a pool only when that is predicted faster (:mod:`mbseig.studies.workers`,
the rule and its measured constants).  ``jobs=1`` runs in-process, ``jobs=N`` on N processes
from the first task.

Ctrl-C.  The workers ignore SIGINT (the parent decides, so a worker never prints a
KeyboardInterrupt traceback): they are started with SIGINT blocked and ignore it before they
unblock it.  A KeyboardInterrupt (or any error) in the parent while a pool runs ends its
workers at once (SIGTERM; SIGKILL after 1 s) instead of waiting for the tasks they run, and
is raised again; every result that arrived before it is in the checkpoint.
"""

from __future__ import annotations

import signal
import sys
import time

from ..errors import MbseigError
from ..statics.linalg import blas_threads
from .workers import (
    MARGIN,
    POOL_START,
    PROBE,
    capped,
    free_cpus,
    interned,
    pool_pays,
    release,
    sigmask,
    start_method,
    timed,
    usable_cpus,
    worker_init,
)

__all__ = ["Runner", "Interrupted", "progress_bar", "blas_threads", "pool_pays", "free_cpus",
           "usable_cpus",
           "POOL_START", "MARGIN", "PROBE"]


#: seconds to wait for a Dask scheduler before giving up with a one-line error
CONNECT_TIMEOUT = 4.0
#: seconds between two looks for a signal while the parent waits on a pool (a SIGINT received
#: by another thread is then acted on within this time)
POLL = 0.2


class Interrupted(KeyboardInterrupt):
    """A study stopped by Ctrl-C (a KeyboardInterrupt): ``done`` of ``total`` grid points had
    finished and are in ``checkpoint`` (a :class:`~mbseig.studies.resume.Checkpoint`, or None);
    ``stage`` says what ran (e.g. "lines", "boundaries 3 of 7")."""

    def __init__(self, done, total, stage="", checkpoint=None):
        super().__init__(f"interrupted after {done} of {total} points")
        self.done, self.total, self.stage, self.checkpoint = done, total, stage, checkpoint


def _connect(Client, address, timeout):
    """A distributed.Client on ``address``, or one MbseigError line within ``timeout`` seconds
    when the scheduler cannot be reached (the default would wait 30 s and raise a traceback)."""
    try:
        return Client(address, timeout=f"{timeout:g}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        detail = " ".join(str(exc).split()) or type(exc).__name__
        if len(detail) > 160:
            detail = detail[:157] + "..."
        raise MbseigError(f"cannot reach the Dask scheduler at {address!r} within "
                          f"{timeout:g} s ({type(exc).__name__}: {detail})",
                          element="--scheduler") from None


class Runner:
    """Runs a pure function over argument tuples: in-process, local processes or Dask.

    jobs : None (default: in-process or a pool, decided per stage, module docstring), 1
        (in-process) or the number of local processes.
    checkpoint : a :class:`~mbseig.studies.resume.Checkpoint`; every task's result is written
        to it as it completes and a task it already holds is not run again.
    points : the study's grid points; each ``map(..., points=k)`` task holds k of them.  A
        KeyboardInterrupt inside the ``with`` block leaves it as :class:`Interrupted`, with
        the points held (read or finished) and the stage that ran.
    """

    def __init__(self, *, jobs=None, scheduler=None, progress=None, blas_threads=1,
                 connect_timeout=CONNECT_TIMEOUT, checkpoint=None, points=0):
        from .resume import Checkpoint

        self.blas = blas_threads
        self.checkpoint = checkpoint if checkpoint is not None else Checkpoint(None, deferred=True)
        self.jobs = jobs
        self.scheduler = scheduler
        self.connect_timeout = connect_timeout
        # progress: a callback (label, done, total), True for progress bars (tqdm), or None/False
        self.progress = (progress_bar() if progress is True else
                         None if progress is False or progress is None else progress)
        if self.progress is not None and not callable(self.progress):
            raise MbseigError(f"progress must be True, False, None or a callable "
                              f"(label, done, total), got {progress!r}", element="progress")
        self.kind = ("dask" if scheduler else "processes" if jobs is not None and jobs > 1
                     else "serial")
        self.decisions = []  # per stage: (label, tasks, "serial" | "processes", why)
        self.points = self.checkpoint.points  # grid points held, of all
        self.points[:] = [0, int(points)]
        self.stages = []  # (label, tasks) of every map, in order
        self._client = self._pool = None
        self._tokens = []

    def __enter__(self):
        if self.kind == "dask":
            try:
                from distributed import Client
            except ImportError:
                raise MbseigError("--scheduler needs the optional extra: "
                                  "pip install 'mbseig[dask]'",
                                  element="--scheduler") from None
            self._client = (self.scheduler if not isinstance(self.scheduler, str)
                            else _connect(Client, self.scheduler, self.connect_timeout))
        return self

    def __exit__(self, exc_type, *exc):
        if self._pool is not None:
            if exc_type is None:
                self._pool.shutdown()
            else:
                self.stop()
        if self._client is not None and isinstance(self.scheduler, str):
            self._client.close()
        release(self._tokens)
        if exc_type is not None and issubclass(exc_type, KeyboardInterrupt) and not issubclass(
                exc_type, Interrupted):
            raise self.interrupted() from None
        return False

    def interrupted(self) -> Interrupted:
        """What an interruption leaves: the grid points held, the stage that ran."""
        label, n = self.stages[-1] if self.stages else ("", 0)
        held = self.checkpoint.held(label) if label else 0
        stage = f"{label} {held} of {n}" if label else ""
        return Interrupted(min(self.points[0], self.points[1]), self.points[1], stage,
                           self.checkpoint)

    def stop(self):
        """End the pool's workers now (an interruption or an error): SIGTERM, SIGKILL for one
        still alive after 1 s; the tasks they ran are lost, those that arrived are kept."""
        pool, self._pool = self._pool, None
        if pool is None:
            return
        procs = list((getattr(pool, "_processes", None) or {}).values())
        for p in procs:
            try:
                p.terminate()
            except (OSError, ValueError, AttributeError):
                pass
        pool.shutdown(wait=False, cancel_futures=True)
        deadline = time.monotonic() + 1.0
        for p in procs:
            try:
                p.join(max(0.0, deadline - time.monotonic()))
                if p.is_alive():
                    p.kill()
            except (OSError, ValueError, AttributeError, AssertionError):
                pass

    def _workers(self, n):
        """The pool (created on first use, with n workers)."""
        if self._pool is None:
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(max_workers=n, initializer=worker_init)
            self.kind = "processes"
        return self._pool

    def map(self, fn, calls, label, points=0):
        """[fn(*args, **kwargs) for args, kwargs in calls], in order.  With a checkpoint, the
        tasks it holds are read instead of run, and each result is written to it as soon as
        it arrives (so an interruption loses only the tasks still running).  ``points``: the
        grid points each task holds (the count an interruption reports): one number for all,
        or one per task."""
        total = len(calls)
        per = list(points) if isinstance(points, (list, tuple)) else [points] * total
        self.stages.append((label, total))
        results = [None] * total
        todo = []
        for i in range(total):
            held, value = self.checkpoint.get(label, i)
            if held:
                results[i] = value
            else:
                todo.append(i)
        done = total - len(todo)
        waiting = set(todo)
        self.points[0] += sum(per[i] for i in range(total) if i not in waiting)
        if self.progress:
            self.progress(label, done, total)

        def arrived(i, value):
            nonlocal done
            results[i] = value
            self.checkpoint.put(label, i, value)
            done += 1
            self.points[0] += per[i]
            if self.progress:
                self.progress(label, done, total)

        if self.kind == "dask":
            self._dask(fn, calls, todo, arrived)
            return results
        if self.jobs is None:  # time the first tasks here, then decide (module docstring)
            times = []
            while todo and len(times) < PROBE:
                i = todo.pop(0)
                value, seconds, transfer = timed(fn, self.blas, *calls[i])
                times.append((seconds, transfer))
                arrived(i, value)
            own = 1 + (self._pool._max_workers if self._pool is not None else 0)
            free, load = free_cpus(own)
            workers = min(free, len(todo))
            start = 0.0 if self._pool is not None else POOL_START.get(start_method(), 1.5)
            per_task, transfer = times[-1] if times else (0.0, 0.0)
            use = len(times) == PROBE and pool_pays(len(todo), per_task, transfer, workers, start)
            self.decisions.append((label, total, "processes" if use else "serial",
                                   {"per_task": per_task, "transfer": transfer,
                                    "workers": workers, "start": start, "load": load,
                                    "remaining": len(todo)}))
            if not use:
                for i in todo:
                    arrived(i, capped(fn, self.blas, *calls[i]))
                return results
            pool = self._workers(workers)
        elif self.jobs <= 1:
            for i in todo:
                a, kw = calls[i]
                arrived(i, capped(fn, self.blas, a, kw))
            return results
        else:
            pool = self._workers(self.jobs)
        self._pooled(pool, fn, calls, todo, arrived)
        return results

    def _pooled(self, pool, fn, calls, todo, arrived):
        """The tasks ``todo`` on the pool, each result handed to ``arrived`` as it completes;
        on an error or an interruption the workers are ended at once (:meth:`stop`)."""
        from concurrent.futures import FIRST_COMPLETED, wait

        args = interned(calls, todo, self._tokens)
        try:
            # SIGINT blocked while the pool starts its workers: a worker starts with it blocked
            # and ignores it before it unblocks it (_worker_init); here it is delivered after
            blocked = sigmask(getattr(signal, "SIG_BLOCK", None), {signal.SIGINT})
            try:
                futs = {pool.submit(capped, fn, self.blas, args[i], calls[i][1]): i
                        for i in todo}
            finally:
                if blocked is not None:
                    sigmask(signal.SIG_SETMASK, blocked)
            pending = set(futs)
            while pending:
                finished, pending = wait(pending, timeout=POLL, return_when=FIRST_COMPLETED)
                failed = None
                for fut in sorted(finished, key=futs.get):
                    if fut.exception() is not None:
                        failed = failed or fut
                    else:
                        arrived(futs[fut], fut.result())
                if failed is not None:
                    failed.result()  # (raises the task's error)
        except BaseException:
            self.stop()
            raise

    def _dask(self, fn, calls, todo, arrived):
        from distributed import as_completed as das_completed

        # a worker lost while it runs a task: the scheduler runs the task again on another
        # worker, and its future completes once (tests/test_resume.py kills one)
        futs = [self._client.submit(capped, fn, self.blas, *calls[i], pure=False) for i in todo]
        index = {f.key: i for f, i in zip(futs, todo, strict=True)}
        try:
            for fut in das_completed(futs):
                arrived(index[fut.key], fut.result())
        except BaseException:
            try:
                self._client.cancel(futs, asynchronous=False)
            except Exception:  # (the cluster may be gone: nothing left to cancel)
                pass
            raise


def progress_bar(stream=None):
    """A progress callback ``(label, done, total)`` drawing one tqdm bar a stage (lines,
    boundaries, curves) on ``stream`` (default stderr) with its rate and the time left.  Its
    ``close()`` ends the bars left unfinished (an error or Ctrl-C: the message that follows
    starts on a line of its own)."""
    from tqdm import tqdm

    stream = sys.stderr if stream is None else stream
    bars = {}

    def show(label, done, total):
        bar = bars.get(label)
        if bar is None or bar.total != total:
            if bar is not None:
                bar.close()
            bar = bars[label] = tqdm(total=total, desc=f"{label:<10}", file=stream,
                                     unit="task", dynamic_ncols=True, leave=True,
                                     bar_format="{desc} {percentage:3.0f}%|{bar}| "
                                                "{n_fmt}/{total_fmt} "
                                                "[{elapsed}<{remaining}, {rate_fmt}]")
        bar.update(done - bar.n)
        if done >= total:
            bar.close()
            bars.pop(label, None)

    def close():
        while bars:
            bars.popitem()[1].close()

    show.close = close
    return show
