"""SLEPc worker of the ``partial-slepc`` path (:mod:`mbseig.eigen.slepc`): run as a script by a
Python that has slepc4py (often the system Python, whose numpy is not the one mbseig runs on).

    python slepc_worker.py IN OUT [--wait]

IN is a folder of ``.npy`` files: the CSR arrays of M, P, Q (``{M,P,Q}_{data,indices,indptr}``),
``shape``, and ``options.json`` with ``nev``, ``target``, ``tol``, ``maxit``, ``ncv``, ``factor``
(LU package), ``ordering``, ``upper_tol``.  With ``--wait`` the worker imports PETSc and SLEPc
first and then waits for one line on its standard input before it reads IN, so that its start
overlaps the writing of IN by the caller (one process only).
The polynomial eigenproblem (M s² + P s + Q) x = 0 is solved by TOAR (a Krylov method on the
companion linearization that stores one n-vector per basis vector instead of two), spectral
transformation shift-and-invert at ``target`` (one LU of T(target) = target²M + target P + Q,
``preonly`` KSP), eigenpairs nearest ``target`` in magnitude.  OUT is a folder too: ``X.npy``
(complex n × k: the vectors of the eigenvalues ``columns``, all of them unless ``upper_tol`` is
given) and ``result.npz`` with ``s`` (complex), ``columns``, ``its``, ``nconv`` and the timings
(``setup``: the imports, numpy's included, reading IN and assembling the matrices; ``solve``:
PEPSolve; ``extract``: the eigenvectors gathered and written).
Only numpy, petsc4py and slepc4py are imported here (no scipy, no mbseig).

Under MPI (``mpiexec -n P python slepc_worker.py IN OUT``) the same script runs on P
processes: each maps IN's arrays and assembles its own contiguous block of rows (PETSc's split:
n // P rows each, the first n mod P one more), the LU is a parallel one (the ``factor`` option:
``mumps``), the eigenvectors are gathered to rank 0, which writes OUT;
every rank writes its peak resident memory to ``OUT/rank<r>.json``.
"""

import time

T_START = time.perf_counter()  # the setup's clock starts before the imports, numpy's included

import json  # noqa: E402 - after T_START: the setup time includes the imports
import os  # noqa: E402 - after T_START: the setup time includes the imports
import sys  # noqa: E402 - after T_START: the setup time includes the imports

import numpy as np  # noqa: E402 - after T_START: the setup time includes numpy's import


def _rows(n, size, rank):
    """[r0, r1): the rows of ``rank`` in PETSc's default split of n rows over ``size``."""
    base, extra = divmod(n, size)
    r0 = rank * base + min(rank, extra)
    return r0, r0 + base + (1 if rank < extra else 0)


class _Folder:
    """IN's arrays by name, each mapped from its ``.npy`` file (read only where sliced)."""

    def __init__(self, path):
        self.path = path

    def __getitem__(self, key):
        return np.load(os.path.join(self.path, f"{key}.npy"), mmap_mode="r")


def _mat(PETSc, comm, d, key, shape):
    """The CSR matrix ``key`` of IN as a PETSc AIJ matrix, this process's rows only."""
    r0, r1 = _rows(shape[0], comm.getSize(), comm.getRank())
    indptr = np.asarray(d[f"{key}_indptr"])
    lo, hi = int(indptr[r0]), int(indptr[r1])
    local = (indptr[r0:r1 + 1] - lo).astype(PETSc.IntType)
    indices = d[f"{key}_indices"][lo:hi].astype(PETSc.IntType)
    data = d[f"{key}_data"][lo:hi].astype(PETSc.ScalarType)
    A = PETSc.Mat().createAIJ(size=((r1 - r0, shape[0]), (r1 - r0, shape[1])),
                              csr=(local, indices, data), comm=comm)
    A.assemble()
    return A


