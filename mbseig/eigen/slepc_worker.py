"""SLEPc worker of the ``partial-slepc`` path (:mod:`mbseig.eigen.slepc`): run as a script by a
Python that has slepc4py (often the system Python, whose numpy is not the one mbseig runs on).

    python slepc_worker.py IN.npz OUT.npz

IN.npz holds the CSR arrays of M, P, Q (``{M,P,Q}_{data,indices,indptr}``, ``shape``) and the
options ``nev``, ``target``, ``tol``, ``maxit``, ``ncv``, ``factor`` (LU package), ``ordering``.
The polynomial eigenproblem (M s² + P s + Q) x = 0 is solved by TOAR (a Krylov method on the
companion linearization that stores one n-vector per basis vector instead of two), spectral
transformation shift-and-invert at ``target`` (one LU of T(target) = target²M + target P + Q,
``preonly`` KSP), eigenpairs nearest ``target`` in magnitude.  OUT.npz holds ``s`` (complex),
``X`` (complex n × nconv, columns as SLEPc returns them), ``its``, ``nconv`` and the timings.
Only numpy, petsc4py and slepc4py are imported here (no scipy, no mbseig).
"""

import json
import sys
import time

import numpy as np


def _mat(PETSc, d, key, shape):
    indptr = d[f"{key}_indptr"].astype(PETSc.IntType)
    indices = d[f"{key}_indices"].astype(PETSc.IntType)
    data = d[f"{key}_data"].astype(PETSc.ScalarType)
    A = PETSc.Mat().createAIJ(size=shape, csr=(indptr, indices, data), comm=PETSc.COMM_SELF)
    A.assemble()
    return A


def main(path_in, path_out):
    t0 = time.perf_counter()
    import petsc4py

    petsc4py.init([])
    import slepc4py

    slepc4py.init([])
    from petsc4py import PETSc
    from slepc4py import SLEPc

    d = np.load(path_in)
    opts = json.loads(str(d["options"]))
    shape = tuple(int(x) for x in d["shape"])
    M, P, Q = (_mat(PETSc, d, k, shape) for k in ("M", "P", "Q"))
    t1 = time.perf_counter()
    pep = SLEPc.PEP().create(comm=PETSc.COMM_SELF)
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
    s = np.empty(nconv, complex)
    X = np.empty((n, nconv), complex)
    xr, xi = Q.createVecs()
    for i in range(nconv):
        s[i] = pep.getEigenpair(i, xr, xi)
        X[:, i] = xr.getArray() + 1j * xi.getArray()
    np.savez(path_out, s=s, X=X, its=pep.getIterationNumber(), nconv=nconv,
             setup=t1 - t0, solve=t2 - t1, extract=time.perf_counter() - t2,
             reason=int(pep.getConvergedReason()), factor=opts.get("factor", "superlu"))


if __name__ == "__main__":
    try:
        main(sys.argv[1], sys.argv[2])
    except Exception as exc:  # one line for the parent's SolverError (PETSc errors included)
        print(" ".join(f"{type(exc).__name__}: {exc}".split())[:400], file=sys.stderr)
        sys.exit(2)
