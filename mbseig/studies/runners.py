"""Runners for studies: one pure function over many argument tuples, in-process, on local
processes or on a Dask cluster, with the same results on each (tests/test_sweep.py).

Each call runs with BLAS capped to ``blas_threads`` threads (default 1, through threadpoolctl
when it is installed): a study's points are small dense problems, for which a second BLAS thread
only adds synchronization, and with several workers on few cores it costs far more (a 6×6
triangular solve measured 13 ms with two OpenBLAS threads on a busy 2-core machine, 30 µs with
one).
"""

from __future__ import annotations

import os
import sys

from ..errors import MbseigError
from ..eigen.dense import blas_held
from ..statics.linalg import blas_threads

__all__ = ["Runner", "progress_bar", "blas_threads"]


#: seconds to wait for a Dask scheduler before giving up with a one-line error
CONNECT_TIMEOUT = 4.0


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


def _capped(fn, n, args, kwargs):
    """fn(*args, **kwargs) with BLAS capped (module docstring); module level, so picklable."""
    with blas_threads(n), blas_held(n):
        return fn(*args, **kwargs)


class Runner:
    """Runs a pure function over argument tuples: in-process, local processes or Dask."""

    def __init__(self, *, jobs=None, scheduler=None, progress=None, blas_threads=1,
                 connect_timeout=CONNECT_TIMEOUT, checkpoint=None):
        self.blas = blas_threads
        # checkpoint: a mbseig.studies.resume.Checkpoint; every task's result is written to it
        # as it completes and a task it already holds is not run again
        self.checkpoint = checkpoint
        self.jobs = jobs if jobs is not None else (os.cpu_count() or 1)
        self.scheduler = scheduler
        self.connect_timeout = connect_timeout
        # progress: a callback (label, done, total), True for progress bars (tqdm), or None/False
        self.progress = (progress_bar() if progress is True else
                         None if progress is False or progress is None else progress)
        if self.progress is not None and not callable(self.progress):
            raise MbseigError(f"progress must be True, False, None or a callable "
                              f"(label, done, total), got {progress!r}", element="progress")
        self.kind = "dask" if scheduler else ("serial" if self.jobs <= 1 else "processes")
        self._client = self._pool = None

    def __enter__(self):
        if self.kind == "dask":
            try:
                from distributed import Client
            except ImportError:
                raise MbseigError("--scheduler needs the optional extra: pip install 'mbseig[dask]'",
                                  element="--scheduler") from None
            self._client = (self.scheduler if not isinstance(self.scheduler, str)
                            else _connect(Client, self.scheduler, self.connect_timeout))
        elif self.kind == "processes":
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(max_workers=self.jobs)
        return self

    def __exit__(self, *exc):
        if self._pool is not None:
            self._pool.shutdown()
        if self._client is not None and isinstance(self.scheduler, str):
            self._client.close()

    def map(self, fn, calls, label):
        """[fn(*args, **kwargs) for args, kwargs in calls], in order.  With a checkpoint, the
        tasks it holds are read instead of run, and each result is written to it as soon as
        it arrives (so an interruption loses only the tasks still running)."""
        total = len(calls)
        results = [None] * total
        todo = []
        for i in range(total):
            held, value = (self.checkpoint.get(label, i) if self.checkpoint is not None
                           else (False, None))
            if held:
                results[i] = value
            else:
                todo.append(i)
        done = total - len(todo)
        if self.progress:
            self.progress(label, done, total)

        def arrived(i, value):
            nonlocal done
            results[i] = value
            if self.checkpoint is not None:
                self.checkpoint.put(label, i, value)
            done += 1
            if self.progress:
                self.progress(label, done, total)

        if self.kind == "serial":
            for i in todo:
                a, kw = calls[i]
                arrived(i, _capped(fn, self.blas, a, kw))
            return results
        if self.kind == "processes":
            from concurrent.futures import as_completed

            futs = {self._pool.submit(_capped, fn, self.blas, *calls[i]): i for i in todo}
            for fut in as_completed(futs):
                arrived(futs[fut], fut.result())
            return results
        from distributed import as_completed as das_completed

        # a worker lost while it runs a task: the scheduler runs the task again on another
        # worker, and its future completes once (tests/test_resume.py kills one)
        futs = [self._client.submit(_capped, fn, self.blas, *calls[i], pure=False) for i in todo]
        index = {f.key: i for f, i in zip(futs, todo)}
        for fut in das_completed(futs):
            arrived(index[fut.key], fut.result())
        return results


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
                                     bar_format="{desc} {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} "
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
