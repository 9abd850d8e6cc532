"""Optional SLEPc backend of the partial path (``solver="partial-slepc"``; docs/scaling.md).

SLEPc's polynomial eigensolver (PEP, TOAR with shift-and-invert) solves the same bordered pencil
as ``partial-companion``; mbseig then checks every returned pair exactly as it checks its own
(backward error η on the bordered problem, condition κ, coverage), in
:func:`mbseig.eigen.partial.solve_partial`.  slepc4py is often available only for the
distribution's Python (Debian: ``python3-slepc4py python3-petsc4py``), compiled against another
numpy than the one mbseig runs on, so the solve runs in a separate process: the Python named by
``MBSEIG_SLEPC_PYTHON``, else this Python if it imports slepc4py, else ``/usr/bin/python3``.  The
matrices go to it as ``.npy`` files in a temporary folder (in ``/dev/shm`` where it has room)
and the eigenpairs come back the same way (:mod:`mbseig.eigen.slepc_worker`); a worker on one
process is started before the files are written and imports PETSc meanwhile.  The folder names
the PIDs of the solve and of its worker; a folder left by a killed solve goes at the next solve
(:func:`reap_stale`).  ``PETSC_DIR`` and ``SLEPC_DIR`` default to the distribution's real-scalar
builds when unset.

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

__all__ = ["reap_stale", "slepc_available", "slepc_python", "slepc_ranks", "slepc_solve",
           "worker_python"]

_WORKER = Path(__file__).with_name("slepc_worker.py")


def _env(ranks=None):
    """The worker's environment: PETSc's and SLEPc's folders, one BLAS thread, and on one
    process Open MPI's ``ob1`` messaging layer (a process that talks to no other needs no
    network probe; it halves PETSc's start, 0.33 → 0.13 s here).  Set variables are kept."""
    env = dict(os.environ)
    for var, pattern in (("PETSC_DIR", "/usr/lib/petscdir/petsc*/x86_64-linux-gnu-real"),
                         ("SLEPC_DIR", "/usr/lib/slepcdir/slepc*/x86_64-linux-gnu-real")):
        if not env.get(var):
            found = sorted(glob.glob(pattern))
            if found:
                env[var] = found[-1]
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env.setdefault(var, "1")
    if ranks == 1:
        env.setdefault("OMPI_MCA_pml", "ob1")
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


def worker_python():
    """The Python that is to run the worker, chosen without starting it (a probe costs a
    petsc4py import, ≈ 0.4 s, at every solve in a fresh process): ``MBSEIG_SLEPC_PYTHON``, else
    this Python if it has slepc4py and petsc4py, else ``/usr/bin/python3``.  A candidate that
    cannot import them is found out by the worker itself, which says so in one line."""
    import importlib.util

    named = os.environ.get("MBSEIG_SLEPC_PYTHON")
    if named:
        return named if Path(named).exists() else None
    if all(importlib.util.find_spec(m) is not None for m in ("petsc4py", "slepc4py")):
        return sys.executable
    return "/usr/bin/python3" if Path("/usr/bin/python3").exists() else None


_MISSING = ("solver 'partial-slepc' needs slepc4py (Debian: apt install python3-slepc4py "
            "python3-petsc4py; or set MBSEIG_SLEPC_PYTHON to a Python that imports slepc4py)")


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


def _scratch(*mats):
    """Where the worker's files go: ``/dev/shm`` (memory) when it has room for twice the
    matrices and 32 vectors, else the default temporary folder."""
    shm = "/dev/shm"
    try:
        n = mats[0].shape[0]
        need = 2 * sum(12 * A.nnz + 4 * n for A in mats) + 32 * 16 * n
        if os.access(shm, os.W_OK) and shutil.disk_usage(shm).free > need:
            return shm
    except OSError:
        pass
    return None


PREFIX = "mbseig-slepc-"
_OWNERS = "owners"  # in each scratch folder: the PIDs of the solve and of its worker


def reap_stale(folder=None):
    """Remove the scratch folders of solves whose processes are all gone (a solve killed by
    SIGKILL or a power cut leaves its folder, up to the size of its matrices and vectors, in
    ``/dev/shm``, that is in memory).  Only this user's folders that name their processes are
    touched: a folder being set up (no list yet) and one of a live solve stay.  Returns the
    folders removed."""
    folder = folder or tempfile.gettempdir()
    removed = []
    try:
        entries = [e for e in os.scandir(folder) if e.name.startswith(PREFIX) and e.is_dir()]
    except OSError:
        return removed
    uid = os.getuid() if hasattr(os, "getuid") else None
    for entry in entries:
        try:
            if uid is not None and entry.stat().st_uid != uid:
                continue
            with open(os.path.join(entry.path, _OWNERS)) as f:
                space, *words = f.read().split()
            pids = [int(w) for w in words]
        except (OSError, ValueError):
            continue
        if space != _namespace():  # (another container's processes are not visible from here)
            continue
        if pids and not any(_alive(pid) for pid in pids):
            shutil.rmtree(entry.path, ignore_errors=True)
            removed.append(entry.path)
    return removed


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # (another user's process of that number: not ours to judge)
        return True
    return True


