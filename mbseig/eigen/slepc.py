"""Optional SLEPc backend of the partial path (``solver="partial-slepc"``; docs/scaling.md).

SLEPc's polynomial eigensolver (PEP, TOAR with shift-and-invert) solves the same bordered pencil
as ``partial-companion``; mbseig then checks every returned pair exactly as it checks its own
(backward error η on the bordered problem, condition κ, coverage), in
:func:`mbseig.eigen.partial.solve_partial`.  slepc4py is often available only for the
distribution's Python (Debian: ``python3-slepc4py python3-petsc4py``), compiled against another
numpy than the one mbseig runs on, so the solve runs in a separate process: the Python named by
``MBSEIG_SLEPC_PYTHON``, else this Python if it imports slepc4py, else ``/usr/bin/python3``.  The
matrices go to it through a temporary ``.npz`` file and the eigenpairs come back the same way
(:mod:`mbseig.eigen.slepc_worker`).  ``PETSC_DIR`` and ``SLEPC_DIR`` default to the
distribution's real-scalar builds when unset.

LU package: ``umfpack`` by default (with pivoting: the bordered matrix has a zero block, on which
PETSc's own LU, which does not pivot, stops with a zero pivot); ``superlu`` and ``mumps`` also work.

Several processes: with ``MBSEIG_SLEPC_RANKS=P`` (or ``ranks=P``) the worker runs under
``mpiexec -n P`` (Open MPI or MPICH from the distribution), each process holding a block of rows,
with the parallel LU of MUMPS (``superlu_dist``, whose pivoting is static, stops at the zero block
of the bordered matrix: PETSc error 71, zero pivot); the eigenvectors are gathered to rank
0 and checked by mbseig as on one process.  ``info["peak_rss_mb"]`` lists each rank's peak memory.
"""

from __future__ import annotations

import functools
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from ..errors import SolverError

__all__ = ["slepc_available", "slepc_python", "slepc_ranks", "slepc_solve"]

_WORKER = Path(__file__).with_name("slepc_worker.py")


def _env():
    env = dict(os.environ)
    for var, pattern in (("PETSC_DIR", "/usr/lib/petscdir/petsc*/x86_64-linux-gnu-real"),
                         ("SLEPC_DIR", "/usr/lib/slepcdir/slepc*/x86_64-linux-gnu-real")):
        if not env.get(var):
            found = sorted(glob.glob(pattern))
            if found:
                env[var] = found[-1]
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env.setdefault(var, "1")
    return env


@functools.lru_cache(maxsize=1)
def slepc_python():
    """The Python that runs the SLEPc worker, or None when no candidate imports slepc4py."""
    named = os.environ.get("MBSEIG_SLEPC_PYTHON")
    candidates = [named] if named else [sys.executable, "/usr/bin/python3"]
    for exe in candidates:
        if not exe or not Path(exe).exists():
            continue
        try:
            p = subprocess.run([exe, "-c", "import petsc4py, slepc4py"], env=_env(),
                               capture_output=True, timeout=60)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if p.returncode == 0:
            return exe
    return None


def slepc_available() -> bool:
    return slepc_python() is not None


def slepc_ranks(ranks=None) -> int:
    """The MPI processes of the SLEPc worker: ``ranks``, else ``MBSEIG_SLEPC_RANKS``, else 1."""
    raw = os.environ.get("MBSEIG_SLEPC_RANKS", "1") if ranks is None else ranks
    try:
        value = int(raw)
    except (TypeError, ValueError):
        value = 0
    if value < 1 or str(raw).strip() != str(value):
        raise SolverError(f"MBSEIG_SLEPC_RANKS must be a positive integer, got {raw!r}")
    return value