def _peak_rss_kb():
    """Peak resident memory of this process in kB: VmHWM (ru_maxrss can carry the peak of the
    process that started this one across the exec)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def _gathered(PETSc, v):
    """The whole of the distributed vector v on rank 0 (None elsewhere)."""
    if v.getComm().getSize() == 1:  # read before v changes: no copy needed
        return v.getArray(readonly=True)
    scatter, whole = PETSc.Scatter.toZero(v)
    scatter.scatter(v, whole, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    out = whole.getArray().copy() if v.getComm().getRank() == 0 else None
    scatter.destroy()
    whole.destroy()
    return out


def main(path_in, path_out, wait=False):
    t0 = T_START
    import petsc4py

    petsc4py.init([])
    import slepc4py

    slepc4py.init([])
    from petsc4py import PETSc
    from slepc4py import SLEPc

    comm = PETSc.COMM_WORLD
    rank = comm.getRank()
    if wait:  # the caller writes IN meanwhile; one line on stdin says it is complete
        waited = time.perf_counter()
        if not sys.stdin.readline().strip():
            raise RuntimeError("the caller ended before its input was written")
        t0 += time.perf_counter() - waited  # the wait is the caller's time, not the setup's
    d = _Folder(path_in)
    with open(os.path.join(path_in, "options.json")) as f:
        opts = json.load(f)
    shape = tuple(int(x) for x in d["shape"])
    M, P, Q = (_mat(PETSc, comm, d, k, shape) for k in ("M", "P", "Q"))
    del d
    t1 = time.perf_counter()
    pep = SLEPc.PEP().create(comm=comm)
    pep.setOperators([Q, P, M])
    pep.setProblemType(SLEPc.PEP.ProblemType.GENERAL)
    pep.setType(SLEPc.PEP.Type.TOAR)
    ncv = int(opts.get("ncv") or 0)
    pep.setDimensions(int(opts["nev"]), ncv if ncv > 0 else PETSc.DECIDE, PETSc.DECIDE)
    pep.setTolerances(float(opts.get("tol", 1e-12)), int(opts.get("maxit", 1000)))
    pep.setConvergenceTest(SLEPc.PEP.Conv.NORM)  # ‖T(s)x‖ / ((|s|²‖M‖ + |s|‖P‖ + ‖Q‖)‖x‖)
    pep.setTarget(float(opts["target"]))
    pep.setWhichEigenpairs(SLEPc.PEP.Which.TARGET_MAGNITUDE)
    st = pep.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    ksp = st.getKSP()
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.LU)
    pc.setFactorSolverType(opts.get("factor", "superlu"))
    if opts.get("ordering"):
        pc.setFactorOrdering(opts["ordering"])
    pep.setFromOptions()
    pep.solve()
    t2 = time.perf_counter()
    nconv = pep.getConverged()
    n = shape[0]
    s = np.array([pep.getEigenpair(i) for i in range(nconv)], complex)
    # a real pencil's eigenpairs come in conjugate pairs: with ``upper_tol`` only the vectors of
    # the upper half-plane (Im s ≥ −upper_tol·|s|) are returned, their partners being conjugates
    tol = opts.get("upper_tol")
    cols = (np.flatnonzero(s.imag >= -tol * np.maximum(np.abs(s), 1e-300)) if tol is not None
            else np.arange(nconv))
    # column-major: each vector is written in one contiguous stretch (a row-major X took 3.7 s
    # for 23 vectors of 1.1e6 entries, its column writes strided), straight into X.npy mapped
    # in memory (no second copy of X to save)
    X = (np.lib.format.open_memmap(os.path.join(path_out, "X.npy"), mode="w+", dtype=complex,
                                   shape=(n, cols.size), fortran_order=True)
         if rank == 0 else None)
    xr, xi = Q.createVecs()
    for j, i in enumerate(cols):
        pep.getEigenpair(int(i), xr, xi)
        re, im = _gathered(PETSc, xr), _gathered(PETSc, xi)
        if rank == 0:
            X[:, j].real = re
            X[:, j].imag = im
    with open(os.path.join(path_out, f"rank{rank}.json"), "w") as f:
        json.dump({"rank": rank, "peak_rss_kb": _peak_rss_kb()}, f)
    if rank == 0:
        X.flush()
        del X
        # written last: its presence says that the whole of OUT is there
        np.savez(os.path.join(path_out, "result.npz"), s=s, columns=cols,
                 its=pep.getIterationNumber(), nconv=nconv, setup=t1 - t0, solve=t2 - t1,
                 extract=time.perf_counter() - t2, reason=int(pep.getConvergedReason()),
                 factor=opts.get("factor", "superlu"), ranks=comm.getSize())
    return comm.getSize()


if __name__ == "__main__":
    try:
        size = main(sys.argv[1], sys.argv[2], wait="--wait" in sys.argv[3:])
    except Exception as exc:  # one line for the parent's SolverError (PETSc errors included)
        print(" ".join(f"{type(exc).__name__}: {exc}".split())[:400], file=sys.stderr)
        sys.exit(2)
    if size == 1:  # OUT is complete and closed: the caller waits for this exit, and PETSc's and
        sys.stdout.flush()  # the interpreter's teardown (≈ 70 ms) serves nothing here; under
        sys.stderr.flush()  # mpiexec the ranks finalize MPI as usual
        os._exit(0)
