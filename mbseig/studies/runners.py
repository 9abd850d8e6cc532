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
from ..statics.linalg import blas_threads

__all__ = ["Runner", "progress_bar", "blas_threads"]


def _capped(fn, n, args, kwargs):
    """fn(*args, **kwargs) with BLAS capped (module docstring); module level, so picklable."""
    with blas_threads(n):
        return fn(*args, **kwargs)


class Runner:
    """Runs a pure function over argument tuples: in-process, local processes or Dask."""

    def __init__(self, *, jobs=None, scheduler=None, progress=None, blas_threads=1):
        self.blas = blas_threads
        self.jobs = jobs if jobs is not None else (os.cpu_count() or 1)
        self.scheduler = scheduler
        self.progress = progress
        self.kind = "dask" if scheduler else ("serial" if self.jobs <= 1 else "processes")
        self._client = self._pool = None

    def __enter__(self):
        if self.kind == "dask":
            try:
                from distributed import Client
            except ImportError:
                raise MbseigError("--scheduler needs the optional extra: pip install 'mbseig[dask]'",
                                  element="--scheduler") from None
            self._client = self.scheduler if not isinstance(self.scheduler, str) else Client(self.scheduler)
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
        """[fn(*args, **kwargs) for args, kwargs in calls], in order."""
        total, done = len(calls), 0
        results = [None] * total
        if self.progress:
            self.progress(label, 0, total)
        if self.kind == "serial":
            for i, (a, kw) in enumerate(calls):
                results[i] = _capped(fn, self.blas, a, kw)
                done += 1
                if self.progress:
                    self.progress(label, done, total)
            return results
        if self.kind == "processes":
            from concurrent.futures import as_completed

            futs = {self._pool.submit(_capped, fn, self.blas, a, kw): i
                    for i, (a, kw) in enumerate(calls)}
            for fut in as_completed(futs):
                results[futs[fut]] = fut.result()
                done += 1
                if self.progress:
                    self.progress(label, done, total)
            return results
        from distributed import as_completed as das_completed

        futs = [self._client.submit(_capped, fn, self.blas, a, kw, pure=False) for a, kw in calls]
        index = {f.key: i for i, f in enumerate(futs)}
        for fut in das_completed(futs):
            results[index[fut.key]] = fut.result()
            done += 1
            if self.progress:
                self.progress(label, done, total)
        return results


def progress_bar(stream=sys.stderr, width=30):
    """A progress callback drawing ``label [#####.....] k/n`` on one line of ``stream``."""
    def show(label, done, total):
        filled = int(width * done / total) if total else width
        stream.write(f"\r{label:<10} [{'#' * filled}{'.' * (width - filled)}] {done}/{total}")
        if done >= total:
            stream.write("\n")
        stream.flush()
    return show