def _launch(exe, ranks, env):
    """The command that starts the worker: the Python itself, or ``mpiexec -n ranks`` of it."""
    if ranks == 1:
        return [exe]
    mpiexec = shutil.which("mpiexec") or shutil.which("mpirun")
    if mpiexec is None:
        raise SolverError(f"partial-slepc on {ranks} processes needs mpiexec (Debian: it comes "
                          "with python3-petsc4py's Open MPI); none is on the PATH")
    if hasattr(os, "geteuid") and os.geteuid() == 0:  # Open MPI refuses root unless told
        env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
        env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    return [mpiexec, "-n", str(ranks), exe]


def slepc_solve(Mb, Pb, Qb, nev, target=0.0, *, tol=1e-14, maxit=1000, ncv=None,
                factor=None, ranks=None, upper_tol=None):
    """(s, X, info): ``nev`` or more eigenpairs of (Mb s² + Pb s + Qb) x = 0 nearest ``target``
    (real), from SLEPc's TOAR with shift-and-invert, in a worker process (``ranks`` MPI
    processes: module docstring).  ``factor``: the LU package, ``umfpack`` on one process and
    ``mumps`` on several by default.  X's columns are the vectors of ``info["columns"]`` of s:
    every eigenvalue, or with ``upper_tol`` those with Im s ≥ −upper_tol·|s| (the conjugate
    partners of the others; half the vectors to gather and to pass back)."""
    exe = slepc_python()
    if exe is None:
        raise SolverError("solver 'partial-slepc' needs slepc4py (Debian: apt install "
                          "python3-slepc4py python3-petsc4py; or set MBSEIG_SLEPC_PYTHON to a "
                          "Python that imports slepc4py)")
    ranks = slepc_ranks(ranks)
    factor = factor or ("umfpack" if ranks == 1 else "mumps")
    env = _env()
    launch = _launch(exe, ranks, env)
    opts = {"nev": int(nev), "target": float(target), "tol": float(tol), "maxit": int(maxit),
            "ncv": int(ncv or 0), "factor": factor,
            "upper_tol": None if upper_tol is None else float(upper_tol)}
    arrays = {"shape": np.array(Mb.shape), "options": json.dumps(opts)}
    for key, A in (("M", Mb), ("P", Pb), ("Q", Qb)):
        A = A.tocsr(copy=True)
        A.sum_duplicates()
        A.sort_indices()
        arrays.update({f"{key}_data": A.data, f"{key}_indices": A.indices, f"{key}_indptr": A.indptr})
    with tempfile.TemporaryDirectory(prefix="mbseig-slepc-") as tmp:
        path_in, path_out = os.path.join(tmp, "in.npz"), os.path.join(tmp, "out.npz")
        np.savez(path_in, **arrays)
        del arrays
        p = subprocess.run(launch + [str(_WORKER), path_in, path_out], env=env,
                           capture_output=True, text=True)
        if p.returncode != 0 or not os.path.exists(path_out):
            # the worker's own one-line message comes first (mpiexec appends banners after it)
            last = next((line for line in p.stderr.splitlines()
                         if line.strip() and set(line.strip()) != {"-"}), "no message")
            raise SolverError(f"partial-slepc: the SLEPc worker failed (exit {p.returncode}: "
                              f"{last})")
        try:
            with np.load(path_out) as out:
                s, X = out["s"], out["X"]
                columns = out["columns"]
                info = {k: out[k].item()
                        for k in ("its", "nconv", "setup", "solve", "reason", "factor", "ranks")}
            info["columns"] = columns
            info["peak_rss_mb"] = []
            for r in range(ranks):
                with open(f"{path_out}.rank{r}") as f:
                    info["peak_rss_mb"].append(round(json.load(f)["peak_rss_kb"] / 1024.0, 1))
        except (OSError, ValueError, KeyError) as exc:
            raise SolverError(f"partial-slepc: the worker's result is unreadable ({exc})") from None
    if info["reason"] < 0:
        raise SolverError(f"partial-slepc: SLEPc did not converge (reason {info['reason']}, "
                          f"{info['nconv']} of {nev} pairs after {info['its']} restarts)")
    return s, X, info