def _namespace():
    """This process's PID namespace (Linux), so that a folder in a ``/dev/shm`` shared between
    containers is judged only by processes that can see its owners."""
    try:
        return os.readlink("/proc/self/ns/pid").replace(" ", "")
    except OSError:
        return "-"


def _own(tmp, *pids, first=False):
    with open(os.path.join(tmp, _OWNERS), "w" if first else "a") as f:
        f.write((f"{_namespace()}\n" if first else "") + "".join(f"{pid}\n" for pid in pids))


def _write_input(folder, mats, opts):
    """The worker's IN folder: each CSR array as a ``.npy`` file, the options as JSON."""
    np.save(os.path.join(folder, "shape.npy"), np.array(mats[0].shape))
    for key, A in zip("MPQ", mats, strict=True):
        A = A.tocsr(copy=True)
        A.sum_duplicates()
        A.sort_indices()
        for part in ("data", "indices", "indptr"):
            np.save(os.path.join(folder, f"{key}_{part}.npy"), getattr(A, part))
        del A
    with open(os.path.join(folder, "options.json"), "w") as f:
        json.dump(opts, f)


def slepc_solve(Mb, Pb, Qb, nev, target=0.0, *, tol=1e-14, maxit=1000, ncv=None,
                factor=None, ranks=None, upper_tol=None):
    """(s, X, info): ``nev`` or more eigenpairs of (Mb s² + Pb s + Qb) x = 0 nearest ``target``
    (real), from SLEPc's TOAR with shift-and-invert, in a worker process (``ranks`` MPI
    processes: module docstring).  ``factor``: the LU package, ``umfpack`` on one process and
    ``mumps`` on several by default.  X's columns are the vectors of ``info["columns"]`` of s:
    every eigenvalue, or with ``upper_tol`` those with Im s ≥ −upper_tol·|s| (the conjugate
    partners of the others; half the vectors to gather and to pass back)."""
    exe = worker_python()
    if exe is None:
        named = os.environ.get("MBSEIG_SLEPC_PYTHON")
        raise SolverError(_MISSING + (f": MBSEIG_SLEPC_PYTHON names {named}, which does not exist"
                                      if named else ""))
    ranks = slepc_ranks(ranks)
    factor = factor or ("umfpack" if ranks == 1 else "mumps")
    env = _env(ranks)
    launch = _launch(exe, ranks, env)
    opts = {"nev": int(nev), "target": float(target), "tol": float(tol), "maxit": int(maxit),
            "ncv": int(ncv or 0), "factor": factor,
            "upper_tol": None if upper_tol is None else float(upper_tol)}
    scratch = _scratch(Mb, Pb, Qb)
    reap_stale(scratch)
    with tempfile.TemporaryDirectory(prefix=PREFIX, dir=scratch) as tmp:
        _own(tmp, os.getpid(), first=True)
        path_in, path_out = os.path.join(tmp, "in"), os.path.join(tmp, "out")
        os.mkdir(path_in)
        os.mkdir(path_out)
        wait = ranks == 1  # one process starts while IN is written (module docstring)
        cmd = launch + [str(_WORKER), path_in, path_out] + (["--wait"] if wait else [])
        proc = None
        try:
            if wait:
                proc = subprocess.Popen(cmd, env=env, stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                _own(tmp, proc.pid)
            _write_input(path_in, (Mb, Pb, Qb), opts)
            if proc is None:
                proc = subprocess.Popen(cmd, env=env, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                _own(tmp, proc.pid)
            _, err = proc.communicate("go\n" if wait else None)
        except BaseException:
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait()
            raise
        result = os.path.join(path_out, "result.npz")
        if proc.returncode != 0 or not os.path.exists(result):
            # the worker's own one-line message comes first (mpiexec appends banners after it)
            last = next((line for line in err.splitlines()
                         if line.strip() and set(line.strip()) != {"-"}), "no message")
            if last.startswith("ModuleNotFoundError") and ("petsc4py" in last
                                                           or "slepc4py" in last):
                raise SolverError(f"{_MISSING}: {exe} says {last}")
            raise SolverError(f"partial-slepc: the SLEPc worker failed (exit {proc.returncode}: "
                              f"{last})")
        try:
            with np.load(result) as out:
                s, columns = out["s"], out["columns"]
                info = {k: out[k].item() for k in ("its", "nconv", "setup", "solve", "extract",
                                                   "reason", "factor", "ranks")}
            # mapped, not read (the folder goes at the end of this block; a mapped file stays
            # readable until it is unmapped): the search gathers its columns from it once
            X = np.load(os.path.join(path_out, "X.npy"),
                        mmap_mode="r" if os.name == "posix" else None)
            info["columns"] = columns
            info["peak_rss_mb"] = []
            for r in range(ranks):
                with open(os.path.join(path_out, f"rank{r}.json")) as f:
                    info["peak_rss_mb"].append(round(json.load(f)["peak_rss_kb"] / 1024.0, 1))
        except (OSError, ValueError, KeyError) as exc:
            raise SolverError(f"partial-slepc: the worker's result is unreadable ({exc})") from None
    if info["reason"] < 0:
        raise SolverError(f"partial-slepc: SLEPc did not converge (reason {info['reason']}, "
                          f"{info['nconv']} of {nev} pairs after {info['its']} restarts)")
    return s, X, info
